//! [`MeshWorld`]: a closed triangle mesh (an OBJ shape model such as `shared/data/asteroids/itokawa.obj`) as a
//! ground-truth world.
//!
//! ## Frame and scale
//! The mesh keeps the file's frame (the shape models are centred on the body's centre of mass), with every
//! coordinate multiplied by the loader's scale (1000 for kilometres) and by [`MeshWorld::new`]'s extra `scale`
//! (e.g. 0.1 makes the 535 m Itokawa a 53 m rock field whose facets are rover-sized, ~0.8 m). Faces whose
//! winding makes the enclosed volume negative are flipped as a whole so normals point out.
//!
//! ## Signed distance
//! Unsigned distance: exact closest point on each triangle (Ericson, *Real-Time Collision Detection* 5.1.5, f64),
//! minimised over all triangles with a bounding-volume hierarchy (median split of the centroids along the longest
//! axis, leaves of at most [`LEAF_TRIANGLES`], built in the constructor): a node is opened only if its box is
//! closer than the best triangle so far, so the result equals brute force over all triangles (tested).
//!
//! Sign: the **angle-weighted pseudo-normal** (Baerentzen & Aanaes, "Signed distance computation using the angle
//! weighted pseudonormal", IEEE TVCG 2005) of the feature holding the closest point (face normal, sum of the two
//! face normals at an edge, angle-weighted vertex normal): `sign(dot(p - q, n))` is exact for a closed,
//! consistently oriented 2-manifold. It is chosen over ray parity because it is one query (no extra ray casts),
//! it agrees with the gradient by construction, and it does not flip on rays grazing an edge or vertex. Its
//! weakness is a mesh with holes or non-manifold edges: the constructor counts edges that do not have exactly
//! two faces ([`MeshWorld::open_edges`]); if there are any, the world falls back to **ray parity** (majority of
//! three rays in fixed, skew directions), which tolerates a small hole as long as two of the three rays miss it.
//! [`MeshWorld::sign_mode`] says which is in use. Both shipped shape models are closed (pseudo-normals).
//!
//! Gradient: `sign * (p - q) / |p - q|`, q the closest point (zero exactly on the surface).
//!
//! ## Ray casts and heights
//! Ray casts are exact: Moller-Trumbore ("Fast, minimum storage ray/triangle intersection", 1997), two-sided,
//! through the same hierarchy (slab test per box), nearest hit in `[0, max_range]`. [`World::height_at`] is a
//! downward ray cast from above the bounds: the top surface under `(x, y)`, `None` where the vertical misses.
//!
//! Parameters: [`LEAF_TRIANGLES`] = 4 (triangles per leaf; small leaves favour the many distance queries of the
//! ESDF checks over build time, which is a few milliseconds for 16k triangles).

use super::geometry::P3;
use firmware::geom::p3::{self, add_scaled, cross, dot, norm, sub, unit_or};
use super::{Aabb, World};
use crate::terrain::obj::TriMesh;
use crate::truth::solid::{ExactGeometry, Solid};
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};

/// Most triangles in one leaf of the hierarchy. Default 4.
pub const LEAF_TRIANGLES: usize = 4;

/// How the inside/outside sign is decided (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SignMode {
    /// Angle-weighted pseudo-normal of the closest feature (closed 2-manifold meshes).
    PseudoNormal,
    /// Majority of three ray-parity tests (meshes with open or non-manifold edges).
    RayParity,
}

/// Why a mesh cannot become a world.
#[derive(Debug, Clone, PartialEq)]
pub struct MeshWorldError(pub String);

impl core::fmt::Display for MeshWorldError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl core::error::Error for MeshWorldError {}

#[derive(Debug, Clone, Copy)]
struct Node {
    lo: P3,
    hi: P3,
    /// Leaf: first index into `order`; inner: index of the left child (right child is `left + 1`... not
    /// assumed: stored in `right`).
    first: u32,
    /// Leaf: triangle count (> 0); inner: 0.
    count: u32,
    right: u32,
}

/// Feature of a triangle holding a closest point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Feature {
    Vertex(usize),
    /// Edge from corner k to corner (k + 1) % 3.
    Edge(usize),
    Face,
}

/// A closed triangle mesh world.
#[derive(Debug, Clone)]
pub struct MeshWorld {
    name: String,
    verts: Vec<P3>,
    tris: Vec<[u32; 3]>,
    face_n: Vec<P3>,
    vert_n: Vec<P3>,
    /// Per triangle, per edge k (corner k -> k+1): the edge pseudo-normal.
    edge_n: Vec<[P3; 3]>,
    nodes: Vec<Node>,
    order: Vec<u32>,
    lo: P3,
    hi: P3,
    open_edges: usize,
    sign_mode: SignMode,
}

/// `a / |a|`, zero for a zero vector (a degenerate triangle's normal counts for nothing).
fn unit(a: P3) -> P3 {
    unit_or(a, [0.0; 3])
}

/// Squared distance from `p` to the box `[lo, hi]` (0 inside).
fn box_dist2(p: P3, lo: P3, hi: P3) -> f64 {
    let mut s = 0.0;
    for k in 0..3 {
        let d = (lo[k] - p[k]).max(0.0).max(p[k] - hi[k]);
        s += d * d;
    }
    s
}

/// Ray-box slab test: entry parameter if the ray `o + t d` meets the box within `[0, tmax]`.
fn ray_box(o: P3, inv: P3, lo: P3, hi: P3, tmax: f64) -> Option<f64> {
    let mut t0: f64 = 0.0;
    let mut t1 = tmax;
    for k in 0..3 {
        if !inv[k].is_finite() {
            // The ray is parallel to this slab: inside it or never.
            if o[k] < lo[k] || o[k] > hi[k] {
                return None;
            }
            continue;
        }
        let a = (lo[k] - o[k]) * inv[k];
        let b = (hi[k] - o[k]) * inv[k];
        let (a, b) = if a <= b { (a, b) } else { (b, a) };
        t0 = t0.max(a);
        t1 = t1.min(b);
        if t0 > t1 {
            return None;
        }
    }
    Some(t0)
}

/// Closest point on triangle `(a, b, c)` to `p` and the feature it lies on (Ericson 5.1.5).
fn closest_feature(p: P3, a: P3, b: P3, c: P3) -> (P3, Feature) {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Feature::Vertex(0));
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Feature::Vertex(1));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (add_scaled(a, ab, d1 / (d1 - d3)), Feature::Edge(0));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Feature::Vertex(2));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (add_scaled(a, ac, d2 / (d2 - d6)), Feature::Edge(2));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return (add_scaled(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))), Feature::Edge(1));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    (add_scaled(add_scaled(a, ab, v), ac, w), Feature::Face)
}

/// Moller-Trumbore, two-sided: ray parameter of the hit with triangle `(a, b, c)`, if any, `t >= 0`. Barycentric
/// bounds are widened by 1e-12 so a ray through a shared edge is not lost to rounding.
pub fn ray_triangle(o: P3, d: P3, a: P3, b: P3, c: P3) -> Option<f64> {
    let e1 = sub(b, a);
    let e2 = sub(c, a);
    let pv = cross(d, e2);
    let det = dot(e1, pv);
    if det.abs() < 1e-300 {
        return None;
    }
    let inv = 1.0 / det;
    let tv = sub(o, a);
    let u = dot(tv, pv) * inv;
    // A hair of tolerance so a ray through a shared edge or vertex is not missed by both triangles.
    const EPS: f64 = 1e-12;
    if !(-EPS..=1.0 + EPS).contains(&u) {
        return None;
    }
    let qv = cross(tv, e1);
    let v = dot(d, qv) * inv;
    if v < -EPS || u + v > 1.0 + EPS {
        return None;
    }
    let t = dot(e2, qv) * inv;
    (t >= 0.0).then_some(t)
}

/// Fixed, skew directions for ray-parity signs (not unit: parity needs none; no component zero, so no ray runs
/// along a coordinate plane where shape-model vertices often line up).
const PARITY_DIRS: [P3; 3] = [[0.5813, 0.3127, 0.7511], [-0.4172, 0.8566, -0.3035], [0.2063, -0.6612, -0.7214]];

impl MeshWorld {
    /// Builds the world from `mesh` (already in metres), multiplying every coordinate by `scale`.
    pub fn new(name: &str, mesh: &TriMesh, scale: f64) -> Result<MeshWorld, MeshWorldError> {
        let bad = |s: String| Err(MeshWorldError(s));
        if !(scale.is_finite() && scale > 0.0) {
            return bad(format!("scale must be finite and > 0, got {scale}"));
        }
        if mesh.triangles.is_empty() {
            return bad("the mesh has no triangles".into());
        }
        if mesh.triangles.len() >= u32::MAX as usize / 2 {
            return bad(format!("{} triangles is too many", mesh.triangles.len()));
        }
        let verts: Vec<P3> = mesh.vertices.iter().map(|v| p3::scale(*v, scale)).collect();
        if verts.iter().any(|v| !v.iter().all(|x| x.is_finite())) {
            return bad("a vertex is not finite after scaling".into());
        }
        let mut tris = Vec::with_capacity(mesh.triangles.len());
        for (i, t) in mesh.triangles.iter().enumerate() {
            if t.iter().any(|&k| k as usize >= verts.len()) {
                return bad(format!("triangle {i} refers to a missing vertex"));
            }
            tris.push(*t);
        }
        let corner = |t: &[u32; 3], k: usize| verts[t[k] as usize];
        // Orientation: flip everything if the signed volume is negative.
        let vol: f64 = tris.iter().map(|t| dot(corner(t, 0), cross(corner(t, 1), corner(t, 2)))).sum::<f64>() / 6.0;
        if vol < 0.0 {
            for t in &mut tris {
                t.swap(1, 2);
            }
        }
        let face_n: Vec<P3> = tris
            .iter()
            .map(|t| unit(cross(sub(corner(t, 1), corner(t, 0)), sub(corner(t, 2), corner(t, 0)))))
            .collect();
        // Vertex pseudo-normals: incident face normals weighted by the corner angle.
        let mut vert_n = vec![[0.0; 3]; verts.len()];
        for (t, n) in tris.iter().zip(&face_n) {
            for k in 0..3 {
                let p = corner(t, k);
                let e1 = unit(sub(corner(t, (k + 1) % 3), p));
                let e2 = unit(sub(corner(t, (k + 2) % 3), p));
                let ang = dot(e1, e2).clamp(-1.0, 1.0).acos();
                let v = &mut vert_n[t[k] as usize];
                *v = add_scaled(*v, *n, ang);
            }
        }
        // Edges: sort (min, max, triangle, k) to find each edge's faces.
        let mut edges: Vec<(u32, u32, u32, u8)> = Vec::with_capacity(tris.len() * 3);
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.push((a.min(b), a.max(b), i as u32, k as u8));
            }
        }
        edges.sort_unstable();
        let mut edge_n = vec![[[0.0; 3]; 3]; tris.len()];
        let mut open_edges = 0;
        let mut s = 0;
        while s < edges.len() {
            let mut e = s + 1;
            while e < edges.len() && edges[e].0 == edges[s].0 && edges[e].1 == edges[s].1 {
                e += 1;
            }
            if e - s != 2 {
                open_edges += 1;
            }
            let sum = edges[s..e].iter().fold([0.0; 3], |acc, x| p3::add(acc, face_n[x.2 as usize]));
            for x in &edges[s..e] {
                edge_n[x.2 as usize][x.3 as usize] = sum;
            }
            s = e;
        }
        let (lo, hi) = verts.iter().fold(([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]), |(l, h), v| (p3::min(l, *v), p3::max(h, *v)));
        let mut w = MeshWorld {
            name: name.to_string(),
            verts,
            tris,
            face_n,
            vert_n,
            edge_n,
            nodes: Vec::new(),
            order: Vec::new(),
            lo,
            hi,
            open_edges,
            sign_mode: if open_edges == 0 { SignMode::PseudoNormal } else { SignMode::RayParity },
        };
        w.build_bvh();
        Ok(w)
    }

    fn tri(&self, t: usize) -> [P3; 3] {
        let i = self.tris[t];
        [self.verts[i[0] as usize], self.verts[i[1] as usize], self.verts[i[2] as usize]]
    }

    fn build_bvh(&mut self) {
        let n = self.tris.len();
        let cent: Vec<P3> = (0..n)
            .map(|t| {
                let [a, b, c] = self.tri(t);
                p3::scale(p3::add(p3::add(a, b), c), 1.0 / 3.0)
            })
            .collect();
        let mut order: Vec<u32> = (0..n as u32).collect();
        let mut nodes = Vec::with_capacity(2 * n / LEAF_TRIANGLES + 1);
        // Explicit stack of (node index, first, count).
        nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], first: 0, count: 0, right: 0 });
        let mut stack = vec![(0usize, 0usize, n)];
        while let Some((ni, first, count)) = stack.pop() {
            let slice = &mut order[first..first + count];
            let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            let (mut clo, mut chi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
            for &t in slice.iter() {
                for p in self.tri(t as usize) {
                    lo = p3::min(lo, p);
                    hi = p3::max(hi, p);
                }
                clo = p3::min(clo, cent[t as usize]);
                chi = p3::max(chi, cent[t as usize]);
            }
            if count <= LEAF_TRIANGLES {
                nodes[ni] = Node { lo, hi, first: first as u32, count: count as u32, right: 0 };
                continue;
            }
            let ext = sub(chi, clo);
            let axis = if ext[0] >= ext[1] && ext[0] >= ext[2] {
                0
            } else if ext[1] >= ext[2] {
                1
            } else {
                2
            };
            let mid = count / 2;
            slice.select_nth_unstable_by(mid, |a, b| cent[*a as usize][axis].total_cmp(&cent[*b as usize][axis]));
            let left = nodes.len();
            nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], first: 0, count: 0, right: 0 });
            nodes.push(Node { lo: [0.0; 3], hi: [0.0; 3], first: 0, count: 0, right: 0 });
            nodes[ni] = Node { lo, hi, first: left as u32, count: 0, right: left as u32 + 1 };
            stack.push((left, first, mid));
            stack.push((left + 1, first + mid, count - mid));
        }
        self.nodes = nodes;
        self.order = order;
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.tris.len()
    }

    /// The corners of triangle `t` (after scaling and orientation), metres.
    pub fn triangle(&self, t: usize) -> Option<[P3; 3]> {
        (t < self.tris.len()).then(|| self.tri(t))
    }

    /// Edges that do not have exactly two faces (0 for a closed 2-manifold).
    pub fn open_edges(&self) -> usize {
        self.open_edges
    }

    /// The sign rule in use.
    pub fn sign_mode(&self) -> SignMode {
        self.sign_mode
    }

    /// Enclosed volume, cubic metres (positive: normals point out).
    pub fn volume(&self) -> f64 {
        (0..self.tris.len())
            .map(|t| {
                let [a, b, c] = self.tri(t);
                dot(a, cross(b, c))
            })
            .sum::<f64>()
            / 6.0
    }

    /// Unsigned distance, closest point, triangle and feature.
    fn nearest(&self, p: P3) -> (f64, P3, usize, Feature) {
        let mut best = (f64::INFINITY, p, 0usize, Feature::Face);
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let n = self.nodes[ni as usize];
            if box_dist2(p, n.lo, n.hi) >= best.0 {
                continue;
            }
            if n.count > 0 {
                for &t in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let [a, b, c] = self.tri(t as usize);
                    let (q, f) = closest_feature(p, a, b, c);
                    let d = sub(p, q);
                    let d2 = dot(d, d);
                    if d2 < best.0 {
                        best = (d2, q, t as usize, f);
                    }
                }
            } else {
                let (l, r) = (self.nodes[n.first as usize], self.nodes[n.right as usize]);
                let (dl, dr) = (box_dist2(p, l.lo, l.hi), box_dist2(p, r.lo, r.hi));
                // Visit the nearer child first (pushed last).
                if dl <= dr {
                    stack.push(n.right);
                    stack.push(n.first);
                } else {
                    stack.push(n.first);
                    stack.push(n.right);
                }
            }
        }
        (best.0.sqrt(), best.1, best.2, best.3)
    }

    /// Every ray parameter `t >= 0` where the ray `o + t d` crosses the surface (unsorted).
    fn hits(&self, o: P3, d: P3, max_t: f64, mut visit: impl FnMut(f64)) {
        let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let n = self.nodes[ni as usize];
            if ray_box(o, inv, n.lo, n.hi, max_t).is_none() {
                continue;
            }
            if n.count > 0 {
                for &t in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let [a, b, c] = self.tri(t as usize);
                    if let Some(h) = ray_triangle(o, d, a, b, c) {
                        if h <= max_t {
                            visit(h);
                        }
                    }
                }
            } else {
                stack.push(n.right);
                stack.push(n.first);
            }
        }
    }

    /// Nearest hit of the ray `o + t d` (`d` need not be unit) with `t` in `[0, max_t]`.
    pub fn first_hit(&self, o: P3, d: P3, max_t: f64) -> Option<f64> {
        let inv = [1.0 / d[0], 1.0 / d[1], 1.0 / d[2]];
        let mut best = max_t;
        let mut found = false;
        let mut stack: Vec<u32> = Vec::with_capacity(64);
        stack.push(0);
        while let Some(ni) = stack.pop() {
            let n = self.nodes[ni as usize];
            if ray_box(o, inv, n.lo, n.hi, best).is_none() {
                continue;
            }
            if n.count > 0 {
                for &t in &self.order[n.first as usize..(n.first + n.count) as usize] {
                    let [a, b, c] = self.tri(t as usize);
                    if let Some(h) = ray_triangle(o, d, a, b, c) {
                        if h <= best {
                            best = h;
                            found = true;
                        }
                    }
                }
            } else {
                let (l, r) = (self.nodes[n.first as usize], self.nodes[n.right as usize]);
                let tl = ray_box(o, inv, l.lo, l.hi, best);
                let tr = ray_box(o, inv, r.lo, r.hi, best);
                match (tl, tr) {
                    (Some(a), Some(b)) if a <= b => {
                        stack.push(n.right);
                        stack.push(n.first);
                    }
                    (Some(_), Some(_)) => {
                        stack.push(n.first);
                        stack.push(n.right);
                    }
                    (Some(_), None) => stack.push(n.first),
                    (None, Some(_)) => stack.push(n.right),
                    (None, None) => {}
                }
            }
        }
        found.then_some(best)
    }

    /// Inside test by ray parity: odd number of crossings along the fixed direction `k` (0..3).
    pub fn inside_by_parity(&self, p: P3, k: usize) -> bool {
        let mut n = 0usize;
        self.hits(p, PARITY_DIRS[k % 3], f64::INFINITY, |_| n += 1);
        n % 2 == 1
    }

    /// Signed distance (negative inside) and closest surface point, f64.
    pub fn sdf_closest(&self, p: P3) -> (f64, P3) {
        let (d, q, t, f) = self.nearest(p);
        let inside = match self.sign_mode {
            SignMode::PseudoNormal => {
                let n = match f {
                    Feature::Face => self.face_n[t],
                    Feature::Edge(k) => self.edge_n[t][k],
                    Feature::Vertex(k) => self.vert_n[self.tris[t][k] as usize],
                };
                dot(sub(p, q), n) < 0.0
            }
            SignMode::RayParity => (0..3).filter(|&k| self.inside_by_parity(p, k)).count() >= 2,
        };
        (if inside { -d } else { d }, q)
    }
}

impl DistanceField for MeshWorld {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        let q = [p.x as f64, p.y as f64, p.z as f64];
        if !q.iter().all(|x| x.is_finite()) {
            return DistanceQuery::Unknown;
        }
        let (d, c) = self.sdf_closest(q);
        let v = sub(q, c);
        let n = norm(v);
        let s = if d >= 0.0 { 1.0 } else { -1.0 };
        let gradient =
            if n > 1e-12 { Vec3::new((s * v[0] / n) as Real, (s * v[1] / n) as Real, (s * v[2] / n) as Real) } else { Vec3::zeros() };
        DistanceQuery::Known { distance: d as Real, gradient }
    }
}

impl World for MeshWorld {
    fn name(&self) -> &str {
        &self.name
    }

    fn bounds(&self) -> Aabb {
        let v = |a: P3| Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
        Aabb { min: v(self.lo), max: v(self.hi) }
    }

    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
        let o = [origin.x as f64, origin.y as f64, origin.z as f64];
        let d = unit([dir.x as f64, dir.y as f64, dir.z as f64]);
        if norm(d) == 0.0 || max_range.is_nan() || max_range < 0.0 {
            return None;
        }
        self.first_hit(o, d, max_range as f64).map(|t| t as Real)
    }

    fn height_at(&self, x: Real, y: Real) -> Option<Real> {
        let top = self.hi[2] + 1.0;
        let t = self.first_hit([x as f64, y as f64, top], [0.0, 0.0, -1.0], top - self.lo[2] + 1.0)?;
        Some((top - t) as Real)
    }

    fn exact_geometry(&self) -> ExactGeometry {
        ExactGeometry { solids: vec![Solid::Mesh { vertices: self.verts.clone(), triangles: self.tris.clone() }] }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::geometry::closest_point_on_triangle;

    /// SplitMix64 uniform numbers for test points (independent of the code under test).
    pub(crate) struct Uni(pub u64);
    impl Uni {
        pub(crate) fn random_range(&mut self, r: core::ops::Range<f64>) -> f64 {
            self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
            let mut z = self.0;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            r.start + (r.end - r.start) * ((z >> 11) as f64 / (1u64 << 53) as f64)
        }
    }

    /// An icosphere of radius `r`: subdivided icosahedron, counter-clockwise seen from outside.
    pub(crate) fn icosphere(r: f64, subdivisions: usize) -> TriMesh {
        let g = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<P3> = [
            [-1.0, g, 0.0], [1.0, g, 0.0], [-1.0, -g, 0.0], [1.0, -g, 0.0],
            [0.0, -1.0, g], [0.0, 1.0, g], [0.0, -1.0, -g], [0.0, 1.0, -g],
            [g, 0.0, -1.0], [g, 0.0, 1.0], [-g, 0.0, -1.0], [-g, 0.0, 1.0],
        ]
        .iter()
        .map(|p| p3::scale(unit(*p), r))
        .collect();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5], [0, 5, 1], [0, 1, 7], [0, 7, 10], [0, 10, 11], [1, 5, 9], [5, 11, 4], [11, 10, 2],
            [10, 7, 6], [7, 1, 8], [3, 9, 4], [3, 4, 2], [3, 2, 6], [3, 6, 8], [3, 8, 9], [4, 9, 5],
            [2, 4, 11], [6, 2, 10], [8, 6, 7], [9, 8, 1],
        ];
        for _ in 0..subdivisions {
            let mut mid = std::collections::BTreeMap::new();
            let mut m = |a: u32, b: u32, v: &mut Vec<P3>| -> u32 {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push(p3::scale(unit(p3::add(v[a as usize], v[b as usize])), r));
                    v.len() as u32 - 1
                })
            };
            let mut nf = Vec::new();
            for t in &f {
                let ab = m(t[0], t[1], &mut v);
                let bc = m(t[1], t[2], &mut v);
                let ca = m(t[2], t[0], &mut v);
                nf.extend([[t[0], ab, ca], [t[1], bc, ab], [t[2], ca, bc], [ab, bc, ca]]);
            }
            f = nf;
        }
        TriMesh { vertices: v, triangles: f }
    }

    fn brute(w: &MeshWorld, p: P3) -> f64 {
        (0..w.triangle_count())
            .map(|t| {
                let [a, b, c] = w.triangle(t).unwrap();
                norm(sub(p, closest_point_on_triangle(p, a, b, c)))
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn icosphere_distance_matches_brute_force_and_sign_matches_parity() {
        let w = MeshWorld::new("ico", &icosphere(2.0, 2), 1.0).unwrap();
        assert_eq!(w.open_edges(), 0);
        assert_eq!(w.sign_mode(), SignMode::PseudoNormal);
        let mut rng = Uni(7);
        for _ in 0..2000 {
            let p = [rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0), rng.random_range(-3.0..3.0)];
            let (sd, _) = w.sdf_closest(p);
            let b = brute(&w, p);
            assert!((sd.abs() - b).abs() < 1e-12, "{p:?}: {sd} vs brute {b}");
            assert_eq!(sd < 0.0, w.inside_by_parity(p, 0), "{p:?}: sd {sd}");
        }
    }

    #[test]
    fn reversed_winding_is_flipped_outward() {
        let mut m = icosphere(1.0, 1);
        for t in &mut m.triangles {
            t.swap(1, 2);
        }
        let w = MeshWorld::new("ico", &m, 3.0).unwrap();
        assert!(w.volume() > 0.0);
        let (d, _) = w.sdf_closest([0.0; 3]);
        assert!(d < -2.5, "{d}");
        let (d, _) = w.sdf_closest([4.0, 0.0, 0.0]);
        assert!((d - 1.0).abs() < 1e-9, "{d}");
    }

    #[test]
    fn an_open_mesh_falls_back_to_ray_parity() {
        let mut m = icosphere(1.0, 2);
        m.triangles.pop();
        let w = MeshWorld::new("holed", &m, 1.0).unwrap();
        assert_eq!(w.open_edges(), 3);
        assert_eq!(w.sign_mode(), SignMode::RayParity);
        assert!(w.sdf_closest([0.1, 0.05, 0.0]).0 < 0.0);
        assert!(w.sdf_closest([1.5, 0.0, 0.2]).0 > 0.0);
    }

    #[test]
    fn raycast_matches_brute_force() {
        let w = MeshWorld::new("ico", &icosphere(2.0, 2), 1.0).unwrap();
        let mut rng = Uni(3);
        for _ in 0..1000 {
            let o = [rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0), rng.random_range(-4.0..4.0)];
            let d = unit([rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)]);
            let brute = (0..w.triangle_count())
                .filter_map(|t| {
                    let [a, b, c] = w.triangle(t).unwrap();
                    ray_triangle(o, d, a, b, c)
                })
                .filter(|&t| t <= 5.0)
                .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
            let got = w.first_hit(o, d, 5.0);
            match (got, brute) {
                (Some(a), Some(b)) => assert!((a - b).abs() < 1e-12, "{a} vs {b}"),
                (None, None) => {}
                _ => panic!("{o:?} {d:?}: {got:?} vs {brute:?}"),
            }
        }
        // A ray from the centre hits the sphere between the inscribed and the circumscribed radius.
        let t = w.raycast(&Vec3::zeros(), &Vec3::new(0.3, -0.2, 0.9), 10.0).unwrap();
        assert!(t > 1.9 && t <= 2.0 + 1e-6, "{t}");
        let h = w.height_at(0.0, 0.0).unwrap();
        assert!(h > 1.9 && h <= 2.0 + 1e-6, "{h}");
        assert!(w.height_at(3.0, 0.0).is_none());
    }

    #[test]
    fn bad_meshes_are_rejected() {
        let w = MeshWorld::new("x", &icosphere(1.0, 0), 1.0).unwrap();
        assert_eq!(w.query(&Vec3::new(f32::NAN, 0.0, 0.0)), DistanceQuery::Unknown);
        assert!(MeshWorld::new("x", &TriMesh::default(), 1.0).is_err());
        assert!(MeshWorld::new("x", &icosphere(1.0, 0), f64::NAN).is_err());
        assert!(MeshWorld::new("x", &icosphere(1.0, 0), 0.0).is_err());
    }
}
