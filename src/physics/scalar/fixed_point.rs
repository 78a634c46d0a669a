//! The fixed-point backends (I8F24, the firmware's; I16F16; I32F32): products on
//! the format's bits, conversions rounded once, and the inverse root of `rsqrt.rs`.

use super::product::{mul_shr, mul_wide};
use super::rsqrt::rsqrt_bits;
use super::*;

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

/// `bits · 2^-n` rounded half away from zero, `0 < n < NBITS` ([`Scalar::shr`]
/// on a format's bits): on the magnitude, so that neither MAX nor MIN can
/// overflow. Two forms of the same bits: the Cortex-M0 takes
/// [`round_shr_sum`]'s, which runs some 200 times in the v1's heaviest
/// difficulty-9 frame, a few instructions and a branch fewer there (59 453 →
/// 58 680 M0 instructions, and 1 212 B of flash back); elsewhere
/// [`round_shr_bit`]'s `(m >> n) + ((m >> (n − 1)) & 1)` with a conditional
/// negation (on the M4 the sum was no cheaper: the difficulty-9 mazes' average
/// frames 0.4 % dearer).
pub(super) trait RoundShr {
    fn round_shr(self, n: u32) -> Self;
}

macro_rules! round_shr {
    ($bits:ty, $sum:ident, $bit:ident) => {
        impl RoundShr for $bits {
            #[inline(always)]
            fn round_shr(self, n: u32) -> Self {
                if cfg!(all(target_arch = "arm", not(target_has_atomic = "32"))) {
                    $sum(self, n)
                } else {
                    $bit(self, n)
                }
            }
        }

        /// [`RoundShr`]'s sum form: `(m + 2^(n−1)) >> n` (below `2^NBITS` for
        /// `n < NBITS`), the sign put back by `(q ^ s) − s`.
        #[inline(always)]
        pub(super) fn $sum(bits: $bits, n: u32) -> $bits {
            let sign = bits >> (<$bits>::BITS - 1);
            let q = ((bits.unsigned_abs() + (1 << (n - 1))) >> n) as $bits;
            (q ^ sign).wrapping_sub(sign)
        }

        /// [`RoundShr`]'s bit form: `(m >> n)` plus the bit below, negated for a
        /// negative value.
        #[inline(always)]
        pub(super) fn $bit(bits: $bits, n: u32) -> $bits {
            let m = bits.unsigned_abs();
            let q = ((m >> n) + ((m >> (n - 1)) & 1)) as $bits;
            if bits < 0 {
                q.wrapping_neg()
            } else {
                q
            }
        }
    };
}

/// `bits · 2^n` saturated to the word (`n < NBITS`: [`Scalar::shl`] on a
/// format's bits). Two forms of the same bits: the Cortex-M0 takes
/// [`sat_shl_back`]'s, the shift kept when shifting back gives the value
/// again (four instructions fewer there than comparing with `±(MAX >> n)`,
/// and 324 B of the v1's flash); elsewhere [`sat_shl_limit`]'s comparison,
/// which LLVM can turn into a saturation instruction (with the shift-back form
/// the M4's difficulty-9 mazes and grand-tour took 2 % more a frame).
pub(super) trait SatShl {
    fn sat_shl(self, n: u32) -> Self;
}

macro_rules! sat_shl {
    ($bits:ty, $back:ident, $limit:ident) => {
        impl SatShl for $bits {
            #[inline(always)]
            fn sat_shl(self, n: u32) -> Self {
                if cfg!(all(target_arch = "arm", not(target_has_atomic = "32"))) {
                    $back(self, n)
                } else {
                    $limit(self, n)
                }
            }
        }

        /// [`SatShl`]'s shift-back form (`−2^(NBITS−1−n)` shifts exactly to
        /// MIN, which the comparison also gives).
        #[inline(always)]
        pub(super) fn $back(bits: $bits, n: u32) -> $bits {
            let shifted = bits << n;
            if shifted >> n == bits {
                shifted
            } else if bits > 0 {
                <$bits>::MAX
            } else {
                <$bits>::MIN
            }
        }

        /// [`SatShl`]'s comparison form: MAX above `MAX >> n`, MIN below its
        /// negation.
        #[inline(always)]
        pub(super) fn $limit(bits: $bits, n: u32) -> $bits {
            let limit = <$bits>::MAX >> n;
            if bits > limit {
                <$bits>::MAX
            } else if bits < -limit {
                <$bits>::MIN
            } else {
                bits << n
            }
        }
    };
}

sat_shl!(i32, sat_shl_back, sat_shl_limit);
sat_shl!(i64, sat_shl_back_wide, sat_shl_limit_wide);

round_shr!(i32, round_shr_sum, round_shr_bit);
round_shr!(i64, round_shr_sum_wide, round_shr_bit_wide);

/// The fixed-point quotient on a format's bits: `fixed`'s `saturating_div`
/// (`rhs != 0`).
trait FracQuotient {
    fn div_frac<const FRAC: u32>(self, rhs: Self) -> Self;
}

impl FracQuotient for i32 {
    #[inline(always)]
    fn div_frac<const FRAC: u32>(self, rhs: i32) -> i32 {
        super::quotient::div_frac::<FRAC>(self, rhs)
    }
}

impl FracQuotient for i64 {
    #[inline(always)]
    fn div_frac<const FRAC: u32>(self, rhs: i64) -> i64 {
        use fixed::{types::extra::U32, FixedI64};
        debug_assert_eq!(FRAC, 32, "the one 64-bit format is I32F32");
        FixedI64::<U32>::from_bits(self)
            .saturating_div(FixedI64::<U32>::from_bits(rhs))
            .to_bits()
    }
}

/// The fixed-point square root on a format's bits, rounded down: `fixed`'s
/// `sqrt` (`self > 0`).
trait FracRoot {
    fn sqrt_frac<const FRAC: u32>(self) -> Self;
}

impl FracRoot for i32 {
    #[inline(always)]
    fn sqrt_frac<const FRAC: u32>(self) -> i32 {
        super::rsqrt::sqrt_bits::<FRAC>(self as u32) as i32
    }
}

impl FracRoot for i64 {
    #[inline(always)]
    fn sqrt_frac<const FRAC: u32>(self) -> i64 {
        use fixed::{types::extra::U32, FixedI64};
        debug_assert_eq!(FRAC, 32, "the one 64-bit format is I32F32");
        FixedI64::<U32>::from_bits(self).sqrt().to_bits()
    }
}

impl FracProduct for i64 {
    #[inline(always)]
    fn mul_shr<const FRAC: u32>(self, rhs: i64) -> i64 {
        ((self as i128 * rhs as i128) >> FRAC) as i64
    }
}

/// `|mg| · scale`, exact, as its low 32 bits and the rest: with `scale = sh·2³²
/// + sl` (`sh < 2³¹`, a non-negative i64), `|mg|·sl < 2⁶⁴` and `|mg|·sh < 2⁶²`.
#[inline(always)]
fn pull_product(mg: i32, scale: u64) -> (u32, u64) {
    let m = mg.unsigned_abs();
    let low_product = mul_wide(m, scale as u32);
    let high_product = mul_wide(m, (scale >> 32) as u32);
    (low_product as u32, high_product + (low_product >> 32))
}

/// `from_scaled`'s rounding of a kick's product `P = (low, high)` (see
/// [`pull_product`]) by `2^-s`, `s` in `32..64`, on 64-bit words and without a
/// 64-bit bias: each rounding is one shift of the high word by `s − 32` (below
/// 32, which the mask tells the compiler: a 64-bit shift by a variable amount
/// is then a few word shifts, where one that may pass 32 takes twice as many).
/// To nearest, `⌊(P + 2^(s−1))/2^s⌋ = ⌊(⌊P/2^(s−1)⌋ + 1)/2⌋`; away from zero,
/// `⌈P/2^s⌉ = ⌊(P − 1)/2^s⌋ + 1` for `P ≥ 1` (the borrow of `P − 1` reaches
/// the high word only when the low one is zero). `high` is below `2^62 + 2^32`,
/// so `⌊P/2^31⌋` fits a word pair. The result is the bits of the format
/// `[lo, hi]`: the quotient saturated before its sign is applied (at `hi`, or
/// at `−lo` below zero), which for a 32-bit format is a compare of words.
#[inline(always)]
fn pull_quotient(
    (low, high): (u32, u64),
    negative: bool,
    s: u32,
    away: bool,
    (lo, hi): (i64, i64),
) -> i64 {
    let t = (s - 32) & 31;
    let q = if away {
        if high == 0 && low == 0 {
            0
        } else {
            ((high - u64::from(low == 0)) >> t) + 1
        }
    } else {
        ((((high << 1) | u64::from(low >> 31)) >> t) + 1) >> 1
    };
    // Two's complement: the bound below zero is one past the bound above it
    // (`lo = −hi − 1`), so one saturation and a conditional negation.
    debug_assert_eq!(lo, -hi - 1);
    let q = q.min(hi as u64 + u64::from(negative)) as i64;
    let sign = -i64::from(negative);
    (q ^ sign).wrapping_sub(sign)
}

/// [`pull_quotient`] for a quotient the format holds (below `2^31`, a 32-bit
/// format's: [`Scalar::from_pull_fits_at`]): the same rounding, the high
/// word's shift taken to one word (`⌊P/2^(s−1)⌋ < 2^32` then) and no
/// saturation.
#[inline(always)]
fn pull_quotient_fits((low, high): (u32, u64), negative: bool, s: u32, away: bool) -> i32 {
    let t = (s - 32) & 31;
    let q = if away {
        if high == 0 && low == 0 {
            0
        } else {
            (((high - u64::from(low == 0)) >> t) as u32).wrapping_add(1)
        }
    } else {
        let h = (((high << 1) | u64::from(low >> 31)) >> t) as u32;
        (h >> 1) + (h & 1)
    };
    let sign = -i32::from(negative);
    ((q as i32) ^ sign).wrapping_sub(sign)
}

/// [`Scalar::from_pull`] by the 128-bit product (shifts outside `32..64` of the
/// format's fraction, a negative scale): out of line and cold, so that the word
/// path every tilt sample takes saves and restores only the registers it uses.
#[cold]
#[inline(never)]
fn pull_wide<T: Scalar>(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (T, T) {
    let n = mg as i128 * scale as i128;
    (
        T::from_scaled(n, dv_shift, false),
        T::from_scaled(n, dp_shift, true),
    )
}

/// Whether both of a kick's shifts leave the product's quotient on the high
/// word pair ([`pull_quotient`]'s `s − 32` below 32) for a format of `frac`
/// fraction bits; else the 128-bit path.
#[inline(always)]
fn word_shifts(frac: u32, dv_shift: u32, dp_shift: u32) -> bool {
    (32..64).contains(&dv_shift.wrapping_sub(frac))
        && (32..64).contains(&dp_shift.wrapping_sub(frac))
}

/// [`Scalar::from_pull`]'s word path for a fixed-point format, inlined into
/// its two entry points: `from_pull` (shifts at run time) and `from_pull_at`
/// (constant shifts: a 64-bit shift by a constant is a few instructions fewer
/// on the Cortex-M than one by a variable).
trait PullWords: Sized {
    fn pull_words(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self);
    /// `pull_words` for a kick the format holds ([`pull_quotient_fits`]).
    fn pull_words_fits(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self);
}

macro_rules! fixed_scalar {
    ($t:ty, $wide:ty, $name:literal) => {
        impl PullWords for $t {
            #[inline(always)]
            fn pull_words(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self) {
                let frac = <$t>::FRAC_NBITS;
                if scale < 0 || !word_shifts(frac, dv_shift, dp_shift) {
                    return pull_wide(mg, scale, dv_shift, dp_shift);
                }
                let product = pull_product(mg, scale as u64);
                let range = (<$t>::MIN.to_bits() as i64, <$t>::MAX.to_bits() as i64);
                let dv = pull_quotient(product, mg < 0, dv_shift - frac, false, range);
                let dp = pull_quotient(product, mg < 0, dp_shift - frac, true, range);
                (<$t>::from_bits(dv as _), <$t>::from_bits(dp as _))
            }
            #[inline(always)]
            fn pull_words_fits(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self) {
                let frac = <$t>::FRAC_NBITS;
                // A 64-bit format's quotients need their words.
                let wide = <$t>::MAX.to_bits() as i64 > i64::from(i32::MAX);
                if scale < 0 || !word_shifts(frac, dv_shift, dp_shift) || wide {
                    return Self::pull_words(mg, scale, dv_shift, dp_shift);
                }
                let product = pull_product(mg, scale as u64);
                let dv = pull_quotient_fits(product, mg < 0, dv_shift - frac, false);
                let dp = pull_quotient_fits(product, mg < 0, dp_shift - frac, true);
                debug_assert_eq!(
                    (<$t>::from_bits(dv as _), <$t>::from_bits(dp as _)),
                    Self::pull_words(mg, scale, dv_shift, dp_shift),
                    "a kick the format does not hold"
                );
                (<$t>::from_bits(dv as _), <$t>::from_bits(dp as _))
            }
        }

        impl Scalar for $t {
            const ZERO: Self = <$t>::ZERO;
            const ONE: Self = <$t>::ONE;
            const NAME: &'static str = $name;
            const EXACT_UNIT: bool = true;
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
                // Round half away from zero so that +v and -v move by mirror amounts.
                <$t>::from_bits(self.to_bits().round_shr(n))
            }
            #[inline]
            fn shl(self, n: u32) -> Self {
                // A shift and a range check (the generic saturating multiply is a
                // call): see `SatShl`.
                <$t>::from_bits(self.to_bits().sat_shl(n))
            }
            fn sqrt(self) -> Self {
                if self <= <$t>::ZERO {
                    <$t>::ZERO
                } else {
                    <$t>::from_bits(self.to_bits().sqrt_frac::<{ <$t>::FRAC_NBITS }>())
                }
            }
            fn div(self, rhs: Self) -> Self {
                if rhs == <$t>::ZERO {
                    <$t>::ZERO
                } else {
                    <$t>::from_bits(
                        self.to_bits()
                            .div_frac::<{ <$t>::FRAC_NBITS }>(rhs.to_bits()),
                    )
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
            // Out of line: one copy for every tilt sample's kicks (the v1's flash).
            #[inline(never)]
            fn from_pull(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) -> (Self, Self) {
                <$t as PullWords>::pull_words(mg, scale, dv_shift, dp_shift)
            }
            #[inline(never)]
            fn from_pull_at<const DV_SHIFT: u32, const DP_SHIFT: u32>(
                mg: i32,
                scale: i64,
            ) -> (Self, Self) {
                <$t as PullWords>::pull_words(mg, scale, DV_SHIFT, DP_SHIFT)
            }
            // Inlined into a flat world's tilt sample, its one caller (the
            // plane axes' two copies): its word path is short.
            #[inline(always)]
            fn from_pull_fits_at<const DV_SHIFT: u32, const DP_SHIFT: u32>(
                mg: i32,
                scale: i64,
            ) -> (Self, Self) {
                <$t as PullWords>::pull_words_fits(mg, scale, DV_SHIFT, DP_SHIFT)
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

/// `n·2^-shift` as the bits of a fixed-point number with `frac` fraction bits,
/// rounded to nearest (away from zero when `away`) and clamped to `[lo, hi]`: the
/// general case of the fixed-point `from_scaled`, in i128.
#[inline(never)]
pub(super) fn scaled_bits(n: i128, shift: u32, away: bool, frac: u32, lo: i64, hi: i64) -> i64 {
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
