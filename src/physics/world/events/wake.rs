//! Which sleeping marbles a new tilt wakes.
//!
//! A sleeping marble (`Marble::asleep`) is one its last step left as it was;
//! a new pull wakes it so that the pull may move it. Yet a marble at rest
//! against a wall, pressed into it by a tilt whose part along the wall static
//! friction holds, is not moved by a tilt that wobbles a few milli-g: its step
//! is a still flight (no speed, the held face's normal part and the rolling
//! resistance leave no kick) inside its free region — the quiet frame with
//! nothing to fly, which leaves the marble as it is. In the study's maze a
//! quarter of the frames were that step, each a whole quiet frame's work.
//!
//! So a new pull lets such a marble sleep on when the step it would fly is
//! that one: its speed zero, no edge carried over, the flight's acceleration
//! (`World::accel`, the step's one use of the pull) still over the whole step
//! with every held face kept, and the free region serving the still flight as
//! the quiet frame would. Those are the quiet frame's own tests on the
//! marble's own state, so the step it skips is the step it would have flown.
//! Marbles that interact (`Effects::marbles` with several) are all woken as
//! before: their steps are flown together, pair by pair, not as quiet frames.

use super::super::super::geometry::sweep::swept;
use super::{Aabb, CarriedEdge, Scalar, Segment, Vec3, World};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Wakes the sleeping marbles the world's new pull could move: all of them
    /// under fixed steps and where marbles interact; under events, each but
    /// those whose step would be a still quiet frame.
    #[inline(never)]
    pub(in crate::physics::world) fn wake_moved(&mut self) {
        let fx = self.params.spec.effects;
        let alone = !(fx.marbles && self.marbles.len() > 1);
        let events = self.params.events() && alone;
        for n in 0..self.marbles.len() {
            if !self.marbles[n].asleep {
                continue;
            }
            let still = events
                && if fx.holes {
                    self.sleeps_on::<true>(n)
                } else {
                    self.sleeps_on::<false>(n)
                };
            // Known still under one pull, the marble's step under the next
            // depends on that pull alone.
            self.held_still[n] = still;
            if !still {
                self.marbles[n].asleep = false;
            }
        }
    }

    /// Whether marble `n` sleeps on under the world's new pull: its step would
    /// be a still quiet frame. `space`: the world has holes (3-D).
    #[inline]
    fn sleeps_on<const SPACE: bool>(&self, n: usize) -> bool {
        if self.held_still[n] {
            self.held_by_pull::<SPACE>(n)
        } else {
            self.still_step(n, SPACE)
        }
    }

    /// Whether marble `n`'s step would be a still quiet frame: at rest, no edge
    /// carried over, its free region serving the still flight (built with its
    /// held faces, the centre inside, as `quiet` asks), every held face kept
    /// by `hold` (the centre on it; backed, as the region says), and the pull
    /// held (`held_by_pull`). `accel`'s and `quiet`'s tests for a marble at
    /// rest, on the same sums (debug builds ask `accel` too).
    /// Not generic over `space` (asked once a marble falls asleep, where
    /// `held_by_pull` is asked every tilt sample): one copy, for the
    /// micro:bits' flash.
    #[inline(never)]
    fn still_step(&self, n: usize, space: bool) -> bool {
        let still = self.rests_held(n, space);
        debug_assert_eq!(
            still,
            if space {
                self.still_by_accel::<true>(n)
            } else {
                self.still_by_accel::<false>(n)
            },
            "marble {n}"
        );
        still
    }

    /// [`World::still_step`].
    fn rests_held(&self, n: usize, space: bool) -> bool {
        let m = &self.marbles[n];
        if m.vel != Vec3::ZERO || self.pivots[n] != CarriedEdge::NONE {
            return false;
        }
        let (region, held) = (&self.free[n], m.rest_mask);
        if !region.built_with(held) || (held != 0 && !region.under_held(m, space)) {
            return false;
        }
        let r = self.params.radius;
        let mut bits = held;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            let at = if up { plane + r } else { plane - r };
            // Held on the floor, the hold would set `supported`: a change.
            if m.pos.axis(axis) != at || (axis == 1 && up && !m.supported) {
                return false;
            }
        }
        // The still flight's swept box is its centre (`swept` of a flight
        // with no speed, kick or bend is the point, exactly).
        let path = Aabb {
            min: m.pos,
            max: m.pos,
        };
        let held = if space {
            self.held_by_pull::<true>(n)
        } else {
            self.held_by_pull::<false>(n)
        };
        held && region.contains(&path, r + self.tol(), space)
    }

    /// For a marble at rest on its held faces, the hold's other tests passed
    /// (its centre on each face, backed): whether the pull holds it still.
    /// `World::accel`'s pull-dependent tests on the same sums: each held face,
    /// lowest bit first, pressed by what the faces before it left of the pull
    /// (`hold`), nothing left along y', and the rest held by static friction
    /// (`Drag::flight` of a still marble), or none without friction.
    #[inline]
    fn held_by_pull<const SPACE: bool>(&self, n: usize) -> bool {
        let m = &self.marbles[n];
        let fx = self.params.spec.effects;
        if fx.board_motion || (SPACE && !m.supported) {
            return false;
        }
        let mut dv = self.kick_roll.dv;
        if !SPACE {
            dv.y = S::ZERO;
        }
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
            let pull = dv.axis(axis);
            if !(if up { pull < S::ZERO } else { pull > S::ZERO }) {
                return false;
            }
            dv.set_axis(axis, S::ZERO);
        }
        dv.y == S::ZERO
            && if fx.friction {
                self.drag.holds_at_rest(dv.x, dv.z)
            } else {
                dv.x == S::ZERO && dv.z == S::ZERO
            }
    }

    /// [`World::still_step`] by the step's own sums: `accel` from the
    /// marble's state, then `quiet`'s swept box and region test (debug
    /// builds' check of it; release builds drop the call).
    fn still_by_accel<const SPACE: bool>(&self, n: usize) -> bool {
        let mut m = self.marbles[n];
        if m.vel != Vec3::ZERO || self.pivots[n] != CarriedEdge::NONE {
            return false;
        }
        let held = m.rest_mask;
        let a = self.accel::<SPACE>(n, &mut m, S::ONE);
        let still = a.kick.dv == Vec3::ZERO
            && a.kick.dp == Vec3::ZERO
            && a.len == S::ONE
            && a.stop.is_none()
            && m.rest_mask == held
            && m.supported == self.marbles[n].supported;
        let region = &self.free[n];
        if !still || !(region.built_with(held) && (held == 0 || a.backed)) {
            return false;
        }
        let seg = Segment::new(m.pos, m.vel, a.kick.dv, a.kick.dp, self.params.k);
        let path = swept(seg.p, seg.pos_at(S::ONE), seg.h, S::ONE);
        region.contains(&path, self.params.radius + self.tol(), SPACE)
    }
}

#[cfg(test)]
mod tests {
    use super::super::super::super::dynamics::effects::Drag;
    use super::super::super::super::dynamics::integrate::Kick;
    use super::Vec3;

    type S = ::fixed::types::I8F24;

    /// `Drag::holds_at_rest` is what `Drag::flight` decides for a still
    /// marble: it keeps the marble still (no kick, the whole step) exactly
    /// when static friction holds the pull, in the plane and along one axis.
    #[test]
    fn holds_at_rest_is_the_still_flight() {
        let f = S::from_num;
        let pulls = [
            0.0, 1e-6, -1e-6, 2e-4, -2e-4, 0.0011, -0.0011, 0.003, 0.05, -0.9,
        ];
        let mut held = 0;
        for decel in [0.0, 0.001, 0.004] {
            let drag = Drag::<S>::new(f(decel), 7);
            for &ax in &pulls {
                for &az in &pulls {
                    let dv = Vec3::new(f(ax), S::ZERO, f(az));
                    let mut kick = Kick { dv, dp: dv.shr(1) };
                    let d = drag.flight(Vec3::ZERO, &mut kick, S::ONE);
                    let still = kick.dv == Vec3::ZERO
                        && kick.dp == Vec3::ZERO
                        && d.len == S::ONE
                        && d.stop.is_none();
                    let holds = drag.holds_at_rest(dv.x, dv.z);
                    assert_eq!(still, holds, "pull ({ax}, {az}), decel {decel}");
                    held += usize::from(holds);
                }
            }
        }
        // Both answers occur: the zero pull is held even without friction.
        assert!(held > 3 && held < 3 * 100, "{held}");
    }
}
