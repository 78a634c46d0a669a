//! The ghost's state in the page: its buffers, every attempt written as a
//! ghost while it plays (`Recorder`), and the best run of the level replayed
//! beside the next attempt (`GhostRun`), racing from the player's first tilt
//! (`ghost::race_frame`). The page's calls on it are [`crate::ghost`]'s.

use core::cell::UnsafeCell;

use marble_rolling::game::ghost::{race_frame, Ghost, GhostWriter, Readings};
use marble_rolling::game::rules::{Game, Phase};
use marble_rolling::game::session::Session;
use marble_rolling::physics::Fx;

use crate::Single;

/// Bytes of a ghost (its format: `marble_rolling::game::ghost`). The
/// autopilot's runs take 188 to 279 B per second, a run with a sensor's noise
/// 489 (docs/ghost.md): 64 KiB keep about four minutes, or two of the noisy
/// run, longer than any built-in level's limit; a longer run leaves no ghost.
pub(crate) const GHOST_CAPACITY: usize = 64 * 1024;

/// Where the page writes a stored ghost for [`load_ghost`].
pub(crate) static GHOST_IN: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The ghost on show, copied from [`GHOST_IN`]: its replay reads it frame by
/// frame (see [`GhostRun`]).
pub(crate) static GHOST: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The attempt in play, written as a ghost while it is played (see [`Recorder`]).
pub(crate) static RECORD: Single<UnsafeCell<[u8; GHOST_CAPACITY]>> =
    Single(UnsafeCell::new([0; GHOST_CAPACITY]));

/// The attempt in play, written as a ghost frame by frame into [`RECORD`]: a
/// win is then a ghost already, without a copy of its readings.
pub(crate) struct Recorder {
    pub(crate) writer: Option<GhostWriter<'static>>,
    /// Frames of the attempt seen so far.
    pub(crate) frames: u32,
    /// The writer has every reading of the attempt from its first frame.
    pub(crate) whole: bool,
}

impl Recorder {
    pub(crate) fn new() -> Self {
        Recorder {
            writer: None,
            frames: 0,
            whole: false,
        }
    }

    /// Starts over, for an attempt at its first frame.
    pub(crate) fn start(&mut self) {
        // The old writer goes first: it holds the only reference into RECORD.
        self.writer = None;
        // SAFETY: single thread (see `Single`). The writer just dropped was
        // the only reference into RECORD (a finished ghost is handed out as a
        // length, its slice dropped at once), so this one is alone.
        let buf: &'static mut [u8; GHOST_CAPACITY] = unsafe { &mut *RECORD.0.get() };
        self.writer = GhostWriter::new(buf).ok();
        self.frames = 0;
        self.whole = self.writer.is_some();
    }

    /// After a frame, a restart or a new level: keeps the frame's reading.
    pub(crate) fn observe(&mut self, session: &Session<'static, Fx>) {
        let frames = session.game().frames();
        if frames == 0 {
            if self.frames != 0 || self.writer.is_none() {
                self.start();
            }
            return;
        }
        if frames == self.frames {
            // A finished attempt on show: no frame played.
            return;
        }
        let pushed = frames == self.frames + 1
            && self
                .writer
                .as_mut()
                .is_some_and(|w| w.push(session.reading()).is_ok());
        // A frame missed, or no room left: this attempt leaves no ghost.
        self.whole &= pushed;
        self.frames = frames;
    }

    /// The ghost of the attempt that just ended (a win) in [`RECORD`]: its
    /// length, or 0 if the attempt was not kept whole.
    pub(crate) fn finish(&mut self, session: &Session<'static, Fx>) -> u32 {
        let Some(writer) = self.writer.take() else {
            return 0;
        };
        if !self.whole || writer.frames() != session.game().frames() {
            return 0;
        }
        writer
            .finish(session.state_hash(), session.tilt().calibration())
            .map_or(0, |bytes| bytes.len() as u32)
    }
}

/// A stored ghost played beside the live game, one frame per live frame.
pub(crate) struct GhostRun {
    pub(crate) session: Session<'static, Fx>,
    pub(crate) ghost: Ghost<'static>,
    pub(crate) readings: Readings<'static>,
    /// Its time on the level clock, frames (measured by the replay that
    /// checked it).
    pub(crate) clock: u32,
    /// Its frames before its clock started: it plays them at once and waits
    /// there for the player's first tilt ([`race_frame`]).
    pub(crate) idle: u32,
}

impl GhostRun {
    /// Plays the ghost as far as it goes beside the live attempt `live`
    /// ([`race_frame`]: from the player's first tilt), from its start again if
    /// the live game started over, or to its end.
    pub(crate) fn follow(&mut self, live: &Game<'static, Fx>) {
        let frames = race_frame(self.idle, live);
        if frames < self.session.game().frames() {
            // A restart keeps the calibration, the ghost's.
            self.session.restart();
            self.readings = self.ghost.readings();
        }
        while self.session.game().frames() < frames && self.session.game().phase() == Phase::Playing
        {
            match self.readings.next() {
                Some(Ok(reading)) => {
                    self.session.frame(reading);
                }
                // Checked when loaded: the readings neither end early nor break.
                _ => break,
            }
        }
    }
}
