//! World ↔ tile frame (eq. 4).
//!
//! The tile frame has the orthonormal basis `e'x, e'y, e'z` (columns of `B`, world
//! coordinates) and origin `O'`. A world point `P` has tile coordinates
//! `v'_P = B⁻¹ (v_P − v_O')`, and because `B` is orthonormal `B⁻¹ = Bᵀ`: no inverse
//! is ever computed.

use super::super::scalar::Scalar;
use super::super::vec::Vec3;

/// A rigid frame: origin and orthonormal basis, both in world coordinates.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame<S> {
    /// `v_O'`, the tile frame's origin in world coordinates.
    pub origin: Vec3<S>,
    /// `e'x, e'y, e'z` in world coordinates.
    pub basis: [Vec3<S>; 3],
}

impl<S: Scalar> Frame<S> {
    /// The identity frame (tile frame = world frame).
    pub fn identity() -> Self {
        let (o, l) = (S::ZERO, S::ONE);
        Frame {
            origin: Vec3::ZERO,
            basis: [Vec3::new(l, o, o), Vec3::new(o, l, o), Vec3::new(o, o, l)],
        }
    }

    /// Eq. 4: world point → tile coordinates, `Bᵀ (p − O')`.
    #[inline]
    pub fn to_tile(&self, p: Vec3<S>) -> Vec3<S> {
        self.dir_to_tile(p - self.origin)
    }

    /// Eq. 4 for a direction or velocity (no origin): `Bᵀ v`.
    #[inline]
    pub(crate) fn dir_to_tile(&self, v: Vec3<S>) -> Vec3<S> {
        Vec3::new(
            self.basis[0].dot(v),
            self.basis[1].dot(v),
            self.basis[2].dot(v),
        )
    }

    /// The inverse of eq. 4: tile point → world, `O' + B p'`.
    #[inline]
    pub fn to_world(&self, p: Vec3<S>) -> Vec3<S> {
        self.origin + self.dir_to_world(p)
    }

    /// `B v'` for a direction or velocity.
    #[inline]
    pub(crate) fn dir_to_world(&self, v: Vec3<S>) -> Vec3<S> {
        self.basis[0].scale(v.x) + self.basis[1].scale(v.y) + self.basis[2].scale(v.z)
    }

    /// The board's frame for a board rotated by the small rotation vector `angle`
    /// (radians, world axes) about `pivot` (world): `B = I + [angle]×`, then
    /// re-orthonormalised (Gram–Schmidt) so eq. 4's transpose stays the inverse.
    /// Once per tilt sample; normalising takes two inverse roots and no division.
    pub fn rotated(angle: Vec3<S>, pivot: Vec3<S>) -> Self {
        let i = Frame::<S>::identity();
        let col = |e: Vec3<S>| e + angle.cross(e);
        let x = normalize(col(i.basis[0]));
        let y0 = col(i.basis[1]);
        let y = normalize(y0 - x.scale(x.dot(y0)));
        let z = x.cross(y);
        let basis = [x, y, z];
        // The pivot stays put: O' = pivot − B·pivot.
        let mut f = Frame {
            origin: Vec3::ZERO,
            basis,
        };
        f.origin = pivot - f.dir_to_world(pivot);
        f
    }
}

/// `v / |v|` (zero stays zero), through the inverse root: no division.
pub(crate) fn normalize<S: Scalar>(v: Vec3<S>) -> Vec3<S> {
    let inv = v.length_sq().rsqrt();
    if inv == S::ZERO {
        return v;
    }
    v.scale(inv)
}
