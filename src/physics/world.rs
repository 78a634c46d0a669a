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

use super::dynamics::effects::{marble_pair, rolling_resistance, BoardMotion, Effects};
use super::dynamics::integrate::{advance, advance_plane, kick_axis, Kick};
use super::dynamics::respond::{resolve, Impact, Outcome, T_LOG2};
use super::geometry::broadphase::{candidates, candidates_plane};
use super::geometry::grid::Tiles;
use super::geometry::narrowphase::{contact, lid_contact, Contact};
use super::geometry::tiles::{LayoutError, TileIndex, TileLayout};
use super::scalar::Scalar;
use super::vec::Vec3;

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
        effects: Effects { rolling: true, friction: false, board_motion: false, holes: false, marbles: false },
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
    /// `e` over 1, or the step rate outside 2^6 ..= 2^14 steps/s.
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
    /// Per-axis speed cap (pitch/s).
    pub v_max: S,
    /// `dt = 2^-k` s.
    pub k: u32,
    /// Where the integers came from.
    pub spec: PhysicsSpec,
}

impl<S: Scalar> Params<S> {
    /// Validates a spec and converts it.
    pub fn new(spec: PhysicsSpec) -> Result<Self, SetupError> {
        let layout = TileLayout::<S>::from_um(spec.short_um, spec.long_um).map_err(SetupError::Layout)?;
        if spec.radius_um == 0 || 2 * spec.radius_um as u64 >= spec.long_um as u64 {
            return Err(SetupError::MarbleSize);
        }
        if spec.restitution_milli > 1000 || !(6..=14).contains(&spec.step_log2) {
            return Err(SetupError::Parameter);
        }
        let k = spec.step_log2;
        let radius = layout.from_um_len(spec.radius_um as i64);
        let threshold = S::ratio(spec.rest_threshold_um_s as i64, (layout.pitch_um as i64) << T_LOG2);
        let cap = S::from_int(64);
        let v_max = radius.shr(2).shl(k).min(cap);
        Ok(Params {
            layout,
            radius,
            restitution: S::ratio(spec.restitution_milli as i64, 1000),
            threshold,
            v_max,
            k,
            spec,
        })
    }

    /// The step `dt` in seconds.
    pub fn dt(&self) -> f64 {
        1.0 / (1u64 << self.k) as f64
    }
}

/// One marble.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Marble<S> {
    /// Centre in the tile frame (pitch).
    pub pos: Vec3<S>,
    /// Velocity (pitch/s).
    pub vel: Vec3<S>,
    /// Touching the floor (rolling) at the end of the last step.
    pub supported: bool,
    /// Fallen through a hole or off the board: no longer simulated.
    pub out: bool,
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
}

/// A board of tiles with up to `M` marbles on it.
#[derive(Clone, Debug)]
pub struct World<'a, S: Scalar, const M: usize> {
    params: Params<S>,
    tiles: Tiles<'a>,
    marbles: HVec<Marble<S>, M>,
    gravity_mg: [i32; 3],
    kick_roll: Kick<S>,
    kick_free: Kick<S>,
    decel: S,
    motion: BoardMotion<S>,
    extent: (S, S),
    /// What the steps did so far.
    pub stats: StepStats,
}

/// The largest acceleration the physics accepts per axis (milli-g); the tilt path
/// clamps implausible readings long before this.
pub const MAX_MG: i32 = 8_000;

impl<'a, S: Scalar, const M: usize> World<'a, S, M> {
    /// A world with marbles resting on the floor at `starts` (tile-frame x', z'; the
    /// height is set to the radius).
    pub fn new(params: Params<S>, tiles: Tiles<'a>, starts: &[(S, S)]) -> Result<Self, SetupError> {
        if starts.is_empty() || starts.len() > M {
            return Err(SetupError::MarbleCount);
        }
        let layout = params.layout;
        let extent = (layout.span_xz(tiles.nx() as i32 - 1).1, layout.span_xz(tiles.nz() as i32 - 1).1);
        let mut marbles = HVec::new();
        for (n, &(x, z)) in starts.iter().enumerate() {
            let pos = Vec3::new(x, params.radius, z);
            let inside = x > S::ZERO && z > S::ZERO && x < extent.0 && z < extent.1;
            if !inside || overlaps_any(&layout, tiles, pos, params.radius) {
                return Err(SetupError::BadStart(n));
            }
            let m = Marble { pos, vel: Vec3::ZERO, supported: true, out: false };
            marbles.push(m).map_err(|_| SetupError::MarbleCount)?;
        }
        let mut w = World {
            params,
            tiles,
            marbles,
            gravity_mg: [0; 3],
            kick_roll: Kick::default(),
            kick_free: Kick::default(),
            decel: S::ZERO,
            motion: BoardMotion::default(),
            extent,
            stats: StepStats::default(),
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
    /// Mutable marbles (tests, tools and game rules place them).
    pub fn marbles_mut(&mut self) -> &mut [Marble<S>] {
        &mut self.marbles
    }
    /// The gravity last set (milli-g, tile frame).
    pub fn gravity_mg(&self) -> [i32; 3] {
        self.gravity_mg
    }
    /// The board's extent along x' and z' (pitch).
    pub fn extent(&self) -> (S, S) {
        self.extent
    }

    /// Sets the apparent gravity in the tile frame, in milli-g (a flat board is
    /// `(0, -1000, 0)`: down). Clamped to ±[`MAX_MG`] per axis. Computes the kicks
    /// once, so the steps that follow only add.
    pub fn set_gravity_mg(&mut self, g: [i32; 3]) {
        let g = g.map(|v| v.clamp(-MAX_MG, MAX_MG));
        self.gravity_mg = g;
        let (pitch, k) = (self.params.layout.pitch_um, self.params.k);
        let roll = if self.params.spec.effects.rolling { (5, 7) } else { (1, 1) };
        let reach = self.params.radius.shr(3);
        self.kick_free = Kick::from_mg(g, (1, 1), pitch, k).clamped(reach);
        self.kick_roll = if roll == (1, 1) { self.kick_free } else { Kick::from_mg(g, roll, pitch, k).clamped(reach) };
        // Rolling resistance decelerates by c_rr·g_n (·5/7 when rolling), g_n = −g_y.
        let load = (-g[1]).max(0);
        let ppm = self.params.spec.rolling_resistance_ppm as i64;
        self.decel = kick_axis::<S>(load, ppm * roll.0, 1_000_000 * roll.1, pitch, k).0;
    }

    /// Sets the board's rotation (used with the `board_motion` effect).
    pub fn set_board_motion(&mut self, motion: BoardMotion<S>) {
        self.motion = motion;
    }

    /// Advances the world by one step `dt`.
    pub fn step(&mut self) {
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
            if !m.out {
                self.step_marble::<SPACE>(&mut m);
                self.marbles[n] = m;
            }
        }
    }

    fn step_marble<const SPACE: bool>(&mut self, m: &mut Marble<S>) {
        let k = self.params.k;
        let effects = self.params.spec.effects;
        let supported = !SPACE || m.supported;
        let mut kick = if supported { self.kick_roll } else { self.kick_free };
        if effects.friction && supported {
            self.stats.friction_runs = self.stats.friction_runs.wrapping_add(1);
            rolling_resistance(&mut m.vel, &mut kick, self.decel, k);
        }
        if effects.board_motion {
            self.stats.board_motion_runs = self.stats.board_motion_runs.wrapping_add(1);
            let mut extra = self.motion.kick(m.pos, m.vel.shr(k), k);
            if !SPACE {
                extra.dv.y = S::ZERO;
                extra.dp.y = S::ZERO;
            }
            kick = kick.plus(extra).clamped(self.params.radius.shr(3));
        }
        let start = m.pos;
        if SPACE {
            self.stats.space_runs = self.stats.space_runs.wrapping_add(1);
            advance(&mut m.pos, &mut m.vel, &kick, k);
        } else {
            advance_plane(&mut m.pos, &mut m.vel, &kick, k);
        }
        m.vel = m.vel.clamp_abs(self.params.v_max);
        m.supported = self.collide_tiles::<SPACE>(m, &kick, start);
        self.check_out::<SPACE>(m);
    }

    /// Contact passes against the tiles (and, in 3-D, the lid); returns whether the
    /// floor supports the marble.
    fn collide_tiles<const SPACE: bool>(&mut self, m: &mut Marble<S>, kick: &Kick<S>, start: Vec3<S>) -> bool {
        let p = self.params;
        let (r, k, layout, tiles) = (p.radius, p.k, p.layout, self.tiles);
        // The kick's a·dt in the solver's units: a·T² = a·dt · 2^(k−10).
        let acc = if k >= 2 * T_LOG2 { kick.dv.shl(k - 2 * T_LOG2) } else { kick.dv.shr(2 * T_LOG2 - k) };
        let half = S::ONE.half();
        let slop = r.shr(2);
        let mut supported = !SPACE;
        for pass in 0..3 {
            let range = if SPACE { candidates(&layout, m.pos, r) } else { candidates_plane(&layout, m.pos, r) };
            let mut touched = false;
            // The tiles in reach, then (3-D only) the lid; each asked with the current
            // position, since earlier contacts in the pass may have moved the marble.
            for item in range.solid(tiles).map(Some).chain(SPACE.then_some(None)) {
                let c = match item {
                    Some(t) => contact(m.pos, r, t, &layout.tile_box(t), tiles),
                    None => lid_contact(m.pos, r, layout.l),
                };
                let Some(c) = c else { continue };
                touched = true;
                if pass == 2 {
                    // Still overlapping after two passes: a wedge the passes could not
                    // settle. Anything deeper than the slop undoes the step.
                    if c.depth > slop {
                        m.pos = start;
                        m.vel = Vec3::ZERO;
                        self.stats.reverts = self.stats.reverts.wrapping_add(1);
                        return supported;
                    }
                    continue;
                }
                self.apply_contact(m, &c, acc);
                if SPACE && c.normal.y > half {
                    supported = true;
                }
            }
            if !touched {
                break;
            }
        }
        supported
    }

    /// Resolves one contact (eq. 1 at the instant of impact, see `respond`).
    fn apply_contact(&mut self, m: &mut Marble<S>, c: &Contact<S>, acc: Vec3<S>) {
        let p = self.params;
        let sub = p.k - T_LOG2;
        self.stats.contacts = self.stats.contacts.wrapping_add(1);
        let v_board = if p.spec.effects.board_motion {
            self.motion.surface_velocity(m.pos - c.normal.scale(p.radius)).shl(sub)
        } else {
            Vec3::ZERO
        };
        let imp = Impact { n: c.normal, depth: c.depth, v: m.vel.shr(T_LOG2), v_board, acc, dt: S::ONE.shr(sub) };
        let res = resolve(&imp, p.restitution, p.threshold);
        m.pos += c.normal.scale(res.push);
        let vn_now = m.vel.dot(c.normal);
        let vn_new = (res.vn + v_board.dot(c.normal)).shl(T_LOG2).clamp(-p.v_max, p.v_max);
        // A slanted normal can move speed between axes: keep every axis under the cap
        // (the no-tunnelling bound is per axis).
        m.vel = (m.vel - c.normal.scale(vn_now) + c.normal.scale(vn_new)).clamp_abs(p.v_max);
        if res.outcome == Outcome::Collision {
            self.stats.collisions = self.stats.collisions.wrapping_add(1);
        }
    }

    fn check_out<const SPACE: bool>(&self, m: &mut Marble<S>) {
        let (ex, ez) = self.extent;
        let p = m.pos;
        if SPACE {
            let margin = S::from_int(2);
            let depth = self.params.layout.s + self.params.radius + self.params.radius;
            if p.y < -depth || p.y > S::from_int(4) || p.x < -margin || p.z < -margin || p.x > ex + margin || p.z > ez + margin {
                m.out = true;
            }
        } else if p.x < S::ZERO || p.z < S::ZERO || p.x > ex || p.z > ez {
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
        let p = self.params;
        let r2 = p.radius + p.radius;
        for a in 0..self.marbles.len() {
            for b in a + 1..self.marbles.len() {
                let (ma, mb) = (self.marbles[a], self.marbles[b]);
                if ma.out || mb.out {
                    continue;
                }
                let d = mb.pos - ma.pos;
                if d.x.abs() >= r2 || d.y.abs() >= r2 || d.z.abs() >= r2 {
                    continue;
                }
                let len2 = d.length_sq();
                if len2 >= r2 * r2 {
                    continue;
                }
                let len = len2.sqrt();
                let n = if len == S::ZERO {
                    Vec3::new(S::ONE, S::ZERO, S::ZERO)
                } else {
                    Vec3::new(d.x.div(len), d.y.div(len), d.z.div(len))
                };
                let push = (r2 - len).half();
                let (va, vb) = marble_pair(ma.vel.shr(T_LOG2), mb.vel.shr(T_LOG2), n, p.restitution, p.threshold);
                let mut na = ma;
                let mut nb = mb;
                na.pos -= n.scale(push);
                nb.pos += n.scale(push);
                let set = |m: &mut Marble<S>, v_step: Vec3<S>| {
                    let old = m.vel.dot(n);
                    let new = v_step.dot(n).shl(T_LOG2).clamp(-p.v_max, p.v_max);
                    m.vel = (m.vel - n.scale(old) + n.scale(new)).clamp_abs(p.v_max);
                };
                set(&mut na, va);
                set(&mut nb, vb);
                let still = Kick::default();
                na.supported = self.collide_tiles::<SPACE>(&mut na, &still, ma.pos) || na.supported;
                nb.supported = self.collide_tiles::<SPACE>(&mut nb, &still, mb.pos) || nb.supported;
                self.marbles[a] = na;
                self.marbles[b] = nb;
            }
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

/// Whether a marble at `c` overlaps any solid tile (start validation, tests).
pub fn overlaps_any<S: Scalar>(layout: &TileLayout<S>, tiles: Tiles<'_>, c: Vec3<S>, r: S) -> bool {
    candidates(layout, c, r)
        .solid(tiles)
        .filter(|t: &TileIndex| t.j >= 1)
        .any(|t| super::geometry::narrowphase::overlaps(c, r, &layout.tile_box(t)))
}
