//! Event stepping ([`Stepping::Events`](super::Stepping::Events)): the step follows the physics, not the clock.
//!
//! The integrator is exact for the piecewise-constant pull a tilt sensor delivers,
//! so nothing is gained by cutting a frame into fixed substeps except the step
//! bound against tunnelling — and that bound caps the speed. Here each marble
//! instead flies the closed form ([`Segment`]) to its next **event**, handles it,
//! and flies on, as many times as the physics asks, in time order:
//!
//! 1. **The reach test** ([`sweep`](super::super::geometry::sweep)): the box the
//!    centre sweeps until the end of the step, widened by the radius, against the
//!    grid (eq. 7). No root, no division. A tile behind a face the marble is held
//!    on cannot be touched (the centre stays a radius in front of the face) and is
//!    left out. In a maze nearly every frame finds nothing, and the frame is one
//!    closed-form update — the same sums as one fixed step.
//! 2. Otherwise **the earliest event**: for every tile in reach, the time of
//!    impact ([`toi`](crate::physics::dynamics::toi): exact for faces, converging separating planes for edges and
//!    corners; the ghost-bump rule of eq. 8's narrowphase decides who owns a
//!    contact on a seam), the lid, the instant a held face's tile runs out under the
//!    contact point, the instant rolling resistance stops the marble.
//! 3. **Fly there and handle it**: a touch is eq. 1 at that instant, with the
//!    normal speed at impact taken from the energy along the normal (so rounding
//!    cannot add energy); slower than the restitution threshold it is a contact,
//!    and a face the pull presses the marble against is then *held* (the pull's
//!    normal part dropped) until its support ends. A marble between two close walls
//!    bounces from one to the other in time order and never sinks into either.
//!
//! **Effects whose acceleration is not piecewise constant** get an interval of
//! their own: rolling resistance opposes the velocity, which the pull turns, so its
//! direction is held for at most 1/8 rad of turning, at the interval's midpoint
//! (`Drag::flight`); the board's fictitious forces depend on position and velocity
//! and are held while the board turns by 1/64 rad (`BoardMotion::flight_len`). Both
//! give one interval per frame when the velocity does not turn and the board is
//! still.
//!
//! **Slices.** What is not a parabola between events — a marble rolling slowly
//! around a convex edge under a pull, or starting inside a tile — is flown in
//! *slices*: `2^-j` of the step (`j ≥ 3`: 1024 per second or finer, short enough
//! that the pull sinks it at most `2^-12·r` into that one tile), with the events of
//! every other tile found as always, and the fixed step's contact passes (the
//! push-out of `respond`) at the slice's end. Two marbles pressed together go on
//! the same way, pushed apart by the fixed step's pair code. A marble rolling
//! round an edge that holds it is flown in pivot slices (`events/pivot.rs`) instead: the pull's
//! part into the edge dropped, the centre put back on the sphere about the edge
//! at each end, so the slice is bounded by the turn and not by the sink — about
//! 8 a frame where plain slices took 32.
//!
//! **Bounded work.** A marble gets at most [`MAX_EVENTS`] events per step. Bounces
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
//! **The speed limit** is the number format's: velocities saturate at 128 pitch/s per
//! axis (I8F24's range; 1.54 m/s at a 12 mm pitch), and a pull is limited to what a
//! step can add within that range (`Params::mg_max`: 8 g down to a 9.8 mm pitch at
//! 128 steps/s). A saturated velocity loses energy; it never overflows and never
//! tunnels.

use super::super::dynamics::integrate::Kick;
use super::super::dynamics::respond::T_LOG2;
use super::super::dynamics::toi::{entry, impact_speed, toi_box, Segment, Toi};
use super::super::geometry::broadphase::TileRange;
use super::super::geometry::narrowphase::{offset, owned, shadowed, Contact, Feature};
use super::super::geometry::sweep::{reach, swept};
use super::super::geometry::tiles::{Aabb, TileIndex};
use super::{marble_pair, Marble, Scalar, Solver, Vec3, World};

mod pivot;

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
    /// Marble `marble` flew `seg` from `from` to `to` (fractions of the step;
    /// `seg` starts at `from`).
    fn flight(&mut self, marble: usize, from: S, to: S, seg: &Segment<S>);
}

impl<S> StepObserver<S> for () {
    #[inline(always)]
    fn flight(&mut self, _: usize, _: S, _: S, _: &Segment<S>) {}
}

/// What ends a flight.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Event<S> {
    /// The flight's interval ends (the step's, or an effect's interval).
    End,
    /// A slice ends: the fixed step's contact passes push the marble out.
    SliceEnd,
    /// Touching tile `.1` (or the lid, [`LID`]).
    Touch(Contact<S>, TileIndex),
    /// Inside tile `.0` (it started there, or another marble pushed it there).
    Inside(TileIndex),
    /// Held face `bit` runs out of tile under the contact point.
    Release(u8),
    /// Rolling resistance brings the speed along its direction to zero.
    Stop,
    /// A search stopped short of a contact: search again from here.
    Later,
}

/// The lid, where a tile index is asked for.
const LID: TileIndex = TileIndex::new(i32::MIN, 0, 0);
/// No tile: a blind slice (every tile left to the passes at its end).
const EVERY: TileIndex = TileIndex::new(i32::MAX, 0, 0);

/// A slice under way (see the module doc).
#[derive(Clone, Copy, Debug)]
struct Slice<S> {
    /// The tile its events leave out: the one the marble rolls around or is in.
    skip: TileIndex,
    /// Where it started (the passes undo a step back to there, as fixed steps do).
    start: Vec3<S>,
    /// When it started and ends (fractions of the step).
    from: S,
    to: S,
    /// A pivot slice (`pivot.rs`): `skip` is an edge the marble rolls around.
    pivot: bool,
}

/// How a slice asked for around a tile begins.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Around {
    /// A plain slice.
    Slice,
    /// A slow touch on an edge: a pivot slice if the edge holds the marble, else
    /// a plain slice.
    Touched,
    /// A pivot slice ended: another while the edge holds, else free flight.
    Rolling,
}

/// One marble's way through the step.
#[derive(Clone, Copy, Debug)]
struct Flight<S> {
    /// How far into the step (steps, `0 ..= 1`).
    t: S,
    /// The closed form from `t` on.
    seg: Segment<S>,
    /// How long its acceleration holds (steps from `t`, at most `1 − t`).
    len: S,
    /// When rolling resistance stops it (steps from `t`).
    stop: Option<S>,
    /// Whether the pull alone cannot beat static friction.
    holds: bool,
    /// Rolling resistance's direction (x', z').
    dir: (S, S),
    /// Events so far in this step.
    events: u32,
    /// Out of events at full restitution: impacts are inelastic.
    inelastic: bool,
    /// Events in a row with no time passing.
    idle: u32,
    /// A slice asked for (around this tile), started at the next flight.
    want: Option<TileIndex>,
    /// How the slice asked for begins.
    around: Around,
    /// The slice under way.
    slice: Option<Slice<S>>,
}

impl<S: Scalar> Flight<S> {
    fn start() -> Self {
        Flight {
            t: S::ZERO,
            seg: Segment::still(Vec3::ZERO),
            len: S::ONE,
            stop: None,
            holds: false,
            dir: (S::ZERO, S::ZERO),
            events: 0,
            inelastic: false,
            idle: 0,
            want: None,
            around: Around::Slice,
            slice: None,
        }
    }

    /// The step's time after `s` more steps (exactly 1 at the end).
    #[inline]
    fn after(&self, s: S) -> S {
        if s == S::ONE - self.t {
            S::ONE
        } else {
            self.t + s
        }
    }
}

/// Whether the box `b` lies behind a face the marble is held on (then it cannot be
/// touched: the centre stays a radius in front of that face).
#[inline]
fn behind_held<S: Scalar>(m: &Marble<S>, b: &Aabb<S>) -> bool {
    let mut bits = m.rest_mask;
    while bits != 0 {
        let bit = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        let (axis, up) = (bit / 2, bit % 2 == 1);
        let plane = m.rest_plane[axis];
        if (up && b.max.axis(axis) <= plane) || (!up && b.min.axis(axis) >= plane) {
            return true;
        }
    }
    false
}

/// The event step's speed limit, the number format's range: `|v| ≤ 127 pitch/s`
/// (I8F24 holds ±128, and a velocity's component along any direction must fit, not
/// only its axes). Faster is scaled back along its own direction (energy is lost,
/// nothing overflows).
#[inline(always)]
pub(crate) fn cap_speed<S: Scalar>(v: Vec3<S>) -> Vec3<S> {
    // Under 127/√3 on every axis: under 127 whatever the direction. Compared
    // without `abs` (I8F24's MIN has none), so that this test, the one almost
    // every flight takes, stays inline where the rest is not.
    let quick = S::from_int(73);
    if v.x < quick && v.x > -quick && v.y < quick && v.y > -quick && v.z < quick && v.z > -quick {
        return v;
    }
    cap_speed_far(v)
}

/// [`cap_speed`] past the quick test.
fn cap_speed_far<S: Scalar>(v: Vec3<S>) -> Vec3<S> {
    // A saturated axis (I8F24's MIN) first back to −MAX, whose magnitude exists.
    let v = v.clamp_abs(S::from_int(128));
    // In pitch/T (1/32 s): components ≤ 4, squares ≤ 48.
    let top = S::from_int(127).shr(T_LOG2);
    let s2 = v.shr(T_LOG2).length_sq();
    if s2 <= top.times(top) {
        return v;
    }
    v.scale(top.times(s2.rsqrt_fine()))
}

/// `v`, scaled down if need be so that it is no faster than `than` (compared in
/// pitch/T, squares in range): `|v|·(1 − x)` with `x` the relative excess of the
/// squares is at most `|than|`.
#[inline]
fn no_faster<S: Scalar>(v: Vec3<S>, than: Vec3<S>) -> Vec3<S> {
    let (a, b) = (v.shr(T_LOG2).length_sq(), than.shr(T_LOG2).length_sq());
    if a <= b {
        return v;
    }
    let keep = S::ONE - (a - b).div(a);
    v.scale(keep.max(S::ZERO))
}

fn max_abs<S: Scalar>(v: Vec3<S>) -> S {
    v.x.abs().max(v.y.abs()).max(v.z.abs())
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
        let fx = self.params.spec.effects;
        let together = fx.marbles && self.marbles.len() > 1;
        match (fx.holes, together) {
            (true, false) => self.fly_each::<true, O>(obs),
            (false, false) => self.fly_each::<false, O>(obs),
            (true, true) => self.fly_together::<true, O>(obs),
            (false, true) => self.fly_together::<false, O>(obs),
        }
    }

    /// The touching tolerance: a ten-thousandth of the radius or four LSB.
    #[inline]
    fn tol(&self) -> S {
        let lsb = S::ZERO - S::ZERO.next_down();
        self.params.radius.shr(14).max(lsb + lsb + lsb + lsb)
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
    fn fly_each<const SPACE: bool, O: StepObserver<S>>(&mut self, obs: &mut O) {
        for n in 0..self.marbles.len() {
            let mut m = self.marbles[n];
            if m.out || m.asleep {
                continue;
            }
            self.count_runs::<SPACE>(&m);
            let mut f = Flight::start();
            self.fly_out::<SPACE, O>(n, &mut m, &mut f, obs);
            self.finish::<SPACE>(n, &mut m);
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
            flights += 1;
            if flights > MAX_FLIGHTS {
                self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
                return;
            }
            let (s, ev) = self.next::<SPACE>(m, f);
            self.land::<SPACE, O>(n, m, f, s, ev, obs);
        }
    }

    /// The end of a marble's step: out of play, asleep (as the fixed step decides).
    fn finish<const SPACE: bool>(&mut self, n: usize, m: &mut Marble<S>) {
        if !SPACE {
            m.supported = true;
        }
        self.check_out::<SPACE>(m);
        m.asleep = self.sleeping && *m == self.marbles[n] && !self.params.spec.effects.board_motion;
        self.marbles[n] = *m;
    }

    /// The marble's next flight and the event that ends it (steps from `f.t`):
    /// the flight's acceleration, a slice begun if one was asked for, the search.
    fn next<const SPACE: bool>(&mut self, m: &mut Marble<S>, f: &mut Flight<S>) -> (S, Event<S>) {
        self.prepare::<SPACE>(m, f);
        if f.events >= 2 * MAX_EVENTS && f.slice.is_none() {
            // Past every bound: blind slices to the end of the step.
            f.want = Some(EVERY);
        }
        if let Some(skip) = f.want.take() {
            let around = core::mem::replace(&mut f.around, Around::Slice);
            let pivot = around != Around::Slice && skip != EVERY && self.pivot_hold(m, f, skip);
            if pivot || around != Around::Rolling {
                let len = if pivot {
                    self.pivot_len(m, f, skip)
                } else {
                    self.slice_len(&f.seg).min(f.len)
                };
                f.slice = Some(Slice {
                    skip,
                    start: m.pos,
                    from: f.t,
                    to: f.after(len),
                    pivot,
                });
                self.stats.slices = self.stats.slices.wrapping_add(1);
            }
        } else if let Some(sl) = f.slice.as_mut().filter(|sl| sl.pivot) {
            // A pivot slice goes on after an event inside it: the edge still holds
            // the marble, or the rest is a plain slice.
            let skip = sl.skip;
            if !self.pivot_hold(m, f, skip) {
                let to = f.after(self.slice_len(&f.seg).min(f.len));
                if let Some(sl) = f.slice.as_mut() {
                    sl.pivot = false;
                    sl.to = sl.to.min(to);
                }
            }
        }
        match f.slice {
            Some(sl) => {
                let limit = (sl.to - f.t).min(f.len);
                let (s, ev) = if sl.skip == EVERY {
                    (limit, Event::End)
                } else {
                    self.search::<SPACE>(m, f, limit, sl.skip, !sl.pivot)
                };
                if ev == Event::End && f.after(s) == sl.to {
                    (s, Event::SliceEnd)
                } else {
                    (s, ev)
                }
            }
            None => self.search::<SPACE>(m, f, f.len, EVERY, false),
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
            _ => self.handle::<SPACE>(m, f, s, ev),
        }
    }

    /// The flight from the marble's state at `f.t`: the pull (rolling when on the
    /// floor), rolling resistance and the board's motion over their intervals, the
    /// held faces' normal parts dropped.
    fn prepare<const SPACE: bool>(&self, m: &mut Marble<S>, f: &mut Flight<S>) {
        let p = &self.params;
        let (k, fx) = (p.k, p.spec.effects);
        let rem = S::ONE - f.t;
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
        let mut len = rem;
        f.stop = None;
        f.holds = false;
        if fx.board_motion {
            let mut extra = self.motion.kick(m.pos, m.vel.shr(k), k);
            extra.dv = extra.dv.clamp_abs(p.v_max.half());
            if !SPACE {
                extra.dv.y = S::ZERO;
                extra.dp.y = S::ZERO;
            }
            kick = Kick {
                dv: Vec3::new(
                    kick.dv.x.sat_add(extra.dv.x),
                    kick.dv.y.sat_add(extra.dv.y),
                    kick.dv.z.sat_add(extra.dv.z),
                ),
                dp: kick.dp + extra.dp.clamp_abs(S::ONE.half()),
            };
            len = len.min(self.motion.flight_len(rem));
        }
        if m.rest_mask != 0 && self.hold::<SPACE>(m, &mut kick) {
            m.supported = true;
        }
        if fx.friction && supported {
            // On what the held faces leave of the pull: a marble pressed into a wall
            // and not along it is held by static friction.
            let d = self.drag.flight(m.vel, &mut kick, len);
            len = d.len;
            f.stop = d.stop;
            f.holds = d.holds;
            f.dir = d.dir;
            let mut bits = m.rest_mask;
            while bits != 0 {
                let axis = (bits.trailing_zeros() / 2) as usize;
                bits &= bits - 1;
                kick.set_axis(axis, (S::ZERO, S::ZERO));
            }
        }
        f.seg = Segment::new(m.pos, m.vel, kick.dv, kick.dp, k);
        f.len = len;
    }

    /// The earliest event of the flight `f` within `limit` steps, leaving tile
    /// `skip` out (a slice's; [`EVERY`] for none) and, if `rest_out`, every tile
    /// the marble rests against (a plain slice's: its passes take them).
    fn search<const SPACE: bool>(
        &self,
        m: &Marble<S>,
        f: &Flight<S>,
        limit: S,
        skip: TileIndex,
        rest_out: bool,
    ) -> (S, Event<S>) {
        let p = &self.params;
        let (r, layout, tiles) = (p.radius, &p.layout, self.tiles);
        let seg = &f.seg;
        let tol = self.tol();
        let mut best = (limit, Event::End);
        if let Some(s) = f.stop {
            if s < best.0 {
                best = (s, Event::Stop);
            }
        }
        let path = swept(seg.p, seg.pos_at(limit), seg.h, limit);
        // Held faces: the tile behind the contact point must stay there.
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            if let Some((s, done)) = self.support_ends::<SPACE>(m, bit, seg, &path, best.0) {
                if s < best.0 {
                    best = (
                        s,
                        if done {
                            Event::Release(bit)
                        } else {
                            Event::Later
                        },
                    );
                }
            }
        }
        // In a slice, every tile the marble rests against is left out like the
        // slice's own: the passes at the slice's end take the slow contacts, as
        // fixed steps do. Where a marble rolls over an edge that two floor tiles
        // share, the two would otherwise hand the slice back and forth, a
        // zero-length event each, until the step's event budget ran out and
        // blind slices flew the marble 9 µm into the next edge (found by the
        // multi-storey property, a slot beside a hole; one storey has it too).
        // A pivot slice leaves out only its edge: another tile it rests against
        // would be sunk into over the pivot slice's length (two edges under a
        // marble over a slot), so it is found at once and a plain slice takes over.
        let slicing = rest_out && skip != EVERY && skip != LID;
        let skip = if skip == EVERY || skip == LID || self.still_skipped(seg, skip, limit) {
            skip
        } else {
            EVERY
        };
        // Tiles in reach (plain loops: iterator adapters cost more than the test).
        let mut range = reach(layout, &path, r + tol, SPACE);
        self.leave_out_held(m, &mut range);
        let mut k = range.lo.k;
        while k <= range.hi.k {
            let mut j = range.lo.j;
            while j <= range.hi.j {
                let mut i = range.lo.i;
                while i <= range.hi.i {
                    let t = TileIndex::new(i, j, k);
                    if tiles.is_solid(t)
                        && t != skip
                        && !(slicing && self.still_skipped(seg, t, limit))
                    {
                        let b = layout.tile_box(t);
                        // `leave_out_held` left exactly the tiles not behind a held face.
                        debug_assert!(!behind_held(m, &b));
                        match toi_box(seg, r, &b, best.0, tol) {
                            Toi::Hit { at, contact, d } => {
                                if at < best.0 {
                                    // The ghost-bump rule: a touch on a seam
                                    // belongs to the surface of the tiles.
                                    let c = if shadowed(t, d, tiles) {
                                        owned(t, &b, d, r, tiles)
                                    } else {
                                        Some(contact)
                                    };
                                    if let Some(c) = c {
                                        best = (at, Event::Touch(c, t));
                                    }
                                }
                            }
                            Toi::Inside { at } => {
                                if at <= best.0 {
                                    best = (at, Event::Inside(t));
                                }
                            }
                            Toi::Later(at) => {
                                if at < best.0 {
                                    best = (at, Event::Later);
                                }
                            }
                            Toi::Miss => {}
                        }
                    }
                    i += 1;
                }
                j += 1;
            }
            k += 1;
        }
        let lid_y = if SPACE { self.lid() } else { S::ZERO };
        if SPACE && skip != LID && path.max.y + r + tol >= lid_y {
            let lid = Aabb {
                min: Vec3::new(S::from_int(-127), lid_y, S::from_int(-127)),
                max: Vec3::new(S::from_int(127), S::from_int(127), S::from_int(127)),
            };
            if !behind_held(m, &lid) {
                match toi_box(seg, r, &lid, best.0, tol) {
                    Toi::Hit { at, contact, .. } if at < best.0 => {
                        best = (at, Event::Touch(contact, LID));
                    }
                    Toi::Inside { at } if at <= best.0 => best = (at, Event::Inside(LID)),
                    Toi::Later(at) if at < best.0 => best = (at, Event::Later),
                    _ => {}
                }
            }
        }
        best
    }

    /// Narrows `range` by the faces the marble is held on: the rows of tiles
    /// behind a held face cannot be touched, and a marble rolling along a wall
    /// would otherwise look up every tile of that wall in reach, every frame.
    /// Tiles meet at the face's plane (eq. 5), so the rows behind it are those
    /// on the far side of the tile that starts there: exactly the tiles
    /// [`behind_held`] would refuse (eq. 6 and eq. 5 agree on every boundary),
    /// so the search need not ask it per tile (debug builds still check).
    #[inline]
    fn leave_out_held(&self, m: &Marble<S>, range: &mut TileRange) {
        let layout = &self.params.layout;
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as usize;
            bits &= bits - 1;
            let (axis, up) = (bit / 2, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            let (at, starts) = if axis == 1 {
                let at = layout.index_y(plane);
                (at, layout.span_y(at).0)
            } else {
                let at = layout.index_xz(plane);
                (at, layout.span_xz(at).0)
            };
            let (lo, hi) = match axis {
                0 => (&mut range.lo.i, &mut range.hi.i),
                1 => (&mut range.lo.j, &mut range.hi.j),
                _ => (&mut range.lo.k, &mut range.hi.k),
            };
            if up {
                // Held from above: every row before `at` ends at or below the plane.
                *lo = (*lo).max(at);
            } else {
                // Held from below: the rows from the first one starting at or above
                // the plane on.
                let first = if starts >= plane { at } else { at + 1 };
                *hi = (*hi).min(first - 1);
            }
        }
    }

    /// Whether a slice still leaves its own tile `skip` out of the flight `seg`:
    /// only while the marble rests on it, at most two tolerances off and not
    /// closing faster than the restitution threshold. A marble that has left it
    /// (bounced off the wall across a narrow corridor, say) and flies back is
    /// searched against it like against any tile: the passes at the slice's end
    /// are for the slow contact the slice was begun for, and a return at speed
    /// would sink into the tile until then (the narrow-corridor regression, 47 µm
    /// at 1 pitch/s). Nor while it closes fast enough to sink more than `2^-12·r`
    /// into the tile within the slice's `limit` steps: a marble over a slot,
    /// rolling round one edge, closes on the other at up to the threshold, and
    /// over a slice that sank it `1.3·10⁻³ r` in (the storey property).
    fn still_skipped(&self, seg: &Segment<S>, skip: TileIndex, limit: S) -> bool {
        let p = &self.params;
        let (r, tol) = (p.radius, self.tol());
        let d = offset(seg.p, &p.layout.tile_box(skip));
        let near = r + tol + tol;
        if d.x.abs() > near || d.y.abs() > near || d.z.abs() > near {
            return false;
        }
        let d2 = d.length_sq();
        if d2 > near.times(near) {
            return false;
        }
        // Closing at `w = −u·d/|d|` (pitch/step) faster than the threshold, in
        // squares: (u·d)² > w_t²·|d|².
        let ud = seg.u.dot(d);
        let w_t = if p.k >= T_LOG2 {
            p.threshold.shr(p.k - T_LOG2)
        } else {
            p.threshold.shl(T_LOG2 - p.k)
        };
        if ud >= S::ZERO {
            return true;
        }
        // Sinking `w·limit` with `|d| ≈ r` (resting, a tolerance off): `−u·d·limit`
        // against `r²/4096`; |u| < 1 per axis and |d| ≤ 2r keep both in range.
        ud.times(ud) <= w_t.times(w_t).times(d2)
            && (S::ZERO - ud).times(limit) <= r.times(r).shr(12)
    }

    /// When the centre, flying `seg`, first enters a column whose tile behind held
    /// face `bit` is missing: `(time, exact)`, within `limit` steps.
    fn support_ends<const SPACE: bool>(
        &self,
        m: &Marble<S>,
        bit: u8,
        seg: &Segment<S>,
        path: &Aabb<S>,
        limit: S,
    ) -> Option<(S, bool)> {
        let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
        if axis == 1 && !up {
            return None; // the lid is everywhere
        }
        let layout = &self.params.layout;
        let plane = m.rest_plane[axis];
        let behind = if up { plane.next_down() } else { plane };
        let (mut i0, mut i1) = (layout.index_xz(path.min.x), layout.index_xz(path.max.x));
        let (mut k0, mut k1) = (layout.index_xz(path.min.z), layout.index_xz(path.max.z));
        let (mut j0, mut j1) = if SPACE {
            (layout.index_y(path.min.y), layout.index_y(path.max.y))
        } else {
            (1, 1)
        };
        match axis {
            0 => (i0, i1) = (layout.index_xz(behind), layout.index_xz(behind)),
            1 => (j0, j1) = (layout.index_y(behind), layout.index_y(behind)),
            _ => (k0, k1) = (layout.index_xz(behind), layout.index_xz(behind)),
        }
        let axes = [axis != 0, SPACE && axis != 1, axis != 2];
        let mut first: Option<(S, bool)> = None;
        for k in k0..=k1 {
            for j in j0..=j1 {
                for i in i0..=i1 {
                    let t = TileIndex::new(i, j, k);
                    if self.tiles.is_solid(t) {
                        continue;
                    }
                    // Eq. 5's columns are `[lo, hi)`: a centre on `hi` is still in
                    // the next one, which holds the face (eq. 6 says so, and the
                    // hold asks eq. 6). Entering through `hi` at the closed end
                    // released the face on the seam, a touch held it again at
                    // once, and the two took turns until the idle rule flew a
                    // blind slice at 28 pitch/s into the next wall (3.7·10⁻³ r
                    // in: the storey property).
                    let b = layout.tile_box(t);
                    let hi = Vec3::new(
                        b.max.x.next_down(),
                        b.max.y.next_down(),
                        b.max.z.next_down(),
                    );
                    if let Some(e) = entry(seg, b.min, hi, axes, limit) {
                        if first.is_none_or(|f| e.0 < f.0) {
                            first = Some(e);
                        }
                    }
                }
            }
        }
        first
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
        m.pos = f.seg.pos_at(s);
        m.vel = cap_speed(f.seg.vel_at(s));
        f.t = to;
    }

    /// Handles event `ev`, reached after a flight of `s` steps.
    fn handle<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        f: &mut Flight<S>,
        s: S,
        ev: Event<S>,
    ) {
        self.stats.events = self.stats.events.wrapping_add(1);
        f.events += 1;
        if f.events == MAX_EVENTS {
            self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
            f.inelastic = true;
        }
        f.idle = if s == S::ZERO { f.idle + 1 } else { 0 };
        // A slow touch on an edge pivots, unless it is a second contact found
        // inside a pivot slice (two supports: plain slices, passes for both).
        let edge = matches!(ev, Event::Touch(c, _) if c.feature == Feature::Edge)
            && !f.slice.is_some_and(|sl| sl.pivot);
        let slice = match ev {
            Event::Touch(c, t) => self.touch::<SPACE>(m, &f.seg, &c, f.inelastic).then_some(t),
            Event::Inside(t) => Some(t),
            Event::Release(bit) => {
                m.rest_mask &= !(1 << bit);
                if bit == 3 {
                    m.supported = false;
                }
                None
            }
            Event::Stop => {
                self.drag.stopped(&mut m.vel, f.dir, f.holds);
                None
            }
            Event::Later | Event::End | Event::SliceEnd => None,
        };
        // A contact that keeps coming back with no time passing is not a parabola.
        let slice = match (slice, f.idle > IDLE_EVENTS) {
            (None, true) => Some(EVERY),
            (s, _) => s,
        };
        if let Some(t) = slice {
            f.idle = 0;
            if f.slice.is_some() {
                // A slice under way ends here (its passes), the new one begins.
                self.end_slice::<SPACE>(m, f);
                // Ending a pivot slice turns the velocity to the old edge's
                // tangent, which can point back into the contact just made: a
                // marble over a slot, rolling on one edge, touches the other and
                // would fly the new slice into it at the speed the touch took
                // away (CI, the narrow-corridor property: 1.02·10⁻³ r in).
                if let Event::Touch(c, _) = ev {
                    let vn = m.vel.dot(c.normal);
                    if vn < S::ZERO {
                        m.vel -= c.normal.scale(vn);
                    }
                }
            }
            f.want = Some(t);
            f.around = if edge && t != EVERY {
                Around::Touched
            } else {
                Around::Slice
            };
        }
    }

    /// A touch (the marble is at the contact, `seg` the flight that brought it):
    /// eq. 1 at this instant, or a contact. Returns `true` when the marble must go on
    /// in slices (a slow contact with an edge it is pulled against).
    fn touch<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        seg: &Segment<S>,
        c: &Contact<S>,
        inelastic: bool,
    ) -> bool {
        let p = self.params;
        let e = if inelastic { S::ZERO } else { p.restitution };
        let (k, r, n) = (p.k, p.radius, c.normal);
        self.stats.contacts = self.stats.contacts.wrapping_add(1);
        // Half the approach acceleration (pitch/step²).
        let beta = -seg.h.dot(n);
        // The normal speed at impact from the energy along the normal: for a face
        // from the flight's start to the exact contact plane, where the marble is
        // put; for an edge from where it is, put back on the rounded edge.
        let (w, d) = match c.feature {
            Feature::Face(a) => {
                let a = a as usize;
                let up = n.axis(a) > S::ZERO;
                let at = if up { c.plane + r } else { c.plane - r };
                let d0 = if up {
                    seg.p.axis(a) - at
                } else {
                    at - seg.p.axis(a)
                };
                m.pos.set_axis(a, at);
                (-seg.u.dot(n), d0)
            }
            _ => {
                m.pos += n.scale(c.depth);
                (-m.vel.shr(k).dot(n), -c.depth)
            }
        };
        let wc = impact_speed(w, beta, d, k);
        let vn = m.vel.dot(n);
        if wc <= p.threshold.shl(T_LOG2) || e == S::ZERO {
            // A contact: no normal speed left (no bounce, no jitter, no Zeno).
            m.vel -= n.scale(vn);
            if beta <= S::ZERO {
                // Not pulled in: it leaves by itself. Off a slanted normal, what
                // rounding leaves of the normal speed could read as a touch again
                // at once: set it a hair off the edge (outwards, with the pull).
                if c.feature == Feature::Edge {
                    let hair = self.tol();
                    m.pos += n.scale(hair + hair);
                }
                return false;
            }
            if let Feature::Face(a) = c.feature {
                let a = a as usize;
                let up = n.axis(a) > S::ZERO;
                if self.behind_solid::<SPACE>(m.pos, a, up, c.plane) {
                    m.rest_mask |= 1 << (2 * a + up as usize);
                    m.rest_plane[a] = c.plane;
                    if SPACE && a == 1 && up {
                        m.supported = true;
                    }
                    return false;
                }
            }
            return true;
        }
        // A bounce. The impact speed is the energy's, and never more than the
        // flight's own.
        let wc = wc.min((-vn).max(S::ZERO));
        let v_c = m.vel - n.scale(vn + wc);
        // Eq. 1, `v' = v − (1 + e)((v − v_b)·n)n`, with its `(1 + e)` split so that
        // no intermediate leaves the format's range at top speed.
        let out = if p.spec.effects.board_motion {
            // Against the board's surface velocity, in pitch/T (1/32 s) where their
            // sum fits.
            let v_b = self
                .motion
                .surface_velocity(m.pos - n.scale(r))
                .shl(k - T_LOG2)
                .clamp_abs(p.v_max.shr(T_LOG2 + 1));
            let vt = v_c.shr(T_LOG2);
            let vn_rel = (vt - v_b).dot(n);
            (vt - n.scale(vn_rel) - n.scale(e.times(vn_rel))).shl(T_LOG2)
        } else {
            // v_c's normal part is −w_c: v' = (v_c + w_c·n) + e·w_c·n.
            m.vel - n.scale(vn) + n.scale(e.times(wc))
        };
        // A still board takes no energy in and gives none: a slanted normal's
        // rounding (or an approximate root's) must not either.
        m.vel = if p.spec.effects.board_motion {
            cap_speed(out)
        } else {
            no_faster(cap_speed(out), v_c)
        };
        self.stats.collisions = self.stats.collisions.wrapping_add(1);
        self.impacts.record(wc);
        if SPACE && n.y > S::ONE.half() {
            m.supported = false;
        }
        false
    }

    /// A slice's length: `2^-j` of the step, `j ≥ 3` (1/1024 s at 128 steps/s), short
    /// enough that each axis moves at most `r/4` (the fixed step's bound against
    /// tunnelling) and the pull sinks the marble at most `2^-12·r` into what it
    /// rolls around before the passes push it out (inside the `10⁻³·r` clearance the
    /// tests hold everything to).
    fn slice_len(&self, seg: &Segment<S>) -> S {
        let r = self.params.radius;
        let (um, hm) = (max_abs(seg.u), max_abs(seg.h));
        let mut len = S::ONE.shr(3);
        let mut j = 3;
        while j < 10 && (um.times(len) > r.shr(2) || hm.times(len.times(len)) > r.shr(12)) {
            len = len.half();
            j += 1;
        }
        len
    }

    /// The end of a slice: the fixed step's contact passes, over the slice, from
    /// where it started.
    fn end_slice<const SPACE: bool>(&mut self, m: &mut Marble<S>, f: &mut Flight<S>) {
        let Some(sl) = f.slice.take() else {
            return;
        };
        if sl.pivot {
            self.onto_pivot(m, sl.skip);
        }
        let k = self.params.k;
        let solver = Solver {
            acc: self.solver(f.seg.dv, k).acc,
            dt: (f.t - sl.from).shr(k - T_LOG2),
        };
        let floor = m.rest_mask & (1 << 3) != 0;
        let supported = self.contact_passes::<SPACE>(m, &solver, sl.start);
        m.vel = cap_speed(m.vel);
        if SPACE {
            m.supported = supported || floor;
        }
        if sl.pivot {
            // On round the edge while it holds (asked at the next flight).
            f.want = Some(sl.skip);
            f.around = Around::Rolling;
        }
    }

    /// Several marbles that touch each other: one timeline for all, every event —
    /// a marble's own or a pair's — in time order.
    fn fly_together<const SPACE: bool, O: StepObserver<S>>(&mut self, obs: &mut O) {
        self.stats.pair_runs = self.stats.pair_runs.wrapping_add(1);
        let count = self.marbles.len();
        let before = self.marbles.clone();
        let mut fl = [Flight::start(); M];
        let mut plan: [Option<(S, Event<S>)>; M] = [None; M];
        let mut live = [false; M];
        for (n, alive) in live.iter_mut().enumerate().take(count) {
            let m = self.marbles[n];
            *alive = !m.out;
            if *alive && !m.asleep {
                self.count_runs::<SPACE>(&m);
            }
        }
        let (p, tol) = (self.params, self.tol());
        let r2 = p.radius + p.radius;
        let point = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ZERO,
        };
        let mut now = S::ZERO;
        let mut rounds = 0u32;
        loop {
            rounds += 1;
            if rounds > 2 * MAX_EVENTS * (count as u32 + 1) {
                // Out of events: every marble finishes its step on its own, then the
                // fixed step's pair code.
                for n in 0..count {
                    let mut m = self.marbles[n];
                    if !live[n] || m.asleep {
                        continue;
                    }
                    self.stats.event_limits = self.stats.event_limits.wrapping_add(1);
                    fl[n].events = fl[n].events.max(2 * MAX_EVENTS);
                    self.fly_out::<SPACE, O>(n, &mut m, &mut fl[n], obs);
                    self.marbles[n] = m;
                }
                self.collide_marbles::<SPACE>();
                break;
            }
            // Each moving marble's next event of its own.
            for n in 0..count {
                if !live[n] || plan[n].is_some() {
                    continue;
                }
                let mut m = self.marbles[n];
                if m.asleep || fl[n].t >= S::ONE {
                    fl[n].t = if m.asleep { now } else { fl[n].t };
                    fl[n].seg = Segment::still(m.pos);
                    plan[n] = Some((S::ONE, Event::End));
                    continue;
                }
                let (s, ev) = self.next::<SPACE>(&mut m, &mut fl[n]);
                self.marbles[n] = m;
                plan[n] = Some((fl[n].after(s), ev));
            }
            let mut first: Option<(S, usize)> = None;
            for (n, pl) in plan.iter().enumerate().take(count) {
                if let (true, Some((t, _))) = (live[n], pl) {
                    if first.is_none_or(|(b, _)| *t < b) {
                        first = Some((*t, n));
                    }
                }
            }
            let Some((mut when, mut who)) = first else {
                break;
            };
            // Pairs, in their relative motion: each a sphere of radius 2r.
            let mut pair: Option<(usize, usize, Option<Contact<S>>)> = None;
            for a in 0..count {
                for b in a + 1..count {
                    // Two marbles asleep against each other stay so: they fell
                    // asleep because a whole step under this same pull changed
                    // neither, and the step is deterministic. Waking them for their
                    // own contact cost a stacked pair 47 events and 35 slices a
                    // frame, every frame (the drop-onto-marble stress scene:
                    // 370 k instructions a frame at rest).
                    if !live[a] || !live[b] || (self.marbles[a].asleep && self.marbles[b].asleep) {
                        continue;
                    }
                    // Both at the later of their own times (a marble a slice
                    // ahead of the others is checked from where it is).
                    let t0 = now.max(fl[a].t).max(fl[b].t);
                    if t0 >= when {
                        continue;
                    }
                    let at = |n: usize| {
                        let g = &fl[n].seg;
                        let s = t0 - fl[n].t;
                        (g.pos_at(s), g.u_at(s), g.h)
                    };
                    let ((pa, ua, ha), (pb, ub, hb)) = (at(a), at(b));
                    let rel = Segment {
                        p: pb - pa,
                        v: Vec3::ZERO,
                        u: ub - ua,
                        dv: Vec3::ZERO,
                        h: hb - ha,
                    };
                    let horizon = when - t0;
                    // Out of reach over the horizon: no touch, and no square of a
                    // far separation (I8F24's |d|² leaves its range past 11.3
                    // pitch; wrapped, a pair 16 pitches apart read as touching).
                    // Within reach every axis is under 2r + tol plus a step's
                    // relative travel (2 pitch at 127 pitch/s): squares under 48.
                    let path = swept(rel.p, rel.pos_at(horizon), rel.h, horizon);
                    let near = r2 + tol;
                    if path.min.x > near
                        || path.max.x < -near
                        || path.min.y > near
                        || path.max.y < -near
                        || path.min.z > near
                        || path.max.z < -near
                    {
                        continue;
                    }
                    match toi_box(&rel, r2, &point, horizon, tol) {
                        Toi::Hit { at, contact, .. }
                            if t0 + at < when || (at == S::ZERO && t0 <= when) =>
                        {
                            when = t0 + at;
                            pair = Some((a, b, Some(contact)));
                        }
                        Toi::Inside { at } if t0 + at <= when => {
                            when = t0 + at;
                            pair = Some((a, b, None));
                        }
                        Toi::Later(at) if t0 + at < when => {
                            // Re-check the pair from there: an event of marble a.
                            when = t0 + at;
                            who = a;
                            pair = None;
                        }
                        _ => {}
                    }
                }
            }
            if pair.is_none() && when >= S::ONE && plan[who].is_some_and(|(_, e)| e == Event::End) {
                // Nothing before the end of the step: everyone flies there.
                for n in 0..count {
                    if live[n] && fl[n].t < S::ONE && !self.marbles[n].asleep {
                        let mut m = self.marbles[n];
                        let s = S::ONE - fl[n].t;
                        let ev = plan[n].map_or(Event::End, |(_, e)| e);
                        self.land::<SPACE, O>(n, &mut m, &mut fl[n], s, ev, obs);
                        self.marbles[n] = m;
                    }
                }
                if (0..count).all(|n| !live[n] || fl[n].t >= S::ONE || self.marbles[n].asleep) {
                    break;
                }
                for pl in plan.iter_mut() {
                    *pl = None;
                }
                continue;
            }
            match pair {
                Some((a, b, contact)) => {
                    for n in [a, b] {
                        let mut m = self.marbles[n];
                        if m.asleep {
                            m.asleep = false;
                            self.count_runs::<SPACE>(&m);
                            fl[n].t = when;
                        } else if when > fl[n].t {
                            let s = when - fl[n].t;
                            self.fly(n, &mut m, &mut fl[n], s, obs);
                        }
                        self.marbles[n] = m;
                        plan[n] = None;
                    }
                    self.stats.events = self.stats.events.wrapping_add(1);
                    let slow = match contact {
                        Some(c) => self.pair_touch(a, b, &c),
                        None => true,
                    };
                    if slow {
                        self.pair_slice::<SPACE, O>(a, b, &mut fl, obs);
                    }
                }
                None => {
                    let n = who;
                    let (t, ev) = plan[n].unwrap_or((when, Event::Later));
                    let (t, ev) = if when < t {
                        (when, Event::Later)
                    } else {
                        (t, ev)
                    };
                    let mut m = self.marbles[n];
                    let s = (t - fl[n].t).max(S::ZERO);
                    self.land::<SPACE, O>(n, &mut m, &mut fl[n], s, ev, obs);
                    self.marbles[n] = m;
                    plan[n] = None;
                }
            }
            now = now.max(when);
        }
        for n in 0..count {
            if !live[n] {
                continue;
            }
            let mut m = self.marbles[n];
            if !SPACE {
                m.supported = true;
            }
            self.check_out::<SPACE>(&mut m);
            m.asleep = self.sleeping && m == before[n] && !self.params.spec.effects.board_motion;
            self.marbles[n] = m;
        }
    }

    /// Two marbles touching (eq. 1 between them, each taking half, as
    /// `collide_marbles` does). Returns `true` when the contact is slow and the pair
    /// must go on in slices.
    fn pair_touch(&mut self, a: usize, b: usize, c: &Contact<S>) -> bool {
        let p = self.params;
        let n = c.normal;
        let (ma, mb) = (self.marbles[a], self.marbles[b]);
        let (va, vb) = (ma.vel.shr(T_LOG2), mb.vel.shr(T_LOG2));
        let approach = -(vb - va).dot(n);
        let (na, nb, bounce) = marble_pair(va, vb, n, p.restitution, p.threshold);
        if bounce > S::ZERO {
            self.impacts.record(bounce.shl(T_LOG2));
        }
        let set = |m: &mut Marble<S>, v: Vec3<S>| {
            let old = m.vel.dot(n);
            let new = n.scale(v.dot(n).shl(T_LOG2).clamp(-p.v_max, p.v_max));
            // The sum can pass the speed limit (a fast marble struck sideways):
            // saturated, then scaled back to it.
            let t = m.vel - n.scale(old);
            m.vel = cap_speed(Vec3::new(
                t.x.sat_add(new.x),
                t.y.sat_add(new.y),
                t.z.sat_add(new.z),
            ));
            m.asleep = false;
        };
        set(&mut self.marbles[a], na);
        set(&mut self.marbles[b], nb);
        approach <= p.threshold
    }

    /// Two marbles pressed together: both fly one slice, then the fixed step's pair
    /// code pushes them apart and runs their tile passes.
    fn pair_slice<const SPACE: bool, O: StepObserver<S>>(
        &mut self,
        a: usize,
        b: usize,
        fl: &mut [Flight<S>; M],
        obs: &mut O,
    ) {
        let p = self.params;
        let r = p.radius;
        let mut len = S::ONE.shr(3);
        for n in [a, b] {
            let mut m = self.marbles[n];
            self.prepare::<SPACE>(&mut m, &mut fl[n]);
            self.marbles[n] = m;
            let seg = fl[n].seg;
            let (um, hm) = (max_abs(seg.u), max_abs(seg.h));
            let mut j = 3;
            while j < 10 && (um.times(len) > r.shr(3) || hm.times(len.times(len)) > r.shr(12)) {
                len = len.half();
                j += 1;
            }
            len = len.min(fl[n].len);
        }
        for n in [a, b] {
            let mut m = self.marbles[n];
            let f = &mut fl[n];
            let to = f.after(len);
            obs.flight(n, f.t, to, &f.seg);
            let start = m.pos;
            m.pos = f.seg.pos_at(len);
            m.vel = cap_speed(f.seg.vel_at(len));
            f.t = to;
            let solver = Solver {
                acc: self.solver(f.seg.dv, p.k).acc,
                dt: len.shr(p.k - T_LOG2),
            };
            let floor = m.rest_mask & (1 << 3) != 0;
            let supported = self.contact_passes::<SPACE>(&mut m, &solver, start);
            if SPACE {
                m.supported = supported || floor;
            }
            self.marbles[n] = m;
        }
        self.collide_pair::<SPACE>(a, b);
        for n in [a, b] {
            self.marbles[n].vel = cap_speed(self.marbles[n].vel);
        }
        self.stats.slices = self.stats.slices.wrapping_add(1);
    }
}
