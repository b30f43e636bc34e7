//! The general true tether: the taut tether from the root anchor to the rover over and around a world's exact
//! geometry ([`crate::truth::solid`]), for every world kind, from geometry only (no distance field, no code shared
//! with `firmware::tether`; the visibility queries are parry's exact ray casts on the solids' shapes,
//! [`crate::physics::terrain`]).
//!
//! # Model
//! A taut tether is a polyline that bends only on the terrain's **convex edges** (on a smooth face it is straight,
//! and a shortest path never touches a concave corner). The wrap edges ([`WrapEdges`]):
//! - a prism's edges (both end polygons and the lateral edges), all convex;
//! - a cylinder's side as the vertical edges of the circumscribed regular [`CYLINDER_SIDES`]-gon (64): a tether
//!   wrapped by an angle `phi` is longer than on the true circle by at most `r phi (1 / cos(pi / 64) - 1)`,
//!   0.12 % of the wrapped arc (0.3 mm for a half turn round the 0.25 m pole), plus its top rim's polygon edges;
//! - a height grid's and a mesh's triangle edges whose two faces meet at a convex dihedral of more than
//!   [`MIN_CONVEX_DEG`] (0.5 degrees), inside the region of interest the caller names (a DEM has millions of
//!   edges; the tether can only touch those near the root and the rover's path).
//!
//! Each wrap edge carries its outward direction (the normalised sum of its faces' outward normals); contact
//! points sit [`CONTACT_OFFSET_M`] (1 mm) out along it so a segment leaving a contact does not start on the
//! surface (the length error is at most 2 mm per contact, in practice far less: the offset is nearly
//! perpendicular to the tether).
//!
//! # The tether follows the rover ([`TautTether::update`])
//! The tether's shape depends on where the rover has been (it is dragged round the pole, it stays round it),
//! so it is kept as state: the root, the contacts (edge, position along it) and the rover end. A move of the end
//! is cut into steps of at most [`MAX_STEP_M`] (5 cm); after each step, until nothing changes (bounded):
//! 1. **catch**: a segment that the terrain now blocks gets a contact on the wrap edge that gives the shortest
//!    detour with both new segments free, among the edges within [`CATCH_RADIUS_M`] of the swept triangle;
//! 2. **tighten**: each contact slides along its edge to the point of the shortest path through it between its
//!    neighbours (unfolding the two segments about the edge, clamped to the edge), unless that blocks a segment;
//! 3. **release**: a contact the tether no longer presses into the edge (the sum of the unit vectors to its
//!    neighbours points out of the edge's outward direction) is removed.
//!
//! [`TautTether::shortest`] starts a tether from scratch: the straight segment if free, otherwise A* over a
//! visibility graph of points sampled along the wrap edges ([`SHORTEST_SAMPLE_M`] apart), then tightened.

use core::cmp::Ordering;
use std::collections::{BTreeMap, BinaryHeap};

use crate::physics::terrain::PhysicsTerrain;
use crate::truth::solid::{ExactGeometry, Solid};
use firmware::geom::p3::{add_scaled, cross, dist, dot, norm, sub, P3};

/// Sides of the polygon standing for a cylinder's wrap edges.
pub const CYLINDER_SIDES: usize = 64;
/// Smallest convex dihedral (degrees) of a height-grid or mesh edge that counts as a wrap edge.
pub const MIN_CONVEX_DEG: f64 = 0.5;
/// Offset of a contact point from its edge, out along the edge's outward direction, metres.
pub const CONTACT_OFFSET_M: f64 = 0.001;
/// Longest step of the rover end between two catch/tighten/release rounds, metres.
pub const MAX_STEP_M: f64 = 0.05;
/// Wrap edges farther than this from the swept triangle are not tried when a segment is caught, metres.
pub const CATCH_RADIUS_M: f64 = 0.3;
/// Sample spacing along wrap edges for the visibility graph of [`TautTether::shortest`], metres.
pub const SHORTEST_SAMPLE_M: f64 = 0.25;
/// Rounds of catch / tighten / release per step.
const ROUNDS: usize = 12;
/// Most contacts a tether holds (beyond: the update fails with [`TautError::TooManyContacts`]).
pub const MAX_CONTACTS: usize = 256;

/// A convex edge of the terrain the tether can bend on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WrapEdge {
    /// One end.
    pub a: P3,
    /// The other end.
    pub b: P3,
    /// Unit outward direction (between the faces' outward normals).
    pub out: P3,
}

impl WrapEdge {
    /// The contact point at parameter `t` in [0, 1], offset out of the terrain.
    pub fn point(&self, t: f64) -> P3 {
        let on = add_scaled(self.a, sub(self.b, self.a), t);
        add_scaled(on, self.out, CONTACT_OFFSET_M)
    }
}

/// Why a tether cannot be computed.
#[derive(Debug, Clone, PartialEq)]
pub enum TautError {
    /// No tether from the root reaches the rover without passing through the terrain (with these wrap edges).
    NoPath,
    /// More than [`MAX_CONTACTS`] contacts.
    TooManyContacts,
    /// A segment stayed blocked after every catch round: the wrap edges cannot route round what blocks it.
    Stuck {
        /// The blocked segment's ends.
        segment: [P3; 2],
    },
}

impl core::fmt::Display for TautError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            TautError::NoPath => f.write_str("no tether path from the root to the rover outside the terrain"),
            TautError::TooManyContacts => write!(f, "the tether would touch more than {MAX_CONTACTS} edges"),
            TautError::Stuck { segment } => write!(f, "the tether segment {:?} -> {:?} passes through the terrain and no wrap edge routes round it", segment[0], segment[1]),
        }
    }
}

/// The wrap edges of a world and its shapes for visibility.
#[derive(Debug, Clone)]
pub struct WrapEdges {
    /// The edges.
    pub edges: Vec<WrapEdge>,
    terrain: PhysicsTerrain,
    /// Edges by end point (rounded to the micrometre), so a contact at an edge's end can move on to the next.
    at_vertex: BTreeMap<[i64; 3], Vec<usize>>,
}

fn vertex_key(p: P3) -> [i64; 3] {
    p.map(|c| (c * 1e6).round() as i64)
}

fn unit(a: P3) -> P3 {
    let n = norm(a);
    if n > 0.0 {
        [a[0] / n, a[1] / n, a[2] / n]
    } else {
        [0.0; 3]
    }
}

fn in_region(p: P3, region: &([f64; 3], [f64; 3])) -> bool {
    (0..3).all(|k| p[k] >= region.0[k] && p[k] <= region.1[k])
}

/// Convex edges of a triangle set: each edge shared by exactly two triangles whose dihedral is convex by more
/// than [`MIN_CONVEX_DEG`]; triangles counter-clockwise seen from outside.
fn convex_triangle_edges(verts: &[P3], tris: &[[u32; 3]], region: &([f64; 3], [f64; 3]), out: &mut Vec<WrapEdge>) {
    let normal = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|i| verts.get(i as usize).copied().unwrap_or([0.0; 3]));
        unit(cross(sub(b, a), sub(c, a)))
    };
    // edge (lo, hi) -> triangles (BTreeMap: deterministic order).
    let mut by_edge: BTreeMap<(u32, u32), Vec<usize>> = BTreeMap::new();
    for (k, t) in tris.iter().enumerate() {
        let keep = t.iter().any(|&i| verts.get(i as usize).is_some_and(|p| in_region(*p, region)));
        if !keep {
            continue;
        }
        for e in 0..3 {
            let (i, j) = (t[e], t[(e + 1) % 3]);
            by_edge.entry((i.min(j), i.max(j))).or_default().push(k);
        }
    }
    let cos_min = MIN_CONVEX_DEG.to_radians().cos();
    for ((i, j), ts) in by_edge {
        let [t1, t2] = ts.as_slice() else { continue };
        let (n1, n2) = (normal(&tris[*t1]), normal(&tris[*t2]));
        if dot(n1, n2) > cos_min {
            continue;
        }
        let (a, b) = (verts[i as usize], verts[j as usize]);
        // Convex iff the far corner of the second triangle lies below the first triangle's plane.
        let far = tris[*t2].iter().map(|&v| verts[v as usize]).find(|p| *p != a && *p != b).unwrap_or(a);
        if dot(n1, sub(far, a)) >= 0.0 {
            continue;
        }
        out.push(WrapEdge { a, b, out: unit([n1[0] + n2[0], n1[1] + n2[1], n1[2] + n2[2]]) });
    }
}

impl WrapEdges {
    /// The wrap edges of `geometry` whose height-grid or mesh edges touch `region` (min, max corners); prism and
    /// cylinder edges are all kept.
    pub fn new(geometry: &ExactGeometry, region: ([f64; 3], [f64; 3])) -> Result<WrapEdges, String> {
        let terrain = PhysicsTerrain::new(geometry).map_err(|e| e.0)?;
        let mut edges = Vec::new();
        for s in &geometry.solids {
            match s {
                Solid::Ground { .. } => {}
                Solid::Prism { polygon, extrusion } => {
                    let n = polygon.len();
                    let top: Vec<P3> = polygon.iter().map(|p| [p[0] + extrusion[0], p[1] + extrusion[1], p[2] + extrusion[2]]).collect();
                    let c = polygon.iter().fold([0.0; 3], |acc, p| add_scaled(acc, *p, 1.0 / n as f64));
                    let pn = unit(cross(sub(polygon[1 % n], polygon[0]), sub(polygon[2 % n], polygon[0])));
                    // The end faces' outward normals: away from the other end.
                    let n_bottom = if dot(pn, *extrusion) > 0.0 { [-pn[0], -pn[1], -pn[2]] } else { pn };
                    let n_top = [-n_bottom[0], -n_bottom[1], -n_bottom[2]];
                    // A side face's outward normal: perpendicular to the extrusion and its polygon edge, away from
                    // the centroid.
                    let side = |k: usize| {
                        let (p, q) = (polygon[k], polygon[(k + 1) % n]);
                        let mut m = unit(cross(sub(q, p), *extrusion));
                        if dot(m, sub(p, c)) < 0.0 {
                            m = [-m[0], -m[1], -m[2]];
                        }
                        m
                    };
                    for k in 0..n {
                        let m = side(k);
                        let (p, q) = (polygon[k], polygon[(k + 1) % n]);
                        edges.push(WrapEdge { a: p, b: q, out: unit([m[0] + n_bottom[0], m[1] + n_bottom[1], m[2] + n_bottom[2]]) });
                        edges.push(WrapEdge { a: top[k], b: top[(k + 1) % n], out: unit([m[0] + n_top[0], m[1] + n_top[1], m[2] + n_top[2]]) });
                        let mp = side((k + n - 1) % n);
                        edges.push(WrapEdge { a: p, b: top[k], out: unit([m[0] + mp[0], m[1] + mp[1], m[2] + mp[2]]) });
                    }
                }
                Solid::Cylinder { centre, radius, z0, z1 } => {
                    let rr = radius / (core::f64::consts::PI / CYLINDER_SIDES as f64).cos();
                    let corner = |k: usize, z: f64| {
                        let a = (k as f64 + 0.5) * core::f64::consts::TAU / CYLINDER_SIDES as f64;
                        [centre[0] + rr * a.cos(), centre[1] + rr * a.sin(), z]
                    };
                    for k in 0..CYLINDER_SIDES {
                        let a = (k as f64 + 0.5) * core::f64::consts::TAU / CYLINDER_SIDES as f64;
                        edges.push(WrapEdge { a: corner(k, *z0), b: corner(k, *z1), out: [a.cos(), a.sin(), 0.0] });
                        // The side face between corners k and k + 1 faces the angle halfway between them.
                        let f = a + 0.5 * core::f64::consts::TAU / CYLINDER_SIDES as f64;
                        let side_n = [f.cos(), f.sin(), 0.0];
                        edges.push(WrapEdge { a: corner(k, *z1), b: corner(k + 1, *z1), out: unit([side_n[0], side_n[1], 1.0]) });
                    }
                }
                Solid::HeightGrid { nx, ny, x0, y0, spacing, heights } => {
                    let (nx, ny) = (*nx, *ny);
                    // Only the posts inside the region (plus one) become vertices.
                    let i0 = (((region.0[0] - x0) / spacing).floor() as i64 - 1).clamp(0, nx as i64 - 1) as usize;
                    let i1 = (((region.1[0] - x0) / spacing).ceil() as i64 + 1).clamp(0, nx as i64 - 1) as usize;
                    let j0 = (((region.0[1] - y0) / spacing).floor() as i64 - 1).clamp(0, ny as i64 - 1) as usize;
                    let j1 = (((region.1[1] - y0) / spacing).ceil() as i64 + 1).clamp(0, ny as i64 - 1) as usize;
                    let (w, h) = (i1 - i0 + 1, j1 - j0 + 1);
                    let mut verts = Vec::with_capacity(w * h);
                    for j in j0..=j1 {
                        for i in i0..=i1 {
                            verts.push([x0 + i as f64 * spacing, y0 + j as f64 * spacing, heights.get(j * nx + i).copied().unwrap_or(f64::NAN)]);
                        }
                    }
                    let mut tris = Vec::new();
                    let id = |i: usize, j: usize| ((j - j0) * w + (i - i0)) as u32;
                    for j in j0..j1 {
                        for i in i0..i1 {
                            let c = [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)];
                            if c.iter().any(|&v| !verts[v as usize][2].is_finite()) {
                                continue;
                            }
                            tris.push([c[0], c[1], c[2]]);
                            tris.push([c[0], c[2], c[3]]);
                        }
                    }
                    let all = ([f64::NEG_INFINITY; 3], [f64::INFINITY; 3]);
                    convex_triangle_edges(&verts, &tris, &all, &mut edges);
                }
                Solid::Mesh { vertices, triangles } => convex_triangle_edges(vertices, triangles, &region, &mut edges),
            }
        }
        let mut at_vertex: BTreeMap<[i64; 3], Vec<usize>> = BTreeMap::new();
        for (k, e) in edges.iter().enumerate() {
            at_vertex.entry(vertex_key(e.a)).or_default().push(k);
            at_vertex.entry(vertex_key(e.b)).or_default().push(k);
        }
        Ok(WrapEdges { edges, terrain, at_vertex })
    }

    /// The index of the edge with the same ends as `e` (to the micrometre), if there is one.
    pub fn find(&self, e: &WrapEdge) -> Option<usize> {
        let (ka, kb) = (vertex_key(e.a), vertex_key(e.b));
        let at_a = self.at_vertex.get(&ka)?;
        let same = |k: usize| self.edges.get(k).is_some_and(|f| vertex_key(f.a) == ka && vertex_key(f.b) == kb);
        at_a.iter().copied().find(|&k| same(k))
    }

    /// True when the segment misses the terrain.
    pub fn free(&self, a: P3, b: P3) -> bool {
        self.terrain.segment_free(a, b)
    }

    fn edge(&self, k: usize) -> Option<&WrapEdge> {
        self.edges.get(k)
    }
}

/// One contact of the tether: an edge and the position along it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Index into [`WrapEdges::edges`].
    pub edge: usize,
    /// Position along the edge, 0 at `a`, 1 at `b`.
    pub t: f64,
}

/// The taut tether's state.
#[derive(Debug, Clone, PartialEq)]
pub struct TautTether {
    /// The root anchor.
    pub root: P3,
    /// Contacts, from the root.
    pub contacts: Vec<Contact>,
    /// The rover end.
    pub end: P3,
}

/// The parameter in [0, 1] of the shortest path `a -> edge(t) -> b` (unfolding about the edge's line).
fn best_t(e: &WrapEdge, a: P3, b: P3) -> f64 {
    let d = sub(e.b, e.a);
    let l2 = dot(d, d);
    if l2 < 1e-18 {
        return 0.0;
    }
    let u = unit(d);
    let l = l2.sqrt();
    let (sa, sb) = (dot(sub(a, e.a), u), dot(sub(b, e.a), u));
    let perp = |p: P3, s: f64| norm(sub(p, add_scaled(e.a, u, s)));
    let (da, db) = (perp(a, sa), perp(b, sb));
    let s = if da + db > 0.0 { sa + (sb - sa) * da / (da + db) } else { sa };
    (s / l).clamp(0.0, 1.0)
}

/// Closest distance between segment `p-q` and the triangle `(a, b, c)`, approximately (sampled along the segment
/// against the exact point-triangle distance): good to a fifth of the segment over 16 samples, enough for a
/// candidate filter.
fn segment_triangle_distance(p: P3, q: P3, a: P3, b: P3, c: P3) -> f64 {
    (0..=16)
        .map(|k| {
            let s = add_scaled(p, sub(q, p), k as f64 / 16.0);
            dist(s, crate::world::geometry::closest_point_on_triangle(s, a, b, c))
        })
        .fold(f64::INFINITY, f64::min)
}

/// The axis-aligned bounding box of `pts` (min, max corners).
fn bounding_box(pts: &[P3]) -> (P3, P3) {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    (lo, hi)
}

/// The distance between two axis-aligned boxes (0 when they overlap): a lower bound of the distance between any
/// two point sets inside them.
fn box_gap(alo: P3, ahi: P3, blo: P3, bhi: P3) -> f64 {
    let g: [f64; 3] = core::array::from_fn(|k| (blo[k] - ahi[k]).max(alo[k] - bhi[k]).max(0.0));
    norm(g)
}

#[derive(PartialEq)]
struct Item(f64, usize);
impl Eq for Item {}
impl PartialOrd for Item {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Item {
    fn cmp(&self, o: &Self) -> Ordering {
        o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
    }
}

impl TautTether {
    /// The points of the polyline: root, contacts, end.
    pub fn points(&self, w: &WrapEdges) -> Vec<P3> {
        let mut v = vec![self.root];
        v.extend(self.contacts.iter().filter_map(|c| w.edge(c.edge).map(|e| e.point(c.t))));
        v.push(self.end);
        v
    }

    /// Total length, metres.
    pub fn length(&self, w: &WrapEdges) -> f64 {
        self.points(w).windows(2).map(|p| dist(p[0], p[1])).sum()
    }

    /// The point the free tether leaves from (the last contact, or the root).
    pub fn last_anchor(&self, w: &WrapEdges) -> P3 {
        self.contacts.last().and_then(|c| w.edge(c.edge)).map_or(self.root, |e| e.point(self.contacts[self.contacts.len() - 1].t))
    }

    /// The shortest tether from `root` to `end` (module docs): straight if free, else the visibility graph's
    /// shortest path over sampled wrap-edge points, tightened and released.
    pub fn shortest(w: &WrapEdges, root: P3, end: P3, sample_m: f64) -> Result<TautTether, TautError> {
        let mut t = TautTether { root, contacts: Vec::new(), end };
        if w.free(root, end) {
            return Ok(t);
        }
        let (_, contacts) = Self::visibility_path(w, root, end, sample_m)?;
        let rev = contacts;
        t.contacts = rev;
        t.relax(w, None)?;
        Ok(t)
    }

    /// A* over the visibility graph of root, end and points `sample_m` apart on every wrap edge: the path's
    /// points and its contacts.
    fn visibility_path(w: &WrapEdges, root: P3, end: P3, sample_m: f64) -> Result<(Vec<P3>, Vec<Contact>), TautError> {
        let mut nodes: Vec<(P3, Option<Contact>)> = vec![(root, None), (end, None)];
        for (k, e) in w.edges.iter().enumerate() {
            let n = (dist(e.a, e.b) / sample_m).ceil().max(1.0) as usize;
            for s in 0..=n {
                let tt = s as f64 / n as f64;
                nodes.push((e.point(tt), Some(Contact { edge: k, t: tt })));
            }
        }
        let n = nodes.len();
        let mut best = vec![f64::INFINITY; n];
        let mut prev = vec![usize::MAX; n];
        let mut done = vec![false; n];
        let mut heap = BinaryHeap::new();
        // A*: the straight distance to the end is a consistent heuristic, so a node's first pop is its shortest
        // distance, and only nodes near the shortest path are expanded (a DEM's edges are many).
        let to_end: Vec<f64> = nodes.iter().map(|(p, _)| dist(*p, end)).collect();
        best[0] = 0.0;
        heap.push(Item(to_end[0], 0));
        while let Some(Item(_, i)) = heap.pop() {
            if done[i] {
                continue;
            }
            done[i] = true;
            if i == 1 {
                break;
            }
            let d = best[i];
            for j in 0..n {
                if done[j] || j == i {
                    continue;
                }
                let nd = d + dist(nodes[i].0, nodes[j].0);
                if nd < best[j] && w.free(nodes[i].0, nodes[j].0) {
                    best[j] = nd;
                    prev[j] = i;
                    heap.push(Item(nd + to_end[j], j));
                }
            }
        }
        if !best[1].is_finite() {
            return Err(TautError::NoPath);
        }
        let (mut pts, mut contacts) = (vec![end], Vec::new());
        let mut k = prev[1];
        while k != usize::MAX {
            pts.push(nodes[k].0);
            if let Some(c) = nodes[k].1 {
                contacts.push(c);
            }
            if k == 0 {
                break;
            }
            k = prev[k];
        }
        pts.reverse();
        contacts.reverse();
        Ok((pts, contacts))
    }

    /// The brute-force length: the visibility graph's shortest path over wrap-edge points `sample_m` apart,
    /// not tightened (the oracle of the tests; exact as `sample_m` goes to 0).
    pub fn shortest_untightened(w: &WrapEdges, root: P3, end: P3, sample_m: f64) -> Result<f64, TautError> {
        if w.free(root, end) {
            return Ok(dist(root, end));
        }
        let (path, _) = Self::visibility_path(w, root, end, sample_m)?;
        Ok(path.windows(2).map(|p| dist(p[0], p[1])).sum())
    }

    /// Move the rover end to `to` (module docs), in steps of at most [`MAX_STEP_M`].
    pub fn update(&mut self, w: &WrapEdges, to: P3) -> Result<(), TautError> {
        let from = self.end;
        let n = (dist(from, to) / MAX_STEP_M).ceil().max(1.0) as usize;
        for k in 1..=n {
            let prev = self.end;
            self.end = add_scaled(from, sub(to, from), k as f64 / n as f64);
            self.relax(w, Some(prev))?;
        }
        Ok(())
    }

    /// Catch, tighten, release until nothing changes (bounded). `prev_end`: the end before this step.
    fn relax(&mut self, w: &WrapEdges, prev_end: Option<P3>) -> Result<(), TautError> {
        for _ in 0..ROUNDS {
            let caught = self.catch(w, prev_end)?;
            self.tighten(w);
            let released = self.release(w);
            if !caught && !released {
                break;
            }
        }
        self.tighten(w);
        let pts = self.points(w);
        if let Some(seg) = pts.windows(2).find(|p| !w.free(p[0], p[1])) {
            return Err(TautError::Stuck { segment: [seg[0], seg[1]] });
        }
        Ok(())
    }

    /// Insert a contact into every blocked segment. True when something was inserted.
    fn catch(&mut self, w: &WrapEdges, prev_end: Option<P3>) -> Result<bool, TautError> {
        let mut changed = false;
        let mut i = 0;
        // Segment i runs from point i to point i + 1 of `points()`.
        while i <= self.contacts.len() {
            let pts = self.points(w);
            let (a, b) = (pts[i], pts[i + 1]);
            if w.free(a, b) {
                i += 1;
                continue;
            }
            if self.contacts.len() >= MAX_CONTACTS {
                return Err(TautError::TooManyContacts);
            }
            // The swept triangle: the segment now and where its far end was (the rover's previous position for
            // the last segment).
            let last = i == self.contacts.len();
            let swept = if last { prev_end.unwrap_or(b) } else { b };
            let mut best: Option<(f64, bool, Contact)> = None;
            // The edges of the segment's own ends cannot route round what blocks it.
            let own = [i.checked_sub(1).and_then(|j| self.contacts.get(j)).map(|c| c.edge), self.contacts.get(i).map(|c| c.edge)];
            let (lo, hi) = bounding_box(&[a, b, swept]);
            for (k, e) in w.edges.iter().enumerate() {
                if own.contains(&Some(k)) {
                    continue;
                }
                // The boxes' gap bounds the distance from below: a cheap exact rejection before the sampled one.
                let (elo, ehi) = bounding_box(&[e.a, e.b]);
                if box_gap(lo, hi, elo, ehi) > CATCH_RADIUS_M
                    || segment_triangle_distance(e.a, e.b, a, b, swept) > CATCH_RADIUS_M
                {
                    continue;
                }
                let t = best_t(e, a, b);
                let q = e.point(t);
                if !w.free(a, q) {
                    continue;
                }
                let both = w.free(q, b);
                let len = dist(a, q) + dist(q, b);
                let better = match best {
                    None => true,
                    Some((bl, bb, _)) => (both && !bb) || (both == bb && len < bl),
                };
                if better {
                    best = Some((len, both, Contact { edge: k, t }));
                }
            }
            let Some((_, _, c)) = best else { return Err(TautError::Stuck { segment: [a, b] }) };
            self.contacts.insert(i, c);
            changed = true;
            // Re-check the new second half next (i + 1) after the first half (i), which is free by choice.
            i += 1;
        }
        Ok(changed)
    }

    /// Slide every contact to its locally shortest position (a few sweeps).
    fn tighten(&mut self, w: &WrapEdges) {
        for _ in 0..8 {
            let mut moved = 0.0f64;
            for i in 0..self.contacts.len() {
                let pts = self.points(w);
                let (a, b) = (pts[i], pts[i + 2]);
                let Some(e) = w.edge(self.contacts[i].edge) else { continue };
                let t = best_t(e, a, b);
                let q = e.point(t);
                if (t - self.contacts[i].t).abs() > 0.0 && w.free(a, q) && w.free(q, b) {
                    moved = moved.max(dist(q, pts[i + 1]));
                    self.contacts[i].t = t;
                }
                // Clamped at an end of its edge: the contact may belong on a neighbouring edge.
                let t = self.contacts[i].t;
                if t <= 0.0 || t >= 1.0 {
                    let here = e.point(t);
                    let end = if t <= 0.0 { e.a } else { e.b };
                    let mut best = (dist(a, here) + dist(here, b), self.contacts[i]);
                    for &k in w.at_vertex.get(&vertex_key(end)).map_or(&[][..], |v| v.as_slice()) {
                        let Some(f) = w.edge(k) else { continue };
                        let tk = best_t(f, a, b);
                        let qk = f.point(tk);
                        let len = dist(a, qk) + dist(qk, b);
                        if len < best.0 - 1e-9 && w.free(a, qk) && w.free(qk, b) {
                            best = (len, Contact { edge: k, t: tk });
                        }
                    }
                    if best.1 != self.contacts[i] {
                        moved = moved.max(dist(here, w.edge(best.1.edge).map_or(here, |f| f.point(best.1.t))));
                        self.contacts[i] = best.1;
                    }
                }
            }
            if moved < 1e-7 {
                break;
            }
        }
    }

    /// Remove contacts the tether does not press into. True when one was removed.
    fn release(&mut self, w: &WrapEdges) -> bool {
        let mut changed = false;
        let mut i = 0;
        while i < self.contacts.len() {
            let pts = self.points(w);
            let (a, q, b) = (pts[i], pts[i + 1], pts[i + 2]);
            let Some(e) = w.edge(self.contacts[i].edge) else {
                self.contacts.remove(i);
                continue;
            };
            // Two contacts at one point: one is enough.
            if dist(a, q) < 1e-6 || dist(q, b) < 1e-6 {
                self.contacts.remove(i);
                changed = true;
                continue;
            }
            let pull = [unit(sub(a, q)), unit(sub(b, q))];
            let s = [pull[0][0] + pull[1][0], pull[0][1] + pull[1][1], pull[0][2] + pull[1][2]];
            // Pressing into the edge: the pull points against the outward direction. A straight-through contact
            // (s = 0) is released too, when the shortcut is free.
            if dot(s, e.out) >= -1e-9 && w.free(a, b) {
                self.contacts.remove(i);
                changed = true;
            } else {
                i += 1;
            }
        }
        changed
    }
}

#[cfg(test)]
mod tests;
