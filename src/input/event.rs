//! What the input layer hands the game: tilt readings, commands, and the
//! sensor going down or coming back. Every board produces these, from an
//! accelerometer and buttons or from a terminal's keys; the game consumes
//! them without knowing which.

use super::axes::AccelMg;

// ---------------------------------------------------------------------------
// Tilt and commands
// ---------------------------------------------------------------------------

/// A discrete user command.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Command {
    /// Restart the current level.
    Restart,
    /// Skip to the next level.
    NextLevel,
    /// Take the current (filtered) tilt as level.
    Calibrate,
    /// Hand the board to the autopilot, or take it back.
    ToggleAutopilot,
    /// Sound off, or back on.
    ToggleMute,
    /// Leave the game (QEMU exits with status 0).
    Quit,
}

/// What an input produces.
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputEvent {
    /// A new tilt reading (replaces the previous one).
    Tilt(AccelMg),
    /// A command for the game.
    Command(Command),
    /// The accelerometer is down (the supervisor gave up on it, for this
    /// reason): the game pauses until [`InputEvent::SensorUp`].
    SensorDown(Fault),
    /// The accelerometer delivers plausible samples again: the game resumes
    /// where it paused.
    SensorUp,
}

/// Why a poll produced no usable sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Fault {
    /// The bus transfer failed (NACK, arbitration loss, driver refusal, …).
    Bus,
    /// A bus transfer did not finish in time (a hung bus, cleared by the
    /// board before reporting).
    Timeout,
    /// The sensor answered but had no new data for longer than expected
    /// (see [`SupervisorConfig::not_ready_before_fault`](super::sensor::SupervisorConfig::not_ready_before_fault)), or its samples
    /// are stuck.
    NoData,
    /// The sample failed the [`Plausibility`](super::sensor::Plausibility) check (or the sensor is not
    /// the one expected).
    Implausible,
}
