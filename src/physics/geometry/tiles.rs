//! The seed's tile layout: where tile `[i, j, k]` is (eq. 5) and which tile holds a
//! point (eq. 6).
//!
//! Lengths are in cell pitches (`s + l = 1`, see [`crate::physics::scalar`]), so the
//! seed's `⌊a/(s+l)⌋` is `⌊a⌋` and eq. 6 costs two floors and no division:
//!
//! ```text
//! i = 2⌊a⌋ + [a ≥ ⌊a⌋ + s]            (x' and z')
//! j = 2⌊b⌋ + 1 + [b ≥ ⌊b⌋ + 1 − s]    (y')
//! ```
//!
//! (`[·]` is 1 when true.) This is the seed's eq. 6 with `s + l = 1`: its inner term
//! `⌊(a − s) − ⌊a⌋⌋ + 1` is 1 exactly when `a ≥ ⌊a⌋ + s`, and for y'
//! `⌊b + s⌋ = ⌊b⌋ + [b ≥ ⌊b⌋ + 1 − s]`. The comparison is made against the very
//! expression eq. 5 uses for the boundary (`n + s`, `(m + 1) − s`), so the two
//! equations agree to the last bit in every backend: in fixed point every term is
//! exact anyway, and in floating point a boundary that rounds, rounds the same way
//! in both. (Evaluated in the seed's order, `a − s` rounds on its own and puts
//! floating-point points one ULP from a boundary into the wrong tile.)
//!
//! Along x' and z' even indices are short tiles (walls, posts) and odd ones long
//! tiles (cells); along y' `j = 0` is the floor slab `[-s, 0)` and `j = 1` the wall
//! layer `[0, l)`, and the pattern repeats one pitch up per storey: storey `n`'s
//! slab `j = 2n` is `[n − s, n)`, its walls `j = 2n + 1` are `[n, n + 1 − s)`.

use super::super::scalar::Scalar;
use super::super::vec::Vec3;

/// Integer tile coordinates `[i, j, k]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct TileIndex {
    /// Column along x'.
    pub i: i32,
    /// Layer along y' (`2n`: storey `n`'s floor slab, `2n + 1`: its walls).
    pub j: i32,
    /// Row along z'.
    pub k: i32,
}

impl TileIndex {
    /// `[i, j, k]`.
    pub const fn new(i: i32, j: i32, k: i32) -> Self {
        TileIndex { i, j, k }
    }
}

/// An axis-aligned box `[min, max)` in the tile frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb<S> {
    /// Lower corner `(x'-, y'-, z'-)`.
    pub min: Vec3<S>,
    /// Upper corner `(x'+, y'+, z'+)`.
    pub max: Vec3<S>,
}

/// Why a tile layout was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LayoutError {
    /// `s` or `l` is zero.
    ZeroWidth,
    /// `s + l` is outside the supported 1 mm ..= 100 mm.
    PitchOutOfRange,
}

/// Smallest cell pitch `s + l` in micrometres that [`TileLayout::from_um`]
/// sets up: 1 mm. The level parser checks the same constants.
pub const MIN_PITCH_UM: u32 = 1_000;
/// Largest cell pitch `s + l` in micrometres: 100 mm, so that a 127-tile board
/// (63.5 pitches) stays well inside I8F24's ±128 pitches.
pub const MAX_PITCH_UM: u32 = 100_000;

/// The short width `s` and long width `l`, in pitches (`s + l = 1` exactly).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TileLayout<S> {
    /// Short width (walls, posts, the floor slab's thickness), in pitches.
    pub s: S,
    /// Long width (cells, wall height), in pitches: `1 - s`.
    pub l: S,
    /// One pitch in micrometres, to convert to and from millimetres.
    pub pitch_um: u32,
}

impl<S: Scalar> TileLayout<S> {
    /// The layout of a maze with short width `short_um` and long width `long_um`
    /// (micrometres).
    pub fn from_um(short_um: u32, long_um: u32) -> Result<Self, LayoutError> {
        if short_um == 0 || long_um == 0 {
            return Err(LayoutError::ZeroWidth);
        }
        let pitch = short_um as u64 + long_um as u64;
        if !(MIN_PITCH_UM as u64..=MAX_PITCH_UM as u64).contains(&pitch) {
            return Err(LayoutError::PitchOutOfRange);
        }
        let s = S::ratio(short_um as i64, pitch as i64);
        Ok(TileLayout {
            s,
            l: S::ONE - s,
            pitch_um: pitch as u32,
        })
    }

    /// Eq. 5 along x' (and z'): the extent `[lo, hi)` of column `i`.
    #[inline]
    pub fn span_xz(&self, i: i32) -> (S, S) {
        let n = S::from_int(i.div_euclid(2));
        if i.rem_euclid(2) == 0 {
            (n, n + self.s)
        } else {
            (n + self.s, n + S::ONE)
        }
    }

    /// Eq. 5 along y': the extent `[lo, hi)` of layer `j`.
    #[inline]
    pub fn span_y(&self, j: i32) -> (S, S) {
        let m = j.div_euclid(2);
        if j.rem_euclid(2) == 0 {
            (S::from_int(m) - self.s, S::from_int(m))
        } else {
            // `(m + 1) − s` rather than `m + l`: the same expression as the next
            // layer's lower bound, so the layers meet exactly in floating point too.
            (S::from_int(m), S::from_int(m + 1) - self.s)
        }
    }

    /// Eq. 5: the box of tile `[i, j, k]`.
    #[inline]
    pub fn tile_box(&self, t: TileIndex) -> Aabb<S> {
        let (x0, x1) = self.span_xz(t.i);
        let (y0, y1) = self.span_y(t.j);
        let (z0, z1) = self.span_xz(t.k);
        Aabb {
            min: Vec3::new(x0, y0, z0),
            max: Vec3::new(x1, y1, z1),
        }
    }

    /// Eq. 6, `f_x'` (and `f_z'`): the column holding coordinate `a`.
    #[inline]
    pub fn index_xz(&self, a: S) -> i32 {
        let n = a.floor_int();
        2 * n + (a >= S::from_int(n) + self.s) as i32
    }

    /// Eq. 6, `f_y'`: the layer holding height `b`.
    #[inline]
    pub fn index_y(&self, b: S) -> i32 {
        let n = b.floor_int();
        2 * n + 1 + (b >= S::from_int(n + 1) - self.s) as i32
    }

    /// The storey whose wall layer or floor slab holds height `b` (a marble on a
    /// slab, or falling through a hole in it, is on that slab's storey).
    #[inline]
    pub fn storey_of(&self, b: S) -> i32 {
        self.index_y(b).div_euclid(2)
    }

    /// Eq. 6 for a point.
    #[inline]
    pub fn index_of(&self, p: Vec3<S>) -> TileIndex {
        TileIndex::new(self.index_xz(p.x), self.index_y(p.y), self.index_xz(p.z))
    }

    /// Millimetres → pitches (setup and tools).
    pub fn from_mm(&self, mm: f64) -> S {
        S::from_f64(mm * 1000.0 / self.pitch_um as f64)
    }

    /// Micrometres → pitches, exactly rounded (setup).
    pub fn from_um_len(&self, um: i64) -> S {
        S::ratio(um, self.pitch_um as i64)
    }

    /// Pitches → millimetres (tools, traces).
    pub fn to_mm(&self, v: S) -> f64 {
        v.to_f64() * self.pitch_um as f64 / 1000.0
    }
}
