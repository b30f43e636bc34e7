//! Batches (OMPL's `ImplicitGraph::addNewSamples` and `prune`): the RGG terms, drawing the samples (uniform,
//! informed, catch-boundary), copying attachments into them, and pruning before a batch.

use heapless::Vec;
use rand_core::Rng;

use crate::config::abit as cfg;

use crate::geom::unit_ball_measure;
use crate::plan::space::{
    uniform01, Arena, GoalRegion, InformedSample, MotionValidator, OptimizationObjective, StateSpace,
    StateValidityChecker,
};
use super::node::{F_FREE, F_GOAL, F_INCONSISTENT, F_IN_TREE, F_START};
use super::{AbitStar, NONE};

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    pub(super) fn prune(&mut self) {
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
    pub(super) fn disconnect(&mut self, i: u32) {
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

    /// A new sample: near a catch boundary (a fraction `catch_sample_fraction` of the draws, non-Markovian
    /// spaces), else uniform before the first solution and informed after it.
    pub(super) fn draw_sample(&mut self, catch_histories: &mut Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }>) -> Option<S::State> {
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

    pub(super) fn new_batch(&mut self) {
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

    /// OMPL's `numSamples() + numVertices()`: live states (samples and vertices) plus tree vertices, the `q` of
    /// the truncation and final-search inflation factors. Bounded by the arena size.
    pub(super) fn ompl_graph_size(&self) -> f64 {
        let vertices = self.arena.nodes.iter().filter(|n| n.in_tree() && !n.has(F_FREE)).count();
        ((self.st.live_nodes + vertices).max(1)) as f64
    }
}
