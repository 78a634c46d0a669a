//! The game's sizes the micro:bit v2 is built to, which the QEMU board runs
//! too: the generated maze's reach and the ghosts' room. QEMU has no nRF52
//! emulator, so the v2's maze and ghost code is measured on QEMU's Cortex-M4
//! (its stack, its flash, which runs it keeps); that holds only while both
//! boards take these figures from here, not from each other. Pure constants,
//! so the two boards import this module and not each other.

use crate::game::endless::{Reach, MOST_STOREYS};

/// The largest generated maze the endless run plays ([`crate::game::endless`]):
/// 10 cells a side (21 tiles; a small view follows the marble) on up to four
/// storeys. Its slot keeps 444 B of tiles in the game task's static RAM, and
/// its text takes at most 1 992 B of stack while it is parsed, between two
/// levels (`cargo xtask size-report` has the v2's figures).
pub const MAZE_REACH: Reach = Reach {
    size: 10,
    storeys: MOST_STOREYS,
};

/// The ghosts' region (`marble_rolling::records::Ghosts`), bytes: four 4 KiB
/// pages. Each level's best run is one item of at most a page; a full region
/// makes the oldest ghost give way.
pub const GHOSTS_BYTES: usize = 4 * 4096;

/// The longest run recorded and kept as a ghost, bytes (the game task's two
/// buffers, `app::GhostKit`): about 7 s of the autopilot's play at its
/// 279 B/s, 4 s of a noisy sensor's at 489 B/s (docs/ghost.md).
pub const GHOST_BYTES: usize = 2048;
