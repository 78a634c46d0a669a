//! A tilt sample's kick (`Scalar::from_pull`, `Scalar::from_pull_at`) against
//! the 128-bit product it replaces, in every format.

use super::tests::rng;
use super::*;

/// A tilt sample's kick on 64-bit words ([`Scalar::from_pull`]) against the
/// 128-bit product it replaces, bit for bit, in each fixed-point format: every
/// shift the kicks use and beyond, both roundings, the extremes of `mg` and of
/// the scale (a pull's scale is below 2⁶³).
#[test]
fn pull_kicks_are_the_128_bit_kicks() {
    fn check<S: Scalar>(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) {
        let n = mg as i128 * scale as i128;
        assert_eq!(
            S::from_pull(mg, scale, dv_shift, dp_shift),
            (
                S::from_scaled(n, dv_shift, false),
                S::from_scaled(n, dp_shift, true)
            ),
            "{} {mg} · {scale} >> {dv_shift}, {dp_shift}",
            S::NAME
        );
    }
    fn all(mg: i32, scale: i64, dv_shift: u32, dp_shift: u32) {
        check::<I8F24>(mg, scale, dv_shift, dp_shift);
        check::<I16F16>(mg, scale, dv_shift, dp_shift);
        check::<I32F32>(mg, scale, dv_shift, dp_shift);
    }
    let mgs = [i32::MIN, -8_000, -1_000, -1, 0, 1, 981, 8_000, i32::MAX];
    let scales = [0, 1, 0xffff_ffff, 1 << 32, 3 << 40, i64::MAX >> 8, i64::MAX];
    for mg in mgs {
        for scale in scales {
            for shift in 40..=110 {
                all(mg, scale, shift, shift);
                all(mg, scale, shift, shift + 8);
                // A kick's shifts: 56 + k and 56 + 2k + 1 (below 128, as
                // `from_scaled` takes them).
                all(mg, scale, shift, (2 * shift - 55).min(127));
            }
        }
    }
    let mut state = 0x9e37_79b9_7f4a_7c15;
    for _ in 0..100_000 {
        let mg = rng(&mut state) as i32 >> (rng(&mut state) % 32);
        let scale = (rng(&mut state) >> 1) as i64 >> (rng(&mut state) % 63);
        let dv_shift = 40 + (rng(&mut state) % 70) as u32;
        let dp_shift = 40 + (rng(&mut state) % 70) as u32;
        all(mg, scale, dv_shift, dp_shift);
    }
}

/// The kick at the boards' step with its shifts constant
/// ([`Scalar::from_pull_at`]) against the 128-bit product, in every format
/// (floating point takes the default, `from_pull`).
#[test]
fn constant_shift_kicks_are_the_128_bit_kicks() {
    fn check<S: Scalar>(mg: i32, scale: i64) {
        let n = mg as i128 * scale as i128;
        assert_eq!(
            S::from_pull_at::<63, 71>(mg, scale),
            (S::from_scaled(n, 63, false), S::from_scaled(n, 71, true)),
            "{} {mg} · {scale}",
            S::NAME
        );
    }
    let mut state = 0x2f4a_7c15_9e37_79b9;
    let mgs = [i32::MIN, -8_000, -1, 0, 1, 981, 8_000, i32::MAX];
    let scales = [
        0,
        1,
        0xffff_ffff,
        1 << 32,
        3 << 40,
        i64::MAX >> 8,
        i64::MAX,
        -5,
    ];
    let random = (0..20_000).map(|_| {
        let mg = rng(&mut state) as i32 >> (rng(&mut state) % 32);
        (mg, (rng(&mut state) >> 1) as i64 >> (rng(&mut state) % 63))
    });
    let edges = mgs
        .iter()
        .flat_map(|&mg| scales.iter().map(move |&s| (mg, s)));
    for (mg, scale) in edges.chain(random) {
        check::<I8F24>(mg, scale);
        check::<I16F16>(mg, scale);
        check::<I32F32>(mg, scale);
        check::<f32>(mg, scale);
        check::<f64>(mg, scale);
    }
}
