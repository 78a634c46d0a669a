//! docs/accuracy.md: tables, Pareto front, verdicts.

use std::fmt::Write;

use marble_rolling::physics::{PhysicsSpec, Stepping};
use marble_rolling::study::{
    is_events, steps_per_second, Scene, SceneId, BACKENDS, DEFAULT_STEP_LOG2, EFFECT_VARIANTS,
    FRAME_LOG2, REFERENCE_STEP_LOG2, SECONDS, STEPPINGS, VARIANT_STEPPINGS,
};

use super::target::TargetRun;
use super::{Engine, Study};

/// The accuracy target: mm from the reference after 10 s of rolling.
pub const TARGET_MM: f64 = 0.05;
/// The cost budget: Cortex-M4 instructions per marble per simulated millisecond
/// in a flat maze, at the firmware default (issue 13).
pub const BUDGET_PER_MS: f64 = 100.0;
/// The peer target: at least this many times cheaper than rapier2d.
pub const PEER_FACTOR: f64 = 100.0;

/// A number with about 3 significant digits.
pub fn sig(x: f64) -> String {
    if !x.is_finite() {
        return "–".into();
    }
    let a = x.abs();
    if a == 0.0 {
        "0".into()
    } else if !(1e-3..1e5).contains(&a) {
        format!("{x:.1e}")
    } else if a >= 100.0 {
        format!("{x:.0}")
    } else if a >= 10.0 {
        format!("{x:.1}")
    } else if a >= 1.0 {
        format!("{x:.2}")
    } else {
        let digits = (-a.log10()).ceil() as usize + 2;
        format!("{x:.digits$}")
    }
}

fn opt(x: Option<f64>) -> String {
    x.map(sig).unwrap_or_else(|| "–".into())
}

/// A configuration's stepping in the per-scene tables: `1024 (128×8)`, or
/// `events (128×1)` for event stepping.
fn rate(k: u32) -> String {
    if is_events(k) {
        format!("events ({}×1)", 1u32 << FRAME_LOG2)
    } else {
        format!("{} ({}×{})", 1u32 << k, 128, 1u32 << (k - FRAME_LOG2))
    }
}

/// A configuration's stepping in names and plots: `1024`, or `events`.
pub fn label(k: u32) -> String {
    if is_events(k) {
        "events".into()
    } else {
        (1u32 << k).to_string()
    }
}

/// Steps per simulated second (an event step is a whole frame).
pub fn per_second(k: u32) -> f64 {
    steps_per_second(k) as f64
}

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
        self.m4_ms.map(|c| c <= BUDGET_PER_MS)
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

fn current_default(configs: &[Config]) -> Option<&Config> {
    configs
        .iter()
        .find(|c| c.backend == 0 && c.k == DEFAULT_STEP_LOG2)
}

/// The backends compared with rapier2d: the recommended one and the firmware's
/// current `i8f24` (once if they are the same).
fn peer_backends(configs: &[Config]) -> Vec<usize> {
    let mut v = Vec::new();
    if let Some(r) = recommended(configs) {
        v.push(r.backend);
    }
    if !v.contains(&0) {
        v.push(0);
    }
    v
}

/// The rapier2d rate ours at `k` is compared with: the same rate, and for
/// events the firmware's 1024 steps/s (rapier2d has no event mode).
pub fn peer_rate(k: u32) -> u32 {
    if is_events(k) {
        DEFAULT_STEP_LOG2
    } else {
        k
    }
}

/// Backend `b` at `k` against rapier2d at [`peer_rate`]`(k)` in one scene, per
/// simulated second: (time ratio, instruction ratio, as accurate).
fn versus(study: &Study, id: SceneId, b: usize, k: u32) -> Option<(f64, Option<f64>, bool)> {
    let rk = peer_rate(k);
    let r = study.cells.get(&(id, Engine::Rapier, rk))?;
    let o = study.cells.get(&(id, Engine::Ours(b), k))?;
    // Per step × steps per simulated second, on both sides.
    let (rs, os) = (per_second(rk), per_second(k));
    let ir = match (r.host_ir, o.host_ir) {
        (Some(a), Some(b)) => Some(a * rs / (b * os)),
        _ => None,
    };
    let as_good = o.err_max <= r.err_max && o.out.cap_hits == 0 && o.out.reverts == 0 && !o.out.out;
    Some((r.host.min_ns * rs / (o.host.min_ns * os), ir, as_good))
}

/// The recommended configuration (else the current default) against rapier2d at
/// 1024 steps/s, per simulated second, over the scenes: (backend, its `k`,
/// smallest time ratio and its scene, smallest instruction ratio, as accurate
/// everywhere).
#[allow(clippy::type_complexity)]
fn peer_verdict(
    study: &Study,
    configs: &[Config],
) -> Option<(usize, u32, f64, SceneId, Option<f64>, bool)> {
    let c = recommended(configs).or_else(|| current_default(configs))?;
    let (b, k) = (c.backend, c.k);
    let mut worst: Option<(f64, SceneId)> = None;
    let mut ir_worst: Option<f64> = None;
    let mut all_good = true;
    for s in Scene::all() {
        let (t, ir, good) = versus(study, s.id, b, k)?;
        // Judged on the suite's scenes, like the accuracy target (not the maze).
        all_good &= good || s.id == SceneId::Maze;
        if worst.is_none_or(|(w, _)| t < w) {
            worst = Some((t, s.id));
        }
        if let Some(ir) = ir {
            ir_worst = Some(ir_worst.map_or(ir, |w: f64| w.min(ir)));
        }
    }
    let (t, id) = worst?;
    Some((b, k, t, id, ir_worst, all_good))
}

fn verdict(ok: Option<bool>) -> &'static str {
    match ok {
        Some(true) => "**met**",
        Some(false) => "**not met**",
        None => "**not measured**",
    }
}

fn target_status(run: &Option<TargetRun>) -> String {
    match run {
        None => "not run (`--no-target` / `--no-m0`)".into(),
        Some(r) => match &r.error {
            None => format!(
                "{} runs counted in {:.0} s; calibration `{}`",
                r.counts.len(),
                r.seconds,
                r.calibration
            ),
            Some(e) => format!(
                "**failed** after {:.0} s ({} runs counted): {e}",
                r.seconds,
                r.counts.len()
            ),
        },
    }
}

/// The short summary printed at the end of `cargo accuracy`.
pub fn summary(study: &Study) -> String {
    let configs = configs(study);
    let mut s = String::new();
    let _ = writeln!(s, "accuracy study: {} configurations", configs.len());
    let line = |c: &Config| {
        format!(
            "{}: suite error {} mm (rolling 10 s {} mm), maze {} M4 instr/step = {} per simulated ms (M0 {} per ms), host {} ns/step",
            c.name(),
            sig(c.suite),
            sig(c.roll10),
            opt(c.m4_step),
            opt(c.m4_ms),
            opt(c.m0_ms),
            sig(c.host_ns)
        )
    };
    if let Some(d) = current_default(&configs) {
        let _ = writeln!(s, "  current default {}", line(d));
    }
    if let Some(e) = configs.iter().find(|c| c.backend == 0 && is_events(c.k)) {
        let _ = writeln!(s, "  event stepping {}", line(e));
    }
    match recommended(&configs) {
        Some(r) => {
            let _ = writeln!(s, "  recommended default {}", line(r));
        }
        None => {
            let _ = writeln!(s, "  no configuration meets the accuracy target");
        }
    }
    if let Some((b, k, ratio, id, ir, good)) = peer_verdict(study, &configs) {
        let _ = writeln!(
            s,
            "  vs rapier2d at {} steps/s, {} @ {}, per simulated s: ≥ {}× less host time (worst scene: {}), ≥ {}× fewer host instructions, {}",
            1u32 << peer_rate(k),
            BACKENDS[b],
            label(k),
            sig(ratio),
            Scene::get(id).name,
            opt(ir),
            if good { "as accurate or better in every judged scene" } else { "less accurate in some judged scene" }
        );
    }
    // Per scene, the default backend with events and at 1024 steps/s.
    for k in [marble_rolling::study::EVENTS_LOG2, DEFAULT_STEP_LOG2] {
        for sc in Scene::all() {
            if let Some((t, ir, good)) = versus(study, sc.id, 0, k) {
                let _ = writeln!(
                    s,
                    "    {} @ {} vs rapier2d @ {}, {}: {}× less time, {} fewer instructions per simulated s{}",
                    BACKENDS[0],
                    label(k),
                    1u32 << peer_rate(k),
                    sc.name,
                    sig(t),
                    ir.map(|i| format!("{}×", sig(i))).unwrap_or_else(|| "–".into()),
                    if good { "" } else { " (less accurate)" }
                );
            }
        }
    }
    s
}

/// docs/accuracy.md.
pub fn markdown(study: &Study) -> String {
    let configs = configs(study);
    let mut md = String::new();
    let w = &mut md;
    let _ = writeln!(w, "# Accuracy and what it costs\n");
    let _ = writeln!(
        w,
        "Generated by `cargo accuracy` (study/src/main.rs; scenes in src/study/; target benchmarks boards/qemu/src/bin/bench.rs and study/bench-m0/src/main.rs). Do not edit by hand: rerun it.\n"
    );
    let _ = writeln!(
        w,
        "Host: {}. Total {:.0} s ({}).{}\n",
        study.host_cpu,
        study
            .phases
            .iter()
            .find(|p| p.0 == "total")
            .map(|p| p.1)
            .unwrap_or(0.0),
        study
            .phases
            .iter()
            .filter(|p| p.0 != "total")
            .map(|(n, t)| format!("{n} {t:.0} s"))
            .collect::<Vec<_>>()
            .join(", "),
        if study.quick {
            " **Quick mode: fewer timing repetitions.**"
        } else {
            ""
        }
    );

    // Verdicts.
    let rec = recommended(&configs);
    let any = cheapest(&configs, false);
    let cur = current_default(&configs);
    let _ = writeln!(w, "## Verdict\n");
    let _ = writeln!(
        w,
        "**Accuracy target**: the *suite error* — the worst of (a) rolling: distance from the f64 reference after 10 s on the incline, (b) bouncing: the largest distance from the reference over the 10 s corridor run, (c) resting: distance from the analytic rest position in the corner — within {TARGET_MM} mm; and sound: no reverted step, no lost marble, the speed cap never reached in the suite. The maze is reported but not judged (see its row: even f64 at 4096 steps/s is 0.3 mm off the 16384 steps/s path at some moment, because when a bounce or a static-friction hold falls depends on the step).\n"
    );
    let _ = writeln!(w, "| target | result |\n|---|---|");
    let _ = writeln!(
        w,
        "| within {TARGET_MM} mm of the f64 reference after 10 s at ≤ {BUDGET_PER_MS} Cortex-M4 instructions per marble per simulated ms in a flat maze, at the firmware default | {} — {} |",
        verdict(rec.and_then(|r| r.affordable())),
        match rec {
            Some(r) => format!(
                "the cheapest configuration inside the accuracy target (with the full speed range), event stepping and fixed steps alike, is **{}** at {} M4 instructions per simulated ms ({} per step); {}",
                r.name(),
                opt(r.m4_ms),
                opt(r.m4_step),
                match r.m4_ms {
                    Some(c) if c > BUDGET_PER_MS => format!("{}× over the budget", sig(c / BUDGET_PER_MS)),
                    Some(_) => "inside the budget".into(),
                    None => "no target count".into(),
                }
            ),
            None => "no configuration reaches the accuracy target".into(),
        }
    );
    let peer = peer_verdict(study, &configs);
    let _ = writeln!(
        w,
        "| ≥ {PEER_FACTOR}× fewer host instructions per simulated second than rapier2d at {} steps/s, at equal or better accuracy, in every scene | {} — {} |",
        1u32 << DEFAULT_STEP_LOG2,
        verdict(peer.map(|(_, _, _, _, ir, good)| ir.map(|i| good && i >= PEER_FACTOR)).unwrap_or(None)),
        match peer {
            Some((b, k, t, id, ir, good)) => format!(
                "`{} @ {}` (the recommended default): at least **{}×** fewer host instructions (callgrind) and {}× less host time (worst scene: {}) per simulated second than rapier2d, {}",
                BACKENDS[b],
                label(k),
                opt(ir),
                sig(t),
                Scene::get(id).name,
                if good { "with a smaller largest error in every judged scene (incline, bounce, corner)" } else { "but not as accurate in every judged scene" }
            ),
            None => "not measured".into(),
        }
    );
    let _ = writeln!(w);
    // The recommendation, from the data: the cheapest configuration inside the
    // accuracy target with the full speed range (`recommended`), against the
    // firmware's current default and the best of the other stepping mode.
    if let (Some(r), Some(c)) = (rec, cur) {
        let how = |x: &Config| {
            if is_events(x.k) {
                format!(
                    "`{}` with event stepping (one step per {} Hz frame, each marble flying its closed form from event to event)",
                    BACKENDS[x.backend],
                    1u32 << FRAME_LOG2
                )
            } else {
                format!(
                    "`{}` at {} steps/s ({} Hz × {} substeps, fixed steps)",
                    BACKENDS[x.backend],
                    1u32 << x.k,
                    1u32 << FRAME_LOG2,
                    1u32 << (x.k - FRAME_LOG2)
                )
            }
        };
        let figures = |x: &Config| {
            format!(
                "suite error {} mm, {} M4 instructions per step in the maze = {} per simulated ms ({} on the M0)",
                sig(x.suite),
                opt(x.m4_step),
                opt(x.m4_ms),
                opt(x.m0_ms)
            )
        };
        if r.backend == c.backend && r.k == c.k {
            let _ = writeln!(w, "**Recommended firmware default: {}** — the current default — is the cheapest configuration inside the accuracy target that keeps the full speed range ({}); keep it.\n", how(r), figures(r));
        } else {
            let _ = writeln!(
                w,
                "**Recommended firmware default: {}**: the cheapest configuration inside the accuracy target that keeps the full speed range — {}. The current default {} has {} ({}).\n",
                how(r),
                figures(r),
                c.name(),
                figures(c),
                if c.accurate() { "also inside the target" } else { "outside the target" }
            );
        }
        // The best of the other stepping mode, for the trade-off.
        let other = configs
            .iter()
            .filter(|x| x.accurate() && x.full_speed && is_events(x.k) != is_events(r.k))
            .min_by(|a, b| a.cost().total_cmp(&b.cost()));
        if let Some(o) = other {
            let _ = writeln!(
                w,
                "The cheapest {} configuration inside the target is {}: {} — {}× the recommended default's cost.\n",
                if is_events(o.k) { "event-stepping" } else { "fixed-step" },
                o.name(),
                figures(o),
                sig(o.cost() / r.cost())
            );
        }
        if is_events(r.k) || is_events(c.k) {
            // The study builds benchmarks, not the firmware: the flash figure is
            // the firmware's (docs/boards.md, "Budget").
            let _ = writeln!(
                w,
                "**Flash**: not measured by the study. The firmware links one stepper, chosen at compile time (`Player<W, H, PILOT, EVENTS>`): the micro:bit v2 firmware (with its records, at its opt-level \"z\") is 62 372 B with fixed steps and 80 244 B with the event stepper (`cargo xtask size-report`, with `EVENTS` set in boards/microbit/src/main.rs), so the boards with a 64 KiB budget keep fixed steps and QEMU's board runs events — the recommendation holds where the flash allows it.\n"
            );
        }
    }
    if let (Some(a), Some(r)) = (any, rec) {
        if a.backend != r.backend || a.k != r.k {
            let _ = writeln!(
                w,
                "Cheaper still, if the game never needs the top of the speed range: **{}** ({} mm, {} M4 instructions per ms). Its speed cap is {} pitch/s ({} mm/s) instead of 64 pitch/s: no scene of the suite reaches it, but a marble released from rest under a 0.5 g tilt does within 5 cells (54 pitch/s), and at the cap the step bound, not the physics, sets the speed.\n",
                a.name(),
                sig(a.suite),
                opt(a.m4_ms),
                sig(speed_cap(a.k)),
                sig(speed_cap(a.k) * 12.0)
            );
        }
    }

    // Method.
    let _ = writeln!(w, "## What is measured\n");
    let _ = writeln!(
        w,
        "**Stepping modes.** *Fixed steps*: discrete steps with an exact time-of-impact response (eq. 1 applied at the moment of contact within the step) and a speed cap as the no-tunnelling step bound (each velocity axis ≤ min(r/4 per step, 64 pitch/s); a step that would still overlap is undone and counted as a revert); the cost of the bound is the speed cap, which the step rate sets. *Event stepping* (`Stepping::Events`, the rows labelled `events`): one step per 128 Hz frame, in which each marble flies its closed form to its next event (a touch, a face's support ending, a stop) and on, as many times as the physics asks; its only speed limit is the number format's range. Its costs per simulated ms divide by 128 steps/s:\n"
    );
    let _ = writeln!(w, "| steps/s | speed cap pitch/s | mm/s |\n|---|---|---|");
    for k in STEPPINGS {
        let _ = writeln!(
            w,
            "| {} | {} | {} |",
            rate(k),
            sig(speed_cap(k)),
            sig(speed_cap(k) * 12.0)
        );
    }
    let _ = writeln!(w, "\nThe incline reaches 11.7 pitch/s and the bounce 24 pitch/s, so 128 steps/s caps both and 256 steps/s the bounce: the \"steps at cap\" column.\n");
    let _ = writeln!(w, "**Scenes** (src/study/; 12 mm pitch, 3.5 mm marble, e = 0.5; the tilt is set once per 128 Hz frame, as the firmware does; {SECONDS} s each):\n");
    let _ = writeln!(
        w,
        "| scene | board | tilt | effects | analytic |\n|---|---|---|---|---|"
    );
    let _ = writeln!(w, "| incline | 127 × 127-tile open floor | constant 2 mg along x' and z' | rolling | x₀ + ½·(5/7)·g·sinθ·t² (58 pitches in 10 s, 11.7 pitch/s, under the 64 pitch/s cap) |");
    let _ = writeln!(w, "| bounce | closed corridor, 1 × 25 cells (300 mm) | ±20 mg along it, flipping every 2.5 s; 10 mg into a side wall (always moving, up to 24 pitch/s) | rolling | – |");
    let _ = writeln!(w, "| maze | built-in level `switchback` (flat) | scripted: 30 mg along each row in turn (+x', −x', +x'), about 20 mg across so the marble drops through each row's opening, a ±45 mg triangle wobble (1.25 s) that rocks it back and forth; no autopilot | rolling, friction | – |");
    let _ = writeln!(w, "| corner | closed 3 × 3-cell box | constant 300 mg × 300 mg into a corner | rolling | rest at r from both walls |\n");
    let _ = writeln!(
        w,
        "**Accuracy**: distance (x', z') from an `f64` reference run at 2^{REFERENCE_STEP_LOG2} = {} steps/s after 1 s and 10 s, and the largest distance over the run (sampled every frame); distance from the analytic solution where one exists; energy: end-of-run ½·c·v² − g·x per unit mass (c = 7/5 rolling) minus the reference's, in % of the reference's largest kinetic energy (on the incline, where energy is conserved, this is the drift); overlap: the deepest penetration of the marble into any wall tile at the end of any step (the fixed step tolerates r/4 = 875 µm before it reverts; event steps end at frames); contacts and bounces from `World::stats`; steps at cap: steps that ended with a velocity axis at the speed cap.\n",
        1u32 << REFERENCE_STEP_LOG2
    );
    let _ = writeln!(
        w,
        "**Cost**: (1) host time per step: whole 10 s runs without instrumentation (`study::run_plain`), one warm-up then ≥ {} timed runs, the minimum reported (the median is in the per-scene tables; their difference is the noise, typically a few % — more for the shortest runs); profile `study` = release at opt-level 3 for every crate, ours and rapier2d alike. Host instructions per step: `valgrind --tool=callgrind` counting only inside `run_plain`, at {} steps/s and with event stepping (rapier2d at that rate). (2) Target instructions per step: the same runs (same code, same end state: the hashes are compared below) in QEMU 7.2 with `-icount shift=7,align=off,sleep=off`, counted by a hardware timer calibrated against a NOP loop of known length — Cortex-M4F on `mps2-an386` (`boards/qemu/src/bin/bench.rs`, TIMER0 at 25 MHz, 3.2 ticks per instruction) and Cortex-M0 on `microbit` (`study/bench-m0/src/main.rs`, nRF51 TIMER0 at 16 MHz, 2.048 ticks per instruction; built with i8f24, i16f16 and f32 only: the code of all six backends with event stepping overflows the nRF51's 256 KiB of flash), both built with the firmware's release profile (opt-level s, fat LTO; ARMv6-M with the v1's `-inline-threshold=0`, .cargo/config.toml). Per-step figures include the per-frame tilt update (`set_gravity_mg`, exact divisions, whenever the tilt changes). Instructions, not cycles: an M4 needs somewhat more cycles than instructions (loads, taken branches, divisions). Per simulated ms = per step × steps per simulated second ÷ 1000 (event stepping: 128 steps, one per frame, per simulated second).\n",
        if study.quick { 3 } else { 7 },
        1u32 << DEFAULT_STEP_LOG2
    );
    let _ = writeln!(w, "- Cortex-M4F: {}", target_status(&study.m4));
    let _ = writeln!(w, "- Cortex-M0: {}", target_status(&study.m0));
    let hash_check = |run: &Option<TargetRun>, m4: bool| -> String {
        let mut same = 0;
        let mut diff = Vec::new();
        for ((id, e, k), c) in &study.cells {
            let Engine::Ours(_) = e else { continue };
            let count = if m4 { &c.m4 } else { &c.m0 };
            if let Some(n) = count {
                if n.hash == c.out.hash {
                    same += 1;
                } else {
                    diff.push(format!(
                        "{} {} @ {}",
                        Scene::get(*id).name,
                        e.name(),
                        label(*k)
                    ));
                }
            }
        }
        if run.is_none() {
            return String::new();
        }
        diff.sort();
        if diff.is_empty() {
            format!("all {same} end-state hashes equal the host's")
        } else {
            format!(
                "{same} end-state hashes equal the host's, {} differ: {}",
                diff.len(),
                diff.join(", ")
            )
        }
    };
    if study.m4.is_some() {
        let _ = writeln!(w, "- Cortex-M4F vs host: {}", hash_check(&study.m4, true));
    }
    if study.m0.is_some() {
        let _ = writeln!(w, "- Cortex-M0 vs host: {}", hash_check(&study.m0, false));
    }
    if let Some(n) = &study.callgrind_note {
        let _ = writeln!(w, "- callgrind: {n}");
    }
    let _ = writeln!(w);

    // Headline table.
    let _ = writeln!(w, "## Configurations: accuracy against cost\n");
    let _ = writeln!(
        w,
        "One row per scalar backend × stepping: fixed steps at each rate (steps/s = 128 Hz frames × substeps) and event stepping (`events`: one step per frame). Errors in mm. Cost in the flat maze. ✔ = inside the accuracy target (suite error ≤ {TARGET_MM} mm, no revert, no lost marble, never at the speed cap); P = on the Pareto front of suite error vs M4 instructions per simulated ms.\n"
    );
    let _ = writeln!(
        w,
        "| config | suite error | rolling 10 s | rolling 1 s | rolling vs analytic | bounce max | bounce 10 s | corner rest | maze max | maze 10 s | max overlap µm | steps at cap | M4 instr/step | M4 instr/ms | M0 instr/ms | host ns/step | host instr/step | |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for c in &configs {
        let _ = writeln!(
            w,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {}{} |",
            c.name(),
            sig(c.suite),
            sig(c.roll10),
            sig(c.roll1),
            sig(c.roll_ana10),
            sig(c.bounce_max),
            sig(c.bounce10),
            sig(c.corner_ana10),
            sig(c.maze_max),
            sig(c.maze10),
            sig(c.pen_um),
            c.cap_hits,
            opt(c.m4_step),
            opt(c.m4_ms),
            opt(c.m0_ms),
            sig(c.host_ns),
            opt(c.host_ir),
            if c.accurate() { "✔" } else { "" },
            if c.pareto { " P" } else { "" }
        );
    }
    let _ = writeln!(w);
    let mut front: Vec<&Config> = configs.iter().filter(|c| c.pareto).collect();
    front.sort_by(|a, b| a.cost().total_cmp(&b.cost()));
    let _ = writeln!(
        w,
        "**Pareto front** (cheapest first; suite error, M4 instructions per simulated ms): {}.\n",
        front
            .iter()
            .map(|c| format!("{} ({} mm, {})", c.name(), sig(c.suite), sig(c.cost())))
            .collect::<Vec<_>>()
            .join(" → ")
    );
    let _ = writeln!(w, "![suite error vs cost](accuracy.png)\n");

    // Peer.
    let _ = writeln!(w, "## Against rapier2d\n");
    let _ = writeln!(
        w,
        "rapier2d 0.36 (f32, top view, mm; a ball on box colliders merged from the wall tiles, gravity = tangential tilt × 5/7 for rolling, restitution matched, frictionless walls, our rolling resistance as a force; `length_unit` = {} so its slop is 5 µm). Its error is measured against *our* f64 reference — the same idealised model — as the largest distance over the 10 s run. Compared: the recommended backend and the firmware's current `i8f24`, at the same step rate, and with event stepping against rapier2d at 1024 steps/s (rapier2d has no event mode). Ratios are per simulated second (per step × steps per second on each side). Host instructions (callgrind) at the default rate and with events only.\n",
        super::peer::LENGTH_UNIT
    );
    let backs = peer_backends(&configs);
    let mut head = String::from(
        "| ours | rapier2d steps/s | scene | rapier2d: max error mm | ns/step | instr/step |",
    );
    let mut rule = String::from("|---|---|---|---|---|---|");
    for &b in &backs {
        let _ = write!(
            head,
            " {0}: max error mm | ns/step | instr/step | time ratio per sim. s | instr ratio per sim. s |",
            BACKENDS[b]
        );
        rule.push_str("---|---|---|---|---|");
    }
    let _ = writeln!(w, "{head}\n{rule}");
    for k in STEPPINGS {
        for s in Scene::all() {
            let Some(r) = study.cells.get(&(s.id, Engine::Rapier, peer_rate(k))) else {
                continue;
            };
            let mut row = format!(
                "| {} | {} | {} | {} | {} | {} |",
                label(k),
                1u32 << peer_rate(k),
                s.name,
                sig(r.err_max),
                sig(r.host.min_ns),
                opt(r.host_ir)
            );
            for &b in &backs {
                let Some(o) = study.cells.get(&(s.id, Engine::Ours(b), k)) else {
                    continue;
                };
                let (t, ir, good) = versus(study, s.id, b, k).unwrap_or((f64::NAN, None, false));
                let mark = if good { "" } else { " ✗" };
                let _ = write!(
                    row,
                    " {}{mark} | {} | {} | {}× | {} |",
                    sig(o.err_max),
                    sig(o.host.min_ns),
                    opt(o.host_ir),
                    sig(t),
                    ir.map(|i| format!("{}×", sig(i)))
                        .unwrap_or_else(|| "–".into())
                );
            }
            let _ = writeln!(w, "{row}");
        }
    }
    let _ = writeln!(
        w,
        "\n✗: our error is larger than rapier2d's there (or our run reached the speed cap).\n"
    );

    // Effects.
    let _ = writeln!(
        w,
        "## What each effect costs (and that a scene without it does not pay)\n"
    );
    let _ = writeln!(
        w,
        "`i8f24` at {} steps/s and with event stepping, the maze (`switchback`) and the bounce corridor with effect sets switched on one by one. `World::stats` counts every run of an effect's code: a switched-off effect's counter stays 0, and its cost is one predictable branch per step. `board_motion` runs with the board held still (its code runs, its physics is idle); `marbles` with one marble only costs its branch (the pair code needs two). Where an effect changes the physics (rolling, friction, holes) the marble takes a different path, so part of a difference is the path (e.g. more or fewer wall contacts); `board_motion` with a still board keeps the path, so its row is its code alone.\n",
        1u32 << DEFAULT_STEP_LOG2
    );
    let _ = writeln!(w, "| scene | stepping | effects | M4 instr/step | M4 instr/ms | M0 instr/step | M0 instr/ms | host ns/step | contacts | friction runs | board-motion runs | 3-D runs | pair runs |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|");
    for scene in [SceneId::Maze, SceneId::Bounce] {
        let name = Scene::get(scene).name;
        for k in VARIANT_STEPPINGS {
            for (v, (vn, _)) in EFFECT_VARIANTS.iter().enumerate() {
                let Some((out, t)) = study.variants.get(&(scene, v, k)) else {
                    continue;
                };
                let key = (name.to_string(), BACKENDS[0].to_string(), vn.to_string(), k);
                let m4 = study
                    .m4
                    .as_ref()
                    .and_then(|r| r.counts.get(&key))
                    .map(|c| c.per_step());
                let m0 = study
                    .m0
                    .as_ref()
                    .and_then(|r| r.counts.get(&key))
                    .map(|c| c.per_step());
                let s = out.stats;
                let ms = |x: Option<f64>| opt(x.map(|x| x * per_second(k) / 1000.0));
                let _ = writeln!(
                    w,
                    "| {name} | {} | {vn} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
                    label(k),
                    opt(m4),
                    ms(m4),
                    opt(m0),
                    ms(m0),
                    sig(t.min_ns),
                    s.contacts,
                    s.friction_runs,
                    s.board_motion_runs,
                    s.space_runs,
                    s.pair_runs
                );
            }
        }
    }
    let _ = writeln!(w);

    // Hot spots.
    if !study.profiles.is_empty() {
        let _ = writeln!(
            w,
            "## Where the time goes (host): the default configuration and event stepping\n"
        );
        let _ = writeln!(
            w,
            "callgrind, x86-64 instructions inside `run_plain`, self cost per function (generic arguments elided). The target's mix differs (the M4 has no 64-bit multiply-high, the M0 no divide), but the ranking shows what to make cheaper first.\n"
        );
        for (title, rows) in &study.profiles {
            let _ = writeln!(w, "**{title}**\n\n| share | function |\n|---|---|");
            for (pct, f) in rows {
                let _ = writeln!(w, "| {pct:.1} % | `{f}` |");
            }
            let _ = writeln!(w);
        }
    }

    // Per-scene tables.
    let _ = writeln!(w, "## Per scene\n");
    for s in Scene::all() {
        let r = &study.reference[&s.id];
        let _ = writeln!(
            w,
            "### {}\n\nReference (f64 @ {}): at 10 s ({}, {}) mm, {} contacts, {} bounces, largest overlap {} µm.\n",
            s.name,
            1u32 << REFERENCE_STEP_LOG2,
            sig(r.pos10[0]),
            sig(r.pos10[1]),
            r.contacts,
            r.collisions,
            sig(r.max_pen_um)
        );
        let _ = writeln!(w, "| engine | steps/s | error 1 s | error 10 s | max error | vs analytic 1 s | vs analytic 10 s | energy % | max overlap µm | contacts | bounces | reverts | steps at cap | host ns/step (min / median) | M4 instr/step | M0 instr/step |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        let mut engines: Vec<Engine> = (0..BACKENDS.len()).map(Engine::Ours).collect();
        engines.push(Engine::Rapier);
        for e in engines {
            for k in STEPPINGS {
                let Some(c) = study.cells.get(&(s.id, e, k)) else {
                    continue;
                };
                let _ = writeln!(
                    w,
                    "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {}{} | {} | {} / {} | {} | {} |",
                    e.name(),
                    rate(k),
                    sig(c.err1),
                    sig(c.err10),
                    sig(c.err_max),
                    opt(c.ana1),
                    opt(c.ana10),
                    sig(c.energy_pct),
                    sig(c.out.max_pen_um),
                    c.out.contacts,
                    c.out.collisions,
                    c.out.reverts,
                    if c.out.out { " (left the board)" } else { "" },
                    if e == Engine::Rapier { "–".to_string() } else { c.out.cap_hits.to_string() },
                    sig(c.host.min_ns),
                    sig(c.host.median_ns),
                    opt(c.m4.as_ref().map(|n| n.per_step())),
                    opt(c.m0.as_ref().map(|n| n.per_step()))
                );
            }
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w, "For rapier2d, \"contacts\" counts steps with an active contact and \"bounces\" velocity reversals at a contact; it has no reverts.\n");
    md
}
