//! Where each micro:bit keeps its levels region in flash; the format, its reader
//! and writer are [`crate::game::levels_region`] (the game plays the region's
//! levels, below the boards).

use core::ops::Range;

pub use crate::game::levels_region::*;

/// The micro:bit v1's region: the last 4 KiB of the nRF51822's 256 KiB (the
/// firmware's budget is 144 KiB).
pub const V1: Range<u32> = 0x3_F000..0x4_0000;
/// The micro:bit v2's region: the 4 KiB page below the best times
/// (`board::microbit::RECORDS`, 0x7C000..0x80000, which checks that the two
/// stay apart).
pub const V2: Range<u32> = 0x7_B000..0x7_C000;

// Each region is one whole erase unit in its chip's flash (nRF51822: 256 KiB
// in 1 KiB pages; nRF52833: 512 KiB in 4 KiB pages): checked when the crate
// builds.
const _: () = {
    assert!((V1.end - V1.start) as usize == SIZE);
    assert!(V1.start.is_multiple_of(1024) && V1.end <= 256 * 1024);
    assert!((V2.end - V2.start) as usize == SIZE);
    assert!(V2.start.is_multiple_of(4096) && V2.end <= 512 * 1024);
};
