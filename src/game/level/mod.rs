//! The text level format, parsed by one `const fn` at compile time (built-in levels
//! live in flash, and a malformed one fails the build naming its line and column)
//! and at run time (host tools get the same error as a value — never a panic).
//!
//! ```text
//! name: Corridor            ← header: `key: value` lines, all optional
//! effects: rolling, friction
//! ---                       ← end of header
//! #########                 ← grid: one character per tile column [i, *, k]
//! #S.....G#
//! #########
//! ```
//!
//! | key | meaning | default |
//! |-----|---------|---------|
//! | `name` | shown by tools | `untitled` |
//! | `short_mm` | short tile width `s` (walls, posts), 0.001 ..= 100 | `2` |
//! | `long_mm` | long tile width `l` (cells), 0.001 ..= 100; pitch `s + l` 1 ..= 100 | `10` |
//! | `marble_radius_mm` | marble radius, 0.001 ..= 100 and `2r < l` | `3.5` |
//! | `restitution` | `e` in eq. 1, 0 ..= 1 | `0.5` |
//! | `effects` | the effects that are on: a comma list of `rolling`, `friction`, `board_motion`; empty or `none` for none | `rolling` |
//! | `rolling_resistance` | rolling-resistance coefficient (with `friction`) | `0.01` |
//! | `time_limit_s` | seconds before the attempt times out, 1 ..= 3600 | `60` |
//!
//! `effects` is the exact list of what is on: `effects: friction` slides with
//! friction (no rolling), `effects:` alone or `effects: none` is a marble that
//! slides without friction (it accelerates at `g·sinθ`, not the rolling `5/7` of
//! it); without the key a level rolls. A later `effects` line replaces an earlier one.
//!
//! Numbers take up to three decimals (`rolling_resistance` six). Grid characters:
//! `#` wall (a tile in layer `j = 1` on top of the floor), `.` floor, `O` hole (no
//! floor tile), `S` marble start, `G` goal. Column `i` is the character's position,
//! row `k` the line's; even indices are short tiles, odd ones long, so `S` and `G`
//! must sit at odd column and odd row (a long×long cell). Holes and several `S` switch
//! on the `holes` and `marbles` effects. All rows have the same length, at most 127.
//!
//! # Storeys
//!
//! A maze of several storeys (eq. 5 along y': storey `n` is the floor slab
//! `j = 2n` and the wall layer `j = 2n + 1` on it, one pitch above storey
//! `n − 1`) lists them **top to bottom**, each a grid as above, separated by a
//! line `===`. Every storey has the first one's rows and columns. A storey's
//! floor is the ceiling of the storey below; the top storey has the lid. `O` is a
//! hole into the storey below (in the lowest storey: out of the maze), so it may
//! not lie over a wall of the storey below (the marble would sink onto the
//! wall's top, 2 mm down, and stick there). `S` and `G` may be on any storey; a
//! maze of several storeys always moves in 3-D (the `holes` effect).
//!
//! ```text
//! ---
//! #######                   ← top storey (here storey 1)
//! #S.O..#
//! #######
//! ===
//! #######                   ← the storey below (storey 0)
//! #...G.#
//! #######
//! ```
//!
//! The parser refuses what the physics setup ([`Params::new`]) would refuse of a
//! header (pitch `s + l` 1 ..= 100 mm, `2r < l`), at the value that breaks the rule
//! (the later of the keys involved). A leading UTF-8 byte-order mark is skipped
//! (columns on line 1 count from the first character after it).
//!
//! Text read as bytes (a file, the browser's buffer) goes through [`text`] first:
//! bytes that are not UTF-8 are an error at their line and column
//! ([`LevelErrorKind::NotUtf8`]), like any other.
//!
//! [`Params::new`]: crate::physics::world::Params::new

mod builtins;
mod errors;
mod grid;
mod header;
mod scan;

use crate::physics::geometry::grid::{words_for, TileGrid, Tiles, MAX_STOREYS};
pub use crate::physics::geometry::tiles::{MAX_PITCH_UM, MIN_PITCH_UM};
use crate::physics::world::PhysicsSpec;

#[doc(hidden)]
pub use builtins::{__const_panic, name_bytes, BuiltinGrid};
pub use errors::{text, LevelError, LevelErrorKind, NumberKey};
use grid::{grid, Grid};
use header::{header, Header};
use scan::{grid_shape, grid_start, without_bom};

/// Most marbles a level may start (several `S`).
pub const MAX_MARBLES: usize = 4;
/// Most goal cells a level may have.
pub(crate) const MAX_GOALS: usize = 4;

/// A long×long cell on a storey (odd `i`, odd `k`; storey 0 is the lowest):
/// where a marble starts or a goal lies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cell {
    /// Column along x'.
    pub i: u8,
    /// Row along z'.
    pub k: u8,
    /// Storey (its floor slab is layer `j = 2·storey`).
    pub storey: u8,
}

impl Cell {
    /// Cell `(i, k)` on storey `storey`.
    pub const fn new(i: u8, k: u8, storey: u8) -> Self {
        Cell { i, k, storey }
    }
}

/// Everything about a level except its tiles.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LevelInfo<'a> {
    /// The level's name.
    pub name: &'a str,
    /// Physics parameters and effects.
    pub spec: PhysicsSpec,
    /// Seconds before the attempt times out.
    pub time_limit_s: u16,
    /// Tiles along x' (columns).
    pub nx: u8,
    /// Tiles along z' (rows).
    pub nz: u8,
    /// Storeys (1 ..= [`MAX_STOREYS`]).
    pub storeys: u8,
    starts: [Cell; MAX_MARBLES],
    n_starts: u8,
    goals: [Cell; MAX_GOALS],
    n_goals: u8,
}

impl LevelInfo<'_> {
    /// The same header under `name`: a level kept after the text it was parsed
    /// from is gone (a generated maze, whose text is written, parsed and
    /// dropped) borrows its name from a buffer of its own.
    pub(crate) const fn renamed<'n>(self, name: &'n str) -> LevelInfo<'n> {
        LevelInfo {
            name,
            spec: self.spec,
            time_limit_s: self.time_limit_s,
            nx: self.nx,
            nz: self.nz,
            storeys: self.storeys,
            starts: self.starts,
            n_starts: self.n_starts,
            goals: self.goals,
            n_goals: self.n_goals,
        }
    }

    /// Start cells, in reading order (top storey first).
    pub fn starts(&self) -> &[Cell] {
        &self.starts[..self.n_starts as usize]
    }
    /// Goal cells, in reading order (top storey first).
    pub fn goals(&self) -> &[Cell] {
        &self.goals[..self.n_goals as usize]
    }
}

/// A parsed level: header and owned tiles (`WORDS` words of occupancy bits).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Level<'a, const WORDS: usize> {
    /// The header and the cells that matter to the rules.
    pub info: LevelInfo<'a>,
    /// `tile_state`.
    pub grid: TileGrid<WORDS>,
}

/// A borrowed level: what the game, the renderer and the autopilot take.
#[derive(Clone, Copy, Debug)]
pub struct LevelView<'a> {
    /// Header and cells.
    pub info: LevelInfo<'a>,
    /// Tiles.
    pub tiles: Tiles<'a>,
}

impl<'a, const WORDS: usize> Level<'a, WORDS> {
    /// The borrowed view.
    pub const fn view(&'a self) -> LevelView<'a> {
        LevelView {
            info: self.info,
            tiles: self.grid.view(),
        }
    }
}

/// Occupancy words a level needs (`0` when its grid is malformed; `parse` then reports
/// why). Use it to size [`Level`] for a `const` level.
pub const fn words_needed(src: &str) -> usize {
    let b = without_bom(src.as_bytes());
    let Some(grid_start) = grid_start(b) else {
        return 1;
    };
    let (nx, nz, storeys) = grid_shape(b, grid_start);
    let storeys = if storeys == 0 {
        1
    } else if storeys > MAX_STOREYS {
        MAX_STOREYS
    } else {
        storeys
    };
    let w = words_for(
        if nx == 0 { 1 } else { nx },
        2 * storeys,
        if nz == 0 { 1 } else { nz },
    );
    if w == 0 {
        1
    } else {
        w
    }
}

/// Parses a level. `WORDS` must be at least [`words_needed`]`(src)`.
pub const fn parse<const WORDS: usize>(src: &str) -> Result<Level<'_, WORDS>, LevelError> {
    let b = without_bom(src.as_bytes());
    let h: Header<'_> = match header(b) {
        Ok(h) => h,
        Err(e) => return Err(e),
    };
    let g: Grid<WORDS> = match grid(b, h.grid_at, h.grid_line) {
        Ok(g) => g,
        Err(e) => return Err(e),
    };
    let mut effects = h.effects;
    effects.holes = g.holes;
    effects.marbles = g.n_starts > 1;
    let mut spec = h.spec;
    spec.effects = effects;
    Ok(Level {
        info: LevelInfo {
            name: h.name,
            spec,
            time_limit_s: h.time_limit_s,
            nx: g.nx as u8,
            nz: g.nz as u8,
            storeys: g.storeys as u8,
            starts: g.starts,
            n_starts: g.n_starts as u8,
            goals: g.goals,
            n_goals: g.n_goals as u8,
        },
        grid: g.tiles,
    })
}
