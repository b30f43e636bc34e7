//! The objective of Paton et al.: length, yaw change and roll, with its heuristic and informed sampler.

use rand_core::Rng;

use crate::geom::Real;
use crate::map::DistanceField;
use crate::plan::space::{uniform01, Cost, InformedSample, OptimizationObjective, StateSpace};
use crate::tether::AnchorHistory;

use super::{MotionPlan, RoverState, TetherSpace};

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
