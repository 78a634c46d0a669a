//! Dynamics: how the marble moves (integrate), what a contact does to it (respond),
//! when it next touches something in event stepping (toi), and the optional
//! effects a scene may switch on (effects).

pub mod effects;
pub mod integrate;
pub mod respond;
pub mod toi;
