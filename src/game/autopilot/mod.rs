//! The autopilot: tilts the board to roll a marble along the shortest cell path to
//! a goal (demos, `cargo sim --autopilot`, the QEMU demo, end-to-end tests).
//!
//! It produces what a human produces — an accelerometer **reading**
//! ([`AccelMg`](crate::input::axes::AccelMg), board frame; a flat board reads
//! `(0, +1000, 0)`) — so the caller runs it through the same tilt path as a real
//! sensor:
//!
//! ```text
//! let r = autopilot.reading_mg(&game);
//! if let Ok(g) = tilt_filter.push(r) { game.set_gravity_mg(g); }
//! game.frame();
//! ```
//!
//! **Several marbles** share the tilt. The autopilot steers the one whose start is
//! nearest a goal (any marble in a goal wins), and guards every marble against
//! holes: whenever a marble's cell opens onto a hole (or off the board) on the side
//! the tilt pulls it to, that tilt component is limited to what holds the marble in
//! its cell's centre.
//!
//! The plan (a distance field to the goals, made once per level) is
//! `planning`'s; following it frame by frame with a tilt is `control`'s.

pub(crate) mod control;
pub(crate) mod planning;

use planning::FIELD_BYTES;

/// The autopilot for one level (see the module documentation).
#[derive(Clone, Debug)]
pub struct Autopilot {
    /// Distance to the nearest goal mod 3, plus 1, 2 bits per cell (0: unreachable).
    field: [u8; FIELD_BYTES],
    /// Cells along x' and z', and storeys (0 when the maze is too large to plan).
    ncx: u8,
    ncz: u8,
    storeys: u8,
    /// The marble steered.
    marble: u8,
    /// Its start's distance to a goal in cells (`u16::MAX`: no way).
    start_cells: u16,
    /// The in-plane gravity asked for last frame, mg.
    last: [i16; 2],
    /// Extra tilt for a marble that does not move although asked to, mg.
    boost: [i16; 2],
    /// The steered marble's position last frame (q12 pitch).
    last_pos: [i32; 2],
    /// The steered marble's cell and storey last frame (`u8::MAX`: not seen yet)
    /// and its distance to the goal (cells).
    cell: [u8; 3],
    dist: u16,
    /// The least distance reached so far, and the frames since it was reached.
    best: u16,
    stalled: u16,
}

impl Autopilot {
    /// The largest tilt the autopilot asks for (per in-plane axis), milli-g.
    pub const TILT_LIMIT_MG: i32 = 250;
    /// The tilt used only to lift a marble out of a gap it has stopped in (the slot's
    /// edges need about 300 mg).
    pub const ESCAPE_TILT_MG: i32 = 450;
    /// Its size in RAM, bytes.
    pub const RAM_BYTES: usize = core::mem::size_of::<Autopilot>();
}
