//! The buffers the page and the module share, and the editor's level kept
//! in them: the level text the page writes (`TEXT`), the answers it reads
//! (`OUT`), and the editor's (or a generated maze's) level and its text,
//! where the player borrows them for as long as it plays them.

use core::cell::{RefCell, UnsafeCell};
use core::fmt::Write;

use marble_rolling::game::level::{
    parse, text as level_text, Level, LevelError, LevelErrorKind, LevelView,
};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::physics::geometry::grid::{words_for, MAX_LAYERS, MAX_STOREYS, MAX_TILES_XZ};

use crate::game_loop::{with_app, App, Source};
use crate::Single;

/// Occupancy words of the largest level the format allows: the editor's level
/// is parsed into a grid of this size (as the host tools' run-time levels are).
pub(crate) const MAX_WORDS: usize = words_for(MAX_TILES_XZ, MAX_LAYERS, MAX_TILES_XZ);

/// Bytes of level text the editor can hand over: the largest grid the format
/// takes (127 × 127 tiles on every storey, CRLF line ends, the `===` between
/// storeys) and 4 KiB of header. Any longer text is no level: the page then
/// hands over the lines that fit ([`TEXT_CUT`]).
pub(crate) const TEXT_CAPACITY: usize =
    MAX_STOREYS * (MAX_TILES_XZ * (MAX_TILES_XZ + 2) + 5) + 4 * 1024;

/// Set in the length given to [`check_level`] or [`play_level`] when the text
/// was longer than [`TEXT_CAPACITY`]: the buffer holds its first lines, whose
/// first error (a grid over 127 tiles says so on its first rows) is the one
/// to show rather than the length alone.
pub(crate) const TEXT_CUT: u32 = 1 << 31;

/// Bytes of an answer (a name, an error message).
pub(crate) const OUT_CAPACITY: usize = 1024;

/// The editor's level, then the built-in ones (`next level` goes on there).
pub(crate) const CUSTOM_LIST: usize = 1 + LEVELS.len();

/// Where the page writes level text for [`check_level`] and [`play_level`].
pub(crate) static TEXT: Single<UnsafeCell<[u8; TEXT_CAPACITY]>> =
    Single(UnsafeCell::new([0; TEXT_CAPACITY]));

/// Where answers are written for the page to read.
pub(crate) static OUT: Single<RefCell<Out>> = Single(RefCell::new(Out {
    bytes: [0; OUT_CAPACITY],
    len: 0,
}));

/// The editor's level (see [`Custom`]).
pub(crate) static CUSTOM: Single<UnsafeCell<Custom>> = Single(UnsafeCell::new(Custom {
    len: 0,
    level: None,
    list: None,
}));

/// The text of the editor's level, under [`Custom`]'s rule. A static of its
/// own: all zeros, it takes no bytes of the module, where inside `Custom`
/// (whose `None`s are not zeros) it would be data, byte for byte.
pub(crate) static CUSTOM_TEXT: Single<UnsafeCell<[u8; TEXT_CAPACITY]>> =
    Single(UnsafeCell::new([0; TEXT_CAPACITY]));

/// The level the editor started, kept where the player can borrow it for as
/// long as it plays it: the player takes `'static` levels (the firmware's are
/// in flash). Its text is copied from [`TEXT`] into [`CUSTOM_TEXT`], so that
/// editing does not change the level in play (its name borrows the text).
///
/// It is rewritten only by [`install_custom`], and only after the player that
/// borrowed the previous one has been replaced by one on a built-in level:
/// no reference into it is alive while it changes.
pub(crate) struct Custom {
    /// Bytes of [`CUSTOM_TEXT`] in use.
    pub(crate) len: usize,
    pub(crate) level: Option<Level<'static, MAX_WORDS>>,
    pub(crate) list: Option<[LevelView<'static>; CUSTOM_LIST]>,
}

/// A fixed buffer that `write!` fills; what does not fit is dropped (an error
/// message is a line; a cut one still names line and column first).
pub(crate) struct Out {
    pub(crate) bytes: [u8; OUT_CAPACITY],
    pub(crate) len: usize,
}

impl Write for Out {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let room = OUT_CAPACITY - self.len;
        let mut take = s.len().min(room);
        // Never cut a character in two: the page decodes UTF-8.
        while !s.is_char_boundary(take) {
            take -= 1;
        }
        self.bytes[self.len..self.len + take].copy_from_slice(&s.as_bytes()[..take]);
        self.len += take;
        Ok(())
    }
}

/// Writes `args` as the answer; returns its length in bytes.
pub(crate) fn answer(args: core::fmt::Arguments) -> u32 {
    let mut out = OUT.0.borrow_mut();
    out.len = 0;
    let _ = out.write_fmt(args);
    out.len as u32
}

/// Puts `text` in [`CUSTOM_TEXT`], its level in [`CUSTOM`], and returns the
/// list it heads: with the built-in levels after it, or `alone`.
///
/// # Safety
///
/// No reference into [`CUSTOM`] or [`CUSTOM_TEXT`] may be alive: the player
/// must be on a built-in level (see [`Custom`]).
pub(crate) unsafe fn install_custom(
    text: &str,
    alone: bool,
) -> Result<&'static [LevelView<'static>], LevelError> {
    // SAFETY: the caller guarantees nothing borrows CUSTOM; from here on the
    // level and list borrow it for as long as the next player plays them, and
    // the next install replaces that player first.
    let Custom { len, level, list }: &'static mut Custom = unsafe { &mut *CUSTOM.0.get() };
    // SAFETY: as CUSTOM: the level just dropped was the only borrower.
    let stored: &'static mut [u8; TEXT_CAPACITY] = unsafe { &mut *CUSTOM_TEXT.0.get() };
    *level = None;
    *list = None;
    *len = 0;
    // `text` comes from TEXT, which is no larger: this only keeps a slip from trapping.
    let Some(stored) = stored.get_mut(..text.len()) else {
        return Err(LevelError {
            line: 1,
            column: 1,
            kind: LevelErrorKind::TooLarge,
        });
    };
    stored.copy_from_slice(text.as_bytes());
    *len = text.len();
    let stored: &'static [u8] = stored;
    // The bytes are `text`'s, which is UTF-8.
    let stored = core::str::from_utf8(stored).unwrap_or_default();
    let level: &'static Level<'static, MAX_WORDS> = level.insert(parse(stored)?);
    let mut views = [level.view(); CUSTOM_LIST];
    views[1..].copy_from_slice(&LEVELS);
    let list: &'static [LevelView<'static>] = list.insert(views);
    Ok(if alone { &list[..1] } else { list })
}

/// Why text from the page is not even a level to parse.
pub(crate) enum TextError {
    /// More than [`TEXT_CAPACITY`] bytes, and no error in the lines that fit.
    TooLong,
    /// The parser's error, or bytes that are not UTF-8 (the page's
    /// `TextEncoder` always sends UTF-8; a bug there is still only a message,
    /// the one `cargo sim` gives for such a file).
    Level(LevelError),
}

impl core::fmt::Display for TextError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TextError::TooLong => write!(
                f,
                "1:1: longer than {TEXT_CAPACITY} bytes, more than a level of \
                 {MAX_TILES_XZ} × {MAX_TILES_XZ} tiles on {MAX_STOREYS} storeys takes"
            ),
            // `line:column: message`, as `cargo sim -- --check` prints it after the file name.
            TextError::Level(error) => write!(f, "{error}"),
        }
    }
}

/// The first `len` bytes of [`TEXT`] as text, or where it stops being UTF-8.
pub(crate) fn text(len: u32) -> Result<&'static str, TextError> {
    // SAFETY: single thread (see `Single`); the page writes TEXT only between
    // calls, and what is returned is used before this call returns.
    let bytes: &'static [u8; TEXT_CAPACITY] = unsafe { &*TEXT.0.get() };
    let Some(bytes) = bytes.get(..len as usize) else {
        return Err(TextError::TooLong);
    };
    level_text(bytes).map_err(TextError::Level)
}

/// The text as a valid level's source, or why it is not one.
pub(crate) fn checked(len: u32) -> Result<&'static str, TextError> {
    if len & TEXT_CUT != 0 {
        return Err(cut_error(len & !TEXT_CUT));
    }
    let source = text(len)?;
    parse::<MAX_WORDS>(source).map_err(TextError::Level)?;
    Ok(source)
}

/// Why a text longer than [`TEXT_CAPACITY`] is no level, from its first `len`
/// bytes (whole lines): the parser's first error in them, unless it is one
/// that more lines could have undone (no start or goal yet, a storey cut
/// short), else its length.
pub(crate) fn cut_error(len: u32) -> TextError {
    let error = match text(len) {
        Ok(prefix) => match parse::<MAX_WORDS>(prefix) {
            Ok(_) => return TextError::TooLong,
            Err(error) => error,
        },
        Err(TextError::Level(error)) => error,
        Err(TextError::TooLong) => return TextError::TooLong,
    };
    match error.kind {
        LevelErrorKind::MissingSeparator
        | LevelErrorKind::EmptyGrid
        | LevelErrorKind::StartCount
        | LevelErrorKind::GoalCount
        | LevelErrorKind::StoreyRows
        | LevelErrorKind::EmptyStorey
        | LevelErrorKind::NotUtf8 { .. } => TextError::TooLong,
        _ => TextError::Level(error),
    }
}

/// Writes the error (`line:column: message`) as the answer; its length.
pub(crate) fn error_answer(error: impl core::fmt::Display) -> u32 {
    answer(format_args!("{error}"))
}

/// Where the page writes level text (UTF-8) for [`check_level`] and [`play_level`].
#[no_mangle]
pub extern "C" fn text_ptr() -> *mut u8 {
    TEXT.0.get().cast()
}

/// How many bytes [`text_ptr`]'s buffer holds.
#[no_mangle]
pub extern "C" fn text_capacity() -> u32 {
    TEXT_CAPACITY as u32
}

/// The bit that marks a length as the first lines of a longer text (`TEXT_CUT`).
#[no_mangle]
pub extern "C" fn text_cut() -> u32 {
    TEXT_CUT
}

/// Where answers are (see the module doc).
#[no_mangle]
pub extern "C" fn out_ptr() -> *const u8 {
    OUT.0.borrow().bytes.as_ptr()
}

/// Parses the `len` bytes of level text: 0 if it is a valid level, else the
/// length of its `line:column: message` in the answer buffer. With
/// `TEXT_CUT` set, they are the first lines of a text too long to hold.
#[no_mangle]
pub extern "C" fn check_level(len: u32) -> u32 {
    match checked(len) {
        Ok(_) => 0,
        Err(error) => error_answer(error),
    }
}

/// Plays the `len` bytes of level text, if valid (then `next level` goes on to
/// the built-in ones): 0, or the error's length as [`check_level`]. A level the
/// parser takes but the physics refuses (it cannot be: the parser checks the
/// same rules) is reported too, and the game goes on where it was.
#[no_mangle]
pub extern "C" fn play_level(len: u32) -> u32 {
    match checked(len) {
        Ok(source) => with_app(0, |app| play_source(app, source, Source::Editor)),
        Err(error) => error_answer(error),
    }
}

/// Plays `source` (valid level text) as the level from `kind` (the editor's
/// or a generated maze): 0, or the length of the error in the answer buffer.
pub(crate) fn play_source(app: &mut App, source: &'static str, kind: Source) -> u32 {
    let resume = app.level_number() as usize;
    // First off the editor's old level: nothing may borrow it while it changes.
    if !app.start(&LEVELS, 0) {
        return answer(format_args!("1:1: the built-in levels cannot be set up"));
    }
    app.source = Source::Builtin;
    let alone = matches!(kind, Source::Generated(_));
    // SAFETY: the player is on a built-in level, so nothing borrows CUSTOM.
    let list = match unsafe { install_custom(source, alone) } {
        Ok(list) => list,
        Err(error) => return error_answer(TextError::Level(error)),
    };
    if app.start(list, 0) {
        app.source = kind;
        0
    } else {
        app.start(&LEVELS, resume.min(LEVELS.len() - 1));
        answer(format_args!(
            "1:1: the level cannot be set up by the physics"
        ))
    }
}

/// The text of the editor's level or generated maze last played (see
/// [`source_text_len`]).
#[no_mangle]
pub extern "C" fn source_text_ptr() -> *const u8 {
    // SAFETY: only the address is taken; the page reads it between calls.
    unsafe { (*CUSTOM_TEXT.0.get()).as_ptr() }
}

/// Bytes at [`source_text_ptr`].
#[no_mangle]
pub extern "C" fn source_text_len() -> u32 {
    // SAFETY: single thread (see `Single`); a read of a number between calls.
    unsafe { (*CUSTOM.0.get()).len as u32 }
}
