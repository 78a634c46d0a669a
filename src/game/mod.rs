//! The game: levels (built-in and generated), the rules that turn physics into
//! won / fell / time-up, the session that feeds them the tilt, and the autopilot.
//! The game loop on top of them, with the picture and the sounds, is
//! [`crate::player`].

pub mod autopilot;
pub mod endless;
pub mod generate;
pub mod ghost;
pub mod level;
pub mod levels;
pub mod levels_region;
pub mod rules;
pub mod session;
pub mod stress;
