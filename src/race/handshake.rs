//! Two boards finding each other on a shared channel.
//!
//! A board looking for an opponent says hello a few times a second, with its
//! id and the maze it offers. Proposals go one way only, from the lower id to
//! the higher: a board that hears the hello of a higher id proposes to it
//! (race packets addressed to it, carrying its own offer); a board that hears
//! a proposal while looking accepts it. Each is paired once it hears a race
//! packet addressed to itself from the other: the proposer hears the answer,
//! the acceptor the proposal. So pairing is mutual, a board never proposes to
//! two boards at once, and since proposals climb the ids a third board on the
//! channel cannot close a ring of proposals that waits forever: the highest id
//! only ever accepts. A proposal unanswered for `PROPOSE_FRAMES`, or whose
//! board is seen racing another, is dropped and the board looks again.
//!
//! The race's maze is the proposer's offer: both agree on it because the
//! acceptor takes it from the proposal.

use super::packet::MazeSpec;

/// How long a proposal waits for an answer: 2 s of frames.
pub(crate) const PROPOSE_FRAMES: u32 = 256;

/// Where the handshake stands.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Stage {
    /// Saying hello, waiting for a proposal or a higher id's hello.
    Searching,
    /// Proposed to `peer` at frame `since`, waiting for its answer.
    Proposed {
        /// The board proposed to.
        peer: u32,
        /// When.
        since: u32,
    },
    /// Racing `peer` on `maze` (paired at frame `at`).
    Paired {
        /// The opponent.
        peer: u32,
        /// The race's maze.
        maze: MazeSpec,
        /// The local frame of the pairing.
        at: u32,
    },
}

/// One board's side of the handshake.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Handshake {
    me: u32,
    offer: MazeSpec,
    stage: Stage,
}

impl Handshake {
    /// Board `me` (not 0) offering `offer`.
    pub(crate) const fn new(me: u32, offer: MazeSpec) -> Self {
        Handshake {
            me,
            offer,
            stage: Stage::Searching,
        }
    }

    /// This board's id.
    pub(crate) fn me(&self) -> u32 {
        self.me
    }

    /// The maze this board offers.
    pub(crate) fn offer(&self) -> MazeSpec {
        self.offer
    }

    /// Where the handshake stands.
    pub(crate) fn stage(&self) -> Stage {
        self.stage
    }

    /// Who race packets go to, and on which maze: the board proposed to or
    /// paired with.
    pub(crate) fn addressee(&self) -> Option<(u32, MazeSpec)> {
        match self.stage {
            Stage::Searching => None,
            Stage::Proposed { peer, .. } => Some((peer, self.offer)),
            Stage::Paired { peer, maze, .. } => Some((peer, maze)),
        }
    }

    /// A hello from `from` heard at frame `now`.
    pub(crate) fn hello(&mut self, from: u32, now: u32) {
        if self.stage == Stage::Searching && from > self.me {
            self.stage = Stage::Proposed {
                peer: from,
                since: now,
            };
        }
    }

    /// A race packet from `from` to `to` on `maze`, at frame `now`: whether it
    /// belongs to this board's race (pairing with its sender if need be).
    pub(crate) fn race(&mut self, from: u32, to: u32, maze: MazeSpec, now: u32) -> bool {
        if to != self.me {
            if matches!(self.stage, Stage::Proposed { peer, .. } if peer == from) {
                // The board proposed to races another: look again.
                self.stage = Stage::Searching;
            }
            return false;
        }
        match self.stage {
            Stage::Searching if from < self.me => {
                self.stage = Stage::Paired {
                    peer: from,
                    maze,
                    at: now,
                };
                true
            }
            Stage::Searching => false,
            Stage::Proposed { peer, .. } if peer == from && maze == self.offer => {
                self.stage = Stage::Paired {
                    peer,
                    maze,
                    at: now,
                };
                true
            }
            Stage::Proposed { .. } => false,
            Stage::Paired { peer, maze: m, .. } => peer == from && maze == m,
        }
    }

    /// Frame `now` passes: an unanswered proposal expires.
    pub(crate) fn tick(&mut self, now: u32) {
        if let Stage::Proposed { since, .. } = self.stage {
            if now.wrapping_sub(since) >= PROPOSE_FRAMES {
                self.stage = Stage::Searching;
            }
        }
    }
}
