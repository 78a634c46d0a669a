//! A race as a board plays it: its own session, the link, the opponent's
//! replay and the verdict, one [`Race::frame`] per game frame.

use crate::game::level::LevelView;
use crate::game::rules::Phase;
use crate::game::session::Session;
use crate::input::axes::AccelMg;
use crate::physics::world::SetupError;
use crate::physics::Scalar;

use super::packet::{Drop, End, MAX_PACKET};
use super::replay::{
    decide, Opponent, Run, Verdict, CATCH_UP, RACE_CONFIG, RACE_EVENTS, RACE_TILT,
};
use super::session::{Heard, LinkStage, RaceLink};
use super::stream::{EARLY_BLOCKS, INBOX_READINGS, OUT_BLOCKS};

/// Why a race could not start.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RaceError {
    /// The link has no opponent yet.
    NotPaired,
    /// The maze does not set up.
    Setup(SetupError),
}

impl core::fmt::Display for RaceError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            RaceError::NotPaired => f.write_str("no opponent yet"),
            RaceError::Setup(e) => write!(f, "the race's maze cannot be set up: {e:?}"),
        }
    }
}

/// What the screen says about the race.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// This many frames to the start.
    Countdown(u32),
    /// Both run.
    Racing,
    /// This board's run is over; the opponent's is not yet known.
    Waiting,
    /// The verdict.
    Decided(Verdict),
}

/// A race under way on one board, its link of the sizes `O`, `I`, `E`
/// ([`RaceLink`]).
#[derive(Clone, Debug)]
pub struct Race<
    'a,
    S: Scalar,
    const O: usize = OUT_BLOCKS,
    const I: usize = INBOX_READINGS,
    const E: usize = EARLY_BLOCKS,
> {
    link: RaceLink<O, I, E>,
    own: Session<'a, S>,
    opponent: Opponent<'a, S>,
    /// This board's run can no longer reach the opponent whole.
    lost: bool,
}

impl<'a, S: Scalar, const O: usize, const I: usize, const E: usize> Race<'a, S, O, I, E> {
    /// The race on `level`, the maze `link` agreed on (the caller generates
    /// and parses it: `super::maze`).
    pub fn new(link: RaceLink<O, I, E>, level: LevelView<'a>) -> Result<Self, RaceError> {
        if link.paired().is_none() {
            return Err(RaceError::NotPaired);
        }
        let mut own = Session::new(level, RACE_CONFIG, RACE_TILT).map_err(RaceError::Setup)?;
        own.tilt_mut().set_calibration(link.calibration());
        let opponent = Opponent::new(level).map_err(RaceError::Setup)?;
        Ok(Race {
            link,
            own,
            opponent,
            lost: false,
        })
    }

    /// One frame: once the countdown is over and while this board's run goes
    /// on, it plays the reading `reading` gives for its session as it stands
    /// (asked only then: an autopilot is asked once a frame played); then the
    /// opponent's replay catches up with what has arrived (at most
    /// `CATCH_UP` frames).
    pub fn frame(&mut self, reading: impl FnOnce(&Session<'a, S>) -> AccelMg) -> Phase {
        self.link.tick();
        if self.link.stage() == LinkStage::Racing && self.own.game().phase() == Phase::Playing {
            let reading = reading(&self.own);
            let phase = self.own.frame_in::<RACE_EVENTS>(reading);
            if self.link.push_own(reading).is_err() {
                self.lost = true;
            }
            if phase != Phase::Playing {
                let end = End {
                    frames: self.own.game().frames(),
                    hash: self.own.state_hash(),
                };
                if self.link.end_own(end).is_err() {
                    self.lost = true;
                }
            }
        }
        self.opponent.step(&mut self.link, CATCH_UP);
        self.own.game().phase()
    }

    /// A packet from the channel ([`RaceLink::receive`]).
    pub fn receive(&mut self, bytes: &[u8]) -> Result<Heard, Drop> {
        self.link.receive(bytes)
    }

    /// The packet to send now, if any ([`RaceLink::transmit`]).
    pub fn transmit<'b>(&mut self, buf: &'b mut [u8; MAX_PACKET]) -> Option<&'b [u8]> {
        self.link.transmit(buf)
    }

    /// The link.
    pub fn link(&self) -> &RaceLink<O, I, E> {
        &self.link
    }

    /// This board's session.
    pub fn own(&self) -> &Session<'a, S> {
        &self.own
    }

    /// The opponent's replay.
    pub fn opponent(&self) -> &Opponent<'a, S> {
        &self.opponent
    }

    /// This board's run so far.
    pub fn own_run(&self) -> Run {
        let g = self.own.game();
        Run {
            frames: g.frames(),
            phase: g.phase(),
        }
    }

    /// The verdict, once the runs settle it.
    pub fn verdict(&self) -> Option<Verdict> {
        decide(self.own_run(), self.opponent.run())
    }

    /// Nothing left to do: the verdict is known, each board holds the other's
    /// whole run, and the replay has reached the opponent's end (checked:
    /// [`Opponent::verified`]).
    pub fn finished(&self) -> bool {
        self.verdict().is_some() && self.link.complete() && self.opponent.verified().is_some()
    }

    /// This board's run overflowed the outbox (the opponent unheard too
    /// long): the opponent cannot replay it, and will not reach a verdict.
    pub fn lost(&self) -> bool {
        self.lost
    }

    /// What the screen says.
    pub fn status(&self) -> Status {
        if let Some(v) = self.verdict() {
            return Status::Decided(v);
        }
        match self.link.stage() {
            LinkStage::Countdown(n) => Status::Countdown(n),
            _ if self.own.game().phase() != Phase::Playing => Status::Waiting,
            _ => Status::Racing,
        }
    }
}
