//! Generated mazes (`game::generate`): the same text from a seed every time, a
//! level the parser and the physics accept, a way from every start to the goal
//! that the autopilot plans — and the autopilot wins it through the tilt path,
//! with both steppers, over many seeds, sizes, storeys and difficulties.

use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::generate::{
    generate, GenerateError, Maze, MAX_DIFFICULTY, MAX_SIZE, MAX_TEXT_BYTES, MIN_SIZE,
};
use marble_rolling::game::level::{parse, Level};
use marble_rolling::game::rules::{Game, GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::physics::geometry::grid::{words_for, MAX_STOREYS};
use proptest::prelude::*;

/// Occupancy words of the largest generated maze.
const WORDS: usize = words_for(
    2 * MAX_SIZE as usize + 1,
    2 * MAX_STOREYS,
    2 * MAX_SIZE as usize + 1,
);

fn text(m: &Maze) -> String {
    m.to_string()
}

fn level(src: &str) -> Box<Level<'_, WORDS>> {
    Box::new(parse::<WORDS>(src).unwrap_or_else(|e| panic!("{e}\n{src}")))
}

/// FNV-1a of the text: pins the generator's output (the same on every target).
fn fnv(s: &str) -> u64 {
    s.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3)
    })
}

#[test]
fn the_same_seed_gives_the_same_text() {
    for (seed, size, storeys, difficulty) in [(1, 5, 1, 0), (2, 8, 3, 5), (u32::MAX, 15, 4, 9)] {
        let a = text(&generate(seed, size, storeys, difficulty).unwrap());
        let b = text(&generate(seed, size, storeys, difficulty).unwrap());
        assert_eq!(a, b);
    }
    // Different seeds, different mazes.
    let a = text(&generate(1, 6, 2, 3).unwrap());
    let b = text(&generate(2, 6, 2, 3).unwrap());
    assert_ne!(a, b);
}

#[test]
fn a_small_maze_reads_as_expected() {
    let t = text(&generate(7, 3, 2, 0).unwrap());
    println!("{t}");
    let lines: Vec<&str> = t.lines().collect();
    assert_eq!(lines[0], "name: maze-7-3x3x2-d0");
    assert_eq!(lines[1], "effects: rolling");
    assert!(lines[2].starts_with("time_limit_s: "), "{t}");
    assert_eq!(lines[3], "---");
    // Two storeys of 7 × 7 tiles, top first, with the separator between.
    assert_eq!(lines.len(), 4 + 7 + 1 + 7);
    assert_eq!(lines[11], "===");
    let grid: String = lines[4..].concat();
    assert_eq!(grid.matches('S').count(), 1);
    assert_eq!(grid.matches('G').count(), 1);
    assert_eq!(grid.matches('O').count(), 1, "one hole to the storey below");
    assert_eq!(lines[4], "#######");
    assert_eq!(lines[10], "#######");
}

/// The texts of a few mazes, pinned: a change to the generator, or to the random
/// numbers under it, shows here (the cross-target guarantee rests on integer
/// arithmetic and on `rand_xorshift`'s reproducibility).
#[test]
fn pinned_texts() {
    let got: Vec<u64> = [(1, 5, 1, 0), (42, 7, 2, 4), (2026, 15, 4, 9)]
        .iter()
        .map(|&(seed, size, storeys, d)| fnv(&text(&generate(seed, size, storeys, d).unwrap())))
        .collect();
    println!("{got:#018x?}");
    assert_eq!(got, PINNED);
}

const PINNED: [u64; 3] = [
    0xfe26_f5c5_9c69_290c,
    0x803f_a665_d357_bb61,
    0x048c_d9b0_ba81_7459,
];

#[test]
fn bad_arguments_are_named() {
    let cases = [
        (
            generate(1, MIN_SIZE - 1, 1, 0),
            GenerateError::Size(1),
            "size 1",
        ),
        (
            generate(1, MAX_SIZE + 1, 1, 0),
            GenerateError::Size(16),
            "size 16",
        ),
        (generate(1, 5, 0, 0), GenerateError::Storeys(0), "0 storeys"),
        (generate(1, 5, 5, 0), GenerateError::Storeys(5), "5 storeys"),
        (
            generate(1, 5, 1, MAX_DIFFICULTY + 1),
            GenerateError::Difficulty(10),
            "difficulty 10",
        ),
    ];
    for (got, want, words) in cases {
        assert_eq!(got, Err(want));
        let msg = want.to_string();
        assert!(msg.contains(words), "{msg}");
    }
}

#[test]
fn a_maze_is_small() {
    let size = core::mem::size_of::<Maze>();
    println!("size_of::<Maze>() = {size} bytes");
    assert!(size <= 1024, "{size} bytes");
}

#[test]
fn the_largest_text_fits_its_bound() {
    for seed in 0..8 {
        let t = text(&generate(seed, MAX_SIZE, MAX_STOREYS as u8, MAX_DIFFICULTY).unwrap());
        assert!(t.len() <= MAX_TEXT_BYTES, "{} > {MAX_TEXT_BYTES}", t.len());
    }
}

#[test]
fn difficulty_adds_marbles_pits_and_effects() {
    let easy = generate(3, 7, 1, 0).unwrap();
    let hard = generate(3, 7, 1, MAX_DIFFICULTY).unwrap();
    // Larger mazes keep one marble (`MAX_SIZE_FOR_MARBLES`).
    assert_eq!(generate(3, 8, 1, MAX_DIFFICULTY).unwrap().marbles(), 1);
    assert_eq!(easy.marbles(), 1);
    assert_eq!(easy.pits(), 0);
    assert_eq!(hard.marbles(), 3);
    // One pit per two levels of difficulty, as far as the dead ends go.
    assert!((1..=4).contains(&hard.pits()), "{}", hard.pits());
    assert_eq!(generate(3, 12, 1, MAX_DIFFICULTY).unwrap().pits(), 4);
    let (e, h) = (text(&easy), text(&hard));
    assert!(e.contains("effects: rolling\n"), "{e}");
    assert!(
        h.contains("effects: rolling, friction, board_motion\n"),
        "{h}"
    );
    let parsed = level(&h);
    assert!(parsed.info.spec.effects.holes && parsed.info.spec.effects.marbles);
}

/// How an autopilot run ended.
fn autopilot_run(src: &str, config: GameConfig) -> (Phase, u32, u32) {
    let l = level(src);
    let view = l.view();
    let mut ap = Autopilot::new(&view);
    let mut session = Session::<fixed::types::I8F24>::new(view, config, SYNTHETIC_TILT)
        .unwrap_or_else(|e| panic!("set up: {e}\n{src}"));
    while session.game().phase() == Phase::Playing {
        let r = ap.reading_mg(session.game());
        session.frame(r);
    }
    let g = session.game();
    (
        g.phase(),
        g.frames(),
        u32::from(view.info.time_limit_s) * config.frame_hz(),
    )
}

/// Parses, sets up, and the autopilot plans a way from a start to the goal that
/// is as long as the generator's.
fn accepted(m: &Maze) -> Result<(), TestCaseError> {
    let src = text(m);
    let l = level(&src);
    let view = l.view();
    prop_assert_eq!(view.info.storeys, m.storeys());
    prop_assert_eq!(view.info.starts().len(), m.marbles());
    prop_assert_eq!(view.info.goals().len(), 1);
    prop_assert!(Game::<fixed::types::I8F24>::new(view, GameConfig::DEFAULT).is_ok());
    prop_assert!(m.every_start_reaches_the_goal());
    let ap = Autopilot::new(&view);
    let planned = ap.path_cells();
    prop_assert!(planned.is_some(), "no way planned:\n{}", src);
    // The first start's way is the generator's; another marble may be nearer.
    prop_assert!(
        planned.unwrap() <= m.path_cells(),
        "{:?} vs {}\n{}",
        planned,
        m.path_cells(),
        src
    );
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    #[test]
    fn every_maze_is_accepted_and_planned(
        seed in any::<u32>(),
        size in MIN_SIZE..=MAX_SIZE,
        storeys in 1..=MAX_STOREYS as u8,
        difficulty in 0..=MAX_DIFFICULTY,
    ) {
        accepted(&generate(seed, size, storeys, difficulty).unwrap())?;
    }
}

/// The autopilot against 256 generated mazes (a fixed pseudo-random draw of seed,
/// size, storeys and difficulty over their whole ranges), each played with both
/// steppers. The autopilot steers every marble with one tilt: on a few small
/// mazes with two or three marbles it runs out of time (a run of 10 000 random
/// mazes lost 7 with each stepper, the same mazes with both: 4 to 7 cells a
/// side, one storey, difficulty 4 to 9), so this holds it to a win rate of
/// 99 % and prints what it lost. A random draw per run made the suite fail
/// about once in 30 runs.
#[test]
fn the_autopilot_wins_nearly_every_maze() {
    let mut state: u64 = 0x6a09_e667_f3bc_c909;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    };
    let (mut games, mut lost) = (0u32, Vec::new());
    for _ in 0..256 {
        let seed = next() as u32;
        let size = MIN_SIZE + (next() % u64::from(MAX_SIZE - MIN_SIZE + 1)) as u8;
        let storeys = 1 + (next() % MAX_STOREYS as u64) as u8;
        let difficulty = (next() % (u64::from(MAX_DIFFICULTY) + 1)) as u8;
        let m = generate(seed, size, storeys, difficulty).unwrap();
        for config in [GameConfig::EVENTS, GameConfig::DEFAULT] {
            games += 1;
            let (phase, frames, limit) = autopilot_run(&text(&m), config);
            if phase != Phase::Won {
                lost.push(format!(
                    "{:?} seed {seed} size {size} storeys {storeys} difficulty {difficulty}: {} after {frames} of {limit} frames",
                    config.stepping,
                    phase.as_str()
                ));
            }
        }
    }
    println!("the autopilot lost {} of {games}: {lost:#?}", lost.len());
    assert!(
        lost.len() as u32 * 100 <= games,
        "lost {} of {games}: {lost:#?}",
        lost.len()
    );
}

/// The autopilot on 168 mazes per difficulty (six seeds × sizes 3, 5, …, 15 × 1–4 storeys,
/// alternately event and fixed steps): how many it wins and its slowest pace,
/// the figures behind `Maze::time_limit_s`, `Maze::board_motion` and
/// `MAX_SIZE_FOR_MARBLES` (a panic, from an overflow check, counts as lost)
/// (`cargo test --features tools --test generate survey -- --ignored --nocapture`).
#[test]
#[ignore]
fn survey() {
    for d in 0..=MAX_DIFFICULTY {
        let (mut won, mut n, mut worst) = (0, 0, 0.0f64);
        let mut lost = Vec::new();
        for seed in 0..6u32 {
            for size in [3u8, 5, 7, 9, 11, 13, 15] {
                for storeys in 1..=4u8 {
                    let m = generate(seed * 977 + 13, size, storeys, d).unwrap();
                    let config = if seed % 2 == 0 {
                        GameConfig::EVENTS
                    } else {
                        GameConfig::DEFAULT
                    };
                    let src = text(&m);
                    let Ok((phase, frames, _)) =
                        std::panic::catch_unwind(|| autopilot_run(&src, config))
                    else {
                        lost.push((m.seed(), size, storeys, "panicked"));
                        continue;
                    };
                    n += 1;
                    if phase == Phase::Won {
                        won += 1;
                        worst = worst
                            .max(frames as f64 / 128.0 / f64::from(m.path_cells() + m.turns()));
                    } else {
                        lost.push((m.seed(), size, storeys, phase.as_str()));
                    }
                }
            }
        }
        println!("d{d}: won {won}/{n}, worst {worst:.3} s per cell+turn; lost {lost:?}");
    }
}
