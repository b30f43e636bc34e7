//! Bounded-leg A*, Morad et al. section V-A.6, Figs. 10-11: A* over the hop graph where robot m may hop from a to
//! b only if
//!
//! - the hop is possible: d_ab <= h_max (edges longer than that are not in the graph), and
//! - the leg stays within the tether: |c_m + h| <= r_max, with c_m the hub-to-robot vector measured before
//!   planning (draw-wire encoder length and direction) and h = b - a the hop (Fig. 11's |c_m + h| <= r_max).
//!
//! The hub is held by the gripped robots while one hops, and follows the team between rounds, so every hop of the
//! plan is checked against the same c_m; only the first hop is executed before the next scan and replan (the
//! paper replans before each hop). Each robot runs this independently, without talking to the others.
//!
//! Cost: the edge loss L'_ab; heuristic: straight-line distance to the goal region (admissible since
//! L'_ab >= d_ab). When the goal region is unreachable within the scene (normal when the goal is in another
//! scene) the result is the path to the expanded vertex closest to the goal (`Approximate(Ended::SearchComplete)`).
//!
//! Parameters: `r_max` (default 15 m) minus `landing_margin` (0.5 m); `astar_budget` expansions (4096).
//! Open list: a [`crate::plan::heap::IndexedHeap`] of at most `V` vertices (V = 512 by default) ordered by
//! (f, vertex index); an open vertex whose f is not below infinity (infinite or NaN) is never expanded.

use super::graph::HopGraph;
use crate::config::team::TeamParams;
use crate::geom::{norm3, Real, Vec3};
use crate::plan::status::{Ended, Status};
use crate::plan::heap::{HeapItems, IndexedHeap, NOT_IN_HEAP};
use heapless::Vec as HVec;

/// Status of a local plan, the shared [`Status`] with the bounded-leg A*'s detail: `Exact(())` reaches the goal
/// region; `Approximate(Ended::SearchComplete)`: the goal region is not reachable, the path ends at the reachable
/// vertex closest to the goal; `Approximate(Ended::BudgetExhausted)`: the expansion budget ran out, the path is the
/// best so far (closest to the goal; possibly the start alone); `NoSolution(Ended::SearchComplete)`: no hop from
/// the start brings the robot closer to the goal; `InvalidInput(())`: the start vertex does not exist.
pub type AStarStatus = Status<(), Ended, Ended, ()>;

/// The word a report prints for `status`: `Exact`, `Approximate`, `BudgetExhausted`, `NoSolution` or
/// `InvalidInput`.
pub fn status_label(status: &AStarStatus) -> &'static str {
    match status {
        Status::Exact(()) => "Exact",
        Status::Approximate(Ended::BudgetExhausted) => "BudgetExhausted",
        Status::Approximate(_) => "Approximate",
        Status::NoSolution(_) => "NoSolution",
        Status::InvalidInput(()) => "InvalidInput",
    }
}

/// A* scratch arena for `V` vertices.
pub struct AStarArena<const V: usize> {
    g: [Real; V],
    parent: [u16; V],
    closed: [bool; V],
    /// The open list's keys (f = g + h) and positions, by vertex.
    keys: OpenKeys<V>,
    open: IndexedHeap<V>,
}

/// f and open-list position per vertex.
struct OpenKeys<const V: usize> {
    f: [Real; V],
    pos: [u32; V],
}

impl<const V: usize> OpenKeys<V> {
    /// Can vertex `v` be expanded (`f` below infinity: not infinite, not NaN)?
    fn selectable(&self, v: u32) -> bool {
        self.f.get(v as usize).is_some_and(|&f| f < Real::INFINITY)
    }
}

/// Least f first, ties to the lower index, vertices that cannot be expanded last: the vertex a scan over the open
/// vertices in index order with `f < best` picks is the heap's front.
impl<const V: usize> HeapItems for OpenKeys<V> {
    fn before(&self, a: u32, b: u32) -> bool {
        let (Some(&fa), Some(&fb)) = (self.f.get(a as usize), self.f.get(b as usize)) else { return false };
        match (self.selectable(a), self.selectable(b)) {
            (true, true) => fa < fb || (fa == fb && a < b),
            (true, false) => true,
            (false, true) => false,
            (false, false) => a < b,
        }
    }
    fn set_position(&mut self, id: u32, pos: u32) {
        if let Some(p) = self.pos.get_mut(id as usize) {
            *p = pos;
        }
    }
    fn position(&self, id: u32) -> Option<u32> {
        self.pos.get(id as usize).copied()
    }
}

impl<const V: usize> AStarArena<V> {
    /// Empty arena. Checked at compile time: vertex indices (`u16`, `u16::MAX` = no parent) fit `V`.
    pub const fn new() -> Self {
        const {
            assert!(V <= u16::MAX as usize, "AStarArena: V must fit u16 vertex indices");
        }
        Self {
            g: [Real::INFINITY; V],
            parent: [u16::MAX; V],
            closed: [false; V],
            keys: OpenKeys { f: [Real::INFINITY; V], pos: [NOT_IN_HEAP; V] },
            open: IndexedHeap::new(),
        }
    }
}

impl<const V: usize> Default for AStarArena<V> {
    fn default() -> Self {
        Self::new()
    }
}

/// A local plan: vertex indices from the start (included) to the end.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalPath<const H: usize> {
    /// Status.
    pub status: AStarStatus,
    /// Vertices of the path, start first (truncated to `H` entries from the start if longer).
    pub vertices: HVec<u16, H>,
    /// Total loss of the path.
    pub loss: Real,
    /// Expansions used.
    pub expansions: u32,
}

/// Run bounded-leg A* from vertex `start` towards `goal` (region of radius `goal_tol`) with the leg `c_m`.
pub fn bounded_leg_astar<const V: usize, const E: usize, const H: usize>(
    graph: &HopGraph<V, E>,
    arena: &mut AStarArena<V>,
    start: u16,
    goal: &Vec3,
    goal_tol: Real,
    c_m: &Vec3,
    params: &TeamParams,
) -> LocalPath<H> {
    // Vertex indices are `u16` (`u as u16`, `cur as u16` below `V`), `u16::MAX` meaning no parent.
    const {
        assert!(V <= u16::MAX as usize, "bounded_leg_astar: V must fit u16 vertex indices");
    }
    let n = graph.n_vertices;
    let mut out = LocalPath { status: Status::InvalidInput(()), vertices: HVec::new(), loss: 0.0, expansions: 0 };
    if start as usize >= n {
        return out;
    }
    let r_eff = params.r_max - params.landing_margin;
    let hdist = |v: usize| -> Real {
        let p = graph.vertices.get(v).map(|x| x.pos).unwrap_or_else(Vec3::zeros);
        (norm3(&(p - goal)) - goal_tol).max(0.0)
    };
    for i in 0..n {
        if let (Some(g), Some(p), Some(c)) = (arena.g.get_mut(i), arena.parent.get_mut(i), arena.closed.get_mut(i)) {
            *g = Real::INFINITY;
            *p = u16::MAX;
            *c = false;
        }
    }
    arena.open.clear();
    if let (Some(g), Some(f)) = (arena.g.get_mut(start as usize), arena.keys.f.get_mut(start as usize)) {
        *g = 0.0;
        *f = 0.0 + hdist(start as usize);
        let _ = arena.open.push(u32::from(start), &mut arena.keys);
    }
    let mut best = start as usize;
    let mut best_h = hdist(best);
    let mut status = Status::Approximate(Ended::SearchComplete);
    let mut reached = None;
    // the open vertex with the smallest f (ties: lower index); none left that can be expanded ends the search
    while let Some(top) = arena.open.peek().filter(|&v| arena.keys.selectable(v)) {
        let u = top as usize;
        if out.expansions >= params.astar_budget {
            status = Status::Approximate(Ended::BudgetExhausted);
            break;
        }
        out.expansions += 1;
        let _ = arena.open.pop(&mut arena.keys);
        if let Some(c) = arena.closed.get_mut(u) {
            *c = true;
        }
        let hu = hdist(u);
        if hu < best_h {
            best_h = hu;
            best = u;
        }
        if hu <= 0.0 {
            reached = Some(u);
            status = Status::Exact(());
            break;
        }
        let gu = arena.g.get(u).copied().unwrap_or(Real::INFINITY);
        let pu = graph.vertices.get(u).map(|x| x.pos).unwrap_or_else(Vec3::zeros);
        for e in graph.out_edges(u) {
            let b = e.to as usize;
            if arena.closed.get(b) == Some(&true) {
                continue;
            }
            let pb = match graph.vertices.get(b) {
                Some(v) => v.pos,
                None => continue,
            };
            // the bounded leg: the landing point must stay within the tether of the hub
            if norm3(&(c_m + (pb - pu))) > r_eff {
                continue;
            }
            let cand = gu + e.loss;
            if cand < arena.g.get(b).copied().unwrap_or(Real::INFINITY) {
                if let (Some(g), Some(p), Some(f)) = (arena.g.get_mut(b), arena.parent.get_mut(b), arena.keys.f.get_mut(b)) {
                    *g = cand;
                    *p = u as u16;
                    *f = cand + hdist(b);
                    // capacity V, each vertex queued at most once: the push always fits
                    if !arena.open.contains(b as u32, &arena.keys) {
                        let _ = arena.open.push(b as u32, &mut arena.keys);
                    } else {
                        arena.open.update(b as u32, &mut arena.keys);
                    }
                }
            }
        }
    }
    let end = reached.unwrap_or(best);
    if end == start as usize {
        out.status = if status == Status::Approximate(Ended::BudgetExhausted) {
            status
        } else {
            Status::NoSolution(Ended::SearchComplete)
        };
        let _ = out.vertices.push(start);
        return out;
    }
    out.status = status;
    out.loss = arena.g.get(end).copied().unwrap_or(Real::INFINITY);
    // walk back to the start (bounded by V), then reverse into the output
    let mut chain: HVec<u16, 1024> = HVec::new();
    let mut cur = end;
    for _ in 0..V.min(1024) {
        let _ = chain.push(cur as u16);
        if cur == start as usize {
            break;
        }
        cur = arena.parent.get(cur).copied().unwrap_or(u16::MAX) as usize;
        if cur >= n {
            break;
        }
    }
    for &v in chain.iter().rev() {
        if out.vertices.push(v).is_err() {
            break;
        }
    }
    out
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::super::graph::AnchorVertex;
    use super::*;
    use std::boxed::Box;
    use std::vec::Vec;

    /// Oracle: Bellman-Ford over the same graph with the same bounded-leg filter, to a fixed goal vertex.
    fn oracle<const V: usize, const E: usize>(g: &HopGraph<V, E>, start: usize, goal: usize, c_m: &Vec3, r_eff: Real) -> Real {
        let n = g.n_vertices;
        let mut d: Vec<Real> = std::vec![Real::INFINITY; n];
        d[start] = 0.0;
        for _ in 0..n {
            for a in 0..n {
                if !d[a].is_finite() {
                    continue;
                }
                for e in g.out_edges(a) {
                    let b = e.to as usize;
                    if norm3(&(c_m + (g.vertices[b].pos - g.vertices[a].pos))) > r_eff {
                        continue;
                    }
                    if d[a] + e.loss < d[b] {
                        d[b] = d[a] + e.loss;
                    }
                }
            }
        }
        d[goal]
    }

    #[test]
    fn bounded_leg_astar_is_optimal_and_respects_both_bounds() {
        let p = TeamParams { r_max: 9.0, ..TeamParams::DEFAULT };
        let r_eff = p.r_max - p.landing_margin;
        let h = p.h_max - p.landing_margin;
        for seed in 0..20u32 {
            let mut g: Box<HopGraph<128, 16384>> = Box::default();
            let mut s = seed.wrapping_mul(2_654_435_761).wrapping_add(1);
            let mut rnd = || {
                s ^= s << 13;
                s ^= s >> 17;
                s ^= s << 5;
                (s % 10_000) as Real / 10_000.0
            };
            for _ in 0..100 {
                let v = AnchorVertex { pos: Vec3::new(rnd() * 40.0, rnd() * 20.0, rnd() * 2.0), score: rnd() };
                g.push_vertex(v).unwrap();
            }
            g.build_edges(&p);
            let goal_v = 99usize;
            let goal = g.vertices[goal_v].pos;
            let c_m = Vec3::new(-3.0 + 6.0 * rnd(), -3.0 + 6.0 * rnd(), 0.0);
            let mut arena: Box<AStarArena<128>> = Box::default();
            let path: LocalPath<64> = bounded_leg_astar(&g, &mut arena, 0, &goal, 1e-4, &c_m, &p);
            let best = oracle(&g, 0, goal_v, &c_m, r_eff);
            if best.is_finite() {
                assert_eq!(path.status, Status::Exact(()), "seed {seed}");
                assert!((path.loss - best).abs() <= 1e-3 * best.max(1.0), "seed {seed}: {} vs {best}", path.loss);
                for w in path.vertices.windows(2) {
                    let (a, b) = (g.vertices[w[0] as usize].pos, g.vertices[w[1] as usize].pos);
                    assert!(norm3(&(b - a)) <= h + 1e-5);
                    assert!(norm3(&(c_m + (b - a))) <= r_eff + 1e-5);
                }
                assert_eq!(*path.vertices.last().unwrap() as usize, goal_v);
            } else {
                assert_ne!(path.status, Status::Exact(()), "seed {seed}");
            }
        }
    }

    #[test]
    fn budget_and_invalid_start_are_outcomes() {
        let mut g: Box<HopGraph<16, 256>> = Box::default();
        for k in 0..10 {
            g.push_vertex(AnchorVertex { pos: Vec3::new(k as Real * 3.0, 0.0, 0.0), score: 0.0 }).unwrap();
        }
        g.build_edges(&TeamParams::DEFAULT);
        let mut arena: Box<AStarArena<16>> = Box::default();
        let goal = Vec3::new(27.0, 0.0, 0.0);
        let p = TeamParams { astar_budget: 2, ..TeamParams::DEFAULT };
        let r: LocalPath<16> = bounded_leg_astar(&g, &mut arena, 0, &goal, 0.1, &Vec3::zeros(), &p);
        assert_eq!(r.status, Status::Approximate(Ended::BudgetExhausted));
        assert!(r.vertices.len() >= 2, "best-so-far path kept");
        let r: LocalPath<16> = bounded_leg_astar(&g, &mut arena, 12, &goal, 0.1, &Vec3::zeros(), &TeamParams::DEFAULT);
        assert_eq!(r.status, Status::InvalidInput(()));
        // a leg already at the tether limit pointing away from the goal: no hop towards it is allowed
        let far = Vec3::new(14.4, 0.0, 0.0);
        let r: LocalPath<16> = bounded_leg_astar(&g, &mut arena, 0, &goal, 0.1, &far, &TeamParams::DEFAULT);
        assert_eq!(r.status, Status::NoSolution(Ended::SearchComplete));
    }
}
