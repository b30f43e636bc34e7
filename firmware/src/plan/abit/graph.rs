//! The implicit graph and the tree (OMPL's `ImplicitGraph`): node allocation in the arena and its free list, nearest neighbours, parent / child bookkeeping, cost
//! propagation and the best goal.

use heapless::Vec;
use rand_core::Rng;

use crate::config::abit as cfg;

use crate::plan::space::{
    Cost, GoalRegion, MotionValidator, OptimizationObjective, StateSpace, StateValidityChecker,
};
use super::node::{Node, F_FREE, F_GOAL, F_INCONSISTENT, F_IN_TREE, F_TWIN};
use super::{AbitStar, Connection, NONE};

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    /// The node in arena slot `i` (the index [`Node::parent`] returns), free slots included; `None` past the end.
    pub fn node(&self, i: u32) -> Option<&Node<S::State, S::Attachment>> {
        self.arena.nodes.get(i as usize)
    }

    pub(super) fn node_mut(&mut self, i: u32) -> Option<&mut Node<S::State, S::Attachment>> {
        self.arena.nodes.get_mut(i as usize)
    }

    pub(super) fn g(&self, i: u32) -> Cost {
        self.node(i).map_or(f64::INFINITY, |n| n.cost)
    }

    pub(super) fn heuristics(&self, state: &S::State) -> (Cost, Cost) {
        let obj = &self.pdef.objective;
        let h_come = obj.motion_cost_heuristic(self.space, &self.pdef.start, state);
        let h_go = self.st.goal_state.as_ref().map_or(f64::INFINITY, |g| obj.motion_cost_heuristic(self.space, state, g));
        (h_come, h_go)
    }

    /// Put a state in a free slot (reused first). `None` when the arena is full.
    pub(super) fn alloc(&mut self, state: S::State, attachment: Option<S::Attachment>, flags: u8) -> Option<u32> {
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

    pub(super) fn free(&mut self, i: u32) {
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

    pub(super) fn add_goal_vertex(&mut self, goal: S::State) -> Option<u32> {
        if self.st.goals.is_full() {
            return None;
        }
        let i = self.alloc(goal, None, F_GOAL)?;
        // Cannot fail: checked not full above.
        let _ = self.st.goals.push(i);
        Some(i)
    }

    /// Indices of the k nearest nodes (k-nearest, the node itself included as in OMPL) or of the nodes within r.
    pub(super) fn neighbours(&mut self, of: u32) -> Vec<(f64, u32), { cfg::NEIGHBOUR_CAPACITY }> {
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

    /// A vertex is expanded on the current search once one of its outgoing edges has been processed (OMPL's
    /// `registerExpansion`); a vertex improved after that is inconsistent and re-expanded in the final search.
    pub(super) fn register_expansion(&mut self, u: u32) {
        let search = self.st.search_id;
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

    /// Propagate a cost change of `root` to its descendants (pre-order walk via parent links, bounded by NV).
    pub(super) fn propagate_costs(&mut self, root: u32) {
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

    pub(super) fn add_edge(&mut self, parent: u32, child: u32, edge_cost: Cost, attachment: S::Attachment) {
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
    pub(super) fn update_goal(&mut self) -> bool {
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

    pub(super) fn has_solution(&self) -> bool {
        self.st.best_goal != NONE
    }
}
