//! The micro:bit v1's LED wiring: 25 LEDs on a 3 × 9 matrix of GPIO lines.
//!
//! Self-contained on purpose (only `core`, no `crate::` paths): the xtask
//! includes this very file (`#[path]`) to turn the GPIO levels it reads from
//! QEMU's trace back into the 5×5 picture, so the firmware and the check
//! share one table.
//!
//! # The table and its source
//!
//! The micro:bit v1 schematic wires the 5×5 LEDs as 3 row lines (anodes,
//! active high) × 9 column lines (cathodes, active low); two of the 27
//! crossings have no LED. The mapping is the micro:bit runtime's (DAL,
//! `lancaster-university/microbit-dal`):
//!
//! * pins, `inc/drivers/MicroBitDisplay.h`, `MICROBIT_DISPLAY_TYPE ==
//!   MICROBIT_SB2` (the production v1 board): `MICROBIT_DISPLAY_ROW_PINS
//!   P0_13, P0_14, P0_15` and `MICROBIT_DISPLAY_COLUMN_PINS P0_4 … P0_12`;
//! * LEDs, `inc/core/MicroBitMatrixMaps.h`, `microbitDisplayMap` for
//!   `MICROBIT_SB2`: entry `[column × 3 + row]` is the screen point `{x, y}`
//!   of the LED at that crossing (`x` left → right, `y` top → bottom),
//!   `{NO_CONN, NO_CONN}` where there is none:
//!
//! ```text
//!   {0,0},{4,2},{2,4},      column 1: rows 1, 2, 3
//!   {2,0},{0,2},{4,4},      column 2
//!   {4,0},{2,2},{0,4},      column 3
//!   {4,3},{1,0},{0,1},      column 4
//!   {3,3},{3,0},{1,1},      column 5
//!   {2,3},{3,4},{2,1},      column 6
//!   {1,3},{1,4},{3,1},      column 7
//!   {0,3},{NO_CONN,NO_CONN},{4,1},   column 8
//!   {1,2},{NO_CONN,NO_CONN},{3,2}    column 9
//! ```
//!
//! `DAL_MAP` is that table transcribed as it stands; `LED_MAP` (screen →
//! crossing) is derived from it at compile time, and the host tests
//! (`tests/microbit_v1.rs`) check that the 25 LEDs land on 25 distinct
//! crossings and that the unused two are `UNUSED` (row 2 × columns 8 and 9).
//! The nrf-rs `microbit` crate's v1 `LED_LAYOUT` gives the same mapping.

/// Row lines (LED anodes, driven high to light a row).
pub const ROWS: usize = 3;
/// Column lines (LED cathodes, driven low to light an LED of the lit row).
pub const COLS: usize = 9;
/// The screen: 5 × 5 LEDs.
pub const SIZE: usize = 5;

/// GPIO numbers (port 0) of ROW1..ROW3.
pub const ROW_PINS: [u8; ROWS] = [13, 14, 15];
/// GPIO numbers (port 0) of COL1..COL9.
pub const COL_PINS: [u8; COLS] = [4, 5, 6, 7, 8, 9, 10, 11, 12];

/// The lowest row pin: rows are consecutive pins from here.
pub const FIRST_ROW_PIN: u32 = 13;
/// The lowest column pin: columns are consecutive pins from here.
pub(crate) const FIRST_COL_PIN: u32 = 4;
/// Every column bit of a `COLS`-bit mask.
pub(crate) const COL_MASK: u32 = (1 << COLS) - 1;
/// Every row bit of a `ROWS`-bit mask.
pub const ROW_MASK: u32 = (1 << ROWS) - 1;
/// The GPIO `OUT` bits of the matrix (P0.04 ..= P0.15).
pub const MATRIX_PINS: u32 = (ROW_MASK << FIRST_ROW_PIN) | (COL_MASK << FIRST_COL_PIN);

/// The DAL's `microbitDisplayMap` for `MICROBIT_SB2`: `DAL_MAP[column][row]`
/// is the screen point `(x, y)` lit by that crossing, `None` for `NO_CONN`.
pub const DAL_MAP: [[Option<(u8, u8)>; ROWS]; COLS] = [
    [Some((0, 0)), Some((4, 2)), Some((2, 4))],
    [Some((2, 0)), Some((0, 2)), Some((4, 4))],
    [Some((4, 0)), Some((2, 2)), Some((0, 4))],
    [Some((4, 3)), Some((1, 0)), Some((0, 1))],
    [Some((3, 3)), Some((3, 0)), Some((1, 1))],
    [Some((2, 3)), Some((3, 4)), Some((2, 1))],
    [Some((1, 3)), Some((1, 4)), Some((3, 1))],
    [Some((0, 3)), None, Some((4, 1))],
    [Some((1, 2)), None, Some((3, 2))],
];

/// The crossings without an LED, as `(row, column)`, 0-based: ROW2 × COL8
/// and ROW2 × COL9.
pub const UNUSED: [(u8, u8); 2] = [(1, 7), (1, 8)];

/// Screen → crossing: `LED_MAP[y][x]` is the `(row, column)` (0-based) that
/// lights pixel `(x, y)`. Derived from [`DAL_MAP`] at compile time; a pixel
/// the table did not cover would stay at `(u8::MAX, u8::MAX)`, which the host
/// tests rule out.
pub const LED_MAP: [[(u8, u8); SIZE]; SIZE] = {
    let mut map = [[(u8::MAX, u8::MAX); SIZE]; SIZE];
    let mut col = 0;
    while col < COLS {
        let mut row = 0;
        while row < ROWS {
            if let Some((x, y)) = DAL_MAP[col][row] {
                map[y as usize][x as usize] = (row as u8, col as u8);
            }
            row += 1;
        }
        col += 1;
    }
    map
};

/// The screen pixel `(x, y)` that crossing `(row, col)` lights, if any.
pub const fn pixel_of(row: usize, col: usize) -> Option<(u8, u8)> {
    if row < ROWS && col < COLS {
        DAL_MAP[col][row]
    } else {
        None
    }
}

/// The GPIO `OUT` word for one scan step: row `row` (0-based) high, the
/// other rows low; the columns whose bits are set in `lit` low (lit), the
/// rest high. Bits outside [`MATRIX_PINS`] are 0. A row out of range drives
/// no row (all dark).
pub const fn out_word(row: usize, lit: u32) -> u32 {
    let rows = if row < ROWS { 1u32 << row } else { 0 };
    (rows << FIRST_ROW_PIN) | ((!lit & COL_MASK) << FIRST_COL_PIN)
}

/// The `OUT` word with every LED off: rows low, columns high.
pub const DARK: u32 = out_word(ROWS, 0);

/// What the matrix pins of a GPIO level word light: the mask of rows driven
/// high and the mask of columns driven low. An LED is lit when both its row
/// and its column are.
pub const fn decode_levels(levels: u32) -> (u32, u32) {
    let rows = (levels >> FIRST_ROW_PIN) & ROW_MASK;
    let lit = !(levels >> FIRST_COL_PIN) & COL_MASK;
    (rows, lit)
}
