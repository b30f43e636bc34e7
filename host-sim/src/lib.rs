//! # host-sim — the simulator and the operator's tool
//!
//! Worlds (analytic scenes and real terrain), rover and tether truth, sensors, links to the flight software
//! (in-process, or the emulated board in QEMU), field logs (record, replay, MCAP export), campaigns and pictures.
//! The `tetherbot` binary is the CLI over this library.
//!
//! Foundation: [`link`] (the host-side [`link::FlightLink`] trait, the in-process link, the recording wrapper),
//! [`qemu`] (the emulated flight computer as a `FlightLink`), [`session`] (host side of the protocol),
//! [`fieldlog`] (the log format), [`replay`], [`mcap_export`], [`scripted`] (built-in scripted scenarios),
//! [`testkit`] (the bad-input matrix, reusable over any link), [`cli`] (subcommand implementations).
//!
//! Worlds and sensing: [`world`] (ground truth: ledge, crater wall, height maps), [`terrain`] (GeoTIFF, Esri ASCII,
//! NumPy, OBJ import; PLY, PCD, LAS/LAZ point clouds thinned to the flight scan), [`scenario`] (scenario files,
//! TOML), [`sensor`] (range sensor), [`truth`] (the true tether), [`mapcheck`] (onboard map against ground truth).
//!
//! Campaigns: [`campaign`] (Paton et al.'s Table I), [`mission::campaign`], [`shard`] (a campaign split over a
//! cluster and merged back, byte for byte), [`soak`] (a long mission across the sequence-number wrap).
//!
//! Planning: [`harness`] (every planner on every shared problem), [`homotopy`] (tether-demand planes, closed
//! loop), [`team`] and [`movingai`] (tethered climbing teams, grid benchmarks).

#[cfg(feature = "sim")]
pub mod campaign;
#[cfg(feature = "sim")]
pub mod physics;
#[cfg(feature = "sim")]
pub mod cli;
pub mod fieldlog;
pub mod harness;
pub mod homotopy;
pub mod link;
pub mod mapcheck;
#[cfg(feature = "sim")]
pub mod mcap_export;
pub mod mission;
pub mod movingai;
pub mod qemu;
pub mod replay;
pub mod scenario;
pub mod scripted;
pub mod sensor;
pub mod session;
pub mod shard;
#[cfg(feature = "sim")]
pub mod soak;
pub mod team;
pub mod terrain;
pub mod testkit;
pub mod truth;
pub mod world;
