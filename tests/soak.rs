//! The soak: 24 hours of simulated play — the autopilot through every built-in level
//! in turn, interleaved with bouts of random shaking — with the invariants checked
//! every frame. Marked `#[ignore]` for `cargo test` (it takes minutes in a debug
//! build); CI runs it in release speed with overflow checks on:
//!
//!     cargo test --profile soak --test soak -- --ignored
//!
//! (`SOAK_SECONDS` overrides the 24 hours, e.g. for a quick look.)

mod common;

use common::Lcg;
use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::physics::geometry::broadphase::candidates;
use marble_rolling::physics::geometry::narrowphase::offset;
use marble_rolling::physics::{Fx, Scalar};

/// 24 hours with fixed steps, the stepper this soak was written for (and the
/// study's baseline).
#[test]
#[ignore = "minutes in a debug build; CI runs it with --profile soak"]
fn twenty_four_hours_of_play() {
    soak(GameConfig::FIXED);
}

/// The same 24 hours with event stepping, the default on every board. It found
/// two ways off the board under ±2 g shaking, both in grand-tour after a marble
/// fell through a hole by the border wall: held up against the floor slab's
/// underside at exactly `−s − r` and carried along it by the shaken board's
/// surface velocity (frame 539 521), and rolled round the border slab's lower
/// edges out from under the board (frame 659 548). A marble at or below
/// `−s − r`, or with its centre past the board's edge, is now out.
#[test]
#[ignore = "minutes in a debug build; CI runs it with --profile soak"]
fn twenty_four_hours_of_play_with_events() {
    soak(GameConfig::DEFAULT);
}

fn soak(config: GameConfig) {
    let seconds: u64 = std::env::var("SOAK_SECONDS")
        .ok()
        .and_then(|h| h.parse().ok())
        .unwrap_or(24 * 3600);
    let total_frames = seconds * config.frame_hz() as u64;
    let mut rng = Lcg(2026);
    let (mut frames, mut wins, mut falls, mut timeouts, mut shaken) =
        (0u64, 0u32, 0u32, 0u32, 0u64);
    let mut level = 0usize;
    while frames < total_frames {
        let view = LEVELS[level % LEVELS.len()];
        let mut session = Session::<Fx>::new(view, config, SYNTHETIC_TILT).expect("built-in level");
        let mut ap = Autopilot::new(&view);
        // Every third attempt starts with a bout of shaking (random readings up to ±2 g,
        // the sensor's range), then the autopilot takes over from wherever it ended up.
        let shake_frames = if level % 3 == 2 {
            rng.range(128, 2048) as u64
        } else {
            0
        };
        let mut n = 0u64;
        loop {
            let phase = if n < shake_frames {
                shaken += 1;
                session.frame(AccelMg::new(
                    rng.range(-2000, 2000),
                    rng.range(-500, 2000),
                    rng.range(-2000, 2000),
                ))
            } else {
                session.autopilot_frame(&mut ap)
            };
            n += 1;
            frames += 1;
            check(&session, frames);
            match phase {
                Phase::Playing => {}
                Phase::Won => {
                    wins += 1;
                    break;
                }
                Phase::Fell => {
                    falls += 1;
                    break;
                }
                Phase::TimeUp => {
                    timeouts += 1;
                    break;
                }
            }
            if frames >= total_frames {
                break;
            }
        }
        level += 1;
    }
    println!(
        "soak: {seconds} s = {frames} frames, {level} attempts: {wins} won, {falls} fell, {timeouts} timed out; {shaken} frames shaken"
    );
    assert!(wins > 0);
}

/// Invariants after every frame: every marble in play keeps its radius from every
/// tile, stays on the board's extent, and no step was ever undone.
fn check(session: &Session<'_, Fx>, frame: u64) {
    let w = session.game().world();
    let p = w.params();
    let r = p.radius.to_f64();
    let (ex, ez) = w.extent();
    for m in w.marbles().iter().filter(|m| !m.out) {
        for t in candidates(&p.layout, m.pos, p.radius).solid(w.tiles()) {
            let d = offset(m.pos, &p.layout.tile_box(t)).to_f64();
            let dist = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            assert!(
                dist >= r * (1.0 - 1e-3),
                "frame {frame}: clearance {dist} < r {r}"
            );
        }
        // On the floor or above it (below, it is falling through a hole: out soon).
        let on_board = m.pos.y < Fx::ZERO
            || (m.pos.x >= Fx::ZERO && m.pos.z >= Fx::ZERO && m.pos.x <= ex && m.pos.z <= ez);
        assert!(
            on_board,
            "frame {frame}: off the board: {:?} level {} g {:?}",
            m,
            session.game().level().info.name,
            w.gravity_mg()
        );
        let v = m.vel.to_f64();
        assert!(
            v.iter().all(|c| c.abs() <= p.v_max.to_f64()),
            "frame {frame}: over the speed cap"
        );
    }
    assert_eq!(w.stats.reverts, 0, "frame {frame}: a step was undone");
}
