//! The ghost: a whole run kept as its tilt readings, one per frame, and replayed
//! bit-exactly.
//!
//! The physics is deterministic on every board, so a run is fully described by
//! the readings that went into [`Session::frame`]: played again into a fresh
//! session of the same level and configuration they give the same frames and end
//! with the same state hash — the ghost marble racing the player is that replay,
//! stepped beside the live game.
//!
//! # Format (version 1)
//!
//! ```text
//! 0  "MG" 1 0        magic, version, reserved
//! 4  frames          u32 LE: readings in the run
//! 8  state_hash      u64 LE: Session::state_hash at the run's end
//! 16 offset_x        i32 LE: the tilt path's calibration during the run (mg)
//! 20 offset_z        i32 LE
//! 24 tokens          LEB128 varints, until the end
//! ```
//!
//! Each token starts with a varint `h`. Even `h` is a **run**: the last reading
//! again for `h / 2` frames. Odd `h` is **one frame** whose axes `x, y, z` (bits
//! 0, 1, 2 of `h >> 1`) that changed follow as zigzag varints of the change. The
//! reading before the first frame is a flat board `(0, 1000, 0)` mg.
//!
//! The calibration is part of the run (the tilt path subtracts it from every
//! reading; a restart keeps it), so the replay sets it first. A calibration
//! changed in the middle of a run is not recorded: that run's replay misses its
//! hash, which [`replay`] reports.
//!
//! # Why this coding
//!
//! * **No quantisation**: the replay has to end on the record's hash, and any
//!   reading rounded differently is a different run.
//! * **Deltas**: a hand (or the autopilot, at most 10 mg a frame) tilts smoothly,
//!   so a frame's change is a one-byte varint per axis that moved.
//! * **Run lengths**: keys and the autopilot hold a tilt for many frames (a held
//!   key repeats the same reading), and a run of any length costs a varint.
//!
//! # Racing from the first tilt
//!
//! A ghost races the player on the level clock (`rules`), which starts at the
//! first tilt that rolls a marble: the ghost's own frames before its clock
//! started (its looking at the maze) are played at once and it waits there,
//! at its start, until the player's clock starts; then one ghost frame per
//! frame on the player's clock ([`race_frame`]). A ghost that followed the
//! frames since the level loaded would be at the goal before a player who
//! looked for two seconds had touched anything.
//!
//! The autopilot's runs of the built-in levels take 188 to 279 bytes per second
//! of run (header included), against 768 for three `i16` a frame; with a
//! sensor's noise (±4 mg on every axis, every frame) `corner` takes 489 (`cargo test --features tools
//! --test ghost -- --nocapture` prints them).

use crate::input::axes::AccelMg;
use crate::input::sensor::Calibration;
use crate::physics::Fx;

use super::session::Session;

mod race;
pub use race::{race_frame, replay, Checking, RaceError, Racer};

/// Bytes before the tokens.
pub const HEADER_BYTES: usize = 24;
const MAGIC: [u8; 4] = [b'M', b'G', 1, 0];
/// The reading before the first frame.
const FLAT: AccelMg = AccelMg::LEVEL;

/// What is wrong with a ghost, or with writing one.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum GhostError {
    /// The buffer has no room for the next frame.
    Full,
    /// Not a ghost of this version (the first four bytes).
    BadHeader,
    /// The tokens end inside a token, or hold fewer or more frames than the
    /// header says; `at` is the byte offset.
    Truncated {
        /// Byte offset where the ghost stopped making sense.
        at: usize,
    },
    /// A reading beyond ±2³¹ mg: not a reading.
    Overflow {
        /// Byte offset of the token.
        at: usize,
    },
}

impl core::fmt::Display for GhostError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            GhostError::Full => f.write_str("no room left for the ghost's next frame"),
            GhostError::BadHeader => f.write_str("not a ghost (version 1): bad header"),
            GhostError::Truncated { at } => {
                write!(f, "ghost cut short or miscounted at byte {at}")
            }
            GhostError::Overflow { at } => {
                write!(f, "ghost reading out of range at byte {at}")
            }
        }
    }
}

/// Writes a run's readings into a caller's buffer (no allocation).
#[derive(Debug)]
pub struct GhostWriter<'a> {
    tokens: TokenWriter<'a>,
}

impl<'a> GhostWriter<'a> {
    /// A writer into `buf` (at least [`HEADER_BYTES`]).
    pub fn new(buf: &'a mut [u8]) -> Result<Self, GhostError> {
        if buf.len() < HEADER_BYTES {
            return Err(GhostError::Full);
        }
        buf[..HEADER_BYTES].fill(0);
        buf[..4].copy_from_slice(&MAGIC);
        let mut tokens = TokenWriter::new(buf, FLAT);
        tokens.len = HEADER_BYTES;
        Ok(GhostWriter { tokens })
    }

    /// Forgets every frame: the writer starts a new ghost in its buffer.
    pub fn restart(&mut self) {
        let t = &mut self.tokens;
        t.len = HEADER_BYTES;
        t.frames = 0;
        t.last = FLAT;
        t.run = 0;
    }

    /// Frames written so far.
    pub fn frames(&self) -> u32 {
        self.tokens.frames
    }

    /// Adds one frame's reading. On [`GhostError::Full`] the ghost so far stays
    /// whole (finish it, or drop it).
    pub fn push(&mut self, reading: AccelMg) -> Result<(), GhostError> {
        self.tokens.push(reading)
    }

    /// Closes the ghost with the run's end state hash and the tilt path's
    /// calibration during the run; returns its bytes.
    pub fn finish(
        mut self,
        state_hash: u64,
        calibration: Calibration,
    ) -> Result<&'a [u8], GhostError> {
        let t = &mut self.tokens;
        t.flush_run()?;
        t.buf[4..8].copy_from_slice(&t.frames.to_le_bytes());
        t.buf[8..16].copy_from_slice(&state_hash.to_le_bytes());
        t.buf[16..20].copy_from_slice(&calibration.offset_x.to_le_bytes());
        t.buf[20..24].copy_from_slice(&calibration.offset_z.to_le_bytes());
        let len = t.len;
        Ok(&self.tokens.buf[..len])
    }
}

/// The ghost's tokens alone, without its header, from any reading before the
/// first: the coding other formats reuse (the race's blocks of readings,
/// `crate::race`). [`Readings::from_tokens`] reads them back.
#[derive(Debug)]
pub struct TokenWriter<'a> {
    buf: &'a mut [u8],
    len: usize,
    frames: u32,
    last: AccelMg,
    /// Frames repeating `last`, not written yet.
    run: u32,
}

impl<'a> TokenWriter<'a> {
    /// A writer into `buf`; `before` is the reading before the first frame.
    pub fn new(buf: &'a mut [u8], before: AccelMg) -> Self {
        TokenWriter {
            buf,
            len: 0,
            frames: 0,
            last: before,
            run: 0,
        }
    }

    /// Frames written so far.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Bytes written so far; a pending run of repeated readings adds its
    /// token (a varint of twice its frames) when the writer finishes.
    pub(crate) fn len(&self) -> usize {
        self.len
    }

    /// Adds one frame's reading. On [`GhostError::Full`] the tokens so far stay
    /// whole.
    pub fn push(&mut self, reading: AccelMg) -> Result<(), GhostError> {
        if reading == self.last {
            self.run += 1;
            self.frames += 1;
            return Ok(());
        }
        // The pending run and this frame go in together or not at all.
        let (mark, run) = (self.len, self.run);
        let result = self.flush_run().and_then(|()| {
            // The file's coding, axis by axis.
            let (reading, last) = (reading.to_array(), self.last.to_array());
            let changed = |a: usize| reading[a] != last[a];
            let mask = (0..3).filter(|&a| changed(a)).fold(0u32, |m, a| m | 1 << a);
            self.varint(u64::from(mask << 1 | 1))?;
            for (a, (&now, &was)) in reading.iter().zip(&last).enumerate() {
                if changed(a) {
                    self.varint(zigzag(i64::from(now) - i64::from(was)))?;
                }
            }
            Ok(())
        });
        if result.is_err() {
            self.len = mark;
            self.run = run;
            return result;
        }
        self.run = 0;
        self.last = reading;
        self.frames += 1;
        Ok(())
    }

    /// Writes the pending run; returns the tokens.
    pub fn finish(mut self) -> Result<&'a [u8], GhostError> {
        self.flush_run()?;
        let len = self.len;
        Ok(&self.buf[..len])
    }

    fn flush_run(&mut self) -> Result<(), GhostError> {
        if self.run > 0 {
            self.varint(u64::from(self.run) << 1)?;
        }
        self.run = 0;
        Ok(())
    }

    fn varint(&mut self, mut v: u64) -> Result<(), GhostError> {
        loop {
            let Some(slot) = self.buf.get_mut(self.len) else {
                return Err(GhostError::Full);
            };
            let byte = (v & 0x7f) as u8;
            v >>= 7;
            *slot = if v == 0 { byte } else { byte | 0x80 };
            self.len += 1;
            if v == 0 {
                return Ok(());
            }
        }
    }
}

fn zigzag(d: i64) -> u64 {
    ((d << 1) ^ (d >> 63)) as u64
}

fn unzigzag(u: u64) -> i64 {
    (u >> 1) as i64 ^ -((u & 1) as i64)
}

/// A ghost read from its bytes: the header, and the readings one frame at a
/// time ([`Ghost::readings`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ghost<'a> {
    /// Readings in the run.
    pub frames: u32,
    /// The state hash at the run's end.
    pub state_hash: u64,
    /// The tilt path's calibration during the run.
    pub calibration: Calibration,
    tokens: &'a [u8],
}

impl<'a> Ghost<'a> {
    /// Reads the header and checks that the tokens hold exactly `frames` readings.
    pub fn parse(bytes: &'a [u8]) -> Result<Self, GhostError> {
        if bytes.len() < HEADER_BYTES || bytes[..4] != MAGIC {
            return Err(GhostError::BadHeader);
        }
        let word = |r: core::ops::Range<usize>| {
            let mut b = [0u8; 8];
            b[..r.len()].copy_from_slice(&bytes[r]);
            u64::from_le_bytes(b)
        };
        let ghost = Ghost {
            frames: word(4..8) as u32,
            state_hash: word(8..16),
            calibration: Calibration {
                offset_x: word(16..20) as u32 as i32,
                offset_z: word(20..24) as u32 as i32,
            },
            tokens: &bytes[HEADER_BYTES..],
        };
        let mut n: u32 = 0;
        let mut it = ghost.readings();
        while let Some(r) = it.next() {
            r?;
            n += 1;
            if n > ghost.frames {
                return Err(GhostError::Truncated { at: it.at() });
            }
        }
        if n != ghost.frames {
            return Err(GhostError::Truncated { at: bytes.len() });
        }
        Ok(ghost)
    }

    /// The readings, frame by frame.
    pub fn readings(&self) -> Readings<'a> {
        Readings::from_tokens(self.tokens, FLAT)
    }
}

/// The readings of a [`Ghost`], one per frame.
#[derive(Clone, Debug)]
pub struct Readings<'a> {
    tokens: &'a [u8],
    pos: usize,
    last: AccelMg,
    run: u64,
}

impl<'a> Readings<'a> {
    /// The readings coded by bare `tokens` (a [`TokenWriter`]'s), `before`
    /// being the reading before the first. Error offsets count as in a ghost,
    /// from the start of its header.
    pub fn from_tokens(tokens: &'a [u8], before: AccelMg) -> Self {
        Readings {
            tokens,
            pos: 0,
            last: before,
            run: 0,
        }
    }
}

impl Readings<'_> {
    /// Byte offset in the ghost (header included).
    fn at(&self) -> usize {
        HEADER_BYTES + self.pos
    }

    fn varint(&mut self) -> Result<u64, GhostError> {
        let mut v: u64 = 0;
        for shift in (0..64).step_by(7) {
            let Some(&b) = self.tokens.get(self.pos) else {
                return Err(GhostError::Truncated { at: self.at() });
            };
            self.pos += 1;
            v |= u64::from(b & 0x7f) << shift;
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err(GhostError::Overflow { at: self.at() })
    }
}

impl Iterator for Readings<'_> {
    type Item = Result<AccelMg, GhostError>;

    fn next(&mut self) -> Option<Self::Item> {
        if self.run > 0 {
            self.run -= 1;
            return Some(Ok(self.last));
        }
        if self.pos >= self.tokens.len() {
            return None;
        }
        let start = self.at();
        let step = (|| {
            let h = self.varint()?;
            if h & 1 == 0 {
                if h == 0 {
                    return Err(GhostError::Truncated { at: start });
                }
                self.run = (h >> 1) - 1;
                return Ok(self.last);
            }
            let mask = h >> 1;
            if mask == 0 || mask > 7 {
                return Err(GhostError::Truncated { at: start });
            }
            let mut next = self.last.to_array();
            for (a, value) in next.iter_mut().enumerate() {
                if mask & (1 << a) != 0 {
                    let d = unzigzag(self.varint()?);
                    *value = i32::try_from(i64::from(*value) + d)
                        .map_err(|_| GhostError::Overflow { at: start })?;
                }
            }
            let next = AccelMg::from_array(next);
            self.last = next;
            Ok(next)
        })();
        if step.is_err() {
            // Stop after an error.
            self.pos = self.tokens.len();
            self.run = 0;
        }
        Some(step)
    }
}

/// A board's recording of the live attempts at one level into a buffer: the
/// current attempt's readings from its first frame ([`Recorder::observe`]
/// after every frame), started over on a restart, the buffer's size the
/// longest run it keeps.
#[derive(Debug)]
pub struct Recorder<'r> {
    writer: GhostWriter<'r>,
    /// Why the attempt cannot be a ghost: frames missed, or a full buffer.
    lost: Option<RecordError>,
}

/// Why a won attempt gives no ghost.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RecordError {
    /// The run outgrew the buffer of `bytes` bytes.
    TooLong {
        /// The buffer's size.
        bytes: usize,
    },
    /// Frames of the attempt were not seen (the recording started late).
    Missed,
}

impl<'r> Recorder<'r> {
    /// A recorder into `buf` (at least [`HEADER_BYTES`]).
    pub fn new(buf: &'r mut [u8]) -> Result<Self, GhostError> {
        Ok(Recorder {
            writer: GhostWriter::new(buf)?,
            lost: None,
        })
    }

    /// Takes the frame `session` has just played, if it played one: a new
    /// attempt (fewer frames than recorded) starts the recording over.
    pub fn observe(&mut self, session: &Session<'_, Fx>) {
        let frames = session.game().frames();
        if frames < self.writer.frames() {
            self.writer.restart();
            self.lost = None;
        }
        let recorded = self.writer.frames();
        if frames == recorded || self.lost.is_some() {
            return;
        }
        if frames != recorded + 1 {
            self.lost = Some(RecordError::Missed);
        } else if self.writer.push(session.reading()).is_err() {
            self.lost = Some(RecordError::TooLong {
                bytes: self.writer.tokens.buf.len(),
            });
        }
    }

    /// The attempt `session` ended as a ghost (its end state hash and the
    /// tilt path's calibration in the header).
    pub fn finish(self, session: &Session<'_, Fx>) -> Result<&'r [u8], RecordError> {
        let bytes = self.writer.tokens.buf.len();
        if let Some(lost) = self.lost {
            return Err(lost);
        }
        if self.writer.frames() != session.game().frames() {
            return Err(RecordError::Missed);
        }
        self.writer
            .finish(session.state_hash(), session.tilt().calibration())
            .map_err(|_| RecordError::TooLong { bytes })
    }
}
