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
/// operands are 32-bit here, which [`mul_shr_halves`] uses. Not inlined: one copy
/// for all the step's products keeps the v1 within its flash.
#[cfg(all(target_arch = "arm", not(target_has_atomic = "32")))]
#[inline(never)]
pub(super) fn mul_shr<const FRAC: u32>(a: i32, b: i32) -> i32 {
    mul_shr_halves::<FRAC>(a, b)
}

/// `mul_shr` from four 16 × 16 → 32 products, exact. With `a = ah·2¹⁶ + al`
/// (`ah` signed, `al` in `0..2¹⁶`) and `b` likewise, `a·b = ah·bh·2³² +
/// (ah·bl + al·bh)·2¹⁶ + al·bl`, and every partial product fits 32 bits:
/// `|ah·bh| ≤ 2³⁰`, `ah·bl` and `al·bh` lie in `[−2³¹ + 2¹⁵, 2³¹)`, `al·bl < 2³²`
/// unsigned. The product is kept as two words, `ah·bh : al·bl`, and each cross
/// product added in at bit 16 as its own two words (`c >> 16 : c << 16`) with
/// a carry: the `adds`/`adcs` pairs a Cortex-M0 has, where a 64-bit sum of the
/// cross products first would take a third word and a spill to the stack
/// (the function: 30 instructions that way, 27 this way; LLVM reassociates a
/// sum of sign-extended 64-bit terms back into the first form).
#[cfg_attr(
    not(all(target_arch = "arm", not(target_has_atomic = "32"))),
    allow(dead_code)
)]
#[inline(always)]
pub(super) fn mul_shr_halves<const FRAC: u32>(a: i32, b: i32) -> i32 {
    let (ah, al) = (a >> 16, a & 0xffff);
    let (bh, bl) = (b >> 16, b & 0xffff);
    let (c1, c2) = (ah * bl, al * bh);
    let (lo, carry) = (al as u32 * bl as u32).overflowing_add((c1 << 16) as u32);
    let hi = (ah * bh).wrapping_add(c1 >> 16).wrapping_add(carry as i32);
    let (lo, carry) = lo.overflowing_add((c2 << 16) as u32);
    let hi = hi.wrapping_add(c2 >> 16).wrapping_add(carry as i32);
    if FRAC == 0 {
        lo as i32
    } else {
        (hi << (32 - FRAC)) | (lo >> FRAC) as i32
    }
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
