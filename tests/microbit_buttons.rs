//! Buttons A/B: debounce and combinations (src/buttons.rs) with the
//! micro:bit timing (10 ms samples: 30 ms debounce, 1 s A+B hold).

use marble_rolling::board::microbit::BUTTONS;
use marble_rolling::input::buttons::{ButtonConfig, ButtonEvent, Buttons};

/// Feeds `n` identical samples, collecting events.
fn hold(b: &mut Buttons, a: bool, bb: bool, n: usize) -> Vec<ButtonEvent> {
    (0..n).filter_map(|_| b.update(a, bb)).collect()
}

#[test]
fn b_alone_is_next_level_on_release() {
    let mut b = Buttons::new(BUTTONS);
    assert_eq!(hold(&mut b, false, true, 10), vec![]);
    assert!(b.b_pressed());
    assert_eq!(hold(&mut b, false, false, 10), vec![ButtonEvent::NextLevel]);
}

#[test]
fn b_held_alone_toggles_the_sound_once_and_is_not_next_level() {
    let mut b = Buttons::new(BUTTONS);
    // Just short of the 1 s hold: a plain NextLevel on release.
    let mut events = hold(&mut b, false, true, 95);
    events.extend(hold(&mut b, false, false, 10));
    assert_eq!(events, vec![ButtonEvent::NextLevel]);
    // Held on: one ToggleMute at 1 s, nothing more while held or on release.
    let mut events = hold(&mut b, false, true, 400);
    events.extend(hold(&mut b, false, false, 10));
    assert_eq!(events, vec![ButtonEvent::ToggleMute]);
    // A held B that becomes A+B is a calibration, never a mute.
    let mut events = hold(&mut b, false, true, 50);
    events.extend(hold(&mut b, true, true, 120));
    events.extend(hold(&mut b, false, false, 10));
    assert_eq!(events, vec![ButtonEvent::Calibrate]);
}

#[test]
fn a_alone_is_restart_on_release() {
    let mut b = Buttons::new(BUTTONS);
    assert_eq!(hold(&mut b, true, false, 10), vec![]);
    assert_eq!(hold(&mut b, false, false, 10), vec![ButtonEvent::Restart]);
}

#[test]
fn bounces_shorter_than_the_debounce_are_ignored() {
    let mut b = Buttons::new(BUTTONS);
    let mut events = Vec::new();
    for i in 0..200 {
        // Two-sample glitches every 10 samples.
        let raw = i % 10 < 2;
        events.extend(b.update(raw, false));
        events.extend(b.update(false, raw));
    }
    assert_eq!(events, vec![]);
    assert!(!b.a_pressed() && !b.b_pressed());
}

#[test]
fn contact_bounce_on_press_and_release_gives_one_event() {
    let mut b = Buttons::new(BUTTONS);
    let press = [true, false, true, true, false, true, true, true, true, true];
    let release = [
        false, true, false, false, true, false, false, false, false, false,
    ];
    let mut events = Vec::new();
    for &raw in press.iter().chain(release.iter()) {
        events.extend(b.update(raw, false));
    }
    assert_eq!(events, vec![ButtonEvent::Restart]);
}

#[test]
fn a_plus_b_held_calibrates_once_and_suppresses_singles() {
    let mut b = Buttons::new(BUTTONS);
    let mut events = hold(&mut b, true, false, 5); // A first
    events.extend(hold(&mut b, true, true, 150)); // then both, 1.5 s
    events.extend(hold(&mut b, false, true, 10)); // release A first
    events.extend(hold(&mut b, false, false, 10)); // then B
    assert_eq!(events, vec![ButtonEvent::Calibrate]);
}

#[test]
fn a_plus_b_hold_timing() {
    let mut b = Buttons::new(BUTTONS);
    // Debounce (3 samples) then the hold (100 samples) counted from both down.
    let events = hold(&mut b, true, true, 3 + BUTTONS.hold_samples as usize - 2);
    assert_eq!(events, vec![]);
    assert_eq!(b.update(true, true), Some(ButtonEvent::Calibrate));
    assert_eq!(hold(&mut b, true, true, 1000), vec![]);
}

#[test]
fn short_a_plus_b_does_nothing() {
    let mut b = Buttons::new(BUTTONS);
    let mut events = hold(&mut b, true, true, 20);
    events.extend(hold(&mut b, false, false, 10));
    assert_eq!(events, vec![]);
    // Normal operation resumes afterwards.
    let mut events = hold(&mut b, false, true, 5);
    events.extend(hold(&mut b, false, false, 5));
    assert_eq!(events, vec![ButtonEvent::NextLevel]);
}

#[test]
fn second_calibration_needs_a_new_hold() {
    let mut b = Buttons::new(BUTTONS);
    let mut events = hold(&mut b, true, true, 120);
    events.extend(hold(&mut b, false, false, 5));
    events.extend(hold(&mut b, true, true, 120));
    assert_eq!(events, vec![ButtonEvent::Calibrate, ButtonEvent::Calibrate]);
}

#[test]
fn zero_config_does_not_panic() {
    let mut b = Buttons::new(ButtonConfig {
        debounce_samples: 0,
        hold_samples: 0,
    });
    assert_eq!(b.update(true, true), Some(ButtonEvent::Calibrate));
    assert_eq!(b.update(false, false), None);
    assert_eq!(b.update(true, false), None);
    assert_eq!(b.update(false, false), Some(ButtonEvent::Restart));
}
