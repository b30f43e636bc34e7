//! # workloads — fixed benchmark workloads and test problems for the flight software (not flight code)
//!
//! Fixed, deterministic planning workloads for on-target cost figures (instruction counts on the emulated
//! Cortex-M7, `tetherbot board bench`) and their host twins (the same code, run by the unit tests below and by
//! `tetherbot board bench` to check that the board computed the same answer), and the test problems the planners
//! are checked and benchmarked on. Nothing here flies: the board crate links it for its bench mode only, the
//! host for its tests, benchmarks and the board comparison. `no_std`, no heap, no panics, like `firmware`, so the
//! same code runs on the board and on the host.
//!
//! - [`geometric`]: R^n with axis-aligned box obstacles, the shared ABIT* benchmark problems (wall with a gap,
//!   3D box world) and the planner's tests (`tests/abit_geometric.rs`).
//! - [`ledge`]: the ledge world of Paton et al. VI-A (with or without the test-3 pole) as an exact analytic
//!   distance field; host-sim's ledge worlds wrap it.
//! - [`homotopy_tile`]: the homotopy planning phases on a terrain tile (the HiRISE scarp of the mission scenario).
//! - [`ledge_pole`]: the opt-in `tethered_test3` workload (Table I test 3 on the board).
//! - [`team`]: the climbing-team workloads (a synthetic scan, a local plan, a D* Lite replan).
//! - [`config`]: the workloads' own capacities (fixtures, not flight settings).
//!
//! Workloads (all inputs are constants; the only randomness is [`SplitMix64`] with a fixed seed):
//!
//! | name | what | paper |
//! |---|---|---|
//! | `settle_plane_30deg` | [`firmware::rover::settle`] on an exact inclined plane ([`InclinedPlane`], 30 deg) | Paton et al. IV-B |
//! | `predict_anchors_step_lip` | [`firmware::tether::predict_anchors`] over a 4 m step ([`Step`]): the tether attaches on the lip | Paton et al. Alg. 1 |
//! | `pose_stability_plane_30deg` | [`firmware::rover::check_pose_stability`] of the settled pose, tether to an anchor upslope | Paton et al. IV-C |
//! | `stability_lp_interior_point` | the margin LP of that pose's inline boom (two wheel contacts, taut tether) by [`firmware::stability::lp`] (the interior-point method) | Paton et al. IV-C |
//! | `stability_lp_simplex` | the same LP by [`firmware::stability::simplex`] (the flight solver) | Paton et al. IV-C |
//! | `stability_lp_batch_build` | [`lp_batch`]: building the 96 margin LPs of 48 real Axel poses (0/25/50 deg, 8 yaws, anchor up or downslope; boom inline and in contact) | Paton et al. IV-C |
//! | `stability_lp_batch_interior_point` | building and solving them by the interior-point method | Paton et al. IV-C |
//! | `stability_lp_batch_simplex` | building and solving them by the simplex | Paton et al. IV-C |
//! | `abit_wall_gap_r2` | ABIT* on [`geometric::wall_gap`] in R^2, [`ABIT_ITERATIONS`] iterations, seed [`ABIT_SEED`] | Strub & Gammell |
//! | `team_local_plan` | [`team::local_plan_workload`] (scan, cull, hop graph, A*) | Morad et al. |
//! | `team_dstar_replan` | [`team::dstar_workload`] (plan, move, crevasse, replan) | Morad et al. |
//! | `homotopy_btm_build_c` | BTM of scenario C's plane (two triangular obstacles) | Tanner et al. IV |
//! | `homotopy_preplan_c` | Alg. 1 pre-planning a0 -> g on scenario C | Tanner et al. Alg. 1 |
//!
//! Default too, but not in [`run_all`] (their input is a terrain tile the caller lends: the board embeds it, the host
//! cuts it from the mission scenario): [`homotopy_tile::run`], the navigator's three homotopy planning phases on the
//! HiRISE scarp tile, `homotopy_tile_segment`, `homotopy_tile_hold`, `homotopy_tile_route` (Abad-Manterola et al.;
//! Tanner et al. Alg. 1; `host-sim/doc/homotopy.md`, "On the board").
//!
//! Opt-in (not in [`run_all`]; tens of billions of instructions under QEMU):
//!
//! | name | what | paper |
//! |---|---|---|
//! | `tethered_test3` | [`ledge_pole::run_ledge_pole`]: ABIT* over the tether-aware space on the exact ledge + pole world ([`ledge::Ledge::with_pole`]), Table I test 3, 750 iterations, seed 1 | Paton et al. V, VI-A |
//!
//! Run it on the emulated board with `tetherbot board bench --build --workload tethered_test3` (see
//! [`ledge_pole`] and `host-sim/doc/board_test3.md` for the measured instruction counts and arena sizes).
//!
//! Each workload's outcome is condensed into a one-line [`Summary`] whose floats are printed with `{}` (the
//! shortest decimal that round-trips, so two summaries are equal exactly when the bits are). A [`Harness`] times
//! the work (the board: SysTick under `-icount shift=0`; the host: nothing) and receives the summaries.
//! The big arenas are lent by the caller in [`Arenas`] (statics on the board, boxes on the host).
#![no_std]
#![forbid(unsafe_code)]
#![cfg_attr(
    not(test),
    deny(
        clippy::unwrap_used,
        clippy::expect_used,
        clippy::panic,
        clippy::indexing_slicing
    )
)]

#[cfg(test)]
extern crate std;

use core::fmt::Write;

use firmware::config::rover::RoverParams;
use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};
use firmware::plan::abit::{AbitParams, AbitStar, DefaultAbitArena};
use firmware::plan::homotopy::plan::PlanReport;
use firmware::plan::homotopy::planes::{HoldModel, SoilMap};
use firmware::plan::homotopy::{preplan, Btm, HomotopyParams, Workspace};
use firmware::plan::space::{Budget, GoalState, PathLength, Planner, PlannerStatus, ProblemDefinition};
use firmware::plan::status::Status;
use firmware::plan::team::dstar_lite::{outcome_label, DStarArena, Found};
use firmware::plan::team::leg_astar::status_label;
use firmware::plan::team::DefaultLocalPlanner;
use firmware::plan::tethered::PhaseClock;
use firmware::plan::SplitMix64;
use firmware::config::stability::{SIMPLEX_MAX_PIVOTS, SOLVER_MAX_ITERATIONS, SOLVER_TOLERANCE};
use firmware::rover::{boom_inline_angle, check_pose_stability, settle, stability_problem, SettleOutcome};
use firmware::stability::simplex;
use firmware::stability::StabilityOutcome;
use firmware::tether::{predict_anchors, Anchor, AnchorHistory};

use geometric::wall_gap;
use team::{dstar_workload, local_plan_workload, synthetic_scan, SCAN_SIDE};

pub mod config;
pub mod geometric;
pub mod homotopy_tile;
pub mod ledge;
pub mod ledge_pole;
pub mod lp_batch;
pub mod team;

/// One workload's result in one line (at most 240 bytes; longer text is cut).
pub type Summary = heapless::String<240>;

/// Iterations of the ABIT* workload. Default 2000: a first solution through the 6 % gap and some refinement.
pub const ABIT_ITERATIONS: u32 = 2000;
/// Seed of the ABIT* workload's sampler.
pub const ABIT_SEED: u64 = 3;
/// Slope of the settle / stability workloads' plane, degrees.
pub const PLANE_SLOPE_DEG: Real = 30.0;
/// Height of the [`Step`]'s lip, m.
pub const STEP_HEIGHT_M: Real = 4.0;
/// Points of the team workload's synthetic scan.
pub const SCAN_POINTS: usize = SCAN_SIDE * SCAN_SIDE;

/// The ABIT* arena of the wall-with-gap workload (default capacities of `config::abit`).
pub type WallGapArena = DefaultAbitArena<[f64; 2], ()>;

/// An inclined plane through the origin, `z = -tan(alpha) x` (descending towards `+x`); exact SDF.
#[derive(Debug, Clone, Copy)]
pub struct InclinedPlane {
    /// Unit normal `(sin alpha, 0, cos alpha)`.
    pub normal: Vec3,
}

impl InclinedPlane {
    /// The plane of slope `alpha_rad`.
    pub fn new(alpha_rad: Real) -> Self {
        Self { normal: Vec3::new(libm::sinf(alpha_rad), 0.0, libm::cosf(alpha_rad)) }
    }
}

impl DistanceField for InclinedPlane {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        DistanceQuery::Known { distance: p.dot(&self.normal), gradient: self.normal }
    }
}

/// A step: solid where `z < 0`, or where `x < 0` and `z < h` (a vertical wall at `x = 0` with its lip at
/// `(0, *, h)`); exact SDF.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    /// Height `h` of the upper level, m.
    pub height_m: Real,
}

impl DistanceField for Step {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        let (x, z, h) = (p.x, p.z, self.height_m);
        let (d, g) = if z < 0.0 || (x < 0.0 && z < h) {
            // inside: the nearest boundary among the floor (x >= 0), the upper level (x < 0) and the wall
            let floor = if x >= 0.0 { z } else { Real::INFINITY };
            let top = if x < 0.0 { h - z } else { Real::INFINITY };
            let wall = if z > 0.0 && z < h { -x } else { Real::INFINITY };
            if wall < floor.min(top) {
                (-wall, Vec3::x())
            } else {
                (-floor.min(top), Vec3::z())
            }
        } else if x >= 0.0 && z >= h {
            // above the lip: nearest is the lip edge
            let v = Vec3::new(x, 0.0, z - h);
            let n = firmware::geom::norm3(&v);
            if n > 1e-9 {
                (n, v / n)
            } else {
                (0.0, Vec3::new(core::f32::consts::FRAC_1_SQRT_2, 0.0, core::f32::consts::FRAC_1_SQRT_2))
            }
        } else if x >= 0.0 {
            // beside the wall, below the lip: the wall or the floor
            if x < z {
                (x, Vec3::x())
            } else {
                (z, Vec3::z())
            }
        } else {
            (z - h, Vec3::z())
        };
        DistanceQuery::Known { distance: d, gradient: g }
    }
}

/// The big arenas the workloads need, lent by the caller.
pub struct Arenas<'a> {
    /// ABIT* storage (~1.5 MiB at the default capacities).
    pub abit: &'a mut WallGapArena,
    /// Team local planner (~0.6 MiB).
    pub local: &'a mut DefaultLocalPlanner,
    /// The team workload's scan buffer.
    pub scan: &'a mut [Vec3; SCAN_POINTS],
    /// D* Lite storage.
    pub dstar: &'a mut DStarArena<GLOBAL_GRID_MAX_CELLS>,
    /// Homotopy BTM.
    pub btm: &'a mut Btm,
    /// Homotopy planning workspace.
    pub homotopy: &'a mut Workspace,
}

/// Runs the workloads: `measure` times the work, `result` gets the outcome.
pub trait Harness {
    /// Run `work` once, timing it.
    fn measure(&mut self, name: &'static str, work: &mut dyn FnMut());
    /// The outcome of workload `name`.
    fn result(&mut self, name: &'static str, summary: &str);
    /// Where workload `name`'s time went, phase by phase (only workloads given a clock report it). Default: dropped.
    fn phases(&mut self, _name: &'static str, _phases: &str) {}
}

/// A distance field that counts its queries and, with a clock, the ticks spent in them (the per-phase profile of
/// a workload: `ledge_pole::Phases`). The answers are the wrapped field's.
pub struct TimedField<'a, D> {
    inner: &'a D,
    clock: Option<&'a dyn PhaseClock>,
    queries: core::cell::Cell<u64>,
    ticks: core::cell::Cell<u64>,
}

impl<'a, D: DistanceField> TimedField<'a, D> {
    /// Wraps `inner`; timed when `clock` is given.
    pub fn new(inner: &'a D, clock: Option<&'a dyn PhaseClock>) -> Self {
        Self { inner, clock, queries: core::cell::Cell::new(0), ticks: core::cell::Cell::new(0) }
    }
    /// Queries so far.
    pub fn queries(&self) -> u64 {
        self.queries.get()
    }
    /// Ticks spent in queries so far (0 without a clock).
    pub fn ticks(&self) -> u64 {
        self.ticks.get()
    }
}

impl<D: DistanceField> DistanceField for TimedField<'_, D> {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        self.queries.set(self.queries.get().saturating_add(1));
        let Some(c) = self.clock else { return self.inner.query(p) };
        let t0 = c.ticks();
        let q = self.inner.query(p);
        self.ticks.set(self.ticks.get().saturating_add(c.ticks().saturating_sub(t0)));
        q
    }
    fn lipschitz_bound(&self) -> Option<Real> {
        self.inner.lipschitz_bound()
    }
}

fn line(args: core::fmt::Arguments<'_>) -> Summary {
    let mut s = Summary::new();
    // A summary longer than the capacity is cut (write_fmt stops at the first push that does not fit).
    let _ = s.write_fmt(args);
    s
}

/// The settle workload's query: yaw 0.7 rad at (0.3, 0.2, 0) on the 30-degree plane.
pub fn settle_workload() -> SettleOutcome {
    let plane = InclinedPlane::new(PLANE_SLOPE_DEG.to_radians());
    settle(&plane, &Vec3::new(0.3, 0.2, 0.0), 0.7, &RoverParams::AXEL)
}

/// The anchor that tethers the stability workload: 10 m upslope, 1 m above the plane.
pub fn upslope_anchor() -> Vec3 {
    let t = libm::tanf(PLANE_SLOPE_DEG.to_radians());
    Vec3::new(-10.0, 0.0, 10.0 * t + 1.0)
}

/// The tether workload: root anchor above the upper level, the rover moves from above the lower floor to the
/// floor under the line over the lip; Alg. 1 attaches an anchor on the lip `(0, 0, STEP_HEIGHT_M)`.
pub fn predict_anchors_workload(out: &mut AnchorHistory) -> Result<firmware::tether::PredictStats, firmware::tether::TetherError> {
    let a0 = AnchorHistory::new(Anchor::root(Vec3::new(-5.0, 0.0, 6.0)));
    predict_anchors(
        &Step { height_m: STEP_HEIGHT_M },
        &a0,
        &Vec3::new(3.0, 0.0, 4.5),
        &Vec3::new(1.0, 0.0, 0.5),
        out,
    )
}

/// Scenario C of the homotopy planner (shared/SCENARIOS.md; Tanner et al. IV, Fig. 11): a 20 m x 20 m plane at
/// 50 deg, firm soil (mu = 0.91), two triangular obstacles, a0 = (8, 19.5), g = (12, 1.5). Same geometry as
/// `host-sim/src/homotopy/scenarios.rs::scenario_c`.
pub mod scenario_c {
    use firmware::plan::homotopy::geo::{pt, Pt};

    /// Plane outline.
    pub fn plane() -> [Pt; 4] {
        [pt(0.0, 0.0), pt(20.0, 0.0), pt(20.0, 20.0), pt(0.0, 20.0)]
    }
    /// First obstacle.
    pub fn o1() -> [Pt; 3] {
        [pt(6.0, 14.0), pt(9.0, 11.0), pt(10.0, 15.0)]
    }
    /// Second obstacle.
    pub fn o2() -> [Pt; 3] {
        [pt(11.0, 8.0), pt(14.0, 6.0), pt(14.5, 9.5)]
    }
    /// Root anchor a0.
    pub fn a0() -> Pt {
        pt(8.0, 19.5)
    }
    /// Goal g.
    pub fn g() -> Pt {
        pt(12.0, 1.5)
    }
    /// Slope, degrees.
    pub const SLOPE_DEG: f64 = 50.0;
    /// Friction coefficient.
    pub const MU: f64 = 0.91;
}

/// Runs every workload once, in the order of the module table.
pub fn run_all(arenas: &mut Arenas<'_>, h: &mut impl Harness) {
    let params = RoverParams::AXEL;

    // Traversability: settle.
    let mut settled = SettleOutcome::InvalidInput;
    h.measure("settle_plane_30deg", &mut || settled = settle_workload());
    let s = match &settled {
        SettleOutcome::Settled(p) => {
            let t = p.pose.translation.vector;
            line(format_args!(
                "Settled iterations={} axle=({},{},{}) roll={}",
                p.iterations, t.x, t.y, t.z, p.roll_rad
            ))
        }
        other => line(format_args!("{other:?}")),
    };
    h.result("settle_plane_30deg", &s);

    // Tether: anchors over the step.
    let mut history = AnchorHistory::default();
    let mut predicted = Err(firmware::tether::TetherError::EmptyHistory);
    h.measure("predict_anchors_step_lip", &mut || predicted = predict_anchors_workload(&mut history));
    let s = match &predicted {
        Ok(st) => {
            let lip = history.last().map(|a| a.point).unwrap_or_default();
            line(format_args!(
                "anchors={} last=({},{},{}) attached={} detached={} queries={}",
                history.len(),
                lip.x,
                lip.y,
                lip.z,
                st.attached,
                st.detached,
                st.queries
            ))
        }
        Err(e) => line(format_args!("{e:?}")),
    };
    h.result("predict_anchors_step_lip", &s);

    // Stability of the settled pose, tethered upslope.
    if let SettleOutcome::Settled(pose) = settled {
        let plane = InclinedPlane::new(PLANE_SLOPE_DEG.to_radians());
        let anchor = upslope_anchor();
        let mut out = None;
        h.measure("pose_stability_plane_30deg", &mut || {
            out = Some(check_pose_stability(&plane, &pose, Some(&anchor), &params))
        });
        let s = match &out {
            Some(Ok((StabilityOutcome::Stable(r), boom))) | Some(Ok((StabilityOutcome::Unstable(r), boom))) => line(format_args!(
                "{} boom={:?} margin={} tension_n={} lp_iterations={}",
                if matches!(out, Some(Ok((StabilityOutcome::Stable(_), _)))) { "Stable" } else { "Unstable" },
                boom,
                r.margin,
                r.tension_n,
                r.iterations
            )),
            other => line(format_args!("{other:?}")),
        };
        h.result("pose_stability_plane_30deg", &s);

        // The margin LP alone, by both solvers: the per-solve cost side by side.
        let problem = stability_problem(&pose, boom_inline_angle(&pose, &anchor), None, Some(&anchor), &params);
        if let Ok(lp) = problem.to_lp() {
            let mut ipm = None;
            h.measure("stability_lp_interior_point", &mut || {
                ipm = Some(lp.solve(SOLVER_MAX_ITERATIONS, SOLVER_TOLERANCE))
            });
            let s = match &ipm {
                Some(sol) => line(format_args!("{:?} margin={} iterations={}", sol.status, -sol.objective, sol.iterations)),
                None => line(format_args!("not run")),
            };
            h.result("stability_lp_interior_point", &s);
            let mut spx = None;
            h.measure("stability_lp_simplex", &mut || spx = Some(simplex::solve(&lp, SIMPLEX_MAX_PIVOTS)));
            let s = match &spx {
                Some(sol) => line(format_args!("{:?} margin={} pivots={}", sol.status, -sol.objective, sol.iterations)),
                None => line(format_args!("not run")),
            };
            h.result("stability_lp_simplex", &s);
        }
    }

    // The margin LP over a batch of real poses, by both solvers.
    let batch = lp_batch::problems();
    for (name, pass) in [
        ("stability_lp_batch_build", lp_batch::Pass::Build),
        ("stability_lp_batch_interior_point", lp_batch::Pass::InteriorPoint),
        ("stability_lp_batch_simplex", lp_batch::Pass::Simplex),
    ] {
        let mut r = lp_batch::BatchResult::default();
        h.measure(name, &mut || r = lp_batch::run(&batch, pass));
        h.result(name, &line(format_args!("problems={} optimal={} margin_sum={}", r.problems, r.optimal, r.margin_sum)));
    }

    // ABIT* on the wall with a gap.
    let problem = wall_gap::<2>("wall_gap_r2");
    let pdef = ProblemDefinition {
        start: problem.start,
        start_attachment: (),
        goal: GoalState { state: problem.goal, tolerance: 0.0 },
        objective: PathLength::new(),
    };
    let (mut space, mut validity, mut motion) = (problem.space, problem.obstacles.clone(), problem.obstacles.clone());
    let mut rng = SplitMix64(ABIT_SEED);
    let mut planner = AbitStar::new(
        &mut *arenas.abit,
        &mut space,
        &mut validity,
        &mut motion,
        &pdef,
        &mut rng,
        AbitParams::ompl_defaults(),
    );
    let mut report = None;
    h.measure("abit_wall_gap_r2", &mut || report = Some(planner.solve(&Budget::iterations(ABIT_ITERATIONS))));
    let s = match report {
        Some(r) => {
            let u = planner.arena_use();
            let (found, cost) = match r.status {
                PlannerStatus::Exact(cost) => (true, cost),
                _ => (false, planner.best_cost()),
            };
            line(format_args!(
                "found={} cost={} iterations={} batches={} edges_evaluated={} arena_use nodes={} queue={} memo={}",
                found,
                cost,
                r.counters.iterations,
                r.counters.batches,
                r.counters.edges_evaluated,
                u.nodes,
                u.queue,
                u.memo
            ))
        }
        None => line(format_args!("not run")),
    };
    h.result("abit_wall_gap_r2", &s);

    // Team: one local plan, one D* Lite replan.
    let n = synthetic_scan(&mut arenas.scan[..]);
    let mut plan = None;
    let (local, scan) = (&mut *arenas.local, &arenas.scan[..]);
    h.measure("team_local_plan", &mut || plan = Some(local_plan_workload(local, scan.get(..n).unwrap_or(&[]))));
    let s = match &plan {
        Some(Ok(p)) => {
            let end = p.hops.last().copied().unwrap_or_default();
            line(format_args!(
                "{} hops={} end=({},{},{}) loss={} expansions={}",
                status_label(&p.status),
                p.hops.len(),
                end.x,
                end.y,
                end.z,
                p.loss,
                p.expansions
            ))
        }
        Some(Err(e)) => line(format_args!("{e:?}")),
        None => line(format_args!("not run")),
    };
    h.result("team_local_plan", &s);
    let mut d = None;
    let dstar = &mut *arenas.dstar;
    h.measure("team_dstar_replan", &mut || d = Some(dstar_workload(dstar)));
    let s = match &d {
        Some(Ok(Status::Exact(Found { cost, expansions }))) => {
            line(format_args!("Found cost={cost} expansions={expansions}"))
        }
        // As the `{:?}` of the result read before the shared status: `Ok(NoPath { expansions: 3 })`.
        Some(Ok(o @ Status::NoSolution(n))) => {
            line(format_args!("Ok({} {{ expansions: {} }})", outcome_label(o), n.expansions))
        }
        Some(Ok(Status::Approximate(n) | Status::InvalidInput(n))) => match *n {},
        Some(Err(e)) => line(format_args!("Err({e:?})")),
        None => line(format_args!("not run")),
    };
    h.result("team_dstar_replan", &s);

    // Homotopy: BTM of scenario C, then Alg. 1.
    let (plane, o1, o2) = (scenario_c::plane(), scenario_c::o1(), scenario_c::o2());
    let btm = &mut *arenas.btm;
    let mut built = None;
    h.measure("homotopy_btm_build_c", &mut || built = Some(btm.build(&plane, &[&o1, &o2])));
    let s = match &built {
        Some(Ok(_)) => line(format_args!("triangles={}", btm.triangle_count())),
        Some(Err(e)) => line(format_args!("{e:?}")),
        None => line(format_args!("not run")),
    };
    h.result("homotopy_btm_build_c", &s);
    if matches!(built, Some(Ok(_))) {
        let model = HoldModel::point_mass(scenario_c::SLOPE_DEG.to_radians(), SoilMap::uniform(scenario_c::MU));
        let ws = &mut *arenas.homotopy;
        let mut constraints = heapless::Vec::new();
        let mut rep = PlanReport::default();
        let mut out = None;
        let btm = &*btm;
        h.measure("homotopy_preplan_c", &mut || {
            out = Some(preplan(
                btm,
                &model,
                &HomotopyParams::default(),
                ws,
                scenario_c::a0(),
                scenario_c::g(),
                &mut constraints,
                &mut rep,
            ))
        });
        let s = match &out {
            Some(Ok(Some(p))) => line(format_args!(
                "plan class_cost={} anchors={} descent_points={} classes_examined={} rounds={}",
                p.class.cost,
                p.anchors.len(),
                p.descent.len(),
                rep.examined.len(),
                rep.rounds
            )),
            Some(Ok(None)) => line(format_args!("no plan classes_examined={} rounds={}", rep.examined.len(), rep.rounds)),
            Some(Err(e)) => line(format_args!("{e:?}")),
            None => line(format_args!("not run")),
        };
        h.result("homotopy_preplan_c", &s);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::boxed::Box;
    use std::string::String;
    use std::vec::Vec;

    /// Runs the workloads on the host: no timing, summaries collected.
    struct Collect(Vec<(&'static str, String)>);
    impl Harness for Collect {
        fn measure(&mut self, _: &'static str, work: &mut dyn FnMut()) {
            work()
        }
        fn result(&mut self, name: &'static str, summary: &str) {
            self.0.push((name, summary.into()));
        }
    }

    #[test]
    fn step_sdf_is_exact_at_probe_points() {
        let s = Step { height_m: 4.0 };
        let d = |x: Real, z: Real| match s.query(&Vec3::new(x, 0.0, z)) {
            DistanceQuery::Known { distance, .. } => distance,
            DistanceQuery::Unknown => Real::NAN,
        };
        assert_eq!(d(3.0, 1.0), 1.0); // above the floor, 3 m from the wall
        assert_eq!(d(-2.0, 5.0), 1.0); // above the upper level
        assert_eq!(d(3.0, 8.0), 5.0); // 3-4-5 from the lip
        assert_eq!(d(-1.0, 2.0), -1.0); // inside, 1 m behind the wall
    }

    /// All workloads, `times` times over the same host arenas (fresh boxes for the first run).
    fn run_fresh(times: usize) -> Vec<Vec<(&'static str, String)>> {
        let mut abit: Box<WallGapArena> = Box::default();
        let mut local: Box<DefaultLocalPlanner> = Box::default();
        let mut scan: Box<[Vec3; SCAN_POINTS]> = Box::new([Vec3::zeros(); SCAN_POINTS]);
        let mut dstar: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let mut btm: Box<Btm> = Box::default();
        let mut ws: Box<Workspace> = Box::default();
        let mut arenas = Arenas {
            abit: &mut abit,
            local: &mut local,
            scan: &mut scan,
            dstar: &mut dstar,
            btm: &mut btm,
            homotopy: &mut ws,
        };
        (0..times)
            .map(|_| {
                let mut h = Collect(Vec::new());
                run_all(&mut arenas, &mut h);
                h.0
            })
            .collect()
    }

    #[test]
    fn workloads_do_real_work() {
        let runs = run_fresh(2);
        let h = Collect(runs[0].clone());
        for (n, s) in &h.0 {
            std::eprintln!("{n}: {s}");
        }
        let get = |n: &str| h.0.iter().find(|(k, _)| *k == n).map(|(_, s)| s.clone()).unwrap_or_default();
        assert_eq!(h.0.len(), 13, "{:?}", h.0);

        // settle: the analytic answer, axle one wheel radius above the plane, up axis = normal
        let plane = InclinedPlane::new(PLANE_SLOPE_DEG.to_radians());
        let SettleOutcome::Settled(p) = settle_workload() else { panic!("{}", get("settle_plane_30deg")) };
        let params = RoverParams::AXEL;
        let height = p.pose.translation.vector.dot(&plane.normal);
        assert!((height - params.wheel_radius_m).abs() < 2.0 * params.contact_threshold_m, "{height}");
        assert!(firmware::rover::rover_up(&p).dot(&plane.normal) > 0.9995);
        assert!(get("settle_plane_30deg").starts_with("Settled "));

        // tether: one anchor attached on the lip (0, 0, 4)
        let mut hist = AnchorHistory::default();
        assert!(predict_anchors_workload(&mut hist).is_ok());
        assert_eq!(hist.len(), 2);
        let lip = hist.last().map(|a| a.point).unwrap_or_default();
        assert!((lip - Vec3::new(0.0, 0.0, STEP_HEIGHT_M)).norm() < 0.02, "{lip:?}");
        assert!(get("predict_anchors_step_lip").starts_with("anchors=2 "));

        // stability: a taut tether upslope holds the rover on a 30-degree plane (wheel mu of the Axel model)
        let (o, _) = check_pose_stability(&plane, &p, Some(&upslope_anchor()), &params).unwrap();
        assert!(o.is_stable(), "{o:?}");
        assert!(get("pose_stability_plane_30deg").starts_with("Stable "));
        // the margin LP alone: both solvers reach the same optimum (the interior point to its 1e-9 tolerance)
        let margin = |name: &str| -> f64 {
            let s = get(name);
            s.split(' ').find_map(|w| w.strip_prefix("margin=")).and_then(|m| m.parse().ok()).unwrap_or(f64::NAN)
        };
        assert!(get("stability_lp_interior_point").starts_with("Optimal "), "{}", get("stability_lp_interior_point"));
        assert!(get("stability_lp_simplex").starts_with("Optimal "), "{}", get("stability_lp_simplex"));
        let (m_ipm, m_spx) = (margin("stability_lp_interior_point"), margin("stability_lp_simplex"));
        assert!(m_spx > 0.0 && (m_ipm - m_spx).abs() < 1e-7, "{m_ipm} vs {m_spx}");
        // the batch: every problem solved by both, the same margins (to the interior point's tolerance)
        let batch = |name: &str| {
            let s = get(name);
            let f = |key: &str| s.split(' ').find_map(|w| w.strip_prefix(key)).and_then(|m| m.parse::<f64>().ok());
            (f("problems=").unwrap_or(0.0), f("optimal=").unwrap_or(-1.0), f("margin_sum=").unwrap_or(f64::NAN))
        };
        let (n, _, _) = batch("stability_lp_batch_build");
        let (n_ipm, opt_ipm, sum_ipm) = batch("stability_lp_batch_interior_point");
        let (n_spx, opt_spx, sum_spx) = batch("stability_lp_batch_simplex");
        assert!(n >= 60.0 && n == n_ipm && n == n_spx && opt_ipm == n && opt_spx == n, "{n} {opt_ipm} {opt_spx}");
        assert!((sum_ipm - sum_spx).abs() < 1e-7 * n, "{sum_ipm} vs {sum_spx}");

        // ABIT*: a solution through the gap, never shorter than the analytic optimum
        let s = get("abit_wall_gap_r2");
        assert!(s.starts_with("found=true cost="), "{s}");
        let cost: f64 = s["found=true cost=".len()..].split(' ').next().unwrap().parse().unwrap();
        let opt = geometric::wall_gap_optimal_cost();
        assert!(cost >= opt - 1e-9 && cost < 1.5 * opt, "{cost} vs {opt}");
        assert!(s.contains(&std::format!("iterations={ABIT_ITERATIONS} ")), "{s}");

        // team: the workloads' own tests check the answers; here that they ran to an answer
        let s = get("team_local_plan");
        assert!(s.starts_with("Exact ") || s.starts_with("Approximate "), "{s}");
        assert!(get("team_dstar_replan").starts_with("Found "), "{}", get("team_dstar_replan"));

        // homotopy: the BTM covers the plane and Alg. 1 chooses a class
        assert!(get("homotopy_btm_build_c").starts_with("triangles="));
        let s = get("homotopy_preplan_c");
        assert!(s.starts_with("plan class_cost="), "{s}");
        // the class's cost is at least the straight distance a0 -> g
        let c: f64 = s["plan class_cost=".len()..].split(' ').next().unwrap().parse().unwrap();
        assert!(c >= scenario_c::a0().dist(scenario_c::g()) - 1e-9, "{c}");

        // deterministic: a second run gives the same summaries
        // and on reused arenas (the planners reset the storage they are lent)
        assert_eq!(h.0, runs[1]);
    }
}
