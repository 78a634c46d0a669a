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
//! (on mazes of up to [`MAX_SIZE_FOR_MARBLES`] cells a side);
//! `board_motion` (from 6, on one or two storeys: see [`Maze::board_motion`]); and a time limit that shrinks from three to one and a
//! half times the autopilot's measured pace (see [`Maze::time_limit_s`]).
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

use core::fmt;

use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

use super::level::MAX_MARBLES;
use crate::physics::geometry::grid::MAX_STOREYS;

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
pub const MAX_SIZE_FOR_MARBLES: u8 = 7;
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
    pub const EMPTY: Maze = Maze {
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
    pub fn generate(
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
    /// Cells along a side.
    pub fn size(&self) -> u8 {
        self.size
    }
    /// Storeys.
    pub fn storeys(&self) -> u8 {
        self.storeys
    }
    /// The difficulty.
    pub fn difficulty(&self) -> u8 {
        self.difficulty
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
    pub fn time_limit_s(&self) -> u16 {
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
    pub fn board_motion(&self) -> bool {
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

    fn link(&mut self, storey: usize, c: usize, d: u8, to: usize) {
        let cells = &mut self.cells[storey];
        match d {
            0 => cells[to] |= EAST,
            1 => cells[c] |= EAST,
            2 => cells[to] |= SOUTH,
            _ => cells[c] |= SOUTH,
        }
    }

    /// A depth-first search from `entry` that opens a link to every unvisited cell
    /// it steps into (the recursive backtracker, with an explicit stack: a cell
    /// is pushed once, so the stack holds at most every cell). `depth` gets each
    /// cell's distance from `entry` along the tree (≤ 224: a `u8`).
    fn carve(
        &mut self,
        storey: usize,
        entry: usize,
        depth: &mut [u8; MAX_CELLS],
        rng: &mut XorShiftRng,
    ) {
        const UNSEEN: u8 = u8::MAX;
        let n = self.len();
        depth[..n].fill(UNSEEN);
        let mut stack = [0u8; MAX_CELLS];
        let mut top = 1;
        stack[0] = entry as u8;
        depth[entry] = 0;
        while top > 0 {
            let c = usize::from(stack[top - 1]);
            let mut choices = [0u8; 4];
            let mut k = 0;
            for d in 0..4 {
                if let Some(m) = self.neighbour(c, d) {
                    if depth[m] == UNSEEN {
                        choices[k] = d;
                        k += 1;
                    }
                }
            }
            if k == 0 {
                top -= 1;
                continue;
            }
            let d = choices[below(rng, k as u32) as usize];
            if let Some(m) = self.neighbour(c, d) {
                self.link(storey, c, d, m);
                depth[m] = depth[c] + 1;
                stack[top] = m as u8;
                top += 1;
            }
        }
    }

    /// Open links of cell `c`.
    fn degree(&self, storey: usize, c: usize) -> u8 {
        (0..4).filter(|&d| self.open(storey, c, d)).count() as u8
    }

    /// A dead end other than `entry`, at random among those at least half as deep
    /// as the deepest (so the way through the storey is long, but not always the
    /// longest). A tree of two or more cells always has one.
    fn pick_dead_end(
        &self,
        storey: usize,
        entry: usize,
        depth: &[u8; MAX_CELLS],
        rng: &mut XorShiftRng,
    ) -> usize {
        let n = self.len();
        let leaf = |c: usize| c != entry && self.degree(storey, c) == 1;
        let deepest = (0..n)
            .filter(|&c| leaf(c))
            .map(|c| depth[c])
            .max()
            .unwrap_or(0);
        let deep = |c: usize| leaf(c) && 2 * u16::from(depth[c]) >= u16::from(deepest);
        let count = (0..n).filter(|&c| deep(c)).count() as u32;
        let pick = below(rng, count.max(1)) as usize;
        (0..n).filter(|&c| deep(c)).nth(pick).unwrap_or(n - 1)
    }

    /// Marks the way from `exit` back to the storey's entry (down the depths), and
    /// counts its cells and turns.
    fn mark_path(&mut self, storey: usize, exit: usize, depth: &[u8; MAX_CELLS]) {
        let mut c = exit;
        let mut last_dir = None;
        self.cells[storey][c] |= PATH;
        while depth[c] > 0 {
            let Some((d, m)) = (0..4u8)
                .filter(|&d| self.open(storey, c, d))
                .filter_map(|d| self.neighbour(c, d).map(|m| (d, m)))
                .find(|&(_, m)| depth[m] + 1 == depth[c])
            else {
                break;
            };
            if last_dir.is_some_and(|l| l != d) {
                self.turns += 1;
            }
            last_dir = Some(d);
            self.cells[storey][m] |= PATH;
            self.path_cells += 1;
            c = m;
        }
    }

    /// Dead ends of `storey` off the way through it, in cell order.
    fn spare_dead_ends(&self, storey: usize) -> impl Iterator<Item = usize> + '_ {
        (0..self.len()).filter(move |&c| {
            self.cells[storey][c] & (PATH | START | HOLE | GOAL) == 0 && self.degree(storey, c) == 1
        })
    }

    /// Sets `bit` on a dead end of `storey` off the way, chosen at random;
    /// nothing when there is none left.
    fn mark_spare_dead_end(&mut self, storey: usize, bit: u8, rng: &mut XorShiftRng) {
        let spare = self.spare_dead_ends(storey).count();
        if spare == 0 {
            return;
        }
        let pick = below(rng, spare as u32) as usize;
        let chosen = self.spare_dead_ends(storey).nth(pick);
        if let Some(c) = chosen {
            self.cells[storey][c] |= bit;
        }
    }

    /// From difficulty 4 a second marble, from 7 a third, each in a dead end of the
    /// top storey off the way (when there is one) — on mazes of up to
    /// [`MAX_SIZE_FOR_MARBLES`] cells a side.
    fn add_marbles(&mut self, storey: usize, rng: &mut XorShiftRng) {
        if self.size > MAX_SIZE_FOR_MARBLES {
            return;
        }
        let extra = usize::from(self.difficulty >= 4) + usize::from(self.difficulty >= 7);
        for _ in 0..extra.min(MAX_MARBLES - 1) {
            self.mark_spare_dead_end(storey, START, rng);
        }
    }

    /// From difficulty 2, one pit per two levels of difficulty in dead ends of the
    /// lowest storey off the way to the goal (as many as there are).
    fn add_pits(&mut self, rng: &mut XorShiftRng) {
        for _ in 0..self.difficulty / 2 {
            self.mark_spare_dead_end(0, HOLE, rng);
        }
    }

    /// The reachability check: from every start, a flood over the cells (until
    /// nothing new is reached; rows as bit masks, no queue) that moves along
    /// open links into cells with a floor, and from a hole above the lowest storey
    /// only down to the cell below, reaches the goal. Pits are never entered.
    pub fn every_start_reaches_the_goal(&self) -> bool {
        let n = usize::from(self.size);
        let storeys = usize::from(self.storeys);
        for s in 0..storeys {
            for c in 0..self.len() {
                if self.cells[s][c] & START == 0 {
                    continue;
                }
                let mut seen = [[0u16; MAX_SIZE as usize]; MAX_STOREYS];
                seen[s][c / n] |= 1 << (c % n);
                let mut grew = true;
                let mut won = false;
                while grew && !won {
                    grew = false;
                    for t in 0..storeys {
                        for a in 0..self.len() {
                            if seen[t][a / n] & (1 << (a % n)) == 0 {
                                continue;
                            }
                            let cell = self.cells[t][a];
                            won |= cell & GOAL != 0;
                            let mut reach = |t: usize, b: usize| {
                                if seen[t][b / n] & (1 << (b % n)) == 0 {
                                    seen[t][b / n] |= 1 << (b % n);
                                    grew = true;
                                }
                            };
                            if cell & HOLE != 0 {
                                // Over a hole: the marble drops (a pit is never entered).
                                if t > 0 {
                                    reach(t - 1, a);
                                }
                                continue;
                            }
                            for d in 0..4 {
                                if let Some(b) = self.neighbour(a, d) {
                                    let pit = t == 0 && self.cells[t][b] & HOLE != 0;
                                    if self.open(t, a, d) && !pit {
                                        reach(t, b);
                                    }
                                }
                            }
                        }
                    }
                }
                if !won {
                    return false;
                }
            }
        }
        true
    }

    /// The tile character at column `i`, row `k` of `storey`.
    fn tile(&self, storey: usize, i: usize, k: usize) -> char {
        let n = usize::from(self.size);
        let last = 2 * n;
        if i == 0
            || k == 0
            || i == last
            || k == last
            || (i.is_multiple_of(2) && k.is_multiple_of(2))
        {
            return '#';
        }
        let cell = |x: usize, z: usize| self.cells[storey][z * n + x];
        match (i % 2, k % 2) {
            (1, 1) => {
                let c = cell(i / 2, k / 2);
                if c & START != 0 {
                    'S'
                } else if c & GOAL != 0 {
                    'G'
                } else if c & HOLE != 0 {
                    'O'
                } else {
                    '.'
                }
            }
            // A short tile between two cells along x' (even column) or z'.
            (0, _) if cell(i / 2 - 1, k / 2) & EAST != 0 => '.',
            (_, 0) if cell(i / 2, k / 2 - 1) & SOUTH != 0 => '.',
            _ => '#',
        }
    }
}

/// The level text (see [`crate::game::level`]): [`Maze::write_text`].
impl fmt::Display for Maze {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write_text(f)
    }
}

impl Maze {
    /// Writes the level text (see [`crate::game::level`]): a header naming the
    /// maze by its arguments, then the storeys top to bottom. Strings and
    /// digits only, no format machinery: a board writes its mazes with this,
    /// and `core::fmt`'s number formatting is kilobytes of flash the micro:bit
    /// v1 does not have to spare.
    pub fn write_text<W: fmt::Write>(&self, w: &mut W) -> fmt::Result {
        w.write_str("name: maze-")?;
        decimal(w, self.seed)?;
        w.write_char('-')?;
        decimal(w, self.size.into())?;
        w.write_char('x')?;
        decimal(w, self.size.into())?;
        w.write_char('x')?;
        decimal(w, self.storeys.into())?;
        w.write_str("-d")?;
        decimal(w, self.difficulty.into())?;
        w.write_str("\neffects: rolling")?;
        if self.difficulty >= 1 {
            w.write_str(", friction")?;
        }
        if self.board_motion() {
            w.write_str(", board_motion")?;
        }
        w.write_str("\ntime_limit_s: ")?;
        decimal(w, self.time_limit_s().into())?;
        w.write_str("\n---\n")?;
        let tiles = 2 * usize::from(self.size) + 1;
        for storey in (0..usize::from(self.storeys)).rev() {
            for k in 0..tiles {
                for i in 0..tiles {
                    w.write_char(self.tile(storey, i, k))?;
                }
                w.write_char('\n')?;
            }
            if storey > 0 {
                w.write_str("===\n")?;
            }
        }
        Ok(())
    }
}

/// `n` in decimal, without leading zeros: from the largest power of ten not
/// above it (no digit buffer to index, so no bounds check to panic).
fn decimal<W: fmt::Write>(w: &mut W, n: u32) -> fmt::Result {
    let mut power = 1u32;
    // `power · 10 ≤ n` here, so it cannot overflow.
    while n / power >= 10 {
        power *= 10;
    }
    loop {
        w.write_char(char::from(b'0' + (n / power % 10) as u8))?;
        if power == 1 {
            return Ok(());
        }
        power /= 10;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decimals_are_written_as_format_writes_them() {
        extern crate std;
        use std::string::{String, ToString};
        for n in [0, 1, 9, 10, 99, 100, 4_096, 1_000_000_000, u32::MAX] {
            let mut s = String::new();
            decimal(&mut s, n).unwrap();
            assert_eq!(s, n.to_string());
        }
    }

    /// The check is not a formality: a maze whose way is cut fails it.
    #[test]
    fn the_check_catches_a_cut_way() {
        let mut m = generate(5, 6, 1, 0).unwrap();
        assert!(m.every_start_reaches_the_goal());
        for c in m.cells[0].iter_mut() {
            if *c & GOAL != 0 {
                // Wall the goal in.
                *c &= !(EAST | SOUTH);
            }
        }
        for c in 0..m.len() {
            for d in [1, 3] {
                if let Some(g) = m.neighbour(c, d) {
                    if m.cells[0][g] & GOAL != 0 {
                        m.cells[0][c] &= !(if d == 1 { EAST } else { SOUTH });
                    }
                }
            }
        }
        assert!(!m.every_start_reaches_the_goal());
        // Without the hole to the storey below, the top storey is a dead end.
        let mut m = generate(5, 4, 2, 0).unwrap();
        assert!(m.every_start_reaches_the_goal());
        for c in m.cells[1].iter_mut() {
            *c &= !HOLE;
        }
        assert!(!m.every_start_reaches_the_goal());
    }
}
