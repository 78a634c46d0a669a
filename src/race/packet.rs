//! The race's packets: their layout (version 1), how one is written, and the
//! checks a received one passes before anything in it is believed.
//!
//! ```text
//! 0   "MR" 1 kind        magic, version, kind (1 hello, 2 race)
//! 4   from               u32 LE: the sender's id (never 0)
//! 8   to                 u32 LE: the opponent's id, 0 in a hello
//! 12  seq                u16 LE: the sender's packet counter (wraps)
//! 14  maze               seed u32 LE, size, storeys, difficulty: the sender's offer
//!                        (hello) or the race's maze (race)
//! 21  race only:
//!     calibration        offset_x, offset_z: zigzag varints (mg)
//!     ack                varint: frames of `to`'s run the sender holds, in order
//!     flags              bit 0: the sender holds `to`'s end; bit 1: an end follows
//!     end                frames varint, state hash u64 LE (flag bit 1 only)
//!     blocks, until the CRC:
//!       first            varint: the frame of the block's first reading
//!       len              u8, 1 ..= BLOCK_BYTES (28)
//!       tokens           the ghost's coding, from the reading before `first`
//! n-2 CRC-16/IBM-3740    u16 LE over bytes 0 .. n-2
//! ```
//!
//! A packet is at most [`MAX_PACKET`] (124) bytes. The checks, in order: length,
//! CRC (garbled), magic (another protocol), version, kind, then the body's
//! framing; every failure is a [`Drop`] and nothing else happens. A block's
//! tokens are decoded only when the block is taken (`stream`).

use crc::{Crc, NoTable, CRC_16_IBM_3740};

use crate::input::sensor::Calibration;

/// The longest packet (bytes, CRC included): the payload of an IEEE 802.15.4
/// frame, the one mode embassy-nrf 0.11 drives the nRF52833's radio in
/// (`radio::ieee802154::Packet::CAPACITY`, 125 bytes), less the group byte in
/// front of it ([`super::air`]), so a packet is one radio frame. It holds the fixed fields and three blocks of [`BLOCK_BYTES`]: the oldest
/// block the opponent lacks and two more in turn (with room for one, a lossy
/// link would deliver one block a round trip).
pub const MAX_PACKET: usize = 124;
/// The protocol's version: a packet of any other is dropped.
pub(crate) const VERSION: u8 = 1;
/// The most token bytes in a block: three blocks and their heads fit a packet
/// beside the fixed fields.
pub const BLOCK_BYTES: usize = 28;
/// Bytes of a hello, CRC included.
pub const HELLO_BYTES: usize = MAZE_END + 2;

const MAGIC: [u8; 2] = [b'M', b'R'];
const KIND_HELLO: u8 = 1;
const KIND_RACE: u8 = 2;
const MAZE_END: usize = 21;
const FLAG_HAVE_END: u8 = 1;
const FLAG_END: u8 = 2;
const CRC: Crc<u16, NoTable> = Crc::<u16, NoTable>::new(&CRC_16_IBM_3740);

/// The maze a race is run on: [`crate::game::generate::generate`]'s arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct MazeSpec {
    /// The generator's seed.
    pub seed: u32,
    /// Cells along a side.
    pub size: u8,
    /// Storeys.
    pub storeys: u8,
    /// Difficulty.
    pub difficulty: u8,
}

/// A run's end as its runner reports it: frames played and the state hash
/// after the last.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct End {
    /// Frames of the run (readings).
    pub frames: u32,
    /// `Session::state_hash` after the last frame.
    pub hash: u64,
}

/// Why a received packet was dropped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Drop {
    /// Shorter than a header and its CRC, or longer than [`MAX_PACKET`].
    Length,
    /// The CRC does not match: garbled on the way.
    Crc,
    /// Not a race packet (magic), or an unknown kind.
    Foreign,
    /// A race packet of another version.
    Version,
    /// The CRC matches but the body does not parse (its `at` byte).
    Malformed {
        /// Byte offset where it stopped making sense.
        at: usize,
    },
    /// Sound, but not from the opponent to this board: a third board, or a race
    /// this board is not in.
    NotOurs,
    /// A packet already received (its `seq`), or older than the window kept.
    Replayed,
    /// The packet says what contradicts what the opponent said before (another
    /// maze, calibration or end).
    Inconsistent,
}

impl core::fmt::Display for Drop {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match *self {
            Drop::Length => f.write_str("race packet of a wrong length"),
            Drop::Crc => f.write_str("race packet garbled (CRC)"),
            Drop::Foreign => f.write_str("not a race packet"),
            Drop::Version => f.write_str("race packet of another version"),
            Drop::Malformed { at } => write!(f, "race packet malformed at byte {at}"),
            Drop::NotOurs => f.write_str("race packet of another race"),
            Drop::Replayed => f.write_str("race packet received before"),
            Drop::Inconsistent => {
                f.write_str("race packet contradicting the opponent's earlier ones")
            }
        }
    }
}

/// What a race packet says beyond its header.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RaceBody<'a> {
    /// The sender's calibration during its run.
    pub calibration: Calibration,
    /// Frames of the receiver's run the sender holds, in order.
    pub ack: u32,
    /// The sender holds the receiver's end.
    pub have_end: bool,
    /// The sender's end, once its run is over.
    pub end: Option<End>,
    /// The blocks, framing checked ([`RaceBody::blocks`]).
    blocks: &'a [u8],
}

impl<'a> RaceBody<'a> {
    /// The blocks: `(first frame, tokens)`.
    pub fn blocks(&self) -> Blocks<'a> {
        Blocks { rest: self.blocks }
    }
}

/// The blocks of a race packet, in the order sent.
#[derive(Clone, Debug)]
pub struct Blocks<'a> {
    rest: &'a [u8],
}

impl<'a> Iterator for Blocks<'a> {
    type Item = (u32, &'a [u8]);

    fn next(&mut self) -> Option<Self::Item> {
        // The framing was checked when the packet was read.
        let (first, used) = read_varint(self.rest, 0).ok()?;
        let len = *self.rest.get(used)? as usize;
        let tokens = self.rest.get(used + 1..used + 1 + len)?;
        self.rest = &self.rest[used + 1 + len..];
        Some((u32::try_from(first).ok()?, tokens))
    }
}

/// A received packet that passed every check.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Packet<'a> {
    /// The sender.
    pub from: u32,
    /// The addressee, 0 for everyone (a hello).
    pub to: u32,
    /// The sender's packet counter.
    pub seq: u16,
    /// The offer (hello) or the race's maze.
    pub maze: MazeSpec,
    /// A race packet's body; `None` for a hello.
    pub race: Option<RaceBody<'a>>,
}

/// Reads and checks `bytes`.
pub fn parse(bytes: &[u8]) -> Result<Packet<'_>, Drop> {
    if bytes.len() < HELLO_BYTES || bytes.len() > MAX_PACKET {
        return Err(Drop::Length);
    }
    let (body, tail) = bytes.split_at(bytes.len() - 2);
    if CRC.checksum(body) != u16::from_le_bytes([tail[0], tail[1]]) {
        return Err(Drop::Crc);
    }
    if body[..2] != MAGIC {
        return Err(Drop::Foreign);
    }
    if body[2] != VERSION {
        return Err(Drop::Version);
    }
    let word = |at: usize| u32::from_le_bytes([body[at], body[at + 1], body[at + 2], body[at + 3]]);
    let from = word(4);
    let to = word(8);
    let seq = u16::from_le_bytes([body[12], body[13]]);
    let maze = MazeSpec {
        seed: word(14),
        size: body[18],
        storeys: body[19],
        difficulty: body[20],
    };
    if from == 0 {
        return Err(Drop::Malformed { at: 4 });
    }
    let race = match body[3] {
        KIND_HELLO if body.len() == MAZE_END && to == 0 => None,
        KIND_HELLO => return Err(Drop::Malformed { at: 8 }),
        KIND_RACE if to != 0 && to != from => Some(race_body(body)?),
        KIND_RACE => return Err(Drop::Malformed { at: 8 }),
        _ => return Err(Drop::Foreign),
    };
    Ok(Packet {
        from,
        to,
        seq,
        maze,
        race,
    })
}

fn race_body(body: &[u8]) -> Result<RaceBody<'_>, Drop> {
    let mut at = MAZE_END;
    let field = |at: &mut usize| -> Result<u64, Drop> {
        let (v, used) = read_varint(body, *at)?;
        *at += used;
        Ok(v)
    };
    let offset = |at: &mut usize| -> Result<i32, Drop> {
        let start = *at;
        i32::try_from(unzigzag(field(at)?)).map_err(|_| Drop::Malformed { at: start })
    };
    let calibration = Calibration {
        offset_x: offset(&mut at)?,
        offset_z: offset(&mut at)?,
    };
    let start = at;
    let ack = u32::try_from(field(&mut at)?).map_err(|_| Drop::Malformed { at: start })?;
    let flags = *body.get(at).ok_or(Drop::Malformed { at })?;
    if flags & !(FLAG_HAVE_END | FLAG_END) != 0 {
        return Err(Drop::Malformed { at });
    }
    at += 1;
    let end = if flags & FLAG_END != 0 {
        let start = at;
        let frames = u32::try_from(field(&mut at)?).map_err(|_| Drop::Malformed { at: start })?;
        let hash = body
            .get(at..at + 8)
            .ok_or(Drop::Malformed { at })?
            .iter()
            .rev()
            .fold(0u64, |h, &b| h << 8 | u64::from(b));
        at += 8;
        Some(End { frames, hash })
    } else {
        None
    };
    let blocks = &body[at..];
    let mut pos = 0;
    while pos < blocks.len() {
        let (first, used) =
            read_varint(blocks, pos).map_err(|_| Drop::Malformed { at: at + pos })?;
        if u32::try_from(first).is_err() {
            return Err(Drop::Malformed { at: at + pos });
        }
        pos += used;
        let len = *blocks.get(pos).ok_or(Drop::Malformed { at: at + pos })? as usize;
        if len == 0 || len > BLOCK_BYTES || pos + 1 + len > blocks.len() {
            return Err(Drop::Malformed { at: at + pos });
        }
        pos += 1 + len;
    }
    Ok(RaceBody {
        calibration,
        ack,
        have_end: flags & FLAG_HAVE_END != 0,
        end,
        blocks,
    })
}

/// A varint at `at`: its value and its length. At most ten bytes.
fn read_varint(bytes: &[u8], at: usize) -> Result<(u64, usize), Drop> {
    let mut v: u64 = 0;
    for i in 0..10 {
        let b = *bytes.get(at + i).ok_or(Drop::Malformed { at: at + i })?;
        v |= u64::from(b & 0x7f).checked_shl(7 * i as u32).unwrap_or(0);
        if b & 0x80 == 0 {
            return Ok((v, i + 1));
        }
    }
    Err(Drop::Malformed { at })
}

fn zigzag(d: i32) -> u64 {
    u64::from(((d << 1) ^ (d >> 31)) as u32)
}

fn unzigzag(u: u64) -> i64 {
    (u >> 1) as i64 ^ -((u & 1) as i64)
}

/// Writes one packet into a caller's buffer: the header, then (race packets)
/// the fixed fields and as many blocks as fit, then [`Writer::finish`] adds
/// the CRC.
#[derive(Debug)]
pub struct Writer<'a> {
    buf: &'a mut [u8; MAX_PACKET],
    len: usize,
}

impl<'a> Writer<'a> {
    /// A hello from `from` offering `maze`.
    pub fn hello(buf: &'a mut [u8; MAX_PACKET], from: u32, seq: u16, maze: MazeSpec) -> Self {
        let mut w = Writer { buf, len: 0 };
        w.header(KIND_HELLO, from, 0, seq, maze);
        w
    }

    /// A race packet from `from` to `to`, with everything but the blocks.
    #[allow(clippy::too_many_arguments)]
    pub fn race(
        buf: &'a mut [u8; MAX_PACKET],
        from: u32,
        to: u32,
        seq: u16,
        maze: MazeSpec,
        calibration: Calibration,
        ack: u32,
        have_end: bool,
        end: Option<End>,
    ) -> Self {
        let mut w = Writer { buf, len: 0 };
        w.header(KIND_RACE, from, to, seq, maze);
        w.varint(zigzag(calibration.offset_x));
        w.varint(zigzag(calibration.offset_z));
        w.varint(u64::from(ack));
        let flags =
            if have_end { FLAG_HAVE_END } else { 0 } | if end.is_some() { FLAG_END } else { 0 };
        w.bytes(&[flags]);
        if let Some(e) = end {
            w.varint(u64::from(e.frames));
            w.bytes(&e.hash.to_le_bytes());
        }
        w
    }

    fn header(&mut self, kind: u8, from: u32, to: u32, seq: u16, maze: MazeSpec) {
        self.bytes(&[MAGIC[0], MAGIC[1], VERSION, kind]);
        self.bytes(&from.to_le_bytes());
        self.bytes(&to.to_le_bytes());
        self.bytes(&seq.to_le_bytes());
        self.bytes(&maze.seed.to_le_bytes());
        self.bytes(&[maze.size, maze.storeys, maze.difficulty]);
    }

    // The fixed fields take at most 21 + 2·5 + 5 + 1 + 5 + 8 = 50 bytes, far
    // inside the buffer: writing them cannot run out of room.
    fn bytes(&mut self, b: &[u8]) {
        self.buf[self.len..self.len + b.len()].copy_from_slice(b);
        self.len += b.len();
    }

    fn varint(&mut self, mut v: u64) {
        loop {
            let byte = (v & 0x7f) as u8;
            v >>= 7;
            self.bytes(&[if v == 0 { byte } else { byte | 0x80 }]);
            if v == 0 {
                return;
            }
        }
    }

    /// Adds a block if it fits (leaving room for the CRC); whether it did.
    pub fn block(&mut self, first: u32, tokens: &[u8]) -> bool {
        let mut head = [0u8; 5];
        let mut n = 0;
        let mut v = first;
        loop {
            let byte = (v & 0x7f) as u8;
            v >>= 7;
            head[n] = if v == 0 { byte } else { byte | 0x80 };
            n += 1;
            if v == 0 {
                break;
            }
        }
        if tokens.is_empty()
            || tokens.len() > BLOCK_BYTES
            || self.len + n + 1 + tokens.len() + 2 > MAX_PACKET
        {
            return false;
        }
        self.bytes(&head[..n]);
        self.bytes(&[tokens.len() as u8]);
        self.bytes(tokens);
        true
    }

    /// Bytes written so far (without the CRC).
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is written (never: the header is written first).
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Adds the CRC; returns the packet.
    pub fn finish(self) -> &'a [u8] {
        let crc = CRC.checksum(&self.buf[..self.len]);
        self.buf[self.len..self.len + 2].copy_from_slice(&crc.to_le_bytes());
        &self.buf[..self.len + 2]
    }
}
