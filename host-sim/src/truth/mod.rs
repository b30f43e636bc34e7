//! Simulator-side ground truth computed from a world's exact geometry (never from the flight software's map).
//!
//! [`solid`]: a world's exact geometry as primitive solids; [`tether`]: the closed-form true tether of the ledge
//! worlds (lip, pole), kept as the oracle of [`taut`], the general true tether on every world.

pub mod solid;
#[cfg(feature = "sim")]
pub mod taut;
pub mod tether;
