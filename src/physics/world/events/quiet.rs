//! The quiet frame: a marble whose whole step is one flight inside its free
//! region (`free.rs`) — nothing in reach, no stop, no slice, no edge carried
//! over. In a maze that is nearly every frame, and the general loop
//! (`fly_out`: a flight, its search, its landing, each asking what else might be
//! under way) is then one closed form and a box test.
//!
//! The same work in the same order as the general loop's first flight, so the
//! same bits: the flight's acceleration (`prepare`), the swept box against the
//! region (the served search), the flight to the step's end. A frame that turns
//! out not to be quiet hands its prepared flight to the general loop, which goes
//! on from there without preparing it again.

use super::super::super::geometry::sweep::swept;
use super::{cap_speed, Flight, Marble, Scalar, StepObserver, World, SEARCH};

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Flies marble `n`'s whole step as one flight if its free region serves it;
    /// else leaves `f` prepared for the general loop (or untouched if no flight
    /// may begin) and returns false.
    #[inline]
    pub(super) fn quiet<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        obs: &mut O,
    ) -> bool {
        if f.want.is_some() || self.out_of_flights() {
            return false;
        }
        self.spend(1, SEARCH);
        self.prepare::<SPACE>(n, m, f);
        f.prepared = true;
        // The whole step one interval, no stop before its end: the search's
        // answer is then the step's end, if nothing is in reach.
        if f.len != S::ONE || f.stop.is_some_and(|s| s < S::ONE) {
            return false;
        }
        let seg = &f.seg;
        let end = seg.pos_at(S::ONE);
        let path = swept(seg.p, end, seg.h, S::ONE);
        let reach = self.params.radius + self.tol();
        if !self.free[n].serves(m, &path, reach, SPACE) {
            return false;
        }
        self.stats.free_served = self.stats.free_served.wrapping_add(1);
        obs.flight(n, S::ZERO, S::ONE, seg);
        m.pos = end;
        m.vel = cap_speed(seg.vel_at(S::ONE));
        f.t = S::ONE;
        f.prepared = false;
        true
    }
}
