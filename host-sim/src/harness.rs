//! One harness that runs every planner of the project on every shared problem it applies to.
//!
//! - [`shared_problems`] lists the shared problems (today: the geometric ABIT* benchmark problems of issue 6 —
//!   a wall with a narrow offset gap in R^2, R^4, R^8 and a 3D box world, `workloads::geometric`).
//! - [`planners`] lists the planners, each a [`HarnessPlanner`] saying which problems it applies to.
//! - [`run_all`] runs every (planner, problem, seed) combination and returns one [`RunResult`] per run, with the
//!   returned path re-validated independently of the planner ([`verify_geometric_path`]).
//!
//! To add a planner: implement [`HarnessPlanner`] and add it to [`planners`]; to add a problem: add a
//! [`SharedProblem`] variant and list it in [`shared_problems`]. The integration test `tests/tests/planners.rs`
//! runs the whole matrix with small budgets; `tetherbot abit-bench` runs the ABIT*/OMPL comparison on top of it.

use core::time::Duration;
use std::time::Instant;

use firmware::plan::abit::{AbitArena, AbitParams, AbitStar};
use firmware::plan::space::{Budget, GoalState, PathLength, Planner, ProblemDefinition, StateSpace};
use heapless::Vec as HVec;
use rand_core::SeedableRng;
use workloads::geometric::{box_world_3d, wall_gap, GeometricProblem};

/// A shared problem.
// A handful of problems exist at a time; their size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
pub enum SharedProblem {
    /// Geometric problem in R^2.
    Geometric2(GeometricProblem<2>),
    /// Geometric problem in R^3.
    Geometric3(GeometricProblem<3>),
    /// Geometric problem in R^4.
    Geometric4(GeometricProblem<4>),
    /// Geometric problem in R^8.
    Geometric8(GeometricProblem<8>),
}

impl SharedProblem {
    /// Short name.
    pub fn name(&self) -> &'static str {
        match self {
            Self::Geometric2(p) => p.name,
            Self::Geometric3(p) => p.name,
            Self::Geometric4(p) => p.name,
            Self::Geometric8(p) => p.name,
        }
    }
    /// The plain-text description read by the OMPL driver (geometric problems).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let _ = match self {
            Self::Geometric2(p) => p.write_text(&mut s),
            Self::Geometric3(p) => p.write_text(&mut s),
            Self::Geometric4(p) => p.write_text(&mut s),
            Self::Geometric8(p) => p.write_text(&mut s),
        };
        s
    }
}

/// The shared problems: `wall2`, `wall4`, `wall8` (wall with a narrow offset gap) and `box3d`.
pub fn shared_problems() -> Vec<SharedProblem> {
    vec![
        SharedProblem::Geometric2(wall_gap::<2>("wall2")),
        SharedProblem::Geometric4(wall_gap::<4>("wall4")),
        SharedProblem::Geometric8(wall_gap::<8>("wall8")),
        SharedProblem::Geometric3(box_world_3d()),
    ]
}

/// What one run is allowed.
#[derive(Debug, Clone, Copy)]
pub struct RunSpec {
    /// Seed of the planner's generator (`rand_pcg::Pcg64::seed_from_u64`).
    pub seed: u64,
    /// Iteration budget.
    pub iterations: u32,
    /// Optional wall-clock limit.
    pub time_limit: Option<Duration>,
}

/// The outcome of one run.
#[derive(Debug, Clone)]
pub struct RunResult {
    /// Planner name.
    pub planner: &'static str,
    /// Problem name.
    pub problem: &'static str,
    /// Seed.
    pub seed: u64,
    /// Exact solution found?
    pub solved: bool,
    /// Wall-clock time to the first solution (from planner set-up).
    pub first_solution_time: Option<Duration>,
    /// Iteration of the first solution.
    pub first_solution_iteration: Option<u32>,
    /// Cost of the best solution at the end.
    pub final_cost: Option<f64>,
    /// Iterations run.
    pub iterations: u32,
    /// Batches run.
    pub batches: u32,
    /// Motion checks.
    pub edges_evaluated: u32,
    /// State checks.
    pub states_checked: u32,
    /// Total wall-clock time.
    pub total_time: Duration,
    /// Independent re-validation of the returned path (`None` without a path).
    pub path_verified: Option<bool>,
}

/// A planner the harness can run.
pub trait HarnessPlanner {
    /// Name in tables.
    fn name(&self) -> &'static str;
    /// Does the planner apply to this problem?
    fn applies_to(&self, problem: &SharedProblem) -> bool;
    /// Run once.
    fn run(&self, problem: &SharedProblem, spec: &RunSpec) -> RunResult;
}

/// Every planner of the project.
pub fn planners() -> Vec<Box<dyn HarnessPlanner>> {
    vec![Box::new(AbitGeometric { params: AbitParams::ompl_defaults() })]
}

/// Run every planner on every problem it applies to, for each seed.
pub fn run_all(seeds: &[u64], iterations: u32, time_limit: Option<Duration>) -> Vec<RunResult> {
    let mut out = Vec::new();
    for planner in planners() {
        for problem in shared_problems() {
            if !planner.applies_to(&problem) {
                continue;
            }
            for &seed in seeds {
                out.push(planner.run(&problem, &RunSpec { seed, iterations, time_limit }));
            }
        }
    }
    out
}

/// Independent check of a geometric path: starts at the start, ends at the goal, and every segment is free of
/// every box, checked by dense sampling (1000 states per segment plus both ends) against the boxes — a different
/// test from the planner's slab test. Returns the path length if valid.
pub fn verify_geometric_path<const N: usize>(p: &GeometricProblem<N>, path: &[[f64; N]]) -> Option<f64> {
    if path.first() != Some(&p.start) || path.last() != Some(&p.goal) {
        return None;
    }
    let free = |x: &[f64; N]| p.space.contains(x) && !p.obstacles.boxes.iter().any(|b| b.contains(x));
    let mut length = 0.0;
    for w in path.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        for i in 0..=1000 {
            let x = p.space.interpolate(a, b, i as f64 / 1000.0);
            if !free(&x) {
                return None;
            }
        }
        length += p.space.distance(a, b);
    }
    Some(length)
}

/// ABIT* (firmware::plan::abit) on the geometric problems, OMPL defaults.
pub struct AbitGeometric {
    /// Parameters.
    pub params: AbitParams,
}

/// Host arena sizes for the benchmark (large: the host has memory; the board uses `config::abit`).
const HOST_NODES: usize = 16384;
const HOST_QUEUE: usize = 262_144;
const HOST_MEMO: usize = 65536;
/// Stack of the worker thread that holds the arena while it is built (the arena is ~15 MB).
const WORKER_STACK: usize = 256 << 20;

/// Run ABIT* once on a geometric problem. Runs on a worker thread with a large stack (the arena is built
/// there before it is boxed).
pub fn run_abit_geometric<const N: usize>(
    p: &GeometricProblem<N>,
    params: AbitParams,
    spec: &RunSpec,
) -> RunResult {
    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .stack_size(WORKER_STACK)
            .spawn_scoped(s, || run_abit_geometric_inner(p, params, spec));
        match worker.map(|h| h.join()) {
            Ok(Ok(r)) => r,
            _ => RunResult {
                planner: "ABIT* (ours)",
                problem: p.name,
                seed: spec.seed,
                solved: false,
                first_solution_time: None,
                first_solution_iteration: None,
                final_cost: None,
                iterations: 0,
                batches: 0,
                edges_evaluated: 0,
                states_checked: 0,
                total_time: Duration::ZERO,
                path_verified: Some(false),
            },
        }
    })
}

fn run_abit_geometric_inner<const N: usize>(
    p: &GeometricProblem<N>,
    params: AbitParams,
    spec: &RunSpec,
) -> RunResult {
    let mut arena: Box<AbitArena<[f64; N], (), HOST_NODES, HOST_QUEUE, HOST_MEMO>> = Box::default();
    let mut space = p.space;
    let mut validity = p.obstacles.clone();
    let mut motion = p.obstacles.clone();
    let pdef = ProblemDefinition {
        start: p.start,
        start_attachment: (),
        goal: GoalState { state: p.goal, tolerance: 0.0 },
        objective: PathLength::new(),
    };
    let mut rng = rand_pcg::Pcg64::seed_from_u64(spec.seed);
    let t0 = Instant::now();
    let mut planner = AbitStar::new(&mut arena, &mut space, &mut validity, &mut motion, &pdef, &mut rng, params);
    let mut first_time = None;
    let limit = spec.time_limit;
    let report = planner.solve_until(&Budget::iterations(spec.iterations), |c| {
        if first_time.is_none() && c.first_solution_iteration != 0 {
            first_time = Some(t0.elapsed());
        }
        limit.is_some_and(|l| t0.elapsed() >= l)
    });
    let total = t0.elapsed();
    if first_time.is_none() && report.counters.first_solution_iteration != 0 {
        first_time = Some(total);
    }
    let mut path: HVec<([f64; N], ()), 1024> = HVec::new();
    let verified = match planner.write_path(&mut path) {
        Ok(_) => {
            let states: Vec<[f64; N]> = path.iter().map(|(s, _)| *s).collect();
            let cost = planner.best_cost();
            Some(verify_geometric_path(p, &states).is_some_and(|len| (len - cost).abs() <= 1e-9 * (1.0 + cost)))
        }
        Err(_) => None,
    };
    let c = report.counters;
    RunResult {
        planner: "ABIT* (ours)",
        problem: p.name,
        seed: spec.seed,
        solved: report.status.is_exact(),
        first_solution_time: first_time,
        first_solution_iteration: (c.first_solution_iteration != 0).then_some(c.first_solution_iteration),
        final_cost: report.status.is_exact().then(|| planner.best_cost()),
        iterations: c.iterations,
        batches: c.batches,
        edges_evaluated: c.edges_evaluated,
        states_checked: c.states_checked,
        total_time: total,
        path_verified: verified,
    }
}

impl HarnessPlanner for AbitGeometric {
    fn name(&self) -> &'static str {
        "ABIT* (ours)"
    }
    fn applies_to(&self, problem: &SharedProblem) -> bool {
        matches!(
            problem,
            SharedProblem::Geometric2(_)
                | SharedProblem::Geometric3(_)
                | SharedProblem::Geometric4(_)
                | SharedProblem::Geometric8(_)
        )
    }
    fn run(&self, problem: &SharedProblem, spec: &RunSpec) -> RunResult {
        match problem {
            SharedProblem::Geometric2(p) => run_abit_geometric(p, self.params, spec),
            SharedProblem::Geometric3(p) => run_abit_geometric(p, self.params, spec),
            SharedProblem::Geometric4(p) => run_abit_geometric(p, self.params, spec),
            SharedProblem::Geometric8(p) => run_abit_geometric(p, self.params, spec),
        }
    }
}
