//! Dynamics: how the marble moves (integrate), what a contact does to it (respond),
//! when it next touches something in event stepping (toi), the optional
//! effects a scene may switch on (effects), and the board's motion that one of
//! them follows from the tilt (board_motion).

pub mod board_motion;
pub mod effects;
pub mod integrate;
pub mod respond;
pub(crate) mod toi;
