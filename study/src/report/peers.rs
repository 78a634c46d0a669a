//! Ours against the peers (rapier2d and Box2D v3): the rates compared, the
//! ratios per simulated second, the verdict's figures and the table.

use std::fmt::Write;

use marble_rolling::study::{is_events, Scene, SceneId, BACKENDS, DEFAULT_STEP_LOG2, STEPPINGS};

use super::super::peer::{box2d, rapier};
use super::super::{Engine, Study, PEERS};
use super::config::{current_default, recommended, Config};
use super::{label, opt, per_second, sig};

/// Box2D's recommended setting: 4 substeps a step, at the study's 128 Hz frames
/// 512 steps/s.
pub const BOX2D_STEP_LOG2: u32 = 9;

/// The backends compared with the peers: the recommended one and the
/// firmware's current `i8f24` (once if they are the same).
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

/// The peer's rate ours at `k` is compared with: the same rate, and for events
/// (the peers have no event mode) rapier2d at the firmware's 1024 steps/s and
/// Box2D at its recommended 4 substeps.
pub fn peer_rate(peer: Engine, k: u32) -> u32 {
    match peer {
        _ if !is_events(k) => k,
        Engine::Box2d => BOX2D_STEP_LOG2,
        _ => DEFAULT_STEP_LOG2,
    }
}

/// The rates a peer's host instructions are counted at: the default rate and
/// the one our event stepping is compared with.
pub fn callgrind_rates(peer: Engine) -> Vec<u32> {
    let mut v = vec![DEFAULT_STEP_LOG2];
    let e = peer_rate(peer, marble_rolling::study::EVENTS_LOG2);
    if !v.contains(&e) {
        v.push(e);
    }
    v
}

/// Backend `b` at `k` against `peer` at [`peer_rate`] in one scene, per
/// simulated second: (time ratio, instruction ratio, as accurate).
pub fn versus(
    study: &Study,
    peer: Engine,
    id: SceneId,
    b: usize,
    k: u32,
) -> Option<(f64, Option<f64>, bool)> {
    let rk = peer_rate(peer, k);
    let r = study.cells.get(&(id, peer, rk))?;
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

/// The recommended configuration (else the current default) against a peer,
/// per simulated second, over the scenes.
#[derive(Clone, Copy, Debug)]
pub struct PeerVerdict {
    /// Our backend.
    pub backend: usize,
    /// Our stepping.
    pub k: u32,
    /// The peer's stepping.
    pub peer_k: u32,
    /// The smallest time ratio, and its scene.
    pub time: (f64, SceneId),
    /// The smallest instruction ratio, and its scene (callgrind).
    pub instructions: Option<(f64, SceneId)>,
    /// Ours as accurate or better in every judged scene (not the maze).
    pub as_good: bool,
}

/// The recommended configuration (else the current default) against `peer`.
pub fn peer_verdict(study: &Study, configs: &[Config], peer: Engine) -> Option<PeerVerdict> {
    let c = recommended(configs).or_else(|| current_default(configs))?;
    let (b, k) = (c.backend, c.k);
    let mut time: Option<(f64, SceneId)> = None;
    let mut instructions: Option<(f64, SceneId)> = None;
    let mut as_good = true;
    for s in Scene::all() {
        let (t, ir, good) = versus(study, peer, s.id, b, k)?;
        // Judged on the suite's scenes, like the accuracy target (not the maze).
        as_good &= good || s.id == SceneId::Maze;
        if time.is_none_or(|(w, _)| t < w) {
            time = Some((t, s.id));
        }
        if let Some(ir) = ir {
            if instructions.is_none_or(|(w, _)| ir < w) {
                instructions = Some((ir, s.id));
            }
        }
    }
    Some(PeerVerdict {
        backend: b,
        k,
        peer_k: peer_rate(peer, k),
        time: time?,
        instructions,
        as_good,
    })
}

/// How a peer is set up, for the report.
fn description(peer: Engine) -> String {
    match peer {
        Engine::Box2d => format!(
            "Box2D {} (the development snapshot the `boxdd` 0.6 crate pins; C, f32; built by `cc` at -O3 like the study; one worker thread): a circle on box polygons, one static body per merged wall box, its rotation locked; 1 mm of the study = 0.1 m to Box2D ({} length units per metre), so the 3.5 mm marble is the 0.35 m ball its tolerances are tuned for (linear slop 50 µm, restitution threshold 10 mm/s, sleep below 0.5 mm/s); continuous collision, soft contacts and sleeping as its defaults have them. Stepped once per 128 Hz frame with 2^(k−7) substeps (`b2World_Step(1/128, n)`): `steps/s` counts substeps, so a per-step figure is per substep; its overlap, contacts and bounces are sampled once per frame. Event stepping is compared with 512 steps/s (128 Hz × 4 substeps, Box2D's recommended setting).",
            box2d::version(),
            box2d::LENGTH_UNITS_PER_METRE
        ),
        _ => format!(
            "rapier2d 0.36 (Rust, f32): a ball collider on cuboid colliders; `length_unit` = {} so its slop is 5 µm; CCD as its defaults have it. Stepped at the study's rate (`PhysicsWorld::step` with `dt` = 1/rate). Event stepping is compared with 1024 steps/s, the firmware's fixed rate.",
            rapier::LENGTH_UNIT
        ),
    }
}

/// `## Against the peers`: one table per peer.
pub fn section(w: &mut String, study: &Study, configs: &[Config]) {
    let _ = writeln!(w, "## Against the peers: rapier2d and Box2D v3\n");
    let _ = writeln!(
        w,
        "Both peers get the same scene, top view, in mm: a disc on fixed boxes merged from the wall tiles (a straight wall is one box), gravity = the tangential tilt × 5/7 when the scene rolls (a 2-D disc cannot roll; the same reduction ours applies), restitution matched, frictionless walls, our rolling resistance as a force against the motion with static hold below it. Not modelled: our restitution threshold and our speed cap. Their error is measured against *our* f64 reference — the same idealised model — as the largest distance over the 10 s run; the overlap is the same depth into a wall tile as ours. Compared: the recommended backend and the firmware's current `i8f24`, at the same step rate, and with event stepping against each peer's reference rate (the peers have no event mode). Ratios are per simulated second (per step × steps per second on each side). Host instructions (callgrind) at the default rate and at the event-stepping comparison rate only.\n"
    );
    let backs = peer_backends(configs);
    for peer in PEERS {
        let name = peer.title();
        let _ = writeln!(w, "### {name}\n\n{}\n", description(peer));
        let mut head =
            format!("| ours | {name} steps/s | scene | {name}: max error mm | max overlap µm | ns/step | instr/step |");
        let mut rule = String::from("|---|---|---|---|---|---|---|");
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
            let pk = peer_rate(peer, k);
            for s in Scene::all() {
                let Some(r) = study.cells.get(&(s.id, peer, pk)) else {
                    continue;
                };
                let mut row = format!(
                    "| {} | {} | {} | {} | {} | {} | {} |",
                    label(k),
                    1u32 << pk,
                    s.name,
                    sig(r.err_max),
                    sig(r.out.max_pen_um),
                    sig(r.host.min_ns),
                    opt(r.host_ir)
                );
                for &b in &backs {
                    let Some(o) = study.cells.get(&(s.id, Engine::Ours(b), k)) else {
                        continue;
                    };
                    let (t, ir, good) =
                        versus(study, peer, s.id, b, k).unwrap_or((f64::NAN, None, false));
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
            "\n✗: our error is larger than {name}'s there (or our run reached the speed cap).\n"
        );
    }
}
