//! The inverse square root and the square root on a fixed-point format's bits,
//! without a division.

use super::product::mul_wide;

/// `1/√x` for a fixed-point `x = bits·2^-frac > 0`, as bits of the same format,
/// rounded to nearest (within 1 LSB).
///
/// Written by hand because no crate offers a division-free fixed-point inverse
/// root: Cortex-M has no 64-bit divide and Cortex-M0 no divide at all, and this is
/// on the per-step path of rolling resistance and of every edge contact. `x` is
/// scaled by a power of four into `m ∈ [1, 4)`, a 96-entry table (by `m`'s top
/// bits) seeds `1/√m` to within 0.8 %, and Newton steps `y ← y·(3 − m·y²)/2` in
/// Q31 with 32×32→64-bit products (one instruction each on a Cortex-M3/M4, four
/// 16-bit multiplies on a Cortex-M0: `mul_wide`) take it
/// to 10⁻⁴, then 1.5·10⁻⁸ — enough for 24 fraction bits — and a third step for
/// wider formats.
pub(crate) fn rsqrt_bits(bits: u64, frac: u32) -> u64 {
    if bits == 0 {
        return 0;
    }
    // x = bits·2^-frac = m·4^k with m ∈ [1, 4), m in Q30 (fits 32 bits: m < 4):
    // bits·2^(30 − frac − 2k). With b the bit length of `bits` that shift is
    // 31 − b or 32 − b, so a value that fits 32 bits (every 32-bit format) needs
    // no 64-bit shift: the same k and m on one word.
    let (k, m) = if let Ok(x) = u32::try_from(bits) {
        normalise_word(x, frac)
    } else {
        let b = 64 - bits.leading_zeros() as i32;
        let k = (b - 1 - frac as i32).div_euclid(2);
        let sh = 30 - frac as i32 - 2 * k;
        (k, if sh >= 0 { bits << sh } else { bits >> (-sh) } as u32)
    };
    let y = rsqrt_q31(m, if frac <= 24 { 2 } else { 3 });
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

/// `x = bits·2^-frac = m·4^k` for `bits > 0` of one word: `(k, m)` with `m` in
/// Q30 (`[1, 4)`), shifted by `30 − frac − 2k`, which is `−1 ..= 31`.
#[inline(always)]
fn normalise_word(bits: u32, frac: u32) -> (i32, u32) {
    let b = 32 - bits.leading_zeros() as i32;
    let k = (b - 1 - frac as i32).div_euclid(2);
    let sh = 30 - frac as i32 - 2 * k;
    (k, if sh >= 0 { bits << sh } else { bits >> (-sh) })
}

/// `1/√m` in Q31 for `m` in Q30 (`[1, 4)`): the seed, then `steps` Newton
/// steps `y·(3 − m·y²)/2`.
#[inline(always)]
fn rsqrt_q31(m: u32, steps: u32) -> u32 {
    let slice = ((m >> 25) as usize).saturating_sub(32).min(95);
    let mut y: u32 = RSQRT_SEED[slice]; // Q31
    for _ in 0..steps {
        // (3 − m·y²)/2 in Q31 is (3·2^31 − my2)/2 = 3·2^30 − my2/2.
        let y2 = (mul_wide(y, y) >> 31) as u32; // Q31
        let my2 = (mul_wide(m, y2) >> 30) as u32; // Q31, ≈ 1
        let t = (3u32 << 30).wrapping_sub(my2 >> 1);
        y = (mul_wide(y, t) >> 31) as u32;
    }
    y
}

/// `√x` for `x = bits·2^-FRAC > 0` in a 32-bit format, as bits of the same
/// format rounded down: `⌊√(bits·2^FRAC)⌋`, which is `fixed`'s `sqrt` (the
/// tests hold it to the crate). `fixed` takes it a bit at a time, 28 rounds of
/// a compare and a subtract for I8F24, every time of impact and impact speed
/// of the event step (9 % of drop-onto-marble's worst frame on the M4). Here
/// the inverse root's seed and two Newton steps give `√m = m·(1/√m)` to
/// `1.5·10⁻⁸`, within a few units of the result, and comparing squares with
/// `bits·2^FRAC` makes it exact.
#[inline(never)]
pub(crate) fn sqrt_bits<const FRAC: u32>(bits: u32) -> u32 {
    debug_assert!(FRAC <= 27, "the high word's shift needs FRAC ≤ 27");
    if bits == 0 {
        return 0;
    }
    let (k, m) = normalise_word(bits, FRAC);
    // √x·2^FRAC = (m/2^30)·(y/2^31)·2^k·2^FRAC = m·y·2^-(61 − k − FRAC), and
    // that shift is at least 32 for a 32-bit format: taken on the high word.
    let y = rsqrt_q31(m, 2);
    let s = (61 - k - FRAC as i32) as u32;
    let mut r = ((mul_wide(m, y) >> 32) as u32) >> (s - 32).min(31);
    let n = (bits as u64) << FRAC;
    while mul_wide(r, r) > n {
        r -= 1;
    }
    while mul_wide(r + 1, r + 1) <= n {
        r += 1;
    }
    r
}

/// `1/√m` in Q31 at the middle of the 96 slices of width 1/32 covering `[1, 4)`.
pub(super) const RSQRT_SEED: [u32; 96] = [
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
