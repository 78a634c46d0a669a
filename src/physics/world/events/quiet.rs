//! The quiet frame: a marble whose whole step is one flight inside its free
//! region (`free.rs`) — nothing in reach, no stop, no slice, no edge carried
//! over. In a maze that is nearly every frame, and the general loop
//! (`fly_out`: a flight, its search, its landing, each asking what else might be
//! under way) is then one closed form and a box test.
//!
//! The same work in the same order as the general loop's first flight, so the
//! same bits (every end-state hash is the same with it or without the free
//! regions: `tests/free_region.rs`): the flight's acceleration (`World::accel`,
//! which `prepare` writes into the loop's flight), the swept box against the
//! region (the served search), the flight to the step's end. A frame that turns
//! out not to be quiet hands the loop its first flight with that acceleration
//! set (`Flight::prepared`), and the loop goes on from there without preparing
//! it again.

use super::super::super::geometry::sweep::swept;
use super::{cap_speed, Flight, Marble, Scalar, Segment, StepObserver, Vec3, World, SEARCH};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Flies marble `n`'s whole step as one flight if its free region serves it
    /// (`None`); else the general loop's flight, its first acceleration
    /// prepared if the budget let one begin.
    #[inline]
    pub(super) fn quiet<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        obs: &mut O,
    ) -> Option<Flight<S>> {
        // Rolling along one wall of a flat world, unwatched: the same frame
        // on that axis alone (`events/along.rs`).
        if !SPACE
            && !O::WATCHES
            && m.rest_mask != 0
            && self.params.spec.effects.friction
            && self.roll_along(n, m)
        {
            return None;
        }
        self.quiet_frame::<SPACE, O>(n, m, obs)
    }

    /// The quiet frame by the general sums, for any marble (`quiet` asks the
    /// one-axis roll first; debug builds compare the two).
    #[inline]
    pub(super) fn quiet_frame<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        obs: &mut O,
    ) -> Option<Flight<S>> {
        if self.out_of_flights() {
            return Some(Flight::begin());
        }
        self.spend(1, SEARCH);
        let a = self.accel::<SPACE>(n, m, S::ONE);
        // The whole step one interval, no stop before its end: the search's
        // answer is then the step's end, if nothing is in reach.
        if a.len == S::ONE && a.stop.is_none_or(|s| s >= S::ONE) {
            // In the plane the marble has no y' speed and its kick no y' part
            // (`accel` drops it): said here, the flight's y' sums fold away.
            debug_assert!(SPACE || m.vel.y == S::ZERO, "a plane marble moving in y'");
            let v = if SPACE {
                m.vel
            } else {
                Vec3::new(m.vel.x, S::ZERO, m.vel.z)
            };
            let seg = Segment::new(m.pos, v, a.kick.dv, a.kick.dp, self.params.k);
            let end = seg.pos_at(S::ONE);
            let path = swept(seg.p, end, seg.h, S::ONE);
            let reach = self.params.radius + self.tol();
            // The region holds the marble's faces: as `under_held` found before
            // the hold, if the hold kept them all; with none held, if it was
            // built with none.
            let region = &self.free[n];
            let held = m.rest_mask;
            let holds = region.built_with(held) && (held == 0 || a.backed);
            if holds && region.contains(&path, reach, SPACE) {
                self.stats.free_served = self.stats.free_served.wrapping_add(1);
                obs.flight(n, S::ZERO, S::ONE, &seg);
                m.pos = end;
                m.vel = cap_speed(seg.vel_at(S::ONE));
                return None;
            }
        }
        let mut f = Flight::begin();
        f.set_accel(m, &a, self.params.k);
        f.prepared = true;
        Some(f)
    }
}
