//! The floating-point backends (f32, f64): the reference the fixed formats are
//! measured against in the study.

use super::*;

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
pub(super) fn ilog2_f32(x: f32) -> i32 {
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

pub(super) fn pow2_neg_f32(n: u32) -> f32 {
    // 2^-n built from the exponent field: exact, no libm call. n ≤ 126 in practice.
    f32::from_bits((127u32.saturating_sub(n.min(126))) << 23)
}
