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
/// Fraction bits of a [`PullScale`].
const SCALE_SHIFT: u32 = 56;

/// The boards' step (`GameConfig::EVENTS`: one event step a 1/128 s frame),
/// whose kicks take their shifts as constants: `a·dt` by `SCALE_SHIFT + k`,
/// `½·a·dt²` by `SCALE_SHIFT + 2k + 1`.
const BOARD_K: u32 = 7;
const BOARD_DV_SHIFT: u32 = SCALE_SHIFT + BOARD_K;
const BOARD_DP_SHIFT: u32 = SCALE_SHIFT + 2 * BOARD_K + 1;

/// Pitches/s² per milli-g (times a ratio such as rolling's 5/7), as an integer with
/// 56 fraction bits (10⁻¹⁸ relative: exact even for the `f64` reference): computed once per level with one division, after which a
/// tilt sample's kick is a multiply and a shift per axis — no division on the
/// per-sample path (a 64-bit division is a library call on Cortex-M).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PullScale(i64);

impl PullScale {
    /// The scale for `a = mg · 9.80665 mm/s² · num/den` in a layout of `pitch_um`
    /// (`num ≥ 0`, `den > 0`), rounded to nearest.
    ///
    /// `round(980 665·num·2^56 / (100·pitch_um·den))` by long division in 64 bits,
    /// 16 quotient bits at a time: the numerator needs 99 bits, and 128-bit
    /// arithmetic cost the micro:bit v1 over a kilobyte of its 64 KiB of flash for
    /// a function that runs three times per level. The divisor stays below 2^48
    /// (pitch ≤ 100 mm, `den` ≤ 2^24), so each shifted remainder fits.
    pub fn new(num: i64, den: i64, pitch_um: u32) -> Self {
        let a = G_UM_PER_MG_X100 as u64 * num.max(0) as u64;
        let d = 100 * u64::from(pitch_um) * den.max(1) as u64;
        let (mut q, mut r) = (a / d, a % d);
        for bits in [16, 16, 16, SCALE_SHIFT - 48] {
            r <<= bits;
            q = match q.checked_mul(1 << bits) {
                Some(q) => q | (r / d),
                None => return PullScale(i64::MAX),
            };
            r %= d;
        }
        // Half up: the remainder against the divisor's half, rounded down.
        q += u64::from(r >= d - d / 2);
        PullScale(q.min(i64::MAX as u64) as i64)
    }

    /// `a·dt` (to nearest) and `½·a·dt²` (away from zero) for `mg` milli-g at
    /// `dt = 2^-k` s. The displacement is rounded away from zero because one rounded
    /// short of the pull would add `a·ε` of energy every step (measured: +4·10⁻⁴ over
    /// 10⁴ elastic bounces in I32F32), while one rounded past it only loses it.
    pub fn kick<S: Scalar>(self, mg: i32, k: u32) -> (S, S) {
        // The boards' step with its shifts constant, every other rate at run time.
        if k == BOARD_K {
            S::from_pull_at::<BOARD_DV_SHIFT, BOARD_DP_SHIFT>(mg, self.0)
        } else {
            S::from_pull(mg, self.0, SCALE_SHIFT + k, SCALE_SHIFT + 2 * k + 1)
        }
    }

    /// [`PullScale::kick`] for a pull the number format holds (`|a·dt|` within
    /// its range: `Params::mg_max` bounds event stepping's pull so), the same
    /// bits: at the boards' step rate without the quotients' saturation.
    #[inline(always)]
    pub fn kick_fits<S: Scalar>(self, mg: i32, k: u32) -> (S, S) {
        if k == BOARD_K {
            S::from_pull_fits_at::<BOARD_DV_SHIFT, BOARD_DP_SHIFT>(mg, self.0)
        } else {
            self.kick(mg, k)
        }
    }
}

impl<S: Scalar> Kick<S> {
    /// One axis of the kick of a `mg` milli-g pull scaled by `scale`: `(a·dt, ½·a·dt²)`
    /// with the displacement limited to `±reach` (the step bound against tunnelling;
    /// it only binds for strong pulls at low step rates). Each axis depends on that
    /// axis of the pull alone, so a tilt that moves one axis recomputes one.
    pub(crate) fn axis_of(mg: i32, scale: PullScale, reach: S, k: u32) -> (S, S) {
        let (dv, dp) = scale.kick::<S>(mg, k);
        (dv, dp.clamp(-reach, reach))
    }

    /// Sets axis `axis` (0 = x', 1 = y', 2 = z') to `(dv, dp)`.
    pub(crate) fn set_axis(&mut self, axis: usize, (dv, dp): (S, S)) {
        self.dv.set_axis(axis, dv);
        self.dp.set_axis(axis, dp);
    }

    /// The sum of two kicks (constant accelerations add).
    pub fn plus(self, o: Self) -> Self {
        Kick {
            dv: self.dv + o.dv,
            dp: self.dp + o.dp,
        }
    }

    /// This kick with each axis of its displacement limited to `±reach` (the step
    /// bound against tunnelling; it only binds for strong pulls at low step rates).
    pub fn clamped(self, reach: S) -> Self {
        Kick {
            dv: self.dv,
            dp: self.dp.clamp_abs(reach),
        }
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
pub(crate) fn advance_plane<S: Scalar>(p: &mut Vec3<S>, v: &mut Vec3<S>, kick: &Kick<S>, k: u32) {
    p.x += v.x.shr(k) + kick.dp.x;
    p.z += v.z.shr(k) + kick.dp.z;
    v.x += kick.dv.x;
    v.z += kick.dv.z;
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 128-bit formula the long division replaces.
    fn reference(num: i64, den: i64, pitch_um: u32) -> i64 {
        let n = (G_UM_PER_MG_X100 as i128 * num as i128) << SCALE_SHIFT;
        let d = 100 * pitch_um as i128 * den as i128;
        ((n + d / 2) / d).min(i64::MAX as i128) as i64
    }

    #[test]
    fn long_division_equals_the_128_bit_formula() {
        let edges = [
            (1, 1, 12_000),
            (5, 7, 12_000),
            (10_000 * 5, 1_000_000 * 7, 12_000),
            (1, 1, 1_000),
            (1, 1, 100_000),
            (5_000_000, 7_000_000, 1_000),
            (0, 7, 12_000),
            (1_000_000, 1, 1_000),
        ];
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let random = core::iter::repeat_with(move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            let num = (x % 5_000_001) as i64;
            let den = ((x >> 23) % 7_000_000 + 1) as i64;
            let pitch = ((x >> 45) % 99_001 + 1_000) as u32;
            (num, den, pitch)
        });
        for (num, den, pitch) in edges.into_iter().chain(random.take(200_000)) {
            assert_eq!(
                PullScale::new(num, den, pitch).0,
                reference(num, den, pitch),
                "{num}/{den} at {pitch} µm"
            );
        }
    }
}
