//! Our engine on the host: accuracy runs (instrumented) and timing runs (plain).

use std::time::Instant;

use marble_rolling::physics::{Effects, Scalar, StepStats, TileIndex, World};
use marble_rolling::study::{
    drive, run_plain, steps, with_backend, Job, Scene, SceneId, Trace, FRAME_LOG2,
};

/// Standard gravity per milli-g, mm/s².
pub const MM_S2_PER_MG: f64 = 9.806_65;

/// What one run did, in millimetres and seconds.
#[derive(Clone, Debug, Default)]
pub struct Outcome {
    /// Position (x', z') after 1 s, mm.
    pub pos1: [f64; 2],
    /// Position after 10 s, mm.
    pub pos10: [f64; 2],
    /// Mechanical energy per unit mass at the end (mm²/s²), see [`energy`].
    pub energy_end: f64,
    /// The largest kinetic energy per unit mass seen (mm²/s²).
    pub ke_max: f64,
    /// The deepest overlap of the marble with a solid tile, µm (0: none).
    pub max_pen_um: f64,
    /// Marble–tile contacts resolved (our engine) or contact-steps (a peer).
    pub contacts: u64,
    /// Bounces.
    pub collisions: u64,
    /// Reverted steps (ours; must be 0).
    pub reverts: u64,
    /// Steps that ended with a velocity axis at the speed cap (ours): the step
    /// bound changed the physics.
    pub cap_hits: u64,
    /// Whether the marble left the board.
    pub out: bool,
    /// `World::state_hash` at the end (ours).
    pub hash: u64,
    /// Steps taken.
    pub steps: u32,
    /// Step counters (ours).
    pub stats: StepStats,
    /// Position (mm) at every frame boundary (128 per second), the start included.
    pub track: Vec<[f64; 2]>,
}

/// `½·c·v² − g·p` per unit mass (mm²/s²), `c = 7/5` when the marble rolls (its
/// spin's energy), `g` the tangential gravity of the tilt in force at the end.
pub fn energy(rolling: bool, g_mg: [i32; 3], pos_mm: [f64; 2], vel_mm_s: [f64; 2]) -> (f64, f64) {
    let c = if rolling { 1.4 } else { 1.0 };
    let ke = 0.5 * c * (vel_mm_s[0] * vel_mm_s[0] + vel_mm_s[1] * vel_mm_s[1]);
    let pe = -MM_S2_PER_MG * (g_mg[0] as f64 * pos_mm[0] + g_mg[2] as f64 * pos_mm[1]);
    (ke + pe, ke)
}

/// The clearance (pitch) between the marble's centre and the nearest solid wall
/// tile around it (and the floor in 3-D), minus the radius: negative = overlap.
pub fn overlap<S: Scalar>(w: &World<'static, S, 1>) -> f64 {
    let m = w.marbles()[0];
    let p = w.params();
    let r = p.radius.to_f64();
    let c = m.pos.to_f64();
    let (i0, i1) = (
        p.layout.index_xz(m.pos.x - p.radius) - 1,
        p.layout.index_xz(m.pos.x + p.radius) + 1,
    );
    let (k0, k1) = (
        p.layout.index_xz(m.pos.z - p.radius) - 1,
        p.layout.index_xz(m.pos.z + p.radius) + 1,
    );
    let layers: &[i32] = if p.spec.effects.holes { &[0, 1] } else { &[1] };
    let mut best = f64::INFINITY;
    for &j in layers {
        for k in k0..=k1 {
            for i in i0..=i1 {
                let t = TileIndex::new(i, j, k);
                if !w.tiles().is_solid(t) {
                    continue;
                }
                let b = p.layout.tile_box(t);
                let (lo, hi) = (b.min.to_f64(), b.max.to_f64());
                let mut d2 = 0.0;
                for a in [0, 1, 2] {
                    if a == 1 && j == 1 && !p.spec.effects.holes {
                        continue; // the plane: the marble is beside the wall, at any height
                    }
                    let v = if c[a] < lo[a] {
                        lo[a] - c[a]
                    } else if c[a] > hi[a] {
                        c[a] - hi[a]
                    } else {
                        0.0
                    };
                    d2 += v * v;
                }
                best = best.min(d2.sqrt());
            }
        }
    }
    best - r
}

struct Measure {
    scene: Scene,
    step_log2: u32,
    effects: Effects,
}

impl Job for Measure {
    type Output = Option<Outcome>;
    fn run<S: Scalar>(self) -> Option<Outcome> {
        let scene = self.scene;
        let mut w = scene.world::<S>(self.step_log2, self.effects).ok()?;
        let layout = w.params().layout;
        let mm = |v: S| layout.to_mm(v);
        let rolling = self.effects.rolling;
        // Steps per simulated second and per frame: events step once a frame.
        let k = w.params().k;
        let one = 1u32 << k;
        let pitch_mm = layout.pitch_um as f64 / 1000.0;
        let mut out = Outcome::default();
        let mut min_gap = f64::INFINITY;
        let mut cap_hits = 0u64;
        let trace: Trace = scene.trace;
        let frame_mask = (1u32 << (k - FRAME_LOG2)) - 1;
        let m0 = w.marbles()[0];
        out.track.push([mm(m0.pos.x), mm(m0.pos.z)]);
        drive(&mut w, &trace, 0, steps(self.step_log2), |w, n| {
            let m = w.marbles()[0];
            if n & frame_mask == 0 {
                out.track.push([mm(m.pos.x), mm(m.pos.z)]);
            }
            min_gap = min_gap.min(overlap(w));
            let cap = w.params().v_max;
            if m.vel.x.abs() >= cap || m.vel.z.abs() >= cap {
                cap_hits += 1;
            }
            let v = [mm(m.vel.x), mm(m.vel.z)];
            let ke = 0.5 * if rolling { 1.4 } else { 1.0 } * (v[0] * v[0] + v[1] * v[1]);
            out.ke_max = out.ke_max.max(ke);
            if n == one {
                out.pos1 = [mm(m.pos.x), mm(m.pos.z)];
            }
        });
        let m = w.marbles()[0];
        out.pos10 = [mm(m.pos.x), mm(m.pos.z)];
        out.energy_end = energy(
            rolling,
            w.gravity_mg(),
            out.pos10,
            [mm(m.vel.x), mm(m.vel.z)],
        )
        .0;
        out.max_pen_um = (-min_gap).max(0.0) * pitch_mm * 1000.0;
        out.contacts = w.stats.contacts as u64;
        out.collisions = w.stats.collisions as u64;
        out.reverts = w.stats.reverts as u64;
        out.cap_hits = cap_hits;
        out.out = m.out;
        out.hash = w.state_hash();
        out.steps = w.stats.steps;
        out.stats = w.stats;
        Some(out)
    }
}

/// An instrumented run of `scene` with backend `backend` at `2^step_log2` steps/s
/// ([`marble_rolling::study::EVENTS_LOG2`]: event stepping, a step per frame).
pub fn measure(
    scene: SceneId,
    backend: usize,
    step_log2: u32,
    effects: Option<Effects>,
) -> Option<Outcome> {
    let scene = Scene::get(scene);
    let effects = effects.unwrap_or(scene.spec.effects);
    with_backend(
        backend,
        Measure {
            scene,
            step_log2,
            effects,
        },
    )?
}

/// Host time per step: the minimum and the median over repeated whole runs.
#[derive(Clone, Copy, Debug, Default)]
pub struct Timing {
    /// Fastest run, ns/step.
    pub min_ns: f64,
    /// Median run, ns/step.
    pub median_ns: f64,
    /// Runs timed.
    pub runs: usize,
}

/// Times `run` (one whole scene run of `steps` steps, set up by `prepare`): one
/// warm-up, then repeats until `reps` runs and at least `min_total_s` seconds.
pub fn time_runs<W>(
    steps: u32,
    reps: usize,
    min_total_s: f64,
    mut prepare: impl FnMut() -> W,
    mut run: impl FnMut(&mut W),
) -> Timing {
    let mut w = prepare();
    run(&mut w);
    let mut samples = Vec::new();
    let start = Instant::now();
    while samples.len() < reps
        || (start.elapsed().as_secs_f64() < min_total_s && samples.len() < 200)
    {
        let mut w = prepare();
        let t = Instant::now();
        run(&mut w);
        let dt = t.elapsed().as_secs_f64();
        std::hint::black_box(&mut w);
        samples.push(dt * 1e9 / steps as f64);
    }
    samples.sort_by(|a, b| a.total_cmp(b));
    Timing {
        min_ns: samples[0],
        median_ns: samples[samples.len() / 2],
        runs: samples.len(),
    }
}

struct Time {
    scene: Scene,
    step_log2: u32,
    effects: Effects,
    reps: usize,
    min_total_s: f64,
}

impl Job for Time {
    type Output = Option<Timing>;
    fn run<S: Scalar>(self) -> Option<Timing> {
        let w0 = self.scene.world::<S>(self.step_log2, self.effects).ok()?;
        let trace = self.scene.trace;
        Some(time_runs(
            steps(self.step_log2),
            self.reps,
            self.min_total_s,
            || w0.clone(),
            |w| run_plain(w, &trace),
        ))
    }
}

/// Host time per step of a plain (unobserved) run.
pub fn time(
    scene: SceneId,
    backend: usize,
    step_log2: u32,
    effects: Option<Effects>,
    reps: usize,
    min_total_s: f64,
) -> Option<Timing> {
    let scene = Scene::get(scene);
    let effects = effects.unwrap_or(scene.spec.effects);
    with_backend(
        backend,
        Time {
            scene,
            step_log2,
            effects,
            reps,
            min_total_s,
        },
    )?
}

struct Plain {
    scene: Scene,
    step_log2: u32,
    effects: Effects,
}

impl Job for Plain {
    type Output = Option<u64>;
    fn run<S: Scalar>(self) -> Option<u64> {
        let mut w = self.scene.world::<S>(self.step_log2, self.effects).ok()?;
        run_plain(&mut w, &self.scene.trace);
        Some(w.state_hash())
    }
}

/// One plain run (what callgrind counts): returns the end state's hash.
pub fn plain(
    scene: SceneId,
    backend: usize,
    step_log2: u32,
    effects: Option<Effects>,
) -> Option<u64> {
    let scene = Scene::get(scene);
    let effects = effects.unwrap_or(scene.spec.effects);
    with_backend(
        backend,
        Plain {
            scene,
            step_log2,
            effects,
        },
    )?
}
