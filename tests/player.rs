//! The game loop step every front end runs (`player::Player::tick`):
//! a downed sensor pauses the game and the game resumes exactly where it was;
//! the terminal player's keys give the firmware's readings and game.

use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::{Command, InputEvent};
use marble_rolling::input::keys::KeyTilt;
use marble_rolling::input::sensor::Fault;
use marble_rolling::player::{Player, LOSS_PAUSE_FRAMES, WIN_PAUSE_FRAMES};
use marble_rolling::render::screens::fault_frame;

type FivePlayer = Player<'static, 5, 5, true, false>;

/// A reading that rolls the marble: 0.3 g towards +x.
const TILTED: AccelMg = AccelMg::new(-300, 954, 0);

fn player(level: usize) -> FivePlayer {
    FivePlayer::new(&LEVELS, level, SYNTHETIC_TILT, false).expect("built-in level")
}

#[test]
fn a_downed_sensor_pauses_the_game_and_it_resumes_where_it_was() {
    let mut reference = player(1);
    let mut paused = player(1);
    for _ in 0..40 {
        reference.tick(TILTED, false);
        paused.tick(TILTED, false);
    }
    assert_eq!(
        paused.session().state_hash(),
        reference.session().state_hash()
    );

    assert!(paused.handle(InputEvent::SensorDown(Fault::Bus)));
    let hash = paused.session().state_hash();
    let frames = paused.game().frames();
    let steps = paused.game().steps();
    let first = paused.tick(TILTED, true);
    assert_eq!(
        first.frame,
        Some(fault_frame::<5, 5>()),
        "the fault picture is shown"
    );
    for _ in 0..500 {
        let tick = paused.tick(TILTED, true);
        assert_eq!(
            tick.frame, None,
            "the fault picture is handed out once per outage"
        );
        assert_eq!(tick.finished, None);
    }
    assert!(paused.status().sensor_down);
    assert_eq!(paused.session().state_hash(), hash, "no physics while down");
    assert_eq!(paused.game().frames(), frames, "the level clock stopped");
    assert_eq!(paused.game().steps(), steps);

    // Commands still work while down (a restart, say); here none is sent.
    assert!(paused.handle(InputEvent::SensorUp));
    let back = paused.tick(TILTED, true);
    assert!(back.frame.is_some(), "the game's picture again");
    assert_ne!(back.frame, Some(fault_frame::<5, 5>()));
    reference.tick(TILTED, false);
    for _ in 0..200 {
        reference.tick(TILTED, false);
        paused.tick(TILTED, false);
        assert_eq!(
            paused.session().state_hash(),
            reference.session().state_hash()
        );
    }
    assert!(!paused.status().sensor_down);
}

#[test]
fn an_outage_during_the_win_display_holds_it() {
    let mut p = FivePlayer::new(&LEVELS, 0, SYNTHETIC_TILT, true).expect("level");
    let mut won = None;
    for frame in 0..20_000 {
        if let Some(phase) = p.tick(AccelMg::LEVEL, false).finished {
            won = Some((phase, frame));
            break;
        }
    }
    assert_eq!(
        won.map(|w| w.0),
        Some(Phase::Won),
        "the autopilot wins level 1"
    );
    p.handle(InputEvent::SensorDown(Fault::NoData));
    for _ in 0..10 * WIN_PAUSE_FRAMES {
        p.tick(AccelMg::LEVEL, false);
    }
    assert_eq!(
        p.level_index(),
        0,
        "the win display does not run out while paused"
    );
    p.handle(InputEvent::SensorUp);
    for _ in 0..=WIN_PAUSE_FRAMES {
        p.tick(AccelMg::LEVEL, false);
    }
    assert_eq!(
        p.level_index(),
        1,
        "then the next level, as without the outage"
    );
    const { assert!(LOSS_PAUSE_FRAMES < WIN_PAUSE_FRAMES) };
}

#[test]
fn commands_reach_the_game_and_quit_is_reported() {
    let mut p = player(2);
    for _ in 0..50 {
        p.tick(TILTED, false);
    }
    assert!(p.game().frames() > 0);
    assert!(p.handle(InputEvent::Command(Command::Restart)));
    assert_eq!(p.game().frames(), 0);
    assert!(p.handle(InputEvent::Command(Command::NextLevel)));
    assert_eq!(p.level_index(), 3);
    assert!(!p.handle(InputEvent::Command(Command::Quit)));
    // Tilt events are not commands: the tilt is passed to every tick.
    assert!(p.handle(InputEvent::Tilt(AccelMg::LEVEL)));
}

/// Raw terminal bytes: right, right, up (an escape sequence and WASD), then
/// a level key.
const BYTES: &[u8] = b"\x1b[C\x1b[Cw d\x1bOA";

#[test]
fn key_bytes_give_the_same_game_on_every_front_end() {
    // The firmware's terminal input feeds raw bytes to KeyTilt.
    let mut keys = KeyTilt::new();
    let events: Vec<InputEvent> = BYTES.iter().filter_map(|&b| keys.feed(b)).collect();
    assert_eq!(events.len(), 6, "{events:?}");
    let readings: Vec<AccelMg> = events
        .iter()
        .filter_map(|e| match e {
            InputEvent::Tilt(t) => Some(*t),
            _ => None,
        })
        .collect();
    // Two presses to the right: x = -200 mg, and y makes the total 1 g with
    // the integer root the firmware uses.
    assert_eq!(readings[1], AccelMg::new(-200, 979, 0));
    let play = |events: &[InputEvent]| {
        let mut p = player(1);
        let mut keys_tilt = AccelMg::LEVEL;
        for event in events {
            if let InputEvent::Tilt(t) = event {
                keys_tilt = *t;
            }
            for _ in 0..64 {
                p.tick(keys_tilt, false);
            }
        }
        p.session().state_hash()
    };
    let firmware = play(&events);
    #[cfg(feature = "tools")]
    {
        use crossterm::event::{KeyCode, KeyEvent, KeyModifiers};
        use marble_rolling::host::play::key_of;
        let codes = [
            KeyCode::Right,
            KeyCode::Right,
            KeyCode::Char('w'),
            KeyCode::Char(' '),
            KeyCode::Char('d'),
            KeyCode::Up,
        ];
        let mut keys = KeyTilt::new();
        let terminal: Vec<InputEvent> = codes
            .iter()
            .filter_map(|&code| key_of(KeyEvent::new(code, KeyModifiers::NONE)))
            .map(|key| keys.press(key))
            .collect();
        assert_eq!(
            terminal, events,
            "cargo play's keys give the firmware's readings"
        );
        assert_eq!(play(&terminal), firmware, "and the same game");
    }
    assert_ne!(
        firmware,
        player(1).session().state_hash(),
        "the keys moved the marble"
    );
}

/// A new record (the records task's news, `Player::announce_record`) turns the
/// rest of the win's display into growing squares; it is never shown outside a
/// win, and the next level starts without it.
#[test]
fn a_new_record_shows_growing_squares_until_the_next_level() {
    use marble_rolling::render::screens::{record_frame, win_frame};
    let mut p = FivePlayer::new(&LEVELS, 0, SYNTHETIC_TILT, true).expect("level");
    // Not during play.
    p.announce_record();
    assert!(!p.status().new_record);
    let mut last = None;
    for _ in 0..20_000 {
        let tick = p.tick(AccelMg::LEVEL, true);
        if tick.finished == Some(Phase::Won) {
            last = tick.frame;
            break;
        }
    }
    let last = last.expect("the autopilot wins level 1");
    // Before the news: the win's flash.
    let left = WIN_PAUSE_FRAMES;
    assert_eq!(
        p.tick(AccelMg::LEVEL, true).frame,
        Some(win_frame(&last, left))
    );
    p.announce_record();
    assert!(p.status().new_record);
    let mut rings = std::collections::BTreeSet::new();
    for left in (1..left).rev() {
        let frame = p.tick(AccelMg::LEVEL, true).frame.expect("drawn");
        assert_eq!(frame, record_frame::<5, 5>(WIN_PAUSE_FRAMES - left));
        // One square around the centre at a time.
        let lit: Vec<(usize, usize)> = (0..25)
            .map(|i| (i % 5, i / 5))
            .filter(|&(x, y)| frame.get(x, y) > 0)
            .collect();
        let ring = lit[0].0.abs_diff(2).max(lit[0].1.abs_diff(2));
        assert!(lit
            .iter()
            .all(|&(x, y)| x.abs_diff(2).max(y.abs_diff(2)) == ring));
        assert_eq!(lit.len(), if ring == 0 { 1 } else { 8 * ring });
        rings.insert(ring);
    }
    assert_eq!(
        rings.len(),
        3,
        "the squares grow from the centre to the edge"
    );
    p.tick(AccelMg::LEVEL, true);
    assert_eq!(p.level_index(), 1);
    assert!(!p.status().new_record, "the next level starts without it");
}

/// The level clock (`game::rules`, one rule for every board): it does not run
/// while nothing rolls, starts within a few frames of the first tilt that rolls
/// the marble, and the time limit counts from there; the physics steps all
/// along, so the clock changes no state hash.
#[test]
fn the_clock_starts_at_the_first_tilt_that_rolls_a_marble() {
    fn check<const EVENTS: bool>() {
        let mut p = Player::<5, 5, true, EVENTS>::new(&LEVELS, 1, SYNTHETIC_TILT, false)
            .expect("built-in level");
        const LOOKING: u32 = 300;
        for _ in 0..LOOKING {
            p.tick(AccelMg::LEVEL, false);
        }
        assert_eq!(p.game().frames(), LOOKING);
        assert_eq!(p.game().clock_frames(), 0, "looking at the maze is free");
        assert!(!p.game().clock_started());
        assert_eq!(p.status().frames, 0, "the status shows the clock");
        // Noise a hand gives (a few mg): the rolling resistance holds the marble.
        for n in 0..200 {
            let wobble = AccelMg::new((n % 5) - 2, 1000, (n % 3) - 1);
            p.tick(wobble, false);
        }
        assert_eq!(
            p.game().clock_frames(),
            0,
            "a wobble that rolls nothing is free"
        );
        let idle = p.game().frames();
        let mut started_after = None;
        for n in 1..=64 {
            p.tick(TILTED, false);
            if p.game().clock_started() {
                started_after = Some(n);
                break;
            }
        }
        let started_after = started_after.expect("a 0.3 g tilt starts the clock");
        assert!(
            started_after <= 8,
            "the clock started {started_after} frames after the tilt"
        );
        assert_eq!(
            p.game().clock_frames() + idle + started_after - 1,
            p.game().frames()
        );
        for _ in 0..100 {
            p.tick(TILTED, false);
        }
        assert_eq!(p.status().frames, p.game().clock_frames());
        assert_eq!(
            p.game().frames() - p.game().clock_frames(),
            idle + started_after - 1,
            "once started, the clock runs with the frames"
        );
    }
    check::<false>();
    check::<true>();
}

/// The time limit is on the clock: an attempt whose first 20 s were spent
/// looking still has the whole limit to play; one nobody touches at all ends
/// as time up at the limit (a board left alone does not play one attempt for
/// ever).
#[test]
fn the_time_limit_counts_from_the_clock_start() {
    let limit = u32::from(LEVELS[0].info.time_limit_s) * 128;
    let mut untouched = player(0);
    let mut ended = None;
    for frame in 1..=limit + 10 {
        if let Some(phase) = untouched.tick(AccelMg::LEVEL, false).finished {
            ended = Some((phase, frame));
            break;
        }
    }
    assert_eq!(
        ended,
        Some((Phase::TimeUp, limit)),
        "untouched: time up at the limit"
    );

    // corner: the marble rolled right a little (the clock starts), then back
    // against the left wall and held there until the time is up.
    let mut p = player(1);
    let looking = 20 * 128;
    for _ in 0..looking {
        p.tick(AccelMg::LEVEL, false);
    }
    let limit = u32::from(LEVELS[1].info.time_limit_s) * 128;
    let mut ended = None;
    for frame in 1..=2 * limit {
        let reading = if frame <= 32 {
            TILTED
        } else {
            AccelMg::new(300, 954, 0)
        };
        if let Some(phase) = p.tick(reading, false).finished {
            ended = Some((phase, frame, p.game().clock_frames()));
            break;
        }
    }
    let (phase, frame, clock) = ended.expect("the attempt ends");
    assert_eq!(phase, Phase::TimeUp);
    assert_eq!(clock, limit, "time up after the whole limit on the clock");
    assert!(
        (limit..limit + 8).contains(&frame),
        "the looking time was not charged: time up {frame} frames after the first tilt"
    );
    assert_eq!(p.game().frames(), looking + frame);
}
