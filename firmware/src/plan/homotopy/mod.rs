//! Homotopy planning on tether-demand planes (Abad-Manterola, Nesnas, Burdick, *Motion Planning on Steep Terrain
//! for the Tethered Axel Rover*; Tanner, Burdick, Nesnas, *Online Motion Planning for Tethered Robots in Extreme
//! Terrain*, ICRA 2013).
//!
//! The tether-demand plane (2D frame: `x` across, `y` upslope) minus its polygonal obstacles is triangulated into a
//! BTM ([`btm`]); paths are classified by L-values ([`lvalue`]); an L-value-constrained A* over triangles
//! enumerates homotopy classes a0 -> g ([`classes`]); each class's sleeve gives its shortest homotopic path (the taut
//! tether) by the funnel algorithm and its intermediate anchors ([`sleeve`]); controllable sets decide passability
//! ([`control`]); Alg. 2 (ascent feasibility) and Alg. 1 (pre-planning, ascent first then a descent in the same
//! sleeve) are in [`plan`]; Alg. 3 (online replanning with local retriangulation) in [`online`]. The terrain model
//! (plane classification, soil regions, `theta_max = asin(mu cot alpha)`) is [`planes`]. Planes, fold lines,
//! unfolding and inflated obstacles from a DEM tile, and routes back in the world frame, are [`dem`]; Axel's holding
//! limit from the core's stability check (next to the point-mass baseline) is [`axel`].
//!
//! Numbers are `f64` inside (complex logarithms of L-values and orientation tests need the headroom; see
//! [`lvalue`]). All storage is fixed-size (capacities in [`crate::config::homotopy`]); the big pieces
//! ([`btm::Btm`] ~0.3 MiB, [`plan::Workspace`] ~0.3 MiB) are owned by the caller. Every loop is bounded by a
//! capacity or a budget; a full arena or an exhausted budget is a typed outcome.
//!
//! Deviation from the brief: capacities are plain consts rather than const generics (one consistent set sized for
//! the papers' problems; change them in `config::homotopy`).

pub mod axel;
pub mod classes;
pub mod btm;
pub mod control;
pub mod dem;
pub mod geo;
pub mod lvalue;
pub mod online;
pub mod plan;
pub mod sleeve;
pub mod planes;

pub use classes::{enumerate_classes, HomotopyClass, SearchArena, SearchOutcome, SearchStart};
pub use btm::{Btm, BtmError, UpdateReport};
pub use geo::{pt, Pt};
pub use lvalue::{polyline_lvalue, LValue};
pub use online::{MapChange, OnlineAction, OnlinePlanner};
pub use plan::{feasibility_check, preplan, Feasibility, Plan, HomotopyParams, Workspace};
pub use sleeve::{anchors, shortest_homotopic_path, Anchor, Path, Sleeve};
pub use planes::{theta_max, HoldLimit, HoldModel, SoilMap};
pub use dem::{DemDescent, DemError, DemParams, DemScratch, HeightTile, RouteError, TileError, WorldRoute};
