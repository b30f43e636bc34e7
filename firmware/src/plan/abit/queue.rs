//! The edge queue (OMPL's `SearchQueue`): queued edges in a slab ordered by the indexed heap of
//! [`crate::plan::heap`], each in its parent's list of queued outgoing edges, and the expansion of a vertex into
//! its outgoing edges.

use heapless::Vec;
use rand_core::Rng;

use crate::plan::heap::{HeapItems, NOT_IN_HEAP};
use crate::plan::space::{
    Arena, Cost, GoalRegion, MotionValidator, OptimizationObjective, StateSpace, StateValidityChecker,
};
use super::node::{F_FREE, F_INCONSISTENT, F_START, F_TWIN};
use super::{AbitStar, NONE};

/// A queued edge `parent -> child`: a slot of the arena's edge slab.
#[derive(Debug, Clone, Copy)]
pub(super) struct QueueEdge {
    /// `[g(u) + c^(u,v) + eps h^(v), g(u) + c^(u,v), g(u)]`, compared lexicographically.
    pub(super) key: [f64; 3],
    /// The heuristic edge cost `c^(u,v)`.
    pub(super) c_hat: Cost,
    pub(super) parent: u32,
    pub(super) child: u32,
    pub(super) parent_generation: u32,
    pub(super) child_generation: u32,
    /// Position in the heap (`NOT_IN_HEAP` when not queued).
    pub(super) heap_pos: u32,
    /// Next in the parent's list of queued outgoing edges (the free list's link while free).
    pub(super) next_out: u32,
    pub(super) prev_out: u32,
    /// An edge into a tree vertex that cannot improve it, queued because the space predicts that the motion would
    /// give the child another attachment: it goes to a history twin (see `enqueue_conditionally`).
    pub(super) reveals: bool,
}

impl QueueEdge {
    /// The queue order: the key lexicographically, ties by node indices (deterministic).
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

/// The edge slab is what the heap orders: ids are slab slots.
impl<const NQ: usize> HeapItems for Vec<QueueEdge, NQ> {
    fn before(&self, a: u32, b: u32) -> bool {
        match (self.get(a as usize), self.get(b as usize)) {
            (Some(x), Some(y)) => x.before(y),
            _ => false,
        }
    }
    fn set_position(&mut self, id: u32, pos: u32) {
        if let Some(e) = self.get_mut(id as usize) {
            e.heap_pos = pos;
        }
    }
    fn position(&self, id: u32) -> Option<u32> {
        self.get(id as usize).map(|e| e.heap_pos)
    }
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
    // An indexed binary heap (`plan::heap`, OMPL's `BinaryHeap` with element handles) over a slab of edges: every
    // queued edge knows its heap position and sits in its parent's list of queued outgoing edges, so the keys of a
    // vertex's edges are updated as soon as its cost-to-come changes (OMPL's `Vertex::updateCostAndDepth`), and an
    // edge already queued is updated instead of duplicated (OMPL's `enqueueEdge`).

    pub(super) fn edge(&self, slot: u32) -> Option<&QueueEdge> {
        self.arena.edges.get(slot as usize)
    }

    /// Queue a new edge (the caller checked it is not queued yet).
    pub(super) fn queue_insert(&mut self, mut e: QueueEdge) {
        e.heap_pos = NOT_IN_HEAP;
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
        let arena = &mut *self.arena;
        if arena.heap.push(slot, &mut arena.edges).is_err() {
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
    }

    /// Unlink a slab slot from its parent's list and put it on the free list.
    pub(super) fn release_edge(&mut self, slot: u32) {
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
            entry.heap_pos = NOT_IN_HEAP;
        }
        self.st.free_edge = slot;
    }

    /// Take the front edge out of the queue.
    pub(super) fn queue_pop(&mut self) -> Option<QueueEdge> {
        let arena = &mut *self.arena;
        let slot = arena.heap.pop(&mut arena.edges)?;
        let e = self.edge(slot).copied();
        self.release_edge(slot);
        e
    }

    pub(super) fn queue_clear(&mut self) {
        self.arena.heap.clear();
        self.arena.edges.clear();
        self.st.free_edge = NONE;
        for n in self.arena.nodes.iter_mut() {
            n.first_out = NONE;
        }
    }

    /// Re-key every queued edge (new inflation factor) and restore the heap.
    pub(super) fn queue_rebuild(&mut self) {
        let len = self.arena.heap.len();
        for i in 0..len {
            let Some(slot) = self.arena.heap.get(i) else { continue };
            let Some(e) = self.edge(slot).copied() else { continue };
            let key = self.sort_key(e.parent, e.child, e.c_hat);
            if let Some(entry) = self.arena.edges.get_mut(slot as usize) {
                entry.key = key;
            }
        }
        let arena = &mut *self.arena;
        arena.heap.heapify(&mut arena.edges);
    }

    /// Re-key the queued outgoing edges of `v` after its cost-to-come changed. Bounded by the slab size.
    pub(super) fn update_out_edges(&mut self, v: u32) {
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
            let arena = &mut *self.arena;
            arena.heap.update(slot, &mut arena.edges);
            slot = e.next_out;
        }
    }

    /// The slab slot of the queued edge `parent -> child`, if queued. Bounded by the slab size.
    pub(super) fn find_queued(&self, parent: u32, child: u32) -> Option<u32> {
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

    pub(super) fn sort_key(&self, parent: u32, child: u32, c_hat: Cost) -> [f64; 3] {
        let g = self.g(parent);
        let h = self.node(child).map_or(f64::INFINITY, |n| n.h_go);
        [g + c_hat + self.st.inflation * h, g + c_hat, g]
    }

    /// Drop entries at the front whose nodes left the tree or were freed (only possible across prunings, which
    /// clear the queue; kept as a guard). Bounded by the queue length.
    pub(super) fn clean_front(&mut self) {
        let budget = self.arena.heap.len() + 1;
        for _ in 0..budget {
            let Some(front) = self.arena.heap.peek().and_then(|s| self.edge(s)).copied() else {
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
            let _ = self.queue_pop();
        }
    }

    pub(super) fn enqueue_conditionally(&mut self, parent: u32, child: u32) {
        let conflict = self.twins_enabled() && self.histories_conflict(parent, child);
        if conflict {
            // The edge will go to a twin of the child; only a known-invalid motion rules it out.
            if matches!(self.arena.memo_get(parent, child), Some(None)) {
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
            if let Some(e) = self.arena.edges.get_mut(slot as usize) {
                e.key = key;
                e.reveals = reveals;
            }
            let arena = &mut *self.arena;
            arena.heap.update(slot, &mut arena.edges);
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
    pub(super) fn insert_outgoing_edges(&mut self, v: u32, reexpansion: bool) {
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
}
