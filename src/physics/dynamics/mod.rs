//! Dynamics: how the marble moves (integrate), what a contact does to it (respond),
//! and the optional effects a scene may switch on (effects).

pub mod effects;
pub mod integrate;
pub mod respond;
