//! Planners.
//!
//! - [`space`]: the planner abstractions (OMPL's split: state space, validity checker, motion validator,
//!   objective, goal region, problem definition, budget, status) with non-Markovian attachments.
//! - [`geometric`]: R^n with box obstacles — the shared geometric problems (wall with a gap, 3D box world).
//! - [`abit`]: ABIT* over settled SE(3) states with non-Markovian anchor histories (Paton et al. V).
//! - [`heap`]: the fixed-capacity indexed binary min-heap, the open list of a search (ABIT*'s edge queue).
//! - [`homotopy`]: homotopy-based planning on tether-demand planes (Abad-Manterola et al.; Tanner et al.).
//! - [`team`]: tethered climbing teams (Morad et al.).
//! - [`tethered`]: the tether-aware state space of Paton et al. IV-V (settled SE(3) states, anchor histories,
//!   stability-checked motions) for [`abit`].

pub mod abit;
pub mod heap;
pub mod geometric;
pub mod homotopy;
pub mod space;
pub mod team;
pub mod tethered;
