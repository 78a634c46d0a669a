//! A playing session: where a reading becomes a frame. Every front end (the host
//! simulator, the terminal player, both firmwares) drives the game through this one
//! sequence, which is why their `state_hash`es agree for the same inputs:
//!
//! ```text
//! reading (AccelMg) ─→ tilt path (plausibility, low-pass, calibration)
//!                   ─→ gravity (GravityMg) ─→ Game::set_gravity_mg ─→ Game::frame
//! ```
//!
//! Once the low-pass has settled, the gravity is the calibrated reading itself: a
//! board held at θ rolls the marble at 5/7·g·sin θ (`tests/tilt_path.rs`). Nothing
//! is cut off near level; a resting marble is held by rolling resistance (effect
//! `friction`), see [`crate::input::tilt`].
//!
//! The reading comes from the caller (sensor, keys, trace, ghost) or from the
//! autopilot, always as an [`AccelMg`]: what a source skips of the tilt path is
//! its [`TiltConfig`]'s (e.g. [`SYNTHETIC_TILT`]), not a second way in.

use crate::input::axes::AccelMg;
use crate::input::tilt::{TiltConfig, TiltError, TiltFilter};
use crate::physics::world::SetupError;
use crate::physics::Scalar;

use super::autopilot::Autopilot;
use super::level::LevelView;
use super::rules::{Game, GameConfig, Phase};

/// The tilt path's settings for synthetic inputs (keys, traces, autopilot):
/// [`TiltConfig::DEFAULT`] (low-pass, no dead zone) except that identical
/// consecutive readings are normal there, so the stuck-sensor check is off.
pub const SYNTHETIC_TILT: TiltConfig = TiltConfig {
    stuck_samples: 0,
    ..TiltConfig::DEFAULT
};

/// A game, its tilt path and (optionally) its autopilot.
#[derive(Clone, Debug)]
pub struct Session<'a, S: Scalar> {
    game: Game<'a, S>,
    tilt: TiltFilter,
    tilt_config: TiltConfig,
    reading: AccelMg,
    tilt_errors: u32,
    last_tilt_error: Option<TiltError>,
}

impl<'a, S: Scalar> Session<'a, S> {
    /// A session on `level`.
    pub fn new(
        level: LevelView<'a>,
        config: GameConfig,
        tilt: TiltConfig,
    ) -> Result<Self, SetupError> {
        Ok(Session {
            game: Game::new(level, config)?,
            tilt: TiltFilter::new(tilt),
            tilt_config: tilt,
            reading: AccelMg::LEVEL,
            tilt_errors: 0,
            last_tilt_error: None,
        })
    }

    /// The game.
    pub fn game(&self) -> &Game<'a, S> {
        &self.game
    }
    /// The game, mutably (tools and tests).
    pub fn game_mut(&mut self) -> &mut Game<'a, S> {
        &mut self.game
    }
    /// The last reading fed in.
    pub fn reading(&self) -> AccelMg {
        self.reading
    }
    /// The tilt path.
    pub fn tilt(&self) -> &TiltFilter {
        &self.tilt
    }
    /// The tilt path, mutably (calibration).
    pub fn tilt_mut(&mut self) -> &mut TiltFilter {
        &mut self.tilt
    }
    /// The tilt path's configuration (the calibration it started with, not
    /// the one in force: [`TiltFilter::calibration`]).
    pub(crate) fn tilt_config(&self) -> TiltConfig {
        self.tilt_config
    }
    /// Readings the tilt path rejected so far, and the last reason.
    pub fn tilt_errors(&self) -> (u32, Option<TiltError>) {
        (self.tilt_errors, self.last_tilt_error)
    }

    /// Plays one frame with `reading` from the accelerometer (or a stand-in). A
    /// rejected reading keeps the last good tilt: the game goes on.
    pub fn frame(&mut self, reading: AccelMg) -> Phase {
        self.take(reading);
        self.game.frame()
    }

    /// [`Session::frame`] with the stepper fixed at compile time (firmware:
    /// `Game::frame_in`).
    pub fn frame_in<const EVENTS: bool>(&mut self, reading: AccelMg) -> Phase {
        self.take(reading);
        self.game.frame_in::<EVENTS>()
    }

    fn take(&mut self, reading: AccelMg) {
        self.reading = reading;
        match self.tilt.push(reading) {
            Ok(g) => self.game.set_gravity_mg(g),
            Err(e) => {
                self.tilt_errors = self.tilt_errors.saturating_add(1);
                self.last_tilt_error = Some(e);
            }
        }
    }

    /// Plays one frame with the autopilot's reading: it looks at the game as it is
    /// and tilts, exactly as [`Session::frame`] would take a human's tilt.
    pub fn autopilot_frame(&mut self, autopilot: &mut Autopilot) -> Phase {
        let reading = autopilot.reading_mg(&self.game);
        self.frame(reading)
    }

    /// Starts the level over; the tilt path keeps its calibration.
    pub fn restart(&mut self) {
        self.game.restart();
        let cal = self.tilt.calibration();
        self.tilt = TiltFilter::new(self.tilt_config);
        self.tilt.set_calibration(cal);
    }

    /// The exact state's digest (see `World::state_hash`).
    pub fn state_hash(&self) -> u64 {
        self.game.world().state_hash()
    }
}
