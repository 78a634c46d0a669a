//! One board's side of the race protocol, without a radio: bytes in
//! ([`RaceLink::receive`]), bytes out ([`RaceLink::transmit`]), one
//! [`RaceLink::tick`] per game frame. The handshake ([`super::handshake`]), the
//! streams with their acknowledgements ([`super::stream`]), the countdown, the
//! silence watch and the counters of what was dropped live here; the physics
//! does not (the opponent's replay is [`super::replay`]).
//!
//! Time is the board's own frame count: nothing here reads a clock, and the two
//! boards' counts are never compared.

use super::handshake::{Handshake, Stage};
use super::packet::{self, Drop, End, MazeSpec, Writer, MAX_PACKET};
use super::stream::{
    Inbox, Outbox, Overflow, Taken, EARLY_BLOCKS, INBOX_READINGS, LEAN_EARLY_BLOCKS,
    LEAN_INBOX_READINGS, LEAN_OUT_BLOCKS, OUT_BLOCKS,
};
use crate::input::axes::AccelMg;
use crate::input::sensor::Calibration;

/// Frames between two hellos while searching (4 a second).
pub(crate) const HELLO_EVERY: u32 = 32;
/// Frames between two race packets while a stream is under way (32 a second).
pub(crate) const SEND_EVERY: u32 = 4;
/// Frames without a packet from the opponent before the board says it is
/// alone: 3 s.
pub const SILENCE_FRAMES: u32 = 384;
/// Frames from the pairing to the start: 3 s to get ready.
pub const COUNTDOWN_FRAMES: u32 = 384;

/// What was sent, received and dropped, by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Counters {
    /// Packets sent.
    pub sent: u32,
    /// Bytes sent.
    pub sent_bytes: u32,
    /// Packets received (all).
    pub received: u32,
    /// Packets that passed every check.
    pub accepted: u32,
    /// Dropped: wrong length.
    pub length: u32,
    /// Dropped: garbled (CRC).
    pub crc: u32,
    /// Dropped: not a race packet.
    pub foreign: u32,
    /// Dropped: another version.
    pub version: u32,
    /// Dropped: malformed body.
    pub malformed: u32,
    /// Dropped: another race (a third board).
    pub not_ours: u32,
    /// Dropped: received before.
    pub replayed: u32,
    /// Dropped: contradicting the opponent's earlier packets.
    pub(crate) inconsistent: u32,
    /// Blocks taken into the opponent's readings, or kept until the gap
    /// before them fills.
    pub blocks_taken: u32,
    /// Blocks left: already held or kept, or no room yet.
    pub(crate) blocks_left: u32,
    /// Blocks whose tokens did not decode.
    pub(crate) blocks_bad: u32,
}

impl Counters {
    /// Packets dropped, every reason.
    pub fn dropped(&self) -> u32 {
        self.length
            + self.crc
            + self.foreign
            + self.version
            + self.malformed
            + self.not_ours
            + self.replayed
            + self.inconsistent
    }

    fn count(&mut self, d: Drop) {
        let c = match d {
            Drop::Length => &mut self.length,
            Drop::Crc => &mut self.crc,
            Drop::Foreign => &mut self.foreign,
            Drop::Version => &mut self.version,
            Drop::Malformed { .. } => &mut self.malformed,
            Drop::NotOurs => &mut self.not_ours,
            Drop::Replayed => &mut self.replayed,
            Drop::Inconsistent => &mut self.inconsistent,
        };
        *c = c.saturating_add(1);
    }
}

/// What a packet that passed the checks was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Heard {
    /// A hello.
    Hello,
    /// A packet of this board's race.
    Race,
}

/// Where the link stands, for the screen.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum LinkStage {
    /// Looking for an opponent.
    Searching,
    /// Proposed to a board, waiting for its answer.
    Proposed,
    /// Paired: this many frames to the start.
    Countdown(u32),
    /// Racing (the countdown is over).
    Racing,
}

/// Packets received before, by their `seq`: the newest and a window of 64
/// behind it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
struct SeqWindow {
    top: Option<u16>,
    /// Bit `i`: `top - i` was received.
    seen: u64,
}

impl SeqWindow {
    /// Whether `seq` is new (and remembers it).
    fn fresh(&mut self, seq: u16) -> bool {
        let Some(top) = self.top else {
            self.top = Some(seq);
            self.seen = 1;
            return true;
        };
        let ahead = seq.wrapping_sub(top) as i16;
        if ahead > 0 {
            self.seen = self.seen.checked_shl(ahead as u32).unwrap_or(0) | 1;
            self.top = Some(seq);
            return true;
        }
        let back = u32::from(ahead.unsigned_abs());
        if back >= 64 || self.seen & (1 << back) != 0 {
            return false;
        }
        self.seen |= 1 << back;
        true
    }
}

/// One board's side of the race protocol, keeping up to `O` blocks of its own
/// run until acknowledged, `I` of the opponent's readings until replayed and
/// `E` of its blocks that came after a gap (the defaults, [`OUT_BLOCKS`],
/// [`INBOX_READINGS`] and [`EARLY_BLOCKS`], are the host's and QEMU's; a board
/// with less RAM to give keeps fewer: [`RaceLink::sized`]). Fewer blocks out
/// is a shorter silence the run outlives; fewer readings in, a replay that
/// takes a late burst of blocks in more turns.
#[derive(Clone, Debug)]
pub struct RaceLink<
    const O: usize = OUT_BLOCKS,
    const I: usize = INBOX_READINGS,
    const E: usize = EARLY_BLOCKS,
> {
    hs: Handshake,
    calibration: Calibration,
    now: u32,
    seq: u16,
    next_send: u32,
    last_heard: u32,
    window: SeqWindow,
    out: Outbox<O>,
    inbox: Inbox<I, E>,
    peer_calibration: Option<Calibration>,
    reply: bool,
    counters: Counters,
}

impl RaceLink {
    /// Board `me` (any id but 0: a board draws one at random when it powers
    /// on, so a restarted board is a new one) offering `offer`, its tilt path
    /// calibrated by `calibration` for the whole race; the default sizes.
    pub fn new(me: core::num::NonZeroU32, offer: MazeSpec, calibration: Calibration) -> Self {
        Self::sized(me, offer, calibration)
    }
}

/// A [`RaceLink`] of the lean sizes ([`super::stream::LEAN_OUT_BLOCKS`] and
/// the others), for a board with little RAM to give.
pub type LeanLink = RaceLink<LEAN_OUT_BLOCKS, LEAN_INBOX_READINGS, LEAN_EARLY_BLOCKS>;

impl<const O: usize, const I: usize, const E: usize> RaceLink<O, I, E> {
    /// As [`RaceLink::new`], with the sizes of the type.
    pub fn sized(me: core::num::NonZeroU32, offer: MazeSpec, calibration: Calibration) -> Self {
        let me = me.get();
        RaceLink {
            hs: Handshake::new(me, offer),
            calibration,
            now: 0,
            seq: 0,
            // Boards powered on together do not say hello in step.
            next_send: me % HELLO_EVERY,
            last_heard: 0,
            window: SeqWindow::default(),
            out: Outbox::new(),
            inbox: Inbox::new(),
            peer_calibration: None,
            reply: false,
            counters: Counters::default(),
        }
    }

    /// This board's id.
    pub fn me(&self) -> u32 {
        self.hs.me()
    }

    /// The handshake's stage.
    pub fn handshake(&self) -> Stage {
        self.hs.stage()
    }

    /// The opponent and the race's maze, once paired.
    pub fn paired(&self) -> Option<(u32, MazeSpec)> {
        match self.hs.stage() {
            Stage::Paired { peer, maze, .. } => Some((peer, maze)),
            _ => None,
        }
    }

    /// Where the link stands.
    pub fn stage(&self) -> LinkStage {
        match self.hs.stage() {
            Stage::Searching => LinkStage::Searching,
            Stage::Proposed { .. } => LinkStage::Proposed,
            Stage::Paired { at, .. } => {
                let since = self.now.wrapping_sub(at);
                if since >= COUNTDOWN_FRAMES {
                    LinkStage::Racing
                } else {
                    LinkStage::Countdown(COUNTDOWN_FRAMES - since)
                }
            }
        }
    }

    /// The board's frames since it was made.
    pub fn now(&self) -> u32 {
        self.now
    }

    /// This board's calibration during the race.
    pub(crate) fn calibration(&self) -> Calibration {
        self.calibration
    }

    /// The opponent's calibration, once heard (before any of its readings).
    pub(crate) fn peer_calibration(&self) -> Option<Calibration> {
        self.peer_calibration
    }

    /// Paired, the race not complete (`RaceLink::complete`), and nothing heard
    /// from the opponent for [`SILENCE_FRAMES`]. (Once complete, both boards
    /// fall quiet on purpose.)
    pub fn silent(&self) -> bool {
        self.paired().is_some()
            && !self.complete()
            && self.now.wrapping_sub(self.last_heard) >= SILENCE_FRAMES
    }

    /// Frames since the opponent was last heard (0 before the pairing).
    pub fn quiet_frames(&self) -> u32 {
        if self.paired().is_some() {
            self.now.wrapping_sub(self.last_heard)
        } else {
            0
        }
    }

    /// The counters.
    pub fn counters(&self) -> &Counters {
        &self.counters
    }

    /// This board's stream.
    pub fn outbox(&self) -> &Outbox<O> {
        &self.out
    }

    /// The opponent's stream.
    pub fn inbox(&self) -> &Inbox<I, E> {
        &self.inbox
    }

    /// Both runs are over and each board holds the other's whole: nothing
    /// left to send but answers.
    pub(crate) fn complete(&self) -> bool {
        self.out.delivered() && self.inbox.complete()
    }

    /// One frame passes.
    pub fn tick(&mut self) {
        self.now = self.now.wrapping_add(1);
        self.hs.tick(self.now);
    }

    /// This board's next reading of its run. After an [`Overflow`] (the
    /// opponent unheard while the outbox filled) the run cannot reach it.
    pub fn push_own(&mut self, reading: AccelMg) -> Result<(), Overflow> {
        self.out.push(reading)
    }

    /// This board's run is over.
    pub(crate) fn end_own(&mut self, end: End) -> Result<(), Overflow> {
        self.out.end(end)
    }

    /// The opponent's next reading, in order.
    pub(crate) fn pop_opponent(&mut self) -> Option<AccelMg> {
        self.inbox.pop()
    }

    /// A packet from the channel. Whatever it holds, it is checked, counted,
    /// and either used or dropped.
    pub fn receive(&mut self, bytes: &[u8]) -> Result<Heard, Drop> {
        self.counters.received = self.counters.received.saturating_add(1);
        let r = self.take(bytes);
        match r {
            Ok(_) => self.counters.accepted = self.counters.accepted.saturating_add(1),
            Err(d) => self.counters.count(d),
        }
        r
    }

    fn take(&mut self, bytes: &[u8]) -> Result<Heard, Drop> {
        let p = packet::parse(bytes)?;
        if p.from == self.me() {
            // Its own packet, echoed by the channel.
            return Err(Drop::NotOurs);
        }
        let Some(body) = p.race else {
            self.hs.hello(p.from, self.now);
            return Ok(Heard::Hello);
        };
        let was_paired = self.paired().is_some();
        if !self.hs.race(p.from, p.to, p.maze, self.now) {
            return Err(Drop::NotOurs);
        }
        if !was_paired {
            self.window = SeqWindow::default();
            self.last_heard = self.now;
        }
        if !self.window.fresh(p.seq) {
            return Err(Drop::Replayed);
        }
        if self.peer_calibration.is_some_and(|c| c != body.calibration) {
            return Err(Drop::Inconsistent);
        }
        if let Some(end) = body.end {
            if !self.inbox.set_end(end) {
                return Err(Drop::Inconsistent);
            }
        }
        self.peer_calibration = Some(body.calibration);
        self.last_heard = self.now;
        self.out.ack(body.ack, body.have_end);
        let mut carried = body.end.is_some();
        for (first, tokens) in body.blocks() {
            carried = true;
            let c = &mut self.counters;
            match self.inbox.take(first, tokens) {
                Taken::Frames(_) | Taken::Kept => c.blocks_taken = c.blocks_taken.saturating_add(1),
                Taken::Left => c.blocks_left = c.blocks_left.saturating_add(1),
                Taken::Bad => c.blocks_bad = c.blocks_bad.saturating_add(1),
            }
        }
        let sent = self.out.frames() - self.out.unsent();
        let lacks = body.ack < sent || (self.out.ended().is_some() && !body.have_end);
        self.reply |= carried || lacks;
        Ok(Heard::Race)
    }

    /// The packet to send now, if one is due (call once a frame): a hello
    /// while searching, else a race packet to the opponent with its
    /// acknowledgement, this board's end if not yet held, and the blocks it
    /// lacks. Once `RaceLink::complete`, only answers to the opponent's
    /// packets.
    pub fn transmit<'b>(&mut self, buf: &'b mut [u8; MAX_PACKET]) -> Option<&'b [u8]> {
        let me = self.me();
        let packet = match self.hs.addressee() {
            None => {
                if (self.now.wrapping_sub(self.next_send) as i32) < 0 {
                    return None;
                }
                self.next_send = self.now.wrapping_add(HELLO_EVERY);
                Writer::hello(buf, me, self.seq, self.hs.offer()).finish()
            }
            Some((peer, maze)) => {
                let due = !self.complete() && self.now.wrapping_sub(self.next_send) as i32 >= 0;
                if !(due || self.reply) {
                    return None;
                }
                self.reply = false;
                self.next_send = self.now.wrapping_add(SEND_EVERY);
                let end = self.out.end_to_send();
                let mut w = Writer::race(
                    buf,
                    me,
                    peer,
                    self.seq,
                    maze,
                    self.calibration,
                    self.inbox.have(),
                    self.inbox.end().is_some(),
                    end,
                );
                if self.paired().is_some() {
                    self.out.fill(&mut w);
                }
                w.finish()
            }
        };
        self.seq = self.seq.wrapping_add(1);
        let c = &mut self.counters;
        c.sent = c.sent.saturating_add(1);
        c.sent_bytes = c.sent_bytes.saturating_add(packet.len() as u32);
        Some(packet)
    }
}
