//! `## What is measured`: stepping modes, scenes, the accuracy and cost
//! methods, and the target runs' status.

use std::fmt::Write;

use marble_rolling::study::{Scene, DEFAULT_STEP_LOG2, REFERENCE_STEP_LOG2, SECONDS, STEPPINGS};

use super::super::target::TargetRun;
use super::super::{Engine, Study};
use super::config::speed_cap;
use super::{label, rate, sig, target_status};

/// `## What is measured`.
pub fn section(w: &mut String, study: &Study) {
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
        "**Cost**: (1) host time per step: whole 10 s runs without instrumentation (`study::run_plain`), one warm-up then ≥ {} timed runs, the minimum reported (the median is in the per-scene tables; their difference is the noise, typically a few % — more for the shortest runs); profile `study` = release at opt-level 3 for every crate, ours and the peers alike (Box2D's C sources at -O3 through `cc`). Host instructions per step: `valgrind --tool=callgrind` counting only inside `run_plain`, at {} steps/s and with event stepping (the peers at that rate and at the rate event stepping is compared with). (2) Target instructions per step: the same runs (same code, same end state: the hashes are compared below) in QEMU 7.2 with `-icount shift=7,align=off,sleep=off`, counted by a hardware timer calibrated against a NOP loop of known length — Cortex-M4F on `mps2-an386` (`boards/qemu/src/bin/bench.rs`, TIMER0 at 25 MHz, 3.2 ticks per instruction) and Cortex-M0 on `microbit` (`study/bench-m0/src/main.rs`, nRF51 TIMER0 at 16 MHz, 2.048 ticks per instruction; built with i8f24, i16f16 and f32 only: the code of all six backends with event stepping overflows the nRF51's 256 KiB of flash), both built with the firmware's release profile (opt-level s, fat LTO; ARMv6-M with LLVM's default inlining, as the v1 firmware: .cargo/config.toml). Per-step figures include the per-frame tilt update (`set_gravity_mg`, exact divisions, whenever the tilt changes). Instructions, not cycles: an M4 needs somewhat more cycles than instructions (loads, taken branches, divisions). Per simulated ms = per step × steps per simulated second ÷ 1000 (event stepping: 128 steps, one per frame, per simulated second).\n",
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
}
