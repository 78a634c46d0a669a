//! The number type the physics is written against.
//!
//! # Units and the default fixed format
//!
//! Lengths are measured in **cell pitches**: one pitch is `s + l`, a short tile plus a
//! long tile. In that unit the seed's `⌊a / (s+l)⌋` (eq. 6) is the integer part of `a`,
//! so point → tile costs a floor and one compare instead of a division. Time is in
//! seconds, velocities in pitches per second.
//!
//! The firmware default is [`I8F24`]: a 32-bit word with 24 fraction bits. Its range,
//! ±128 pitches, holds the largest board the level format allows (127 tiles = 64
//! pitches per axis) with a margin for a marble falling off an edge, after which the
//! marble is frozen (see `MarbleState::Out`). One LSB is 2⁻²⁴ pitch, about 0.7 nm
//! at a 12 mm pitch, so the quantities that are small in this unit stay exact enough:
//!
//! * the velocity gained per step, `g·dt` at 0.01 g and 1024 steps/s, is about
//!   0.008 pitch/s = 130 000 LSB (relative rounding 4·10⁻⁶);
//! * `g·dt²`, the position gained from rest in one step, is 7.8·10⁻⁶ pitch = 130 LSB.
//!   That is why the integrator never forms `g·dt²` from rounded parts: it adds the
//!   exact `½·a·dt²` that is precomputed once per tilt sample (see `integrate`).
//!
//! Accelerations in pitches/s² (a full `g` is ~800 pitch/s²) do not fit in I8F24,
//! so the physics never stores them: it stores velocity increments per step.
//! Millimetres with I16F16 were the other candidate; there `g·dt` at 0.01 g is 6 400
//! LSB and the per-step rounding of the velocity gives 0.3 mm after 10 s — six times
//! the accuracy target — which is why the unit is the pitch and not the millimetre.
//!
//! Only the contact path divides or takes square roots ([`Scalar::sqrt`],
//! [`Scalar::div`]); the free-flight step is adds, shifts and a few multiplies.

use core::fmt::Debug;
use core::ops::{Add, AddAssign, Mul, Neg, Sub, SubAssign};

use fixed::types::{I16F16, I32F32, I8F24};

/// A real number as the physics needs it. Implemented for three fixed-point formats,
/// `f32`, [`MicroF32`] (f32 with `micromath`'s approximate square root) and `f64`.
pub trait Scalar:
    Copy
    + PartialOrd
    + PartialEq
    + Debug
    + Default
    + Add<Output = Self>
    + Sub<Output = Self>
    + Mul<Output = Self>
    + Neg<Output = Self>
    + AddAssign
    + SubAssign
    + 'static
{
    /// Zero.
    const ZERO: Self;
    /// One.
    const ONE: Self;
    /// A short stable name, used by tools and reports.
    const NAME: &'static str;
    /// Whether [`Scalar::sqrt`] is correctly rounded (all but micromath's).
    const EXACT_SQRT: bool = true;
    /// Whether a dot product with a unit axis (one component ±1, the others 0)
    /// is that component of the other vector, ± and bit for bit, and such an
    /// axis scaled by `k` is `±k` there and 0 elsewhere: the fixed-point
    /// formats, whose products by 0 and ±1 are exact; not the floating-point
    /// ones, where a sum with a product by 0 can turn a −0 into +0.
    const EXACT_UNIT: bool = false;
    /// The integer `n`, exactly (`|n| < 128` for the narrowest format).
    fn from_int(n: i32) -> Self;
    /// `self · rhs`: the value of `*`, bit for bit, and its overflow check in debug
    /// builds. Fixed point forms it with one widening multiply and a shift, where
    /// the `fixed` operator multiplies by an operand shifted up first, which takes a
    /// double-width multiply (three multiplies and the shifts on a Cortex-M): the
    /// per-step products (vectors, rolling resistance, the board's motion) use this.
    #[inline(always)]
    fn times(self, rhs: Self) -> Self {
        self * rhs
    }
    /// The nearest value to `x` (setup and tests; not used inside the step).
    fn from_f64(x: f64) -> Self;
    /// `num / den`, rounded to nearest; setup only (`den != 0`).
    fn ratio(num: i64, den: i64) -> Self {
        Self::from_f64(num as f64 / den as f64)
    }
    /// `n·2^-shift`, rounded to nearest, or away from zero when `away` (the integer
    /// path of the per-sample kick: a multiply and a shift, no division).
    fn from_scaled(n: i128, shift: u32, away: bool) -> Self {
        let exact = n as f64 / (1u128 << shift.min(127)) as f64;
        let x = Self::from_f64(exact);
        if away && x.to_f64().abs() < exact.abs() {
            if exact > 0.0 {
                -((-x).next_down())
            } else {
                x.next_down()
            }
        } else {
            x
        }
    }
    /// A tilt sample's kick `(a·dt, ½·a·dt²)` from `mg` milli-g and a pull's
    /// `scale ≥ 0`: `mg · scale · 2^-dv_shift` rounded to nearest and `mg · scale ·
    /// 2^-dp_shift` rounded away from zero, each as [`Scalar::from_scaled`] rounds.
    /// Fixed point forms the 95-bit product once, from two 32 × 32 → 64 multiplies,
    /// where `from_scaled` takes a 128-bit one (on the Cortex-M0 a 128-bit product
    /// is six library multiplies): every tilt sample pays for it, on every axis
    /// it moves.
    fn from_pull(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self) {
        let n = mg as i128 * scale as i128;
        (
            Self::from_scaled(n, dv_shift, false),
            Self::from_scaled(n, dp_shift, true),
        )
    }
    /// [`Scalar::from_pull`] with its shifts known when compiled: the same
    /// bits, where fixed point shifts its words by constants (the boards'
    /// step rate, every tilt sample).
    #[inline]
    fn from_pull_at<const DV_SHIFT: u32, const DP_SHIFT: u32>(mg: i32, scale: i64) -> (Self, Self) {
        Self::from_pull(mg, scale, DV_SHIFT, DP_SHIFT)
    }
    /// [`Scalar::from_pull_at`] for a kick the format holds without
    /// saturating (the caller's bound on `mg` says so: `World::pull_axis`):
    /// the same bits, where a 32-bit fixed-point format takes the rounded
    /// quotients on one word, with no saturation.
    #[inline]
    fn from_pull_fits_at<const DV_SHIFT: u32, const DP_SHIFT: u32>(
        mg: i32,
        scale: i64,
    ) -> (Self, Self) {
        Self::from_pull_at::<DV_SHIFT, DP_SHIFT>(mg, scale)
    }
    /// The value as `f64` (exact for every implemented type except `f64` itself,
    /// which is the identity).
    fn to_f64(self) -> f64;
    /// `⌊self⌋` as an integer, exact.
    fn floor_int(self) -> i32;
    /// `self · 2^-n`, rounded to nearest for fixed point: a time step `dt = 2^-n`
    /// multiplies without a multiplier and without bias.
    fn shr(self, n: u32) -> Self;
    /// `self · 2^n`, saturating at the type's range (fixed point).
    fn shl(self, n: u32) -> Self;
    /// Square root of a non-negative value (contact path only). Negative → zero.
    fn sqrt(self) -> Self;
    /// `self / rhs` for `rhs != 0` (contact path only); zero when `rhs == 0`.
    fn div(self, rhs: Self) -> Self;
    /// `1/√self` for `self > 0` (zero otherwise): what normalising a vector takes.
    /// Fixed point computes it with integer Newton steps and no division (see
    /// `rsqrt_bits`); floating point with a root and a division.
    fn rsqrt(self) -> Self {
        if self <= Self::ZERO {
            Self::ZERO
        } else {
            Self::ONE.div(self.sqrt())
        }
    }
    /// [`Scalar::sqrt`] to the format's precision: itself when exact, two Newton
    /// steps on an approximate one (event stepping's times and speeds).
    #[inline]
    fn sqrt_fine(self) -> Self {
        let mut s = self.sqrt();
        if !Self::EXACT_SQRT && s > Self::ZERO {
            for _ in 0..2 {
                s = (s + self.div(s)).half();
            }
        }
        s
    }
    /// [`Scalar::rsqrt`] to the format's precision: itself when exact, two Newton
    /// steps `y·(3 − x·y²)/2` on an approximate one (event stepping's normals).
    #[inline]
    fn rsqrt_fine(self) -> Self {
        let mut y = self.rsqrt();
        if !Self::EXACT_SQRT && y > Self::ZERO {
            for _ in 0..2 {
                y = y * (Self::from_int(3) - self * y * y).half();
            }
        }
        y
    }
    /// The next representable value below `self` (tests probe tile boundaries with it).
    fn next_down(self) -> Self;
    /// The format's least positive step at zero: one LSB of a fixed-point
    /// format (the rounding margin of the swept boxes, the tolerances).
    #[inline]
    fn lsb() -> Self {
        Self::ZERO - Self::ZERO.next_down()
    }
    /// `⌊log2 |self|⌋` (`i32::MIN` for zero): the event step scales its quadratics by
    /// a power of two with it, so that their squares keep every bit.
    fn ilog2(self) -> i32;
    /// `self + o`, saturating at the type's range (fixed point): the event step's
    /// velocity update, where the speed's only limit is the format's range.
    #[inline]
    fn sat_add(self, o: Self) -> Self {
        self + o
    }
    /// Bits of the exact value, for state hashing.
    fn hash_bits(self) -> u64;
    /// Absolute value.
    fn abs(self) -> Self {
        if self < Self::ZERO {
            -self
        } else {
            self
        }
    }
    /// `self / 2` (exact in fixed point up to the last bit).
    fn half(self) -> Self {
        self.shr(1)
    }
    /// The larger of two values.
    fn max(self, o: Self) -> Self {
        if self > o {
            self
        } else {
            o
        }
    }
    /// The smaller of two values.
    fn min(self, o: Self) -> Self {
        if self < o {
            self
        } else {
            o
        }
    }
    /// Clamped into `[lo, hi]`.
    fn clamp(self, lo: Self, hi: Self) -> Self {
        self.max(lo).min(hi)
    }
}

mod fixed_point;
mod float;
mod micro;
mod product;
mod quotient;
mod rsqrt;
#[cfg(test)]
mod pull_tests;
#[cfg(test)]
mod shift_tests;
#[cfg(test)]
mod tests;

pub use micro::MicroF32;
pub(crate) use rsqrt::rsqrt_bits;
