//! The fixed-point shifts' two forms each (`fixed_point::RoundShr`,
//! `fixed_point::SatShl`: the Cortex-M0's and every other target's) against
//! the expressions they replaced, on every target.

use super::fixed_point::{
    round_shr_bit, round_shr_bit_wide, round_shr_sum, round_shr_sum_wide, sat_shl_back,
    sat_shl_back_wide, sat_shl_limit, sat_shl_limit_wide,
};
use super::tests::rng;
use super::*;

/// The saturating left shift's two forms (shifted, and kept when it shifts
/// back: the Cortex-M0's; the range check, `MAX` above `MAX >> n`, `MIN` below
/// its negation: elsewhere) against the range check written out, and `shl`
/// itself: every shift of every format, the ends of the range, each side
/// of the limits and random words.
#[test]
fn shl_saturates_where_the_range_check_did() {
    let mut state = 0x2c1b_3c6d_9f4a_7e55_u64;
    for n in 0..32u32 {
        let limit = i32::MAX >> n;
        let want = |b: i32| {
            if b > limit {
                i32::MAX
            } else if b < -limit {
                i32::MIN
            } else {
                b << n
            }
        };
        let near = [limit, -limit, i32::MIN >> n];
        let words = [i32::MIN, i32::MIN + 1, -1, 0, 1, i32::MAX - 1, i32::MAX]
            .into_iter()
            .chain(
                near.into_iter()
                    .flat_map(|b| [b.saturating_sub(1), b, b.saturating_add(1)]),
            )
            .chain((0..2000).map(|_| (rng(&mut state) as i32) >> (n % 31)));
        for b in words {
            assert_eq!(I8F24::from_bits(b).shl(n).to_bits(), want(b), "{b} << {n}");
            assert_eq!(I16F16::from_bits(b).shl(n).to_bits(), want(b), "{b} << {n}");
            // Both forms, whichever this target's `shl` takes.
            assert_eq!(sat_shl_back(b, n), want(b), "{b} << {n}");
            assert_eq!(sat_shl_limit(b, n), want(b), "{b} << {n}");
        }
    }
    for n in 0..64u32 {
        let limit = i64::MAX >> n;
        for b in [
            i64::MIN,
            -limit - 1,
            -limit,
            -1,
            0,
            1,
            limit,
            limit.saturating_add(1),
            i64::MAX,
        ]
        .into_iter()
        .chain((0..500).map(|_| (rng(&mut state) as i64) >> (n % 63)))
        {
            let want = if b > limit {
                i64::MAX
            } else if b < -limit {
                i64::MIN
            } else {
                b << n
            };
            assert_eq!(I32F32::from_bits(b).shl(n).to_bits(), want, "{b} << {n}");
            assert_eq!(sat_shl_back_wide(b, n), want, "{b} << {n}");
            assert_eq!(sat_shl_limit_wide(b, n), want, "{b} << {n}");
        }
    }
}

/// The rounding shift's two forms (`m + 2^(n−1)` shifted, the sign put back
/// without a branch: the Cortex-M0's; `(m >> n) + ((m >> (n − 1)) & 1)`
/// negated for a negative value: elsewhere) against the latter written out,
/// and `shr` itself: every shift of every format, the ends of the range, the
/// ties and random words.
#[test]
fn shr_is_the_magnitude_rounded_half_up_and_the_sign_put_back() {
    let mut state = 0x5851_f42d_4c95_7f2d_u64;
    let want = |bits: i64, n: u32| {
        let m = bits.unsigned_abs();
        let q = ((m >> n) + ((m >> (n - 1)) & 1)) as i64;
        if bits < 0 {
            -q
        } else {
            q
        }
    };
    let ends = [
        i32::MIN,
        i32::MIN + 1,
        -3,
        -2,
        -1,
        0,
        1,
        2,
        3,
        i32::MAX - 1,
        i32::MAX,
    ];
    let mut checked = 0;
    for n in 1..32 {
        let half = 1i64 << (n - 1);
        let ties = [half, -half, 3 * half, -3 * half, half - 1, 1 - half];
        let words = ends
            .iter()
            .map(|&b| b as i64)
            .chain(ties.iter().copied().filter(|&b| b as i32 as i64 == b))
            .chain((0..2000).map(|_| rng(&mut state) as i32 as i64));
        for bits in words {
            let b = bits as i32;
            assert_eq!(
                I8F24::from_bits(b).shr(n).to_bits() as i64,
                want(bits, n),
                "{b} >> {n}"
            );
            assert_eq!(
                I16F16::from_bits(b).shr(n).to_bits() as i64,
                want(bits, n),
                "{b} >> {n}"
            );
            // Both forms, whichever this target's `shr` takes.
            assert_eq!(round_shr_sum(b, n) as i64, want(bits, n), "{b} >> {n}");
            assert_eq!(round_shr_bit(b, n) as i64, want(bits, n), "{b} >> {n}");
            checked += 4;
        }
    }
    for n in 1..64 {
        for bits in [i64::MIN, i64::MIN + 1, -1, 0, 1, i64::MAX]
            .into_iter()
            .chain((0..500).map(|_| rng(&mut state) as i64))
        {
            let m = bits.unsigned_abs();
            let q = ((m >> n) + ((m >> (n - 1)) & 1)) as i64;
            let q = if bits < 0 { -q } else { q };
            assert_eq!(I32F32::from_bits(bits).shr(n).to_bits(), q, "{bits} >> {n}");
            assert_eq!(round_shr_sum_wide(bits, n), q, "{bits} >> {n}");
            assert_eq!(round_shr_bit_wide(bits, n), q, "{bits} >> {n}");
            checked += 1;
        }
    }
    assert!(checked > 100_000);
}
