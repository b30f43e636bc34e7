//! The state space: settled states ([`RoverState`]), the surface trace and settling, sampling (uniform and
//! catch-boundary), anchor-history compatibility, and the [`StateSpace`] implementation.

use core::cell::Cell;

use rand_core::Rng;

use crate::config::rover::RoverParams;
use crate::config::tether::ANCHOR_HISTORY_CAPACITY;
use crate::config::tethered::{
    AXLE_SETTLE_HEADING_RAD, AXLE_SETTLE_ROUNDS, AXLE_SETTLE_TOLERANCE_M, CATCH_PAIR_ATTEMPTS, GOAL_SETTLE_YAWS, MAX_WHEEL_CONTACT_INCLINE_RAD, SURFACE_MIN_STEP_M, SURFACE_TRACE_STEPS, SURFACE_UNKNOWN_STEPS,
    SURFACE_UNKNOWN_STEP_M,
};
use crate::geom::{angle_diff, norm3, Real, Vec3};
use crate::map::{DistanceField, DistanceQuery, UnobservedAsFree};
use crate::plan::space::{uniform01, CatchSample, StateSpace, StateValidityChecker};
use crate::rover::{settle, SettleOutcome, SettledPose};
use crate::tether::{predict_anchors, tether_touches, AnchorHistory, PredictStats, TetherError};

use super::phases::{Phase, PhaseClock, PhaseTicks};
use super::{PlanBounds, TetherSpaceParams};

/// A settled rover state (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RoverState {
    /// The surface point the state was settled from.
    pub ground: Vec3,
    /// The yaw about the surface normal given to the settler, radians.
    pub theta: Real,
    /// The settled pose. For an off-map goal only `pose.translation` is meaningful.
    pub settled: SettledPose,
    /// An off-map goal (section VI-B): not settled, outside the planning bounds.
    pub off_map: bool,
}

impl RoverState {
    /// Axle centre, world frame (the tether end used for anchor prediction).
    pub fn axle(&self) -> Vec3 {
        self.settled.pose.translation.vector
    }
    /// Heading of the rover's x axis projected on the horizontal plane, radians.
    pub fn heading(&self) -> Real {
        crate::geom::heading(&self.settled.pose.rotation)
    }
    /// Roll: the angle of the axle (rover y axis) above the horizontal, radians, in `[0, pi/2]`.
    pub fn roll(&self) -> Real {
        let y = self.settled.pose.rotation * Vec3::y();
        libm::asinf(libm::fabsf(y.z).min(1.0))
    }
    /// An off-map goal at `point` (its pose has the identity rotation).
    pub fn off_map_goal(point: Vec3) -> Self {
        let settled = SettledPose {
            pose: crate::geom::Pose3::translation(point.x, point.y, point.z),
            roll_rad: 0.0,
            wheels: [crate::rover::WheelContact { point, normal: Vec3::z(), gap_m: 0.0 }; 2],
            iterations: 0,
        };
        RoverState { ground: point, theta: 0.0, settled, off_map: true }
    }
}

/// The surface under `(x, y)`: the highest **observed** surface of the column between `z_top` and `z_bottom`.
/// Sphere tracing down the distance field; unknown space (a column nobody's ray crossed above the terrain: a floor
/// far below a rim, a slope seen from below) is stepped through by [`SURFACE_UNKNOWN_STEP_M`], at most
/// [`SURFACE_UNKNOWN_STEPS`] times, down to the first observed space. `None` when no surface is reached within
/// [`SURFACE_TRACE_STEPS`] sphere-tracing steps or the unknown-space budget, or below `z_bottom`. Whatever lies
/// unobserved above the surface found is the settler's to refuse: a pose needs observed space round the rover.
pub fn surface_point(map: &impl DistanceField, x: Real, y: Real, z_top: Real, z_bottom: Real) -> Option<Vec3> {
    let mut z = z_top;
    let mut traced = 0;
    let mut unknown = 0;
    while traced < SURFACE_TRACE_STEPS {
        if z < z_bottom {
            return None;
        }
        let p = Vec3::new(x, y, z);
        let DistanceQuery::Known { distance, .. } = map.query(&p) else {
            unknown += 1;
            if unknown > SURFACE_UNKNOWN_STEPS {
                return None;
            }
            z -= SURFACE_UNKNOWN_STEP_M;
            continue;
        };
        traced += 1;
        if !distance.is_finite() {
            return None;
        }
        if distance <= SURFACE_MIN_STEP_M * 0.5 {
            // At most half a minimum step from the surface (or inside it, just below): the settler takes it from
            // here (it starts `settle_delta_m` up along the normal).
            return Some(p);
        }
        z -= distance.max(SURFACE_MIN_STEP_M);
    }
    None
}

/// The tilt of the surface at `ground` (radians from level) and the settler yaw (`settle`'s `theta_m`) that faces
/// straight downhill, from the footprint normal. `None` in unknown space or on level ground.
pub fn fall_line_theta(map: &impl DistanceField, ground: &Vec3, rover: &RoverParams) -> Option<(Real, Real)> {
    let n = crate::rover::footprint_normal(map, ground, rover)?;
    let tilt = libm::acosf(n.z.clamp(-1.0, 1.0));
    // the settler measures yaw about n from world x projected on the tangent plane (world y if x is parallel to n)
    let project = |v: Vec3| crate::geom::normalize3(&(v - n * n.dot(&v)), 1e-4);
    let x_t = project(Vec3::x()).or_else(|| project(Vec3::y()))?;
    let downhill = project(-Vec3::z())?;
    Some((tilt, libm::atan2f(x_t.cross(&downhill).dot(&n), x_t.dot(&downhill))))
}

/// Why a sample or an interpolated state could not be settled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SettleFailure {
    /// No surface under the point within the bounds.
    NoSurface,
    /// The settler found no ground.
    NoGround,
    /// Body collision.
    Collision,
    /// Unknown (unobserved) space.
    UnknownSpace,
    /// The settler ran out of iterations.
    Budget,
    /// A wheel rests on a surface steeper than `MAX_WHEEL_CONTACT_INCLINE_RAD` (a pole's side, a wall), or such
    /// a surface cuts through a wheel's rim so that no drop clears it (`SettleOutcome::Wedged`): the settler's
    /// answer there is not a pose Axel can stand in.
    SteepContact,
    /// Non-finite input.
    InvalidInput,
}

/// Settle the rover at the surface point under `(x, y)` with yaw `theta` about the normal. A pose with a wheel on a
/// surface steeper than `MAX_WHEEL_CONTACT_INCLINE_RAD` is refused ([`SettleFailure::SteepContact`]).
pub fn settle_at(
    map: &impl DistanceField,
    bounds: &PlanBounds,
    rover: &RoverParams,
    x: Real,
    y: Real,
    theta: Real,
) -> Result<RoverState, SettleFailure> {
    settle_checked(map, bounds, rover, x, y, theta, true)
}

/// The state `settle` gives whose axle centre lies horizontally at `(x, y)` with heading `heading`: fixed-point
/// rounds (at most `AXLE_SETTLE_ROUNDS`) move the surface point by the axle's horizontal miss and the settle yaw
/// by the heading's, until within `AXLE_SETTLE_TOLERANCE_M` and `AXLE_SETTLE_HEADING_RAD`. A round that does
/// not settle ends it with that failure (the ground at the rover's own pose is what failed); when the rounds run
/// out the last state is returned (on ground the rover stands on, the miss left is millimetres).
pub fn settle_under_axle_with(
    settle: impl Fn(Real, Real, Real) -> Result<RoverState, SettleFailure>,
    x: Real,
    y: Real,
    heading: Real,
) -> Result<RoverState, SettleFailure> {
    let (mut gx, mut gy, mut theta) = (x, y, heading);
    let mut st = settle(gx, gy, theta)?;
    for _ in 1..AXLE_SETTLE_ROUNDS {
        let a = st.axle();
        let (ex, ey) = (x - a.x, y - a.y);
        let eh = angle_diff(heading, st.heading());
        if libm::hypotf(ex, ey) <= AXLE_SETTLE_TOLERANCE_M && libm::fabsf(eh) <= AXLE_SETTLE_HEADING_RAD {
            break;
        }
        gx += ex;
        gy += ey;
        theta = crate::geom::wrap_angle(theta + eh);
        st = settle(gx, gy, theta)?;
    }
    Ok(st)
}

/// [`settle_at`], with the steep-contact check only when `check_steep` ([`StartEscape::steep_ok`]).
fn settle_checked(
    map: &impl DistanceField,
    bounds: &PlanBounds,
    rover: &RoverParams,
    x: Real,
    y: Real,
    theta: Real,
    check_steep: bool,
) -> Result<RoverState, SettleFailure> {
    if !(x.is_finite() && y.is_finite() && theta.is_finite()) {
        return Err(SettleFailure::InvalidInput);
    }
    let ground = surface_point(map, x, y, bounds.max[2], bounds.min[2]).ok_or(SettleFailure::NoSurface)?;
    settle_on(map, rover, ground, theta, check_steep)
}

/// [`settle_checked`] on the surface point `ground` already found under the query position.
fn settle_on(
    map: &impl DistanceField,
    rover: &RoverParams,
    ground: Vec3,
    theta: Real,
    check_steep: bool,
) -> Result<RoverState, SettleFailure> {
    match settle(map, &ground, theta, rover) {
        SettleOutcome::Settled(settled) if check_steep && settled.wheels.iter().any(|w| rests_on_steep_surface(map, w)) => {
            Err(SettleFailure::SteepContact)
        }
        SettleOutcome::Settled(settled) => Ok(RoverState { ground, theta, settled, off_map: false }),
        SettleOutcome::NoGround => Err(SettleFailure::NoGround),
        SettleOutcome::Collision { .. } => Err(SettleFailure::Collision),
        SettleOutcome::Wedged { .. } => Err(SettleFailure::SteepContact),
        SettleOutcome::UnknownSpace => Err(SettleFailure::UnknownSpace),
        SettleOutcome::BudgetExhausted { .. } => Err(SettleFailure::Budget),
        SettleOutcome::InvalidInput => Err(SettleFailure::InvalidInput),
    }
}

/// Does the wheel rest on a surface steeper than `MAX_WHEEL_CONTACT_INCLINE_RAD`? Both its contact normal and the
/// distance field's gradient at the contact point must say so. The contact normal alone is not enough on a map: on
/// smooth ground its in-plane part points from the rim point nearest the surface to the wheel centre, and a bump of
/// 2 cm (a fifth of a 10 cm voxel) moves that rim point 20 degrees round a 0.35 m wheel, so a 55-degree face reads
/// as 75 degrees here and there. A wheel against a pole's side or a wall meets a steep gradient as well; one resting
/// on an edge meets the gradient of a face of that edge and is left to the stability check (its contact normal).
/// Unobserved contact points count as steep.
pub(super) fn rests_on_steep_surface(map: &impl DistanceField, wheel: &crate::rover::WheelContact) -> bool {
    let limit = libm::cosf(MAX_WHEEL_CONTACT_INCLINE_RAD);
    if wheel.normal.z >= limit {
        return false;
    }
    match map.query(&wheel.point) {
        DistanceQuery::Known { gradient, .. } => match crate::geom::normalize3(&gradient, 1e-6) {
            Some(u) => u.z < limit || u.z.is_nan(),
            None => true,
        },
        DistanceQuery::Unknown => true,
    }
}

/// Counters of the space's work (sampling) and of the motion validator's work and failures, by reason.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct MotionStats {
    /// Sampling draws.
    pub samples_drawn: u32,
    /// Draws that settled.
    pub samples_settled: u32,
    /// Settle calls (samples and interpolated states).
    pub settles: u32,
    /// `predict_anchors` calls.
    pub anchor_predictions: u32,
    /// Stability checks.
    pub stability_checks: u32,
    /// Motions checked.
    pub motions: u32,
    /// Motions found valid.
    pub motions_valid: u32,
    /// Invalid: an interpolated state did not settle (no ground, collision, budget).
    pub fail_settle: u32,
    /// Of `fail_settle`: the body collided with the terrain.
    pub settle_collision: u32,
    /// Of `fail_settle`: a wheel rested on a surface steeper than `MAX_WHEEL_CONTACT_INCLINE_RAD`.
    pub settle_steep: u32,
    /// Invalid: unknown space met (settling, tether sweep or stability).
    pub fail_unknown: u32,
    /// Invalid: anchor prediction failed (history full, budget) or the tether bends too much.
    pub fail_tether: u32,
    /// Invalid: an interpolated state is not statically stable with its anchor history.
    pub fail_unstable: u32,
    /// Invalid: more than `MAX_MOTION_STATES` interpolated states, or an off-map goal too far from the edge.
    pub fail_too_long: u32,
    /// Surface points tested for the tether shadow by the catch-boundary sampler.
    pub catch_probes: u32,
    /// Catch-boundary pairs found (each then settled like a uniform sample).
    pub catch_samples: u32,
}

impl MotionStats {
    /// Adds `other`'s counts to these (saturating): a sum over several steps or searches.
    pub fn add(&mut self, other: &MotionStats) {
        let pairs: [(&mut u32, u32); 16] = [
            (&mut self.samples_drawn, other.samples_drawn),
            (&mut self.samples_settled, other.samples_settled),
            (&mut self.settles, other.settles),
            (&mut self.anchor_predictions, other.anchor_predictions),
            (&mut self.stability_checks, other.stability_checks),
            (&mut self.motions, other.motions),
            (&mut self.motions_valid, other.motions_valid),
            (&mut self.fail_settle, other.fail_settle),
            (&mut self.settle_collision, other.settle_collision),
            (&mut self.settle_steep, other.settle_steep),
            (&mut self.fail_unknown, other.fail_unknown),
            (&mut self.fail_tether, other.fail_tether),
            (&mut self.fail_unstable, other.fail_unstable),
            (&mut self.fail_too_long, other.fail_too_long),
            (&mut self.catch_probes, other.catch_probes),
            (&mut self.catch_samples, other.catch_samples),
        ];
        for (mine, theirs) in pairs {
            *mine = mine.saturating_add(theirs);
        }
    }
}

/// The tether-aware state space over a distance field (the onboard map, or a world on the host).
pub struct TetherSpace<'m, D> {
    pub(super) map: &'m D,
    pub(super) bounds: PlanBounds,
    pub(super) rover: RoverParams,
    pub(super) params: TetherSpaceParams,
    pub(super) stats: Cell<MotionStats>,
    pub(super) escape: Option<StartEscape>,
    pub(super) margin_escape: Option<MarginEscape>,
    pub(super) clock: Option<&'m dyn PhaseClock>,
    pub(super) phases: Cell<PhaseTicks>,
}

/// Where a state may settle with the rover's own body clearance instead of the space's, and, if the start needed
/// it, with a wheel against a steep surface ([`TetherSpace::with_start_escape`]): within `radius_m` (horizontally)
/// of a start that the rover stands on but the map refuses (within the space's extra clearance of a rock that
/// appeared beside it, or a wheel against the rock's side). Without it every motion from such a start fails in its
/// first interpolated state, and a start that does not settle cannot be planned from at all.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StartEscape {
    /// The start's surface point, x (m).
    pub x: Real,
    /// The start's surface point, y (m).
    pub y: Real,
    /// Radius of the zone (m).
    pub radius_m: Real,
    /// The rover with its own clearance.
    pub rover: RoverParams,
    /// Steep wheel contacts accepted in the zone.
    pub steep_ok: bool,
}

/// The way out of a start the rover stands on whose stability margin on the map is below the space's
/// `min_stability_margin` but not below the mission's own floor ([`TetherSpace::with_margin_escape`]): within
/// `radius_m` (horizontally, axle to the start's axle) a state is stable enough with `min_margin` instead. Without it
/// every motion from such a start fails in its first interpolated state, and the mission could only stop where it
/// stands; with it the plan leaves through states no worse than the floor and every state beyond the zone keeps the
/// full minimum.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarginEscape {
    /// The start's axle position, x (m).
    pub x: Real,
    /// The start's axle position, y (m).
    pub y: Real,
    /// Radius of the zone (m).
    pub radius_m: Real,
    /// The smallest margin accepted in the zone, in rover weights (as `min_stability_margin`).
    pub min_margin: f64,
}

impl<'m, D: DistanceField> TetherSpace<'m, D> {
    /// A space over `map` within `bounds`. Errors name the offending parameter.
    pub fn new(
        map: &'m D,
        bounds: PlanBounds,
        rover: RoverParams,
        params: TetherSpaceParams,
    ) -> Result<Self, (&'static str, &'static str)> {
        if !bounds.is_valid() {
            return Err(("bounds", "must be a finite box with min < max on every axis"));
        }
        params.validate()?;
        Ok(Self {
            map,
            bounds,
            rover,
            params,
            stats: Cell::new(MotionStats::default()),
            escape: None,
            margin_escape: None,
            clock: None,
            phases: Cell::new(PhaseTicks::default()),
        })
    }
    /// The same space timing its phases on `clock` ([`PhaseTicks`]; benchmarks only).
    pub fn with_phase_clock(mut self, clock: &'m dyn PhaseClock) -> Self {
        self.clock = Some(clock);
        self
    }
    /// Clock ticks spent per phase so far (all 0 without a [`PhaseClock`]).
    pub fn phase_ticks(&self) -> PhaseTicks {
        self.phases.get()
    }
    /// Runs `work`, adding its ticks to `phase` when a clock is lent.
    pub(super) fn timed<R>(&self, phase: Phase, work: impl FnOnce() -> R) -> R {
        let Some(clock) = self.clock else { return work() };
        let t0 = clock.ticks();
        let r = work();
        let dt = clock.ticks().saturating_sub(t0);
        let mut p = self.phases.get();
        p.add(phase, dt);
        self.phases.set(p);
        r
    }
    /// The same space where a state within `escape.radius_m` of the start that collides with the space's body
    /// clearance settles with the rover's own ([`StartEscape`]).
    pub fn with_start_escape(mut self, escape: Option<StartEscape>) -> Self {
        self.escape = escape;
        self
    }
    /// The space with a [`MarginEscape`] round a start whose margin is thin (`None`: none).
    pub fn with_margin_escape(mut self, escape: Option<MarginEscape>) -> Self {
        self.margin_escape = escape;
        self
    }
    /// The smallest stability margin a state with this pose needs: `min_stability_margin`, or the margin escape's
    /// within its zone.
    pub fn min_margin_at(&self, st: &SettledPose) -> f64 {
        let a = st.pose.translation.vector;
        match self.margin_escape {
            Some(e) if libm::hypotf(a.x - e.x, a.y - e.y) <= e.radius_m => e.min_margin.min(self.params.min_stability_margin),
            _ => self.params.min_stability_margin,
        }
    }
    /// The distance field planned on.
    pub fn map(&self) -> &'m D {
        self.map
    }
    /// The planning bounds.
    pub fn bounds(&self) -> &PlanBounds {
        &self.bounds
    }
    /// The parameters.
    pub fn params(&self) -> &TetherSpaceParams {
        &self.params
    }
    /// The rover model.
    pub fn rover(&self) -> &RoverParams {
        &self.rover
    }
    /// Work counters so far.
    pub fn stats(&self) -> MotionStats {
        self.stats.get()
    }
    pub(super) fn count(&self, f: impl FnOnce(&mut MotionStats)) {
        let mut s = self.stats.get();
        f(&mut s);
        self.stats.set(s);
    }
    /// Anchor prediction (Alg. 1) from `a0` at `x0` to `x1`, through unobserved space as free when
    /// `tether_through_unobserved` is set.
    pub fn predict(&self, a0: &AnchorHistory, x0: &Vec3, x1: &Vec3, out: &mut AnchorHistory) -> Result<PredictStats, TetherError> {
        self.timed(Phase::Anchors, || {
            if self.params.tether_through_unobserved {
                predict_anchors(&UnobservedAsFree(self.map), a0, x0, x1, out)
            } else {
                predict_anchors(self.map, a0, x0, x1, out)
            }
        })
    }
    /// Settle a state at the surface under `(x, y)` (counted).
    pub fn settle_state(&self, x: Real, y: Real, theta: Real) -> Result<RoverState, SettleFailure> {
        self.count(|s| s.settles += 1);
        self.timed(Phase::Settle, || {
            if !(x.is_finite() && y.is_finite() && theta.is_finite()) {
                return Err(SettleFailure::InvalidInput);
            }
            let b = &self.bounds;
            let ground = surface_point(self.map, x, y, b.max[2], b.min[2]).ok_or(SettleFailure::NoSurface)?;
            self.settle_ground(ground, theta)
        })
    }
    /// [`Self::settle_state`] on the surface point `ground` a sampler has already found (not traced again).
    fn settle_state_on(&self, ground: Vec3, theta: Real) -> Result<RoverState, SettleFailure> {
        self.count(|s| s.settles += 1);
        self.timed(Phase::Settle, || self.settle_ground(ground, theta))
    }
    /// The settle of [`Self::settle_state`] at its surface point, with the start escape's relaxed rover near it.
    fn settle_ground(&self, ground: Vec3, theta: Real) -> Result<RoverState, SettleFailure> {
        match (settle_on(self.map, &self.rover, ground, theta, true), self.escape) {
            (Err(SettleFailure::Collision | SettleFailure::SteepContact), Some(e))
                if libm::hypotf(ground.x - e.x, ground.y - e.y) <= e.radius_m =>
            {
                settle_on(self.map, &e.rover, ground, theta, !e.steep_ok)
            }
            (r, _) => r,
        }
    }
    /// The state whose settled axle centre stands horizontally at `(x, y)` with heading `heading` (a pose
    /// estimate: where the rover *is*). [`Self::settle_state`] takes the surface point and the yaw about the
    /// surface normal instead: on a slope the axle stands `r sin(slope)` downhill of its surface point (0.2 m at 35
    /// degrees: the normal leans downhill) and the heading differs from that yaw, so settling the estimate's axle
    /// as a surface point checks a pose 0.2 m downhill of the rover. See [`settle_under_axle_with`].
    pub fn settle_under_axle(&self, x: Real, y: Real, heading: Real) -> Result<RoverState, SettleFailure> {
        settle_under_axle_with(|gx, gy, th| self.settle_state(gx, gy, th), x, y, heading)
    }
    /// A goal state: settled at `(x, y)` when inside the bounds (at the first yaw that settles), an off-map goal at
    /// `point` otherwise.
    pub fn goal_state(&self, point: Vec3, theta: Real) -> Result<RoverState, SettleFailure> {
        if self.bounds.contains_xy(point.x, point.y) {
            // The goal region is a position (the axle within the tolerance): the first of `GOAL_SETTLE_YAWS` yaws,
            // from `theta` round, at which the rover settles there (one yaw may put the body on a ridge).
            let mut first = Err(SettleFailure::InvalidInput);
            for k in 0..GOAL_SETTLE_YAWS {
                let yaw = theta + core::f32::consts::TAU * k as Real / GOAL_SETTLE_YAWS as Real;
                match self.settle_state(point.x, point.y, crate::geom::wrap_angle(yaw)) {
                    Ok(s) => return Ok(s),
                    Err(e) if k == 0 => first = Err(e),
                    Err(_) => {}
                }
            }
            first
        } else if crate::geom::is_finite3(&point) {
            Ok(RoverState::off_map_goal(point))
        } else {
            Err(SettleFailure::InvalidInput)
        }
    }

    /// [`Self::goal_state`], or, when the goal's column is not observed yet ([`SettleFailure::NoSurface`],
    /// [`SettleFailure::UnknownSpace`]: a floor below a lip that no ray has reached), an **unobserved goal**: an
    /// off-map state at `point` inside the bounds, which no motion reaches. A planner tracking approximate solutions
    /// then returns the path to the state nearest to it, and the rover observes the goal on the way (a receding
    /// horizon). A goal on observed ground where the rover does not settle (collision, steep contact, no ground) is
    /// still refused.
    pub fn goal_or_unobserved(&self, point: Vec3, theta: Real) -> Result<RoverState, SettleFailure> {
        match self.goal_state(point, theta) {
            Err(SettleFailure::NoSurface | SettleFailure::UnknownSpace) if crate::geom::is_finite3(&point) => {
                Ok(RoverState::off_map_goal(point))
            }
            r => r,
        }
    }

    pub(super) fn sample_at<R: Rng + ?Sized>(&mut self, rng: &mut R, x: Real, y: Real) -> Option<RoverState> {
        let p = self.params.sample_perturbation_m;
        let px = x + p * (2.0 * uniform01(rng) as Real - 1.0);
        let py = y + p * (2.0 * uniform01(rng) as Real - 1.0);
        let u = uniform01(rng) as Real;
        self.count(|s| s.samples_drawn += 1);
        if !self.bounds.contains_xy(px, py) {
            return None;
        }
        let b = self.bounds;
        let ground = surface_point(self.map, px, py, b.max[2], b.min[2])?;
        let theta = match fall_line_theta(self.map, &ground, &self.rover) {
            Some((tilt, downhill)) if tilt > self.params.fall_line_tilt_rad => {
                downhill + self.params.fall_line_yaw_spread_rad * (2.0 * u - 1.0)
            }
            _ => core::f32::consts::TAU * u - core::f32::consts::PI,
        };
        let st = self.settle_state_on(ground, theta).ok()?;
        self.count(|s| s.samples_settled += 1);
        Some(st)
    }

    /// Is the tether end above the surface point under `(x, y)` (one wheel radius up) in the shadow of terrain
    /// seen from `pivot`, i.e. would a straight tether from `pivot` touch terrain? `None` outside the bounds, over
    /// no surface, or when the line meets unknown space.
    fn in_tether_shadow(&self, pivot: &Vec3, x: Real, y: Real) -> Option<bool> {
        if !self.bounds.contains_xy(x, y) {
            return None;
        }
        self.count(|s| s.catch_probes = s.catch_probes.saturating_add(1));
        let b = self.bounds;
        let ground = surface_point(self.map, x, y, b.max[2], b.min[2])?;
        let end = ground + Vec3::new(0.0, 0.0, self.rover.wheel_radius_m);
        tether_touches(self.map, pivot, &end).ok()
    }

    /// The catch-boundary sampler of [`StateSpace::sample_catch_boundary`]: the Gaussian (bridge) sampling of
    /// obstacle boundaries, applied to the tether's line of sight instead of collision. Draw a uniform `(x, y)`
    /// and a second point within `catch_pair_radius_m` of it; when exactly one of the two is in the tether
    /// shadow of the history's last anchor, settle a state at their midpoint (within half the radius of the
    /// shadow's edge). At most `CATCH_PAIR_ATTEMPTS` pairs.
    fn catch_boundary_sample<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        history: &AnchorHistory,
    ) -> CatchSample<RoverState> {
        let Some(pivot) = history.last().map(|a| a.point) else { return CatchSample::NotFound };
        let b = self.bounds;
        let r = self.params.catch_pair_radius_m;
        for _ in 0..CATCH_PAIR_ATTEMPTS {
            let x = b.min[0] + (b.max[0] - b.min[0]) * uniform01(rng) as Real;
            let y = b.min[1] + (b.max[1] - b.min[1]) * uniform01(rng) as Real;
            let angle = core::f32::consts::TAU * uniform01(rng) as Real;
            let dist = r * libm::sqrtf(uniform01(rng) as Real);
            let (qx, qy) = (x + dist * libm::cosf(angle), y + dist * libm::sinf(angle));
            let Some(p_shadow) = self.in_tether_shadow(&pivot, x, y) else { continue };
            let Some(q_shadow) = self.in_tether_shadow(&pivot, qx, qy) else { continue };
            if p_shadow != q_shadow {
                self.count(|s| s.catch_samples = s.catch_samples.saturating_add(1));
                return match self.sample_at(rng, 0.5 * (x + qx), 0.5 * (y + qy)) {
                    Some(st) => CatchSample::Sampled(st),
                    None => CatchSample::Rejected,
                };
            }
        }
        CatchSample::NotFound
    }

    /// Are two anchor histories compatible? Both are reduced to their **wraps** (runs of consecutive anchors less
    /// than `anchor_cluster_m` apart: one obstacle the tether bends around, e.g. the 8 anchors of half a turn
    /// around a pole), each represented by its last anchor; compatible when they have the same number of wraps and
    /// the representatives lie within `anchor_match_m` of each other. Histories that differ only in how finely
    /// the same wrap was discretised are compatible; wraps on different sides of an obstacle are not.
    pub fn histories_match(&self, a: &AnchorHistory, b: &AnchorHistory) -> bool {
        let (wa, wb) = (wraps(a, self.params.anchor_cluster_m), wraps(b, self.params.anchor_cluster_m));
        wa.len() == wb.len() && wa.iter().zip(wb.iter()).all(|(p, q)| norm3(&(p - q)) <= self.params.anchor_match_m)
    }
}

/// The wraps of a history (see [`TetherSpace::histories_match`]): the last anchor of every run of consecutive
/// anchors closer than `cluster_m`, root first.
pub fn wraps(h: &AnchorHistory, cluster_m: Real) -> heapless::Vec<Vec3, ANCHOR_HISTORY_CAPACITY> {
    let mut out: heapless::Vec<Vec3, ANCHOR_HISTORY_CAPACITY> = heapless::Vec::new();
    let mut prev: Option<Vec3> = None;
    for a in h.as_slice() {
        match (prev, out.last_mut()) {
            (Some(p), Some(last)) if norm3(&(a.point - p)) < cluster_m => *last = a.point,
            _ => {
                let _ = out.push(a.point);
            }
        }
        prev = Some(a.point);
    }
    out
}

impl<D: DistanceField> StateSpace for TetherSpace<'_, D> {
    type State = RoverState;
    type Attachment = AnchorHistory;
    const NON_MARKOVIAN: bool = true;

    /// States live on the 2D surface manifold (plus a yaw that only the cost sees): the RGG terms use d = 2.
    fn dimension(&self) -> usize {
        2
    }
    fn measure(&self) -> f64 {
        self.bounds.area()
    }
    fn distance(&self, a: &RoverState, b: &RoverState) -> f64 {
        f64::from(norm3(&(b.axle() - a.axle())))
    }
    /// Ground point and yaw interpolated, then settled; when that fails, the nearer end state.
    fn interpolate(&self, a: &RoverState, b: &RoverState, t: f64) -> RoverState {
        let t = t.clamp(0.0, 1.0) as Real;
        let g = a.ground + (b.ground - a.ground) * t;
        let theta = a.theta + angle_diff(b.theta, a.theta) * t;
        match self.settle_state(g.x, g.y, theta) {
            Ok(s) => s,
            Err(_) if t < 0.5 => *a,
            Err(_) => *b,
        }
    }
    fn sample_uniform<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Option<RoverState> {
        let b = self.bounds;
        let x = b.min[0] + (b.max[0] - b.min[0]) * uniform01(rng) as Real;
        let y = b.min[1] + (b.max[1] - b.min[1]) * uniform01(rng) as Real;
        self.sample_at(rng, x, y)
    }
    fn attachments_compatible(&self, resulting: &AnchorHistory, existing: &AnchorHistory) -> bool {
        self.histories_match(resulting, existing)
    }
    /// Statically stable with the tether pulling towards the history's pull anchor, margin at least
    /// `min_stability_margin` (the end-state check of a motion that keeps this history).
    fn valid_with_attachment(&self, state: &RoverState, attachment: &AnchorHistory) -> bool {
        self.stable_enough(&state.settled, attachment).is_ok()
    }
    /// Alg. 1 over the straight line between the two axles, from `attachment` (no settling, no stability).
    fn predict_attachment(
        &self,
        from: &RoverState,
        attachment: &AnchorHistory,
        to: &RoverState,
    ) -> Option<AnchorHistory> {
        if from.off_map || to.off_map {
            return None;
        }
        self.count(|s| s.anchor_predictions += 1);
        let mut out = AnchorHistory::default();
        self.predict(attachment, &from.axle(), &to.axle(), &mut out).ok()?;
        Some(out)
    }
    /// Near the edge of the tether shadow of the history's last anchor (see `catch_boundary_sample`).
    fn sample_catch_boundary<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        attachment: &AnchorHistory,
    ) -> CatchSample<RoverState> {
        self.catch_boundary_sample(rng, attachment)
    }
}

/// State validity: settled (every state the space produces is), finite.
#[derive(Debug, Clone, Copy, Default)]
pub struct TetherValidity;

impl<D: DistanceField> StateValidityChecker<TetherSpace<'_, D>> for TetherValidity {
    fn is_valid(&mut self, state: &RoverState) -> bool {
        crate::geom::is_finite3(&state.axle())
    }
}
