//! Planners.
//!
//! - [`abit`]: ABIT* over settled SE(3) states with non-Markovian anchor histories (Paton et al. V).
//! - [`homotopy`]: homotopy-based planning on tether-demand planes (Abad-Manterola et al.; Tanner et al.).
//! - [`team`]: tethered climbing teams (Morad et al.).

pub mod abit;
pub mod homotopy;
pub mod team;
