//! A `GoalRequest` for [`PlannerChoice::Homotopy`](crate::protocol::PlannerChoice) on board (issue 20 item 4): the
//! global route on the uploaded terrain tile (Abad-Manterola et al. III-VI, Alg. 1; Tanner et al. II), driven leg by
//! leg with tethered ABIT* on the onboard map (Paton et al. V). The design is in the module docs of [`crate::nav`].
//!
//! The global plan runs in three `plan_step` calls, one phase each (every executive step stays bounded):
//! 1. **Segment**: [`DemDescent::segment`] of the tile from the configured root anchor to the goal (corridor
//!    half width `HOMOTOPY_CORRIDOR_HALF_WIDTH_M` 6 m, soil friction `Configure.rover.friction_coefficient`, the
//!    rest [`DemParams::for_rover`] of the configured rover), [`DemDescent::check_ends`], [`DemDescent::build_btm`];
//! 2. **Hold**: Axel's holding limit on the wall ([`axel_model`]: about 30 settles and stability checks);
//! 3. **Route**: Alg. 1 ([`preplan`], `HomotopyParams::default()`) with Axel's model, the plan mapped to the world
//!    ([`DemDescent::route_to_world`], refusing more tether than `Configure.tether.max_payout_m`), cut into legs.
//!
//! Legs: the route's descent waypoints (DEM heights), skipping those within `HOMOTOPY_LEG_MIN_M` (1 m) of the
//! previous leg goal and splitting stretches longer than `HOMOTOPY_LEG_MAX_M` (5 m); the last leg's goal is the
//! goal request's position. At most `HOMOTOPY_MAX_LEGS` (32); a longer route is refused.

use crate::config::nav::{
    HOMOTOPY_CORRIDOR_HALF_WIDTH_M, HOMOTOPY_LEG_MAX_M, HOMOTOPY_LEG_MIN_M, HOMOTOPY_MAX_LEGS,
};
use crate::plan::homotopy::axel::axel_model;
use crate::config::homotopy::MAX_OBSTACLES;
use crate::plan::homotopy::btm::Btm;
use crate::plan::homotopy::geo::polygons_overlap;
use crate::plan::homotopy::dem::{
    dop_merge, dop_polygon, dop_support, DemDescent, DemError, DemParams, DemScratch, HeightTile, RouteError,
    WorldRoute,
};
use crate::plan::homotopy::planes::HoldModel;
use crate::plan::homotopy::plan::{preplan, HomotopyParams, PlanReport, Workspace};
use crate::protocol::{GoalRequest, Point3, Pose, Quat, Waypoint};

use super::planning::{GoalRefusal, PlanSetup};

/// Caller-lent storage of the global planner (~0.66 MiB: the BTM 240 KiB, the A* workspace 292 KiB, the
/// segmentation scratch 112 KiB, the descent and the route), lent to a navigator with
/// [`Navigator::with_homotopy`](super::Navigator::with_homotopy). Its empty `Btm` and A* arena are not all zero
/// bytes, so a board's static of it is in `.data`.
pub struct HomotopyStorage {
    scratch: DemScratch,
    pub(crate) btm: Btm,
    ws: Workspace,
    descent: Option<DemDescent>,
    model: Option<HoldModel>,
    /// The route of the goal being driven (world frame), kept for the anchor comparison.
    pub(crate) route: Option<WorldRoute>,
    /// Leg goals, world frame, in order (the last is the goal request's position).
    pub(crate) legs: heapless::Vec<[f32; 3], HOMOTOPY_MAX_LEGS>,
}

impl HomotopyStorage {
    /// Empty (const: part of the board's static planning storage).
    pub const fn new() -> Self {
        Self {
            scratch: DemScratch::new(),
            btm: Btm::new(),
            ws: Workspace::new(),
            descent: None,
            model: None,
            route: None,
            legs: heapless::Vec::new(),
        }
    }
}

impl Default for HomotopyStorage {
    fn default() -> Self {
        Self::new()
    }
}

/// Where a navigator finds the global planner's storage: anything that lends a [`HomotopyStorage`], or
/// [`NoGlobalPlanner`] (homotopy goals answered `PlannerUnavailable`).
pub trait GlobalPlanStorage {
    /// The storage, if there is one.
    fn global(&mut self) -> Option<&mut HomotopyStorage>;
    /// The storage, if there is one.
    fn global_ref(&self) -> Option<&HomotopyStorage>;
}

/// No global planner: homotopy goals are answered `PlannerUnavailable` (the navigator of [`Navigator::new`](super::Navigator::new)).
#[derive(Debug, Clone, Copy, Default)]
pub struct NoGlobalPlanner;

impl GlobalPlanStorage for NoGlobalPlanner {
    fn global(&mut self) -> Option<&mut HomotopyStorage> {
        None
    }
    fn global_ref(&self) -> Option<&HomotopyStorage> {
        None
    }
}

impl<T: core::borrow::BorrowMut<HomotopyStorage>> GlobalPlanStorage for T {
    fn global(&mut self) -> Option<&mut HomotopyStorage> {
        Some(self.borrow_mut())
    }
    fn global_ref(&self) -> Option<&HomotopyStorage> {
        Some(self.borrow())
    }
}

/// Where a homotopy goal is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Phase {
    /// Next step: segment the tile and build the BTM.
    Segment,
    /// Next step: Axel's holding limit.
    Hold,
    /// Next step: Alg. 1 and the world route.
    Route,
    /// The route is planned; legs are driven with ABIT*.
    Legs,
}

/// The homotopy goal being planned or driven.
#[derive(Debug, Clone, Copy)]
pub(crate) struct HomotopyGoal {
    /// The goal request (the final leg's goal region).
    pub goal: GoalRequest,
    pub phase: Phase,
    /// The leg being driven (index into `HomotopyStorage::legs`).
    pub leg: usize,
    /// The leg's ABIT* problem is set up (false: the next drive step sets up leg `leg`).
    pub leg_active: bool,
}

/// Counters of homotopy goals (for tests, logs and reports).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct HomotopyStats {
    /// Global routes planned.
    pub routes: u32,
    /// Legs started.
    pub legs_started: u32,
    /// Tracked anchors farther than `HOMOTOPY_ANCHOR_AGREEMENT_M` from every anchor the route expects, counted
    /// at each leg's start.
    pub anchor_disagreements: u32,
    /// Global replans (Alg. 3): a leg's ABIT* found no path (the onboard map contradicts the tile there), its goal
    /// region became an obstacle of the BTM and the route was planned again. The only reason counted so far.
    pub global_replans: u32,
    /// Global replans that found no route (the mission then stops `NoSolution`).
    pub global_replan_failures: u32,
}

/// The outcome of one planning phase.
pub(crate) enum PhaseOutcome {
    /// More phases to run.
    Continue,
    /// The route is planned: its cost (3D tether length, m) and the classes examined.
    Planned { cost: f32, classes: u32 },
    /// Refused (logged by the caller with the reason).
    Refused(GoalRefusal),
}

/// Runs the next phase of the global plan.
pub(crate) fn phase_step(
    h: &mut HomotopyGoal,
    tile: &HeightTile,
    store: &mut HomotopyStorage,
    setup: &PlanSetup,
    start: Option<&Pose>,
) -> PhaseOutcome {
    let a0 = [f64::from(setup.root.x), f64::from(setup.root.y)];
    let g = [f64::from(h.goal.position.x), f64::from(h.goal.position.y)];
    match h.phase {
        Phase::Segment => segment_phase(h, tile, store, setup, a0, g),
        Phase::Hold => hold_phase(h, store, setup),
        Phase::Route => route_phase(h, tile, store, setup, start),
        Phase::Legs => PhaseOutcome::Continue,
    }
}

// One function per phase, never inlined into each other: each phase's locals (the descent, the A* report, the
// route) live in its own frame, so the deepest stack is the largest phase's, not their sum.

#[inline(never)]
fn segment_phase(
    h: &mut HomotopyGoal,
    tile: &HeightTile,
    store: &mut HomotopyStorage,
    setup: &PlanSetup,
    a0: [f64; 2],
    g: [f64; 2],
) -> PhaseOutcome {
    let params =
        DemParams::for_rover(&setup.rover, f64::from(setup.rover.wheel_mu), HOMOTOPY_CORRIDOR_HALF_WIDTH_M);
    let descent = match DemDescent::segment(tile, a0, g, &params, &mut store.scratch) {
        Ok(d) => d,
        Err(e) => return refuse_dem(e),
    };
    if let Err(e) = descent.check_ends() {
        return refuse_dem(e);
    }
    if let Err(e) = descent.build_btm(&mut store.btm) {
        log::warn!("homotopy: BTM of the descent not built: {e:?}");
        return PhaseOutcome::Refused(GoalRefusal::NoRoute);
    }
    log::info!(
        "homotopy: {} planes, {} obstacles ({} on the edge), {} BTM triangles",
        descent.planes.len(),
        descent.obstacles.len(),
        descent.edge_obstacles.len(),
        store.btm.triangle_count()
    );
    store.model = Some(descent.hold_model());
    store.descent = Some(descent);
    h.phase = Phase::Hold;
    PhaseOutcome::Continue
}

#[inline(never)]
fn hold_phase(h: &mut HomotopyGoal, store: &mut HomotopyStorage, setup: &PlanSetup) -> PhaseOutcome {
    let Some(pm) = store.model else { return PhaseOutcome::Refused(GoalRefusal::NoRoute) };
    let (ax, limits) = axel_model(&pm, &setup.rover);
    log::info!(
        "homotopy: Axel holds within {} deg of upslope on the wall ({} stability checks)",
        limits[0].theta_max_rad.to_degrees(),
        limits[0].checks
    );
    store.model = Some(ax);
    h.phase = Phase::Route;
    PhaseOutcome::Continue
}

#[inline(never)]
fn route_phase(
    h: &mut HomotopyGoal,
    tile: &HeightTile,
    store: &mut HomotopyStorage,
    setup: &PlanSetup,
    start: Option<&Pose>,
) -> PhaseOutcome {
    let (Some(descent), Some(model)) = (store.descent.as_ref(), store.model) else {
        return PhaseOutcome::Refused(GoalRefusal::NoRoute);
    };
    let (mut lc, mut report) = (heapless::Vec::new(), PlanReport::default());
    let plan = preplan(
        &store.btm,
        &model,
        &HomotopyParams::default(),
        &mut store.ws,
        descent.a0,
        descent.g,
        &mut lc,
        &mut report,
    );
    let classes = u32::try_from(report.examined.len()).unwrap_or(u32::MAX);
    let plan = match plan {
        Ok(Some(p)) => p,
        Ok(None) => {
            log::warn!("homotopy: no class passes Alg. 2 ({classes} examined)");
            return PhaseOutcome::Refused(GoalRefusal::NoRoute);
        }
        Err(e) => {
            log::warn!("homotopy: Alg. 1 failed: {e:?}");
            return PhaseOutcome::Refused(GoalRefusal::NoRoute);
        }
    };
    let route = match descent.route_to_world(tile, &plan, f64::from(setup.max_payout_m)) {
        Ok(r) => r,
        Err(RouteError::TetherTooLong { needed_m, max_payout_m }) => {
            log::warn!("homotopy: the route needs {needed_m} m of tether, the spool has {max_payout_m} m");
            return PhaseOutcome::Refused(GoalRefusal::PayoutExceeded);
        }
        Err(e) => {
            log::warn!("homotopy: the route cannot be mapped to the world: {e:?}");
            return PhaseOutcome::Refused(GoalRefusal::RouteRefused);
        }
    };
    let goal = [h.goal.position.x, h.goal.position.y, h.goal.position.z];
    let from = start.map(|p| [p.position.x, p.position.y, p.position.z]);
    if !cut_legs(&route, from, goal, &mut store.legs) {
        log::warn!("homotopy: the route needs more than {HOMOTOPY_MAX_LEGS} legs");
        return PhaseOutcome::Refused(GoalRefusal::RouteRefused);
    }
    let cost = route.tether_length_m as f32;
    log::info!(
        "homotopy: route of {} legs, tether {cost} m, {} intermediate anchors",
        store.legs.len(),
        route.anchors.len()
    );
    store.route = Some(route);
    h.phase = Phase::Legs;
    h.leg = 0;
    h.leg_active = false;
    PhaseOutcome::Planned { cost, classes }
}

/// Tanner et al. Alg. 3 on board (reduced): the leg to `blocked` found no path on the onboard map, so the tile was
/// wrong there. A regular octagon of radius `HOMOTOPY_BLOCK_RADIUS_M` round it (unfolded) is added to the BTM (a
/// local update, Tanner Lemma 1; merged with the obstacles it overlaps into one 8-DOP round them all) and the route
/// planned again from the root anchor with Alg. 1; the legs then start after the route segment nearest to the
/// rover. The tether the rover already paid out is not a constraint of the new plan (Alg. 3's plan from the
/// tether's end is not done).
pub(crate) fn replan_around(
    h: &mut HomotopyGoal,
    tile: &HeightTile,
    store: &mut HomotopyStorage,
    setup: &PlanSetup,
    start: Option<&Pose>,
    blocked: [f32; 2],
) -> PhaseOutcome {
    let Some(c) = store.descent.as_ref().and_then(|d| d.unfold_xy([f64::from(blocked[0]), f64::from(blocked[1])])) else {
        return PhaseOutcome::Refused(GoalRefusal::NoRoute);
    };
    let r = crate::config::nav::HOMOTOPY_BLOCK_RADIUS_M;
    let mut corners: heapless::Vec<crate::plan::homotopy::geo::Pt, 8> = heapless::Vec::new();
    for k in 0..8 {
        let a = (2 * k + 1) as f64 * core::f64::consts::FRAC_PI_8;
        let _ = corners.push(crate::plan::homotopy::geo::pt(c.x + r * libm::cos(a), c.y + r * libm::sin(a)));
    }
    // Where the region overlaps obstacles already in the BTM (a region blocked before, an obstacle of the tile),
    // they become one 8-DOP round all of them (bigger obstacles are conservative). Bounded: each pass takes in one
    // more obstacle.
    let mut hull = dop_support(&corners);
    let mut merged: heapless::Vec<u8, MAX_OBSTACLES> = heapless::Vec::new();
    for _ in 0..MAX_OBSTACLES {
        let poly = dop_polygon(&hull);
        let hit = store.btm.obstacles().find(|(k, o)| !merged.contains(k) && polygons_overlap(&poly, &o.corners));
        let Some((k, o)) = hit else { break };
        dop_merge(&mut hull, &dop_support(&o.corners));
        if merged.push(k).is_err() {
            break;
        }
    }
    let joined = if merged.is_empty() {
        store.btm.add_obstacle(&corners)
    } else {
        let n = merged.len();
        log::info!("homotopy: the blocked region at ({}, {}) merges with {n} obstacles", blocked[0], blocked[1]);
        store.btm.merge_obstacles(&merged, &dop_polygon(&hull))
    };
    if let Err(e) = joined {
        log::warn!("homotopy: the blocked region at ({}, {}) cannot join the BTM: {e:?}", blocked[0], blocked[1]);
        return PhaseOutcome::Refused(GoalRefusal::NoRoute);
    }
    h.phase = Phase::Route;
    route_phase(h, tile, store, setup, start)
}

fn refuse_dem(e: DemError) -> PhaseOutcome {
    log::warn!("homotopy: the tile's descent was not segmented: {e:?}");
    PhaseOutcome::Refused(GoalRefusal::DescentNotSegmented)
}

fn dist2(a: [f32; 3], b: [f32; 3]) -> f32 {
    libm::hypotf(a[0] - b[0], a[1] - b[1])
}

/// The route's waypoints as leg goals (module docs); `false` when they do not fit `HOMOTOPY_MAX_LEGS`.
fn cut_legs(
    route: &WorldRoute,
    from: Option<[f32; 3]>,
    goal: [f32; 3],
    legs: &mut heapless::Vec<[f32; 3], HOMOTOPY_MAX_LEGS>,
) -> bool {
    legs.clear();
    let wp = |w: &[f64; 3]| [w[0] as f32, w[1] as f32, w[2] as f32];
    // the route starts at the root anchor; the rover may already be down it: the legs start after the route segment
    // nearest to the rover (horizontally), never back up the route
    let skip = from.map_or(0, |f| nearest_segment(route, f).saturating_add(1));
    let pts = route.waypoints.iter().skip(skip).map(wp).chain(core::iter::once(goal));
    let mut last = from.or_else(|| route.waypoints.first().map(wp));
    let n = route.waypoints.len().saturating_sub(skip).saturating_add(1);
    for (i, p) in pts.enumerate() {
        let is_goal = i + 1 == n;
        let Some(l) = last else {
            last = Some(p);
            continue;
        };
        let d = dist2(l, p);
        if d < HOMOTOPY_LEG_MIN_M && !is_goal {
            continue;
        }
        // a long stretch in equal parts of at most HOMOTOPY_LEG_MAX_M (bounded: at most HOMOTOPY_MAX_LEGS)
        let parts = libm::ceilf(d / HOMOTOPY_LEG_MAX_M).clamp(1.0, HOMOTOPY_MAX_LEGS as f32) as usize;
        for k in 1..=parts {
            let t = k as f32 / parts as f32;
            let q = [l[0] + t * (p[0] - l[0]), l[1] + t * (p[1] - l[1]), l[2] + t * (p[2] - l[2])];
            if legs.push(q).is_err() {
                return false;
            }
        }
        last = Some(p);
    }
    // the goal is the last leg even when it lies within HOMOTOPY_LEG_MIN_M of the previous one
    if let Some(l) = legs.last_mut() {
        *l = goal;
    }
    !legs.is_empty()
}

/// Index of the route segment `waypoints[k] -> waypoints[k + 1]` horizontally nearest to `p` (0 for a route of
/// fewer than two points).
fn nearest_segment(route: &WorldRoute, p: [f32; 3]) -> usize {
    let mut best = (f32::INFINITY, 0usize);
    for (k, w) in route.waypoints.windows(2).enumerate() {
        let [a, b] = w else { continue };
        let (ax, ay, bx, by) = (a[0] as f32, a[1] as f32, b[0] as f32, b[1] as f32);
        let (dx, dy) = (bx - ax, by - ay);
        let l2 = dx * dx + dy * dy;
        let t = if l2 > 0.0 { (((p[0] - ax) * dx + (p[1] - ay) * dy) / l2).clamp(0.0, 1.0) } else { 0.0 };
        let d = libm::hypotf(ax + t * dx - p[0], ay + t * dy - p[1]);
        if d < best.0 {
            best = (d, k);
        }
    }
    best.1
}

/// The route as plan waypoints (the leg goals, each facing the next, with the root and the anchors the route
/// expects; margin 0: the tile gives no stability margin, the legs' ABIT* plans do).
pub(crate) fn route_waypoints(store: &HomotopyStorage, root: Point3, plan: &mut crate::exec::PlanBuffer) {
    plan.clear();
    let Some(route) = store.route.as_ref() else { return };
    let mut anchors: heapless::Vec<Point3, { crate::config::protocol::MAX_ANCHORS_PER_WAYPOINT }> =
        heapless::Vec::new();
    let _ = anchors.push(root);
    for a in route.anchors.iter() {
        if anchors.push(Point3::new(a[0] as f32, a[1] as f32, a[2] as f32)).is_err() {
            break;
        }
    }
    let legs = store.legs.as_slice();
    for (i, p) in legs.iter().enumerate() {
        let prev = if i == 0 { [root.x, root.y, root.z] } else { legs.get(i - 1).copied().unwrap_or(*p) };
        let yaw = libm::atan2f(p[1] - prev[1], p[0] - prev[0]);
        let (s, c) = (libm::sinf(0.5 * yaw), libm::cosf(0.5 * yaw));
        let w = Waypoint {
            pose: Pose { position: Point3::new(p[0], p[1], p[2]), orientation: Quat { x: 0.0, y: 0.0, z: s, w: c } },
            anchors: anchors.clone(),
            stability_margin: 0.0,
        };
        if plan.push(w).is_err() {
            break;
        }
    }
}

/// Tracked anchors (after the root) farther than `HOMOTOPY_ANCHOR_AGREEMENT_M` from every anchor the route expects.
pub(crate) fn anchor_disagreements(store: &HomotopyStorage, tracked: &crate::tether::AnchorHistory) -> u32 {
    let Some(route) = store.route.as_ref() else { return 0 };
    let mut n = 0u32;
    for a in tracked.as_slice().iter().skip(1) {
        let near = route.anchors.iter().any(|e| {
            let (dx, dy, dz) = (e[0] as f32 - a.point.x, e[1] as f32 - a.point.y, e[2] as f32 - a.point.z);
            libm::sqrtf(dx * dx + dy * dy + dz * dz) <= crate::config::nav::HOMOTOPY_ANCHOR_AGREEMENT_M
        });
        if !near {
            n = n.saturating_add(1);
            log::warn!(
                "homotopy: tracked anchor ({}, {}, {}) is not one the route expects ({} expected)",
                a.point.x,
                a.point.y,
                a.point.z,
                route.anchors.len()
            );
        }
    }
    n
}
