//! The physics' input ranges, in units its callers speak: what the tilt path must
//! stay within to reach the world unchanged. A leaf module, so that the input
//! layer can size its own bounds from them without reaching into the world.

/// The largest pull the physics takes per axis (milli-g): 8 g. With the event
/// stepper a level may take less (`Params::mg_max`, when a step's `a·dt` would not
/// fit the number format); `World::set_gravity_mg` holds every pull to its level's
/// bound.
pub const MAX_MG: i32 = 8_000;
