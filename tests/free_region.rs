//! Event stepping's free region (`src/physics/world/events/free.rs`) is a pure
//! cache: a world that builds free regions and one that never does step to the
//! same bits, frame for frame, on the levels, the stress scenes, generated mazes
//! and on every backend; and the region does answer searches.
mod common;

use common::*;
use marble_rolling::game::generate::generate;
use marble_rolling::game::level::{parse, Level};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::game::stress::STRESS;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::physics::{Effects, Fx, Scalar, Vec3};
use marble_rolling::player::Player;

type Pilot<'a> = Player<'a, 19, 9, true, true>;

/// Plays `a` (free regions on) by its autopilot and `b` (off) on the same
/// readings, checking the two states after every frame; returns the searches
/// the regions answered and the flights flown.
fn twins(name: &str, a: &mut Pilot<'_>, b: &mut Pilot<'_>, frames: u32) -> (u32, u32) {
    b.session_mut()
        .game_mut()
        .world_mut()
        .set_free_regions(false);
    for n in 0..frames {
        let reading = a.reading(AccelMg::LEVEL);
        let pa = a.session_mut().frame_in::<true>(reading);
        let pb = b.session_mut().frame_in::<true>(reading);
        assert_eq!(
            a.session().state_hash(),
            b.session().state_hash(),
            "{name}: frame {n}"
        );
        assert_eq!(pa, pb, "{name}: frame {n}");
        if pa != Phase::Playing {
            break;
        }
    }
    let on = a.session_mut().game_mut().world_mut().stats;
    let off = b.session_mut().game_mut().world_mut().stats;
    assert_eq!(off.free_served, 0, "{name}: served with the regions off");
    (on.free_served, on.flights)
}

#[test]
fn the_levels_play_the_same_without_it() {
    let (mut served, mut flights) = (0, 0);
    for (index, level) in LEVELS.iter().enumerate() {
        let mut a = Pilot::new(&LEVELS, index, SYNTHETIC_TILT, true).expect("level sets up");
        let mut b = Pilot::new(&LEVELS, index, SYNTHETIC_TILT, true).expect("level sets up");
        let (s, f) = twins(level.info.name, &mut a, &mut b, 2048);
        served += s;
        flights += f;
    }
    // Most flights on the levels cross open floor.
    assert!(
        served * 2 > flights,
        "the regions answered {served} of {flights} searches"
    );
}

#[test]
fn generated_mazes_play_the_same_without_it() {
    for (seed, storeys, difficulty) in [(1, 1, 9), (2, 2, 9), (5, 2, 6), (7, 3, 2)] {
        let text = generate(seed, 6, storeys, difficulty)
            .expect("the maze generates")
            .to_string();
        let level: Level<'_, 1016> = parse(&text).expect("the maze parses");
        let name = format!("maze {seed} {storeys} {difficulty}");
        let mut a = Pilot::single(level.view(), SYNTHETIC_TILT, true).expect("maze sets up");
        let mut b = Pilot::single(level.view(), SYNTHETIC_TILT, true).expect("maze sets up");
        let (served, _) = twins(&name, &mut a, &mut b, 4096);
        assert!(served > 0, "{name}: the regions answered nothing");
    }
}

#[test]
fn the_stress_scenes_play_the_same_without_it() {
    for scene in &STRESS {
        let config = Pilot::CONFIG;
        let mut a = Session::<Fx>::new(scene.level, config, SYNTHETIC_TILT).expect("scene");
        let mut b = Session::<Fx>::new(scene.level, config, SYNTHETIC_TILT).expect("scene");
        b.game_mut().world_mut().set_free_regions(false);
        for n in 0..scene.frames {
            a.frame_in::<true>((scene.tilt)(n));
            b.frame_in::<true>((scene.tilt)(n));
            assert_eq!(
                a.state_hash(),
                b.state_hash(),
                "{}: frame {n}",
                scene.level.info.name
            );
        }
    }
}

/// Event stepping with rolling and rolling resistance, holes (3-D) or not,
/// marbles that touch or not.
fn events_with<S: Scalar>(holes: bool, marbles: bool) -> marble_rolling::physics::Params<S> {
    params::<S>(spec_in(
        Stepping::Events,
        Effects {
            holes,
            friction: true,
            rolling: true,
            marbles,
            ..Effects::NONE
        },
    ))
}

/// Two marbles in a walled maze with a hole, rolled, tilted about, shot and
/// left to rest, on every backend, with and without holes (3-D or the floor):
/// the same marbles after every step, and the regions answered searches.
fn same_on_every_backend<S: Scalar>() {
    let g = grid(&[
        "###########",
        "#.........#",
        "#.###.#.#.#",
        "#.#.....#.#",
        "#.#.#o###.#",
        "#.........#",
        "###########",
    ]);
    for holes in [false, true] {
        let p = events_with::<S>(holes, true);
        let starts = [cell_centre(&p, 1, 1), cell_centre(&p, 9, 5)];
        let mut a = world(p, &g, &starts);
        let mut b = world(p, &g, &starts);
        b.set_free_regions(false);
        for w in [&mut a, &mut b] {
            w.marbles_mut()[1].vel = Vec3::new(S::from_f64(-9.0), S::ZERO, S::from_f64(-2.5));
        }
        let tilts = [
            [0, -1000, 0],
            [300, -1000, 0],
            [300, -1000, 250],
            [-500, -1000, -100],
            [0, -1000, -700],
            [20, -1000, 10],
        ];
        for (n, t) in tilts.iter().enumerate() {
            a.set_gravity_mg(*t);
            b.set_gravity_mg(*t);
            for step in 0..(2 << p.k) {
                a.step();
                b.step();
                assert_eq!(
                    a.marbles(),
                    b.marbles(),
                    "{} holes {holes}: phase {n} step {step}",
                    S::NAME
                );
            }
        }
        assert!(a.stats.free_served > 0, "{}: nothing served", S::NAME);
        assert_eq!(a.stats.flights, b.stats.flights, "{}", S::NAME);
    }
}
for_each_backend!(the_same_on_every_backend, same_on_every_backend);

/// A marble at rest in a corner whose pull turns away from one wall without
/// beating static friction (a wandering tilt on a nearly level board): it lets
/// go of that wall and stays where it is, frame after frame. The region built
/// with both walls answers those still frames (its let-go wall is a radius
/// away, nothing else in reach), and the world plays as without it.
fn still_in_a_corner<S: Scalar>() {
    let g = grid(&["#####", "#...#", "#...#", "#####"]);
    for holes in [false, true] {
        let p = events_with::<S>(holes, false);
        let start = [cell_centre(&p, 1, 1)];
        let mut a = world(p, &g, &start);
        let mut b = world(p, &g, &start);
        b.set_free_regions(false);
        // Into the corner at x' = 0, z' = 0, until it rests there.
        for w in [&mut a, &mut b] {
            w.set_gravity_mg([-300, -1000, -300]);
            for _ in 0..(2 << p.k) {
                w.step();
            }
            w.set_gravity_mg([-300, -1000, -2]);
            w.step();
        }
        let before = a.stats.free_served;
        // Away from the x' wall by a milli-g or two, still into the z' wall:
        // rolling resistance (1 % of g) holds the marble.
        for n in 0..64 {
            let t = [1 + n % 2, -1000, -300];
            a.set_gravity_mg(t);
            b.set_gravity_mg(t);
            let at = a.marbles()[0].pos;
            a.step();
            b.step();
            assert_eq!(
                a.marbles(),
                b.marbles(),
                "{} holes {holes}: step {n}",
                S::NAME
            );
            assert_eq!(a.marbles()[0].pos, at, "{} holes {holes}: moved", S::NAME);
        }
        assert!(
            a.stats.free_served - before >= 60,
            "{} holes {holes}: served {} of 64 still frames",
            S::NAME,
            a.stats.free_served - before
        );
    }
}
for_each_backend!(
    the_region_answers_a_still_marble_in_a_corner,
    still_in_a_corner
);
