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
//! * [`play`]: all of it around this board's own session ([`Race`]).
//! * [`wire`]: the packets on a byte stream (a UART between two boards).
//!
//! docs/race.md describes the protocol and what a lost packet costs.

pub mod handshake;
pub mod packet;
pub mod play;
pub mod replay;
pub mod session;
pub mod stream;
pub mod wire;

pub use packet::{MazeSpec, MAX_PACKET};
pub use play::{Race, RaceError, Status};
pub use replay::{decide, Run, Verdict};
pub use session::{Counters, LinkStage, RaceLink};

use crate::game::generate::{generate, GenerateError, Maze};

/// The race's maze: what both boards generate from the agreed [`MazeSpec`].
pub fn maze(spec: MazeSpec) -> Result<Maze, GenerateError> {
    generate(spec.seed, spec.size, spec.storeys, spec.difficulty)
}
