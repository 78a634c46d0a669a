//! The full screens the game loop shows instead of the maze: a won level
//! flashing, a new record's growing squares, and the cross while the sensor is
//! down.
//!
//! Each is a pure function of the frames left in its pause (or of nothing), so
//! the player, the app's display hand-off and the tests draw the same picture
//! for the same frame.

use crate::game::rules::GameConfig;
use crate::matrix::{Frame, MAX_BRIGHTNESS};

/// Flash period of the win display, frames (on and off for this long each):
/// an eighth of a second at the game's frame rate.
const WIN_FLASH_FRAMES: u32 = GameConfig::DEFAULT.frame_hz() / 8;

/// The won level's display: the final picture flashing with a full-on
/// screen, an eighth of a second each; `left` counts the frames down.
pub fn win_frame<const W: usize, const H: usize>(last: &Frame<W, H>, left: u32) -> Frame<W, H> {
    if win_flash(left) {
        Frame::filled(MAX_BRIGHTNESS)
    } else {
        *last
    }
}

/// A new record's display: squares growing from the centre to the edge, an
/// eighth of a second each, over and over; `shown` counts the frames since
/// the display began.
pub fn record_frame<const W: usize, const H: usize>(shown: u32) -> Frame<W, H> {
    let (cx, cy) = (W / 2, H / 2);
    let rings = cx.max(cy) as u32 + 1;
    let ring = (shown / WIN_FLASH_FRAMES.max(1) % rings) as usize;
    let mut frame = Frame::new();
    for y in 0..H {
        for x in 0..W {
            if x.abs_diff(cx).max(y.abs_diff(cy)) == ring {
                frame.set(x, y, MAX_BRIGHTNESS);
            }
        }
    }
    frame
}

/// Whether [`win_frame`] shows the full-on screen with `left` frames to go.
pub(crate) fn win_flash(left: u32) -> bool {
    (left / WIN_FLASH_FRAMES.max(1)).is_multiple_of(2)
}

/// Shown while the accelerometer is down: a cross from corner to corner.
pub fn fault_frame<const W: usize, const H: usize>() -> Frame<W, H> {
    let mut frame = Frame::new();
    for y in 0..H {
        let x = if H > 1 { y * (W - 1) / (H - 1) } else { 0 };
        frame.set(x, y, MAX_BRIGHTNESS);
        frame.set(W - 1 - x, y, MAX_BRIGHTNESS);
    }
    frame
}
