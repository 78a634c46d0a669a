//! The event step's speed limit ([`cap_speed`]: the number format's range, so
//! that no velocity overflows I8F24) and the magnitudes its flights compare.
//! Apart from the step because the fixed step's contact layer and the pair code
//! cap with it too.

use super::{Scalar, Vec3, T_LOG2};

/// The event step's speed limit, the number format's range: `|v| ≤ 127 pitch/s`
/// (I8F24 holds ±128, and a velocity's component along any direction must fit, not
/// only its axes). Faster is scaled back along its own direction (energy is lost,
/// nothing overflows).
#[inline(always)]
pub(crate) fn cap_speed<S: Scalar>(v: Vec3<S>) -> Vec3<S> {
    // Under 127/√3 on every axis: under 127 whatever the direction. Compared
    // without `abs` (I8F24's MIN has none), so that this test, the one almost
    // every flight takes, stays inline where the rest is not.
    let quick = S::from_int(73);
    if v.x < quick && v.x > -quick && v.y < quick && v.y > -quick && v.z < quick && v.z > -quick {
        return v;
    }
    cap_speed_far(v)
}

/// [`cap_speed`] past the quick test.
fn cap_speed_far<S: Scalar>(v: Vec3<S>) -> Vec3<S> {
    // A saturated axis (I8F24's MIN) first back to −MAX, whose magnitude exists.
    let v = v.clamp_abs(S::from_int(128));
    // In pitch/T (1/32 s): components ≤ 4, squares ≤ 48.
    let top = S::from_int(127).shr(T_LOG2);
    let s2 = v.shr(T_LOG2).length_sq();
    if s2 <= top.times(top) {
        return v;
    }
    v.scale(top.times(s2.rsqrt_fine()))
}

/// `v`, scaled down if need be so that it is no faster than `than` (compared in
/// pitch/T, squares in range): `|v|·(1 − x)` with `x` the relative excess of the
/// squares is at most `|than|`.
#[inline]
pub(super) fn no_faster<S: Scalar>(v: Vec3<S>, than: Vec3<S>) -> Vec3<S> {
    let (a, b) = (v.shr(T_LOG2).length_sq(), than.shr(T_LOG2).length_sq());
    if a <= b {
        return v;
    }
    let keep = S::ONE - (a - b).div(a);
    v.scale(keep.max(S::ZERO))
}

/// The largest of `v`'s components in magnitude.
pub(super) fn max_abs<S: Scalar>(v: Vec3<S>) -> S {
    v.x.abs().max(v.y.abs()).max(v.z.abs())
}
