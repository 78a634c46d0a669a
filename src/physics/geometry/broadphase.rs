//! Candidate tiles (eq. 7): the index box spanned by the marble's bounding box.
//!
//! `i- = f_x'(a - r)`, `i+ = f_x'(a + r)` and the same for `j` and `k`; only the
//! candidates present in `tile_state` go on to the narrowphase (seed §1.3.3).

use super::super::scalar::Scalar;
use super::super::vec::Vec3;
use super::grid::Tiles;
use super::tiles::{TileIndex, TileLayout};

/// The inclusive index box `[i-, i+] × [j-, j+] × [k-, k+]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileRange {
    /// Lowest corner `[i-, j-, k-]`.
    pub lo: TileIndex,
    /// Highest corner `[i+, j+, k+]`.
    pub hi: TileIndex,
}

impl TileRange {
    /// The low and high bound along `axis` (0 = i, 1 = j, 2 = k), to narrow or
    /// widen the range on one axis.
    #[inline]
    pub(crate) fn axis_mut(&mut self, axis: usize) -> (&mut i32, &mut i32) {
        match axis {
            0 => (&mut self.lo.i, &mut self.hi.i),
            1 => (&mut self.lo.j, &mut self.hi.j),
            _ => (&mut self.lo.k, &mut self.hi.k),
        }
    }
}

/// Eq. 7 in 3-D.
#[inline]
pub fn candidates<S: Scalar>(layout: &TileLayout<S>, c: Vec3<S>, r: S) -> TileRange {
    TileRange {
        lo: TileIndex::new(
            layout.index_xz(c.x - r),
            layout.index_y(c.y - r),
            layout.index_xz(c.z - r),
        ),
        hi: TileIndex::new(
            layout.index_xz(c.x + r),
            layout.index_y(c.y + r),
            layout.index_xz(c.z + r),
        ),
    }
}

/// Eq. 7 for a marble on the floor of a flat maze: only the wall layer `j = 1` can
/// be touched (the floor is implicit), so `j- = j+ = 1`.
#[inline]
pub(crate) fn candidates_plane<S: Scalar>(layout: &TileLayout<S>, c: Vec3<S>, r: S) -> TileRange {
    TileRange {
        lo: TileIndex::new(layout.index_xz(c.x - r), 1, layout.index_xz(c.z - r)),
        hi: TileIndex::new(layout.index_xz(c.x + r), 1, layout.index_xz(c.z + r)),
    }
}

impl TileRange {
    /// No tiles at all (`lo > hi`): never equal to the candidates of a point.
    pub const EMPTY: TileRange = TileRange {
        lo: TileIndex::new(1, 1, 1),
        hi: TileIndex::new(0, 0, 0),
    };

    /// Every index in the box, in `k, j, i` order.
    pub fn iter(self) -> impl Iterator<Item = TileIndex> {
        (self.lo.k..=self.hi.k).flat_map(move |k| {
            (self.lo.j..=self.hi.j)
                .flat_map(move |j| (self.lo.i..=self.hi.i).map(move |i| TileIndex::new(i, j, k)))
        })
    }

    /// The candidates that exist (seed §1.3.3).
    pub fn solid(self, tiles: Tiles<'_>) -> impl Iterator<Item = TileIndex> + '_ {
        self.iter().filter(move |t| tiles.is_solid(*t))
    }
}
