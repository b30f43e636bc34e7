//! Capacities, budgets and parameters of [`crate::plan::team`] (Morad, Kalita, Thangavelautham, IEEE Aerospace
//! 2018: tethered climbing teams of SphereX robots).
//!
//! Arena sizes are `usize` consts used as const-generic arguments or as the minimum length of storage lent by the
//! caller; parameters that a mission may tune at run time live in [`TeamParams`] with documented defaults.

use crate::geom::Real;

/// Robots in the team. Default 4: the "x" configuration of section III (four robots, four tethers, one hub).
pub const TEAM_SIZE: usize = 4;

/// Range points per scene (one scan of one robot). Default 4096: the paper's lidar scan had ~30 000 points for a
/// 5.6 m wall; a robot's planning scene at hop scale needs far fewer (the surface grid below is 48 x 48), and
/// 4096 points x 28 bytes stays under 120 KiB of SRAM.
pub const SCENE_MAX_POINTS: usize = 4096;

/// Neighbours used for a point's normal (plane fit to the point and its k nearest neighbours, section V-A.2).
/// Default 8: enough for a stable 3 x 3 covariance, small enough for a bounded search.
pub const KNN_K: usize = 8;

/// Buckets of the kNN index per axis of the scene's plane (a fixed 2-D bucket grid). Default 32 (1024 buckets).
pub const KNN_BUCKETS_PER_AXIS: usize = 32;

/// Surface grid cells per axis (the bounded reconstruction: a height/normal grid over the scene plane).
/// Default 48: 2304 surface vertices, 1 m cells for a 48 m scene (10 m hops need >= 10 cells per hop radius).
pub const SURFACE_CELLS_PER_AXIS: usize = 48;

/// Surface vertices = grid cells.
pub const SURFACE_MAX_VERTICES: usize = SURFACE_CELLS_PER_AXIS * SURFACE_CELLS_PER_AXIS;

/// Vertices kept in the hop graph after culling. Default 512: 15 % of the 2304 surface vertices is 346; the rest is
/// headroom for a caller that keeps a larger fraction.
pub const GRAPH_MAX_VERTICES: usize = 512;

/// Directed edges in the hop graph. Default 32768: 512 vertices x 64 neighbours within a hop.
pub const GRAPH_MAX_EDGES: usize = 32768;

/// Hops in one robot's local path. Default 64.
pub const PATH_MAX_HOPS: usize = 64;

/// Cells of the global grid of scenes that the board keeps in static memory (the host lends larger storage for
/// Moving AI maps). Default 64 x 64 = 4096 cells (47 bytes per cell: ~190 KiB of D* Lite state).
pub const GLOBAL_GRID_MAX_CELLS: usize = 64 * 64;

/// Bisection steps of the hub motion at the end of a round (`plan::team::formation::Team::hub_motion`: how far
/// towards the attached robots' centroid the hub may move with every leg within r_max). Default 24: the step
/// fraction in [0, 1] is then resolved to 2^-24, the spacing of `f32` values just below 1.
pub const HUB_BISECTION_STEPS: usize = 24;

/// Jacobi sweeps of the 3 x 3 symmetric eigen-solver of a point's normal (`plan::team::scene`, plane fit of
/// section V-A.2). Default 32: a 3 x 3 matrix converges in fewer than 10; past the bound the fit reports
/// non-convergence instead of looping.
pub const EIGEN_MAX_SWEEPS: usize = 32;

/// Tunable parameters of the team planner (all lengths metres).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TeamParams {
    /// Maximum hop length h_max. Default 10 m (section VI, Fig. 15: 10 m hops on the 500 m scaled rock wall;
    /// Fig. 16 on Itokawa used 30 m).
    pub h_max: Real,
    /// Tether length r_max (hub to robot). Default 15 m (not given in the paper; 1.5 h_max keeps the "x" open).
    pub r_max: Real,
    /// Margin subtracted from h_max and r_max inside the planner for the difference between the reconstructed
    /// surface and where the robot really grips. Default 0.5 m.
    pub landing_margin: Real,
    /// Fraction of surface vertices kept after culling, per mille. Default 150 (the paper's 15 %).
    pub keep_permille: u16,
    /// Weight of relative height in the anchor score. Default 1.0.
    pub w_relative_height: Real,
    /// Weight of flatness (local plane-fit residual) in the anchor score. Default 1.0.
    pub w_flatness: Real,
    /// Depth below the local plane (metres) at which the relative-height term reaches 1. Default 1 m.
    pub relief_scale: Real,
    /// Residual (metres RMS) at which the flatness term reaches 1. Default 0.5 m.
    pub flatness_scale: Real,
    /// Radius (metres) of the neighbourhood for relative height and flatness. Default 3 m.
    pub score_radius: Real,
    /// Extra score for a vertex filled in by the reconstruction (not observed). Default 0.5.
    pub unobserved_penalty: Real,
    /// Metres of path per unit of anchor score in the edge loss L'_ab = d_ab + risk_m * r_b. Default 5 m.
    pub risk_m: Real,
    /// Reconstruction fills unobserved cells at most this many cells from an observed one. Default 4.
    pub fill_max_cells: u16,
    /// Gauss-Seidel sweeps of the membrane fill (the bounded stand-in for the Poisson solve). Default 30.
    pub fill_sweeps: u16,
    /// A* expansions per local plan. Default 4096.
    pub astar_budget: u32,
}

impl TeamParams {
    /// The defaults documented on each field (rock-wall scale, Fig. 15).
    pub const DEFAULT: TeamParams = TeamParams {
        h_max: 10.0,
        r_max: 15.0,
        landing_margin: 0.5,
        keep_permille: 150,
        w_relative_height: 1.0,
        w_flatness: 1.0,
        relief_scale: 1.0,
        flatness_scale: 0.5,
        score_radius: 3.0,
        unobserved_penalty: 0.5,
        risk_m: 5.0,
        fill_max_cells: 4,
        fill_sweeps: 30,
        astar_budget: 4096,
    };
}

impl Default for TeamParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Walls (blocked crossings between two scenes) the team mission records for its report
/// (`plan::team::mission`). Default 64: more walls than that are still given to D* Lite (its grid holds them),
/// only the record is full.
pub const MISSION_MAX_WALLS: usize = 64;

/// Cells of the D* Lite route the team mission records (the cells its start moved through). Default 256.
pub const MISSION_MAX_ROUTE: usize = 256;

/// Budgets and thresholds of the team mission (`plan::team::mission`, Morad et al. sections V-A.6 and V-A.7).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MissionParams {
    /// Rounds (every attached robot has had its turn, then the hub moves) before `BudgetExhausted`. Default 200.
    pub max_rounds: u32,
    /// Hops commanded before `BudgetExhausted`. Default 2000.
    pub max_hops: u32,
    /// D* Lite expansions per (re)plan. Default 20 000 (a 64 x 64 grid of scenes needs at most 4096 per plan).
    pub dstar_budget: u32,
    /// Rounds in a row without progress towards the next scene before the crossing becomes a wall. Default 2
    /// (one round without progress can be a hub held back by a laggard; two is a crossing the local planners
    /// cannot make — the crevasse of Fig. 12).
    pub stall_rounds: u16,
    /// Rounds in a row without progress in the goal's scene before the mission gives up
    /// (`Blocked(GoalUnreachable)`). Default 6: there is no other route to try there, so giving up is final and
    /// waits longer than a wall does; near the goal the hub's steps shrink as the robots reach their slots.
    pub goal_stall_rounds: u16,
    /// Progress that counts, as a fraction of h_max: the hub must get this much closer to the next scene's
    /// waypoint in a round. Default 0.1 (1 m with 10 m hops).
    pub progress_fraction: Real,
    /// Radius of the scan points averaged for a waypoint's height over the scene plane, as a fraction of the
    /// scene (cell) size. Default 0.25.
    pub waypoint_radius_fraction: Real,
}

impl MissionParams {
    /// The defaults documented on each field.
    pub const DEFAULT: MissionParams = MissionParams {
        max_rounds: 200,
        max_hops: 2000,
        dstar_budget: 20_000,
        stall_rounds: 2,
        goal_stall_rounds: 6,
        progress_fraction: 0.1,
        waypoint_radius_fraction: 0.25,
    };
}

impl Default for MissionParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}
