//! Non-Markovian attachments (Paton et al. V-A and this project's extensions): history twins, revealing edges,
//! the attachment a new sample copies, and catch-boundary samples. The graph's side ([`ImplicitGraph`]'s methods
//! here) compares the attachments its nodes hold; the planner's side creates twins, predicts attachments and
//! draws what a new sample needs.

use heapless::Vec;
use rand_core::Rng;

use crate::config::abit as cfg;

use crate::plan::space::{uniform01, Arena, CatchSample, OptimizationObjective, StateSpace};
use super::graph::ImplicitGraph;
use super::node::{Node, F_GOAL, F_TWIN};
use super::AbitStar;

/// The tree vertices whose histories a batch's catch-boundary samples follow (one per compatibility class).
pub(super) type CatchHistories = Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }>;

impl<St, A, const NV: usize> ImplicitGraph<St, A, NV> {
    /// Does one of the nodes `of` hold an attachment compatible with `att`?
    fn any_compatible<S>(&self, space: &S, of: &[u32], att: &A) -> bool
    where
        S: StateSpace<State = St, Attachment = A>,
    {
        of.iter().any(|&j| {
            let other = self.node(j).and_then(|n| n.attachment.as_ref());
            other.is_some_and(|b| space.attachments_compatible(att, b))
        })
    }

    /// Do `u` (the parent) and `w` — a tree vertex, or a sample that copied an attachment — hold incompatible
    /// attachments? (The parent's own attachment stands in for the motion's result, which is only known after the
    /// motion check.) A sample that copied one history must not lock out every other history: the edge goes to a
    /// twin of undetermined history instead.
    pub(super) fn histories_conflict<S>(&self, space: &S, u: u32, w: u32) -> bool
    where
        S: StateSpace<State = St, Attachment = A>,
    {
        let (Some(un), Some(wn)) = (self.node(u), self.node(w)) else { return false };
        match (un.attachment.as_ref(), wn.attachment.as_ref()) {
            (Some(a), Some(b)) => !space.attachments_compatible(a, b),
            _ => false,
        }
    }

    /// The distinct (mutually incompatible) attachments among the `k` tree vertices nearest to `state`, one
    /// vertex each, in order of distance (deterministic). Bounded by the arena size and `NEIGHBOUR_CAPACITY`.
    fn distinct_nearby_attachments<S>(&self, space: &S, state: &St, k: usize) -> Vec<u32, { cfg::NEIGHBOUR_CAPACITY }>
    where
        S: StateSpace<State = St, Attachment = A>,
    {
        let admit = |n: &Node<St, A>| n.in_tree() && n.attachment.is_some();
        let (near, _) = self.nearest(space, state, k.clamp(1, cfg::NEIGHBOUR_CAPACITY), f64::INFINITY, admit);
        let mut distinct: Vec<u32, { cfg::NEIGHBOUR_CAPACITY }> = Vec::new();
        for &(_, i) in near.iter() {
            let Some(att) = self.node(i).and_then(|n| n.attachment.as_ref()) else { continue };
            if !self.any_compatible(space, &distinct, att) {
                let _ = distinct.push(i);
            }
        }
        distinct
    }

    /// One tree vertex per distinct attachment (compatibility class), in arena order, up to
    /// `CATCH_ATTACHMENT_CAPACITY`: the histories whose catch boundaries a batch samples. Bounded by the arena
    /// size times that capacity.
    pub(super) fn distinct_attachment_vertices<S>(&self, space: &S) -> CatchHistories
    where
        S: StateSpace<State = St, Attachment = A>,
    {
        let mut distinct = CatchHistories::new();
        for (i, n) in self.nodes().iter().enumerate() {
            let Some(att) = n.attachment.as_ref().filter(|_| n.in_tree()) else { continue };
            if !self.any_compatible(space, &distinct, att) && distinct.push(i as u32).is_err() {
                break;
            }
        }
        distinct
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    O: OptimizationObjective<S>,
{
    /// Would the motion from tree vertex `u` into tree vertex `w` give `w` an attachment incompatible with the one
    /// it holds? From the memo when the motion was checked, else from the space's prediction
    /// ([`StateSpace::predict_attachment`]); `false` when neither knows.
    pub(super) fn reveals_attachment(&mut self, u: u32, w: u32) -> bool {
        let predicted = match self.arena.memo.get(self.arena.graph.nodes(), u, w) {
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
    pub(super) fn twin_for_attachment(&mut self, v: u32, att: &S::Attachment) -> Option<u32> {
        let mut cur = v;
        for _ in 0..cfg::MAX_HISTORY_TWINS {
            let fits = match self.node(cur)?.attachment.as_ref() {
                None => true,
                Some(existing) => self.space.attachments_compatible(att, existing),
            };
            if fits {
                return Some(cur);
            }
            match self.arena.graph.live_twin(cur) {
                Some(twin) => cur = twin,
                None => return self.new_twin(cur),
            }
        }
        None
    }

    /// A twin of `cur`'s state with undetermined attachment, linked as `cur`'s twin.
    pub(super) fn new_twin(&mut self, cur: u32) -> Option<u32> {
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
        if let Some(n) = self.arena.graph.node_mut(created) {
            n.flags |= F_TWIN;
        }
        let generation = self.node(created).map_or(0, |n| n.generation);
        if let Some(n) = self.arena.graph.node_mut(cur) {
            n.twin = created;
            n.twin_generation = generation;
        }
        Some(created)
    }

    /// The node an edge from `u` into the state of `v` should target: `v` itself, or the first twin of `v` that
    /// is unconnected or of a compatible history, creating a twin with undetermined history at the end of the
    /// chain if there is room (`MAX_HISTORY_TWINS`). `None` if no target is possible.
    pub(super) fn twin_target(&mut self, u: u32, v: u32) -> Option<u32> {
        match self.node(u)?.attachment.clone() {
            Some(att) => self.twin_for_attachment(v, &att),
            None => Some(v),
        }
    }
}

/// What a new sample draws: its copied attachment and catch-boundary states.
impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    O: OptimizationObjective<S>,
    R: Rng,
{
    /// The attachment a new sample copies (Paton et al. V-A): one of the distinct (mutually incompatible)
    /// attachments among the k nearest tree vertices, chosen uniformly, so rare histories (the one anchored on the
    /// column, Fig. 7d) are copied as often as the common one. Bounded by the arena size and `NEIGHBOUR_CAPACITY`.
    pub(super) fn copied_attachment(&mut self, state: &S::State) -> Option<S::Attachment> {
        let distinct = self.arena.graph.distinct_nearby_attachments(self.space, state, self.st.k);
        if distinct.is_empty() {
            return None;
        }
        let pick = ((uniform01(self.rng) * distinct.len() as f64) as usize).min(distinct.len() - 1);
        distinct.get(pick).and_then(|&i| self.node(i)).and_then(|n| n.attachment.clone())
    }

    /// A sample near the catch boundary of one of `histories` (chosen uniformly), kept only if it can improve
    /// the solution (informed set by rejection, as for uniform draws). A history whose boundary the space did
    /// not find leaves `histories` for the rest of the batch, so a root anchor that sees the whole planning area
    /// costs one search per batch, not one per draw.
    pub(super) fn catch_sample(&mut self, histories: &mut CatchHistories) -> Option<S::State> {
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
}
