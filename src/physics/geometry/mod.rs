//! Geometry: where tiles are and how far the marble is from them. Pure queries, no
//! state, no time: data flows tiles → broadphase → narrowphase → `dynamics`.

pub mod broadphase;
pub mod frame;
pub mod grid;
pub mod narrowphase;
pub(crate) mod sweep;
pub mod tiles;
