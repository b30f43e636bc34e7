//! Benchmarks of ABIT* (`firmware::plan::abit`, OMPL defaults) on the shared geometric problems of
//! `host_sim::harness::shared_problems` (a wall with a narrow offset gap in R^2, R^4, R^8 and the 3D box world):
//! - `abit first solution/<problem>`: planner set-up (`AbitStar::new`) plus iterations until the first solution
//!   (at most 50 000 iterations);
//! - `abit 3000 iterations/<problem>`: set-up plus a fixed budget of 3000 iterations (OMPL's count: one edge
//!   processed or one batch / final search started).
//!
//! Every measured call uses the next seed (1, 2, 3, ...), so a figure is a mean over many random problems
//! instances rather than one lucky or unlucky seed. The arena (host capacities, ~15 MB) is built once on a
//! worker thread with a large stack and reused (`AbitStar::new` clears it).
//! The side-by-side with OMPL 1.5.2 is `tetherbot abit-bench` (see `host-sim/doc/abit_bench.md`).
//! Run: `cargo bench -p host-sim --bench abit`.

use core::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use firmware::plan::abit::{AbitArena, AbitParams, AbitStar};
use firmware::plan::space::{Budget, GoalState, PathLength, Planner, ProblemDefinition};
use host_sim::harness::{shared_problems, SharedProblem};
use workloads::geometric::GeometricProblem;
use rand_core::SeedableRng;

type Arena<const N: usize> = AbitArena<[f64; N], (), 16384, 262_144, 65536>;

/// Box an arena on a thread with a stack large enough to build it.
fn boxed_arena<const N: usize>() -> Box<Arena<N>> {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(Box::<Arena<N>>::default)
        .expect("spawn the arena builder")
        .join()
        .expect("build the arena")
}

/// One run: set-up plus `budget` iterations, or until the first solution when `first_only`. Returns the cost.
fn run<const N: usize>(
    arena: &mut Arena<N>,
    p: &GeometricProblem<N>,
    seed: u64,
    budget: u32,
    first_only: bool,
) -> f64 {
    let mut space = p.space;
    let mut validity = p.obstacles.clone();
    let mut motion = p.obstacles.clone();
    let pdef = ProblemDefinition {
        start: p.start,
        start_attachment: (),
        goal: GoalState {
            state: p.goal,
            tolerance: 0.0,
        },
        objective: PathLength::new(),
    };
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let mut planner = AbitStar::new(
        arena,
        &mut space,
        &mut validity,
        &mut motion,
        &pdef,
        &mut rng,
        AbitParams::ompl_defaults(),
    );
    planner.solve_until(&Budget::iterations(budget), |c| {
        first_only && c.first_solution_iteration != 0
    });
    planner.best_cost()
}

fn bench_problem<const N: usize>(c: &mut Criterion, p: &GeometricProblem<N>) {
    let mut arena = boxed_arena::<N>();
    let mut seed = 0u64;
    c.benchmark_group("abit first solution")
        .sample_size(20)
        .measurement_time(Duration::from_secs(3))
        .bench_function(p.name, |b| {
            b.iter(|| {
                seed += 1;
                run(&mut arena, p, seed, 50_000, true)
            })
        });
    let mut seed = 0u64;
    c.benchmark_group("abit 3000 iterations")
        .sample_size(10)
        .measurement_time(Duration::from_secs(5))
        .bench_function(p.name, |b| {
            b.iter(|| {
                seed += 1;
                run(&mut arena, p, seed, 3000, false)
            })
        });
}

fn abit(c: &mut Criterion) {
    for problem in shared_problems() {
        match &problem {
            SharedProblem::Geometric2(p) => bench_problem(c, p),
            SharedProblem::Geometric3(p) => bench_problem(c, p),
            SharedProblem::Geometric4(p) => bench_problem(c, p),
            SharedProblem::Geometric8(p) => bench_problem(c, p),
        }
    }
}

criterion_group!(benches, abit);
criterion_main!(benches);
