//! Simulator-side ground truth computed from a world's exact geometry (never from the flight software's map).

pub mod tether;
