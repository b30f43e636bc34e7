//! Capacities, budgets and default parameters of [`crate::plan::tethered`], the tether-aware state space of
//! Paton et al. section V (settled SE(3) states, in-place turns plus straight drives, anchor histories).

/// Sphere-tracing steps of the top-down search for the terrain surface under a sampled (x, y). Each step moves
/// down by the ESDF distance (at least [`SURFACE_MIN_STEP_M`]); 64 steps cover 64 x 1.5 m (the ESDF band) and any
/// surface reached through a 5 cm minimum step over 3.2 m of unbanded space.
pub const SURFACE_TRACE_STEPS: u32 = 64;

/// Smallest step of the surface trace, metres (default 0.05 m: one voxel of the default map).
pub const SURFACE_MIN_STEP_M: f32 = 0.05;

/// Yaws tried when settling the rover under a goal position (the first that settles is the goal state), evenly
/// round from the requested yaw. Default 8 (every 45 degrees).
pub const GOAL_SETTLE_YAWS: u32 = 8;

/// Settling rounds of `TetherSpace::settle_under_axle` (the state whose axle stands at a pose estimate's axle
/// centre, with its heading). Default 4: the first round misses by the axle's offset from its surface point,
/// `r sin(slope)` (0.2 m at 35 degrees), and each round cuts the miss by the change of that offset over it
/// (a few mm on ground the rover can stand on).
pub const AXLE_SETTLE_ROUNDS: u32 = 4;
/// The axle of `TetherSpace::settle_under_axle` is where it was asked when horizontally this close, metres, and its
/// heading within [`AXLE_SETTLE_HEADING_RAD`]. Default 0.005 m (a tenth of the default map's voxel).
pub const AXLE_SETTLE_TOLERANCE_M: f32 = 0.005;
/// Heading tolerance of `TetherSpace::settle_under_axle`, radians. Default 0.005 rad (0.3 degrees).
pub const AXLE_SETTLE_HEADING_RAD: f32 = 0.005;

/// Step of the surface trace through unknown space, metres. Default 0.1 m: no thicker than the observed band
/// round a surface (the map's truncation in front of it, 0.15 m by default, plus the fill under it), so the trace
/// cannot step over an observed surface.
pub const SURFACE_UNKNOWN_STEP_M: f32 = 0.1;
/// Steps of the surface trace through unknown space, at most. Default 128: 12.8 m of unobserved column above the
/// surface (a floor far below a rim or a mast's view).
pub const SURFACE_UNKNOWN_STEPS: u32 = 128;

/// Most interpolated states of one motion (turns and drive together). A motion that would need more is invalid
/// (`MotionFailure::TooLong`): 256 states at the default 0.2 m resolution is a 51 m drive.
pub const MAX_MOTION_STATES: u32 = 256;

/// An anchor closer to the axle than the boom length plus this clearance is within the boom's reach: the tether
/// pulls towards the anchor before it (`plan::tethered::tether_pull_anchor`). Default 0.35 m (the wheel radius:
/// closer than that, the inline boom tip ends at the edge the tether wraps).
pub const BOOM_REACH_CLEARANCE_M: f32 = 0.35;

/// Largest `refine_substeps` accepted (bounds the refinement loop). Default 16.
pub const MAX_REFINE_SUBSTEPS: u32 = 16;

/// Pairs of surface points tried for one catch-boundary sample (`TetherSpace::sample_catch_boundary`) before it
/// reports `NotFound` (the planner then stops sampling that history's boundary until the next batch). Default
/// 512: on the ledge of test 3 about one pair in 110 straddles the pole's tether shadow, so a search fails about
/// once in 100; each pair costs two surface traces and two sweep lines (~150 ESDF queries).
pub const CATCH_PAIR_ATTEMPTS: u32 = 512;

/// Steepest surface a settled wheel may rest on, radians from the horizontal (`plan::tethered::settle_at`).
/// Default 75 degrees (1.309 rad): the 55-degree slope and the edge contacts of its lip pass; a wheel climbing the
/// side of the test-3 pole (the settler tilts the rover 30 degrees against it) does not, and near such poses the
/// settler's answer changes from pose to failure within millimetres, so the map and the true terrain disagree.
/// A contact is steep when both its contact normal and the distance field's gradient at the contact point are
/// steeper than this (`plan::tethered::space::rests_on_steep_surface`: a map's bumps tilt the contact normal alone).
pub const MAX_WHEEL_CONTACT_INCLINE_RAD: f32 = 1.309;

/// Default parameters of the tether-aware space ([`crate::plan::tethered::TetherSpaceParams::DEFAULT`]).
pub mod defaults {
    /// Weight of path length in the objective (per metre of axle travel). Default 1.0.
    pub const W_LENGTH: f64 = 1.0;
    /// Weight of yaw change (per radian of in-place turning). Default 0.25: a half turn costs as much as 0.8 m.
    pub const W_YAW: f64 = 0.25;
    /// Weight of roll (per radian of roll per metre driven). Default 1.0: driving 1 m at 10 degrees of roll costs
    /// 0.17 m extra.
    pub const W_ROLL: f64 = 1.0;
    /// Spacing of interpolated states along a straight drive, metres. Default 0.2 m (a fifth of the track width);
    /// steps over an edge are refined (`REFINE_TILT_RAD`, `REFINE_SUBSTEPS`).
    pub const DRIVE_RESOLUTION_M: f32 = 0.2;
    /// Two consecutive drive states whose rover frames' up axes differ by more than this are refined (the drive
    /// step between them is checked at `REFINE_SUBSTEPS` points). Default 0.1 rad (6 degrees): flat ground and
    /// uniform slopes are never refined, the lip of the 55-degree ledge always is (the margin of the pose that
    /// straddles the lip dips to zero over ~0.1 m of ground, half a drive step; measured on the ledge world).
    pub const REFINE_TILT_RAD: f32 = 0.1;
    /// Sub-steps of a refined drive step. Default 8 (0.025 m at the default 0.2 m drive resolution): the margin
    /// over a sharp lip can dip below zero within a few centimetres, and a map's rounded lip shows that dip only at
    /// about 2.5 cm spacing (the measurement that set it: `host-sim/doc/abit_notes.md`).
    pub const REFINE_SUBSTEPS: u32 = 8;
    /// Distance between the field's surfaces and the true terrain that the states over an edge must tolerate
    /// (`plan::tethered` settles them this far ahead and behind too). Default 0 m: an exact field. A planner on a
    /// map sets about half a voxel (the campaign does).
    pub const SURFACE_UNCERTAINTY_M: f32 = 0.0;
    /// Spacing of interpolated headings of an in-place turn, radians. Default 0.5 rad (29 degrees).
    pub const TURN_RESOLUTION_RAD: f32 = 0.5;
    /// The tether end moves less than this between two interpolated states: anchor prediction is skipped (the
    /// history cannot change). Default 0.01 m.
    pub const TETHER_STILL_M: f32 = 0.01;
    /// Smallest stability margin (friction headroom, see `crate::stability`) an interpolated state must keep.
    /// Default 0.02: 2 % of the rover's weight in reserve on every friction facet for the difference between the
    /// map and the terrain (Axel standing on flat ground has a margin of 0.055).
    pub const MIN_STABILITY_MARGIN: f64 = 0.02;
    /// Half-width of the uniform perturbation of a sampled surface point in x and y, metres. Default 0.05 m.
    pub const SAMPLE_PERTURBATION_M: f32 = 0.05;
    /// A state within this distance (in x, y) of the planning bounds may connect to an off-map goal (Paton et al.
    /// VI-B). Default 1.0 m.
    pub const OFF_MAP_EDGE_M: f32 = 1.0;
    /// Two anchor histories are compatible when their wraps' representative anchors are within this distance.
    /// Default 0.3 m (3 voxels of the campaign's map, 6 of the flight map).
    pub const ANCHOR_MATCH_M: f32 = 0.3;
    /// Consecutive anchors closer than this belong to one wrap (one obstacle the tether bends around). Default
    /// 0.6 m: more than the diameter of the ledge's 0.5 m pole, less than the distance between distinct obstacles.
    pub const ANCHOR_CLUSTER_M: f32 = 0.6;
    /// Largest total bend of the tether over its anchors, radians. Default 1.5 pi (270 degrees): enough to wrap
    /// behind a pole and come back over the lip of a ledge (Paton et al. test 3, about 220 degrees), not enough to
    /// circle an obstacle (a full turn multiplies the tension across the wrap by exp(2 pi mu), 6.6 at mu = 0.3).
    pub const MAX_TETHER_BEND_RAD: f32 = 1.5 * core::f32::consts::PI;
    /// Samples on surfaces tilted more than this face along the fall line (downhill), radians. Default 0.35 rad
    /// (20 degrees): on gentler ground Axel can stand at any heading.
    pub const FALL_LINE_TILT_RAD: f32 = 0.35;
    /// Half-width of the uniform yaw perturbation about the fall line, radians. Default 0.15 rad (8.6 degrees):
    /// within the +-15 degrees that Axel holds on the 55-degree slope.
    pub const FALL_LINE_YAW_SPREAD_RAD: f32 = 0.15;
    /// Largest distance between the two surface points of a catch-boundary pair, metres. Default 0.5 m (half a
    /// rover length): the sample lands within 0.25 m of the boundary of the tether shadow, and a 0.6 m shadow such
    /// as the one the ledge's pole casts is straddled.
    pub const CATCH_PAIR_RADIUS_M: f32 = 0.5;
    /// Anchor prediction treats unobserved space as free (`TetherSpaceParams::tether_through_unobserved`). Default
    /// false (Paton et al.: unknown space is unsafe); the navigator sets it (`TetherSpaceParams::ONBOARD`).
    pub const TETHER_THROUGH_UNOBSERVED: bool = false;
}
