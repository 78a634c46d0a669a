//! The products of two 32-bit words: the fixed-point product of a 32-bit
//! format ([`mul_shr`]) and the full 64-bit product ([`mul_wide`]), each one
//! instruction where the core multiplies 32 × 32 → 64 and four 16-bit products
//! on the Cortex-M0, which has no such multiply.

/// Bits `FRAC..FRAC + 32` of the exact product `a · b`, wrapping: the fixed-point
/// product of two 32-bit formats with `FRAC` fraction bits. One `smull` and a
/// shift where the core has a 32 × 32 → 64 multiply.
#[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
#[inline(always)]
pub(super) fn mul_shr<const FRAC: u32>(a: i32, b: i32) -> i32 {
    ((a as i64 * b as i64) >> FRAC) as i32
}

/// Bits `FRAC..FRAC + 32` of the exact product `a · b` on ARMv6-M (the
/// Cortex-M0 of the micro:bit v1: recognised by its lack of 32-bit atomic
/// read-modify-write, as the architecture's own `target_feature`s are unstable).
///
/// Its `muls` keeps the low 32 bits only, so LLVM builds an `i64` product from a
/// call to the generic 64 × 64 library multiply (`__aeabi_lmul`, 37 instructions
/// with its stack frame), 27 % of the v1 demo's instructions through it. Both
/// operands are 32-bit here, which [`mul_shr_split`] uses. Not inlined: one copy
/// for all the step's products keeps the v1 within its flash.
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
#[inline(never)]
pub(super) fn mul_shr<const FRAC: u32>(a: i32, b: i32) -> i32 {
    mul_shr_split::<FRAC>(a, b)
}

/// `mul_shr` for `16 ≤ FRAC < 32`, by the first operand's size: two 16-bit
/// products ([`mul_shr_short`]) when it fits 16 signed bits, four
/// ([`mul_shr_halves`]) otherwise. Many of the step's first operands are small
/// in the pitch unit (2¹⁵ LSB is 2⁻⁹ pitch, about 20 µm): in the host
/// simulator's plays of grand-tour and of a difficulty-9 maze, 54 % and 52 % of
/// the step's products have a 16-bit first operand (31 % and 20 % a 16-bit
/// second one). The test (`a >> 15` against its low half's sign,
/// which shares a shift with the split) costs 4 instructions on the long path
/// and saves 9 on the short one (15 with the call frame, against 24); testing
/// the second operand too cost more on the worst frames than it saved. A zero
/// first operand, a short one, is answered at once: a vector's component on
/// an axis the motion does not use (a flat scene's y', a marble pressed on
/// another in a plane) is one, a third of the products of a vector there.
/// Tested on the short path only (two instructions there, none on the long
/// one), the v1's worst frames moved −2.2 to +0.3 % (four-shaken 129 836 →
/// 128 805, drop-onto-marble 84 695 → 83 617, grand-tour 58 969 → 57 695,
/// maze-2-7x7x2-d9 65 109 → 65 297); tested before the split, −4.2 to +1.1 %.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn mul_shr_split<const FRAC: u32>(a: i32, b: i32) -> i32 {
    // `a` fits 16 bits when its bits from 15 up all equal bit 15. Written so
    // rather than `al == a`, which LLVM turns into an add of 2¹⁵ and a range
    // test (a constant to build and no shift shared with the split).
    let al = a as i16 as i32;
    if (a >> 15) == (al >> 15) {
        if a == 0 {
            return 0;
        }
        mul_shr_short::<FRAC>(b, a)
    } else {
        mul_shr_halves::<FRAC>(a, b)
    }
}

/// `mul_shr` when `short` fits 16 signed bits (`16 ≤ FRAC < 32`): with `a =
/// ah·2¹⁶ + al` (`ah = a >> 16`, `al` in `[0, 2¹⁶)`), `a·short = c·2¹⁶ + lo` with
/// `c = ah·short` (`|c| ≤ 2³⁰`) and `lo = al·short` (`|lo| < 2³¹`: a word), so
/// the bits from `FRAC` are `⌊(c + ⌊lo / 2¹⁶⌋) / 2^(FRAC−16)⌋`, whose sum fits a
/// word (`|·| ≤ 2³⁰ + 2¹⁵`). The exact quotient is below 2³¹ in magnitude, so
/// it is also the wrapping one.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn mul_shr_short<const FRAC: u32>(a: i32, short: i32) -> i32 {
    const {
        assert!(
            FRAC >= 16 && FRAC < 32,
            "a 32-bit format with 16 to 31 fraction bits"
        )
    };
    debug_assert_eq!(short as i16 as i32, short, "a 16-bit operand");
    let (ah, al) = (a >> 16, a & 0xffff);
    ((ah * short) + ((al * short) >> 16)) >> (FRAC - 16)
}

/// `mul_shr` from four 16 × 16 → 32 products, exact, for `16 ≤ FRAC < 32`.
///
/// Each operand is split into *signed* halves, `a = ah·2¹⁶ + al` with `al =
/// a as i16` in `[−2¹⁵, 2¹⁵)` and `ah = (a − al)/2¹⁶` in `[−2¹⁵, 2¹⁵]` (taken
/// as `(a >> 16) − (al >> 15)`: `a − al` itself can be 2³¹). With `hh = ah·bh`,
/// `c1 = ah·bl`, `c2 = al·bh` and `lo = al·bl`, each of magnitude at most 2³⁰,
/// the product is `hh·2³² + (c1 + c2)·2¹⁶ + lo`, so its bits from `FRAC` are
/// `hh·2^(32−FRAC) + ⌊s / 2^(FRAC−16)⌋` with `s = c1 + c2 + ⌊lo / 2¹⁶⌋`
/// (nested floors). That `s` fits 32 bits: `|s| ≥ 2³¹` would need `|c1|` and
/// `|c2|` above `2³⁰ − 2¹⁵`, which only halves of magnitude 2¹⁵ give (`bl = al
/// = −2¹⁵`, then `ah = bh = 2¹⁵`: `a = b = 2³¹ − 2¹⁵`), and there `s = −2³¹ +
/// 2¹⁴`. So the sum needs no carry word, which unsigned low halves (`c1` and
/// `c2` up to 2³¹ each) do: on the Cortex-M0 the function is 24 instructions
/// with its frame, against 27 (the tests hold it to the 64-bit product on
/// the extremes of every half and on random operands).
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn mul_shr_halves<const FRAC: u32>(a: i32, b: i32) -> i32 {
    const {
        assert!(
            FRAC >= 16 && FRAC < 32,
            "a 32-bit format with 16 to 31 fraction bits"
        )
    };
    let al = a as i16 as i32;
    let ah = (a >> 16) - (al >> 15);
    let bl = b as i16 as i32;
    let bh = (b >> 16) - (bl >> 15);
    let s = (ah * bl)
        .wrapping_add(al * bh)
        .wrapping_add((al * bl) >> 16);
    ((ah * bh) << (32 - FRAC)).wrapping_add(s >> (FRAC - 16))
}

/// The exact product `a · b` of two 32-bit words. One `umull` where the core
/// has a 32 × 32 → 64 multiply.
#[cfg(not(all(target_arch = "arm", not(target_has_atomic = "32"))))]
#[inline(always)]
pub(super) fn mul_wide(a: u32, b: u32) -> u64 {
    a as u64 * b as u64
}

/// The exact product `a · b` on ARMv6-M, from four 16 × 16 → 32 products
/// ([`mul_wide_halves`]): LLVM would call the 64 × 64 library multiply.
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
#[inline(always)]
pub(super) fn mul_wide(a: u32, b: u32) -> u64 {
    mul_wide_halves(a, b)
}

/// `a · b` from the products of their 16-bit halves: `ah·bh·2³² + (ah·bl +
/// al·bh)·2¹⁶ + al·bl`, each partial product below 2³², their sums in 64 bits.
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn mul_wide_halves(a: u32, b: u32) -> u64 {
    let (ah, al) = (a >> 16, a & 0xffff);
    let (bh, bl) = (b >> 16, b & 0xffff);
    let cross = (ah * bl) as u64 + (al * bh) as u64;
    (((ah * bh) as u64) << 32) + (cross << 16) + (al * bl) as u64
}
