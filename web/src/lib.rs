//! Marble Rolling in a browser: the library's game — its fixed-point physics,
//! levels, level parser, tilt path, autopilot and renderer — compiled to
//! `wasm32-unknown-unknown`, driven by `web/www/app.js`.
//!
//! This crate is only the glue. Each frame is one [`Player::tick`], the very
//! step the firmware's game task, `cargo play` and the host tests call, fed a
//! reading made by the library's [`Tilt::from_xz`] from the page's tilt
//! (keys, mouse joystick or the phone's orientation) through
//! [`SYNTHETIC_TILT`], the tilt path `cargo play` and `cargo sim` use. So a run
//! here plays the same game as on the host and the boards, and the autopilot
//! ends each built-in level with `cargo sim -- --autopilot`'s `state_hash`
//! (the browser test checks that).
//!
//! # Both steppers
//!
//! The page plays with event stepping, as every board and `cargo sim` do by
//! default (the accuracy study's recommendation), and can switch to fixed
//! steps, the study's baseline: [`set_stepping`]. The stepper is a constant of
//! the [`Player`] type (a board links one), so the page holds either player
//! (`AnyPlayer`); both cost the module their code, which a browser can spare.
//!
//! # Generated mazes and the ghost
//!
//! [`play_generated`] plays the maze of a seed from the core's generator
//! (`game::generate`, with `cargo sim -- --generate`'s defaults), parsed from
//! its text as the editor's level is, alone in its list: a win plays it again.
//! Every attempt is written as a ghost while it plays (`Recorder`, the
//! core's `game::ghost` format); a win's ghost is handed to the page
//! ([`finished_ghost_len`], [`record_ptr`]), which keeps the best per level in
//! `localStorage` and hands it back at the next attempt ([`load_ghost`]): it
//! is taken only if its replay wins the level on its recorded state hash, and
//! then a second session fed its readings plays one frame per live frame.
//!
//! # Why no wasm-bindgen
//!
//! The interface is numbers and a few byte buffers, so it is plain
//! `extern "C"` functions over linear memory and a hand-written loader.
//! wasm-bindgen would need its CLI at exactly the crate's version (a
//! multi-minute `cargo install` on every fresh CI machine) and a generated JS
//! glue file, for no gain here. Strings cross as UTF-8 bytes: the page writes
//! a level's text into [`text_ptr`]'s buffer; answers (names, error messages)
//! come back in [`out_ptr`]'s buffer, their length the function's result.
//!
//! # State without an allocator
//!
//! Everything lives in statics: the game (about what the firmware keeps in
//! RAM), the one level typed into the editor (or generated), parsed in place,
//! and three ghost buffers (the attempt's, the page's, the one on show). A
//! `wasm32-unknown-unknown` module without the atomics feature runs on one
//! thread, the page's, and every export runs to its end before the next one
//! starts; `Single` states that. The other `unsafe` code reads the text
//! buffer the page writes, keeps the editor's level (see `Custom`) and lends
//! the ghost buffers to the ghost's writer and reader (see `Recorder`,
//! `load_ghost`). A wrong input — a malformed level, an out-of-range index, a
//! broken ghost — is an answer (an error message, a zero), never a trap.
#![cfg_attr(target_arch = "wasm32", no_std)]

use core::cell::{RefCell, UnsafeCell};
use core::fmt::Write;

use marble_rolling::board::microbit::{HEIGHT, WIDTH};
use marble_rolling::game::generate::{generate, MAX_TEXT_BYTES};
use marble_rolling::game::ghost::{replay, Ghost, GhostWriter, Readings};
use marble_rolling::game::level::{
    parse, text as level_text, Cell, Level, LevelError, LevelErrorKind, LevelView, MAX_MARBLES,
};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::player::Tick;
use marble_rolling::game::player::{Player, FRAME_HZ};
use marble_rolling::game::rules::{Game, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::event::Tilt;
use marble_rolling::physics::geometry::grid::{words_for, MAX_LAYERS, MAX_TILES_XZ};
use marble_rolling::physics::world::World;
use marble_rolling::physics::{Fx, TileIndex};
use marble_rolling::render;

/// The micro:bit's player (its 5×5 matrix) with the autopilot (the page has
/// a button for it, as the QEMU board has a key), stepped by events (`EVENTS`)
/// or fixed steps: `cargo sim -- --stepping events|fixed` replays either.
type WebPlayer<const EVENTS: bool> = Player<'static, WIDTH, HEIGHT, true, EVENTS>;

/// The player on the stepper the page chose (see the module doc).
enum AnyPlayer {
    Events(WebPlayer<true>),
    Fixed(WebPlayer<false>),
}

/// `$body` with `$p` bound to the player, whichever stepper it has.
macro_rules! each {
    ($player:expr, $p:ident => $body:expr) => {
        match $player {
            AnyPlayer::Events($p) => $body,
            AnyPlayer::Fixed($p) => $body,
        }
    };
}

impl AnyPlayer {
    fn new(
        levels: &'static [LevelView<'static>],
        index: usize,
        events: bool,
        autopilot: bool,
    ) -> Option<AnyPlayer> {
        Some(if events {
            AnyPlayer::Events(WebPlayer::new(levels, index, SYNTHETIC_TILT, autopilot).ok()?)
        } else {
            AnyPlayer::Fixed(WebPlayer::new(levels, index, SYNTHETIC_TILT, autopilot).ok()?)
        })
    }
    fn events(&self) -> bool {
        matches!(self, AnyPlayer::Events(_))
    }
    fn tick(&mut self, reading: [i32; 3]) -> Tick<WIDTH, HEIGHT> {
        each!(self, p => p.tick(reading, true))
    }
    fn game(&self) -> &Game<'static, Fx> {
        each!(self, p => p.game())
    }
    fn level_index(&self) -> usize {
        each!(self, p => p.level_index())
    }
    fn session(&self) -> &Session<'static, Fx> {
        each!(self, p => p.session())
    }
    fn state_hash(&self) -> u64 {
        self.session().state_hash()
    }
    fn reading(&self) -> [i32; 3] {
        each!(self, p => p.session().reading())
    }
    fn autopilot(&self) -> bool {
        each!(self, p => p.autopilot())
    }
    fn set_autopilot(&mut self, on: bool) {
        each!(self, p => p.set_autopilot(on))
    }
    fn restart(&mut self) {
        each!(self, p => p.restart())
    }
    fn next_level(&mut self) {
        each!(self, p => p.next_level())
    }
}

/// Occupancy words of the largest level the format allows: the editor's level
/// is parsed into a grid of this size (as the host tools' run-time levels are).
const MAX_WORDS: usize = words_for(MAX_TILES_XZ, MAX_LAYERS, MAX_TILES_XZ);
/// Bytes of level text the editor can hand over: a 127 × 127 grid with its
/// line ends is 16 256, the header a few hundred more.
const TEXT_CAPACITY: usize = 32 * 1024;
/// Bytes of an answer (a name, an error message).
const OUT_CAPACITY: usize = 1024;
/// The editor's level, then the built-in ones (`next level` goes on there).
const CUSTOM_LIST: usize = 1 + LEVELS.len();
/// Bytes of a ghost (its format: `marble_rolling::game::ghost`). The
/// autopilot's runs take 188 to 279 B per second, a run with a sensor's noise
/// 489 (docs/ghost.md): 64 KiB keep about four minutes, or two of the noisy
/// run, longer than any built-in level's limit; a longer run leaves no ghost.
const GHOST_CAPACITY: usize = 64 * 1024;
/// `cargo sim -- --generate SEED`'s defaults (`src/host/generated.rs`, which
/// the no_std build does not have): the same seed gives the same maze here.
/// The browser test holds the page to that text.
const DEFAULT_MAZE_SIZE: u8 = 6;
const DEFAULT_MAZE_STOREYS: u8 = 1;
const DEFAULT_MAZE_DIFFICULTY: u8 = 2;

/// A value of this module's single thread (see the module doc).
struct Single<T>(T);

// SAFETY: wasm32-unknown-unknown without the `atomics` target feature has no
// threads: the page calls one export at a time, each runs to its end. On the
// host (where this crate only builds, for `cargo check` and clippy) nothing
// calls these functions.
unsafe impl<T> Sync for Single<T> {}

/// Where the page writes level text for [`check_level`] and [`play_level`].
static TEXT: Single<UnsafeCell<[u8; TEXT_CAPACITY]>> = Single(UnsafeCell::new([0; TEXT_CAPACITY]));
/// Where answers are written for the page to read.
static OUT: Single<RefCell<Out>> = Single(RefCell::new(Out {
    bytes: [0; OUT_CAPACITY],
    len: 0,
}));
/// The editor's level (see [`Custom`]).
static CUSTOM: Single<UnsafeCell<Custom>> = Single(UnsafeCell::new(Custom {
    text: [0; TEXT_CAPACITY],
    len: 0,
    level: None,
    list: None,
}));
/// The game, set up by [`init`].
static APP: Single<RefCell<Option<App>>> = Single(RefCell::new(None));
/// Where the page writes a stored ghost for [`load_ghost`].
static GHOST_IN: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));
/// The ghost on show, copied from [`GHOST_IN`]: its replay reads it frame by
/// frame (see [`GhostRun`]).
static GHOST: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));
/// The attempt in play, written as a ghost while it is played (see [`Recorder`]).
static RECORD: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The level the editor started, kept where the player can borrow it for as
/// long as it plays it: the player takes `'static` levels (the firmware's are
/// in flash). Its text is copied here from [`TEXT`], so that editing does not
/// change the level in play (its name borrows the text).
///
/// It is rewritten only by [`install_custom`], and only after the player that
/// borrowed the previous one has been replaced by one on a built-in level:
/// no reference into it is alive while it changes.
struct Custom {
    text: [u8; TEXT_CAPACITY],
    /// Bytes of `text` in use.
    len: usize,
    level: Option<Level<'static, MAX_WORDS>>,
    list: Option<[LevelView<'static>; CUSTOM_LIST]>,
}

/// A fixed buffer that `write!` fills; what does not fit is dropped (an error
/// message is a line; a cut one still names line and column first).
struct Out {
    bytes: [u8; OUT_CAPACITY],
    len: usize,
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
fn answer(args: core::fmt::Arguments) -> u32 {
    let mut out = OUT.0.borrow_mut();
    out.len = 0;
    let _ = out.write_fmt(args);
    out.len as u32
}

/// The last attempt that finished (won, fell, timed out), for the page's best
/// times and the browser test's hashes.
#[derive(Clone, Copy)]
struct Finished {
    /// Attempts finished since [`init`]: the page notices a new one by it.
    count: u32,
    level: u32,
    source: Source,
    phase: Phase,
    frames: u32,
    /// Frames on the level clock (the time a player is shown and a record keeps).
    clock: u32,
    hash: u64,
    /// Bytes of the attempt's ghost in [`RECORD`] (a win played whole from its
    /// first frame, that fitted); 0 for none.
    ghost_len: u32,
}

/// Where the level list in play comes from.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Source {
    /// The built-in levels.
    Builtin,
    /// The editor's level, then the built-in ones.
    Editor,
    /// A generated maze alone: a win plays it again, against the ghost of
    /// that win if it is the best.
    Generated(MazeArgs),
}

/// The arguments of [`generate`] a generated maze came from.
#[derive(Clone, Copy, PartialEq, Eq)]
struct MazeArgs {
    seed: u32,
    size: u8,
    storeys: u8,
    difficulty: u8,
}

struct App {
    player: AnyPlayer,
    /// The level list in play (the built-ins, or the editor's level and them).
    levels: &'static [LevelView<'static>],
    /// Where that list comes from.
    source: Source,
    /// The page's tilt, as the accelerometer reading the player is fed.
    reading: [i32; 3],
    /// The matrix as the last frame drew it, row by row (brightness 0..=15).
    led: [u8; WIDTH * HEIGHT],
    finished: Finished,
    recorder: Recorder,
    /// The stored best run of the level in play, replayed beside it.
    ghost: Option<GhostRun>,
}

impl App {
    fn new() -> Option<App> {
        let player = AnyPlayer::new(
            &LEVELS,
            0,
            marble_rolling::game::rules::DEFAULT_EVENTS,
            false,
        )?;
        Some(App {
            player,
            levels: &LEVELS,
            source: Source::Builtin,
            reading: Tilt::FLAT.reading_mg(),
            led: [0; WIDTH * HEIGHT],
            finished: Finished {
                count: 0,
                level: 0,
                source: Source::Builtin,
                phase: Phase::Playing,
                frames: 0,
                clock: 0,
                hash: 0,
                ghost_len: 0,
            },
            recorder: Recorder::new(),
            ghost: None,
        })
        .map(|mut app| {
            app.recorder.start();
            app
        })
    }

    /// Plays level `index` of `levels` from its start with the stepper in
    /// use; the autopilot setting carries over. False (and the game
    /// unchanged) if it cannot be set up.
    fn start(&mut self, levels: &'static [LevelView<'static>], index: usize) -> bool {
        self.start_stepped(levels, index, self.player.events())
    }

    /// [`App::start`] with the stepper `events` picks.
    fn start_stepped(
        &mut self,
        levels: &'static [LevelView<'static>],
        index: usize,
        events: bool,
    ) -> bool {
        match AnyPlayer::new(levels, index, events, self.player.autopilot()) {
            Some(player) => {
                self.player = player;
                self.levels = levels;
                // Another level (or stepper): the ghost on show was not for it.
                self.ghost = None;
                self.recorder.start();
                true
            }
            None => false,
        }
    }

    fn tick(&mut self) -> u32 {
        let level = self.player.level_index();
        let tick = self.player.tick(self.reading);
        if let Some(frame) = tick.frame {
            for (y, row) in frame.rows().iter().enumerate() {
                self.led[y * WIDTH..(y + 1) * WIDTH].copy_from_slice(row);
            }
        }
        let moved_on = self.player.level_index() != level;
        if moved_on {
            self.ghost = None;
        }
        self.follow_attempt();
        let mut flags = 0;
        if let Some(phase) = tick.finished {
            let ghost_len = match phase {
                Phase::Won => self.recorder.finish(self.player.session()),
                _ => 0,
            };
            let game = self.player.game();
            self.finished = Finished {
                count: self.finished.count.wrapping_add(1),
                level: self.level_number(),
                source: self.level_source(),
                phase,
                frames: game.frames(),
                clock: game.clock_frames(),
                hash: self.player.state_hash(),
                ghost_len,
            };
            flags |= TICK_FINISHED;
        }
        if moved_on || self.player.game().frames() == 0 {
            flags |= TICK_NEW_ATTEMPT;
        }
        flags
    }

    /// After a frame (or a restart, a new level): the attempt's reading goes
    /// into its ghost, and the ghost on show plays as far as the attempt.
    fn follow_attempt(&mut self) {
        let session = self.player.session();
        self.recorder.observe(session);
        if let Some(ghost) = &mut self.ghost {
            ghost.follow(session.game().frames());
        }
    }

    /// Where the level in play comes from (the built-ins after the editor's
    /// level are built-in).
    fn level_source(&self) -> Source {
        match self.source {
            Source::Editor if self.player.level_index() > 0 => Source::Builtin,
            source => source,
        }
    }

    /// Whether the level in play is the editor's.
    fn is_custom_level(&self) -> bool {
        self.level_source() == Source::Editor
    }

    /// The level in play as a built-in index (the editor's or a generated
    /// maze: the built-ins' count).
    fn level_number(&self) -> u32 {
        let index = self.player.level_index();
        let builtin = match self.source {
            Source::Builtin => Some(index),
            Source::Editor => index.checked_sub(1),
            Source::Generated(_) => None,
        };
        builtin.unwrap_or(LEVELS.len()) as u32
    }

    fn level(&self) -> &LevelView<'static> {
        self.player.game().level()
    }
}

/// The attempt in play, written as a ghost frame by frame into [`RECORD`]: a
/// win is then a ghost already, without a copy of its readings.
struct Recorder {
    writer: Option<GhostWriter<'static>>,
    /// Frames of the attempt seen so far.
    frames: u32,
    /// The writer has every reading of the attempt from its first frame.
    whole: bool,
}

impl Recorder {
    fn new() -> Self {
        Recorder {
            writer: None,
            frames: 0,
            whole: false,
        }
    }

    /// Starts over, for an attempt at its first frame.
    fn start(&mut self) {
        // The old writer goes first: it holds the only reference into RECORD.
        self.writer = None;
        // SAFETY: single thread (see `Single`). The writer just dropped was
        // the only reference into RECORD (a finished ghost is handed out as a
        // length, its slice dropped at once), so this one is alone.
        let buf: &'static mut [u8; GHOST_CAPACITY] = unsafe { &mut *RECORD.0.get() };
        self.writer = GhostWriter::new(buf).ok();
        self.frames = 0;
        self.whole = self.writer.is_some();
    }

    /// After a frame, a restart or a new level: keeps the frame's reading.
    fn observe(&mut self, session: &Session<'static, Fx>) {
        let frames = session.game().frames();
        if frames == 0 {
            if self.frames != 0 || self.writer.is_none() {
                self.start();
            }
            return;
        }
        if frames == self.frames {
            // A finished attempt on show: no frame played.
            return;
        }
        let pushed = frames == self.frames + 1
            && self
                .writer
                .as_mut()
                .is_some_and(|w| w.push(session.reading()).is_ok());
        // A frame missed, or no room left: this attempt leaves no ghost.
        self.whole &= pushed;
        self.frames = frames;
    }

    /// The ghost of the attempt that just ended (a win) in [`RECORD`]: its
    /// length, or 0 if the attempt was not kept whole.
    fn finish(&mut self, session: &Session<'static, Fx>) -> u32 {
        let Some(writer) = self.writer.take() else {
            return 0;
        };
        if !self.whole || writer.frames() != session.game().frames() {
            return 0;
        }
        writer
            .finish(session.state_hash(), session.tilt().calibration())
            .map_or(0, |bytes| bytes.len() as u32)
    }
}

/// A stored ghost played beside the live game, one frame per live frame.
struct GhostRun {
    session: Session<'static, Fx>,
    ghost: Ghost<'static>,
    readings: Readings<'static>,
    /// Its time on the level clock, frames (measured by the replay that
    /// checked it).
    clock: u32,
}

impl GhostRun {
    /// Plays the ghost as far as frame `frames` of the live attempt (from its
    /// start again if the live game started over), or to its end.
    fn follow(&mut self, frames: u32) {
        if frames < self.session.game().frames() {
            // A restart keeps the calibration, the ghost's.
            self.session.restart();
            self.readings = self.ghost.readings();
        }
        while self.session.game().frames() < frames && self.session.game().phase() == Phase::Playing
        {
            match self.readings.next() {
                Some(Ok(reading)) => {
                    self.session.frame(reading);
                }
                // Checked when loaded: the readings neither end early nor break.
                _ => break,
            }
        }
    }
}

/// A [`Write`] into a byte buffer that fails, rather than cut the text, when
/// it is full (a cut level text would be another level).
struct Cursor<'a> {
    bytes: &'a mut [u8],
    len: usize,
}

impl Write for Cursor<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        let end = self.len + s.len();
        let slot = self.bytes.get_mut(self.len..end).ok_or(core::fmt::Error)?;
        slot.copy_from_slice(s.as_bytes());
        self.len = end;
        Ok(())
    }
}

/// Writes the maze's level text into [`TEXT`]: its length, or the length of
/// the generator's error in the answer buffer.
fn generated_text(maze: MazeArgs) -> Result<u32, u32> {
    let generated = generate(maze.seed, maze.size, maze.storeys, maze.difficulty)
        .map_err(|e| answer(format_args!("{e}")))?;
    // SAFETY: single thread (see `Single`); no reference into TEXT is alive
    // between calls, and this one ends here.
    let bytes: &mut [u8; TEXT_CAPACITY] = unsafe { &mut *TEXT.0.get() };
    let mut cursor = Cursor { bytes, len: 0 };
    write!(cursor, "{generated}").map_err(|_| {
        answer(format_args!(
            "internal error: maze {} is longer than {MAX_TEXT_BYTES} bytes",
            maze.seed
        ))
    })?;
    Ok(cursor.len as u32)
}

/// A `u32` argument as a `u8` one (too large: `u8::MAX`, which every range
/// check of [`generate`] refuses with its range).
fn small(n: u32) -> u8 {
    u8::try_from(n).unwrap_or(u8::MAX)
}

type WebWorld = World<'static, Fx, MAX_MARBLES>;

/// Coordinate `axis` (0 x, 1 y, 2 z) of marble `index` in `world`, mm (0 for none).
fn marble_coord(world: &WebWorld, index: u32, axis: u32) -> f64 {
    let Some(marble) = world.marbles().get(index as usize) else {
        return 0.0;
    };
    let value = match axis {
        0 => marble.pos.x,
        1 => marble.pos.y,
        _ => marble.pos.z,
    };
    world.params().layout.to_mm(value)
}

/// The storey marble `index` of `world` is on, within the level's `storeys`.
fn storey_of(world: &WebWorld, index: u32, storeys: u8) -> u32 {
    world.marbles().get(index as usize).map_or(0, |m| {
        let storeys = i32::from(storeys).max(1);
        world
            .params()
            .layout
            .storey_of(m.pos.y)
            .clamp(0, storeys - 1) as u32
    })
}

/// Whether marble `index` of `world` is out of play (or there is none).
fn is_out(world: &WebWorld, index: u32) -> bool {
    world.marbles().get(index as usize).is_none_or(|m| m.out)
}

/// [`tick`]'s result bit: an attempt finished in this frame.
const TICK_FINISHED: u32 = 1;
/// [`tick`]'s result bit: a new attempt started (another level, or a restart).
const TICK_NEW_ATTEMPT: u32 = 2;

/// Runs `f` on the game; `default` before [`init`] (or if it failed).
fn with_app<R>(default: R, f: impl FnOnce(&mut App) -> R) -> R {
    match APP.0.borrow_mut().as_mut() {
        Some(app) => f(app),
        None => default,
    }
}

/// Puts `text` in [`CUSTOM`] and returns the list it heads: with the built-in
/// levels after it, or `alone`.
///
/// # Safety
///
/// No reference into [`CUSTOM`] may be alive: the player must be on a built-in
/// level (see [`Custom`]).
unsafe fn install_custom(
    text: &str,
    alone: bool,
) -> Result<&'static [LevelView<'static>], LevelError> {
    // SAFETY: the caller guarantees nothing borrows CUSTOM; from here on the
    // level and list borrow it for as long as the next player plays them, and
    // the next install replaces that player first.
    let Custom {
        text: stored,
        len,
        level,
        list,
    }: &'static mut Custom = unsafe { &mut *CUSTOM.0.get() };
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
enum TextError {
    /// More than [`TEXT_CAPACITY`] bytes.
    TooLong,
    /// The parser's error, or bytes that are not UTF-8 (the page's
    /// `TextEncoder` always sends UTF-8; a bug there is still only a message,
    /// the one `cargo sim` gives for such a file).
    Level(LevelError),
}

impl core::fmt::Display for TextError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TextError::TooLong => write!(f, "1:1: longer than {TEXT_CAPACITY} bytes"),
            // `line:column: message`, as `cargo sim -- --check` prints it after the file name.
            TextError::Level(error) => write!(f, "{error}"),
        }
    }
}

/// The first `len` bytes of [`TEXT`] as text, or where it stops being UTF-8.
fn text(len: u32) -> Result<&'static str, TextError> {
    // SAFETY: single thread (see `Single`); the page writes TEXT only between
    // calls, and what is returned is used before this call returns.
    let bytes: &'static [u8; TEXT_CAPACITY] = unsafe { &*TEXT.0.get() };
    let Some(bytes) = bytes.get(..len as usize) else {
        return Err(TextError::TooLong);
    };
    level_text(bytes).map_err(TextError::Level)
}

/// The text as a valid level's source, or why it is not one.
fn checked(len: u32) -> Result<&'static str, TextError> {
    let source = text(len)?;
    parse::<MAX_WORDS>(source).map_err(TextError::Level)?;
    Ok(source)
}

/// Writes the error (`line:column: message`) as the answer; its length.
fn error_answer(error: impl core::fmt::Display) -> u32 {
    answer(format_args!("{error}"))
}

// ---------------------------------------------------------------------------
// The exports. Numbers only; see the module doc for strings.
// ---------------------------------------------------------------------------

/// Sets the game up on the first built-in level; 1 on success.
#[no_mangle]
pub extern "C" fn init() -> u32 {
    let mut app = APP.0.borrow_mut();
    if app.is_none() {
        *app = App::new();
    }
    app.is_some() as u32
}

/// Game frames per second (the firmware's: 128).
#[no_mangle]
pub extern "C" fn frame_hz() -> u32 {
    FRAME_HZ
}

/// The LED matrix's width (the micro:bit's 5).
#[no_mangle]
pub extern "C" fn led_width() -> u32 {
    WIDTH as u32
}

/// The LED matrix's height.
#[no_mangle]
pub extern "C" fn led_height() -> u32 {
    HEIGHT as u32
}

/// Where the matrix's brightness values are (`led_width × led_height` bytes,
/// row by row, 0..=15), as the last [`tick`] drew them.
#[no_mangle]
pub extern "C" fn led_ptr() -> *const u8 {
    with_app(core::ptr::null(), |app| app.led.as_ptr())
}

/// One game frame at the current tilt: the loop's step ([`Player::tick`]).
/// Bit 0: an attempt finished; bit 1: a new attempt started.
#[no_mangle]
pub extern "C" fn tick() -> u32 {
    with_app(0, App::tick)
}

/// `n` frames (the browser test's fast-forward: the same step as [`tick`]);
/// stops early after a frame that finished an attempt if `stop_on_finish`.
/// Returns the frames played.
#[no_mangle]
pub extern "C" fn ticks(n: u32, stop_on_finish: u32) -> u32 {
    with_app(0, |app| {
        for done in 1..=n {
            if app.tick() & TICK_FINISHED != 0 && stop_on_finish != 0 {
                return done;
            }
        }
        n
    })
}

/// The page's tilt in milli-g: `right_mg` lowers the right edge (the marble
/// rolls right), `up_mg` lowers the far edge (it rolls up the screen). Made a
/// 1 g reading in the board frame by the library ([`Tilt::from_xz`]: x right,
/// z towards the player, so both signs flip as the keys' do in
/// `input::keys::KeyTilt`).
#[no_mangle]
pub extern "C" fn set_tilt(right_mg: i32, up_mg: i32) {
    with_app((), |app| {
        app.reading = Tilt::from_xz(right_mg.saturating_neg(), up_mg).reading_mg();
    })
}

/// The reading fed to the game last, x (mg, board frame).
#[no_mangle]
pub extern "C" fn reading_x() -> i32 {
    with_app(0, |app| app.player.reading()[0])
}

/// The reading fed to the game last, z (mg, board frame).
#[no_mangle]
pub extern "C" fn reading_z() -> i32 {
    with_app(0, |app| app.player.reading()[2])
}

/// Built-in levels.
#[no_mangle]
pub extern "C" fn level_count() -> u32 {
    LEVELS.len() as u32
}

/// Built-in level `index`'s name in the answer buffer; its length (0 if none).
#[no_mangle]
pub extern "C" fn builtin_name(index: u32) -> u32 {
    match LEVELS.get(index as usize) {
        Some(level) => answer(format_args!("{}", level.info.name)),
        None => 0,
    }
}

/// Plays built-in level `index` from its start; 1 on success.
#[no_mangle]
pub extern "C" fn select_level(index: u32) -> u32 {
    with_app(0, |app| {
        if index as usize >= LEVELS.len() {
            return 0;
        }
        let ok = app.start(&LEVELS, index as usize);
        if ok {
            app.source = Source::Builtin;
        }
        ok as u32
    })
}

/// Starts the level over.
#[no_mangle]
pub extern "C" fn restart() {
    with_app((), |app| {
        app.player.restart();
        app.follow_attempt();
    })
}

/// Moves on to the next level (after the last built-in: the first).
#[no_mangle]
pub extern "C" fn next_level() {
    with_app((), |app| {
        let level = app.player.level_index();
        app.player.next_level();
        if app.player.level_index() != level {
            app.ghost = None;
        }
        app.follow_attempt();
    })
}

/// Hands the board to the autopilot (`on` ≠ 0) or takes it back.
#[no_mangle]
pub extern "C" fn set_autopilot(on: u32) {
    with_app((), |app| app.player.set_autopilot(on != 0))
}

/// 1 while the autopilot plays.
#[no_mangle]
pub extern "C" fn autopilot() -> u32 {
    with_app(0, |app| app.player.autopilot() as u32)
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

/// Where answers are (see the module doc).
#[no_mangle]
pub extern "C" fn out_ptr() -> *const u8 {
    OUT.0.borrow().bytes.as_ptr()
}

/// Parses the `len` bytes of level text: 0 if it is a valid level, else the
/// length of its `line:column: message` in the answer buffer.
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
fn play_source(app: &mut App, source: &'static str, kind: Source) -> u32 {
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

/// 1 while the editor's level is the one in play.
#[no_mangle]
pub extern "C" fn level_is_custom() -> u32 {
    with_app(0, |app| app.is_custom_level() as u32)
}

/// The level in play: its built-in index, or the built-ins' count for the
/// editor's level.
#[no_mangle]
pub extern "C" fn level_index() -> u32 {
    with_app(0, |app| app.level_number())
}

/// The level in play's name in the answer buffer; its length.
#[no_mangle]
pub extern "C" fn level_name() -> u32 {
    with_app(0, |app| answer(format_args!("{}", app.level().info.name)))
}

/// The time limit of the level in play, seconds.
#[no_mangle]
pub extern "C" fn time_limit_s() -> u32 {
    with_app(0, |app| u32::from(app.level().info.time_limit_s))
}

/// Where the attempt stands: 0 playing, 1 won, 2 fell, 3 time up.
#[no_mangle]
pub extern "C" fn phase() -> u32 {
    with_app(0, |app| phase_code(app.player.game().phase()))
}

fn phase_code(phase: Phase) -> u32 {
    match phase {
        Phase::Playing => 0,
        Phase::Won => 1,
        Phase::Fell => 2,
        Phase::TimeUp => 3,
    }
}

/// Frames played in this attempt (the clock's idle ones included: the
/// simulated time `cargo sim` reports).
#[no_mangle]
pub extern "C" fn frames() -> u32 {
    with_app(0, |app| app.player.game().frames())
}

/// Frames on the level clock in this attempt (`Game::clock_frames`: it starts
/// at the first tilt that rolls a marble, on every board).
#[no_mangle]
pub extern "C" fn clock_frames() -> u32 {
    with_app(0, |app| app.player.game().clock_frames())
}

/// 1 while the page plays with event stepping, 0 with fixed steps.
#[no_mangle]
pub extern "C" fn stepping_events() -> u32 {
    with_app(0, |app| app.player.events() as u32)
}

/// Switches the stepper (`events` ≠ 0: event stepping, else fixed steps) and
/// starts the level in play over with it; 1 on success.
#[no_mangle]
pub extern "C" fn set_stepping(events: u32) -> u32 {
    with_app(0, |app| {
        let index = app.player.level_index();
        app.start_stepped(app.levels, index, events != 0) as u32
    })
}

/// The exact state's digest (`Session::state_hash`, as `cargo sim` prints it).
#[no_mangle]
pub extern "C" fn state_hash() -> u64 {
    with_app(0, |app| app.player.state_hash())
}

/// Attempts finished so far (see the `finished_*` functions for the last one).
#[no_mangle]
pub extern "C" fn finished_count() -> u32 {
    with_app(0, |app| app.finished.count)
}

/// The last finished attempt's level (as [`level_index`]).
#[no_mangle]
pub extern "C" fn finished_level() -> u32 {
    with_app(0, |app| app.finished.level)
}

/// 1 if the last finished attempt was on the editor's level.
#[no_mangle]
pub extern "C" fn finished_custom() -> u32 {
    with_app(0, |app| (app.finished.source == Source::Editor) as u32)
}

/// 1 if the last finished attempt was on a generated maze.
#[no_mangle]
pub extern "C" fn finished_generated() -> u32 {
    with_app(0, |app| {
        matches!(app.finished.source, Source::Generated(_)) as u32
    })
}

/// Bytes of the last finished attempt's ghost at [`record_ptr`]: a win played
/// whole from its first frame (0 for a loss, or a run longer than the buffer
/// holds). They stay there until the next attempt starts.
#[no_mangle]
pub extern "C" fn finished_ghost_len() -> u32 {
    with_app(0, |app| app.finished.ghost_len)
}

/// How the last finished attempt ended (as [`phase`]).
#[no_mangle]
pub extern "C" fn finished_phase() -> u32 {
    with_app(0, |app| phase_code(app.finished.phase))
}

/// Frames the last finished attempt took.
#[no_mangle]
pub extern "C" fn finished_frames() -> u32 {
    with_app(0, |app| app.finished.frames)
}

/// The last finished attempt's time on the level clock, frames.
#[no_mangle]
pub extern "C" fn finished_clock() -> u32 {
    with_app(0, |app| app.finished.clock)
}

/// `state_hash` at the end of the last finished attempt.
#[no_mangle]
pub extern "C" fn finished_hash() -> u64 {
    with_app(0, |app| app.finished.hash)
}

/// Tile columns of the level in play.
#[no_mangle]
pub extern "C" fn level_nx() -> u32 {
    with_app(0, |app| u32::from(app.level().info.nx))
}

/// Tile rows of the level in play.
#[no_mangle]
pub extern "C" fn level_nz() -> u32 {
    with_app(0, |app| u32::from(app.level().info.nz))
}

/// Storeys of the level in play (1 for a flat maze).
#[no_mangle]
pub extern "C" fn level_storeys() -> u32 {
    with_app(1, |app| u32::from(app.level().info.storeys).max(1))
}

/// What tile `(i, k)` of storey `storey` (0 the lowest) is: 0 floor, 1 wall,
/// 2 hole, 3 goal, 4 start, 5 outside (also for a storey the level lacks).
#[no_mangle]
pub extern "C" fn tile_kind(i: u32, k: u32, storey: u32) -> u32 {
    with_app(5, |app| {
        let level = app.level();
        let info = &level.info;
        if i >= u32::from(info.nx) || k >= u32::from(info.nz) || storey >= u32::from(info.storeys) {
            return 5;
        }
        let cell = Cell::new(i as u8, k as u8, storey as u8);
        let storey = storey as i32;
        let solid = |j| {
            level
                .tiles
                .is_solid(TileIndex::new(i as i32, 2 * storey + j, k as i32))
        };
        if solid(1) {
            1
        } else if !solid(0) {
            2
        } else if info.goals().contains(&cell) {
            3
        } else if info.starts().contains(&cell) {
            4
        } else {
            0
        }
    })
}

/// The storey marble `index` is on (0 the lowest; the one whose wall layer or
/// floor slab holds its centre, as the LED view and QEMU's maps take it).
#[no_mangle]
pub extern "C" fn marble_storey(index: u32) -> u32 {
    with_app(0, |app| {
        storey_of(app.player.game().world(), index, app.level().info.storeys)
    })
}

/// How much brighter the floor is drawn `elapsed` frames after the followed
/// marble dropped to a lower storey, out of [`drop_flash`]: the LED matrix's
/// flash (`render::drop_glow`), so the page shows the drop as the board does.
#[no_mangle]
pub extern "C" fn drop_glow(elapsed: u32) -> u32 {
    with_app(0, |app| {
        u32::from(render::drop_glow(
            elapsed,
            app.player.game().config().frame_log2,
        ))
    })
}

/// The drop flash's full strength ([`drop_glow`] right after a drop).
#[no_mangle]
pub extern "C" fn drop_flash() -> u32 {
    u32::from(render::DROP_FLASH)
}

/// Where tile column (or row: the layout is the same along both) `i` begins,
/// in mm; `i = nx` gives where the last one ends. Walls and cells differ in
/// width, so the page draws them from these edges.
#[no_mangle]
pub extern "C" fn tile_edge_mm(i: i32) -> f64 {
    with_app(0.0, |app| {
        let layout = &app.player.game().world().params().layout;
        layout.to_mm(layout.span_xz(i).0)
    })
}

/// A tile pitch in mm: the height between two storeys' floors (eq. 5).
#[no_mangle]
pub extern "C" fn pitch_mm() -> f64 {
    with_app(0.0, |app| {
        f64::from(app.player.game().world().params().layout.pitch_um) / 1000.0
    })
}

/// The marble radius, mm.
#[no_mangle]
pub extern "C" fn marble_radius_mm() -> f64 {
    with_app(0.0, |app| {
        f64::from(app.level().info.spec.radius_um) / 1000.0
    })
}

/// Marbles in the level.
#[no_mangle]
pub extern "C" fn marble_count() -> u32 {
    with_app(0, |app| app.player.game().world().marbles().len() as u32)
}

/// Coordinate `axis` (0 x right, 1 y up, 2 z towards the player) of marble
/// `index`'s centre, mm in the tile frame (0 for no such marble).
#[no_mangle]
pub extern "C" fn marble_mm(index: u32, axis: u32) -> f64 {
    with_app(0.0, |app| {
        marble_coord(app.player.game().world(), index, axis)
    })
}

/// 1 if marble `index` is out of play (fell).
#[no_mangle]
pub extern "C" fn marble_out(index: u32) -> u32 {
    with_app(1, |app| is_out(app.player.game().world(), index) as u32)
}

// ---------------------------------------------------------------------------
// Generated mazes.
// ---------------------------------------------------------------------------

/// `cargo sim -- --generate`'s default maze size (cells a side).
#[no_mangle]
pub extern "C" fn default_maze_size() -> u32 {
    u32::from(DEFAULT_MAZE_SIZE)
}

/// `cargo sim -- --generate`'s default storeys.
#[no_mangle]
pub extern "C" fn default_maze_storeys() -> u32 {
    u32::from(DEFAULT_MAZE_STOREYS)
}

/// `cargo sim -- --generate`'s default difficulty.
#[no_mangle]
pub extern "C" fn default_maze_difficulty() -> u32 {
    u32::from(DEFAULT_MAZE_DIFFICULTY)
}

/// Generates the maze of `seed` (`marble_rolling::game::generate`, as
/// `cargo sim -- --generate SEED --size SIZE --storeys STOREYS --difficulty
/// DIFFICULTY` does) and writes its level text into [`text_ptr`]'s buffer:
/// its length; or, negated, the length of the generator's error (an argument
/// out of its range, which it names) in the answer buffer.
#[no_mangle]
pub extern "C" fn generate_level(seed: u32, size: u32, storeys: u32, difficulty: u32) -> i32 {
    let maze = MazeArgs {
        seed,
        size: small(size),
        storeys: small(storeys),
        difficulty: small(difficulty),
    };
    match generated_text(maze) {
        Ok(len) => len as i32,
        Err(len) => -(len as i32),
    }
}

/// Plays the maze of [`generate_level`] alone (a win plays it again): 0, or
/// the length of the error in the answer buffer (the game goes on where it
/// was). Its text stays at [`source_text_ptr`].
#[no_mangle]
pub extern "C" fn play_generated(seed: u32, size: u32, storeys: u32, difficulty: u32) -> u32 {
    let maze = MazeArgs {
        seed,
        size: small(size),
        storeys: small(storeys),
        difficulty: small(difficulty),
    };
    let len = match generated_text(maze) {
        Ok(len) => len,
        Err(len) => return len,
    };
    let source = match checked(len) {
        Ok(source) => source,
        Err(error) => {
            return answer(format_args!(
                "internal error: generated maze {seed} does not parse: {error}"
            ))
        }
    };
    with_app(0, |app| play_source(app, source, Source::Generated(maze)))
}

/// The text of the editor's level or generated maze last played (see
/// [`source_text_len`]).
#[no_mangle]
pub extern "C" fn source_text_ptr() -> *const u8 {
    // SAFETY: only the address is taken; the page reads it between calls.
    unsafe { (*CUSTOM.0.get()).text.as_ptr() }
}

/// Bytes at [`source_text_ptr`].
#[no_mangle]
pub extern "C" fn source_text_len() -> u32 {
    // SAFETY: single thread (see `Single`); a read of a number between calls.
    unsafe { (*CUSTOM.0.get()).len as u32 }
}

/// The generated maze in play: its argument `what` (0 seed, 1 size, 2
/// storeys, 3 difficulty); 0 if the level in play is not a generated maze.
#[no_mangle]
pub extern "C" fn level_maze(what: u32) -> u32 {
    with_app(0, |app| match app.level_source() {
        Source::Generated(maze) => match what {
            0 => maze.seed,
            1 => u32::from(maze.size),
            2 => u32::from(maze.storeys),
            _ => u32::from(maze.difficulty),
        },
        _ => 0,
    })
}

/// 1 while a generated maze is in play.
#[no_mangle]
pub extern "C" fn level_is_generated() -> u32 {
    with_app(0, |app| {
        matches!(app.level_source(), Source::Generated(_)) as u32
    })
}

// ---------------------------------------------------------------------------
// The ghost: the best run of a level, replayed beside the next attempt.
// ---------------------------------------------------------------------------

/// Where the last win's ghost is ([`finished_ghost_len`] bytes).
#[no_mangle]
pub extern "C" fn record_ptr() -> *const u8 {
    RECORD.0.get().cast()
}

/// Where the page writes a stored ghost for [`load_ghost`].
#[no_mangle]
pub extern "C" fn ghost_in_ptr() -> *mut u8 {
    GHOST_IN.0.get().cast()
}

/// Bytes a ghost can have.
#[no_mangle]
pub extern "C" fn ghost_capacity() -> u32 {
    GHOST_CAPACITY as u32
}

/// Takes the `len` bytes at [`ghost_in_ptr`] as the ghost of the level in
/// play, if its replay (with the stepper in play) wins the level and ends on
/// the ghost's state hash; it then plays beside the attempt, from the
/// attempt's frame. 0, or the length of why not in the answer buffer (a
/// ghost of another build, level or stepper; the page then forgets it).
#[no_mangle]
pub extern "C" fn load_ghost(len: u32) -> u32 {
    with_app(0, |app| {
        // Nothing borrows GHOST from here on.
        app.ghost = None;
        // SAFETY: single thread; the page writes GHOST_IN only between calls.
        let input: &[u8; GHOST_CAPACITY] = unsafe { &*GHOST_IN.0.get() };
        let Some(bytes) = input.get(..len as usize) else {
            return answer(format_args!("a ghost is at most {GHOST_CAPACITY} bytes"));
        };
        // SAFETY: the ghost just dropped was the only reference into GHOST;
        // from here on the new one borrows it until the next load or clear.
        let stored: &'static mut [u8; GHOST_CAPACITY] = unsafe { &mut *GHOST.0.get() };
        stored[..bytes.len()].copy_from_slice(bytes);
        let stored: &'static [u8] = &stored[..bytes.len()];
        let ghost = match Ghost::parse(stored) {
            Ok(ghost) => ghost,
            Err(e) => return answer(format_args!("{e}")),
        };
        let level = *app.level();
        let config = app.player.game().config();
        let (Ok(mut check), Ok(mut session)) = (
            Session::<Fx>::new(level, config, SYNTHETIC_TILT),
            Session::<Fx>::new(level, config, SYNTHETIC_TILT),
        ) else {
            return answer(format_args!("the level cannot be set up for the ghost"));
        };
        match replay(&mut check, &ghost) {
            Ok((Phase::Won, true)) => {}
            Ok((phase, same)) => {
                return answer(format_args!(
                    "the ghost's replay ends {} after {} frames{}: not a run of this level",
                    match phase {
                        Phase::Won => "won",
                        Phase::Playing => "unfinished",
                        Phase::Fell => "fallen",
                        Phase::TimeUp => "timed out",
                    },
                    check.game().frames(),
                    if same { "" } else { " on another state hash" }
                ))
            }
            Err(e) => return answer(format_args!("{e}")),
        }
        session.tilt_mut().set_calibration(ghost.calibration);
        let mut run = GhostRun {
            session,
            ghost,
            readings: ghost.readings(),
            clock: check.game().clock_frames(),
        };
        run.follow(app.player.game().frames());
        app.ghost = Some(run);
        0
    })
}

/// Drops the ghost on show.
#[no_mangle]
pub extern "C" fn clear_ghost() {
    with_app((), |app| app.ghost = None)
}

/// 1 while a ghost plays beside the attempt.
#[no_mangle]
pub extern "C" fn ghost_active() -> u32 {
    with_app(0, |app| app.ghost.is_some() as u32)
}

/// The ghost's recorded run: `what` 0 its frames, 1 its time on the level
/// clock (frames); 0 without a ghost.
#[no_mangle]
pub extern "C" fn ghost_record(what: u32) -> u32 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| match what {
            0 => g.ghost.frames,
            _ => g.clock,
        })
    })
}

/// The state hash the ghost's run ended on (its header's).
#[no_mangle]
pub extern "C" fn ghost_record_hash() -> u64 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.ghost.state_hash)
    })
}

/// Frames the ghost has played so far in this attempt.
#[no_mangle]
pub extern "C" fn ghost_frames() -> u32 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.session.game().frames())
    })
}

/// Where the ghost's replay stands (as [`phase`]).
#[no_mangle]
pub extern "C" fn ghost_phase() -> u32 {
    with_app(0, |app| {
        app.ghost
            .as_ref()
            .map_or(0, |g| phase_code(g.session.game().phase()))
    })
}

/// The ghost's replay's state hash now: the record's once it has ended.
#[no_mangle]
pub extern "C" fn ghost_state_hash() -> u64 {
    with_app(0, |app| {
        app.ghost.as_ref().map_or(0, |g| g.session.state_hash())
    })
}

/// Marbles of the ghost (0 without one).
#[no_mangle]
pub extern "C" fn ghost_marble_count() -> u32 {
    with_app(0, |app| {
        app.ghost
            .as_ref()
            .map_or(0, |g| g.session.game().world().marbles().len() as u32)
    })
}

/// As [`marble_mm`], for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_mm(index: u32, axis: u32) -> f64 {
    with_app(0.0, |app| {
        app.ghost
            .as_ref()
            .map_or(0.0, |g| marble_coord(g.session.game().world(), index, axis))
    })
}

/// As [`marble_out`], for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_out(index: u32) -> u32 {
    with_app(1, |app| {
        app.ghost
            .as_ref()
            .is_none_or(|g| is_out(g.session.game().world(), index)) as u32
    })
}

/// As [`marble_storey`], for the ghost's marble `index`.
#[no_mangle]
pub extern "C" fn ghost_marble_storey(index: u32) -> u32 {
    with_app(0, |app| {
        let storeys = app.level().info.storeys;
        app.ghost
            .as_ref()
            .map_or(0, |g| storey_of(g.session.game().world(), index, storeys))
    })
}

#[cfg(target_arch = "wasm32")]
#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    // No panic is expected (inputs are checked, the library reports errors as
    // values); should one happen, the module traps and the page says so.
    core::arch::wasm32::unreachable()
}

/// The editor's messages, on the host (`cargo test -p marble-web`): what the
/// page shows for a level is `cargo sim -- --check`'s after the file name.
#[cfg(test)]
mod tests {
    use super::*;

    /// The answer [`check_level`] gives for `bytes` in the text buffer ("" for ok).
    fn checked_message(bytes: &[u8]) -> String {
        // SAFETY: one test, one thread: nothing else touches TEXT or OUT.
        let text: &mut [u8; TEXT_CAPACITY] = unsafe { &mut *TEXT.0.get() };
        text[..bytes.len()].copy_from_slice(bytes);
        let len = check_level(bytes.len() as u32) as usize;
        String::from_utf8(OUT.0.borrow().bytes[..len].to_vec()).unwrap()
    }

    /// The buffers are statics, and the harness runs tests in parallel: one at a time.
    static SERIAL: std::sync::Mutex<()> = std::sync::Mutex::new(());

    #[test]
    fn messages_name_line_column_bytes_and_ranges() {
        let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        assert_eq!(checked_message(b"---\n#####\n#S.G#\n#####\n"), "");
        assert_eq!(
            checked_message(b"name: a\n---\n#####\n#S\xffG#\n#####\n"),
            "4:3: not UTF-8 (byte 0xFF)"
        );
        // A character cut short at the end is reported at its first byte.
        assert_eq!(
            checked_message("name: é".as_bytes().split_last().unwrap().1),
            "1:7: not UTF-8 (byte 0xC3)"
        );
        assert_eq!(
            checked_message(b"restitution: 1.5\n---\n#####\n#S.G#\n#####\n"),
            "1:14: value out of range: restitution is 0 ..= 1"
        );
        assert_eq!(
            checked_message(&[b'a'; TEXT_CAPACITY]),
            "2:1: no `---` line between header and grid"
        );
        // One byte more than the buffer: the length alone says it.
        assert_eq!(
            {
                let len = check_level(TEXT_CAPACITY as u32 + 1) as usize;
                String::from_utf8(OUT.0.borrow().bytes[..len].to_vec()).unwrap()
            },
            format!("1:1: longer than {TEXT_CAPACITY} bytes")
        );
    }

    /// The page's round trip, natively (with overflow checks): a generated
    /// maze's autopilot win is recorded, handed back as the stored ghost,
    /// replayed beside the next attempt to the win's hash; a ghost with one
    /// byte changed is refused.
    #[test]
    fn ghost_of_a_generated_maze_replays_to_its_hash() {
        let _alone = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
        assert_eq!(init(), 1);
        assert_eq!(play_generated(7, 6, 2, 2), 0);
        // SAFETY: one test at a time; the page reads these buffers the same way.
        let text = unsafe {
            std::slice::from_raw_parts(source_text_ptr(), source_text_len() as usize).to_vec()
        };
        let maze = generate(7, 6, 2, 2).unwrap().to_string();
        assert_eq!(String::from_utf8(text).unwrap(), maze);
        set_autopilot(1);
        let count = finished_count();
        ticks(4000 * FRAME_HZ, 1);
        assert_eq!((finished_count(), finished_phase()), (count + 1, 1));
        let (frames, hash) = (finished_frames(), finished_hash());
        let len = finished_ghost_len() as usize;
        assert!(len > 24, "{len} bytes");
        // SAFETY: as above.
        let ghost = unsafe { std::slice::from_raw_parts(record_ptr(), len).to_vec() };
        set_autopilot(0);
        // The win's pause, then the maze again.
        ticks(FRAME_HZ + 1, 0);
        assert_eq!((level_is_generated(), super::frames()), (1, 0));
        let load = |bytes: &[u8]| {
            // SAFETY: as above.
            unsafe { std::ptr::copy_nonoverlapping(bytes.as_ptr(), ghost_in_ptr(), bytes.len()) };
            load_ghost(bytes.len() as u32)
        };
        assert_eq!(load(&ghost), 0);
        ticks(frames + 10, 0);
        assert_eq!(
            (ghost_phase(), ghost_frames(), ghost_state_hash()),
            (1, frames, hash)
        );
        // The player never tilted: its attempt still waits for the first roll.
        assert_eq!((phase(), clock_frames()), (0, 0));
        let mut other = ghost.clone();
        let last = other.len() - 1;
        other[last] ^= 1;
        assert_ne!(load(&other), 0);
        assert_eq!(ghost_active(), 0);
    }
}
