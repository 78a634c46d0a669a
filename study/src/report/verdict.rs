//! The report's verdict: the targets, the recommended firmware default, and
//! what the firmware links.

use std::fmt::Write;

use marble_rolling::game::rules::DEFAULT_EVENTS;
use marble_rolling::study::{is_events, Scene, BACKENDS, DEFAULT_STEP_LOG2, FRAME_LOG2};

use super::super::{Engine, Study, PEERS};
use super::config::{cheapest, current_default, recommended, speed_cap, Config};
use super::peers::{peer_verdict, BOX2D_STEP_LOG2};
use super::{label, opt, sig, verdict, BUDGET_M0_PER_MS, BUDGET_PER_MS, PEER_FACTOR, TARGET_MM};

/// `## Verdict`.
pub fn section(w: &mut String, study: &Study, configs: &[Config]) {
    let rec = recommended(configs);
    let any = cheapest(configs, false);
    let cur = current_default(configs);
    let _ = writeln!(w, "## Verdict\n");
    let _ = writeln!(
        w,
        "**Accuracy target**: the *suite error* — the worst of (a) rolling: distance from the f64 reference after 10 s on the incline, (b) bouncing: the largest distance from the reference over the 10 s corridor run, (c) resting: distance from the analytic rest position in the corner — within {TARGET_MM} mm; and sound: no reverted step, no lost marble, the speed cap never reached in the suite. The maze is reported but not judged (see its row: even f64 at 4096 steps/s is 0.3 mm off the 16384 steps/s path at some moment, because when a bounce or a static-friction hold falls depends on the step).\n"
    );
    let _ = writeln!(w, "| target | result |\n|---|---|");
    let _ = writeln!(
        w,
        "| within {TARGET_MM} mm of the f64 reference after 10 s at ≤ {BUDGET_PER_MS} Cortex-M4 (≤ {BUDGET_M0_PER_MS} Cortex-M0) instructions per marble per simulated ms in a flat maze, at the firmware default | {} — {} |",
        verdict(rec.and_then(|r| r.affordable())),
        match rec {
            Some(r) => format!(
                "the cheapest configuration inside the accuracy target (with the full speed range), event stepping and fixed steps alike, is **{}** at {} M4 instructions per simulated ms ({} per step; {}) and {} M0 instructions per simulated ms ({})",
                r.name(),
                opt(r.m4_ms),
                opt(r.m4_step),
                against(r.m4_ms, BUDGET_PER_MS),
                opt(r.m0_ms),
                against(r.m0_ms, BUDGET_M0_PER_MS)
            ),
            None => "no configuration reaches the accuracy target".into(),
        }
    );
    for peer in PEERS {
        let v = peer_verdict(study, configs, peer);
        let name = peer.title();
        // rapier2d carries the study's target; Box2D v3, the field's reference,
        // is reported beside it.
        let (target, met) = if peer == Engine::Rapier {
            (
                format!("≥ {PEER_FACTOR}× fewer host instructions per simulated second than {name} at {} steps/s, at equal or better accuracy, in every scene", 1u32 << DEFAULT_STEP_LOG2),
                verdict(v.and_then(|v| v.instructions.map(|(i, _)| v.as_good && i >= PEER_FACTOR))),
            )
        } else {
            (
                format!("host instructions per simulated second and accuracy against {name} at 128 Hz × {} substeps (its recommended setting), in every scene: reported beside rapier2d, no target", 1u32 << (BOX2D_STEP_LOG2 - FRAME_LOG2)),
                "**reported**",
            )
        };
        let _ = writeln!(
            w,
            "| {target} | {met} — {} |",
            match v {
                Some(v) => format!(
                    "`{} @ {}` (the recommended default) against {name} at {} steps/s: at least **{}×** fewer host instructions (callgrind; worst scene: {}) and {}× less host time (worst scene: {}) per simulated second, {}",
                    BACKENDS[v.backend],
                    label(v.k),
                    1u32 << v.peer_k,
                    opt(v.instructions.map(|i| i.0)),
                    v.instructions.map_or("–", |i| Scene::get(i.1).name),
                    sig(v.time.0),
                    Scene::get(v.time.1).name,
                    if v.as_good { "with a smaller largest error in every judged scene (incline, bounce, corner)" } else { "but not as accurate in every judged scene" }
                ),
                None => "not measured".into(),
            }
        );
    }
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
                "**Flash**: not measured by the study (it builds benchmarks, not the firmware). The firmware links one stepper, chosen at compile time (`Player<W, H, PILOT, EVENTS>`), and every board links {} (`EVENTS` is `game::rules::DEFAULT_EVENTS` in each board's src/main.rs) inside its flash budget: 144 KiB on the micro:bit v2 (`cargo xtask size-report`) and 144 KiB on the micro:bit v1 (`cargo xtask check-microbit-v1`); CI runs both, and docs/boards.md (\"Budget\") has their figures.\n",
                if DEFAULT_EVENTS { "the event stepper" } else { "fixed steps" }
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
}

/// A cost against its budget, in words.
fn against(cost: Option<f64>, budget: f64) -> String {
    match cost {
        Some(c) if c > budget => format!("{}× over the budget", sig(c / budget)),
        Some(_) => "inside the budget".into(),
        None => "no target count".into(),
    }
}
