//! The board's own motion, followed from the tilt: each pull the board reports
//! gives the board's frame (eq. 4, turned by the small angle the pull shows),
//! and the change between two frames its angular velocity and acceleration
//! ([`BoardMotion`], what the `board_motion` effect throws the marbles with).
//!
//! A board turned by the small angle θ sees gravity `(−θz, −1, θx)·|g|`, so the
//! angle is read off `g/|g|`; `1/|g|` comes from the division-free inverse root
//! (`rsqrt_bits`: `2^60/|g|` as an integer, `|g|²` read as a number with 40
//! fraction bits), so following the board costs no division on any target.

use super::super::geometry::frame::Frame;
use super::super::scalar::{rsqrt_bits, Scalar};
use super::super::vec::Vec3;
use super::effects::BoardMotion;

/// The board's last frame and angular velocity (per step), from the pulls so
/// far; `None` before the first, which starts the board at rest.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub(crate) struct BoardTrack<S> {
    last: Option<(Frame<S>, Vec3<S>)>,
}

impl<S: Scalar> BoardTrack<S> {
    /// Nothing followed yet: the next pull starts the board at rest.
    pub const fn new() -> Self {
        Self { last: None }
    }

    /// The motion that takes the board from the last pull's frame to the one
    /// `g` (milli-g, board frame) shows, turning about `pivot` (tile frame),
    /// one pull per frame of `2^substeps_log2` steps.
    pub fn follow(&mut self, g: [i32; 3], pivot: Vec3<S>, substeps_log2: u32) -> BoardMotion<S> {
        let frame = tilted_frame(g, pivot);
        let (omega, omega_dot) = match self.last {
            Some((prev, prev_omega)) => {
                // Radians per frame → per step; the change per frame → per step².
                let w = BoardMotion::rotation_between(&prev, &frame).shr(substeps_log2);
                (w, (w - prev_omega).shr(substeps_log2))
            }
            None => (Vec3::ZERO, Vec3::ZERO),
        };
        self.last = Some((frame, omega));
        BoardMotion {
            omega,
            omega_dot,
            pivot,
        }
    }
}

/// The frame of a board that feels the pull `g` (milli-g), turned about
/// `pivot`: the small angle `(g_z, 0, −g_x)/|g|` through [`Frame::rotated`].
pub(crate) fn tilted_frame<S: Scalar>(g: [i32; 3], pivot: Vec3<S>) -> Frame<S> {
    let norm2 = (g[0] as i64).pow(2) + (g[1] as i64).pow(2) + (g[2] as i64).pow(2);
    let inv = rsqrt_bits(norm2.max(1) as u64, 40) as i128;
    let angle = Vec3::new(
        S::from_scaled(g[2] as i128 * inv, 60, false),
        S::ZERO,
        S::from_scaled(-(g[0] as i128) * inv, 60, false),
    );
    Frame::rotated(angle, pivot)
}
