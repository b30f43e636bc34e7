//! The directed hop graph, Morad et al. section V-A.5: vertices are the kept anchor points (plus the robot's
//! current anchor as vertex 0); an edge a -> b exists when the hop is physically possible, |b - a| <= h_max
//! (Fig. 10's "prune edges that are too distant to hop to"), and carries two weights:
//!
//! - d_ab, the Euclidean distance;
//! - L'_ab = L_b + r_b, the loss of landing on b. The paper leaves L_b implicit; we take L_b = d_ab (the hop's
//!   length as its loss) and scale the anchor score r_b to metres with `risk_m`, so L'_ab = d_ab + risk_m * r_b:
//!   the A* minimises hop distance plus the summed risk of the anchor points it lands on, and d_ab <= L'_ab
//!   keeps the straight-line heuristic admissible.
//!
//! Edges are directed because L' depends on the target. Storage is compressed rows: `first[a]..first[a+1]` are
//! a's edges. A full edge arena is an outcome ([`GraphOutcome::edges_full`]): the vertices built so far keep
//! their edges, later ones have none.
//!
//! Parameters: `h_max` (default 10 m), `landing_margin` (default 0.5 m, subtracted from h_max), `risk_m`
//! (default 5 m per unit score).

use crate::config::team::TeamParams;
use crate::geom::{norm3, Real, Vec3};

/// A graph vertex: an anchor point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnchorVertex {
    /// World position.
    pub pos: Vec3,
    /// Anchor score r (0 = safest).
    pub score: Real,
}

/// A directed edge.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HopEdge {
    /// Target vertex.
    pub to: u16,
    /// Euclidean distance d_ab.
    pub d: Real,
    /// Loss L'_ab = d_ab + risk_m * r_b.
    pub loss: Real,
}

/// What graph generation produced.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct GraphOutcome {
    /// Vertices.
    pub vertices: usize,
    /// Edges.
    pub edges: usize,
    /// The edge arena filled up; vertices from `first_without_edges` on have no outgoing edges.
    pub edges_full: bool,
}

/// A hop graph with `V` vertices and `E` edges at most.
pub struct HopGraph<const V: usize, const E: usize> {
    /// Vertices (the first `n_vertices`).
    pub vertices: [AnchorVertex; V],
    /// Number of vertices.
    pub n_vertices: usize,
    first: [u32; V],
    count: [u16; V],
    /// Edge arena.
    pub edges: [HopEdge; E],
    /// Number of edges.
    pub n_edges: usize,
}

impl<const V: usize, const E: usize> HopGraph<V, E> {
    /// An empty graph.
    pub const fn new() -> Self {
        Self {
            vertices: [AnchorVertex { pos: Vec3::new(0.0, 0.0, 0.0), score: 0.0 }; V],
            n_vertices: 0,
            first: [0; V],
            count: [0; V],
            edges: [HopEdge { to: 0, d: 0.0, loss: 0.0 }; E],
            n_edges: 0,
        }
    }

    /// Remove all vertices and edges.
    pub fn clear(&mut self) {
        self.n_vertices = 0;
        self.n_edges = 0;
    }

    /// Add a vertex; `Err(v)` hands it back when the arena is full.
    pub fn push_vertex(&mut self, v: AnchorVertex) -> Result<u16, AnchorVertex> {
        match self.vertices.get_mut(self.n_vertices) {
            Some(slot) if self.n_vertices < u16::MAX as usize => {
                *slot = v;
                self.n_vertices += 1;
                Ok((self.n_vertices - 1) as u16)
            }
            _ => Err(v),
        }
    }

    /// Build the edges among the current vertices (brute force over pairs: V^2 distance tests, bounded by V).
    pub fn build_edges(&mut self, params: &TeamParams) -> GraphOutcome {
        let h = params.h_max - params.landing_margin;
        self.n_edges = 0;
        let mut full = false;
        for a in 0..self.n_vertices {
            let start = self.n_edges;
            let pa = self.vertices.get(a).map(|v| v.pos).unwrap_or_else(Vec3::zeros);
            if !full {
                for b in 0..self.n_vertices {
                    if a == b {
                        continue;
                    }
                    let vb = match self.vertices.get(b) {
                        Some(v) => *v,
                        None => continue,
                    };
                    let d = norm3(&(vb.pos - pa));
                    if d > h {
                        continue;
                    }
                    match self.edges.get_mut(self.n_edges) {
                        Some(e) => {
                            *e = HopEdge { to: b as u16, d, loss: d + params.risk_m * vb.score };
                            self.n_edges += 1;
                        }
                        None => {
                            full = true;
                            break;
                        }
                    }
                }
            }
            if let (Some(f), Some(c)) = (self.first.get_mut(a), self.count.get_mut(a)) {
                *f = start as u32;
                *c = (self.n_edges - start).min(u16::MAX as usize) as u16;
            }
        }
        GraphOutcome { vertices: self.n_vertices, edges: self.n_edges, edges_full: full }
    }

    /// Outgoing edges of `a`.
    pub fn out_edges(&self, a: usize) -> &[HopEdge] {
        let f = self.first.get(a).copied().unwrap_or(0) as usize;
        let c = self.count.get(a).copied().unwrap_or(0) as usize;
        self.edges.get(f..f + c).unwrap_or(&[])
    }
}

impl<const V: usize, const E: usize> Default for HopGraph<V, E> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::boxed::Box;

    #[test]
    fn edges_are_exactly_the_pairs_within_a_hop_with_the_documented_losses() {
        let p = TeamParams::DEFAULT;
        let mut g: Box<HopGraph<64, 4096>> = Box::default();
        // a deterministic scatter
        for k in 0..40u32 {
            let x = ((k * 37) % 23) as Real;
            let y = ((k * 11) % 17) as Real;
            let z = ((k * 5) % 3) as Real;
            g.push_vertex(AnchorVertex { pos: Vec3::new(x, y, z), score: (k % 7) as Real / 7.0 }).unwrap();
        }
        let out = g.build_edges(&p);
        assert!(!out.edges_full);
        let h = p.h_max - p.landing_margin;
        let mut expected = 0;
        for a in 0..40 {
            for b in 0..40 {
                let d = norm3(&(g.vertices[b].pos - g.vertices[a].pos));
                let present = g.out_edges(a).iter().find(|e| e.to as usize == b);
                if a != b && d <= h {
                    expected += 1;
                    let e = present.expect("missing edge");
                    assert!((e.d - d).abs() < 1e-6);
                    assert!((e.loss - (d + p.risk_m * g.vertices[b].score)).abs() < 1e-5);
                } else {
                    assert!(present.is_none(), "edge {a}->{b} of length {d}");
                }
            }
        }
        assert_eq!(out.edges, expected);
    }

    #[test]
    fn full_edge_arena_is_an_outcome_and_keeps_earlier_vertices() {
        let mut g: Box<HopGraph<16, 8>> = Box::default();
        for k in 0..6 {
            g.push_vertex(AnchorVertex { pos: Vec3::new(k as Real, 0.0, 0.0), score: 0.0 }).unwrap();
        }
        let out = g.build_edges(&TeamParams::DEFAULT);
        assert!(out.edges_full);
        assert_eq!(out.edges, 8);
        assert_eq!(g.out_edges(0).len(), 5);
        assert!(g.out_edges(5).is_empty());
        let mut small: HopGraph<2, 1> = HopGraph::new();
        let v = AnchorVertex { pos: Vec3::zeros(), score: 0.0 };
        assert!(small.push_vertex(v).is_ok() && small.push_vertex(v).is_ok());
        assert_eq!(small.push_vertex(v), Err(v));
    }
}
