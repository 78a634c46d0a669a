//! Marble–tile distance (eq. 8), extended with the contact normal and depth.
//!
//! Eq. 8 sums the squares of the six per-face excesses `d_{x'±}, d_{y'±}, d_{z'±}`;
//! at most one of each pair is non-zero, so they form one signed vector
//! `d = c − clamp(c, box)`: the offset from the closest point of the box to the
//! centre. `|d| − r` is eq. 8, `d/|d|` the contact normal.
//!
//! Three refinements the seed leaves open, each a named hard case:
//! * **Face contacts need no root.** When only one component of `d` is non-zero
//!   (the common case: a wall or the floor), the normal is that axis and the depth
//!   `r − |d_axis|`.
//! * **Inside the box** (`d = 0`: the centre on a face, edge or corner, or deeper),
//!   the normal is the nearest *exposed* face, the depth `r` plus the distance to it.
//! * **Ghost bumps.** A tile whose closest point lies on a face shared with another
//!   solid tile is skipped: that neighbour is at least as close and owns the contact.
//!   Seams between floor tiles and between the tiles of one wall then produce no
//!   sideways normals, which is what makes other engines "bump".

use super::super::scalar::Scalar;
use super::super::vec::Vec3;
use super::grid::Tiles;
use super::tiles::{Aabb, TileIndex};

/// `d = c − clamp(c, box)`; its components are eq. 8's `d_{x'+} − d_{x'-}` etc.
#[inline]
pub fn offset<S: Scalar>(c: Vec3<S>, b: &Aabb<S>) -> Vec3<S> {
    let axis = |v: S, lo: S, hi: S| {
        if v > hi {
            v - hi
        } else if v < lo {
            v - lo
        } else {
            S::ZERO
        }
    };
    Vec3::new(
        axis(c.x, b.min.x, b.max.x),
        axis(c.y, b.min.y, b.max.y),
        axis(c.z, b.min.z, b.max.z),
    )
}

/// Eq. 8 as the seed writes it: distance between the marble's surface and the tile
/// (negative when they overlap). Uses a square root: tests and tools only; the step
/// compares squares instead.
pub fn distance<S: Scalar>(c: Vec3<S>, r: S, b: &Aabb<S>) -> S {
    offset(c, b).length_sq().sqrt() - r
}

/// Whether the centre is a whole radius or more from the box along some axis: then
/// the marble cannot touch it, and [`contact`] says so at its first test (the very
/// same comparisons). The step asks this before running the contact passes at all.
#[inline]
pub(crate) fn out_of_reach<S: Scalar>(c: Vec3<S>, r: S, b: &Aabb<S>) -> bool {
    beyond(offset(c, b), r)
}

#[inline]
fn beyond<S: Scalar>(d: Vec3<S>, r: S) -> bool {
    d.x.abs() >= r || d.y.abs() >= r || d.z.abs() >= r
}

/// Seed §1.3.5: the marble overlaps the tile (`d < 0` in eq. 8), without a root.
#[inline]
pub fn overlaps<S: Scalar>(c: Vec3<S>, r: S, b: &Aabb<S>) -> bool {
    let d = offset(c, b);
    if beyond(d, r) {
        return false;
    }
    d.length_sq() < r.times(r)
}

/// Which part of the tile the marble touches.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Feature {
    /// A face; the normal is along this axis (0 = x', 1 = y', 2 = z').
    Face(u8),
    /// An edge or a corner: the normal is not axis-aligned.
    Edge,
    /// The centre is on or inside the box.
    Inside,
}

/// A marble–tile contact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact<S> {
    /// Unit normal pointing out of the tile, towards the marble's centre.
    pub normal: Vec3<S>,
    /// Penetration depth: `r` minus the centre's distance to the tile (`> 0`).
    pub depth: S,
    /// The touched feature.
    pub feature: Feature,
    /// For an axis-aligned normal (a face, or leaving the box through one): the
    /// face's coordinate on that axis, so the marble can be put exactly at `plane ± r`
    /// (in floating point `p + (r − (p − plane))` is not always `plane + r`).
    pub plane: S,
}

fn neighbour(t: TileIndex, axis: usize, up: bool) -> TileIndex {
    let d = if up { 1 } else { -1 };
    match axis {
        0 => TileIndex::new(t.i + d, t.j, t.k),
        1 => TileIndex::new(t.i, t.j + d, t.k),
        _ => TileIndex::new(t.i, t.j, t.k + d),
    }
}

/// The unit vector along `axis`, up it if `positive` (a face's outward normal).
pub(crate) fn unit<S: Scalar>(axis: usize, positive: bool) -> Vec3<S> {
    let v = if positive { S::ONE } else { -S::ONE };
    match axis {
        0 => Vec3::new(v, S::ZERO, S::ZERO),
        1 => Vec3::new(S::ZERO, v, S::ZERO),
        _ => Vec3::new(S::ZERO, S::ZERO, v),
    }
}

/// The contact between a marble (centre `c`, radius `r`) and the solid tile `t` with
/// box `b`, or `None` when they do not overlap or a solid neighbour owns the contact.
pub fn contact<S: Scalar>(
    c: Vec3<S>,
    r: S,
    t: TileIndex,
    b: &Aabb<S>,
    tiles: Tiles<'_>,
) -> Option<Contact<S>> {
    let d = offset(c, b);
    if beyond(d, r) {
        return None;
    }
    // Ghost-bump rule: the closest point is on a face shared with a solid tile.
    // Axis by axis, not a loop over an axis index: the contact passes ask this
    // for every solid tile in reach, and on the Cortex-M0 the indexed reads
    // of a `Vec3` and the neighbour's index cost more than the tests.
    let step = |v: S| if v > S::ZERO { 1 } else { -1 };
    let (on_x, on_y, on_z) = (d.x != S::ZERO, d.y != S::ZERO, d.z != S::ZERO);
    if (on_x && tiles.is_solid(TileIndex::new(t.i + step(d.x), t.j, t.k)))
        || (on_y && tiles.is_solid(TileIndex::new(t.i, t.j + step(d.y), t.k)))
        || (on_z && tiles.is_solid(TileIndex::new(t.i, t.j, t.k + step(d.z))))
    {
        return None;
    }
    let nonzero = on_x as u8 + on_y as u8 + on_z as u8;
    let face_axis = if on_z {
        2
    } else if on_y {
        1
    } else {
        0
    };
    match nonzero {
        0 => inside(c, r, t, b, tiles),
        1 => {
            let v = d.axis(face_axis);
            let plane = if v > S::ZERO {
                b.max.axis(face_axis)
            } else {
                b.min.axis(face_axis)
            };
            Some(Contact {
                normal: unit(face_axis, v > S::ZERO),
                depth: r - v.abs(),
                feature: Feature::Face(face_axis as u8),
                plane,
            })
        }
        _ => {
            let len2 = d.length_sq();
            if len2 >= r.times(r) {
                return None;
            }
            // The normal from an inverse root: no root, no division.
            let inv = len2.rsqrt();
            if inv == S::ZERO {
                return inside(c, r, t, b, tiles);
            }
            Some(Contact {
                normal: d.scale(inv),
                depth: r - len2.times(inv),
                feature: Feature::Edge,
                plane: S::ZERO,
            })
        }
    }
}

/// The ghost-bump rule on its own: whether the closest point of tile `t` to a centre
/// at offset `d` (see [`offset`]) lies on a face shared with a solid neighbour, which
/// then owns the contact ([`contact`] skips such tiles the same way).
pub(crate) fn shadowed<S: Scalar>(t: TileIndex, d: Vec3<S>, tiles: Tiles<'_>) -> bool {
    (0..3).any(|axis| {
        let v = d.axis(axis);
        v != S::ZERO && tiles.is_solid(neighbour(t, axis, v > S::ZERO))
    })
}

/// A contact with tile `t` (box `b`) found at offset `d` from its closest point, as
/// the solid tiles around it see it: the components of `d` that point into a solid
/// neighbour lie inside the union of tiles and are dropped (the ghost-bump rule of
/// [`contact`], applied to a touch rather than an overlap). What is left is a face
/// of the union (one component), an edge (two or three), or nothing (a tile buried
/// on that side). Event stepping uses it: two tiles of a wall both see a marble
/// arriving on their seam as touching their rounded edge, and each edge is the
/// other's face.
pub fn owned<S: Scalar>(
    t: TileIndex,
    b: &Aabb<S>,
    d: Vec3<S>,
    r: S,
    tiles: Tiles<'_>,
) -> Option<Contact<S>> {
    let mut e = Vec3::ZERO;
    let mut nonzero = 0;
    let mut axis = 0;
    for a in 0..3 {
        let v = d.axis(a);
        if v != S::ZERO && !tiles.is_solid(neighbour(t, a, v > S::ZERO)) {
            e.set_axis(a, v);
            nonzero += 1;
            axis = a;
        }
    }
    match nonzero {
        0 => None,
        1 => {
            let v = e.axis(axis);
            let up = v > S::ZERO;
            Some(Contact {
                normal: unit(axis, up),
                depth: r - v.abs(),
                feature: Feature::Face(axis as u8),
                plane: if up {
                    b.max.axis(axis)
                } else {
                    b.min.axis(axis)
                },
            })
        }
        _ => {
            let len2 = e.length_sq();
            let inv = len2.rsqrt_fine();
            (inv != S::ZERO).then(|| Contact {
                normal: e.scale(inv),
                depth: r - len2.times(inv),
                feature: Feature::Edge,
                plane: S::ZERO,
            })
        }
    }
}

/// The centre is on or inside the box: leave through the nearest exposed face.
fn inside<S: Scalar>(
    c: Vec3<S>,
    r: S,
    t: TileIndex,
    b: &Aabb<S>,
    tiles: Tiles<'_>,
) -> Option<Contact<S>> {
    let mut best: Option<(S, usize, bool)> = None;
    for axis in 0..3 {
        for up in [false, true] {
            if tiles.is_solid(neighbour(t, axis, up)) {
                continue;
            }
            let gap = if up {
                b.max.axis(axis) - c.axis(axis)
            } else {
                c.axis(axis) - b.min.axis(axis)
            };
            if best.is_none_or(|(g, _, _)| gap < g) {
                best = Some((gap, axis, up));
            }
        }
    }
    // A tile buried on all six sides cannot be reached from outside: no contact.
    let (gap, axis, up) = best?;
    let plane = if up {
        b.max.axis(axis)
    } else {
        b.min.axis(axis)
    };
    Some(Contact {
        normal: unit(axis, up),
        depth: r + gap,
        feature: Feature::Inside,
        plane,
    })
}

/// The maze's lid: a plane on top of the walls (`y' = l`), as on the real toy. It
/// only matters in 3-D scenes (the flat maze keeps the marble on the floor anyway):
/// shaken upside down, the marble stays in the maze instead of flying out of it.
#[inline]
pub(crate) fn lid_contact<S: Scalar>(c: Vec3<S>, r: S, top: S) -> Option<Contact<S>> {
    let depth = c.y + r - top;
    if depth <= S::ZERO {
        return None;
    }
    Some(Contact {
        normal: Vec3::new(S::ZERO, -S::ONE, S::ZERO),
        depth,
        feature: Feature::Face(1),
        plane: top,
    })
}

#[cfg(test)]
mod tests {
    use super::super::grid::TileGrid;
    use super::super::tiles::TileLayout;
    use super::*;
    use fixed::types::I8F24;

    type S = I8F24;

    /// What the step skips the contact passes on is what `contact` finds nothing on,
    /// and a marble resting on a face from below that face's axis is among it.
    #[test]
    fn out_of_reach_means_no_contact() {
        let layout = TileLayout::<S>::from_um(2_000, 10_000).unwrap();
        let mut grid = TileGrid::<8>::new(5, 2, 5).unwrap();
        let t = TileIndex::new(2, 1, 2);
        grid.set(2, 1, 2, true);
        let (tiles, b) = (grid.view(), layout.tile_box(t));
        let r = layout.from_um_len(3_500);
        let y = r;
        let held = Vec3::new(b.min.x - r, y, b.min.z + Scalar::half(layout.s));
        assert!(out_of_reach(held, r, &b));
        // Every 1/32 pitch over the tile and a cell around it.
        for a in 0..96 {
            for c in 0..96 {
                let (x, z) = (S::ratio(a, 32), S::ratio(c, 32));
                let p = Vec3::new(x, y, z);
                if out_of_reach(p, r, &b) {
                    assert_eq!(contact(p, r, t, &b, tiles), None, "{p:?}");
                }
            }
        }
    }
}
