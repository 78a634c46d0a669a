//! The autopilot end to end: through the tilt path, frame by frame, it wins every
//! built-in level within the level's time limit — on the firmware's scalar and on
//! the float backends, with other tilt-path settings too — deterministically.

use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::level::{parse, Cell, LevelView};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{Game, GameConfig, Phase};
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::tilt::{GravityMg, TiltConfig, TiltFilter};
use marble_rolling::physics::{Scalar, Vec3};

/// How one attempt ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Outcome {
    phase: Phase,
    frames: u32,
    hash: u64,
    /// Largest |x| or |z| of any reading, mg.
    max_tilt: i32,
    /// Largest change of x or z from one reading to the next, mg.
    max_step: i32,
}

/// Plays `game` with the autopilot until the attempt ends: each frame the
/// autopilot's reading goes through the tilt path (`None`: gravity = −reading,
/// no filter), then the game plays the frame — as `cargo sim --autopilot` does.
fn play<S: Scalar>(mut game: Game<'_, S>, tilt: Option<TiltConfig>) -> Outcome {
    let level = *game.level();
    let mut ap = Autopilot::new(&level);
    let mut filter = tilt.map(TiltFilter::new);
    let (mut max_tilt, mut max_step, mut prev) = (0, 0, AccelMg::LEVEL);
    while game.phase() == Phase::Playing {
        let r = ap.reading_mg(&game);
        let m2 = r.magnitude_sq();
        assert!(
            (990_000..=1_000_000).contains(&m2),
            "{}: |reading|² = {m2}",
            level.info.name
        );
        max_tilt = max_tilt.max(r.x.abs()).max(r.z.abs());
        max_step = max_step.max((r.x - prev.x).abs()).max((r.z - prev.z).abs());
        prev = r;
        let g = match filter.as_mut() {
            Some(f) => f.push(r).ok(),
            None => Some(GravityMg::new(-r.x, -r.y, -r.z)),
        };
        if let Some(g) = g {
            game.set_gravity_mg(g);
        }
        game.frame();
    }
    Outcome {
        phase: game.phase(),
        frames: game.frames(),
        hash: game.world().state_hash(),
        max_tilt,
        max_step,
    }
}

fn play_level<S: Scalar>(level: LevelView<'_>, tilt: Option<TiltConfig>) -> Outcome {
    play(
        Game::<S>::new(level, GameConfig::DEFAULT).expect("level sets up"),
        tilt,
    )
}

/// Every built-in level won within its time limit; prints the frames each took.
fn wins_every_level<S: Scalar>(tilt: Option<TiltConfig>) {
    let hz = GameConfig::DEFAULT.frame_hz();
    let mut lost = Vec::new();
    for level in LEVELS.iter() {
        let o = play_level::<S>(*level, tilt);
        println!(
            "{:14} {:16} {:7} after {:5} frames ({:5.2} s of {:3} s), max tilt {:3} mg, max step {:2} mg",
            S::NAME,
            level.info.name,
            o.phase.as_str(),
            o.frames,
            o.frames as f64 / hz as f64,
            level.info.time_limit_s,
            o.max_tilt,
            o.max_step
        );
        assert!(
            o.max_tilt <= Autopilot::ESCAPE_TILT_MG,
            "{}: tilt {}",
            level.info.name,
            o.max_tilt
        );
        assert!(
            o.max_step <= 10,
            "{}: tilt step {}",
            level.info.name,
            o.max_step
        );
        if o.phase != Phase::Won || o.frames > u32::from(level.info.time_limit_s) * hz {
            lost.push((level.info.name, o.phase.as_str(), o.frames));
        }
    }
    assert!(lost.is_empty(), "{} {tilt:?}: not won: {lost:?}", S::NAME);
}

#[test]
fn wins_every_builtin_level_i8f24() {
    wins_every_level::<fixed::types::I8F24>(Some(SYNTHETIC_TILT));
}

#[test]
fn wins_every_builtin_level_f32() {
    wins_every_level::<f32>(Some(SYNTHETIC_TILT));
}

#[test]
fn wins_every_builtin_level_f64() {
    wins_every_level::<f64>(Some(SYNTHETIC_TILT));
}

#[test]
fn wins_every_builtin_level_with_the_sensor_tilt_path() {
    // The real accelerometer's settings, stuck-sensor check included.
    wins_every_level::<fixed::types::I8F24>(Some(TiltConfig::DEFAULT));
}

#[test]
fn wins_with_other_tilt_paths() {
    // No filter at all (gravity = −reading), a quick filter, a sluggish one, and
    // (ramped) dead zones, which the default path does not have: more or less lag
    // and friction than the gains were tuned for.
    let paths = [
        None,
        Some(TiltConfig {
            filter_shift: 1,
            dead_zone_mg: 10,
            ..SYNTHETIC_TILT
        }),
        Some(TiltConfig {
            filter_shift: 5,
            dead_zone_mg: 20,
            ..SYNTHETIC_TILT
        }),
        Some(TiltConfig {
            filter_shift: 4,
            dead_zone_mg: 40,
            ..SYNTHETIC_TILT
        }),
    ];
    for tilt in paths {
        wins_every_level::<fixed::types::I8F24>(tilt);
    }
}

#[test]
fn is_deterministic() {
    for level in LEVELS.iter() {
        let a = play_level::<fixed::types::I8F24>(*level, Some(SYNTHETIC_TILT));
        let b = play_level::<fixed::types::I8F24>(*level, Some(SYNTHETIC_TILT));
        assert_eq!(a, b, "{}", level.info.name);
        assert_eq!(a.phase, Phase::Won, "{}", level.info.name);
    }
}

#[test]
fn ram_is_modest() {
    let size = core::mem::size_of::<Autopilot>();
    println!("size_of::<Autopilot>() = {size} bytes");
    assert_eq!(size, Autopilot::RAM_BYTES);
    assert!(size <= 1024, "{size} bytes");
}

#[test]
fn plans_the_shortest_path() {
    // corner: right along row 1, down, left along row 3.
    let corner = LEVELS[1];
    let ap = Autopilot::new(&corner);
    assert_eq!(ap.marble(), 0);
    assert_eq!(ap.path_cells(), Some(3 + 1 + 3));
    assert_eq!(
        ap.next_cell(&corner, Cell::new(1, 1, 0)),
        Some(Cell::new(3, 1, 0))
    );
    assert_eq!(
        ap.next_cell(&corner, Cell::new(7, 1, 0)),
        Some(Cell::new(7, 3, 0))
    );
    assert_eq!(
        ap.next_cell(&corner, Cell::new(7, 3, 0)),
        Some(Cell::new(5, 3, 0))
    );
    assert_eq!(ap.next_cell(&corner, Cell::new(1, 3, 0)), None, "the goal");
    // A hole cell is never entered; a gap (a short tile without floor) is crossed.
    let stones = LEVELS[3];
    let ap = Autopilot::new(&stones);
    assert_eq!(
        ap.next_cell(&stones, Cell::new(5, 1, 0)),
        Some(Cell::new(7, 1, 0)),
        "over the gap"
    );
    assert_eq!(
        ap.next_cell(&stones, Cell::new(5, 3, 0)),
        Some(Cell::new(5, 1, 0)),
        "not into the hole at (3, 3)"
    );
    assert_eq!(ap.path_cells(), Some(7));
    // With several marbles it steers the one nearest a goal: in grand-tour the lower
    // one (8 cells; the upper one's 11-cell way ends in the lower one's row, where it
    // would be blocked by it).
    assert_eq!(Autopilot::new(&LEVELS[4]).marble(), 0);
    let tour = Autopilot::new(&LEVELS[7]);
    assert_eq!(tour.marble(), 1);
    assert_eq!(tour.path_cells(), Some(8));
}

#[test]
fn stops_at_a_corner_before_a_hole() {
    // Straight on past the corner (3, 1) is the hole (5, 1).
    let level = parse::<8>(
        "name: brink
time_limit_s: 30
---
#########
#S...O###
###.#####
#G..#####
#########
",
    )
    .expect("parses");
    let view = level.view();
    for tilt in [Some(SYNTHETIC_TILT), None] {
        let o = play_level::<fixed::types::I8F24>(view, tilt);
        assert_eq!(o.phase, Phase::Won, "{tilt:?}: {o:?}");
    }
}

#[test]
fn keeps_the_other_marble_out_of_a_hole() {
    // The autopilot steers the upper marble to the goal; the lower one, bumped
    // towards the hole below it, must be caught.
    let level = parse::<8>(
        "name: guard
time_limit_s: 30
---
###########
#S.......G#
###########
#S........#
#.#########
#O#########
###########
",
    )
    .expect("parses");
    let view = level.view();
    assert_eq!(Autopilot::new(&view).marble(), 0);
    let mut game = Game::<fixed::types::I8F24>::new(view, GameConfig::DEFAULT).expect("sets up");
    game.world_mut().marbles_mut()[1].vel.z = fixed::types::I8F24::from_num(3);
    let mut idle = game.clone();
    for _ in 0..128 {
        idle.frame();
    }
    assert_eq!(idle.phase(), Phase::Fell, "left alone, it falls");
    let o = play(game, Some(SYNTHETIC_TILT));
    assert_eq!(o.phase, Phase::Won, "{o:?}");
}

#[test]
fn lifts_a_marble_out_of_a_gap() {
    let level = parse::<8>(
        "name: slot
effects: rolling, friction
time_limit_s: 30
---
#########
#S..O..G#
#########
",
    )
    .expect("parses");
    let view = level.view();
    let mut game = Game::<fixed::types::I8F24>::new(view, GameConfig::DEFAULT).expect("sets up");
    // At rest over the middle of the 2 mm gap (column 4 spans x' = 2 ..= 2 + s).
    let s = game.world().params().layout.s;
    let m = &mut game.world_mut().marbles_mut()[0];
    m.pos.x = fixed::types::I8F24::from_num(2) + s.half();
    m.vel = Vec3::ZERO;
    // Level, it stays there.
    let mut still = game.clone();
    for _ in 0..256 {
        still.frame();
    }
    assert_eq!(still.phase(), Phase::Playing);
    let o = play(game, Some(SYNTHETIC_TILT));
    assert_eq!(o.phase, Phase::Won, "{o:?}");
    assert!(
        o.max_tilt > Autopilot::TILT_LIMIT_MG,
        "needed the escape tilt: {o:?}"
    );
    println!("out of the gap and home after {} frames", o.frames);
}

#[test]
fn unreachable_goal_is_reported_and_the_board_stays_level() {
    let level = parse::<8>(
        "name: walled
---
#########
#S..#..G#
#########
",
    )
    .expect("parses");
    let view = level.view();
    let mut ap = Autopilot::new(&view);
    assert_eq!(ap.path_cells(), None);
    let game = Game::<f64>::new(view, GameConfig::DEFAULT).expect("sets up");
    assert_eq!(ap.reading_mg(&game), AccelMg::LEVEL);
}
