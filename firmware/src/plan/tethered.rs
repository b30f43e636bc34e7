//! The tether-aware state space of Paton et al. (*Navigation on the Line*, IROS 2020) sections IV-V: settled
//! SE(3) states on the terrain, motions of in-place turns plus straight drives, validated by settling, body
//! collision, anchor prediction (Alg. 1) and static stability at every interpolated state, with the anchor history
//! as the non-Markovian attachment of [`crate::plan::space`]. Plug it into [`crate::plan::abit::AbitStar`].
//!
//! # States ([`RoverState`])
//! A state is the surface point it was settled from (`ground`), the yaw about the surface normal given to the
//! settler (`theta`), and the settled pose ([`crate::rover::settle`], Fig. 2). A sample (section V): draw `(x, y)`
//! uniformly in the planning bounds, find the terrain surface below it by sphere tracing down the ESDF from the top
//! of the bounds ([`surface_point`]), perturb `(x, y)` by up to `sample_perturbation_m`, draw a yaw, settle.
//! The yaw is uniform on surfaces tilted up to `fall_line_tilt_rad`; on steeper ones it is the downhill fall line
//! plus a uniform perturbation of up to `fall_line_yaw_spread_rad` ([`fall_line_theta`]). Axel holds a steep slope
//! only along the fall line (on the 55-degree slope of Paton et al. VI-A a pose turned 15 degrees off it is already
//! unstable), so a uniformly drawn yaw would waste eleven samples in twelve there; and facing downhill loses nothing,
//! because the rover is symmetric and drives either way. A failed settle (no ground, body collision, unknown space,
//! budget, a wheel on a surface steeper than 75 degrees such as a pole's side) is a failed draw.
//! **Catch-boundary samples** ([`StateSpace::sample_catch_boundary`], a fraction of the planner's draws): the
//! Gaussian (bridge) sampling of obstacle boundaries applied to the tether's line of sight. Two surface points at
//! most `catch_pair_radius_m` apart are drawn; when exactly one of them is in the shadow of the history's last anchor
//! (a straight tether from it to the point's axle height would touch terrain, [`crate::tether::tether_touches`]), the
//! sample is settled at their midpoint. These are the places where the tether starts to wrap an obstacle (behind
//! the pole of Paton et al. VI-A, test 3), which uniform samples rarely straddle. The planner only ever sees settled
//! states, so state validity is settledness; the
//! attachment-dependent checks belong to the motion, except for a sample that copied a neighbour's anchor history
//! (Paton et al. V-A), which must be stable with it (`StateSpace::valid_with_attachment`).
//!
//! # Motions ([`TetherMotionValidator`])
//! From `a` to `b`: turn in place at `a` to the drive heading, drive the straight line from `a.ground` to
//! `b.ground` (its `(x, y)` projection; the surface under each point found by the same trace), turn in place at
//! `b` to `b`'s yaw. Axel drives either way, so the drive heading is the one of `{psi, psi + pi}` that needs less
//! turning. Interpolated states are `drive_resolution_m` apart along the drive and `turn_resolution_rad` apart in
//! the turns; where two consecutive drive states tilt more than `refine_tilt_rad` apart (an edge such as the lip of
//! the ledge, over which the margin of the straddling pose dips to zero within ~0.1 m, less than a drive step),
//! the step between them is also checked at `refine_substeps` evenly spaced points, and each of these states must
//! also be stable settled `surface_uncertainty_m` ahead and behind along the drive (the map's edge is not where the
//! true edge is); each is settled (body collision included), its tether end (the axle centre) is moved from the
//! previous state's with [`predict_anchors`] (skipped when it moved less than `tether_still_m`), and it must be
//! statically stable ([`check_pose_stability`]) with a margin of at least `min_stability_margin`, the tether pulling
//! towards the last anchor of the history that lies beyond the boom's reach ([`tether_pull_anchor`]: an anchor
//! closer than the boom, e.g. the lip right after the rover went over it, is under the boom, which rests on it). The motion's attachment is the anchor history at `b`. Every failure is counted by
//! reason ([`MotionStats`]). A tether that bends more than `max_tether_bend_rad` in total over its anchors
//! ([`tether_bend`]) makes the motion invalid: the stability model treats anchors as frictionless, while a real
//! tether wrapped by an angle `phi` carries a tension ratio of up to `exp(mu phi)` (the capstan equation) across the
//! wrap; the limit also keeps the planner from exploring paths that circle an obstacle again and again.
//!
//! # Objective ([`TetherObjective`])
//! `cost = w_length * |axle_b - axle_a| + w_yaw * (|turn at a| + |turn at b|) + w_roll * |axle_b - axle_a| *
//! (|roll_a| + |roll_b|) / 2` (roll: the angle of the axle above the horizontal). The heuristic is
//! `w_length * |axle_b - axle_a|`, a lower bound of the cost. Informed samples are drawn in the 2D ellipse of the
//! `(x, y)` projection (which contains the informed set, because the heuristic only grows with the third
//! coordinate) and kept when the settled state's heuristic sum is below the best cost.
//!
//! # Off-map goals (section VI-B)
//! A goal outside the planning bounds ([`RoverState::off_map`]) connects from any state within `off_map_edge_m` of
//! the bounds (in `x, y`), at the cost of the straight-line distance.
//!
//! # Anchor-history compatibility (section V-A)
//! Rewiring is only allowed between compatible histories. Anchor prediction discretises a tether wrapped around a
//! curved obstacle into many anchors (about one per 0.4 rad on the 0.25 m pole), so two tree vertices reached around
//! the same side of the same pole rarely hold identical lists. Histories are therefore compared by their wraps
//! ([`wraps`]: runs of consecutive anchors closer than `anchor_cluster_m`, each represented by its last anchor):
//! compatible when they have as many wraps and the representatives lie within `anchor_match_m`
//! ([`TetherSpace::histories_match`]). Every returned path is re-checked from the root anchor when it is
//! re-validated, so this tolerance cannot hide an unstable path.
//!
//! # Parameters ([`TetherSpaceParams::DEFAULT`], `config::tethered::defaults`)
//! | parameter | default |
//! |---|---|
//! | `w_length`, `w_yaw`, `w_roll` | 1.0 /m, 0.25 /rad, 1.0 /(rad m) |
//! | `drive_resolution_m` | 0.2 m |
//! | `turn_resolution_rad` | 0.5 rad |
//! | `tether_still_m` | 0.01 m |
//! | `min_stability_margin` | 0.02 rover weights |
//! | `sample_perturbation_m` | 0.05 m |
//! | `off_map_edge_m` | 1.0 m |
//! | `anchor_match_m` | 0.3 m |
//! | `anchor_cluster_m` | 0.6 m |
//! | `max_tether_bend_rad` | 4.71 rad (270 degrees) |
//! | `fall_line_tilt_rad` | 0.35 rad (20 degrees) |
//! | `fall_line_yaw_spread_rad` | 0.15 rad (8.6 degrees) |
//! | `refine_tilt_rad` | 0.1 rad (6 degrees) |
//! | `refine_substeps` | 8 (0.025 m sub-steps; at most `MAX_REFINE_SUBSTEPS = 16`) |
//! | `surface_uncertainty_m` | 0 m (exact field; the campaign sets half a voxel when planning on the map) |
//! | `catch_pair_radius_m` | 0.5 m |
//!
//! Budgets (`config::tethered`): `SURFACE_TRACE_STEPS = 64` (minimum step `SURFACE_MIN_STEP_M = 0.05`),
//! `MAX_MOTION_STATES = 256` interpolated states per motion, `CATCH_PAIR_ATTEMPTS = 512` point pairs per
//! catch-boundary sample.

use core::cell::Cell;

use rand_core::Rng;

use crate::config::rover::RoverParams;
use crate::config::tether::ANCHOR_HISTORY_CAPACITY;
use crate::config::tethered::{
    defaults, BOOM_REACH_CLEARANCE_M, CATCH_PAIR_ATTEMPTS, MAX_MOTION_STATES, MAX_REFINE_SUBSTEPS,
    MAX_WHEEL_CONTACT_INCLINE_RAD, SURFACE_MIN_STEP_M, SURFACE_TRACE_STEPS,
};
use crate::geom::{norm3, Real, Vec3};
use crate::map::{DistanceField, DistanceQuery};
use crate::plan::space::{
    uniform01, CatchSample, Cost, InformedSample, MotionCheck, MotionValidator, OptimizationObjective, StateSpace,
    StateValidityChecker,
};
use crate::rover::{check_pose_stability, settle, SettleOutcome, SettledPose};
use crate::stability::StabilityOutcome;
use crate::tether::{predict_anchors, tether_touches, AnchorHistory, TetherError};

/// Parameters of the space (see the module docs for their meaning and defaults).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TetherSpaceParams {
    /// Objective weight of axle travel, per metre.
    pub w_length: f64,
    /// Objective weight of in-place turning, per radian.
    pub w_yaw: f64,
    /// Objective weight of roll, per radian per metre.
    pub w_roll: f64,
    /// Spacing of interpolated states along a drive, metres.
    pub drive_resolution_m: Real,
    /// Spacing of interpolated headings of a turn, radians.
    pub turn_resolution_rad: Real,
    /// Tether-end motion below which anchor prediction is skipped, metres.
    pub tether_still_m: Real,
    /// Smallest stability margin of every interpolated state (fraction of the rover's weight).
    pub min_stability_margin: f64,
    /// Half-width of the (x, y) perturbation of a sampled surface point, metres.
    pub sample_perturbation_m: Real,
    /// Distance from the bounds within which a state connects to an off-map goal, metres.
    pub off_map_edge_m: Real,
    /// Anchor-matching tolerance of history compatibility, metres.
    pub anchor_match_m: Real,
    /// Consecutive anchors closer than this belong to one wrap, metres.
    pub anchor_cluster_m: Real,
    /// Largest total bend of the tether over all its anchors, radians.
    pub max_tether_bend_rad: Real,
    /// Samples on surfaces tilted more than this face along the fall line, radians.
    pub fall_line_tilt_rad: Real,
    /// Half-width of the uniform yaw perturbation about the fall line, radians.
    pub fall_line_yaw_spread_rad: Real,
    /// Two consecutive drive states whose rover frames tilt more than this apart are refined, radians.
    pub refine_tilt_rad: Real,
    /// Sub-steps a refined drive step is split into (1 = no refinement, at most `MAX_REFINE_SUBSTEPS`).
    pub refine_substeps: u32,
    /// How far the field's surfaces may be from the true terrain, metres (0 for an exact field; half a voxel for
    /// a map). Every state of a refined drive step must also be stable settled this far ahead and behind along
    /// the drive, with the same anchor history.
    pub surface_uncertainty_m: Real,
    /// Largest distance between the two surface points of a catch-boundary pair, metres
    /// ([`TetherSpace::sample_catch_boundary`]).
    pub catch_pair_radius_m: Real,
}

impl TetherSpaceParams {
    /// The defaults of `config::tethered::defaults`.
    pub const DEFAULT: TetherSpaceParams = TetherSpaceParams {
        w_length: defaults::W_LENGTH,
        w_yaw: defaults::W_YAW,
        w_roll: defaults::W_ROLL,
        drive_resolution_m: defaults::DRIVE_RESOLUTION_M,
        turn_resolution_rad: defaults::TURN_RESOLUTION_RAD,
        tether_still_m: defaults::TETHER_STILL_M,
        min_stability_margin: defaults::MIN_STABILITY_MARGIN,
        sample_perturbation_m: defaults::SAMPLE_PERTURBATION_M,
        off_map_edge_m: defaults::OFF_MAP_EDGE_M,
        anchor_match_m: defaults::ANCHOR_MATCH_M,
        anchor_cluster_m: defaults::ANCHOR_CLUSTER_M,
        max_tether_bend_rad: defaults::MAX_TETHER_BEND_RAD,
        fall_line_tilt_rad: defaults::FALL_LINE_TILT_RAD,
        fall_line_yaw_spread_rad: defaults::FALL_LINE_YAW_SPREAD_RAD,
        refine_tilt_rad: defaults::REFINE_TILT_RAD,
        refine_substeps: defaults::REFINE_SUBSTEPS,
        surface_uncertainty_m: defaults::SURFACE_UNCERTAINTY_M,
        catch_pair_radius_m: defaults::CATCH_PAIR_RADIUS_M,
    };

    /// The first field that is out of range, with the reason.
    pub fn validate(&self) -> Result<(), (&'static str, &'static str)> {
        let pos = |v: f64| v > 0.0 && v.is_finite();
        let nonneg = |v: f64| v >= 0.0 && v.is_finite();
        if !pos(self.w_length) {
            return Err(("w_length", "must be > 0 (it makes the heuristic informative)"));
        }
        if !nonneg(self.w_yaw) || !nonneg(self.w_roll) {
            return Err(("w_yaw/w_roll", "must be >= 0 and finite"));
        }
        if !pos(f64::from(self.drive_resolution_m)) || !pos(f64::from(self.turn_resolution_rad)) {
            return Err(("drive_resolution_m/turn_resolution_rad", "must be > 0 and finite"));
        }
        if !nonneg(f64::from(self.tether_still_m))
            || !nonneg(f64::from(self.sample_perturbation_m))
            || !nonneg(f64::from(self.off_map_edge_m))
            || !nonneg(f64::from(self.anchor_match_m))
            || !nonneg(f64::from(self.anchor_cluster_m))
            || !nonneg(f64::from(self.max_tether_bend_rad))
            || !nonneg(f64::from(self.fall_line_tilt_rad))
            || !nonneg(f64::from(self.fall_line_yaw_spread_rad))
        {
            return Err(("tether_still_m/sample_perturbation_m/off_map_edge_m/anchor_match_m", "must be >= 0"));
        }
        if !self.min_stability_margin.is_finite() {
            return Err(("min_stability_margin", "must be finite"));
        }
        if !pos(f64::from(self.refine_tilt_rad)) {
            return Err(("refine_tilt_rad", "must be > 0 and finite"));
        }
        if !nonneg(f64::from(self.surface_uncertainty_m)) {
            return Err(("surface_uncertainty_m", "must be >= 0 and finite"));
        }
        if !pos(f64::from(self.catch_pair_radius_m)) {
            return Err(("catch_pair_radius_m", "must be > 0 and finite"));
        }
        if self.refine_substeps == 0 || self.refine_substeps > MAX_REFINE_SUBSTEPS {
            return Err(("refine_substeps", "must be in 1..=MAX_REFINE_SUBSTEPS (config::tethered)"));
        }
        Ok(())
    }
}

impl Default for TetherSpaceParams {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The planning bounds: an axis-aligned box; samples are drawn in its `(x, y)` rectangle and surfaces are searched
/// from `max[2]` down to `min[2]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanBounds {
    /// Lower corner, world frame.
    pub min: [Real; 3],
    /// Upper corner, world frame.
    pub max: [Real; 3],
}

impl PlanBounds {
    /// Are the bounds a proper finite box?
    pub fn is_valid(&self) -> bool {
        self.min.iter().chain(self.max.iter()).all(|v| v.is_finite())
            && self.min.iter().zip(self.max.iter()).all(|(a, b)| a < b)
    }
    /// Is `(x, y)` inside the rectangle?
    pub fn contains_xy(&self, x: Real, y: Real) -> bool {
        x >= self.min[0] && x <= self.max[0] && y >= self.min[1] && y <= self.max[1]
    }
    /// Distance of `(x, y)` (inside) to the nearest side of the rectangle.
    pub fn edge_distance_xy(&self, x: Real, y: Real) -> Real {
        let dx = (x - self.min[0]).min(self.max[0] - x);
        let dy = (y - self.min[1]).min(self.max[1] - y);
        dx.min(dy)
    }
    /// Area of the rectangle, m^2.
    pub fn area(&self) -> f64 {
        f64::from(self.max[0] - self.min[0]) * f64::from(self.max[1] - self.min[1])
    }
}

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
        let x = self.settled.pose.rotation * Vec3::x();
        libm::atan2f(x.y, x.x)
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

/// The surface under `(x, y)`: sphere tracing down the distance field from `z_top` to `z_bottom`. `None` when no
/// surface is reached within [`SURFACE_TRACE_STEPS`] or a query meets unknown space.
pub fn surface_point(map: &impl DistanceField, x: Real, y: Real, z_top: Real, z_bottom: Real) -> Option<Vec3> {
    let mut z = z_top;
    for _ in 0..SURFACE_TRACE_STEPS {
        if z < z_bottom {
            return None;
        }
        let p = Vec3::new(x, y, z);
        let DistanceQuery::Known { distance, .. } = map.query(&p) else { return None };
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
    /// A wheel rests on a surface steeper than `MAX_WHEEL_CONTACT_INCLINE_RAD` (a pole's side, a wall): the
    /// settler's answer there is not a pose Axel can stand in.
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
    if !(x.is_finite() && y.is_finite() && theta.is_finite()) {
        return Err(SettleFailure::InvalidInput);
    }
    let ground = surface_point(map, x, y, bounds.max[2], bounds.min[2]).ok_or(SettleFailure::NoSurface)?;
    match settle(map, &ground, theta, rover) {
        SettleOutcome::Settled(settled)
            if settled.wheels.iter().any(|w| w.normal.z < libm::cosf(MAX_WHEEL_CONTACT_INCLINE_RAD)) =>
        {
            Err(SettleFailure::SteepContact)
        }
        SettleOutcome::Settled(settled) => Ok(RoverState { ground, theta, settled, off_map: false }),
        SettleOutcome::NoGround => Err(SettleFailure::NoGround),
        SettleOutcome::Collision { .. } => Err(SettleFailure::Collision),
        SettleOutcome::UnknownSpace => Err(SettleFailure::UnknownSpace),
        SettleOutcome::BudgetExhausted { .. } => Err(SettleFailure::Budget),
        SettleOutcome::InvalidInput => Err(SettleFailure::InvalidInput),
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

/// The tether-aware state space over a distance field (the onboard map, or a world on the host).
pub struct TetherSpace<'m, D> {
    map: &'m D,
    bounds: PlanBounds,
    rover: RoverParams,
    params: TetherSpaceParams,
    stats: Cell<MotionStats>,
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
        Ok(Self { map, bounds, rover, params, stats: Cell::new(MotionStats::default()) })
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
    fn count(&self, f: impl FnOnce(&mut MotionStats)) {
        let mut s = self.stats.get();
        f(&mut s);
        self.stats.set(s);
    }
    /// Settle a state at the surface under `(x, y)` (counted).
    pub fn settle_state(&self, x: Real, y: Real, theta: Real) -> Result<RoverState, SettleFailure> {
        self.count(|s| s.settles += 1);
        settle_at(self.map, &self.bounds, &self.rover, x, y, theta)
    }
    /// A goal state: settled at `(x, y)` when inside the bounds, an off-map goal at `point` otherwise.
    pub fn goal_state(&self, point: Vec3, theta: Real) -> Result<RoverState, SettleFailure> {
        if self.bounds.contains_xy(point.x, point.y) {
            self.settle_state(point.x, point.y, theta)
        } else if crate::geom::is_finite3(&point) {
            Ok(RoverState::off_map_goal(point))
        } else {
            Err(SettleFailure::InvalidInput)
        }
    }

    fn sample_at<R: Rng + ?Sized>(&mut self, rng: &mut R, x: Real, y: Real) -> Option<RoverState> {
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
        let st = self.settle_state(px, py, theta).ok()?;
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

    /// The stability of a settled state with the last anchor of `history` (counted). `Ok(margin)` when stable
    /// with at least `min_stability_margin`.
    pub fn stable_with(&self, st: &SettledPose, history: &AnchorHistory) -> Result<f64, MotionFailure> {
        self.count(|s| s.stability_checks += 1);
        let pull = tether_pull_anchor(st, history, &self.rover);
        match check_pose_stability(self.map, st, pull.as_ref(), &self.rover) {
            Ok((StabilityOutcome::Stable(r), _)) if r.margin >= self.params.min_stability_margin => Ok(r.margin),
            Ok((StabilityOutcome::Unknown(_), _)) => Err(MotionFailure::Unknown),
            _ => Err(MotionFailure::Unstable),
        }
    }

    /// Check a motion (see the module docs) and return the anchor history at its end.
    pub fn check(&self, from: &RoverState, history: &AnchorHistory, to: &RoverState) -> Result<AnchorHistory, MotionFailure> {
        self.count(|s| s.motions += 1);
        let r = self.check_inner(from, history, to);
        self.count(|s| match &r {
            Ok(_) => s.motions_valid += 1,
            Err(MotionFailure::Settle(SettleFailure::UnknownSpace)) | Err(MotionFailure::Unknown) => {
                s.fail_unknown += 1
            }
            Err(MotionFailure::Settle(_)) => s.fail_settle += 1,
            Err(MotionFailure::Tether(TetherError::UnknownSpace)) => s.fail_unknown += 1,
            Err(MotionFailure::Tether(_)) | Err(MotionFailure::TetherBend) => s.fail_tether += 1,
            Err(MotionFailure::Unstable) => s.fail_unstable += 1,
            Err(MotionFailure::TooLong) | Err(MotionFailure::OffMap) => s.fail_too_long += 1,
        });
        r
    }

    fn check_inner(&self, from: &RoverState, history: &AnchorHistory, to: &RoverState) -> Result<AnchorHistory, MotionFailure> {
        if from.off_map {
            return Err(MotionFailure::OffMap);
        }
        if to.off_map {
            let a = from.axle();
            return if self.bounds.edge_distance_xy(a.x, a.y) <= self.params.off_map_edge_m {
                Ok(history.clone())
            } else {
                Err(MotionFailure::OffMap)
            };
        }
        let plan = MotionPlan::new(from, to, &self.params);
        if plan.total_states() > MAX_MOTION_STATES {
            return Err(MotionFailure::TooLong);
        }
        let mut walk = TetherWalk { hist: history.clone(), scratch: AnchorHistory::default(), tether_end: from.axle() };
        let mut prev = *from;
        for k in 1..=plan.total_states() {
            let point = plan.state(k);
            let mut refined = false;
            let st = match point {
                MotionPoint::Turn { at_end, theta } => {
                    let base = if at_end { to } else { from };
                    self.settle_state(base.ground.x, base.ground.y, theta).map_err(MotionFailure::Settle)?
                }
                MotionPoint::Drive { x, y, theta } => {
                    let st = self.settle_state(x, y, theta).map_err(MotionFailure::Settle)?;
                    // Over an edge (the lip of a ledge) the margin can dip to zero within a few centimetres, less
                    // than one drive step: where the rover frame tilts a lot between two drive states, the states
                    // in between are checked too.
                    if tilt_between(&prev.settled, &st.settled) > self.params.refine_tilt_rad {
                        let n = self.params.refine_substeps.min(MAX_REFINE_SUBSTEPS);
                        for j in 1..n {
                            let t = j as Real / n as Real;
                            let g = prev.ground + (st.ground - prev.ground) * t;
                            let mid = self.settle_state(g.x, g.y, theta).map_err(MotionFailure::Settle)?;
                            self.advance(&mut walk, &mid)?;
                            self.stable_nearby(&mid, &(st.ground - prev.ground), &walk.hist)?;
                        }
                        refined = true;
                    }
                    st
                }
                MotionPoint::End => *to,
            };
            self.advance(&mut walk, &st)?;
            if refined {
                self.stable_nearby(&st, &(st.ground - prev.ground), &walk.hist)?;
            }
            prev = st;
        }
        Ok(walk.hist)
    }

    /// A state on an edge must also be stable where the true terrain may put it: settled `surface_uncertainty_m`
    /// ahead and behind along the drive direction `along`, with the same anchor history (the map's rounded edge sits
    /// up to half a voxel from the true one, and the margin over an edge changes within centimetres).
    fn stable_nearby(&self, st: &RoverState, along: &Vec3, hist: &AnchorHistory) -> Result<(), MotionFailure> {
        let u = self.params.surface_uncertainty_m;
        let len = libm::sqrtf(along.x * along.x + along.y * along.y);
        if u <= 0.0 || len <= 1e-6 {
            return Ok(());
        }
        for sign in [-1.0, 1.0] {
            let (dx, dy) = (sign * u * along.x / len, sign * u * along.y / len);
            let near = self.settle_state(st.ground.x + dx, st.ground.y + dy, st.theta).map_err(MotionFailure::Settle)?;
            self.stable_with(&near.settled, hist)?;
        }
        Ok(())
    }

    /// One interpolated state of a motion: predict the anchors up to it, bound the tether's bend, check stability.
    fn advance(&self, walk: &mut TetherWalk, st: &RoverState) -> Result<(), MotionFailure> {
        let end = st.axle();
        if norm3(&(end - walk.tether_end)) >= self.params.tether_still_m {
            self.count(|s| s.anchor_predictions += 1);
            predict_anchors(self.map, &walk.hist, &walk.tether_end, &end, &mut walk.scratch).map_err(MotionFailure::Tether)?;
            core::mem::swap(&mut walk.hist, &mut walk.scratch);
            walk.tether_end = end;
            if tether_bend(&walk.hist, &end) > self.params.max_tether_bend_rad {
                return Err(MotionFailure::TetherBend);
            }
        }
        self.stable_with(&st.settled, &walk.hist).map(|_| ())
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

/// The tether along a motion being checked: the anchor history so far and where the tether ended when it was
/// last predicted.
struct TetherWalk {
    hist: AnchorHistory,
    scratch: AnchorHistory,
    tether_end: Vec3,
}

/// Angle between the up axes (rover z) of two settled poses, radians.
fn tilt_between(a: &SettledPose, b: &SettledPose) -> Real {
    let (ua, ub) = (a.pose.rotation * Vec3::z(), b.pose.rotation * Vec3::z());
    libm::acosf(ua.dot(&ub).clamp(-1.0, 1.0))
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

/// Total bend of the tether, radians: the sum over the intermediate anchors of the angle between the incoming and
/// the outgoing tether segment (the last segment ends at `end`).
pub fn tether_bend(h: &AnchorHistory, end: &Vec3) -> Real {
    let a = h.as_slice();
    let mut total = 0.0;
    for (i, mid) in a.iter().enumerate().skip(1) {
        let (Some(prev), next) = (a.get(i - 1), a.get(i + 1).map_or(*end, |n| n.point)) else { continue };
        let (u, v) = (mid.point - prev.point, next - mid.point);
        let (nu, nv) = (norm3(&u), norm3(&v));
        if nu > 1e-6 && nv > 1e-6 {
            total += libm::acosf((u.dot(&v) / (nu * nv)).clamp(-1.0, 1.0));
        }
    }
    total
}

/// The anchor the tether pulls the rover towards: the most recent anchor farther from the axle than the boom
/// reaches (`boom_length_m + BOOM_REACH_CLEARANCE_M`). An anchor within the boom's reach (the lip of a ledge just
/// after the rover went over it) lies between the axle and the boom tip, so the tether leaving the tip runs over it
/// towards the anchor before it; the boom then rests on that edge, which the in-contact boom configuration models.
/// `None` for an empty history.
pub fn tether_pull_anchor(st: &SettledPose, history: &AnchorHistory, rover: &RoverParams) -> Option<Vec3> {
    let axle = st.pose.translation.vector;
    let reach = rover.boom_length_m + BOOM_REACH_CLEARANCE_M;
    let anchors = history.as_slice();
    anchors
        .iter()
        .rev()
        .find(|a| norm3(&(a.point - axle)) > reach)
        .or(anchors.first())
        .map(|a| a.point)
}

/// Why a motion is invalid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionFailure {
    /// An interpolated state did not settle.
    Settle(SettleFailure),
    /// Anchor prediction failed.
    Tether(TetherError),
    /// An interpolated state is unstable (or below the margin).
    Unstable,
    /// The stability problem had no reliable answer (treated as unsafe).
    Unknown,
    /// More interpolated states than `MAX_MOTION_STATES`.
    TooLong,
    /// The tether would bend more than `max_tether_bend_rad` over its anchors.
    TetherBend,
    /// A motion from an off-map goal, or to one from too far from the bounds' edge.
    OffMap,
}

/// One interpolated state of a motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionPoint {
    /// A heading of an in-place turn, at the start (`at_end = false`) or the end state.
    Turn {
        /// At the end state.
        at_end: bool,
        /// Settler yaw.
        theta: Real,
    },
    /// A point of the straight drive.
    Drive {
        /// x of the ground point.
        x: Real,
        /// y of the ground point.
        y: Real,
        /// Settler yaw (the drive heading).
        theta: Real,
    },
    /// The end state itself.
    End,
}

/// The interpolation of one motion: `turn_a` headings at the start (the last one is the drive heading), `drive`
/// points (the last one is the end state's ground point), `turn_b - 1` headings at the end, then the end state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionPlan {
    a_ground: Vec3,
    b_ground: Vec3,
    a_theta: Real,
    drive_theta: Real,
    turn_a: u32,
    drive: u32,
    turn_b: u32,
    /// Radians turned at the start.
    pub turn_a_rad: Real,
    /// Radians turned at the end.
    pub turn_b_rad: Real,
}

/// `a - b` wrapped to `(-pi, pi]`.
fn angle_diff(a: Real, b: Real) -> Real {
    let tau = core::f32::consts::TAU;
    let mut d = libm::fmodf(a - b, tau);
    if d > core::f32::consts::PI {
        d -= tau;
    } else if d <= -core::f32::consts::PI {
        d += tau;
    }
    d
}

fn steps(amount: Real, resolution: Real) -> u32 {
    let n = libm::ceilf(libm::fabsf(amount) / resolution);
    if n.is_finite() && n < (MAX_MOTION_STATES * 2) as Real {
        n as u32
    } else {
        MAX_MOTION_STATES * 2
    }
}

impl MotionPlan {
    /// The interpolation of the motion `a -> b`. Settler yaws are used as headings (on level ground they are the
    /// same; on a slope the settler measures yaw from the world x axis projected on the slope).
    pub fn new(a: &RoverState, b: &RoverState, p: &TetherSpaceParams) -> Self {
        let d = b.ground - a.ground;
        let len = libm::sqrtf(d.x * d.x + d.y * d.y);
        let psi = if len > 1e-6 { libm::atan2f(d.y, d.x) } else { a.theta };
        let cost_of = |h: Real| libm::fabsf(angle_diff(h, a.theta)) + libm::fabsf(angle_diff(b.theta, h));
        let back = psi + core::f32::consts::PI;
        let drive_theta = if cost_of(back) < cost_of(psi) { back } else { psi };
        let turn_a_rad = angle_diff(drive_theta, a.theta);
        let turn_b_rad = angle_diff(b.theta, drive_theta);
        MotionPlan {
            a_ground: a.ground,
            b_ground: b.ground,
            a_theta: a.theta,
            drive_theta,
            turn_a: steps(turn_a_rad, p.turn_resolution_rad),
            drive: steps(len, p.drive_resolution_m),
            turn_b: steps(turn_b_rad, p.turn_resolution_rad),
            turn_a_rad,
            turn_b_rad,
        }
    }
    /// Interpolated states, the end state included.
    pub fn total_states(&self) -> u32 {
        self.turn_a.saturating_add(self.drive).saturating_add(self.turn_b.max(1))
    }
    /// The `k`-th interpolated state, `1 ..= total_states()` (the start state is `k = 0`, not checked again).
    /// Turns end at the drive heading; the drive's last point is the end state's ground, at the drive heading.
    pub fn state(&self, k: u32) -> MotionPoint {
        if k <= self.turn_a {
            let t = k as Real / self.turn_a.max(1) as Real;
            return MotionPoint::Turn { at_end: false, theta: self.a_theta + t * self.turn_a_rad };
        }
        let k = k - self.turn_a;
        if k <= self.drive {
            let t = k as Real / self.drive.max(1) as Real;
            let p = self.a_ground + (self.b_ground - self.a_ground) * t;
            return MotionPoint::Drive { x: p.x, y: p.y, theta: self.drive_theta };
        }
        let k = k - self.drive;
        if k < self.turn_b {
            let t = k as Real / self.turn_b.max(1) as Real;
            return MotionPoint::Turn { at_end: true, theta: self.drive_theta + t * self.turn_b_rad };
        }
        MotionPoint::End
    }
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
        self.stable_with(&state.settled, attachment).is_ok()
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
        predict_anchors(self.map, attachment, &from.axle(), &to.axle(), &mut out).ok()?;
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

/// The motion validator (see the module docs); the work counters live in the space ([`TetherSpace::stats`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct TetherMotionValidator;

impl<D: DistanceField> MotionValidator<TetherSpace<'_, D>> for TetherMotionValidator {
    fn check_motion(
        &mut self,
        space: &TetherSpace<'_, D>,
        from: &RoverState,
        from_attachment: &AnchorHistory,
        to: &RoverState,
    ) -> MotionCheck<AnchorHistory> {
        match space.check(from, from_attachment, to) {
            Ok(attachment) => MotionCheck::Valid { attachment },
            Err(_) => MotionCheck::Invalid,
        }
    }
}

/// Paton et al.'s objective: weighted yaw change + roll + length (see the module docs).
#[derive(Debug, Clone, Copy, Default)]
pub struct TetherObjective;

impl<D: DistanceField> OptimizationObjective<TetherSpace<'_, D>> for TetherObjective {
    fn motion_cost(&self, space: &TetherSpace<'_, D>, from: &RoverState, _: &AnchorHistory, to: &RoverState) -> Cost {
        let p = space.params();
        let len = space.distance(from, to);
        if from.off_map || to.off_map {
            return p.w_length * len;
        }
        let plan = MotionPlan::new(from, to, p);
        let turn = f64::from(libm::fabsf(plan.turn_a_rad) + libm::fabsf(plan.turn_b_rad));
        let roll = 0.5 * f64::from(from.roll() + to.roll());
        p.w_length * len + p.w_yaw * turn + p.w_roll * len * roll
    }
    fn motion_cost_heuristic(&self, space: &TetherSpace<'_, D>, from: &RoverState, to: &RoverState) -> Cost {
        space.params().w_length * space.distance(from, to)
    }
    fn sample_informed<R: Rng + ?Sized>(
        &self,
        space: &mut TetherSpace<'_, D>,
        rng: &mut R,
        start: &RoverState,
        goal: &RoverState,
        max_cost: Cost,
    ) -> InformedSample<RoverState> {
        // The (x, y) ellipse with foci at the axles' projections and major axis max_cost / w_length contains the
        // projection of the informed set (3D distances are never shorter than their projections).
        let major = max_cost / space.params().w_length;
        let (a, b) = (start.axle(), goal.axle());
        let (fx, fy) = (f64::from(b.x - a.x), f64::from(b.y - a.y));
        let c = 0.5 * libm::sqrt(fx * fx + fy * fy);
        if !major.is_finite() || 0.5 * major <= c {
            return InformedSample::Unsupported;
        }
        let semi_a = 0.5 * major;
        let semi_b = libm::sqrt(semi_a * semi_a - c * c);
        // uniform in the unit disk, scaled and rotated
        let r = libm::sqrt(uniform01(rng));
        let phi = core::f64::consts::TAU * uniform01(rng);
        let (u, v) = (semi_a * r * libm::cos(phi), semi_b * r * libm::sin(phi));
        let (cos_t, sin_t) = if c > 0.0 { (fx / (2.0 * c), fy / (2.0 * c)) } else { (1.0, 0.0) };
        let x = 0.5 * f64::from(a.x + b.x) + u * cos_t - v * sin_t;
        let y = 0.5 * f64::from(a.y + b.y) + u * sin_t + v * cos_t;
        match space.sample_at(rng, x as Real, y as Real) {
            Some(s) if self.motion_cost_heuristic(space, start, &s) + self.motion_cost_heuristic(space, &s, goal) < max_cost => {
                InformedSample::Sampled(s)
            }
            _ => InformedSample::Rejected,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tether::Anchor;

    /// The plane z = 0 (exact signed distance).
    struct Ground;
    impl DistanceField for Ground {
        fn query(&self, p: &Vec3) -> DistanceQuery {
            DistanceQuery::Known { distance: p.z, gradient: Vec3::z() }
        }
    }
    struct Nothing;
    impl DistanceField for Nothing {
        fn query(&self, _: &Vec3) -> DistanceQuery {
            DistanceQuery::Unknown
        }
    }
    const BOUNDS: PlanBounds = PlanBounds { min: [-10.0, -10.0, -1.0], max: [10.0, 10.0, 5.0] };

    fn history(points: &[[Real; 3]]) -> AnchorHistory {
        let mut h = AnchorHistory::default();
        for p in points {
            h.push(Anchor { point: Vec3::new(p[0], p[1], p[2]), gradient: Vec3::z() }).unwrap();
        }
        h
    }

    #[test]
    fn surface_point_finds_the_plane_and_refuses_unknown_space() {
        let p = surface_point(&Ground, 1.0, 2.0, 5.0, -1.0).unwrap();
        assert!(p.z.abs() <= SURFACE_MIN_STEP_M * 0.5, "{p:?}");
        assert_eq!((p.x, p.y), (1.0, 2.0));
        assert_eq!(surface_point(&Nothing, 1.0, 2.0, 5.0, -1.0), None);
        // the surface is below the search range
        assert_eq!(surface_point(&Ground, 0.0, 0.0, 5.0, 1.0), None);
    }

    #[test]
    fn tether_bend_is_the_sum_of_turning_angles() {
        let straight = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        assert!(tether_bend(&straight, &Vec3::new(2.0, 0.0, 0.0)).abs() < 1e-5);
        let right = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
        let b = tether_bend(&right, &Vec3::new(1.0, 1.0, 0.0));
        assert!((b - core::f32::consts::FRAC_PI_2).abs() < 1e-5, "{b}");
        // two right angles in a row: a U-turn around a post
        let u = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
        let b = tether_bend(&u, &Vec3::new(0.0, 1.0, 0.0));
        assert!((b - core::f32::consts::PI).abs() < 1e-5, "{b}");
    }

    #[test]
    fn wraps_merge_close_anchors_and_compatibility_follows_them() {
        let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
        // root, then three anchors 0.1 m apart around a post, then a lip 3 m away
        let fine = history(&[[9.0, 0.0, 6.0], [0.0, 0.25, 4.5], [-0.1, 0.2, 4.5], [-0.2, 0.1, 4.5], [3.0, -0.5, 4.0]]);
        let coarse = history(&[[9.0, 0.0, 6.0], [0.0, 0.25, 4.5], [-0.18, 0.12, 4.5], [3.0, -0.5, 4.0]]);
        let w = wraps(&fine, space.params().anchor_cluster_m);
        assert_eq!(w.len(), 3);
        assert_eq!(w[1], Vec3::new(-0.2, 0.1, 4.5));
        assert!(space.histories_match(&fine, &coarse));
        // the same post wrapped on its other side (last anchor 0.5 m away) is another history
        let other_side = history(&[[9.0, 0.0, 6.0], [0.0, -0.25, 4.5], [-0.2, -0.3, 4.5], [3.0, -0.5, 4.0]]);
        assert!(!space.histories_match(&fine, &other_side));
        // one wrap more or less is another history
        let root_only = history(&[[9.0, 0.0, 6.0]]);
        assert!(!space.histories_match(&root_only, &coarse));
        assert!(space.histories_match(&root_only, &root_only.clone()));
    }

    #[test]
    fn motion_plan_turns_the_short_way_and_drives_backwards_when_cheaper() {
        let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
        let a = space.settle_state(0.0, 0.0, 0.0).unwrap();
        let b = space.settle_state(2.0, 0.0, 0.0).unwrap();
        let p = MotionPlan::new(&a, &b, space.params());
        assert_eq!((p.turn_a_rad, p.turn_b_rad), (0.0, 0.0));
        // 2 m at 0.2 m: 10 drive states, the last of which is followed by the end state
        assert_eq!(p.total_states(), 11);
        assert_eq!(p.state(11), MotionPoint::End);
        assert!(matches!(p.state(10), MotionPoint::Drive { x, .. } if (x - 2.0).abs() < 1e-5));
        // facing away from the target: Axel reverses instead of turning around
        let c = space.settle_state(-2.0, 0.0, 0.0).unwrap();
        let p = MotionPlan::new(&a, &c, space.params());
        assert!(p.turn_a_rad.abs() < 1e-5 && p.turn_b_rad.abs() < 1e-5, "{p:?}");
        // a quarter turn at the end, in ceil((pi/2) / 0.5) = 4 steps
        let d = space.settle_state(2.0, 0.0, core::f32::consts::FRAC_PI_2).unwrap();
        let p = MotionPlan::new(&a, &d, space.params());
        assert!((p.turn_b_rad.abs() - core::f32::consts::FRAC_PI_2).abs() < 1e-5);
        assert_eq!(p.total_states(), 10 + 4);
    }

    #[test]
    fn flat_ground_motion_is_valid_and_keeps_a_straight_tether() {
        let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
        let a = space.settle_state(0.0, 0.0, 0.0).unwrap();
        let b = space.settle_state(3.0, 1.0, 0.5).unwrap();
        let root = history(&[[-6.0, 0.0, 2.0]]);
        let h = space.check(&a, &root, &b).unwrap();
        assert_eq!(h.len(), 1);
        let s = space.stats();
        assert_eq!((s.motions, s.motions_valid), (1, 1));
        assert!(s.stability_checks as usize >= MotionPlan::new(&a, &b, space.params()).total_states() as usize);
    }

    #[test]
    fn off_map_goal_connects_only_near_the_edge() {
        let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
        let goal = space.goal_state(Vec3::new(30.0, 0.0, 0.35), 0.0).unwrap();
        assert!(goal.off_map);
        let root = history(&[[-6.0, 0.0, 2.0]]);
        let near = space.settle_state(9.5, 0.0, 0.0).unwrap();
        let far = space.settle_state(0.0, 0.0, 0.0).unwrap();
        assert!(space.check(&near, &root, &goal).is_ok());
        assert_eq!(space.check(&far, &root, &goal), Err(MotionFailure::OffMap));
        assert_eq!(space.check(&goal, &root, &near), Err(MotionFailure::OffMap));
    }

    #[test]
    fn bad_parameters_and_bounds_are_named() {
        let mut p = TetherSpaceParams::DEFAULT;
        p.drive_resolution_m = 0.0;
        assert_eq!(TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, p).err().map(|e| e.0), Some("drive_resolution_m/turn_resolution_rad"));
        let mut b = BOUNDS;
        b.max[2] = b.min[2];
        assert_eq!(TetherSpace::new(&Ground, b, RoverParams::AXEL, TetherSpaceParams::DEFAULT).err().map(|e| e.0), Some("bounds"));
    }
}
