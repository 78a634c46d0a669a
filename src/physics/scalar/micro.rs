//! `f32` with micromath's approximate square root: the study's cheapest float.

use super::float::{ilog2_f32, pow2_neg_f32};
use super::*;

/// `f32` whose square root is `micromath`'s fast approximation (exponent halving,
/// up to ~6 % off): the study's "f32 + micromath" backend, showing what that costs
/// in accuracy.
#[derive(Clone, Copy, PartialEq, PartialOrd, Debug, Default)]
pub struct MicroF32(pub f32);

impl Add for MicroF32 {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        MicroF32(self.0 + o.0)
    }
}
impl Sub for MicroF32 {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        MicroF32(self.0 - o.0)
    }
}
impl Mul for MicroF32 {
    type Output = Self;
    fn mul(self, o: Self) -> Self {
        MicroF32(self.0 * o.0)
    }
}
impl Neg for MicroF32 {
    type Output = Self;
    fn neg(self) -> Self {
        MicroF32(-self.0)
    }
}
impl AddAssign for MicroF32 {
    fn add_assign(&mut self, o: Self) {
        self.0 += o.0
    }
}
impl SubAssign for MicroF32 {
    fn sub_assign(&mut self, o: Self) {
        self.0 -= o.0
    }
}

impl Scalar for MicroF32 {
    const ZERO: Self = MicroF32(0.0);
    const ONE: Self = MicroF32(1.0);
    const NAME: &'static str = "f32-micromath";
    const EXACT_SQRT: bool = false;
    fn from_int(n: i32) -> Self {
        MicroF32(n as f32)
    }
    fn from_f64(x: f64) -> Self {
        MicroF32(x as f32)
    }
    fn to_f64(self) -> f64 {
        self.0 as f64
    }
    fn floor_int(self) -> i32 {
        use micromath::F32Ext;
        F32Ext::floor(self.0) as i32
    }
    fn shr(self, n: u32) -> Self {
        MicroF32(self.0 * pow2_neg_f32(n))
    }
    fn shl(self, n: u32) -> Self {
        MicroF32(self.0 * (1u64 << n) as f32)
    }
    fn sqrt(self) -> Self {
        use micromath::F32Ext;
        if self.0 <= 0.0 {
            MicroF32(0.0)
        } else {
            MicroF32(F32Ext::sqrt(self.0))
        }
    }
    fn div(self, rhs: Self) -> Self {
        if rhs.0 == 0.0 {
            MicroF32(0.0)
        } else {
            MicroF32(self.0 / rhs.0)
        }
    }
    fn next_down(self) -> Self {
        MicroF32(f32::next_down(self.0))
    }
    fn hash_bits(self) -> u64 {
        self.0.to_bits() as u64
    }
    fn ilog2(self) -> i32 {
        ilog2_f32(self.0)
    }
}
