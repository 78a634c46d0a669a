//! Host time per physics step, per scalar backend, on the accuracy study's scenes
//! (src/study.rs) at the default 1024 steps/s.
//!
//! `cargo bench --bench step` prints one table per scene, one row per backend
//! ([`BACKENDS`]); each iteration times 1024 steps, so per-step time = reported
//! time / 1024 (the "items/s" throughput is steps/s).
//! `cargo bench --bench step -- --test` runs each benchmark once (CI).

use divan::counter::ItemsCount;
use divan::{black_box, Bencher};
use marble_rolling::physics::Scalar;
use marble_rolling::study::{
    drive, with_backend, Job, Scene, SceneId, BACKENDS, DEFAULT_STEP_LOG2,
};

/// Steps timed per iteration (one second of scene time at the default rate).
const STEPS: u32 = 1 << DEFAULT_STEP_LOG2;

fn main() {
    divan::main();
}

/// One iteration: a fresh world of the scene (built outside the timed region),
/// then its first [`STEPS`] steps under the scene's trace.
struct Steps<'a, 'b> {
    bencher: Bencher<'a, 'b>,
    scene: Scene,
}

impl Job for Steps<'_, '_> {
    type Output = ();
    fn run<S: Scalar>(self) {
        let scene = self.scene;
        self.bencher
            .counter(ItemsCount::new(STEPS))
            .with_inputs(|| {
                scene
                    .world::<S>(DEFAULT_STEP_LOG2, scene.spec.effects)
                    .expect("scene world")
            })
            .bench_local_values(|mut w| {
                drive(&mut w, black_box(&scene.trace), 0, STEPS, |_, _| {});
                black_box(w)
            });
    }
}

fn bench(bencher: Bencher, id: SceneId, backend: &str) {
    let index = BACKENDS
        .iter()
        .position(|b| *b == backend)
        .expect("backend");
    with_backend(
        index,
        Steps {
            bencher,
            scene: Scene::get(id),
        },
    )
    .expect("backend");
}

#[divan::bench(args = BACKENDS)]
fn incline(bencher: Bencher, backend: &str) {
    bench(bencher, SceneId::Incline, backend);
}

#[divan::bench(args = BACKENDS)]
fn bounce(bencher: Bencher, backend: &str) {
    bench(bencher, SceneId::Bounce, backend);
}

#[divan::bench(args = BACKENDS)]
fn maze(bencher: Bencher, backend: &str) {
    bench(bencher, SceneId::Maze, backend);
}

#[divan::bench(args = BACKENDS)]
fn corner(bencher: Bencher, backend: &str) {
    bench(bencher, SceneId::Corner, backend);
}
