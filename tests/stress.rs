//! The stress scenes (`game::stress`) do what they are named for, on the host,
//! with the stepper every board plays: the QEMU demo counts their frames'
//! instructions, and a scene that quietly stopped stressing anything would make
//! that bound mean nothing. Each scene is also held to the stability rules: no
//! marble inside a tile or another marble by more than 5 µm, none out of a closed
//! maze.
mod common;

use common::min_clearance;
use marble_rolling::game::rules::GameConfig;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::game::stress::{StressScene, STRESS};
use marble_rolling::physics::{Fx, Scalar};

fn scene(name: &str) -> StressScene {
    *STRESS
        .iter()
        .find(|s| s.level.info.name == name)
        .unwrap_or_else(|| panic!("no stress scene {name}"))
}

/// What a scene did, frame by frame.
#[derive(Default)]
struct Seen {
    /// Bounces (eq. 1 with `e`).
    bounces: u32,
    /// Each frame's storey of each marble.
    storeys: Vec<Vec<i32>>,
    /// The closest two marbles came (pitch), between their surfaces.
    closest_pair: f64,
    /// The least clearance of any marble from any tile, minus its radius (pitch).
    deepest: f64,
    /// Each frame's flights (`StepStats::flights`) and marble-steps the flight
    /// budget cut.
    flights: Vec<(u32, u32)>,
    /// Each frame's drop of the first marble below where it was after the
    /// first frame, in radii.
    drop: Vec<f64>,
}

fn play(s: &StressScene) -> Seen {
    let mut session =
        Session::<Fx>::new(s.level, GameConfig::DEFAULT, SYNTHETIC_TILT).expect("scene sets up");
    let mut seen = Seen {
        closest_pair: f64::INFINITY,
        deepest: f64::INFINITY,
        ..Seen::default()
    };
    let mut first_y = None;
    for frame in 0..s.frames {
        let before = session.game_mut().world_mut().stats;
        session.frame((s.tilt)(frame));
        let w = session.game_mut().world_mut();
        seen.flights.push((
            w.stats.flights - before.flights,
            w.stats.budget_cuts - before.budget_cuts,
        ));
        seen.bounces += u32::from(w.take_impacts().count);
        let p = *w.params();
        let r = p.radius.to_f64();
        let ms = w.marbles();
        assert!(
            ms.iter().all(|m| !m.out),
            "{} frame {frame}: a marble left the closed maze",
            s.level.info.name
        );
        let y = ms[0].pos.y.to_f64();
        let start = *first_y.get_or_insert(y);
        seen.drop.push((start - y) / r);
        seen.storeys
            .push(ms.iter().map(|m| p.layout.storey_of(m.pos.y)).collect());
        for n in 0..ms.len() {
            seen.deepest = seen.deepest.min(min_clearance(w, n) - r);
            for o in n + 1..ms.len() {
                let (a, b) = (ms[n].pos.to_f64(), ms[o].pos.to_f64());
                let d =
                    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
                seen.closest_pair = seen.closest_pair.min(d - 2.0 * r);
            }
        }
    }
    seen
}

/// 5 µm in pitch (12 mm).
const FIVE_UM: f64 = 0.005 / 12.0;

fn stable(name: &str, seen: &Seen) {
    assert!(
        seen.deepest > -FIVE_UM,
        "{name}: {} pitch into a tile",
        -seen.deepest
    );
    assert!(
        seen.closest_pair > -FIVE_UM,
        "{name}: marbles {} pitch into each other",
        -seen.closest_pair
    );
}

#[test]
fn stress_rattle_corner_keeps_bouncing_at_full_restitution() {
    let seen = play(&scene("rattle-corner"));
    stable("rattle-corner", &seen);
    // e = 1 and no friction: nothing damps it, it bounces on for all 4 s.
    assert!(seen.bounces >= 100, "{} bounces", seen.bounces);
}

#[test]
fn stress_four_shaken_marbles_collide_and_never_overlap() {
    let seen = play(&scene("four-shaken"));
    stable("four-shaken", &seen);
    assert!(seen.closest_pair < FIVE_UM, "the marbles never met");
    assert!(seen.bounces >= 20, "{} bounces", seen.bounces);
}

#[test]
fn stress_drop_lands_on_the_marble_below() {
    let seen = play(&scene("drop-onto-marble"));
    stable("drop-onto-marble", &seen);
    // The top marble (the first `S`, storey 1) ends below, on or beside the other.
    assert_eq!(seen.storeys[0], vec![1, 0], "starts: one above, one below");
    assert_eq!(seen.storeys.last().unwrap()[0], 0, "the top marble fell");
    assert!(
        seen.closest_pair < FIVE_UM,
        "it never touched the marble below"
    );
}

/// A marble rolling off a hole's rim nearly fast enough to leave it (the top
/// marble of drop-onto-marble, of long-fall) flies one slice past the edge, not
/// plain slices that its pull kept bringing back to the edge: those took 17 or 18
/// flights a frame and the flight budget cut the landing's frame in 44 frames.
/// Now the budget cuts one marble-step a frame at most there (drop-onto-marble's
/// frame 10 asks 82 units of the budget's 80, and the frame it carries into is
/// cut too).
#[test]
fn stress_rolling_off_a_rim_takes_a_few_flights() {
    for name in ["drop-onto-marble", "long-fall"] {
        let s = scene(name);
        let seen = play(&s);
        stable(name, &seen);
        // Until its centre is below the rim, the top of the floor it rolled on.
        let rim = seen.drop.iter().take_while(|&&d| d < 1.0).count();
        assert!(rim > 8, "{name}: off the rim at frame {rim}");
        for (frame, &(flights, cuts)) in seen.flights.iter().enumerate().take(rim) {
            assert!(
                flights <= 8 && cuts <= 1,
                "{name} frame {frame}: {flights} flights, {cuts} cut, rolling off the rim"
            );
        }
    }
}

#[test]
fn stress_long_fall_drops_two_storeys() {
    let seen = play(&scene("long-fall"));
    stable("long-fall", &seen);
    let storeys: Vec<i32> = seen.storeys.iter().map(|s| s[0]).collect();
    assert_eq!(storeys[0], 2, "starts on the top storey");
    assert_eq!(*storeys.last().unwrap(), 0, "ends at the bottom");
    assert!(storeys.windows(2).all(|w| w[1] <= w[0]), "only ever falls");
}
