//! Event stepping ([`Stepping::Events`](super::Stepping::Events)): the step follows the physics, not the clock.
//!
//! The integrator is exact for the piecewise-constant pull a tilt sensor delivers,
//! so nothing is gained by cutting a frame into fixed substeps except the step
//! bound against tunnelling — and that bound caps the speed. Here each marble
//! instead flies the closed form ([`Segment`]) to its next **event**, handles it,
//! and flies on, as many times as the physics asks, in time order:
//!
//! 1. **The reach test** (`sweep`): the box the
//!    centre sweeps until the end of the step, widened by the radius, against the
//!    grid (eq. 7). No root, no division. A tile behind a face the marble is held
//!    on cannot be touched (the centre stays a radius in front of the face) and is
//!    left out. In a maze nearly every frame finds nothing, and the frame is one
//!    closed-form update — the same sums as one fixed step. A search that finds
//!    nothing leaves the marble a *free region* (`events/free.rs`): later flights
//!    whose swept box stays inside it skip the test, and a step that is one
//!    such flight is the *quiet frame* (`events/quiet.rs`): the closed form and
//!    a box test, without the event loop.
//! 2. Otherwise **the earliest event** (`events/search.rs`): for every tile in
//!    reach, the time of impact (`toi`: exact for
//!    faces, converging separating planes for edges and corners; the ghost-bump
//!    rule of eq. 8's narrowphase decides who owns a contact on a seam), the lid,
//!    the instant a held face's tile runs out under the contact point, the instant
//!    rolling resistance stops the marble.
//! 3. **Fly there and handle it** (`events/touch.rs`): a touch is eq. 1 at that
//!    instant, with the normal speed at impact taken from the energy along the
//!    normal (so rounding cannot add energy); slower than the restitution threshold
//!    it is a contact, and a face the pull presses the marble against is then
//!    *held* (the pull's normal part dropped) until its support ends. A marble
//!    between two close walls bounces from one to the other in time order and
//!    never sinks into either.
//!
//! **Effects whose acceleration is not piecewise constant** get an interval of
//! their own: rolling resistance opposes the velocity, which the pull turns, so its
//! direction is taken at the interval's midpoint and held while that moves the
//! marble at most 1 µm off the model's path (`Drag::flight`); the board's
//! fictitious forces depend on position and velocity and are held while the board
//! turns by 1/64 rad (`BoardMotion::flight_len`). Both give one interval per frame
//! when the velocity does not turn and the board is still.
//!
//! **Slices.** What is not a parabola between events — a marble rolling slowly
//! around a convex edge under a pull, or starting inside a tile — is flown in
//! *slices*: `2^-j` of the step (`j ≥ 3`: 1024 per second or finer, short enough
//! that the pull sinks it at most `2^-12·r` into that one tile), with the events of
//! every other tile found as always, and the fixed step's contact passes (the
//! push-out of `respond`) at the slice's end. Two marbles pressed together go on
//! the same way, pushed apart by the fixed step's pair code; a marble touching
//! another that stands still rolls on it in slices about its centre, or rests
//! there, and the still one is not woken (`events/rest.rs`). A marble rolling
//! round an edge that holds it is flown in pivot slices (`events/pivot.rs`) instead: the pull's
//! part into the edge dropped, the centre put back on the sphere about the edge
//! at each end, so the slice is bounded by the turn and not by the sink — about
//! 8 a frame where plain slices took 32.
//!
//! **Bounded work.** A step spends at most [`FLIGHT_BUDGET`] units of work, all
//! marbles together, each piece of work weighed by its cost (a search, the tiles
//! it tests, a slice's passes, every pair's test and time of impact, a pair slice); past
//! it the rest of the step is carried over to the next
//! (`events/budget.rs`), so a marble landing on another or four marbles shaken in
//! a box cost a bounded frame. No built-in level gets there. Within the budget a
//! marble gets at most [`MAX_EVENTS`] events per step (reachable only with a
//! larger budget, set by [`World::set_flight_budget`]). Bounces
//! between two walls with `e < 1` lose speed geometrically and end in a contact
//! below the restitution threshold (`e = 0.9` from 1.5 m/s: 41 bounces), so
//! physics with `e < 1` does not get near it. With `e = 1` the count is the cross
//! speed over the gap: 1.5 m/s across a 20 µm gap is 590 bounces in a 1/128 s
//! frame, under the bound; a gap under 12 µm at that speed would pass it. Then the
//! rest of that marble's step treats every impact as inelastic (`e = 0`): it stops
//! buzzing, loses only energy and never sinks; `StepStats::event_limits` counts
//! it. (Past twice the bound, slices finish the step: unreachable once impacts are
//! inelastic, kept so the step always ends.)
//!
//! **The speed limit** (`events/speed.rs`) is the number format's: velocities
//! saturate at 128 pitch/s per axis (I8F24's range; 1.54 m/s at a 12 mm pitch), and
//! a pull is limited to what a step can add within that range (`Params::mg_max`:
//! 8 g down to a 9.8 mm pitch at 128 steps/s). A saturated velocity loses energy;
//! it never overflows and never tunnels.
//!
//! Here the step itself, in the order of the work; what a marble carries from
//! one flight to the next (its `Flight`, the slice under way, the `Event` that
//! ends a flight) is `events/flight.rs`.

use super::super::dynamics::integrate::Kick;
use super::super::dynamics::respond::T_LOG2;
use super::super::dynamics::toi::{along, bend_of, entry, impact_speed, toi_box, Segment, Toi};
use super::super::geometry::broadphase::TileRange;
use super::super::geometry::narrowphase::{offset, owned, shadowed, Contact, Feature};
use super::super::geometry::sweep::{quarter, reach, swept, swept_axis};
use super::super::geometry::tiles::{Aabb, TileIndex};
pub use budget::FLIGHT_BUDGET;
use budget::{SEARCH, SLICE_END, TILE};
pub(super) use free::FreeRegion;

use super::{marble_pair, Marble, Scalar, Solver, Vec3, World};

use flight::{Accel, Around, Event, Flight, Slice, EVERY, LID};
pub(crate) use speed::cap_speed;
use speed::{max_abs, no_faster};
pub(super) use touch::touch_tolerance;

mod along;
mod budget;
mod flight;
mod free;
mod pair_test;
mod pivot;
mod quiet;
mod rest;
mod search;
mod speed;
mod together;
mod touch;
mod wake;

/// Events one marble may have in one step at full restitution (see the module
/// doc): past it the step's impacts are inelastic, and past twice it the rest of
/// the step is flown in slices.
pub const MAX_EVENTS: u32 = 1024;

/// Flights one marble may take in one step before the rest of its step is
/// dropped (a guard that no test reaches: past `2·MAX_EVENTS` events the step is
/// finished in slices of at least `2^-10` of the step).
const MAX_FLIGHTS: u32 = 4 * MAX_EVENTS + 1024;

/// Events in a row at the same instant before the marble is moved on by a slice
/// (a contact that keeps coming back without time passing is not a parabola).
const IDLE_EVENTS: u32 = 4;

/// Watches an event step: every piece of closed-form flight, as it is flown (the
/// simulator samples them for its per-millisecond trace). Flights in time order
/// per marble; a marble's state can jump at a flight's end (a bounce, a slice's
/// push-out), so a sample at that instant belongs to the next flight.
pub trait StepObserver<S> {
    /// Whether it is told anything: a step watched by none may take a
    /// flight's shortcut that builds no [`Segment`] (`events/along.rs`).
    const WATCHES: bool = true;
    /// Marble `marble` flew `seg` from `from` to `to` (fractions of the step;
    /// `seg` starts at `from`).
    fn flight(&mut self, marble: usize, from: S, to: S, seg: &Segment<S>);
}

impl<S> StepObserver<S> for () {
    const WATCHES: bool = false;
    #[inline(always)]
    fn flight(&mut self, _: usize, _: S, _: S, _: &Segment<S>) {}
}

impl<S: Scalar, const M: usize> World<'_, S, M> {
    /// Advances by one step like [`World::step`], telling `obs` about every flight
    /// (event stepping; fixed steps just step).
    pub fn step_observed<O: StepObserver<S>>(&mut self, obs: &mut O) {
        if self.params.events() {
            self.step_events(obs);
        } else {
            self.step();
        }
    }

    /// One event step (see the module doc).
    pub(super) fn step_events<O: StepObserver<S>>(&mut self, obs: &mut O) {
        self.stats.steps = self.stats.steps.wrapping_add(1);
        self.flights_left = self.flight_budget;
        let fx = self.params.spec.effects;
        let together = fx.marbles && self.marbles.len() > 1;
        match (fx.holes, together) {
            (true, false) => self.fly_each::<true, O>(obs),
            (false, false) => self.fly_each::<false, O>(obs),
            (true, true) => self.fly_together::<true, O>(obs),
            (false, true) => self.fly_together::<false, O>(obs),
        }
    }

    /// The touching tolerance ([`touch_tolerance`]).
    #[inline]
    fn tol(&self) -> S {
        self.tol
    }

    /// The restitution threshold in pitch a step: slower than it, a marble's
    /// motion against a surface is a resting contact's.
    #[inline]
    fn threshold_per_step(&self) -> S {
        let p = &self.params;
        if p.k >= T_LOG2 {
            p.threshold.shr(p.k - T_LOG2)
        } else {
            p.threshold.shl(T_LOG2 - p.k)
        }
    }

    /// The effect counters, once per marble-step (as the fixed step counts them).
    fn count_runs<const SPACE: bool>(&mut self, m: &Marble<S>) {
        let fx = self.params.spec.effects;
        let s = &mut self.stats;
        if fx.friction && (!SPACE || m.supported) {
            s.friction_runs = s.friction_runs.wrapping_add(1);
        }
        if fx.board_motion {
            s.board_motion_runs = s.board_motion_runs.wrapping_add(1);
        }
        if SPACE {
            s.space_runs = s.space_runs.wrapping_add(1);
        }
    }

    /// Every marble on its own (one marble, or marbles that do not interact).
    ///
    /// The step's flight budget is shared: each marble may take what is left of
    /// it over the marbles still to fly, so that one marble's hard step cannot
    /// leave the next one none.
    fn fly_each<const SPACE: bool, O: StepObserver<S>>(&mut self, obs: &mut O) {
        // Only a share needs the count: one marble (most often) takes it all.
        let mut to_fly = if self.marbles.len() > 1 {
            self.marbles.iter().filter(|m| !m.out && !m.asleep).count() as u32
        } else {
            1
        };
        let mut left = self.flight_budget;
        for n in 0..self.marbles.len() {
            // Asked in place, in one test: a resting scene's step is mostly this.
            if self.marbles[n].out | self.marbles[n].asleep {
                self.pivots[n] = CarriedEdge::NONE;
                continue;
            }
            let mut m = self.marbles[n];
            self.count_runs::<SPACE>(&m);
            // The last marble to fly (the only one, most often) takes what is
            // left without a division (a library call on the Cortex-M0).
            let share = if to_fly <= 1 {
                left
            } else {
                (left / to_fly).max(1)
            };
            self.flights_left = share;
            // No edge carried over to roll round: the step may be a quiet one.
            let flight = if self.pivots[n] == CarriedEdge::NONE {
                self.quiet::<SPACE, O>(n, &mut m, obs)
            } else {
                Some(Flight::begin())
            };
            let (may_sleep, quiet) = if let Some(mut f) = flight {
                self.go_on_round(n, &mut f);
                self.fly_out::<SPACE, O>(n, &mut m, &mut f, obs);
                self.pivots[n] = ended_round(&f);
                (f.t >= S::ONE || self.cut(&f), false)
            } else {
                (true, true)
            };
            left = left.saturating_sub(share - self.flights_left);
            to_fly = to_fly.saturating_sub(1);
            self.finish::<SPACE>(n, &mut m, may_sleep, quiet);
        }
    }

    /// A flight that begins round the edge marble `n`'s last step ended on.
    #[inline]
    fn go_on_round(&mut self, n: usize, f: &mut Flight<S>) {
        if let Some(t) = self.pivots[n].take() {
            f.want = Some(t);
            f.around = Around::Rolling;
        }
    }

    /// Flies marble `n` to the end of the step, event by event. Past
    /// [`MAX_FLIGHTS`] (unreachable: events are bounded, then slices of a fixed
    /// length end the step) the rest of the step is dropped and counted in
    /// `event_limits`: the marble stays where it is, the device goes on.
    fn fly_out<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        obs: &mut O,
    ) {
        let mut flights = 0u32;
        while f.t < S::ONE {
            if self.out_of_flights() {
                // A slice under way gets its passes here, as at its end.
                self.end_slice::<SPACE>(m, f);
                return;
            }
            flights += 1;
            if flights > MAX_FLIGHTS {
                self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
                return;
            }
            let (s, ev) = self.next::<SPACE>(n, m, f);
            self.land::<SPACE, O>(n, m, f, s, ev, obs);
        }
    }

    /// The end of a marble's step: out of play (not after a `quiet` step in the
    /// plane, which ends in its free region, on the board), asleep (as the fixed
    /// step decides, if it may `sleep`: see `events/budget.rs`).
    fn finish<const SPACE: bool>(&mut self, n: usize, m: &mut Marble<S>, sleep: bool, quiet: bool) {
        m.supported |= !SPACE;
        if SPACE || !quiet {
            self.check_out::<SPACE>(m);
        }
        m.asleep = self.sleeping
            && sleep
            && *m == self.marbles[n]
            && !self.params.spec.effects.board_motion;
        self.marbles[n] = *m;
    }

    /// The marble's next flight and the event that ends it (steps from `f.t`):
    /// the flight's acceleration, a slice begun if one was asked for, the search.
    fn next<const SPACE: bool>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
    ) -> (S, Event<S>) {
        if f.prepared {
            f.prepared = false;
        } else {
            self.spend(1, SEARCH);
            self.prepare::<SPACE>(n, m, f);
        }
        if f.events >= 2 * MAX_EVENTS && f.slice.is_none() {
            // Past every bound: blind slices to the end of the step.
            f.want = Some(EVERY);
        }
        // Most flights ask for no slice, have none under way and roll on no
        // marble: one test for the three.
        if f.want.is_some() || f.roll.is_some() || f.slice.is_some() {
            let mut rolls = false;
            if let Some(lo) = f.roll.take() {
                // At rest on a still marble and an edge or a face (`events/rest.rs`),
                // or on rolling on it; a slice about an edge touched goes first (its
                // pair tests find the still marble again).
                if self.rests_on(m, &self.marbles[lo as usize], f, SPACE) {
                    m.vel = Vec3::ZERO;
                    f.set_seg(Segment::still(m.pos));
                    f.rest = Some(lo);
                    f.want = None;
                    f.slice = None;
                    return (S::ONE - f.t, Event::End);
                }
                rolls = f.want.is_none() && self.roll_slice(m, f, lo);
            }
            if rolls {
                // A roll slice begun (`events/rest.rs`): its flight is set.
            } else if let Some(skip) = f.want.take() {
                let around = core::mem::replace(&mut f.around, Around::Slice);
                let rail = f.rail.take();
                // The edge's nearest point, once for the hold, the rail and the
                // slice's length (neither moves the centre): a reciprocal square
                // root each.
                let asked =
                    skip != EVERY && (around != Around::Slice || (skip != LID && rail.is_some()));
                let point = if asked {
                    self.pivot_point(m.pos, skip)
                } else {
                    None
                };
                let pivot =
                    around != Around::Slice && skip != EVERY && self.pivot_hold(m, f, point);
                let rail = !pivot
                    && skip != EVERY
                    && skip != LID
                    && rail.is_some_and(|first| self.rail_hold(m, f, first, skip, point));
                if pivot || around != Around::Rolling {
                    // A touched edge the marble leaves is left out like a pivot's
                    // (`pivot_len`); an event inside ends that like a rail slice.
                    let long = if pivot || rail || around == Around::Touched {
                        self.pivot_len(f, point, !pivot && !rail)
                    } else {
                        None
                    };
                    let len = long.unwrap_or_else(|| self.slice_len(&f.seg).min(f.len));
                    f.slice = Some(Slice {
                        skip,
                        start: m.pos,
                        from: f.t,
                        to: f.after(len),
                        pivot,
                        rail: !pivot && long.is_some(),
                        on: None,
                    });
                    self.stats.slices = self.stats.slices.wrapping_add(1);
                }
            } else if f.slice.is_some_and(|sl| sl.rail) {
                // An event inside a rail slice (a bounce off a wall at its end, say)
                // leaves the flight its whole pull again: the rest of the slice is a
                // plain one, bounded by the sink (a rail slice of 3/4 step going on
                // after a bounce can sink the marble 3.4 % of r).
                let to = f.after(self.slice_len(&f.seg).min(f.len));
                if let Some(sl) = f.slice.as_mut() {
                    sl.rail = false;
                    sl.to = sl.to.min(to);
                }
            } else if let Some(lo) = f.slice.and_then(|sl| sl.on) {
                // A slice rolling on a sleeping marble goes on after an event inside
                // it while the marble still holds it; else it ends here.
                if !self.roll_hold(m, f, lo) {
                    if let Some(sl) = f.slice.as_mut() {
                        sl.on = None;
                    }
                    self.end_slice::<SPACE>(m, f);
                }
            } else if let Some(sl) = f.slice.as_mut().filter(|sl| sl.pivot) {
                // A pivot slice goes on after an event inside it: the edge still holds
                // the marble, or the rest is a plain slice.
                let skip = sl.skip;
                if !self.pivot_hold(m, f, self.pivot_point(m.pos, skip)) {
                    let to = f.after(self.slice_len(&f.seg).min(f.len));
                    if let Some(sl) = f.slice.as_mut() {
                        sl.pivot = false;
                        sl.to = sl.to.min(to);
                    }
                }
            }
        }
        match f.slice {
            Some(sl) => {
                let limit = (sl.to - f.t).min(f.len);
                let (s, ev) = if sl.skip == EVERY && sl.on.is_none() {
                    (limit, Event::End)
                } else {
                    let rest_out = !sl.pivot && sl.on.is_none();
                    self.search::<SPACE>(n, m, f, limit, sl.skip, rest_out)
                };
                if ev == Event::End && f.after(s) == sl.to {
                    (s, Event::SliceEnd)
                } else {
                    (s, ev)
                }
            }
            None => self.search::<SPACE>(n, m, f, f.len, EVERY, false),
        }
    }

    /// Flies `s` steps and handles the event there.
    #[inline]
    fn land<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        s: S,
        ev: Event<S>,
        obs: &mut O,
    ) {
        self.fly(n, m, f, s, obs);
        match ev {
            Event::End => {}
            Event::SliceEnd => self.end_slice::<SPACE>(m, f),
            _ => self.handle(m, f, s, ev, SPACE),
        }
    }

    /// The flight from the marble's state at `f.t` ([`World::accel`]).
    fn prepare<const SPACE: bool>(&self, n: usize, m: &mut Marble<S>, f: &mut Flight<S>) {
        let a = self.accel::<SPACE>(n, m, S::ONE - f.t);
        f.set_accel(m, &a, self.params.k);
    }

    /// The acceleration of a marble's flight with `rem` steps left: the pull
    /// (rolling when on the floor), rolling resistance and the board's motion
    /// over their intervals, the held faces' normal parts dropped.
    ///
    /// Inlined into both callers (`prepare`, the quiet frame) where flash is
    /// plenty: 40 Cortex-M4 instructions a quiet frame (`cargo xtask bench-m4`,
    /// maze). One copy on the Cortex-M0 (ARMv6-M has no 32-bit atomics): a
    /// second cost the micro:bit v1 3.3 KB of flash and bought its worst frames
    /// nothing.
    #[cfg_attr(
        not(all(target_arch = "arm", not(target_has_atomic = "32"))),
        inline(always)
    )]
    #[cfg_attr(all(target_arch = "arm", not(target_has_atomic = "32")), inline(never))]
    fn accel<const SPACE: bool>(&self, n: usize, m: &mut Marble<S>, rem: S) -> Accel<S> {
        let p = &self.params;
        let (k, fx) = (p.k, p.spec.effects);
        let supported = !SPACE || m.supported;
        let mut kick = if supported {
            self.kick_roll
        } else {
            self.kick_free
        };
        if !SPACE {
            // The plane only: y' is left alone, as `advance_plane` does.
            kick.dv.y = S::ZERO;
            kick.dp.y = S::ZERO;
        }
        let mut a = Accel {
            kick,
            len: rem,
            stop: None,
            holds: false,
            dir: None,
            backed: false,
        };
        if fx.board_motion {
            let mut extra = self.motion.kick(m.pos, m.vel.shr(k), k);
            extra.dv = extra.dv.clamp_abs(p.v_max.half());
            if !SPACE {
                extra.dv.y = S::ZERO;
                extra.dp.y = S::ZERO;
            }
            let kick = a.kick;
            a.kick = Kick {
                dv: Vec3::new(
                    kick.dv.x.sat_add(extra.dv.x),
                    kick.dv.y.sat_add(extra.dv.y),
                    kick.dv.z.sat_add(extra.dv.z),
                ),
                dp: kick.dp + extra.dp.clamp_abs(S::ONE.half()),
            };
            a.len = a.len.min(self.motion.flight_len(rem));
        }
        if m.rest_mask != 0 {
            a.backed = self.free[n].under_held(m, SPACE);
            if self.hold::<SPACE>(m, &mut a.kick, a.backed) {
                m.supported = true;
            }
        }
        if fx.friction && supported {
            // On what the held faces leave of the pull: a marble pressed into a wall
            // and not along it is held by static friction.
            let d = self.drag.flight(m.vel, &mut a.kick, a.len);
            a.len = d.len;
            a.stop = d.stop;
            a.holds = d.holds;
            a.dir = Some(d.dir);
            // The held axes keep no kick: the hold dropped it, and the drag,
            // along a velocity and a pull that are both zero on them, adds none.
            debug_assert!((0..3).all(|axis| m.rest_mask & (0b11 << (2 * axis)) == 0
                || (a.kick.dv.axis(axis) == S::ZERO && a.kick.dp.axis(axis) == S::ZERO)));
        }
        a
    }

    /// Flies `s` steps of the closed form.
    #[inline]
    fn fly<O: StepObserver<S>>(
        &self,
        n: usize,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        s: S,
        obs: &mut O,
    ) {
        if s == S::ZERO {
            return;
        }
        let to = f.after(s);
        obs.flight(n, f.t, to, &f.seg);
        m.pos = match f.end.take() {
            Some((at, end)) if at == s => end,
            _ => f.seg.pos_at(s),
        };
        m.vel = cap_speed(f.seg.vel_at(s));
        f.t = to;
    }
}

/// The edge a flight's step ended on in a pivot slice, to go on round at the
/// next step's start (`World::go_on_round`).
fn ended_round<S: Scalar>(f: &Flight<S>) -> CarriedEdge {
    if f.t >= S::ONE && f.around == Around::Rolling {
        CarriedEdge::new(f.want)
    } else {
        CarriedEdge::NONE
    }
}

/// The tile of the edge a step ended on ([`ended_round`]), kept per marble
/// in the world in 3 bytes: the level's setup keeps several copies of the
/// world on the micro:bit v1's stack, where a `TileIndex` a marble (16 B with
/// its `Option`) cost 396 B of its 12 KiB. An edge is a solid tile's, inside
/// the grid (at most 127 columns, rows and layers:
/// [`MAX_TILES_XZ`](crate::physics::geometry::grid::MAX_TILES_XZ)), so each
/// index fits 7 bits; one that would not is not carried, and the next step
/// finds the edge by its touch.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(in crate::physics::world) struct CarriedEdge([u8; 3]);

impl CarriedEdge {
    pub(in crate::physics::world) const NONE: Self = CarriedEdge([u8::MAX; 3]);

    fn new(tile: Option<TileIndex>) -> Self {
        match tile {
            Some(t) if (t.i | t.j | t.k) as u32 <= 127 => {
                CarriedEdge([t.i as u8, t.j as u8, t.k as u8])
            }
            _ => Self::NONE,
        }
    }

    /// The tile, leaving none.
    fn take(&mut self) -> Option<TileIndex> {
        let [i, j, k] = core::mem::replace(self, Self::NONE).0;
        (i != u8::MAX).then(|| TileIndex::new(i.into(), j.into(), k.into()))
    }
}
