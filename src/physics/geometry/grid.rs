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
