//! ABIT* — Advanced Batch Informed Trees (Strub & Gammell, ICRA 2020), as used by Paton et al. (IROS 2020)
//! section V, with the non-Markovian extensions of section V-A (Fig. 7). Heap-free, every loop bounded.
//!
//! ## The algorithm (follows OMPL 1.5.2's `BITstar`/`ABITstar`)
//! - **Implicit RGG.** Samples arrive in batches of `samples_per_batch` and form, with the start and goals, an
//!   edge-implicit random geometric graph: k-nearest with `k = ceil(rewire_factor (e + e/d) ln q)` (OMPL's default,
//!   "kABITstar"; the node itself counts among the k, as in OMPL) or r-disc with
//!   `r = rewire_factor (2 (1 + 1/d) mu / zeta_d)^(1/d) (ln q / q)^(1/d)`. `q` = the number of states before the
//!   batch, not counting the vertices the preceding pruning disconnected and kept as samples (OMPL adds those
//!   "recycled" samples back after computing the terms), plus the batch size on the first batch.
//! - **Informed sampling.** Once a solution of cost `c_best` exists, new samples are drawn from the informed set
//!   `{x : h(start, x) + h(x, goal) < c_best}` — directly (the prolate hyperspheroid in R^n, through
//!   [`OptimizationObjective::sample_informed`]) or, for general spaces, by rejection on the heuristic.
//! - **Edge queue** ordered lexicographically by `[g(u) + c^(u,v) + eps h^(v), g(u) + c^(u,v), g(u)]` with the
//!   inflation factor `eps`; ties by node indices (deterministic). The very first queue holds only the start's
//!   edges to its k = |starts| + |goals| nearest states, i.e. the direct start-goal edge, so iteration 1
//!   evaluates it (Paton et al. test 1: solution on the first iteration).
//! - **Inflation and truncation.** Every batch starts a search with `eps = initial_inflation_factor` (1e6).
//!   A search ends when the queue is empty or its front edge cannot improve the solution even after dividing by
//!   the truncation factor `1 + truncation_scaling_parameter / q`, with OMPL's `q = numSamples() + numVertices()`:
//!   the live states (samples and vertices, after the batch is drawn) plus the tree vertices. With a solution,
//!   the batch then gets a final search with `eps = 1 + inflation_scaling_parameter / q` (same `q`, counted
//!   then) that re-keys the queue and re-expands the inconsistent vertices: as in OMPL's `addEdge`, a vertex
//!   improved after its expansion in this search (its descendants only get their queued edges re-keyed).
//!   Then the next batch starts.
//! - **Lazy edge evaluation.** An edge is checked only when popped and only if it can still improve the tree
//!   and the solution with its true cost; results are memoised (OMPL's black/white lists) in a fixed hash table.
//!   As in OMPL, where the lists live in the vertex, a memo entry survives the pruning of its states (in
//!   Markovian spaces), so a known-invalid edge from or to a recycled sample is never queued again.
//! - **Pruning** before a batch when the states that cannot improve the solution (vertices included) are at
//!   least `prune_fraction` of OMPL's `numSamples() + numVertices()`:
//!   samples with `h(start,x) + h(x,goal) >= c_best` are dropped, vertices with `g(x) + h(x,goal) > c_best` are
//!   disconnected (and kept as samples if they can still help).
//! - **Anytime.** The best solution is kept at all times; [`AbitStar::write_path`] extracts it.
//!
//! One **iteration** is one call of [`Planner::step`]: it processes one edge of the queue or starts a
//! batch / final search — OMPL's `numIterations`.
//!
//! ## Non-Markovian attachments (Paton et al. V-A)
//! - The attachment of a vertex is set when it is first connected (from the motion validator's result).
//! - A fraction `attachment_copy_fraction` of new samples gets a predetermined attachment copied from a
//!   neighbour: one of the distinct attachments (compatibility classes, [`StateSpace::attachments_compatible`])
//!   among its k nearest tree vertices, chosen uniformly (so a rare history, e.g. the one anchored on the column of
//!   Fig. 7d, is copied as often as the common one). Such a sample is checked with its attachment at once
//!   ([`StateSpace::valid_with_attachment`]: on the ledge, a slope sample that copied the root-only history is
//!   unstable) and dropped if invalid; a kept one only connects through a motion yielding a compatible attachment.
//! - No rewiring to a parent whose motion gives an incompatible attachment
//!   ([`StateSpace::attachments_compatible`]).
//! - After each improvement a fresh goal state with undetermined attachment is added (up to
//!   `config::abit::GOAL_CAPACITY` goals), so the next better path can connect to a goal.
//!
//! - **History twins** (this project's addition, in the spirit of Fig. 7d: "multiple anchor histories can expand
//!   into a region"): a cost-to-come comparison between vertices of incompatible histories is meaningless, yet
//!   BIT*'s "can this edge improve the child?" test lets the cheaper history block the other everywhere it
//!   arrived first (Fig. 7c). So an edge from `u` into a tree vertex `w` whose attachment is incompatible with
//!   `u`'s goes to a twin of `w`'s state with undetermined attachment (created on demand, at most
//!   `config::abit::MAX_HISTORY_TWINS` copies per state). On the corner-column toy problem of the tests this
//!   takes the success rate from 0/20 (copying, fresh goals and twins off) to 20/20 in 6000 iterations.
//!   A motion whose true attachment turns out incompatible with its child's also connects a twin (compatible with
//!   the motion's attachment) instead of being discarded. The start's pose can have twins too (the tree's root
//!   stays the start itself): on the ledge, coming back to the start's pose with the tether around the pole is
//!   the natural place to begin the descent.
//! - **Revealing edges** (this project's addition, `reveal_attachments`): BIT* does not queue an edge between two
//!   tree vertices that cannot lower the child's cost-to-come, and two vertices of the same history look
//!   interchangeable. But the motion between them may give the child another history: on the ledge of Paton et
//!   al. VI-A every vertex of the ledge top is first reached with the root-only history, and the edges that would
//!   wrap the tether around the pole (between two vertices on either side of its shadow) are never tried. So when
//!   such an edge fails the cost test, the planner asks the space for a cheap prediction of the motion's
//!   attachment ([`StateSpace::predict_attachment`]; the tethered rover: Alg. 1 along the straight line between
//!   the two tether ends, no settling) and queues the edge if the prediction is incompatible with the child's
//!   history; it then connects a twin of the child.
//! - **Goal edges** (this project's addition, `goal_edges`): every vertex also queues its edges to the goals,
//!   wherever they are. In a non-Markovian space the validity of the long direct motion to the goal depends on the
//!   history, which the tree only finds far from the start: on the ledge, one straight drive from a vertex in
//!   front of the pole, with the tether wrapped around it, reaches the goal 7 m away, while the k nearest states of
//!   that vertex lie within ~3 m. One iteration per vertex, when the edge reaches the front of the queue. Where no
//!   goal motion can succeed before a detour, that iteration is wasted: on the column toy of the tests (40 seeds,
//!   1000 iterations, catch-boundary samples off) goal edges lower the success from 30 to 16 (at 2000 iterations,
//!   36 to 34).
//! - **Catch-boundary samples** (this project's addition, `catch_sample_fraction`): a fraction of the sample draws
//!   is taken where a history the tree knows would change ([`StateSpace::sample_catch_boundary`]; the tethered
//!   rover: along the edge of the tether shadow that terrain casts as seen from the history's last anchor). Each
//!   such draw picks one of the tree's distinct histories uniformly (at the first batch, the start's). After a
//!   solution they are kept only inside the informed set. On the ledge the pole's shadow is a 0.6 m strip behind
//!   the pole: uniform samples straddle it so rarely that in 5 trials of 100 no edge across it was ever in a
//!   k-nearest list (seed 9: the vertices behind the pole stood at |y| > 1.1 m, every pair across more than
//!   the 2.99 m of the 21 nearest apart), and the tether never wrapped the pole within the budget.
//! - Measured on test 3 of Table I (`tetherbot campaign ledge_test3 --trials 30`, planning on the 0.10 m map):
//!   4/30 found with neither goal nor revealing edges, 5/30 with revealing edges only, 8/30 with goal edges only,
//!   21/30 with both (78/100); with twins of the start's pose as well, 94/100; with catch-boundary samples as
//!   well (100 trials), see `host-sim/doc/campaign.md`.
//!
//! These are active only when [`StateSpace::NON_MARKOVIAN`] is true.
//!
//! ## Parameters ([`AbitParams::ompl_defaults`], from `config::abit`)
//! | parameter | default |
//! |---|---|
//! | `samples_per_batch` | 100 |
//! | `rewire_factor` | 1.1 |
//! | `connection` | k-nearest |
//! | `initial_inflation_factor` | 1e6 |
//! | `inflation_scaling_parameter` | 10 |
//! | `truncation_scaling_parameter` | 5 |
//! | `pruning` / `prune_fraction` | on / 0.05 |
//! | `attachment_copy_fraction` | 0.25 |
//! | `fresh_goal_on_improvement` | true |
//! | `history_twins` | true |
//! | `goal_edges` | true |
//! | `reveal_attachments` | true |
//! | `catch_sample_fraction` | 0.1 (non-Markovian only) |
//! | `track_approximate` | false (as OMPL) |
//! | `sample_attempts_per_sample` | 2 |
//! | `informed_rejection_attempts` | 100 |
//! | `drop_dead_edges` | false (OMPL: a dead edge costs an iteration when it reaches the front) |
//!
//! ## Memory
//! Everything lives in an [`AbitArena`] lent by the caller: `NV` nodes (start, goals, samples, vertices),
//! `NQ` queued edges, `NM` memo entries. A full node arena or edge queue ends `solve` with
//! `Termination::ArenaFull` and keeps the best solution; a full memo only costs repeated edge checks.

use heapless::Vec;
use rand_core::Rng;

use crate::config::abit as cfg;

use super::space::{
    uniform01, Arena, CatchSample, Cost, Counters, GoalRegion, InformedSample, InvalidInput, MotionCheck, MotionValidator,
    OptimizationObjective, Planner, PlannerStatus, ProblemDefinition, StateSpace, StateValidityChecker,
    StepOutcome,
};
use crate::geom::unit_ball_measure;

/// "No node".
const NONE: u32 = u32::MAX;
/// Probes per memo lookup (open addressing, linear probing).
const MEMO_PROBES: usize = 8;

/// How the implicit RGG connects states.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Connection {
    /// k-nearest (OMPL's default for BIT*/ABIT*).
    KNearest,
    /// r-disc.
    RDisc,
}

/// Planner parameters. See the module docs for the defaults and their sources.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AbitParams {
    /// Samples per batch.
    pub samples_per_batch: u32,
    /// RGG rewire factor.
    pub rewire_factor: f64,
    /// k-nearest or r-disc.
    pub connection: Connection,
    /// Inflation of the first search of every batch.
    pub initial_inflation_factor: f64,
    /// Final search inflation is `1 + inflation_scaling_parameter / q`.
    pub inflation_scaling_parameter: f64,
    /// Truncation factor is `1 + truncation_scaling_parameter / q`.
    pub truncation_scaling_parameter: f64,
    /// Prune the graph before batches.
    pub pruning: bool,
    /// Prune only if at least this fraction of states can be pruned.
    pub prune_fraction: f64,
    /// Fraction of new samples that copy the nearest tree vertex's attachment (non-Markovian spaces only).
    pub attachment_copy_fraction: f64,
    /// Add a goal with undetermined attachment after each improvement (non-Markovian spaces only).
    pub fresh_goal_on_improvement: bool,
    /// When a vertex's outgoing edge reaches a tree vertex of an incompatible history, connect it to a twin of
    /// that state with undetermined history instead (up to `config::abit::MAX_HISTORY_TWINS` per state;
    /// non-Markovian spaces only). See the module docs.
    pub history_twins: bool,
    /// Report the vertex closest to the goal as an approximate solution when no exact one exists.
    pub track_approximate: bool,
    /// Sampling attempts per requested sample.
    pub sample_attempts_per_sample: u32,
    /// Uniform draws per informed sample when the objective has no direct informed sampler.
    pub informed_rejection_attempts: u32,
    /// BIT*'s edge-queue pruning as the paper states it (Gammell et al. 2020: after a vertex improves, the queued
    /// edges into it that can no longer improve it leave the queue), instead of OMPL's lazy discard at the front
    /// of the queue, which costs an iteration per edge. Same search, fewer iterations; off by default, because
    /// OMPL's iteration count (and so Paton et al.'s Table I) includes those discards. An experiment knob.
    pub drop_dead_edges: bool,
    /// Every vertex also queues its edges to the goals, whatever their distance (non-Markovian spaces only; see
    /// the module docs).
    pub goal_edges: bool,
    /// Queue an edge between two tree vertices that cannot improve the child when the space predicts that the
    /// motion would give the child another attachment; it connects a history twin (non-Markovian spaces with
    /// `history_twins` only; see the module docs).
    pub reveal_attachments: bool,
    /// Fraction of sample draws taken near where a known attachment would change
    /// ([`StateSpace::sample_catch_boundary`]; non-Markovian spaces only; see the module docs).
    pub catch_sample_fraction: f64,
}

impl AbitParams {
    /// OMPL 1.5.2's ABIT* defaults (plus the non-Markovian defaults of `config::abit`).
    pub const fn ompl_defaults() -> Self {
        Self {
            samples_per_batch: cfg::SAMPLES_PER_BATCH,
            rewire_factor: cfg::REWIRE_FACTOR,
            connection: Connection::KNearest,
            initial_inflation_factor: cfg::INITIAL_INFLATION_FACTOR,
            inflation_scaling_parameter: cfg::INFLATION_SCALING_PARAMETER,
            truncation_scaling_parameter: cfg::TRUNCATION_SCALING_PARAMETER,
            pruning: true,
            prune_fraction: cfg::PRUNE_FRACTION,
            attachment_copy_fraction: cfg::ATTACHMENT_COPY_FRACTION,
            fresh_goal_on_improvement: true,
            history_twins: true,
            track_approximate: false,
            sample_attempts_per_sample: cfg::SAMPLE_ATTEMPTS_PER_SAMPLE,
            informed_rejection_attempts: cfg::INFORMED_REJECTION_ATTEMPTS,
            drop_dead_edges: false,
            goal_edges: true,
            reveal_attachments: true,
            catch_sample_fraction: cfg::CATCH_SAMPLE_FRACTION,
        }
    }

    fn check(&self) -> Result<(), InvalidInput> {
        let p = InvalidInput::Parameter;
        if self.samples_per_batch == 0 {
            return Err(p("samples_per_batch must be at least 1"));
        }
        if !(self.rewire_factor > 0.0 && self.rewire_factor.is_finite()) {
            return Err(p("rewire_factor must be positive and finite"));
        }
        if !(self.initial_inflation_factor >= 1.0 && self.initial_inflation_factor.is_finite()) {
            return Err(p("initial_inflation_factor must be >= 1 and finite"));
        }
        if !(self.inflation_scaling_parameter >= 0.0 && self.inflation_scaling_parameter.is_finite()) {
            return Err(p("inflation_scaling_parameter must be >= 0 and finite"));
        }
        if !(self.truncation_scaling_parameter >= 0.0 && self.truncation_scaling_parameter.is_finite()) {
            return Err(p("truncation_scaling_parameter must be >= 0 and finite"));
        }
        if !(0.0..=1.0).contains(&self.prune_fraction) {
            return Err(p("prune_fraction must be in [0, 1]"));
        }
        if !(0.0..=1.0).contains(&self.attachment_copy_fraction) {
            return Err(p("attachment_copy_fraction must be in [0, 1]"));
        }
        if !(0.0..=1.0).contains(&self.catch_sample_fraction) {
            return Err(p("catch_sample_fraction must be in [0, 1]"));
        }
        if self.sample_attempts_per_sample == 0 || self.informed_rejection_attempts == 0 {
            return Err(p("sampling attempts must be at least 1"));
        }
        Ok(())
    }
}

impl Default for AbitParams {
    fn default() -> Self {
        Self::ompl_defaults()
    }
}

const F_IN_TREE: u8 = 1;
const F_FREE: u8 = 2;
const F_START: u8 = 4;
const F_GOAL: u8 = 8;
const F_INCONSISTENT: u8 = 16;
/// A history twin (see `twin_target`): reached through the chain of its state's original node, never listed as a
/// neighbour itself (twins at one state would otherwise crowd the k nearest out of the neighbour lists).
const F_TWIN: u8 = 32;

/// A state of the implicit graph: a sample, or a vertex of the tree when `in_tree`.
#[derive(Debug, Clone)]
pub struct Node<St, A> {
    /// The state.
    pub state: St,
    /// Its attachment: `None` while undetermined (unconnected sample that did not copy one).
    pub attachment: Option<A>,
    parent: u32,
    first_child: u32,
    next_sibling: u32,
    edge_cost: Cost,
    cost: Cost,
    h_come: Cost,
    h_go: Cost,
    generation: u32,
    expanded_search: u32,
    first_out: u32,
    twin: u32,
    twin_generation: u32,
    flags: u8,
}

impl<St, A> Node<St, A> {
    fn has(&self, f: u8) -> bool {
        self.flags & f != 0
    }
    /// Is this node a vertex of the tree?
    pub fn in_tree(&self) -> bool {
        self.has(F_IN_TREE)
    }
    /// Parent index in the arena, if connected and not the root.
    pub fn parent(&self) -> Option<u32> {
        (self.parent != NONE).then_some(self.parent)
    }
    /// Cost-to-come through the tree (`INFINITY` if not connected).
    pub fn cost(&self) -> Cost {
        self.cost
    }
}

#[derive(Debug, Clone, Copy)]
struct QueueEdge {
    key: [f64; 3],
    c_hat: Cost,
    parent: u32,
    child: u32,
    parent_generation: u32,
    child_generation: u32,
    heap_pos: u32,
    next_out: u32,
    prev_out: u32,
    /// An edge into a tree vertex that cannot improve it, queued because the space predicts that the motion would
    /// give the child another attachment: it goes to a history twin (see `enqueue_conditionally`).
    reveals: bool,
}

impl QueueEdge {
    fn before(&self, other: &Self) -> bool {
        for (a, b) in self.key.iter().zip(other.key.iter()) {
            if a < b {
                return true;
            }
            if a > b {
                return false;
            }
        }
        (self.parent, self.child) < (other.parent, other.child)
    }
}

#[derive(Debug, Clone)]
struct MemoEntry<A> {
    parent: u32,
    parent_generation: u32,
    child: u32,
    child_generation: u32,
    result: Option<A>,
}

/// The planner's storage, owned by the caller (a `static` on the board, a `Box` on the host) and lent to
/// [`AbitStar::new`]. Capacities: `NV` nodes, `NQ` queued edges, `NM` memo entries (see `config::abit`).
pub struct AbitArena<St, A, const NV: usize, const NQ: usize, const NM: usize> {
    nodes: Vec<Node<St, A>, NV>,
    /// Queued edges (a slab with a free list; slots are stable while queued).
    edges: Vec<QueueEdge, NQ>,
    /// The binary heap of slab indices, ordered by the edges' keys.
    heap: Vec<u32, NQ>,
    memo: Vec<Option<MemoEntry<A>>, NM>,
}

impl<St, A, const NV: usize, const NQ: usize, const NM: usize> AbitArena<St, A, NV, NQ, NM> {
    /// An empty arena (const, so it can be a `static`).
    pub const fn new() -> Self {
        Self { nodes: Vec::new(), edges: Vec::new(), heap: Vec::new(), memo: Vec::new() }
    }
    /// Nodes currently used (including freed slots awaiting reuse).
    pub fn nodes_used(&self) -> usize {
        self.nodes.len()
    }
    /// Edges currently queued.
    pub fn queue_len(&self) -> usize {
        self.heap.len()
    }
}

/// An arena with the default capacities of `config::abit` (what the board uses).
pub type DefaultAbitArena<St, A> =
    AbitArena<St, A, { cfg::NODE_CAPACITY }, { cfg::EDGE_QUEUE_CAPACITY }, { cfg::EDGE_MEMO_CAPACITY }>;

impl<St, A, const NV: usize, const NQ: usize, const NM: usize> Default for AbitArena<St, A, NV, NQ, NM> {
    fn default() -> Self {
        Self::new()
    }
}

/// High-water marks of the arenas (for sizing the board's arenas).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ArenaUse {
    /// Most node slots used.
    pub nodes: usize,
    /// Longest edge queue.
    pub queue: usize,
    /// Memo slots filled.
    pub memo: usize,
}

/// Why a path could not be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathError {
    /// No exact (or, if tracked, approximate) solution yet.
    NoSolution,
    /// The output buffer is too small for the path; the needed length is given.
    TooLong(usize),
}

/// The search state of a suspended [`AbitStar`]: everything the planner keeps outside its arena (inflation and
/// truncation, the goals, the best solution, the free lists, the counters), as plain data, so a caller that cannot
/// keep the planner's borrows alive between calls (the on-board navigator, between executive steps) can hold it
/// and continue the search later with [`AbitStar::resume`]. The graph, the edge queue and the memo stay in the
/// arena.
#[derive(Debug, Clone)]
pub struct AbitSuspended<St> {
    params: AbitParams,
    goal_state: Option<St>,
    goals: Vec<u32, { cfg::GOAL_CAPACITY }>,
    free_head: u32,
    free_edge: u32,
    live_nodes: usize,
    best_goal: u32,
    best_cost: Cost,
    min_cost: Cost,
    inflation: f64,
    truncation: f64,
    search_id: u32,
    search_done: bool,
    final_search: bool,
    k: usize,
    r: f64,
    recycled: usize,
    approx_vertex: u32,
    approx_h: Cost,
    pending_full: Option<Arena>,
    counters: Counters,
    invalid: Option<InvalidInput>,
    high_water: ArenaUse,
}

impl<St> AbitSuspended<St> {
    /// The work counters when the search was suspended.
    pub fn counters(&self) -> Counters {
        self.counters
    }
}

/// ABIT* over a [`StateSpace`] with attachments. See the module docs.
pub struct AbitStar<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize>
where
    S: StateSpace,
{
    arena: &'a mut AbitArena<S::State, S::Attachment, NV, NQ, NM>,
    space: &'a mut S,
    validity: &'a mut V,
    motion: &'a mut M,
    pdef: &'a ProblemDefinition<S, G, O>,
    rng: &'a mut R,
    /// The search state (everything but the borrows): what [`Self::suspend`] hands out.
    st: AbitSuspended<S::State>,
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    /// Set up the planner on a problem. The arena is cleared. Invalid input (start or goal invalid, bad
    /// parameters, an arena too small) is reported by [`Planner::status`] as `InvalidInput`; `solve` then
    /// returns at once.
    pub fn new(
        arena: &'a mut AbitArena<S::State, S::Attachment, NV, NQ, NM>,
        space: &'a mut S,
        validity: &'a mut V,
        motion: &'a mut M,
        pdef: &'a ProblemDefinition<S, G, O>,
        rng: &'a mut R,
        params: AbitParams,
    ) -> Self {
        arena.nodes.clear();
        arena.edges.clear();
        arena.heap.clear();
        arena.memo.clear();
        // Bounded by NM.
        for _ in 0..NM {
            if arena.memo.push(None).is_err() {
                break;
            }
        }
        let mut planner = Self {
            arena,
            space,
            validity,
            motion,
            pdef,
            rng,
            st: AbitSuspended {
                params,
                goal_state: None,
                goals: Vec::new(),
                free_head: NONE,
                free_edge: NONE,
                live_nodes: 0,
                best_goal: NONE,
                best_cost: f64::INFINITY,
                min_cost: f64::INFINITY,
                inflation: params.initial_inflation_factor,
                truncation: 1.0,
                search_id: 1,
                search_done: false,
                final_search: false,
                k: 0,
                r: f64::INFINITY,
                recycled: 0,
                approx_vertex: NONE,
                approx_h: f64::INFINITY,
                pending_full: None,
                counters: Counters::default(),
                invalid: None,
                high_water: ArenaUse::default(),
            },
        };
        if let Err(e) = planner.set_up() {
            planner.st.invalid = Some(e);
        }
        planner
    }

    /// Release the borrows and keep the search: the graph, queue and memo stay in the arena, the rest is
    /// returned. Resume it with [`Self::resume`]; a new problem starts with [`Self::new`] instead.
    pub fn suspend(self) -> AbitSuspended<S::State> {
        self.st
    }

    /// Continue a suspended search where [`Self::suspend`] left it. The caller's contract: the arena is the one
    /// the search was suspended from, untouched since; the problem, the space (its map) and the validators answer
    /// as they did; `rng` continues the generator's sequence. Then the search goes on exactly as if it had never
    /// been interrupted (`a_suspended_and_resumed_search_is_the_uninterrupted_search`, and `nav`'s tests).
    pub fn resume(
        arena: &'a mut AbitArena<S::State, S::Attachment, NV, NQ, NM>,
        space: &'a mut S,
        validity: &'a mut V,
        motion: &'a mut M,
        pdef: &'a ProblemDefinition<S, G, O>,
        rng: &'a mut R,
        suspended: AbitSuspended<S::State>,
    ) -> Self {
        Self { arena, space, validity, motion, pdef, rng, st: suspended }
    }

    fn set_up(&mut self) -> Result<(), InvalidInput> {
        self.st.params.check()?;
        if NV < 3 || NQ < 1 {
            return Err(InvalidInput::ArenaTooSmall);
        }
        let pdef = self.pdef;
        self.st.counters.states_checked += 1;
        if !self.validity.is_valid(&pdef.start) {
            return Err(InvalidInput::StartInvalid);
        }
        let goal = pdef.goal.sample_goal(self.rng).ok_or(InvalidInput::GoalUnsampleable)?;
        self.st.counters.states_checked += 1;
        if !self.validity.is_valid(&goal) {
            return Err(InvalidInput::GoalInvalid);
        }
        let h = pdef.objective.motion_cost_heuristic(self.space, &pdef.start, &goal);
        if h.is_nan() || h < 0.0 {
            return Err(InvalidInput::HeuristicNotAdmissible);
        }
        self.st.min_cost = h;
        self.st.goal_state = Some(goal.clone());
        // Start: the root, a vertex with the start attachment.
        let start = self
            .alloc(pdef.start.clone(), Some(pdef.start_attachment.clone()), F_START | F_IN_TREE)
            .ok_or(InvalidInput::ArenaTooSmall)?;
        if let Some(n) = self.arena.nodes.get_mut(start as usize) {
            n.cost = 0.0;
        }
        self.add_goal_vertex(goal).ok_or(InvalidInput::ArenaTooSmall)?;
        // OMPL: before the first batch, k = |starts| + |goals| and r = infinity, so the first queue holds the
        // start-goal edge only.
        self.st.k = 1 + self.st.goals.len();
        self.st.r = f64::INFINITY;
        self.insert_outgoing_edges(start, false);
        Ok(())
    }

    // ---------------------------------------------------------------- arena helpers

    /// The node in arena slot `i` (the index [`Node::parent`] returns), free slots included; `None` past the end.
    pub fn node(&self, i: u32) -> Option<&Node<S::State, S::Attachment>> {
        self.arena.nodes.get(i as usize)
    }

    fn node_mut(&mut self, i: u32) -> Option<&mut Node<S::State, S::Attachment>> {
        self.arena.nodes.get_mut(i as usize)
    }

    fn g(&self, i: u32) -> Cost {
        self.node(i).map_or(f64::INFINITY, |n| n.cost)
    }

    fn heuristics(&self, state: &S::State) -> (Cost, Cost) {
        let obj = &self.pdef.objective;
        let h_come = obj.motion_cost_heuristic(self.space, &self.pdef.start, state);
        let h_go = self.st.goal_state.as_ref().map_or(f64::INFINITY, |g| obj.motion_cost_heuristic(self.space, state, g));
        (h_come, h_go)
    }

    /// Put a state in a free slot (reused first). `None` when the arena is full.
    fn alloc(&mut self, state: S::State, attachment: Option<S::Attachment>, flags: u8) -> Option<u32> {
        let (h_come, h_go) = self.heuristics(&state);
        let fresh = |generation: u32| Node {
            state,
            attachment,
            parent: NONE,
            first_child: NONE,
            next_sibling: NONE,
            edge_cost: 0.0,
            cost: f64::INFINITY,
            h_come,
            h_go,
            generation,
            expanded_search: 0,
            first_out: NONE,
            twin: NONE,
            twin_generation: 0,
            flags,
        };
        let index = if self.st.free_head != NONE {
            let i = self.st.free_head;
            let slot = self.arena.nodes.get_mut(i as usize)?;
            self.st.free_head = slot.next_sibling;
            let generation = slot.generation.wrapping_add(1);
            *slot = fresh(generation);
            i
        } else {
            let i = self.arena.nodes.len() as u32;
            self.arena.nodes.push(fresh(0)).ok()?;
            i
        };
        self.st.live_nodes += 1;
        self.st.high_water.nodes = self.st.high_water.nodes.max(self.st.live_nodes);
        Some(index)
    }

    fn free(&mut self, i: u32) {
        let head = self.st.free_head;
        if let Some(n) = self.node_mut(i) {
            n.flags = F_FREE;
            n.generation = n.generation.wrapping_add(1);
            n.parent = NONE;
            n.first_child = NONE;
            n.next_sibling = head;
            n.cost = f64::INFINITY;
            n.attachment = None;
            self.st.free_head = i;
            self.st.live_nodes = self.st.live_nodes.saturating_sub(1);
        }
    }

    fn add_goal_vertex(&mut self, goal: S::State) -> Option<u32> {
        if self.st.goals.is_full() {
            return None;
        }
        let i = self.alloc(goal, None, F_GOAL)?;
        // Cannot fail: checked not full above.
        let _ = self.st.goals.push(i);
        Some(i)
    }

    // ---------------------------------------------------------------- edge queue
    //
    // An indexed binary heap over a slab of edges (OMPL's `BinaryHeap` with element handles): every queued edge
    // knows its heap position and sits in its parent's list of queued outgoing edges, so the keys of a vertex's
    // edges are updated as soon as its cost-to-come changes (OMPL's `Vertex::updateCostAndDepth`), and an edge
    // already queued is updated instead of duplicated (OMPL's `enqueueEdge`).

    fn edge(&self, slot: u32) -> Option<&QueueEdge> {
        self.arena.edges.get(slot as usize)
    }

    fn heap_before(&self, a: usize, b: usize) -> bool {
        let (Some(&x), Some(&y)) = (self.arena.heap.get(a), self.arena.heap.get(b)) else {
            return false;
        };
        match (self.edge(x), self.edge(y)) {
            (Some(x), Some(y)) => x.before(y),
            _ => false,
        }
    }

    fn heap_swap(&mut self, a: usize, b: usize) {
        let len = self.arena.heap.len();
        if a >= len || b >= len {
            return;
        }
        self.arena.heap.swap(a, b);
        for i in [a, b] {
            if let Some(&slot) = self.arena.heap.get(i) {
                if let Some(e) = self.arena.edges.get_mut(slot as usize) {
                    e.heap_pos = i as u32;
                }
            }
        }
    }

    fn sift_up(&mut self, mut i: usize) -> usize {
        // Bounded: i halves every round.
        while i > 0 {
            let p = (i - 1) / 2;
            if self.heap_before(i, p) {
                self.heap_swap(i, p);
                i = p;
            } else {
                break;
            }
        }
        i
    }

    fn sift_down(&mut self, mut i: usize) {
        let len = self.arena.heap.len();
        // Bounded: i at least doubles every round.
        loop {
            let l = 2 * i + 1;
            if l >= len {
                break;
            }
            let r = l + 1;
            let c = if r < len && self.heap_before(r, l) { r } else { l };
            if self.heap_before(c, i) {
                self.heap_swap(c, i);
                i = c;
            } else {
                break;
            }
        }
    }

    fn heap_fix(&mut self, pos: usize) {
        let up = self.sift_up(pos);
        if up == pos {
            self.sift_down(pos);
        }
    }

    /// Queue a new edge (the caller checked it is not queued yet).
    fn queue_insert(&mut self, mut e: QueueEdge) {
        let pos = self.arena.heap.len();
        e.heap_pos = pos as u32;
        e.prev_out = NONE;
        e.next_out = self.node(e.parent).map_or(NONE, |n| n.first_out);
        let slot = if self.st.free_edge != NONE {
            let slot = self.st.free_edge;
            let Some(entry) = self.arena.edges.get_mut(slot as usize) else { return };
            self.st.free_edge = entry.next_out;
            *entry = e;
            slot
        } else {
            let slot = self.arena.edges.len() as u32;
            if self.arena.edges.push(e).is_err() {
                self.st.pending_full = Some(Arena::EdgeQueue);
                return;
            }
            slot
        };
        if self.arena.heap.push(slot).is_err() {
            // Cannot happen (heap and slab have the same capacity); keep the slab consistent anyway.
            self.st.pending_full = Some(Arena::EdgeQueue);
            self.release_edge(slot);
            return;
        }
        if let Some(next) = self.arena.edges.get_mut(e.next_out as usize) {
            next.prev_out = slot;
        }
        if let Some(p) = self.node_mut(e.parent) {
            p.first_out = slot;
        }
        self.st.high_water.queue = self.st.high_water.queue.max(self.arena.heap.len());
        self.sift_up(pos);
    }

    /// Unlink a slab slot from its parent's list and put it on the free list.
    fn release_edge(&mut self, slot: u32) {
        let Some(e) = self.edge(slot).copied() else { return };
        if e.prev_out == NONE {
            if let Some(p) = self.node_mut(e.parent) {
                if p.first_out == slot {
                    p.first_out = e.next_out;
                }
            }
        } else if let Some(prev) = self.arena.edges.get_mut(e.prev_out as usize) {
            prev.next_out = e.next_out;
        }
        if let Some(next) = self.arena.edges.get_mut(e.next_out as usize) {
            next.prev_out = e.prev_out;
        }
        let free = self.st.free_edge;
        if let Some(entry) = self.arena.edges.get_mut(slot as usize) {
            entry.next_out = free;
            entry.prev_out = NONE;
            entry.heap_pos = NONE;
        }
        self.st.free_edge = slot;
    }

    fn heap_pop(&mut self) -> Option<QueueEdge> {
        let last = self.arena.heap.len().checked_sub(1)?;
        self.heap_swap(0, last);
        let slot = self.arena.heap.pop()?;
        self.sift_down(0);
        let e = self.edge(slot).copied();
        self.release_edge(slot);
        e
    }

    fn queue_clear(&mut self) {
        self.arena.heap.clear();
        self.arena.edges.clear();
        self.st.free_edge = NONE;
        for n in self.arena.nodes.iter_mut() {
            n.first_out = NONE;
        }
    }

    /// Re-key every queued edge (new inflation factor) and restore the heap.
    fn queue_rebuild(&mut self) {
        let len = self.arena.heap.len();
        for i in 0..len {
            let Some(&slot) = self.arena.heap.get(i) else { continue };
            let Some(e) = self.edge(slot).copied() else { continue };
            let key = self.sort_key(e.parent, e.child, e.c_hat);
            if let Some(entry) = self.arena.edges.get_mut(slot as usize) {
                entry.key = key;
            }
        }
        for i in (0..len / 2).rev() {
            self.sift_down(i);
        }
    }

    /// Re-key the queued outgoing edges of `v` after its cost-to-come changed. Bounded by the slab size.
    fn update_out_edges(&mut self, v: u32) {
        let mut slot = self.node(v).map_or(NONE, |n| n.first_out);
        for _ in 0..NQ {
            if slot == NONE {
                break;
            }
            let Some(e) = self.edge(slot).copied() else { break };
            let key = self.sort_key(e.parent, e.child, e.c_hat);
            if let Some(entry) = self.arena.edges.get_mut(slot as usize) {
                entry.key = key;
            }
            self.heap_fix(e.heap_pos as usize);
            slot = e.next_out;
        }
    }

    /// The slab slot of the queued edge `parent -> child`, if queued. Bounded by the slab size.
    fn find_queued(&self, parent: u32, child: u32) -> Option<u32> {
        let mut slot = self.node(parent).map_or(NONE, |n| n.first_out);
        for _ in 0..NQ {
            if slot == NONE {
                return None;
            }
            let e = self.edge(slot)?;
            if e.child == child {
                return Some(slot);
            }
            slot = e.next_out;
        }
        None
    }

    fn sort_key(&self, parent: u32, child: u32, c_hat: Cost) -> [f64; 3] {
        let g = self.g(parent);
        let h = self.node(child).map_or(f64::INFINITY, |n| n.h_go);
        [g + c_hat + self.st.inflation * h, g + c_hat, g]
    }

    /// Drop entries at the front whose nodes left the tree or were freed (only possible across prunings, which
    /// clear the queue; kept as a guard). Bounded by the queue length.
    fn clean_front(&mut self) {
        let budget = self.arena.heap.len() + 1;
        for _ in 0..budget {
            let Some(front) = self.arena.heap.first().and_then(|&s| self.edge(s)).copied() else {
                return;
            };
            let valid = match (self.node(front.parent), self.node(front.child)) {
                (Some(p), Some(c)) => {
                    p.generation == front.parent_generation
                        && c.generation == front.child_generation
                        && p.in_tree()
                        && !c.has(F_FREE)
                }
                _ => false,
            };
            if valid {
                return;
            }
            let _ = self.heap_pop();
        }
    }

    // ---------------------------------------------------------------- memo (black / white lists)

    fn memo_slot(parent: u32, child: u32) -> usize {
        let h = (parent as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (child as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        if NM == 0 {
            0
        } else {
            ((h ^ (h >> 29)) % NM as u64) as usize
        }
    }

    fn generations(&self, parent: u32, child: u32) -> (u32, u32) {
        (
            self.node(parent).map_or(NONE, |n| n.generation),
            self.node(child).map_or(NONE, |n| n.generation),
        )
    }

    fn memo_get(&self, parent: u32, child: u32) -> Option<Option<S::Attachment>> {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        for p in 0..MEMO_PROBES.min(NM) {
            let slot = self.arena.memo.get((home + p) % NM.max(1))?;
            match slot {
                Some(e) if e.parent == parent && e.child == child => {
                    return (e.parent_generation == pg && e.child_generation == cg).then(|| e.result.clone());
                }
                None => return None,
                _ => {}
            }
        }
        None
    }

    fn memo_put(&mut self, parent: u32, child: u32, result: Option<S::Attachment>) {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        let mut target = None;
        for p in 0..MEMO_PROBES.min(NM) {
            let idx = (home + p) % NM.max(1);
            let Some(slot) = self.arena.memo.get(idx) else { break };
            let reusable = match slot {
                None => true,
                Some(e) if e.parent == parent && e.child == child => true,
                Some(e) => {
                    // A stale entry (either node freed or disconnected since) may be overwritten.
                    let (epg, ecg) = self.generations(e.parent, e.child);
                    epg != e.parent_generation || ecg != e.child_generation
                }
            };
            if reusable {
                target = Some(idx);
                break;
            }
        }
        // Full neighbourhood: replace the home slot (the memo is a cache).
        let idx = target.unwrap_or(home);
        let was_empty = matches!(self.arena.memo.get(idx), Some(None));
        if let Some(slot) = self.arena.memo.get_mut(idx) {
            *slot = Some(MemoEntry { parent, parent_generation: pg, child, child_generation: cg, result });
            if was_empty {
                self.st.high_water.memo += 1;
            }
        }
    }

    /// Is the edge known to be unusable (invalid, or incompatible with the child's attachment)?
    fn blacklisted(&self, parent: u32, child: u32) -> bool {
        match self.memo_get(parent, child) {
            Some(None) => true,
            Some(Some(att)) => match self.node(child).and_then(|c| c.attachment.as_ref()) {
                Some(existing) => !self.space.attachments_compatible(&att, existing),
                None => false,
            },
            None => false,
        }
    }

    /// Check the motion parent -> child (memoised). Returns the child's attachment after the motion.
    fn check_edge(&mut self, parent: u32, child: u32) -> Option<S::Attachment> {
        if let Some(result) = self.memo_get(parent, child) {
            self.st.counters.memo_hits += 1;
            return result;
        }
        self.st.counters.edges_evaluated += 1;
        let result = match (self.arena.nodes.get(parent as usize), self.arena.nodes.get(child as usize)) {
            (Some(p), Some(c)) => match p.attachment.as_ref() {
                Some(att) => match self.motion.check_motion(self.space, &p.state, att, &c.state) {
                    MotionCheck::Valid { attachment } => Some(attachment),
                    MotionCheck::Invalid => None,
                },
                None => None,
            },
            _ => None,
        };
        self.memo_put(parent, child, result.clone());
        result
    }

    // ---------------------------------------------------------------- graph

    /// Indices of the k nearest nodes (k-nearest, the node itself included as in OMPL) or of the nodes within r.
    fn neighbours(&mut self, of: u32) -> Vec<(f64, u32), { cfg::NEIGHBOUR_CAPACITY }> {
        let mut out: Vec<(f64, u32), { cfg::NEIGHBOUR_CAPACITY }> = Vec::new();
        let Some(center) = self.node(of).map(|n| n.state.clone()) else {
            return out;
        };
        let (limit, radius) = match self.st.params.connection {
            Connection::KNearest => (self.st.k, f64::INFINITY),
            Connection::RDisc => (usize::MAX, self.st.r),
        };
        let cap = limit.min(cfg::NEIGHBOUR_CAPACITY);
        let mut truncated = limit > cfg::NEIGHBOUR_CAPACITY && limit != usize::MAX;
        for (i, n) in self.arena.nodes.iter().enumerate() {
            if n.has(F_FREE) || n.has(F_TWIN) {
                continue;
            }
            let d = self.space.distance(&center, &n.state);
            if d > radius || cap == 0 {
                continue;
            }
            let entry = (d, i as u32);
            if out.len() == cap {
                match out.last() {
                    Some(last) if entry < *last => {
                        let _ = out.pop();
                        if limit == usize::MAX {
                            truncated = true;
                        }
                    }
                    _ => {
                        if limit == usize::MAX {
                            truncated = true;
                        }
                        continue;
                    }
                }
            }
            // Insertion sort (bounded by NEIGHBOUR_CAPACITY).
            let pos = out.iter().position(|e| entry < *e).unwrap_or(out.len());
            let _ = out.insert(pos, entry);
        }
        if truncated {
            self.st.counters.neighbour_lists_truncated += 1;
        }
        out
    }

    fn enqueue_conditionally(&mut self, parent: u32, child: u32) {
        let conflict = self.twins_enabled() && self.histories_conflict(parent, child);
        if conflict {
            // The edge will go to a twin of the child; only a known-invalid motion rules it out.
            if matches!(self.memo_get(parent, child), Some(None)) {
                return;
            }
        } else if self.blacklisted(parent, child) {
            return;
        }
        let (Some(p), Some(c)) = (self.node(parent), self.node(child)) else {
            return;
        };
        let c_hat = self.pdef.objective.motion_cost_heuristic(self.space, &p.state, &c.state);
        // Can it ever improve the solution? h(start,u) + c^(u,v) + h(v,goal) <= c_best.
        if p.h_come + c_hat + c.h_go > self.st.best_cost {
            return;
        }
        // Can it ever improve the child's cost-to-come? h(start,u) + c^(u,v) <= g(v). (A child of another
        // history is not a competitor: the edge goes to its twin.)
        let mut reveals = false;
        if !conflict && c.in_tree() && p.h_come + c_hat > c.cost {
            // ... unless the motion would give the child another attachment (the tether catching on a column
            // between two vertices that both hold the root-only history): then it reaches a twin of the child.
            if !(self.twins_enabled() && self.st.params.reveal_attachments && self.reveals_attachment(parent, child)) {
                return;
            }
            reveals = true;
        }
        let (Some(p), Some(c)) = (self.node(parent), self.node(child)) else {
            return;
        };
        let (pg, cg) = (p.generation, c.generation);
        let key = self.sort_key(parent, child, c_hat);
        if let Some(slot) = self.find_queued(parent, child) {
            let pos = self.edge(slot).map_or(0, |e| e.heap_pos as usize);
            if let Some(e) = self.arena.edges.get_mut(slot as usize) {
                e.key = key;
                e.reveals = reveals;
            }
            self.heap_fix(pos);
            return;
        }
        self.queue_insert(QueueEdge {
            key,
            c_hat,
            parent,
            child,
            parent_generation: pg,
            child_generation: cg,
            heap_pos: 0,
            next_out: NONE,
            prev_out: NONE,
            reveals,
        });
    }

    /// Queue the outgoing edges of a vertex (to its children, to its unconnected neighbours, and — cascading
    /// rewirings, ABIT* — to its connected neighbours).
    fn insert_outgoing_edges(&mut self, v: u32, reexpansion: bool) {
        let Some(n) = self.node(v) else { return };
        if n.h_come + n.h_go > self.st.best_cost {
            return;
        }
        let (own_parent, first_child) = (n.parent, n.first_child);
        if reexpansion {
            if let Some(n) = self.node_mut(v) {
                n.flags &= !F_INCONSISTENT;
            }
        }
        // Current children first (bounded by the arena size).
        let mut c = first_child;
        for _ in 0..NV {
            if c == NONE {
                break;
            }
            self.enqueue_conditionally(v, c);
            c = self.node(c).map_or(NONE, |n| n.next_sibling);
        }
        let neighbours = self.neighbours(v);
        for &(_, w) in neighbours.iter() {
            if w == v {
                continue;
            }
            let Some(wn) = self.node(w) else { continue };
            // Unconnected samples, and (cascading rewirings) connected vertices other than the root, my
            // children and my parent. The root only for a history twin: the start's pose holding another history.
            let consider = if !wn.in_tree() {
                true
            } else if wn.has(F_START) {
                self.twins_enabled()
            } else {
                wn.parent != v && own_parent != w
            };
            if consider {
                self.enqueue_conditionally(v, w);
            }
        }
        if S::NON_MARKOVIAN && self.st.params.goal_edges {
            for gi in 0..self.st.goals.len() {
                let Some(&g) = self.st.goals.get(gi) else { break };
                let listed = neighbours.iter().any(|&(_, w)| w == g);
                if g != v && !listed && self.node(g).is_some_and(|n| !n.has(F_FREE) && !n.has(F_TWIN)) {
                    self.enqueue_conditionally(v, g);
                }
            }
        }
    }

    fn twins_enabled(&self) -> bool {
        S::NON_MARKOVIAN && self.st.params.history_twins
    }

    /// Would the motion from tree vertex `u` into tree vertex `w` give `w` an attachment incompatible with the one
    /// it holds? From the memo when the motion was checked, else from the space's prediction
    /// ([`StateSpace::predict_attachment`]); `false` when neither knows.
    fn reveals_attachment(&mut self, u: u32, w: u32) -> bool {
        let predicted = match self.memo_get(u, w) {
            Some(known) => known,
            None => {
                let (Some(un), Some(wn)) = (self.node(u), self.node(w)) else { return false };
                let Some(att) = un.attachment.as_ref() else { return false };
                let predicted = self.space.predict_attachment(&un.state, att, &wn.state);
                self.st.counters.attachment_predictions = self.st.counters.attachment_predictions.saturating_add(1);
                predicted
            }
        };
        let (Some(pred), Some(existing)) = (predicted, self.node(w).and_then(|n| n.attachment.as_ref())) else {
            return false;
        };
        !self.space.attachments_compatible(&pred, existing)
    }

    /// The node of `v`'s state that a motion ending with attachment `att` connects to: `v` or the first of its
    /// twins whose attachment is undetermined or compatible with `att`, creating a twin at the end of the chain if
    /// there is room.
    fn twin_for_attachment(&mut self, v: u32, att: &S::Attachment) -> Option<u32> {
        let mut cur = v;
        for _ in 0..cfg::MAX_HISTORY_TWINS {
            let fits = match self.node(cur)?.attachment.as_ref() {
                None => true,
                Some(existing) => self.space.attachments_compatible(att, existing),
            };
            if fits {
                return Some(cur);
            }
            let (twin, twin_generation) = self.node(cur).map(|n| (n.twin, n.twin_generation))?;
            let twin_alive = self.node(twin).is_some_and(|t| t.generation == twin_generation && !t.has(F_FREE));
            if twin_alive {
                cur = twin;
                continue;
            }
            return self.new_twin(cur);
        }
        None
    }

    /// A twin of `cur`'s state with undetermined attachment, linked as `cur`'s twin.
    fn new_twin(&mut self, cur: u32) -> Option<u32> {
        let (state, is_goal) = self.node(cur).map(|n| (n.state.clone(), n.has(F_GOAL)))?;
        let created = if is_goal {
            self.add_goal_vertex(state)
        } else {
            let i = self.alloc(state, None, 0);
            if i.is_none() {
                self.st.pending_full = Some(Arena::Nodes);
            }
            i
        }?;
        self.st.counters.history_twins += 1;
        if let Some(n) = self.node_mut(created) {
            n.flags |= F_TWIN;
        }
        let generation = self.node(created).map_or(0, |n| n.generation);
        if let Some(n) = self.node_mut(cur) {
            n.twin = created;
            n.twin_generation = generation;
        }
        Some(created)
    }

    /// Do `u` (the parent) and `w` — a tree vertex, or a sample that copied an attachment — hold incompatible
    /// attachments? (The parent's own attachment stands in for the motion's result, which is only known after the
    /// motion check.) A sample that copied one history must not lock out every other history: the edge goes to a
    /// twin of undetermined history instead.
    fn histories_conflict(&self, u: u32, w: u32) -> bool {
        let (Some(un), Some(wn)) = (self.node(u), self.node(w)) else { return false };
        match (un.attachment.as_ref(), wn.attachment.as_ref()) {
            (Some(a), Some(b)) => !self.space.attachments_compatible(a, b),
            _ => false,
        }
    }

    /// The node an edge from `u` into the state of `v` should target: `v` itself, or the first twin of `v` that
    /// is unconnected or of a compatible history, creating a twin with undetermined history at the end of the
    /// chain if there is room (`MAX_HISTORY_TWINS`). `None` if no target is possible.
    fn twin_target(&mut self, u: u32, v: u32) -> Option<u32> {
        match self.node(u)?.attachment.clone() {
            Some(att) => self.twin_for_attachment(v, &att),
            None => Some(v),
        }
    }

    /// A vertex is expanded on the current search once one of its outgoing edges has been processed (OMPL's
    /// `registerExpansion`); a vertex improved after that is inconsistent and re-expanded in the final search.
    fn register_expansion(&mut self, u: u32) {
        let search = self.st.search_id;
        if let Some(n) = self.node_mut(u) {
            n.expanded_search = search;
        }
    }

    fn unlink_from_parent(&mut self, child: u32) {
        let Some(parent) = self.node(child).map(|n| n.parent) else { return };
        if parent == NONE {
            return;
        }
        let next = self.node(child).map_or(NONE, |n| n.next_sibling);
        let head = self.node(parent).map_or(NONE, |n| n.first_child);
        if head == child {
            if let Some(p) = self.node_mut(parent) {
                p.first_child = next;
            }
        } else {
            let mut c = head;
            for _ in 0..NV {
                if c == NONE {
                    break;
                }
                let sib = self.node(c).map_or(NONE, |n| n.next_sibling);
                if sib == child {
                    if let Some(cn) = self.node_mut(c) {
                        cn.next_sibling = next;
                    }
                    break;
                }
                c = sib;
            }
        }
        if let Some(n) = self.node_mut(child) {
            n.parent = NONE;
            n.next_sibling = NONE;
        }
    }

    /// Propagate a cost change of `root` to its descendants (pre-order walk via parent links, bounded by NV).
    fn propagate_costs(&mut self, root: u32) {
        let mut cur = self.node(root).map_or(NONE, |n| n.first_child);
        for _ in 0..(2 * NV + 2) {
            if cur == NONE || cur == root {
                return;
            }
            let (parent, edge_cost, first_child) =
                self.node(cur).map_or((NONE, 0.0, NONE), |n| (n.parent, n.edge_cost, n.first_child));
            let g = self.g(parent) + edge_cost;
            // Only the rewired vertex itself joins the inconsistent set (`add_edge`), as in OMPL
            // (`BITstar::addEdge`): descendants get their queued edges re-keyed, not re-expanded.
            if let Some(n) = self.node_mut(cur) {
                n.cost = g;
            }
            self.update_out_edges(cur);
            if first_child != NONE {
                cur = first_child;
                continue;
            }
            // Climb until a node with a next sibling, stopping at root.
            let mut up = cur;
            cur = NONE;
            for _ in 0..NV {
                if up == root || up == NONE {
                    break;
                }
                let (sib, par) = self.node(up).map_or((NONE, NONE), |n| (n.next_sibling, n.parent));
                if sib != NONE {
                    cur = sib;
                    break;
                }
                up = par;
            }
        }
    }

    fn add_edge(&mut self, parent: u32, child: u32, edge_cost: Cost, attachment: S::Attachment) {
        let was_in_tree = self.node(child).is_some_and(|n| n.in_tree());
        if was_in_tree {
            self.st.counters.rewirings += 1;
            self.unlink_from_parent(child);
        }
        let g = self.g(parent) + edge_cost;
        let head = self.node(parent).map_or(NONE, |n| n.first_child);
        if let Some(n) = self.node_mut(child) {
            n.parent = parent;
            n.edge_cost = edge_cost;
            n.cost = g;
            n.attachment = Some(attachment);
            n.flags |= F_IN_TREE;
            n.next_sibling = head;
        }
        if let Some(p) = self.node_mut(parent) {
            p.first_child = child;
        }
        self.update_out_edges(child);
        self.propagate_costs(child);
        if self.st.params.track_approximate {
            let h = self.node(child).map_or(f64::INFINITY, |n| n.h_go);
            if h < self.st.approx_h {
                self.st.approx_h = h;
                self.st.approx_vertex = child;
            }
        }
        let expanded = self.node(child).is_some_and(|n| n.expanded_search == self.st.search_id);
        if !expanded {
            self.insert_outgoing_edges(child, false);
        } else if let Some(n) = self.node_mut(child) {
            n.flags |= F_INCONSISTENT;
        }
    }

    /// Recompute the best goal; true if the solution improved.
    fn update_goal(&mut self) -> bool {
        let mut best = (self.st.best_cost, self.st.best_goal);
        for &gi in self.st.goals.iter() {
            if let Some(n) = self.arena.nodes.get(gi as usize) {
                if n.in_tree() && n.cost < best.0 {
                    best = (n.cost, gi);
                }
            }
        }
        if best.0 < self.st.best_cost {
            self.st.best_cost = best.0;
            self.st.best_goal = best.1;
            self.st.counters.improvements += 1;
            if self.st.counters.first_solution_iteration == 0 {
                self.st.counters.first_solution_iteration = self.st.counters.iterations;
            }
            if S::NON_MARKOVIAN && self.st.params.fresh_goal_on_improvement {
                let has_open_goal = self.st.goals.iter().any(|&gi| {
                    self.node(gi).is_some_and(|n| !n.in_tree() && n.attachment.is_none())
                });
                if !has_open_goal {
                    if let Some(goal) = self.st.goal_state.clone() {
                        // A full goal list or arena only means no fresh goal this time.
                        let _ = self.add_goal_vertex(goal);
                    }
                }
            }
            true
        } else {
            false
        }
    }

    fn has_solution(&self) -> bool {
        self.st.best_goal != NONE
    }

    // ---------------------------------------------------------------- batches

    fn prune(&mut self) {
        if !self.has_solution() {
            return;
        }
        let best = self.st.best_cost;
        // OMPL: prunable states (vertices included) over `numSamples() + numVertices()`.
        let total = self.ompl_graph_size();
        let prunable = self
            .arena
            .nodes
            .iter()
            .filter(|n| !n.has(F_FREE) && !n.has(F_START) && n.h_come + n.h_go >= best)
            .count();
        if (prunable as f64) / total < self.st.params.prune_fraction {
            return;
        }
        self.st.counters.prunings += 1;
        let len = self.arena.nodes.len();
        // Pass 1: disconnect vertices that cannot be on a better path; drop samples that cannot help.
        for i in 0..len as u32 {
            let Some(n) = self.node(i) else { continue };
            if n.has(F_FREE) || n.has(F_START) {
                continue;
            }
            if n.in_tree() {
                if i != self.st.best_goal && n.cost + n.h_go > best {
                    self.disconnect(i);
                    // Kept as a sample: OMPL "recycles" it, i.e. it rejoins the samples only after the next
                    // batch's RGG terms are computed.
                    if self.node(i).is_some_and(|n| !n.has(F_FREE)) {
                        self.st.recycled += 1;
                    }
                }
            } else if !n.has(F_GOAL) && n.h_come + n.h_go >= best {
                self.free(i);
            }
        }
        // Pass 2 (robust to rounding): vertices whose parent left the tree leave it too. Bounded sweeps.
        for _ in 0..len {
            let mut changed = false;
            for i in 0..len as u32 {
                let Some(n) = self.node(i) else { continue };
                if n.in_tree() && !n.has(F_START) {
                    let parent_ok = self.node(n.parent).is_some_and(|p| p.in_tree());
                    if !parent_ok {
                        self.disconnect(i);
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
    }

    /// Take a vertex out of the tree; keep it as a sample if it can still help, otherwise free it.
    fn disconnect(&mut self, i: u32) {
        self.unlink_from_parent(i);
        // Orphan the children (they are disconnected by the caller's sweep).
        let mut c = self.node(i).map_or(NONE, |n| n.first_child);
        for _ in 0..NV {
            if c == NONE {
                break;
            }
            let next = self.node(c).map_or(NONE, |n| n.next_sibling);
            if let Some(cn) = self.node_mut(c) {
                cn.parent = NONE;
                cn.next_sibling = NONE;
            }
            c = next;
        }
        let best = self.st.best_cost;
        let Some(n) = self.node_mut(i) else { return };
        n.first_child = NONE;
        n.flags &= !(F_IN_TREE | F_INCONSISTENT);
        n.cost = f64::INFINITY;
        n.attachment = None;
        // The generation keys the memo (OMPL's per-vertex black/white lists, which survive pruning): a motion's
        // result depends on the parent's attachment, which changes with a reconnection only in non-Markovian
        // spaces; in Markovian ones the memo of a recycled state stays valid, as in OMPL.
        if S::NON_MARKOVIAN {
            n.generation = n.generation.wrapping_add(1);
        }
        let keep = n.has(F_GOAL) || n.h_come + n.h_go < best;
        if !keep {
            self.free(i);
        }
        if self.st.approx_vertex == i {
            self.st.approx_vertex = NONE;
            self.st.approx_h = f64::INFINITY;
        }
    }

    /// The attachment a new sample copies (Paton et al. V-A): one of the distinct (mutually incompatible)
    /// attachments among the k nearest tree vertices, chosen uniformly, so rare histories (the one anchored on the
    /// column, Fig. 7d) are copied as often as the common one. Bounded by the arena size and `NEIGHBOUR_CAPACITY`.
    fn copied_attachment(&mut self, state: &S::State) -> Option<S::Attachment> {
        let cap = self.st.k.clamp(1, cfg::NEIGHBOUR_CAPACITY);
        let mut near: Vec<(f64, u32), { cfg::NEIGHBOUR_CAPACITY }> = Vec::new();
        for (i, n) in self.arena.nodes.iter().enumerate() {
            if !n.in_tree() || n.attachment.is_none() {
                continue;
            }
            let entry = (self.space.distance(state, &n.state), i as u32);
            if near.len() == cap {
                match near.last() {
                    Some(last) if entry < *last => {
                        let _ = near.pop();
                    }
                    _ => continue,
                }
            }
            let pos = near.iter().position(|e| entry < *e).unwrap_or(near.len());
            let _ = near.insert(pos, entry);
        }
        // Distinct attachments, in order of distance (deterministic).
        let mut distinct: Vec<u32, { cfg::NEIGHBOUR_CAPACITY }> = Vec::new();
        for &(_, i) in near.iter() {
            let Some(att) = self.node(i).and_then(|n| n.attachment.as_ref()) else { continue };
            if !self.any_compatible(&distinct, att) {
                let _ = distinct.push(i);
            }
        }
        if distinct.is_empty() {
            return None;
        }
        let pick = ((uniform01(self.rng) * distinct.len() as f64) as usize).min(distinct.len() - 1);
        distinct.get(pick).and_then(|&i| self.node(i)).and_then(|n| n.attachment.clone())
    }

    /// Does one of the nodes `of` hold an attachment compatible with `att`?
    fn any_compatible(&self, of: &[u32], att: &S::Attachment) -> bool {
        of.iter().any(|&j| {
            let other = self.node(j).and_then(|n| n.attachment.as_ref());
            other.is_some_and(|b| self.space.attachments_compatible(att, b))
        })
    }

    /// One tree vertex per distinct attachment (compatibility class), in arena order, up to
    /// `CATCH_ATTACHMENT_CAPACITY`: the histories whose catch boundaries a batch samples. Bounded by the arena
    /// size times that capacity.
    fn distinct_attachment_vertices(&self) -> Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }> {
        let mut distinct: Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }> = Vec::new();
        for (i, n) in self.arena.nodes.iter().enumerate() {
            let Some(att) = n.attachment.as_ref().filter(|_| n.in_tree()) else { continue };
            if !self.any_compatible(&distinct, att) && distinct.push(i as u32).is_err() {
                break;
            }
        }
        distinct
    }

    /// A sample near the catch boundary of one of `histories` (chosen uniformly), kept only if it can improve
    /// the solution (informed set by rejection, as for uniform draws). A history whose boundary the space did
    /// not find leaves `histories` for the rest of the batch, so a root anchor that sees the whole planning area
    /// costs one search per batch, not one per draw.
    fn catch_sample(&mut self, histories: &mut Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }>) -> Option<S::State> {
        let pick = ((uniform01(self.rng) * histories.len() as f64) as usize).min(histories.len().saturating_sub(1));
        let att = histories.get(pick).and_then(|&i| self.node(i)).and_then(|n| n.attachment.clone())?;
        let x = match self.space.sample_catch_boundary(self.rng, &att) {
            CatchSample::Sampled(x) => x,
            CatchSample::Rejected => return None,
            CatchSample::NotFound => {
                let _ = histories.swap_remove(pick);
                return None;
            }
        };
        if self.has_solution() {
            let (hc, hg) = self.heuristics(&x);
            if hc + hg >= self.st.best_cost {
                return None;
            }
        }
        self.st.counters.catch_samples = self.st.counters.catch_samples.saturating_add(1);
        Some(x)
    }

    /// A new sample: near a catch boundary (a fraction `catch_sample_fraction` of the draws, non-Markovian
    /// spaces), else uniform before the first solution and informed after it.
    fn draw_sample(&mut self, catch_histories: &mut Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }>) -> Option<S::State> {
        if !catch_histories.is_empty() && uniform01(self.rng) < self.st.params.catch_sample_fraction {
            if let Some(x) = self.catch_sample(catch_histories) {
                return Some(x);
            }
        }
        if !self.has_solution() {
            return self.space.sample_uniform(self.rng);
        }
        let pdef = self.pdef;
        let goal = self.st.goal_state.as_ref()?;
        // Like OMPL's direct informed sampler, retry draws rejected by the bounds (bounded).
        for _ in 0..self.st.params.informed_rejection_attempts {
            match pdef.objective.sample_informed(self.space, self.rng, &pdef.start, goal, self.st.best_cost) {
                InformedSample::Sampled(x) => return Some(x),
                InformedSample::Rejected => continue,
                InformedSample::Unsupported => break,
            }
        }
        // No direct sampler: rejection sampling on the heuristic (OMPL RejectionInfSampler), bounded.
        for _ in 0..self.st.params.informed_rejection_attempts {
            let x = self.space.sample_uniform(self.rng)?;
            let (hc, hg) = self.heuristics(&x);
            if hc + hg < self.st.best_cost {
                return Some(x);
            }
        }
        None
    }

    fn new_batch(&mut self) {
        self.st.counters.batches += 1;
        let batch = self.st.params.samples_per_batch as usize;
        // RGG terms for the number of states we have (OMPL: plus the batch on the very first batch).
        // OMPL counts the states before the recycled ones (vertices disconnected by the last pruning and kept
        // as samples) are added back.
        let mut q = self.st.live_nodes.saturating_sub(self.st.recycled);
        self.st.recycled = 0;
        if q == 1 + self.st.goals.len() {
            q += batch;
        }
        let qf = (q.max(2)) as f64;
        let d = self.space.dimension().max(1) as f64;
        let e = core::f64::consts::E;
        self.st.k = libm::ceil(self.st.params.rewire_factor * (e + e / d) * libm::log(qf)) as usize;
        let r_rgg = libm::pow(
            2.0 * (1.0 + 1.0 / d) * (self.space.measure() / unit_ball_measure(self.space.dimension().max(1))),
            1.0 / d,
        );
        self.st.r = self.st.params.rewire_factor * r_rgg * libm::pow(libm::log(qf) / qf, 1.0 / d);

        let mut catch_histories = if S::NON_MARKOVIAN && self.st.params.catch_sample_fraction > 0.0 {
            self.distinct_attachment_vertices()
        } else {
            Vec::new()
        };
        let attempts = self.st.params.sample_attempts_per_sample as usize * batch;
        let mut added = 0usize;
        for _ in 0..attempts {
            if added >= batch {
                break;
            }
            let Some(x) = self.draw_sample(&mut catch_histories) else { continue };
            self.st.counters.states_checked += 1;
            if !self.validity.is_valid(&x) {
                continue;
            }
            let attachment = if S::NON_MARKOVIAN
                && self.st.params.attachment_copy_fraction > 0.0
                && uniform01(self.rng) < self.st.params.attachment_copy_fraction
            {
                self.copied_attachment(&x)
            } else {
                None
            };
            // A copied attachment makes the sample's attachment-dependent validity checkable now (Paton V-A).
            if let Some(a) = attachment.as_ref() {
                if !self.space.valid_with_attachment(&x, a) {
                    self.st.counters.samples_invalid_with_copy += 1;
                    continue;
                }
            }
            if self.alloc(x, attachment, 0).is_none() {
                self.st.pending_full = Some(Arena::Nodes);
                break;
            }
            added += 1;
            self.st.counters.samples_added += 1;
        }
    }

    fn start_index(&self) -> u32 {
        0
    }

    /// OMPL's `numSamples() + numVertices()`: live states (samples and vertices) plus tree vertices, the `q` of
    /// the truncation and final-search inflation factors. Bounded by the arena size.
    fn ompl_graph_size(&self) -> f64 {
        let vertices = self.arena.nodes.iter().filter(|n| n.in_tree() && !n.has(F_FREE)).count();
        ((self.st.live_nodes + vertices).max(1)) as f64
    }

    /// High-water marks of the arenas so far.
    pub fn arena_use(&self) -> ArenaUse {
        self.st.high_water
    }

    /// Current inflation factor.
    pub fn inflation_factor(&self) -> f64 {
        self.st.inflation
    }

    /// Current k of the k-nearest RGG (OMPL `getConnectivityK`).
    pub fn connectivity_k(&self) -> usize {
        self.st.k
    }

    /// Current truncation factor.
    pub fn truncation_factor(&self) -> f64 {
        self.st.truncation
    }

    /// Cost of the best solution (`INFINITY` if none).
    pub fn best_cost(&self) -> Cost {
        self.st.best_cost
    }

    /// The heuristic lower bound on the solution cost (start-goal heuristic).
    pub fn min_cost(&self) -> Cost {
        self.st.min_cost
    }

    /// Live nodes (start, goals, samples and vertices).
    pub fn num_states(&self) -> usize {
        self.st.live_nodes
    }

    /// All live nodes (for pictures and tests).
    pub fn nodes(&self) -> impl Iterator<Item = &Node<S::State, S::Attachment>> {
        self.arena.nodes.iter().filter(|n| !n.has(F_FREE))
    }

    fn path_end(&self) -> Option<u32> {
        if self.has_solution() {
            Some(self.st.best_goal)
        } else if self.st.params.track_approximate && self.st.approx_vertex != NONE {
            Some(self.st.approx_vertex)
        } else {
            None
        }
    }

    /// Write the best path (start first) into `out`, each state with its attachment. Returns the number of
    /// states written.
    pub fn write_path<const P: usize>(
        &self,
        out: &mut Vec<(S::State, S::Attachment), P>,
    ) -> Result<usize, PathError> {
        out.clear();
        let end = self.path_end().ok_or(PathError::NoSolution)?;
        let mut len = 0usize;
        let mut cur = end;
        for _ in 0..NV {
            if cur == NONE {
                break;
            }
            len += 1;
            cur = self.node(cur).map_or(NONE, |n| n.parent);
        }
        if len > P {
            return Err(PathError::TooLong(len));
        }
        // Fill from the goal backwards: write in reverse order by walking len times per slot would be O(n^2);
        // instead push goal->start and reverse in place.
        let mut cur = end;
        for _ in 0..len {
            let Some(n) = self.node(cur) else { break };
            let Some(att) = n.attachment.clone() else { break };
            if out.push((n.state.clone(), att)).is_err() {
                return Err(PathError::TooLong(len));
            }
            cur = n.parent;
        }
        out.reverse();
        Ok(out.len())
    }

    // ---------------------------------------------------------------- the iteration

    fn iterate(&mut self) -> StepOutcome {
        self.st.counters.iterations += 1;
        self.clean_front();
        if self.st.search_done || self.arena.heap.is_empty() {
            if self.st.final_search || !self.has_solution() {
                if self.st.params.pruning {
                    self.prune();
                }
                self.new_batch();
                self.st.inflation = self.st.params.initial_inflation_factor;
                self.queue_clear();
                self.st.search_id = self.st.search_id.wrapping_add(1);
                self.insert_outgoing_edges(self.start_index(), false);
                self.st.final_search = false;
                self.st.truncation = 1.0 + self.st.params.truncation_scaling_parameter / self.ompl_graph_size();
                self.st.search_done = false;
                return match self.st.pending_full.take() {
                    Some(a) => StepOutcome::ArenaFull(a),
                    None => StepOutcome::NewBatch,
                };
            }
            // Final search of this batch: less inflation, re-key, re-expand the inconsistent vertices.
            self.st.inflation = 1.0 + self.st.params.inflation_scaling_parameter / self.ompl_graph_size();
            self.queue_rebuild();
            for i in 0..self.arena.nodes.len() as u32 {
                let inconsistent = self.node(i).is_some_and(|n| n.has(F_INCONSISTENT) && n.in_tree());
                if inconsistent {
                    self.insert_outgoing_edges(i, true);
                }
            }
            self.st.final_search = true;
            self.st.search_done = false;
            return match self.st.pending_full.take() {
                Some(a) => StepOutcome::ArenaFull(a),
                None => StepOutcome::FinalSearch,
            };
        }
        // `drop_dead_edges`: edges that can no longer improve their child leave without an iteration (bounded by the
        // queue's capacity).
        let mut popped = None;
        for _ in 0..NQ {
            let Some(edge) = self.heap_pop() else { break };
            if self.st.params.drop_dead_edges && self.edge_cannot_improve_child(&edge) {
                self.st.counters.edges_dropped += 1;
                continue;
            }
            popped = Some(edge);
            break;
        }
        let Some(edge) = popped else {
            return StepOutcome::ProcessedEdge;
        };
        self.st.counters.edges_popped += 1;
        let (u, v) = (edge.parent, edge.child);
        let outcome = self.process_edge(u, v, edge.c_hat, edge.reveals);
        match self.st.pending_full.take() {
            Some(a) => StepOutcome::ArenaFull(a),
            None => outcome,
        }
    }

    /// A queued edge `(u, v)` whose child `v` already has a cost-to-come no worse than `g(u) + c_hat(u, v)`: the
    /// test `process_edge` discards it with. Not for edges that would go to a history twin of `v` (their target's
    /// cost is not `v`'s) nor for tree edges (a freebie expands the child).
    fn edge_cannot_improve_child(&self, e: &QueueEdge) -> bool {
        let (Some(un), Some(vn)) = (self.node(e.parent), self.node(e.child)) else { return false };
        if e.reveals || vn.parent == e.parent || (self.twins_enabled() && self.histories_conflict(e.parent, e.child)) {
            return false;
        }
        un.cost + e.c_hat >= vn.cost
    }

    fn process_edge(&mut self, u: u32, v: u32, c_hat: Cost, reveals: bool) -> StepOutcome {
        // Non-Markovian: an edge into a vertex of another history goes to a twin of that state.
        let v = if self.twins_enabled() && self.node(v).is_some_and(|n| n.parent != u) {
            match self.twin_target(u, v) {
                Some(t) => t,
                None => return StepOutcome::ProcessedEdge,
            }
        } else {
            v
        };
        let (Some(un), Some(vn)) = (self.node(u), self.node(v)) else {
            return StepOutcome::ProcessedEdge;
        };
        // Already in the tree: a freebie, expand the child.
        if vn.parent == u && vn.in_tree() {
            if un.expanded_search != self.st.search_id {
                self.register_expansion(u);
            }
            self.insert_outgoing_edges(v, false);
            return StepOutcome::ProcessedEdge;
        }
        let (g_u, h_come_u, g_v, h_go_v) = (un.cost, un.h_come, vn.cost, vn.h_go);
        // Truncated search: can this edge improve the solution by more than the truncation factor?
        if (g_u + c_hat + h_go_v) * self.st.truncation >= self.st.best_cost {
            self.st.search_done = true;
            return StepOutcome::ProcessedEdge;
        }
        // Could it improve the child's cost-to-come? (An edge that reveals another attachment goes to a twin.)
        if g_u + c_hat >= g_v && !reveals {
            return StepOutcome::ProcessedEdge;
        }
        let Some(att_u) = un.attachment.as_ref() else {
            return StepOutcome::ProcessedEdge;
        };
        let c = self.pdef.objective.motion_cost(self.space, &un.state, att_u, &vn.state);
        if c.is_nan() || c < 0.0 {
            return StepOutcome::ProcessedEdge;
        }
        // Could the true edge improve the solution?
        if h_come_u + c + h_go_v >= self.st.best_cost {
            return StepOutcome::ProcessedEdge;
        }
        let Some(att) = self.check_edge(u, v) else {
            return StepOutcome::ProcessedEdge;
        };
        let compatible = match self.node(v).and_then(|n| n.attachment.as_ref()) {
            Some(existing) => self.space.attachments_compatible(&att, existing),
            None => true,
        };
        let (v, g_v) = if compatible {
            (v, g_v)
        } else {
            self.st.counters.incompatible_attachments += 1;
            // The motion revealed another history: it connects a twin of the child's state (Fig. 7d).
            if !self.twins_enabled() {
                return StepOutcome::ProcessedEdge;
            }
            let Some(t) = self.twin_for_attachment(v, &att) else {
                return StepOutcome::ProcessedEdge;
            };
            (t, self.g(t))
        };
        if g_u + c < g_v {
            self.add_edge(u, v, c, att);
            self.register_expansion(u);
            if self.update_goal() {
                return StepOutcome::ImprovedSolution;
            }
        }
        StepOutcome::ProcessedEdge
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> Planner
    for AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    fn step(&mut self) -> StepOutcome {
        if self.st.invalid.is_some() {
            return StepOutcome::Converged;
        }
        // OMPL stops iterating when no better solution is possible (minCost >= bestCost).
        if self.has_solution() && self.st.best_cost <= self.st.min_cost {
            return StepOutcome::Converged;
        }
        self.iterate()
    }

    fn counters(&self) -> Counters {
        self.st.counters
    }

    fn status(&self) -> PlannerStatus {
        if let Some(e) = self.st.invalid {
            PlannerStatus::InvalidInput(e)
        } else if self.has_solution() {
            PlannerStatus::ExactSolution { cost: self.st.best_cost }
        } else if self.st.params.track_approximate && self.st.approx_vertex != NONE {
            PlannerStatus::ApproximateSolution { cost_to_go: self.st.approx_h }
        } else {
            PlannerStatus::NoSolutionWithinBudget
        }
    }

    fn objective_satisfied(&self) -> bool {
        self.has_solution() && self.pdef.objective.is_satisfied(self.st.best_cost)
    }
}
