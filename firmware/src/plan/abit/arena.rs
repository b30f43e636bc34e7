//! The planner's storage ([`AbitArena`]): the implicit graph (the nodes, `graph.rs`), the edge queue (`queue.rs`)
//! and the edge memo (`memo.rs`), with their capacities, and the one operation that needs both the tree and the
//! queue: propagating a cost change down the tree.

use crate::config::abit as cfg;

use super::graph::ImplicitGraph;
use super::memo::EdgeMemo;
use super::queue::SearchQueue;
use super::NONE;

/// The planner's storage, owned by the caller (a `static` on the board, a `Box` on the host) and lent to
/// [`AbitStar::new`](super::AbitStar::new). Capacities: `NV` nodes, `NQ` queued edges, `NM` memo entries (see
/// `config::abit`).
pub struct AbitArena<St, A, const NV: usize, const NQ: usize, const NM: usize> {
    pub(super) graph: ImplicitGraph<St, A, NV>,
    pub(super) queue: SearchQueue<NQ>,
    pub(super) memo: EdgeMemo<A, NM>,
}

impl<St, A, const NV: usize, const NQ: usize, const NM: usize> AbitArena<St, A, NV, NQ, NM> {
    /// An empty arena (const, so it can be a `static`).
    pub const fn new() -> Self {
        Self { graph: ImplicitGraph::new(), queue: SearchQueue::new(), memo: EdgeMemo::new() }
    }

    /// Nodes currently used (including freed slots awaiting reuse).
    pub fn nodes_used(&self) -> usize {
        self.graph.nodes().len()
    }

    /// Edges currently queued.
    pub fn queue_len(&self) -> usize {
        self.queue.len()
    }

    /// Empty graph, queue and memo, for a new problem.
    pub(super) fn reset(&mut self) {
        self.graph.clear();
        self.queue.reset();
        self.memo.reset();
    }

    /// Re-key the queued outgoing edges of `v` (its cost-to-come changed) under inflation factor `inflation`.
    pub(super) fn rekey_out_edges(&mut self, v: u32, inflation: f64) {
        self.queue.rekey_out_edges(self.graph.nodes(), v, inflation);
    }

    /// Propagate a cost change of `root` to its descendants, re-keying each one's queued edges (a pre-order walk
    /// via parent links, bounded by NV). Only `root` itself joins the inconsistent set (the caller's `add_edge`),
    /// as in OMPL (`BITstar::addEdge`): descendants get their queued edges re-keyed, not re-expanded.
    pub(super) fn propagate_costs(&mut self, root: u32, inflation: f64) {
        let mut cur = self.graph.node(root).map_or(NONE, |n| n.first_child);
        for _ in 0..(2 * NV + 2) {
            if cur == NONE || cur == root {
                return;
            }
            self.graph.update_cost_from_parent(cur);
            self.rekey_out_edges(cur, inflation);
            cur = self.graph.next_in_subtree(cur, root);
        }
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
