//! A marble's free region: a box of tiles around it in which the search can find
//! nothing, so that a flight inside it skips the search.
//!
//! In a maze nearly every search finds no tile in reach and no end to a held
//! face's support, yet each pays for the swept box's tile indices (eq. 6), the
//! held faces' narrowing, the grid lookups and the support columns: some 800
//! instructions, most of a quiet frame. The region is built when a search finds
//! its tiles in reach empty: grown from them, up to [`GROW_X`] columns each way
//! across x' and [`GROW`] rows across z' (and y'), while every tile in it is
//! empty and every tile behind a held face under it is solid. The grid keeps a
//! row along x' as consecutive bits, so the growth reads words: a column's worth
//! of rows at once across x' (`Tiles::run_from`), runs of whole rows across z'
//! (`Tiles::rows_run`), a row at a time across y' (`Tiles::row_is`). It is kept with the held faces it assumed; a later flight whose
//! swept box (widened by the radius and the tolerance, as the reach test widens
//! it) lies inside it, with the same held faces, has exactly the search's answer
//! without the search: no tile, no lid, no support ending, only the flight's own
//! end or stop. The tiles and the layout never change, so the region stays true
//! until the held faces change or the marble leaves it.
//!
//! A pure cache: every state hash is the same with it or without it. The bounds
//! are tile boundaries (eq. 5) compared with the very sums the reach test feeds to
//! eq. 6, which eq. 5 and 6 decide alike on every boundary, on every backend.

use super::super::super::geometry::grid::Tiles;
use super::{reach, Aabb, Marble, Scalar, Segment, TileRange, Vec3, World};

/// Rows a region grows each way beyond the search's own tiles across y' and
/// z': a marble crossing an open floor keeps one
/// region for several frames (grown further, a rebuild would cost more than
/// the searches it spares, and its frame on the micro:bit v1 more than the
/// frame's budget).
const GROW: i32 = 8;

/// Columns a region grows each way across x', where the grid's rows answer
/// for many tiles at once (`grow_x`, at most 32).
const GROW_X: u32 = 16;

/// Held-face bits of a region that holds none: it serves no flight.
const NONE: u8 = u8::MAX;

/// A marble's free region: the centre's box (tile frame) and the held faces it
/// was built with. Each side of the box is a tile boundary; the swept box
/// widened by `r + tol` must lie inside it, except on a side a held face bounds
/// (the search leaves the rows behind a held face out whatever the path), where
/// the swept box itself must.
#[derive(Clone, Copy, Debug)]
pub(in crate::physics::world) struct FreeRegion<S> {
    lo: Vec3<S>,
    hi: Vec3<S>,
    /// `Marble::rest_mask` when built ([`NONE`]: no region). Each held face's
    /// plane is the box's side it bounds (a region is built only then), so the
    /// planes need no room of their own: the level's setup keeps several copies
    /// of the world on the micro:bit v1's stack.
    held: u8,
}

impl<S: Scalar> FreeRegion<S> {
    pub(in crate::physics::world) const EMPTY: Self = FreeRegion {
        lo: Vec3 {
            x: S::ZERO,
            y: S::ZERO,
            z: S::ZERO,
        },
        hi: Vec3 {
            x: S::ZERO,
            y: S::ZERO,
            z: S::ZERO,
        },
        held: NONE,
    };

    /// Whether the region was built for a marble holding the faces `rest_mask`.
    #[inline]
    pub(in crate::physics::world) fn built_with(&self, rest_mask: u8) -> bool {
        self.held == rest_mask
    }

    /// Whether the marble holds the faces the region was built with.
    #[inline]
    fn holds(&self, m: &Marble<S>) -> bool {
        let held = self.held;
        if held != m.rest_mask {
            return false;
        }
        // Axis by axis (bit `2·axis + up`; held from above, the low side): no
        // loop over the bits, and none of it for a marble that holds nothing.
        let p = &m.rest_plane;
        let side = |bit: u8, side: S, plane: S| held & (1 << bit) == 0 || side == plane;
        held == 0
            || (side(0, self.hi.x, p[0])
                && side(1, self.lo.x, p[0])
                && side(2, self.hi.y, p[1])
                && side(3, self.lo.y, p[1])
                && side(4, self.hi.z, p[2])
                && side(5, self.lo.z, p[2]))
    }

    /// Whether the tile behind every face the marble is held on is there under
    /// its centre (what `World::behind_solid` asks the grid for each), known
    /// without the grid: the region was built with those faces and every tile
    /// behind them under it solid. `space`: the world has holes (3-D).
    #[inline]
    pub(in crate::physics::world) fn under_held(&self, m: &Marble<S>, space: bool) -> bool {
        let (c, lo, hi) = (m.pos, self.lo, self.hi);
        // Eq. 5's tiles are `[lo, hi)`, as eq. 6 indexes the centre.
        self.holds(m)
            && lo.x <= c.x
            && c.x < hi.x
            && lo.z <= c.z
            && c.z < hi.z
            && (!space || (lo.y <= c.y && c.y < hi.y))
    }

    /// [`FreeRegion::under_held`] for a flat world's marble holding one face,
    /// bit `2·H + up`, with which the region was built: that face's plane is
    /// the region's side (held from above, the low one) and the centre is
    /// inside across x' and z'.
    #[inline(always)]
    pub(in crate::physics::world) fn under_face<const H: usize>(
        &self,
        m: &Marble<S>,
        up: bool,
    ) -> bool {
        debug_assert_eq!(self.held, 1 << (2 * H + up as usize));
        let (c, lo, hi) = (m.pos, self.lo, self.hi);
        let side = if up { lo.axis(H) } else { hi.axis(H) };
        let under =
            side == m.rest_plane[H] && lo.x <= c.x && c.x < hi.x && lo.z <= c.z && c.z < hi.z;
        debug_assert_eq!(under, self.under_held(m, false));
        under
    }

    /// Whether the flight `seg` of the marble, whose centre sweeps `path`, can
    /// meet nothing: the search would return the flight's own end or stop.
    /// `(r, reach)`: the radius, and with the tolerance. `space`: the world has
    /// holes (3-D). Out of line, one copy for both kinds of world: the
    /// micro:bit v1's flash.
    #[inline(never)]
    pub(in crate::physics::world) fn serves(
        &self,
        m: &Marble<S>,
        seg: &Segment<S>,
        path: &Aabb<S>,
        (r, reach): (S, S),
        space: bool,
    ) -> bool {
        if self.holds(m) {
            self.contains(path, reach, space)
        } else {
            self.serves_still(m, seg, path, (r, reach), space)
        }
    }

    /// Whether the region answers a still flight (no speed and no kick: the
    /// centre stays where it is all step) of a marble that has let go of some
    /// of the faces the region was built with and holds the others at their
    /// planes: a marble at rest in a corner whose pull has turned away from
    /// one wall without beating static friction, frame after frame while the
    /// tilt wanders. The search would find nothing: a still centre approaches
    /// no tile (every approach speed and pull is zero, bit for bit) and enters
    /// no column (the hold kept only faces supported under it), and it is in
    /// no tile: those in reach within the region are empty, and those behind a
    /// let-go face lie beyond its plane, which the centre is at least a radius
    /// in front of (so a rounded edge there is not nearer than the tolerance).
    /// Asked by the search (`serves`): the quiet frame's served path stays as
    /// it was, and a still marble's frame goes on to the search.
    #[inline]
    fn serves_still(
        &self,
        m: &Marble<S>,
        seg: &Segment<S>,
        path: &Aabb<S>,
        (r, reach): (S, S),
        space: bool,
    ) -> bool {
        // The faces first: most searches this asks have no region at all.
        let (built, held) = (self.held, m.rest_mask);
        if built == NONE || held & !built != 0 {
            return false;
        }
        if seg.v != Vec3::ZERO || seg.dv != Vec3::ZERO || seg.h != Vec3::ZERO {
            return false;
        }
        let mut bits = built;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
            // Held from above (`up`) the face bounds the low side.
            let (side, c) = (
                if up {
                    self.lo.axis(axis)
                } else {
                    self.hi.axis(axis)
                },
                m.pos.axis(axis),
            );
            let kept = if held & (1 << bit) != 0 {
                m.rest_plane[axis] == side
            } else if up {
                // As the hold puts a resting centre (`plane ± r`): the same
                // sums, so a float backend's rounding agrees too.
                c >= side + r
            } else {
                c <= side - r
            };
            if !kept {
                return false;
            }
        }
        self.contains(path, reach, space)
    }

    /// [`FreeRegion::serves`] for a marble known to hold the region's faces
    /// (the quiet frame's: `under_held` said so before the hold, which kept
    /// them all).
    #[inline(always)]
    pub(in crate::physics::world) fn contains(
        &self,
        path: &Aabb<S>,
        reach: S,
        space: bool,
    ) -> bool {
        // A held face's up bit (axis·2 + 1) bounds the low side, its down bit
        // the high side: that side is not widened.
        let widen = |bit: u8| {
            if self.held & (1 << bit) != 0 {
                S::ZERO
            } else {
                reach
            }
        };
        let x = path.min.x - widen(1) >= self.lo.x && path.max.x + widen(0) < self.hi.x;
        let z = path.min.z - widen(5) >= self.lo.z && path.max.z + widen(4) < self.hi.z;
        let y = !space || (path.min.y - widen(3) >= self.lo.y && path.max.y + widen(2) < self.hi.y);
        x && z && y
    }
}

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Builds marble `n`'s region around `path` (its flight's swept box, whose
    /// widened tiles the search just found empty: `searched`, the range it
    /// read); none if the support of a held face already runs out under them.
    /// `space`: the world has holes (3-D).
    /// Out of line and not generic over `space`: it runs a few times a second,
    /// and one copy keeps the micro:bit v1 within its flash.
    #[inline(never)]
    pub(super) fn build_free(
        &mut self,
        n: usize,
        m: &Marble<S>,
        path: &Aabb<S>,
        searched: &TileRange,
        space: bool,
    ) {
        self.free[n] = FreeRegion::EMPTY;
        let layout = self.params.layout;
        let mut range = reach(&layout, path, self.params.radius + self.tol(), space);
        // A held face bounds its side whatever the path, from the face's row on
        // (`leave_out_held` narrows the open side to it); the row behind it must
        // be solid under the whole region (the lid's need not: it is everywhere).
        let mut behind = [None; 3];
        let held = m.rest_mask;
        let mut bits = held;
        while bits != 0 {
            let bit = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (axis, up) = (bit / 2, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            if axis != 1 || space {
                let (lo, hi) = range.axis_mut(axis);
                if up {
                    *lo = i32::MIN;
                } else {
                    *hi = i32::MAX;
                }
            }
            if axis != 1 || up {
                let at = if up { plane.next_down() } else { plane };
                behind[axis] = Some(if axis == 1 {
                    layout.index_y(at)
                } else {
                    layout.index_xz(at)
                });
            }
        }
        self.leave_out_held(m, &mut range);
        // The search read these very tiles (the same reach, narrowed alike,
        // unless a held face's row lies beyond it): only the rows behind the
        // held faces are new.
        if !fits(self.tiles, &range, &behind, range != *searched) {
            return;
        }
        // Grow each side that no held face bounds: across x' and z' by runs
        // (`grow_x`, `grow_z`), across y' a layer at a time.
        for side in 0..6 {
            let axis = side / 2;
            if (axis == 1 && !space) || held & (1 << (side ^ 1)) != 0 {
                continue;
            }
            if axis != 1 {
                let up = side % 2 == 1;
                let g = if axis == 0 {
                    grow_x(self.tiles, &range, &behind, up)
                } else {
                    grow_z(self.tiles, &range, &behind, up)
                };
                let (lo, hi) = range.axis_mut(axis);
                if up {
                    *hi += g;
                } else {
                    *lo -= g;
                }
                continue;
            }
            for _ in 0..GROW {
                // The row just beyond that side, then the side moved onto it.
                let (lo, hi) = range.axis_mut(axis);
                let next = if side % 2 == 0 { *lo - 1 } else { *hi + 1 };
                let mut row = range;
                let (row_lo, row_hi) = row.axis_mut(axis);
                (*row_lo, *row_hi) = (next, next);
                if !row_fits_y(self.tiles, &row, &behind) {
                    break;
                }
                let (lo, hi) = range.axis_mut(axis);
                *(if side % 2 == 0 { lo } else { hi }) = next;
            }
        }
        let mut region = FreeRegion {
            lo: layout.tile_box(range.lo).min,
            hi: layout.tile_box(range.hi).max,
            held,
        };
        if space {
            // The lid is searched when the widened box reaches it.
            region.hi.y = region.hi.y.min(self.lid());
        }
        // On the board, so that a quiet step in the plane, which ends inside
        // its region, has not left it (`finish` skips `check_out`): the border
        // walls keep a region there anyway.
        let (ex, ez) = self.extent();
        (region.lo.x, region.lo.z) = (region.lo.x.max(S::ZERO), region.lo.z.max(S::ZERO));
        (region.hi.x, region.hi.z) = (region.hi.x.min(ex), region.hi.z.min(ez));
        if region.holds(m) {
            self.free[n] = region;
        }
    }
}

/// How many columns beyond its x' side (`up`: the high one) `r` can grow by,
/// up to [`GROW_X`]: as many as the row-by-row growth would add (`fits` on each
/// new column), counted along the grid's rows. A new column's tiles must be
/// empty, and the tiles behind a held floor (`behind[1]`) or z' face
/// (`behind[2]`) there solid; the row behind a held x' face is the same for
/// every column (`fits` read it for `r`).
fn grow_x(tiles: Tiles<'_>, r: &TileRange, behind: &[Option<i32>; 3], up: bool) -> i32 {
    let from = if up { r.hi.i + 1 } else { r.lo.i - 1 };
    let mut g = GROW_X;
    for k in r.lo.k..=r.hi.k {
        for j in r.lo.j..=r.hi.j {
            g = g.min(tiles.run_from(j, k, from, up, g, false));
        }
        if let Some(j) = behind[1] {
            g = g.min(tiles.run_from(j, k, from, up, g, true));
        }
    }
    if let Some(k) = behind[2] {
        for j in r.lo.j..=r.hi.j {
            g = g.min(tiles.run_from(j, k, from, up, g, true));
        }
    }
    g as i32
}

/// How many rows beyond its z' side (`up`: the high one) `r` can grow by, up
/// to [`GROW`]: as many as the row-by-row growth would add (`fits` on each new
/// row), counted a layer's rows at a time. A new row's tiles must be empty,
/// and the tiles behind a held floor (`behind[1]`) or x' face (`behind[0]`)
/// there solid; the row behind a held z' face is the same for every row.
fn grow_z(tiles: Tiles<'_>, r: &TileRange, behind: &[Option<i32>; 3], up: bool) -> i32 {
    let from = if up { r.hi.k + 1 } else { r.lo.k - 1 };
    let (lo, hi) = (r.lo.i, r.hi.i);
    let mut g = GROW as u32;
    for j in r.lo.j..=r.hi.j {
        g = g.min(tiles.rows_run(j, from, up, g, (lo, hi), false));
        if let Some(i) = behind[0] {
            g = g.min(tiles.rows_run(j, from, up, g, (i, i), true));
        }
    }
    if let Some(j) = behind[1] {
        g = g.min(tiles.rows_run(j, from, up, g, (lo, hi), true));
    }
    g as i32
}

/// `fits(r, behind, true)` for the layer `r` a region grows onto across y',
/// without the layer behind a held floor or lid: growing across y' leaves it as
/// `fits` read it for the region.
fn row_fits_y(tiles: Tiles<'_>, r: &TileRange, behind: &[Option<i32>; 3]) -> bool {
    let (lo, hi) = (r.lo.i, r.hi.i);
    for k in r.lo.k..=r.hi.k {
        for j in r.lo.j..=r.hi.j {
            if !tiles.row_is(j, k, lo, hi, false) {
                return false;
            }
        }
    }
    if let Some(i) = behind[0] {
        for k in r.lo.k..=r.hi.k {
            for j in r.lo.j..=r.hi.j {
                if !tiles.row_is(j, k, i, i, true) {
                    return false;
                }
            }
        }
    }
    if let Some(k) = behind[2] {
        for j in r.lo.j..=r.hi.j {
            if !tiles.row_is(j, k, lo, hi, true) {
                return false;
            }
        }
    }
    true
}

/// Whether every tile behind a held face under `r` (the row `behind[axis]`
/// across the other two axes) is solid and, if `own`, every tile of `r` empty.
#[inline(never)]
fn fits(tiles: Tiles<'_>, r: &TileRange, behind: &[Option<i32>; 3], own: bool) -> bool {
    // Axis 3: the range itself, whose tiles must be empty; first, so that a row
    // that meets a wall fails on it before the tiles behind the held faces are
    // read.
    for axis in [3, 0, 1, 2] {
        if axis == 3 && !own {
            continue;
        }
        let mut s = *r;
        match behind.get(axis) {
            Some(Some(row)) => {
                let (lo, hi) = s.axis_mut(axis);
                (*lo, *hi) = (*row, *row);
            }
            Some(None) => continue,
            None => {}
        }
        // A row along x' at a time: a word of the grid answers for its tiles.
        for k in s.lo.k..=s.hi.k {
            for j in s.lo.j..=s.hi.j {
                if !tiles.row_is(j, k, s.lo.i, s.hi.i, axis < 3) {
                    return false;
                }
            }
        }
    }
    true
}
