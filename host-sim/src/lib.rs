//! # host-sim — the simulator and the operator's tool
//!
//! Worlds (analytic scenes and real terrain), rover and tether truth, sensors, links to the flight software
//! (in-process, or the emulated board in QEMU), field logs (record, replay, MCAP export), campaigns and pictures.
//! The `tetherbot` binary is the CLI over this library.

pub mod cli;
pub mod mapcheck;
pub mod scenario_file;
pub mod sensor;
pub mod terrain;
pub mod world;
