//! The event step's reach test: can the marble touch anything at all in an
//! interval? Eq. 7's broadphase, applied to the box the centre sweeps instead of
//! the centre itself — no root, no division.
//!
//! Over `σ ∈ [0, len]` the centre follows `c(σ) = p + u·σ + h·σ²`. Along each axis
//! the parabola lies between its chord and the chord moved by `|h|·len²/4` towards
//! the side it bends to (`h·σ(σ − len)` is smallest at `σ = len/2`), so the box of
//! its two ends widened that way holds the whole path ([`swept`]). A tile can be
//! touched only if it lies within a radius of that box: eq. 6 on the box's corners
//! moved out by the radius gives the candidate index range ([`reach`]). In a maze
//! nearly every frame finds no solid tile there, and the frame is then one
//! closed-form update.

use super::super::scalar::Scalar;
use super::super::vec::Vec3;
use super::broadphase::TileRange;
use super::tiles::{Aabb, TileIndex, TileLayout};

/// The box holding the centre's path from `p` (at 0) to `end` (at `len`) bending
/// with `h` (half the acceleration, per step²).
#[inline]
pub(crate) fn swept<S: Scalar>(p: Vec3<S>, end: Vec3<S>, h: Vec3<S>, len: S) -> Aabb<S> {
    let quarter = quarter(len);
    let (x0, x1) = swept_axis(p.x, end.x, h.x, quarter);
    let (y0, y1) = swept_axis(p.y, end.y, h.y, quarter);
    let (z0, z1) = swept_axis(p.z, end.z, h.z, quarter);
    Aabb {
        min: Vec3::new(x0, y0, z0),
        max: Vec3::new(x1, y1, z1),
    }
}

/// `len²/4`, the bulge's factor over `len` steps (`None` for a whole step:
/// a shift instead).
#[inline]
pub(crate) fn quarter<S: Scalar>(len: S) -> Option<S> {
    if len == S::ONE {
        None
    } else {
        Some(len.times(len).shr(2))
    }
}

/// One axis of [`swept`]: from `a` to `b` bending with `h`, `quarter` from
/// [`quarter`].
#[inline(always)]
pub(crate) fn swept_axis<S: Scalar>(a: S, b: S, h: S, quarter: Option<S>) -> (S, S) {
    let bulge = match quarter {
        None => h.abs().shr(2),
        Some(q) => h.abs().times(q),
    };
    let (mut lo, mut hi) = if a < b { (a, b) } else { (b, a) };
    // A positive h bends the path down from the chord, a negative one up; one
    // LSB more for the rounding of the ends.
    let lsb = S::lsb();
    if h > S::ZERO {
        lo = lo - bulge - lsb;
    } else if h < S::ZERO {
        hi = hi + bulge + lsb;
    }
    (lo, hi)
}

/// The tiles within `r` of the box `b` (eq. 7 on the swept box); in the plane
/// (`space == false`) the wall layer only.
#[inline]
pub fn reach<S: Scalar>(layout: &TileLayout<S>, b: &Aabb<S>, r: S, space: bool) -> TileRange {
    let (j0, j1) = if space {
        (layout.index_y(b.min.y - r), layout.index_y(b.max.y + r))
    } else {
        (1, 1)
    };
    TileRange {
        lo: TileIndex::new(
            layout.index_xz(b.min.x - r),
            j0,
            layout.index_xz(b.min.z - r),
        ),
        hi: TileIndex::new(
            layout.index_xz(b.max.x + r),
            j1,
            layout.index_xz(b.max.z + r),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_swept_box_holds_the_path() {
        type S = fixed::types::I8F24;
        let f = S::from_f64;
        for (u, h) in [
            (0.5, -0.3),
            (-0.2, 0.4),
            (0.0, 0.25),
            (0.7, 0.0),
            (0.1, -0.6),
        ] {
            for len in [1.0, 0.5, 0.3] {
                let p = Vec3::new(f(3.0), f(0.2), f(5.0));
                let uu = Vec3::new(f(u), S::ZERO, f(-u));
                let hh = Vec3::new(f(h), S::ZERO, f(h / 2.0));
                let at = |s: f64| {
                    let s = f(s);
                    p + uu.scale(s) + hh.scale(s.times(s))
                };
                let b = swept(p, at(len), hh, f(len));
                for n in 0..=64 {
                    let c = at(len * n as f64 / 64.0);
                    for a in [0, 2] {
                        let tol = 4e-7;
                        assert!(
                            c.axis(a).to_f64() >= b.min.axis(a).to_f64() - tol
                                && c.axis(a).to_f64() <= b.max.axis(a).to_f64() + tol,
                            "u {u} h {h} len {len} step {n}: {c:?} outside {b:?}"
                        );
                    }
                }
            }
        }
    }
}
