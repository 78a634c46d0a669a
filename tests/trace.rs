//! The `sim` trace's sampler ([`marble_rolling::host::motion_trace::step_sampled`]) on
//! worlds driven directly: event steps sampled every 1/1024 s end where the step
//! ends, and two marbles pressed together never overlap in any sample.

use marble_rolling::game::levels::by_name;
use marble_rolling::game::rules::{Game, GameConfig};
use marble_rolling::host::motion_trace::{sample, samples_per_step, step_sampled, FlightLog};
use marble_rolling::physics::{Fx, Scalar};

/// The built-in two-marble level in event stepping, one step per 1/128 s frame.
fn two_marbles<S: Scalar>() -> Game<'static, S> {
    let (_, level) = by_name("two-marbles").expect("built-in level");
    Game::new(level, GameConfig::EVENTS).expect("sets up")
}

/// Tilts (milli-g, tile frame) that roll the marbles into each other and apart:
/// 300 mg along z' one way, then the other, then along x'.
fn tilt(frame: u32) -> [i32; 3] {
    match frame / 128 {
        0 => [0, -1000, -300],
        1 => [0, -1000, 300],
        2 => [300, -1000, -300],
        _ => [-300, -1000, 300],
    }
}

fn check<S: Scalar>() {
    let mut game = two_marbles::<S>();
    let w = game.world_mut();
    assert!(w.params().events());
    let samples = samples_per_step(w);
    assert_eq!(samples, 8, "1/1024 s in a 1/128 s step");
    let layout = w.params().layout;
    let mm = |v: S| layout.to_mm(v);
    let two_r = 2.0 * mm(w.params().radius);
    let mut log = FlightLog::default();
    let (mut exact, mut closest, mut flights) = (0u32, f64::INFINITY, 0usize);
    let frames = 4 * 128;
    for frame in 0..frames {
        w.set_gravity_mg(tilt(frame));
        let before = w.marbles().to_vec();
        let (slices, cuts) = (w.stats.slices, w.stats.budget_cuts);
        let rows = step_sampled(w, &mut log, samples);
        assert_eq!(rows.len(), samples as usize);
        let after = w.marbles();
        // The last row is the world after the step, every marble.
        let last = rows.last().unwrap();
        assert_eq!(last.len(), after.len());
        for (n, m) in after.iter().enumerate() {
            assert_eq!(last[n], (m.pos, m.vel), "frame {frame} marble {n}");
            // Sampling the flights at the step's end agrees with it: exactly,
            // unless a slice ended there: a plain slice's contact passes push the
            // marble out by a hair at that instant (two marbles pressed
            // together), a pivot slice puts it back on the sphere about its edge,
            // by at most r·δθ²/2 for the turn δθ ≤ √2/8 rad a pivot slice allows
            // (r/64); or unless the flight budget cut the step, whose pair code
            // pushes apart two marbles the cut left at different times.
            let (p, _) = sample(log.of(n), &before[n], S::ONE);
            let d = (mm(p.x) - mm(m.pos.x))
                .hypot(mm(p.y) - mm(m.pos.y))
                .hypot(mm(p.z) - mm(m.pos.z));
            if w.stats.slices == slices && w.stats.budget_cuts == cuts {
                assert_eq!(p, m.pos, "frame {frame} marble {n}");
                exact += 1;
            } else {
                let bound = 0.002 + two_r / 2.0 / 64.0;
                assert!(d < bound, "frame {frame} marble {n}: {d} mm from the world");
            }
            flights += log.of(n).len();
        }
        // No two marbles overlap at any sampled instant.
        for row in &rows {
            let (a, b) = (row[0].0, row[1].0);
            let d = (mm(a.x) - mm(b.x))
                .hypot(mm(a.y) - mm(b.y))
                .hypot(mm(a.z) - mm(b.z));
            closest = closest.min(d);
        }
    }
    assert!(flights > 0, "event steps report their flights");
    assert!(exact >= 100, "only {exact} step ends without a slice");
    assert!(
        closest >= two_r - 0.01,
        "{} marbles {closest} mm apart (2r = {two_r} mm)",
        S::NAME
    );
    assert!(closest < two_r + 0.1, "the marbles met: {closest} mm");
}

#[test]
fn event_samples_end_at_the_step_and_marbles_never_overlap() {
    check::<Fx>();
    check::<f64>();
}
