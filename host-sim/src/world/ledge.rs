//! The 55-degree ledge worlds of Paton et al. section VI-A (Fig. 8; `shared/SCENARIOS.md` section A), with exact
//! signed distance and exact ray casts.
//!
//! # Coordinate convention
//! World frame: x east, y north, z up, metres. The flat ground is the plane `z = 0` (solid below).
//! The ledge is a prism standing on the ground:
//! - top face `z = 4` over `x in [-5, 0]`, `y in [-5, 5]` (the ledge is 10 m long along y, 5 m deep along x,
//!   4 m high: the 10 x 5 x 4 m of the paper, whose text does not say whether the slope is included in the 5 m;
//!   here it is added in front of the 5 m top);
//! - back wall `x = -5` and side walls `y = +-5`, vertical;
//! - the slope: the face from the lip `x = 0, z = 4` down to the toe `x = 4 / tan(55 deg) = 2.8008 m, z = 0`,
//!   descending towards +x, inclined 55 degrees to the horizontal.
//!
//! With the pole ([`LedgeWorld::with_pole`], test 3): a vertical cylinder of radius [`POLE_RADIUS_M`] = 0.25 m
//! standing on the top face at [`POLE_CENTRE_XY`] = (-2.5, 0) (the middle of the ledge top) and rising
//! [`POLE_HEIGHT_M`] = 6 m above it (to z = 10 m). Assumptions, since the paper gives no numbers: "tall" is taken as
//! higher than the root anchors of tests 1-3 (z = 6.35 m), so a taut tether wraps around the pole's side and never
//! slips over its cap; 0.25 m is a stout post a tether can wrap.
//!
//! # Tests 1-3 (start, goal, root anchors)
//! - Start ([`START_GROUND`]): the ground point (-1.5, 0, 4) on the ledge top, 1.5 m behind the lip, rover facing
//!   +x (down the slope). The rover reference point is the axle centre, one wheel radius (0.35 m) above the
//!   ground: [`START_AXLE`] = (-1.5, 0, 4.35).
//! - Goal ([`GOAL_GROUND`]): (6.0, 0, 0) on the flat ground, 3.2 m beyond the toe of the slope.
//! - Test 1 root anchor ([`ROOT_ANCHOR_TEST1`]): 4.9 m behind and 2.0 m above the rover's axle centre:
//!   (-6.4, 0, 6.35), i.e. 1.4 m behind the ledge's back wall, in the air (a mast or a lander).
//! - Tests 2 and 3 root anchor ([`ROOT_ANCHOR_TEST2`]): 8.2 m in front of and 2.0 m above the axle centre:
//!   (6.7, 0, 6.35), above the flat ground beyond the slope.
//!
//! # Distance and gradient
//! The terrain's boundary is a union of planar faces (ground outside the ledge's footprint, top, back, two sides,
//! slope) plus, with the pole, the pole's side and cap (and the top face gets a hole under the pole). The unsigned
//! distance is the exact minimum over these faces (computed in f64); its sign comes from an exact inside test;
//! the gradient is `(q - c) / |q - c|` (outside) or `(c - q) / |q - c|` (inside), with `c` the closest boundary
//! point, so it always points away from the terrain; on the surface itself it is the face normal.
//! Ray casts intersect every face exactly; a ray starting inside the terrain hits at distance 0.

use super::{Aabb, World};
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};

/// Slope angle of the ledge's front face, degrees.
pub const SLOPE_DEG: f64 = 55.0;
/// Height of the ledge top above the ground, metres.
pub const LEDGE_HEIGHT_M: f64 = 4.0;
/// Depth of the ledge top along x (from the back wall at x = -5 to the lip at x = 0), metres.
pub const LEDGE_DEPTH_M: f64 = 5.0;
/// Half of the ledge's length along y (10 m long), metres.
pub const LEDGE_HALF_WIDTH_M: f64 = 5.0;
/// Radius of the test-3 pole, metres (assumption, see the module docs).
pub const POLE_RADIUS_M: f64 = 0.25;
/// Height of the test-3 pole above the ledge top, metres (assumption, see the module docs).
pub const POLE_HEIGHT_M: f64 = 6.0;
/// Centre of the test-3 pole on the ledge top, (x, y) metres.
pub const POLE_CENTRE_XY: [f64; 2] = [-2.5, 0.0];
/// Start ground point of tests 1-3 (on the ledge top, facing +x).
pub const START_GROUND: [f64; 3] = [-1.5, 0.0, 4.0];
/// Start axle centre (rover reference point) of tests 1-3: one wheel radius above [`START_GROUND`].
pub const START_AXLE: [f64; 3] = [-1.5, 0.0, 4.35];
/// Goal ground point of tests 1-3 (flat ground below the slope).
pub const GOAL_GROUND: [f64; 3] = [6.0, 0.0, 0.0];
/// Test 1 root anchor: 4.9 m behind and 2.0 m above the start axle centre.
pub const ROOT_ANCHOR_TEST1: [f64; 3] = [-6.4, 0.0, 6.35];
/// Tests 2 and 3 root anchor: 8.2 m in front of and 2.0 m above the start axle centre.
pub const ROOT_ANCHOR_TEST2: [f64; 3] = [6.7, 0.0, 6.35];

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn dist(a: P, b: P) -> f64 {
    let d = sub(a, b);
    dot(d, d).sqrt()
}

/// x of the slope's toe (where the slope meets the ground), metres.
pub fn toe_x() -> f64 {
    LEDGE_HEIGHT_M / SLOPE_DEG.to_radians().tan()
}

/// A planar convex face: vertices (counter-clockwise seen from outside) and outward unit normal.
#[derive(Debug, Clone)]
struct Face {
    verts: Vec<P>,
    normal: P,
}

impl Face {
    fn new(verts: Vec<P>) -> Self {
        // Newell's method for the normal.
        let mut n = [0.0; 3];
        for (i, a) in verts.iter().enumerate() {
            let b = verts[(i + 1) % verts.len()];
            n[0] += (a[1] - b[1]) * (a[2] + b[2]);
            n[1] += (a[2] - b[2]) * (a[0] + b[0]);
            n[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        let l = dot(n, n).sqrt();
        Face { verts, normal: [n[0] / l, n[1] / l, n[2] / l] }
    }

    fn contains_projection(&self, q: P) -> bool {
        let n = self.normal;
        self.verts.iter().enumerate().all(|(i, a)| {
            let b = self.verts[(i + 1) % self.verts.len()];
            let e = sub(b, *a);
            let w = sub(q, *a);
            // (e x w) . n >= 0 for a point left of the edge (CCW seen from outside).
            let c = [e[1] * w[2] - e[2] * w[1], e[2] * w[0] - e[0] * w[2], e[0] * w[1] - e[1] * w[0]];
            dot(c, n) >= -1e-12
        })
    }

    fn closest(&self, q: P) -> P {
        let a0 = self.verts[0];
        let h = dot(sub(q, a0), self.normal);
        let proj = [q[0] - h * self.normal[0], q[1] - h * self.normal[1], q[2] - h * self.normal[2]];
        if self.contains_projection(proj) {
            return proj;
        }
        let mut best = a0;
        let mut bd = f64::INFINITY;
        for (i, a) in self.verts.iter().enumerate() {
            let b = self.verts[(i + 1) % self.verts.len()];
            let c = closest_on_segment(q, *a, b);
            let d = dist(q, c);
            if d < bd {
                bd = d;
                best = c;
            }
        }
        best
    }

    fn ray(&self, o: P, d: P) -> Option<f64> {
        let den = dot(d, self.normal);
        if den.abs() < 1e-15 {
            return None;
        }
        let t = dot(sub(self.verts[0], o), self.normal) / den;
        if t < 0.0 {
            return None;
        }
        let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
        self.contains_projection(p).then_some(t)
    }
}

fn closest_on_segment(q: P, a: P, b: P) -> P {
    let ab = sub(b, a);
    let l2 = dot(ab, ab);
    let t = if l2 > 0.0 { (dot(sub(q, a), ab) / l2).clamp(0.0, 1.0) } else { 0.0 };
    [a[0] + t * ab[0], a[1] + t * ab[1], a[2] + t * ab[2]]
}

/// The ledge world, optionally with the test-3 pole. See the module docs for the geometry.
#[derive(Debug, Clone)]
pub struct LedgeWorld {
    name: &'static str,
    faces: Vec<Face>,
    pole: bool,
}

impl LedgeWorld {
    /// Flat ground plus the ledge with its 55-degree slope (tests 1 and 2).
    pub fn new() -> Self {
        Self::build(false)
    }

    /// The ledge plus a tall pole in the middle of its top (test 3).
    pub fn with_pole() -> Self {
        Self::build(true)
    }

    fn build(pole: bool) -> Self {
        let h = LEDGE_HEIGHT_M;
        let w = LEDGE_HALF_WIDTH_M;
        let xb = -LEDGE_DEPTH_M;
        let xt = toe_x();
        let faces = vec![
            // slope (normal +x,+z)
            Face::new(vec![[0.0, w, h], [0.0, -w, h], [xt, -w, 0.0], [xt, w, 0.0]]),
            // back wall (normal -x)
            Face::new(vec![[xb, -w, h], [xb, w, h], [xb, w, 0.0], [xb, -w, 0.0]]),
            // side y = +w (normal +y)
            Face::new(vec![[xb, w, h], [0.0, w, h], [xt, w, 0.0], [xb, w, 0.0]]),
            // side y = -w (normal -y)
            Face::new(vec![[0.0, -w, h], [xb, -w, h], [xb, -w, 0.0], [xt, -w, 0.0]]),
        ];
        LedgeWorld { name: if pole { "ledge55-pole" } else { "ledge55" }, faces, pole }
    }

    /// True when the world has the test-3 pole.
    pub fn has_pole(&self) -> bool {
        self.pole
    }

    /// Exact inside test (closed solid, points on the surface count as inside).
    pub fn inside(&self, q: P) -> bool {
        if q[2] <= 0.0 {
            return true;
        }
        if self.pole && self.in_pole(q) {
            return true;
        }
        let in_y = q[1].abs() <= LEDGE_HALF_WIDTH_M;
        let in_x = q[0] >= -LEDGE_DEPTH_M;
        let under = q[2] <= LEDGE_HEIGHT_M && q[2] <= LEDGE_HEIGHT_M - q[0] * SLOPE_DEG.to_radians().tan();
        in_y && in_x && under
    }

    fn in_pole(&self, q: P) -> bool {
        let dx = q[0] - POLE_CENTRE_XY[0];
        let dy = q[1] - POLE_CENTRE_XY[1];
        dx * dx + dy * dy <= POLE_RADIUS_M * POLE_RADIUS_M
            && q[2] >= LEDGE_HEIGHT_M
            && q[2] <= LEDGE_HEIGHT_M + POLE_HEIGHT_M
    }

    /// The closest boundary point to `q` and the outward normal of the face it lies on.
    fn closest_boundary(&self, q: P) -> (P, P) {
        let mut best = ([0.0; 3], [0.0, 0.0, 1.0]);
        let mut bd = f64::INFINITY;
        let mut consider = |c: P, n: P| {
            let d = dist(q, c);
            if d < bd {
                bd = d;
                best = (c, n);
            }
        };
        for f in &self.faces {
            consider(f.closest(q), f.normal);
        }
        // Ground outside the footprint rectangle [xb, xt] x [-w, w].
        let (xb, xt, w) = (-LEDGE_DEPTH_M, toe_x(), LEDGE_HALF_WIDTH_M);
        consider(closest_outside_rect(q, xb, xt, w), [0.0, 0.0, 1.0]);
        // Top rectangle [xb, 0] x [-w, w] at z = h, minus the pole's disk.
        let h = LEDGE_HEIGHT_M;
        let top = [q[0].clamp(xb, 0.0), q[1].clamp(-w, w), h];
        let [cx, cy] = POLE_CENTRE_XY;
        let r = POLE_RADIUS_M;
        let (dx, dy) = (top[0] - cx, top[1] - cy);
        let rho = (dx * dx + dy * dy).sqrt();
        if self.pole && rho < r {
            let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
            consider([cx + r * ux, cy + r * uy, h], [0.0, 0.0, 1.0]);
        } else {
            consider(top, [0.0, 0.0, 1.0]);
        }
        if self.pole {
            let (dx, dy) = (q[0] - cx, q[1] - cy);
            let rho = (dx * dx + dy * dy).sqrt();
            let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
            // side
            let z = q[2].clamp(h, h + POLE_HEIGHT_M);
            consider([cx + r * ux, cy + r * uy, z], [ux, uy, 0.0]);
            // cap
            let s = rho.min(r);
            consider([cx + s * ux, cy + s * uy, h + POLE_HEIGHT_M], [0.0, 0.0, 1.0]);
        }
        best
    }

    /// Exact signed distance (negative inside) and gradient (away from the terrain), in f64.
    pub fn sdf(&self, q: P) -> (f64, P) {
        let (c, n) = self.closest_boundary(q);
        let d = dist(q, c);
        let inside = self.inside(q);
        if d < 1e-9 {
            return (0.0, n);
        }
        let v = sub(q, c);
        let s = if inside { -1.0 } else { 1.0 };
        (s * d, [s * v[0] / d, s * v[1] / d, s * v[2] / d])
    }

    /// Exact ray cast in f64: distance along the unit `dir` to the first surface point, up to `max_range`.
    pub fn raycast_f64(&self, o: P, d: P, max_range: f64) -> Option<f64> {
        if self.inside(o) {
            return Some(0.0);
        }
        let mut best = f64::INFINITY;
        for f in &self.faces {
            if let Some(t) = f.ray(o, d) {
                best = best.min(t);
            }
        }
        let (xb, xt, w, h) = (-LEDGE_DEPTH_M, toe_x(), LEDGE_HALF_WIDTH_M, LEDGE_HEIGHT_M);
        // ground plane (outside the footprint) and top face
        for (z, on) in [(0.0, false), (h, true)] {
            if d[2].abs() > 1e-15 {
                let t = (z - o[2]) / d[2];
                if t >= 0.0 {
                    let (x, y) = (o[0] + t * d[0], o[1] + t * d[1]);
                    let in_rect = if on {
                        x >= xb && x <= 0.0 && y.abs() <= w
                    } else {
                        x >= xb && x <= xt && y.abs() <= w
                    };
                    if in_rect == on {
                        best = best.min(t);
                    }
                }
            }
        }
        if self.pole {
            let [cx, cy] = POLE_CENTRE_XY;
            let r = POLE_RADIUS_M;
            let (ox, oy) = (o[0] - cx, o[1] - cy);
            let a = d[0] * d[0] + d[1] * d[1];
            if a > 1e-15 {
                let b = 2.0 * (ox * d[0] + oy * d[1]);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if disc >= 0.0 {
                    let t = (-b - disc.sqrt()) / (2.0 * a);
                    let z = o[2] + t * d[2];
                    if t >= 0.0 && z >= h && z <= h + POLE_HEIGHT_M {
                        best = best.min(t);
                    }
                }
            }
            if d[2].abs() > 1e-15 {
                let t = (h + POLE_HEIGHT_M - o[2]) / d[2];
                let (x, y) = (o[0] + t * d[0] - cx, o[1] + t * d[1] - cy);
                if t >= 0.0 && x * x + y * y <= r * r {
                    best = best.min(t);
                }
            }
        }
        (best <= max_range).then_some(best)
    }

    /// Top-surface height under (x, y), f64.
    pub fn height_f64(&self, x: f64, y: f64) -> f64 {
        let [cx, cy] = POLE_CENTRE_XY;
        if self.pole && (x - cx).powi(2) + (y - cy).powi(2) <= POLE_RADIUS_M * POLE_RADIUS_M {
            return LEDGE_HEIGHT_M + POLE_HEIGHT_M;
        }
        if y.abs() > LEDGE_HALF_WIDTH_M || x < -LEDGE_DEPTH_M {
            return 0.0;
        }
        if x <= 0.0 {
            LEDGE_HEIGHT_M
        } else {
            (LEDGE_HEIGHT_M - x * SLOPE_DEG.to_radians().tan()).max(0.0)
        }
    }
}

impl Default for LedgeWorld {
    fn default() -> Self {
        Self::new()
    }
}

/// Closest point to `q` on the plane z = 0 outside the rectangle [x0, x1] x [-w, w].
fn closest_outside_rect(q: P, x0: f64, x1: f64, w: f64) -> P {
    let (x, y) = (q[0], q[1]);
    if x < x0 || x > x1 || y.abs() > w {
        return [x, y, 0.0];
    }
    // Inside the rectangle: move to the nearest edge.
    let cands = [(x - x0, [x0, y]), (x1 - x, [x1, y]), (w - y, [x, w]), (y + w, [x, -w])];
    let mut best = cands[0];
    for c in cands {
        if c.0 < best.0 {
            best = c;
        }
    }
    [best.1[0], best.1[1], 0.0]
}

fn to_p(v: &Vec3) -> P {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

impl DistanceField for LedgeWorld {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        if !firmware::geom::is_finite3(p) {
            return DistanceQuery::Unknown;
        }
        let (d, g) = self.sdf(to_p(p));
        DistanceQuery::Known {
            distance: d as Real,
            gradient: Vec3::new(g[0] as Real, g[1] as Real, g[2] as Real),
        }
    }
}

impl World for LedgeWorld {
    fn name(&self) -> &str {
        self.name
    }

    fn bounds(&self) -> Aabb {
        let top = if self.pole { LEDGE_HEIGHT_M + POLE_HEIGHT_M } else { LEDGE_HEIGHT_M };
        Aabb { min: Vec3::new(-10.0, -10.0, 0.0), max: Vec3::new(12.0, 10.0, top as Real) }
    }

    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
        self.raycast_f64(to_p(origin), to_p(dir), f64::from(max_range)).map(|t| t as Real)
    }

    fn height_at(&self, x: Real, y: Real) -> Option<Real> {
        Some(self.height_f64(f64::from(x), f64::from(y)) as Real)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;
    use rand_pcg::Pcg64;

    fn rng() -> Pcg64 {
        Pcg64::new(0xcafe_f00d_d15e_a5e5, 0xa02_bdbf_7bb3_c0a7)
    }
    fn unif(r: &mut Pcg64, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (r.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Independent boundary sampling: points on every face of the union surface on a grid of spacing `h`,
    /// classified by the inside test of a neighbourhood (a boundary point has inside and outside points nearby).
    fn surface_samples(w: &LedgeWorld, h: f64) -> Vec<P> {
        let mut pts = Vec::new();
        let n = |a: f64, b: f64| ((b - a) / h).ceil() as usize;
        let xt = toe_x();
        // ground around (clipped to a box of interest)
        for i in 0..=n(-9.0, 9.0) {
            for j in 0..=n(-8.0, 8.0) {
                let (x, y) = (-9.0 + i as f64 * h, -8.0 + j as f64 * h);
                if !(x >= -5.0 && x <= xt && y.abs() <= 5.0) {
                    pts.push([x, y, 0.0]);
                }
            }
        }
        // top and slope, as a height field over the footprint
        for i in 0..=n(-5.0, xt) {
            for j in 0..=n(-5.0, 5.0) {
                let (x, y) = ((-5.0 + i as f64 * h).min(xt), (-5.0 + j as f64 * h).min(5.0));
                let z = if x <= 0.0 { 4.0 } else { 4.0 - x * SLOPE_DEG.to_radians().tan() };
                if !(w.pole && (x + 2.5).powi(2) + y * y < POLE_RADIUS_M.powi(2)) {
                    pts.push([x, y, z]);
                }
                // slope face sampled along its own length too (it is steep)
            }
        }
        let ls = 4.0 / SLOPE_DEG.to_radians().sin();
        for i in 0..=n(0.0, ls) {
            for j in 0..=n(-5.0, 5.0) {
                let s = (i as f64 * h).min(ls);
                let a = SLOPE_DEG.to_radians();
                pts.push([s * a.cos(), (-5.0 + j as f64 * h).min(5.0), 4.0 - s * a.sin()]);
            }
        }
        // walls
        for i in 0..=n(0.0, 4.0) {
            let z = (i as f64 * h).min(4.0);
            for j in 0..=n(-5.0, 5.0) {
                pts.push([-5.0, (-5.0 + j as f64 * h).min(5.0), z]);
            }
            let xe = if z >= 4.0 { 0.0 } else { (4.0 - z) / SLOPE_DEG.to_radians().tan() };
            for k in 0..=n(-5.0, xe) {
                let x = (-5.0 + k as f64 * h).min(xe);
                pts.push([x, 5.0, z]);
                pts.push([x, -5.0, z]);
            }
        }
        if w.pole {
            let r = POLE_RADIUS_M;
            let m = (2.0 * core::f64::consts::PI * r / h).ceil() as usize;
            for k in 0..m {
                let a = k as f64 * 2.0 * core::f64::consts::PI / m as f64;
                for i in 0..=n(4.0, 10.0) {
                    pts.push([-2.5 + r * a.cos(), r * a.sin(), (4.0 + i as f64 * h).min(10.0)]);
                }
                for i in 0..=n(0.0, r) {
                    let s = (i as f64 * h).min(r);
                    pts.push([-2.5 + s * a.cos(), s * a.sin(), 10.0]);
                }
            }
        }
        pts
    }

    fn check_against_samples(w: &LedgeWorld, seed_shift: u64) {
        let h = 0.05;
        let pts = surface_samples(w, h);
        let mut r = rng();
        for _ in 0..seed_shift {
            r.next_u64();
        }
        for _ in 0..300 {
            let q = [unif(&mut r, -7.0, 5.0), unif(&mut r, -6.0, 6.0), unif(&mut r, -1.0, 7.0)];
            let brute = pts.iter().map(|p| dist(q, *p)).fold(f64::INFINITY, f64::min);
            let (d, g) = w.sdf(q);
            // Sampling error of the oracle is at most h / sqrt(2) on a grid of spacing h.
            assert!(d.abs() <= brute + 1e-9, "exact distance {d} exceeds sampled {brute} at {q:?}");
            assert!(brute - d.abs() <= h * 0.75, "distance {d} vs sampled {brute} at {q:?}");
            // sign: independent inside test by the height field (no overhangs except the pole)
            let hf = w.height_f64(q[0], q[1]);
            assert_eq!(d < 0.0, q[2] < hf - 1e-9 && d.abs() > 1e-9, "sign at {q:?}: d {d} height {hf}");
            let gn = dot(g, g).sqrt();
            assert!((gn - 1.0).abs() < 1e-9);
        }
    }

    #[test]
    fn distance_matches_sampled_surface_ledge() {
        check_against_samples(&LedgeWorld::new(), 0);
    }

    #[test]
    fn distance_matches_sampled_surface_pole() {
        check_against_samples(&LedgeWorld::with_pole(), 1000);
    }

    #[test]
    fn gradient_matches_finite_differences() {
        for w in [LedgeWorld::new(), LedgeWorld::with_pole()] {
            let mut r = rng();
            let mut checked = 0;
            for _ in 0..2000 {
                let q = [unif(&mut r, -7.0, 5.0), unif(&mut r, -6.0, 6.0), unif(&mut r, -1.0, 7.0)];
                let (d, g) = w.sdf(q);
                let e = 1e-6;
                let fd: Vec<f64> = (0..3)
                    .map(|k| {
                        let mut a = q;
                        let mut b = q;
                        a[k] += e;
                        b[k] -= e;
                        (w.sdf(a).0 - w.sdf(b).0) / (2.0 * e)
                    })
                    .collect();
                let fdn = (fd[0] * fd[0] + fd[1] * fd[1] + fd[2] * fd[2]).sqrt();
                // skip the medial axis (kinks), where the finite difference is not a unit vector
                if (fdn - 1.0).abs() > 1e-4 || d.abs() < 1e-3 {
                    continue;
                }
                checked += 1;
                for k in 0..3 {
                    assert!((fd[k] - g[k]).abs() < 1e-4, "gradient {g:?} vs fd {fd:?} at {q:?}");
                }
            }
            assert!(checked > 1500, "too few smooth points checked: {checked}");
        }
    }

    #[test]
    fn raycast_matches_marching_with_inside_test() {
        for w in [LedgeWorld::new(), LedgeWorld::with_pole()] {
            let mut r = rng();
            let mut hits = 0;
            for _ in 0..500 {
                let o = [unif(&mut r, -8.0, 8.0), unif(&mut r, -7.0, 7.0), unif(&mut r, 0.1, 12.0)];
                if w.inside(o) {
                    assert_eq!(w.raycast_f64(o, [0.0, 0.0, -1.0], 100.0), Some(0.0));
                    continue;
                }
                let (th, ph) = (unif(&mut r, 0.0, core::f64::consts::TAU), unif(&mut r, -1.5, 1.2));
                let d = [ph.cos() * th.cos(), ph.cos() * th.sin(), ph.sin()];
                let got = w.raycast_f64(o, d, 30.0);
                // oracle: march with the inside test, then bisect
                let step = 0.002;
                let mut t = 0.0;
                let mut oracle = None;
                while t < 30.0 {
                    let p = [o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]];
                    if w.inside(p) {
                        let (mut lo, mut hi) = (t - step, t);
                        for _ in 0..50 {
                            let m = 0.5 * (lo + hi);
                            let pm = [o[0] + m * d[0], o[1] + m * d[1], o[2] + m * d[2]];
                            if w.inside(pm) {
                                hi = m
                            } else {
                                lo = m
                            }
                        }
                        oracle = Some(hi);
                        break;
                    }
                    t += step;
                }
                match (got, oracle) {
                    (Some(a), Some(b)) => {
                        hits += 1;
                        assert!((a - b).abs() < 1e-6, "ray {o:?} {d:?}: {a} vs {b}")
                    }
                    (None, None) => {}
                    // a grazing hit thinner than the marching step
                    (Some(a), None) => assert!(a > 30.0 - 1e-6 || w.sdf(o).0 >= 0.0, "missed oracle {a}"),
                    (None, Some(b)) => panic!("ray {o:?} {d:?}: no hit, oracle {b}"),
                }
            }
            assert!(hits > 150, "too few hits: {hits}");
        }
    }

    #[test]
    fn face_normals_point_out_of_the_terrain() {
        let w = LedgeWorld::new();
        for f in &w.faces {
            let k = f.verts.len() as f64;
            let c = f.verts.iter().fold([0.0; 3], |a, v| [a[0] + v[0] / k, a[1] + v[1] / k, a[2] + v[2] / k]);
            let out = [c[0] + 0.01 * f.normal[0], c[1] + 0.01 * f.normal[1], c[2] + 0.01 * f.normal[2]];
            let inn = [c[0] - 0.01 * f.normal[0], c[1] - 0.01 * f.normal[1], c[2] - 0.01 * f.normal[2]];
            assert!(!w.inside(out) && w.inside(inn), "face normal {:?}", f.normal);
            // on the surface the gradient is the face normal
            let (d, g) = w.sdf(c);
            assert!(d.abs() < 1e-9 && dist(g, f.normal) < 1e-9);
        }
    }

    #[test]
    fn anchors_and_slope_geometry() {
        let w = LedgeWorld::new();
        assert!((toe_x() - 4.0 / 55f64.to_radians().tan()).abs() < 1e-12);
        // slope angle from the face normal
        let (_, g) = w.sdf([1.5, 0.0, 4.0]);
        let ang = g[2].acos().to_degrees();
        assert!((ang - 55.0).abs() < 1e-9, "{ang}");
        assert_eq!(sub(ROOT_ANCHOR_TEST1, START_AXLE), [-4.9, 0.0, 2.0]);
        let d2 = sub(ROOT_ANCHOR_TEST2, START_AXLE);
        assert!((d2[0] - 8.2).abs() < 1e-12 && (d2[2] - 2.0).abs() < 1e-12);
        assert!(!w.inside(ROOT_ANCHOR_TEST1) && !w.inside(ROOT_ANCHOR_TEST2));
    }
}
