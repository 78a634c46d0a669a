//! A 3-vector over any [`Scalar`]: positions, velocities and normals in the tile frame.

use core::ops::{Add, AddAssign, Neg, Sub, SubAssign};

use super::scalar::Scalar;

/// `(x, y, z)`; in the tile frame x' runs along the grid columns, y' up out of the
/// board, z' along the grid rows towards the player.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Vec3<S> {
    /// x' component.
    pub x: S,
    /// y' component (up).
    pub y: S,
    /// z' component.
    pub z: S,
}

impl<S: Scalar> Vec3<S> {
    /// The zero vector.
    pub const ZERO: Self = Vec3 {
        x: S::ZERO,
        y: S::ZERO,
        z: S::ZERO,
    };

    /// A vector from its components.
    #[inline]
    pub const fn new(x: S, y: S, z: S) -> Self {
        Vec3 { x, y, z }
    }
    /// Every component times `k`.
    #[inline]
    pub fn scale(self, k: S) -> Self {
        Vec3::new(self.x.times(k), self.y.times(k), self.z.times(k))
    }
    /// Every component times `2^-n` (see [`Scalar::shr`]).
    // A rounding scale by a power of two, not the bit shift `>>` of `core::ops::Shr`.
    #[allow(clippy::should_implement_trait)]
    #[inline]
    pub fn shr(self, n: u32) -> Self {
        Vec3::new(self.x.shr(n), self.y.shr(n), self.z.shr(n))
    }
    /// Every component times `2^n` (see [`Scalar::shl`]).
    #[allow(clippy::should_implement_trait)]
    #[inline]
    pub(crate) fn shl(self, n: u32) -> Self {
        Vec3::new(self.x.shl(n), self.y.shl(n), self.z.shl(n))
    }
    /// Dot product.
    #[inline]
    pub fn dot(self, o: Self) -> S {
        self.x.times(o.x) + self.y.times(o.y) + self.z.times(o.z)
    }
    /// Cross product.
    #[inline]
    pub fn cross(self, o: Self) -> Self {
        Vec3::new(
            self.y.times(o.z) - self.z.times(o.y),
            self.z.times(o.x) - self.x.times(o.z),
            self.x.times(o.y) - self.y.times(o.x),
        )
    }
    /// `|v|²`. Callers keep `v` small (per-step units) so this cannot overflow.
    #[inline]
    pub(crate) fn length_sq(self) -> S {
        self.dot(self)
    }
    /// The component along the axis `axis` (0 = x', 1 = y', 2 = z').
    #[inline]
    pub fn axis(self, axis: usize) -> S {
        match axis {
            0 => self.x,
            1 => self.y,
            _ => self.z,
        }
    }

    /// Sets the component along the axis `axis` (0 = x', 1 = y', 2 = z').
    #[inline]
    pub(crate) fn set_axis(&mut self, axis: usize, value: S) {
        match axis {
            0 => self.x = value,
            1 => self.y = value,
            _ => self.z = value,
        }
    }
    /// Component-wise clamp into `[-limit, limit]`.
    #[inline]
    pub fn clamp_abs(self, limit: S) -> Self {
        Vec3::new(
            self.x.clamp(-limit, limit),
            self.y.clamp(-limit, limit),
            self.z.clamp(-limit, limit),
        )
    }
    /// Component-wise sum saturating at the type's range (equal to `+` whenever
    /// that does not overflow).
    #[inline]
    pub(crate) fn sat_add(self, o: Self) -> Self {
        Vec3::new(
            self.x.sat_add(o.x),
            self.y.sat_add(o.y),
            self.z.sat_add(o.z),
        )
    }
    /// The components as `f64`.
    pub fn to_f64(self) -> [f64; 3] {
        [self.x.to_f64(), self.y.to_f64(), self.z.to_f64()]
    }
}

impl<S: Scalar> Add for Vec3<S> {
    type Output = Self;
    #[inline]
    fn add(self, o: Self) -> Self {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}
impl<S: Scalar> Sub for Vec3<S> {
    type Output = Self;
    #[inline]
    fn sub(self, o: Self) -> Self {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}
impl<S: Scalar> Neg for Vec3<S> {
    type Output = Self;
    #[inline]
    fn neg(self) -> Self {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}
impl<S: Scalar> AddAssign for Vec3<S> {
    #[inline]
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}
impl<S: Scalar> SubAssign for Vec3<S> {
    #[inline]
    fn sub_assign(&mut self, o: Self) {
        *self = *self - o;
    }
}
