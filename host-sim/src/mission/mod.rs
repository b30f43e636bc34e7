//! The closed-loop mission simulator (issue 18): the host side of a tethered descent with the flight software in
//! the loop.
//!
//! - [`params`]: the `[mission]` section of a scenario (execution, sensing, disturbance models, hidden rocks);
//! - [`world`]: the true world (terrain plus rocks; what the rover meets and what the sensor sees);
//! - [`truth`]: the true tether, the statics (tension, margin, the fall judge) and the tether drift;
//! - [`executor`]: each commanded motion executed on the true world in small increments;
//! - [`sensing`]: scans with the localisation error, tether readings, the overview scan from the mast;
//! - [`run`]: one mission over a link; [`link`]: the in-process flight software on the scenario's map;
//! - [`campaign`]: N seeds in parallel and the table; [`faults`]: fault campaigns (issue 24); [`svg`]: the picture.
//!
//! `host-sim/doc/mission.md` describes the models and their gaps.

#[cfg(feature = "sim")]
pub mod campaign;
#[cfg(feature = "sim")]
pub mod executor;
#[cfg(feature = "sim")]
pub mod faults;
pub mod link;
pub mod params;
#[cfg(feature = "sim")]
pub mod run;
#[cfg(feature = "sim")]
pub mod sensing;
#[cfg(feature = "sim")]
pub mod svg;
#[cfg(feature = "sim")]
pub mod truth;
pub mod world;
