//! The input path, from what a board reads to the gravity the physics gets:
//!
//! ```text
//! accelerometer ─► sensor: axis map, plausibility, fault supervision ─┐
//! buttons ───────► buttons: debounce, A / B / A+B hold ───────────────┼─► events ─► game
//! terminal keys ─► keys: decoding, key tilt ──────────────────────────┘
//!                          (in the game's session) tilt: calibration, low-pass, stuck check ─► physics
//! ```
//!
//! Everything here is pure: a board feeds bytes, pin levels and samples in,
//! and host tests drive the same code.

pub mod accel_timing;
pub mod axes;
pub mod event;
pub mod keys;
#[cfg(feature = "lsm303agr")]
pub mod lsm303;
pub mod buttons;
pub mod idle;
pub mod pacing;
pub mod race_setup;
pub mod sensor;
pub mod tilt;
