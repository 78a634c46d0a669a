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
/// bits): Algorithm D on 16-bit digits. `d` is shifted until its top bit is set
/// (the numerator with it), so that each quotient digit estimated from the top
/// digits is at most 2 too large; the estimate is brought down while its
/// product with the divisor's second digit shows it too large.
pub(super) fn divide_words(high: u32, low: u32, d: u32) -> u32 {
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
