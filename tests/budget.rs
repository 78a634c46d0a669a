//! The step's flight budget (`physics::world::FLIGHT_BUDGET`) and its fallback
//! (`src/physics/world/events/budget.rs`): a step's work is capped, and the rest
//! of a step that reaches the cap is carried over, which neither sinks a marble
//! into a tile or another marble, nor adds energy, nor depends on the target.
mod common;

use common::*;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::game::stress::{StressScene, STRESS};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::physics::{
    Effects, Fx, Params, PhysicsSpec, Scalar, Vec3, World, FLIGHT_BUDGET,
};
use marble_rolling::player::Player;

/// 5 µm in pitch (10 mm: `PhysicsSpec::DEFAULT`'s long tile).
const FIVE_UM: f64 = 0.005 / 10.0;

fn energy<S: Scalar>(v: Vec3<S>) -> f64 {
    let v = v.to_f64();
    0.5 * (v[0] * v[0] + v[1] * v[1] + v[2] * v[2])
}

/// Four marbles shot across a closed box at `e = 1` on a level board, with a
/// budget of eight units (one search's fixed part): every step is cut after its
/// first round, the one a step never cuts. For
/// two seconds no marble is ever inside a tile or another marble by more than
/// 5 µm, at any flight's start, middle or end, the marbles' energy never grows
/// (rounding aside), and they keep moving (a cut slows the scene; it does not
/// freeze it).
fn small_budget<S: Scalar>() {
    let g = closed_box(3);
    let p = params::<S>(PhysicsSpec {
        restitution_milli: 1000,
        ..spec_in(
            Stepping::Events,
            Effects {
                marbles: true,
                ..Effects::NONE
            },
        )
    });
    let shots = [(40.0, 13.0), (-31.0, 22.0), (17.0, -45.0), (-8.0, -3.0)];
    let mut w = four_in_corners(p, &g, 5, shots);
    w.set_flight_budget(8);
    assert_eq!(w.flight_budget(), 8);
    let r = p.radius.to_f64();
    let floor = r * (1.0 - loose::<S>()) - FIVE_UM;
    let mut travelled = 0.0;
    for n in 0..256 {
        let e0: f64 = w.marbles().iter().map(|m| energy(m.vel)).sum();
        let before: Vec<[f64; 3]> = w.marbles().iter().map(|m| m.pos.to_f64()).collect();
        let c = step_checked(&mut w, 0);
        assert!(c >= floor, "{} step {n}: marble 0 clearance {c}", S::NAME);
        let ms = w.marbles();
        for a in 0..4 {
            assert!(!ms[a].out, "{} step {n}: marble {a} left the box", S::NAME);
            let c = min_clearance(&w, a);
            assert!(c >= floor, "{} step {n}: marble {a} clearance {c}", S::NAME);
            let (pa, qa) = (ms[a].pos.to_f64(), before[a]);
            travelled += ((pa[0] - qa[0]).powi(2) + (pa[2] - qa[2]).powi(2)).sqrt();
            for (b, other) in ms.iter().enumerate().skip(a + 1) {
                let pb = other.pos.to_f64();
                let d =
                    ((pa[0] - pb[0]).powi(2) + (pa[1] - pb[1]).powi(2) + (pa[2] - pb[2]).powi(2))
                        .sqrt();
                assert!(
                    d >= 2.0 * r * (1.0 - loose::<S>()) - FIVE_UM,
                    "{} step {n}: marbles {a} and {b} {} pitch into each other",
                    S::NAME,
                    2.0 * r - d
                );
            }
        }
        let e1: f64 = ms.iter().map(|m| energy(m.vel)).sum();
        // Rounding only: a bounce off a slanted pair normal rounds each
        // component to the format (I16F16's 2^-16 pitch/s is 10^-4 of the energy
        // here, with the same pair code and no budget).
        let slack = match S::NAME {
            "f32-micromath" => 1e-2,
            "i16f16" => 1e-3,
            _ => 1e-5,
        };
        assert!(
            e1 <= e0 * (1.0 + slack) + 1e-9,
            "{} step {n}: energy {e0} → {e1}",
            S::NAME
        );
    }
    assert!(
        w.stats.budget_cuts > 100,
        "{}: the budget cut only {} marble-steps",
        S::NAME,
        w.stats.budget_cuts
    );
    assert!(
        w.stats.collisions > 10,
        "{}: {} bounces",
        S::NAME,
        w.stats.collisions
    );
    // Four marbles at 8–48 pitch/s for 2 s: slowed by the cuts, they still
    // travel far, not a few steps' worth.
    println!(
        "{}: {travelled} pitch, {} cuts, {} bounces",
        S::NAME,
        w.stats.budget_cuts,
        w.stats.collisions
    );
    assert!(
        travelled > 20.0,
        "{}: the marbles travelled {travelled} pitch",
        S::NAME
    );
}
for_each_backend!(a_small_budget_keeps_every_rule, small_budget);

/// Every pair's time of impact counts against the budget, those its quick bound
/// rejects too: four marbles rolling slowly in the corners of a closed box, too
/// far apart ever to touch, spend more a step when they are tested as pairs than
/// the same four flown each on its own (no pair tested). Uncounted, four shaken
/// marbles tested 20 to 30 pairs a frame past the budget.
fn pair_tests_count<S: Scalar>() {
    let g = closed_box(5);
    let work = |marbles: bool| {
        let p = params::<S>(spec_in(
            Stepping::Events,
            Effects {
                marbles,
                ..Effects::NONE
            },
        ));
        let slow = [(0.5, 0.0), (-0.5, 0.0), (0.0, -0.5), (0.0, 0.5)];
        let mut w = four_in_corners(p, &g, 9, slow);
        w.set_sleeping(false);
        for _ in 0..16 {
            w.step();
        }
        assert_eq!(w.stats.budget_cuts, 0, "{}: the budget cut a step", S::NAME);
        w.stats.work
    };
    let (alone, paired) = (work(false), work(true));
    assert!(
        paired >= alone + 16 * 6,
        "{}: {alone} units flown alone, {paired} tested as six pairs over 16 steps",
        S::NAME
    );
}
for_each_backend!(every_pair_test_counts_against_the_budget, pair_tests_count);

/// A cut slows only the marbles that can meet: two marbles pressed together
/// against a wall under a small budget are cut every step, while a third rolling
/// freely across the box, out of their reach, ends each step where it would with
/// no budget at all, bit for bit.
fn free_marble_keeps_time<S: Scalar>() {
    let g = closed_box(7);
    let p = params::<S>(spec_in(
        Stepping::Events,
        Effects {
            marbles: true,
            ..Effects::NONE
        },
    ));
    let (ax, az) = cell_centre(&p, 1, 1);
    let two_r = (p.radius + p.radius).to_f64();
    let b = (ax, S::from_f64(az.to_f64() + two_r));
    let free = cell_centre(&p, 9, 11);
    let run = |budget: u32| {
        let mut w = world(p, &g, &[(ax, az), b, free]);
        w.set_flight_budget(budget);
        // The pair pressed against the wall at z' = 0 and rolling along it
        // (a pair at rest there would rest: `events/rest.rs`); the free marble
        // rolls along x' and drifts down z', too slowly to reach a wall in the
        // 36 steps (it reaches z' = 0 at the 44th).
        w.set_gravity_mg([60, -1000, -100]);
        w.marbles_mut()[2].vel = Vec3::new(S::from_f64(-2.0), S::ZERO, S::ZERO);
        let mut path = Vec::new();
        for _ in 0..36 {
            w.step();
            path.push(w.marbles()[2].pos);
        }
        (path, w.stats.budget_cuts)
    };
    let (cut, cuts) = run(24);
    let (whole, none) = run(u32::MAX);
    assert!(cuts > 4, "{}: only {cuts} marble-steps cut", S::NAME);
    assert_eq!(none, 0);
    assert_eq!(
        cut,
        whole,
        "{}: the free marble was slowed by the cut",
        S::NAME
    );
}
for_each_backend!(
    a_cut_slows_only_the_marbles_that_can_meet,
    free_marble_keeps_time
);

/// Four marbles at the centres of the cells `(1, 1)`, `(far, 1)`, `(1, far)` and
/// `(far, far)` of `g`, moving at `vel` (pitch/s, x' and z').
fn four_in_corners<S: Scalar>(
    p: Params<S>,
    g: &Grid,
    far: i32,
    vel: [(f64, f64); 4],
) -> World<'_, S, 4> {
    let starts = [
        cell_centre(&p, 1, 1),
        cell_centre(&p, far, 1),
        cell_centre(&p, 1, far),
        cell_centre(&p, far, far),
    ];
    let mut w = world(p, g, &starts);
    for (m, (x, z)) in w.marbles_mut().iter_mut().zip(vel) {
        m.vel = Vec3::new(S::from_f64(x), S::ZERO, S::from_f64(z));
    }
    w
}

fn scene(name: &str) -> StressScene {
    *STRESS
        .iter()
        .find(|s| s.level.info.name == name)
        .unwrap_or_else(|| panic!("no stress scene {name}"))
}

/// A scene as the boards play it.
fn play(s: &StressScene) -> (Vec<u32>, u32, u64, bool) {
    // Each frame's units of work, the cuts, the final hash, and whether every
    // marble ended at rest, reporting zero velocity.
    let mut session =
        Session::<Fx>::new(s.level, Player::<19, 9, true, true>::CONFIG, SYNTHETIC_TILT)
            .expect("scene sets up");
    let mut work = Vec::new();
    for frame in 0..s.frames {
        let before = session.game_mut().world_mut().stats.work;
        session.frame((s.tilt)(frame));
        work.push(session.game_mut().world_mut().stats.work - before);
    }
    let w = session.game_mut().world_mut();
    let cuts = w.stats.budget_cuts;
    let asleep = w.marbles().iter().all(|m| m.asleep && m.vel == Vec3::ZERO);
    (work, cuts, session.state_hash(), asleep)
}

/// Four marbles shaken hard reach the budget (it is what the budget is for),
/// and with it no frame spends more than a sixth past it: a search, a pair's
/// test and a pair slice are begun only when the budget left covers them, so a
/// frame spends the larger of its first round (never cut: up to 88 units here)
/// and the budget, and past them only the tiles of its last search; the same
/// scene gives the same frames and hash twice.
#[test]
fn four_shaken_marbles_are_cut_to_the_budget() {
    let s = scene("four-shaken");
    let (work, cuts, hash, _) = play(&s);
    assert!(cuts > 0, "four shaken marbles never reached the budget");
    let worst = work.iter().copied().max().unwrap_or(0);
    assert!(
        worst < FLIGHT_BUDGET + FLIGHT_BUDGET / 6,
        "{worst} units of work in a frame (budget {FLIGHT_BUDGET})"
    );
    let (again, _, hash_again, _) = play(&s);
    assert_eq!(
        (work, hash),
        (again, hash_again),
        "the budget is not deterministic"
    );
}

/// A marble landing on another, which lies against the wall under the hole,
/// strikes it and rolls and rests on it (`events/rest.rs`): the budget cuts
/// one marble-step in each of two frames at most, as it rolls off the rim
/// (frame 10 asks 82 units, and the frame it carries into is cut too; the pair
/// once flew dozens of pair slices a step and was cut for 45 frames), and the
/// pair, in the cradle of the hole's rim
/// and the marble below, comes to rest and reports zero velocity.
#[test]
fn a_landing_on_a_marble_is_cut_twice_at_most() {
    let s = scene("drop-onto-marble");
    let (work, cuts, _, asleep) = play(&s);
    let worst = work.iter().copied().max().unwrap_or(0);
    assert!(
        cuts <= 2,
        "the landing was cut {cuts} times ({worst} units in a frame)"
    );
    assert!(
        asleep,
        "the pair never came to rest, or reports a velocity at rest"
    );
}

/// No built-in level reaches the budget when the autopilot plays it: the
/// fallback is for scenes built to reach it, not for play.
#[test]
fn no_built_in_level_reaches_the_budget() {
    for (index, level) in LEVELS.iter().enumerate() {
        let mut player = Player::<19, 9, true, true>::new(&LEVELS, index, SYNTHETIC_TILT, true)
            .expect("level sets up");
        for _ in 0..1024 {
            let reading = player.reading(AccelMg::LEVEL);
            if player.session_mut().frame_in::<true>(reading) != Phase::Playing {
                break;
            }
        }
        let cuts = player
            .session_mut()
            .game_mut()
            .world_mut()
            .stats
            .budget_cuts;
        assert_eq!(cuts, 0, "{} reached the budget", level.info.name);
    }
}

/// **A cut inside a slice.** Two marbles on a storey over a hole, one shot at
/// the other under a hard tilt (the property run's shrunk case): the budget runs
/// out while a marble is in a slice, which may sink it up to `2^-12·r` into the
/// tile it leaves to the slice's passes. The cut runs those passes where it stops
/// the marble, so no marble is ever closer than its radius to a tile (it was
/// 3.7 µm in before they did).
fn cut_in_a_slice<S: Scalar>() {
    let g = grid(&[
        "###############",
        "#..O..........#",
        "#.##.#..#.....#",
        "#.............#",
        "###############",
    ]);
    let p = params::<S>(spec_in(
        Stepping::Events,
        Effects {
            rolling: true,
            holes: true,
            marbles: true,
            ..Effects::NONE
        },
    ));
    let mut w = world(p, &g, &[cell_centre(&p, 13, 1), cell_centre(&p, 1, 1)]);
    w.marbles_mut()[0].vel = Vec3::new(S::from_int(6), S::ZERO, S::from_int(-4));
    w.set_gravity_mg([-2185, -657, -72]);
    let r = p.radius.to_f64();
    for n in 0..steps_of(&p, 120) {
        w.step();
        for (k, m) in w.marbles().iter().enumerate() {
            if !m.out {
                let c = min_clearance(&w, k);
                assert!(
                    c >= r * (1.0 - loose::<S>()),
                    "{} step {n}: marble {k} at clearance {c} < r = {r}",
                    S::NAME
                );
            }
        }
    }
    // The firmware's format reaches the budget here; the others' rounding may
    // take another way through the scene.
    if S::NAME == "i8f24" {
        assert!(w.stats.budget_cuts > 0, "the budget never ran out");
    }
}
for_each_backend!(
    a_cut_inside_a_slice_leaves_no_marble_in_a_tile,
    cut_in_a_slice
);
