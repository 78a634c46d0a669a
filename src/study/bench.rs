//! The target benchmarks' plan: which measurements the Cortex-M4F and
//! Cortex-M0 binaries run ([`bench_plan`]), and one run of a scene with its
//! instructions counted ([`bench_one`]), whose state hash must be the host's.

use super::{
    run_plain, with_backend_in, Job, Scene, SceneId, ALL_BACKENDS, BACKENDS, EFFECT_VARIANTS,
    STEPPINGS, VARIANT_STEPPINGS,
};
use crate::physics::{Effects, Scalar};

/// One target measurement: what to run.
#[derive(Clone, Copy, Debug)]
pub struct BenchItem {
    /// The scene.
    pub scene: SceneId,
    /// Index into [`BACKENDS`].
    pub backend: usize,
    /// `log2` of the step rate ([`EVENTS_LOG2`](super::EVENTS_LOG2): event stepping).
    pub step_log2: u32,
    /// Index into [`EFFECT_VARIANTS`], or `None` for the scene's own effects.
    pub variant: Option<usize>,
}

impl BenchItem {
    /// The effects this item runs with.
    pub(crate) fn effects(&self) -> Effects {
        match self.variant {
            Some(v) => EFFECT_VARIANTS[v % EFFECT_VARIANTS.len()].1,
            None => Scene::get(self.scene).spec.effects,
        }
    }
    /// The variant's name (`scene` when the scene's own effects).
    pub fn variant_name(&self) -> &'static str {
        match self.variant {
            Some(v) => EFFECT_VARIANTS[v % EFFECT_VARIANTS.len()].0,
            None => "scene",
        }
    }
}

/// Calls `f` for every target measurement: each scene × backend × stepping
/// ([`STEPPINGS`]: events, then the fixed rates) with the scene's own effects,
/// then the effect variants of the maze and of the bounce corridor at the default
/// backend, at the default rate and with events ([`VARIANT_STEPPINGS`]).
/// `backends` selects backends by index (bit `n` for [`BACKENDS`]`[n]`), `rates`
/// step rates by `log2` (bit `k`; bit 0 is [`EVENTS_LOG2`](super::EVENTS_LOG2)); the variants always run.
pub fn bench_plan(backends: u32, rates: u32, mut f: impl FnMut(BenchItem)) {
    for scene in [
        SceneId::Incline,
        SceneId::Bounce,
        SceneId::Maze,
        SceneId::Corner,
    ] {
        for backend in 0..BACKENDS.len() {
            if backends & (1 << backend) == 0 {
                continue;
            }
            for k in STEPPINGS {
                if rates & (1 << k) != 0 {
                    f(BenchItem {
                        scene,
                        backend,
                        step_log2: k,
                        variant: None,
                    });
                }
            }
        }
    }
    for scene in [SceneId::Maze, SceneId::Bounce] {
        for step_log2 in VARIANT_STEPPINGS {
            for v in 0..EFFECT_VARIANTS.len() {
                f(BenchItem {
                    scene,
                    backend: 0,
                    step_log2,
                    variant: Some(v),
                });
            }
        }
    }
}

/// A finished target measurement, as the benchmark binaries print it.
#[derive(Clone, Copy, Debug, Default)]
pub struct BenchResult {
    /// Steps run.
    pub steps: u32,
    /// Instructions of the whole run (steps and per-frame tilt updates).
    pub instructions: u64,
    /// [`World::state_hash`](crate::physics::World::state_hash) at the end (must match the host's).
    pub hash: u64,
    /// Contacts resolved.
    pub contacts: u32,
    /// Bounces.
    pub collisions: u32,
}

/// Runs `item` once, with `count` timing the stepping (it runs the closure it is
/// given and returns its instruction count).
pub fn bench_one(
    item: &BenchItem,
    count: &mut dyn FnMut(&mut dyn FnMut()) -> u64,
) -> Option<BenchResult> {
    bench_one_in::<ALL_BACKENDS>(item, count)
}

/// [`bench_one`] compiled for the backends in `MASK` only (see `with_backend_in`).
pub fn bench_one_in<const MASK: u32>(
    item: &BenchItem,
    count: &mut dyn FnMut(&mut dyn FnMut()) -> u64,
) -> Option<BenchResult> {
    struct One<'a> {
        item: BenchItem,
        count: &'a mut dyn FnMut(&mut dyn FnMut()) -> u64,
    }
    impl Job for One<'_> {
        type Output = Option<BenchResult>;
        fn run<S: Scalar>(self) -> Option<BenchResult> {
            let scene = Scene::get(self.item.scene);
            let mut w = scene
                .world::<S>(self.item.step_log2, self.item.effects())
                .ok()?;
            let trace = scene.trace;
            let instructions = (self.count)(&mut || run_plain(&mut w, &trace));
            Some(BenchResult {
                steps: w.stats.steps,
                instructions,
                hash: w.state_hash(),
                contacts: w.stats.contacts,
                collisions: w.stats.collisions,
            })
        }
    }
    with_backend_in::<MASK, _>(item.backend, One { item: *item, count })?
}
