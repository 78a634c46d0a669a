//! Time integration at a fixed step `dt = 2^-k` s.
//!
//! Between tilt samples the acceleration is constant, and for constant acceleration
//!
//! ```text
//! p' = p + v·dt + ½·a·dt²        v' = v + a·dt
//! ```
//!
//! is the exact solution, not an approximation: the integrator adds no truncation
//! error of its own, whatever the step. `a·dt` and `½·a·dt²` (a [`Kick`]) are
//! computed once per tilt sample from integers with a single rounding each, and `v·dt`
//! is a rounding shift. So the free-flight step is three shifts and six adds per
//! marble, with no multiply, division or root.

use super::super::scalar::Scalar;
use super::super::vec::Vec3;

/// What a constant acceleration `a` does in one step.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Kick<S> {
    /// `a·dt`: velocity gained per step (pitch/s).
    pub dv: Vec3<S>,
    /// `½·a·dt²`: position gained per step from rest (pitch).
    pub dp: Vec3<S>,
}

/// Standard gravity in µm/s² per milli-g ×100 (9.80665 m/s² = 980 665 ×10⁻⁵).
const G_UM_PER_MG_X100: i64 = 980_665;

/// `a·dt` and `½·a·dt²` for an acceleration of `mg` milli-g, scaled by `num/den`,
/// in a layout of `pitch_um`, at `dt = 2^-k` s. Exact integers, one rounding each:
/// to nearest for `a·dt`; away from zero for `½·a·dt²`, because a displacement
/// rounded short of the pull would add `a·ε` of energy every step (measured: +4·10⁻⁴
/// over 10⁴ elastic bounces in I32F32), while one rounded past it only loses it.
pub fn kick_axis<S: Scalar>(mg: i32, num: i64, den: i64, pitch_um: u32, k: u32) -> (S, S) {
    // a [pitch/s²] = mg · 9.80665 mm/s² / pitch_mm = mg · 980 665 / (100 · pitch_µm).
    let n = mg as i64 * G_UM_PER_MG_X100 * num;
    let d = 100 * pitch_um as i64 * den;
    (S::ratio(n, d << k), S::ratio_away(n, d << (2 * k + 1)))
}

impl<S: Scalar> Kick<S> {
    /// The kick of a `g_mg` (milli-g, tile frame) acceleration whose tangential part
    /// (x', z') is scaled by `tangential = (num, den)`.
    pub fn from_mg(g_mg: [i32; 3], tangential: (i64, i64), pitch_um: u32, k: u32) -> Self {
        let (tx, px) = kick_axis(g_mg[0], tangential.0, tangential.1, pitch_um, k);
        let (ty, py) = kick_axis(g_mg[1], 1, 1, pitch_um, k);
        let (tz, pz) = kick_axis(g_mg[2], tangential.0, tangential.1, pitch_um, k);
        Kick { dv: Vec3::new(tx, ty, tz), dp: Vec3::new(px, py, pz) }
    }

    /// The sum of two kicks (constant accelerations add).
    pub fn plus(self, o: Self) -> Self {
        Kick { dv: self.dv + o.dv, dp: self.dp + o.dp }
    }

    /// This kick with each axis of its displacement limited to `±reach` (the step
    /// bound against tunnelling; it only binds for strong pulls at low step rates).
    pub fn clamped(self, reach: S) -> Self {
        Kick { dv: self.dv, dp: self.dp.clamp_abs(reach) }
    }

    /// This kick with its components along the unit normal `n` removed.
    pub fn without_normal(self, n: Vec3<S>) -> Self {
        Kick { dv: self.dv - n.scale(self.dv.dot(n)), dp: self.dp - n.scale(self.dp.dot(n)) }
    }
}

/// One step of exact constant-acceleration motion: `p += v·dt + ½a·dt²`, `v += a·dt`.
#[inline]
pub fn advance<S: Scalar>(p: &mut Vec3<S>, v: &mut Vec3<S>, kick: &Kick<S>, k: u32) {
    *p += v.shr(k) + kick.dp;
    *v += kick.dv;
}

/// The flat-maze version of [`advance`]: the marble stays on the floor, y' is left alone.
#[inline]
pub fn advance_plane<S: Scalar>(p: &mut Vec3<S>, v: &mut Vec3<S>, kick: &Kick<S>, k: u32) {
    p.x += v.x.shr(k) + kick.dp.x;
    p.z += v.z.shr(k) + kick.dp.z;
    v.x += kick.dv.x;
    v.z += kick.dv.z;
}
