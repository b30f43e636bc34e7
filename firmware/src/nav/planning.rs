//! Goal planning on board: the tethered ABIT* problem on the onboard map, suspended between executive steps.
//! See the module docs of [`crate::nav`] for the design.

use core::borrow::BorrowMut;
use core::cell::Cell;

use hal::Instant;

use crate::config::nav as cfg;
use crate::config::protocol::MAX_ANCHORS_PER_WAYPOINT;
use crate::config::rover::RoverParams;
use crate::config::tether::ANCHOR_HISTORY_CAPACITY;
use crate::exec::{PlanBuffer, PlanProgress};
use crate::geom::{norm3, wrap_angle, Real, Vec3};
use crate::map::{DistanceField, DistanceQuery, Map};
use crate::plan::abit::{AbitArena, AbitParams, AbitStar, AbitSuspended};
use crate::plan::space::{
    Budget, GoalState, MotionCheck, MotionValidator, Planner, PlannerStatus, ProblemDefinition, Termination,
};
use crate::plan::tethered::{
    tether_pull_anchor, MarginEscape, MotionPlan, MotionStats, PlanBounds, RoverState, SettleFailure, StartEscape,
    TetherMotionValidator, TetherObjective, TetherSpace, TetherSpaceParams, TetherValidity,
};
use crate::rover::check_pose_stability;
use crate::stability::StabilityOutcome;
use crate::protocol::{Configure, Motion, PlanState, Point3, Pose, Quat, Waypoint};
use crate::tether::{Anchor, AnchorHistory};
use crate::plan::rng::SplitMix64;

/// The on-board ABIT* arena (capacities of `config::nav`).
pub type NavArena = AbitArena<
    RoverState,
    AnchorHistory,
    { cfg::NODE_CAPACITY },
    { cfg::EDGE_QUEUE_CAPACITY },
    { cfg::EDGE_MEMO_CAPACITY },
>;

/// The navigator's planning storage, lent like the map's (a `Box` on the host, a `static` on the board). Its empty
/// state is all zero bytes (empty `heapless` vectors, an empty tile), so the board keeps it in `.bss`.
pub struct NavPlanStorage {
    /// The ABIT* arena (nodes, edge queue, ABIT*'s own edge memo).
    pub arena: NavArena,
    pub(crate) path: heapless::Vec<(RoverState, AnchorHistory), { cfg::PATH_CAPACITY }>,
    pub(crate) motions: heapless::Vec<Motion, { cfg::MOTION_CAPACITY }>,
    /// The goal's search between executive steps ([`AbitStar::suspend`]), at most one; empty when the next step
    /// starts a new search (a new goal, a changed map). A vector rather than an `Option`, so the empty storage
    /// stays all zero bytes.
    suspended: heapless::Vec<AbitSuspended<RoverState>, 1>,
    /// The generator's state when the search was suspended.
    rng_state: u64,
    /// The anchor history of the start state (the mission's tracked history when replanning mid-mission); empty =
    /// the root anchor alone.
    pub(crate) start_history: AnchorHistory,
    /// The terrain tile in use and the one being uploaded (`nav::tile`, 128 KiB).
    pub(crate) tile: super::tile::TileStorage,
}

impl NavPlanStorage {
    /// Empty storage (const, so it can be a `static`).
    pub const fn new() -> Self {
        Self {
            arena: AbitArena::new(),
            path: heapless::Vec::new(),
            motions: heapless::Vec::new(),
            suspended: heapless::Vec::new(),
            rng_state: 0,
            start_history: AnchorHistory::empty(),
            tile: super::tile::TileStorage::new(),
        }
    }
    /// Bytes of the storage (for the board's memory report).
    pub const fn bytes() -> usize {
        core::mem::size_of::<Self>()
    }
}

impl Default for NavPlanStorage {
    fn default() -> Self {
        Self::new()
    }
}

/// Why a goal request was refused (`InvalidInput`), or why planning stopped without a plan. Counted per reason in
/// [`NavPlanStats::refusals`] (indexed by the discriminant) and logged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum GoalRefusal {
    /// No `Configure` reached the navigator (no root anchor, no rover model).
    NotConfigured,
    /// No scan has arrived yet, so the rover's pose is unknown.
    NoPose,
    /// The onboard map holds no blocks.
    MapEmpty,
    /// No block of the map is known to contain the surface (e.g. scattered returns): no planning bounds.
    NoSurface,
    /// The rover does not settle on the map at its pose: no ground within reach, or the settler found no pose
    /// (unobserved ground and a collision have their own reasons: [`Self::StartUnobserved`],
    /// [`Self::StartInCollision`]).
    StartNotSettled,
    /// The goal lies inside the mapped area but the rover does not settle there.
    GoalNotSettled,
    /// The planner rejected the problem (a parameter or the arena); see the log.
    PlannerRejected,
    /// A homotopy goal with no terrain tile uploaded (protocol v7 `TileChunk`).
    NoTile,
    /// The tile's descent from the root anchor to the goal could not be segmented into planes (the log names the
    /// `DemError`: corridor outside the tile, no tether-demand stretch, a blocked end, ...).
    DescentNotSegmented,
    /// No homotopy class of the descent is feasible for Axel (Alg. 1 found no route), or the BTM was not built.
    NoRoute,
    /// The route needs more tether than `Configure.tether.max_payout_m`.
    PayoutExceeded,
    /// The route touches an obstacle on the corridor's edge, cannot be folded back onto the tile, or needs more
    /// legs than `HOMOTOPY_MAX_LEGS`.
    RouteRefused,
    /// A reset lost the tether state (no retained anchor history survived): planning from a straight tether would
    /// be unsafe, so every goal is refused until the ground recovers the rover.
    TetherStateLost,
    /// On the map, the ground or the space under the rover at its pose is unobserved (`SettleFailure::UnknownSpace`
    /// or `NoSurface`): at a frontier, e.g. a wheel over a lip whose face no ray has reached.
    StartUnobserved,
    /// On the map, the rover at its pose collides with the terrain or has a wheel against a steep face
    /// (`SettleFailure::Collision` or `SteepContact`, with the start's escape zone too).
    StartInCollision,
}

impl GoalRefusal {
    /// Number of reasons.
    pub const COUNT: usize = 15;
    /// A sentence a person can act on.
    pub fn reason(self) -> &'static str {
        match self {
            Self::NotConfigured => "no Configure received: root anchor and rover unknown",
            Self::NoPose => "no scan received yet: the rover's pose is unknown",
            Self::MapEmpty => "the onboard map is empty: send scans first",
            Self::NoSurface => "no observed surface in the map to plan on: scan the terrain around the rover densely",
            Self::StartNotSettled => "the rover does not settle on the map at its pose (no ground within reach, or no settled pose)",
            Self::GoalNotSettled => "the goal is inside the mapped area but the rover does not settle there",
            Self::PlannerRejected => "the planner rejected the problem (parameters or arena)",
            Self::NoTile => "homotopy goal without a terrain tile: upload one (TileChunk) first",
            Self::DescentNotSegmented => {
                "the tile's descent from the root anchor to the goal was not segmented (see the log): move the goal or upload a tile covering the corridor"
            }
            Self::NoRoute => "no homotopy route on the tile is feasible for the rover: move the goal or the root anchor",
            Self::PayoutExceeded => "the homotopy route needs more tether than max_payout_m: move the goal or use a longer tether",
            Self::RouteRefused => "the homotopy route touches the corridor's edge obstacles or has too many legs (see the log)",
            Self::TetherStateLost => "the tether state was lost in a reset: recover the anchor history before a new goal",
            Self::StartUnobserved => "the ground under the rover is unobserved on the map at its pose: scan around the rover",
            Self::StartInCollision => "on the map the rover collides at its pose or has a wheel on a steep face: drive it clear",
        }
    }
}

/// Counters of on-board planning (for tests and logs).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct NavPlanStats {
    /// Goals accepted.
    pub goals_accepted: u32,
    /// Goals refused, by [`GoalRefusal`] discriminant.
    pub refusals: [u32; GoalRefusal::COUNT],
    /// Why the current goal was refused or its planning stopped with `InvalidInput` (`None` while it is accepted
    /// and planning); sent to the ground with the refusal (`Autonomy::refusal`).
    pub last_refusal: Option<GoalRefusal>,
    /// `plan_step` calls.
    pub steps: u32,
    /// Planner iterations run.
    pub iterations_run: u64,
    /// Steps that resumed the suspended search.
    pub resumes: u32,
    /// Searches restarted on a changed map (a scan arrived between two steps), keeping the goal's iteration count.
    pub restarts: u32,
    /// Settles run (samples, interpolated states of motion checks, goal states).
    pub settles_run: u64,
    /// Static-stability problems solved (motion checks and the plan's margins).
    pub stability_checks_run: u64,
    /// Motion checks run.
    pub motion_checks_run: u32,
    /// The space's work and motion-failure counters of the last step (samples, settles, stability checks, motions
    /// invalid by reason).
    pub last_step: MotionStats,
    /// The same counters summed over every step of every goal.
    pub totals: MotionStats,
    /// Waypoints whose anchor history was shortened to `MAX_ANCHORS_PER_WAYPOINT` (root and most recent kept).
    pub anchors_truncated: u32,
    /// Search rounds added to a mission's search that had spent its budget with nothing the mission could drive
    /// ([`Problem::extend`]).
    pub search_extensions: u32,
    /// Turns in place to look at an unobserved goal (`nav::mission`, `look_at_goal`).
    pub looks: u32,
}

impl NavPlanStats {
    /// Counts a refusal and keeps it as the current goal's reason.
    pub(crate) fn refused(&mut self, why: GoalRefusal) {
        if let Some(n) = self.refusals.get_mut(why as usize) {
            *n = n.saturating_add(1);
        }
        self.last_refusal = Some(why);
    }
}

/// What the navigator keeps from `Configure` for planning.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlanSetup {
    pub root: Vec3,
    pub rover: RoverParams,
    pub seed: u64,
    pub samples_per_batch: u32,
    /// `Configure.mission.min_margin_n`: no waypoint below it is sent.
    pub min_margin_n: f32,
    /// `Configure.tether.max_payout_m`: no waypoint needing more tether is sent.
    pub max_payout_m: f32,
    /// The rover's weight, newtons (`mass_kg * STANDARD_GRAVITY`): margins are fractions of it.
    pub weight_n: f32,
}

impl PlanSetup {
    /// The planning setup of a validated `Configure`: the Axel model with the configured wheel radius, track, boom,
    /// mass (split body / boom by `BOOM_MASS_FRACTION`), friction and tension limit.
    pub fn from_configure(c: &Configure) -> Self {
        let mut rover = RoverParams::AXEL;
        rover.wheel_radius_m = c.rover.wheel_radius_m;
        rover.track_m = c.rover.axle_length_m;
        rover.boom_length_m = c.rover.boom_length_m;
        rover.boom_mass_kg = c.rover.mass_kg * cfg::BOOM_MASS_FRACTION;
        rover.body_mass_kg = c.rover.mass_kg - rover.boom_mass_kg;
        rover.wheel_mu = c.rover.friction_coefficient;
        rover.tether_max_tension_n = c.tether.max_tension_n;
        rover.footprint_unobserved_max = cfg::FOOTPRINT_UNOBSERVED_MAX;
        let r = c.tether.root_anchor;
        PlanSetup {
            root: Vec3::new(r.x, r.y, r.z),
            rover,
            seed: c.planner.rng_seed,
            samples_per_batch: c.planner.batch_size.clamp(1, cfg::SAMPLES_PER_BATCH),
            min_margin_n: c.mission.min_margin_n,
            max_payout_m: c.tether.max_payout_m,
            weight_n: c.rover.mass_kg * crate::config::mission::STANDARD_GRAVITY,
        }
    }
}

/// A goal being planned.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Problem {
    pub start: RoverState,
    /// The goal position the planner settles its goal state at, and the radius of its goal region round that
    /// state: the request's position and tolerance, or a position of the request's region where the rover settles
    /// and what is left of the tolerance there ([`goal_in_region`]).
    pub goal: Vec3,
    pub tolerance: f64,
    /// The goal request's position and tolerance.
    pub requested_goal: Vec3,
    pub requested_tolerance: f64,
    pub root: Vec3,
    pub bounds: PlanBounds,
    pub rover: RoverParams,
    pub seed: u64,
    pub abit: AbitParams,
    pub budget: u32,
    /// The goal request's own budget (`max_iterations`, capped): one search round ([`Problem::extend`]).
    pub round: u32,
    /// The search ended on its iteration budget alone (time left, not converged, arena not full): another round
    /// would go on where it stopped.
    pub budget_spent: bool,
    pub deadline: Option<Instant>,
    pub done: u32,
    /// Iterations of the goal before the current search began (non-zero after the map changed under a search,
    /// which then restarted on the new map).
    pub search_base: u32,
    pub best_cost: Option<f32>,
    pub finished: Option<PlanState>,
    /// Smallest margin of a sent waypoint, newtons; the rover's weight; the tether on the spool.
    pub min_margin_n: f32,
    pub weight_n: f32,
    pub max_payout_m: f32,
    /// Waypoints cut from the end of the last plan (margin below the minimum or more tether than the spool).
    pub cut: u32,
    /// The space's work and motion-failure counters summed over this goal's steps (logged when the search ends).
    pub work: MotionStats,
    /// Set when the start collides with the extra voxel of clearance: the zone round it where states settle with
    /// the rover's own clearance, so motions can take it away ([`StartEscape`]).
    pub escape: Option<StartEscape>,
    /// Set when the start's margin on the map is below the planner's minimum but the rover stands there stable:
    /// the zone round it where states need only the start's own margin ([`thin_start_escape`]).
    pub margin_escape: Option<MarginEscape>,
}

impl Problem {
    /// Another search round of the goal's budget for a search that spent its iterations without a plan the
    /// mission can drive; never beyond `MAX_PLAN_ITERATIONS` in all. `false` (nothing changed) when the search
    /// ended otherwise (time budget, converged, arena full) or the cap is reached. The suspended search resumes.
    pub fn extend(&mut self) -> bool {
        if !self.budget_spent || self.budget >= cfg::MAX_PLAN_ITERATIONS {
            return false;
        }
        self.budget = self.budget.saturating_add(self.round.max(1)).min(cfg::MAX_PLAN_ITERATIONS);
        self.budget_spent = false;
        self.finished = None;
        true
    }

    /// The space this problem is planned in, over `map`.
    pub fn space<'m, D: DistanceField>(&self, map: &'m D) -> Option<TetherSpace<'m, D>> {
        TetherSpace::new(map, self.bounds, self.rover, TetherSpaceParams::ONBOARD)
            .ok()
            .map(|s| s.with_start_escape(self.escape).with_margin_escape(self.margin_escape))
    }
}

/// A [`MarginEscape`] round the problem's start when the rover stands there stable on the map (tether pulling
/// towards `history`'s pull anchor) with a margin below the planner's minimum but at least `floor` rover weights:
/// within `START_ESCAPE_VOXELS` of the start's axle, states need only the start's own margin, so the plan can
/// leave it without passing anything worse. `None` when the start has the full margin, or not even the floor.
pub(crate) fn thin_start_escape<D: DistanceField>(
    map: &D,
    problem: &Problem,
    history: &AnchorHistory,
    voxel_m: Real,
    floor: f64,
) -> Option<MarginEscape> {
    let space = problem.space(map)?;
    let st = &problem.start.settled;
    if space.stable_with(st, history).is_ok() {
        return None;
    }
    let pull = tether_pull_anchor(st, history, &problem.rover);
    match check_pose_stability(map, st, pull.as_ref(), &problem.rover) {
        Ok((StabilityOutcome::Stable(r), _)) if r.margin >= floor => {
            let a = problem.start.axle();
            Some(MarginEscape { x: a.x, y: a.y, radius_m: cfg::START_ESCAPE_VOXELS * voxel_m, min_margin: r.margin })
        }
        _ => None,
    }
}

/// The planning bounds of the map: the extent of its **surface blocks** (blocks whose centre is known to lie
/// within half a block diagonal of the surface: blocks of carved free space high above the terrain are left out),
/// plus `BOUNDS_Z_MARGIN_M` in z, grown to contain `start` in `(x, y)`. The surface search of a sample starts at
/// the top of the bounds, so the top must lie in observed space: a block's worth above the highest surface.
/// `None` when the map has no surface block.
pub(crate) fn map_bounds(map: &Map<'_>, start: &Vec3) -> Option<PlanBounds> {
    let edge = map.config().voxel_size * crate::config::map::BLOCK_EDGE as Real;
    let near = 0.5 * edge * libm::sqrtf(3.0);
    let mut lo = [Real::INFINITY; 3];
    let mut hi = [Real::NEG_INFINITY; 3];
    for slot in 0..map.blocks_used() {
        let Some(c) = map.block_coord(slot) else { break };
        let centre = Vec3::new((c[0] as Real + 0.5) * edge, (c[1] as Real + 0.5) * edge, (c[2] as Real + 0.5) * edge);
        match map.query(&centre) {
            DistanceQuery::Known { distance, .. } if libm::fabsf(distance) <= near => {}
            _ => continue,
        }
        for ((l, h), ci) in lo.iter_mut().zip(hi.iter_mut()).zip(c) {
            *l = l.min(ci as Real * edge);
            *h = h.max((ci + 1) as Real * edge);
        }
    }
    let [lx, ly, lz] = lo;
    let [hx, hy, hz] = hi;
    let b = PlanBounds {
        min: [lx.min(start.x), ly.min(start.y), lz - cfg::BOUNDS_Z_MARGIN_M],
        max: [hx.max(start.x), hy.max(start.y), hz + cfg::BOUNDS_Z_MARGIN_M],
    };
    b.is_valid().then_some(b)
}

/// `bounds` cut to the planning window: the horizontal box spanned by `start` and `goal`, grown by
/// `PLAN_WINDOW_MARGIN_M` (see there). `bounds` contains the start, so the cut is never empty; a goal outside
/// `bounds` stays an off-map goal.
pub(crate) fn planning_window(bounds: PlanBounds, start: &Vec3, goal: &Vec3) -> PlanBounds {
    let m = cfg::PLAN_WINDOW_MARGIN_M;
    let mut b = bounds;
    for (k, (s, g)) in [(start.x, goal.x), (start.y, goal.y)].into_iter().enumerate() {
        if let (Some(lo), Some(hi)) = (b.min.get_mut(k), b.max.get_mut(k)) {
            *lo = lo.max(s.min(g) - m);
            *hi = hi.min(s.max(g) + m);
        }
    }
    if b.is_valid() { b } else { bounds }
}

/// Set up a goal: settle the start under the last known pose, check the goal, and return the problem.
pub(crate) fn set_up(
    map: &Map<'_>,
    setup: &PlanSetup,
    pose: &Pose,
    goal: &crate::protocol::GoalRequest,
    budget: u32,
    now: Instant,
) -> Result<Problem, GoalRefusal> {
    if map.blocks_used() == 0 {
        return Err(GoalRefusal::MapEmpty);
    }
    let p = pose.position;
    let start_xy = Vec3::new(p.x, p.y, p.z);
    let g = Vec3::new(goal.position.x, goal.position.y, goal.position.z);
    let bounds = map_bounds(map, &start_xy).ok_or(GoalRefusal::NoSurface)?;
    let bounds = planning_window(bounds, &start_xy, &g);
    log::info!("nav: planning bounds {:?} .. {:?}", bounds.min, bounds.max);
    let mut rover = setup.rover;
    // As the campaign does on a map: one voxel of extra body clearance for the map's discretisation.
    rover.body_clearance_m += map.config().voxel_size;
    let space =
        TetherSpace::new(map, bounds, rover, TetherSpaceParams::ONBOARD).map_err(|_| GoalRefusal::PlannerRejected)?;
    let yaw = crate::geom::heading(&pose.to_isometry().rotation);
    let mut escape = None;
    // The pose estimate is the axle centre and its heading: the start is the state whose axle stands there.
    let start = match space.settle_under_axle(p.x, p.y, yaw) {
        Ok(s) => Ok(s),
        // The rover stands here, but on the map it is within the extra voxel of an obstacle (a rock that appeared
        // beside it) or has a wheel against a steep face (the rock's side). Plan from the pose it settles in with
        // its own clearance (and, only if that is still refused, with the steep contact), and let states within
        // START_ESCAPE_VOXELS of it do the same, so motions can take it away (every motion from it would otherwise
        // fail in its first interpolated state); every other state keeps every check.
        Err(SettleFailure::Collision | SettleFailure::SteepContact) => {
            let radius_m = cfg::START_ESCAPE_VOXELS * map.config().voxel_size;
            let zone = |steep_ok, x, y, radius_m| StartEscape { x, y, radius_m, rover: setup.rover, steep_ok };
            // The start's surface point lies within a wheel radius of the axle: find it with the zone that wide,
            // then centre the zone on it.
            let settle_with = |steep_ok| {
                let relaxed = TetherSpace::new(map, bounds, rover, TetherSpaceParams::ONBOARD)
                    .map_err(|_| SettleFailure::InvalidInput)?;
                let wide = zone(steep_ok, p.x, p.y, radius_m + setup.rover.wheel_radius_m);
                let s = relaxed.with_start_escape(Some(wide)).settle_under_axle(p.x, p.y, yaw)?;
                Ok::<_, SettleFailure>((s, zone(steep_ok, s.ground.x, s.ground.y, radius_m)))
            };
            match settle_with(false) {
                Err(SettleFailure::SteepContact) => settle_with(true),
                r => r,
            }
            .map(|(s, e)| {
                log::info!(
                    "nav: the start ({}, {}) settles only with the rover's own clearance{}: states within {} m of it too",
                    e.x,
                    e.y,
                    if e.steep_ok { " and a steep wheel contact" } else { "" },
                    e.radius_m
                );
                escape = Some(e);
                s
            })
        }
        Err(e) => Err(e),
    }
    .map_err(|e| {
        log::warn!("nav: the start does not settle at ({}, {}): {:?}", p.x, p.y, e);
        match e {
            SettleFailure::UnknownSpace | SettleFailure::NoSurface => GoalRefusal::StartUnobserved,
            SettleFailure::Collision | SettleFailure::SteepContact => GoalRefusal::StartInCollision,
            SettleFailure::NoGround | SettleFailure::Budget | SettleFailure::InvalidInput => GoalRefusal::StartNotSettled,
        }
    })?;
    let tolerance = f64::from(goal.tolerance_m);
    let (goal_state, goal_at, region) = goal_in_region(&space, g, tolerance, start.axle()).map_err(|e| {
        log::warn!("nav: the goal does not settle at ({}, {}) nor within its region: {:?}", g.x, g.y, e);
        GoalRefusal::GoalNotSettled
    })?;
    if goal_state.off_map && bounds.contains_xy(g.x, g.y) {
        log::info!("nav: the goal's column at ({}, {}) is not observed yet: planning towards it", g.x, g.y);
    }
    let mut abit = AbitParams::ompl_defaults();
    abit.samples_per_batch = setup.samples_per_batch;
    abit.draws_per_step = cfg::DRAWS_PER_STEP;
    abit.track_approximate = cfg::TRACK_APPROXIMATE;
    let deadline = (goal.time_budget_ms > 0)
        .then(|| Instant::from_micros(now.micros.saturating_add(u64::from(goal.time_budget_ms) * 1000)));
    Ok(Problem {
        start,
        goal: goal_at,
        tolerance: region,
        requested_goal: g,
        requested_tolerance: tolerance,
        root: setup.root,
        bounds,
        rover,
        seed: setup.seed ^ u64::from(goal.goal_id).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        abit,
        budget,
        round: budget,
        budget_spent: false,
        deadline,
        done: 0,
        search_base: 0,
        best_cost: None,
        finished: None,
        min_margin_n: setup.min_margin_n,
        weight_n: setup.weight_n,
        max_payout_m: setup.max_payout_m,
        cut: 0,
        work: MotionStats::default(),
        escape,
        margin_escape: None,
    })
}

/// The goal state of the request's position `goal` and tolerance `tol`, the position it settles at and the radius
/// of the planner's goal region round it. The rover settled at `goal` ([`TetherSpace::goal_or_unobserved`]:
/// an unobserved goal too) with the whole tolerance; where it does not settle there on observed ground (the body
/// on a rock's voxels, a steep contact), the goal region is a position within `tol` (the mission arrives when the
/// axle is within it): of `GOAL_REGION_RINGS` rings of 8 positions, `tol / 4` apart, round `goal`, the innermost
/// ring with a position where the rover settles with its axle at most `3 tol / 4` from `goal`, and there the
/// position nearest `from` (the rover comes from there; the first of equals from +x, anticlockwise). The region
/// shrinks by the axle's distance from `goal`, so that a plan reaching it ends within `tol` of `goal`. Else the
/// first failure at `goal`.
fn goal_in_region<D: DistanceField>(
    space: &TetherSpace<'_, D>,
    goal: Vec3,
    tol: f64,
    from: Vec3,
) -> Result<(RoverState, Vec3, f64), SettleFailure> {
    let first = match space.goal_or_unobserved(goal, 0.0) {
        Ok(s) => return Ok((s, goal, tol)),
        Err(e @ (SettleFailure::InvalidInput | SettleFailure::NoSurface | SettleFailure::UnknownSpace)) => return Err(e),
        Err(e) => e,
    };
    let step = tol as Real / 4.0;
    for ring in 1..=cfg::GOAL_REGION_RINGS {
        let mut best: Option<(Real, RoverState, Vec3, f64)> = None;
        for k in 0..8u32 {
            let a = core::f32::consts::TAU * k as Real / 8.0;
            let r = step * ring as Real;
            let p = Vec3::new(goal.x + r * libm::cosf(a), goal.y + r * libm::sinf(a), goal.z);
            let Ok(st) = space.goal_state(p, 0.0) else { continue };
            let d = f64::from(libm::hypotf(st.axle().x - goal.x, st.axle().y - goal.y));
            let near = libm::hypotf(st.axle().x - from.x, st.axle().y - from.y);
            if !st.off_map && d <= 0.75 * tol && best.as_ref().is_none_or(|b| near < b.0) {
                best = Some((near, st, p, tol - d));
            }
        }
        if let Some((_, st, p, region)) = best {
            log::info!("nav: the goal does not settle at ({}, {}) ({first:?}); its region's goal state is at ({}, {})", goal.x, goal.y, p.x, p.y);
            return Ok((st, p, region));
        }
    }
    Err(first)
}

/// [`TetherMotionValidator`], counting the motion checks of one `plan_step` call (its stop predicate bounds them).
struct CountedMotions<'c> {
    checks: &'c Cell<u32>,
}

impl<D: DistanceField> MotionValidator<TetherSpace<'_, D>> for CountedMotions<'_> {
    fn check_motion(
        &mut self,
        space: &TetherSpace<'_, D>,
        from: &RoverState,
        from_attachment: &AnchorHistory,
        to: &RoverState,
    ) -> MotionCheck<AnchorHistory> {
        self.checks.set(self.checks.get().saturating_add(1));
        TetherMotionValidator.check_motion(space, from, from_attachment, to)
    }
}

/// The motion primitives of one path segment `a -> b` (Paton et al. V: turn in place to the drive heading, drive
/// straight, turn in place to `b`'s yaw), as [`MotionPlan`] interpolates and the validator checked them. A drive
/// along the reverse heading (Axel drives either way) is a negative distance. Tiny turns and drives are left out.
pub fn segment_motions(a: &RoverState, b: &RoverState, params: &TetherSpaceParams) -> [Option<Motion>; 3] {
    let plan = MotionPlan::new(a, b, params);
    let d = b.ground - a.ground;
    let len_xy = libm::sqrtf(d.x * d.x + d.y * d.y);
    let drive = if len_xy > 1e-6 {
        let psi = libm::atan2f(d.y, d.x);
        let heading = a.theta + plan.turn_a_rad;
        let forward = libm::fabsf(wrap_angle(heading - psi)) < core::f32::consts::FRAC_PI_2;
        let dist = norm3(&d);
        Some(if forward { dist } else { -dist })
    } else {
        None
    };
    let turn = |r: Real| (libm::fabsf(r) >= cfg::MIN_TURN_RAD).then_some(Motion::Turn { yaw_rad: r });
    [
        turn(plan.turn_a_rad),
        drive.filter(|s| libm::fabsf(*s) >= cfg::MIN_DRIVE_M).map(|distance_m| Motion::Straight { distance_m }),
        turn(plan.turn_b_rad),
    ]
}

/// The protocol waypoint of a path state (anchors: the root and the most recent ones that fit).
pub(crate) fn waypoint(s: &RoverState, h: &AnchorHistory, margin: f32, truncated: &mut u32) -> Waypoint {
    let t = s.settled.pose.translation.vector;
    let q = s.settled.pose.rotation.quaternion();
    let mut anchors = heapless::Vec::new();
    let all = h.as_slice();
    let skip = all.len().saturating_sub(MAX_ANCHORS_PER_WAYPOINT);
    if skip > 0 {
        *truncated = truncated.saturating_add(1);
    }
    // the root, then the most recent anchors that fit (all of them when nothing is cut)
    let keep = all.first().into_iter().chain(all.iter().skip(skip.saturating_add(1)));
    for a in keep.take(MAX_ANCHORS_PER_WAYPOINT) {
        let _ = anchors.push(Point3 { x: a.point.x, y: a.point.y, z: a.point.z });
    }
    Waypoint {
        pose: Pose { position: Point3 { x: t.x, y: t.y, z: t.z }, orientation: Quat { x: q.i, y: q.j, z: q.k, w: q.w } },
        anchors,
        stability_margin: margin,
    }
}

/// Run the problem for at most `iterations` new iterations (see the module docs: the search is resumed, or
/// restarted after a map change). Fills `plan` and the storage's motions when planning finishes with a path.
pub(crate) fn step<P: BorrowMut<NavPlanStorage>>(
    map: &Map<'_>,
    problem: &mut Problem,
    storage: &mut P,
    stats: &mut NavPlanStats,
    now: Instant,
    iterations: u32,
    plan: &mut PlanBuffer,
) -> PlanProgress {
    let store = storage.borrow_mut();
    stats.steps = stats.steps.saturating_add(1);
    let out_of_time = problem.deadline.is_some_and(|d| now >= d);
    // With no time left, only the best solution so far is restored (no new iterations).
    let target = if out_of_time { problem.done } else { problem.done.saturating_add(iterations).min(problem.budget) };
    let Some(mut space) = problem.space(map) else {
        stats.refused(GoalRefusal::PlannerRejected);
        problem.finished = Some(PlanState::InvalidInput);
        return finished(problem, PlanState::InvalidInput);
    };
    let again = || goal_in_region(&space, problem.requested_goal, problem.requested_tolerance, problem.start.axle());
    // the region's goal position first, when there is one (`goal_in_region` begins at the requested position)
    let resolved = if problem.goal == problem.requested_goal {
        again()
    } else {
        space.goal_or_unobserved(problem.goal, 0.0).map(|g| (g, problem.goal, problem.tolerance)).or_else(|_| again())
    };
    let goal_state = match resolved {
        Ok((g, at, region)) => {
            (problem.goal, problem.tolerance) = (at, region);
            g
        }
        Err(_) => {
            // The map changed under the goal since it was accepted.
            log::warn!("nav: {}", GoalRefusal::GoalNotSettled.reason());
            stats.refused(GoalRefusal::GoalNotSettled);
            problem.finished = Some(PlanState::InvalidInput);
            return finished(problem, PlanState::InvalidInput);
        }
    };
    let start_attachment = if store.start_history.is_empty() {
        AnchorHistory::new(Anchor::root(problem.root))
    } else {
        store.start_history.clone()
    };
    let pdef = ProblemDefinition {
        start: problem.start,
        start_attachment,
        goal: GoalState { state: goal_state, tolerance: problem.tolerance },
        objective: TetherObjective,
    };
    // Resume the search the last step suspended, or (a new goal; a changed map, under which its motion checks no
    // longer hold) start a new one from the goal's seed for the rest of the goal's budget.
    let resumable = store
        .suspended
        .first()
        .is_some_and(|s| problem.search_base.saturating_add(s.counters().iterations) == problem.done);
    let suspended = if resumable { store.suspended.pop() } else { None };
    store.suspended.clear();
    if suspended.is_none() && problem.done > problem.search_base {
        stats.restarts = stats.restarts.saturating_add(1);
        problem.search_base = problem.done;
    }
    let mut rng = SplitMix64(if suspended.is_some() { store.rng_state } else { problem.seed });
    let mut validity = TetherValidity;
    let new_checks = Cell::new(0u32);
    let mut motions = CountedMotions { checks: &new_checks };
    let arena = &mut store.arena;
    let mut planner = match suspended {
        Some(s) => {
            stats.resumes = stats.resumes.saturating_add(1);
            AbitStar::resume(arena, &mut space, &mut validity, &mut motions, &pdef, &mut rng, s)
        }
        None => AbitStar::new(arena, &mut space, &mut validity, &mut motions, &pdef, &mut rng, problem.abit),
    };
    // The search's own iteration counts (the goal's minus the iterations of searches on earlier maps).
    let first_new = problem.done.saturating_sub(problem.search_base);
    let first_sampling = planner.counters().sampling_steps;
    // At least one new iteration, then stop after MOTION_CHECKS_PER_STEP motion checks, or after a step that went
    // on drawing a batch (DRAWS_PER_STEP draws): the geometric work of one call stays bounded whatever the
    // iteration count.
    let report = planner.solve_until(&Budget::iterations(target.saturating_sub(problem.search_base)), |c| {
        c.sampling_steps > first_sampling || (c.iterations > first_new && new_checks.get() >= cfg::MOTION_CHECKS_PER_STEP)
    });
    let c = report.counters;
    stats.iterations_run = stats.iterations_run.saturating_add(u64::from(c.iterations.saturating_sub(first_new)));
    problem.done = problem.search_base.saturating_add(c.iterations);
    problem.best_cost = match report.status {
        PlannerStatus::Exact(cost) => Some(cost as f32),
        _ => None,
    };
    let ended_by_search = matches!(
        report.termination,
        Termination::Converged | Termination::ArenaFull(_) | Termination::ObjectiveSatisfied | Termination::InvalidInput
    );
    let done = out_of_time || problem.done >= problem.budget || ended_by_search;
    problem.budget_spent = done && !out_of_time && !ended_by_search;
    let state = match report.status {
        PlannerStatus::Exact(_) => PlanState::ExactSolution,
        PlannerStatus::Approximate(_) => PlanState::ApproximateSolution,
        PlannerStatus::NoSolution(_) => PlanState::NoSolutionWithinBudget,
        PlannerStatus::InvalidInput(e) => {
            log::warn!("nav: planner rejected the problem: {e:?}");
            PlanState::InvalidInput
        }
    };
    let mut state = state;
    let solved = done && matches!(state, PlanState::ExactSolution | PlanState::ApproximateSolution);
    let written = if solved { planner.write_path(&mut store.path).is_ok() } else { false };
    let _ = store.suspended.push(planner.suspend());
    store.rng_state = rng.0;
    stats.motion_checks_run = stats.motion_checks_run.saturating_add(new_checks.get());
    if solved {
        if !written || store.path.len() < 2 {
            // No path (TooLong: more states than PATH_CAPACITY; or an approximate "path" of the start alone).
            state = PlanState::NoSolutionWithinBudget;
            store.path.clear();
        } else {
            problem.cut = fill_plan(&space, problem, &mut store.path, &mut store.motions, stats, plan);
            if store.path.len() < 2 {
                log::warn!("nav: no waypoint after the start passes the margin and payout checks");
                state = PlanState::NoSolutionWithinBudget;
                store.path.clear();
                store.motions.clear();
                plan.clear();
            } else if problem.cut > 0 {
                // The plan no longer reaches the goal: honestly approximate.
                state = PlanState::ApproximateSolution;
            }
        }
    }
    stats.last_step = space.stats();
    stats.totals.add(&stats.last_step);
    problem.work.add(&stats.last_step);
    stats.settles_run = stats.settles_run.saturating_add(u64::from(stats.last_step.settles));
    stats.stability_checks_run = stats.stability_checks_run.saturating_add(u64::from(stats.last_step.stability_checks));
    if done {
        problem.finished = Some(state);
        let w = &problem.work;
        log::info!(
            "nav: search ended {state:?} after {} iterations ({:?}): samples {} drawn / {} settled / {} evicted; motions {} checked / {} valid; invalid by reason: settle {} ({} collisions, {} steep contacts), unknown space {}, tether {}, unstable {}, too long {}",
            problem.done,
            report.termination,
            w.samples_drawn,
            w.samples_settled,
            report.counters.samples_evicted,
            w.motions,
            w.motions_valid,
            w.fail_settle,
            w.settle_collision,
            w.settle_steep,
            w.fail_unknown,
            w.fail_tether,
            w.fail_unstable,
            w.fail_too_long
        );
        finished(problem, state)
    } else {
        PlanProgress::Searching { iterations: problem.done, best_cost: problem.best_cost }
    }
}

fn finished(problem: &Problem, state: PlanState) -> PlanProgress {
    PlanProgress::Finished {
        state,
        iterations: problem.done,
        best_cost: if matches!(state, PlanState::ExactSolution) { problem.best_cost } else { None },
    }
}

/// Waypoints (with stability margins from the map) and motion primitives of the stored path. The path is cut
/// before its first on-map state whose stability margin on the map is below `min_margin_n` (or fails the check),
/// or whose tether (its anchor history to the axle) is longer than `max_payout_m`: such a waypoint is never sent
/// nor driven. Returns the number of states cut.
fn fill_plan<D: DistanceField>(
    space: &TetherSpace<'_, D>,
    problem: &Problem,
    path: &mut heapless::Vec<(RoverState, AnchorHistory), { cfg::PATH_CAPACITY }>,
    motions: &mut heapless::Vec<Motion, { cfg::MOTION_CAPACITY }>,
    stats: &mut NavPlanStats,
    plan: &mut PlanBuffer,
) -> u32 {
    plan.clear();
    motions.clear();
    let mut keep = path.len();
    for (k, (s, h)) in path.iter().enumerate() {
        if s.off_map {
            continue;
        }
        let margin = match space.stable_with(&s.settled, h) {
            Ok(m) if (m as f32) * problem.weight_n >= problem.min_margin_n => m as f32,
            Ok(m) => {
                log::warn!("nav: plan cut at state {k}: margin {} N below the minimum", m as f32 * problem.weight_n);
                keep = k;
                break;
            }
            Err(e) => {
                log::warn!("nav: plan cut at state {k}: not stable by the margin check: {e:?}");
                keep = k;
                break;
            }
        };
        if h.length_to(&s.axle()) > problem.max_payout_m {
            log::warn!("nav: plan cut at state {k}: needs more tether than max_payout_m");
            keep = k;
            break;
        }
        if plan.push(waypoint(s, h, margin, &mut stats.anchors_truncated)).is_err() {
            keep = k;
            break;
        }
    }
    let cut = path.len().saturating_sub(keep) as u32;
    path.truncate(keep);
    let mut prev: Option<&RoverState> = None;
    for (s, _) in path.iter().filter(|(s, _)| !s.off_map) {
        if let Some(a) = prev {
            for m in segment_motions(a, s, space.params()).into_iter().flatten() {
                if motions.push(m).is_err() {
                    break;
                }
            }
        }
        prev = Some(s);
    }
    cut
}

/// Cut the stored plan after state `last` (the states up to it and the motions of their segments stay): the mission
/// drives the prefix and plans again at its end. `params` must be the space's the motions were made with.
pub(crate) fn truncate_plan<P: BorrowMut<NavPlanStorage>>(storage: &mut P, last: usize, params: &TetherSpaceParams) {
    let s = storage.borrow_mut();
    s.path.truncate(last.saturating_add(1));
    // as `fill_plan` made them: the segments between the on-map states
    let mut count = 0usize;
    let mut prev: Option<&RoverState> = None;
    for (st, _) in s.path.iter().filter(|(st, _)| !st.off_map) {
        if let Some(a) = prev {
            count += segment_motions(a, st, params).into_iter().flatten().count();
        }
        prev = Some(st);
    }
    s.motions.truncate(count);
}

/// The motion primitive at `index` of the last plan.
pub(crate) fn motion_at<P: BorrowMut<NavPlanStorage>>(storage: &mut P, index: usize) -> Option<Motion> {
    storage.borrow_mut().motions.get(index).copied()
}

/// Forget the suspended search (the map changed: the next step starts a new search on the new map).
pub(crate) fn forget_search<P: BorrowMut<NavPlanStorage>>(storage: &mut P) {
    storage.borrow_mut().suspended.clear();
}

/// Forget the last plan (a new goal); the next plan starts from the root anchor alone unless a start history is
/// set again.
pub(crate) fn clear_plan<P: BorrowMut<NavPlanStorage>>(storage: &mut P) {
    let s = storage.borrow_mut();
    s.suspended.clear();
    s.path.clear();
    s.motions.clear();
    s.start_history = AnchorHistory::empty();
}

/// The states and anchor histories of the last plan (start first), for tests and pictures.
pub(crate) fn path<P: BorrowMut<NavPlanStorage>>(storage: &mut P) -> &[(RoverState, AnchorHistory)] {
    &storage.borrow_mut().path
}

const _: () = assert!(ANCHOR_HISTORY_CAPACITY <= u8::MAX as usize);
