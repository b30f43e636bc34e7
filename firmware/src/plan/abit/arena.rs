//! The planner's storage ([`AbitArena`]): the node arena, the edge queue (a slab and its indexed heap) and the
//! edge memo, with their capacities and high-water marks.

use heapless::Vec;

use crate::config::abit as cfg;
use crate::plan::heap::IndexedHeap;

use super::memo::MemoEntry;
use super::node::Node;
use super::queue::QueueEdge;

/// The planner's storage, owned by the caller (a `static` on the board, a `Box` on the host) and lent to
/// [`AbitStar::new`]. Capacities: `NV` nodes, `NQ` queued edges, `NM` memo entries (see `config::abit`).
pub struct AbitArena<St, A, const NV: usize, const NQ: usize, const NM: usize> {
    pub(super) nodes: Vec<Node<St, A>, NV>,
    /// Queued edges (a slab with a free list; slots are stable while queued).
    pub(super) edges: Vec<QueueEdge, NQ>,
    /// The indexed binary heap of slab indices, ordered by the edges' keys.
    pub(super) heap: IndexedHeap<NQ>,
    pub(super) memo: Vec<Option<MemoEntry<A>>, NM>,
}

impl<St, A, const NV: usize, const NQ: usize, const NM: usize> AbitArena<St, A, NV, NQ, NM> {
    /// An empty arena (const, so it can be a `static`).
    pub const fn new() -> Self {
        Self { nodes: Vec::new(), edges: Vec::new(), heap: IndexedHeap::new(), memo: Vec::new() }
    }
    /// Nodes currently used (including freed slots awaiting reuse).
    pub fn nodes_used(&self) -> usize {
        self.nodes.len()
    }
    /// Edges currently queued.
    pub fn queue_len(&self) -> usize {
        self.heap.len()
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

