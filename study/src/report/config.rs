//! Our configurations (scalar backend × stepping), summarised over the scenes,
//! and the choices the report makes among them.

use marble_rolling::game::rules::DEFAULT_EVENTS;
use marble_rolling::physics::{PhysicsSpec, Stepping};
use marble_rolling::study::{
    is_events, SceneId, BACKENDS, DEFAULT_STEP_LOG2, EVENTS_LOG2, FRAME_LOG2, STEPPINGS,
};

use super::super::{Engine, Study};
use super::{label, per_second, BUDGET_M0_PER_MS, BUDGET_PER_MS, TARGET_MM};

/// One of our configurations, summarised.
#[derive(Clone, Debug)]
pub struct Config {
    /// Backend index.
    pub backend: usize,
    /// log2 of the step rate ([`marble_rolling::study::EVENTS_LOG2`]: events).
    pub k: u32,
    /// Incline (free rolling) error vs the reference after 10 s, mm: the headline.
    pub roll10: f64,
    /// Incline error after 1 s.
    pub roll1: f64,
    /// Incline error vs the analytic solution after 10 s.
    pub roll_ana10: f64,
    /// Bounce scene, error after 10 s.
    pub bounce10: f64,
    /// Bounce scene, largest error over the run.
    pub bounce_max: f64,
    /// Maze, largest error over the run.
    pub maze_max: f64,
    /// Steps that ended at the speed cap, over all scenes.
    pub cap_hits: u64,
    /// Corner: distance from the analytic rest position after 10 s.
    pub corner_ana10: f64,
    /// Maze error after 10 s.
    pub maze10: f64,
    /// Largest overlap over all scenes, µm.
    pub pen_um: f64,
    /// Reverted steps or marbles lost, over all scenes.
    pub faults: u64,
    /// M4 instructions per step in the maze.
    pub m4_step: Option<f64>,
    /// M4 instructions per simulated ms in the maze.
    pub m4_ms: Option<f64>,
    /// M0 instructions per simulated ms in the maze.
    pub m0_ms: Option<f64>,
    /// Host ns per step in the maze (minimum of the runs).
    pub host_ns: f64,
    /// Host instructions per step in the maze (callgrind, default rate only).
    pub host_ir: Option<f64>,
    /// The suite error: the worst of rolling after 10 s, bounce over the run and
    /// corner rest (mm). The maze is reported, not judged: its path is sensitive
    /// to the step itself (f64 at 4096 steps/s is still 0.3 mm off the 16384 reference).
    pub suite: f64,
    /// The speed cap at this rate is the engine's full 64 pitch/s (the step
    /// bound r/4 per step does not undercut it).
    pub full_speed: bool,
    /// On the Pareto front (suite error vs cost).
    pub pareto: bool,
}

impl Config {
    /// The name, e.g. `i8f24 @ 1024` or `i8f24 @ events`.
    pub fn name(&self) -> String {
        format!("{} @ {}", BACKENDS[self.backend], label(self.k))
    }
    /// Meets the accuracy target: the suite error within [`TARGET_MM`], and sound:
    /// no revert, no lost marble, the speed cap never reached in any scene.
    pub fn accurate(&self) -> bool {
        self.suite <= TARGET_MM && self.faults == 0 && self.cap_hits == 0
    }
    /// Meets the cost budget (unknown without the target run).
    pub fn affordable(&self) -> Option<bool> {
        let m0 = self.m0_ms.is_none_or(|c| c <= BUDGET_M0_PER_MS);
        self.m4_ms.map(|c| c <= BUDGET_PER_MS && m0)
    }
    /// The cost the Pareto front and the recommendation use: M4 instructions per
    /// simulated ms, or host ns per simulated ms without a target run.
    pub fn cost(&self) -> f64 {
        self.m4_ms
            .unwrap_or(self.host_ns * per_second(self.k) / 1000.0)
    }
}

/// All of our configurations.
pub fn configs(study: &Study) -> Vec<Config> {
    let mut v = Vec::new();
    for b in 0..BACKENDS.len() {
        for k in STEPPINGS {
            let cell = |s: SceneId| study.cells.get(&(s, Engine::Ours(b), k));
            let (Some(inc), Some(bo), Some(mz), Some(co)) = (
                cell(SceneId::Incline),
                cell(SceneId::Bounce),
                cell(SceneId::Maze),
                cell(SceneId::Corner),
            ) else {
                continue;
            };
            let all = [inc, bo, mz, co];
            // Per simulated ms from simulated time: an event step is 1/128 s.
            let per_ms = |n: f64| n * per_second(k) / 1000.0;
            v.push(Config {
                backend: b,
                k,
                roll10: inc.err10,
                roll1: inc.err1,
                roll_ana10: inc.ana10.unwrap_or(f64::NAN),
                bounce10: bo.err10,
                bounce_max: bo.err_max,
                maze_max: mz.err_max,
                cap_hits: all.iter().map(|c| c.out.cap_hits).sum(),
                corner_ana10: co.ana10.unwrap_or(f64::NAN),
                maze10: mz.err10,
                pen_um: all.iter().map(|c| c.out.max_pen_um).fold(0.0, f64::max),
                faults: all.iter().map(|c| c.out.reverts + c.out.out as u64).sum(),
                m4_step: mz.m4.as_ref().map(|c| c.per_step()),
                m4_ms: mz.m4.as_ref().map(|c| per_ms(c.per_step())),
                m0_ms: mz.m0.as_ref().map(|c| per_ms(c.per_step())),
                host_ns: mz.host.min_ns,
                host_ir: mz.host_ir,
                suite: inc.err10.max(bo.err_max).max(co.ana10.unwrap_or(0.0)),
                full_speed: full_speed(k),
                pareto: false,
            });
        }
    }
    let snapshot = v.clone();
    for c in v.iter_mut() {
        c.pareto = !snapshot.iter().any(|o| {
            o.suite <= c.suite && o.cost() <= c.cost() && (o.suite < c.suite || o.cost() < c.cost())
        });
    }
    v
}

/// The speed cap at `2^k` steps/s, pitch/s (events: the number format's range).
pub fn speed_cap(k: u32) -> f64 {
    let (step_log2, stepping) = if is_events(k) {
        (FRAME_LOG2, Stepping::Events)
    } else {
        (k, Stepping::Fixed)
    };
    marble_rolling::physics::Params::<f64>::new(PhysicsSpec {
        step_log2,
        stepping,
        ..PhysicsSpec::DEFAULT
    })
    .map(|p| p.v_max)
    .unwrap_or(0.0)
}

/// Whether the rate keeps the full 64 pitch/s cap.
pub fn full_speed(k: u32) -> bool {
    speed_cap(k) >= 64.0
}

/// The cheapest configuration inside the accuracy target (`full_speed`: among
/// those that also keep the full speed range).
pub fn cheapest(configs: &[Config], need_full_speed: bool) -> Option<&Config> {
    configs
        .iter()
        .filter(|c| c.accurate() && (c.full_speed || !need_full_speed))
        .min_by(|a, b| a.cost().total_cmp(&b.cost()))
}

/// The recommended default: the cheapest configuration inside the accuracy
/// target that keeps the full speed range.
pub fn recommended(configs: &[Config]) -> Option<&Config> {
    cheapest(configs, true)
}

/// The firmware's stepping: the one the game's rules pick
/// (`game::rules::DEFAULT_EVENTS`; fixed steps at the default rate otherwise).
pub fn firmware_k() -> u32 {
    if DEFAULT_EVENTS {
        EVENTS_LOG2
    } else {
        DEFAULT_STEP_LOG2
    }
}

/// The firmware's default: `i8f24` with [`firmware_k`].
pub fn current_default(configs: &[Config]) -> Option<&Config> {
    configs
        .iter()
        .find(|c| c.backend == 0 && c.k == firmware_k())
}
