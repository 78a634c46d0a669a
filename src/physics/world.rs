//! The stateful layer: marbles on a board of tiles, stepped at a fixed rate.
//!
//! Data flows one way each step, per marble: effects shape the kick → integrate →
//! broadphase (eq. 7) → narrowphase (eq. 8) → respond (eq. 1) → out-of-play check;
//! then, only with several marbles, marble–marble contacts.
//!
//! **No tunnelling, by a step bound.** Each axis of the velocity is capped at
//! `v_max = min(r/4 per step, 64 pitch/s)` and each axis of the kick's displacement
//! `½·a·dt²` at `r/8`, so the centre moves at most `3r/8` per axis and `0.65·r`
//! overall in one step. The contact passes leave the centre at
//! least `r − r/4` from every solid box, and a step whose end state still overlaps
//! deeper than that is undone (`StepStats::reverts`). So the centre can never enter
//! a tile, let alone cross one, however thin the tile and whatever the step. At the
//! default 1024 steps/s and a 3.5 mm marble in a 12 mm pitch the cap is 64 pitch/s
//! (0.77 m/s), well above what a tilted toy reaches in one cell.

use heapless::Vec as HVec;

use super::dynamics::effects::{marble_pair, BoardMotion, Drag, Effects};
use super::dynamics::integrate::{advance, advance_plane, Kick, PullScale};
use super::dynamics::respond::{resolve, Impact, Outcome, T_LOG2};

pub mod events;
use super::geometry::broadphase::{candidates, candidates_plane, TileRange};
use super::geometry::grid::Tiles;
use super::geometry::narrowphase::{contact, lid_contact, out_of_reach, Contact, Feature};
use super::geometry::tiles::{LayoutError, TileIndex, TileLayout};
use super::scalar::Scalar;
use super::vec::Vec3;
pub use events::{StepObserver, MAX_EVENTS};

/// How [`World::step`] crosses its interval `dt`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stepping {
    /// Discrete steps: the closed form over `dt`, then the contact passes at its end
    /// (time of impact solved inside the step); no tunnelling by the step bound, so
    /// the speed is capped at `min(r/4 per step, 64 pitch/s)` per axis.
    #[default]
    Fixed,
    /// Events: each marble flies the closed form to its next event — the end of the
    /// step, the instant it touches a tile, the lid or another marble, loses a
    /// face's support or stops under rolling resistance — as many as the physics
    /// has, in time order (see [`events`]). No speed cap but the number format's.
    /// `dt` is then the frame (2^7 ..= 2^10 steps/s).
    Events,
}

/// The physical description of a scene, in integers (independent of the scalar).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PhysicsSpec {
    /// Short tile width `s` (µm).
    pub short_um: u32,
    /// Long tile width `l` (µm).
    pub long_um: u32,
    /// Marble radius (µm).
    pub radius_um: u32,
    /// Coefficient of restitution `e` ×1000.
    pub restitution_milli: u32,
    /// Rolling-resistance coefficient ×10⁶ (used with the `friction` effect).
    pub rolling_resistance_ppm: u32,
    /// Restitution threshold: impacts slower than this (µm/s) are contacts.
    pub rest_threshold_um_s: u32,
    /// `log2` of the step rate: `dt = 2^-step_log2` s.
    pub step_log2: u32,
    /// The effects the scene needs.
    pub effects: Effects,
    /// Fixed steps or events.
    pub stepping: Stepping,
}

impl PhysicsSpec {
    /// The defaults: 2 mm walls, 10 mm cells, a 7 mm marble, `e = 0.5`, 1 % rolling
    /// resistance, 20 mm/s restitution threshold, 1024 steps/s, rolling on.
    pub const DEFAULT: PhysicsSpec = PhysicsSpec {
        short_um: 2_000,
        long_um: 10_000,
        radius_um: 3_500,
        restitution_milli: 500,
        rolling_resistance_ppm: 10_000,
        rest_threshold_um_s: 20_000,
        step_log2: 10,
        effects: Effects {
            rolling: true,
            friction: false,
            board_motion: false,
            holes: false,
            marbles: false,
        },
        stepping: Stepping::Fixed,
    };
}

impl Default for PhysicsSpec {
    fn default() -> Self {
        PhysicsSpec::DEFAULT
    }
}

/// Why a scene could not be set up.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SetupError {
    /// The tile widths are unusable.
    Layout(LayoutError),
    /// The marble does not fit in a cell (`2r ≥ l`) or has zero radius.
    MarbleSize,
    /// `e` over 1, or the step rate outside 2^6 ..= 2^14 steps/s (events: 2^7 ..=
    /// 2^10).
    Parameter,
    /// More marbles than the world has room for, or none.
    MarbleCount,
    /// Marble number `.0` starts inside a tile or outside the board.
    BadStart(usize),
}

/// The spec turned into scalars.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params<S> {
    /// The tile layout.
    pub layout: TileLayout<S>,
    /// Marble radius (pitch).
    pub radius: S,
    /// Coefficient of restitution.
    pub restitution: S,
    /// Restitution threshold (pitch/T, the contact solver's unit).
    pub threshold: S,
    /// Per-axis speed cap (pitch/s): the step bound in fixed steps, the number
    /// format's range (128 pitch/s) with events.
    pub v_max: S,
    /// The largest pull per axis (milli-g): [`MAX_MG`], or with events less when a
    /// step's `a·dt` would not fit the number format (a pitch under 9.8 mm at 2^7
    /// steps/s).
    pub mg_max: i32,
    /// `dt = 2^-k` s.
    pub k: u32,
    /// Where the integers came from.
    pub spec: PhysicsSpec,
}

impl<S: Scalar> Params<S> {
    /// Validates a spec and converts it.
    pub fn new(spec: PhysicsSpec) -> Result<Self, SetupError> {
        let layout =
            TileLayout::<S>::from_um(spec.short_um, spec.long_um).map_err(SetupError::Layout)?;
        if spec.radius_um == 0 || 2 * spec.radius_um as u64 >= spec.long_um as u64 {
            return Err(SetupError::MarbleSize);
        }
        let events = spec.stepping == Stepping::Events;
        let rates = if events { 7..=10 } else { 6..=14 };
        if spec.restitution_milli > 1000 || !rates.contains(&spec.step_log2) {
            return Err(SetupError::Parameter);
        }
        let k = spec.step_log2;
        let radius = layout.from_um_len(spec.radius_um as i64);
        let threshold = S::ratio(
            spec.rest_threshold_um_s as i64,
            (layout.pitch_um as i64) << T_LOG2,
        );
        let (v_max, mg_max) = if events {
            // The format's range: 128 pitch/s (saturating at I8F24's largest value),
            // and a pull whose a·dt stays within it: mg ≤ 127 pitch/s · 2^k / (g per
            // mg in pitch/s²) = 127·2^k·pitch_um / 9806.65.
            let fits = (127i64 << k) * layout.pitch_um as i64 * 100 / 980_665;
            (S::from_int(128), fits.min(MAX_MG as i64) as i32)
        } else {
            let cap = S::from_int(64);
            (radius.shr(2).shl(k).min(cap), MAX_MG)
        };
        Ok(Params {
            layout,
            radius,
            restitution: S::ratio(spec.restitution_milli as i64, 1000),
            threshold,
            v_max,
            mg_max,
            k,
            spec,
        })
    }

    /// The step `dt` in seconds.
    pub fn dt(&self) -> f64 {
        1.0 / (1u64 << self.k) as f64
    }

    /// Whether the world steps by events.
    pub fn events(&self) -> bool {
        self.spec.stepping == Stepping::Events
    }
}

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
    /// since (same pull, board still, no neighbour touched it): every further step
    /// would too, so it is skipped — bit-for-bit the same result, at no cost.
    pub asleep: bool,
    /// Faces the marble rests on (bit `2·axis + up`) and their planes: while the pull
    /// still presses it there, the step holds it on them instead of letting it sink
    /// in and pushing it back — the same motion (a resting contact zeroes the normal
    /// motion either way), at a fraction of the cost.
    rest_mask: u8,
    rest_plane: [S; 3],
}

impl<S: PartialEq> PartialEq for Marble<S> {
    // Inlined: the sleep test asks it after every step of every awake marble.
    #[inline]
    fn eq(&self, o: &Self) -> bool {
        self.pos == o.pos && self.vel == o.vel && self.supported == o.supported && self.out == o.out
    }
}

/// Counters of what the step did. Each effect's counter moves only when that
/// effect's code runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct StepStats {
    /// Steps taken.
    pub steps: u32,
    /// Marble–tile contacts resolved.
    pub contacts: u32,
    /// Of those, bounces (eq. 1 with `e`).
    pub collisions: u32,
    /// Steps undone because the end state overlapped a tile (should stay 0).
    pub reverts: u32,
    /// Marble-steps that ran the rolling-resistance code.
    pub friction_runs: u32,
    /// Marble-steps that ran the board-motion code.
    pub board_motion_runs: u32,
    /// Marble-steps that ran the 3-D (holes) code.
    pub space_runs: u32,
    /// Steps that ran the marble–marble code.
    pub pair_runs: u32,
    /// Events stepping: events handled (impacts, contacts, a face's support
    /// ending, stops, re-checks; not the step's end).
    pub events: u32,
    /// Events stepping: discrete slices flown instead of a closed form (a marble
    /// rolling around an edge, pressed against another marble, or starting inside
    /// a tile), see [`events`].
    pub slices: u32,
    /// Events stepping: marble-steps that ran out of events ([`events::MAX_EVENTS`])
    /// and finished in slices. Physics does not get there: 0 in every test.
    pub event_limits: u32,
}

/// How many bounces between two [`World::take_impacts`] keep their speed.
pub const IMPACTS_KEPT: usize = 4;

/// The bounces against tiles and between marbles (eq. 1 with `e`, not the slow
/// impacts that become contacts) since the last [`World::take_impacts`], for
/// what a game plays or shows of them: a click per bounce, louder the harder it
/// hits. A bounce between two marbles counts once, at their closing speed.
///
/// Kept like [`StepStats`]: each bounce adds a count and, for the first
/// [`IMPACTS_KEPT`], its speed. No other code runs for it, whether anybody takes
/// them or not; the physics never reads them.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Impacts<S> {
    /// Bounces, all of them (saturating).
    pub count: u16,
    /// The normal speed at impact (pitch/s) of the first [`IMPACTS_KEPT`], in the
    /// order they happened.
    speeds: [S; IMPACTS_KEPT],
}

impl<S: Scalar> Impacts<S> {
    fn record(&mut self, speed: S) {
        if let Some(slot) = self.speeds.get_mut(self.count as usize) {
            *slot = speed;
        }
        self.count = self.count.saturating_add(1);
    }

    /// The speeds kept (pitch/s), in order.
    pub fn speeds(&self) -> &[S] {
        &self.speeds[..(self.count as usize).min(IMPACTS_KEPT)]
    }
}

/// The contact solver's view of a step (see [`respond`](super::dynamics::respond)):
/// the pull as `a·T²` (pitch/T²) and the step's length in `T`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Solver<S> {
    acc: Vec3<S>,
    dt: S,
}

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
    kicks_ready: bool,
    sleeping: bool,
    /// Per-milli-g scales: full gravity, the rolling (tangential) share, and the
    /// rolling-resistance deceleration per unit load.
    pulls: [PullScale; 3],
    /// Per marble, the last candidate range found free of solid tiles (the tiles
    /// never change, so it stays free): the next step usually has the same one.
    clear: [TileRange; M],
    /// What the steps did so far.
    pub stats: StepStats,
    /// The bounces since [`World::take_impacts`].
    impacts: Impacts<S>,
}

/// The largest acceleration the physics accepts per axis (milli-g); the tilt path
/// clamps implausible readings long before this.
pub const MAX_MG: i32 = 8_000;

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
            gravity_mg: [0; 3],
            kick_roll: Kick::default(),
            kick_free: Kick::default(),
            drag: Drag::default(),
            motion: BoardMotion::default(),
            extent,
            kicks_ready: false,
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
    /// Mutable marbles (tests, tools and game rules place them). Wakes them all:
    /// the caller may move one.
    pub fn marbles_mut(&mut self) -> &mut [Marble<S>] {
        for m in self.marbles.iter_mut() {
            m.asleep = false;
        }
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
    /// `(0, -1000, 0)`: down). Clamped to ±[`MAX_MG`] per axis. Computes the kicks
    /// once, so the steps that follow only add.
    pub fn set_gravity_mg(&mut self, g: [i32; 3]) {
        let lim = self.params.mg_max;
        // max then min, not `clamp`: its `min <= max` assertion would link core::fmt.
        let g = g.map(|v| v.max(-lim).min(lim));
        // Per axis: each axis of the kicks depends on that axis of the pull alone
        // (the displacement clamp is per axis too), and a tilt usually moves one
        // axis at a time — the others keep their kicks, bit for bit.
        let fresh = !self.kicks_ready;
        let changed = [0, 1, 2].map(|a| fresh || g[a] != self.gravity_mg[a]);
        if !(changed[0] || changed[1] || changed[2]) {
            return;
        }
        self.kicks_ready = true;
        self.gravity_mg = g;
        // A new pull can move a resting marble.
        for m in self.marbles.iter_mut() {
            m.asleep = false;
        }
        let k = self.params.k;
        // Fixed steps bound the kick's displacement (no tunnelling); events need no
        // bound (|½·a·dt²| < 1 pitch by `mg_max`).
        let reach = if self.params.events() {
            S::from_int(64)
        } else {
            self.params.radius.shr(3)
        };
        let [full, roll, resist] = self.pulls;
        let falls = self.params.spec.effects.holes;
        for axis in (0..3).filter(|&a| changed[a]) {
            // Rolling scales the tangential axes only (x', z'): the normal is full.
            let rolls = axis != 1 && roll != full;
            let rolling = Kick::axis_of(g[axis], if rolls { roll } else { full }, reach, k);
            self.kick_roll.set_axis(axis, rolling);
            // What a scene does not use costs nothing: a flat world never flies
            // free, and the free kick's plane axes would be two more exact
            // products per tilt sample (a tenth of a maze frame, `cargo accuracy`).
            if !rolls {
                self.kick_free.set_axis(axis, rolling);
            } else if falls {
                self.kick_free
                    .set_axis(axis, Kick::axis_of(g[axis], full, reach, k));
            }
        }
        // Rolling resistance decelerates by c_rr·g_n (·5/7 when rolling), g_n = −g_y.
        if changed[1] && self.params.spec.effects.friction {
            self.drag = Drag::new(resist.kick::<S>((-g[1]).max(0), k).0, k);
        }
    }

    /// The bounces since the last call (see [`Impacts`]), and a fresh count.
    pub fn take_impacts(&mut self) -> Impacts<S> {
        core::mem::take(&mut self.impacts)
    }

    /// Turns skipping of resting marbles on (the default) or off. Off, every marble
    /// is stepped every time: the tests use it to check that skipping changes nothing.
    pub fn set_sleeping(&mut self, on: bool) {
        self.sleeping = on;
        for m in self.marbles.iter_mut() {
            m.asleep = false;
        }
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
        }
    }

    /// Advances the world by one step `dt` (fixed, or by events: see [`Stepping`]).
    ///
    /// Both steppers are linked wherever this is called. Firmware, whose mode is
    /// a constant, calls [`World::step_in`] and links only its own.
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
    /// for that mode); the game's [`Player`](crate::game::player::Player) sets up
    /// both from one constant.
    #[inline]
    pub fn step_in<const EVENTS: bool>(&mut self) {
        debug_assert_eq!(EVENTS, self.params.events(), "stepper and spec disagree");
        if EVENTS {
            self.step_events(&mut ());
        } else {
            self.step_fixed();
        }
    }

    fn step_fixed(&mut self) {
        self.stats.steps = self.stats.steps.wrapping_add(1);
        if self.params.spec.effects.holes {
            self.step_marbles::<true>();
        } else {
            self.step_marbles::<false>();
        }
        if self.params.spec.effects.marbles && self.marbles.len() > 1 {
            if self.params.spec.effects.holes {
                self.collide_marbles::<true>();
            } else {
                self.collide_marbles::<false>();
            }
        }
    }

    fn step_marbles<const SPACE: bool>(&mut self) {
        for n in 0..self.marbles.len() {
            let mut m = self.marbles[n];
            if !m.out && !m.asleep {
                self.step_marble::<SPACE>(n, &mut m);
                // Asleep only when the step changed nothing at all and the board
                // is not turning (its pull then changes every step). The step
                // works on the copy: the stored marble is still the one before it.
                m.asleep =
                    self.sleeping && m == self.marbles[n] && !self.params.spec.effects.board_motion;
                self.marbles[n] = m;
            }
        }
    }

    fn step_marble<const SPACE: bool>(&mut self, n: usize, m: &mut Marble<S>) {
        let k = self.params.k;
        let effects = self.params.spec.effects;
        let supported = !SPACE || m.supported;
        let mut kick = if supported {
            self.kick_roll
        } else {
            self.kick_free
        };
        if effects.friction && supported {
            self.stats.friction_runs = self.stats.friction_runs.wrapping_add(1);
            self.drag.apply(&mut m.vel, &mut kick);
        }
        if effects.board_motion {
            self.stats.board_motion_runs = self.stats.board_motion_runs.wrapping_add(1);
            let mut extra = self.motion.kick(m.pos, m.vel.shr(k), k);
            // A violently jerked board can ask for more than the speed range holds.
            extra.dv = extra.dv.clamp_abs(self.params.v_max);
            if !SPACE {
                extra.dv.y = S::ZERO;
                extra.dp.y = S::ZERO;
            }
            kick = kick.plus(extra).clamped(self.params.radius.shr(3));
        }
        let mut held_on_floor = false;
        if m.rest_mask != 0 {
            held_on_floor = self.hold::<SPACE>(m, &mut kick);
        }
        let start = m.pos;
        if SPACE {
            self.stats.space_runs = self.stats.space_runs.wrapping_add(1);
            advance(&mut m.pos, &mut m.vel, &kick, k);
        } else {
            advance_plane(&mut m.pos, &mut m.vel, &kick, k);
        }
        m.vel = m.vel.clamp_abs(self.params.v_max);
        m.supported = self.collide_tiles::<SPACE>(n, m, &kick, start) || held_on_floor;
        self.check_out::<SPACE>(m);
    }

    /// Contact passes against the tiles (and, in 3-D, the lid) for marble number
    /// `n`; returns whether the floor supports the marble.
    ///
    /// Nearly every step has no solid tile in reach at all (a marble on the floor
    /// reaches only the wall layer; one held on a floor or on a face it rests
    /// against from +x'/+z' has that tile just outside its reach), and then the
    /// passes end after the first with nothing touched: what they return is known
    /// without them. That case is checked here, inline and with no contact code (and
    /// without even the tile lookups when the candidates are the ones last found
    /// free); the passes run only when a solid tile (or the lid) is within a radius
    /// of the centre on every axis.
    #[inline(always)]
    fn collide_tiles<const SPACE: bool>(
        &mut self,
        n: usize,
        m: &mut Marble<S>,
        kick: &Kick<S>,
        start: Vec3<S>,
    ) -> bool {
        let (r, tiles, layout) = (self.params.radius, self.tiles, &self.params.layout);
        let range = if SPACE {
            candidates(layout, m.pos, r)
        } else {
            candidates_plane(layout, m.pos, r)
        };
        let mut clear = range == self.clear[n];
        if !clear {
            clear = true;
            // No solid tile at all: the range is free wherever the marble is in it.
            let mut empty = true;
            let mut k = range.lo.k;
            while clear && k <= range.hi.k {
                let mut j = range.lo.j;
                while clear && j <= range.hi.j {
                    let mut i = range.lo.i;
                    while clear && i <= range.hi.i {
                        let t = TileIndex::new(i, j, k);
                        if tiles.is_solid(t) {
                            // A solid tile a whole radius away along some axis is not
                            // touched either: the first pass would find no contact
                            // with it (`contact`'s first test, the same comparisons).
                            // That is a marble resting on a face it touches from −x'/−z'
                            // (the face's plane is the tile's lower bound, in reach),
                            // or passing a post diagonally. Not cached: it depends on
                            // where the marble is.
                            // (A floor tile in reach, in 3-D, is a marble sinking into
                            // it: a contact, not worth the test.)
                            empty = false;
                            clear = j >= 1 && out_of_reach(m.pos, r, &layout.tile_box(t));
                        }
                        i += 1;
                    }
                    j += 1;
                }
                k += 1;
            }
            if empty {
                self.clear[n] = range;
            }
        }
        if clear && (!SPACE || lid_contact(m.pos, r, self.lid()).is_none()) {
            // What the passes return when the first touches nothing.
            return !SPACE;
        }
        let solver = self.solver(kick.dv, self.params.k);
        self.contact_passes::<SPACE>(m, &solver, start)
    }

    /// The contact solver's view of a step of `2^-k` s whose pull adds `dv` (pitch/s)
    /// to the velocity: the acceleration `a·T² = dv · 2^(k−10)` and the step's length
    /// in `T`.
    pub(crate) fn solver(&self, dv: Vec3<S>, k: u32) -> Solver<S> {
        Solver {
            acc: if k >= 2 * T_LOG2 {
                dv.shl(k - 2 * T_LOG2)
            } else {
                dv.shr(2 * T_LOG2 - k)
            },
            dt: S::ONE.shr(k - T_LOG2),
        }
    }

    /// The contact passes of [`World::collide_tiles`].
    #[inline(never)]
    fn contact_passes<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        kick: &Solver<S>,
        start: Vec3<S>,
    ) -> bool {
        let (r, tiles) = (self.params.radius, self.tiles);
        let layout = self.params.layout;
        let mut supported = !SPACE;
        for pass in 0..3 {
            let range = if SPACE {
                candidates(&layout, m.pos, r)
            } else {
                candidates_plane(&layout, m.pos, r)
            };
            let mut touched = false;
            // Face contacts on distinct axes push the marble straight back into the
            // free part of its own cell, where nothing else can be in reach (2r < l):
            // then no further pass is needed. Edges, or two faces on one axis, get one.
            let mut faces = 0u8;
            let mut settled = true;
            // The tiles in reach, then (3-D only) the lid, each asked with the current
            // position (earlier contacts in the pass may have moved the marble). Plain
            // loops: iterator adapters here cost more than the geometry.
            let mut k = range.lo.k;
            while k <= range.hi.k {
                let mut j = range.lo.j;
                while j <= range.hi.j {
                    let mut i = range.lo.i;
                    while i <= range.hi.i {
                        let t = TileIndex::new(i, j, k);
                        if tiles.is_solid(t) {
                            if let Some(c) = contact(m.pos, r, t, &layout.tile_box(t), tiles) {
                                touched = true;
                                settled &= face_once(&mut faces, &c);
                                if self.take_contact::<SPACE>(
                                    m,
                                    &c,
                                    kick,
                                    pass,
                                    start,
                                    &mut supported,
                                ) {
                                    return supported;
                                }
                            }
                        }
                        i += 1;
                    }
                    j += 1;
                }
                k += 1;
            }
            if SPACE {
                if let Some(c) = lid_contact(m.pos, r, self.lid()) {
                    touched = true;
                    settled &= face_once(&mut faces, &c);
                    if self.take_contact::<SPACE>(m, &c, kick, pass, start, &mut supported) {
                        return supported;
                    }
                }
            }
            if !touched || (pass == 0 && settled) {
                break;
            }
        }
        supported
    }

    /// One contact of a pass: resolved in passes 0 and 1; in pass 2, anything still
    /// deeper than the slop (a wedge the passes could not settle) undoes the step.
    /// Returns `true` when the step was undone.
    fn take_contact<const SPACE: bool>(
        &mut self,
        m: &mut Marble<S>,
        c: &Contact<S>,
        kick: &Solver<S>,
        pass: u32,
        start: Vec3<S>,
        supported: &mut bool,
    ) -> bool {
        if pass == 2 {
            if c.depth > self.params.radius.shr(2) {
                m.pos = start;
                m.vel = Vec3::ZERO;
                self.stats.reverts = self.stats.reverts.wrapping_add(1);
                return true;
            }
            return false;
        }
        let outcome = self.apply_contact(m, c, kick);
        if let (Feature::Face(axis), Outcome::Contact) = (c.feature, outcome) {
            let up = c.normal.axis(axis as usize) > S::ZERO;
            m.rest_mask |= 1 << (2 * axis + up as u8);
            m.rest_plane[axis as usize] = c.plane;
        }
        if SPACE && c.normal.y > S::ONE.half() {
            *supported = true;
        }
        false
    }

    /// Keeps a resting marble on the faces it rests on: while it sits exactly on the
    /// face, does not move along its normal, the pull presses it in and the tile is
    /// still there under the contact point, the kick's normal part is dropped. Any of
    /// these failing releases the face (the contact passes take over again). Returns
    /// whether it is held on the floor.
    fn hold<const SPACE: bool>(&self, m: &mut Marble<S>, kick: &mut Kick<S>) -> bool {
        let r = self.params.radius;
        let mut on_floor = false;
        // The set bits only, lowest first (the same order as a scan of all six: the
        // body clears no bit but its own).
        let mut bits = m.rest_mask;
        while bits != 0 {
            let bit = bits.trailing_zeros() as u8;
            bits &= bits - 1;
            let (axis, up) = ((bit / 2) as usize, bit % 2 == 1);
            let plane = m.rest_plane[axis];
            let at = if up { plane + r } else { plane - r };
            let pull = kick.dv.axis(axis);
            let presses = if up { pull < S::ZERO } else { pull > S::ZERO };
            let mut keep = m.pos.axis(axis) == at && m.vel.axis(axis) == S::ZERO && presses;
            if keep {
                keep = self.behind_solid::<SPACE>(m.pos, axis, up, plane);
            }
            if keep {
                kick.set_axis(axis, (S::ZERO, S::ZERO));
                on_floor |= axis == 1 && up;
            } else {
                m.rest_mask &= !(1 << bit);
            }
        }
        on_floor
    }

    /// Whether the tile behind the contact point of a marble centred at `c` resting
    /// on the face at `plane` (axis `axis`, from above when `up`) is there (the lid,
    /// −y, always is).
    #[inline]
    fn behind_solid<const SPACE: bool>(&self, c: Vec3<S>, axis: usize, up: bool, plane: S) -> bool {
        if axis == 1 && !up {
            return true;
        }
        let layout = &self.params.layout;
        let behind = if up { plane.next_down() } else { plane };
        // Eq. 6 for the other two axes of the centre (the flat maze's walls are
        // layer 1).
        let j = || if SPACE { layout.index_y(c.y) } else { 1 };
        let t = match axis {
            0 => TileIndex::new(layout.index_xz(behind), j(), layout.index_xz(c.z)),
            1 => TileIndex::new(
                layout.index_xz(c.x),
                layout.index_y(behind),
                layout.index_xz(c.z),
            ),
            _ => TileIndex::new(layout.index_xz(c.x), j(), layout.index_xz(behind)),
        };
        self.tiles.is_solid(t)
    }

    /// Resolves one contact (eq. 1 at the instant of impact, see `respond`).
    fn apply_contact(&mut self, m: &mut Marble<S>, c: &Contact<S>, kick: &Solver<S>) -> Outcome {
        let p = &self.params;
        let sub = p.k - T_LOG2;
        let v_board = if p.spec.effects.board_motion {
            // The board's surface is held to the marble's speed range (64 pitch/s):
            // faster is no toy, and it keeps the solver's squares in range.
            self.motion
                .surface_velocity(m.pos - c.normal.scale(p.radius))
                .shl(sub)
                .clamp_abs(p.v_max.shr(T_LOG2))
        } else {
            Vec3::ZERO
        };
        let imp = Impact {
            n: c.normal,
            depth: c.depth,
            v: m.vel.shr(T_LOG2),
            v_board,
            acc: kick.acc,
            dt: kick.dt,
        };
        let res = resolve(&imp, p.restitution, p.threshold);
        match c.feature {
            // Axis-aligned: put the centre exactly at `plane ± (r + lift)`.
            Feature::Face(_) | Feature::Inside => {
                let (axis, up) = axis_of(c.normal);
                let at = if up {
                    c.plane + p.radius + res.lift
                } else {
                    c.plane - p.radius - res.lift
                };
                match axis {
                    0 => m.pos.x = at,
                    1 => m.pos.y = at,
                    _ => m.pos.z = at,
                }
            }
            Feature::Edge => m.pos += c.normal.scale(res.push),
        }
        let vn_now = m.vel.dot(c.normal);
        // Under the format's top (127 pitch/s, the event step's limit; fixed steps
        // cap lower): `normal × vn_new` below must fit, and a unit normal times 128
        // does not — it wrapped to −128 in release builds (found by the property
        // `step_survives_arbitrary_states`).
        let top = p.v_max.min(S::from_int(127));
        let vn_new = (res.vn + v_board.dot(c.normal))
            .shl(T_LOG2)
            .clamp(-top, top);
        let mut tangential = m.vel - c.normal.scale(vn_now);
        if res.deficit > S::ZERO {
            // Pay the rest of the push-out's energy from the tangential speed (rare:
            // a fast marble grazing an edge under a strong pull). In T units: ½|v_t|².
            let vt = tangential.shr(T_LOG2);
            let s2 = vt.length_sq();
            let keep = if s2 > res.deficit + res.deficit {
                S::ONE - (res.deficit + res.deficit).div(s2)
            } else {
                S::ZERO
            };
            tangential = tangential.scale(keep.sqrt());
        }
        // A slanted normal can move speed between axes: keep every axis under the cap
        // (the no-tunnelling bound is per axis). The sum saturates only past the
        // range, at event stepping's speeds, which keeps its magnitude under it.
        m.vel = tangential
            .sat_add(c.normal.scale(vn_new))
            .clamp_abs(p.v_max);
        if p.events() {
            m.vel = events::cap_speed(m.vel);
        }
        self.stats.contacts = self.stats.contacts.wrapping_add(1);
        if res.outcome == Outcome::Collision {
            self.stats.collisions = self.stats.collisions.wrapping_add(1);
            self.impacts.record(res.impact.shl(T_LOG2));
        }
        res.outcome
    }

    fn check_out<const SPACE: bool>(&self, m: &mut Marble<S>) {
        let (ex, ez) = self.extent;
        let p = m.pos;
        // Past the board's edge: the border walls and the lid close every
        // storey, so a centre beyond them went under the board through a hole
        // (a board shaken hard rolled a fallen marble round the border slab's
        // lower edges and out sideways: the events soak, frame 659 548).
        let beyond = p.x < S::ZERO || p.z < S::ZERO || p.x > ex || p.z > ez;
        if SPACE {
            // Through a hole once entirely below the floor slab (top at or below
            // −s): there is nothing down there to hold it, not even under the
            // neighbouring tiles. At exactly −s the slab's underside could hold it
            // up: a board shaken hard (its surface velocity in eq. 1) carried a
            // fallen marble along the underside at 120 pitch/s (the events soak,
            // frame 539 521).
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

    /// Marble–marble contacts. A marble pushed by its neighbour gets one more tile
    /// pass from where it stood, so a pair squeezed against a wall never leaves one
    /// of them inside it.
    fn collide_marbles<const SPACE: bool>(&mut self) {
        self.stats.pair_runs = self.stats.pair_runs.wrapping_add(1);
        for a in 0..self.marbles.len() {
            for b in a + 1..self.marbles.len() {
                self.collide_pair::<SPACE>(a, b);
            }
        }
    }

    /// One pair of [`World::collide_marbles`]: pushed apart when they overlap, eq. 1
    /// between them, then the tile passes for both. Returns whether they touched.
    fn collide_pair<const SPACE: bool>(&mut self, a: usize, b: usize) -> bool {
        let p = self.params;
        let r2 = p.radius + p.radius;
        let (ma, mb) = (self.marbles[a], self.marbles[b]);
        if ma.out || mb.out {
            return false;
        }
        let d = mb.pos - ma.pos;
        if d.x.abs() >= r2 || d.y.abs() >= r2 || d.z.abs() >= r2 {
            return false;
        }
        let len2 = d.length_sq();
        if len2 >= r2 * r2 {
            return false;
        }
        let inv = len2.rsqrt();
        let (n, len) = if inv == S::ZERO {
            (Vec3::new(S::ONE, S::ZERO, S::ZERO), S::ZERO)
        } else {
            (d.scale(inv), len2 * inv)
        };
        let push = (r2 - len).half();
        let (va, vb, bounce) = marble_pair(
            ma.vel.shr(T_LOG2),
            mb.vel.shr(T_LOG2),
            n,
            p.restitution,
            p.threshold,
        );
        if bounce > S::ZERO {
            self.impacts.record(bounce.shl(T_LOG2));
        }
        let mut na = Marble {
            asleep: false,
            ..ma
        };
        let mut nb = Marble {
            asleep: false,
            ..mb
        };
        na.pos -= n.scale(push);
        nb.pos += n.scale(push);
        let set = |m: &mut Marble<S>, v_step: Vec3<S>| {
            let old = m.vel.dot(n);
            let new = v_step.dot(n).shl(T_LOG2).clamp(-p.v_max, p.v_max);
            m.vel = (m.vel - n.scale(old))
                .sat_add(n.scale(new))
                .clamp_abs(p.v_max);
            if p.events() {
                m.vel = events::cap_speed(m.vel);
            }
        };
        set(&mut na, va);
        set(&mut nb, vb);
        let still = self.solver(Vec3::ZERO, p.k);
        // The passes themselves (what `collide_tiles` comes to), without its
        // inline shortcut for the common case: this one is rare.
        na.supported = self.contact_passes::<SPACE>(&mut na, &still, ma.pos) || na.supported;
        nb.supported = self.contact_passes::<SPACE>(&mut nb, &still, mb.pos) || nb.supported;
        self.marbles[a] = na;
        self.marbles[b] = nb;
        true
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

/// The axis of an axis-aligned unit normal and whether it points up that axis.
fn axis_of<S: Scalar>(n: Vec3<S>) -> (usize, bool) {
    if n.x != S::ZERO {
        (0, n.x > S::ZERO)
    } else if n.y != S::ZERO {
        (1, n.y > S::ZERO)
    } else {
        (2, n.z > S::ZERO)
    }
}

/// Records a face contact's axis in `faces`; `false` for an edge or inside contact,
/// or a second contact on an axis already seen (those need another pass).
fn face_once<S: Scalar>(faces: &mut u8, c: &Contact<S>) -> bool {
    match c.feature {
        Feature::Face(axis) => {
            let bit = 1u8 << axis;
            let fresh = *faces & bit == 0;
            *faces |= bit;
            fresh
        }
        _ => false,
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
pub fn overlaps_any<S: Scalar>(layout: &TileLayout<S>, tiles: Tiles<'_>, c: Vec3<S>, r: S) -> bool {
    candidates(layout, c, r)
        .solid(tiles)
        // Slab `j = 2n` (eq. 5) tops out at `y' = n`.
        .filter(|t: &TileIndex| t.j & 1 == 1 || S::from_int(t.j >> 1) > c.y)
        .any(|t| super::geometry::narrowphase::overlaps(c, r, &layout.tile_box(t)))
}
