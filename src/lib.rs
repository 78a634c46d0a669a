//! Marble Rolling: the no_std core of a tilt-controlled marble maze.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod physics;
