//! The autopilot's control: each frame, the tilt that rolls the steered marble
//! along the plan.
//!
//! All arithmetic after reading the marble's state is integer: positions and
//! velocities are converted exactly (through the [`Scalar`]'s own floor and shifts,
//! never through a float) to 1/4096 pitch, so every backend runs the same integer
//! controller, and a given backend is bit-for-bit deterministic.
//!
//! Per axis, a velocity loop `tilt = KV·(v_want − v)` plus a step: the level's
//! rolling resistance (`c_rr`·1000 mg with `friction`) and 10 mg more, which sharpens
//! the loop against the tilt path's lag. Along the straight run the marble is
//! on, `v_want` is `K_POS·d` (capped at a top speed) for the distance `d` to the run's
//! end, a corner where it must stop; when the run ends in a goal it is the top speed
//! (the goal only has to be entered). Across the run the same loop keeps the marble on
//! the corridor's centre line; a new run starts only once the marble is nearly on it
//! (no cutting into corner posts). Around that:
//!
//! * **Gaps.** A marble that reaches a 2 mm gap slower than about 4 pitch/s drops into
//!   the slot and cannot climb out below ~300 mg, so runs over a gap are taken at
//!   6 pitch/s at least, and a marble that stopped in one anyway is tilted out with
//!   [`Autopilot::ESCAPE_TILT_MG`] towards the side nearer the goal.
//! * **Stalls.** A marble asked to move that does not move (a tilt path with a dead
//!   zone, or more resistance than planned for) gets 1 mg more tilt per frame, up to 120 mg.
//! * **Patience.** No step nearer the goal for 3 s (a tilt path with more lag than
//!   planned for makes the marble overshoot and oscillate): the gains go down in
//!   turn to ¾·KV and ½·K_POS, then ½·KV and ¼·K_POS, with the top speed.
//! * **Smoothness.** The tilt is limited to ±[`Autopilot::TILT_LIMIT_MG`] and changes
//!   by at most 10 mg a frame, like a brisk hand: with `board_motion`, faster tilting
//!   makes the board itself throw the marbles.

use super::planning::{connected, is_goal, is_pit, solid, Dir, STOREYS};
use super::Autopilot;
use crate::game::level::LevelView;
use crate::game::rules::Game;
use crate::input::axes::AccelMg;
use crate::physics::geometry::grid::Tiles;
use crate::physics::geometry::tiles::TileLayout;
use crate::physics::world::{Marble, PhysicsSpec};
use crate::physics::Scalar;

/// Fraction bits of the controller's fixed-point lengths (pitch) and speeds (pitch/s).
const Q: u32 = 12;
const ONE: i64 = 1 << Q;

// Tuning. Tried on every built-in level and backend through the default tilt path
// (low-pass, no dead zone), and also without a filter, with filter shifts 1–5 and
// (ramped) dead zones of 10–40 mg.

/// Tilt gain: milli-g per pitch/s of speed error.
const KV: i64 = 12;
/// Position gain of an approach, 1/s: the speed wanted `d` before a stop is `K_POS·d`.
const K_POS: i64 = 5;
/// Top speed along a straight run, pitch/s (q12): 6 pitch/s = 72 mm/s.
const V_MAX: i64 = 6 * ONE;
/// Least speed over a gap (a short tile without floor), pitch/s (q12): a marble
/// much slower than about 4 pitch/s drops into the 2 mm slot and stays there.
const V_GAP: i64 = 6 * ONE;
/// Added to a non-zero tilt on top of what rolling resistance takes
/// (see [`step_mg`]), mg: a small relay step that makes the loop brake and correct
/// sooner than the tilt path's low-pass lag alone allows (without it the marble
/// overshoots corner's first run into the end wall: 334 frames instead of 241).
const STEP_MG: i64 = 10;
/// The tilt over which the step ([`STEP_MG`] plus the resistance) ramps in (avoids
/// chatter around zero).
const COMP_RAMP_MG: i64 = 4;
/// Below this speed (pitch/s, q12) a marble asked to move counts as stalled…
const V_STALL: i64 = ONE / 4;
/// …and gets up to this much extra tilt, 1 mg more per frame, mg.
const BOOST_MAX_MG: i64 = 120;
/// Frames without getting nearer the goal before the gains change (3 s).
const PATIENCE_FRAMES: u16 = 384;
/// The most the tilt changes from one frame to the next, mg: a brisk hand (1.3 g/s
/// at 128 frames/s). With `board_motion`, much faster tilting makes the board itself
/// throw the marbles (without a tilt filter, 16 mg per frame already does).
const SLEW_MG: i32 = 10;
/// A new straight run starts once the marble is this close to its centre line…
const ALIGN_POS: i64 = ONE * 15 / 100;
/// …and moves across it slower than this (pitch/s, q12).
const ALIGN_VEL: i64 = ONE * 6 / 10;

impl Autopilot {
    /// The accelerometer reading (board frame, milli-g) the autopilot wants for the
    /// next frame: a tilt of magnitude 1 g, `x` and `z` within
    /// ±[`Autopilot::TILT_LIMIT_MG`] (±[`Autopilot::ESCAPE_TILT_MG`] while lifting
    /// the marble out of a gap), changing by at most 10 mg a frame. A reading with
    /// `x < 0` rolls the marble towards +x'. Feed it through the tilt path.
    ///
    /// Call it once per frame (it keeps the last tilt and follows the marble's
    /// progress), with an attempt at the level the autopilot was made for.
    pub fn reading_mg<S: Scalar>(&mut self, game: &Game<'_, S>) -> AccelMg {
        let [gx, gz] = self.gravity_in_plane(game);
        let gx = gx.clamp(self.last[0] as i32 - SLEW_MG, self.last[0] as i32 + SLEW_MG);
        let gz = gz.clamp(self.last[1] as i32 - SLEW_MG, self.last[1] as i32 + SLEW_MG);
        self.last = [gx as i16, gz as i16];
        // The rest of 1 g on the board's normal, as the keys' tilt makes it
        // (|x|, |z| ≤ 450 mg: within the 1 g its clamp allows).
        AccelMg::from_xz(-gx, -gz)
    }

    /// The in-plane gravity `[x', z']` (milli-g) the autopilot wants.
    fn gravity_in_plane<S: Scalar>(&mut self, game: &Game<'_, S>) -> [i32; 2] {
        let level = game.level();
        let tiles = &level.tiles;
        let s = to_q(game.world().params().layout.s);
        let marbles = game.world().marbles();
        let Some(m) = marbles.get(self.marble as usize).filter(|m| !m.out) else {
            return [0, 0];
        };
        let layout = &game.world().params().layout;
        let me = MarbleQ::new(m, layout, s, self);
        // How fast it really moved since the last frame (q12 pitch/s): a marble
        // pressed into a wall or a post may keep a velocity it cannot follow.
        let frame_log2 = game.config().frame_log2;
        let moved = [0, 1].map(|a| (me.pos[a] - self.last_pos[a] as i64).abs() << frame_log2);
        self.last_pos = me.pos.map(|p| p as i32);
        let k = self.progress(level, me.cell);
        let mut limit = Self::TILT_LIMIT_MG as i64;
        let mut cmd = [0i64; 2];
        if let Some((a, sign)) = self
            .in_gap(tiles, &me, s)
            .filter(|&(a, _)| moved[a] < V_GAP / 4)
        {
            // Stopped in a gap: only a steep tilt lifts the marble out.
            limit = Self::ESCAPE_TILT_MG as i64;
            cmd[a] = sign * limit;
            cmd[1 - a] = k.hold(me.centre[1 - a] - me.pos[1 - a], me.vel[1 - a]);
        } else if let Some(dir) = self.step_towards_goal(tiles, me.cell) {
            let along = if matches!(dir, Dir::Left | Dir::Right) {
                0
            } else {
                1
            };
            let across = 1 - along;
            // The end of the straight run (a corner or a goal), and whether it crosses
            // a gap the marble has not crossed yet.
            let (dx, dz) = dir.delta();
            let sign: i64 = if dx + dz > 0 { 1 } else { -1 };
            let cy = me.cell[2];
            let (mut ex, mut ez) = (me.cell[0], me.cell[1]);
            let mut gap = self.gap_ahead(tiles, [ex - dx, ez - dz, cy], dir, s, me.pos[along]);
            loop {
                gap = gap || self.gap_ahead(tiles, [ex, ez, cy], dir, s, me.pos[along]);
                ex += dx;
                ez += dz;
                let e = [ex, ez, cy];
                if is_goal(level, e) || self.step_towards_goal(tiles, e) != Some(dir) {
                    break;
                }
            }
            // Across: onto the corridor's centre line.
            let e_across = me.centre[across] - me.pos[across];
            cmd[across] = k.hold(e_across, me.vel[across]);
            let aligned = e_across.abs() <= ALIGN_POS && me.vel[across].abs() <= ALIGN_VEL;
            let (pos, vel) = (me.pos[along], me.vel[along]);
            cmd[along] = if !aligned {
                k.hold(me.centre[along] - pos, vel)
            } else {
                let mut want = if is_goal(level, [ex, ez, cy]) {
                    sign * k.v_max
                } else {
                    k.approach_speed([centre(ex, s), centre(ez, s)][along] - pos)
                };
                // Cross a gap briskly: a slow marble drops into the slot and stays.
                if gap && sign * want < V_GAP {
                    want = sign * V_GAP;
                }
                k.tilt(k.kv * (want - vel))
            };
        } else {
            // In a goal already, or nowhere to go: stay in the cell.
            cmd = [0, 1].map(|a| k.hold(me.centre[a] - me.pos[a], me.vel[a]));
        }
        // A marble asked to move that does not (a dead zone in the tilt path, or more
        // resistance than planned for): lean in a little more each frame.
        for a in 0..2 {
            let sign: i64 = if cmd[a] > 0 { 1 } else { -1 };
            let b = self.boost[a] as i64;
            self.boost[a] = if cmd[a].abs() >= k.comp + COMP_RAMP_MG && moved[a] < V_STALL {
                (b + 1).min(BOOST_MAX_MG)
            } else {
                b - (b + 7) / 8
            } as i16;
            cmd[a] += sign * self.boost[a] as i64;
        }
        // Guard every marble against a hole (or an open edge) next to it: towards
        // one, tilt no more than what brings that marble to rest in its cell's centre
        // (which brakes one already rolling that way).
        for (n, m) in marbles.iter().enumerate().filter(|(_, m)| !m.out) {
            // The steered marble's was made above.
            let q = if n == self.marble as usize {
                me
            } else {
                MarbleQ::new(m, layout, s, self)
            };
            for dir in Dir::ALL {
                let (dx, dz) = dir.delta();
                if connected(tiles, q.cell, dir)
                    && is_pit(tiles, [q.cell[0] + dx, q.cell[1] + dz, q.cell[2]])
                {
                    let (a, toward) = if dx != 0 {
                        (0, dx as i64)
                    } else {
                        (1, dz as i64)
                    };
                    let h = Gains::at(0, k.comp).hold(q.centre[a] - q.pos[a], q.vel[a]);
                    if toward * cmd[a] > toward * h {
                        cmd[a] = h;
                    }
                }
            }
        }
        cmd.map(|c| c.clamp(-limit, limit) as i32)
    }

    /// Whether the marble's centre is over a gap (a short tile without floor between
    /// two cells): the axis across the gap and the way out, towards the side nearer
    /// the goal.
    fn in_gap(&self, tiles: &Tiles, me: &MarbleQ, s: i64) -> Option<(usize, i64)> {
        // The tile under the centre (eq. 6 in q12).
        let tile = |p: i64| (2 * (p >> Q) + ((p & (ONE - 1)) >= s) as i64) as i32;
        let (i, k, cy) = (tile(me.pos[0]), tile(me.pos[1]), me.cell[2]);
        if solid(tiles, i, 2 * cy, k)
            || solid(tiles, i, 2 * cy + 1, k)
            || (i % 2 == 1) == (k % 2 == 1)
        {
            return None;
        }
        // The two cells the gap joins: along x' for an even column, else along z'.
        let a = if i % 2 == 0 { 0 } else { 1 };
        let lo = [(i - 1).div_euclid(2), (k - 1).div_euclid(2)];
        let hi = if a == 0 {
            [lo[0] + 1, lo[1]]
        } else {
            [lo[0], lo[1] + 1]
        };
        let (cl, ch) = (self.code([lo[0], lo[1], cy]), self.code([hi[0], hi[1], cy]));
        // Towards the cell one step nearer the goal; towards the reachable one when
        // only one is.
        let up = if cl == 0 || ch == 0 {
            ch != 0
        } else {
            cl == ch % 3 + 1
        };
        Some((a, if up { 1 } else { -1 }))
    }

    /// Follows the steered marble's distance to the goal from cell to cell and
    /// returns the gains to use: gentler ones, in turn, while it makes no progress
    /// (a tilt path with more lag than planned for makes the marble overshoot and
    /// oscillate; slower approaches settle).
    fn progress(&mut self, level: &LevelView, cell: [i32; 3]) -> Gains {
        let new = [cell[0] as u8, cell[1] as u8, cell[2] as u8];
        if self.cell == [u8::MAX; 3] {
            // The first frame (the autopilot may take over a game in progress).
            self.dist = self.cells_to_goal(level, cell).unwrap_or(u16::MAX);
            self.best = self.dist;
            self.cell = new;
        } else if new != self.cell {
            let (a, b) = (self.code(self.cell.map(i32::from)), self.code(cell));
            if a == 0 || self.dist == u16::MAX {
                // From a cell off the planned ways: count afresh.
                self.dist = self.cells_to_goal(level, cell).unwrap_or(u16::MAX);
            } else if b != 0 {
                if b == a % 3 + 1 {
                    self.dist = self.dist.saturating_add(1);
                } else if a == b % 3 + 1 {
                    self.dist = self.dist.saturating_sub(1);
                }
            }
            self.cell = new;
        }
        if self.dist < self.best {
            self.best = self.dist;
            self.stalled = 0;
        } else {
            self.stalled = self.stalled.saturating_add(1);
        }
        Gains::at(
            (self.stalled / PATIENCE_FRAMES) % 3,
            step_mg(&level.info.spec),
        )
    }

    /// Whether there is a gap between cell `(cx, cz)` and its neighbour `dir` whose
    /// far edge the marble at `pos` (along `dir`'s axis, q12) has not passed.
    fn gap_ahead(&self, tiles: &Tiles, c: [i32; 3], dir: Dir, s: i64, pos: i64) -> bool {
        let (dx, dz) = dir.delta();
        let (i, k, j) = (2 * c[0] + 1 + dx, 2 * c[1] + 1 + dz, 2 * c[2]);
        if !self.inside(c) || solid(tiles, i, j, k) || solid(tiles, i, j + 1, k) {
            return false;
        }
        let lo = ((if dx != 0 { i } else { k } / 2) as i64) << Q;
        if dx + dz > 0 {
            pos < lo + s
        } else {
            pos >= lo
        }
    }
}

/// A marble's state in the controller's integers.
#[derive(Clone, Copy)]
struct MarbleQ {
    /// Position `[x', z']`, pitch (q12).
    pos: [i64; 2],
    /// Velocity, pitch/s (q12).
    vel: [i64; 2],
    /// The cell nearest the centre (cell coordinates, clamped to the grid) and
    /// the storey it is on.
    cell: [i32; 3],
    /// That cell's centre (q12).
    centre: [i64; 2],
}

impl MarbleQ {
    fn new<S: Scalar>(m: &Marble<S>, layout: &TileLayout<S>, s: i64, ap: &Autopilot) -> Self {
        let pos = [to_q(m.pos.x), to_q(m.pos.z)];
        let vel = [to_q(m.vel.x), to_q(m.vel.z)];
        // Cell n's centre is n + (1 + s)/2; the boundary between n and n + 1 lies at
        // n + 1 + s/2, halfway between the centres.
        let cell_of = |p: i64, n: u8| (((p - s / 2) >> Q) as i32).min(n as i32 - 1).max(0);
        let storey = if STOREYS {
            layout.storey_of(m.pos.y).min(ap.storeys() - 1).max(0)
        } else {
            0
        };
        let cell = [cell_of(pos[0], ap.ncx), cell_of(pos[1], ap.ncz), storey];
        MarbleQ {
            pos,
            vel,
            cell,
            centre: [centre(cell[0], s), centre(cell[1], s)],
        }
    }
}

/// The centre of cell `n` along an axis (q12), for a short width `s` (q12).
fn centre(n: i32, s: i64) -> i64 {
    ((n as i64) << Q) + (ONE + s) / 2
}

/// The loop gains at one patience level (see [`Autopilot::progress`]).
struct Gains {
    /// mg per pitch/s (q12 input).
    kv: i64,
    /// Approach speed per distance, 1/s, ×4.
    k_pos4: i64,
    /// Top speed (q12).
    v_max: i64,
    /// Added to a non-zero tilt, mg ([`step_mg`]).
    comp: i64,
}

impl Gains {
    fn at(level: u16, comp: i64) -> Gains {
        let (kv, kp, vm) = match level {
            0 => (4, 4, 4),
            1 => (3, 2, 2),
            _ => (2, 1, 1),
        };
        Gains {
            kv: KV * kv / 4,
            k_pos4: K_POS * kp,
            v_max: V_MAX * vm / 4,
            comp,
        }
    }

    /// The tilt that brings the marble to rest `e` ahead (q12 pitch) at speed `v`.
    fn hold(&self, e: i64, v: i64) -> i64 {
        self.tilt(self.kv * (self.approach_speed(e) - v))
    }

    /// The speed wanted `e` before a stop (signed like `e`): `K_POS·e`, at most
    /// the top speed.
    fn approach_speed(&self, e: i64) -> i64 {
        let v = (self.k_pos4 * e.abs() / 4).min(self.v_max);
        if e < 0 {
            -v
        } else {
            v
        }
    }

    /// A raw tilt `KV·Δv` (mg · 2^Q) → mg, with the step [`Gains::comp`] ramped in
    /// over the first [`COMP_RAMP_MG`].
    fn tilt(&self, raw_q: i64) -> i64 {
        let raw = raw_q >> Q;
        let step = (raw.abs() * self.comp / COMP_RAMP_MG).min(self.comp);
        if raw < 0 {
            raw - step
        } else {
            raw + step
        }
    }
}

/// The step added to a non-zero tilt on a level's board, mg: [`STEP_MG`] plus what
/// balances rolling resistance — with `friction`, a marble keeps rolling (or starts)
/// only while the in-plane pull is over `c_rr·g_n` (≈ `c_rr` · 1000 mg near level;
/// see [`crate::physics::dynamics::effects::Drag`]), rounded up.
fn step_mg(spec: &PhysicsSpec) -> i64 {
    let resistance = if spec.effects.friction {
        (spec.rolling_resistance_ppm as i64 + 999) / 1000
    } else {
        0
    };
    STEP_MG + resistance
}

/// A [`Scalar`] as a q12 integer, exactly rounded down: the integer part by the
/// scalar's own floor, the fraction six bits at a time (no float, no overflow in
/// the narrowest format).
fn to_q<S: Scalar>(v: S) -> i64 {
    let n = v.floor_int();
    let mut f = v - S::from_int(n);
    let mut q = n as i64;
    for _ in 0..Q / 6 {
        f = f.shl(6);
        let b = f.floor_int().clamp(0, 63);
        f -= S::from_int(b);
        q = (q << 6) + b as i64;
    }
    q
}
