//! Where a chip's axes point on its board, in the chip's own terms: the
//! virtual chips turn a board-frame tilt into their raw axes with it, apart
//! from the firmware's axis tables, so a sign error in either shows.

use crate::input::sensor::{AccelMg, Axis, AxisMap, AxisSource};

/// Where a chip's axes point on the board: for each chip axis, the board axis
/// (`x` right, `y` up out of the LEDs, `z` towards the player) it lies along,
/// negated when it points the other way. At rest a chip axis reads the
/// board-frame reading along it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Placement {
    /// The board direction of the chip's `x`.
    pub x: AxisSource,
    /// The board direction of the chip's `y`.
    pub y: AxisSource,
    /// The board direction of the chip's `z`.
    pub z: AxisSource,
}

impl Placement {
    /// The placement a board's firmware table assumes (its inverse): for a
    /// board with no table of the chip's own, where a sign error cannot show.
    pub const fn assumed_by(map: &AxisMap) -> Placement {
        let sources = [map.x, map.y, map.z];
        let board_axes = [Axis::X, Axis::Y, Axis::Z];
        let mut chip = [AxisSource::pos(Axis::X); 3];
        let mut i = 0;
        while i < 3 {
            let slot = match sources[i].axis {
                Axis::X => 0,
                Axis::Y => 1,
                Axis::Z => 2,
            };
            chip[slot] = AxisSource {
                axis: board_axes[i],
                negate: sources[i].negate,
            };
            i += 1;
        }
        Placement {
            x: chip[0],
            y: chip[1],
            z: chip[2],
        }
    }

    /// A board-frame reading in the chip's axes: the values its registers
    /// hold, x, y, z.
    pub const fn raw(&self, board: AccelMg) -> [i32; 3] {
        let board = board.to_array();
        let chip = [self.x, self.y, self.z];
        let mut raw = [0i32; 3];
        let mut i = 0;
        while i < 3 {
            let value = board[match chip[i].axis {
                Axis::X => 0,
                Axis::Y => 1,
                Axis::Z => 2,
            }];
            raw[i] = if chip[i].negate {
                value.saturating_neg()
            } else {
                value
            };
            i += 1;
        }
        raw
    }
}

/// The LSM303AGR on the micro:bit v2, in the chip's terms: its `x` points to
/// the left edge (button A), its `y` to the edge connector (the player), its
/// `z` out of the back (the chip sits on the back of the board). Read off the
/// raw readings of a board held in each orientation, as the micro:bit runtime
/// (CODAL's LSM303 driver with its upside-down coordinate space) and the Rust
/// "micro:bit v2 book" give them: raw x +1 g with the right edge down, raw y
/// +1 g with the logo edge down, raw z +1 g lying screen-down; an axis reads
/// +1 g when it points up. Not derived from the firmware's `AXIS_MAP`.
pub const MICROBIT_V2: Placement = Placement {
    x: AxisSource::neg(Axis::X),
    y: AxisSource::pos(Axis::Z),
    z: AxisSource::neg(Axis::Y),
};

/// A board-frame reading expressed in the chip's axes (x, y, z): the inverse
/// of `map` (which gives each board axis from a sensor axis and a sign).
pub const fn to_sensor_frame(map: &AxisMap, board: AccelMg) -> [i32; 3] {
    let board = board.to_array();
    let mut raw = [0i32; 3];
    let sources = [map.x, map.y, map.z];
    let mut i = 0;
    while i < 3 {
        let value = if sources[i].negate {
            board[i].saturating_neg()
        } else {
            board[i]
        };
        let axis = match sources[i].axis {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        };
        raw[axis] = value;
        i += 1;
    }
    raw
}
