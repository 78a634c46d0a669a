//! Multi-storey mazes (issue 18): the level format's storeys and its errors, a
//! marble dropping one storey (time and restitution, every backend and both
//! steppers), the hard cases of a drop, and properties over random closed
//! multi-storey mazes.
mod common;

use common::*;
use marble_rolling::game::level::{parse, words_needed, Cell, Level, LevelError, LevelErrorKind};
use marble_rolling::game::rules::{Game, GameConfig, Phase};
use marble_rolling::input::tilt::GravityMg;
use marble_rolling::physics::{Params, Scalar, TileIndex, Vec3, World};
use proptest::prelude::*;

/// Room for a 127 × 8 × 127 grid.
const BIG: usize = 4033;

fn level(src: &str) -> Level<'_, BIG> {
    parse::<BIG>(src).unwrap_or_else(|e| panic!("{e}\n{src}"))
}

fn error(src: &str) -> LevelError {
    match parse::<BIG>(src) {
        Ok(_) => panic!("parsed:\n{src}"),
        Err(e) => e,
    }
}

/// Two storeys: the top one (storey 1) has a hole in cell (3, 1) and the start,
/// the lower one (storey 0) the goal.
const TWO: &str = "restitution: 0.5
---
#######
#S.O..#
#######
===
#######
#....G#
#######
";

#[test]
fn storeys_are_listed_top_to_bottom() {
    let l = level(TWO);
    assert_eq!(l.info.storeys, 2);
    assert_eq!(l.info.starts(), &[Cell::new(1, 1, 1)]);
    assert_eq!(l.info.goals(), &[Cell::new(5, 1, 0)]);
    assert!(l.info.spec.effects.holes, "a maze of storeys moves in 3-D");
    let t = l.grid.view();
    assert_eq!((t.nx(), t.ny(), t.nz(), t.storeys()), (7, 4, 3, 2));
    // Storey 1: its slab (j = 2) has the hole, its walls are in j = 3.
    assert!(t.is_solid(TileIndex::new(1, 2, 1)));
    assert!(!t.is_solid(TileIndex::new(3, 2, 1)));
    assert!(t.is_solid(TileIndex::new(0, 3, 1)));
    assert!(!t.is_solid(TileIndex::new(1, 3, 1)));
    // Storey 0 is whole.
    assert!(t.is_solid(TileIndex::new(3, 0, 1)));
    assert!(t.is_solid(TileIndex::new(0, 1, 0)));
    assert!(!t.is_solid(TileIndex::new(3, 1, 1)));
    // 7 × 4 × 3 = 84 bits.
    assert_eq!(words_needed(TWO), 3);
}

#[test]
fn a_one_storey_level_is_unchanged() {
    let l = level("---\n#####\n#S.G#\n#####\n");
    assert_eq!(l.info.storeys, 1);
    assert_eq!(l.grid.view().ny(), 2);
    assert!(!l.info.spec.effects.holes);
    assert_eq!(words_needed("---\n#####\n#S.G#\n#####\n"), 1);
}

#[test]
fn storey_errors_name_line_and_column() {
    let at = |src: &str| {
        let e = error(src);
        (e.line, e.column, e.kind)
    };
    // A storey with a row more than the first: reported at that row.
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n#####\n#...#\n#...#\n#####\n"),
        (9, 1, LevelErrorKind::StoreyRows)
    );
    // A row fewer: reported at the separator that ends it.
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n#####\n#####\n===\n#####\n#...#\n#####\n"),
        (8, 1, LevelErrorKind::StoreyRows)
    );
    // ... or, in the last storey, at its last row.
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n#####\n#####\n"),
        (7, 1, LevelErrorKind::StoreyRows)
    );
    // A row of another length in the second storey.
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n#####\n#..#\n#####\n"),
        (7, 5, LevelErrorKind::RaggedRow)
    );
    // Separators with no rows: first, doubled, last.
    assert_eq!(
        at("---\n===\n#####\n#S.G#\n#####\n"),
        (2, 1, LevelErrorKind::EmptyStorey)
    );
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n===\n#####\n#...#\n#####\n"),
        (6, 1, LevelErrorKind::EmptyStorey)
    );
    assert_eq!(
        at("---\n#####\n#S.G#\n#####\n===\n"),
        (5, 1, LevelErrorKind::EmptyStorey)
    );
    // Five storeys: the fourth separator is one too many.
    let five = "---\n###\n#S#\n###\n===\n###\n#.#\n###\n===\n###\n#.#\n###\n===\n###\n#G#\n###\n===\n###\n#.#\n###\n";
    assert_eq!(at(five), (17, 1, LevelErrorKind::TooManyStoreys));
    // A wall under a hole: reported at the wall, in the storey below.
    assert_eq!(
        at("---\n#######\n#S.O.G#\n#######\n===\n#######\n#..#..#\n#######\n"),
        (7, 4, LevelErrorKind::HoleAboveWall)
    );
    // The messages say what to do.
    let e = error("---\n#######\n#S.O.G#\n#######\n===\n#######\n#..#..#\n#######\n");
    assert!(e.to_string().starts_with("7:4: wall under a hole"), "{e}");
    assert!(LevelErrorKind::TooManyStoreys.message().contains('4'));
}

#[test]
fn holes_over_holes_and_lowest_holes_are_allowed() {
    // A shaft through two storeys, and a hole out of the maze in the lowest.
    let l = level("---\n#######\n#S.O..#\n#######\n===\n#######\n#..O..#\n#######\n===\n#######\n#..O.G#\n#######\n");
    assert_eq!(l.info.storeys, 3);
    assert_eq!(l.info.starts()[0].storey, 2);
    assert_eq!(l.info.goals()[0].storey, 0);
    let t = l.grid.view();
    for j in [0, 2, 4] {
        assert!(!t.is_solid(TileIndex::new(3, j, 1)), "slab {j} open");
    }
}

fn params_of<S: Scalar>(l: &Level<'_, BIG>, st: Stepping) -> Params<S> {
    params(stepped(l.info.spec, st))
}

/// Standard gravity in pitches/s².
fn g_pitch<S: Scalar>(p: &Params<S>) -> f64 {
    9806.65 / (p.layout.pitch_um as f64 / 1000.0)
}

/// Dropped at rest over the hole of [`TWO`], the marble falls one storey
/// (`l + s`, one pitch) in `√(2(l+s)/g)`: its first impact comes in the step
/// that holds that instant, at `g·t`; it then rises to `e²` of the drop.
fn drop_one_storey<S: Scalar>(st: Stepping) {
    let l = level(TWO);
    let p = params_of::<S>(&l, st);
    let (x, z) = cell_centre(&p, 3, 1);
    let start = Vec3::new(x, S::ONE + p.radius, z);
    let mut w: World<'_, S, 4> =
        World::with_centres(p, l.grid.view(), &[start]).expect("a start over the hole");
    w.set_gravity_mg([0, -1000, 0]);
    let g = g_pitch(&p);
    let dt = p.dt();
    let fall = (2.0 * 1.0 / g).sqrt();
    let mut landed = None;
    for n in 1..=(0.2 / dt) as u32 {
        w.step();
        let impacts = w.take_impacts();
        if let Some(&speed) = impacts.speeds().first() {
            landed = Some((n, speed.to_f64()));
            break;
        }
    }
    let (n, speed) = landed.expect("lands within 0.2 s");
    let t = n as f64 * dt;
    println!(
        "{} {st:?}: lands in step {n} (t ≤ {t:.5} s, want {fall:.5} s) at {speed:.4} pitch/s (want {:.4})",
        S::NAME,
        g * fall
    );
    assert!(
        t - dt < fall + 1e-9 && fall <= t + 1e-9,
        "{}: landing step {n}",
        S::NAME
    );
    // The impact speed goes through a root: micromath's is approximate (5 %).
    let tol = loose::<S>();
    assert!(
        (speed - g * fall).abs() <= tol * g * fall,
        "{}: impact {speed} against {}",
        S::NAME,
        g * fall
    );
    // The rebound: the apex above the lower storey's floor is e²·(l + s).
    let floor = p.radius.to_f64();
    let mut apex = w.marbles()[0].pos.y.to_f64();
    for _ in 0..(0.2 / dt) as u32 {
        w.step();
        apex = apex.max(w.marbles()[0].pos.y.to_f64());
    }
    let e = 0.5;
    let rise = apex - floor;
    println!(
        "{} {st:?}: rebound apex {rise:.5} pitch (want {:.5})",
        S::NAME,
        e * e
    );
    // Fixed steps see the apex at a step's end: at most ½·g·dt² below it; the
    // rebound speed goes through micromath's approximate root.
    let sample = 0.5 * g * dt * dt;
    assert!(
        (rise - e * e).abs() <= 0.01 + sample + 0.5 * loose::<S>(),
        "{}: apex {rise} pitch, want {}",
        S::NAME,
        e * e
    );
    let m = w.marbles()[0];
    assert!(!m.out, "stays in the maze");
    assert_eq!(p.layout.storey_of(m.pos.y), 0, "ends on the storey below");
}
for_each_backend_and_mode!(a_drop_falls_one_storey_and_bounces_by_e, drop_one_storey);

/// Steps `w` for `seconds`, checking after every step (and inside every flight
/// of the event stepper) that marble 0 is nowhere closer than `r·(1 − 10⁻³)` to
/// a solid tile of any storey; returns the least clearance seen (pitch).
fn run_checked<S: Scalar>(w: &mut World<'_, S, 4>, seconds: f64) -> f64 {
    let r = w.params().radius.to_f64();
    let steps = (seconds / w.params().dt()) as u32;
    let mut least = f64::INFINITY;
    for n in 0..steps {
        if w.marbles()[0].out {
            break;
        }
        let c = step_checked(w, 0);
        least = least.min(c);
        assert!(
            c >= r * (1.0 - 1e-3),
            "{}: step {n}: clearance {c} < r {r} at {:?}",
            S::NAME,
            w.marbles()[0].pos.to_f64()
        );
    }
    least
}

/// Rolled fast into a hole whose far edge and the wall below it are close: the
/// marble touches the hole's edge and the lower storey's wall on the way down
/// (edge contacts in 3-D), never sinks into either, and rests on the storey
/// below.
fn drop_next_to_a_wall<S: Scalar>(st: Stepping) {
    let l = level(
        "restitution: 0.5
---
#########
#S.....O#
#########
===
#########
#......G#
#########
",
    );
    let p = params_of::<S>(&l, st);
    for (speed_mm_s, tilt) in [(300.0, 200), (800.0, 500), (1500.0, 1000)] {
        let (x, z) = cell_centre(&p, 5, 1);
        let start = Vec3::new(x, S::ONE + p.radius, z);
        let mut w: World<'_, S, 4> = World::with_centres(p, l.grid.view(), &[start]).unwrap();
        w.marbles_mut()[0].vel.x = p.layout.from_mm(speed_mm_s);
        w.set_gravity_mg([tilt, -1000, 0]);
        let least = run_checked(&mut w, 1.0);
        let m = w.marbles()[0];
        println!(
            "{} {st:?} {speed_mm_s} mm/s: least clearance {least:.6} pitch, ends at {:?}",
            S::NAME,
            m.pos.to_f64()
        );
        assert!(!m.out, "{}: the lower storey is closed", S::NAME);
        assert_eq!(
            p.layout.storey_of(m.pos.y),
            0,
            "{}: fell one storey",
            S::NAME
        );
        // Pressed into the end wall of the lower storey by the tilt.
        let end = p.layout.span_xz(8).0.to_f64();
        assert!(
            (m.pos.x.to_f64() - (end - p.radius.to_f64())).abs() < 1e-3,
            "{}: against the end wall",
            S::NAME
        );
    }
}
for_each_backend_and_mode!(
    a_drop_next_to_a_wall_touches_edges_never_sinks,
    drop_next_to_a_wall
);

/// Thrown diagonally from over a hole, the marble strikes the hole's edges as it
/// falls and then the post that stands at the corner below the hole.
fn drop_past_a_post<S: Scalar>(st: Stepping) {
    let l = level(
        "restitution: 0.8
---
#########
#S......#
#.......#
#..O....#
#.......#
#.......#
#########
===
#########
#.......#
#.......#
#.......#
#...#...#
#......G#
#########
",
    );
    let p = params_of::<S>(&l, st);
    let mut touched_lower = 0;
    for (vx, vz) in [
        (200.0, 200.0),
        (400.0, 250.0),
        (250.0, 400.0),
        (900.0, 900.0),
    ] {
        let (x, z) = cell_centre(&p, 3, 3);
        let start = Vec3::new(x, S::ONE + p.radius, z);
        let mut w: World<'_, S, 4> = World::with_centres(p, l.grid.view(), &[start]).unwrap();
        w.marbles_mut()[0].vel.x = p.layout.from_mm(vx);
        w.marbles_mut()[0].vel.z = p.layout.from_mm(vz);
        w.set_gravity_mg([0, -1000, 0]);
        run_checked(&mut w, 2.0);
        let m = w.marbles()[0];
        assert!(!m.out);
        if p.layout.storey_of(m.pos.y) == 0 {
            touched_lower += 1;
        }
    }
    assert!(
        touched_lower >= 1,
        "{}: some throws fall through the hole",
        S::NAME
    );
}
for_each_backend_and_mode!(a_drop_past_a_post_never_sinks, drop_past_a_post);

/// Resting over a 2 mm slot (a hole in a short tile) of the upper storey, the
/// marble sags onto the slot's two edges and stays on its storey.
fn rests_over_a_slot<S: Scalar>(st: Stepping) {
    // The slot: column 4 (a short tile) of storey 1, between cells 3 and 5.
    let l2 = level("---\n#######\n#S..O.#\n#######\n===\n#######\n#....G#\n#######\n");
    let p = params_of::<S>(&l2, st);
    let (x, z) = (
        p.layout.span_xz(4).0 + p.layout.s.half(),
        cell_centre(&p, 5, 1).1,
    );
    let start = Vec3::new(x, S::ONE + p.radius, z);
    let mut w: World<'_, S, 4> = World::with_centres(p, l2.grid.view(), &[start]).unwrap();
    w.set_gravity_mg([0, -1000, 0]);
    run_checked(&mut w, 3.0);
    let m = w.marbles()[0];
    let sag = p.layout.to_mm(S::ONE + p.radius - m.pos.y);
    // r − √(r² − (s/2)²) = 3.5 − √(12.25 − 1) mm.
    let want = 3.5 - (3.5f64 * 3.5 - 1.0).sqrt();
    println!("{} {st:?}: sag {sag:.5} mm (want {want:.5})", S::NAME);
    assert_eq!(p.layout.storey_of(m.pos.y), 1, "{}: stays up", S::NAME);
    // micromath's approximate root puts the resting point 0.05 mm off.
    assert!(
        (sag - want).abs() < 0.01 + loose::<S>(),
        "{}: sag {sag} mm",
        S::NAME
    );
    let speed = p.layout.to_mm(S::ONE) * m.vel.to_f64().iter().map(|v| v * v).sum::<f64>().sqrt();
    println!("{} {st:?}: speed at the end {speed:.6} mm/s", S::NAME);
    // On two edges the coarse backends do not settle: i16f16 (events) keeps
    // 2.3 mm/s and micromath 13–20 mm/s of jitter; they still stay up.
    let bound = if loose::<S>() > 1e-3 { 25.0 } else { 0.1 };
    assert!(speed < bound, "{}: at rest ({speed} mm/s)", S::NAME);
}
for_each_backend_and_mode!(
    a_marble_over_a_slot_does_not_fall_through,
    rests_over_a_slot
);

/// The game: a start on the top storey, the goal below; tilted towards the hole
/// the marble drops and wins on the lower storey (the rules judge the storey).
#[test]
fn the_goal_is_on_its_storey() {
    // A goal on each storey: (7, 1) above, (5, 1) below; the hole at (3, 1).
    let l = level("---\n#########\n#S.O...G#\n#########\n===\n#########\n#....G..#\n#########\n");
    let view = l.view();
    let mut game: Game<'_, fixed::types::I8F24> =
        Game::new(view, GameConfig::default()).expect("game");
    assert_eq!(
        game.world().marbles()[0].pos.y,
        fixed::types::I8F24::ONE + game.world().params().radius,
        "starts on storey 1"
    );
    // Roll right: over the hole at (3, 1) it drops to storey 0 and rolls on to
    // its goal at (5, 1), under the tile before the goal above.
    let mut phase = Phase::Playing;
    for _ in 0..(10 * 128) {
        game.set_gravity_mg(GravityMg::new(150, -990, 0));
        phase = game.frame();
        if phase != Phase::Playing {
            break;
        }
    }
    assert_eq!(phase, Phase::Won);
    let m = game.world().marbles()[0];
    assert_eq!(game.world().params().layout.storey_of(m.pos.y), 0);
}

/// A random closed maze of `storeys` storeys of `cx × cz` cells: border walls on
/// every storey, random inner walls and posts, random holes in the upper
/// storeys' floors where the storey below has no wall; the lowest storey has
/// no holes, so nothing can leave the maze.
fn storey_maze() -> impl Strategy<Value = String> {
    (2usize..=4, 2usize..=4, 2usize..=4, any::<u64>(), 0u32..30).prop_map(
        |(storeys, cx, cz, seed, density)| {
            let (nx, nz) = (2 * cx + 1, 2 * cz + 1);
            let mut s = seed | 1;
            let mut rnd = move || {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                (s % 100) as u32
            };
            // Bottom up, so each storey knows the walls below it.
            let mut grids: Vec<Vec<Vec<u8>>> = Vec::new();
            for n in 0..storeys {
                let mut g = vec![vec![b'.'; nx]; nz];
                for (k, row) in g.iter_mut().enumerate() {
                    for (i, c) in row.iter_mut().enumerate() {
                        let border = i == 0 || k == 0 || i == nx - 1 || k == nz - 1;
                        let wall_below = n > 0 && grids[n - 1][k][i] == b'#';
                        if border {
                            *c = b'#';
                        } else if (i, k) == (1, 1) {
                            *c = if n == storeys - 1 { b'S' } else { b'.' };
                        } else if n > 0 && !wall_below && rnd() < density {
                            *c = b'O';
                        } else if (i % 2 == 0 || k % 2 == 0) && rnd() < density {
                            *c = b'#';
                        }
                    }
                }
                grids.push(g);
            }
            grids[0][nz - 2][nx - 2] = b'G';
            let mut src = String::from("restitution: 0.9\n---\n");
            for (t, g) in grids.iter().rev().enumerate() {
                if t > 0 {
                    src.push_str("===\n");
                }
                for row in g {
                    src.push_str(std::str::from_utf8(row).unwrap());
                    src.push('\n');
                }
            }
            src
        },
    )
}

fn shaken<S: Scalar>(src: &str, st: Stepping, tilts: &[(i32, i32)]) -> Result<(), TestCaseError> {
    let l = match parse::<BIG>(src) {
        Ok(l) => l,
        // A wall may land under a hole only where the generator allows none.
        Err(e) => return Err(TestCaseError::fail(format!("{e}\n{src}"))),
    };
    let p = params_of::<S>(&l, st);
    let start = l.info.starts()[0];
    let (x, z) = cell_centre(&p, start.i as i32, start.k as i32);
    let centre = Vec3::new(x, S::from_int(start.storey as i32) + p.radius, z);
    let mut w: World<'_, S, 4> = World::with_centres(p, l.grid.view(), &[centre]).unwrap();
    let r = p.radius.to_f64();
    let frame = (1u32 << p.k) / 128;
    for &(tx, tz) in tilts {
        w.set_gravity_mg([tx, -900, tz]);
        for _ in 0..frame.max(1) * 16 {
            let c = step_checked(&mut w, 0);
            prop_assert!(c >= r * (1.0 - 1e-3), "clearance {} < r {}\n{}", c, r, src);
            let m = w.marbles()[0];
            prop_assert!(
                !m.out,
                "left a closed maze at {:?}\n{}",
                m.pos.to_f64(),
                src
            );
            let storey = p.layout.storey_of(m.pos.y);
            prop_assert!((0..l.info.storeys as i32).contains(&storey));
        }
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Never inside a slab or a wall on any storey, never out of a closed
    /// multi-storey maze, shaken hard (events, the QEMU firmware's stepper).
    #[test]
    fn storeys_events_never_inside_never_out(
        src in storey_maze(),
        tilts in prop::collection::vec((-900i32..=900, -900i32..=900), 4..12),
    ) {
        shaken::<fixed::types::I8F24>(&src, Stepping::Events, &tilts)?;
    }

    /// The same with fixed steps (the micro:bits' stepper).
    #[test]
    fn storeys_fixed_never_inside_never_out(
        src in storey_maze(),
        tilts in prop::collection::vec((-900i32..=900, -900i32..=900), 4..8),
    ) {
        shaken::<fixed::types::I8F24>(&src, Stepping::Fixed, &tilts)?;
    }
}

/// Found by the property above (and present with one storey too): rolling at
/// 500 mm/s over the edge that two floor tiles share beside a slot and a hole,
/// the event stepper handed a slice back and forth between the two tiles until
/// its event budget ran out, then flew blind 9 µm into the next edge. Every
/// backend, both steppers: never closer than `r·(1 − 10⁻³)`.
fn seam_beside_a_slot<S: Scalar>(st: Stepping) {
    let l = level(
        "restitution: 0.9
---
#########
#S....#.#
#.......#
#OO.O...#
#....##.#
#...#...#
#.##..O##
#.O..G.O#
#########
",
    );
    let p = params_of::<S>(&l, st);
    let (x, z) = cell_centre(&p, 1, 1);
    let mut w: World<'_, S, 4> =
        World::with_centres(p, l.grid.view(), &[Vec3::new(x, p.radius, z)]).unwrap();
    let r = p.radius.to_f64();
    let frame = ((1u32 << p.k) / 128).max(1);
    for (tx, tz) in [(-506, -659), (773, -240), (-792, 773), (0, 0)] {
        w.set_gravity_mg([tx, -900, tz]);
        for n in 0..16 * frame {
            if w.marbles()[0].out {
                return;
            }
            let c = step_checked(&mut w, 0);
            assert!(
                c >= r * (1.0 - 1e-3),
                "{} {st:?}: step {n}: clearance {c}",
                S::NAME
            );
        }
    }
}
for_each_backend_and_mode!(
    rolling_over_a_seam_beside_a_slot_never_sinks,
    seam_beside_a_slot
);
