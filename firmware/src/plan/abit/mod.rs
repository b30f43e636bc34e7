//! ABIT* — Advanced Batch Informed Trees (Strub & Gammell, ICRA 2020; BIT*: Gammell, Barfoot & Srinivasa, IJRR
//! 2020), the planner of Paton et al. (IROS 2020) section V, with the non-Markovian extensions of section V-A
//! (Fig. 7). It follows OMPL 1.5.2's `BITstar`/`ABITstar`. Heap-free, every loop bounded.
//!
//! ## Files (OMPL's split of `informedtrees/bitstar/`)
//! The data structures are types of their own over the arena, generic only over what they store; the planner's
//! methods in each file name only the bounds they use (the space, the objective, the generator, ...).
//!
//! | file | what | OMPL |
//! |---|---|---|
//! | `mod.rs` | [`AbitStar`]: set-up, the iteration ([`Planner::step`]), processing one edge, the public API | `BITstar.cpp` |
//! | `params.rs` | [`AbitParams`] and their defaults | the planner's parameters |
//! | `node.rs` | [`Node`] and its flags | `Vertex` |
//! | `arena.rs` | [`AbitArena`]: the graph, the queue and the memo, lent by the caller; cost propagation (tree and queue); [`ArenaUse`] | (the planner's storage) |
//! | `graph.rs` | `ImplicitGraph`: nodes and free list, goal vertices, nearest neighbours, tree links, pruning; the planner's heuristics, `add_edge`, best goal | `ImplicitGraph` |
//! | `queue.rs` | `SearchQueue`: the edge slab over [`crate::plan::heap::IndexedHeap`]; the planner's vertex expansion | `SearchQueue` |
//! | `memo.rs` | `EdgeMemo`: memoised motion checks keyed by node generations | the vertices' black / white lists |
//! | `attachments.rs` | history twins, revealing edges, copied attachments, catch-boundary samples | (Paton et al. V-A) |
//! | `batch.rs` | batches: RGG terms, sampling, informed sampling; starting a batch or its final search | `ImplicitGraph::addNewSamples`, `BITstar::iterate` |
//! | `suspend.rs` | [`AbitSuspended`]: suspend and resume a search | — |
//! | `tests.rs` | the graph, the queue and the memo driven on their own (the real line) | — |
//!
//! ## The algorithm
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
//! - **Inflation and truncation.** Every batch starts a search with `eps = initial_inflation_factor`.
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
//! Active only when [`StateSpace::NON_MARKOVIAN`] is true (the tethered rover's anchor histories).
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
//! This project adds four mechanisms, each with its own switch (how they were measured on the toy of the tests and
//! on Table I's test 3: `host-sim/doc/abit_notes.md`):
//! - **History twins** (`history_twins`, in the spirit of Fig. 7d: "multiple anchor histories can expand into a
//!   region"): a cost-to-come comparison between vertices of incompatible histories is meaningless, yet BIT*'s
//!   "can this edge improve the child?" test lets the cheaper history block the other everywhere it arrived first
//!   (Fig. 7c). So an edge from `u` into a tree vertex `w` whose attachment is incompatible with `u`'s goes to a
//!   twin of `w`'s state with undetermined attachment (created on demand, at most
//!   `config::abit::MAX_HISTORY_TWINS` copies per state). A motion whose true attachment turns out incompatible
//!   with its child's also connects a twin (compatible with the motion's attachment) instead of being discarded.
//!   The start's pose can have twins too (the tree's root stays the start itself): on the ledge, coming back to the
//!   start's pose with the tether around the pole is the natural place to begin the descent.
//! - **Revealing edges** (`reveal_attachments`): BIT* does not queue an edge between two tree vertices that cannot
//!   lower the child's cost-to-come, and two vertices of the same history look interchangeable. But the motion
//!   between them may give the child another history: on the ledge of Paton et al. VI-A every vertex of the ledge
//!   top is first reached with the root-only history, and the edges that would wrap the tether around the pole
//!   (between two vertices on either side of its shadow) would never be tried. So when such an edge fails the
//!   cost test, the planner asks the space for a cheap prediction of the motion's attachment
//!   ([`StateSpace::predict_attachment`]; the tethered rover: Alg. 1 along the straight line between the two
//!   tether ends, no settling) and queues the edge if the prediction is incompatible with the child's history; it
//!   then connects a twin of the child.
//! - **Goal edges** (`goal_edges`): every vertex also queues its edges to the goals, wherever they are. In a
//!   non-Markovian space the validity of the long direct motion to the goal depends on the history, which the tree
//!   may only find far from the start (on the ledge: a vertex in front of the pole holding the wrapped history,
//!   whose k nearest states are much closer than the goal). One iteration per vertex, when the edge reaches the
//!   front of the queue; where no goal motion can succeed before a detour, that iteration is wasted.
//! - **Catch-boundary samples** (`catch_sample_fraction`): a fraction of the sample draws is taken where a history
//!   the tree knows would change ([`StateSpace::sample_catch_boundary`]; the tethered rover: along the edge of the
//!   tether shadow that terrain casts as seen from the history's last anchor), because uniform samples rarely
//!   straddle a narrow shadow and then no edge across it is in a k-nearest list. Each such draw picks one of the
//!   tree's distinct histories uniformly (at the first batch, the start's); a history whose boundary the space does
//!   not find leaves the batch's list. After a solution they are kept only inside the informed set.
//!
//! ## Parameters ([`AbitParams::ompl_defaults`], values from `config::abit`)
//! | parameter | default | meaning |
//! |---|---|---|
//! | `samples_per_batch` | 100 (OMPL) | samples drawn per batch |
//! | `rewire_factor` | 1.1 (OMPL) | scales the RGG's k or r |
//! | `connection` | k-nearest (OMPL) | k-nearest or r-disc RGG |
//! | `initial_inflation_factor` | 1e6 (OMPL) | `eps` of each batch's first search |
//! | `inflation_scaling_parameter` | 10 (OMPL) | final search `eps = 1 + 10 / q` |
//! | `truncation_scaling_parameter` | 5 (OMPL) | a search stops at factor `1 + 5 / q` |
//! | `pruning` / `prune_fraction` | on / 0.05 (OMPL) | prune when at least this fraction of the states can go |
//! | `sample_attempts_per_sample` | 2 (OMPL) | draws allowed per requested sample |
//! | `informed_rejection_attempts` | 100 | rejection draws per informed sample without a direct sampler |
//! | `track_approximate` | false (OMPL) | report the vertex closest to the goal when no exact solution exists |
//! | `drop_dead_edges` | false (OMPL) | drop queued edges that can no longer improve their child without an iteration (OMPL, and so Paton et al.'s Table I, spend an iteration on each) |
//! | `attachment_copy_fraction` | 0.25 | V-A: fraction of samples that copy a neighbour's attachment (the paper gives no value) |
//! | `fresh_goal_on_improvement` | true | V-A: a fresh goal with undetermined attachment after each improvement |
//! | `history_twins` | true | history twins (above) |
//! | `reveal_attachments` | true | revealing edges (above) |
//! | `goal_edges` | true | goal edges (above) |
//! | `catch_sample_fraction` | 0.1 | catch-boundary samples (above) |
//! | `evict_samples` | true (OMPL's arena is unbounded) | before a batch without a solution, free unconnected samples, oldest batch first, to keep room for `ROOM_FOR_BATCHES` batches (see Memory) |
//! | `draws_per_step` | 0 (OMPL: a whole batch in one iteration) | sample draws per `step` while a batch is drawn; the on-board navigator bounds it so that one executive step never draws a whole batch |
//!
//! The last five act only in non-Markovian spaces, so on R^n the planner is OMPL's ABIT* with OMPL's defaults.
//! Capacities and bounds (`config::abit`): `NODE_CAPACITY` 4096, `EDGE_QUEUE_CAPACITY` 16384,
//! `EDGE_MEMO_CAPACITY` 16384 (the [`DefaultAbitArena`]), `MEMO_PROBES` 8, `NEIGHBOUR_CAPACITY` 64, `GOAL_CAPACITY` 8,
//! `MAX_HISTORY_TWINS` 4, `CATCH_ATTACHMENT_CAPACITY` 8; `DEFAULT_ITERATION_BUDGET` 750 (Table I).
//!
//! ## Memory
//! Everything lives in an [`AbitArena`] lent by the caller: `NV` nodes (start, goals, samples, vertices),
//! `NQ` queued edges, `NM` memo entries. Before each batch without a solution (`evict_samples`) the node arena
//! keeps room for `ROOM_FOR_BATCHES` (2) batches: where it has less, unconnected samples are freed, the oldest
//! batch's first
//! (counted in `Counters::samples_evicted`; they hold no work done, and the tree, the goals and every state a live
//! history twin hangs from stay). A node arena still full, or a full edge queue, ends `solve` with
//! `Termination::ArenaFull` and keeps the best solution; a full memo only costs repeated edge checks.

mod arena;
mod attachments;
mod batch;
mod graph;
mod memo;
mod node;
mod params;
mod queue;
mod suspend;
#[cfg(test)]
mod tests;

use heapless::Vec;
use rand_core::Rng;

use super::space::{
    Cost, Counters, Ended, GoalRegion, InvalidInput, MotionValidator, OptimizationObjective, Planner, PlannerStatus,
    ProblemDefinition, StateSpace, StateValidityChecker, StepOutcome,
};

pub use arena::{AbitArena, ArenaUse, DefaultAbitArena};
pub use node::Node;
pub use params::{AbitParams, Connection};
pub use suspend::AbitSuspended;

use memo::MemoCheck;
use node::{F_FREE, F_IN_TREE, F_START};
use queue::QueueEdge;

/// "No node".
const NONE: u32 = u32::MAX;

/// The start's node: the first allocated, the root of the tree.
const START: u32 = 0;

/// Why a path could not be written.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathError {
    /// No exact (or, if tracked, approximate) solution yet.
    NoSolution,
    /// The output buffer is too small for the path; the needed length is given.
    TooLong(usize),
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
    /// The search state (everything but the borrows and the arena): what [`Self::suspend`] hands out.
    st: AbitSuspended<S::State>,
}

/// Setting up a problem asks for every bound the planner needs to run (a planner that cannot step cannot be
/// built), the goal region's included: it is sampled here.
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
        arena.reset();
        let mut planner = Self::resume(arena, space, validity, motion, pdef, rng, AbitSuspended::fresh(params));
        if let Err(e) = planner.set_up() {
            planner.st.invalid = Some(e);
        }
        planner
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
        if let Some(n) = self.arena.graph.node_mut(start) {
            n.cost = 0.0;
        }
        self.add_goal_vertex(goal).ok_or(InvalidInput::ArenaTooSmall)?;
        // OMPL: before the first batch, k = |starts| + |goals| and r = infinity, so the first queue holds the
        // start-goal edge only.
        self.st.k = 1 + self.arena.graph.goals().len();
        self.st.r = f64::INFINITY;
        self.insert_outgoing_edges(start, false);
        Ok(())
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
{
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
        self.arena.graph.live()
    }

    /// All live nodes (for pictures and tests).
    pub fn nodes(&self) -> impl Iterator<Item = &Node<S::State, S::Attachment>> {
        self.arena.graph.nodes().iter().filter(|n| !n.has(F_FREE))
    }

    /// The node in arena slot `i` (the index [`Node::parent`] returns), free slots included; `None` past the end.
    pub fn node(&self, i: u32) -> Option<&Node<S::State, S::Attachment>> {
        self.arena.graph.node(i)
    }

    fn has_solution(&self) -> bool {
        self.st.best_goal != NONE
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
        // Push goal -> start, then reverse in place.
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

    /// Are history twins on (a non-Markovian space and `history_twins`)?
    fn twins_enabled(&self) -> bool {
        S::NON_MARKOVIAN && self.st.params.history_twins
    }

    /// `ImplicitGraph::histories_conflict` in this planner's space.
    fn histories_conflict(&self, u: u32, w: u32) -> bool {
        self.arena.graph.histories_conflict(&*self.space, u, w)
    }

    /// Take the front edge out of the queue. With `drop_dead_edges`, edges that can no longer improve their child
    /// leave without an iteration (bounded by the queue's capacity).
    fn pop_edge(&mut self) -> Option<QueueEdge> {
        for _ in 0..NQ {
            let arena = &mut *self.arena;
            let edge = arena.queue.pop(arena.graph.nodes_mut())?;
            if self.st.params.drop_dead_edges && self.edge_cannot_improve_child(&edge) {
                self.st.counters.edges_dropped += 1;
                continue;
            }
            return Some(edge);
        }
        None
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
}

/// Processing one edge of the queue: the motion checks (memoised) and the tree's growth.
impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
{
    /// Check the motion parent -> child (memoised, `memo.rs`). Returns the child's attachment after the motion.
    fn check_edge(&mut self, parent: u32, child: u32) -> Option<S::Attachment> {
        let arena = &mut *self.arena;
        match arena.memo.check(arena.graph.nodes(), &*self.space, &mut *self.motion, parent, child) {
            MemoCheck::Known(result) => {
                self.st.counters.memo_hits += 1;
                result
            }
            MemoCheck::Checked { result, filled } => {
                self.st.counters.edges_evaluated += 1;
                if filled {
                    self.st.high_water.memo += 1;
                }
                result
            }
        }
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
                self.arena.graph.register_expansion(u, self.st.search_id);
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
            (t, self.arena.graph.g(t))
        };
        if g_u + c < g_v {
            self.add_edge(u, v, c, att);
            self.arena.graph.register_expansion(u, self.st.search_id);
            if self.update_goal() {
                return StepOutcome::ImprovedSolution;
            }
        }
        StepOutcome::ProcessedEdge
    }
}

/// One iteration (OMPL's `BITstar::iterate`): start a batch or the final search of one, or process one edge.
impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> Planner
    for AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    R: Rng,
{
    fn step(&mut self) -> StepOutcome {
        if self.st.invalid.is_some() {
            return StepOutcome::Converged;
        }
        // A batch drawn over several steps (`draws_per_step`): go on drawing; the iteration that started the batch
        // counted it.
        if self.st.sampling.is_some() {
            self.st.counters.sampling_steps += 1;
            self.continue_batch();
            return match self.st.pending_full.take() {
                Some(a) => StepOutcome::ArenaFull(a),
                None => StepOutcome::NewBatch,
            };
        }
        // OMPL stops iterating when no better solution is possible (minCost >= bestCost).
        if self.has_solution() && self.st.best_cost <= self.st.min_cost {
            return StepOutcome::Converged;
        }
        self.st.counters.iterations += 1;
        let arena = &mut *self.arena;
        arena.queue.clean_front(arena.graph.nodes_mut());
        let outcome = if self.st.search_done || self.arena.queue.is_empty() {
            if self.st.final_search || !self.has_solution() {
                self.start_batch();
                StepOutcome::NewBatch
            } else {
                self.start_final_search();
                StepOutcome::FinalSearch
            }
        } else {
            let Some(edge) = self.pop_edge() else {
                return StepOutcome::ProcessedEdge;
            };
            self.st.counters.edges_popped += 1;
            self.process_edge(edge.parent, edge.child, edge.c_hat, edge.reveals)
        };
        match self.st.pending_full.take() {
            Some(a) => StepOutcome::ArenaFull(a),
            None => outcome,
        }
    }

    fn counters(&self) -> Counters {
        self.st.counters
    }

    fn status(&self) -> PlannerStatus {
        if let Some(e) = self.st.invalid {
            PlannerStatus::InvalidInput(e)
        } else if self.has_solution() {
            PlannerStatus::Exact(self.st.best_cost)
        } else if self.st.params.track_approximate && self.st.approx_vertex != NONE {
            PlannerStatus::Approximate(self.st.approx_h)
        } else {
            PlannerStatus::NoSolution(Ended::BudgetExhausted)
        }
    }

    fn objective_satisfied(&self) -> bool {
        self.has_solution() && self.pdef.objective.is_satisfied(self.st.best_cost)
    }
}
