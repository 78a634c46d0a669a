//! The game: levels (built-in and generated), the rules that turn physics into
//! won / fell / time-up, and the autopilot.

pub mod autopilot;
pub mod generate;
pub mod ghost;
pub mod player;
pub mod level;
pub mod levels;
pub mod rules;
pub mod session;
pub mod stress;
