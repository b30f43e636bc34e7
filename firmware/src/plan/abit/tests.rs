//! The seams on their own: the implicit graph, the search queue and the edge memo, each driven directly on the real
//! line (the planner as a whole is tested on the geometric problems of `firmware/workloads/tests/abit_geometric.rs`
//! and on the tethered rover in `nav`'s tests).

extern crate std;

use std::vec::Vec as StdVec;

use rand_core::Rng;

use super::graph::ImplicitGraph;
use super::memo::{EdgeMemo, MemoCheck};
use super::node::{F_FREE, F_GOAL, F_IN_TREE, F_START, F_TWIN};
use super::queue::SearchQueue;
use super::{Connection, NONE};
use crate::config::abit::NEIGHBOUR_CAPACITY;
use crate::plan::heap::Full;
use crate::plan::space::{MotionCheck, MotionValidator, StateSpace};

/// The real line: a state is a position, the distance `|a - b|`.
struct Line;

impl StateSpace for Line {
    type State = f64;
    type Attachment = ();
    fn dimension(&self) -> usize {
        1
    }
    fn measure(&self) -> f64 {
        10.0
    }
    fn distance(&self, a: &f64, b: &f64) -> f64 {
        libm::fabs(a - b)
    }
    fn interpolate(&self, a: &f64, b: &f64, t: f64) -> f64 {
        a + (b - a) * t
    }
    fn sample_uniform<R: Rng + ?Sized>(&mut self, _: &mut R) -> Option<f64> {
        None
    }
}

/// Motions shorter than 2 are valid; counts the checks.
struct ShortMotions {
    checks: u32,
}

impl MotionValidator<Line> for ShortMotions {
    fn check_motion(&mut self, _: &Line, from: &f64, _: &(), to: &f64) -> MotionCheck<()> {
        self.checks += 1;
        if libm::fabs(to - from) < 2.0 {
            MotionCheck::Valid { attachment: () }
        } else {
            MotionCheck::Invalid
        }
    }
}

type Graph = ImplicitGraph<f64, (), 16>;

/// Nodes at `xs` with `h_come = x`, `h_go = 10 - x`; the first is the tree's root (cost 0, the attachment `()`).
fn graph(xs: &[f64]) -> Graph {
    let mut g = Graph::new();
    for (i, &x) in xs.iter().enumerate() {
        let (attachment, flags) = if i == 0 { (Some(()), F_START | F_IN_TREE) } else { (None, 0) };
        g.alloc(x, attachment, flags, (x, 10.0 - x)).unwrap();
    }
    g.node_mut(0).unwrap().cost = 0.0;
    g
}

/// `root`'s subtree in the order of `next_in_subtree`.
fn walk(g: &Graph, root: u32) -> StdVec<u32> {
    let mut out = StdVec::new();
    let mut cur = g.node(root).unwrap().first_child;
    while cur != NONE && out.len() < 16 {
        out.push(cur);
        cur = g.next_in_subtree(cur, root);
    }
    out
}

#[test]
fn a_freed_slot_is_reused_first_as_a_new_generation_and_a_full_arena_says_so() {
    let mut g = graph(&[0.0, 1.0, 2.0]);
    let generation = g.node(1).unwrap().generation;
    g.free(1);
    assert!(g.node(1).unwrap().has(F_FREE));
    assert_eq!(g.live(), 2);
    assert_eq!(g.alloc(5.0, None, 0, (5.0, 5.0)), Some(1), "the freed slot first");
    assert_eq!(g.node(1).unwrap().generation, generation + 2, "freeing and reusing each make a new generation");
    assert_eq!((g.live(), g.nodes().len()), (3, 3));
    let mut small = ImplicitGraph::<f64, (), 2>::new();
    assert_eq!(small.alloc(0.0, None, 0, (0.0, 0.0)), Some(0));
    assert_eq!(small.alloc(1.0, None, 0, (0.0, 0.0)), Some(1));
    assert_eq!(small.alloc(2.0, None, 0, (0.0, 0.0)), None, "full");
    assert_eq!(small.live(), 2);
}

#[test]
fn neighbours_are_the_k_nearest_or_those_within_r_nearest_first_ties_by_index_twins_left_out() {
    let mut g = graph(&[0.0, 3.0, 1.0, -1.0, 2.0, 1.0]);
    let ids = |near: &[(f64, u32)]| near.iter().map(|&(_, i)| i).collect::<StdVec<_>>();
    let (near, cut) = g.neighbours(&Line, 0, Connection::KNearest, 3, 0.0);
    assert_eq!((ids(&near), cut), (std::vec![0, 2, 3], false), "the node itself counts, as in OMPL");
    let (near, cut) = g.neighbours(&Line, 0, Connection::RDisc, 0, 1.5);
    assert_eq!((ids(&near), cut), (std::vec![0, 2, 3, 5], false));
    g.node_mut(2).unwrap().flags |= F_TWIN;
    let (near, _) = g.neighbours(&Line, 0, Connection::KNearest, 3, 0.0);
    assert_eq!(ids(&near), [0, 3, 5], "a history twin is reached through its state's original node");
    let (near, cut) = g.neighbours(&Line, 0, Connection::KNearest, NEIGHBOUR_CAPACITY + 1, 0.0);
    assert_eq!((near.len(), cut), (5, true), "a k above the capacity is a cut list");
}

#[test]
fn linking_rewiring_and_the_subtree_walk() {
    let mut g = graph(&[0.0, 1.0, 2.0, 3.0]);
    assert!(!g.link(0, 1, 1.0, ()));
    assert!(!g.link(1, 2, 1.0, ()));
    assert!(!g.link(1, 3, 2.0, ()));
    assert_eq!((g.g(1), g.g(2), g.g(3)), (1.0, 2.0, 3.0));
    assert_eq!(walk(&g, 0), [1, 3, 2], "pre-order, the newest child first");
    assert!(g.link(0, 3, 2.5, ()), "3 was in the tree: a rewiring");
    assert_eq!(g.node(3).unwrap().parent(), Some(0));
    assert_eq!(walk(&g, 0), [3, 1, 2]);
    assert_eq!(walk(&g, 1), [2]);
    g.node_mut(1).unwrap().edge_cost = 0.5;
    g.update_cost_from_parent(1);
    g.update_cost_from_parent(2);
    assert_eq!((g.g(1), g.g(2)), (0.5, 1.5));
    g.unlink_from_parent(2);
    assert_eq!((g.node(2).unwrap().parent(), walk(&g, 1).len()), (None, 0));
}

#[test]
fn pruning_drops_samples_and_disconnects_vertices_that_cannot_improve_the_solution() {
    // root 0; vertices a (g + h_go = 5) and b (g + h_go = 7) under it, e under b; samples c (h = 7) and d (h = 3).
    let mut g = Graph::new();
    let root = g.alloc(0.0, Some(()), F_START | F_IN_TREE, (0.0, 5.0)).unwrap();
    g.node_mut(root).unwrap().cost = 0.0;
    let a = g.alloc(1.0, None, 0, (1.0, 4.0)).unwrap();
    let b = g.alloc(2.0, None, 0, (1.0, 4.0)).unwrap();
    let c = g.alloc(3.0, None, 0, (3.0, 4.0)).unwrap();
    let d = g.alloc(4.0, None, 0, (1.0, 2.0)).unwrap();
    let e = g.alloc(5.0, None, 0, (1.0, 0.0)).unwrap();
    g.link(root, a, 1.0, ());
    g.link(root, b, 3.0, ());
    g.link(b, e, 0.0, ());
    assert_eq!(g.ompl_graph_size(), 10.0, "6 live states plus 4 vertices");
    let before = g.nodes().iter().map(|n| n.generation).collect::<StdVec<_>>();
    assert_eq!(g.prune(6.0, NONE, 0.5, true), None, "1 prunable state of 10 is below the fraction");
    assert!(g.node(c).is_some_and(|n| !n.has(F_FREE)));
    assert_eq!(g.prune(6.0, NONE, 0.05, true), Some(1), "b is kept as a sample: recycled");
    assert!(g.node(a).unwrap().in_tree());
    for (i, what) in [(b, "cannot improve, kept"), (e, "orphaned, kept"), (d, "a sample that can help")] {
        let n = g.node(i).unwrap();
        assert!(!n.in_tree() && !n.has(F_FREE), "{what}");
    }
    assert!(g.node(c).unwrap().has(F_FREE), "a sample that cannot help is dropped");
    assert_eq!(g.live(), 5);
    for i in [b, e] {
        assert_ne!(g.node(i).unwrap().generation, before[i as usize], "a disconnected vertex is a new node");
    }
}

#[test]
fn eviction_frees_the_oldest_unconnected_samples_and_keeps_the_tree_goals_and_twinned_states() {
    // Batch 1: root, goal, vertex a, samples s1 and t (t twinned by a vertex); batch 2: samples s2 and s3 (s3
    // twinned by an unconnected twin w); batch 3: sample s4.
    let mut g = Graph::new();
    g.set_batch(1);
    let root = g.alloc(0.0, Some(()), F_START | F_IN_TREE, (0.0, 5.0)).unwrap();
    g.node_mut(root).unwrap().cost = 0.0;
    let goal = g.alloc(9.0, None, F_GOAL, (9.0, 0.0)).unwrap();
    let a = g.alloc(1.0, None, 0, (1.0, 4.0)).unwrap();
    g.link(root, a, 1.0, ());
    let s1 = g.alloc(2.0, None, 0, (2.0, 3.0)).unwrap();
    let t = g.alloc(3.0, None, 0, (3.0, 2.0)).unwrap();
    let t_twin = g.alloc(3.0, None, F_TWIN | F_IN_TREE, (3.0, 2.0)).unwrap();
    g.set_batch(2);
    let s2 = g.alloc(4.0, None, 0, (4.0, 1.0)).unwrap();
    let s3 = g.alloc(5.0, None, 0, (5.0, 1.0)).unwrap();
    let w = g.alloc(5.0, None, F_TWIN, (5.0, 1.0)).unwrap();
    g.set_batch(3);
    let s4 = g.alloc(6.0, None, 0, (6.0, 1.0)).unwrap();
    for (of, twin) in [(t, t_twin), (s3, w)] {
        let generation = g.node(twin).unwrap().generation;
        let n = g.node_mut(of).unwrap();
        n.twin = twin;
        n.twin_generation = generation;
    }
    assert_eq!(g.node(s4).unwrap().born, 3);
    assert_eq!(g.live(), 10);
    // Room for nothing to go: nothing is freed.
    assert_eq!(g.evict_oldest_samples(10), 0);
    // One to go: batch 1's only unconnected sample without a live twin, s1.
    assert_eq!(g.evict_oldest_samples(9), 1);
    assert!(g.node(s1).unwrap().has(F_FREE));
    // Batch 4's s5 takes s1's slot, the lowest: age, not the slot, decides.
    g.set_batch(4);
    let s5 = g.alloc(7.0, None, 0, (7.0, 1.0)).unwrap();
    assert_eq!(s5, s1);
    // Two to go: batch 2's in slot order; s3 has a live twin (w), so s2, then w (an unconnected twin).
    assert_eq!(g.evict_oldest_samples(8), 2);
    assert!(g.node(s2).unwrap().has(F_FREE) && g.node(w).unwrap().has(F_FREE));
    assert!(!g.node(s3).unwrap().has(F_FREE), "w was still alive when s3's slot came");
    assert!(!g.node(s5).unwrap().has(F_FREE), "the newest sample stays");
    // As many as can go: s3 (its twin is gone now), s4, s5; never the start, the goal, the vertex a, or t, whose
    // twin is a vertex.
    assert_eq!(g.evict_oldest_samples(0), 3);
    assert_eq!(g.live(), 5);
    for i in [root, goal, a, t, t_twin] {
        assert!(!g.node(i).unwrap().has(F_FREE), "node {i} stays");
    }
}

#[test]
fn the_queue_pops_by_key_updates_a_queued_edge_in_place_and_a_full_slab_changes_nothing() {
    let mut g = graph(&[0.0, 4.0, 2.0, 3.0]);
    let mut q = SearchQueue::<3>::new();
    let nodes = g.nodes_mut();
    // Keys with inflation 2: 0->1 [4 + 2 * 6, ..] = 16, 0->2 18, 0->3 17.
    assert_eq!(q.enqueue(nodes, (0, 1), 4.0, false, 2.0), Ok(1));
    assert_eq!(q.enqueue(nodes, (0, 2), 2.0, false, 2.0), Ok(2));
    assert_eq!(q.enqueue(nodes, (0, 3), 3.0, false, 2.0), Ok(3));
    // Queued already (now with inflation 1): updated to [2 + 8, 2, 0] and revealing, not queued twice.
    assert_eq!(q.enqueue(nodes, (0, 2), 2.0, true, 1.0), Ok(3));
    assert_eq!(q.enqueue(nodes, (1, 2), 1.0, false, 2.0), Err(Full));
    assert_eq!(q.len(), 3);
    let front = q.pop(nodes).unwrap();
    assert_eq!((front.child, front.c_hat, front.reveals), (2, 2.0, true));
    assert_eq!(q.pop(nodes).map(|e| e.child), Some(1));
    assert_eq!(q.pop(nodes).map(|e| e.child), Some(3));
    assert!(q.pop(nodes).is_none() && q.is_empty());
    assert_eq!(nodes[0].first_out, NONE, "the parent's list of queued edges is empty again");
    assert_eq!(q.enqueue(nodes, (0, 1), 4.0, false, 2.0), Ok(1), "the slots were released");
}

#[test]
fn a_cost_change_rekeys_a_vertex_edges_and_a_stale_front_is_dropped() {
    let mut g = graph(&[0.0, 1.0, 2.0, 3.0]);
    g.link(0, 1, 1.0, ());
    let mut q = SearchQueue::<8>::new();
    // Inflation 1: 1->2 [1 + 1 + 8, 2, 1], 0->3 [0 + 3 + 7, 3, 0]: equal first terms, 1->2 first.
    q.enqueue(g.nodes_mut(), (1, 2), 1.0, false, 1.0).unwrap();
    q.enqueue(g.nodes_mut(), (0, 3), 3.0, false, 1.0).unwrap();
    q.enqueue(g.nodes_mut(), (1, 3), 2.0, false, 1.0).unwrap();
    g.node_mut(1).unwrap().cost = 5.0;
    q.rekey_out_edges(g.nodes(), 1, 1.0);
    assert_eq!(q.pop(g.nodes_mut()).map(|e| (e.parent, e.child)), Some((0, 3)), "1's edges moved back");
    g.free(2);
    q.clean_front(g.nodes_mut());
    assert_eq!(q.len(), 1, "the edge into the freed node left the queue");
    assert_eq!(q.pop(g.nodes_mut()).map(|e| (e.parent, e.child)), Some((1, 3)));
    q.enqueue(g.nodes_mut(), (0, 3), 3.0, false, 1.0).unwrap();
    q.clear(g.nodes_mut());
    assert!(q.is_empty() && g.nodes().iter().all(|n| n.first_out == NONE));
}

#[test]
fn the_memo_answers_a_checked_motion_until_a_node_is_a_new_generation() {
    let mut g = graph(&[0.0, 1.0, 5.0]);
    let mut memo = EdgeMemo::<(), 8>::new();
    memo.reset();
    let mut motions = ShortMotions { checks: 0 };
    let mut check = |g: &Graph, memo: &mut EdgeMemo<(), 8>, child| memo.check(g.nodes(), &Line, &mut motions, 0, child);
    assert!(matches!(check(&g, &mut memo, 1), MemoCheck::Checked { result: Some(()), filled: true }));
    assert!(matches!(check(&g, &mut memo, 1), MemoCheck::Known(Some(()))));
    assert!(matches!(check(&g, &mut memo, 2), MemoCheck::Checked { result: None, filled: true }));
    assert!(memo.blacklisted(g.nodes(), &Line, 0, 2));
    assert!(!memo.blacklisted(g.nodes(), &Line, 0, 1));
    assert_eq!(memo.get(g.nodes(), 1, 0), None, "a motion is one way");
    // Slot 2 freed and reused: another node, whose motions the memo does not know.
    g.free(2);
    assert_eq!(g.alloc(1.5, None, 0, (1.5, 8.5)), Some(2));
    assert_eq!(memo.get(g.nodes(), 0, 2), None);
    assert!(!memo.blacklisted(g.nodes(), &Line, 0, 2));
    assert!(matches!(check(&g, &mut memo, 2), MemoCheck::Checked { result: Some(()), filled: false }));
    assert_eq!(motions.checks, 3);
}
