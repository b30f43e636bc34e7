//! Capacities and budgets of on-board goal planning in [`crate::nav`]: the tether-aware ABIT* of Paton et al.
//! section V ([`crate::plan::abit`] over [`crate::plan::tethered`]) run on the onboard map.
//!
//! The flight computer (mps2-an500) holds these arenas in SRAM `.bss` (the map's block pool fills the PSRAM); the
//! sizes below keep the navigator's planning storage at about 1 MiB (`NavPlanStorage`, see `crate::nav`).

use crate::geom::Real;

/// Nodes of the on-board ABIT* arena (start, goals, samples and tree vertices). Default 512: five batches of
/// [`SAMPLES_PER_BATCH`] with room for goals and history twins; from the fourth batch on, before a solution,
/// unconnected samples make room for new ones (`config::abit::ROOM_FOR_BATCHES`). A tethered node carries its anchor history (~0.8 KiB),
/// so the 4096 of `config::abit` would need 4 MiB.
pub const NODE_CAPACITY: usize = 512;
/// Queued edges of the on-board ABIT* arena. Default 4096 (k-nearest with k ~ 15-20 at a few hundred states).
pub const EDGE_QUEUE_CAPACITY: usize = 4096;
/// ABIT*'s own edge memo (OMPL's white/black lists) on board. Default 256 entries (each carries an anchor
/// history); a full memo only costs repeated edge checks.
pub const EDGE_MEMO_CAPACITY: usize = 256;
/// New motion checks after which a `plan_step` call stops (after at least one new iteration), whatever its
/// iteration allowance. Default 1: a motion check is tens of settles, anchor predictions and stability LPs (~8 M
/// instructions each on the emulated Cortex-M7), so one per executive step keeps a step well inside the board's
/// 2 s watchdog.
pub const MOTION_CHECKS_PER_STEP: u32 = 1;
/// Samples per ABIT* batch on board when `Configure.planner.batch_size` asks for more. Default 100 (OMPL's).
pub const SAMPLES_PER_BATCH: u32 = 100;
/// ABIT* sample draws per `plan_step` call while a batch is drawn (`AbitParams::draws_per_step`). Default 20: a draw
/// settles a sample and checks its stability (a few ms on the host); a whole batch of 100 samples (up to 200 draws)
/// in one executive step took 0.4-0.8 s on the host and tens of seconds on the emulated board. The search is the
/// same draw for draw; only where the steps end moves.
pub const DRAWS_PER_STEP: u32 = 20;
/// Largest iteration budget of one goal (the goal request's `max_iterations` is capped to it). Default 750 (the
/// budget of Paton et al.'s Table I).
pub const MAX_PLAN_ITERATIONS: u32 = 750;
/// States of the kept best path (start to goal). Default 64: a path of 64 states of up to a few metres each.
pub const PATH_CAPACITY: usize = 64;
/// Motion primitives of a plan: a turn, a drive and a turn per path segment. Default `3 * (PATH_CAPACITY - 1)`.
pub const MOTION_CAPACITY: usize = 3 * (PATH_CAPACITY - 1);
/// Turns smaller than this are not commanded, radians. Default 1e-3 rad (0.06 degrees).
pub const MIN_TURN_RAD: f32 = 1e-3;
/// Drives shorter than this are not commanded, metres. Default 1e-3 m.
pub const MIN_DRIVE_M: f32 = 1e-3;
/// Margin added around the observed map's extent in `z` for the planning bounds, metres. Default 0.5 m, so the
/// surface trace starts above the highest observed block.
pub const BOUNDS_Z_MARGIN_M: f32 = 0.5;
/// The planning window: the planning bounds are the map's extent cut to the horizontal box spanned by the start and
/// the goal, grown by this margin on every side, metres. Default 3.0 m (three Axel lengths: room for detours
/// round rocks and for traverses that keep the tether off an edge). A scan from a mast observes far beyond the
/// descent; sampling all of it wastes most samples on terrain no plan to this goal would use.
pub const PLAN_WINDOW_MARGIN_M: f32 = 3.0;
/// Footprint ring points (of `config::rover::FOOTPRINT_POINTS` = 8) that may lie in unobserved space when the
/// navigator settles the rover on its map (`RoverParams::footprint_unobserved_max`). Default 4 (half the ring):
/// far from the sensor, rays leave one- and two-voxel stripes unobserved, and a 0.5 m ring often crosses one.
pub const FOOTPRINT_UNOBSERVED_MAX: u32 = 4;
/// Report the tree vertex closest to the goal as an approximate solution when no exact one exists (OMPL's
/// approximate solutions). Default true: a goal behind an unpassable ledge yields the best reachable plan,
/// reported as `ApproximateSolution`, never as exact.
pub const TRACK_APPROXIMATE: bool = true;
/// Mass fraction of the rover's `Configure.rover.mass_kg` carried by the boom (the rest is the body at the axle).
/// Default 0.2 (`config::rover::RoverParams::AXEL`: 10 of 50 kg).
pub const BOOM_MASS_FRACTION: f32 = 0.2;

/// Radius, in voxels, of the zone round a start that the map refuses (within its extra voxel of body clearance of a
/// rock that appeared beside the rover, or a wheel against the rock's side) where states settle with the rover's own
/// clearance and, if the start needed it, a steep wheel contact (`plan::tethered::StartEscape`, `nav::planning`). Default 2: the start is less than one voxel into the extra clearance, so a motion leaves it
/// within the zone when it heads up to 60 degrees off the direction straight away from the obstacle.
pub const START_ESCAPE_VOXELS: Real = 2.0;

/// Half width of the descent corridor the navigator segments from an uploaded tile for a `PlannerChoice::Homotopy`
/// goal (`DemParams::corridor_half_width_m`), metres. Default 6.0 m (the host presets' default: ten Axel tracks
/// either side of the root-anchor-to-goal line).
pub const HOMOTOPY_CORRIDOR_HALF_WIDTH_M: f64 = 6.0;
/// Longest leg of a homotopy route driven by one tethered ABIT* plan, metres: a longer stretch of the route is cut
/// into legs of at most this length. Default 5.0 m (ABIT*'s planning window is the start-goal box grown by
/// `PLAN_WINDOW_MARGIN_M`; beyond a few metres the onboard map ahead is mostly unobserved).
pub const HOMOTOPY_LEG_MAX_M: f32 = 5.0;
/// Route waypoints nearer than this to the previous leg goal are skipped, metres. Default 1.0 m (two wheel
/// diameters: the route's fold-line breaks are metres apart, the descent's bends closer).
pub const HOMOTOPY_LEG_MIN_M: f32 = 1.0;
/// Legs of one homotopy route. Default 32 (160 m of route at `HOMOTOPY_LEG_MAX_M`).
pub const HOMOTOPY_MAX_LEGS: usize = 32;
/// Goal tolerance of an intermediate leg, metres (the final leg uses the goal request's). Default 0.5 m (the
/// mission's default goal tolerance scale: the next leg starts from wherever the rover settled).
pub const HOMOTOPY_LEG_TOLERANCE_M: f32 = 0.5;
/// A tracked anchor farther than this from every anchor the route expects is logged as a disagreement between the
/// onboard map and the tile, metres. Default 1.0 m (the footprint inflation of the tile's obstacles is 0.61 m).
pub const HOMOTOPY_ANCHOR_AGREEMENT_M: f32 = 1.0;
/// Global replans of one homotopy goal (Tanner et al. Alg. 3 on board: a leg without a path blocks its goal region
/// in the BTM and the route is planned again). Default 3 (each moves the route off one more blocked region).
pub const HOMOTOPY_MAX_GLOBAL_REPLANS: u32 = 3;
/// Radius of the obstacle a failed leg adds round its goal in the unfolded BTM, metres. Default 1.0 m (Axel's
/// footprint radius 0.61 m, as the tile's obstacles are inflated, plus the leg tolerance's scale).
pub const HOMOTOPY_BLOCK_RADIUS_M: f64 = 1.0;

/// Rings of positions round a goal position where the rover does not settle, searched for a goal state within the
/// goal's tolerance (`nav::planning`, `goal_in_region`): ring k at `k * tolerance / 4`, 8 positions each. Default 2
/// (out to half the tolerance, 16 positions of up to `GOAL_SETTLE_YAWS` settles each): a bound on the work.
pub const GOAL_REGION_RINGS: u32 = 2;

/// Fill of the map's block pool, in eighths, at which a scan makes room before its next batch of points
/// (`Map::forget_beyond`): the map of a long traverse forgets what lies far from the rover instead of dropping every
/// new voxel once full (a 50 m descent fills the 12 MiB pool at 10 cm, `host-sim/doc/homotopy.md`). Default 7 (7/8
/// full).
pub const MAP_FORGET_AT_EIGHTHS: usize = 7;
/// Fill, in eighths, that forgetting aims for. Default 6 (3/4): room for several scans before the next forgetting.
pub const MAP_FORGET_TO_EIGHTHS: usize = 6;
/// Radii round the rover (horizontal, metres) beyond which blocks are forgotten, tried in turn until the pool is at
/// most [`MAP_FORGET_TO_EIGHTHS`] full. Default 40 m down to 8 m: the sensor's default range is 20 m, and within 8 m
/// the map is never forgotten (if that is still too full, the scan's voxels beyond the pool are dropped and
/// counted, as before).
pub const MAP_FORGET_RADII_M: [Real; 7] = [40.0, 32.0, 24.0, 20.0, 16.0, 12.0, 8.0];
