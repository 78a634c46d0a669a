//! What each thing is drawn as: the tiles', the goal's and the marble's
//! brightness, the goal's blink and the glow of a drop onto a lower storey.

use crate::matrix::{Brightness, MAX_BRIGHTNESS};

/// A wall tile (`#`).
pub const WALL: Brightness = 3;
/// A floor tile (`.`, `S`): faint, so that holes show.
pub const FLOOR: Brightness = 1;
/// A hole (`O`, no floor tile): dark.
pub const HOLE: Brightness = 0;
/// A goal cell (`G`) in the lit half of its blink.
pub const GOAL_ON: Brightness = 8;
/// A goal cell (`G`) in the dark half of its blink.
pub const GOAL_OFF: Brightness = 0;
/// Pixels outside the maze (a maze smaller than the matrix is centred).
pub const OUTSIDE: Brightness = 0;
/// A marble's total brightness, spread over up to 2×2 pixels and added on top
/// of the background (saturating at [`MAX_BRIGHTNESS`]).
pub const MARBLE: Brightness = MAX_BRIGHTNESS;
/// Goal blink frequency, as `log2` Hz: 2 Hz.
pub(crate) const BLINK_HZ_LOG2: u32 = 1;
/// Goal blink frequency (Hz): a full on/off cycle every half second, lit for
/// the first quarter second of it (see [`blink_on`]).
pub const BLINK_HZ: u32 = 1 << BLINK_HZ_LOG2;
/// How much brighter the floor is drawn in the frame the followed marble
/// lands on a lower storey (fading to nothing over a quarter second).
pub const DROP_FLASH: Brightness = 6;
/// The drop flash lasts `2^(frame_log2 − DROP_FLASH_LOG2)` frames: 1/4 s.
pub(crate) const DROP_FLASH_LOG2: u32 = 2;
/// Whether the goal is lit in frame `frames` of a game running at
/// `2^frame_log2` frames/s: lit for `frame_hz / (2·BLINK_HZ)` frames, dark for
/// as many, starting lit at frame 0 (at 128 frames/s: 32 on, 32 off).
/// At frame rates below `2·BLINK_HZ` it toggles every frame.
pub fn blink_on(frames: u32, frame_log2: u32) -> bool {
    let shift = frame_log2.saturating_sub(BLINK_HZ_LOG2 + 1);
    frames.checked_shr(shift).unwrap_or(0) & 1 == 0
}

/// How much brighter the floor is `elapsed` frames after a drop, at
/// `2^frame_log2` frames/s: [`DROP_FLASH`] at 0, falling linearly to 0 at a
/// quarter second (at frame rates of 4 frames/s or less, one frame).
pub fn drop_glow(elapsed: u32, frame_log2: u32) -> Brightness {
    let log2 = frame_log2.saturating_sub(DROP_FLASH_LOG2);
    let total = 1u32 << log2.min(16);
    if elapsed >= total {
        return 0;
    }
    ((u32::from(DROP_FLASH) * (total - elapsed)) >> log2.min(16)) as Brightness
}
