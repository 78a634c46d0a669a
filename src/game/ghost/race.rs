//! Racing a stored ghost: its replay checked against its hash (whole, or a
//! stretch at a time on a board), and played beside the live attempt on the
//! level clock (see the parent module's "Racing from the first tilt").

use crate::input::axes::AccelMg;
use crate::input::tilt::TiltConfig;
use crate::physics::world::SetupError;
use crate::physics::{Fx, Scalar};

use super::super::level::LevelView;
use super::super::rules::{Game, GameConfig, Phase};
use super::super::session::Session;
use super::{Ghost, GhostError, Readings};

/// Plays `ghost` into `session` (a fresh session of the ghost's level, game
/// configuration and tilt settings) with the ghost's calibration, frame by frame
/// until the readings end or the attempt does; returns how it ended, and whether
/// the state hash is the ghost's.
pub fn replay<S: Scalar>(
    session: &mut Session<'_, S>,
    ghost: &Ghost<'_>,
) -> Result<(Phase, bool), GhostError> {
    replay_by(session, ghost, Session::frame)
}

/// [`replay`]: the ghost's readings fed to `frame`.
fn replay_by<'a, S: Scalar>(
    session: &mut Session<'a, S>,
    ghost: &Ghost<'_>,
    mut frame: impl FnMut(&mut Session<'a, S>, AccelMg) -> Phase,
) -> Result<(Phase, bool), GhostError> {
    session.tilt_mut().set_calibration(ghost.calibration);
    let mut phase = session.game().phase();
    for r in ghost.readings() {
        if phase != Phase::Playing {
            break;
        }
        phase = frame(session, r?);
    }
    Ok((phase, session.state_hash() == ghost.state_hash))
}

/// How many frames of a ghost's run to have played beside `live`, an attempt
/// at the same level (see the module doc): its `idle` frames, those before its
/// own clock started ([`Game::frames`] − [`Game::clock_frames`] at the end of
/// its replay), then as many as `live` has on its clock. Fewer than the ghost
/// has played means that `live` started over: replay from the start.
pub fn race_frame<S: Scalar>(idle: u32, live: &Game<'_, S>) -> u32 {
    idle.saturating_add(live.clock_frames())
}

/// Why a stored ghost is not raced.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RaceError {
    /// Its bytes are not a ghost.
    Ghost(GhostError),
    /// The level cannot be set up.
    Setup(SetupError),
    /// Its replay does not win the level.
    NotWon,
    /// Its replay wins on another state hash (another build's physics, or
    /// another level under the same key).
    Hash,
}

impl core::fmt::Display for RaceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RaceError::Ghost(e) => write!(f, "{e}"),
            RaceError::Setup(e) => write!(f, "the level cannot be set up: {e:?}"),
            RaceError::NotWon => f.write_str("its replay does not win the level"),
            RaceError::Hash => f.write_str("its replay does not end on its state hash"),
        }
    }
}

/// A stored ghost raced beside the live attempt on a board: its own session,
/// stepped to [`race_frame`] each frame, its readings read from the stored
/// bytes as it goes (no copy of the run in RAM).
#[derive(Clone, Debug)]
pub struct Racer<'a, 'g, const EVENTS: bool> {
    session: Session<'a, Fx>,
    ghost: Ghost<'g>,
    readings: Readings<'g>,
    idle: u32,
}

/// A stored ghost's replay played a stretch at a time ([`Checking::play`]),
/// so that a board can let its other tasks run between stretches: a long run
/// replayed at once would hold the CPU for as long as the physics of every
/// frame of it takes. [`Racer::new`] plays it whole. The replay's session is
/// the racer's: checked in place (`Checking::verify`), a board keeps one
/// session for the ghost, not a second beside it while the first is made.
#[derive(Clone, Debug)]
pub struct Checking<'a, 'g, const EVENTS: bool> {
    racer: Racer<'a, 'g, EVENTS>,
    phase: Phase,
    /// The replay is over: the attempt ended, the readings did, or one of
    /// them was not a reading (`error`).
    ended: bool,
    error: Option<GhostError>,
    /// [`Checking::verify`] found the replay good: the racer is at its start.
    verified: bool,
}

impl<'a, 'g, const EVENTS: bool> Checking<'a, 'g, EVENTS> {
    /// The replay of the ghost in `bytes` on `level` (game configuration
    /// `config`, tilt path `tilt`), at its start.
    pub fn new(
        bytes: &'g [u8],
        level: LevelView<'a>,
        config: GameConfig,
        tilt: TiltConfig,
    ) -> Result<Self, RaceError> {
        let ghost = Ghost::parse(bytes).map_err(RaceError::Ghost)?;
        let mut session = Session::new(level, config, tilt).map_err(RaceError::Setup)?;
        session.tilt_mut().set_calibration(ghost.calibration);
        let phase = session.game().phase();
        Ok(Checking {
            racer: Racer {
                session,
                readings: ghost.readings(),
                ghost,
                idle: 0,
            },
            phase,
            ended: false,
            error: None,
            verified: false,
        })
    }

    /// Plays up to `frames` more frames of the run; whether the replay is
    /// over (then `Checking::verify` says how it ended).
    pub fn play(&mut self, frames: u32) -> bool {
        for _ in 0..frames {
            if self.ended || self.phase != Phase::Playing {
                self.ended = true;
                break;
            }
            match self.racer.readings.next() {
                Some(Ok(r)) => self.phase = self.racer.session.frame_in::<EVENTS>(r),
                Some(Err(e)) => {
                    self.error = Some(e);
                    self.ended = true;
                }
                None => self.ended = true,
            }
        }
        self.ended || self.phase != Phase::Playing
    }

    /// The racer, at its start, once the replay (played to its end here if
    /// it was not) won the level on the ghost's own state hash; or why not.
    /// Again after a good verdict: the same racer, as it is.
    pub(crate) fn verify(&mut self) -> Result<&mut Racer<'a, 'g, EVENTS>, RaceError> {
        if self.verified {
            return Ok(&mut self.racer);
        }
        while !self.play(u32::MAX) {}
        if let Some(e) = self.error {
            return Err(RaceError::Ghost(e));
        }
        let racer = &mut self.racer;
        match (
            self.phase,
            racer.session.state_hash() == racer.ghost.state_hash,
        ) {
            (Phase::Won, true) => {}
            (Phase::Won, false) => return Err(RaceError::Hash),
            _ => return Err(RaceError::NotWon),
        }
        let game = racer.session.game();
        racer.idle = game.frames() - game.clock_frames();
        // A restart keeps the calibration the replay set.
        racer.session.restart();
        racer.readings = racer.ghost.readings();
        self.verified = true;
        Ok(racer)
    }

    /// The racer once `Checking::verify` found the replay good.
    pub fn racer(&self) -> Option<&Racer<'a, 'g, EVENTS>> {
        self.verified.then_some(&self.racer)
    }

    /// [`Checking::racer`], to race it.
    pub fn racer_mut(&mut self) -> Option<&mut Racer<'a, 'g, EVENTS>> {
        self.verified.then_some(&mut self.racer)
    }

    /// `Checking::verify`, the racer moved out.
    pub fn finish(mut self) -> Result<Racer<'a, 'g, EVENTS>, RaceError> {
        self.verify()?;
        Ok(self.racer)
    }
}

impl<'a, 'g, const EVENTS: bool> Racer<'a, 'g, EVENTS> {
    /// The ghost in `bytes` on `level` (game configuration `config`, tilt
    /// path `tilt`), once its whole replay has won the level on its own state
    /// hash (played at once; a board plays it a stretch at a time with
    /// [`Checking`]).
    pub fn new(
        bytes: &'g [u8],
        level: LevelView<'a>,
        config: GameConfig,
        tilt: TiltConfig,
    ) -> Result<Self, RaceError> {
        Checking::<EVENTS>::new(bytes, level, config, tilt)?.finish()
    }

    /// The ghost's time: its frames on the level clock.
    pub fn clock(&self) -> u32 {
        self.ghost.frames - self.idle
    }

    /// The stored ghost's length in bytes.
    pub fn bytes(&self) -> usize {
        super::HEADER_BYTES + self.ghost.tokens.len()
    }

    /// The ghost's run in frames, and its end state hash.
    pub fn run(&self) -> (u32, u64) {
        (self.ghost.frames, self.ghost.state_hash)
    }

    /// Plays the ghost up to where it is beside `live` ([`race_frame`]; from
    /// the start again when `live` started over).
    pub fn follow(&mut self, live: &Game<'_, Fx>) {
        let target = race_frame(self.idle, live).min(self.ghost.frames);
        if target < self.session.game().frames() {
            self.session.restart();
            self.readings = self.ghost.readings();
        }
        while self.session.game().frames() < target {
            match self.readings.next() {
                Some(Ok(r)) => {
                    self.session.frame_in::<EVENTS>(r);
                }
                // Checked whole in `new`: not reached.
                _ => break,
            }
        }
    }

    /// The ghost's game where it is.
    pub fn game(&self) -> &Game<'a, Fx> {
        self.session.game()
    }

    /// Its state hash where it is (at the end of its run: the ghost's own).
    pub fn state_hash(&self) -> u64 {
        self.session.state_hash()
    }
}
