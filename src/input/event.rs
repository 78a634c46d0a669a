//! What the input layer hands the game: tilt readings, commands, and the
//! sensor going down or coming back. Every board produces these, from an
//! accelerometer and buttons or from a terminal's keys; the game consumes
//! them without knowing which.

/// One g in milli-g.
pub(crate) const ONE_G_MG: i32 = 1000;

// ---------------------------------------------------------------------------
// Tilt and commands
// ---------------------------------------------------------------------------

/// An accelerometer reading in milli-g, in the board frame: `x` to the right,
/// `y` up (out of the LEDs), `z` towards the player.
///
/// It is the reaction to gravity, so a flat board reads [`Tilt::FLAT`]
/// (`y = +1000`), and lowering the right edge gives `x < 0`, which makes the
/// marble roll towards `+x`. Likewise `z < 0` rolls it towards the player
/// (down the screen).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tilt {
    /// Right, milli-g.
    pub x: i16,
    /// Up, milli-g.
    pub y: i16,
    /// Towards the player, milli-g.
    pub z: i16,
}

impl Tilt {
    /// The board lying flat.
    pub const FLAT: Tilt = Tilt {
        x: 0,
        y: 1000,
        z: 0,
    };

    /// A 1 g reading with the given `x` and `z` components (clamped to
    /// ±1000 mg together) and `y = +sqrt(1000² - x² - z²)`.
    pub fn from_xz(x: i32, z: i32) -> Tilt {
        let x = x.clamp(-ONE_G_MG, ONE_G_MG);
        let z = z.clamp(-ONE_G_MG, ONE_G_MG);
        let horizontal = x * x + z * z;
        let y = ((ONE_G_MG * ONE_G_MG - horizontal).max(0) as u32).isqrt();
        Tilt {
            x: x as i16,
            y: y as i16,
            z: z as i16,
        }
    }

    /// As the `[x, y, z]` reading the game's tilt path takes.
    pub const fn reading_mg(self) -> [i32; 3] {
        [self.x as i32, self.y as i32, self.z as i32]
    }
}

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
    Tilt(Tilt),
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
