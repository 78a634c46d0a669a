//! The accuracy/cost study's fixed scene suite (`cargo accuracy`, docs/accuracy.md).
//!
//! Everything here is `no_std` and allocation-free, so that the host study
//! (`src/bin/accuracy.rs`) and the target benchmarks (`src/bin/bench.rs` on QEMU's
//! Cortex-M4F, `src/bin/bench_m0.rs` on QEMU's Cortex-M0) step *the same* scenes
//! with *the same* code: the instruction counts measured on the target belong to
//! the very trajectories whose accuracy the host measures (the state hashes
//! printed on both sides must agree).
//!
//! A scene is a board, a start cell, the effects it needs and a tilt trace. The
//! trace is a deterministic function of the frame number (128 frames/s, the
//! firmware's frame rate): the gravity is set once per frame, as the firmware's
//! tilt path does, and the physics takes `2^(k-7)` steps per frame at `2^k`
//! steps/s. No autopilot: its decisions would diverge between backends.

mod bench;

pub use bench::{bench_one, bench_one_in, bench_plan, BenchItem, BenchResult};

use crate::game::levels::by_name;
use crate::game::rules::cell_centre;
use crate::physics::geometry::grid::{words_for, TileGrid, Tiles, MAX_TILES_XZ};
use crate::physics::{
    BoardMotion, Effects, MicroF32, Params, PhysicsSpec, Scalar, SetupError, Stepping, Vec3, World,
};

/// `log2` of the frame rate at which the tilt trace changes (128 Hz).
pub const FRAME_LOG2: u32 = 7;
/// Step rates studied: `2^7 ..= 2^12` steps/s (128 Hz frames × 1 … 32 substeps).
pub const STEP_LOG2: [u32; 6] = [7, 8, 9, 10, 11, 12];
/// The firmware default: 1024 steps/s.
pub const DEFAULT_STEP_LOG2: u32 = 10;
/// Event stepping ([`Stepping::Events`]) where a `step_log2` or a rate mask's bit
/// is asked for: `0` (bit 0), a rate no fixed step runs at. Its steps are the
/// frames themselves (`2^FRAME_LOG2` per second), each flown event by event.
pub const EVENTS_LOG2: u32 = 0;
/// The configurations studied: events, then the fixed step rates.
pub const STEPPINGS: [u32; 7] = [EVENTS_LOG2, 7, 8, 9, 10, 11, 12];
/// The reference run's rate: 2^14 steps/s (in `f64`).
pub const REFERENCE_STEP_LOG2: u32 = 14;
/// Simulated seconds per scene.
pub const SECONDS: u32 = 10;

/// Scalar backends, by [`Scalar::NAME`], the firmware default first.
pub const BACKENDS: [&str; 6] = ["i8f24", "i16f16", "i32f32", "f32", "f32-micromath", "f64"];

/// A computation generic over the scalar, run by [`with_backend`].
pub trait Job {
    /// What it returns.
    type Output;
    /// Runs it with scalar `S`.
    fn run<S: Scalar>(self) -> Self::Output;
}

/// Every backend, as a mask for [`with_backend_in`].
pub(crate) const ALL_BACKENDS: u32 = (1 << BACKENDS.len()) - 1;

/// Runs `job` with backend number `index` of [`BACKENDS`] (`None` if out of range).
pub fn with_backend<J: Job>(index: usize, job: J) -> Option<J::Output> {
    with_backend_in::<ALL_BACKENDS, J>(index, job)
}

/// [`with_backend`] compiled for the backends in `MASK` only (bit `n` for
/// [`BACKENDS`]`[n]`; `None` for the others): a benchmark whose flash cannot hold
/// the code of every backend leaves the rest out of its binary.
pub(crate) fn with_backend_in<const MASK: u32, J: Job>(index: usize, job: J) -> Option<J::Output> {
    let has = |n: u32| MASK & (1 << n) != 0;
    Some(match index {
        0 if has(0) => job.run::<fixed::types::I8F24>(),
        1 if has(1) => job.run::<fixed::types::I16F16>(),
        2 if has(2) => job.run::<fixed::types::I32F32>(),
        3 if has(3) => job.run::<f32>(),
        4 if has(4) => job.run::<MicroF32>(),
        5 if has(5) => job.run::<f64>(),
        _ => return None,
    })
}

const BIG: usize = words_for(MAX_TILES_XZ, 2, MAX_TILES_XZ);
const SMALL: usize = words_for(25, 2, 25);

const fn grid_or_panic<const W: usize>(nx: usize, nz: usize) -> TileGrid<W> {
    match TileGrid::new(nx, 2, nz) {
        Ok(g) => g,
        Err(_) => panic!("study grid does not fit"),
    }
}

/// A floor of `nx × nz` tiles, with a wall ring when `walls`.
const fn board<const W: usize>(nx: usize, nz: usize, walls: bool) -> TileGrid<W> {
    let mut g = grid_or_panic::<W>(nx, nz);
    let mut k = 0;
    while k < nz {
        let mut i = 0;
        while i < nx {
            g.set(i, 0, k, true);
            if walls && (i == 0 || k == 0 || i == nx - 1 || k == nz - 1) {
                g.set(i, 1, k, true);
            }
            i += 1;
        }
        k += 1;
    }
    g
}

/// The largest open floor the format allows: 127 × 127 tiles, no walls.
static OPEN_FLOOR: TileGrid<BIG> = board(MAX_TILES_XZ, MAX_TILES_XZ, false);
/// A closed corridor, one cell wide and 25 cells long (300 mm).
static CORRIDOR: TileGrid<SMALL> = board(51, 3, true);
/// A closed box of 3 × 3 cells.
static BOX: TileGrid<SMALL> = board(7, 7, true);

const MAIN: i32 = 30;
const WOBBLE: i32 = 45;
/// The switchback's wobble period (frames).
const WOBBLE_PERIOD: usize = 160;

/// `frame % WOBBLE_PERIOD`, on the Cortex-M0 without a division below 2¹⁶
/// frames: the quotient by a product and a shift
/// (`wobble_phase_is_the_remainder`). The M0 has no divide instruction, nor a
/// 64-bit product to divide by a constant with, and the library's routine took
/// 87 of its instructions a frame of the harness's own, counted in the physics'
/// figure (elsewhere the operator is that product already, 4 instructions
/// fewer than this).
#[inline]
fn wobble_phase(frame: u32) -> usize {
    const M0: bool = cfg!(all(target_arch = "arm", not(target_has_atomic = "32")));
    if M0 && frame < 1 << 16 {
        let q = (frame * 52_429) >> 23;
        (frame - q * WOBBLE_PERIOD as u32) as usize
    } else {
        frame as usize % WOBBLE_PERIOD
    }
}

/// The switchback's wobble frame by frame within its period: `(x', z')` milli-g.
/// A table, so that the harness's own sums (a remainder, a signed division by
/// 40 and one by 4: 43 Cortex-M4 instructions a frame) do not weigh on the
/// physics' per-step figures it measures: a remainder and a load instead.
static WOBBLES: [(i8, i8); WOBBLE_PERIOD] = {
    let mut table = [(0i8, 0i8); WOBBLE_PERIOD];
    let mut phase = 0;
    while phase < WOBBLE_PERIOD {
        let p = phase as i32;
        let tri = if p < 80 { p - 40 } else { 120 - p };
        let wobble = tri * WOBBLE / 40;
        table[phase] = (wobble as i8, (20 - wobble / 4) as i8);
        phase += 1;
    }
    table
};

/// How the tilt evolves (milli-g, tile frame; `y` is always −1000).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Trace {
    /// A constant tilt.
    Constant {
        /// Along x'.
        gx: i32,
        /// Along z'.
        gz: i32,
    },
    /// `±gx` along x', flipping every `half_period` frames, and a constant `gz`.
    Alternate {
        /// Magnitude along x'.
        gx: i32,
        /// Along z' (presses the marble against a side wall).
        gz: i32,
        /// Frames between flips.
        half_period: u32,
    },
    /// The switchback run: a wall-following tilt (30 mg +x', −x', +x' along the
    /// three rows, about 20 mg +z' so the marble drops through each row's opening
    /// at its end) with a ±45 mg triangle-wave wobble that rocks it back and forth,
    /// as a hand would.
    Switchback,
}

impl Trace {
    /// The gravity for frame `frame` (milli-g, tile frame).
    #[inline]
    pub fn gravity_mg(&self, frame: u32) -> [i32; 3] {
        let (gx, gz) = match *self {
            Trace::Constant { gx, gz } => (gx, gz),
            Trace::Alternate {
                gx,
                gz,
                half_period,
            } => {
                if (frame / half_period.max(1)).is_multiple_of(2) {
                    (gx, gz)
                } else {
                    (-gx, gz)
                }
            }
            Trace::Switchback => {
                let t = frame;
                // Rows: 0–3.5 s +x', 3.5–7 s −x', then +x' to the goal.
                let dir = if t < 7 * 64 {
                    1
                } else if t < 14 * 64 {
                    -1
                } else {
                    1
                };
                // Triangle wobble of ±WOBBLE mg, period 160 frames (1.25 s), on x'
                // (it rocks the marble back along the row) and, a quarter of it
                // against 20 mg, on z' (`WOBBLES`).
                let (wx, gz) = WOBBLES[wobble_phase(t)];
                (dir * MAIN + i32::from(wx), i32::from(gz))
            }
        };
        [gx, -1000, gz]
    }
}

/// Which scene (the board and start; see [`Scene`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum SceneId {
    /// Free rolling down a constant 2 mg × 2 mg incline on the 127 × 127 open
    /// floor: analytic `x(t) = x₀ + ½·(5/7)·g·sinθ·t²`, 58 pitches in 10 s, below
    /// the 64 pitch/s speed cap.
    Incline,
    /// Bouncing between the end walls of a closed 25-cell corridor (e = 0.5), the
    /// 20 mg tilt along it flipping every 2.5 s, 10 mg pressing it against a side
    /// wall: always moving, up to 24 pitch/s.
    Bounce,
    /// The built-in level `switchback` (rolling + friction, no holes: a flat maze)
    /// under a scripted tilt trace.
    Maze,
    /// Resting in a corner of a closed 3 × 3-cell box under a strong diagonal tilt:
    /// analytic rest position `r` from both walls.
    Corner,
}

/// A scene of the suite.
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    /// Which one.
    pub id: SceneId,
    /// Short name (reports, target logs).
    pub name: &'static str,
    /// The board.
    pub tiles: Tiles<'static>,
    /// Physics parameters (the step rate is set per run).
    pub spec: PhysicsSpec,
    /// Start cell `(i, k)` (both odd).
    pub start: (u8, u8),
    /// The tilt.
    pub trace: Trace,
}

impl Scene {
    /// The scene `id`.
    pub fn get(id: SceneId) -> Scene {
        let rolling = Effects {
            rolling: true,
            ..Effects::NONE
        };
        let spec = PhysicsSpec {
            effects: rolling,
            ..PhysicsSpec::DEFAULT
        };
        match id {
            SceneId::Incline => Scene {
                id,
                name: "incline",
                tiles: OPEN_FLOOR.view(),
                spec,
                start: (1, 1),
                trace: Trace::Constant { gx: 2, gz: 2 },
            },
            SceneId::Bounce => Scene {
                id,
                name: "bounce",
                tiles: CORRIDOR.view(),
                spec,
                start: (1, 1),
                trace: Trace::Alternate {
                    gx: 20,
                    gz: 10,
                    half_period: 320,
                },
            },
            SceneId::Maze => {
                let level = by_name("switchback")
                    .map(|(_, l)| l)
                    .unwrap_or(crate::game::levels::LEVELS[0]);
                let start = level
                    .info
                    .starts()
                    .first()
                    .map_or((1, 1), |start| (start.i, start.k));
                Scene {
                    id,
                    name: "maze",
                    tiles: level.tiles,
                    spec: level.info.spec,
                    start,
                    trace: Trace::Switchback,
                }
            }
            SceneId::Corner => Scene {
                id,
                name: "corner",
                tiles: BOX.view(),
                spec,
                start: (3, 3),
                trace: Trace::Constant { gx: 300, gz: 300 },
            },
        }
    }

    /// The whole suite, in report order.
    pub fn all() -> [Scene; 4] {
        [
            SceneId::Incline,
            SceneId::Bounce,
            SceneId::Maze,
            SceneId::Corner,
        ]
        .map(Scene::get)
    }

    /// The spec at `2^step_log2` steps/s with `effects`.
    /// ([`EVENTS_LOG2`]: event stepping at the frame rate).
    pub(crate) fn spec_at(&self, step_log2: u32, effects: Effects) -> PhysicsSpec {
        let (step_log2, stepping) = match step_log2 {
            EVENTS_LOG2 => (FRAME_LOG2, Stepping::Events),
            k => (k, Stepping::Fixed),
        };
        PhysicsSpec {
            step_log2,
            effects,
            stepping,
            ..self.spec
        }
    }

    /// A fresh world for this scene.
    pub fn world<S: Scalar>(
        &self,
        step_log2: u32,
        effects: Effects,
    ) -> Result<World<'static, S, 1>, SetupError> {
        let params = Params::<S>::new(self.spec_at(step_log2, effects))?;
        let start = cell_centre(&params, self.start.0, self.start.1);
        let mut w = World::new(params, self.tiles, &[start])?;
        w.set_gravity_mg(self.trace.gravity_mg(0));
        if effects.board_motion {
            // The effect's code runs every step; the board itself is held still so
            // that the trajectory stays comparable (its cost, not its physics, is
            // what the study measures with it).
            let (ex, ez) = w.extent();
            w.set_board_motion(BoardMotion {
                omega: Vec3::ZERO,
                omega_dot: Vec3::ZERO,
                pivot: Vec3::new(ex.half(), S::ZERO, ez.half()),
            });
        }
        Ok(w)
    }
}

/// Effect sets for the per-effect cost table: none, and each effect added alone
/// to the maze's own (rolling + friction), then all.
pub const EFFECT_VARIANTS: [(&str, Effects); 6] = [
    ("none", Effects::NONE),
    (
        "rolling",
        Effects {
            rolling: true,
            ..Effects::NONE
        },
    ),
    (
        "rolling+friction",
        Effects {
            rolling: true,
            friction: true,
            ..Effects::NONE
        },
    ),
    (
        "+board_motion",
        Effects {
            rolling: true,
            friction: true,
            board_motion: true,
            ..Effects::NONE
        },
    ),
    (
        "+holes",
        Effects {
            rolling: true,
            friction: true,
            holes: true,
            ..Effects::NONE
        },
    ),
    ("all", Effects::ALL),
];

/// Steps of a run of [`SECONDS`] at `2^step_log2` steps/s.
pub const fn steps(step_log2: u32) -> u32 {
    SECONDS * steps_per_second(step_log2)
}

/// Steps per simulated second of a configuration: `2^step_log2`, or the frame
/// rate for [`EVENTS_LOG2`] (an event step is a whole 1/128 s frame). Costs per
/// simulated time divide by this, never by `2^step_log2`.
pub const fn steps_per_second(step_log2: u32) -> u32 {
    match step_log2 {
        EVENTS_LOG2 => 1 << FRAME_LOG2,
        k => 1 << k,
    }
}

/// Whether a configuration's `step_log2` is event stepping ([`EVENTS_LOG2`]).
pub const fn is_events(step_log2: u32) -> bool {
    step_log2 == EVENTS_LOG2
}

/// The rates the per-effect variants run at: the firmware default and events.
pub const VARIANT_STEPPINGS: [u32; 2] = [DEFAULT_STEP_LOG2, EVENTS_LOG2];

/// Advances `w` from step `from` to step `to` (steps counted from the start of the
/// scene), setting the trace's gravity at each frame boundary when it changes, and
/// calling `each` after every step with the number of steps done.
#[inline(always)]
pub fn drive<S: Scalar>(
    w: &mut World<'static, S, 1>,
    trace: &Trace,
    from: u32,
    to: u32,
    mut each: impl FnMut(&World<'static, S, 1>, u32),
) {
    let sub = w.params().k.saturating_sub(FRAME_LOG2);
    let mask = (1u32 << sub) - 1;
    for n in from..to {
        if n & mask == 0 {
            // The world compares with the tilt it has (as the firmware's tilt
            // samples arrive): an unchanged one costs that compare only.
            w.set_gravity_mg(trace.gravity_mg(n >> sub));
        }
        w.step();
        each(w, n + 1);
    }
}

/// Runs a whole scene for [`SECONDS`] without observing it (what the benchmarks
/// time): returns the world at the end.
#[inline(never)]
pub fn run_plain<S: Scalar>(w: &mut World<'static, S, 1>, trace: &Trace) {
    let to = steps(w.params().k);
    drive(w, trace, 0, to, |_, _| {});
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Smoke(SceneId, u32);
    impl Job for Smoke {
        type Output = (u32, u32, bool);
        fn run<S: Scalar>(self) -> (u32, u32, bool) {
            let scene = Scene::get(self.0);
            let mut w = scene
                .world::<S>(self.1, scene.spec.effects)
                .expect("scene sets up");
            drive(&mut w, &scene.trace, 0, steps_per_second(self.1), |_, _| {});
            (w.stats.steps, w.stats.reverts, w.marbles()[0].out)
        }
    }

    #[test]
    fn every_scene_sets_up_and_runs_a_second_in_every_backend() {
        for scene in Scene::all() {
            for (b, name) in BACKENDS.iter().enumerate() {
                for k in [DEFAULT_STEP_LOG2, EVENTS_LOG2] {
                    let (steps, reverts, out) = with_backend(b, Smoke(scene.id, k)).unwrap();
                    assert_eq!(steps, steps_per_second(k), "{} {name} {k}", scene.name);
                    assert_eq!(reverts, 0, "{} {name} {k}", scene.name);
                    assert!(!out, "{} {name} {k}", scene.name);
                }
            }
        }
    }

    /// The switchback's table is its triangle wave: 30 mg along the rows,
    /// ±45 mg wobble on x', 20 mg less a quarter of it on z'.
    #[test]
    fn switchback_trace_is_its_wave() {
        for frame in 0..(SECONDS << FRAME_LOG2) {
            let dir = match frame {
                f if f < 7 * 64 => 1,
                f if f < 14 * 64 => -1,
                _ => 1,
            };
            let phase = (frame % 160) as i32;
            let tri = if phase < 80 { phase - 40 } else { 120 - phase };
            let wobble = tri * 45 / 40;
            let want = [dir * 30 + wobble, -1000, 20 - wobble / 4];
            assert_eq!(Trace::Switchback.gravity_mg(frame), want, "frame {frame}");
        }
    }

    #[test]
    fn wobble_phase_is_the_remainder() {
        // The M0's quotient, checked here on the host.
        for frame in 0..1u32 << 16 {
            let q = (frame * 52_429) >> 23;
            assert_eq!(frame - q * 160, frame % 160, "frame {frame}");
        }
        for frame in (0..1 << 17).chain([u32::MAX - 1, u32::MAX]) {
            assert_eq!(
                wobble_phase(frame),
                frame as usize % WOBBLE_PERIOD,
                "frame {frame}"
            );
        }
    }

    #[test]
    fn traces_are_integer_and_bounded() {
        for scene in Scene::all() {
            for frame in 0..(SECONDS << FRAME_LOG2) {
                let g = scene.trace.gravity_mg(frame);
                assert_eq!(g[1], -1000);
                assert!(
                    g[0].abs() <= 300 && g[2].abs() <= 300,
                    "{} frame {frame}: {g:?}",
                    scene.name
                );
            }
        }
        // The bench plan covers every scene × backend × stepping once, then the
        // variants.
        let mut n = 0;
        bench_plan(u32::MAX, u32::MAX, |_| n += 1);
        assert_eq!(
            n,
            4 * BACKENDS.len() * STEPPINGS.len()
                + 2 * VARIANT_STEPPINGS.len() * EFFECT_VARIANTS.len()
        );
        // Events are a configuration of their own: a frame per step.
        assert_eq!(steps(EVENTS_LOG2), SECONDS * 128);
        assert_eq!(steps_per_second(EVENTS_LOG2), 128);
        assert_eq!(steps_per_second(DEFAULT_STEP_LOG2), 1024);
    }
}
