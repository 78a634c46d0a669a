//! The opponent's marble, replayed from its readings, and who won.
//!
//! The physics is bit-exact on every board and a run is fully described by its
//! readings (`crate::game::ghost`), so the readings the opponent sends,
//! played into a fresh session of the same maze with its calibration, are its
//! run itself: the replay's frames and outcome are the opponent's, and its end
//! is checked against the state hash the opponent reports. Neither board's
//! clock is trusted or compared: the winner is the fewer frames to the goal,
//! decided by [`decide`] from the two runs alone, so both boards reach the same
//! verdict whenever each knows enough to reach one.

use crate::game::level::LevelView;
use crate::game::rules::{GameConfig, Phase};
use crate::game::session::{Session, SYNTHETIC_TILT};
use crate::input::tilt::TiltConfig;
use crate::physics::world::{SetupError, Stepping};
use crate::physics::Scalar;

use super::session::RaceLink;

/// The game's configuration in a race: both boards play with it (event
/// stepping, the firmware's default).
pub const RACE_CONFIG: GameConfig = GameConfig::EVENTS;
/// [`RACE_CONFIG`]'s stepper, fixed at compile time: a board links only the
/// stepper it races with (the other is about 18 KiB of flash on the v2).
pub(crate) const RACE_EVENTS: bool = matches!(RACE_CONFIG.stepping, Stepping::Events);
/// The tilt path's settings in a race, the same on both boards: the replay
/// must filter the readings as their board did. The stuck-sensor check is off
/// (keys repeat a reading, a sensor's supervision is the input layer's).
pub const RACE_TILT: TiltConfig = SYNTHETIC_TILT;
/// The most opponent frames replayed per frame of this board: a replay behind
/// by a second of lost packets catches up in a sixth of a second, and a frame
/// never costs more than eight of the opponent's.
pub(crate) const CATCH_UP: u32 = 8;

/// A run as far as a board knows it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Run {
    /// Frames played.
    pub frames: u32,
    /// The phase after them (`Playing`: the run goes on).
    pub phase: Phase,
}

/// The race's result, for one side.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Verdict {
    /// This side reached the goal in fewer frames, or alone.
    Won,
    /// The other did.
    Lost,
    /// The same frames, or neither reached the goal.
    Draw,
}

impl Verdict {
    /// The other side's verdict.
    pub fn mirrored(self) -> Verdict {
        match self {
            Verdict::Won => Verdict::Lost,
            Verdict::Lost => Verdict::Won,
            Verdict::Draw => Verdict::Draw,
        }
    }
}

/// The verdict for `me` against `them`, once the runs known so far settle it:
/// a function of the two whole runs (fewer frames to the goal wins), decided
/// early only when no frame still to come can change it. `decide(a, b)` is
/// `decide(b, a)` mirrored.
pub fn decide(me: Run, them: Run) -> Option<Verdict> {
    let won = |r: Run| (r.phase == Phase::Won).then_some(r.frames);
    // A run still playing after `frames` can only win in more.
    let beaten = |r: Run, by: u32| r.phase != Phase::Playing || r.frames >= by;
    match (won(me), won(them)) {
        (Some(a), Some(b)) => Some(match a.cmp(&b) {
            core::cmp::Ordering::Less => Verdict::Won,
            core::cmp::Ordering::Greater => Verdict::Lost,
            core::cmp::Ordering::Equal => Verdict::Draw,
        }),
        (Some(a), None) => beaten(them, a).then_some(Verdict::Won),
        (None, Some(b)) => beaten(me, b).then_some(Verdict::Lost),
        (None, None) => {
            (me.phase != Phase::Playing && them.phase != Phase::Playing).then_some(Verdict::Draw)
        }
    }
}

/// The opponent's run, replayed from the readings the link took.
#[derive(Clone, Debug)]
pub struct Opponent<'a, S: Scalar> {
    session: Session<'a, S>,
    calibrated: bool,
    verified: Option<bool>,
}

impl<'a, S: Scalar> Opponent<'a, S> {
    /// A fresh replay of `level` (the race's maze).
    pub(crate) fn new(level: LevelView<'a>) -> Result<Self, SetupError> {
        Ok(Opponent {
            session: Session::new(level, RACE_CONFIG, RACE_TILT)?,
            calibrated: false,
            verified: None,
        })
    }

    /// The replay's session.
    pub fn session(&self) -> &Session<'a, S> {
        &self.session
    }

    /// The run replayed so far.
    pub fn run(&self) -> Run {
        let g = self.session.game();
        Run {
            frames: g.frames(),
            phase: g.phase(),
        }
    }

    /// Once the opponent's end is replayed: whether the replay ended there, on
    /// the opponent's own state hash.
    pub fn verified(&self) -> Option<bool> {
        self.verified
    }

    /// Plays up to `max` of the readings `link` holds; returns how many.
    pub(crate) fn step<const O: usize, const I: usize, const E: usize>(
        &mut self,
        link: &mut RaceLink<O, I, E>,
        max: u32,
    ) -> u32 {
        let mut n = 0;
        if !self.calibrated {
            // The calibration comes with every race packet, before any reading.
            let Some(c) = link.peer_calibration() else {
                return 0;
            };
            self.session.tilt_mut().set_calibration(c);
            self.calibrated = true;
        }
        while n < max && self.session.game().phase() == Phase::Playing {
            let Some(r) = link.pop_opponent() else {
                break;
            };
            self.session.frame_in::<RACE_EVENTS>(r);
            n += 1;
        }
        if self.verified.is_none() {
            if let Some(end) = link.inbox().end() {
                let run = self.run();
                if run.phase != Phase::Playing || run.frames >= end.frames {
                    self.verified = Some(
                        run.phase != Phase::Playing
                            && run.frames == end.frames
                            && self.session.state_hash() == end.hash,
                    );
                }
            }
        }
        n
    }
}
