//! The stability LP over a batch of real Axel poses: settled on exact planes of 0, 25 and 50 degrees at sixteen
//! yaws, tethered to an anchor upslope or downslope, with the boom inline (two wheel contacts) and, where its tip
//! reaches the plane, in contact swept down and over the axle (three contacts): the margin LPs the planners solve
//! (Paton et al. IV-C).
//!
//! Only problems with an equilibrium that is not deeply unstable (simplex margin at least [`DEEPLY_UNSTABLE`]) are
//! kept: both solvers are timed on problems both answer (beyond it the interior point may spend its iteration budget,
//! and callers read Unknown as unstable either way; `tests/tests/stability.rs` checks that against clarabel).
//!
//! The problems are built before the measurement; the three workloads then measure building the LPs alone
//! (`to_lp`), building and solving them by the interior-point method, and building and solving them by the
//! simplex, so the per-solve cost of each solver is (its total - the build) / the number of problems.

use firmware::config::rover::RoverParams;
use firmware::config::stability::{SIMPLEX_MAX_PIVOTS, SOLVER_MAX_ITERATIONS, SOLVER_TOLERANCE};
use firmware::geom::{Real, Vec3};
use firmware::rover::{boom_inline_angle, boom_swept_contact, settle, stability_problem, BoomSweep, SettleOutcome};
use firmware::stability::lp::LpStatus;
use firmware::stability::{simplex, StabilityProblem};
use heapless::Vec as HVec;

use crate::InclinedPlane;

/// Most problems in the batch: 3 slopes x 16 yaws x 2 anchors x 3 boom configurations, of which those answered
/// are kept (about a third).
pub const BATCH_CAPACITY: usize = 128;

/// Margin below which a problem is deeply unstable and left out of the batch (rover weights).
pub const DEEPLY_UNSTABLE: f64 = -0.1;

/// Whether the simplex answers `p` with an optimum of margin at least [`DEEPLY_UNSTABLE`].
fn answered(p: &StabilityProblem) -> bool {
    let Ok(lp) = p.to_lp() else { return false };
    let sol = simplex::solve(&lp, SIMPLEX_MAX_PIVOTS);
    matches!(sol.status, LpStatus::Optimal) && -sol.objective >= DEEPLY_UNSTABLE
}

/// The batch (see the module docs).
pub fn problems() -> HVec<StabilityProblem, BATCH_CAPACITY> {
    let params = RoverParams::AXEL;
    let mut out = HVec::new();
    for slope_deg in [0.0f32, 25.0, 50.0] {
        let plane = InclinedPlane::new(slope_deg.to_radians());
        // the plane descends towards +x: upslope is -x
        let t = libm::tanf(slope_deg.to_radians());
        let anchors = [Vec3::new(-8.0, 0.0, 8.0 * t + 1.0), Vec3::new(8.0, 1.0, -8.0 * t + 0.5)];
        for yaw_k in 0..16 {
            let yaw = yaw_k as Real * core::f32::consts::FRAC_PI_8;
            let SettleOutcome::Settled(pose) = settle(&plane, &Vec3::zeros(), yaw, &params) else { continue };
            for anchor in &anchors {
                let inline = boom_inline_angle(&pose, anchor);
                let mut keep = |p: StabilityProblem| {
                    if answered(&p) {
                        let _ = out.push(p);
                    }
                };
                keep(stability_problem(&pose, inline, None, Some(anchor), &params));
                for sweep in [BoomSweep::Down, BoomSweep::Over] {
                    if let Some(bc) = boom_swept_contact(&plane, &pose, inline, sweep, &params) {
                        keep(stability_problem(&pose, bc.angle_rad, Some(&bc), Some(anchor), &params));
                    }
                }
            }
        }
    }
    out
}

/// What a pass over the batch found: problems, optimal answers, the sum of their margins.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct BatchResult {
    /// Problems in the batch.
    pub problems: u32,
    /// Problems solved to an optimum (`Optimal` or `AlmostOptimal`).
    pub optimal: u32,
    /// Sum of the optimal margins.
    pub margin_sum: f64,
}

/// Which pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Pass {
    /// `to_lp` only.
    Build,
    /// `to_lp` and the interior-point method.
    InteriorPoint,
    /// `to_lp` and the simplex.
    Simplex,
}

/// One pass over the batch.
pub fn run(batch: &[StabilityProblem], pass: Pass) -> BatchResult {
    let mut r = BatchResult::default();
    for p in batch {
        r.problems += 1;
        let Ok(lp) = p.to_lp() else { continue };
        let sol = match pass {
            Pass::Build => continue,
            Pass::InteriorPoint => lp.solve(SOLVER_MAX_ITERATIONS, SOLVER_TOLERANCE),
            Pass::Simplex => simplex::solve(&lp, SIMPLEX_MAX_PIVOTS),
        };
        if matches!(sol.status, LpStatus::Optimal | LpStatus::AlmostOptimal) {
            r.optimal += 1;
            r.margin_sum += -sol.objective;
        }
    }
    r
}
