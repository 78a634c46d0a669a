//! The readings' streams: this board's run cut into blocks kept until the
//! opponent acknowledges them ([`Outbox`]), and the opponent's readings taken
//! in order for its replay ([`Inbox`]).
//!
//! A block is up to `BLOCK_FRAMES` readings in the ghost's coding
//! ([`crate::game::ghost::TokenWriter`]), from the reading before its first
//! frame, so the receiver, which holds exactly that reading when the block is
//! the next it needs, decodes it with nothing else. Blocks are cut once and
//! never re-cut: a repeated block is the same bytes, and the receiver takes a
//! block only when it starts where its readings end. Every packet carries the
//! unacknowledged blocks in turn, from where the last packet stopped (a
//! carousel), so a lost packet costs the time until its blocks come round
//! again, never a wrong reading; a late or repeated one is simply not the next
//! block and is left.

use heapless::{Deque, Vec};

use super::packet::{End, Writer, BLOCK_BYTES};
use crate::game::ghost::{Readings, TokenWriter};
use crate::input::axes::AccelMg;

/// The most readings in a block: a block waits at most this many frames
/// (1/8 s) before it can be sent.
pub(crate) const BLOCK_FRAMES: usize = 16;
/// Blocks kept for the opponent to acknowledge: 128 blocks, about 12 s of the
/// autopilot's play (`tests/race.rs` prints 563 frames in 48 blocks), 16 s if
/// the tilt rests (16 frames a block). 4.5 KiB.
pub const OUT_BLOCKS: usize = 128;
/// Blocks received after a gap, kept until the blocks before them arrive.
pub const EARLY_BLOCKS: usize = 16;
/// The opponent's readings taken and not yet replayed: 2 s at 128 frames/s,
/// 3 KiB.
pub const INBOX_READINGS: usize = 256;
/// [`OUT_BLOCKS`] on a board with less RAM to give (the micro:bit v2, whose
/// static RAM budget is 16 KiB): 48 blocks, about 4.5 s of the autopilot's
/// play, 6 s if the tilt rests, longer than the 3 s of silence after which
/// a board says it is alone. 1.7 KiB.
pub const LEAN_OUT_BLOCKS: usize = 48;
/// [`INBOX_READINGS`] on such a board: 96 readings, 0.75 s, 1.1 KiB; a burst
/// of blocks after a silence is taken over more turns.
pub const LEAN_INBOX_READINGS: usize = 96;
/// [`EARLY_BLOCKS`] on such a board.
pub const LEAN_EARLY_BLOCKS: usize = 8;
/// The reading before a run's first frame: a flat board (the ghost's).
pub(crate) const FLAT: AccelMg = AccelMg::LEVEL;

/// A block of this board's run.
#[derive(Clone, Debug)]
struct Block {
    first: u32,
    frames: u8,
    len: u8,
    tokens: [u8; BLOCK_BYTES],
}

/// This board's run, cut into blocks, until the opponent holds them: up to
/// `N` blocks ([`OUT_BLOCKS`] unless the board has less RAM to give).
#[derive(Clone, Debug)]
pub struct Outbox<const N: usize = OUT_BLOCKS> {
    /// Cut and not acknowledged, oldest first.
    blocks: Deque<Block, N>,
    /// Readings not cut into a block yet.
    pending: Vec<AccelMg, BLOCK_FRAMES>,
    /// The reading before `pending`'s first.
    before: AccelMg,
    /// Frames pushed.
    frames: u32,
    /// Frames the opponent holds.
    acked: u32,
    end: Option<End>,
    end_acked: bool,
    /// The frame of the block the next packet starts from.
    cursor: u32,
    overflowed: bool,
}

/// The outbox has no room: the opponent has not acknowledged as many blocks
/// as it keeps ([`OUT_BLOCKS`] by default).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Overflow;

impl<const N: usize> Default for Outbox<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Outbox<N> {
    /// Empty, before the first frame.
    pub(crate) const fn new() -> Self {
        Outbox {
            blocks: Deque::new(),
            pending: Vec::new(),
            before: FLAT,
            frames: 0,
            acked: 0,
            end: None,
            end_acked: false,
            cursor: 0,
            overflowed: false,
        }
    }

    /// Frames pushed.
    pub fn frames(&self) -> u32 {
        self.frames
    }

    /// Frames the opponent holds.
    pub fn acked(&self) -> u32 {
        self.acked
    }

    /// The end, once [`Outbox::end`] was called.
    pub(crate) fn ended(&self) -> Option<End> {
        self.end
    }

    /// The opponent holds every frame and the end.
    pub(crate) fn delivered(&self) -> bool {
        self.end.is_some() && self.end_acked && self.acked == self.frames
    }

    /// The end, until the opponent holds it.
    pub fn end_to_send(&self) -> Option<End> {
        self.end.filter(|_| !self.end_acked)
    }

    /// Frames pushed and not cut into a block yet.
    pub(crate) fn unsent(&self) -> u32 {
        self.pending.len() as u32
    }

    /// Blocks waiting for their acknowledgement.
    pub fn unacked_blocks(&self) -> usize {
        self.blocks.len()
    }

    /// Adds the next frame's reading. After an [`Overflow`] the run can no
    /// longer reach the opponent whole: every later push fails too.
    pub(crate) fn push(&mut self, reading: AccelMg) -> Result<(), Overflow> {
        if self.overflowed || self.end.is_some() {
            return Err(Overflow);
        }
        if self.pending.is_full() {
            self.cut()?;
        }
        // `cut` leaves room: at least one reading fits a block.
        let _ = self.pending.push(reading);
        self.frames += 1;
        if self.pending.is_full() {
            self.cut()?;
        }
        Ok(())
    }

    /// Closes the run: cuts what is pending and keeps `end` to send. After an
    /// [`Overflow`] there is no end to send: the opponent could not reach it.
    pub(crate) fn end(&mut self, end: End) -> Result<(), Overflow> {
        if self.overflowed {
            return Err(Overflow);
        }
        while !self.pending.is_empty() {
            self.cut()?;
        }
        self.end = Some(end);
        Ok(())
    }

    /// Cuts a block from the front of `pending`: as many readings as fit.
    fn cut(&mut self) -> Result<(), Overflow> {
        if self.blocks.is_full() {
            self.overflowed = true;
            return Err(Overflow);
        }
        let mut block = Block {
            first: self.frames - self.pending.len() as u32,
            frames: 0,
            len: 0,
            tokens: [0; BLOCK_BYTES],
        };
        let mut w = TokenWriter::new(&mut block.tokens, self.before);
        let mut taken = 0;
        let mut prev = self.before;
        for &r in &self.pending {
            // A push that does not fit leaves the writer as it was; a repeated
            // reading writes nothing until `finish` writes its run, one byte
            // for a block's at most 16 frames: it needs that byte free.
            if r == prev && w.len() >= BLOCK_BYTES {
                break;
            }
            if w.push(r).is_err() {
                break;
            }
            prev = r;
            taken += 1;
        }
        let len = w.finish().map_or(0, <[u8]>::len);
        if taken == 0 || len == 0 {
            // Unreachable by the room kept above; refuse rather than send a
            // block that does not decode to its readings.
            self.overflowed = true;
            return Err(Overflow);
        }
        block.frames = taken as u8;
        block.len = len as u8;
        self.before = self.pending[taken - 1];
        let rest: Vec<AccelMg, BLOCK_FRAMES> = self.pending[taken..].iter().copied().collect();
        self.pending = rest;
        let _ = self.blocks.push_back(block);
        Ok(())
    }

    /// The opponent holds `frames` of this run in order, and the end if
    /// `have_end`. Acknowledgements of more than was sent are ignored.
    pub(crate) fn ack(&mut self, frames: u32, have_end: bool) {
        let sent = self.frames - self.pending.len() as u32;
        if frames > sent || frames < self.acked {
            return;
        }
        self.acked = frames;
        while let Some(b) = self.blocks.front() {
            if b.first + u32::from(b.frames) <= frames {
                self.blocks.pop_front();
            } else {
                break;
            }
        }
        if have_end && self.end.is_some() && frames == self.frames {
            self.end_acked = true;
        }
    }

    /// Adds to `w` the oldest unacknowledged block, then the others from the
    /// cursor on, as many as fit, and moves the cursor past them (back to the
    /// start after the newest).
    pub(crate) fn fill(&mut self, w: &mut Writer<'_>) {
        // The oldest block first, in every packet: the one the opponent needs
        // before any other is never more than one packet away.
        let Some(oldest) = self.blocks.front() else {
            return;
        };
        if !w.block(oldest.first, &oldest.tokens[..oldest.len as usize]) {
            return;
        }
        let start = self
            .blocks
            .iter()
            .position(|b| b.first >= self.cursor)
            .unwrap_or(0)
            .max(1);
        let mut last = None;
        for b in self.blocks.iter().skip(start) {
            if !w.block(b.first, &b.tokens[..b.len as usize]) {
                break;
            }
            last = Some(b.first + u32::from(b.frames));
        }
        let newest = self.blocks.back().map(|b| b.first + u32::from(b.frames));
        self.cursor = match last {
            Some(end) if Some(end) != newest => end,
            _ => 0,
        };
    }
}

/// What became of a received block.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub(crate) enum Taken {
    /// The next readings: taken, this many frames (with the early blocks it
    /// joined).
    Frames(u32),
    /// Starts after a gap: kept until the blocks before it arrive.
    Kept,
    /// Already held, kept already, or no room: left for its next turn.
    Left,
    /// The tokens do not decode, or hold more than `BLOCK_FRAMES` readings
    /// or more than the opponent's end.
    Bad,
}

/// The opponent's run as received: up to `R` readings in order, waiting for
/// the replay, and up to `E` blocks that came after a gap ([`INBOX_READINGS`]
/// and [`EARLY_BLOCKS`] unless the board has less RAM to give).
#[derive(Clone, Debug)]
pub struct Inbox<const R: usize = INBOX_READINGS, const E: usize = EARLY_BLOCKS> {
    readings: Deque<AccelMg, R>,
    /// Blocks after a gap.
    early: Vec<Block, E>,
    /// Frames taken (in order).
    have: u32,
    /// The reading of frame `have - 1` (the flat board before the first).
    last: AccelMg,
    end: Option<End>,
}

impl<const R: usize, const E: usize> Default for Inbox<R, E> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const R: usize, const E: usize> Inbox<R, E> {
    /// Empty.
    pub(crate) const fn new() -> Self {
        Inbox {
            readings: Deque::new(),
            early: Vec::new(),
            have: 0,
            last: FLAT,
            end: None,
        }
    }

    /// Frames taken, in order (what this board acknowledges).
    pub fn have(&self) -> u32 {
        self.have
    }

    /// The opponent's end, once received.
    pub fn end(&self) -> Option<End> {
        self.end
    }

    /// Every frame of the opponent's run and its end are here.
    pub(crate) fn complete(&self) -> bool {
        self.end.is_some_and(|e| e.frames == self.have)
    }

    /// Takes a block if it is the next, and the early ones it joins; keeps
    /// it if it comes after a gap.
    pub(crate) fn take(&mut self, first: u32, tokens: &[u8]) -> Taken {
        if first < self.have {
            return Taken::Left;
        }
        if first > self.have {
            if self.end.is_some_and(|e| first >= e.frames) {
                return Taken::Bad;
            }
            if self.early.iter().any(|b| b.first == first) {
                return Taken::Left;
            }
            let mut block = Block {
                first,
                frames: 0,
                len: tokens.len() as u8,
                tokens: [0; BLOCK_BYTES],
            };
            let Some(slot) = block.tokens.get_mut(..tokens.len()) else {
                return Taken::Bad;
            };
            slot.copy_from_slice(tokens);
            return match self.early.push(block) {
                Ok(()) => Taken::Kept,
                Err(block) => {
                    // Full: the block nearest the gap is worth the most.
                    match self.early.iter_mut().max_by_key(|b| b.first) {
                        Some(far) if far.first > first => {
                            *far = block;
                            Taken::Kept
                        }
                        _ => Taken::Left,
                    }
                }
            };
        }
        let taken = match self.next(tokens) {
            Taken::Frames(n) => n,
            other => return other,
        };
        let mut total = taken;
        loop {
            self.early.retain(|b| b.first >= self.have);
            let Some(i) = self.early.iter().position(|b| b.first == self.have) else {
                break;
            };
            let b = self.early.swap_remove(i);
            match self.next(&b.tokens[..b.len as usize]) {
                Taken::Frames(n) => total += n,
                Taken::Left => {
                    // No room yet: keep it for when the replay has caught up.
                    let _ = self.early.push(b);
                    break;
                }
                _ => {}
            }
        }
        Taken::Frames(total)
    }

    /// Decodes the block that starts at `have`.
    fn next(&mut self, tokens: &[u8]) -> Taken {
        let mut block: Vec<AccelMg, BLOCK_FRAMES> = Vec::new();
        for r in Readings::from_tokens(tokens, self.last) {
            match r {
                Ok(r) if block.push(r).is_ok() => {}
                _ => return Taken::Bad,
            }
        }
        let Some(&last) = block.last() else {
            return Taken::Bad;
        };
        let n = block.len() as u32;
        if self.end.is_some_and(|e| self.have + n > e.frames) {
            return Taken::Bad;
        }
        if self.readings.capacity() - self.readings.len() < block.len() {
            return Taken::Left;
        }
        for r in block {
            let _ = self.readings.push_back(r);
        }
        self.have += n;
        self.last = last;
        Taken::Frames(n)
    }

    /// Keeps the opponent's end; `false` if it contradicts one received
    /// before or the frames already held.
    pub(crate) fn set_end(&mut self, end: End) -> bool {
        match self.end {
            Some(e) => e == end,
            None if end.frames < self.have => false,
            None => {
                self.end = Some(end);
                true
            }
        }
    }

    /// The next reading for the replay.
    pub(crate) fn pop(&mut self) -> Option<AccelMg> {
        self.readings.pop_front()
    }
}
