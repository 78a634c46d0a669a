//! The ghost (`game::ghost`): a run kept as its readings, compressed, and replayed
//! into a fresh session to the record's state hash — every built-in level, both
//! steppers — and the format's edges (a full buffer, a cut or foreign file).

use marble_rolling::game::autopilot::Autopilot;
use marble_rolling::game::generate::generate;
use marble_rolling::game::ghost::{
    race_frame, replay, Checking, Ghost, GhostError, GhostWriter, RaceError, Racer, HEADER_BYTES,
};
use marble_rolling::game::level::{parse, LevelView};
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::{GameConfig, Phase};
use marble_rolling::game::session::{Session, SYNTHETIC_TILT};
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::sensor::Calibration;
use proptest::prelude::*;

type Fx = fixed::types::I8F24;

/// The autopilot's run of `level`: its readings, how it ended, its hash.
fn record(level: LevelView<'_>, config: GameConfig) -> (Vec<AccelMg>, Phase, u64) {
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut ap = Autopilot::new(&level);
    let mut readings = Vec::new();
    while session.game().phase() == Phase::Playing {
        let r = ap.reading_mg(session.game());
        readings.push(r);
        session.frame(r);
    }
    (readings, session.game().phase(), session.state_hash())
}

fn encode(readings: &[AccelMg], hash: u64) -> Vec<u8> {
    let mut buf = vec![0u8; HEADER_BYTES + 6 * readings.len() + 16];
    let mut w = GhostWriter::new(&mut buf).unwrap();
    for &r in readings {
        w.push(r).unwrap();
    }
    w.finish(hash, Calibration::NONE).unwrap().to_vec()
}

fn ghost_replays(level: LevelView<'_>, config: GameConfig) -> (usize, f64) {
    let (readings, phase, hash) = record(level, config);
    assert_eq!(phase, Phase::Won, "{}", level.info.name);
    let bytes = encode(&readings, hash);
    let ghost = Ghost::parse(&bytes).unwrap();
    assert_eq!(ghost.frames as usize, readings.len());
    let decoded: Vec<AccelMg> = ghost.readings().map(Result::unwrap).collect();
    assert_eq!(decoded, readings, "{}", level.info.name);
    let mut fresh = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let (end, same) = replay(&mut fresh, &ghost).unwrap();
    assert_eq!(end, Phase::Won, "{}", level.info.name);
    assert!(same, "{}: the replay ends on another hash", level.info.name);
    assert_eq!(fresh.game().frames() as usize, readings.len());
    let seconds = readings.len() as f64 / f64::from(config.frame_hz());
    (bytes.len(), bytes.len() as f64 / seconds)
}

fn ghost_of_every_builtin_level(config: GameConfig) {
    for level in LEVELS.iter() {
        let (bytes, per_s) = ghost_replays(*level, config);
        println!(
            "{:?} {:16} ghost {bytes:5} B, {per_s:5.0} B per second of run",
            config.stepping, level.info.name
        );
    }
}

#[test]
fn ghost_replays_every_builtin_level_to_its_hash_with_events() {
    ghost_of_every_builtin_level(GameConfig::EVENTS);
}

#[test]
fn ghost_replays_every_builtin_level_to_its_hash_with_fixed_steps() {
    ghost_of_every_builtin_level(GameConfig::DEFAULT);
}

#[test]
fn ghost_replays_a_generated_maze() {
    let text = generate(9, 6, 3, 5).unwrap().to_string();
    let level = parse::<512>(&text).unwrap();
    ghost_replays(level.view(), GameConfig::EVENTS);
}

/// The ghost races from the player's first tilt (`race_frame`), not from the
/// level's start: the kept run looked at the maze for 300 frames before the
/// autopilot took over, the live attempt for 40. Until the live clock starts
/// the ghost waits at its start (its own looking played), its clock at 0;
/// from then on both clocks agree and the ghost's marble is where the live
/// one is at every frame (the same autopilot after the same still board), up
/// to the same win.
#[test]
fn ghost_races_from_the_first_tilt() {
    let level = LEVELS[1];
    let config = GameConfig::EVENTS;
    let flat = AccelMg::LEVEL;
    // A player who looks at the maze for `looking` frames, then lets the autopilot play.
    let player = |looking: u32| {
        let mut autopilot = Autopilot::new(&level);
        move |session: &Session<'_, Fx>| {
            if session.game().frames() < looking {
                flat
            } else {
                autopilot.reading_mg(session.game())
            }
        }
    };
    let mut check = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut kept = Vec::new();
    let mut keeper = player(300);
    while check.game().phase() == Phase::Playing {
        let r = keeper(&check);
        kept.push(r);
        check.frame(r);
    }
    assert_eq!(check.game().phase(), Phase::Won);
    let idle = check.game().frames() - check.game().clock_frames();
    assert!(
        idle >= 300,
        "{idle} frames before the kept run's clock started"
    );
    let bytes = encode(&kept, check.state_hash());
    let ghost = Ghost::parse(&bytes).unwrap();
    let mut ghost_session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let start = ghost_session.game().world().marbles()[0].pos;
    let mut ghost_readings = ghost.readings();
    let mut live = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut you = player(40);
    let mut waited = 0;
    while live.game().phase() == Phase::Playing {
        let r = you(&live);
        live.frame(r);
        let target = race_frame(idle, live.game());
        while ghost_session.game().frames() < target {
            ghost_session.frame(ghost_readings.next().unwrap().unwrap());
        }
        let (g, l) = (ghost_session.game(), live.game());
        assert_eq!(
            g.clock_frames(),
            l.clock_frames(),
            "live frame {}",
            l.frames()
        );
        if l.clock_frames() == 0 {
            waited += 1;
            assert_eq!(g.frames(), idle);
            // Its last idle frames may creep (slower than the clock's
            // threshold), never roll: within a thousandth of a pitch.
            let pos = g.world().marbles()[0].pos;
            let off = [pos.x - start.x, pos.y - start.y, pos.z - start.z];
            assert!(
                off.iter().all(|d| d.abs().to_num::<f64>() < 1e-3),
                "live frame {}: the ghost is {off:?} from its start",
                l.frames()
            );
        } else {
            assert_eq!(
                g.world().marbles()[0].pos,
                l.world().marbles()[0].pos,
                "live frame {}",
                l.frames()
            );
        }
    }
    assert!(waited >= 40, "the ghost waited {waited} frames");
    assert_eq!(live.game().phase(), Phase::Won);
    assert_eq!(ghost_session.game().phase(), Phase::Won);
    assert_eq!(ghost_session.game().frames(), kept.len() as u32);
    assert_eq!(ghost_session.state_hash(), ghost.state_hash);
}

#[test]
fn ghost_keeps_the_calibration() {
    let level = LEVELS[1];
    let config = GameConfig::EVENTS;
    let cal = Calibration {
        offset_x: 30,
        offset_z: -20,
    };
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    session.tilt_mut().set_calibration(cal);
    let mut ap = Autopilot::new(&level);
    let mut buf = vec![0u8; 1 << 16];
    let mut w = GhostWriter::new(&mut buf).unwrap();
    while session.game().phase() == Phase::Playing && session.game().frames() < 2000 {
        let r = ap.reading_mg(session.game());
        w.push(r).unwrap();
        session.frame(r);
    }
    let bytes = w.finish(session.state_hash(), cal).unwrap().to_vec();
    let ghost = Ghost::parse(&bytes).unwrap();
    assert_eq!(ghost.calibration, cal);
    let mut fresh = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    assert!(replay(&mut fresh, &ghost).unwrap().1);
    // Without it, another run.
    let mut other = bytes.clone();
    other[16..24].fill(0);
    let ghost = Ghost::parse(&other).unwrap();
    let mut fresh = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    assert!(!replay(&mut fresh, &ghost).unwrap().1);
}

#[test]
fn ghost_replay_of_another_run_misses_the_hash() {
    let level = LEVELS[2];
    let config = GameConfig::EVENTS;
    let (mut readings, _, hash) = record(level, config);
    // One reading 50 mg off, halfway through. (1 mg can vanish in the tilt
    // path's rounding: it leaves the run as it was at many of switchback's
    // frames, the halfway one among them since rolling resistance's intervals
    // are held by the error they make.)
    let n = readings.len() / 2;
    readings[n].x += 50;
    let bytes = encode(&readings, hash);
    let ghost = Ghost::parse(&bytes).unwrap();
    let mut fresh = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let (_, same) = replay(&mut fresh, &ghost).unwrap();
    assert!(!same);
}

/// A board checks a stored ghost a stretch at a time (`Checking`), yielding
/// between stretches: the same racer as the whole replay, after as many
/// stretches as the run has; and a run that misses its hash is refused the
/// same way.
#[test]
fn ghost_is_checked_a_stretch_at_a_time() {
    // Switchback: one reading 50 mg off misses the hash there.
    let level = LEVELS[2];
    let config = GameConfig::EVENTS;
    let (mut readings, phase, hash) = record(level, config);
    assert_eq!(phase, Phase::Won);
    let bytes = encode(&readings, hash);
    let whole = Racer::<true>::new(&bytes, level, config, SYNTHETIC_TILT).unwrap();
    let mut checking = Checking::<true>::new(&bytes, level, config, SYNTHETIC_TILT).unwrap();
    let mut stretches = 0;
    while !checking.play(7) {
        stretches += 1;
    }
    assert_eq!(
        stretches,
        (readings.len() - 1) / 7,
        "{} frames",
        readings.len()
    );
    assert!(checking.play(5), "over stays over");
    let racer = checking.finish().unwrap();
    assert_eq!((racer.run(), racer.clock()), (whole.run(), whole.clock()));
    assert_eq!(racer.game().frames(), 0, "the racer starts at the start");
    // Finishing early plays the rest.
    let early = Checking::<true>::new(&bytes, level, config, SYNTHETIC_TILT).unwrap();
    assert_eq!(early.finish().map(|r| r.run()), Ok(whole.run()));
    // One reading 50 mg off: refused after its stretches, as a whole replay is.
    let n = readings.len() / 2;
    readings[n].x += 50;
    let other = encode(&readings, hash);
    let mut checking = Checking::<true>::new(&other, level, config, SYNTHETIC_TILT).unwrap();
    let mut stretches = 0;
    while !checking.play(7) {
        stretches += 1;
    }
    assert!(stretches > 0);
    let refused = checking.finish().map(|r| r.run());
    assert!(
        matches!(refused, Err(RaceError::Hash | RaceError::NotWon)),
        "{refused:?}"
    );
    assert_eq!(
        Racer::<true>::new(&other, level, config, SYNTHETIC_TILT).map(|r| r.run()),
        refused
    );
}

#[test]
fn ghost_writer_stops_whole_when_full() {
    let readings: Vec<AccelMg> = (0..200)
        .map(|n| AccelMg::new(n * 3, 1000 - n, -n))
        .collect();
    let mut buf = [0u8; 64];
    let mut w = GhostWriter::new(&mut buf).unwrap();
    let mut written = 0;
    for &r in &readings {
        match w.push(r) {
            Ok(()) => written += 1,
            Err(e) => {
                assert_eq!(e, GhostError::Full);
                break;
            }
        }
    }
    assert!(written > 0 && written < readings.len());
    let bytes = w.finish(7, Calibration::NONE).unwrap().to_vec();
    let ghost = Ghost::parse(&bytes).unwrap();
    let back: Vec<_> = ghost.readings().map(Result::unwrap).collect();
    assert_eq!(back, readings[..written]);
    assert_eq!(
        GhostWriter::new(&mut [0u8; 8]).err(),
        Some(GhostError::Full)
    );
}

#[test]
fn ghost_errors_name_the_byte() {
    let readings: Vec<AccelMg> = (0..50)
        .map(|n| AccelMg::new(n * 300, 1000, -n * 200))
        .collect();
    let bytes = encode(&readings, 1);
    assert_eq!(
        Ghost::parse(b"not a ghost at all"),
        Err(GhostError::BadHeader)
    );
    assert_eq!(Ghost::parse(&bytes[..20]), Err(GhostError::BadHeader));
    // Cut inside the tokens.
    let cut = &bytes[..bytes.len() - 1];
    assert!(
        matches!(Ghost::parse(cut), Err(GhostError::Truncated { .. })),
        "{:?}",
        Ghost::parse(cut)
    );
    // The header claims one frame more than the tokens hold.
    let mut more = bytes.clone();
    more[4] += 1;
    assert_eq!(
        Ghost::parse(&more),
        Err(GhostError::Truncated { at: bytes.len() })
    );
    let msg = GhostError::Truncated { at: 17 }.to_string();
    assert!(msg.contains("byte 17"), "{msg}");
}

proptest! {
    #[test]
    fn ghost_of_any_readings_reads_back(
        start in prop::array::uniform3(-2000i32..2000),
        steps in prop::collection::vec((prop::array::uniform3(-40i32..40), 0u32..6), 0..300),
    ) {
        // A noisy sensor's walk, with repeated readings now and then.
        let mut r = start;
        let mut readings = Vec::new();
        for (d, repeat) in steps {
            for a in 0..3 {
                r[a] += d[a];
            }
            for _ in 0..=repeat {
                readings.push(AccelMg::from_array(r));
            }
        }
        let bytes = encode(&readings, 0xfeed);
        let ghost = Ghost::parse(&bytes).unwrap();
        prop_assert_eq!(ghost.state_hash, 0xfeed);
        let back: Vec<AccelMg> = ghost.readings().map(Result::unwrap).collect();
        prop_assert_eq!(back, readings);
    }
}

/// What the coding saves: the autopilot's run of `corner`, as it is and with a
/// sensor's noise (±4 mg on every axis, every frame), against 6 bytes a frame
/// (three `i16`) uncompressed.
#[test]
fn ghost_size_per_second() {
    let (readings, _, hash) = record(LEVELS[1], GameConfig::EVENTS);
    let seconds = readings.len() as f64 / 128.0;
    let mut s: u32 = 0x1234_5678;
    let mut noise = || {
        s ^= s << 13;
        s ^= s >> 17;
        s ^= s << 5;
        (s % 9) as i32 - 4
    };
    let noisy: Vec<AccelMg> = readings
        .iter()
        .map(|r| AccelMg::new(r.x + noise(), r.y + noise(), r.z + noise()))
        .collect();
    let (clean, rough) = (encode(&readings, hash).len(), encode(&noisy, hash).len());
    println!(
        "corner: {:.0} B/s from the autopilot, {:.0} B/s with a sensor's noise, {:.0} B/s raw",
        clean as f64 / seconds,
        rough as f64 / seconds,
        6.0 * 128.0
    );
    assert!(clean < rough && (rough as f64) < 6.0 * readings.len() as f64);
}

/// `cargo play`'s ghost files: a win is written once it replays to its hash,
/// read back, replayed beside a new attempt; a slower win leaves it; a stale
/// file is ignored.
#[cfg(feature = "tools")]
#[test]
fn ghost_file_keeps_the_best_run() {
    use marble_rolling::host::ghost_file::{load, path_for, GhostKeeper, GhostRun};
    let dir = std::path::PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("ghosts-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let level = LEVELS[1];
    let config = GameConfig::EVENTS;
    let name = level.info.name;
    assert_eq!(load(&dir, level, config, SYNTHETIC_TILT), None);
    // An attempt abandoned after 50 frames, then a whole autopilot run.
    let mut keeper = GhostKeeper::new(&dir, name, SYNTHETIC_TILT, None);
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut ap = Autopilot::new(&level);
    for _ in 0..50 {
        session.frame(AccelMg::new(-200, 980, 0));
        assert_eq!(keeper.observe(&session), Ok(None));
    }
    session.restart();
    let mut written = None;
    while session.game().phase() == Phase::Playing {
        session.autopilot_frame(&mut ap);
        if let Some(p) = keeper.observe(&session).unwrap() {
            written = Some(p);
        }
    }
    // The pause after the win sees the same frame again: nothing new.
    assert_eq!(keeper.observe(&session), Ok(None));
    let path = written.expect("the win is written");
    assert_eq!(path, path_for(&dir, name));
    let frames = session.game().frames();
    let bytes = load(&dir, level, config, SYNTHETIC_TILT).expect("a valid ghost");
    assert_eq!(Ghost::parse(&bytes).unwrap().frames, frames);
    // Replayed beside a new attempt: where the first run's marble was, from
    // the new attempt's first tilt (`race_frame`): it waits for one.
    let mut run = GhostRun::new(&bytes, level, config, SYNTHETIC_TILT).unwrap();
    assert_eq!(run.frames(), frames);
    let mut fresh = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let start = run.at(fresh.game()).unwrap();
    for _ in 0..256 {
        fresh.frame(AccelMg::LEVEL);
    }
    assert_eq!(fresh.game().clock_frames(), 0);
    assert_eq!(
        run.at(fresh.game()),
        Some(start),
        "waits for the first tilt"
    );
    let end = run.at(session.game()).unwrap();
    assert_ne!(start, end);
    assert_eq!(
        run.at(Session::<Fx>::new(level, config, SYNTHETIC_TILT)
            .unwrap()
            .game()),
        Some(start),
        "back to the start after a restart"
    );
    let clock = session.game().clock_frames();
    assert_eq!(run.clock(), clock);
    // A slower win on the clock does not replace it.
    let mut slow = GhostKeeper::new(&dir, name, SYNTHETIC_TILT, Some(clock - 1));
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut ap = Autopilot::new(&level);
    while session.game().phase() == Phase::Playing {
        session.autopilot_frame(&mut ap);
        assert_eq!(slow.observe(&session), Ok(None));
    }
    // A faster one on the clock does, though it looked at the maze for 300
    // frames first and took more frames in all.
    let mut faster = GhostKeeper::new(&dir, name, SYNTHETIC_TILT, Some(clock + 1));
    let mut session = Session::<Fx>::new(level, config, SYNTHETIC_TILT).unwrap();
    let mut ap = Autopilot::new(&level);
    let mut kept = None;
    while session.game().phase() == Phase::Playing {
        if session.game().frames() < 300 {
            session.frame(AccelMg::LEVEL);
        } else {
            session.autopilot_frame(&mut ap);
        }
        kept = kept.or(faster.observe(&session).unwrap());
    }
    assert!(session.game().frames() > frames + 299);
    assert_eq!(session.game().clock_frames(), clock);
    assert_eq!(kept, Some(path.clone()));
    let bytes = load(&dir, level, config, SYNTHETIC_TILT).expect("the faster ghost");
    let run = GhostRun::new(&bytes, level, config, SYNTHETIC_TILT).unwrap();
    assert_eq!(
        (run.frames(), run.clock()),
        (session.game().frames(), clock)
    );
    // The same file for another level's grid: stale, ignored.
    std::fs::copy(&path, path_for(&dir, LEVELS[0].info.name)).unwrap();
    assert_eq!(load(&dir, LEVELS[0], config, SYNTHETIC_TILT), None);
    let _ = std::fs::remove_dir_all(&dir);
}
