//! The stateful layer: marbles on a board of tiles, and the two steppers that
//! move them. [`World::step`] is the table of contents:
//!
//! | file | what |
//! |------|------|
//! | `spec.rs` | a scene in integers ([`PhysicsSpec`]) and in the scalar ([`Params`]) |
//! | `marble.rs` | one marble's state ([`Marble`]) |
//! | `stats.rs` | what the steps did ([`StepStats`], [`Impacts`]) |
//! | `fixed.rs` | the fixed stepper: a bounded step, then the contact passes |
//! | [`events`] | the event stepper: closed-form flights from event to event |
//! | `contact.rs` | the contact layer both steppers call: passes, held faces, eq. 1 |
//! | `pairs.rs` | marble–marble contacts |
//!
//! Data flows one way each step, per marble: effects shape the kick → integrate →
//! broadphase (eq. 7) → narrowphase (eq. 8) → respond (eq. 1) → out-of-play check;
//! then, only with several marbles, marble–marble contacts.

use heapless::Vec as HVec;

use super::dynamics::effects::{marble_pair, BoardMotion, Drag, Effects};
use super::dynamics::integrate::{advance, advance_plane, Kick, PullScale};
use super::dynamics::respond::{along_normal, normal_part, resolve, Impact, Outcome, T_LOG2};

use super::geometry::broadphase::{candidates, candidates_plane, TileRange};
use super::geometry::grid::Tiles;
use super::geometry::narrowphase::{contact, lid_contact, out_of_reach, Contact, Feature};
use super::geometry::tiles::{LayoutError, TileIndex, TileLayout};
use super::scalar::Scalar;
use super::vec::Vec3;
mod contact;
pub mod events;
mod fixed;
mod marble;
mod pairs;
mod spec;
mod stats;

pub use events::{StepObserver, FLIGHT_BUDGET, MAX_EVENTS};
pub use marble::Marble;
pub use spec::{Params, PhysicsSpec, SetupError, Stepping};
pub use stats::{Impacts, StepStats, IMPACTS_KEPT};

/// The contact solver's view of a step (see [`respond`](super::dynamics::respond)):
/// the pull as `a·T²` (pitch/T²) and the step's length in `T`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solver<S> {
    acc: Vec3<S>,
    dt: S,
}

/// A new world's gravity until `World::new` sets the first one (its kicks not
/// yet computed): no tilt the clamp lets through, so no tilt compares equal to
/// it and the first one computes every axis. A flag beside it was a load and a
/// branch in every step's compare.
const NO_GRAVITY: [i32; 3] = [i32::MIN; 3];

/// A board of tiles with up to `M` marbles on it.
#[derive(Clone, Debug)]
pub struct World<'a, S: Scalar, const M: usize> {
    params: Params<S>,
    tiles: Tiles<'a>,
    marbles: HVec<Marble<S>, M>,
    gravity_mg: [i32; 3],
    kick_roll: Kick<S>,
    /// The pull of a marble off the floor. Only a world with holes reads its x'
    /// and z' (a flat world's marbles never leave the floor), so only there are
    /// they kept up to date.
    kick_free: Kick<S>,
    drag: Drag<S>,
    motion: BoardMotion<S>,
    extent: (S, S),
    sleeping: bool,
    /// Per-milli-g scales: full gravity, the rolling (tangential) share, and the
    /// rolling-resistance deceleration per unit load.
    pulls: [PullScale; 3],
    /// Per marble, the last candidate range found free of solid tiles (the tiles
    /// never change, so it stays free): the next step usually has the same one.
    clear: [TileRange; M],
    /// Per marble, event stepping's free region (`events/free.rs`).
    free: [events::FreeRegion<S>; M],
    /// Per marble, the edge a pivot slice ended the last step on (event
    /// stepping): the next step goes on round it, as a step does after a pivot
    /// slice of its own, without the touch that would find the edge again at
    /// once. Forgotten when the marbles are set from outside.
    pivots: [events::CarriedEdge; M],
    /// Per marble: asleep, and its step found a still quiet frame under the
    /// pull it fell asleep with or a later one (`events/wake.rs`), nothing
    /// changed since; a new pull then need only be held as that one was.
    /// Cleared with the marble's sleep, wherever it is woken from outside.
    held_still: [bool; M],
    /// Whether searches build free regions (tests turn it off to compare).
    free_regions: bool,
    /// A flat world flown by events, rolling (the boards' mazes): a tilt
    /// sample's plane axes are its rolling kicks alone (`pull_axis`). Kept,
    /// not derived from `params` at each sample: one load where three flags'
    /// reads cost the study's maze 11 000 more Cortex-M4 instructions a run.
    flat_events: bool,
    /// Flights a step may take in all ([`events::FLIGHT_BUDGET`] unless set).
    flight_budget: u32,
    /// Flights the step under way may still take.
    flights_left: u32,
    /// The touching tolerance (`events::touch_tolerance` of the radius).
    tol: S,
    /// What the steps did so far.
    pub stats: StepStats,
    /// The bounces since [`World::take_impacts`].
    impacts: Impacts<S>,
}

pub use super::range::MAX_MG;

impl<'a, S: Scalar, const M: usize> World<'a, S, M> {
    /// A world with marbles resting on the floor at `starts` (tile-frame x', z'; the
    /// height is set to the radius: storey 0).
    pub fn new(params: Params<S>, tiles: Tiles<'a>, starts: &[(S, S)]) -> Result<Self, SetupError> {
        if starts.len() > M {
            return Err(SetupError::MarbleCount);
        }
        let mut centres = [Vec3::ZERO; M];
        for (centre, &(x, z)) in centres.iter_mut().zip(starts) {
            *centre = Vec3::new(x, params.radius, z);
        }
        Self::with_centres(params, tiles, &centres[..starts.len()])
    }

    /// A world with marbles at rest with their centres at `centres` (tile frame,
    /// pitch): on a storey's floor, its height is the storey plus the radius.
    pub fn with_centres(
        mut params: Params<S>,
        tiles: Tiles<'a>,
        centres: &[Vec3<S>],
    ) -> Result<Self, SetupError> {
        // A marble can only leave or reach a storey in 3-D.
        params.spec.effects.holes |= tiles.storeys() > 1;
        if centres.is_empty() || centres.len() > M {
            return Err(SetupError::MarbleCount);
        }
        let layout = params.layout;
        let extent = (
            layout.span_xz(tiles.nx() as i32 - 1).1,
            layout.span_xz(tiles.nz() as i32 - 1).1,
        );
        let lid = lid_height(&layout, tiles);
        let mut marbles = HVec::new();
        for (n, &pos) in centres.iter().enumerate() {
            let (x, z) = (pos.x, pos.z);
            let inside = x > S::ZERO
                && z > S::ZERO
                && x < extent.0
                && z < extent.1
                && pos.y > S::ZERO
                && pos.y + params.radius <= lid;
            if !inside || overlaps_any(&layout, tiles, pos, params.radius) {
                return Err(SetupError::BadStart(n));
            }
            let m = Marble {
                pos,
                vel: Vec3::ZERO,
                supported: true,
                out: false,
                asleep: false,
                rest_mask: 0,
                rest_plane: [S::ZERO; 3],
            };
            marbles.push(m).map_err(|_| SetupError::MarbleCount)?;
        }
        let mut w = World {
            params,
            tiles,
            marbles,
            gravity_mg: NO_GRAVITY,
            kick_roll: Kick::default(),
            kick_free: Kick::default(),
            drag: Drag::default(),
            motion: BoardMotion::default(),
            extent,
            sleeping: true,
            pulls: {
                let pitch = params.layout.pitch_um;
                let roll: (i64, i64) = if params.spec.effects.rolling {
                    (5, 7)
                } else {
                    (1, 1)
                };
                let ppm = params.spec.rolling_resistance_ppm as i64;
                [
                    PullScale::new(1, 1, pitch),
                    PullScale::new(roll.0, roll.1, pitch),
                    PullScale::new(ppm * roll.0, 1_000_000 * roll.1, pitch),
                ]
            },
            clear: [TileRange::EMPTY; M],
            free: [events::FreeRegion::EMPTY; M],
            pivots: [events::CarriedEdge::NONE; M],
            held_still: [false; M],
            free_regions: true,
            flat_events: params.events()
                && params.spec.effects.rolling
                && !params.spec.effects.holes,
            flight_budget: events::FLIGHT_BUDGET,
            flights_left: 0,
            tol: events::touch_tolerance(params.radius),
            stats: StepStats::default(),
            impacts: Impacts::default(),
        };
        w.set_gravity_mg([0, -1000, 0]);
        Ok(w)
    }

    /// The parameters.
    pub fn params(&self) -> &Params<S> {
        &self.params
    }
    /// The tiles.
    pub fn tiles(&self) -> Tiles<'a> {
        self.tiles
    }
    /// The marbles.
    pub fn marbles(&self) -> &[Marble<S>] {
        &self.marbles
    }
    /// This world's state put back as it was in `start`, an earlier copy of it
    /// (the sampled trace's replay of a frame: `host::motion_trace`): the
    /// marbles, the edges they roll round from one step to the next, the caches
    /// and the counters; the pull and the board's motion stay this world's. A
    /// pull other than `start`'s wakes the marbles, as setting it did.
    pub fn rewind_to(&mut self, start: &Self) {
        self.marbles.clone_from(&start.marbles);
        self.pivots = start.pivots;
        self.clear = start.clear;
        self.free = start.free;
        self.held_still = start.held_still;
        self.stats = start.stats;
        if self.gravity_mg != start.gravity_mg {
            for m in self.marbles.iter_mut() {
                m.asleep = false;
            }
            self.held_still = [false; M];
        }
    }
    /// Mutable marbles (tests, tools and game rules place them). Wakes them all:
    /// the caller may move one.
    pub fn marbles_mut(&mut self) -> &mut [Marble<S>] {
        for m in self.marbles.iter_mut() {
            m.asleep = false;
        }
        self.held_still = [false; M];
        self.pivots = [events::CarriedEdge::NONE; M];
        &mut self.marbles
    }
    /// The gravity last set (milli-g, tile frame).
    pub fn gravity_mg(&self) -> [i32; 3] {
        self.gravity_mg
    }
    /// The lid's height (pitch): the top of the top storey's walls.
    #[inline]
    pub fn lid(&self) -> S {
        lid_height(&self.params.layout, self.tiles)
    }

    /// The board's extent along x' and z' (pitch).
    pub fn extent(&self) -> (S, S) {
        self.extent
    }

    /// Sets the apparent gravity in the tile frame, in milli-g (a flat board is
    /// `(0, -1000, 0)`: down). Clamped to the level's bound per axis
    /// ([`Params::mg_max`]: [`MAX_MG`], or less with events on a fine pitch):
    /// the one clamp on the tilt path, here because only the world knows its
    /// level's bound, and because tools and tests hand the world gravities
    /// directly. Computes the kicks once, so the steps that follow only add.
    #[inline]
    pub fn set_gravity_mg(&mut self, g: [i32; 3]) {
        // The same tilt again (a resting board, most samples on some axis)
        // costs its compare where it is handed over, without a call. A tilt
        // the clamp would make the same goes through the clamp.
        let old = self.gravity_mg;
        if g[0] == old[0] && g[1] == old[1] && g[2] == old[2] {
            return;
        }
        self.set_gravity_mg_clamped(g);
    }

    /// [`World::set_gravity_mg`] past its quick compare.
    #[inline(never)]
    fn set_gravity_mg_clamped(&mut self, g: [i32; 3]) {
        let lim = self.params.mg_max;
        // max then min, not `clamp`: its `min <= max` assertion would link core::fmt.
        let clamp = |v: i32| v.max(-lim).min(lim);
        // A sample within the bound on every axis (nearly all): each axis one
        // unsigned compare of its offset from −lim (`mg_max` ≥ 0).
        let span = 2 * lim as u32;
        let inside = |v: i32| v.wrapping_add(lim) as u32 <= span;
        let within = inside(g[0]) & inside(g[1]) & inside(g[2]);
        // A sample within the bound differs from the tilt the world has (its
        // one caller compared them); a clamped one may not. None equals a new
        // world's `NO_GRAVITY`, so its first tilt computes every axis.
        let old = self.gravity_mg;
        let g = if within {
            g
        } else {
            let g = [clamp(g[0]), clamp(g[1]), clamp(g[2])];
            if g[0] == old[0] && g[1] == old[1] && g[2] == old[2] {
                return;
            }
            g
        };
        // Axis by axis: each axis of the kicks depends on that axis of the pull
        // alone (the displacement clamp is per axis too), and a tilt sample
        // usually moves one plane axis by a milli-g or two — the others keep
        // their kicks, bit for bit. An unchanged axis costs a compare; a moved
        // one its own copy of `pull_axis`, each with its axis a constant (out of
        // line, one copy cost the study's maze 14 Cortex-M4 instructions a step,
        // and the micro:bit v1's worst difficulty-9 frame 86 M0, for 408 B of its
        // flash). Plain compares, no array of flags, and no `==` on the arrays (a
        // `memcmp` call on the Cortex-M).
        self.gravity_mg = g;
        if g[0] != old[0] {
            self.pull_axis(0, g[0]);
        }
        if g[1] != old[1] {
            self.pull_axis(1, g[1]);
        }
        if g[2] != old[2] {
            self.pull_axis(2, g[2]);
        }
        // A new pull can move a resting marble: `wake_moved` wakes those it
        // can. By index: a slice's loop was unrolled eight times over, for the
        // one marble most worlds hold (25 host instructions a tilt sample).
        let mut asleep = false;
        for n in 0..self.marbles.len() {
            asleep |= self.marbles[n].asleep;
        }
        if asleep {
            self.wake_moved();
        }
    }

    /// The kicks of axis `axis` of a pull of `mg` milli-g (clamped), and for the
    /// normal axis rolling resistance's deceleration.
    #[inline(always)]
    fn pull_axis(&mut self, axis: usize, mg: i32) {
        let k = self.params.k;
        // A plane axis of a flat world flown by events (the boards' mazes):
        // its rolling kick alone, unclamped — `mg_max` keeps `a·dt` within
        // 127 pitch/s at 2^k ≥ 128 steps a second (`Params::new`), so the
        // format holds the kick and |½·a·dt²| < 1 pitch: the clamp below
        // could not bind.
        if axis != 1 && self.flat_events {
            let [_, roll, _] = self.pulls;
            self.kick_roll.set_axis(axis, roll.kick_fits::<S>(mg, k));
            return;
        }
        // Fixed steps bound the kick's displacement (no tunnelling); events need no
        // bound (|½·a·dt²| < 1 pitch by `mg_max`).
        let reach = if self.params.events() {
            S::from_int(64)
        } else {
            self.params.radius.shr(3)
        };
        let [full, roll, resist] = self.pulls;
        // Rolling scales the tangential axes only (x', z'): the normal is full.
        // Its scale is 5/7 of the full one whenever the effect is on (a pitch of
        // at least 1 mm keeps both below the cap): the flag, not the two scales'
        // 64-bit compare (9 of the Cortex-M0's instructions a tilt sample).
        let rolls = axis != 1 && self.params.spec.effects.rolling;
        let rolling = Kick::axis_of(mg, if rolls { roll } else { full }, reach, k);
        self.kick_roll.set_axis(axis, rolling);
        // What a scene does not use costs nothing: a flat world never flies
        // free, and the free kick's plane axes would be two more exact
        // products per tilt sample (a tenth of a maze frame, `cargo accuracy`).
        if !rolls {
            self.kick_free.set_axis(axis, rolling);
        } else if self.params.spec.effects.holes {
            self.kick_free
                .set_axis(axis, Kick::axis_of(mg, full, reach, k));
        }
        // Rolling resistance decelerates by c_rr·g_n (·5/7 when rolling), g_n = −g_y.
        if axis == 1 && self.params.spec.effects.friction {
            self.drag = Drag::new(resist.kick::<S>((-mg).max(0), k).0, k);
        }
    }

    /// The bounces since the last call (see [`Impacts`]), and a fresh count.
    pub fn take_impacts(&mut self) -> Impacts<S> {
        core::mem::take(&mut self.impacts)
    }

    /// Turns event stepping's free regions on (the default) or off. They are a
    /// cache: the tests turn them off to check that they change nothing.
    pub fn set_free_regions(&mut self, on: bool) {
        self.free_regions = on;
        self.free = [events::FreeRegion::EMPTY; M];
        self.held_still = [false; M];
    }

    /// Turns skipping of resting marbles on (the default) or off. Off, every marble
    /// is stepped every time: the tests use it to check that skipping changes nothing.
    pub fn set_sleeping(&mut self, on: bool) {
        self.sleeping = on;
        for m in self.marbles.iter_mut() {
            m.asleep = false;
        }
        self.held_still = [false; M];
    }

    /// Sets the board's rotation (used with the `board_motion` effect).
    pub fn set_board_motion(&mut self, motion: BoardMotion<S>) {
        // At most 16 rad/s and 1024 rad/s² (a hand shaking the toy hard): a sensor
        // glitch must not turn into an absurd spin of the board.
        let k = self.params.k;
        let w_max = S::ONE.shr(k - 4);
        let a_max = S::ONE.shr(2 * k - 10);
        let motion = BoardMotion {
            omega: motion.omega.clamp_abs(w_max),
            omega_dot: motion.omega_dot.clamp_abs(a_max),
            ..motion
        };
        self.motion = motion;
        if motion.omega != Vec3::ZERO || motion.omega_dot != Vec3::ZERO {
            for m in self.marbles.iter_mut() {
                m.asleep = false;
            }
            self.held_still = [false; M];
        }
    }

    /// Advances the world by one step `dt` (fixed, or by events: see [`Stepping`]).
    ///
    /// Both steppers are linked wherever this is called. Firmware, whose mode is
    /// a constant, calls `World::step_in` and links only its own.
    #[inline]
    pub fn step(&mut self) {
        if self.params.events() {
            self.step_in::<true>();
        } else {
            self.step_in::<false>();
        }
    }

    /// One step by the stepper chosen at compile time: events if `EVENTS`, fixed
    /// steps otherwise. The other stepper is not linked (the event stepper is
    /// about 24 KiB of Cortex-M4 code: more than a 64 KiB board can spare).
    ///
    /// `EVENTS` must agree with the world's [`Stepping`] (its `dt` was validated
    /// for that mode); the game's [`Player`](crate::player::Player) sets up
    /// both from one constant.
    #[inline]
    pub(crate) fn step_in<const EVENTS: bool>(&mut self) {
        debug_assert_eq!(EVENTS, self.params.events(), "stepper and spec disagree");
        if EVENTS {
            self.step_events(&mut ());
        } else {
            self.step_fixed();
        }
    }

    fn check_out<const SPACE: bool>(&self, m: &mut Marble<S>) {
        let (ex, ez) = self.extent;
        let p = m.pos;
        // Past the board's edge: the border walls and the lid close every
        // storey, so a centre beyond them went under the board through a hole
        // (a board shaken hard can roll a fallen marble round the border slab's
        // lower edges and out sideways).
        let beyond = p.x < S::ZERO || p.z < S::ZERO || p.x > ex || p.z > ez;
        if SPACE {
            // Through a hole once entirely below the floor slab (top at or below
            // −s): there is nothing down there to hold it, not even under the
            // neighbouring tiles. At exactly −s the slab's underside could hold it
            // up, and a board shaken hard (its surface velocity in eq. 1) would
            // carry a fallen marble along the underside at up to 120 pitch/s.
            let depth = self.params.layout.s + self.params.radius;
            if beyond || p.y <= -depth || p.y > S::from_int(self.tiles.storeys() as i32 + 3) {
                m.out = true;
            }
        } else if beyond {
            m.out = true;
        }
        if m.out {
            m.vel = Vec3::ZERO;
        }
    }

    /// A 64-bit FNV-1a digest of the exact state of every marble: equal on every
    /// run with the same inputs, on every machine, for a given scalar.
    pub fn state_hash(&self) -> u64 {
        let mut h: u64 = 0xcbf2_9ce4_8422_2325;
        let mut eat = |x: u64| {
            for byte in x.to_le_bytes() {
                h ^= byte as u64;
                h = h.wrapping_mul(0x0000_0100_0000_01b3);
            }
        };
        for m in self.marbles.iter() {
            for v in [m.pos.x, m.pos.y, m.pos.z, m.vel.x, m.vel.y, m.vel.z] {
                eat(v.hash_bits());
            }
            eat(m.supported as u64 | (m.out as u64) << 1);
        }
        h
    }
}

/// The lid's height over `tiles` (pitch): the top of the top storey's walls,
/// `storeys − s` (eq. 5).
#[inline]
fn lid_height<S: Scalar>(layout: &TileLayout<S>, tiles: Tiles<'_>) -> S {
    S::from_int(tiles.storeys() as i32) - layout.s
}

/// Whether a marble at `c` overlaps any solid tile (start validation, tests).
/// A floor slab below the centre does not count: a marble resting on it may
/// overlap it by a rounding (`n + r − r` in floating point on storey `n`).
pub(crate) fn overlaps_any<S: Scalar>(
    layout: &TileLayout<S>,
    tiles: Tiles<'_>,
    c: Vec3<S>,
    r: S,
) -> bool {
    candidates(layout, c, r)
        .solid(tiles)
        // Slab `j = 2n` (eq. 5) tops out at `y' = n`.
        .filter(|t: &TileIndex| t.j & 1 == 1 || S::from_int(t.j >> 1) > c.y)
        .any(|t| super::geometry::narrowphase::overlaps(c, r, &layout.tile_box(t)))
}

#[cfg(test)]
mod tests {
    use super::{Kick, Params, PhysicsSpec, PullScale, Scalar, Stepping};
    use ::fixed::types::{I16F16, I32F32, I8F24};

    /// Event stepping's kicks need no displacement clamp (`World::pull_axis`
    /// gives a flat world's plane axes their kicks without it): at the
    /// strongest pull a level allows (`Params::mg_max`), at every event rate,
    /// pitch and rolling share, a step's displacement stays under a pitch and
    /// the ±64-pitch clamp leaves the kick as it is, in every fixed-point
    /// format.
    #[test]
    fn events_kicks_never_reach_the_clamp() {
        fn check<S: Scalar>() {
            for k in 7..=10 {
                for (short_um, long_um) in [(200, 800), (2_000, 10_000), (20_000, 80_000)] {
                    let spec = PhysicsSpec {
                        short_um,
                        long_um,
                        radius_um: short_um,
                        step_log2: k,
                        stepping: Stepping::Events,
                        ..PhysicsSpec::DEFAULT
                    };
                    let p = Params::<S>::new(spec).expect("valid spec");
                    let pitch = short_um + long_um;
                    for scale in [PullScale::new(1, 1, pitch), PullScale::new(5, 7, pitch)] {
                        let some = (-p.mg_max..=p.mg_max).step_by(37);
                        for mg in some.chain([p.mg_max, -p.mg_max, 0, 1, -1]) {
                            let free = scale.kick::<S>(mg, k);
                            assert_eq!(
                                scale.kick_fits::<S>(mg, k),
                                free,
                                "{} k {k} pitch {pitch} µm {mg} mg",
                                S::NAME
                            );
                            // Under a pitch a step (what `mg_max` is for), so
                            // far inside the clamp.
                            assert!(free.1.abs() < S::ONE, "{} k {k} pitch {pitch} µm", S::NAME);
                            let clamped = Kick::axis_of(mg, scale, S::from_int(64), k);
                            assert_eq!(free, clamped, "{} k {k} pitch {pitch} µm {mg} mg", S::NAME);
                        }
                    }
                }
            }
        }
        check::<I8F24>();
        check::<I16F16>();
        check::<I32F32>();
    }
}
