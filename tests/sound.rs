//! The game's sounds: every bounce reaches them with its real impact speed,
//! their loudness grows with it, and the outcome and the mute work through
//! the player (`src/sound.rs`, `World::take_impacts`).

mod common;

use common::*;
use fixed::types::I8F24;
use marble_rolling::game::levels::LEVELS;
use marble_rolling::game::rules::Phase;
use marble_rolling::game::session::SYNTHETIC_TILT;
use marble_rolling::input::axes::AccelMg;
use marble_rolling::input::event::{Command, InputEvent};
use marble_rolling::physics::{Effects, PhysicsSpec, Scalar, Vec3};
use marble_rolling::player::Player;
use marble_rolling::sound::{self, Sound, CLICK_FROM_MM_S};

type S = I8F24;

fn space() -> Effects {
    Effects {
        holes: true,
        rolling: true,
        ..Effects::NONE
    }
}

/// A marble dropped `h_mm` onto the floor, `e = 1`: the first reported impact
/// speed against √(2gh), in mm/s.
fn drop_impact_mm_s(st: Stepping, h_mm: f64) -> (f64, f64) {
    let floor = open_floor(15);
    let p = params::<S>(PhysicsSpec {
        restitution_milli: 1000,
        ..spec_in(st, space())
    });
    let pitch_mm = p.layout.pitch_um as f64 / 1000.0;
    let mut w = world(p, &floor, &[cell_centre(&p, 7, 7)]);
    w.set_gravity_mg([0, -1000, 0]);
    w.marbles_mut()[0].pos.y = p.radius + S::from_f64(h_mm / pitch_mm);
    w.marbles_mut()[0].supported = false;
    for _ in 0..(1 << p.k) {
        w.step();
        let impacts = w.take_impacts();
        if let Some(&v) = impacts.speeds().first() {
            let reported = sound::mm_per_s(v, p.layout.pitch_um) as f64;
            return (reported, (2.0 * 9806.65 * h_mm).sqrt());
        }
    }
    panic!("{st:?}: no impact within a second of a {h_mm} mm drop");
}

#[test]
fn a_drop_reports_its_impact_speed() {
    for st in [Stepping::Fixed, Stepping::Events] {
        let mut last = None;
        // Under the lid: 10 mm storeys, 7 mm marbles leave 3 mm to fall.
        for h in [0.5, 1.25, 2.5] {
            let (got, want) = drop_impact_mm_s(st, h);
            assert!(
                (got - want).abs() <= want * 0.01 + 1.0,
                "{st:?}: {h} mm drop reported {got} mm/s, √(2gh) = {want:.1}"
            );
            let Some(Sound::Click { loudness }) = sound::click(got as u32) else {
                panic!("{st:?}: no click at {got} mm/s");
            };
            if let Some(before) = last {
                assert!(
                    loudness > before,
                    "{st:?}: {h} mm not louder than the drop before"
                );
            }
            last = Some(loudness);
        }
    }
}

/// A marble shaken in a closed box: every bounce the step counts reaches the
/// impacts (both steppers), and each frame's clicks are exactly the kept
/// impacts fast enough to click.
#[test]
fn every_bounce_is_reported_and_clicks_follow_the_threshold() {
    for st in [Stepping::Fixed, Stepping::Events] {
        let g = closed_box(3);
        let p = params::<S>(PhysicsSpec {
            restitution_milli: 800,
            ..spec_in(st, Effects::NONE)
        });
        let mut w = world(p, &g, &[cell_centre(&p, 3, 3)]);
        w.marbles_mut()[0].vel = Vec3::new(S::from_int(40), S::ZERO, S::from_int(-25));
        let mut state = 0x1234_5678_9abc_def0u64;
        let (mut reported, mut clicks, mut quiet) = (0u32, 0u32, 0u32);
        let frame_steps = steps_of(&p, 8);
        for frame in 0..1024 {
            if frame % 16 == 0 {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let x = (state % 4001) as i32 - 2000;
                let z = ((state >> 20) % 4001) as i32 - 2000;
                w.set_gravity_mg([x, -1000, z]);
            }
            let before = w.stats.collisions;
            for _ in 0..frame_steps {
                w.step();
            }
            let impacts = w.take_impacts();
            assert_eq!(
                u32::from(impacts.count),
                w.stats.collisions - before,
                "{st:?} frame {frame}: a bounce went unreported"
            );
            reported += u32::from(impacts.count);
            let loud = impacts
                .speeds()
                .iter()
                .filter(|&&v| sound::mm_per_s(v, p.layout.pitch_um) >= CLICK_FROM_MM_S)
                .count() as u32;
            quiet += impacts.speeds().len() as u32 - loud;
            let sounds = sound::frame_sounds(&impacts, p.layout.pitch_um, None, false);
            let n = sounds
                .iter()
                .filter(|s| matches!(s, Sound::Click { .. }))
                .count() as u32;
            assert_eq!(n, loud, "{st:?} frame {frame}");
            clicks += n;
            let muted = sound::frame_sounds(&impacts, p.layout.pitch_um, None, true);
            assert!(muted.is_empty());
        }
        assert!(
            clicks > 50,
            "{st:?}: only {clicks} clicks of {reported} bounces"
        );
        let _ = quiet;
    }
}

/// Through the player: a won level ends with the win sound, a mute silences
/// everything, and sound comes back with a second toggle.
#[test]
fn the_player_plays_the_outcome_and_obeys_the_mute() {
    let mut player =
        Player::<5, 5, true, false>::new(&LEVELS, 0, SYNTHETIC_TILT, true).expect("first level");
    let mut win = false;
    for _ in 0..(u32::from(LEVELS[0].info.time_limit_s) * 128) {
        let tick = player.tick(AccelMg::LEVEL, false);
        if tick.finished == Some(Phase::Won) {
            win = tick.sounds.iter().any(|s| s == Sound::Win);
            break;
        }
    }
    assert!(win, "the autopilot's win made no win sound");

    let mut muted =
        Player::<5, 5, true, false>::new(&LEVELS, 0, SYNTHETIC_TILT, true).expect("first level");
    muted.handle(InputEvent::Command(Command::ToggleMute));
    assert!(muted.muted() && muted.status().muted);
    for _ in 0..(u32::from(LEVELS[0].info.time_limit_s) * 128) {
        let tick = muted.tick(AccelMg::LEVEL, false);
        assert!(tick.sounds.is_empty(), "a sound while muted");
        if tick.finished.is_some() {
            break;
        }
    }
    muted.handle(InputEvent::Command(Command::ToggleMute));
    assert!(!muted.muted());
}

/// Two marbles rolled at each other on an open floor (`e = 1`): their bounce is
/// one impact at their closing speed (both steppers), so it clicks like a tile
/// bounce at that speed.
#[test]
fn a_bounce_between_marbles_is_one_impact_at_the_closing_speed() {
    for st in [Stepping::Fixed, Stepping::Events] {
        let floor = open_floor(31);
        let p = params::<S>(PhysicsSpec {
            restitution_milli: 1000,
            ..spec_in(
                st,
                Effects {
                    rolling: true,
                    marbles: true,
                    ..Effects::NONE
                },
            )
        });
        let mut w = world(
            p,
            &floor,
            &[cell_centre(&p, 11, 15), cell_centre(&p, 19, 15)],
        );
        w.set_gravity_mg([0, -1000, 0]);
        let v = 4.0; // pitch/s each: closing at 8
        w.marbles_mut()[0].vel = Vec3::new(S::from_f64(v), S::ZERO, S::ZERO);
        w.marbles_mut()[1].vel = Vec3::new(S::from_f64(-v), S::ZERO, S::ZERO);
        let mut speeds = Vec::new();
        let mut count = 0;
        // Three quarters of a second: they meet after about 0.4 s (4 pitches
        // apart, less a diameter, at 8 pitch/s), and the floor's edges are
        // further than they roll.
        for _ in 0..3 * (1 << p.k) / 4 {
            w.step();
            let impacts = w.take_impacts();
            count += impacts.count;
            speeds.extend(impacts.speeds().iter().map(|s| s.to_f64()));
        }
        assert_eq!(count, 1, "{st:?}: {speeds:?}");
        assert!((speeds[0] - 2.0 * v).abs() < 0.02 * v, "{st:?}: {speeds:?}");
        // They bounced back apart.
        let (a, b) = (w.marbles()[0].vel.x.to_f64(), w.marbles()[1].vel.x.to_f64());
        assert!(a < 0.0 && b > 0.0, "{st:?}: {a} {b}");
    }
}
