//! The planner harness: every planner of the project on every shared problem it applies to
//! (`host_sim::harness`). Small budgets; the full comparison is `tetherbot abit-bench`.

use host_sim::harness::{planners, run_all, shared_problems, SharedProblem};
use workloads::geometric::wall_gap_optimal_cost;

#[test]
fn every_planner_solves_every_shared_problem_it_applies_to_with_verified_paths() {
    let seeds = [1u64, 2, 3];
    let results = run_all(&seeds, 3000, None);
    let problems = shared_problems();
    for planner in planners() {
        for problem in problems.iter().filter(|p| planner.applies_to(p)) {
            let runs: Vec<_> =
                results.iter().filter(|r| r.planner == planner.name() && r.problem == problem.name()).collect();
            assert_eq!(runs.len(), seeds.len(), "{} on {}", planner.name(), problem.name());
            assert!(runs.iter().any(|r| r.solved), "{} never solved {}", planner.name(), problem.name());
            // Analytic lower bounds: the wall's optimum through the gap; the box world's straight line.
            let lower = match problem {
                SharedProblem::Geometric3(_) => 8.0 * 3f64.sqrt(),
                _ => wall_gap_optimal_cost(),
            };
            for r in runs.iter().filter(|r| r.solved) {
                assert_eq!(r.path_verified, Some(true), "{} on {} seed {}", r.planner, r.problem, r.seed);
                let cost = r.final_cost.expect("solved runs have a cost");
                assert!(cost >= lower - 1e-9, "{} on {}: cost {cost} below the optimum {lower}", r.planner, r.problem);
                assert!(r.first_solution_iteration.is_some_and(|i| i <= r.iterations));
            }
        }
    }
}
