//! Every capacity and every budget of the flight software, in one place.
//!
//! One submodule per part of the core, so the numbers sit next to each other and next to their reasons. Arena
//! sizes are `usize` consts used as const-generic arguments; budgets are iteration counts. Change a number here,
//! never a literal in an algorithm. (The capacities of the benchmark workloads are not flight settings: they are
//! `workloads::config`, in `firmware/workloads/`.)
//!
//! ## Where a parameter struct lives
//! - A struct that several parts of the core read is defined here: the rover model ([`rover::RoverParams`], read
//!   by `rover`, `plan::tethered` and `nav`), the map ([`map::MapConfig`]), the climbing team
//!   ([`team::TeamParams`], read by every `plan::team` module).
//! - A struct that one algorithm owns is defined with that algorithm, and its default values are named constants
//!   here: `plan::abit::AbitParams` (defaults in [`abit`]), `plan::tethered::TetherSpaceParams` ([`tethered`]),
//!   `plan::homotopy::HomotopyParams` ([`homotopy`]).
//! - The wire's configuration sections (`protocol::RoverConfig`, ...) are messages, not settings: they are defined
//!   in `protocol` and checked there.

pub mod abit;
pub mod exec;
pub mod homotopy;
pub mod map;
pub mod mission;
pub mod nav;
pub mod protocol;
pub mod rover;
pub mod stability;
pub mod team;
pub mod tethered;
pub mod tether;
