//! The autopilot's plan: the way from every cell to the nearest goal.
//!
//! A breadth-first search over the long×long cells (odd `i`, odd `k`) of every storey
//! from every goal cell. Two neighbouring cells of a storey are connected when the
//! short tile between them has no wall (the storey's wall layer); a missing floor
//! there is a 2 mm gap the marble rolls over, so it is passable. A cell with a wall
//! is never entered, nor a hole in the lowest storey; a hole above it is a one-way
//! step to the cell below (the marble rolls in and drops), so the backward search
//! reaches it only from that cell.
//!
//! # Memory
//!
//! The search result is a distance field stored **modulo 3** in 2 bits per cell
//! (`0` = unreachable, `1..=3` = distance mod 3 + 1): neighbouring cells differ by at
//! most one step, so the way to the goal is always the connected neighbour whose
//! code is one less (mod 3). For the largest grid (63×63 cells, or four storeys of
//! up to 31×31: a larger maze of storeys gets no plan) that is 993 bytes,
//! against 3969 for a `u8` field and 7938 for `u16` — see
//! [`Autopilot::RAM_BYTES`]. The search needs no queue either: it sweeps the grid
//! once per distance, relaxing the cells of the last wavefront (a cell of distance
//! `d − 3` has the same code but no unvisited neighbour, so re-visiting it is
//! harmless). That costs `cells × path length` cell visits once per level — a few
//! thousand for the built-in levels; a 63×63 serpentine would take about a second
//! on a Cortex-M0, at level start only.

use super::Autopilot;
use crate::game::level::{Cell, LevelView};
use crate::physics::geometry::grid::{Tiles, MAX_TILES_XZ};
use crate::physics::geometry::tiles::TileIndex;

/// The most cells along x' or z' (63 for 127 tiles).
pub(crate) const MAX_CELLS_XZ: usize = MAX_TILES_XZ / 2;
/// Whether the game has storeys (feature `storeys`): without, every storey
/// test below is a constant and the plan is the one-storey plan.
pub(super) const STOREYS: bool = cfg!(feature = "storeys");

/// The most cells the plan holds, over all storeys (a 63 × 63 maze, or four
/// storeys of 31 × 31 cells): a larger maze gets no plan.
pub(super) const MAX_PLANNED: usize = MAX_CELLS_XZ * MAX_CELLS_XZ;
pub(super) const FIELD_BYTES: usize = MAX_PLANNED.div_ceil(4);

/// One of the four moves between cells.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Dir {
    /// −x'.
    Left,
    /// +x'.
    Right,
    /// −z'.
    Up,
    /// +z'.
    Down,
}

impl Dir {
    pub(super) const ALL: [Dir; 4] = [Dir::Left, Dir::Right, Dir::Up, Dir::Down];

    /// `(dx, dz)` in cells.
    pub(super) const fn delta(self) -> (i32, i32) {
        match self {
            Dir::Left => (-1, 0),
            Dir::Right => (1, 0),
            Dir::Up => (0, -1),
            Dir::Down => (0, 1),
        }
    }
}

impl Autopilot {
    /// Plans the paths of `level` (once; see the module documentation for the cost).
    pub fn new(level: &LevelView) -> Self {
        let tiles = &level.tiles;
        let ncx = (tiles.nx() / 2).min(MAX_CELLS_XZ) as u8;
        let ncz = (tiles.nz() / 2).min(MAX_CELLS_XZ) as u8;
        let fits = ncx as usize * ncz as usize * tiles.storeys() <= MAX_PLANNED;
        let mut ap = Autopilot {
            field: [0; FIELD_BYTES],
            ncx,
            ncz,
            storeys: if !STOREYS {
                1
            } else if fits {
                tiles.storeys() as u8
            } else {
                0
            },
            marble: 0,
            start_cells: u16::MAX,
            last: [0; 2],
            boost: [0; 2],
            last_pos: [0; 2],
            cell: [u8::MAX; 3],
            dist: 0,
            best: 0,
            stalled: 0,
        };
        for goal in level.info.goals() {
            let c = [(goal.i / 2) as i32, (goal.k / 2) as i32, goal.storey as i32];
            if ap.inside(c) && enterable(tiles, c) {
                ap.set_code(c, 1);
            }
        }
        // Wavefront sweeps: cells at distance d (code d % 3 + 1) label their unvisited
        // connected neighbours d + 1, and the hole above them (a drop is one way:
        // the hole's cell is reached only from below in this backward search).
        let mut d: u32 = 0;
        loop {
            let (from, to) = ((d % 3 + 1) as u8, ((d + 1) % 3 + 1) as u8);
            let mut grew = false;
            for cy in 0..ap.storeys() {
                for cz in 0..ncz as i32 {
                    for cx in 0..ncx as i32 {
                        let c = [cx, cz, cy];
                        if ap.code(c) != from {
                            continue;
                        }
                        for dir in Dir::ALL {
                            let (dx, dz) = dir.delta();
                            let n = [cx + dx, cz + dz, cy];
                            if ap.inside(n)
                                && ap.code(n) == 0
                                && connected(tiles, c, dir)
                                && enterable(tiles, n)
                            {
                                ap.set_code(n, to);
                                grew = true;
                            }
                        }
                        let above = [cx, cz, cy + 1];
                        if is_drop(tiles, above) && ap.inside(above) && ap.code(above) == 0 {
                            ap.set_code(above, to);
                            grew = true;
                        }
                    }
                }
            }
            if !grew {
                break;
            }
            d += 1;
        }
        // Steer the marble whose start is nearest a goal (the first on a tie).
        for (n, start) in level.info.starts().iter().enumerate() {
            let c = [
                (start.i / 2) as i32,
                (start.k / 2) as i32,
                start.storey as i32,
            ];
            if let Some(len) = ap.cells_to_goal(level, c) {
                if len < ap.start_cells {
                    ap.start_cells = len;
                    ap.marble = n as u8;
                }
            }
        }
        ap
    }

    /// The marble the autopilot steers (index into the level's starts).
    pub fn marble(&self) -> usize {
        self.marble as usize
    }

    /// Cells from the steered marble's start to a goal, or `None` when no goal can be
    /// reached from any start.
    pub fn path_cells(&self) -> Option<u16> {
        (self.start_cells != u16::MAX).then_some(self.start_cells)
    }

    /// The next cell (tile indices and storey) on the way from `cell` to a goal:
    /// a neighbour on the same storey, or from a hole the cell below it; `None` at
    /// a goal, and from a cell with no way to one.
    pub fn next_cell(&self, level: &LevelView, cell: Cell) -> Option<Cell> {
        let c = [(cell.i / 2) as i32, (cell.k / 2) as i32, cell.storey as i32];
        if is_goal(level, c) {
            return None;
        }
        let n = self.next(&level.tiles, c)?;
        Some(Cell::new(
            (2 * n[0] + 1) as u8,
            (2 * n[1] + 1) as u8,
            n[2] as u8,
        ))
    }

    /// The move from cell `c` towards a goal along its storey (`None` at a goal,
    /// over a hole, and with no way).
    pub(super) fn step_towards_goal(&self, tiles: &Tiles, c: [i32; 3]) -> Option<Dir> {
        let here = self.code(c);
        if here == 0 || is_drop(tiles, c) {
            return None;
        }
        let want = (here + 1) % 3 + 1; // (d − 1) mod 3 + 1
        Dir::ALL.into_iter().find(|&dir| {
            let (dx, dz) = dir.delta();
            self.code([c[0] + dx, c[1] + dz, c[2]]) == want && connected(tiles, c, dir)
        })
    }

    /// The cell after `c` on the planned way: a neighbour, or under a hole the
    /// cell below.
    pub(super) fn next(&self, tiles: &Tiles, c: [i32; 3]) -> Option<[i32; 3]> {
        if is_drop(tiles, c) {
            let below = [c[0], c[1], c[2] - 1];
            return (self.code(c) != 0 && self.code(below) != 0).then_some(below);
        }
        let (dx, dz) = self.step_towards_goal(tiles, c)?.delta();
        Some([c[0] + dx, c[1] + dz, c[2]])
    }

    /// Cells from cell `c` to a goal by the planned way (a drop counts as one).
    pub(super) fn cells_to_goal(&self, level: &LevelView, mut c: [i32; 3]) -> Option<u16> {
        if self.code(c) == 0 {
            return None;
        }
        let mut n: u16 = 0;
        while !is_goal(level, c) {
            c = self.next(&level.tiles, c)?;
            n += 1;
            if n as usize > MAX_PLANNED {
                return None;
            }
        }
        Some(n)
    }

    pub(super) fn inside(&self, c: [i32; 3]) -> bool {
        c[0] >= 0
            && c[1] >= 0
            && c[2] >= 0
            && c[0] < self.ncx as i32
            && c[1] < self.ncz as i32
            && c[2] < self.storeys()
    }

    /// Storeys planned (without the feature `storeys`, the constant 1).
    #[inline]
    pub(super) fn storeys(&self) -> i32 {
        if STOREYS {
            i32::from(self.storeys)
        } else {
            1
        }
    }

    /// Where cell `c` is in the field: storey after storey, compact.
    pub(super) fn slot(&self, c: [i32; 3]) -> usize {
        (c[2] as usize * self.ncz as usize + c[1] as usize) * self.ncx as usize + c[0] as usize
    }

    pub(super) fn code(&self, c: [i32; 3]) -> u8 {
        if !self.inside(c) {
            return 0;
        }
        let n = self.slot(c);
        (self.field[n / 4] >> (2 * (n % 4))) & 3
    }

    pub(super) fn set_code(&mut self, c: [i32; 3], code: u8) {
        let n = self.slot(c);
        let shift = 2 * (n % 4);
        self.field[n / 4] = (self.field[n / 4] & !(3 << shift)) | (code << shift);
    }
}

pub(super) fn solid(tiles: &Tiles, i: i32, j: i32, k: i32) -> bool {
    tiles.is_solid(TileIndex::new(i, j, k))
}

/// A cell the marble may roll into: floor, no wall (eq. 5: storey `c[2]`'s slab
/// is layer `2·c[2]`, its walls `2·c[2] + 1`).
pub(super) fn enterable(tiles: &Tiles, c: [i32; 3]) -> bool {
    let (i, k, j) = (2 * c[0] + 1, 2 * c[1] + 1, 2 * c[2]);
    solid(tiles, i, j, k) && !solid(tiles, i, j + 1, k)
}

/// A hole above the lowest storey, over a cell without a wall (inside the grid):
/// the marble that rolls in drops one storey.
pub(super) fn is_drop(tiles: &Tiles, c: [i32; 3]) -> bool {
    let (i, k, j) = (2 * c[0] + 1, 2 * c[1] + 1, 2 * c[2]);
    let inside = i < tiles.nx() as i32 && k < tiles.nz() as i32 && i >= 0 && k >= 0;
    STOREYS
        && inside
        && c[2] > 0
        && !solid(tiles, i, j, k)
        && !solid(tiles, i, j + 1, k)
        && !solid(tiles, i, j - 1, k)
}

/// A cell the marble falls out of the maze through: no floor and no wall, and
/// no storey below to land on (also off the grid).
pub(super) fn is_pit(tiles: &Tiles, c: [i32; 3]) -> bool {
    let (i, k, j) = (2 * c[0] + 1, 2 * c[1] + 1, 2 * c[2]);
    !solid(tiles, i, j, k) && !solid(tiles, i, j + 1, k) && !is_drop(tiles, c)
}

/// No wall on the short tile between cell `c` and its neighbour `dir`.
pub(super) fn connected(tiles: &Tiles, c: [i32; 3], dir: Dir) -> bool {
    let (dx, dz) = dir.delta();
    !solid(tiles, 2 * c[0] + 1 + dx, 2 * c[2] + 1, 2 * c[1] + 1 + dz)
}

pub(super) fn is_goal(level: &LevelView, c: [i32; 3]) -> bool {
    level.info.goals().iter().any(|goal| {
        (goal.i / 2) as i32 == c[0] && (goal.k / 2) as i32 == c[1] && goal.storey as i32 == c[2]
    })
}
