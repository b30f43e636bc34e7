//! The ledge-with-pole planning workload, `tethered_test3` in the bench output: one trial of Paton et al.'s Table I
//! test 3 (section VI-A; `shared/SCENARIOS.md` section A), the ledge with a pole the tether must wrap, on the
//! flight computer: ABIT* ([`firmware::plan::abit`]) over the tether-aware space ([`firmware::plan::tethered`])
//! on the exact ledge + pole world ([`Ledge::with_pole`]), 750 iterations, seed 1.
//!
//! The problem is built exactly as host-sim's campaign builds a trial of `host-sim/scenarios/ledge_test3.toml`
//! planning on the exact world (`tetherbot campaign ledge_test3 --field truth`, `campaign::run_trial`): the same
//! start, yaw, root anchor, goal, tolerance and bounds (as f64 constants cast to `f32` the same way), Axel's rover
//! model, [`TetherSpaceParams::DEFAULT`], OMPL's ABIT* defaults with history twins, and the campaign's generator,
//! PCG-64 (`rand_pcg::Pcg64`, re-implemented here as [`Pcg64`] because the core keeps rand_pcg a host-only
//! dependency) seeded with `seed_from_u64(seed)`. `tests/tests/board_ledge_pole.rs` checks that the campaign's
//! `run_trial` and [`plan_ledge_pole`] give the same trial.
//!
//! Parameters: [`ITERATIONS`] = 750 (Table I), [`SEED`] = 1 (the scenario's `seeds.planner`);
//! capacities in [`crate::config`] (512 nodes, 2048 queued edges, 1024 memo entries, 64 path states).
//!
//! It is opt-in on the board (it costs tens of billions of instructions under QEMU): run it with
//! `cargo run -p host-sim --bin tetherbot -- board bench --build --workload tethered_test3 [--iterations N]`;
//! the default `board bench` and CI do not run it. `--iterations 30` is the short variant (the first batch).
//!
//! Its instruction counts, stack and storage on the board, and how they were measured, are in
//! `host-sim/doc/board_test3.md`.

use core::convert::Infallible;
use core::fmt::Write;

use rand_core::{SeedableRng, TryRng};

use firmware::config::rover::RoverParams;
use firmware::geom::Real;
use firmware::geom::p3::to_vec3;
use firmware::map::DistanceField;
use firmware::plan::abit::{AbitArena, AbitParams, AbitStar, ArenaUse, PathError};
use firmware::plan::space::{Budget, Counters, GoalState, Planner, ProblemDefinition, Termination};
use firmware::plan::tethered::{
    MotionStats, PhaseClock, PhaseTicks, PlanBounds, RoverState, TetherMotionValidator, TetherObjective, TetherSpace,
    TetherSpaceParams, TetherValidity,
};
use firmware::tether::{Anchor, AnchorHistory};

use crate::config::{
    LEDGE_POLE_EDGE_MEMO_CAPACITY, LEDGE_POLE_EDGE_QUEUE_CAPACITY, LEDGE_POLE_NODE_CAPACITY, LEDGE_POLE_PATH_CAPACITY,
};
use crate::ledge::Ledge;
use crate::{Harness, Summary, TimedField};

/// Iterations of the workload (Paton et al. Table I: 750).
pub const ITERATIONS: u32 = 750;
/// Planner seed (`ledge_test3.toml`'s `seeds.planner`, the campaign's first trial).
pub const SEED: u64 = 1;
/// Start position (axle centre; settled on the ledge top below it), `rover.start`.
pub const START: [f64; 3] = [-1.5, 0.0, 4.35];
/// Start yaw, degrees (facing +x, down the slope), `rover.yaw_deg`.
pub const START_YAW_DEG: f64 = 0.0;
/// Root anchor: 8.2 m in front of and 2 m above the start, `tether.root_anchor`.
pub const ROOT_ANCHOR: [f64; 3] = [6.7, 0.0, 6.35];
/// Goal position (axle centre on the ground below the slope), `goal.position`.
pub const GOAL: [f64; 3] = [6.0, 0.0, 0.35];
/// Goal radius, metres, `goal.tolerance_m`.
pub const GOAL_TOLERANCE_M: f64 = 0.5;
/// Lower corner of the planning bounds, `plan.bounds_min`.
pub const BOUNDS_MIN: [f64; 3] = [-5.0, -5.0, -0.5];
/// Upper corner of the planning bounds, `plan.bounds_max`.
pub const BOUNDS_MAX: [f64; 3] = [7.5, 5.0, 7.5];

/// The planner arena of the workload (capacities from [`crate::config`]).
pub type LedgePoleArena = AbitArena<
    RoverState,
    AnchorHistory,
    LEDGE_POLE_NODE_CAPACITY,
    LEDGE_POLE_EDGE_QUEUE_CAPACITY,
    LEDGE_POLE_EDGE_MEMO_CAPACITY,
>;

/// A returned path: states with their anchor histories.
pub type LedgePolePath = heapless::Vec<(RoverState, AnchorHistory), LEDGE_POLE_PATH_CAPACITY>;

/// The storage of the workload, lent by the caller (a `.psram` static on the board, a box on the host). Its empty
/// state is all zero bytes.
pub struct LedgePoleStorage {
    /// ABIT* arena.
    pub arena: LedgePoleArena,
    /// The best path after the budget.
    pub path: LedgePolePath,
}

impl LedgePoleStorage {
    /// Empty storage (const, for a static).
    pub const fn new() -> Self {
        Self { arena: AbitArena::new(), path: heapless::Vec::new() }
    }
}

impl Default for LedgePoleStorage {
    fn default() -> Self {
        Self::new()
    }
}

/// PCG-64 (O'Neill 2014: 128-bit LCG, XSL RR output), bit-identical to `rand_pcg::Pcg64` 0.10 including
/// `SeedableRng::from_seed` (state and increment from the seed's little-endian words), so
/// `Pcg64::seed_from_u64(s)` draws what the campaign's generator draws.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Pcg64 {
    state: u128,
    increment: u128,
}

const PCG_MULTIPLIER: u128 = 0x2360_ED05_1FC6_5DA4_4385_DF64_9FCC_F645;

impl Pcg64 {
    fn step(&mut self) {
        self.state = self.state.wrapping_mul(PCG_MULTIPLIER).wrapping_add(self.increment);
    }
}

impl SeedableRng for Pcg64 {
    type Seed = [u8; 32];
    fn from_seed(seed: [u8; 32]) -> Self {
        let mut w = [0u64; 4];
        for (word, chunk) in w.iter_mut().zip(seed.chunks_exact(8)) {
            let mut b = [0u8; 8];
            b.copy_from_slice(chunk);
            *word = u64::from_le_bytes(b);
        }
        let [s0, s1, i0, i1] = w;
        let state = u128::from(s0) | (u128::from(s1) << 64);
        let increment = (u128::from(i0) | (u128::from(i1) << 64)) | 1;
        let mut pcg = Pcg64 { state: state.wrapping_add(increment), increment };
        pcg.step();
        pcg
    }
}

impl TryRng for Pcg64 {
    type Error = Infallible;
    fn try_next_u32(&mut self) -> Result<u32, Infallible> {
        self.try_next_u64().map(|x| x as u32)
    }
    fn try_next_u64(&mut self) -> Result<u64, Infallible> {
        self.step();
        let rot = (self.state >> 122) as u32;
        let xsl = ((self.state >> 64) as u64) ^ (self.state as u64);
        Ok(xsl.rotate_right(rot))
    }
    fn try_fill_bytes(&mut self, dst: &mut [u8]) -> Result<(), Infallible> {
        for chunk in dst.chunks_mut(8) {
            let bytes = self.try_next_u64()?.to_le_bytes();
            for (d, s) in chunk.iter_mut().zip(bytes) {
                *d = s;
            }
        }
        Ok(())
    }
}

/// The planning bounds (as the campaign casts the scenario's).
pub fn bounds() -> PlanBounds {
    PlanBounds { min: BOUNDS_MIN.map(|v| v as Real), max: BOUNDS_MAX.map(|v| v as Real) }
}

/// The planner parameters of the campaign (OMPL's ABIT* defaults, history twins on).
pub fn abit_params() -> AbitParams {
    let mut p = AbitParams::ompl_defaults();
    p.history_twins = true;
    p
}

/// Why the problem could not be set up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LedgePoleError {
    /// The space rejected a parameter: (field, reason).
    Space(&'static str, &'static str),
    /// The start did not settle.
    StartDoesNotSettle,
    /// The goal did not settle.
    GoalDoesNotSettle,
}

/// Where a trial's time went (clock ticks; 0 without a clock) and how many distance-field queries it made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Phases {
    /// The space's phases.
    pub space: PhaseTicks,
    /// Distance-field queries (counted with or without a clock).
    pub field_queries: u64,
    /// Ticks in distance-field queries.
    pub field_ticks: u64,
}

/// The outcome of one trial.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LedgePoleOutcome {
    /// An exact solution was found.
    pub found: bool,
    /// Cost of the best path after the budget (when found).
    pub cost: Option<f64>,
    /// The planner's counters (iterations, batches, edges, first-solution iteration).
    pub counters: Counters,
    /// Why the planner stopped.
    pub termination: Termination,
    /// Arena high-water marks.
    pub arena: ArenaUse,
    /// Work of the space: settles, stability LPs, anchor predictions, motion failures.
    pub stats: MotionStats,
    /// Clock ticks per phase (all 0 without a clock): the space's settle, stability and anchor phases, and every
    /// distance-field query (inside those phases and elsewhere).
    pub phases: Phases,
    /// States of the written path (0 when none; see `path_error`).
    pub path_states: usize,
    /// Anchors of the path's final history (root included).
    pub final_anchors: usize,
    /// Why the path was not written, if it was not.
    pub path_error: Option<PathError>,
}

/// Plans the ledge-with-pole problem (test 3) on `field` with `iterations` iterations and planner seed `seed`, in `arena`; the best path is
/// written to `path`. Mirrors host-sim's `campaign::run_trial`.
/// With a `clock`, each phase is timed ([`Phases`]; the board's bench lends SysTick); the trial is the same with
/// or without it.
pub fn plan_ledge_pole<D: DistanceField, const NV: usize, const NQ: usize, const NM: usize, const NP: usize>(
    field: &D,
    arena: &mut AbitArena<RoverState, AnchorHistory, NV, NQ, NM>,
    path: &mut heapless::Vec<(RoverState, AnchorHistory), NP>,
    iterations: u32,
    seed: u64,
    clock: Option<&dyn PhaseClock>,
) -> Result<LedgePoleOutcome, LedgePoleError> {
    let field = TimedField::new(field, clock);
    let space = TetherSpace::new(&field, bounds(), RoverParams::AXEL, TetherSpaceParams::DEFAULT)
        .map_err(|(f, r)| LedgePoleError::Space(f, r))?;
    let mut space = match clock {
        Some(c) => space.with_phase_clock(c),
        None => space,
    };
    let yaw = START_YAW_DEG.to_radians() as Real;
    let start = space
        .settle_state(START[0] as Real, START[1] as Real, yaw)
        .map_err(|_| LedgePoleError::StartDoesNotSettle)?;
    let goal = space.goal_state(to_vec3(GOAL), 0.0).map_err(|_| LedgePoleError::GoalDoesNotSettle)?;
    let pdef = ProblemDefinition {
        start,
        start_attachment: AnchorHistory::new(Anchor::root(to_vec3(ROOT_ANCHOR))),
        goal: GoalState { state: goal, tolerance: GOAL_TOLERANCE_M },
        objective: TetherObjective,
    };
    let (mut validity, mut motion) = (TetherValidity, TetherMotionValidator);
    let mut rng = Pcg64::seed_from_u64(seed);
    let mut planner = AbitStar::new(arena, &mut space, &mut validity, &mut motion, &pdef, &mut rng, abit_params());
    let report = planner.solve(&Budget::iterations(iterations));
    let written = if report.status.is_exact() { planner.write_path(path) } else { Err(PathError::NoSolution) };
    let found = report.status.is_exact() && written.is_ok();
    let cost = found.then(|| planner.best_cost());
    let arena_use = planner.arena_use();
    Ok(LedgePoleOutcome {
        found,
        cost,
        counters: report.counters,
        termination: report.termination,
        arena: arena_use,
        stats: space.stats(),
        phases: Phases { space: space.phase_ticks(), field_queries: field.queries(), field_ticks: field.ticks() },
        path_states: if found { path.len() } else { 0 },
        final_anchors: if found { path.last().map_or(0, |(_, h)| h.len()) } else { 0 },
        path_error: written.err(),
    })
}

/// The workload's one-line summary of an outcome (equal text on host and board means equal bits).
pub fn summary(out: &Result<LedgePoleOutcome, LedgePoleError>) -> Summary {
    let mut s = Summary::new();
    // A summary longer than the capacity is cut.
    let _ = match out {
        Ok(o) => write!(
            s,
            "found={} first_iteration={} cost={} iterations={} batches={} edges={} nodes={} queue={} memo={} \
             settles={} lps={} anchor_predictions={} path_states={} final_anchors={}",
            o.found,
            o.counters.first_solution_iteration,
            o.cost.unwrap_or(f64::NAN),
            o.counters.iterations,
            o.counters.batches,
            o.counters.edges_evaluated,
            o.arena.nodes,
            o.arena.queue,
            o.arena.memo,
            o.stats.settles,
            o.stats.stability_checks,
            o.stats.anchor_predictions,
            o.path_states,
            o.final_anchors
        ),
        Err(e) => write!(s, "{e:?}"),
    };
    s
}

/// Name of the workload in the bench output and on the command line (`--workload tethered_test3`, the boot word
/// `tetherbot.workload=tethered_test3`).
pub const NAME: &str = "tethered_test3";

/// Runs the workload (`iterations` iterations, seed [`SEED`]) on the exact ledge + pole world, timed by
/// `h`, and reports its summary as [`NAME`].
/// With a `clock` the phases are timed and reported to `h` as well ([`Harness::phases`]).
pub fn run_ledge_pole(
    storage: &mut LedgePoleStorage,
    iterations: u32,
    h: &mut impl Harness,
    clock: Option<&dyn PhaseClock>,
) {
    let field = Ledge::with_pole();
    let mut out = Err(LedgePoleError::StartDoesNotSettle);
    let LedgePoleStorage { arena, path } = storage;
    h.measure(NAME, &mut || out = plan_ledge_pole(&field, arena, path, iterations, SEED, clock));
    h.result(NAME, &summary(&out));
    if let Ok(o) = &out {
        let p = o.phases;
        let mut s = Summary::new();
        // Fits: six numbers and their names.
        let _ = write!(
            s,
            "settle_ticks={} stability_ticks={} anchors_ticks={} field_ticks={} field_queries={}",
            p.space.settle, p.space.stability, p.space.anchors, p.field_ticks, p.field_queries
        );
        h.phases(NAME, &s);
    }
}
