//! Homotopy planning on tether-demand planes, host side: scenarios, the closed-loop simulation with a range
//! sensor, and SVG pictures (see `host-sim/doc/homotopy.md`).

pub mod dem;
pub mod dem_report;
pub mod scenarios;
pub mod sim;
pub mod svg;
pub mod tile;
