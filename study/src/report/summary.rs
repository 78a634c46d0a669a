//! The short summary printed at the end of `cargo accuracy`.

use std::fmt::Write;

use marble_rolling::study::{is_events, Scene, BACKENDS, DEFAULT_STEP_LOG2, EVENTS_LOG2};

use super::super::{Study, PEERS};
use super::config::{configs, current_default, recommended, Config};
use super::peers::{peer_rate, peer_verdict, versus};
use super::{label, opt, sig};

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
    for peer in PEERS {
        let name = peer.title();
        if let Some(v) = peer_verdict(study, &configs, peer) {
            let _ = writeln!(
                s,
                "  vs {name} at {} steps/s, {} @ {}, per simulated s: ≥ {}× less host time (worst scene: {}), ≥ {}× fewer host instructions, {}",
                1u32 << v.peer_k,
                BACKENDS[v.backend],
                label(v.k),
                sig(v.time.0),
                Scene::get(v.time.1).name,
                opt(v.instructions.map(|i| i.0)),
                if v.as_good { "as accurate or better in every judged scene" } else { "less accurate in some judged scene" }
            );
        }
        // Per scene, the default backend with events and at 1024 steps/s.
        for k in [EVENTS_LOG2, DEFAULT_STEP_LOG2] {
            for sc in Scene::all() {
                if let Some((t, ir, good)) = versus(study, peer, sc.id, 0, k) {
                    let _ = writeln!(
                        s,
                        "    {} @ {} vs {name} @ {}, {}: {}× less time, {} fewer instructions per simulated s{}",
                        BACKENDS[0],
                        label(k),
                        1u32 << peer_rate(peer, k),
                        sc.name,
                        sig(t),
                        ir.map(|i| format!("{}×", sig(i))).unwrap_or_else(|| "–".into()),
                        if good { "" } else { " (less accurate)" }
                    );
                }
            }
        }
    }
    s
}
