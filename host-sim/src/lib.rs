//! # host-sim — the simulator and the operator's tool
//!
//! Worlds (analytic scenes and real terrain), rover and tether truth, sensors, links to the flight software
//! (in-process, or the emulated board in QEMU), field logs (record, replay, MCAP export), campaigns and pictures.
//! The `tetherbot` binary is the CLI over this library.
//!
//! Foundation modules: [`link`] (the host-side [`link::FlightLink`] trait, the in-process link, the recording
//! wrapper), [`session`] (host side of the protocol), [`fieldlog`] (the log format), [`replay`], [`mcap_export`],
//! [`scenario`] (built-in scripted scenarios), [`testkit`] (the bad-input matrix, reusable over any link),
//! [`cli`] (subcommand implementations).

pub mod cli;
pub mod fieldlog;
pub mod link;
pub mod mapcheck;
pub mod mcap_export;
pub mod replay;
pub mod scenario;
pub mod scenario_file;
pub mod sensor;
pub mod session;
pub mod terrain;
pub mod testkit;
pub mod world;
