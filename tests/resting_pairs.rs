//! Resting pairs (issue 40): a marble that lands on another lying still rolls on
//! it and comes to rest in the cradle of that marble and a hole's rim, at once,
//! without waking it — the stress scene `drop-onto-marble`, whose landed pair
//! once flew 32 pair slices a step until a whole step changed neither (and, with
//! the flight budget, spent 45 frames cut at the budget, the scene in slow
//! motion). The rule is physics, not a shortcut of sleeping: the scene gives the
//! same states step for step with sleeping off.
mod common;

use common::*;
use marble_rolling::game::level::{parse, Level, LevelView};
use marble_rolling::game::stress::STRESS;
use marble_rolling::physics::{Scalar, Vec3, World};

/// Room for the scene's grid.
const WORDS: usize = 64;

/// 5 µm in pitch (the default 12 mm pitch).
const FIVE_UM: f64 = 0.005 / 12.0;

/// The stress scene `drop-onto-marble` (`game::stress`): a marble on the top
/// storey rolls down a hole onto one lying on the storey below, against the far
/// wall under the hole; its world under the scene's tilt (towards +x', 0.3 g;
/// 0.95 g down).
fn drop_world<S: Scalar>() -> World<'static, S, 4> {
    let l: LevelView<'static> = STRESS[2].level;
    assert_eq!(l.info.name, "drop-onto-marble");
    let mut spec = stepped(l.info.spec, Stepping::Events);
    spec.effects.marbles = true;
    let p = params::<S>(spec);
    let centres: Vec<Vec3<S>> = l
        .info
        .starts()
        .iter()
        .map(|s| {
            let (x, z) = cell_centre(&p, s.i as i32, s.k as i32);
            Vec3::new(x, S::from_int(s.storey as i32) + p.radius, z)
        })
        .collect();
    let mut w = World::with_centres(p, l.tiles, &centres).expect("the scene's marbles");
    w.set_gravity_mg([300, -950, 0]);
    w
}

/// The gap between the two marbles' surfaces (pitch; negative: overlap).
fn pair_gap<S: Scalar>(w: &World<'_, S, 4>) -> f64 {
    let r = w.params().radius.to_f64();
    let (a, b) = (w.marbles()[0].pos.to_f64(), w.marbles()[1].pos.to_f64());
    let d = (0..3).map(|i| (a[i] - b[i]).powi(2)).sum::<f64>().sqrt();
    d - 2.0 * r
}

/// The top marble lands on the lower one (a strike on it first: the lower one,
/// held by the floor and the wall, is never moved once at rest), rolls on it
/// into the hole's rim and rests there, touching both: within a quarter second
/// of its first touch at a step's end (its bounces at `e = ½` take a few
/// hundredths) both sleep, with zero velocities, and stay so; neither is ever
/// more than 5 µm into the other or a tile; the budget cuts at most a few steps.
fn rests_in_the_cradle<S: Scalar>() {
    let mut w = drop_world::<S>();
    let p = *w.params();
    let r = p.radius.to_f64();
    let steps = 1u32 << p.k;
    let mut landed = None;
    let mut asleep_at = None;
    let mut still_at = None;
    for n in 1..=steps {
        w.step();
        let gap = pair_gap(&w);
        assert!(
            gap > -FIVE_UM,
            "{} step {n}: the marbles overlap by {gap}",
            S::NAME
        );
        for i in 0..2 {
            let c = min_clearance(&w, i) - r;
            assert!(
                c > -FIVE_UM,
                "{} step {n}: marble {i} is {c} into a tile",
                S::NAME
            );
        }
        if landed.is_none() && gap < FIVE_UM {
            landed = Some(n);
        }
        let lower = w.marbles()[1];
        match still_at {
            None if lower.asleep => still_at = Some(lower.pos),
            Some(at) => assert_eq!(
                lower.pos,
                at,
                "{} step {n}: the lower marble moved",
                S::NAME
            ),
            None => {}
        }
        let both = w.marbles().iter().all(|m| m.asleep);
        match (asleep_at, both) {
            (None, true) => asleep_at = Some(n),
            (Some(at), false) => panic!("{} step {n}: woke again (asleep at {at})", S::NAME),
            _ => {}
        }
    }
    let landed = landed.expect("the top marble lands on the lower one");
    let asleep = asleep_at.expect("the pair comes to rest");
    let settle = (asleep - landed) as f64 / steps as f64;
    println!(
        "{}: lands at step {landed}, both asleep at {asleep} ({settle:.3} s), {} marble-steps cut",
        S::NAME,
        w.stats.budget_cuts
    );
    assert!(
        settle <= 0.25,
        "{}: {settle} s from landing to rest",
        S::NAME
    );
    assert!(
        w.stats.budget_cuts <= 8,
        "{}: {} cut",
        S::NAME,
        w.stats.budget_cuts
    );
    for m in w.marbles() {
        assert_eq!(
            m.vel,
            Vec3::ZERO,
            "{}: a marble at rest reports a velocity",
            S::NAME
        );
    }
    // In the cradle: on the lower marble and on the rim of the hole above it.
    let (gap, rim) = (pair_gap(&w), min_clearance(&w, 0) - r);
    assert!(gap < FIVE_UM, "{}: {gap} off the lower marble", S::NAME);
    assert!(rim < FIVE_UM, "{}: {rim} off the rim", S::NAME);
    assert!(
        w.marbles()[0].pos.y.to_f64() < 1.0,
        "{}: the top marble is not in the hole",
        S::NAME
    );
}
for_each_backend!(
    a_marble_rests_in_the_cradle_of_a_rim_and_a_marble,
    rests_in_the_cradle
);

/// Resting and rolling on a still marble ask whether it is still, not whether
/// it sleeps: with sleeping off the scene gives the same states step for step
/// (no flight budget in either: skipping changes a step's work).
fn same_awake<S: Scalar>() {
    let (mut a, mut b) = (drop_world::<S>(), drop_world::<S>());
    b.set_sleeping(false);
    a.set_flight_budget(u32::MAX);
    b.set_flight_budget(u32::MAX);
    let mut slept = 0;
    for n in 0..(1u32 << a.params().k) {
        a.step();
        b.step();
        slept += a.marbles().iter().filter(|m| m.asleep).count();
        assert_eq!(a.marbles(), b.marbles(), "{} step {n}", S::NAME);
    }
    assert_eq!(a.state_hash(), b.state_hash());
    assert!(slept > 100, "{}: the pair never slept", S::NAME);
}
for_each_backend!(resting_on_a_marble_is_the_same_asleep_or_awake, same_awake);

/// Two storeys: the lower one open, the upper one's floor open over its right
/// half (three hole cells side by side, no wall between them), so that a
/// marble on one lying at the lower storey's right wall touches no rim.
const ROOM: &str = "effects: rolling, friction
---
#########
#S.O.O.O#
#########
===
#########
#G......#
#########
";

/// The pull of `ROOM`'s tests (milli-g, tile frame): 0.3 g towards +x'.
const PULL: [i32; 3] = [300, -1000, 0];

/// `ROOM` with marble 1 lying still against the lower storey's +x' wall and
/// marble 0 placed touching it at `angle` (degrees from +x', in the x'y'
/// plane): on it, in the opening above.
fn on_a_still_marble<'a, S: Scalar>(l: &'a Level<'a, WORDS>, angle: f64) -> World<'a, S, 4> {
    let mut spec = stepped(l.info.spec, Stepping::Events);
    spec.effects.marbles = true;
    let p = params::<S>(spec);
    let r = p.radius;
    let centre = |i: i32| {
        let (x, z) = cell_centre(&p, i, 1);
        Vec3::new(x, r, z)
    };
    let mut w =
        World::with_centres(p, l.grid.view(), &[centre(1), centre(7)]).expect("the room's marbles");
    // Marble 1 rolls to the wall and comes to rest there, marble 0 against it.
    w.set_gravity_mg(PULL);
    for _ in 0..(2u32 << p.k) {
        w.step();
    }
    let lo = w.marbles()[1];
    assert!(lo.asleep, "{}: the lower marble rests at the wall", S::NAME);
    let a = angle.to_radians();
    let two_r = 2.0 * r.to_f64() + 1e-6;
    let [lx, ly, lz] = lo.pos.to_f64();
    let up = Vec3::new(
        S::from_f64(lx + two_r * a.cos()),
        S::from_f64(ly + two_r * a.sin()),
        S::from_f64(lz),
    );
    let m = &mut w.marbles_mut()[0];
    m.pos = up;
    m.vel = Vec3::ZERO;
    m.supported = false;
    w
}

/// Marble 0's energy per unit mass in the pull (pitch²/s²).
fn energy<S: Scalar>(w: &World<'_, S, 4>) -> f64 {
    let g = 9806.65 / (w.params().layout.pitch_um as f64 / 1000.0) / 1000.0;
    let m = w.marbles()[0];
    let (p, v) = (m.pos.to_f64(), m.vel.to_f64());
    let potential: f64 = (0..3).map(|i| -g * PULL[i] as f64 * p[i]).sum();
    0.5 * v.iter().map(|c| c * c).sum::<f64>() + potential
}

/// Onto a still marble and a wall: placed on the lower marble's near side, the
/// upper marble rolls over its top to the wall in roll slices (at most four a
/// step, where pair slices took 32), never into it and never gaining energy
/// (beyond rounding's: four LSBs of height),
/// and rests there, on the lower marble and against the wall, within 0.25 s;
/// the lower marble never moves.
fn rests_against_the_wall<S: Scalar>() {
    let l = parse::<WORDS>(ROOM).expect("the room parses");
    let mut w = on_a_still_marble::<S>(&l, 100.0);
    let r = w.params().radius.to_f64();
    let lower = w.marbles()[1];
    let steps = 1u32 << w.params().k;
    let mut asleep_at = None;
    let (start, mut slices) = (energy(&w), 0);
    // Rounding's share: the pull (about 1 000 pitch/s²) over four LSBs of height.
    let slack = 1e-6 + 4000.0 * S::lsb().to_f64();
    for n in 1..=steps {
        let (e, s) = (energy(&w), w.stats.slices);
        w.step();
        let gap = pair_gap(&w);
        assert!(
            gap > -FIVE_UM,
            "{} step {n}: {gap} into the lower marble",
            S::NAME
        );
        let moved = w.marbles()[1].pos != lower.pos;
        assert!(!moved, "{} step {n}: the lower marble moved", S::NAME);
        let after = energy(&w);
        assert!(
            after <= e + slack,
            "{} step {n}: energy {e} -> {after}",
            S::NAME
        );
        slices += w.stats.slices - s;
        if asleep_at.is_none() && w.marbles()[0].asleep {
            asleep_at = Some(n);
        }
    }
    let at = asleep_at.expect("the upper marble comes to rest");
    println!("{}: asleep at step {at}, {slices} slices", S::NAME);
    assert!(
        slices <= 4 * at,
        "{}: {slices} slices in {at} steps",
        S::NAME
    );
    assert!(energy(&w) < start, "{}: no energy lost", S::NAME);
    assert!(
        at as f64 / steps as f64 <= 0.25,
        "{}: asleep at step {at}",
        S::NAME
    );
    let (up, lo) = (w.marbles()[0], w.marbles()[1]);
    assert!(up.asleep && lo.asleep, "{}: woke again", S::NAME);
    assert_eq!(up.vel, Vec3::ZERO);
    assert!(pair_gap(&w) < FIVE_UM, "{}: off the lower marble", S::NAME);
    let wall = min_clearance(&w, 0) - r;
    assert!(wall.abs() < FIVE_UM, "{}: {wall} off the wall", S::NAME);
    assert!(
        up.pos.y.to_f64() > lo.pos.y.to_f64() + r,
        "{}: not on top",
        S::NAME
    );
}
for_each_backend!(
    a_marble_rests_on_a_still_marble_against_a_wall,
    rests_against_the_wall
);
