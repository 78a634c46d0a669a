//! Racing a friend: two boards, one generated maze, and a protocol between them
//! that needs only a way to send small packets that may be lost, repeated,
//! reordered, delayed or garbled (the radio, a UART, UDP). No radio here: bytes
//! in, bytes out, one call a frame.
//!
//! * [`packet`]: the packet format (version 1) and its checks (CRC-16, magic,
//!   version, framing); a packet failing any is dropped and counted.
//! * [`handshake`]: two boards find each other and agree on the maze.
//! * [`stream`]: each board's readings, in the ghost's coding, in blocks that
//!   are repeated until acknowledged.
//! * [`session`]: one board's protocol state machine ([`RaceLink`]): countdown,
//!   silence, counters.
//! * [`replay`]: the opponent's marble replayed bit-exactly from its readings,
//!   and the verdict (fewer frames wins).
//! * `play`: all of it around this board's own session ([`Race`]).
//! * [`wire`]: the packets on a byte stream (a UART between two boards).
//! * [`air`]: the packets in radio frames, behind a group byte (the
//!   micro:bit v2's IEEE 802.15.4 radio).
//!
//! docs/race.md describes the protocol and what a lost packet costs.

pub mod air;
pub mod handshake;
pub mod packet;
pub(crate) mod play;
pub mod replay;
pub mod session;
pub mod stream;
pub mod wire;

pub use packet::{MazeSpec, MAX_PACKET};
pub use play::{Race, RaceError, Status};
pub use replay::{decide, Run, Verdict};
pub use session::{Counters, LeanLink, LinkStage, RaceLink};

use core::num::NonZeroU32;

use crate::game::generate::{generate, GenerateError, Maze};

/// The race's maze: what both boards generate from the agreed [`MazeSpec`].
pub fn maze(spec: MazeSpec) -> Result<Maze, GenerateError> {
    generate(spec.seed, spec.size, spec.storeys, spec.difficulty)
}

/// The maze a board offers: one storey of 5 × 5 cells, difficulty 1, its
/// seed from the board's id (a new maze each race). The handshake agrees on
/// the proposer's offer.
pub const fn offer(id: NonZeroU32) -> MazeSpec {
    MazeSpec {
        seed: id.get(),
        size: 5,
        storeys: 1,
        difficulty: 1,
    }
}

/// The board id of race `n` after power-on, from `seed` (the board's random
/// draw at power-on): never 0, and a new one each race, so the opponent
/// takes a board that races again for a new board.
pub const fn race_id(seed: u32, n: u32) -> NonZeroU32 {
    let mixed = (seed ^ n.wrapping_mul(0x9E37_79B9)).wrapping_mul(0x85EB_CA6B);
    match NonZeroU32::new(mixed ^ (mixed >> 16)) {
        Some(id) => id,
        None => NonZeroU32::MIN,
    }
}
