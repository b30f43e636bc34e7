//! The parameters of the space ([`TetherSpaceParams`], defaults in `config::tethered::defaults`) and the
//! planning bounds ([`PlanBounds`]).

use crate::config::tethered::{defaults, MAX_REFINE_SUBSTEPS};
use crate::geom::Real;

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
    /// ([`TetherSpace::sample_catch_boundary`](crate::plan::space::StateSpace::sample_catch_boundary)).
    pub catch_pair_radius_m: Real,
    /// Anchor prediction (Alg. 1) treats unobserved space as free: the tether runs where the rover's sensor
    /// cannot look (behind the rover, back over a rim to a root off the map), and what it meets there unseen shows
    /// in the payout encoder, not in the map (the mission reconciles the two). Settling and stability still refuse
    /// unobserved space.
    pub tether_through_unobserved: bool,
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
        tether_through_unobserved: defaults::TETHER_THROUGH_UNOBSERVED,
    };

    /// The navigator's parameters (on the onboard map, in flight): the defaults with
    /// `tether_through_unobserved` set.
    pub const ONBOARD: TetherSpaceParams = TetherSpaceParams { tether_through_unobserved: true, ..Self::DEFAULT };

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
