//! Planner abstractions, following OMPL's split (`ompl::base`), without heap.
//!
//! | OMPL | here |
//! |---|---|
//! | `StateSpace` + `StateSampler` + `InformedSampler` | [`StateSpace`] (uniform sampling, informed sampling for path length, distance, interpolation) |
//! | `StateValidityChecker` | [`StateValidityChecker`] |
//! | `MotionValidator` | [`MotionValidator`] (returns the attachment of the motion's end state) |
//! | `OptimizationObjective` | [`OptimizationObjective`] (true motion cost, admissible heuristic, informed sampling) |
//! | `GoalSampleableRegion` | [`GoalRegion`] |
//! | `ProblemDefinition` | [`ProblemDefinition`] |
//! | `PlannerTerminationCondition` | [`Budget`] plus an optional stop predicate |
//! | `PlannerStatus` | [`PlannerStatus`] (the shared [`crate::plan::status::Status`]) + [`Termination`] |
//!
//! ## Non-Markovian states (Paton et al. V-A, Fig. 7)
//! A state may carry an **attachment** ([`StateSpace::Attachment`]): for the tethered rover, its anchor history.
//! The attachment of a tree vertex is set when the vertex is connected: the motion validator receives the parent's
//! attachment and returns the attachment at the end of the motion ([`MotionCheck::Valid`]); the motion's validity
//! and cost may depend on the parent's attachment. A vertex already in the tree may only be rewired to a parent
//! whose motion yields an attachment [`StateSpace::attachments_compatible`] with its own (its descendants' validity
//! depends on it). Markovian spaces use `type Attachment = ();` and keep `NON_MARKOVIAN = false`, which switches
//! off attachment copying and fresh goals in the planner.
//!
//! Costs are `f64` ([`Cost`]), as in OMPL; states are whatever the space chooses.
//!
//! ## Wiring the tether-aware space (Paton et al. IV-V) into `plan::abit`
//! - `StateSpace`: `State` = a settled SE(3) pose (plus whatever settling produced that the checks reuse);
//!   `Attachment` = the tether's `AnchorHistory`; `NON_MARKOVIAN = true`; `sample_uniform` = sample a surface
//!   point, perturb, random yaw about the normal, settle (`None` when settling fails); `distance` = a metric on
//!   positions (+ weighted yaw); `attachments_compatible` = same anchors within tolerance.
//! - `StateValidityChecker::is_valid`: settled, no body collision (attachment-independent). An off-map goal
//!   (Paton et al. VI-B) is a state this checker accepts.
//! - `MotionValidator::check_motion(space, from, history, to)`: turn in place + straight drive, interpolated,
//!   every interpolated state settled, collision-checked, `predict_anchors` (Alg. 1) from `history`, QP
//!   stability with the last anchor; returns `Valid { attachment: history_after }` or `Invalid`. For an off-map
//!   goal: valid when `from` is near the map edge.
//! - `OptimizationObjective`: `motion_cost` = weighted yaw change + roll + length; `motion_cost_heuristic` =
//!   `w_length * euclidean distance` (admissible); `sample_informed` may stay unsupported (the planner then
//!   rejection-samples on the heuristic, drawing up to `informed_rejection_attempts` settled samples per sample —
//!   a cheap ellipse pre-test before settling is worth implementing there).
//! - `ProblemDefinition { start, start_attachment: root AnchorHistory, goal: GoalState { .. }, objective }`, then
//!   `AbitStar::new(&mut arena, &mut space, &mut validity, &mut motion, &pdef, &mut rng, params)` and
//!   `solve(&Budget::iterations(750))`; `write_path` gives the states with their anchor histories.

use rand_core::Rng;

pub use crate::plan::status::{Ended, Status};

/// Path cost (OMPL `base::Cost`). Lower is better; `f64::INFINITY` means "no path".
pub type Cost = f64;

/// A uniformly distributed `f64` in `[0, 1)` from 53 random bits (deterministic on every target).
pub fn uniform01<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    const SCALE: f64 = 1.0 / ((1u64 << 53) as f64);
    ((rng.next_u64() >> 11) as f64) * SCALE
}

/// A standard normal sample (Box-Muller through `libm`, deterministic).
pub fn standard_normal<R: Rng + ?Sized>(rng: &mut R) -> f64 {
    // 1 - u is in (0, 1], so the logarithm is finite.
    let u1 = 1.0 - uniform01(rng);
    let u2 = uniform01(rng);
    libm::sqrt(-2.0 * libm::log(u1)) * libm::cos(core::f64::consts::TAU * u2)
}

/// Result of an informed-sampling request.
#[derive(Debug, Clone, PartialEq)]
pub enum InformedSample<St> {
    /// A state drawn uniformly from the informed set (and the space's bounds).
    Sampled(St),
    /// The direct sampler tried and failed (e.g. the draw fell outside the bounds); counts as one attempt.
    Rejected,
    /// No direct informed sampler for this space/objective: the planner falls back to rejection sampling of
    /// uniform states on the heuristic.
    Unsupported,
}

/// Result of a catch-boundary sampling request ([`StateSpace::sample_catch_boundary`]).
#[derive(Debug, Clone, PartialEq)]
pub enum CatchSample<St> {
    /// A state near the boundary.
    Sampled(St),
    /// A boundary point was found but no state could be made there (e.g. settling failed); worth asking again.
    Rejected,
    /// No boundary found within the space's budget (there may be none, e.g. a root anchor that sees the whole
    /// planning area), or the space has no such sampler: the planner stops asking for this attachment until the
    /// next batch.
    NotFound,
}

/// The configuration space: sampling, metric and interpolation (OMPL `StateSpace` + samplers).
pub trait StateSpace {
    /// A state. Stored by value in the planner's arena.
    type State: Clone;
    /// What a state carries about its history (anchor history for the tethered rover); `()` when Markovian.
    type Attachment: Clone + PartialEq;
    /// Whether attachments matter. When `false` the planner never copies attachments to new samples and never
    /// creates fresh goal states (both are pointless when every history is compatible).
    const NON_MARKOVIAN: bool = false;

    /// Dimension of the space (sets the RGG connection terms).
    fn dimension(&self) -> usize;
    /// Lebesgue measure of the sampled domain (sets the RGG connection terms; OMPL `getSpaceMeasure`).
    fn measure(&self) -> f64;
    /// Metric distance.
    fn distance(&self, a: &Self::State, b: &Self::State) -> f64;
    /// The state at fraction `t` in `[0, 1]` along the space's local path from `a` to `b`.
    fn interpolate(&self, a: &Self::State, b: &Self::State, t: f64) -> Self::State;
    /// A uniform sample of the space; `None` when the sampler failed (e.g. settling did not converge). A failed
    /// draw counts as one sampling attempt.
    fn sample_uniform<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Option<Self::State>;
    /// A uniform sample of `{x : |start-x| + |x-goal| <= max_length}` (the prolate hyperspheroid of the
    /// path-length objective, Gammell et al. IROS 2014) within the bounds. Default: unsupported.
    fn sample_informed_path_length<R: Rng + ?Sized>(
        &mut self,
        _rng: &mut R,
        _start: &Self::State,
        _goal: &Self::State,
        _max_length: f64,
    ) -> InformedSample<Self::State> {
        InformedSample::Unsupported
    }
    /// May a vertex holding `existing` be (re)connected by a motion that yields `resulting`? Rewiring to a parent
    /// with an incompatible history is forbidden (Paton et al. V-A). Default: equality.
    fn attachments_compatible(&self, resulting: &Self::Attachment, existing: &Self::Attachment) -> bool {
        resulting == existing
    }
    /// Is `state` valid when it holds `attachment`? The attachment-dependent part of state validity (the tethered
    /// rover: statically stable with the tether pulling towards the history's last anchor), checked for a new
    /// sample that copied an attachment from a neighbour (Paton et al. V-A); a sample that fails is not added.
    /// Default: valid.
    fn valid_with_attachment(&self, _state: &Self::State, _attachment: &Self::Attachment) -> bool {
        true
    }
    /// A quick prediction of the attachment a motion from `from` (holding `attachment`) to `to` would end with,
    /// without checking the motion (the tethered rover: anchor prediction along the straight line between the two
    /// tether ends). The planner uses it to find edges between tree vertices that would reach another attachment.
    /// Default: `None` (no prediction).
    fn predict_attachment(
        &self,
        _from: &Self::State,
        _attachment: &Self::Attachment,
        _to: &Self::State,
    ) -> Option<Self::Attachment> {
        None
    }
    /// A sample near the boundary of the region where a state holding `attachment` would keep it: where the
    /// history would change (the tethered rover: the edge of the tether shadow cast by terrain seen from the
    /// history's last anchor, where the tether starts to catch). The planner draws a fraction of its samples here
    /// so that the motions that change the history (wrapping the tether around an obstacle) have end states
    /// close enough to be neighbours. When no sample results, the planner draws a uniform one instead. Default:
    /// `NotFound` (no bias).
    fn sample_catch_boundary<R: Rng + ?Sized>(
        &mut self,
        _rng: &mut R,
        _attachment: &Self::Attachment,
    ) -> CatchSample<Self::State> {
        CatchSample::NotFound
    }
}

/// State validity (OMPL `StateValidityChecker`): attachment-independent checks of one state (bounds, collision,
/// settling). Attachment-dependent checks (tether stability) belong to the [`MotionValidator`], which sees the
/// history.
pub trait StateValidityChecker<S: StateSpace> {
    /// Is the state valid?
    fn is_valid(&mut self, state: &S::State) -> bool;
}

/// Outcome of a motion check.
#[derive(Debug, Clone, PartialEq)]
pub enum MotionCheck<A> {
    /// The motion is valid; the end state's attachment after the motion.
    Valid {
        /// Attachment of the motion's end state (for the tether: the anchor history after Alg. 1 along the motion).
        attachment: A,
    },
    /// The motion is invalid (collision, instability, ...).
    Invalid,
}

/// Motion validity (OMPL `MotionValidator::checkMotion`), with the parent's attachment.
pub trait MotionValidator<S: StateSpace> {
    /// Check the motion from `from` (holding `from_attachment`) to `to`, end states included.
    fn check_motion(
        &mut self,
        space: &S,
        from: &S::State,
        from_attachment: &S::Attachment,
        to: &S::State,
    ) -> MotionCheck<S::Attachment>;
}

/// The optimisation objective (OMPL `OptimizationObjective`): true motion cost and an admissible heuristic.
pub trait OptimizationObjective<S: StateSpace> {
    /// True cost of the motion `from -> to` given the parent's attachment (only called before the motion check;
    /// must not need validity).
    fn motion_cost(&self, space: &S, from: &S::State, from_attachment: &S::Attachment, to: &S::State) -> Cost;
    /// Admissible (never over-estimating) heuristic of the motion cost; also the cost-to-come and cost-to-go
    /// heuristics of BIT* (`motionCostHeuristic` from a start / to a goal).
    fn motion_cost_heuristic(&self, space: &S, from: &S::State, to: &S::State) -> Cost;
    /// A uniform sample of the informed set `{x : h(start,x) + h(x,goal) < max_cost}`; default unsupported
    /// (the planner then uses rejection sampling on the heuristic, OMPL's `RejectionInfSampler`).
    fn sample_informed<R: Rng + ?Sized>(
        &self,
        _space: &mut S,
        _rng: &mut R,
        _start: &S::State,
        _goal: &S::State,
        _max_cost: Cost,
    ) -> InformedSample<S::State> {
        InformedSample::Unsupported
    }
    /// Is this cost good enough to stop (OMPL `isSatisfied`)? Default: never, i.e. optimise until the budget ends.
    fn is_satisfied(&self, _cost: Cost) -> bool {
        false
    }
}

/// Path length: cost = heuristic = the space's distance; informed sampling through the space's direct sampler
/// (OMPL `PathLengthOptimizationObjective` + `PathLengthDirectInfSampler`).
#[derive(Debug, Clone, Copy, Default)]
pub struct PathLength {
    /// Stop as soon as a path of at most this cost is found (`f64::NEG_INFINITY` to never stop, the default).
    pub cost_threshold: Cost,
}

impl PathLength {
    /// Optimise until the budget ends.
    pub const fn new() -> Self {
        Self { cost_threshold: f64::NEG_INFINITY }
    }
}

impl<S: StateSpace> OptimizationObjective<S> for PathLength {
    fn motion_cost(&self, space: &S, from: &S::State, _: &S::Attachment, to: &S::State) -> Cost {
        space.distance(from, to)
    }
    fn motion_cost_heuristic(&self, space: &S, from: &S::State, to: &S::State) -> Cost {
        space.distance(from, to)
    }
    fn sample_informed<R: Rng + ?Sized>(
        &self,
        space: &mut S,
        rng: &mut R,
        start: &S::State,
        goal: &S::State,
        max_cost: Cost,
    ) -> InformedSample<S::State> {
        space.sample_informed_path_length(rng, start, goal, max_cost)
    }
    fn is_satisfied(&self, cost: Cost) -> bool {
        cost <= self.cost_threshold
    }
}

/// A goal region that can be sampled (OMPL `GoalSampleableRegion`).
pub trait GoalRegion<S: StateSpace> {
    /// Is the state inside the goal region?
    fn is_satisfied(&self, space: &S, state: &S::State) -> bool;
    /// A state of the goal region (the planner asks once per solve set-up).
    fn sample_goal<R: Rng + ?Sized>(&self, rng: &mut R) -> Option<S::State>;
}

/// A single goal state (OMPL `GoalState`), satisfied within `tolerance` of the space's metric.
#[derive(Debug, Clone)]
pub struct GoalState<St> {
    /// The goal.
    pub state: St,
    /// Distance within which a state counts as reaching the goal.
    pub tolerance: f64,
}

impl<S: StateSpace> GoalRegion<S> for GoalState<S::State> {
    fn is_satisfied(&self, space: &S, state: &S::State) -> bool {
        space.distance(&self.state, state) <= self.tolerance
    }
    fn sample_goal<R: Rng + ?Sized>(&self, _rng: &mut R) -> Option<S::State> {
        Some(self.state.clone())
    }
}

/// The problem (OMPL `ProblemDefinition`): start (with its attachment), goal region, objective.
#[derive(Debug, Clone)]
pub struct ProblemDefinition<S: StateSpace, G, O> {
    /// Start state.
    pub start: S::State,
    /// Attachment of the start (for the tether: the root anchor history).
    pub start_attachment: S::Attachment,
    /// Goal region.
    pub goal: G,
    /// Optimisation objective.
    pub objective: O,
}

/// The termination budget (OMPL `PlannerTerminationCondition`, made of counters instead of a clock). A limit of
/// `u32::MAX` means unlimited. `solve` stops at the first limit reached; every limit is reported.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Planner iterations (calls of `step`; OMPL's `numIterations`).
    pub iterations: u32,
    /// Batches of samples.
    pub batches: u32,
    /// Motion checks (OMPL's edge collision checks).
    pub edges_evaluated: u32,
    /// State validity checks (OMPL's state collision checks).
    pub states_checked: u32,
}

impl Budget {
    /// A budget of `n` iterations and nothing else.
    pub const fn iterations(n: u32) -> Self {
        Self { iterations: n, batches: u32::MAX, edges_evaluated: u32::MAX, states_checked: u32::MAX }
    }
    /// No limit: only convergence, a satisfied objective, a full arena or the caller's stop predicate ends it.
    pub const fn unlimited() -> Self {
        Self::iterations(u32::MAX)
    }
}

/// Which budget ran out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BudgetKind {
    /// `Budget::iterations`.
    Iterations,
    /// `Budget::batches`.
    Batches,
    /// `Budget::edges_evaluated`.
    EdgesEvaluated,
    /// `Budget::states_checked`.
    StatesChecked,
}

/// Which arena filled up.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Arena {
    /// The node arena (samples + vertices).
    Nodes,
    /// The edge queue.
    EdgeQueue,
    /// The goal-vertex list.
    Goals,
}

/// Why the input was rejected (all are caller errors; nothing was planned).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InvalidInput {
    /// The start state fails the state validity checker.
    StartInvalid,
    /// The goal region produced no state.
    GoalUnsampleable,
    /// The goal state fails the state validity checker.
    GoalInvalid,
    /// A planner parameter is out of range (the field is named).
    Parameter(&'static str),
    /// The arena cannot even hold the start and goal.
    ArenaTooSmall,
    /// The heuristic returned NaN or a negative value.
    HeuristicNotAdmissible,
}

/// What a sampling planner found (OMPL `PlannerStatus`), the shared [`Status`] with the sampling planners'
/// detail: `Exact(cost)` of the best path, `Approximate(cost_to_go)` (heuristic cost-to-go of the best path's end),
/// `NoSolution(Ended::BudgetExhausted)` (no path within the budget), `InvalidInput(InvalidInput)`.
pub type PlannerStatus = Status<Cost, Cost, Ended, InvalidInput>;

/// Why `solve` returned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Termination {
    /// A budget ran out.
    BudgetExhausted(BudgetKind),
    /// An arena filled up; the best solution so far is kept.
    ArenaFull(Arena),
    /// No better solution is possible (the best cost equals the start-goal heuristic lower bound).
    Converged,
    /// The objective is satisfied.
    ObjectiveSatisfied,
    /// The caller's stop predicate returned true (e.g. a wall-clock limit on the host).
    Stopped,
    /// The input was rejected before planning.
    InvalidInput,
}

/// Work counters, reported with every outcome (the campaign's iteration / batch / edge / state columns).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Calls of `step` (OMPL `numIterations`): one edge processed or one batch/search started.
    pub iterations: u32,
    /// Batches of samples.
    pub batches: u32,
    /// Motion checks run (OMPL edge collision checks; memo hits excluded).
    pub edges_evaluated: u32,
    /// State validity checks run (samples, start, goal).
    pub states_checked: u32,
    /// Edges popped from the queue.
    pub edges_popped: u32,
    /// Queued edges dropped without an iteration (`AbitParams::drop_dead_edges`).
    pub edges_dropped: u32,
    /// Edge evaluations answered by the memo (OMPL's white/black lists).
    pub memo_hits: u32,
    /// Valid samples added.
    pub samples_added: u32,
    /// Samples dropped because they were invalid with the attachment they copied (non-Markovian spaces).
    pub samples_invalid_with_copy: u32,
    /// Rewirings (parent replaced).
    pub rewirings: u32,
    /// Graph prunings.
    pub prunings: u32,
    /// Unconnected samples freed to make room for a batch in the node arena (`AbitStar`'s batches).
    pub samples_evicted: u32,
    /// Edges rejected because the end state's attachment was incompatible (Paton et al. V-A).
    pub incompatible_attachments: u32,
    /// Twins with undetermined history created for edges into vertices of another history.
    pub history_twins: u32,
    /// Attachment predictions asked of the space ([`StateSpace::predict_attachment`]).
    pub attachment_predictions: u32,
    /// Samples drawn near a catch boundary ([`StateSpace::sample_catch_boundary`]).
    pub catch_samples: u32,
    /// Neighbour lists truncated at `NEIGHBOUR_CAPACITY`.
    pub neighbour_lists_truncated: u32,
    /// Steps that went on drawing a batch without an iteration (`AbitParams::draws_per_step`).
    pub sampling_steps: u32,
    /// Iteration at which the first solution was found (0 = none yet).
    pub first_solution_iteration: u32,
    /// Number of solution improvements.
    pub improvements: u32,
}

/// The report of one `solve` call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SolveReport {
    /// What was found.
    pub status: PlannerStatus,
    /// Why the call returned.
    pub termination: Termination,
    /// Work done (cumulative over the planner's life).
    pub counters: Counters,
}

/// What one `step` did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepOutcome {
    /// One edge was processed (or skipped) from the queue.
    ProcessedEdge,
    /// The edge processed improved the best solution.
    ImprovedSolution,
    /// A new batch of samples was added and a new search started.
    NewBatch,
    /// The batch's final (less inflated) search started.
    FinalSearch,
    /// An arena is full: this step could not complete its work (the planner stays consistent).
    ArenaFull(Arena),
    /// The current best solution is provably optimal for the heuristic; nothing more to do.
    Converged,
}

/// A planner in OMPL's sense: `step` is one iteration; `solve` runs steps within a budget.
pub trait Planner {
    /// Run one iteration.
    fn step(&mut self) -> StepOutcome;
    /// Work done so far.
    fn counters(&self) -> Counters;
    /// The current status (best solution so far).
    fn status(&self) -> PlannerStatus;
    /// Run `step` until the budget, convergence, a full arena or `stop` ends it. `stop` is asked before every
    /// iteration (the host passes a wall-clock test; the board passes `|_| false`).
    fn solve_until<F: FnMut(&Counters) -> bool>(&mut self, budget: &Budget, mut stop: F) -> SolveReport {
        // Bounded: every iteration increments `counters().iterations`, which the budget caps at u32::MAX; a step that
        // is not an iteration (ABIT* drawing a batch over several steps) uses up a bounded number of draws.
        loop {
            let c = self.counters();
            let exhausted = if c.iterations >= budget.iterations {
                Some(BudgetKind::Iterations)
            } else if c.batches >= budget.batches {
                Some(BudgetKind::Batches)
            } else if c.edges_evaluated >= budget.edges_evaluated {
                Some(BudgetKind::EdgesEvaluated)
            } else if c.states_checked >= budget.states_checked {
                Some(BudgetKind::StatesChecked)
            } else {
                None
            };
            let termination = if let Some(kind) = exhausted {
                Some(Termination::BudgetExhausted(kind))
            } else if stop(&c) {
                Some(Termination::Stopped)
            } else if let Status::InvalidInput(_) = self.status() {
                Some(Termination::InvalidInput)
            } else {
                match self.step() {
                    StepOutcome::ArenaFull(a) => Some(Termination::ArenaFull(a)),
                    StepOutcome::Converged => Some(Termination::Converged),
                    StepOutcome::ImprovedSolution if self.objective_satisfied() => {
                        Some(Termination::ObjectiveSatisfied)
                    }
                    _ => None,
                }
            };
            if let Some(termination) = termination {
                return SolveReport { status: self.status(), termination, counters: self.counters() };
            }
        }
    }
    /// Run `step` until the budget, convergence or a full arena ends it.
    fn solve(&mut self, budget: &Budget) -> SolveReport {
        self.solve_until(budget, |_| false)
    }
    /// Is the best solution good enough for the objective?
    fn objective_satisfied(&self) -> bool;
}
