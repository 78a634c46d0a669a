//! The backends against each other and against exact arithmetic.

use super::fixed_point::scaled_bits;
use super::product::{mul_shr_halves, mul_shr_short, mul_shr_split, mul_wide_halves};
use super::quotient::{div_frac, divide_digits, divide_reciprocal, divide_words};
use super::rsqrt::{sqrt_bits, RSQRT_SEED};
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

/// The Cortex-M0's product from 16-bit halves against the 64-bit one, bit for
/// bit: every pair of operands built from the extremes of each half (signed and
/// unsigned: the split's `ah = 2¹⁵` and `s = −2³¹ + 2¹⁴` cases among them),
/// and random operands (the M0 end-state hashes in the study check it on the
/// chip).
/// Half-words where a split's carry or sign changes.
const HALVES: [u32; 9] = [0, 1, 2, 0x7ffe, 0x7fff, 0x8000, 0x8001, 0xfffe, 0xffff];

/// Operand `i` of 81: a high and a low half from [`HALVES`].
fn edge(i: usize) -> i32 {
    ((HALVES[i / 9] << 16) | HALVES[i % 9]) as i32
}

/// `product` at 24, 16 and 31 fraction bits against the 64-bit product.
fn is_wide(product: [fn(i32, i32) -> i32; 3], a: i32, b: i32) {
    let wide = a as i64 * b as i64;
    for (f, frac) in product.into_iter().zip([24, 16, 31]) {
        assert_eq!(f(a, b), (wide >> frac) as i32, "{a} · {b} at {frac}");
    }
}

#[test]
fn halves_product_is_the_wide_product() {
    let halves = [
        mul_shr_halves::<24> as fn(i32, i32) -> i32,
        mul_shr_halves::<16>,
        mul_shr_halves::<31>,
    ];
    let check = |a, b| is_wide(halves, a, b);
    for i in 0..81 {
        for j in 0..81 {
            check(edge(i), edge(j));
        }
    }
    let mut state = 0x9e37_79b9_7f4a_7c15;
    for _ in 0..1_000_000 {
        check(rng(&mut state) as i32, rng(&mut state) as i32);
    }
    // Operands near the edges of a half, where a carry or a sign changes.
    for _ in 0..200_000 {
        let near = |state: &mut u64| {
            let r = rng(state);
            let h = HALVES[(r % 9) as usize]
                .wrapping_add((r >> 8) as u32 % 5)
                .wrapping_sub(2);
            let l = HALVES[((r >> 16) % 9) as usize]
                .wrapping_add((r >> 24) as u32 % 5)
                .wrapping_sub(2);
            ((h << 16) ^ (l & 0xffff)) as i32
        };
        check(near(&mut state), near(&mut state));
    }
}

/// The Cortex-M0's product with a 16-bit operand against the 64-bit one: every
/// 16-bit operand against the extremes of each half of the other, and random
/// pairs; then the dispatch by the first operand's size ([`mul_shr_split`]) on
/// operands at and beside the 16-bit limits, zero among them (answered before
/// any product), in both orders, and random ones.
#[test]
fn short_product_is_the_wide_product() {
    let split = [
        mul_shr_split::<24> as fn(i32, i32) -> i32,
        mul_shr_split::<16>,
        mul_shr_split::<31>,
    ];
    let short_product = [
        mul_shr_short::<24> as fn(i32, i32) -> i32,
        mul_shr_short::<16>,
        mul_shr_short::<31>,
    ];
    let check = |a, b| is_wide(split, a, b);
    for short in i16::MIN..=i16::MAX {
        for i in 0..81 {
            is_wide(short_product, edge(i), short as i32);
        }
    }
    let limits = [
        i32::MIN,
        -0x8001,
        -0x8000,
        -0x7fff,
        -1,
        0,
        1,
        0x7ffe,
        0x7fff,
        0x8000,
        0x1_0000,
        i32::MAX,
    ];
    for a in limits {
        for b in limits {
            check(a, b);
        }
    }
    let mut state = 0x6a09_e667_f3bc_c908;
    for _ in 0..1_000_000 {
        let (a, b) = (rng(&mut state) as i32, rng(&mut state) as i32);
        check(a, b);
        check(a, b as i16 as i32);
        check(a as i16 as i32, b);
    }
}

/// The Cortex-M0's full product from 16-bit halves against the native one.
#[test]
fn halves_wide_product_is_the_wide_product() {
    let edges = [0, 1, 0xffff, 0x1_0000, 0x7fff_ffff, 0x8000_0000, u32::MAX];
    for a in edges {
        for b in edges {
            assert_eq!(mul_wide_halves(a, b), a as u64 * b as u64, "{a} · {b}");
        }
    }
    let mut state = 0x2545_f491_4f6c_dd1d;
    for _ in 0..200_000 {
        let (a, b) = (rng(&mut state) as u32, rng(&mut state) as u32);
        assert_eq!(mul_wide_halves(a, b), a as u64 * b as u64, "{a} · {b}");
    }
}

/// The two-digit long division against the 64-bit one: every shift of the
/// divisor, quotients at both ends, random words.
#[test]
fn word_division_is_the_64_bit_division() {
    fn check(high: u32, low: u32, d: u32) {
        let n = (high as u64) << 32 | low as u64;
        assert_eq!(divide_words(high, low, d) as u64, n / d as u64, "{n} / {d}");
        // Both ways, whichever this target takes.
        assert_eq!(
            divide_digits(high, low, d) as u64,
            n / d as u64,
            "{n} / {d}"
        );
        assert_eq!(
            divide_reciprocal(high, low, d) as u64,
            n / d as u64,
            "{n} / {d}"
        );
    }
    let mut state = 0x51_7cc1_b727_220a;
    for shift in 0..32 {
        for _ in 0..2_000 {
            let d = ((rng(&mut state) as u32) | 1 << 31) >> shift;
            let high = rng(&mut state) as u32 % d;
            check(high, rng(&mut state) as u32, d);
            check(d - 1, u32::MAX, d);
            check(0, rng(&mut state) as u32, d);
        }
    }
    for d in [
        1,
        2,
        3,
        0xffff,
        0x1_0000,
        0x1_0001,
        0x7fff_ffff,
        0x8000_0000,
        u32::MAX,
    ] {
        for high in [0, 1, d / 2, d - 1] {
            for low in [0, 1, 0xffff, 0x8000_0000, u32::MAX] {
                check(high.min(d - 1), low, d);
            }
        }
    }
}

/// The fixed-point quotient ([`Scalar::div`]) bit for bit `fixed`'s
/// `saturating_div`, in each format: signs, saturation both ways, `MIN`,
/// quotients at the edges of the range, random operands of every size.
#[test]
fn quotients_are_fixed_s_saturating_quotients() {
    fn check<const FRAC: u32>(a: i32, b: i32) {
        use fixed::types::extra::{U16, U24};
        use fixed::FixedI32;
        let want = match FRAC {
            24 => FixedI32::<U24>::from_bits(a)
                .saturating_div(FixedI32::<U24>::from_bits(b))
                .to_bits(),
            16 => FixedI32::<U16>::from_bits(a)
                .saturating_div(FixedI32::<U16>::from_bits(b))
                .to_bits(),
            _ => unreachable!(),
        };
        assert_eq!(div_frac::<FRAC>(a, b), want, "{a} / {b} ({FRAC})");
    }
    let edges = [
        i32::MIN,
        i32::MIN + 1,
        -(1 << 24),
        -3,
        -1,
        0,
        1,
        2,
        3,
        1 << 16,
        1 << 24,
        (1 << 24) + 1,
        i32::MAX - 1,
        i32::MAX,
    ];
    for a in edges {
        for b in edges.into_iter().filter(|&b| b != 0) {
            check::<24>(a, b);
            check::<16>(a, b);
        }
    }
    let mut state = 0x2b99_2ddf_a232_49d6;
    for _ in 0..300_000 {
        let a = rng(&mut state) as i32 >> (rng(&mut state) % 32);
        let b = rng(&mut state) as i32 >> (rng(&mut state) % 32);
        if b != 0 {
            check::<24>(a, b);
            check::<16>(a, b);
        }
    }
    // Through the trait, I32F32 included (`fixed`'s own quotient there).
    for (a, b) in [(3.0, 7.0), (-1.5, 0.25), (100.0, -0.001), (1e-6, 1e3)] {
        assert_eq!(
            I8F24::from_f64(a).div(I8F24::from_f64(b)),
            I8F24::from_f64(a).saturating_div(I8F24::from_f64(b))
        );
        assert_eq!(
            I32F32::from_f64(a).div(I32F32::from_f64(b)),
            I32F32::from_f64(a).saturating_div(I32F32::from_f64(b))
        );
    }
}

/// The square root ([`Scalar::sqrt`]) bit for bit `fixed`'s, rounded down, in
/// I8F24 and I16F16: the smallest values, every power of two and its
/// neighbours, squares and their neighbours, the largest, random values of
/// every size.
#[test]
fn roots_are_fixed_s_roots() {
    fn check(bits: i32) {
        use fixed::types::extra::{U16, U24};
        use fixed::FixedI32;
        let want24 = FixedI32::<U24>::from_bits(bits).sqrt().to_bits();
        let want16 = FixedI32::<U16>::from_bits(bits).sqrt().to_bits();
        assert_eq!(sqrt_bits::<24>(bits as u32) as i32, want24, "√{bits} (24)");
        assert_eq!(sqrt_bits::<16>(bits as u32) as i32, want16, "√{bits} (16)");
    }
    for bits in 1..5_000 {
        check(bits);
    }
    for p in 0..31 {
        for d in -2..=2 {
            check(((1i64 << p) + d).clamp(1, i32::MAX as i64) as i32);
        }
    }
    for r in [3u64, 4_095, 4_096, 46_340, 1 << 15, 3 << 13] {
        for d in -1..=1 {
            check(((r * r) as i64 + d).clamp(1, i32::MAX as i64) as i32);
        }
    }
    check(i32::MAX);
    let mut state = 0x1d8e_4e27_c47d_124f;
    for _ in 0..500_000 {
        check(((rng(&mut state) as u32 >> (rng(&mut state) % 32)) as i32 & i32::MAX).max(1));
    }
    // Through the trait (the inherent `sqrt` panics below zero).
    assert_eq!(Scalar::sqrt(I8F24::ZERO), I8F24::ZERO);
    assert_eq!(Scalar::sqrt(I8F24::from_f64(-4.0)), I8F24::ZERO);
    assert_eq!(Scalar::sqrt(I8F24::from_f64(2.25)), I8F24::from_f64(1.5));
    assert_eq!(Scalar::sqrt(I32F32::from_f64(2.25)), I32F32::from_f64(1.5));
}

/// [`roots_are_fixed_s_roots`] over every positive I8F24 value (about two
/// minutes in release: `cargo test --release --lib every_root -- --ignored`).
#[test]
#[ignore]
fn every_root_is_fixed_s_root() {
    use fixed::types::extra::U24;
    use fixed::FixedI32;
    for bits in 1..=i32::MAX {
        let want = FixedI32::<U24>::from_bits(bits).sqrt().to_bits();
        assert_eq!(sqrt_bits::<24>(bits as u32) as i32, want, "√{bits}");
    }
}

/// A small deterministic generator (xorshift64*) for the equivalence sweeps
/// (`shift_tests.rs` draws from it too).
pub(super) fn rng(state: &mut u64) -> u64 {
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
