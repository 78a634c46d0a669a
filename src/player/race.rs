//! One race as a board plays it, a frame at a time ([`RaceRound`]): the
//! search for an opponent, the maze made in the board's slot, the race on
//! the tilt, the picture, and what the buttons do. The board's race task
//! (`app::race_task`) only moves packets, ticks and frames around it, so
//! host tests drive the same code.

use core::num::NonZeroU32;

use crate::game::endless::{MazeArgs, MazeError, MazeSlot};
use crate::game::rules::Phase;
use crate::game::session::Session;
use crate::input::axes::AccelMg;
use crate::input::event::Command;
use crate::input::sensor::Calibration;
use crate::matrix::Frame;
use crate::physics::Scalar;
use crate::race::packet::Drop;
use crate::race::session::Heard;
use crate::race::{offer, MazeSpec, Race, RaceError, RaceLink, Status, Verdict, MAX_PACKET};
use crate::render::race::{race_frame, searching_frame};
use crate::render::Renderer;

/// Why a round is over: what the buttons asked for next.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RoundExit {
    /// Race again on the same channel and group (**A** once this board's run
    /// is over; or the agreed maze could not be played here).
    Again,
    /// Back to the chooser of channel and group (**B** while looking for an
    /// opponent, or once this board's run is over).
    Choose,
}

/// What happened in a frame, for the board's log and its speaker.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RoundEvent {
    /// Paired with board `peer` on `maze`.
    Paired {
        /// The opponent's id.
        peer: u32,
        /// The agreed maze.
        maze: MazeSpec,
    },
    /// The agreed maze cannot be played on this board (beyond its reach):
    /// the round is over ([`RoundExit::Again`]).
    Refused(MazeError),
    /// The agreed maze does not set up (a bug in the generator).
    Unplayable(RaceError),
    /// The countdown is over: the runs start.
    Go,
    /// The opponent has been silent for 3 s: this board races on alone.
    Silent,
    /// The opponent is heard again.
    Back,
    /// The verdict, the two runs as this board knows them.
    Verdict {
        /// This board's.
        verdict: Verdict,
        /// This board's run: frames and phase.
        own: (u32, Phase),
        /// The opponent's replay: frames and phase.
        opponent: (u32, Phase),
        /// Whether the replay ended on the opponent's state hash.
        verified: Option<bool>,
    },
}

// No heap to box the race in: the link's room becomes the race's (one
// variant at a time is the point).
#[allow(clippy::large_enum_variant)]
enum Stage<'a, S: Scalar, const O: usize, const I: usize, const E: usize> {
    /// Looking for an opponent.
    Search(RaceLink<O, I, E>),
    /// Racing: the link is the race's.
    Race(Race<'a, S, O, I, E>),
    /// Between the two: the maze could not be played.
    Over,
}

/// One race as board `id` (a new id each round), its link of the sizes `O`,
/// `I`, `E` ([`RaceLink`]), its maze made in a slot of `WORDS` and `TEXT`,
/// drawn on a `W`×`H` matrix.
pub struct RaceRound<
    'a,
    S: Scalar,
    const O: usize,
    const I: usize,
    const E: usize,
    const WORDS: usize,
    const TEXT: usize,
    const W: usize,
    const H: usize,
> {
    stage: Stage<'a, S, O, I, E>,
    /// The slot the race's maze is made in, until it is.
    mazes: Option<&'a mut MazeSlot<WORDS, TEXT>>,
    renderer: Renderer<W, H>,
    status: Option<Status>,
    silent: bool,
}

impl<
        'a,
        S: Scalar,
        const O: usize,
        const I: usize,
        const E: usize,
        const WORDS: usize,
        const TEXT: usize,
        const W: usize,
        const H: usize,
    > RaceRound<'a, S, O, I, E, WORDS, TEXT, W, H>
{
    /// Board `id` looking for an opponent, offering its maze
    /// ([`crate::race::offer`]), the race's maze to be made in `mazes`.
    pub fn new(id: NonZeroU32, mazes: &'a mut MazeSlot<WORDS, TEXT>) -> Self {
        RaceRound {
            stage: Stage::Search(RaceLink::sized(id, offer(id), Calibration::NONE)),
            mazes: Some(mazes),
            renderer: Renderer::new(),
            status: None,
            silent: false,
        }
    }

    /// The race, once paired.
    pub fn race(&self) -> Option<&Race<'a, S, O, I, E>> {
        match &self.stage {
            Stage::Race(race) => Some(race),
            _ => None,
        }
    }

    /// The link, while looking or racing.
    pub fn link(&self) -> Option<&RaceLink<O, I, E>> {
        match &self.stage {
            Stage::Search(link) => Some(link),
            Stage::Race(race) => Some(race.link()),
            Stage::Over => None,
        }
    }

    /// A packet from the air ([`RaceLink::receive`]).
    pub fn receive(&mut self, bytes: &[u8]) -> Result<Heard, Drop> {
        match &mut self.stage {
            Stage::Search(link) => link.receive(bytes),
            Stage::Race(race) => race.receive(bytes),
            Stage::Over => Err(Drop::NotOurs),
        }
    }

    /// The packet to send now, if any ([`RaceLink::transmit`]).
    pub fn transmit<'b>(&mut self, buf: &'b mut [u8; MAX_PACKET]) -> Option<&'b [u8]> {
        match &mut self.stage {
            Stage::Search(link) => link.transmit(buf),
            Stage::Race(race) => race.transmit(buf),
            Stage::Over => None,
        }
    }

    /// One frame, the buttons' `command` since the last (if any): while
    /// looking, **B** ends the round for the chooser; once this board's run
    /// is over, **A** ends it to race again and **B** for the chooser; else
    /// the buttons do nothing (a board that left would leave its opponent
    /// alone). `reading` gives this board's tilt for its session as it
    /// stands (asked only while its run goes on). `Err` when the round is
    /// over; else what happened, if anything worth a log line.
    pub fn frame(
        &mut self,
        command: Option<Command>,
        reading: impl FnOnce(&Session<'a, S>) -> AccelMg,
    ) -> Result<Option<RoundEvent>, RoundExit> {
        let race = match &mut self.stage {
            Stage::Search(link) => {
                if command == Some(Command::NextLevel) {
                    return Err(RoundExit::Choose);
                }
                link.tick();
                return Ok(self.pair());
            }
            Stage::Race(race) => race,
            Stage::Over => return Err(RoundExit::Again),
        };
        if race.own().game().phase() != Phase::Playing {
            match command {
                Some(Command::Restart) => return Err(RoundExit::Again),
                Some(Command::NextLevel) => return Err(RoundExit::Choose),
                _ => {}
            }
        }
        race.frame(reading);
        let status = race.status();
        let before = self.status.replace(status);
        let silent = race.link().silent();
        let event = match (before, status) {
            (Some(Status::Countdown(_)), Status::Racing) => Some(RoundEvent::Go),
            (Some(b), Status::Decided(verdict)) if b != status => {
                let (own, opp) = (race.own_run(), race.opponent().run());
                Some(RoundEvent::Verdict {
                    verdict,
                    own: (own.frames, own.phase),
                    opponent: (opp.frames, opp.phase),
                    verified: race.opponent().verified(),
                })
            }
            _ if silent != self.silent => Some(if silent {
                RoundEvent::Silent
            } else {
                RoundEvent::Back
            }),
            _ => None,
        };
        if !matches!(event, Some(RoundEvent::Go | RoundEvent::Verdict { .. })) {
            self.silent = silent;
        }
        Ok(event)
    }

    /// Once the link is paired: the maze made, the race started.
    fn pair(&mut self) -> Option<RoundEvent> {
        let Stage::Search(link) = &self.stage else {
            return None;
        };
        let (peer, maze) = link.paired()?;
        let Stage::Search(link) = core::mem::replace(&mut self.stage, Stage::Over) else {
            return None;
        };
        let mazes = self.mazes.take()?;
        let args = MazeArgs {
            seed: maze.seed,
            size: maze.size,
            storeys: maze.storeys,
            difficulty: maze.difficulty,
        };
        let level = match mazes.make(args) {
            Ok(level) => level,
            Err(e) => return Some(RoundEvent::Refused(e)),
        };
        match Race::new(link, level) {
            Ok(race) => {
                self.status = Some(race.status());
                self.stage = Stage::Race(race);
                Some(RoundEvent::Paired { peer, maze })
            }
            Err(e) => Some(RoundEvent::Unplayable(e)),
        }
    }

    /// The picture: a dot running round while looking, then the race
    /// ([`race_frame`]).
    pub fn picture(&mut self) -> Frame<W, H> {
        match &self.stage {
            Stage::Search(link) => searching_frame(link.now()),
            Stage::Race(race) => race_frame(&mut self.renderer, race),
            Stage::Over => Frame::new(),
        }
    }
}
