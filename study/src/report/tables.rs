//! The report's tables: our configurations, what each effect costs, the host
//! hot spots and every scene in detail.

use std::fmt::Write;

use marble_rolling::study::{
    Scene, SceneId, BACKENDS, DEFAULT_STEP_LOG2, EFFECT_VARIANTS, REFERENCE_STEP_LOG2, STEPPINGS,
    VARIANT_STEPPINGS,
};

use super::super::{Engine, Study, PEERS};
use super::config::Config;
use super::{label, opt, per_second, rate, sig, TARGET_MM};

/// `## Configurations: accuracy against cost`, with the Pareto front and the chart.
pub fn headline(w: &mut String, configs: &[Config]) {
    let _ = writeln!(w, "## Configurations: accuracy against cost\n");
    let _ = writeln!(
        w,
        "One row per scalar backend × stepping: fixed steps at each rate (steps/s = 128 Hz frames × substeps) and event stepping (`events`: one step per frame). Errors in mm. Cost in the flat maze. ✔ = inside the accuracy target (suite error ≤ {TARGET_MM} mm, no revert, no lost marble, never at the speed cap); P = on the Pareto front of suite error vs M4 instructions per simulated ms.\n"
    );
    let _ = writeln!(
        w,
        "| config | suite error | rolling 10 s | rolling 1 s | rolling vs analytic | bounce max | bounce 10 s | corner rest | maze max | maze 10 s | max overlap µm | steps at cap | M4 instr/step | M4 instr/ms | M0 instr/ms | host ns/step | host instr/step | |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for c in configs {
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
}

/// `## What each effect costs`.
pub fn effects(w: &mut String, study: &Study) {
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
}

/// `## Where the time goes (host)`.
pub fn hot_spots(w: &mut String, study: &Study) {
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
}

/// `## Per scene`.
pub fn scenes(w: &mut String, study: &Study) {
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
        engines.extend(PEERS);
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
                    if e.is_peer() { "–".to_string() } else { c.out.cap_hits.to_string() },
                    sig(c.host.min_ns),
                    sig(c.host.median_ns),
                    opt(c.m4.as_ref().map(|n| n.per_step())),
                    opt(c.m0.as_ref().map(|n| n.per_step()))
                );
            }
        }
        let _ = writeln!(w);
    }
    let _ = writeln!(w, "For the peers, \"contacts\" counts steps (Box2D: frames) that end with an active contact and \"bounces\" velocity reversals at a contact; they have no reverts.\n");
}
