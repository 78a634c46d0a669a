//! What the game task is asked to play ([`GameMode`]) and why it returned
//! ([`GameExit`]), the demo's totals among the reasons.

use crate::game::endless::Seeds;
use crate::input::tilt::TiltConfig;
use crate::physics::world::SetupError;

/// How [`game_task`](super::game_task) plays.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameMode {
    /// A player with a tilt input: endless, levels in order, commands ([`Links::events`](super::Links::events))
    /// obeyed. `tilt` configures the game's tilt path:
    /// [`TiltConfig::SENSOR`] for a real accelerometer (its samples come
    /// judged by the sensor's supervision), [`SYNTHETIC_TILT`](crate::game::session::SYNTHETIC_TILT)
    /// for keys.
    Play {
        /// The tilt path's configuration.
        tilt: TiltConfig,
        /// The level to start at (its number in the run: an index in
        /// [`LEVELS`](crate::game::levels::LEVELS), or past them a generated maze): 0, or the
        /// one the toy fell asleep on. Feature `sleep` only (without it, 0).
        #[cfg(feature = "sleep")]
        level: u8,
        /// Where the seeds of the mazes after the built-in levels come from
        /// (see [`crate::game::endless`]).
        seeds: Seeds,
    },
    /// The headless demo: the autopilot plays each built-in level once, in
    /// order, then [`DEMO_MAZES`](crate::game::endless::DEMO_MAZES) generated
    /// mazes ([`Seeds::Count`]: the same on every run), then
    /// [`game_task`](super::game_task) returns.
    Demo {
        /// Offer the autopilot's wins to the records task (feature
        /// `records`) as if they were a player's: the records check, which
        /// runs the demo twice and reads the first run's records back in the
        /// second. A player's game never records the autopilot's wins.
        records: bool,
    },
}

/// Why [`game_task`](super::game_task) returned.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GameExit {
    /// The player quit.
    Quit,
    /// The demo played every level and its mazes.
    DemoDone(DemoSummary),
    /// No level could be set up (a bug in the built-in levels).
    SetupFailed(SetupError),
    /// Nobody touched the toy for two minutes ([`crate::input::idle`]):
    /// the board may sleep, and resume at the start of `level`. Feature
    /// `sleep` only.
    #[cfg(feature = "sleep")]
    Asleep {
        /// The level on show (its number in the run, as
        /// [`Player::level_index`](crate::player::Player::level_index); at most 255).
        level: u8,
    },
}

/// The demo's totals (what its summary says: [`GameExit::demo_summary`],
/// [`DemoSummary::verdict`]).
#[derive(Clone, Copy, PartialEq, Eq, Hash, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct DemoSummary {
    /// Levels played (generated mazes included).
    pub levels: u8,
    /// Levels won.
    pub won: u8,
    /// Physics steps over all levels.
    pub steps: u64,
    /// Game frames over all levels.
    pub frames: u64,
}

impl DemoSummary {
    /// Every level played was won (and there was at least one).
    pub(crate) const fn all_won(&self) -> bool {
        self.levels > 0 && self.won == self.levels
    }
}
