//! `tile_state`: which tiles exist, as a fixed-size bitset (no allocation).
//!
//! A [`TileGrid`] owns its bits and can be built in a `const` context (built-in
//! levels are parsed at compile time into flash); the physics reads it through the
//! borrowed, copyable [`Tiles`] view. Indices outside the grid are empty tiles.

use super::tiles::TileIndex;

/// The largest number of tiles along x' or z' (63 cells and 64 walls).
pub const MAX_TILES_XZ: usize = 127;
/// The most storeys a maze may have. Storey `n` is a floor slab (layer
/// `j = 2n`, eq. 5: `n − s ≤ y' < n`) under a layer of walls and cells
/// (`j = 2n + 1`: `n ≤ y' < n + 1 − s`); each slab is the ceiling of the
/// storey below.
pub const MAX_STOREYS: usize = 4;
/// The largest number of layers along y': two per storey (`j = 0 ..= 7`).
pub const MAX_LAYERS: usize = 2 * MAX_STOREYS;

/// Number of `u32` words for an `nx × ny × nz` grid.
pub const fn words_for(nx: usize, ny: usize, nz: usize) -> usize {
    (nx * ny * nz).div_ceil(32)
}

/// Why a grid was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GridError {
    /// A dimension is zero or over [`MAX_TILES_XZ`] / [`MAX_LAYERS`].
    BadDimensions,
    /// The grid needs more words than the storage has.
    TooLarge,
}

/// Owned occupancy bits for up to `WORDS × 32` tiles.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TileGrid<const WORDS: usize> {
    nx: u16,
    ny: u16,
    nz: u16,
    bits: [u32; WORDS],
}

impl<const WORDS: usize> TileGrid<WORDS> {
    /// An empty grid of `nx × ny × nz` tiles.
    pub const fn new(nx: usize, ny: usize, nz: usize) -> Result<Self, GridError> {
        if nx == 0
            || nz == 0
            || ny == 0
            || nx > MAX_TILES_XZ
            || nz > MAX_TILES_XZ
            || ny > MAX_LAYERS
        {
            return Err(GridError::BadDimensions);
        }
        if words_for(nx, ny, nz) > WORDS {
            return Err(GridError::TooLarge);
        }
        Ok(TileGrid {
            nx: nx as u16,
            ny: ny as u16,
            nz: nz as u16,
            bits: [0; WORDS],
        })
    }

    /// Sets tile `[i, j, k]` present or absent; `false` when it is outside the grid.
    pub const fn set(&mut self, i: usize, j: usize, k: usize, present: bool) -> bool {
        if i >= self.nx as usize || j >= self.ny as usize || k >= self.nz as usize {
            return false;
        }
        let bit = (j * self.nz as usize + k) * self.nx as usize + i;
        let mask = 1u32 << (bit % 32);
        if present {
            self.bits[bit / 32] |= mask;
        } else {
            self.bits[bit / 32] &= !mask;
        }
        true
    }

    /// Whether tile `[i, j, k]` is present (outside the grid: no), in a
    /// `const` context (the level parser's).
    pub(crate) const fn is_set(&self, i: usize, j: usize, k: usize) -> bool {
        if i >= self.nx as usize || j >= self.ny as usize || k >= self.nz as usize {
            return false;
        }
        let bit = (j * self.nz as usize + k) * self.nx as usize + i;
        self.bits[bit / 32] & (1u32 << (bit % 32)) != 0
    }

    /// Whether tile `[i, j, k]` is present (outside the grid: no).
    pub fn get(&self, t: TileIndex) -> bool {
        self.view().is_solid(t)
    }

    /// The borrowed view the physics reads.
    pub const fn view(&self) -> Tiles<'_> {
        Tiles {
            nx: self.nx,
            ny: self.ny,
            nz: self.nz,
            bits: &self.bits,
        }
    }
}

/// A read-only view of a tile grid.
#[derive(Clone, Copy, Debug)]
pub struct Tiles<'a> {
    nx: u16,
    ny: u16,
    nz: u16,
    bits: &'a [u32],
}

impl Tiles<'_> {
    /// Tiles along x'.
    pub fn nx(&self) -> usize {
        self.nx as usize
    }
    /// Layers along y'.
    pub fn ny(&self) -> usize {
        self.ny as usize
    }
    /// Tiles along z'.
    pub fn nz(&self) -> usize {
        self.nz as usize
    }

    /// `tile_state[i][j][k] == 1`: the tile exists. Outside the grid: no.
    #[inline]
    pub fn is_solid(&self, t: TileIndex) -> bool {
        if t.i < 0 || t.j < 0 || t.k < 0 {
            return false;
        }
        let (i, j, k) = (t.i as usize, t.j as usize, t.k as usize);
        if i >= self.nx as usize || j >= self.ny as usize || k >= self.nz as usize {
            return false;
        }
        let bit = (j * self.nz as usize + k) * self.nx as usize + i;
        match self.bits.get(bit / 32) {
            Some(w) => w & (1 << (bit % 32)) != 0,
            None => false,
        }
    }

    /// Whether every tile `i_lo ..= i_hi` of the row `(j, k)` along x' is
    /// `solid` (outside the grid: empty; an empty span: yes). The row's tiles
    /// are consecutive bits, so a word answers for up to 32 of them where
    /// [`Tiles::is_solid`] asks one at a time (a free region's rows,
    /// `world/events/free.rs`).
    pub fn row_is(&self, j: i32, k: i32, i_lo: i32, i_hi: i32, solid: bool) -> bool {
        self.rows_run(j, k, true, 1, (i_lo, i_hi), solid) == 1
    }

    /// How many rows along x' of layer `j`, from row `k` on, stepping up in z'
    /// (`k, k + 1, …`) or down, up to `max`, have every tile `i_lo ..= i_hi`
    /// (`span`) `solid` (outside the grid: empty; an empty span: every row). A free
    /// region grows across z' by these runs (`world/events/free.rs`).
    pub fn rows_run(
        &self,
        j: i32,
        k: i32,
        up: bool,
        max: u32,
        (i_lo, i_hi): (i32, i32),
        solid: bool,
    ) -> u32 {
        if i_lo > i_hi {
            return max;
        }
        let (nx, ny, nz) = (i32::from(self.nx), i32::from(self.ny), i32::from(self.nz));
        // The span's part outside the grid is empty tiles.
        if solid && (!(0..ny).contains(&j) || i_lo < 0 || i_hi >= nx) {
            return 0;
        }
        let (lo, hi) = (i_lo.max(0), i_hi.min(nx - 1));
        if !(0..ny).contains(&j) || lo > hi {
            return max;
        }
        let count = (hi - lo + 1) as usize;
        let mut n = 0;
        while n < max {
            let row = i64::from(k) + if up { i64::from(n) } else { -i64::from(n) };
            let holds = if (0..i64::from(nz)).contains(&row) {
                let first = (j as usize * nz as usize + row as usize) * nx as usize + lo as usize;
                self.bits_are(first, count, solid)
            } else {
                !solid
            };
            if !holds {
                break;
            }
            n += 1;
        }
        n
    }

    /// Whether the `count` bits from bit `first` on are all `solid` (missing
    /// words: empty).
    fn bits_are(&self, first: usize, count: usize, solid: bool) -> bool {
        let last = first + count - 1;
        let mut bit = first;
        while bit <= last {
            let (word, from) = (bit / 32, bit % 32);
            let to = (last - (bit - from)).min(31);
            // Bits `from ..= to` of the word.
            let mask = (u32::MAX >> (31 - to)) & (u32::MAX << from);
            let w = self.bits.get(word).copied().unwrap_or(0) & mask;
            if w != if solid { mask } else { 0 } {
                return false;
            }
            bit += to + 1 - from;
        }
        true
    }

    /// How many tiles of the row `(j, k)` along x' are `solid` in a row from
    /// tile `i` on, stepping up (`i, i + 1, …`) or down, up to `max` (at most
    /// 32; outside the grid: empty). A free region grows across x' by these
    /// runs, a row each, where row by row it would ask a column of tiles a row
    /// (`world/events/free.rs`).
    pub fn run_from(&self, j: i32, k: i32, i: i32, up: bool, max: u32, solid: bool) -> u32 {
        let max = max.min(32);
        if max == 0 {
            return 0;
        }
        // The `max` tiles as bits, the first one lowest (up) or highest (down).
        let first = if up {
            i
        } else {
            i.saturating_sub(max as i32 - 1)
        };
        let window = self.window(j, k, first, max);
        let run = if up {
            let w = if solid { !window } else { window };
            w.trailing_zeros()
        } else {
            let w = window << (64 - max);
            let w = if solid { !w } else { w };
            w.leading_zeros()
        };
        run.min(max)
    }

    /// Tiles `first .. first + n` of the row `(j, k)` (`n ≤ 32`) as the low `n`
    /// bits, tile `first` lowest; outside the grid: 0.
    fn window(&self, j: i32, k: i32, first: i32, n: u32) -> u64 {
        let (nx, ny, nz) = (i32::from(self.nx), i32::from(self.ny), i32::from(self.nz));
        if !(0..ny).contains(&j) || !(0..nz).contains(&k) {
            return 0;
        }
        let last = first.saturating_add(n as i32 - 1);
        let (lo, hi) = (first.max(0), last.min(nx - 1));
        if lo > hi {
            return 0;
        }
        let at = (j as usize * nz as usize + k as usize) * nx as usize + lo as usize;
        let word = |w: usize| u64::from(self.bits.get(w).copied().unwrap_or(0));
        let bits = (word(at / 32) | word(at / 32 + 1) << 32) >> (at % 32);
        let count = (hi - lo + 1) as u32;
        (bits & (u64::MAX >> (64 - count))) << (lo - first)
    }

    /// Storeys: a slab and a wall layer each (a grid of the floor alone is one;
    /// a grid has at least one layer).
    pub fn storeys(&self) -> usize {
        (self.ny as usize).div_ceil(2)
    }

    /// Whether any floor slab tile (`j = 0, 2, …`) is missing inside the grid, or
    /// there are several storeys: the scene then needs 3-D motion (holes).
    pub fn has_holes(&self) -> bool {
        self.storeys() > 1
            || (0..self.nz as i32)
                .any(|k| (0..self.nx as i32).any(|i| !self.is_solid(TileIndex::new(i, 0, k))))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// An `nx × ny × nz` grid, each tile solid with odds `density` in 4
    /// (0: all empty, 4: all solid), from `seed` (xorshift).
    fn random_grid((nx, ny, nz): (usize, usize, usize), seed: u64, density: u32) -> TileGrid<64> {
        let mut g = TileGrid::<64>::new(nx, ny, nz).unwrap();
        let mut x = seed | 1;
        for j in 0..ny {
            for k in 0..nz {
                for i in 0..nx {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    g.set(i, j, k, (x % 4) < u64::from(density));
                }
            }
        }
        g
    }

    proptest! {
        /// A row read answers as its tiles asked one at a time, on and off the
        /// grid, across word boundaries.
        #[test]
        fn a_row_read_is_its_tiles(
            (nx, ny, nz) in (1usize..=40, 1usize..=3, 1usize..=6),
            seed in any::<u64>(),
            density in 0u32..=4,
            j in -1i32..=3,
            k in -1i32..=6,
            i_lo in -3i32..=42,
            len in -1i32..=45,
            solid in any::<bool>(),
        ) {
            let g = random_grid((nx, ny, nz), seed, density);
            let t = g.view();
            let i_hi = i_lo + len;
            let one_by_one = (i_lo..=i_hi).all(|i| t.is_solid(TileIndex::new(i, j, k)) == solid);
            prop_assert_eq!(t.row_is(j, k, i_lo, i_hi, solid), one_by_one);
        }
    }

    proptest! {
        /// A run counts the tiles asked one at a time, either way, on and off
        /// the grid.
        #[test]
        fn a_run_counts_its_tiles(
            (nx, ny, nz) in (1usize..=40, 1usize..=3, 1usize..=6),
            seed in any::<u64>(),
            density in 0u32..=4,
            j in -1i32..=3,
            k in -1i32..=6,
            i in -40i32..=80,
            up in any::<bool>(),
            max in 0u32..=32,
            solid in any::<bool>(),
        ) {
            let g = random_grid((nx, ny, nz), seed, density);
            let t = g.view();
            let step = if up { 1 } else { -1 };
            let one_by_one = (0..max as i32)
                .take_while(|n| t.is_solid(TileIndex::new(i + step * n, j, k)) == solid)
                .count() as u32;
            prop_assert_eq!(t.run_from(j, k, i, up, max, solid), one_by_one);
        }
    }

    proptest! {
        /// A run of rows counts the rows asked tile by tile, either way, on
        /// and off the grid.
        #[test]
        fn a_run_of_rows_counts_its_rows(
            (nx, ny, nz) in (1usize..=40, 1usize..=3, 1usize..=6),
            seed in any::<u64>(),
            density in 0u32..=4,
            j in -1i32..=3,
            k in -3i32..=8,
            up in any::<bool>(),
            max in 0u32..=10,
            i_lo in -3i32..=42,
            len in -1i32..=45,
            solid in any::<bool>(),
        ) {
            let g = random_grid((nx, ny, nz), seed, density);
            let t = g.view();
            let step = if up { 1 } else { -1 };
            let i_hi = i_lo + len;
            let one_by_one = (0..max as i32)
                .take_while(|n| {
                    (i_lo..=i_hi).all(|i| t.is_solid(TileIndex::new(i, j, k + step * n)) == solid)
                })
                .count() as u32;
            prop_assert_eq!(t.rows_run(j, k, up, max, (i_lo, i_hi), solid), one_by_one);
        }
    }

    #[test]
    fn a_row_far_outside_the_grid_is_empty() {
        let mut g = TileGrid::<8>::new(5, 1, 5).unwrap();
        for i in 0..5 {
            g.set(i, 0, 2, true);
        }
        let t = g.view();
        assert!(t.row_is(0, 2, 0, 4, true));
        assert!(!t.row_is(0, 2, -1, 4, true));
        assert!(t.row_is(0, 9, i32::MIN, i32::MAX, false));
        assert!(!t.row_is(0, 2, i32::MIN, i32::MAX, false));
        assert!(t.row_is(0, 1, i32::MIN, i32::MAX, false));
        assert_eq!(t.run_from(0, 2, i32::MAX, true, 32, false), 32);
        assert_eq!(t.run_from(0, 2, i32::MIN, false, 32, false), 32);
        assert_eq!(t.run_from(0, 2, 4, false, 32, true), 5);
    }
}
