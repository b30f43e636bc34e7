//! Holding with Axel, not the point mass (issue 20 item 2; Abad-Manterola et al. V-B use the rover's dynamics for
//! controllable sets, VI the point mass).
//!
//! On a uniform plane of slope alpha, whether the rover holds on a taut tether depends only on the angle theta
//! between the upslope direction and the tether (the plane looks the same everywhere). [`axel_hold_limit`] finds the
//! largest theta at which Axel holds with the core's stability check: the rover is settled ([`crate::rover::settle`])
//! on an exact plane distance field, facing along the tether or away from it (it chooses), and
//! [`crate::rover::check_pose_stability`] decides with the tether pulling towards an anchor
//! [`AXEL_ANCHOR_DISTANCE_M`] away on the plane at angle theta. Angles are scanned from 0 upward in
//! [`AXEL_THETA_STEP_DEG`] steps ([`AXEL_THETA_STEPS`] at most) and the first failure bounds the limit, then the
//! last interval is bisected [`AXEL_BISECTIONS`] times: holding is taken as monotone in theta (a larger angle needs
//! more lateral friction); the scan keeps every angle below the limit checked. The result plugs into
//! [`HoldLimit::Measured`], so controllable sets, passability and descents use Axel through the same code as the
//! paper's point mass.
//!
//! Parameters: the rover (`RoverParams::AXEL` by default: wheel mu is replaced by the soil's mu), the slope and the
//! soil mu; the constants above (defaults 20 m, 2.5 deg, 72 steps, 6 bisections) live in `config::homotopy`.

use crate::config::homotopy::{AXEL_ANCHOR_DISTANCE_M, AXEL_BISECTIONS, AXEL_THETA_STEPS, AXEL_THETA_STEP_DEG};
use crate::config::rover::RoverParams;
use crate::geom::{Real, Vec3};
use crate::map::{DistanceField, DistanceQuery};
use crate::rover::{check_pose_stability, settle, SettleOutcome};

use super::planes::{HoldLimit, HoldModel};

/// An exact plane `z = tan(alpha) y` (upslope +y), as a signed distance field.
struct SlopePlane {
    n: Vec3,
}

impl DistanceField for SlopePlane {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        DistanceQuery::Known { distance: p.dot(&self.n), gradient: self.n }
    }
}

/// Axel's holding limit on one slope.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AxelLimit {
    /// Largest tether angle from upslope at which the rover holds (rad); negative when it holds at none.
    pub theta_max_rad: f64,
    /// Stability checks run.
    pub checks: usize,
    /// True when the rover did not settle on the plane (then it holds nowhere).
    pub unsettled: bool,
}

/// Does the rover hold on a plane of slope `alpha` with the tether at `theta` from upslope (either facing)?
fn holds_at(plane: &SlopePlane, alpha: f64, theta: f64, params: &RoverParams, checks: &mut usize) -> Option<bool> {
    let (sa, ca) = (libm::sin(alpha), libm::cos(alpha));
    // In-plane unit vectors: across r = +x, upslope u = n x r.
    let u = Vec3::new(0.0, ca as Real, sa as Real);
    let r = Vec3::new(1.0, 0.0, 0.0);
    let dir = u * libm::cos(theta) as Real + r * libm::sin(theta) as Real;
    let anchor = dir * AXEL_ANCHOR_DISTANCE_M as Real;
    // Yaw 0 is world x on the plane (= r); x(psi) = r cos psi + u sin psi, so psi = pi/2 - theta faces the anchor.
    let face = core::f64::consts::FRAC_PI_2 - theta;
    let mut settled_any = false;
    for yaw in [face, face + core::f64::consts::PI] {
        let SettleOutcome::Settled(pose) = settle(plane, &(plane.n * 0.5), yaw as Real, params) else { continue };
        settled_any = true;
        *checks += 1;
        if let Ok((o, _)) = check_pose_stability(plane, &pose, Some(&anchor), params) {
            if o.is_stable() {
                return Some(true);
            }
        }
    }
    settled_any.then_some(false)
}

/// Axel's largest holding angle on a plane of slope `slope_rad` with soil friction `mu` (see the module docs).
pub fn axel_hold_limit(slope_rad: f64, mu: f64, rover: &RoverParams) -> AxelLimit {
    let params = RoverParams { wheel_mu: mu as Real, ..*rover };
    let (sa, ca) = (libm::sin(slope_rad), libm::cos(slope_rad));
    let plane = SlopePlane { n: Vec3::new(0.0, -sa as Real, ca as Real) };
    let mut checks = 0;
    let step = AXEL_THETA_STEP_DEG.to_radians();
    let mut good = -1.0f64;
    let mut bad = None;
    for k in 0..=AXEL_THETA_STEPS {
        let theta = (k as f64 * step).min(core::f64::consts::PI);
        match holds_at(&plane, slope_rad, theta, &params, &mut checks) {
            None => return AxelLimit { theta_max_rad: -1.0, checks, unsettled: true },
            Some(true) => good = theta,
            Some(false) => {
                bad = Some(theta);
                break;
            }
        }
    }
    let Some(mut hi) = bad else { return AxelLimit { theta_max_rad: core::f64::consts::PI, checks, unsettled: false } };
    if good < 0.0 {
        return AxelLimit { theta_max_rad: -1.0, checks, unsettled: false };
    }
    let mut lo = good;
    for _ in 0..AXEL_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if holds_at(&plane, slope_rad, mid, &params, &mut checks) == Some(true) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    AxelLimit { theta_max_rad: lo, checks, unsettled: false }
}

/// `model` with the point mass replaced by Axel's measured limits for each of its two soils.
pub fn axel_model(model: &HoldModel, rover: &RoverParams) -> (HoldModel, [AxelLimit; 2]) {
    let l = axel_hold_limit(model.slope_rad, model.soil.mu_left, rover);
    let r = if model.soil.mu_right == model.soil.mu_left {
        l
    } else {
        axel_hold_limit(model.slope_rad, model.soil.mu_right, rover)
    };
    let limit = HoldLimit::Measured { left_rad: l.theta_max_rad, right_rad: r.theta_max_rad };
    (HoldModel { limit, ..*model }, [l, r])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::homotopy::planes::theta_max;

    /// Axel holds on a gentle slope at every angle (like the point mass: mu cot alpha >= 1), and on a tether-demand
    /// slope its limit is finite and shrinks as the slope steepens.
    #[test]
    fn axel_limit_is_full_on_gentle_slopes_and_shrinks_with_slope() {
        let gentle = axel_hold_limit(15f64.to_radians(), 0.6, &RoverParams::AXEL);
        assert!(gentle.theta_max_rad >= core::f64::consts::PI - 1e-9, "{gentle:?}");
        assert!(theta_max(15f64.to_radians(), 0.6) >= core::f64::consts::PI);
        let a = axel_hold_limit(45f64.to_radians(), 0.6, &RoverParams::AXEL);
        let b = axel_hold_limit(65f64.to_radians(), 0.6, &RoverParams::AXEL);
        assert!(a.theta_max_rad > 0.0 && a.theta_max_rad < core::f64::consts::PI, "{a:?}");
        assert!(b.theta_max_rad < a.theta_max_rad, "{a:?} {b:?}");
    }
}
