//! Marble Rolling: the no_std core of a tilt-controlled marble maze.
//!
//! Data flows one way: board → [`input`] → [`game`] (with its [`physics`]) →
//! [`render`] → [`matrix`] (the display). The [`board`] modules hold the safe,
//! host-tested half of each board; the firmware's tasks are [`app`].
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod physics;
pub mod game;
pub mod input;
/// World → LED-matrix frame: tiles, blinking goal, anti-aliased marbles, a following viewport.
pub mod render;
/// Pin-agnostic LED-matrix frames, BCM scanning and on-time integration.
pub mod matrix;
/// The firmware's board-agnostic tasks and the links between them (feature `app`).
#[cfg(feature = "app")]
pub mod app;
pub mod board;
/// The accuracy/cost study's scene suite, shared by `cargo accuracy` and the target benchmarks.
pub mod study;

// Host tools (`tools` feature only): the library stays no_std everywhere else.
#[cfg(feature = "tools")]
extern crate std;
/// Host tools behind the `tools` feature: the simulator and terminal player CLIs.
#[cfg(feature = "tools")]
pub mod host;
