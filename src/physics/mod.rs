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

pub mod dynamics;
pub mod geometry;
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
    IMPACTS_KEPT, MAX_EVENTS,
};

/// The firmware's default scalar (see [`scalar`] for why).
pub type Fx = fixed::types::I8F24;
