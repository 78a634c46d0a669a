//! The level's grid: storeys top to bottom, one character per tile column,
//! into the tile occupancy (eq. 5's slab and wall layers of each storey) and the
//! start and goal cells.

use super::errors::{err, LevelError, LevelErrorKind};
use super::scan::{grid_shape, is_separator, line_end, trim_end};
use super::{Cell, MAX_GOALS, MAX_MARBLES};
use crate::physics::geometry::grid::{TileGrid, MAX_STOREYS, MAX_TILES_XZ};

/// A grid as read: its tiles and shape, and the cells the rules need.
pub(super) struct Grid<const WORDS: usize> {
    pub(super) tiles: TileGrid<WORDS>,
    pub(super) nx: usize,
    pub(super) nz: usize,
    pub(super) storeys: usize,
    pub(super) starts: [Cell; MAX_MARBLES],
    pub(super) n_starts: usize,
    pub(super) goals: [Cell; MAX_GOALS],
    pub(super) n_goals: usize,
    /// Whether the marble can drop: an `O`, or more than one storey.
    pub(super) holes: bool,
}

/// Reads the grid of `b` from byte `i`, line `line` on (after the header).
pub(super) const fn grid<const WORDS: usize>(
    b: &[u8],
    mut i: usize,
    mut line: usize,
) -> Result<Grid<WORDS>, LevelError> {
    // Grid: storeys top to bottom (`t` from the top; storey `n` from the bottom).
    let (nx, nz, storeys) = grid_shape(b, i);
    if nx == 0 {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::EmptyGrid,
        });
    }
    if nx > MAX_TILES_XZ || nz > MAX_TILES_XZ {
        return Err(LevelError {
            line: line as u32,
            column: 1,
            kind: LevelErrorKind::TooLarge,
        });
    }
    // Past MAX_STOREYS the loop below stops at the separator that starts one too
    // many, having read the first ones as the storeys a grid can hold.
    let storeys = if storeys > MAX_STOREYS {
        MAX_STOREYS
    } else {
        storeys
    };
    let layers = 2 * storeys;
    let mut grid = match TileGrid::<WORDS>::new(nx, layers, if nz == 0 { 1 } else { nz }) {
        Ok(g) => g,
        Err(_) => {
            return Err(LevelError {
                line: line as u32,
                column: 1,
                kind: LevelErrorKind::TooLarge,
            })
        }
    };
    let mut starts = [Cell::new(0, 0, 0); MAX_MARBLES];
    let mut n_starts = 0usize;
    let mut goals = [Cell::new(0, 0, 0); MAX_GOALS];
    let mut n_goals = 0usize;
    let mut holes = storeys > 1;
    let mut t = 0usize;
    let mut k = 0usize;
    let mut last_row_line = line;
    while i < b.len() {
        let e = line_end(b, i);
        let end = trim_end(b, i, e);
        if end > i && is_separator(b, i, end) {
            if k == 0 {
                return err(line, b, i, i, LevelErrorKind::EmptyStorey);
            }
            if k != nz {
                return err(line, b, i, i, LevelErrorKind::StoreyRows);
            }
            t += 1;
            if t >= MAX_STOREYS {
                return err(line, b, i, i, LevelErrorKind::TooManyStoreys);
            }
            k = 0;
        } else if end > i {
            if k >= nz {
                return err(line, b, i, i, LevelErrorKind::StoreyRows);
            }
            let n = storeys - 1 - t;
            let (slab, walls) = (2 * n, 2 * n + 1);
            let mut col = 0usize;
            let mut p = i;
            while p < end {
                let c = b[p];
                if col >= nx {
                    return err(line, b, i, p, LevelErrorKind::RaggedRow);
                }
                let cell = col % 2 == 1 && k % 2 == 1;
                match c {
                    b'#' => {
                        // The storey above is already read: no slab there is its `O`.
                        if n + 1 < storeys && !grid.is_set(col, slab + 2, k) {
                            return err(line, b, i, p, LevelErrorKind::HoleAboveWall);
                        }
                        grid.set(col, slab, k, true);
                        grid.set(col, walls, k, true);
                    }
                    b'.' => {
                        grid.set(col, slab, k, true);
                    }
                    b'O' => holes = true,
                    b'S' | b'G' => {
                        if !cell {
                            return err(line, b, i, p, LevelErrorKind::NotACell);
                        }
                        grid.set(col, slab, k, true);
                        let at = Cell::new(col as u8, k as u8, n as u8);
                        if c == b'S' {
                            if n_starts == MAX_MARBLES {
                                return err(line, b, i, p, LevelErrorKind::StartCount);
                            }
                            starts[n_starts] = at;
                            n_starts += 1;
                        } else {
                            if n_goals == MAX_GOALS {
                                return err(line, b, i, p, LevelErrorKind::GoalCount);
                            }
                            goals[n_goals] = at;
                            n_goals += 1;
                        }
                    }
                    _ => return err(line, b, i, p, LevelErrorKind::BadTile),
                }
                // Advance one character (multi-byte ones are reported above as BadTile).
                p += 1;
                col += 1;
            }
            if col != nx {
                return err(line, b, i, end, LevelErrorKind::RaggedRow);
            }
            k += 1;
            last_row_line = line;
        }
        i = e + 1;
        line += 1;
    }
    if t > 0 && k == 0 {
        return Err(LevelError {
            line: last_row_line as u32 + 1,
            column: 1,
            kind: LevelErrorKind::EmptyStorey,
        });
    }
    if k != nz {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::StoreyRows,
        });
    }
    if n_starts == 0 {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::StartCount,
        });
    }
    if n_goals == 0 {
        return Err(LevelError {
            line: last_row_line as u32,
            column: 1,
            kind: LevelErrorKind::GoalCount,
        });
    }
    Ok(Grid {
        tiles: grid,
        nx,
        nz,
        storeys,
        starts,
        n_starts,
        goals,
        n_goals,
        holes,
    })
}
