//! The closed-loop mission (issue 18, Paton et al. section VII's descent with the loop closed on board): the mission
//! state machine, the tracked tether state, the path-tracking controller and the checks of the loop's input.
//! The design and every parameter are in the module docs of [`crate::nav`]; the constants are `config::mission`.

use core::borrow::BorrowMut;

use hal::Instant;

use crate::config::mission as mcfg;
use crate::config::tether as tcfg;
use crate::config::nav::MAX_PLAN_ITERATIONS;
use crate::exec::DriveStep;
use crate::geom::{norm3, wrap_angle, Real, Vec3};
use crate::map::{Block, DistanceField, DistanceQuery, Map, UnobservedAsFree, VoxelState};
use crate::plan::tethered::{surface_point, MotionFailure, RoverState, TetherSpace, TetherSpaceParams};
use crate::stability::StabilityOutcome;
use crate::protocol::{
    GoalRequest, MissionConfig, MissionState, MissionStatus, Motion, MotionOutcome, MotionReport, PlanState,
    Point3, Pose, Quat, StopReason, Tracking, TetherReading,
};
use crate::tether::{predict_anchors, Anchor, AnchorHistory};

use super::retained::{GroundPatch, Recovered, RetainedPose, TetherCheckpoint};

use super::planning::{self, GoalRefusal, NavPlanStorage};
use super::Navigator;

/// The rover's body pose as the mission tracks it: axle centre and heading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyPose {
    /// Axle centre, world frame, metres.
    pub position: Vec3,
    /// Heading of the body x axis, radians.
    pub yaw: Real,
}

impl BodyPose {
    fn from_wire(p: &Pose) -> Self {
        let iso = p.to_isometry();
        BodyPose { position: iso.translation.vector, yaw: crate::geom::heading(&iso.rotation) }
    }
    /// As a wire pose (yaw-only orientation: the planner's start takes the position and the heading).
    fn to_wire(self) -> Pose {
        let (s, c) = (libm::sinf(0.5 * self.yaw), libm::cosf(0.5 * self.yaw));
        Pose {
            position: Point3::new(self.position.x, self.position.y, self.position.z),
            orientation: Quat { x: 0.0, y: 0.0, z: s, w: c },
        }
    }
}

/// A drive command handed out and not yet reported.
#[derive(Debug, Clone, Copy)]
struct InFlight {
    from: BodyPose,
    /// Lateral tether direction at the start (see [`lateral_pull`]), for the drift estimate.
    pull: Real,
    /// Horizontal unit direction of a straight drive (signed for reverse) and its length (0 for a turn): a scan
    /// taken while the motion runs may come from anywhere along it.
    dir: (Real, Real),
    reach_m: Real,
}

/// Counters of the mission's input checks (also in `MissionStatus`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MissionCounters {
    /// Tether readings rejected (payout jump beyond the physically possible).
    pub tether_rejected: u32,
    /// Motion-report poses rejected (jump against odometry).
    pub pose_jumps: u32,
    /// Scans not integrated (sensor pose disagrees with odometry).
    pub scans_rejected: u32,
    /// Re-estimates of the anchor history after an encoder disagreement.
    pub tether_reestimates: u32,
    /// Remaining-plan motion checks run after motions and scans.
    pub rechecks: u32,
    /// Re-checks that failed (each triggers a replan).
    pub recheck_failures: u32,
    /// Anchor predictions along executed motions that failed (the history was kept).
    pub propagation_failures: u32,
    /// Re-checks that found the current state stable on the map but below the planner's minimum margin, and
    /// replanned from there through states no worse (`planning::thin_start_escape`) instead of stopping.
    pub thin_margin_replans: u32,
}

/// The mission's state (see the `nav` module docs).
#[derive(Debug, Clone)]
pub struct Mission {
    cfg: MissionConfig,
    max_payout_m: f32,
    max_tension_n: f32,
    weight_n: f32,
    root: Option<Vec3>,
    goal: Option<GoalRequest>,
    state: MissionState,
    reason: StopReason,
    pub(crate) body: Option<BodyPose>,
    in_flight: Option<InFlight>,
    /// A scan changed the map while a motion was in flight: check its segment once ([`Navigator::mission_stop_in_flight`]).
    flight_check_due: bool,
    /// Path segment being driven (`path[seg] -> path[seg + 1]`).
    seg: usize,
    /// Next motion of the plan's motion list (open loop).
    next_open: usize,
    /// Segments left to re-check, starting at `recheck_at` (0 = nothing to re-check).
    recheck_left: usize,
    recheck_at: usize,
    pub(crate) tracked: AnchorHistory,
    /// The history at `executed[0]`, where a re-estimate starts: the root alone, or the history recovered after a
    /// reset (positions before the reset are gone, so a re-estimate from the root would straighten the tether).
    base: AnchorHistory,
    /// A checkpoint found at boot (`nav::retained`), applied by the next `Configure` with the same root anchor.
    recovered: Option<TetherCheckpoint>,
    /// The boot found a checkpoint that does not read back: goals are refused (`TetherStateLost`).
    state_lost: bool,
    /// The body pose was recovered and no motion was reported since (scans are not checked against it).
    unmoved_since_recovery: bool,
    /// The ground round the rover after its last complete scan (checkpointed).
    pub(crate) ground: Option<GroundPatch>,
    /// A recovered ground patch for the navigator to write into the new map (taken at the `Configure` that
    /// continues from the checkpoint).
    pub(crate) ground_to_restore: Option<GroundPatch>,
    /// Re-estimate in progress: the next executed position to propagate to (0 = none), and the history so far.
    reestimate_at: usize,
    reestimate_h: AnchorHistory,
    executed: heapless::Vec<Vec3, { mcfg::EXECUTED_CAPACITY }>,
    payout: Option<(f32, f32, u64)>,
    distance_driven_m: f32,
    margin_n: f32,
    cross_track_m: f32,
    replans: u32,
    /// A look at the goal in progress: the heading to turn to before planning again (`Navigator::look_at_goal`).
    look_yaw: Option<Real>,
    /// Looks left for the current goal (`mcfg::MAX_LOOKS` per goal).
    looks_left: u32,
    /// Replans since the rover last came `REPLAN_PROGRESS_M` nearer the goal (the `ReplanLimit` count).
    replans_stuck: u32,
    /// The tracked pose's least horizontal distance to the goal when `replans_stuck` was last reset, metres.
    progress_mark_m: f32,
    motions_done: u32,
    stalls: u32,
    pose_jump_run: u32,
    scan_reject_run: u32,
    drift_num: f32,
    drift_den: f32,
    /// The last checkpoint's generation (`nav::retained`).
    pub(crate) generation: u32,
    /// Counters of rejected input.
    pub counters: MissionCounters,
}

impl Default for Mission {
    fn default() -> Self {
        Self::new()
    }
}

impl Mission {
    /// No mission yet.
    pub const fn new() -> Self {
        Mission {
            cfg: MissionConfig::DEFAULT,
            max_payout_m: 0.0,
            max_tension_n: 0.0,
            weight_n: 0.0,
            root: None,
            goal: None,
            state: MissionState::Idle,
            reason: StopReason::None,
            body: None,
            in_flight: None,
            flight_check_due: false,
            seg: 0,
            next_open: 0,
            recheck_left: 0,
            recheck_at: 0,
            tracked: AnchorHistory::empty(),
            base: AnchorHistory::empty(),
            recovered: None,
            state_lost: false,
            unmoved_since_recovery: false,
            ground: None,
            ground_to_restore: None,
            reestimate_at: 0,
            reestimate_h: AnchorHistory::empty(),
            executed: heapless::Vec::new(),
            payout: None,
            distance_driven_m: 0.0,
            margin_n: 0.0,
            cross_track_m: 0.0,
            replans: 0,
            look_yaw: None,
            looks_left: 0,
            replans_stuck: 0,
            progress_mark_m: f32::INFINITY,
            motions_done: 0,
            stalls: 0,
            pose_jump_run: 0,
            scan_reject_run: 0,
            drift_num: 0.0,
            drift_den: 0.0,
            generation: 0,
            counters: MissionCounters { tether_rejected: 0, pose_jumps: 0, scans_rejected: 0, tether_reestimates: 0, rechecks: 0, recheck_failures: 0, propagation_failures: 0, thin_margin_replans: 0 },
        }
    }

    /// Mission state and stop reason.
    pub fn state(&self) -> (MissionState, StopReason) {
        (self.state, self.reason)
    }

    /// The tracked body pose (from motion reports), if any.
    pub fn body(&self) -> Option<BodyPose> {
        self.body
    }

    /// The tracked anchor history (root first).
    pub fn tracked(&self) -> &AnchorHistory {
        &self.tracked
    }

    /// The learned drift gain (lateral metres per metre per unit of lateral tether direction).
    pub fn drift_gain(&self) -> f32 {
        if self.drift_den > 1e-6 {
            (self.drift_num / self.drift_den).clamp(-mcfg::DRIFT_GAIN_LIMIT, mcfg::DRIFT_GAIN_LIMIT)
        } else {
            0.0
        }
    }

    fn active(&self) -> bool {
        matches!(self.state, MissionState::Planning | MissionState::Driving | MissionState::Verifying)
    }

    fn stop(&mut self, reason: StopReason) {
        if self.state != MissionState::Safe {
            log::warn!("mission: safe stop: {reason:?}");
        }
        self.state = MissionState::Safe;
        self.reason = reason;
        self.recheck_left = 0;
        self.reestimate_at = 0;
    }

    /// A `Configure`: the tether starts at the root anchor.
    pub(crate) fn configure(&mut self, cfg: &crate::protocol::Configure) {
        self.cfg = cfg.mission;
        self.max_payout_m = cfg.tether.max_payout_m;
        self.max_tension_n = cfg.tether.max_tension_n;
        self.weight_n = cfg.rover.mass_kg * mcfg::STANDARD_GRAVITY;
        let r = cfg.tether.root_anchor;
        let root = Vec3::new(r.x, r.y, r.z);
        self.root = Some(root);
        self.tracked = AnchorHistory::new(Anchor::root(root));
        match self.recovered.take() {
            Some(cp) if norm3(&(cp.root - root)) <= mcfg::RECOVERY_ROOT_TOLERANCE_M => {
                log::info!("mission: continuing from the tether state recovered after the reset: {} anchors", cp.anchors.len());
                self.tracked = cp.anchors;
                // The rover has not moved since: its pose is the plan's start (a sensor pose on a slope is not
                // the axle's). Until it moves, scans are not checked against it: the map went with the reset and
                // the ground surveys again, from the lander's mast too (as before a mission's first motion).
                if let Some(p) = cp.body {
                    self.body = Some(BodyPose { position: p.position, yaw: p.yaw });
                    self.unmoved_since_recovery = true;
                }
                self.ground.clone_from(&cp.ground);
                self.ground_to_restore = cp.ground;
            }
            Some(_) => log::warn!("mission: the recovered tether state has another root anchor: a new deployment"),
            None => {}
        }
        self.base.clone_from(&self.tracked);
        self.executed.clear();
        if let Some(b) = self.body {
            let _ = self.executed.push(b.position);
        }
    }

    /// At boot: what the retained block held. A checkpoint makes the mission `Safe` (`Reset`) until the ground
    /// configures the same root again; an unreadable one makes it `Safe` (`TetherStateLost`) and refuses goals.
    pub(crate) fn recover(&mut self, found: Recovered) {
        match found {
            Recovered::Empty => {}
            Recovered::Valid(cp) => {
                log::warn!("mission: reset: tether state recovered ({} anchors, checkpoint {})", cp.anchors.len(), cp.generation);
                self.tracked.clone_from(&cp.anchors);
                self.generation = cp.generation;
                self.recovered = Some(cp);
                self.stop(StopReason::Reset);
            }
            Recovered::Corrupt => {
                log::error!("mission: reset: the tether checkpoint does not read back; goals are refused");
                self.state_lost = true;
                self.stop(StopReason::TetherStateLost);
            }
        }
    }

    /// The boot found an unreadable checkpoint (see [`Self::recover`]).
    pub fn tether_state_lost(&self) -> bool {
        self.state_lost
    }

    /// What a reset must not lose, once configured (`None` before the first `Configure`).
    pub(crate) fn checkpoint(&self) -> Option<TetherCheckpoint> {
        Some(TetherCheckpoint {
            generation: self.generation,
            root: self.root?,
            anchors: self.tracked.clone(),
            body: self.body.map(|b| RetainedPose { position: b.position, yaw: b.yaw }),
            payout_m: self.payout.map_or(0.0, |(p, _, _)| p),
            goal_id: self.goal.map_or(0, |g| g.goal_id),
            ground: self.ground.clone(),
        })
    }

    fn predicted_payout(&self) -> f32 {
        match self.body {
            Some(b) if !self.tracked.is_empty() => self.tracked.length_to(&b.position),
            _ => 0.0,
        }
    }

    fn remember_executed(&mut self, p: Vec3) {
        if self.executed.is_full() {
            // keep every other position: bounded, still a chain of moves from the first
            let mut k = 0;
            let n = self.executed.len();
            for i in (0..n).step_by(2) {
                if let Some(v) = self.executed.get(i).copied() {
                    if let Some(slot) = self.executed.get_mut(k) {
                        *slot = v;
                    }
                    k += 1;
                }
            }
            self.executed.truncate(k);
        }
        let _ = self.executed.push(p);
    }

    /// The status frame.
    pub fn status(&self) -> MissionStatus {
        let fin = |v: f32| if v.is_finite() { v } else { 0.0 };
        let (payout, tension) = self.payout.map_or((0.0, 0.0), |(p, t, _)| (p, t));
        MissionStatus {
            goal_id: self.goal.map_or(0, |g| g.goal_id),
            state: self.state,
            reason: self.reason,
            distance_driven_m: fin(self.distance_driven_m),
            predicted_payout_m: fin(self.predicted_payout()),
            measured_payout_m: payout,
            tension_n: tension,
            margin_n: fin(self.margin_n),
            cross_track_m: fin(self.cross_track_m),
            replans: self.replans,
            anchors: u8::try_from(self.tracked.len()).unwrap_or(u8::MAX),
            motions_done: self.motions_done,
            tether_rejected: self.counters.tether_rejected,
            pose_jumps: self.counters.pose_jumps,
            scans_rejected: self.counters.scans_rejected,
            tether_reestimates: self.counters.tether_reestimates,
        }
    }
}

/// Signed lateral direction of the tether's pull for a motion along `dir` (unit, horizontal) at `p`: the sine of
/// the angle from `dir` to the horizontal direction toward the last anchor (positive = the tether pulls to the
/// left). Zero when the anchor is (horizontally) at the rover.
fn lateral_pull(tracked: &AnchorHistory, p: &Vec3, dir: (Real, Real)) -> Real {
    let Some(a) = tracked.last() else { return 0.0 };
    let (tx, ty) = (a.point.x - p.x, a.point.y - p.y);
    let n = libm::sqrtf(tx * tx + ty * ty);
    if n < 1e-3 {
        return 0.0;
    }
    (dir.0 * ty - dir.1 * tx) / n
}

/// Horizontal distance of `p` from the segment `a -> b`, and the signed lateral offset (left positive).
fn segment_offset(a: &Vec3, b: &Vec3, p: &Vec3) -> (Real, Real, Real, Real) {
    let (dx, dy) = (b.x - a.x, b.y - a.y);
    let len = libm::sqrtf(dx * dx + dy * dy);
    let (px, py) = (p.x - a.x, p.y - a.y);
    if len < 1e-6 {
        return (libm::sqrtf(px * px + py * py), 0.0, 0.0, 0.0);
    }
    let (ux, uy) = (dx / len, dy / len);
    let along = px * ux + py * uy;
    let lat = ux * py - uy * px;
    let t = crate::geom::clamp(along, 0.0, len);
    let (cx, cy) = (px - t * ux, py - t * uy);
    (libm::sqrtf(cx * cx + cy * cy), lat, along, len)
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>, P: BorrowMut<NavPlanStorage>, H: super::GlobalPlanStorage>
    Navigator<B, I, P, H>
{
    /// The mission (state, counters, tracked tether), for tests and pictures.
    pub fn mission(&self) -> &Mission {
        &self.mission
    }

    /// Takes the ground round the rover from the current map ([`GroundPatch`]: the checkpoint keeps it for a
    /// reset), after each complete scan: centred on the tracked axle, or under the scan's sensor while a motion is
    /// in flight (the tracked pose is the motion's start; the scans along it are where the rover is) or before any
    /// pose is tracked; heights searched about the tracked axle's height (the sensor's without one). A cell keeps
    /// the highest observed surface of its column when the map shows free space `GROUND_PATCH_CLEAR_M` above it.
    /// (A survey from the lander's mast is centred on the axle too, once one is tracked.)
    pub(super) fn take_ground_patch(&mut self, sensor: &Pose) {
        let m = &self.mission;
        let p = match m.body {
            Some(b) if m.in_flight.is_none() => b.position,
            _ => Vec3::new(sensor.position.x, sensor.position.y, sensor.position.z),
        };
        let z = m.body.map_or(p.z, |b| b.position.z);
        let Ok(map) = Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used) else {
            return;
        };
        let mut g = GroundPatch::empty([p.x, p.y], z);
        for k in 0..tcfg::GROUND_PATCH_CELLS {
            let (x, y) = g.cell_xy(k);
            let Some(p) = surface_point(&map, x, y, z + tcfg::GROUND_PATCH_ABOVE_M, z - tcfg::GROUND_PATCH_BELOW_M)
            else {
                continue;
            };
            let above = Vec3::new(p.x, p.y, p.z + tcfg::GROUND_PATCH_CLEAR_M);
            // free space above the ground, not the inside of an obstacle the column starts in (a pole)
            if matches!(map.query(&above), DistanceQuery::Known { distance, .. } if distance >= 0.5 * tcfg::GROUND_PATCH_CLEAR_M) {
                g.set(k, p.z);
            }
        }
        self.mission.ground = Some(g);
    }

    /// Writes the ground patch recovered after a reset into the new map: a vertical ray per cell from
    /// `GROUND_PATCH_CLEAR_M` above its ground, so the ground under and round the rover is observed again where the
    /// ground's survey cannot see it. Then the ESDF.
    pub(super) fn restore_ground_patch(&mut self) {
        let Some(g) = self.mission.ground_to_restore.take() else { return };
        let mut status = self.status;
        let Some(mut map) = self.map() else { return };
        let down = [Vec3::new(0.0, 0.0, -tcfg::GROUND_PATCH_CLEAR_M)];
        let mut cells = 0u32;
        for p in g.points() {
            let origin = crate::geom::Pose3::translation(p.x, p.y, p.z + tcfg::GROUND_PATCH_CLEAR_M);
            let out = map.integrate_points(&origin, &down);
            cells += out.points_integrated;
            status.points_integrated = status.points_integrated.saturating_add(out.points_integrated);
            status.voxels_dropped = status.voxels_dropped.saturating_add(out.voxels_dropped);
        }
        if !map.update_esdf().converged {
            status.esdf_budget_exhausted = status.esdf_budget_exhausted.saturating_add(1);
        }
        self.used = map.blocks_used();
        status.blocks_used = u32::try_from(self.used).unwrap_or(u32::MAX);
        self.status = status;
        log::info!("mission: the ground round the rover restored from the checkpoint: {cells} cells");
    }

    /// The pose the next plan starts from: the tracked body pose, else the last scan's sensor pose.
    pub(super) fn start_pose(&self) -> Option<Pose> {
        self.mission.body.map(BodyPose::to_wire).or(self.pose)
    }

    /// A goal request was set up (`accepted`) or refused; a motion in flight is being stopped by the executive.
    pub(super) fn mission_goal(&mut self, goal: &GoalRequest, accepted: bool) {
        let m = &mut self.mission;
        m.goal = Some(*goal);
        m.replans = 0;
        m.replans_stuck = 0;
        m.progress_mark_m = f32::INFINITY;
        m.distance_driven_m = 0.0;
        m.motions_done = 0;
        m.stalls = 0;
        m.seg = 0;
        m.next_open = 0;
        m.recheck_left = 0;
        m.cross_track_m = 0.0;
        m.reason = StopReason::None;
        m.look_yaw = None;
        m.looks_left = mcfg::MAX_LOOKS;
        if accepted {
            m.state = MissionState::Planning;
            // plan from the tracked tether, not a straight one from the root
            if m.tracked.len() > 1 {
                self.storage.borrow_mut().start_history.clone_from(&m.tracked);
            }
        } else {
            m.stop(StopReason::GoalRefused);
        }
    }

    /// Planning finished with `state`, and nothing the mission could drive came of it (no path; an approximate
    /// one not allowed or without `MIN_APPROXIMATE_PROGRESS_M` of progress), or an approximate path over ground
    /// the map shows all the way to the goal: when the search only spent its iterations, it goes on for another
    /// round of the goal's budget ([`planning::Problem::extend`], up to `MAX_PLAN_ITERATIONS` in all) instead of
    /// stopping `NoSolution` or driving. `true` when the search goes on. An approximate path that stops short of
    /// unobserved ground is driven at once: the rover looks again from its end (the receding horizon). One with
    /// the ground to the goal observed ended where the search ran short, and its end can be a dead end (on a slope
    /// Axel holds only along the fall line, a goal beside the end is reached by going back up,
    /// `host-sim/doc/mission.md`), so it is driven only when the rounds are spent.
    pub(super) fn mission_search_more(&mut self, state: PlanState) -> bool {
        if !self.mission.active() {
            return false;
        }
        let allowed = self.mission.goal.is_some_and(|g| g.allow_approximate);
        let approximate_ok = state == PlanState::ApproximateSolution && self.approximate_drivable(allowed);
        let drivable = match state {
            PlanState::ExactSolution => true,
            PlanState::ApproximateSolution => approximate_ok && !self.ground_observed_to_goal(),
            PlanState::NoSolutionWithinBudget => false,
            _ => return false,
        };
        if drivable {
            return false;
        }
        let Some(problem) = self.problem.as_mut() else { return false };
        if !problem.extend() {
            return false;
        }
        self.stats.search_extensions = self.stats.search_extensions.saturating_add(1);
        let (done, budget) = (problem.done, problem.budget);
        if approximate_ok {
            log::info!("mission: an approximate path over observed ground after {done} iterations: on to {budget}");
        } else {
            log::info!("mission: nothing to drive after {done} iterations ({state:?}): the search goes on to {budget}");
        }
        true
    }

    /// Planning finished with `state` (the path is in the storage when solved).
    pub(super) fn mission_planned(&mut self, state: PlanState) {
        if !self.mission.active() {
            return;
        }
        let approximate_ok = self.approximate_drivable(self.mission.goal.is_some_and(|g| g.allow_approximate));
        let m = &mut self.mission;
        m.seg = 0;
        m.next_open = 0;
        match state {
            PlanState::ExactSolution => {
                m.state = MissionState::Driving;
            }
            PlanState::ApproximateSolution if approximate_ok => {
                m.state = MissionState::Driving;
            }
            PlanState::InvalidInput => m.stop(StopReason::GoalRefused),
            _ => {
                if !self.look_at_goal() {
                    self.mission.stop(StopReason::NoSolution);
                }
            }
        }
        if self.mission.state == MissionState::Driving && self.arrived() {
            self.mission_arrived();
        }
    }

    /// The tracked pose is within the mission goal's tolerance: `Arrived`, or, at the goal of a homotopy route's
    /// intermediate leg, on to the next leg (the mission keeps driving; the next drive step sets the leg up).
    fn mission_arrived(&mut self) {
        let legs = self.global.global_ref().map_or(0, |g| g.legs.len());
        if let Some(h) = self.homotopy.as_mut() {
            if h.phase == super::homotopy::Phase::Legs && h.leg_active && h.leg + 1 < legs {
                log::info!("homotopy: leg {} of {legs} reached", h.leg + 1);
                h.leg += 1;
                h.leg_active = false;
                self.mission.state = MissionState::Driving;
                self.mission.recheck_left = 0;
                return;
            }
            if h.phase == super::homotopy::Phase::Legs && !h.leg_active && h.leg < legs {
                // a leg is due (a new route): the mission's goal is still the old leg's, so this is no arrival
                self.mission.state = MissionState::Driving;
                self.mission.recheck_left = 0;
                return;
            }
        }
        self.mission.state = MissionState::Arrived;
    }

    /// A homotopy route's next leg, when one is due (module docs of `nav`): the mission's goal becomes the leg's, the
    /// tracked anchors are compared with the route's, and tethered ABIT* is set up from the tracked pose and
    /// history. `None`: no leg to start (the mission drives on as usual).
    pub(super) fn mission_start_leg(&mut self, now: Instant) -> Option<DriveStep> {
        let mut h = self.homotopy?;
        if h.phase != super::homotopy::Phase::Legs || h.leg_active {
            return None;
        }
        if !matches!(self.mission.state, MissionState::Driving | MissionState::Verifying) || self.mission.in_flight.is_some() {
            return None;
        }
        let (leg, legs, disagreements) = {
            let g = self.global.global_ref()?;
            let leg = g.legs.get(h.leg).copied()?;
            (leg, g.legs.len(), super::homotopy::anchor_disagreements(g, &self.mission.tracked))
        };
        let last = h.leg + 1 == legs;
        let goal = GoalRequest {
            position: Point3::new(leg[0], leg[1], leg[2]),
            tolerance_m: if last { h.goal.tolerance_m } else { crate::config::nav::HOMOTOPY_LEG_TOLERANCE_M },
            planner: crate::protocol::PlannerChoice::Abit,
            ..h.goal
        };
        h.leg_active = true;
        self.homotopy = Some(h);
        self.hstats.legs_started = self.hstats.legs_started.saturating_add(1);
        self.hstats.anchor_disagreements = self.hstats.anchor_disagreements.saturating_add(disagreements);
        log::info!("homotopy: leg {} of {legs} to ({}, {}, {})", h.leg + 1, leg[0], leg[1], leg[2]);
        let m = &mut self.mission;
        m.goal = Some(goal);
        m.progress_mark_m = f32::INFINITY;
        m.replans_stuck = 0;
        m.recheck_left = 0;
        m.state = MissionState::Driving;
        if self.arrived() {
            // already within the leg's tolerance: on to the next one at the next step
            self.mission_arrived();
            return Some(DriveStep::Wait);
        }
        Some(self.plan_from_here(now))
    }

    /// Whether the mission may drive the stored approximate path: its goal allows one (`allowed`) and the path's
    /// last state is at least `MIN_APPROXIMATE_PROGRESS_M` nearer the goal than its first. The one rule for
    /// `mission_search_more`, `mission_planned` and a homotopy leg's failure.
    pub(super) fn approximate_drivable(&mut self, allowed: bool) -> bool {
        allowed && self.approximate_progress_m() >= mcfg::MIN_APPROXIMATE_PROGRESS_M
    }

    /// How much nearer the goal the last state of the stored plan is than its start (axle to goal position),
    /// metres; negative infinity without a plan.
    fn approximate_progress_m(&mut self) -> Real {
        let Some(goal) = self.mission.goal else { return Real::NEG_INFINITY };
        let g = Vec3::new(goal.position.x, goal.position.y, goal.position.z);
        let path = planning::path(&mut self.storage);
        match (path.first(), path.last()) {
            (Some((a, _)), Some((b, _))) => norm3(&(a.axle() - g)) - norm3(&(b.axle() - g)),
            _ => Real::NEG_INFINITY,
        }
    }

    /// Whether the map shows ground all the way from the stored plan's last state to the goal: an occupied voxel
    /// (the terrain behind an observed surface) in every voxel column on the straight line between their axles,
    /// one voxel apart (at most `mcfg::GROUND_TO_GOAL_SAMPLES` columns, spread evenly on a longer line), within
    /// the planning bounds' heights (at most `mcfg::GROUND_COLUMN_VOXELS` voxels down each column). `false`
    /// without a plan, goal or map.
    fn ground_observed_to_goal(&mut self) -> bool {
        let (Some(goal), Some((top, bottom))) =
            (self.mission.goal, self.problem.as_ref().map(|p| (p.bounds.max[2], p.bounds.min[2])))
        else {
            return false;
        };
        let Some(end) = planning::path(&mut self.storage).last().map(|(s, _)| s.axle()) else { return false };
        let Some(map) = self.map() else { return false };
        let voxel = map.config().voxel_size;
        let (dx, dy) = (goal.position.x - end.x, goal.position.y - end.y);
        let columns = ((libm::hypotf(dx, dy) / voxel) as usize).clamp(1, mcfg::GROUND_TO_GOAL_SAMPLES);
        (0..=columns).all(|k| {
            let f = k as Real / columns as Real;
            column_observed(&map, end.x + f * dx, end.y + f * dy, top, bottom)
        })
    }

    /// Planning ended with nothing to drive: when the goal's voxel column is unobserved and the goal's bearing is
    /// more than `LOOK_MIN_TURN_RAD` from the heading, turn in place to face it (a motion check on the current map
    /// with the tracked tether first), so the next scan looks there, then plan again (`mission_drive`). At most
    /// `MAX_LOOKS` per goal. `true` when a look starts (the mission drives it); `false`: the mission stops.
    fn look_at_goal(&mut self) -> bool {
        let m = &self.mission;
        let start = self.plan_start().map(|s| BodyPose { position: s.axle(), yaw: s.heading() });
        let (Some(goal), Some(b), Some(problem)) = (m.goal, m.body.or(start), self.problem) else { return false };
        let bearing = libm::atan2f(goal.position.y - b.position.y, goal.position.x - b.position.x);
        if m.looks_left == 0 || libm::fabsf(wrap_angle(bearing - b.yaw)) < mcfg::LOOK_MIN_TURN_RAD {
            return false;
        }
        let (cfg, used) = (self.cfg, self.used);
        let Ok(map) = Map::reattach(cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), used) else {
            return false;
        };
        let (top, bottom) = (problem.bounds.max[2], problem.bounds.min[2]);
        if column_observed(&map, goal.position.x, goal.position.y, top, bottom) {
            return false;
        }
        let Some(space) = problem.space(&map) else { return false };
        let (x, y) = (b.position.x, b.position.y);
        let Ok(cur) = space.settle_under_axle(x, y, b.yaw) else { return false };
        let full = wrap_angle(bearing - b.yaw);
        // the whole turn, else the largest part of it that passes (a turn towards the goal widens the view)
        let mut look = None;
        for quarters in (1..=4u8).rev() {
            let yaw = b.yaw + full * Real::from(quarters) / 4.0;
            if libm::fabsf(full) * Real::from(quarters) / 4.0 < mcfg::LOOK_MIN_TURN_RAD {
                break;
            }
            let to = space.settle_under_axle(x, y, yaw).map_err(MotionFailure::Settle);
            match to.and_then(|to| space.check(&cur, &m.tracked, &to)) {
                Ok(_) => {
                    look = Some(yaw);
                    break;
                }
                Err(e) => log::info!("mission: a turn {quarters}/4 of the way to the goal fails on the map: {e:?}"),
            }
        }
        let Some(bearing) = look else { return false };
        log::info!("mission: nothing to drive and the goal's column unobserved: turning to heading {bearing} to look");
        planning::clear_plan(&mut self.storage);
        self.stats.looks = self.stats.looks.saturating_add(1);
        let m = &mut self.mission;
        if m.body.is_none() {
            m.body = Some(b);
            m.remember_executed(b.position);
        }
        m.looks_left = m.looks_left.saturating_sub(1);
        m.look_yaw = Some(bearing);
        m.state = MissionState::Driving;
        true
    }

    fn arrived(&self) -> bool {
        match (self.mission.goal, self.mission.body) {
            (Some(g), Some(b)) => {
                let (dx, dy) = (b.position.x - g.position.x, b.position.y - g.position.y);
                libm::sqrtf(dx * dx + dy * dy) <= g.tolerance_m
            }
            _ => false,
        }
    }

    /// A tether-encoder reading: reject impossible jumps, stop on tension, reconcile payout with the tracked tether.
    pub(super) fn mission_tether(&mut self, r: &TetherReading) {
        let m = &mut self.mission;
        if let Some((p, _, t)) = m.payout {
            let dt = r.time_us.saturating_sub(t) as f32 * 1e-6;
            if libm::fabsf(r.payout_m - p) > mcfg::MAX_PAYOUT_RATE_M_PER_S * dt + mcfg::PAYOUT_JUMP_SLACK_M {
                m.counters.tether_rejected = m.counters.tether_rejected.saturating_add(1);
                log::warn!("mission: tether reading rejected: payout {} m after {} m in {dt} s", r.payout_m, p);
                return;
            }
        }
        m.payout = Some((r.payout_m, r.tension_n, r.time_us));
        if !m.active() {
            return;
        }
        if r.tension_n > m.max_tension_n {
            m.stop(StopReason::TensionLimit);
            return;
        }
        // While a motion is in flight the tracked pose is the motion's start: no comparison (nor while a
        // re-estimate runs).
        if m.in_flight.is_some() || m.body.is_none() || m.reestimate_at != 0 {
            return;
        }
        if libm::fabsf(r.payout_m - m.predicted_payout()) <= m.cfg.payout_tolerance_m {
            return;
        }
        // Re-estimate (in bounded parts, see `reestimate_step`); the rover drives no further until it is done.
        if m.reestimate_at == 0 && !m.base.is_empty() {
            m.counters.tether_reestimates = m.counters.tether_reestimates.saturating_add(1);
            m.reestimate_h.clone_from(&m.base);
            m.reestimate_at = 1;
            log::info!("mission: payout {} m vs tracked {} m: re-estimating the anchors", r.payout_m, m.predicted_payout());
        }
    }

    /// Continue the re-estimate of the anchor history from the root along the executed positions on the current
    /// map (Alg. 1, at most `REESTIMATE_PER_STEP` predictions per call). `Some(consistent)` when it finished.
    fn reestimate_step(&mut self) -> Option<bool> {
        let Ok(map) = Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used) else {
            self.mission.reestimate_at = 0;
            return Some(false);
        };
        let m = &mut self.mission;
        let mut out = AnchorHistory::empty();
        for _ in 0..mcfg::REESTIMATE_PER_STEP {
            let k = m.reestimate_at;
            let (Some(a), Some(b)) = (m.executed.get(k.wrapping_sub(1)).copied(), m.executed.get(k).copied()) else {
                break;
            };
            if predict_anchors(&UnobservedAsFree(&map), &m.reestimate_h, &a, &b, &mut out).is_ok() {
                m.reestimate_h.clone_from(&out);
            } else {
                m.counters.propagation_failures = m.counters.propagation_failures.saturating_add(1);
            }
            m.reestimate_at = k + 1;
        }
        if m.reestimate_at < m.executed.len() {
            return None;
        }
        m.reestimate_at = 0;
        m.tracked.clone_from(&m.reestimate_h);
        log::info!("mission: anchor history re-estimated: {} anchors", m.tracked.len());
        let measured = m.payout.map_or(0.0, |(p, _, _)| p);
        Some(libm::fabsf(measured - m.predicted_payout()) <= m.cfg.payout_tolerance_m)
    }

    /// A scan: `false` when its pose disagrees with the tracked body pose (not integrated, counted).
    pub(super) fn mission_scan_accepted(&mut self, sensor: &Pose) -> bool {
        let m = &mut self.mission;
        let Some(b) = m.body.filter(|_| !m.unmoved_since_recovery) else { return true };
        // While a drive runs (scans every few cm of it), the sensor may be anywhere along it: the distance is to
        // the drive's segment from the pose it started at, not to that pose.
        let (origin, dir, reach) = match m.in_flight {
            Some(f) => (f.from.position, f.dir, f.reach_m),
            None => (b.position, (0.0, 0.0), 0.0),
        };
        let (dx, dy) = (sensor.position.x - origin.x, sensor.position.y - origin.y);
        let along = crate::geom::clamp(dx * dir.0 + dy * dir.1, 0.0, reach);
        let (ex, ey) = (dx - along * dir.0, dy - along * dir.1);
        let off = libm::sqrtf(ex * ex + ey * ey);
        if off <= mcfg::SCAN_POSE_TOLERANCE_M {
            m.scan_reject_run = 0;
            return true;
        }
        m.counters.scans_rejected = m.counters.scans_rejected.saturating_add(1);
        m.scan_reject_run = m.scan_reject_run.saturating_add(1);
        log::warn!("mission: scan rejected: sensor {} m from the body pose (or the drive in flight)", off);
        if m.scan_reject_run >= mcfg::MAX_SCAN_REJECTS && m.active() {
            m.stop(StopReason::ScanInconsistent);
        }
        false
    }

    /// An accepted scan is integrated: re-check the whole remaining plan on the changed map.
    pub(super) fn mission_map_changed(&mut self) {
        let m = &mut self.mission;
        m.flight_check_due = m.in_flight.is_some();
        if matches!(m.state, MissionState::Driving | MissionState::Verifying) {
            m.recheck_at = m.seg;
            m.recheck_left = usize::MAX;
            m.state = MissionState::Verifying;
        }
    }

    /// While a motion is in flight and a scan changed the map: one motion check of the segment being driven, from
    /// where the motion started to the segment's end (what the re-check after a report checks from the current
    /// state), once per scan. `true`: the motion stops now, so the rover does not drive on into what the scan
    /// showed (a rock that appeared in the corridor); the re-check after its report plans again from where it
    /// stopped. (Checked from the plan's state at the segment's start instead, a segment the rover had already
    /// driven part of could fail in flight and pass the re-check from where it stopped, and the rover stopped each
    /// new motion of it, without end.)
    pub(super) fn mission_stop_in_flight(&mut self) -> bool {
        if !core::mem::take(&mut self.mission.flight_check_due) || self.mission.in_flight.is_none() {
            return false;
        }
        let Some(problem) = self.problem else { return false };
        let (cfg, used) = (self.cfg, self.used);
        let Ok(map) = Map::reattach(cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), used) else {
            return false;
        };
        let Some(space) = problem.space(&map) else { return false };
        let m = &mut self.mission;
        let path = &self.storage.borrow_mut().path;
        let k = m.seg;
        m.counters.rechecks = m.counters.rechecks.saturating_add(1);
        let ok = match m.in_flight.map(|f| f.from) {
            Some(from) => match space.settle_under_axle(from.position.x, from.position.y, from.yaw) {
                Ok(start) => check_to_segment_end(&space, &start, &m.tracked, path, k),
                Err(_) => false,
            },
            None => true,
        };
        if !ok {
            m.counters.recheck_failures = m.counters.recheck_failures.saturating_add(1);
            log::info!("mission: segment {k} fails on the map a scan changed while driving it: stop the motion");
        }
        !ok
    }

    /// The report of the motion in flight (the executive checked the command id).
    pub(super) fn mission_report(&mut self, r: &MotionReport, motion: Motion) {
        self.mission.unmoved_since_recovery = false;
        self.mission.flight_check_due = false;
        let flight = self.mission.in_flight.take();
        let reported = BodyPose::from_wire(&r.pose);
        let prev = flight.map(|f| f.from).or(self.mission.body);
        // odometry: the last pose moved by the achieved motion
        let body = match prev {
            Some(p) => {
                let pred = Vec3::new(
                    p.position.x + r.achieved_distance_m * libm::cosf(p.yaw),
                    p.position.y + r.achieved_distance_m * libm::sinf(p.yaw),
                    p.position.z,
                );
                let (dx, dy) = (reported.position.x - pred.x, reported.position.y - pred.y);
                let off = libm::sqrtf(dx * dx + dy * dy);
                let dyaw = libm::fabsf(wrap_angle(reported.yaw - (p.yaw + r.achieved_yaw_rad)));
                let limit = mcfg::POSE_JUMP_BASE_M + mcfg::POSE_JUMP_PER_M * libm::fabsf(r.achieved_distance_m);
                if off > limit || dyaw > mcfg::POSE_JUMP_YAW_RAD {
                    let m = &mut self.mission;
                    m.counters.pose_jumps = m.counters.pose_jumps.saturating_add(1);
                    m.pose_jump_run = m.pose_jump_run.saturating_add(1);
                    log::warn!("mission: pose rejected: {off} m / {dyaw} rad from odometry");
                    if m.pose_jump_run >= mcfg::MAX_POSE_JUMPS && m.active() {
                        m.stop(StopReason::PoseJump);
                    }
                    BodyPose { position: pred, yaw: wrap_angle(p.yaw + r.achieved_yaw_rad) }
                } else {
                    self.mission.pose_jump_run = 0;
                    reported
                }
            }
            None => reported,
        };
        // the drift estimate: lateral displacement of a straight drive against the tether's lateral pull
        if let (Some(f), Motion::Straight { .. }) = (flight, motion) {
            let d = r.achieved_distance_m;
            let sgn = if d < 0.0 { -1.0 } else { 1.0 };
            let dir = (sgn * libm::cosf(f.from.yaw), sgn * libm::sinf(f.from.yaw));
            let (mx, my) = (body.position.x - f.from.position.x, body.position.y - f.from.position.y);
            let lat = dir.0 * my - dir.1 * mx;
            if libm::fabsf(d) >= mcfg::MIN_DRIFT_SAMPLE_M && libm::fabsf(f.pull) > 0.05 {
                let m = &mut self.mission;
                m.drift_num += lat * f.pull;
                m.drift_den += f.pull * f.pull * libm::fabsf(d);
            }
        }
        let from = self.mission.body.map(|b| b.position);
        {
            let m = &mut self.mission;
            m.body = Some(body);
            m.distance_driven_m += libm::fabsf(r.achieved_distance_m);
            m.motions_done = m.motions_done.saturating_add(1);
        }
        self.propagate_tether(from, body.position);
        let m = &mut self.mission;
        match r.outcome {
            MotionOutcome::Stalled => {
                m.stalls = m.stalls.saturating_add(1);
                if m.stalls >= mcfg::MAX_STALLS && m.active() {
                    m.stop(StopReason::MotionStalled);
                }
            }
            MotionOutcome::Completed | MotionOutcome::Slipped | MotionOutcome::Stopped => m.stalls = 0,
        }
        if matches!(m.state, MissionState::Driving | MissionState::Verifying) {
            m.state = MissionState::Verifying;
            m.recheck_at = m.seg;
            m.recheck_left = m.recheck_left.max(mcfg::RECHECK_AFTER_MOTION);
            if r.outcome == MotionOutcome::Stalled {
                // a stall: the plan ahead is blocked in a way the map may not show; plan again
                m.recheck_left = 0;
                m.state = MissionState::Driving;
                self.replan_pending = true;
            }
        }
        self.update_cross_track();
        if matches!(self.mission.state, MissionState::Driving | MissionState::Verifying) && self.arrived() {
            self.mission_arrived();
        }
    }

    /// Alg. 1 along the executed motion, from the tracked history (an error keeps the history, counted).
    fn propagate_tether(&mut self, from: Option<Vec3>, to: Vec3) {
        self.mission.remember_executed(to);
        let Some(from) = from else { return };
        let (dx, dy, dz) = (to.x - from.x, to.y - from.y, to.z - from.z);
        if dx * dx + dy * dy + dz * dz < 1e-6 || self.mission.tracked.is_empty() {
            return;
        }
        let Ok(map) = Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used) else {
            return;
        };
        let m = &mut self.mission;
        let mut out = AnchorHistory::empty();
        if predict_anchors(&UnobservedAsFree(&map), &m.tracked, &from, &to, &mut out).is_ok() {
            m.tracked = out;
        } else {
            m.counters.propagation_failures = m.counters.propagation_failures.saturating_add(1);
        }
    }

    fn update_cross_track(&mut self) {
        let Some(b) = self.mission.body else { return };
        let path = planning::path(&mut self.storage);
        let seg = self.mission.seg;
        let closed = self.mission.cfg.tracking == Tracking::ClosedLoop;
        let mut best = Real::INFINITY;
        for (k, w) in path.windows(2).enumerate() {
            if closed && k < seg {
                continue;
            }
            if let [a, c] = w {
                best = best.min(segment_offset(&a.0.axle(), &c.0.axle(), &b.position).0);
            }
        }
        self.mission.cross_track_m = if best.is_finite() { best } else { 0.0 };
    }

    /// No report within the timeout: the executive stopped the rover.
    pub(super) fn mission_timeout(&mut self) {
        self.mission.in_flight = None;
        if self.mission.active() {
            self.mission.stop(StopReason::MotionTimeout);
        }
    }

    /// A cancel of the current goal.
    pub(super) fn mission_cancel(&mut self) {
        self.problem = None;
        self.mission.stop(StopReason::Cancelled);
    }

    /// Shutdown.
    pub(super) fn mission_abort(&mut self) {
        self.mission.in_flight = None;
        self.mission.stop(StopReason::Shutdown);
    }

    /// One drive step (see [`DriveStep`]).
    pub(super) fn mission_drive(&mut self, now: Instant) -> DriveStep {
        match self.mission.state {
            MissionState::Driving | MissionState::Verifying => {}
            _ => return DriveStep::Finished,
        }
        if self.mission.in_flight.is_some() {
            return DriveStep::Wait;
        }
        if self.mission.reestimate_at != 0 {
            return match self.reestimate_step() {
                None => DriveStep::Wait,
                Some(false) => {
                    self.mission.stop(StopReason::TetherInconsistent);
                    DriveStep::Finished
                }
                // the tether lies otherwise than the plan assumed: plan again from the re-estimated history
                Some(true) => self.replan(now),
            };
        }
        if self.replan_pending || self.mission.cross_track_m > self.mission.cfg.replan_cross_track_m {
            self.replan_pending = false;
            return self.replan(now);
        }
        if self.mission.state == MissionState::Verifying {
            return self.recheck_one(now);
        }
        if let (Some(yaw), Some(b)) = (self.mission.look_yaw.take(), self.mission.body) {
            // one turn (where it ends is near enough: the look needs no precision), then a plan on the map the
            // scan after it grows
            let e = wrap_angle(yaw - b.yaw);
            if libm::fabsf(e) <= mcfg::HEADING_TOLERANCE_RAD {
                return self.replan(now);
            }
            let dir = (libm::cosf(b.yaw), libm::sinf(b.yaw));
            let pull = lateral_pull(&self.mission.tracked, &b.position, dir);
            self.mission.in_flight = Some(InFlight { from: b, pull, dir, reach_m: 0.0 });
            self.replan_pending = true;
            return DriveStep::Motion(Motion::Turn { yaw_rad: e });
        }
        let next = match self.mission.cfg.tracking {
            Tracking::OpenLoop => self.open_loop_motion(),
            Tracking::ClosedLoop => self.closed_loop_motion(),
        };
        match next {
            Some(m) => {
                let Some(b) = self.mission.body.or_else(|| self.plan_start().map(|s| BodyPose { position: s.axle(), yaw: s.heading() })) else {
                    self.mission.stop(StopReason::GoalRefused);
                    return DriveStep::Finished;
                };
                if self.mission.body.is_none() {
                    self.mission.body = Some(b);
                    self.mission.remember_executed(b.position);
                }
                let dir = match m {
                    Motion::Straight { distance_m } if distance_m < 0.0 => (-libm::cosf(b.yaw), -libm::sinf(b.yaw)),
                    _ => (libm::cosf(b.yaw), libm::sinf(b.yaw)),
                };
                let pull = lateral_pull(&self.mission.tracked, &b.position, dir);
                let reach_m = match m {
                    Motion::Straight { distance_m } => libm::fabsf(distance_m),
                    _ => 0.0,
                };
                self.mission.in_flight = Some(InFlight { from: b, pull, dir, reach_m });
                DriveStep::Motion(m)
            }
            None => {
                if self.arrived() {
                    self.mission_arrived();
                    if self.mission.state == MissionState::Arrived {
                        DriveStep::Finished
                    } else {
                        // a homotopy leg's goal: the next step sets the next leg up
                        DriveStep::Wait
                    }
                } else {
                    // the end of an exact plan short of the goal, or of an approximate one (driven up to its last
                    // safe state and no farther): plan again from here on the map the drive has grown
                    self.replan(now)
                }
            }
        }
    }

    fn open_loop_motion(&mut self) -> Option<Motion> {
        let k = self.mission.next_open;
        let m = planning::motion_at(&mut self.storage, k)?;
        self.mission.next_open = k.saturating_add(1);
        Some(m)
    }

    /// The tether-aware path-tracking controller: aim at a point `TRACK_SEGMENT_M` ahead on the current segment,
    /// with a heading feed-forward that cancels the drift the learned model predicts for the tether's lateral pull.
    fn closed_loop_motion(&mut self) -> Option<Motion> {
        let b = self.mission.body.or_else(|| self.plan_start().map(|s| BodyPose { position: s.axle(), yaw: s.heading() }))?;
        let gain = self.mission.drift_gain();
        let tracked = self.mission.tracked.clone();
        let params = TetherSpaceParams::ONBOARD;
        let path = planning::path(&mut self.storage);
        let mut seg = self.mission.seg;
        let mut out = None;
        // bounded: at most one pass over the path's segments
        for _ in 0..path.len() {
            let (Some((a, _)), Some((c, _))) = (path.get(seg), path.get(seg + 1)) else { break };
            if c.off_map {
                break;
            }
            let (pa, pc) = (a.axle(), c.axle());
            let (_, _, along, len) = segment_offset(&pa, &pc, &b.position);
            if len - along < mcfg::SEGMENT_DONE_M || len < 1e-3 {
                seg += 1;
                continue;
            }
            // the planner's drive direction for this segment (Axel drives either way)
            let reverse = super::segment_motions(a, c, &params)
                .iter()
                .flatten()
                .any(|m| matches!(m, Motion::Straight { distance_m } if *distance_m < 0.0));
            let t = (along.max(0.0) + mcfg::TRACK_SEGMENT_M).min(len);
            let (ux, uy) = ((pc.x - pa.x) / len, (pc.y - pa.y) / len);
            let target = (pa.x + t * ux - b.position.x, pa.y + t * uy - b.position.y);
            let dist = libm::sqrtf(target.0 * target.0 + target.1 * target.1);
            if dist < 1e-3 {
                seg += 1;
                continue;
            }
            let dir = (target.0 / dist, target.1 / dist);
            let psi = libm::atan2f(dir.1, dir.0);
            let pull = lateral_pull(&tracked, &b.position, dir);
            // drift per metre is gain * pull to the left: aim right of the target by its angle
            let ff = -libm::atanf(gain * pull);
            let want = if reverse { psi + ff + core::f32::consts::PI } else { psi + ff };
            let e = wrap_angle(want - b.yaw);
            out = Some(if libm::fabsf(e) > mcfg::HEADING_TOLERANCE_RAD {
                Motion::Turn { yaw_rad: e }
            } else {
                let d = dist.min(mcfg::TRACK_SEGMENT_M);
                Motion::Straight { distance_m: if reverse { -d } else { d } }
            });
            break;
        }
        self.mission.seg = seg;
        out
    }

    /// One motion check of the remaining plan on the current map (bounded: one per step), from the current state
    /// for the segment being driven; the current state's stability margin first.
    fn recheck_one(&mut self, now: Instant) -> DriveStep {
        if self.mission.recheck_left == 0 {
            self.mission.state = MissionState::Driving;
            return DriveStep::Wait;
        }
        let Some(problem) = self.problem else {
            self.mission.state = MissionState::Driving;
            return DriveStep::Wait;
        };
        let Some(b) = self.mission.body else {
            self.mission.recheck_left = 0;
            self.mission.state = MissionState::Driving;
            return DriveStep::Wait;
        };
        let (cfg, used) = (self.cfg, self.used);
        let Ok(map) = Map::reattach(cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), used) else {
            self.mission.recheck_left = 0;
            self.mission.state = MissionState::Driving;
            return DriveStep::Wait;
        };
        let Some(space) = problem.space(&map) else {
            self.mission.recheck_left = 0;
            self.mission.state = MissionState::Driving;
            return DriveStep::Wait;
        };
        let m = &mut self.mission;
        let path = &self.storage.borrow_mut().path;
        let k = m.recheck_at;
        m.counters.rechecks = m.counters.rechecks.saturating_add(1);
        let ok = if k == m.seg {
            // from the current state: its margin, then the motion to the end of the current segment
            match space.settle_under_axle(b.position.x, b.position.y, b.yaw) {
                Ok(cur) => {
                    let stable_enough = match space.stable_with(&cur.settled, &m.tracked) {
                        Ok(margin) => {
                            m.margin_n = margin as f32 * m.weight_n;
                            if m.margin_n < m.cfg.min_margin_n {
                                log::warn!("mission: margin {} N below the minimum on the map", m.margin_n);
                                m.stop(StopReason::MarginBelowMinimum);
                                return DriveStep::Finished;
                            }
                            true
                        }
                        Err(e) => {
                            // what the decision is made on, for the field log: the state checked and both booms'
                            // answer
                            let pull = crate::plan::tethered::tether_pull_anchor(&cur.settled, &m.tracked, &problem.rover);
                            let answer = crate::rover::check_pose_stability(&map, &cur.settled, pull.as_ref(), &problem.rover);
                            let a = cur.axle();
                            log::warn!(
                                "mission: the current state is not stable enough on the map ({:?}): axle at ({}, {}, {}), heading {}, roll {}, pulled towards {:?}: {:?}",
                                e,
                                a.x,
                                a.y,
                                a.z,
                                cur.heading(),
                                cur.roll(),
                                pull,
                                answer
                            );
                            let floor = f64::from((m.cfg.min_margin_n / m.weight_n).max(0.0));
                            match answer {
                                // Thin but not below the mission's floor: the rover stands here; plan the way out
                                // from here through states no worse than this one (`planning::thin_start_escape`).
                                Ok((StabilityOutcome::Stable(r), _)) if e == MotionFailure::Unstable && r.margin >= floor => {
                                    m.margin_n = r.margin as f32 * m.weight_n;
                                    m.counters.thin_margin_replans = m.counters.thin_margin_replans.saturating_add(1);
                                    log::info!("mission: margin {} N, below the planner's minimum: replan from here", m.margin_n);
                                    false
                                }
                                _ => {
                                    m.margin_n = 0.0;
                                    m.stop(StopReason::MarginBelowMinimum);
                                    return DriveStep::Finished;
                                }
                            }
                        }
                    };
                    stable_enough && check_to_segment_end(&space, &cur, &m.tracked, path, k)
                }
                Err(_) => false,
            }
        } else {
            planned_segment_checks(&space, path, k)
        };
        m.recheck_at = k + 1;
        m.recheck_left = m.recheck_left.saturating_sub(1);
        if m.recheck_at + 1 >= path.len() {
            m.recheck_left = 0;
        }
        if !ok {
            m.counters.recheck_failures = m.counters.recheck_failures.saturating_add(1);
            m.recheck_left = 0;
            m.state = MissionState::Driving;
            if k > m.seg {
                // A later segment fails; those before it passed on this map (the re-check runs in order from the
                // current one): drive them and plan again at their end, on the map the drive grows (a receding
                // horizon), instead of planning again from here on what is seen from here.
                log::info!("mission: re-check of segment {k} failed on the current map: the plan ends before it");
                planning::truncate_plan(&mut self.storage, k, &TetherSpaceParams::ONBOARD);
                return DriveStep::Wait;
            }
            log::info!("mission: re-check of segment {k} failed on the current map: replan");
            return self.replan(now);
        }
        if m.recheck_left == 0 {
            m.state = MissionState::Driving;
        }
        DriveStep::Wait
    }

    /// Plan again from the tracked pose and anchor history.
    fn replan(&mut self, now: Instant) -> DriveStep {
        let m = &mut self.mission;
        if let (Some(g), Some(b)) = (m.goal, m.body) {
            let d = libm::hypotf(b.position.x - g.position.x, b.position.y - g.position.y);
            if d <= m.progress_mark_m - mcfg::REPLAN_PROGRESS_M || !m.progress_mark_m.is_finite() {
                m.progress_mark_m = d;
                m.replans_stuck = 0;
            }
        }
        if m.replans_stuck >= mcfg::MAX_REPLANS {
            m.stop(StopReason::ReplanLimit);
            return DriveStep::Finished;
        }
        m.replans = m.replans.saturating_add(1);
        m.replans_stuck = m.replans_stuck.saturating_add(1);
        self.plan_from_here(now)
    }

    /// Sets up tethered ABIT* from the tracked pose and anchor history to the mission's goal (a replan, or a homotopy
    /// route's next leg).
    fn plan_from_here(&mut self, now: Instant) -> DriveStep {
        let m = &mut self.mission;
        let (Some(goal), Some(setup)) = (m.goal, self.setup) else {
            m.stop(StopReason::GoalRefused);
            return DriveStep::Finished;
        };
        let Some(pose) = self.start_pose() else {
            self.mission.stop(StopReason::GoalRefused);
            return DriveStep::Finished;
        };
        planning::clear_plan(&mut self.storage);
        self.mission.look_yaw = None;
        let budget = goal.max_iterations.min(MAX_PLAN_ITERATIONS);
        let floor = f64::from((self.mission.cfg.min_margin_n / self.mission.weight_n).max(0.0));
        let tracked = &self.mission.tracked;
        let set_up = match Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used) {
            Ok(map) => planning::set_up(&map, &setup, &pose, &goal, budget, now).map(|mut p| {
                p.margin_escape = planning::thin_start_escape(&map, &p, tracked, map.config().voxel_size, floor);
                if let Some(e) = p.margin_escape {
                    log::info!("mission: the start's margin is thin ({} rover weights): states within {} m of it need only that", e.min_margin, e.radius_m);
                }
                p
            }),
            Err(_) => Err(GoalRefusal::MapEmpty),
        };
        let mut problem = match set_up {
            Ok(problem) => problem,
            Err(why) => {
                log::warn!("mission: replan could not be set up from the current pose");
                self.refuse(why);
                self.problem = None;
                self.mission.stop(StopReason::GoalRefused);
                return DriveStep::Finished;
            }
        };
        // another sample sequence than the plan that failed
        problem.seed ^= u64::from(self.mission.replans).wrapping_mul(0xD1B5_4A32_D192_ED03);
        self.problem = Some(problem);
        self.storage.borrow_mut().start_history.clone_from(&self.mission.tracked);
        self.mission.state = MissionState::Planning;
        self.mission.seg = 0;
        self.mission.next_open = 0;
        self.mission.cross_track_m = 0.0;
        log::info!("mission: replan {} from ({}, {})", self.mission.replans, pose.position.x, pose.position.y);
        DriveStep::Replan
    }
}

/// The map shows ground in the voxel column at `(x, y)`: an occupied voxel (the terrain behind an observed surface)
/// between heights `top` and `bottom`, at most `mcfg::GROUND_COLUMN_VOXELS` voxels down from `top`.
fn column_observed(map: &Map<'_>, x: Real, y: Real, top: Real, bottom: Real) -> bool {
    let depth = (((top - bottom) / map.config().voxel_size) as usize).min(mcfg::GROUND_COLUMN_VOXELS);
    let [x, y, z] = map.voxel_index(&Vec3::new(x, y, top));
    (0..=depth as i32).any(|j| map.voxel_state([x, y, z - j]) == VoxelState::Occupied)
}

/// The motion from `cur` with history `tracked` to the end of the plan's segment `k` passes one motion check on
/// the current map (an off-map end, or no segment `k`: nothing to check).
fn check_to_segment_end<D: DistanceField>(
    space: &TetherSpace<'_, D>,
    cur: &RoverState,
    tracked: &AnchorHistory,
    path: &[(RoverState, AnchorHistory)],
    k: usize,
) -> bool {
    match path.get(k + 1) {
        Some((next, _)) if !next.off_map => space.check(cur, tracked, next).is_ok(),
        _ => true,
    }
}

/// The plan's segment `k` (from its planned state and anchor history to the next state) passes one motion check on
/// `space`'s map; a segment that ends off the map (an unobserved goal) or does not exist passes.
fn planned_segment_checks<D: DistanceField>(
    space: &TetherSpace<'_, D>,
    path: &[(RoverState, AnchorHistory)],
    k: usize,
) -> bool {
    match (path.get(k), path.get(k + 1)) {
        (Some((a, ha)), Some((c, _))) if !c.off_map => space.check(a, ha, c).is_ok(),
        _ => true,
    }
}
