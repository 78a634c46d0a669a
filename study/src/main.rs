//! `cargo accuracy`: what accuracy costs in time, measured on the host and on the
//! target, written to `docs/accuracy.md` and `docs/accuracy.png`.
//!
//! One command runs the whole study:
//!
//! 1. accuracy on the host: every scene of [`marble_rolling::study`] × scalar
//!    backend × stepping (event stepping at the frame rate, and fixed steps at
//!    2^7 … 2^12 steps/s), against an `f64` reference at 2^14 steps/s and
//!    against the analytic solution where one exists;
//! 2. the peers: the same scenes in rapier2d and Box2D v3 (f32);
//! 3. host cost: a timing loop (warm-up, repeated whole runs, minimum and median
//!    ns/step) and `valgrind --tool=callgrind` instructions per step;
//! 4. target cost: the `bench` firmware in QEMU mps2-an386 (Cortex-M4F) and
//!    `bench_m0` in QEMU microbit (Cortex-M0), instructions counted under
//!    `-icount shift=7` with a hardware timer calibrated against a NOP loop;
//! 5. the report: tables, Pareto front, verdicts against the targets, chart.
//!
//! Options: `--quick` (fewer timing repetitions), `--no-target`, `--no-m0`,
//! `--no-callgrind`, `--out DIR` (default `docs/`).

mod callgrind;
mod host;
mod peer;
mod plot;
mod report;
mod target;

use std::collections::HashMap;
use std::path::PathBuf;
use std::time::Instant;

use marble_rolling::study::{
    is_events, Scene, SceneId, BACKENDS, DEFAULT_STEP_LOG2, EFFECT_VARIANTS, EVENTS_LOG2,
    REFERENCE_STEP_LOG2, STEPPINGS, VARIANT_STEPPINGS,
};

use host::{Outcome, Timing};
use peer::box2d::Box2d;
use peer::rapier::Rapier;
use target::{Count, Cpu, TargetRun};

/// An engine: one of ours ([`BACKENDS`] index) or a peer.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Engine {
    /// Our engine with `BACKENDS[n]`.
    Ours(usize),
    /// rapier2d, f32.
    Rapier,
    /// Box2D v3 (`boxdd`), f32.
    Box2d,
}

/// The peers, in the order the report lists them.
pub const PEERS: [Engine; 2] = [Engine::Rapier, Engine::Box2d];

impl Engine {
    /// Its name in tables (and `ENGINE` of `--callgrind-child`).
    pub fn name(self) -> &'static str {
        match self {
            Engine::Ours(b) => BACKENDS[b],
            Engine::Rapier => "rapier2d",
            Engine::Box2d => "box2d",
        }
    }

    /// Its name in prose.
    pub fn title(self) -> &'static str {
        match self {
            Engine::Ours(b) => BACKENDS[b],
            Engine::Rapier => "rapier2d",
            Engine::Box2d => "Box2D v3",
        }
    }

    /// Whether it is a peer (no event stepping, no target counts).
    pub fn is_peer(self) -> bool {
        !matches!(self, Engine::Ours(_))
    }

    /// The engine called `name` in tables.
    pub fn by_name(name: &str) -> Option<Engine> {
        PEERS
            .into_iter()
            .find(|e| e.name() == name)
            .or_else(|| BACKENDS.iter().position(|b| *b == name).map(Engine::Ours))
    }
}

/// One scene run in one configuration, with everything measured about it.
#[derive(Clone, Debug, Default)]
pub struct Cell {
    /// The run's own figures.
    pub out: Outcome,
    /// Distance from the reference after 1 s and 10 s, mm.
    pub err1: f64,
    /// After 10 s.
    pub err10: f64,
    /// The largest distance from the reference over the run (sampled every frame).
    pub err_max: f64,
    /// Distance from the analytic solution after 1 s / 10 s, mm (where one exists).
    pub ana1: Option<f64>,
    /// After 10 s.
    pub ana10: Option<f64>,
    /// End energy minus the reference's, in % of the reference's largest kinetic energy.
    pub energy_pct: f64,
    /// Host time per step.
    pub host: Timing,
    /// Host instructions per step (callgrind; default rate and events only).
    pub host_ir: Option<f64>,
    /// Cortex-M4F count.
    pub m4: Option<Count>,
    /// Cortex-M0 count.
    pub m0: Option<Count>,
}

/// Everything the report needs.
#[derive(Default)]
pub struct Study {
    /// By (scene, engine, step_log2); `EVENTS_LOG2` for event stepping (ours only).
    pub cells: HashMap<(SceneId, Engine, u32), Cell>,
    /// The `f64` reference runs at 2^14 steps/s.
    pub reference: HashMap<SceneId, Outcome>,
    /// Per-effect variants on the host, i8f24 at the default rate and with events:
    /// (scene, variant, step_log2) → (outcome, timing).
    pub variants: HashMap<(SceneId, usize, u32), (Outcome, Timing)>,
    /// Target runs.
    pub m4: Option<TargetRun>,
    /// Target runs.
    pub m0: Option<TargetRun>,
    /// Host hot spots of the default configuration (callgrind self cost).
    pub profiles: Vec<(String, Vec<(f64, String)>)>,
    /// Why callgrind figures are missing, if they are.
    pub callgrind_note: Option<String>,
    /// Host description.
    pub host_cpu: String,
    /// Seconds per phase.
    pub phases: Vec<(String, f64)>,
    /// Whether --quick was given.
    pub quick: bool,
}

/// The configurations an engine runs: ours every stepping, the peers the fixed
/// rates (they have no event mode).
fn steppings(e: Engine) -> impl Iterator<Item = u32> {
    STEPPINGS
        .into_iter()
        .filter(move |&k| !e.is_peer() || !is_events(k))
}

/// Analytic position (mm) at `t` seconds, where the scene has one.
fn analytic(id: SceneId, t: f64) -> Option<[f64; 2]> {
    let scene = Scene::get(id);
    let params = marble_rolling::physics::Params::<f64>::new(scene.spec).ok()?;
    let pitch = params.layout.pitch_um as f64 / 1000.0;
    match id {
        SceneId::Incline => {
            let g = scene.trace.gravity_mg(0);
            let (x0, x1) = params.layout.span_xz(scene.start.0 as i32);
            let (z0, z1) = params.layout.span_xz(scene.start.1 as i32);
            let a = |mg: i32| 0.5 * 5.0 / 7.0 * mg as f64 * host::MM_S2_PER_MG * t * t;
            Some([
                (x0 + x1) / 2.0 * pitch + a(g[0]),
                (z0 + z1) / 2.0 * pitch + a(g[2]),
            ])
        }
        SceneId::Corner if t >= 10.0 => {
            // Pressed into the far corner of the 3 × 3-cell box: the wall tiles at
            // i = k = 6 start at 3 pitches; the centre rests one radius before.
            let face = params.layout.span_xz(6).0;
            let c = (face - params.radius) * pitch;
            Some([c, c])
        }
        _ => None,
    }
}

fn dist(a: [f64; 2], b: [f64; 2]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
}

fn host_cpu() -> String {
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .map(|l| l.split(':').nth(1).unwrap_or("").trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".into());
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    format!("{model}, {cores} cores")
}

fn usage() -> ! {
    eprintln!(
        "usage: cargo accuracy [-- [--quick] [--no-target] [--no-m0] [--no-callgrind] [--out DIR]]"
    );
    std::process::exit(2)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--callgrind-child") {
        if let Err(e) = callgrind::child(&args[1..]) {
            eprintln!("{e}");
            std::process::exit(2);
        }
        return;
    }
    let mut quick = false;
    let mut no_target = false;
    let mut no_m0 = false;
    let mut no_callgrind = false;
    if args.first().map(String::as_str) == Some("--trace") {
        // Debugging aid: the f64 reference's track, every quarter second.
        let id = args
            .get(1)
            .and_then(|n| callgrind::scene_by_name(n))
            .unwrap_or_else(|| usage());
        let r = host::measure(id, 5, REFERENCE_STEP_LOG2, None).expect("reference run");
        for (n, p) in r.track.iter().enumerate().step_by(32) {
            println!(
                "{:6.2} s  x {:8.3} mm  z {:8.3} mm",
                n as f64 / 128.0,
                p[0],
                p[1]
            );
        }
        println!(
            "contacts {} bounces {} max overlap {:.3} µm",
            r.contacts, r.collisions, r.max_pen_um
        );
        return;
    }
    // The repository's docs/, beside the study's own folder.
    let study_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut out_dir = study_dir.parent().unwrap_or(study_dir).join("docs");
    let mut it = args.iter();
    while let Some(a) = it.next() {
        match a.as_str() {
            "--quick" => quick = true,
            "--no-target" => no_target = true,
            "--no-m0" => no_m0 = true,
            "--no-callgrind" => no_callgrind = true,
            "--out" => out_dir = PathBuf::from(it.next().unwrap_or_else(|| usage())),
            "-h" | "--help" => usage(),
            // The cargo alias ends in `--`, so `cargo accuracy -- --quick` passes one.
            "--" => {}
            other => {
                eprintln!("unknown option {other}");
                usage()
            }
        }
    }
    let started = Instant::now();
    let mut study = Study {
        quick,
        host_cpu: host_cpu(),
        ..Study::default()
    };
    let scenes = Scene::all();
    let mut engines: Vec<Engine> = (0..BACKENDS.len()).map(Engine::Ours).collect();
    engines.extend(PEERS);

    // 1–2. Accuracy.
    let t = Instant::now();
    eprintln!("accuracy: reference runs (f64, 2^{REFERENCE_STEP_LOG2} steps/s)");
    for s in &scenes {
        let r = host::measure(s.id, 5, REFERENCE_STEP_LOG2, None).expect("reference run");
        study.reference.insert(s.id, r);
    }
    eprintln!(
        "accuracy: {} scenes × {} engines × {} steppings (events and fixed rates)",
        scenes.len(),
        engines.len(),
        STEPPINGS.len()
    );
    for s in &scenes {
        let reference = study.reference[&s.id].clone();
        let ana1 = analytic(s.id, 1.0);
        let ana10 = analytic(s.id, 10.0);
        for &e in &engines {
            for k in steppings(e) {
                let out = match e {
                    Engine::Ours(b) => host::measure(s.id, b, k, None).expect("setup"),
                    Engine::Rapier => peer::measure::<Rapier>(s.id, k),
                    Engine::Box2d => peer::measure::<Box2d>(s.id, k),
                };
                let cell = Cell {
                    err1: dist(out.pos1, reference.pos1),
                    err10: dist(out.pos10, reference.pos10),
                    err_max: out
                        .track
                        .iter()
                        .zip(&reference.track)
                        .map(|(a, b)| dist(*a, *b))
                        .fold(0.0, f64::max),
                    ana1: ana1.map(|a| dist(out.pos1, a)),
                    ana10: ana10.map(|a| dist(out.pos10, a)),
                    energy_pct: (out.energy_end - reference.energy_end)
                        / reference.ke_max.max(1e-9)
                        * 100.0,
                    out,
                    ..Cell::default()
                };
                study.cells.insert((s.id, e, k), cell);
            }
        }
    }
    study
        .phases
        .push(("accuracy runs (host)".into(), t.elapsed().as_secs_f64()));

    // 3. Host time.
    let t = Instant::now();
    let (reps, min_s, peer_reps) = if quick { (3, 0.0, 1) } else { (7, 0.05, 3) };
    eprintln!("host time: timing loop ({reps} runs per configuration after a warm-up)");
    for s in &scenes {
        for &e in &engines {
            for k in steppings(e) {
                let timing = match e {
                    Engine::Ours(b) => host::time(s.id, b, k, None, reps, min_s).expect("setup"),
                    Engine::Rapier => peer::time::<Rapier>(s.id, k, peer_reps, 0.0),
                    Engine::Box2d => peer::time::<Box2d>(s.id, k, peer_reps, 0.0),
                };
                if let Some(c) = study.cells.get_mut(&(s.id, e, k)) {
                    c.host = timing;
                }
            }
        }
    }
    for scene in [SceneId::Maze, SceneId::Bounce] {
        for k in VARIANT_STEPPINGS {
            for (v, (_, fx)) in EFFECT_VARIANTS.iter().enumerate() {
                let out = host::measure(scene, 0, k, Some(*fx)).expect("setup");
                let timing = host::time(scene, 0, k, Some(*fx), reps, min_s).expect("setup");
                study.variants.insert((scene, v, k), (out, timing));
            }
        }
    }
    study
        .phases
        .push(("host timing".into(), t.elapsed().as_secs_f64()));

    // 3b. Callgrind at the default rate (every engine) and with events (ours).
    let t = Instant::now();
    if no_callgrind {
        study.callgrind_note = Some("skipped (--no-callgrind)".into());
    } else if !callgrind::available() {
        study.callgrind_note = Some("valgrind is not installed (apt-get install valgrind)".into());
    } else {
        eprintln!("host instructions: callgrind at 2^{DEFAULT_STEP_LOG2} steps/s, with events and at the peers' comparison rates");
        let exe = std::env::current_exe().expect("own path");
        let work = std::env::temp_dir().join(format!("accuracy-callgrind-{}", std::process::id()));
        let _ = std::fs::create_dir_all(&work);
        let jobs: Vec<(SceneId, Engine, u32)> = scenes
            .iter()
            .flat_map(|s| {
                engines.iter().flat_map(move |&e| {
                    let rates = if e.is_peer() {
                        report::callgrind_rates(e)
                    } else {
                        vec![DEFAULT_STEP_LOG2, EVENTS_LOG2]
                    };
                    rates.into_iter().map(move |k| (s.id, e, k))
                })
            })
            .collect();
        let results = std::sync::Mutex::new(Vec::new());
        let next = std::sync::atomic::AtomicUsize::new(0);
        let threads = std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
            .clamp(1, 4);
        std::thread::scope(|sc| {
            for _ in 0..threads {
                sc.spawn(|| loop {
                    let i = next.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                    let Some(&(id, e, k)) = jobs.get(i) else {
                        break;
                    };
                    let r = callgrind::count(&exe, id, e.name(), k, &work);
                    results.lock().unwrap().push((id, e, k, r));
                });
            }
        });
        let mut failures = Vec::new();
        for (id, k) in [
            (SceneId::Maze, DEFAULT_STEP_LOG2),
            (SceneId::Incline, DEFAULT_STEP_LOG2),
            (SceneId::Maze, EVENTS_LOG2),
        ] {
            let title = format!(
                "{} {} @ {}",
                Scene::get(id).name,
                BACKENDS[0],
                report::label(k)
            );
            match callgrind::profile(&exe, id, BACKENDS[0], k, &work, 12) {
                Ok(rows) => study.profiles.push((title, rows)),
                Err(e) => failures.push(format!("profile {title}: {e}")),
            }
        }
        let _ = std::fs::remove_dir_all(&work);
        for (id, e, k, r) in results.into_inner().unwrap() {
            match r {
                Ok(ir) => {
                    if let Some(c) = study.cells.get_mut(&(id, e, k)) {
                        c.host_ir = Some(ir);
                    }
                }
                Err(msg) => failures.push(format!(
                    "{} {} @ {}: {msg}",
                    Scene::get(id).name,
                    e.name(),
                    report::label(k)
                )),
            }
        }
        if !failures.is_empty() {
            study.callgrind_note = Some(failures.join("; "));
        }
    }
    study.phases.push((
        "callgrind (host instructions)".into(),
        t.elapsed().as_secs_f64(),
    ));

    // 4. Target.
    // Bit k for 2^k steps/s, bit 0 for events.
    let rates: u32 = STEPPINGS.iter().map(|k| 1u32 << k).sum();
    if !no_target {
        // Both QEMU runs at once (one core each); cargo serialises their builds.
        let cpus: Vec<Cpu> = [Cpu::M4, Cpu::M0]
            .into_iter()
            .filter(|&c| c == Cpu::M4 || !no_m0)
            .collect();
        eprintln!(
            "target: {} (build, then run in QEMU)",
            cpus.iter()
                .map(|c| c.name())
                .collect::<Vec<_>>()
                .join(" and ")
        );
        let runs: Vec<(Cpu, TargetRun)> = std::thread::scope(|sc| {
            let handles: Vec<_> = cpus
                .iter()
                .map(|&cpu| sc.spawn(move || (cpu, target::run(cpu, rates))))
                .collect();
            handles
                .into_iter()
                .map(|h| h.join().expect("target thread"))
                .collect()
        });
        for (cpu, run) in runs {
            if let Some(e) = &run.error {
                eprintln!("target: {e}");
            }
            for s in &scenes {
                for (b, backend) in BACKENDS.iter().enumerate() {
                    for k in STEPPINGS {
                        let key = (
                            s.name.to_string(),
                            backend.to_string(),
                            "scene".to_string(),
                            k,
                        );
                        if let (Some(c), Some(n)) = (
                            study.cells.get_mut(&(s.id, Engine::Ours(b), k)),
                            run.counts.get(&key),
                        ) {
                            match cpu {
                                Cpu::M4 => c.m4 = Some(n.clone()),
                                Cpu::M0 => c.m0 = Some(n.clone()),
                            }
                        }
                    }
                }
            }
            study
                .phases
                .push((format!("target {}", cpu.name()), run.seconds));
            match cpu {
                Cpu::M4 => study.m4 = Some(run),
                Cpu::M0 => study.m0 = Some(run),
            }
        }
    }

    // 5. Report.
    study
        .phases
        .push(("total".into(), started.elapsed().as_secs_f64()));
    let _ = std::fs::create_dir_all(&out_dir);
    let md = report::markdown(&study);
    let md_path = out_dir.join("accuracy.md");
    std::fs::write(&md_path, md).expect("write docs/accuracy.md");
    let png_path = out_dir.join("accuracy.png");
    if let Err(e) = plot::chart(&study, &png_path) {
        eprintln!("chart: {e}");
        std::process::exit(1);
    }
    eprintln!(
        "wrote {} and {} in {:.0} s",
        md_path.display(),
        png_path.display(),
        started.elapsed().as_secs_f64()
    );
    print!("{}", report::summary(&study));
}
