//! The micro:bit v2 speaker's PWM order (`board::microbit::speaker`) against a
//! model of the nRF52833 PWM's rules: the firmware's calls must make a wave of
//! each note's pitch and loudness. The model is what the hardware would do
//! with them; the old order, which the model leaves silent, is checked too, so
//! a model that let anything through would show.

use marble_rolling::board::microbit::speaker::{
    compare, silence, start_note, SpeakerPwm, PWM_CLOCK_HZ,
};
use marble_rolling::sound::{notes, Note, Sound};

/// The nRF52833 PWM as the speaker drives it (one channel, one value per
/// sequence, no loop), by the rules of the Product Specification's PWM
/// chapter that the speaker's order depends on:
/// * a task (here `SEQSTART`) sent while `ENABLE` is 0 is ignored;
/// * `ENABLE` = 1 starts nothing: only `SEQSTART` loads the compare value
///   from RAM and starts the wave;
/// * a sequence that has ended keeps its last value on the pin until the PWM
///   is stopped; `ENABLE` = 0 stops the wave;
/// * `COUNTERTOP` sets the period, the compare value the share of it the pin
///   is high (normal polarity: high from the compare value to the top).
#[derive(Debug)]
struct NrfPwm {
    enabled: bool,
    counter_top: u16,
    /// The compare value the running sequence loaded.
    playing: Option<u16>,
    /// Tasks the PWM ignored because it was disabled.
    ignored_tasks: u32,
    /// `SEQSTART` on a PWM already making a wave (embassy-nrf's `set_duty` then
    /// waits for the end of the current period).
    restarts_while_running: u32,
}

impl NrfPwm {
    /// After reset: disabled, `COUNTERTOP` = 0x3FF.
    fn new() -> Self {
        Self {
            enabled: false,
            counter_top: 0x3FF,
            playing: None,
            ignored_tasks: 0,
            restarts_while_running: 0,
        }
    }

    /// The wave on the pin: frequency (Hz) and high share (per mille).
    fn wave(&self) -> Option<(u32, u32)> {
        let compare = self.playing?;
        let top = u32::from(self.counter_top);
        let high = top.saturating_sub(u32::from(compare));
        Some((PWM_CLOCK_HZ / top, 1000 * high / top))
    }
}

impl SpeakerPwm for NrfPwm {
    fn enable(&mut self) {
        self.enabled = true;
    }

    fn disable(&mut self) {
        self.enabled = false;
        self.playing = None;
    }

    fn set_period(&mut self, hz: u32) {
        // embassy-nrf's `SimplePwm::set_period` at the speaker's clock.
        self.counter_top = (PWM_CLOCK_HZ / hz).min(32_767) as u16;
    }

    fn counter_top(&self) -> u16 {
        self.counter_top
    }

    fn start_sequence(&mut self, compare: u16) {
        if !self.enabled {
            self.ignored_tasks += 1;
            return;
        }
        if self.playing.is_some() {
            self.restarts_while_running += 1;
        }
        self.playing = Some(compare);
    }
}

/// The order the firmware had before (`hw::Speaker::play` until this test):
/// duty while disabled, then enable.
fn old_order(pwm: &mut NrfPwm, note: Note) {
    pwm.disable();
    pwm.set_period(u32::from(note.hz));
    let top = pwm.counter_top();
    pwm.start_sequence(compare(top, note.level));
    pwm.enable();
}

/// Every sound the game makes, clicks from the softest to the loudest.
fn every_sound() -> Vec<Sound> {
    let mut sounds = vec![Sound::Win, Sound::Loss];
    sounds.extend([1u8, 64, 128, 200, 255].map(|loudness| Sound::Click { loudness }));
    sounds
}

#[test]
fn the_old_order_is_silent_on_the_model() {
    for sound in every_sound() {
        let mut pwm = NrfPwm::new();
        for note in notes(sound) {
            old_order(&mut pwm, note);
            assert_eq!(pwm.wave(), None, "{sound:?}: {note:?} sounded");
        }
        assert_eq!(pwm.ignored_tasks, notes(sound).len() as u32);
    }
}

#[test]
fn every_note_sounds_at_its_pitch_and_level() {
    for sound in every_sound() {
        let mut pwm = NrfPwm::new();
        for note in notes(sound) {
            start_note(&mut pwm, note);
            let Some((hz, high)) = pwm.wave() else {
                panic!("{sound:?}: {note:?} is silent");
            };
            // COUNTERTOP is whole clock ticks: the pitch within 0.5 %.
            let want = u32::from(note.hz);
            assert!(hz.abs_diff(want) * 200 <= want, "{note:?}: {hz} Hz");
            // level 255 is half the period high; the share within one
            // counter tick (and the ‰ rounding).
            let want = 1000 * u32::from(note.level) / 510;
            let tick = 1 + 1000 / u32::from(pwm.counter_top);
            assert!(high.abs_diff(want) <= tick, "{note:?}: {high} ‰ high");
        }
        assert_eq!(pwm.ignored_tasks, 0, "{sound:?}");
        assert_eq!(pwm.restarts_while_running, 0, "{sound:?}");
        silence(&mut pwm);
        assert_eq!(pwm.wave(), None, "{sound:?} did not stop");
    }
}

#[test]
fn a_note_after_silence_sounds_again() {
    let mut pwm = NrfPwm::new();
    for sound in [Sound::Win, Sound::Click { loudness: 90 }, Sound::Loss] {
        for note in notes(sound) {
            start_note(&mut pwm, note);
            assert!(pwm.wave().is_some(), "{sound:?} after silence");
        }
        silence(&mut pwm);
    }
    assert_eq!(pwm.ignored_tasks, 0);
}

#[test]
fn compare_values_stay_within_the_period() {
    for top in [3u16, 500, 955, 3_030, 32_767] {
        assert_eq!(compare(top, 255), top - top / 2);
        for level in 1..=255u8 {
            let c = compare(top, level);
            assert!(
                c <= top && c >= top - top / 2,
                "top {top} level {level}: {c}"
            );
        }
    }
}
