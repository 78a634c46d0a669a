//! The endless run (`game::endless`): which level comes after level N on each
//! board, the maze slot that the boards parse a generated maze into (the same
//! level, the same `state_hash`, as `cargo sim -- --generate …` plays), each
//! board's slot within its RAM, and the player moving on in the run.

use marble_rolling::board::{microbit, microbit_v1, qemu};
use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::endless::{
    Endless, MazeArgs, MazeError, MazeSlot, Reach, Seeds, Stage, StageError, DEMO_MAZES, FIRST_SIZE,
};
use marble_rolling::game::generate::{generate, text_bytes, MAX_DIFFICULTY, MAX_SIZE};
use marble_rolling::game::level::{parse, LevelView};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{GameConfig, Phase, DEFAULT_EVENTS};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::{Command, InputEvent};
use marble_rolling::physics::geometry::grid::{words_for, MAX_STOREYS};
use marble_rolling::physics::geometry::tiles::TileIndex;
use marble_rolling::physics::Fx;
use marble_rolling::player::Player;

/// The boards' reaches, by name.
const BOARDS: [(&str, Reach); 3] = [
    ("qemu", qemu::MAZE_REACH),
    ("micro:bit v2", microbit::MAZE_REACH),
    ("micro:bit v1", microbit_v1::MAZE_REACH),
];

fn run(reach: Reach, seeds: Seeds) -> Endless {
    Endless {
        from_region: 0,
        builtins: LEVELS.len(),
        reach,
        seeds,
    }
}

fn maze(stage: Stage) -> MazeArgs {
    match stage {
        Stage::Maze(args) => args,
        Stage::Builtin(i) => panic!("built-in level {i} where a maze was expected"),
        Stage::Region(i) => panic!("level {i} of the region where a maze was expected"),
    }
}

#[test]
fn the_built_in_levels_come_first_then_mazes_numbered_by_the_count() {
    let endless = run(qemu::MAZE_REACH, Seeds::Count);
    for i in 0..LEVELS.len() {
        assert_eq!(endless.stage(i), Stage::Builtin(i));
    }
    // Level 11 of the run is the first maze, seeded 11: the demos' three.
    let first = maze(endless.stage(LEVELS.len()));
    assert_eq!(
        first,
        MazeArgs {
            seed: LEVELS.len() as u32 + 1,
            size: FIRST_SIZE,
            storeys: 1,
            difficulty: 1
        }
    );
    let demo: Vec<MazeArgs> = (0..DEMO_MAZES)
        .map(|k| maze(endless.stage(LEVELS.len() + k)))
        .collect();
    assert_eq!(
        demo.iter()
            .map(|m| (m.seed, m.size, m.storeys, m.difficulty))
            .collect::<Vec<_>>(),
        [(11, 4, 1, 1), (12, 4, 2, 1), (13, 4, 3, 2)]
    );
    // The same run twice: the same mazes (QEMU and the v1 are deterministic).
    assert_eq!(
        endless.stage(57),
        run(qemu::MAZE_REACH, Seeds::Count).stage(57)
    );
}

#[test]
fn difficulty_and_size_rise_and_stay_within_reach() {
    for (board, reach) in BOARDS {
        let endless = run(reach, Seeds::Drawn(0xDEAD_BEEF));
        let mut last = maze(endless.stage(LEVELS.len()));
        let mut storeys_seen = [false; MAX_STOREYS + 1];
        for k in 1..200 {
            let m = maze(endless.stage(LEVELS.len() + k));
            assert!(reach.holds(m), "{board}: maze {k} {m:?} beyond {reach:?}");
            assert!(m.difficulty >= last.difficulty, "{board}: {k}");
            assert!(m.size >= last.size, "{board}: {k}");
            assert!(m.difficulty <= MAX_DIFFICULTY);
            storeys_seen[usize::from(m.storeys)] = true;
            last = m;
        }
        // The run reaches the hardest difficulty and the largest size the
        // board keeps, and plays every storey count it can show.
        assert_eq!(last.difficulty, MAX_DIFFICULTY, "{board}");
        assert_eq!(last.size, reach.size, "{board}");
        let seen: Vec<usize> = (0..=MAX_STOREYS).filter(|&n| storeys_seen[n]).collect();
        assert_eq!(
            seen,
            (1..=usize::from(reach.storeys)).collect::<Vec<_>>(),
            "{board}"
        );
    }
}

#[test]
fn drawn_seeds_differ_from_maze_to_maze_and_from_draw_to_draw() {
    let reach = microbit::MAZE_REACH;
    let seeds = |drawn: u32| -> Vec<u32> {
        (0..64)
            .map(|k| maze(run(reach, Seeds::Drawn(drawn)).stage(LEVELS.len() + k)).seed)
            .collect()
    };
    let a = seeds(1);
    let mut unique = a.clone();
    unique.sort_unstable();
    unique.dedup();
    assert_eq!(unique.len(), a.len(), "a run repeats a seed");
    // Two power-ups whose draws are one apart share no maze.
    let b = seeds(2);
    assert!(a.iter().all(|s| !b.contains(s)));
}

#[test]
fn a_reach_beyond_the_generator_is_bounded() {
    let endless = run(
        Reach {
            size: 200,
            storeys: 9,
        },
        Seeds::Count,
    );
    let far = maze(endless.stage(LEVELS.len() + 10_000));
    assert_eq!(
        (far.size, far.storeys <= MAX_STOREYS as u8),
        (MAX_SIZE, true)
    );
    assert!(generate(far.seed, far.size, far.storeys, far.difficulty).is_ok());
    // And a reach of nothing still plays the smallest maze on one storey.
    let tiny = run(
        Reach {
            size: 0,
            storeys: 0,
        },
        Seeds::Count,
    );
    let m = maze(tiny.stage(LEVELS.len() + 5));
    assert_eq!((m.size, m.storeys), (2, 1));
}

/// The level as `cargo sim -- --generate` makes it: the generator's text,
/// parsed with room for any maze.
fn sim_level(args: MazeArgs) -> (String, LevelView<'static>) {
    const WORDS: usize = words_for(
        2 * MAX_SIZE as usize + 1,
        2 * MAX_STOREYS,
        2 * MAX_SIZE as usize + 1,
    );
    let text = generate(args.seed, args.size, args.storeys, args.difficulty)
        .expect("a maze")
        .to_string();
    let src: &'static str = Box::leak(text.clone().into_boxed_str());
    let level = Box::leak(Box::new(parse::<WORDS>(src).expect("parses")));
    (text, level.view())
}

/// The autopilot's run on `level` as the demo plays it (`cargo sim
/// --autopilot`): the outcome, the steps and the state hash.
fn autopilot_run(level: LevelView<'_>) -> (Phase, u64, u64) {
    let config = GameConfig::stepped_by(DEFAULT_EVENTS);
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).expect("sets up");
    let mut pilot = Autopilot::new(&level);
    let limit = u64::from(level.info.time_limit_s) * u64::from(config.frame_hz()) + 10;
    for _ in 0..limit {
        let phase = session.autopilot_frame(&mut pilot);
        if phase != Phase::Playing {
            break;
        }
    }
    (
        session.game().phase(),
        session.game().steps(),
        session.state_hash(),
    )
}

/// Every tile of `level`: its dimensions and which tiles are solid.
fn solid(level: &LevelView<'_>) -> (usize, usize, usize, Vec<bool>) {
    let t = &level.tiles;
    let mut solid = Vec::new();
    for j in 0..t.ny() as i32 {
        for k in 0..t.nz() as i32 {
            for i in 0..t.nx() as i32 {
                solid.push(t.is_solid(TileIndex::new(i, j, k)));
            }
        }
    }
    (t.nx(), t.ny(), t.nz(), solid)
}

/// Each board's slot makes the level `cargo sim` makes from the same
/// arguments: the same header, tiles and name, and the autopilot ends on the
/// same state hash (what `cargo xtask check-demo` and `check-microbit-v1`
/// compare in QEMU, here for more mazes).
fn the_slot_plays_as_the_simulator<const WORDS: usize, const TEXT: usize>(
    slot: &mut MazeSlot<WORDS, TEXT>,
) {
    let endless = run(slot.reach(), Seeds::Count);
    for k in 0..6 {
        let args = maze(endless.stage(LEVELS.len() + k));
        let (text, expected) = sim_level(args);
        assert!(text.len() <= TEXT, "{args:?}: {} bytes", text.len());
        let made = slot.make(args).expect("made");
        assert_eq!(made.info, expected.info, "{args:?}");
        assert_eq!(solid(&made), solid(&expected), "{args:?}");
        assert_eq!(
            made.info.name,
            format!(
                "maze-{}-{}x{}x{}-d{}",
                args.seed, args.size, args.size, args.storeys, args.difficulty
            )
        );
        let run = autopilot_run(made);
        assert_eq!(run, autopilot_run(expected), "{args:?}");
        assert_eq!(run.0, Phase::Won, "{args:?}");
    }
}

#[test]
fn each_boards_slot_makes_the_simulators_level() {
    the_slot_plays_as_the_simulator(&mut MazeSlot::<
        { qemu::MAZE_REACH.words() },
        { qemu::MAZE_REACH.text_bytes() },
    >::new(qemu::MAZE_REACH));
    the_slot_plays_as_the_simulator(&mut MazeSlot::<
        { microbit_v1::MAZE_REACH.words() },
        { microbit_v1::MAZE_REACH.text_bytes() },
    >::new(microbit_v1::MAZE_REACH));
}

#[test]
fn the_largest_maze_within_reach_fits_its_slot() {
    for (board, reach) in BOARDS {
        let largest = MazeArgs {
            seed: u32::MAX,
            size: reach.size,
            storeys: reach.storeys,
            difficulty: MAX_DIFFICULTY,
        };
        let text = generate(largest.seed, largest.size, largest.storeys, MAX_DIFFICULTY)
            .expect("a maze")
            .to_string();
        assert!(
            text.len() <= reach.text_bytes(),
            "{board}: {} bytes",
            text.len()
        );
        assert_eq!(reach.text_bytes(), text_bytes(reach.size, reach.storeys));
    }
    // The v1's slot, made for its reach, holds its largest maze.
    let reach = microbit_v1::MAZE_REACH;
    let mut slot = MazeSlot::<
        { microbit_v1::MAZE_REACH.words() },
        { microbit_v1::MAZE_REACH.text_bytes() },
    >::new(reach);
    let made = slot
        .make(MazeArgs {
            seed: 4_000_000_000,
            size: reach.size,
            storeys: reach.storeys,
            difficulty: MAX_DIFFICULTY,
        })
        .expect("the largest maze within reach");
    assert_eq!(usize::from(made.info.storeys), usize::from(reach.storeys));
}

#[test]
fn a_maze_beyond_the_slot_is_refused_not_cut() {
    let reach = Reach {
        size: 4,
        storeys: 1,
    };
    let mut slot = MazeSlot::<
        {
            Reach {
                size: 4,
                storeys: 1,
            }
            .words()
        },
        {
            Reach {
                size: 4,
                storeys: 1,
            }
            .text_bytes()
        },
    >::new(reach);
    let big = MazeArgs {
        seed: 1,
        size: 5,
        storeys: 1,
        difficulty: 0,
    };
    assert_eq!(slot.make(big).err(), Some(MazeError::BeyondReach(big)));
    // A slot claiming more reach than its buffers: the text does not fit,
    // an error rather than a cut level.
    let mut liar = MazeSlot::<
        {
            Reach {
                size: 4,
                storeys: 1,
            }
            .words()
        },
        64,
    >::new(reach);
    let small = MazeArgs { size: 4, ..big };
    assert_eq!(liar.make(small).err(), Some(MazeError::TextTooLong));
    // Bad arguments are the generator's error.
    assert!(matches!(
        slot.make(MazeArgs {
            difficulty: 200,
            ..small
        }),
        Err(MazeError::Generate(_))
    ));
    assert!(slot.make(small).is_ok());
}

/// A slot keeps the tiles, the header, the name and where the levels region
/// is, not the level text (which is on the stack only while it is parsed): on
/// the v1 the text would be 1 104 B more of static RAM.
#[test]
fn a_slot_keeps_no_text() {
    type V1Slot =
        MazeSlot<{ microbit_v1::MAZE_REACH.words() }, { microbit_v1::MAZE_REACH.text_bytes() }>;
    let size = core::mem::size_of::<V1Slot>();
    let parts = 4 * microbit_v1::MAZE_REACH.words()
        + core::mem::size_of::<marble_rolling::game::level::LevelInfo<'static>>()
        + core::mem::size_of::<Option<marble_rolling::board::levels_region::Region<'static>>>()
        + 28;
    println!(
        "micro:bit v1 maze slot: {size} B on the host, of which {parts} B tiles, header, region and name"
    );
    assert!(size <= parts + 32, "{size} B for {parts} B of parts");
    assert!(microbit_v1::MAZE_REACH.text_bytes() > 32);
}

type FivePlayer<'a> = Player<'a, 5, 5, true, false>;

/// Plays `player` with the autopilot until it wants the next level (at most
/// `frames`); returns whether it did.
fn play_until_next(player: &mut FivePlayer<'_>, frames: u32) -> bool {
    for _ in 0..frames {
        player.tick(AccelMg::LEVEL, false);
        if player.wants_next() {
            return true;
        }
    }
    false
}

#[test]
fn in_the_run_a_player_says_it_is_done_and_keeps_its_number() {
    let mut player = FivePlayer::single(LEVELS[0], SYNTHETIC_TILT, true).expect("level");
    player.endless_at(3);
    assert_eq!(player.level_index(), 3);
    assert_eq!(player.status().level, 3);
    assert!(!player.wants_next());
    assert!(play_until_next(&mut player, 4_000), "won and moved on");
    // It stays on its level: the game task brings the next one.
    assert_eq!(player.level_name(), LEVELS[0].info.name);
    // Skipping is the same.
    let mut player = FivePlayer::single(LEVELS[1], SYNTHETIC_TILT, false).expect("level");
    player.endless_at(12);
    player.handle(InputEvent::Command(Command::NextLevel));
    assert!(player.wants_next());
    assert_eq!(player.level_index(), 12);
}

#[test]
fn a_single_level_outside_the_run_starts_again() {
    let mut player = FivePlayer::single(LEVELS[1], SYNTHETIC_TILT, false).expect("level");
    player.tick(AccelMg::new(-400, 900, 0), false);
    player.handle(InputEvent::Command(Command::NextLevel));
    assert!(!player.wants_next());
    assert_eq!(player.game().frames(), 0, "started again");
    assert_eq!(player.level_name(), LEVELS[1].info.name);
}

#[test]
fn the_next_level_keeps_the_sound_the_calibration_and_the_autopilot() {
    let mut player = FivePlayer::new(&LEVELS, 0, SYNTHETIC_TILT, false).expect("level");
    // A calibration the defaults do not have: taken at a tilted board.
    for _ in 0..64 {
        player.tick(AccelMg::new(120, 990, -80), false);
    }
    player.handle(InputEvent::Command(Command::Calibrate));
    player.handle(InputEvent::Command(Command::ToggleMute));
    player.handle(InputEvent::Command(Command::ToggleAutopilot));
    let carried = player.carried();
    assert!(carried.autopilot());
    // Within the list (the player moves on by itself) …
    player.handle(InputEvent::Command(Command::NextLevel));
    assert_eq!(player.level_index(), 1);
    assert!(player.muted(), "the sound stays off");
    assert!(player.autopilot());
    assert_eq!(player.carried(), carried);
    // … and into a level no list holds (the game task carries it).
    let mut next =
        FivePlayer::single(LEVELS[2], SYNTHETIC_TILT, carried.autopilot()).expect("level");
    assert_ne!(next.carried(), carried);
    next.carry(carried);
    assert_eq!(next.carried(), carried);
}

/// The game task's run (`app::game_task`'s play loop, step for step, without
/// its clock): from the last built-in level into the mazes, each level's
/// player built for it alone and told its number, the settings carried from
/// the player before.
#[test]
fn the_run_goes_on_from_the_last_built_in_level_into_mazes() {
    let reach = microbit_v1::MAZE_REACH;
    let endless = run(reach, Seeds::Count);
    let mut mazes = MazeSlot::<
        { microbit_v1::MAZE_REACH.words() },
        { microbit_v1::MAZE_REACH.text_bytes() },
    >::new(reach);
    let mut number = LEVELS.len() - 1;
    let mut carried = None;
    let mut played = Vec::new();
    for _ in 0..3 {
        let level = endless.level(number, &mut mazes).expect("a level");
        let autopilot = carried.is_none_or(|c: marble_rolling::player::Carried| c.autopilot());
        let mut made = FivePlayer::single(level, SYNTHETIC_TILT, autopilot);
        let player = made.as_mut().expect("set up");
        player.endless_at(number);
        if let Some(carried) = carried {
            player.carry(carried);
        } else {
            // Sound off on the first: the mazes must keep it off.
            player.handle(InputEvent::Command(Command::ToggleMute));
        }
        assert_eq!(usize::from(player.status().level), number);
        assert!(play_until_next(player, 20_000), "{}", player.level_name());
        assert!(player.muted(), "{}", player.level_name());
        played.push(player.level_name().to_string());
        carried = Some(player.carried());
        number = player.level_index() + 1;
    }
    assert_eq!(
        played,
        [
            LEVELS[LEVELS.len() - 1].info.name,
            "maze-11-4x4x1-d1",
            "maze-12-4x4x2-d1"
        ]
    );
    // A level past the built-in levels that the board does not keep is the
    // maze's error, not a crash.
    let far = Endless {
        builtins: LEVELS.len() + 5,
        ..endless
    };
    assert_eq!(
        far.level(LEVELS.len(), &mut mazes).err(),
        Some(StageError::NoBuiltin(LEVELS.len()))
    );
}
