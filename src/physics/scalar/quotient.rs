//! The fixed-point quotient of two 32-bit formats without a 64-bit division.
//!
//! `fixed`'s `saturating_div` forms `(a << FRAC) / b` in `i64`, which no
//! Cortex-M divides in hardware: a call of the generic 64 ÷ 64 library routine
//! (`__aeabi_ldivmod`), about 260 instructions on the M4 and more on the M0,
//! for every time of impact, impact speed and pivot length the event step
//! takes (7 % of the M4's worst frame of drop-onto-marble). The divisor here
//! always fits 32 bits, and so does every quotient that does not saturate, so
//! two 32 ÷ 32 divisions of 16-bit digits do (Knuth's Algorithm D with base
//! 2¹⁶, TAOCP vol. 2, §4.3.1): one `udiv` each on the M4. Written by hand
//! because no crate offers a 64 ÷ 32 division that is cheap on Cortex-M.
//! Bit for bit `fixed`'s result, saturation included: the tests sweep it
//! against the crate.

use super::product::mul_wide;

/// `(a · 2^FRAC) / b` rounded toward zero, saturated to `i32` as `fixed`'s
/// `saturating_div` does (by the operands' signs); `b != 0`, `FRAC < 32`.
#[inline(never)]
pub(super) fn div_frac<const FRAC: u32>(a: i32, b: i32) -> i32 {
    let negative = (a < 0) != (b < 0);
    let (n, d) = (a.unsigned_abs(), b.unsigned_abs());
    // n · 2^FRAC as two words: below 2^63, since n ≤ 2^31 and FRAC < 32.
    let (high, low) = if FRAC == 0 {
        (0, n)
    } else {
        (n >> (32 - FRAC), n << FRAC)
    };
    // A proper fraction, as most of the event step's quotients are (times
    // within the step, the put-back's `wn²/|wt|²`): its bits one at a time.
    #[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
    if n < d {
        let q = divide_below::<FRAC>(n, d) as i32;
        return if negative { q.wrapping_neg() } else { q };
    }
    // A quotient of 2^32 or more saturates whatever its sign.
    let limit = if negative {
        1u32 << 31
    } else {
        (1u32 << 31) - 1
    };
    let q = if high >= d {
        None
    } else {
        Some(divide_words(high, low, d)).filter(|&q| q <= limit)
    };
    match (q, negative) {
        (Some(q), true) => (q as i32).wrapping_neg(),
        (Some(q), false) => q as i32,
        // `fixed` saturates by the operands' signs, not the quotient's: the
        // same here, as `a == 0` never overflows.
        (None, true) => i32::MIN,
        (None, false) => i32::MAX,
    }
}

/// `(high · 2³² + low) / d`, truncated, for `high < d` (the quotient fits 32
/// bits): [`divide_digits`] where the core has a divider.
#[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
#[inline(always)]
pub(super) fn divide_words(high: u32, low: u32, d: u32) -> u32 {
    divide_digits(high, low, d)
}

/// [`divide_words`] on ARMv6-M: [`divide_reciprocal`].
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
#[inline(always)]
pub(super) fn divide_words(high: u32, low: u32, d: u32) -> u32 {
    divide_reciprocal(high, low, d)
}

/// [`divide_words`] without a division (the Cortex-M0's): `d` is shifted until its top bit is set (the
/// numerator with it), its reciprocal taken by Newton's iteration
/// ([`reciprocal`], from below), the quotient estimated from it (from below,
/// a few units short at most) and raised while the exact remainder allows.
///
/// The Cortex-M0 has no divider: [`divide_digits`] took two calls
/// of the library's 32 ÷ 32 division (a loop over the quotient's bits, about
/// 150 instructions each), 450 instructions a quotient in all, every time of
/// impact of the event step (30 in four-shaken's worst frame); this takes ten
/// 32 × 32 → 64 products (`mul_wide`: four 16-bit multiplies each there). Where
/// a core divides words (the M4) the digits are cheaper: they stay there.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
pub(super) fn divide_reciprocal(high: u32, low: u32, d: u32) -> u32 {
    debug_assert!(high < d, "the quotient must fit 32 bits");
    let shift = d.leading_zeros();
    let d = d << shift;
    let (high, low) = if shift == 0 {
        (high, low)
    } else {
        ((high << shift) | (low >> (32 - shift)), low << shift)
    };
    let y = reciprocal(d);
    // ⌊n·y / 2⁶³⌋ with n = high·2³² + low, each partial product floored: at
    // most n/d, so the remainder below is not negative. `high·y < 2⁶³ + 2³⁵`
    // (`high < d`, `y ≤ 2⁶³/d`), so the sum fits.
    let sum = mul_wide(high, y) + (mul_wide(low, y) >> 32);
    let mut q = (sum >> 31) as u32;
    let n = (high as u64) << 32 | low as u64;
    let d = d as u64;
    let mut r = n - mul_wide(q, d as u32);
    while r >= d {
        q += 1;
        r -= d;
    }
    q
}

/// `(n · 2^FRAC) / d`, truncated, for `n < d`: restoring division, one
/// quotient bit a round (a shift, a compare, at most a subtraction: about ten
/// Cortex-M0 instructions), `FRAC` rounds. The remainder stays below `d ≤ 2³¹`,
/// so its double fits a word. On the Cortex-M0 that is about 250 instructions
/// where [`divide_reciprocal`] and its leading-zero count took about 400. The
/// quotient's bit is the round's counter: with a counter of its own LLVM
/// spilled a register in the loop (about 11 instructions a round).
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn divide_below<const FRAC: u32>(n: u32, d: u32) -> u32 {
    debug_assert!(n < d, "a proper fraction");
    let (mut r, mut q) = (n, 0u32);
    // The quotient's bit doubles as the round's counter.
    let mut bit = (1u32 << FRAC) >> 1;
    while bit != 0 {
        r <<= 1;
        if r >= d {
            r -= d;
            q |= bit;
        }
        bit >>= 1;
    }
    q
}

/// `2⁶³ / d` for `d ≥ 2³¹`, from below (the exact reciprocal or up to a few
/// parts in 2³⁰ short of it, and below 2³²): 1/e for `e = d/2³²` in `[½, 1)` in
/// Q31, from the linear seed `48/17 − 32/17·e` (within 1/17) by three Newton
/// steps `y·(2 − e·y)` (1/17 squared three times: under 2⁻³²), each rounded
/// down; the last step may round up by up to two units, which the margin
/// takes back.
#[inline(always)]
fn reciprocal(d: u32) -> u32 {
    // 48/17 in Q31, and 16/17 in Q32 (`32/17·e` in Q31 is `16/17·d`).
    const C48: u64 = 6_063_483_241;
    const C16: u32 = 4_042_322_160;
    let mut y = C48 - (mul_wide(d, C16) >> 32);
    for _ in 0..3 {
        // e·y in Q31: at most 1 and a few units (Newton's steps stay below
        // 1/e, up to the rounding).
        let t = (mul_wide(d, y as u32) >> 32) as u32;
        // 2 − e·y in Q31 is 2³² − t (t > 0).
        y = mul_wide(y as u32, 0u32.wrapping_sub(t)) >> 31;
        y = y.min(u32::MAX as u64);
    }
    (y as u32).saturating_sub(3)
}

/// [`divide_words`] where the core divides words (one `udiv` a digit):
/// Algorithm D on 16-bit digits. `d` is shifted until its top bit is set
/// (the numerator with it), so that each quotient digit estimated from the top
/// digits is at most 2 too large; the estimate is brought down while its
/// product with the divisor's second digit shows it too large.
#[cfg_attr(
    all(target_arch = "arm", not(target_has_atomic = "32")),
    allow(dead_code)
)]
pub(super) fn divide_digits(high: u32, low: u32, d: u32) -> u32 {
    debug_assert!(high < d, "the quotient must fit 32 bits");
    let shift = d.leading_zeros();
    let d = d << shift;
    let (d1, d0) = (d >> 16, d & 0xffff);
    // The numerator's top word and its two low digits, shifted like `d`.
    let top = if shift == 0 {
        high
    } else {
        (high << shift) | (low >> (32 - shift))
    };
    let low = low << shift;
    let (n1, n0) = (low >> 16, low & 0xffff);
    let q1 = digit(top, n1, d1, d0);
    // The partial remainder `top·2¹⁶ + n1 − q1·d`: below `d`, so the wrapping
    // arithmetic gives it exactly.
    let rest = (top << 16)
        .wrapping_add(n1)
        .wrapping_sub(q1.wrapping_mul(d));
    let q0 = digit(rest, n0, d1, d0);
    (q1 << 16) | q0
}

/// One quotient digit of `(top·2¹⁶ + next) / (d1·2¹⁶ + d0)`, where `top <
/// d1·2¹⁶ + d0` and `d1 ≥ 2¹⁵`: `top / d1`, lowered while it is not a digit or
/// its product with `d0` exceeds what the remainder and `next` allow.
#[inline(always)]
fn digit(top: u32, next: u32, d1: u32, d0: u32) -> u32 {
    let mut q = top / d1;
    let mut r = top - q * d1;
    // `r < 2¹⁶` while the loop runs (it stops once `r` reaches 2¹⁶), so
    // `(r << 16) + next` fits; `q · d0` is only formed once `q < 2¹⁶`.
    while q > 0xffff || q * d0 > (r << 16) + next {
        q -= 1;
        r += d1;
        if r > 0xffff {
            break;
        }
    }
    q
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::{Rng, SeedableRng};
    use rand_xorshift::XorShiftRng;

    /// The proper fractions' bit-by-bit quotient is the word division's: `n`
    /// from zero to `d − 1`, divisors from 1 to 2³¹ (`|i32::MIN|`), random pairs.
    #[test]
    fn a_proper_fraction_is_divided_bit_by_bit() {
        let mut rng = XorShiftRng::seed_from_u64(0x9e37_79b9_7f4a_7c15);
        let mut checked = 0;
        let mut check = |n: u32, d: u32| {
            let exact = ((n as u64) << 24) / d as u64;
            assert_eq!(divide_below::<24>(n, d) as u64, exact, "{n} / {d}");
            assert_eq!(
                divide_below::<16>(n, d) as u64,
                ((n as u64) << 16) / d as u64,
                "{n} / {d}"
            );
            checked += 1;
        };
        for d in [
            1u32,
            2,
            3,
            255,
            1 << 16,
            (1 << 24) + 1,
            (1 << 31) - 1,
            1 << 31,
        ] {
            for n in [0, 1, d / 2, d - 1] {
                if n < d {
                    check(n, d);
                }
            }
        }
        for _ in 0..1_000_000 {
            let d = (rng.next_u32() >> (rng.next_u32() % 32)).clamp(1, 1 << 31);
            let n = rng.next_u32() % d;
            check(n, d);
        }
        assert!(checked > 1_000_000);
    }

    /// The reciprocal is at most `2⁶³/d` and at most 8 units short of it
    /// (the quotient's estimate then at most 9 short): both ends of the range,
    /// powers of two and their neighbours, random divisors.
    #[test]
    fn the_reciprocal_is_from_below_and_close() {
        let mut rng = XorShiftRng::seed_from_u64(0x2545_f491_4f6c_dd1d);
        let (mut worst, mut checked) = (0, 0);
        let mut check = |d: u32| {
            let exact = (1u128 << 63) / d as u128;
            let y = reciprocal(d) as u128;
            assert!(y <= exact, "{d}: {y} above {exact}");
            worst = worst.max(exact - y);
            checked += 1;
        };
        for k in 0..31 {
            let p = 1u32 << 31 | 1 << k;
            for d in [p - 1, p, p + 1] {
                check(d.max(1 << 31));
            }
        }
        for d in [1 << 31, (1 << 31) + 1, u32::MAX - 1, u32::MAX] {
            check(d);
        }
        for _ in 0..1_000_000 {
            check(rng.next_u32() | 1 << 31);
        }
        assert!(checked > 1_000_000);
        assert!(worst <= 8, "{worst} units short");
    }
}
