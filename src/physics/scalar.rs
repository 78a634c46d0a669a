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
    /// [`rsqrt_bits`]); floating point with a root and a division.
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

/// The fixed-point product on a format's bits: bits `FRAC..FRAC + N` of the
/// exact `2N`-bit product, wrapping.
trait FracProduct {
    fn mul_shr<const FRAC: u32>(self, rhs: Self) -> Self;
}

impl FracProduct for i32 {
    #[inline(always)]
    fn mul_shr<const FRAC: u32>(self, rhs: i32) -> i32 {
        mul_shr::<FRAC>(self, rhs)
    }
}

impl FracProduct for i64 {
    #[inline(always)]
    fn mul_shr<const FRAC: u32>(self, rhs: i64) -> i64 {
        ((self as i128 * rhs as i128) >> FRAC) as i64
    }
}

/// Bits `FRAC..FRAC + 32` of the exact product `a · b`, wrapping: the fixed-point
/// product of two 32-bit formats with `FRAC` fraction bits. One `smull` and a
/// shift where the core has a 32 × 32 → 64 multiply.
#[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
#[inline(always)]
fn mul_shr<const FRAC: u32>(a: i32, b: i32) -> i32 {
    ((a as i64 * b as i64) >> FRAC) as i32
}

/// Bits `FRAC..FRAC + 32` of the exact product `a · b` on ARMv6-M (the
/// Cortex-M0 of the micro:bit v1: recognised by its lack of 32-bit atomic
/// read-modify-write, as the architecture's own `target_feature`s are unstable).
///
/// Its `muls` keeps the low 32 bits only, so LLVM builds an `i64` product from a
/// call to the generic 64 × 64 library multiply (`__aeabi_lmul`, 37 instructions
/// with its stack frame), which was 27 % of the v1 demo's instructions. Both
/// operands are 32-bit here, which [`mul_shr_halves`] uses. Not inlined: one copy
/// for all the step's products keeps the v1 within its flash.
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
#[inline(never)]
fn mul_shr<const FRAC: u32>(a: i32, b: i32) -> i32 {
    mul_shr_halves::<FRAC>(a, b)
}

/// `mul_shr` from four 16 × 16 → 32 products, exact. With `a = ah·2¹⁶ + al`
/// (`ah` signed, `al` in `0..2¹⁶`) and `b` likewise, `a·b = ah·bh·2³² +
/// (ah·bl + al·bh)·2¹⁶ + al·bl`, and every partial product fits 32 bits:
/// `|ah·bh| ≤ 2³⁰`, `ah·bl` and `al·bh` lie in `[−2³¹ + 2¹⁵, 2³¹)`, `al·bl < 2³²`
/// unsigned. Only their sums need 64 bits, which are adds with carry.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
fn mul_shr_halves<const FRAC: u32>(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, a & 0xffff);
    let (bh, bl) = (b >> 16, b & 0xffff);
    let low = (al as u32 * bl as u32) as i64;
    let cross = (ah * bl) as i64 + (al * bh) as i64;
    let high = (ah * bh) as i64;
    (((high << 32) + (cross << 16) + low) >> FRAC) as i32
}

macro_rules! fixed_scalar {
    ($t:ty, $wide:ty, $name:literal) => {
        impl Scalar for $t {
            const ZERO: Self = <$t>::ZERO;
            const ONE: Self = <$t>::ONE;
            const NAME: &'static str = $name;
            #[inline(always)]
            fn times(self, rhs: Self) -> Self {
                // The operator keeps bits NBITS..2·NBITS of `a · (b << INT_NBITS)`,
                // wrapping; those are bits FRAC..FRAC+NBITS of the exact `a · b`
                // (it fits the wide type), which is what this keeps.
                // The operator's own check: that shifted product must not wrap.
                debug_assert!(
                    {
                        let (a, b) = (self.to_bits() as $wide, rhs.to_bits() as $wide);
                        !a.overflowing_mul(b << <$t>::INT_NBITS).1
                    },
                    "overflow"
                );
                <$t>::from_bits(
                    self.to_bits()
                        .mul_shr::<{ <$t>::FRAC_NBITS }>(rhs.to_bits()),
                )
            }
            #[inline]
            fn from_int(n: i32) -> Self {
                // A shift with a range check: the generic conversion costs far more.
                let int_bits = <$t>::INT_NBITS as i64 - 1;
                let n64 = n as i64;
                if n64 < (1i64 << int_bits) && n64 >= -(1i64 << int_bits) {
                    <$t>::from_bits(((n as i64) << <$t>::FRAC_NBITS) as _)
                } else if n < 0 {
                    <$t>::MIN
                } else {
                    <$t>::MAX
                }
            }
            fn from_f64(x: f64) -> Self {
                <$t>::saturating_from_num(x)
            }
            fn ratio(num: i64, den: i64) -> Self {
                // Exact rational → fixed, rounded to nearest, without going through f64.
                let frac = <$t>::FRAC_NBITS;
                // i64 when it fits: i128 division is a slow library call on Cortex-M.
                if num.unsigned_abs() < (1u64 << (62 - frac)) && den > 0 {
                    let scaled = num << frac;
                    let q = scaled.div_euclid(den);
                    let r = scaled.rem_euclid(den);
                    let q = if 2 * r >= den { q + 1 } else { q };
                    let bits = q.clamp(<$t>::MIN.to_bits() as i64, <$t>::MAX.to_bits() as i64);
                    return <$t>::from_bits(bits as _);
                }
                let scaled = (num as i128) << frac;
                let den = den as i128;
                let q = scaled.div_euclid(den);
                let r = scaled.rem_euclid(den);
                let q = if 2 * r.abs() >= den.abs() {
                    q + den.signum()
                } else {
                    q
                };
                let bits = q.clamp(<$t>::MIN.to_bits() as i128, <$t>::MAX.to_bits() as i128);
                <$t>::from_bits(bits as _)
            }
            #[inline]
            fn to_f64(self) -> f64 {
                self.to_num::<f64>()
            }
            #[inline]
            fn floor_int(self) -> i32 {
                // Arithmetic shift is floor division by 2^FRAC: exact for negatives too.
                (self.to_bits() >> <$t>::FRAC_NBITS) as i32
            }
            #[inline]
            fn shr(self, n: u32) -> Self {
                if n == 0 {
                    return self;
                }
                let bits = self.to_bits();
                // Round half away from zero so that +v and -v move by mirror amounts;
                // on the magnitude, so that neither MAX nor MIN can overflow.
                let m = bits.unsigned_abs();
                let q = ((m >> n) + ((m >> (n - 1)) & 1)) as i64;
                <$t>::from_bits((if bits < 0 { -q } else { q }) as _)
            }
            #[inline]
            fn shl(self, n: u32) -> Self {
                // A range check and a shift (the generic saturating multiply is a call).
                let bits = self.to_bits();
                let limit = <$t>::MAX.to_bits() >> n;
                if bits > limit {
                    <$t>::MAX
                } else if bits < -limit {
                    <$t>::MIN
                } else {
                    <$t>::from_bits(bits << n)
                }
            }
            fn sqrt(self) -> Self {
                if self <= <$t>::ZERO {
                    <$t>::ZERO
                } else {
                    <$t>::sqrt(self)
                }
            }
            fn div(self, rhs: Self) -> Self {
                if rhs == <$t>::ZERO {
                    <$t>::ZERO
                } else {
                    self.saturating_div(rhs)
                }
            }
            // Inlined: at its callers the product (i32 × i64) is known to be narrow,
            // which leaves a few 32×32 multiplies and word moves.
            #[inline(always)]
            fn from_scaled(n: i128, shift: u32, away: bool) -> Self {
                let frac = <$t>::FRAC_NBITS;
                let lo = <$t>::MIN.to_bits() as i64;
                let hi = <$t>::MAX.to_bits() as i64;
                // The per-sample kicks (|n| < 2^94, a right shift by 32..=63): the same
                // rounding as `scaled_bits` with 64-bit words, exact. `m + bias` is split
                // at bit 32: the low words' sum (< 2^33) carries into the high one
                // (< 2^62 + 2^32), and for s ≥ 32 shifting the high sum by s − 32 is
                // shifting the whole by s. i128 shifts, adds and compares are a loop of
                // library code on Cortex-M, several times the cost.
                let m = n.unsigned_abs();
                if shift > frac && (32..64).contains(&(shift - frac)) && m >> 94 == 0 {
                    let s = shift - frac;
                    let bias = if away {
                        (1u64 << s) - 1
                    } else {
                        1u64 << (s - 1)
                    };
                    let low = (m as u32) as u64 + (bias as u32) as u64;
                    let high = (m >> 32) as u64 + (bias >> 32) + (low >> 32);
                    // high < 2^63, so the quotient fits i64 and its negation too.
                    let q = (high >> (s - 32)) as i64;
                    let bits = if n < 0 { -q } else { q };
                    return <$t>::from_bits(bits.clamp(lo, hi) as _);
                }
                <$t>::from_bits(scaled_bits(n, shift, away, frac, lo, hi) as _)
            }
            fn rsqrt(self) -> Self {
                let bits = self.to_bits();
                if bits <= 0 {
                    return <$t>::ZERO;
                }
                let r = rsqrt_bits(bits as u64, <$t>::FRAC_NBITS);
                let max = <$t>::MAX.to_bits() as u64;
                <$t>::from_bits(r.min(max) as _)
            }
            fn next_down(self) -> Self {
                <$t>::from_bits(self.to_bits().saturating_sub(1))
            }
            #[inline]
            fn sat_add(self, o: Self) -> Self {
                self.saturating_add(o)
            }
            #[inline]
            fn ilog2(self) -> i32 {
                let m = self.to_bits().unsigned_abs();
                if m == 0 {
                    i32::MIN
                } else {
                    m.ilog2() as i32 - <$t>::FRAC_NBITS as i32
                }
            }
            #[inline]
            fn hash_bits(self) -> u64 {
                self.to_bits() as i64 as u64
            }
        }
    };
}

fixed_scalar!(I8F24, i64, "i8f24");
fixed_scalar!(I16F16, i64, "i16f16");
fixed_scalar!(I32F32, i128, "i32f32");

impl Scalar for f32 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAME: &'static str = "f32";
    fn from_int(n: i32) -> Self {
        n as f32
    }
    fn from_f64(x: f64) -> Self {
        x as f32
    }
    fn to_f64(self) -> f64 {
        self as f64
    }
    fn floor_int(self) -> i32 {
        libm::floorf(self) as i32
    }
    fn shr(self, n: u32) -> Self {
        self * pow2_neg_f32(n)
    }
    fn shl(self, n: u32) -> Self {
        self * (1u64 << n) as f32
    }
    fn sqrt(self) -> Self {
        if self <= 0.0 {
            0.0
        } else {
            libm::sqrtf(self)
        }
    }
    fn div(self, rhs: Self) -> Self {
        if rhs == 0.0 {
            0.0
        } else {
            self / rhs
        }
    }
    fn next_down(self) -> Self {
        f32::next_down(self)
    }
    fn hash_bits(self) -> u64 {
        self.to_bits() as u64
    }
    fn ilog2(self) -> i32 {
        ilog2_f32(self)
    }
}

/// `⌊log2 |x|⌋` of an `f32` from its exponent field (subnormals: their bit length).
fn ilog2_f32(x: f32) -> i32 {
    let b = x.to_bits() & 0x7fff_ffff;
    if b == 0 {
        return i32::MIN;
    }
    let e = (b >> 23) as i32;
    if e == 0 {
        (31 - b.leading_zeros() as i32) - 149
    } else {
        e - 127
    }
}

impl Scalar for f64 {
    const ZERO: Self = 0.0;
    const ONE: Self = 1.0;
    const NAME: &'static str = "f64";
    fn from_int(n: i32) -> Self {
        n as f64
    }
    fn from_f64(x: f64) -> Self {
        x
    }
    fn to_f64(self) -> f64 {
        self
    }
    fn floor_int(self) -> i32 {
        libm::floor(self) as i32
    }
    fn shr(self, n: u32) -> Self {
        self * pow2_neg_f32(n) as f64
    }
    fn shl(self, n: u32) -> Self {
        self * (1u64 << n) as f64
    }
    fn sqrt(self) -> Self {
        if self <= 0.0 {
            0.0
        } else {
            libm::sqrt(self)
        }
    }
    fn div(self, rhs: Self) -> Self {
        if rhs == 0.0 {
            0.0
        } else {
            self / rhs
        }
    }
    fn next_down(self) -> Self {
        f64::next_down(self)
    }
    fn hash_bits(self) -> u64 {
        self.to_bits()
    }
    fn ilog2(self) -> i32 {
        let b = self.to_bits() & 0x7fff_ffff_ffff_ffff;
        if b == 0 {
            return i32::MIN;
        }
        let e = (b >> 52) as i32;
        if e == 0 {
            (63 - b.leading_zeros() as i32) - 1074
        } else {
            e - 1023
        }
    }
}

/// `n·2^-shift` as the bits of a fixed-point number with `frac` fraction bits,
/// rounded to nearest (away from zero when `away`) and clamped to `[lo, hi]`: the
/// general case of the fixed-point `from_scaled`, in i128.
#[inline(never)]
fn scaled_bits(n: i128, shift: u32, away: bool, frac: u32, lo: i64, hi: i64) -> i64 {
    let bits = if shift <= frac {
        n.saturating_mul(1i128 << (frac - shift))
    } else {
        let s = shift - frac;
        let m = n.unsigned_abs();
        let q = if away {
            (m + (1u128 << s) - 1) >> s
        } else {
            (m + (1u128 << (s - 1))) >> s
        };
        if n < 0 {
            -(q as i128)
        } else {
            q as i128
        }
    };
    bits.clamp(lo as i128, hi as i128) as i64
}

/// `1/√x` for a fixed-point `x = bits·2^-frac > 0`, as bits of the same format,
/// rounded to nearest (within 1 LSB).
///
/// Written by hand because no crate offers a division-free fixed-point inverse
/// root: Cortex-M has no 64-bit divide and Cortex-M0 no divide at all, and this is
/// on the per-step path of rolling resistance and of every edge contact. `x` is
/// scaled by a power of four into `m ∈ [1, 4)`, a 96-entry table (by `m`'s top
/// bits) seeds `1/√m` to within 0.8 %, and Newton steps `y ← y·(3 − m·y²)/2` in
/// Q31 with 32×32→64-bit products (one instruction each on a Cortex-M3/M4) take it
/// to 10⁻⁴, then 1.5·10⁻⁸ — enough for 24 fraction bits — and a third step for
/// wider formats.
pub fn rsqrt_bits(bits: u64, frac: u32) -> u64 {
    if bits == 0 {
        return 0;
    }
    // x = bits·2^-frac = m·4^k with m ∈ [1, 4), m in Q30 (fits 32 bits: m < 4):
    // bits·2^(30 − frac − 2k). With b the bit length of `bits` that shift is
    // 31 − b or 32 − b, so a value that fits 32 bits (every 32-bit format) needs
    // no 64-bit shift: the same k and m on one word.
    let (k, m) = if let Ok(x) = u32::try_from(bits) {
        let b = 32 - x.leading_zeros() as i32;
        let k = (b - 1 - frac as i32).div_euclid(2);
        let sh = 30 - frac as i32 - 2 * k; // −1 ..= 31
        (k, if sh >= 0 { x << sh } else { x >> (-sh) })
    } else {
        let b = 64 - bits.leading_zeros() as i32;
        let k = (b - 1 - frac as i32).div_euclid(2);
        let sh = 30 - frac as i32 - 2 * k;
        (k, if sh >= 0 { bits << sh } else { bits >> (-sh) } as u32)
    };
    let slice = ((m >> 25) as usize).saturating_sub(32).min(95);
    let mut y: u32 = RSQRT_SEED[slice]; // Q31
    let steps = if frac <= 24 { 2 } else { 3 };
    for _ in 0..steps {
        // y·(3 − m·y²)/2 with y in Q31, m in Q30.
        let y2 = ((y as u64 * y as u64) >> 31) as u32; // Q31
        let my2 = ((m as u64 * y2 as u64) >> 30) as u32; // Q31, ≈ 1
                                                         // (3 − m·y²)/2 in Q31 is (3·2^31 − my2)/2 = 3·2^30 − my2/2.
        let t = (3u32 << 30).wrapping_sub(my2 >> 1);
        y = ((y as u64 * t as u64) >> 31) as u32;
    }
    // 1/√x = y·2^-k: from Q31 to `frac` bits.
    let out = frac as i32 - 31 - k;
    if out >= 0 {
        (y as u64) << out
    } else {
        // Rounded to nearest, (y + 2^(s−1)) >> s, on one word: adding 2^(s−1)
        // carries into bit s exactly when bit s − 1 is set; for s ≥ 33 the sum is
        // below 2^s (y < 2^32).
        let s = -out as u32;
        match s {
            1..=31 => ((y >> s) + ((y >> (s - 1)) & 1)) as u64,
            32 => (y >> 31) as u64,
            _ => 0,
        }
    }
}

/// `1/√m` in Q31 at the middle of the 96 slices of width 1/32 covering `[1, 4)`.
const RSQRT_SEED: [u32; 96] = [
    2_130_900_515,
    2_098_855_072,
    2_068_213_208,
    2_038_875_364,
    2_010_751_598,
    1_983_760_420,
    1_957_827_796,
    1_932_886_296,
    1_908_874_354,
    1_885_735_628,
    1_863_418_444,
    1_841_875_310,
    1_821_062_491,
    1_800_939_636,
    1_781_469_447,
    1_762_617_387,
    1_744_351_429,
    1_726_641_819,
    1_709_460_876,
    1_692_782_810,
    1_676_583_559,
    1_660_840_642,
    1_645_533_028,
    1_630_641_020,
    1_616_146_146,
    1_602_031_062,
    1_588_279_468,
    1_574_876_026,
    1_561_806_289,
    1_549_056_637,
    1_536_614_214,
    1_524_466_875,
    1_512_603_139,
    1_501_012_140,
    1_489_683_584,
    1_478_607_716,
    1_467_775_280,
    1_457_177_486,
    1_446_805_984,
    1_436_652_834,
    1_426_710_480,
    1_416_971_728,
    1_407_429_723,
    1_398_077_927,
    1_388_910_104,
    1_379_920_300,
    1_371_102_827,
    1_362_452_250,
    1_353_963_368,
    1_345_631_207,
    1_337_451_002,
    1_329_418_191,
    1_321_528_399,
    1_313_777_432,
    1_306_161_267,
    1_298_676_040,
    1_291_318_043,
    1_284_083_712,
    1_276_969_620,
    1_269_972_473,
    1_263_089_103,
    1_256_316_458,
    1_249_651_603,
    1_243_091_706,
    1_236_634_043,
    1_230_275_986,
    1_224_014_999,
    1_217_848_637,
    1_211_774_541,
    1_205_790_433,
    1_199_894_112,
    1_194_083_452,
    1_188_356_400,
    1_182_710_970,
    1_177_145_240,
    1_171_657_354,
    1_166_245_512,
    1_160_907_976,
    1_155_643_060,
    1_150_449_133,
    1_145_324_612,
    1_140_267_967,
    1_135_277_711,
    1_130_352_405,
    1_125_490_652,
    1_120_691_096,
    1_115_952_423,
    1_111_273_357,
    1_106_652_658,
    1_102_089_122,
    1_097_581_581,
    1_093_128_899,
    1_088_729_972,
    1_084_383_727,
    1_080_089_122,
    1_075_845_140,
];

fn pow2_neg_f32(n: u32) -> f32 {
    // 2^-n built from the exponent field: exact, no libm call. n ≤ 126 in practice.
    f32::from_bits((127u32.saturating_sub(n.min(126))) << 23)
}

/// `f32` whose square root is `micromath`'s fast approximation (exponent halving,
/// up to ~6 % off): the study's "f32 + micromath" backend, showing what that costs
/// in accuracy.
#[derive(Clone, Copy, PartialEq, PartialOrd, Debug, Default)]
pub struct MicroF32(pub f32);

impl Add for MicroF32 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        MicroF32(self.0 + o.0)
    }
}
impl Sub for MicroF32 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        MicroF32(self.0 - o.0)
    }
}
impl Mul for MicroF32 {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        MicroF32(self.0 * o.0)
    }
}
impl Neg for MicroF32 {
    type Output = Self;
    fn neg(self) -> Self {
        MicroF32(-self.0)
    }
}
impl AddAssign for MicroF32 {
    fn add_assign(&mut self, o: Self) {
        self.0 += o.0
    }
}
impl SubAssign for MicroF32 {
    fn sub_assign(&mut self, o: Self) {
        self.0 -= o.0
    }
}

impl Scalar for MicroF32 {
    const ZERO: Self = MicroF32(0.0);
    const ONE: Self = MicroF32(1.0);
    const NAME: &'static str = "f32-micromath";
    const EXACT_SQRT: bool = false;
    fn from_int(n: i32) -> Self {
        MicroF32(n as f32)
    }
    fn from_f64(x: f64) -> Self {
        MicroF32(x as f32)
    }
    fn to_f64(self) -> f64 {
        self.0 as f64
    }
    fn floor_int(self) -> i32 {
        use micromath::F32Ext;
        F32Ext::floor(self.0) as i32
    }
    fn shr(self, n: u32) -> Self {
        MicroF32(self.0 * pow2_neg_f32(n))
    }
    fn shl(self, n: u32) -> Self {
        MicroF32(self.0 * (1u64 << n) as f32)
    }
    fn sqrt(self) -> Self {
        use micromath::F32Ext;
        if self.0 <= 0.0 {
            MicroF32(0.0)
        } else {
            MicroF32(F32Ext::sqrt(self.0))
        }
    }
    fn div(self, rhs: Self) -> Self {
        if rhs.0 == 0.0 {
            MicroF32(0.0)
        } else {
            MicroF32(self.0 / rhs.0)
        }
    }
    fn next_down(self) -> Self {
        MicroF32(f32::next_down(self.0))
    }
    fn hash_bits(self) -> u64 {
        self.0.to_bits() as u64
    }
    fn ilog2(self) -> i32 {
        ilog2_f32(self.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fixed_floor_is_exact_for_negatives() {
        assert_eq!(I8F24::from_f64(-0.5).floor_int(), -1);
        assert_eq!(I8F24::from_int(-3).floor_int(), -3);
        assert_eq!(I8F24::from_bits(-1).floor_int(), -1);
        assert_eq!(I8F24::from_bits(0).floor_int(), 0);
    }

    #[test]
    fn shr_rounds_to_nearest_symmetrically() {
        let x = I8F24::from_bits(3);
        assert_eq!(x.shr(1).to_bits(), 2);
        assert_eq!((-x).shr(1).to_bits(), -2);
        assert_eq!(I8F24::from_bits(5).shr(2).to_bits(), 1);
        assert_eq!(1.5f32.shr(1), 0.75);
        assert_eq!(3.0f64.shr(10), 3.0 / 1024.0);
    }

    #[test]
    fn fixed_rsqrt_is_within_an_lsb() {
        for x in [
            1e-6, 3e-5, 0.001, 0.0123, 0.25, 0.5, 1.0, 2.0, 3.99, 7.0, 100.0, 127.9,
        ] {
            let got = I8F24::from_f64(x).rsqrt().to_f64();
            let q = I8F24::from_f64(x).to_f64();
            let want = 1.0 / q.sqrt();
            if want < 127.0 {
                let lsb = 1.0 / (1u64 << 24) as f64;
                assert!(
                    (got - want).abs() <= (want * 2e-7).max(lsb),
                    "rsqrt {x}: {got} vs {want}"
                );
            }
            let got = I32F32::from_f64(x).rsqrt().to_f64();
            let want = 1.0 / I32F32::from_f64(x).to_f64().sqrt();
            assert!(
                (got - want).abs() <= want * 1e-8 + 1.0 / (1u64 << 32) as f64,
                "i32f32 rsqrt {x}: {got} vs {want}"
            );
            let got = I16F16::from_f64(x).rsqrt().to_f64();
            let q = I16F16::from_f64(x).to_f64();
            if q > 0.0 {
                let want = 1.0 / q.sqrt();
                assert!(
                    (got - want).abs() <= want * 1e-6 + 1.0 / 65536.0,
                    "i16f16 rsqrt {x}: {got} vs {want}"
                );
            }
        }
        assert_eq!(I8F24::ZERO.rsqrt(), I8F24::ZERO);
        assert_eq!(I8F24::from_f64(4.0).rsqrt(), I8F24::from_f64(0.5));
    }

    /// A small deterministic generator (xorshift64*) for the equivalence sweeps.
    /// The Cortex-M0's product from 16-bit halves against the 64-bit one, bit for
    /// bit: every sign and carry combination of the halves, the extremes, and
    /// random operands (the M0 end-state hashes in the study check it on the chip).
    #[test]
    fn halves_product_is_the_wide_product() {
        fn check(a: i32, b: i32) {
            let wide = a as i64 * b as i64;
            assert_eq!(mul_shr_halves::<24>(a, b), (wide >> 24) as i32, "{a} · {b}");
            assert_eq!(mul_shr_halves::<16>(a, b), (wide >> 16) as i32, "{a} · {b}");
            assert_eq!(mul_shr_halves::<0>(a, b), wide as i32, "{a} · {b}");
        }
        let edges = [
            i32::MIN,
            i32::MIN + 1,
            -65_537,
            -65_536,
            -65_535,
            -32_768,
            -1,
            0,
            1,
            0xffff,
            0x1_0000,
            0x7fff_0000,
            0x7fff_ffff,
            -0x7fff_0001,
        ];
        for a in edges {
            for b in edges {
                check(a, b);
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15;
        for _ in 0..200_000 {
            check(rng(&mut state) as i32, rng(&mut state) as i32);
        }
    }

    fn rng(state: &mut u64) -> u64 {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    #[test]
    /// The word-sized fast path against the general i128 code (`scaled_bits`,
    /// the original arithmetic), on edge and random inputs.
    fn from_scaled_matches_the_i128_reference() {
        let check = |n: i128| {
            for shift in 0..=100 {
                for away in [false, true] {
                    let got = I8F24::from_scaled(n, shift, away).to_bits() as i128;
                    let want =
                        scaled_bits(n, shift, away, 24, i32::MIN.into(), i32::MAX.into()) as i128;
                    assert_eq!(got, want, "i8f24 {n} >> {shift} away {away}");
                    let got = I16F16::from_scaled(n, shift, away).to_bits() as i128;
                    let want =
                        scaled_bits(n, shift, away, 16, i32::MIN.into(), i32::MAX.into()) as i128;
                    assert_eq!(got, want, "i16f16 {n} >> {shift} away {away}");
                    let got = I32F32::from_scaled(n, shift, away).to_bits() as i128;
                    let want = scaled_bits(n, shift, away, 32, i64::MIN, i64::MAX) as i128;
                    assert_eq!(got, want, "i32f32 {n} >> {shift} away {away}");
                }
            }
        };
        for n in [0, 1, -1, i128::MAX, i128::MIN, i128::MIN + 1] {
            check(n);
        }
        for p in [31, 32, 33, 62, 63, 64, 93, 94, 95, 96, 126] {
            let v = 1i128 << p;
            for n in [v, v - 1, v + 1, -v, -v + 1, -v - 1] {
                check(n);
            }
        }
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..4000 {
            // Products as the kicks form them (i32 × i64), and wider values.
            let a = rng(&mut state) as i32 as i128;
            let b = rng(&mut state) as i64 as i128;
            let w = (rng(&mut state) as i128) << (rng(&mut state) % 64);
            for n in [a * b, (a >> (rng(&mut state) % 31)) * b, w, -w] {
                check(n);
            }
        }
    }

    #[test]
    fn times_is_the_operator() {
        // Wrapping products too: `overflowing_mul` gives the operator's bits without
        // its debug check, which `times` shares (so overflowing pairs are skipped).
        fn check<T: Scalar + fixed::traits::Fixed>(a: T, b: T) {
            let (want, overflow) = a.overflowing_mul(b);
            if !overflow {
                assert_eq!(a.times(b), want, "{a:?} · {b:?}");
                assert_eq!(a.times(b), a * b, "{a:?} · {b:?}");
            }
        }
        let mut state = 0x5851_f42d_4c95_7f2du64;
        for _ in 0..200_000 {
            let (x, y) = (rng(&mut state), rng(&mut state));
            let (sx, sy) = ((rng(&mut state) % 40) as u32, (rng(&mut state) % 40) as u32);
            check(
                I8F24::from_bits((x as i32) >> (sx % 32)),
                I8F24::from_bits((y as i32) >> (sy % 32)),
            );
            check(
                I16F16::from_bits((x as i32) >> (sx % 32)),
                I16F16::from_bits((y as i32) >> (sy % 32)),
            );
            check(
                I32F32::from_bits((x as i64) >> sx),
                I32F32::from_bits((y as i64) >> sy),
            );
        }
        for v in [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX] {
            for w in [i32::MIN, -(1 << 24), -1, 0, 1, 1 << 24, i32::MAX] {
                check(I8F24::from_bits(v), I8F24::from_bits(w));
                check(I16F16::from_bits(v), I16F16::from_bits(w));
            }
        }
    }

    /// `rsqrt_bits` as first written, all in u64: the one-word paths must give the
    /// same bits.
    fn rsqrt_bits_u64(bits: u64, frac: u32) -> u64 {
        if bits == 0 {
            return 0;
        }
        let b = 64 - bits.leading_zeros() as i32;
        let k = (b - 1 - frac as i32).div_euclid(2);
        let sh = 30 - frac as i32 - 2 * k;
        let m = if sh >= 0 { bits << sh } else { bits >> (-sh) } as u32;
        let slice = ((m >> 25) as usize).saturating_sub(32).min(95);
        let mut y: u32 = RSQRT_SEED[slice];
        let steps = if frac <= 24 { 2 } else { 3 };
        for _ in 0..steps {
            let y2 = ((y as u64 * y as u64) >> 31) as u32;
            let my2 = ((m as u64 * y2 as u64) >> 30) as u32;
            let t = (3u32 << 30).wrapping_sub(my2 >> 1);
            y = ((y as u64 * t as u64) >> 31) as u32;
        }
        let out = frac as i32 - 31 - k;
        let y = y as u64;
        if out >= 0 {
            y << out
        } else {
            let s = -out as u32;
            if s >= 64 {
                0
            } else {
                (y + (1 << (s - 1))) >> s
            }
        }
    }

    #[test]
    fn rsqrt_bits_matches_the_u64_reference() {
        let check = |x: u64| {
            for frac in [0, 1, 16, 23, 24, 25, 31, 32, 40, 48, 60] {
                assert_eq!(
                    rsqrt_bits(x, frac),
                    rsqrt_bits_u64(x, frac),
                    "rsqrt_bits({x}, {frac})"
                );
            }
        };
        for x in [0, 1, 2, 3, u32::MAX as u64, u32::MAX as u64 + 1, u64::MAX] {
            check(x);
        }
        for p in 0..64 {
            for x in [1u64 << p, (1u64 << p) - 1, (1u64 << p) + 1] {
                check(x);
            }
        }
        let mut state = 0x0123_4567_89ab_cdefu64;
        for _ in 0..20_000 {
            let x = rng(&mut state);
            for x in [x, x >> (rng(&mut state) % 64), x as u32 as u64] {
                check(x);
            }
        }
    }

    #[test]
    fn ilog2_is_the_exponent() {
        for x in [1e-7f64, 0.001, 0.25, 0.3, 1.0, 1.5, 2.0, 100.0, -0.75] {
            let want = x.abs().log2().floor() as i32;
            assert_eq!(x.ilog2(), want, "f64 {x}");
            assert_eq!((x as f32).ilog2(), want, "f32 {x}");
            if x.abs() > 1e-6 {
                assert_eq!(I8F24::from_f64(x).ilog2(), want, "i8f24 {x}");
                assert_eq!(I32F32::from_f64(x).ilog2(), want, "i32f32 {x}");
            }
        }
        assert_eq!(I8F24::from_bits(1).ilog2(), -24);
        assert_eq!(I8F24::ZERO.ilog2(), i32::MIN);
        assert_eq!(0.0f32.ilog2(), i32::MIN);
    }

    #[test]
    fn ratio_rounds_to_nearest() {
        let r = I8F24::ratio(1, 3);
        let err = (r.to_f64() - 1.0 / 3.0).abs();
        assert!(err <= 0.5 / (1u64 << 24) as f64);
        assert_eq!(I8F24::ratio(-1, 2).to_f64(), -0.5);
        assert_eq!(I16F16::ratio(2, 12), I16F16::from_f64(2.0 / 12.0));
    }

    #[test]
    fn micromath_sqrt_is_within_its_documented_error() {
        // micromath halves the exponent bits: exact at powers of 4, up to ~6 % off
        // in between (√2 comes out as 1.5).
        for x in [0.01f32, 0.5, 1.0, 2.0, 3.0, 7.9, 100.0] {
            let got = MicroF32(x).sqrt().0;
            let rel = (got - libm::sqrtf(x)).abs() / libm::sqrtf(x);
            assert!(rel < 0.065, "√{x}: {got} ({rel})");
        }
        assert_eq!(MicroF32(4.0).sqrt().0, 2.0);
    }
}
