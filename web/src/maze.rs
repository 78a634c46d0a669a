//! Generated mazes: the core's generator with `cargo sim -- --generate`'s
//! defaults, its text in `TEXT`, played alone.

use core::fmt::Write;

use marble_rolling::game::generate::{generate, MAX_TEXT_BYTES};

use crate::game_loop::{with_app, MazeArgs, Source};
use crate::storage::{answer, checked, play_source, TEXT, TEXT_CAPACITY};

/// `cargo sim -- --generate SEED`'s defaults (`src/host/generated.rs`, which
/// the no_std build does not have): the same seed gives the same maze here.
/// The browser test holds the page to that text.
pub(crate) const DEFAULT_MAZE_SIZE: u8 = 6;

pub(crate) const DEFAULT_MAZE_STOREYS: u8 = 1;

pub(crate) const DEFAULT_MAZE_DIFFICULTY: u8 = 2;

/// A [`Write`] into a byte buffer that fails, rather than cut the text, when
/// it is full (a cut level text would be another level).
pub(crate) struct Cursor<'a> {
    pub(crate) bytes: &'a mut [u8],
    pub(crate) len: usize,
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
pub(crate) fn generated_text(maze: MazeArgs) -> Result<u32, u32> {
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
pub(crate) fn small(n: u32) -> u8 {
    u8::try_from(n).unwrap_or(u8::MAX)
}

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
/// DIFFICULTY` does) and writes its level text into
/// [`text_ptr`](crate::storage::text_ptr)'s buffer: its length; or, negated,
/// the length of the generator's error (an argument out of its range, which
/// it names) in the answer buffer.
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
/// was). Its text stays at [`source_text_ptr`](crate::storage::source_text_ptr).
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
