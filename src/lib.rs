//! Marble Rolling: the no_std core of a tilt-controlled marble maze.
//!
//! Data flows one way: board → [`input`] → [`game`] (with its [`physics`]) →
//! [`render`] → [`matrix`] (the display), and [`sound`] beside the picture;
//! the [`player`] runs that loop a frame at a time, above all of them;
//! imports point down the layers of docs/architecture.md (`tests/layers.rs`
//! checks them). The [`board`] modules hold the safe,
//! host-tested half of each board; the firmware's tasks are `app` (feature
//! `app`); best times live in flash through `records` (feature `records`).
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod physics;
pub mod game;
pub mod input;
pub mod render;
pub mod matrix;
pub mod sound;
pub mod player;
pub mod race;
#[cfg(feature = "records")]
pub mod records;
#[cfg(feature = "app")]
pub mod app;
pub mod board;
pub mod study;

// Host tools (`tools` feature only): the library stays no_std everywhere else.
#[cfg(feature = "tools")]
extern crate std;
#[cfg(feature = "tools")]
pub mod host;
