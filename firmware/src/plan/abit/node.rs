//! A node of the implicit graph (OMPL's `Vertex`): its state, attachment, tree links, costs and flags.

use crate::plan::space::Cost;

use super::NONE;

pub(super) const F_IN_TREE: u8 = 1;
pub(super) const F_FREE: u8 = 2;
pub(super) const F_START: u8 = 4;
pub(super) const F_GOAL: u8 = 8;
pub(super) const F_INCONSISTENT: u8 = 16;
/// A history twin (see `twin_target`): reached through the chain of its state's original node, never listed as a
/// neighbour itself (twins at one state would otherwise crowd the k nearest out of the neighbour lists).
pub(super) const F_TWIN: u8 = 32;

/// A state of the implicit graph: a sample, or a vertex of the tree when `in_tree`.
#[derive(Debug, Clone)]
pub struct Node<St, A> {
    /// The state.
    pub state: St,
    /// Its attachment: `None` while undetermined (unconnected sample that did not copy one).
    pub attachment: Option<A>,
    pub(super) parent: u32,
    pub(super) first_child: u32,
    pub(super) next_sibling: u32,
    pub(super) edge_cost: Cost,
    pub(super) cost: Cost,
    pub(super) h_come: Cost,
    pub(super) h_go: Cost,
    pub(super) generation: u32,
    pub(super) expanded_search: u32,
    pub(super) first_out: u32,
    pub(super) twin: u32,
    pub(super) twin_generation: u32,
    /// The batch during which the node was allocated (the age `ImplicitGraph::evict_oldest_samples` frees by).
    pub(super) born: u32,
    pub(super) flags: u8,
}

impl<St, A> Node<St, A> {
    pub(super) fn has(&self, f: u8) -> bool {
        self.flags & f != 0
    }
    /// Is this node a vertex of the tree?
    pub fn in_tree(&self) -> bool {
        self.has(F_IN_TREE)
    }
    /// Parent index in the arena, if connected and not the root.
    pub fn parent(&self) -> Option<u32> {
        (self.parent != NONE).then_some(self.parent)
    }
    /// Cost-to-come through the tree (`INFINITY` if not connected).
    pub fn cost(&self) -> Cost {
        self.cost
    }
}

