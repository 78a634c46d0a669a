//! The input path, from what a board reads to the gravity the physics gets:
//!
//! ```text
//! accelerometer ─► sensor: axis map, plausibility, fault supervision ─┐
//! buttons ───────► buttons: debounce, A / B / A+B hold ───────────────┼─► events ─► game
//! terminal keys ─► keys: decoding, key tilt ──────────────────────────┘
//!                          (in the game's session) tilt: [plausibility], stuck check, low-pass,
//!                                                  calibration ─► physics
//! ```
//!
//! # One tilt path, and the stages a source skips
//!
//! Every reading is an [`axes::AccelMg`] (board frame, mg), and every one
//! reaches the physics through the game's session and its
//! [`tilt::TiltFilter`], which makes it a [`tilt::GravityMg`]: a sensor's
//! sample ([`sensor::TiltPipeline::tilt`]), the keys' tilt, the autopilot's, a
//! trace's, a ghost's and a race opponent's. One rule says which
//! readings are believed (`plausible::Plausibility::judge`), asked once of each
//! reading (a sensor's sample by its supervision, which counts a refused one as
//! a fault; any other on entry to the filter), and no stage clamps: a believed
//! reading keeps to ±[`plausible::MAX_READING_MG`] per axis, so its gravity is
//! within the physics' range as it is (the world holds it to its level's
//! bound). What a source skips is said here and set in one place:
//!
//! | stage | sensor | keys, autopilot, trace, ghost | where it is set |
//! |---|---|---|---|
//! | axis map | yes | no: made in the board frame | [`sensor::TiltPipeline`] |
//! | plausibility | yes, once: by the supervision (not again on entry: [`tilt::TiltConfig::SENSOR`]) | yes, on entry (an autopilot on a board's sensor session is not judged: its readings are 1 g by construction) | [`tilt::TiltConfig::plausibility`] |
//! | supervision | yes | no: nothing to re-initialise | [`sensor::TiltPipeline`] |
//! | stuck check | yes (the QEMU board's keys and virtual chip share one setting: no) | no: repeats are normal | [`tilt::TiltConfig::stuck_samples`] (0 in `game::session::SYNTHETIC_TILT`) |
//! | low-pass, calibration | yes | yes | [`tilt::TiltConfig`] |
//!
//! Everything here is pure: a board feeds bytes, pin levels and samples in,
//! and host tests drive the same code.

pub(crate) mod accel_timing;
pub mod axes;
pub mod event;
pub mod keys;
#[cfg(feature = "lsm303agr")]
pub mod lsm303;
pub mod buttons;
pub mod idle;
pub mod pacing;
pub(crate) mod plausible;
pub mod race_setup;
pub mod sensor;
pub mod tilt;
