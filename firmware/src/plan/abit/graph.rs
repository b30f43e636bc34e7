//! The implicit graph and its tree (OMPL's `ImplicitGraph`): [`ImplicitGraph`] keeps the nodes of the arena with
//! their free list and the goal vertices, finds nearest neighbours, links and unlinks tree edges, and prunes (OMPL's
//! `ImplicitGraph::prune`). It needs no part of the problem: heuristics come in with a new node, the space only
//! for distances. The planner's side here gives a new node its heuristics, adds an edge to the tree and tracks
//! the best goal.

use heapless::Vec;

use crate::config::abit as cfg;

use crate::plan::space::{Cost, OptimizationObjective, StateSpace};
use super::node::{Node, F_FREE, F_GOAL, F_INCONSISTENT, F_IN_TREE, F_START, F_TWIN};
use super::{AbitStar, Connection, NONE};

/// A list of nearest nodes: `(distance, node)`, nearest first.
pub(super) type Nearest = Vec<(f64, u32), { cfg::NEIGHBOUR_CAPACITY }>;

/// The nodes (start, goals, samples and vertices) in `NV` arena slots, a free list of released slots, and the
/// goal vertices.
pub(super) struct ImplicitGraph<St, A, const NV: usize> {
    nodes: Vec<Node<St, A>, NV>,
    /// First free slot (the free list is linked through `next_sibling`), `NONE` when empty.
    free_head: u32,
    /// Live nodes: start, goals, samples and vertices.
    live: usize,
    /// The goal vertices: the sampled goal, its history twins and the fresh goals of Paton et al. V-A.
    goals: Vec<u32, { cfg::GOAL_CAPACITY }>,
    /// The current batch (stamped on each new node as its `born`).
    batch: u32,
}

impl<St, A, const NV: usize> ImplicitGraph<St, A, NV> {
    /// An empty graph (const, so the arena can be a `static`).
    pub(super) const fn new() -> Self {
        Self { nodes: Vec::new(), free_head: NONE, live: 0, goals: Vec::new(), batch: 0 }
    }

    /// Forget every node.
    pub(super) fn clear(&mut self) {
        self.nodes.clear();
        self.free_head = NONE;
        self.live = 0;
        self.goals.clear();
        self.batch = 0;
    }

    /// The batch that new nodes belong to from now on.
    pub(super) fn set_batch(&mut self, batch: u32) {
        self.batch = batch;
    }

    /// The node in slot `i`, free slots included; `None` past the end.
    pub(super) fn node(&self, i: u32) -> Option<&Node<St, A>> {
        self.nodes.get(i as usize)
    }

    pub(super) fn node_mut(&mut self, i: u32) -> Option<&mut Node<St, A>> {
        self.nodes.get_mut(i as usize)
    }

    /// Every slot in use, free ones included (index = node id).
    pub(super) fn nodes(&self) -> &[Node<St, A>] {
        &self.nodes
    }

    pub(super) fn nodes_mut(&mut self) -> &mut [Node<St, A>] {
        &mut self.nodes
    }

    /// Live nodes (start, goals, samples and vertices).
    pub(super) fn live(&self) -> usize {
        self.live
    }

    /// The goal vertices.
    pub(super) fn goals(&self) -> &[u32] {
        &self.goals
    }

    pub(super) fn goals_full(&self) -> bool {
        self.goals.is_full()
    }

    /// Cost-to-come of node `i` (`INFINITY` when not connected or no such node).
    pub(super) fn g(&self, i: u32) -> Cost {
        self.node(i).map_or(f64::INFINITY, |n| n.cost)
    }

    /// Put a state with its heuristics `(h_come, h_go)` in a free slot (reused first). `None` when the arena is
    /// full.
    pub(super) fn alloc(&mut self, state: St, attachment: Option<A>, flags: u8, h: (Cost, Cost)) -> Option<u32> {
        let (h_come, h_go) = h;
        let born = self.batch;
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
            born,
            flags,
        };
        let index = if self.free_head != NONE {
            let i = self.free_head;
            let slot = self.nodes.get_mut(i as usize)?;
            self.free_head = slot.next_sibling;
            let generation = slot.generation.wrapping_add(1);
            *slot = fresh(generation);
            i
        } else {
            let i = self.nodes.len() as u32;
            self.nodes.push(fresh(0)).ok()?;
            i
        };
        self.live += 1;
        Some(index)
    }

    /// Release slot `i` to the free list (a new generation, so memo entries and queued edges of the old node
    /// become stale).
    pub(super) fn free(&mut self, i: u32) {
        let head = self.free_head;
        if let Some(n) = self.node_mut(i) {
            n.flags = F_FREE;
            n.generation = n.generation.wrapping_add(1);
            n.parent = NONE;
            n.first_child = NONE;
            n.next_sibling = head;
            n.cost = f64::INFINITY;
            n.attachment = None;
            self.free_head = i;
            self.live = self.live.saturating_sub(1);
        }
    }

    /// Frees unconnected samples, those of the oldest batch first (slot order within a batch), until at most
    /// `target_live` nodes are live or no such sample is left; returns how many it freed. Never the start, a goal,
    /// a tree vertex, or a state whose history twin is alive (edges into the state reach the twin through it; an
    /// unconnected twin can go, and then its state). Each pass scans the slots once and frees the oldest batch's
    /// samples, so there are at most as many passes as live nodes.
    pub(super) fn evict_oldest_samples(&mut self, target_live: usize) -> usize {
        let mut freed = 0;
        for _ in 0..NV {
            if self.live <= target_live {
                break;
            }
            let slots = 0..self.nodes.len() as u32;
            let oldest = slots.filter(|&i| self.evictable(i)).filter_map(|i| self.node(i)).map(|n| n.born).min();
            let Some(oldest) = oldest else { break };
            for i in 0..self.nodes.len() as u32 {
                if self.live <= target_live {
                    break;
                }
                if self.evictable(i) && self.node(i).is_some_and(|n| n.born == oldest) {
                    self.free(i);
                    freed += 1;
                }
            }
        }
        freed
    }

    /// Is node `i` an unconnected sample that [`Self::evict_oldest_samples`] may free?
    fn evictable(&self, i: u32) -> bool {
        let Some(n) = self.node(i) else { return false };
        if n.flags & (F_FREE | F_START | F_GOAL | F_IN_TREE) != 0 {
            return false;
        }
        self.live_twin(i).is_none()
    }

    /// Node `i`'s history twin, if it is still the node it was linked to (not freed, its slot not reused).
    pub(super) fn live_twin(&self, i: u32) -> Option<u32> {
        let n = self.node(i)?;
        self.node(n.twin).is_some_and(|t| t.generation == n.twin_generation && !t.has(F_FREE)).then_some(n.twin)
    }

    /// A new goal vertex. `None` when the goal list (`GOAL_CAPACITY`) or the arena is full.
    pub(super) fn add_goal(&mut self, goal: St, h: (Cost, Cost)) -> Option<u32> {
        if self.goals.is_full() {
            return None;
        }
        let i = self.alloc(goal, None, F_GOAL, h)?;
        // Cannot fail: checked not full above.
        let _ = self.goals.push(i);
        Some(i)
    }

    /// The `cap` (at most `NEIGHBOUR_CAPACITY`) nodes nearest to `center` within `radius` among those `admit`
    /// accepts, nearest first (ties by index), and whether one within `radius` was left out for want of room.
    /// Bounded by the arena size times `cap`.
    pub(super) fn nearest<S>(
        &self,
        space: &S,
        center: &St,
        cap: usize,
        radius: f64,
        admit: impl Fn(&Node<St, A>) -> bool,
    ) -> (Nearest, bool)
    where
        S: StateSpace<State = St>,
    {
        let mut out = Nearest::new();
        let cap = cap.min(cfg::NEIGHBOUR_CAPACITY);
        let mut left_out = false;
        for (i, n) in self.nodes.iter().enumerate() {
            if !admit(n) {
                continue;
            }
            let d = space.distance(center, &n.state);
            if d > radius || cap == 0 {
                continue;
            }
            let entry = (d, i as u32);
            if out.len() == cap {
                left_out = true;
                match out.last() {
                    Some(last) if entry < *last => {
                        let _ = out.pop();
                    }
                    _ => continue,
                }
            }
            // Insertion sort (bounded by NEIGHBOUR_CAPACITY).
            // `push`, then swap down to `pos`, rather than heapless' `insert` or `rotate_right`, whose index and
            // length assertions are panic paths the optimiser does not remove (the flight build is proven
            // panic-free, `.ci/run`): the same order, and a loop bounded by NEIGHBOUR_CAPACITY.
            let pos = out.iter().position(|e| entry < *e).unwrap_or(out.len());
            if out.push(entry).is_ok() {
                let mut j = out.len().saturating_sub(1);
                while j > pos {
                    if let Some([a, b]) = out.get_mut(j - 1..=j) {
                        core::mem::swap(a, b);
                    }
                    j -= 1;
                }
            }
        }
        (out, left_out)
    }

    /// The RGG neighbours of node `of` (OMPL's `nearestSamples`): its `k` nearest nodes (the node itself included,
    /// as in OMPL) or the nodes within `r`, history twins left out (they are reached through their state's
    /// original node). Also whether the list was cut at `NEIGHBOUR_CAPACITY`.
    pub(super) fn neighbours<S>(&self, space: &S, of: u32, connection: Connection, k: usize, r: f64) -> (Nearest, bool)
    where
        S: StateSpace<State = St>,
    {
        let Some(center) = self.node(of).map(|n| &n.state) else {
            return (Nearest::new(), false);
        };
        let admit = |n: &Node<St, A>| !n.has(F_FREE) && !n.has(F_TWIN);
        match connection {
            Connection::KNearest => {
                let (out, _) = self.nearest(space, center, k, f64::INFINITY, admit);
                (out, k > cfg::NEIGHBOUR_CAPACITY)
            }
            Connection::RDisc => self.nearest(space, center, usize::MAX, r, admit),
        }
    }

    /// A vertex is expanded on the current search once one of its outgoing edges has been processed (OMPL's
    /// `registerExpansion`); a vertex improved after that is inconsistent and re-expanded in the final search.
    pub(super) fn register_expansion(&mut self, u: u32, search: u32) {
        if let Some(n) = self.node_mut(u) {
            n.expanded_search = search;
        }
    }

    pub(super) fn unlink_from_parent(&mut self, child: u32) {
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

    /// Make `parent -> child` a tree edge (moving `child` from its old parent, a rewiring, if it was in the tree)
    /// with the child's new cost-to-come and attachment. Returns whether it was a rewiring. The child's
    /// descendants keep their old costs: see `AbitArena::propagate_costs`.
    pub(super) fn link(&mut self, parent: u32, child: u32, edge_cost: Cost, attachment: A) -> bool {
        let rewiring = self.node(child).is_some_and(|n| n.in_tree());
        if rewiring {
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
        rewiring
    }

    /// Set `i`'s cost-to-come from its parent's and its edge cost.
    pub(super) fn update_cost_from_parent(&mut self, i: u32) {
        let (parent, edge_cost) = self.node(i).map_or((NONE, 0.0), |n| (n.parent, n.edge_cost));
        let g = self.g(parent) + edge_cost;
        if let Some(n) = self.node_mut(i) {
            n.cost = g;
        }
    }

    /// The node after `cur` in a pre-order walk of `root`'s subtree (via the parent links), `NONE` at the end.
    /// Bounded by the arena size.
    pub(super) fn next_in_subtree(&self, cur: u32, root: u32) -> u32 {
        let first_child = self.node(cur).map_or(NONE, |n| n.first_child);
        if first_child != NONE {
            return first_child;
        }
        // Climb until a node with a next sibling, stopping at root.
        let mut up = cur;
        for _ in 0..NV {
            if up == root || up == NONE {
                break;
            }
            let (sib, par) = self.node(up).map_or((NONE, NONE), |n| (n.next_sibling, n.parent));
            if sib != NONE {
                return sib;
            }
            up = par;
        }
        NONE
    }

    /// The goal vertex in the tree of least cost-to-come below `bound` (the first of equals), if any.
    pub(super) fn cheapest_goal(&self, bound: Cost) -> Option<(Cost, u32)> {
        let mut best = None;
        let mut bound = bound;
        for &gi in self.goals.iter() {
            if let Some(n) = self.node(gi) {
                if n.in_tree() && n.cost < bound {
                    bound = n.cost;
                    best = Some((n.cost, gi));
                }
            }
        }
        best
    }

    /// Is there a goal vertex outside the tree with undetermined attachment (one a better path can still reach)?
    pub(super) fn has_open_goal(&self) -> bool {
        self.goals.iter().any(|&gi| self.node(gi).is_some_and(|n| !n.in_tree() && n.attachment.is_none()))
    }

    /// OMPL's `numSamples() + numVertices()`: live states (samples and vertices) plus tree vertices, the `q` of
    /// the truncation and final-search inflation factors and of the pruning threshold. Bounded by the arena size.
    pub(super) fn ompl_graph_size(&self) -> f64 {
        let vertices = self.nodes.iter().filter(|n| n.in_tree() && !n.has(F_FREE)).count();
        ((self.live + vertices).max(1)) as f64
    }

    /// Prune for a solution of cost `best` reached at goal vertex `best_goal` (OMPL's `ImplicitGraph::prune`), if
    /// at least `prune_fraction` of the states cannot improve it: samples with `h(start,x) + h(x,goal) >= best`
    /// are dropped, vertices with `g(x) + h(x,goal) > best` leave the tree (kept as samples while they can still
    /// help). `new_generations`: a vertex that leaves the tree becomes a new node for the memo (non-Markovian
    /// spaces: a motion's result depends on the attachment the next connection gives it). Returns the number of
    /// vertices kept as samples ("recycled"), `None` when the graph was not pruned.
    pub(super) fn prune(
        &mut self,
        best: Cost,
        best_goal: u32,
        prune_fraction: f64,
        new_generations: bool,
    ) -> Option<usize> {
        let total = self.ompl_graph_size();
        let prunable =
            self.nodes.iter().filter(|n| !n.has(F_FREE) && !n.has(F_START) && n.h_come + n.h_go >= best).count();
        if (prunable as f64) / total < prune_fraction {
            return None;
        }
        let mut recycled = 0;
        let len = self.nodes.len();
        // Pass 1: disconnect vertices that cannot be on a better path; drop samples that cannot help.
        for i in 0..len as u32 {
            let Some(n) = self.node(i) else { continue };
            if n.has(F_FREE) || n.has(F_START) {
                continue;
            }
            if n.in_tree() {
                if i != best_goal && n.cost + n.h_go > best {
                    self.disconnect(i, best, new_generations);
                    // Kept as a sample: OMPL "recycles" it, i.e. it rejoins the samples only after the next
                    // batch's RGG terms are computed.
                    if self.node(i).is_some_and(|n| !n.has(F_FREE)) {
                        recycled += 1;
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
                        self.disconnect(i, best, new_generations);
                        changed = true;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        Some(recycled)
    }

    /// Take a vertex out of the tree; keep it as a sample if it can still help a solution of cost `best`,
    /// otherwise free it. Its children are orphaned (the caller's sweep disconnects them).
    fn disconnect(&mut self, i: u32, best: Cost, new_generation: bool) {
        self.unlink_from_parent(i);
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
        let Some(n) = self.node_mut(i) else { return };
        n.first_child = NONE;
        n.flags &= !(F_IN_TREE | F_INCONSISTENT);
        n.cost = f64::INFINITY;
        n.attachment = None;
        // The generation keys the memo (OMPL's per-vertex black/white lists, which survive pruning); in Markovian
        // spaces the memo of a recycled state stays valid, as in OMPL.
        if new_generation {
            n.generation = n.generation.wrapping_add(1);
        }
        let keep = n.has(F_GOAL) || n.h_come + n.h_go < best;
        if !keep {
            self.free(i);
        }
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    O: OptimizationObjective<S>,
{
    /// `(h(start, x), h(x, goal))`: the heuristics a node carries.
    pub(super) fn heuristics(&self, state: &S::State) -> (Cost, Cost) {
        let obj = &self.pdef.objective;
        let h_come = obj.motion_cost_heuristic(self.space, &self.pdef.start, state);
        let h_go = self.st.goal_state.as_ref().map_or(f64::INFINITY, |g| obj.motion_cost_heuristic(self.space, state, g));
        (h_come, h_go)
    }

    /// A new node for `state`. `None` when the arena is full.
    pub(super) fn alloc(&mut self, state: S::State, attachment: Option<S::Attachment>, flags: u8) -> Option<u32> {
        let h = self.heuristics(&state);
        let i = self.arena.graph.alloc(state, attachment, flags, h)?;
        self.st.high_water.nodes = self.st.high_water.nodes.max(self.arena.graph.live());
        Some(i)
    }

    /// A new goal vertex. `None` when the goal list or the arena is full.
    pub(super) fn add_goal_vertex(&mut self, goal: S::State) -> Option<u32> {
        if self.arena.graph.goals_full() {
            return None;
        }
        let h = self.heuristics(&goal);
        let i = self.arena.graph.add_goal(goal, h)?;
        self.st.high_water.nodes = self.st.high_water.nodes.max(self.arena.graph.live());
        Some(i)
    }

    /// The RGG neighbours of `of` (`ImplicitGraph::neighbours` with this batch's `k` or `r`); a list cut at
    /// `NEIGHBOUR_CAPACITY` is counted.
    pub(super) fn neighbours(&mut self, of: u32) -> Nearest {
        let (connection, k, r) = (self.st.params.connection, self.st.k, self.st.r);
        let (out, truncated) = self.arena.graph.neighbours(&*self.space, of, connection, k, r);
        if truncated {
            self.st.counters.neighbour_lists_truncated += 1;
        }
        out
    }

    /// Add the checked edge `parent -> child` to the tree (OMPL's `BITstar::addEdge`): the child's and its
    /// descendants' costs and queued edges follow; a child not expanded in this search is expanded, an expanded
    /// one becomes inconsistent (re-expanded by the final search).
    pub(super) fn add_edge(&mut self, parent: u32, child: u32, edge_cost: Cost, attachment: S::Attachment) {
        if self.arena.graph.link(parent, child, edge_cost, attachment) {
            self.st.counters.rewirings += 1;
        }
        self.arena.rekey_out_edges(child, self.st.inflation);
        self.arena.propagate_costs(child, self.st.inflation);
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
        } else if let Some(n) = self.arena.graph.node_mut(child) {
            n.flags |= F_INCONSISTENT;
        }
    }

    /// Recompute the best goal; true if the solution improved. In non-Markovian spaces a fresh goal with
    /// undetermined attachment follows an improvement (Paton et al. V-A) unless one is still open.
    pub(super) fn update_goal(&mut self) -> bool {
        let Some((cost, goal)) = self.arena.graph.cheapest_goal(self.st.best_cost) else {
            return false;
        };
        self.st.best_cost = cost;
        self.st.best_goal = goal;
        self.st.counters.improvements += 1;
        if self.st.counters.first_solution_iteration == 0 {
            self.st.counters.first_solution_iteration = self.st.counters.iterations;
        }
        if S::NON_MARKOVIAN && self.st.params.fresh_goal_on_improvement && !self.arena.graph.has_open_goal() {
            if let Some(goal) = self.st.goal_state.clone() {
                // A full goal list or arena only means no fresh goal this time.
                let _ = self.add_goal_vertex(goal);
            }
        }
        true
    }
}
