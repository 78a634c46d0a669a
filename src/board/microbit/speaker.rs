//! The v2 speaker's PWM: the order in which a note is started.
//!
//! The nRF52833's PWM ignores a task sent while it is disabled (nRF52833
//! Product Specification, PWM chapter: the peripheral must be enabled through
//! `ENABLE` before it is used), and enabling it does not start a sequence by
//! itself: only `SEQSTART` loads the duty cycle from RAM and makes a wave. So
//! setting the duty (embassy-nrf's `SimplePwm::set_duty`, which writes the
//! duty to RAM and fires `SEQSTART`) before enabling the PWM loses the task and
//! leaves the speaker silent. The order here, which prevents that, is
//! microbit-bsp's (`speaker.rs`, `PwmSpeaker::start_play`): period, enable,
//! then the duty.
//!
//! Each note starts from a stopped PWM ([`start_note`] disables first, as
//! microbit-bsp stops after each note): embassy-nrf's `set_duty` on an enabled
//! PWM waits for `SEQEND`, which a running PWM gives only when its current
//! period ends (up to 3 ms at 330 Hz), while a freshly enabled one loads the
//! duty at once.
//!
//! The order is written against [`SpeakerPwm`], the few calls the firmware
//! makes, so that `tests/microbit_speaker.rs` checks it on the host against a
//! model of the PWM's rules; `boards/microbit/src/hw.rs` implements it on
//! embassy-nrf's `SimplePwm`.

use crate::sound::Note;

/// The PWM clock the speaker runs at, Hz: 16 MHz divided by 16, so the
/// game's tones (330 Hz .. 2 kHz) have a counter top of 500 .. 3 030.
pub const PWM_CLOCK_HZ: u32 = 1_000_000;

/// What the speaker asks of its PWM: embassy-nrf's `SimplePwm` calls, each
/// named by what it does to the peripheral.
pub trait SpeakerPwm {
    /// Writes `ENABLE` = 1.
    fn enable(&mut self);
    /// Writes `ENABLE` = 0: the wave stops.
    fn disable(&mut self);
    /// Writes `COUNTERTOP` for a wave of `hz` at [`PWM_CLOCK_HZ`].
    fn set_period(&mut self, hz: u32);
    /// Reads `COUNTERTOP`.
    fn counter_top(&self) -> u16;
    /// Writes the compare value (normal polarity: the pin is high while the
    /// counter is at or above it) to the sequence's RAM and fires `SEQSTART`.
    fn start_sequence(&mut self, compare: u16);
}

/// The compare value for a square wave at `level` (1..=255; 255 is 50 % high,
/// the loudest a square wave gets) under counter top `top`.
pub fn compare(top: u16, level: u8) -> u16 {
    let high = u32::from(top) * u32::from(level) / 510;
    // high ≤ top / 2, so the difference is in 0..=top.
    (u32::from(top) - high) as u16
}

/// Starts `note` on `pwm`: stopped, period, enabled, then the sequence.
pub fn start_note<P: SpeakerPwm>(pwm: &mut P, note: Note) {
    pwm.disable();
    pwm.set_period(u32::from(note.hz).max(1));
    pwm.enable();
    let top = pwm.counter_top();
    pwm.start_sequence(compare(top, note.level));
}

/// Silences the speaker.
pub fn silence<P: SpeakerPwm>(pwm: &mut P) {
    pwm.disable();
}
