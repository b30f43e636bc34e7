//! Non-Markovian attachments (Paton et al. V-A and this project's extensions): history twins, revealing edges,
//! the attachment a new sample copies, and catch-boundary samples.

use heapless::Vec;
use rand_core::Rng;

use crate::config::abit as cfg;

use crate::plan::space::{
    uniform01, Arena, CatchSample, GoalRegion, MotionValidator, OptimizationObjective, StateSpace,
    StateValidityChecker,
};
use super::node::{F_FREE, F_GOAL, F_TWIN};
use super::AbitStar;

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    pub(super) fn twins_enabled(&self) -> bool {
        S::NON_MARKOVIAN && self.st.params.history_twins
    }

    /// Would the motion from tree vertex `u` into tree vertex `w` give `w` an attachment incompatible with the one
    /// it holds? From the memo when the motion was checked, else from the space's prediction
    /// ([`StateSpace::predict_attachment`]); `false` when neither knows.
    pub(super) fn reveals_attachment(&mut self, u: u32, w: u32) -> bool {
        let predicted = match self.arena.memo_get(u, w) {
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
    pub(super) fn histories_conflict(&self, u: u32, w: u32) -> bool {
        let (Some(un), Some(wn)) = (self.node(u), self.node(w)) else { return false };
        match (un.attachment.as_ref(), wn.attachment.as_ref()) {
            (Some(a), Some(b)) => !self.space.attachments_compatible(a, b),
            _ => false,
        }
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

    /// The attachment a new sample copies (Paton et al. V-A): one of the distinct (mutually incompatible)
    /// attachments among the k nearest tree vertices, chosen uniformly, so rare histories (the one anchored on the
    /// column, Fig. 7d) are copied as often as the common one. Bounded by the arena size and `NEIGHBOUR_CAPACITY`.
    pub(super) fn copied_attachment(&mut self, state: &S::State) -> Option<S::Attachment> {
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
    pub(super) fn any_compatible(&self, of: &[u32], att: &S::Attachment) -> bool {
        of.iter().any(|&j| {
            let other = self.node(j).and_then(|n| n.attachment.as_ref());
            other.is_some_and(|b| self.space.attachments_compatible(att, b))
        })
    }

    /// One tree vertex per distinct attachment (compatibility class), in arena order, up to
    /// `CATCH_ATTACHMENT_CAPACITY`: the histories whose catch boundaries a batch samples. Bounded by the arena
    /// size times that capacity.
    pub(super) fn distinct_attachment_vertices(&self) -> Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }> {
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
    pub(super) fn catch_sample(&mut self, histories: &mut Vec<u32, { cfg::CATCH_ATTACHMENT_CAPACITY }>) -> Option<S::State> {
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
