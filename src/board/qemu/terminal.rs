//! The QEMU board's screen on its UART terminal: the virtual matrix's perceived
//! frame ([`super::virtual_matrix`]) drawn with ANSI escapes (256-colour greys and
//! shading characters), the game's status below it (level, phase, clock, tilt,
//! the record) and, on a level with storeys, the storey maps. Apart from the
//! virtual matrix because this is the part that knows the game: the matrix
//! models LEDs and hands this screen what a viewer would see.
//!
//! # Storeys
//!
//! The matrix shows one storey, the one holding the marble the view follows.
//! On a level with storeys (feature `storeys`) the terminal also draws every
//! storey as a map below the status lines, side by side, top storey first
//! (`storey 1 (top)`, `storey 0`; storey 0 is the lowest): two characters a
//! tile, with the matrix's shading characters and greys for the brightness
//! the matrix would give the tile ([`storey_tile`]: walls, floor, holes dark,
//! the goal blinking as on the matrix), and each marble in play
//! ([`Status::marbles`]) a full-brightness `█` on its own storey's map. The
//! maps together stay within `MAPS_COLUMNS` (100) columns and each shows at
//! most `MAP_ROWS` (9) tile rows, so that the screen fits a 100×30
//! terminal: a maze too large for that (never a built-in one; up to 23 tiles
//! across fit on two storeys, 15 on three, 11 on four) shows the same window
//! of tiles on every storey, centred on the followed marble and clamped to
//! the maze (`map_window`). Every draw ends by clearing the rest of the
//! screen, so the maps of a level before do not linger under a one-storey
//! level's screen, which draws none.
//!
//! [`storey_tile`]: crate::render::storey_tile
//! [`Status::marbles`]: crate::player::Status

use core::fmt::Write as _;

use super::virtual_matrix::Screen;
use super::{HEIGHT, WIDTH};
#[cfg(feature = "storey-maps")]
use crate::game::endless::{MazeArgs, MazeSlot};
use crate::game::level::LevelView;
use crate::game::levels::LEVELS;
use crate::input::axes::AccelMg;
use crate::matrix::output::Console;
use crate::matrix::{Brightness, Frame};
use crate::player::Status;
use crate::player::FRAME_HZ;
#[cfg(feature = "storey-maps")]
pub use storey_maps::{map_window, MapWindow, MAPS_COLUMNS, MAP_ROWS};

/// One picture of the virtual matrix.
type DisplayFrame = Frame<WIDTH, HEIGHT>;

/// The terminal screen: the matrix, with the game's status (as `status` reads
/// it, e.g. from the game task's link) below it, drawn on `C` when either
/// changed.
pub struct Terminal<C: Console> {
    console: C,
    status: fn() -> Status,
    drawn: Option<(DisplayFrame, Status)>,
    /// The generated maze on show, made again from its arguments for its
    /// storey maps (the game's own is the game task's).
    #[cfg(feature = "storey-maps")]
    maze: ShownMaze,
}

impl<C: Console> Terminal<C> {
    /// A screen on `console`, the game's status read by `status`.
    pub fn new(console: C, status: fn() -> Status) -> Self {
        Self {
            console,
            status,
            drawn: None,
            #[cfg(feature = "storey-maps")]
            maze: ShownMaze {
                slot: MazeSlot::new(super::MAZE_REACH),
                made: None,
            },
        }
    }
}

impl<C: Console> Screen for Terminal<C> {
    fn show(&mut self, frame: &DisplayFrame) {
        let mut status = (self.status)();
        // Redraw for whole tenths of a second only.
        status.frames -= status.frames % (FRAME_HZ / 10).max(1);
        let first = self.drawn.is_none();
        if self.drawn != Some((*frame, status)) {
            #[cfg(feature = "storey-maps")]
            let maze = status.maze.and_then(|args| self.maze.show(args));
            #[cfg(not(feature = "storey-maps"))]
            let maze = None;
            draw(&mut self.console, frame, &status, maze.as_ref(), first);
            self.drawn = Some((*frame, status));
        }
    }
}

/// The generated maze on show, made again here from [`Status::maze`].
#[cfg(feature = "storey-maps")]
struct ShownMaze {
    /// As the game's ([`super::MAZE_REACH`]).
    slot: MazeSlot<{ super::MAZE_REACH.words() }, { super::MAZE_REACH.text_bytes() }>,
    /// What `slot` holds.
    made: Option<MazeArgs>,
}

#[cfg(feature = "storey-maps")]
impl ShownMaze {
    /// The maze of `args`, made only when it is not the one here: once per
    /// level, not once per picture.
    fn show(&mut self, args: MazeArgs) -> Option<LevelView<'_>> {
        if self.made != Some(args) {
            self.made = self.slot.make(args).is_ok().then_some(args);
        }
        self.slot.view()
    }
}

/// `core::fmt` adapter for a [`Console`].
struct Out<'a, C: Console>(&'a mut C);

impl<C: Console> core::fmt::Write for Out<'_, C> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write(s.as_bytes());
        Ok(())
    }
}

/// 256-colour palette index for a brightness: greys 233..=255, 232 for off.
pub fn grey(level: Brightness) -> u8 {
    match level {
        0 => 232,
        level => 233 + ((u16::from(level.min(15)) - 1) * 22 / 14) as u8,
    }
}

/// Shading character for a brightness (so plain-text captures show it too):
/// with the renderer's levels, floor (1) `░`, wall (3) `▒`, lit goal (8)
/// `▓`, marble `█`.
pub fn shade(level: Brightness) -> &'static str {
    match level {
        0 => "\u{b7}",
        1..=2 => "\u{2591}",
        3..=5 => "\u{2592}",
        6..=10 => "\u{2593}",
        _ => "\u{2588}",
    }
}

/// Draws `frame` and a status line at the top left of the terminal; `clear`
/// first clears the screen and hides the cursor. `maze` is the level on show
/// when it is not a built-in one (a generated maze of the endless run), for its
/// name and its storey maps.
pub fn draw<C: Console>(
    console: &mut C,
    frame: &DisplayFrame,
    status: &Status,
    maze: Option<&LevelView<'_>>,
    clear: bool,
) {
    let mut out = Out(console);
    if clear {
        out.0.write(b"\x1b[2J\x1b[?25l");
    }
    out.0.write(b"\x1b[H");
    let _ = write!(out, "  Marble Rolling (QEMU virtual matrix)\x1b[K\r\n\r\n");
    for row in frame.rows() {
        out.0.write(b"    ");
        for &level in row {
            let s = shade(level);
            let _ = write!(out, "\x1b[38;5;{}m{}{}", grey(level), s, s);
        }
        out.0.write(b"\x1b[0m\x1b[K\r\n");
    }
    let tenths = status.frames * 10 / FRAME_HZ.max(1);
    let AccelMg { x, z, .. } = status.reading;
    let number = usize::from(status.level) + 1;
    // Past the built-in levels, the endless run's generated mazes.
    let _ = match (LEVELS.get(usize::from(status.level)), maze) {
        (Some(level), _) => write!(
            out,
            "\r\n  level {}/{} {}",
            number,
            LEVELS.len(),
            level.info.name
        ),
        (None, Some(maze)) => write!(out, "\r\n  level {} {}", number, maze.info.name),
        (None, None) => write!(out, "\r\n  level {} (a generated maze)", number),
    };
    let _ = write!(
        out,
        ": {} {}.{} s{}{}\x1b[K\r\n  tilt x {} z {} mg\x1b[K\r\n",
        status.phase.as_str(),
        tenths / 10,
        tenths % 10,
        if status.autopilot {
            "  (autopilot)"
        } else {
            ""
        },
        if status.muted { "  (sound off)" } else { "" },
        x,
        z
    );
    // The level's record (feature `records`), and the news of a new one.
    #[cfg(feature = "records")]
    {
        match status.best {
            Some(frames) => {
                let cs = frames.saturating_mul(100) / FRAME_HZ.max(1);
                let _ = write!(out, "  best {}.{:02} s", cs / 100, cs % 100);
            }
            None => {
                let _ = write!(out, "  no record yet");
            }
        }
        let news = if status.new_record {
            "  NEW RECORD!"
        } else {
            ""
        };
        let _ = write!(out, "{news}\x1b[K\r\n");
    }
    let _ = write!(
        out,
        "  arrows/WASD tilt, space level, c calibrate, r restart, n next level,\x1b[K\r\n  p autopilot, m sound, q quit\x1b[K\r\n"
    );
    #[cfg(feature = "storey-maps")]
    if let Some(level) = LEVELS.get(usize::from(status.level)).or(maze) {
        if level.info.storeys > 1 {
            storey_maps::draw(&mut out, level, status);
        }
    }
    // Whatever a taller screen left below (the storey maps of the level
    // before) goes.
    out.0.write(b"\x1b[J");
}

/// The storey maps of a level with storeys (see the module doc).
#[cfg(feature = "storey-maps")]
mod storey_maps {
    use core::fmt::Write as _;

    use super::{grey, shade, Out, HEIGHT};
    use crate::game::level::LevelView;
    use crate::matrix::output::Console;
    use crate::matrix::MAX_BRIGHTNESS;
    use crate::player::Status;
    use crate::player::FRAME_HZ;
    use crate::render::{blink_on, storey_tile};

    /// How wide the storey maps may be together, in terminal columns with their
    /// indent: a 100-column terminal shows them whole.
    pub const MAPS_COLUMNS: usize = 100;
    /// Most tile rows a storey map shows: the matrix's, so that the whole screen
    /// fits 30 lines.
    pub const MAP_ROWS: usize = HEIGHT;
    /// The maps' indent (the matrix's), in columns.
    const MAP_INDENT: usize = 4;
    /// Columns between two maps.
    const MAP_GAP: usize = 2;
    /// The widest map title, `storey 3 (top)`.
    const TITLE_COLUMNS: usize = 14;

    /// The tiles the storey maps show, the same on every storey: `(i0, k0)` the
    /// first tile, `(w, h)` tiles across and down.
    #[derive(Clone, Copy, Debug, PartialEq, Eq)]
    pub struct MapWindow {
        /// First tile column shown.
        pub i0: i32,
        /// First tile row shown.
        pub k0: i32,
        /// Tile columns shown.
        pub w: i32,
        /// Tile rows shown.
        pub h: i32,
    }

    /// The window of `level`'s maps (`storeys` of them side by side, two
    /// columns a tile): the whole storey when the maps fit [`MAPS_COLUMNS`]
    /// columns and [`MAP_ROWS`] rows, else as many tiles as fit, centred on the
    /// marble the view follows (`focus`, its tile) and clamped to the maze.
    pub fn map_window(nx: u8, nz: u8, storeys: u8, focus: Option<(i32, i32)>) -> MapWindow {
        let n = usize::from(storeys.max(1));
        let per_map = ((MAPS_COLUMNS - MAP_INDENT) / n).saturating_sub(MAP_GAP);
        let w = i32::from(nx).min((per_map / 2).max(1) as i32);
        let h = i32::from(nz).min(MAP_ROWS as i32);
        let (fi, fk) = focus.unwrap_or((0, 0));
        let start = |f: i32, size: i32, all: i32| (f - size / 2).clamp(0, (all - size).max(0));
        MapWindow {
            i0: start(fi, w, i32::from(nx)),
            k0: start(fk, h, i32::from(nz)),
            w,
            h,
        }
    }

    /// Writes `n` spaces.
    fn pad<C: Console>(out: &mut Out<'_, C>, n: usize) {
        for _ in 0..n {
            out.0.write(b" ");
        }
    }

    /// Every storey of `level` as a map below the status lines, side by side,
    /// top storey first, each titled and drawn with the matrix's characters
    /// ([`storey_tile`]), the marbles in play at full brightness on their own
    /// storey's map.
    pub(super) fn draw<C: Console>(out: &mut Out<'_, C>, level: &LevelView<'_>, status: &Status) {
        let storeys = i32::from(level.info.storeys);
        let focus = status.marbles.iter().flatten().next().map(|m| m.tile());
        let window = map_window(level.info.nx, level.info.nz, level.info.storeys, focus);
        let map_columns = (2 * window.w as usize).max(TITLE_COLUMNS);
        // On the level clock (the status's frames): the goal shows lit until
        // the first roll, then blinks.
        let blink = blink_on(status.frames, FRAME_HZ.trailing_zeros());
        // Titles, top storey first.
        out.0.write(b"\x1b[K\r\n");
        pad(out, MAP_INDENT);
        for storey in (0..storeys).rev() {
            let suffix = if storey == storeys - 1 { " (top)" } else { "" };
            let _ = write!(out, "storey {storey}{suffix}");
            if storey > 0 {
                // `storey N`: one digit (at most 4 storeys).
                pad(out, map_columns + MAP_GAP - "storey 0".len() - suffix.len());
            }
        }
        out.0.write(b"\x1b[K\r\n");
        for k in window.k0..window.k0 + window.h {
            pad(out, MAP_INDENT);
            for storey in (0..storeys).rev() {
                for i in window.i0..window.i0 + window.w {
                    let marble = status
                        .marbles
                        .iter()
                        .flatten()
                        .any(|m| i32::from(m.storey) == storey && m.tile() == (i, k));
                    let level = if marble {
                        MAX_BRIGHTNESS
                    } else {
                        storey_tile(level, i, k, storey, blink)
                    };
                    let s = shade(level);
                    let _ = write!(out, "\x1b[38;5;{}m{}{}", grey(level), s, s);
                }
                out.0.write(b"\x1b[0m");
                if storey > 0 {
                    pad(out, map_columns - 2 * window.w as usize + MAP_GAP);
                }
            }
            out.0.write(b"\x1b[K\r\n");
        }
    }
}

/// Leaves the terminal usable: default colours, cursor shown, new line.
pub fn restore_terminal<C: Console>(console: &mut C) {
    console.write(b"\x1b[0m\x1b[?25h\r\n");
}
