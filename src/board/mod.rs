//! Board support: the safe, host-testable half of each board.
//!
//! The library is `#![forbid(unsafe_code)]`, so only that half lives here
//! (terminal rendering, arithmetic, argument parsing, pin and axis tables).
//! Register access, interrupt handlers and the executor loop live in the
//! board's firmware crate under `boards/` (`boards/qemu`, `boards/microbit`).

// The QEMU board's pure parts are compiled everywhere too (host tests); its
// virtual matrix needs the firmware tasks (feature `app`).
pub mod qemu;
// The micro:bit v2 board module: pure (pin-free) code, compiled everywhere so
// that plain host `cargo test` covers it.
pub mod microbit;
// The micro:bit v1 board module (nRF51822): pure code, host-tested.
pub mod microbit_v1;
// Shared by boards (each board's folder reaches none of the others'):
// what every board's I²C bus shares: the bus-clear rule.
pub mod i2c;
// The micro:bit's accelerometer link, which the v2 runs and the QEMU board models.
pub mod accel_link;
// The watchdog's rule: every task proves it runs.
pub mod watchdog;
// A model of the LSM303AGR, which the QEMU board carries and the v1's virtual
// bus may carry (a v1.5).
pub mod virtual_lsm303agr;
// The levels region both micro:bits read from flash (`cargo xtask hex --level`).
pub mod levels_region;
// The maze reach and the ghosts' sizes the micro:bit v2 is built to and the
// QEMU board runs too.
pub mod game_sizes;
