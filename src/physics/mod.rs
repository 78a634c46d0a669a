//! The physics core: the seed's tile maze in fixed point.
//!
//! | seed | what | home |
//! |------|------|------|
//! | eq. 1 | restitution against a moving board | [`dynamics::respond::restitution`] |
//! | eq. 4 | world ↔ tile frame | [`geometry::frame::Frame`] |
//! | eq. 5 | tile `[i, j, k]` → box | [`geometry::tiles::TileLayout::tile_box`] |
//! | eq. 6 | point → tile index | [`geometry::tiles::TileLayout::index_of`] |
//! | eq. 7 | candidate tiles | [`geometry::broadphase::candidates`] |
//! | eq. 8 | marble–tile distance | [`geometry::narrowphase::distance`], [`geometry::narrowphase::contact`] |
//!
//! Geometry (pure queries) is kept apart from dynamics (motion and response);
//! [`world`] is the only stateful part.
//!
//! # Ranges: why no intermediate leaves its type
//!
//! The narrowest format is I8F24 (±128) for the firmware and I16F16 for its
//! precision floor; lengths are in pitches, so the argument holds for every pitch
//! the level format takes (1 to 100 mm).
//!
//! * **The largest level**: 127 × 127 tiles per storey
//!   ([`geometry::grid::MAX_TILES_XZ`]), four storeys (eight tile layers): every
//!   coordinate lies in `[0, 64)` pitch across and `[0, 5)` up, and so does every
//!   difference of two positions, per axis (under 64).
//! * **The largest speed** is 127 pitch/s along any direction with events
//!   (`events::cap_speed`, scaled back along itself), `r/4` per step with fixed
//!   steps; **the largest pull** is [`range::MAX_MG`] (8 g) or, with events, what a
//!   step can add within that speed (`Params::mg_max`). In step units (pitch, pitch
//!   per step) that is `|u| < 1` and `|h| ≤ ½` at 128 steps/s.
//! * **Nothing far is squared.** A product of two positions' difference would not
//!   fit (`|d|²` passes 128 past 11.3 pitch), so every square is of a quantity
//!   first bounded per axis: a marble's offset from a tile in reach (under
//!   `r + tol` plus a step's travel: under 2 pitch, squares under 12), a pair's
//!   separation only after the per-axis test against `2r + tol` plus the step's
//!   relative travel (squares under 48: `events/together.rs`, `pairs.rs`), speeds in
//!   pitch per 1/32 s (components ≤ 4, squares ≤ 48), the quadratics of the time of
//!   impact in step units (squares under 16, `dynamics/toi.rs`). Sums saturate where
//!   a velocity meets a kick (`sat_add`); the board's kick is clamped before it
//!   is added.
//! * **Checked**: `tests/far_pairs.rs` puts two marbles at the largest separations
//!   of the largest grid on every combination of axes (across the storeys too), at
//!   the top speed, on every backend and both steppers, in the test profile (where
//!   overflow panics), and random far pairs against `f64`; the properties
//!   (`step_survives_arbitrary_states`) and the soak drive arbitrary states with
//!   overflow checks on.

pub mod dynamics;
pub mod geometry;
pub mod range;
pub mod scalar;
pub mod vec;
pub mod world;

pub use dynamics::effects::{BoardMotion, Effects};
pub use dynamics::toi::Segment;
pub use geometry::grid::{TileGrid, Tiles};
pub use geometry::tiles::{TileIndex, TileLayout};
pub use scalar::{MicroF32, Scalar};
pub use vec::Vec3;
pub use world::{
    Impacts, Marble, Params, PhysicsSpec, SetupError, StepObserver, StepStats, Stepping, World,
    FLIGHT_BUDGET, IMPACTS_KEPT, MAX_EVENTS,
};

/// The firmware's default scalar (see [`scalar`] for why).
pub type Fx = fixed::types::I8F24;
