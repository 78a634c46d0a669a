//! The game: levels (built-in and generated), the rules that turn physics into
//! won / fell / time-up, the session that feeds them the tilt, and the autopilot.
//!
//! [`player`] is the game loop on top of them: it drives the picture
//! ([`crate::render`]) and the sounds ([`crate::sound`]), which read the levels
//! and the rules here, so it sits above both in the import layers
//! (docs/architecture.md) although it lives in this directory.

pub mod autopilot;
pub mod endless;
pub mod generate;
pub mod ghost;
pub mod player;
pub mod level;
pub mod levels;
pub mod levels_region;
pub mod rules;
pub mod session;
pub mod stress;
