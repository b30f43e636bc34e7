//! Planners.
//!
//! - [`space`]: the planner abstractions (OMPL's split: state space, validity checker, motion validator,
//!   objective, goal region, problem definition, budget, status) with non-Markovian attachments.
//! - [`abit`]: ABIT* over settled SE(3) states with non-Markovian anchor histories (Paton et al. V).
//! - [`heap`]: the one indexed binary min-heap (fixed capacity, or over lent storage): the open list of every
//!   search (ABIT*'s edge queue, the homotopy and bounded-leg A*, D* Lite).
//! - [`status`]: the status vocabulary every planner reports in (exact / approximate / no solution / invalid input).
//! - [`homotopy`]: homotopy-based planning on tether-demand planes (Abad-Manterola et al.; Tanner et al.).
//! - [`team`]: tethered climbing teams (Morad et al.).
//! - [`tethered`]: the tether-aware state space of Paton et al. IV-V (settled SE(3) states, anchor histories,
//!   stability-checked motions) for [`abit`].
//! - [`rng`]: [`SplitMix64`], the flight random generator (Steele, Lea, Flood 2014).
//!
//! The R^n box-obstacle test problems of [`abit`] and the benchmark workloads are not flight code: they are the
//! `workloads` crate (`firmware/workloads/`).

pub mod abit;
pub mod heap;
pub mod homotopy;
pub mod rng;
pub mod space;
pub mod status;
pub mod team;
pub mod tethered;

pub use rng::SplitMix64;
