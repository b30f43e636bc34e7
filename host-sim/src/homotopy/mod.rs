//! Homotopy planning on tether-demand planes, host side: scenarios, the closed-loop simulation with a range
//! sensor, and SVG pictures (see `host-sim/doc/homotopy.md`).

pub mod scenarios;
pub mod sim;
pub mod svg;
