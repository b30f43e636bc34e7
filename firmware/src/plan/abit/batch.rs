//! Batches (OMPL's `ImplicitGraph::addNewSamples` and `prune`, and where `BITstar::iterate` starts a batch or its
//! final search): the RGG terms, drawing the samples (uniform, informed, catch-boundary), copying attachments into
//! them, and pruning before a batch (the pruning itself is the graph's, `graph.rs`).

use rand_core::Rng;

use crate::config::abit as cfg;
use crate::geom::unit_ball_measure;
use crate::plan::space::{uniform01, Arena, InformedSample, OptimizationObjective, StateSpace, StateValidityChecker};
use super::attachments::CatchHistories;
use super::node::F_INCONSISTENT;
use super::suspend::BatchSampling;
use super::{AbitStar, NONE, START};

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    O: OptimizationObjective<S>,
    R: Rng,
{
    /// Prune before a batch (OMPL's `ImplicitGraph::prune`, see `ImplicitGraph::prune`): only with a solution,
    /// and only when at least `prune_fraction` of the states can go.
    fn prune(&mut self) {
        if !self.has_solution() {
            return;
        }
        let (best, best_goal, fraction) = (self.st.best_cost, self.st.best_goal, self.st.params.prune_fraction);
        let Some(recycled) = self.arena.graph.prune(best, best_goal, fraction, S::NON_MARKOVIAN) else {
            return;
        };
        self.st.counters.prunings += 1;
        self.st.recycled += recycled;
        // The vertex closest to the goal may have left the tree.
        if self.st.approx_vertex != NONE && !self.node(self.st.approx_vertex).is_some_and(|n| n.in_tree()) {
            self.st.approx_vertex = NONE;
            self.st.approx_h = f64::INFINITY;
        }
    }

    /// Before a batch without a solution (`evict_samples`): when the node arena could not hold
    /// [`cfg::ROOM_FOR_BATCHES`] more batches (the samples to draw, and the goals and history twins their search
    /// creates), free unconnected samples, the oldest batch's first, until it can. A sample that stayed out of the
    /// tree through its batches' searches holds no work done; without this, a search that connects few of its
    /// samples (a steep face where most motions are unstable) fills the arena after a few batches and ends
    /// `ArenaFull` with nothing to drive, long before its iteration budget. With a solution, pruning makes the
    /// room (OMPL's), and a full arena ends the search with the solution kept: batches after a solution are
    /// short, and evicting for them would turn the rest of the iteration budget into batch after batch of
    /// sample draws (each a settle and a stability check in the tethered space).
    fn make_room(&mut self) {
        if self.has_solution() {
            return;
        }
        let keep = NV.saturating_sub(cfg::ROOM_FOR_BATCHES.saturating_mul(self.st.params.samples_per_batch as usize));
        if self.arena.graph.live() > keep {
            let freed = self.arena.graph.evict_oldest_samples(keep);
            self.st.counters.samples_evicted = self.st.counters.samples_evicted.saturating_add(freed as u32);
        }
    }

    /// End the current search and start a batch: prune, draw the batch, and begin a search with the initial
    /// inflation factor from the start's edges.
    pub(super) fn start_batch(&mut self) {
        if self.st.params.pruning {
            self.prune();
        }
        if self.st.params.evict_samples {
            self.make_room();
        }
        self.new_batch();
        self.continue_batch();
    }

    /// Draw the batch's samples, at most `draws_per_step` of them per call when that is set; when the batch is
    /// complete, begin its search.
    pub(super) fn continue_batch(&mut self) {
        let Some(mut b) = self.st.sampling.take() else { return };
        let batch = self.st.params.samples_per_batch as usize;
        let limit = match self.st.params.draws_per_step {
            0 => usize::MAX,
            n => n as usize,
        };
        let mut draws = 0usize;
        while b.draws_left > 0 && b.added < batch && draws < limit {
            b.draws_left -= 1;
            draws += 1;
            match self.draw_one(&mut b.catch) {
                Draw::Added => b.added += 1,
                Draw::Rejected => {}
                Draw::ArenaFull => {
                    self.st.pending_full = Some(Arena::Nodes);
                    b.draws_left = 0;
                }
            }
        }
        if b.draws_left > 0 && b.added < batch {
            self.st.sampling = Some(b);
            return;
        }
        self.begin_batch_search();
    }

    /// The search of a drawn batch: the initial inflation factor, from the start's edges.
    fn begin_batch_search(&mut self) {
        self.st.inflation = self.st.params.initial_inflation_factor;
        let arena = &mut *self.arena;
        arena.queue.clear(arena.graph.nodes_mut());
        self.st.search_id = self.st.search_id.wrapping_add(1);
        self.insert_outgoing_edges(START, false);
        self.st.final_search = false;
        self.st.truncation = 1.0 + self.st.params.truncation_scaling_parameter / self.arena.graph.ompl_graph_size();
        self.st.search_done = false;
    }

    /// The final search of a batch: less inflation, re-key the queue, re-expand the inconsistent vertices.
    pub(super) fn start_final_search(&mut self) {
        self.st.inflation = 1.0 + self.st.params.inflation_scaling_parameter / self.arena.graph.ompl_graph_size();
        let arena = &mut *self.arena;
        arena.queue.rekey_all(arena.graph.nodes(), self.st.inflation);
        for i in 0..self.arena.graph.nodes().len() as u32 {
            let inconsistent = self.node(i).is_some_and(|n| n.has(F_INCONSISTENT) && n.in_tree());
            if inconsistent {
                self.insert_outgoing_edges(i, true);
            }
        }
        self.st.final_search = true;
        self.st.search_done = false;
    }

    /// A new sample: near a catch boundary (a fraction `catch_sample_fraction` of the draws, non-Markovian
    /// spaces), else uniform before the first solution and informed after it.
    fn draw_sample(&mut self, catch_histories: &mut CatchHistories) -> Option<S::State> {
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

    /// Draw a batch (OMPL's `ImplicitGraph::addNewSamples`): the RGG terms for the states so far, then up to
    /// `samples_per_batch` valid samples, some with a copied attachment.
    fn new_batch(&mut self) {
        self.st.counters.batches += 1;
        self.arena.graph.set_batch(self.st.counters.batches);
        let batch = self.st.params.samples_per_batch as usize;
        // RGG terms for the number of states we have (OMPL: plus the batch on the very first batch).
        // OMPL counts the states before the recycled ones (vertices disconnected by the last pruning and kept
        // as samples) are added back.
        let mut q = self.arena.graph.live().saturating_sub(self.st.recycled);
        self.st.recycled = 0;
        if q == 1 + self.arena.graph.goals().len() {
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

        let catch_histories = if S::NON_MARKOVIAN && self.st.params.catch_sample_fraction > 0.0 {
            self.arena.graph.distinct_attachment_vertices(&*self.space)
        } else {
            CatchHistories::new()
        };
        let draws_left = self.st.params.sample_attempts_per_sample as usize * batch;
        self.st.sampling = Some(BatchSampling { draws_left, added: 0, catch: catch_histories });
    }

    /// One draw of a batch: a sample, checked, with a copied attachment perhaps, into the graph.
    fn draw_one(&mut self, catch_histories: &mut CatchHistories) -> Draw {
        let Some(x) = self.draw_sample(catch_histories) else { return Draw::Rejected };
        self.st.counters.states_checked += 1;
        if !self.validity.is_valid(&x) {
            return Draw::Rejected;
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
                return Draw::Rejected;
            }
        }
        if self.alloc(x, attachment, 0).is_none() {
            return Draw::ArenaFull;
        }
        self.st.counters.samples_added += 1;
        Draw::Added
    }
}

/// What one draw of a batch gave.
enum Draw {
    /// A valid sample went into the graph.
    Added,
    /// Nothing drawn, or the draw was invalid.
    Rejected,
    /// No node left for a valid sample.
    ArenaFull,
}
