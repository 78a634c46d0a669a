//! The micro:bit v2's power-on choices (`player::power_on`): which
//! buttons held ask for what, the records' clear confirmation, the self-test's
//! frames and the tilt dot's direction (the owner's check of `AXIS_MAP`).

use marble_rolling::board::microbit::{AXIS_MAP, BUTTONS};
use marble_rolling::input::event::{Command, Fault, InputEvent};
use marble_rolling::input::sensor::AccelMg;
use marble_rolling::matrix::MAX_BRIGHTNESS;
use marble_rolling::player::power_on::{
    confirm, confirm_frame, dot, dot_from, power_on, self_test_frame, Confirm, PowerOn, SelfTest,
    CONFIRM_TIMEOUT_SAMPLES, LEVEL_FRAMES, SWEEP_FRAMES,
};

#[test]
fn buttons_held_at_power_on() {
    assert_eq!(power_on(false, false), PowerOn::Play);
    assert_eq!(power_on(true, false), PowerOn::Play);
    assert_eq!(power_on(false, true), PowerOn::SelfTest);
    assert_eq!(power_on(true, true), PowerOn::ClearRecords);
}

/// Feeds the confirmation the v2's `main` runs 10 ms samples until it
/// answers.
fn answer(samples: &[(bool, bool)]) -> Option<bool> {
    let mut question = Confirm::new(BUTTONS);
    samples.iter().find_map(|&(a, b)| question.sample(a, b))
}

fn held(a: bool, b: bool, n: usize) -> Vec<(bool, bool)> {
    vec![(a, b); n]
}

#[test]
fn clearing_needs_a_after_letting_go() {
    // Still holding A+B from power-on, then letting go: no answer.
    let mut s = held(true, true, 200);
    s.extend(held(false, false, 50));
    assert_eq!(answer(&s), None);
    // Then A alone: clear.
    let mut yes = s.clone();
    yes.extend(held(true, false, 10));
    yes.extend(held(false, false, 10));
    assert_eq!(answer(&yes), Some(true));
    // B alone: keep.
    let mut no = s.clone();
    no.extend(held(false, true, 10));
    no.extend(held(false, false, 10));
    assert_eq!(answer(&no), Some(false));
    // Releasing B before A (the A+B chord ending) is not an answer either.
    let mut ragged = held(true, true, 100);
    ragged.extend(held(true, false, 5));
    ragged.extend(held(false, false, 20));
    assert_eq!(answer(&ragged), None);
}

#[test]
fn no_answer_keeps_the_records() {
    // Both buttons stuck down: the timeout keeps them.
    let stuck = held(true, true, CONFIRM_TIMEOUT_SAMPLES as usize);
    assert_eq!(answer(&stuck), Some(false));
    assert_eq!(confirm(None, CONFIRM_TIMEOUT_SAMPLES - 1), None);
}

#[test]
fn the_confirmation_shows_a_question_mark() {
    let f = confirm_frame();
    let lit: usize = (0..5)
        .flat_map(|y| (0..5).map(move |x| (x, y)))
        .filter(|&(x, y)| f.get(x, y) > 0)
        .count();
    assert_eq!(lit, 6);
    assert_eq!(f.get(2, 4), MAX_BRIGHTNESS, "the dot");
    assert_eq!(f.get(2, 3), 0, "the gap above the dot");
}

#[test]
fn self_test_lights_each_led_alone_then_each_level() {
    for led in 0..25usize {
        for k in [0, SWEEP_FRAMES - 1] {
            let f = self_test_frame(led as u32 * SWEEP_FRAMES + k, None);
            for p in 0..25usize {
                let want = if p == led { MAX_BRIGHTNESS } else { 0 };
                assert_eq!(f.get(p % 5, p / 5), want, "led {led} frame {k}: pixel {p}");
            }
        }
    }
    let start = 25 * SWEEP_FRAMES;
    for level in 1..=u32::from(MAX_BRIGHTNESS) {
        let f = self_test_frame(start + (level - 1) * LEVEL_FRAMES, None);
        assert!(
            (0..25).all(|p| u32::from(f.get(p % 5, p / 5)) == level),
            "level {level}"
        );
    }
    assert_eq!(dot_from(), start + u32::from(MAX_BRIGHTNESS) * LEVEL_FRAMES);
    // The dot: nothing while the sensor is down, one pixel otherwise.
    let blank = self_test_frame(dot_from(), None);
    assert!((0..25).all(|p| blank.get(p % 5, p / 5) == 0));
    let f = self_test_frame(dot_from() + 1000, Some(AccelMg::LEVEL));
    assert_eq!(f.get(2, 2), MAX_BRIGHTNESS);
}

/// The self-test as the v2's `main` runs it: a frame each tick, the dot only
/// while the sensor is up, and A (the buttons' `Restart`) ends it; other
/// events change nothing.
#[test]
fn the_self_test_flow_follows_the_events() {
    let mut test = SelfTest::new();
    let level = AccelMg::LEVEL;
    for n in 0..dot_from() {
        assert_eq!(
            test.next_frame(level),
            self_test_frame(n, None),
            "frame {n}"
        );
    }
    let right = AccelMg::new(-1000, 0, 0);
    assert_eq!(test.next_frame(right).get(4, 2), MAX_BRIGHTNESS, "the dot");
    for event in [
        InputEvent::Tilt(AccelMg::LEVEL),
        InputEvent::Command(Command::NextLevel),
    ] {
        assert!(!test.event(event), "{event:?} does not end it");
    }
    assert!(!test.event(InputEvent::SensorDown(Fault::Bus)));
    let down = test.next_frame(right);
    assert!(
        (0..25).all(|p| down.get(p % 5, p / 5) == 0),
        "no dot while down"
    );
    assert!(!test.event(InputEvent::SensorUp));
    assert_eq!(test.next_frame(right).get(4, 2), MAX_BRIGHTNESS, "back up");
    assert!(
        test.event(InputEvent::Command(Command::Restart)),
        "A ends it"
    );
}

/// The dot goes where the marble would roll. With `AXIS_MAP` as shipped, the
/// raw chip readings the micro:bit runtime documents for each tilt (see
/// `tests/microbit_axes.rs`) must move it that way: this is what an owner
/// sees in the self-test, and what they fix in `AXIS_MAP` if it is wrong.
#[test]
fn the_dot_follows_the_way_the_marble_rolls() {
    assert_eq!(dot(0, 0), (2, 2));
    // Board frame: right edge down reads x < 0 (gravity +x): the dot goes right.
    assert_eq!(dot(-1000, 0), (4, 2));
    assert_eq!(dot(-150, 0), (3, 2));
    assert_eq!(dot(1000, 0), (0, 2));
    // The near edge (z, towards the player) down reads z < 0: the bottom row.
    assert_eq!(dot(0, -1000), (2, 4));
    assert_eq!(dot(0, 1000), (2, 0));
    assert_eq!(dot(i32::MIN, i32::MAX), (4, 0));
    // Raw LSM303AGR readings through AXIS_MAP: raw x reads +1 g with the right
    // edge down (the module doc of AXIS_MAP): the dot must go right.
    let right_edge_down = AXIS_MAP.apply(AccelMg::new(1000, 0, 0));
    assert_eq!(dot(right_edge_down.x, right_edge_down.z), (4, 2));
    // Raw y reads +1 g with the logo (far) edge down: the dot goes to the top.
    let logo_down = AXIS_MAP.apply(AccelMg::new(0, 1000, 0));
    assert_eq!(dot(logo_down.x, logo_down.z), (2, 0));
}

/// Sleeping keeps the level in GPREGRET; a wake-up resumes there, any other
/// reset (GPREGRET 0 at power-on, or whatever a debugger left) at level 1.
#[test]
fn the_level_survives_system_off() {
    use marble_rolling::board::microbit::{level_after_reset, sleep_marker};
    for level in 0..16u8 {
        assert_eq!(level_after_reset(sleep_marker(level)), level);
    }
    assert_eq!(level_after_reset(sleep_marker(16)), 0);
    assert_eq!(level_after_reset(0), 0);
    assert_eq!(level_after_reset(0x05), 0);
    assert_eq!(level_after_reset(0xB3), 0);
}
