//! Generated mazes: a level from a seed, the same text on every target, and always
//! winnable.
//!
//! Ten built-in levels are played through in minutes; a generator gives an endless
//! supply. A seed has to give the same maze on the host, the Cortex-M4, the
//! Cortex-M0 and in the browser, so everything here is integer arithmetic on a
//! reproducible generator ([`XorShiftRng`] from `rand_xorshift`: 32-bit operations
//! only, cheap on the M0, and its output is fixed by the crate's contract), and
//! nothing allocates: a [`Maze`] is a fixed array of cell bits (under 1 KiB), and
//! its level text is written by `Display`.
//!
//! # How
//!
//! Each storey is a square of `size × size` cells, carved top storey first into a
//! *perfect maze* (a spanning tree of the cells: one way between any two) by a
//! depth-first search with a fixed stack. The search starts where the marble
//! enters the storey: the start on the top storey, the cell under the hole above
//! on the others. A cell's depth in that search is its distance from the entry
//! along the tree, so the exit needs no extra search: a dead end (a leaf)
//! chosen at random among the deepest half. The exit is a hole (`O`) into the
//! storey below, or on the lowest storey the goal.
//!
//! Difficulty (0 ..= [`MAX_DIFFICULTY`]) adds, in turn: rolling resistance
//! (`friction`, from 1); pits (holes out of the maze, from 2: on the lowest
//! storey, in dead ends off the way to the goal, one more every two levels);
//! a second marble (from 4) and a third (from 7) in dead ends of the top storey
//! (on mazes of up to `MAX_SIZE_FOR_MARBLES` cells a side);
//! `board_motion` (from 6, on one or two storeys: see `Maze::board_motion`); and a time limit that shrinks from three to one and a
//! half times the autopilot's measured pace (see `Maze::time_limit_s`).
//!
//! # Guarantees
//!
//! * **Deterministic:** the same `(seed, size, storeys, difficulty)` gives the same
//!   text on every target (`tests/generate.rs` pins a few).
//! * **Valid:** the text parses ([`crate::game::level::parse`]) and the physics
//!   sets it up: walls close the border, holes lie over cells (never over a wall
//!   of the storey below), starts and goal sit on cells.
//! * **Winnable:** by construction (each storey is a tree, so its exit is reachable
//!   from its entry without crossing its own hole or a pit, which are dead ends),
//!   and checked before a maze is returned: a flood over the cells from every
//!   start ([`Maze::every_start_reaches_the_goal`]) moves along open links, never
//!   into a pit, and from a hole only down. Independently, the host tests parse
//!   the text, plan it with the autopilot and let it win, with both steppers.
//!
//! Here the maze's cells and the order of the work; carving a storey is
//! `generate/carve.rs`, the reachability check `generate/check.rs`, the level
//! text `generate/text.rs`.

use core::fmt;

use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

use crate::physics::geometry::grid::MAX_STOREYS;

mod carve;
mod check;
mod text;

pub(crate) use text::write_name;

/// The fewest cells along a side.
pub const MIN_SIZE: u8 = 2;
/// The most cells along a side: 31 tiles, within the autopilot's plan on four
/// storeys, and a level text under 4 KiB ([`MAX_TEXT_BYTES`]).
pub const MAX_SIZE: u8 = 15;
/// The hardest difficulty.
pub const MAX_DIFFICULTY: u8 = 9;
/// The largest maze (cells a side) that gets more than one marble. Two marbles
/// farther apart than about 11 pitches overflow the event stepper's
/// marble–marble search in the firmware's `I8F24` (a square of the distance
/// passes its range of 128: `survey` in `tests/generate.rs` shows debug builds
/// panicking from size 9 on, event steps only), and on larger mazes the
/// autopilot loses some three-marble runs on time. Up to 7 it wins every one.
pub(crate) const MAX_SIZE_FOR_MARBLES: u8 = 7;
/// The longest level text [`Maze`] writes (four storeys of the largest size).
pub const MAX_TEXT_BYTES: usize = text_bytes(MAX_SIZE, MAX_STOREYS as u8);

/// The longest level text of a maze of `size` cells a side on `storeys`
/// storeys: a header of at most 128 bytes (the longest, every number at its
/// largest and every effect on, is 97), then per storey its rows of `2 size +
/// 1` tiles and a newline, and the `===` line.
pub const fn text_bytes(size: u8, storeys: u8) -> usize {
    let tiles = 2 * size as usize + 1;
    128 + storeys as usize * (tiles * (tiles + 1) + 4)
}

const MAX_CELLS: usize = MAX_SIZE as usize * MAX_SIZE as usize;

// Cell bits.
/// Open towards the cell at `+x'` (no wall on the short tile between).
const EAST: u8 = 1;
/// Open towards the cell at `+z'`.
const SOUTH: u8 = 2;
/// No floor: a hole into the storey below, or on the lowest storey a pit.
const HOLE: u8 = 4;
const START: u8 = 8;
const GOAL: u8 = 16;
/// On the way from the storey's entry to its exit.
const PATH: u8 = 32;

/// Why [`generate`] refused its arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GenerateError {
    /// `size` outside [`MIN_SIZE`] ..= [`MAX_SIZE`].
    Size(u8),
    /// `storeys` outside 1 ..= 4 (1 without the feature `storeys`).
    Storeys(u8),
    /// `difficulty` above [`MAX_DIFFICULTY`].
    Difficulty(u8),
    /// The maze failed its own reachability check: a bug in the generator, never
    /// a maze handed out.
    Unwinnable,
}

impl fmt::Display for GenerateError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            GenerateError::Size(n) => write!(
                f,
                "maze size {n} is outside {MIN_SIZE} ..= {MAX_SIZE} cells a side"
            ),
            GenerateError::Storeys(n) => write!(
                f,
                "{n} storeys is outside 1 ..= {}",
                if STOREYS { MAX_STOREYS } else { 1 }
            ),
            GenerateError::Difficulty(n) => {
                write!(f, "difficulty {n} is outside 0 ..= {MAX_DIFFICULTY}")
            }
            GenerateError::Unwinnable => {
                f.write_str("internal error: the generated maze failed its reachability check")
            }
        }
    }
}

const STOREYS: bool = cfg!(feature = "storeys");

/// A generated maze: its cells, storey by storey, and what the level text says of
/// it. `Display` writes the level text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Maze {
    seed: u32,
    size: u8,
    storeys: u8,
    difficulty: u8,
    /// Cell bits, `[storey][cz · size + cx]`, storey 0 the lowest.
    cells: [[u8; MAX_CELLS]; MAX_STOREYS],
    /// Cells from the start to the goal (a drop counts as one), and the turns
    /// on the way.
    path_cells: u16,
    turns: u16,
}

/// The maze of `size × size` cells on `storeys` storeys that `seed` gives, at
/// `difficulty` (see the module documentation).
pub fn generate(seed: u32, size: u8, storeys: u8, difficulty: u8) -> Result<Maze, GenerateError> {
    let mut maze = Maze::EMPTY;
    maze.generate(seed, size, storeys, difficulty)?;
    Ok(maze)
}

impl Maze {
    /// No maze yet: what [`Maze::generate`] fills in.
    pub(crate) const EMPTY: Maze = Maze {
        seed: 0,
        size: 0,
        storeys: 0,
        difficulty: 0,
        cells: [[0; MAX_CELLS]; MAX_STOREYS],
        path_cells: 0,
        turns: 0,
    };

    /// [`generate`] in place: this maze becomes the one its arguments give (on
    /// an error, no maze: [`Maze::EMPTY`]). A board makes its mazes this way,
    /// so that the 912 bytes are on its stack once, not copied out of the
    /// generator. Out of line, for the same reason.
    #[inline(never)]
    pub(crate) fn generate(
        &mut self,
        seed: u32,
        size: u8,
        storeys: u8,
        difficulty: u8,
    ) -> Result<(), GenerateError> {
        *self = Maze::EMPTY;
        if !(MIN_SIZE..=MAX_SIZE).contains(&size) {
            return Err(GenerateError::Size(size));
        }
        let most = if STOREYS { MAX_STOREYS as u8 } else { 1 };
        if !(1..=most).contains(&storeys) {
            return Err(GenerateError::Storeys(storeys));
        }
        if difficulty > MAX_DIFFICULTY {
            return Err(GenerateError::Difficulty(difficulty));
        }
        (self.seed, self.size, self.storeys, self.difficulty) = (seed, size, storeys, difficulty);
        let mut rng = XorShiftRng::seed_from_u64(u64::from(seed));
        let n = usize::from(size) * usize::from(size);
        let mut depth = [0u8; MAX_CELLS];
        let mut entry = below(&mut rng, n as u32) as usize;
        for storey in (0..usize::from(storeys)).rev() {
            self.carve(storey, entry, &mut depth, &mut rng);
            let exit = self.pick_dead_end(storey, entry, &depth, &mut rng);
            self.mark_path(storey, exit, &depth);
            let top = storey + 1 == usize::from(storeys);
            if top {
                self.cells[storey][entry] |= START;
                self.add_marbles(storey, &mut rng);
            }
            if storey == 0 {
                self.cells[storey][exit] |= GOAL;
                self.add_pits(&mut rng);
            } else {
                self.cells[storey][exit] |= HOLE;
                self.path_cells += 1;
            }
            entry = exit;
        }
        if !self.every_start_reaches_the_goal() {
            *self = Maze::EMPTY;
            return Err(GenerateError::Unwinnable);
        }
        Ok(())
    }
}

/// A number in `0 .. n` (`n ≥ 1`): the top of a 32 × 32-bit product (Lemire's
/// multiply-shift), integer only. Its bias, under `n / 2³²`, does not matter for
/// a maze; what matters is that it is the same number everywhere.
fn below(rng: &mut XorShiftRng, n: u32) -> u32 {
    ((u64::from(rng.next_u32()) * u64::from(n)) >> 32) as u32
}

impl Maze {
    /// The seed.
    pub fn seed(&self) -> u32 {
        self.seed
    }
    /// Storeys.
    pub fn storeys(&self) -> u8 {
        self.storeys
    }
    /// Cells on the way from the start to the goal (each drop counts as one).
    pub fn path_cells(&self) -> u16 {
        self.path_cells
    }
    /// Turns on that way.
    pub fn turns(&self) -> u16 {
        self.turns
    }
    /// Marbles (one, or more from difficulty 4).
    pub fn marbles(&self) -> usize {
        self.count(START)
    }
    /// Pits (holes out of the maze, on the lowest storey).
    pub fn pits(&self) -> usize {
        self.cells[0][..self.len()]
            .iter()
            .filter(|&&c| c & HOLE != 0)
            .count()
    }

    /// The level's time limit: 0.35 s per cell and per turn of the way (the
    /// autopilot needs at most 0.30 s: it stops at every corner; 1 680 mazes of
    /// every difficulty, both steppers, `survey` in `tests/generate.rs`) times a
    /// margin from 3 (difficulty 0) down to 1.5 (difficulty 9), plus 5 s.
    pub(crate) fn time_limit_s(&self) -> u16 {
        let pace_ds = 35 * (u32::from(self.path_cells) + u32::from(self.turns)) / 10;
        let margin_tenths = 30 - 5 * u32::from(self.difficulty) / 3;
        (5 + pace_ds * margin_tenths / 100).min(3600) as u16
    }

    /// Whether the board's own motion throws the marbles (`board_motion`): from
    /// difficulty 6, on one or two storeys only. The board turns about its
    /// bottom, so the marbles of a third and fourth storey are thrown hardest:
    /// there the autopilot lost 33 of 36 mazes at difficulty 6 (sizes 3, 5, 7,
    /// six seeds, event steps; `survey` in `tests/generate.rs`), and won every
    /// one below.
    pub(crate) fn board_motion(&self) -> bool {
        self.difficulty >= 6 && self.storeys <= 2
    }

    fn len(&self) -> usize {
        usize::from(self.size) * usize::from(self.size)
    }

    fn count(&self, bit: u8) -> usize {
        self.cells[..usize::from(self.storeys)]
            .iter()
            .map(|s| s[..self.len()].iter().filter(|&&c| c & bit != 0).count())
            .sum()
    }

    /// The neighbour of cell `c` in direction `d` (0 = −x', 1 = +x', 2 = −z',
    /// 3 = +z'), if it is inside.
    fn neighbour(&self, c: usize, d: u8) -> Option<usize> {
        let n = usize::from(self.size);
        let (x, z) = (c % n, c / n);
        match d {
            0 if x > 0 => Some(c - 1),
            1 if x + 1 < n => Some(c + 1),
            2 if z > 0 => Some(c - n),
            3 if z + 1 < n => Some(c + n),
            _ => None,
        }
    }

    /// Whether the link from cell `c` towards `d` is open.
    fn open(&self, storey: usize, c: usize, d: u8) -> bool {
        let cells = &self.cells[storey];
        match (d, self.neighbour(c, d)) {
            (0, Some(w)) => cells[w] & EAST != 0,
            (1, Some(_)) => cells[c] & EAST != 0,
            (2, Some(u)) => cells[u] & SOUTH != 0,
            (3, Some(_)) => cells[c] & SOUTH != 0,
            _ => false,
        }
    }
}
