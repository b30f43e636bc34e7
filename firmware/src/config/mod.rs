//! Every capacity and every budget of the flight software, in one place.
//!
//! One submodule per part of the core, so the numbers sit next to each other and next to their reasons. Arena
//! sizes are `usize` consts used as const-generic arguments; budgets are iteration counts. Change a number here,
//! never a literal in an algorithm. (The capacities of the benchmark workloads are not flight settings: they are
//! `workloads::config`, in `firmware/workloads/`.)

pub mod abit;
pub mod exec;
pub mod homotopy;
pub mod map;
pub mod nav;
pub mod protocol;
pub mod rover;
pub mod stability;
pub mod team;
pub mod tethered;
pub mod tether;
