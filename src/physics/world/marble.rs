//! One marble's state: what the steppers move, compare for sleep and hash.

use super::Vec3;

/// One marble. Equality compares the physical state (`asleep` is a cache of
/// "nothing will change", not state).
#[derive(Clone, Copy, Debug)]
pub struct Marble<S> {
    /// Centre in the tile frame (pitch).
    pub pos: Vec3<S>,
    /// Velocity (pitch/s).
    pub vel: Vec3<S>,
    /// Touching the floor (rolling) at the end of the last step.
    pub supported: bool,
    /// Fallen through a hole or off the board: no longer simulated.
    pub out: bool,
    /// The last step left this marble exactly as it was and nothing has changed
    /// since (board still, no neighbour touched it, the same pull or, under
    /// event stepping, one its held faces and static friction hold as still:
    /// `events/wake.rs`): every further step would too, so it is skipped —
    /// bit-for-bit the same result, at no cost.
    pub asleep: bool,
    /// Faces the marble rests on (bit `2·axis + up`) and their planes: while the pull
    /// still presses it there, the step holds it on them instead of letting it sink
    /// in and pushing it back — the same motion (a resting contact zeroes the normal
    /// motion either way), at a fraction of the cost.
    pub(super) rest_mask: u8,
    pub(super) rest_plane: [S; 3],
}

impl<S: PartialEq> PartialEq for Marble<S> {
    // Inlined: the sleep test asks it after every step of every awake marble.
    #[inline]
    fn eq(&self, o: &Self) -> bool {
        self.pos == o.pos && self.vel == o.vel && self.supported == o.supported && self.out == o.out
    }
}
