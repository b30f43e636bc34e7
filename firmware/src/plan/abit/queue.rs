//! The edge queue (OMPL's `SearchQueue`): [`SearchQueue`] keeps the queued edges in a slab ordered by the indexed
//! heap of [`crate::plan::heap`] (OMPL's `BinaryHeap` with element handles), each edge also in its parent's list of
//! queued outgoing edges, so the keys of a vertex's edges are updated as soon as its cost-to-come changes (OMPL's
//! `Vertex::updateCostAndDepth`) and an edge already queued is updated instead of duplicated (OMPL's
//! `enqueueEdge`). It needs only the nodes (their costs, heuristics and lists of queued edges). The planner's side
//! here expands a vertex into its outgoing edges.

use heapless::Vec;

use crate::plan::heap::{Full, HeapSlot, IndexedHeap, NOT_IN_HEAP};
use crate::plan::space::{Arena, Cost, OptimizationObjective, StateSpace};
use super::node::{Node, F_FREE, F_INCONSISTENT, F_START, F_TWIN};
use super::{AbitStar, NONE};

/// A queued edge `parent -> child`: a slot of the queue's edge slab.
#[derive(Debug, Clone, Copy)]
pub(super) struct QueueEdge {
    /// `[g(u) + c^(u,v) + eps h^(v), g(u) + c^(u,v), g(u)]`, compared lexicographically.
    key: [f64; 3],
    /// The heuristic edge cost `c^(u,v)`.
    pub(super) c_hat: Cost,
    pub(super) parent: u32,
    pub(super) child: u32,
    parent_generation: u32,
    child_generation: u32,
    /// Position in the heap (`NOT_IN_HEAP` when not queued).
    heap_pos: u32,
    /// Next in the parent's list of queued outgoing edges (the free list's link while free).
    next_out: u32,
    prev_out: u32,
    /// An edge into a tree vertex that cannot improve it, queued because the space predicts that the motion would
    /// give the child another attachment: it goes to a history twin (see `enqueue_conditionally`).
    pub(super) reveals: bool,
}

/// The edge slab is what the heap orders (ids are slab slots), in the queue order: the key lexicographically, ties
/// by node indices (deterministic).
impl HeapSlot for QueueEdge {
    fn before(&self, _: u32, other: &Self, _: u32) -> bool {
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
    fn heap_position(&self) -> u32 {
        self.heap_pos
    }
    fn set_heap_position(&mut self, pos: u32) {
        self.heap_pos = pos;
    }
}

/// The key of the edge `parent -> child` with heuristic cost `c_hat` under inflation factor `inflation`.
fn sort_key<St, A>(nodes: &[Node<St, A>], parent: u32, child: u32, c_hat: Cost, inflation: f64) -> [f64; 3] {
    let g = nodes.get(parent as usize).map_or(f64::INFINITY, |n| n.cost);
    let h = nodes.get(child as usize).map_or(f64::INFINITY, |n| n.h_go);
    [g + c_hat + inflation * h, g + c_hat, g]
}

/// The queued edges: `NQ` slab slots (with a free list; a slot is stable while queued) and the heap of slots.
pub(super) struct SearchQueue<const NQ: usize> {
    edges: Vec<QueueEdge, NQ>,
    heap: IndexedHeap<NQ>,
    /// First free slab slot (the free list is linked through `next_out`), `NONE` when empty.
    free_edge: u32,
}

impl<const NQ: usize> SearchQueue<NQ> {
    /// An empty queue (const, so the arena can be a `static`).
    pub(super) const fn new() -> Self {
        Self { edges: Vec::new(), heap: IndexedHeap::new(), free_edge: NONE }
    }

    /// Edges queued.
    pub(super) fn len(&self) -> usize {
        self.heap.len()
    }

    pub(super) fn is_empty(&self) -> bool {
        self.heap.is_empty()
    }

    /// Forget every edge; the nodes' lists of queued edges must be reset too (`clear`), or be new.
    pub(super) fn reset(&mut self) {
        self.heap.clear();
        self.edges.clear();
        self.free_edge = NONE;
    }

    /// Empty the queue and the nodes' lists of queued edges.
    pub(super) fn clear<St, A>(&mut self, nodes: &mut [Node<St, A>]) {
        self.reset();
        for n in nodes.iter_mut() {
            n.first_out = NONE;
        }
    }

    fn edge(&self, slot: u32) -> Option<&QueueEdge> {
        self.edges.get(slot as usize)
    }

    /// Queue a new edge (the caller checked it is not queued yet). Returns the queue's length; [`Full`] when the
    /// slab is full (nothing changed).
    fn insert<St, A>(&mut self, nodes: &mut [Node<St, A>], mut e: QueueEdge) -> Result<usize, Full> {
        e.heap_pos = NOT_IN_HEAP;
        e.prev_out = NONE;
        e.next_out = nodes.get(e.parent as usize).map_or(NONE, |n| n.first_out);
        let slot = if self.free_edge != NONE {
            let slot = self.free_edge;
            // Cannot fail: the free list holds slab slots.
            let Some(entry) = self.edges.get_mut(slot as usize) else { return Ok(self.heap.len()) };
            self.free_edge = entry.next_out;
            *entry = e;
            slot
        } else {
            let slot = self.edges.len() as u32;
            self.edges.push(e).map_err(|_| Full)?;
            slot
        };
        if self.heap.push(slot, &mut self.edges[..]).is_err() {
            // Cannot happen (heap and slab have the same capacity); keep the slab consistent anyway.
            self.release(nodes, slot);
            return Err(Full);
        }
        if let Some(next) = self.edges.get_mut(e.next_out as usize) {
            next.prev_out = slot;
        }
        if let Some(p) = nodes.get_mut(e.parent as usize) {
            p.first_out = slot;
        }
        Ok(self.heap.len())
    }

    /// Unlink a slab slot from its parent's list and put it on the free list.
    fn release<St, A>(&mut self, nodes: &mut [Node<St, A>], slot: u32) {
        let Some(e) = self.edge(slot).copied() else { return };
        if e.prev_out == NONE {
            if let Some(p) = nodes.get_mut(e.parent as usize) {
                if p.first_out == slot {
                    p.first_out = e.next_out;
                }
            }
        } else if let Some(prev) = self.edges.get_mut(e.prev_out as usize) {
            prev.next_out = e.next_out;
        }
        if let Some(next) = self.edges.get_mut(e.next_out as usize) {
            next.prev_out = e.prev_out;
        }
        let free = self.free_edge;
        if let Some(entry) = self.edges.get_mut(slot as usize) {
            entry.next_out = free;
            entry.prev_out = NONE;
            entry.heap_pos = NOT_IN_HEAP;
        }
        self.free_edge = slot;
    }

    /// Take the front edge out of the queue.
    pub(super) fn pop<St, A>(&mut self, nodes: &mut [Node<St, A>]) -> Option<QueueEdge> {
        let slot = self.heap.pop(&mut self.edges[..])?;
        let e = self.edge(slot).copied();
        self.release(nodes, slot);
        e
    }

    /// Re-key every queued edge (new inflation factor) and restore the heap.
    pub(super) fn rekey_all<St, A>(&mut self, nodes: &[Node<St, A>], inflation: f64) {
        let len = self.heap.len();
        for i in 0..len {
            let Some(slot) = self.heap.get(i) else { continue };
            if let Some(e) = self.edges.get_mut(slot as usize) {
                e.key = sort_key(nodes, e.parent, e.child, e.c_hat, inflation);
            }
        }
        self.heap.heapify(&mut self.edges[..]);
    }

    /// Re-key the queued outgoing edges of `v` after its cost-to-come changed. Bounded by the slab size.
    pub(super) fn rekey_out_edges<St, A>(&mut self, nodes: &[Node<St, A>], v: u32, inflation: f64) {
        let mut slot = nodes.get(v as usize).map_or(NONE, |n| n.first_out);
        for _ in 0..NQ {
            if slot == NONE {
                break;
            }
            let Some(e) = self.edges.get_mut(slot as usize) else { break };
            e.key = sort_key(nodes, e.parent, e.child, e.c_hat, inflation);
            let next = e.next_out;
            self.heap.update(slot, &mut self.edges[..]);
            slot = next;
        }
    }

    /// The slab slot of the queued edge `parent -> child`, if queued. Bounded by the slab size.
    fn find<St, A>(&self, nodes: &[Node<St, A>], parent: u32, child: u32) -> Option<u32> {
        let mut slot = nodes.get(parent as usize).map_or(NONE, |n| n.first_out);
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

    /// Queue `parent -> child` (heuristic cost `c_hat`), or update its key if it is queued already. Returns the
    /// queue's length; [`Full`] when the slab is full.
    pub(super) fn enqueue<St, A>(
        &mut self,
        nodes: &mut [Node<St, A>],
        (parent, child): (u32, u32),
        c_hat: Cost,
        reveals: bool,
        inflation: f64,
    ) -> Result<usize, Full> {
        let (Some(p), Some(c)) = (nodes.get(parent as usize), nodes.get(child as usize)) else {
            return Ok(self.heap.len());
        };
        let (parent_generation, child_generation) = (p.generation, c.generation);
        let key = sort_key(nodes, parent, child, c_hat, inflation);
        if let Some(slot) = self.find(nodes, parent, child) {
            if let Some(e) = self.edges.get_mut(slot as usize) {
                e.key = key;
                e.reveals = reveals;
            }
            self.heap.update(slot, &mut self.edges[..]);
            return Ok(self.heap.len());
        }
        let edge = QueueEdge {
            key,
            c_hat,
            parent,
            child,
            parent_generation,
            child_generation,
            heap_pos: NOT_IN_HEAP,
            next_out: NONE,
            prev_out: NONE,
            reveals,
        };
        self.insert(nodes, edge)
    }

    /// Drop entries at the front whose nodes left the tree or were freed (only possible across prunings, which
    /// clear the queue; kept as a guard). Bounded by the queue length.
    pub(super) fn clean_front<St, A>(&mut self, nodes: &mut [Node<St, A>]) {
        let budget = self.heap.len() + 1;
        for _ in 0..budget {
            let Some(front) = self.heap.peek().and_then(|s| self.edge(s)).copied() else {
                return;
            };
            let valid = match (nodes.get(front.parent as usize), nodes.get(front.child as usize)) {
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
            let _ = self.pop(nodes);
        }
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    O: OptimizationObjective<S>,
{
    /// Queue the edge `parent -> child` if it can improve the solution and the child (BIT*'s conditions, with the
    /// non-Markovian exceptions: an edge into another history goes to a twin; one that reveals another history
    /// is queued).
    pub(super) fn enqueue_conditionally(&mut self, parent: u32, child: u32) {
        let conflict = self.twins_enabled() && self.histories_conflict(parent, child);
        if conflict {
            // The edge will go to a twin of the child; only a known-invalid motion rules it out.
            if matches!(self.arena.memo.get(self.arena.graph.nodes(), parent, child), Some(None)) {
                return;
            }
        } else if self.arena.memo.blacklisted(self.arena.graph.nodes(), self.space, parent, child) {
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
        let arena = &mut *self.arena;
        match arena.queue.enqueue(arena.graph.nodes_mut(), (parent, child), c_hat, reveals, self.st.inflation) {
            Ok(len) => self.st.high_water.queue = self.st.high_water.queue.max(len),
            Err(Full) => self.st.pending_full = Some(Arena::EdgeQueue),
        }
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
            if let Some(n) = self.arena.graph.node_mut(v) {
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
            for gi in 0..self.arena.graph.goals().len() {
                let Some(&g) = self.arena.graph.goals().get(gi) else { break };
                let listed = neighbours.iter().any(|&(_, w)| w == g);
                if g != v && !listed && self.node(g).is_some_and(|n| !n.has(F_FREE) && !n.has(F_TWIN)) {
                    self.enqueue_conditionally(v, g);
                }
            }
        }
    }
}
