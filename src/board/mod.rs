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
// What every board's I²C bus shares: the bus-clear rule.
pub mod i2c;
// The levels region both micro:bits read from flash (`cargo xtask hex --level`).
pub mod levels_region;
