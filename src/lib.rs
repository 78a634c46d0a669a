//! Marble Rolling: the no_std core of a tilt-controlled marble maze.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

/// The firmware's board-agnostic tasks (feature `app`).
#[cfg(feature = "app")]
pub mod app;
pub mod board;
/// Two-button debouncing and the A / B / A+B-hold combinations.
pub mod buttons;
pub mod game;
/// Pin-agnostic LED-matrix frames, BCM scanning and on-time integration.
pub mod matrix;
pub mod physics;
/// World → LED-matrix frame: tiles, blinking goal, anti-aliased marbles, a following viewport.
pub mod render;
/// Accelerometer axis mapping, plausibility, calibration and fault supervision.
pub mod sensor;
/// The accuracy/cost study's scene suite, shared by `cargo accuracy` and the target benchmarks.
pub mod study;
/// Tilt input path: accelerometer sample → filtered, calibrated gravity for the physics.
pub mod tilt;

// Host tools (`tools` feature only): the library stays no_std everywhere else.
#[cfg(feature = "tools")]
extern crate std;
/// Host tools behind the `tools` feature: the simulator and terminal player CLIs.
#[cfg(feature = "tools")]
pub mod host;
