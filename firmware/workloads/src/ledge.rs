//! The 55-degree ledge of Paton et al. section VI-A (Fig. 8; `shared/SCENARIOS.md` section A), with or without
//! the test-3 pole, as an exact analytic distance field with exact ray casts: the one ledge geometry of the
//! project. The `tethered_test3` workload plans on it ([`crate::ledge_pole`]); host-sim's `ledge` and
//! `ledge_pole` worlds (`host-sim/src/world/ledge.rs`) wrap it. `no_std`, `libm` only, so the board and the
//! host compute the same bits.
//!
//! # Geometry
//! World frame: x east, y north, z up, metres. The flat ground is the plane `z = 0` (solid below).
//! The ledge is a prism standing on the ground:
//! - top face `z = 4` ([`LEDGE_HEIGHT_M`]) over `x in [-5, 0]`, `y in [-5, 5]` (the ledge is 10 m long along y,
//!   5 m deep along x ([`LEDGE_DEPTH_M`], [`LEDGE_HALF_WIDTH_M`]), 4 m high: the 10 x 5 x 4 m of the paper, whose
//!   text does not say whether the slope is included in the 5 m; here it is added in front of the 5 m top);
//! - back wall `x = -5` and side walls `y = +-5`, vertical;
//! - the slope: the face from the lip `x = 0, z = 4` down to the toe `x = 4 / tan(55 deg) = 2.8008 m, z = 0`
//!   ([`toe_x`]), descending towards +x, inclined [`SLOPE_DEG`] = 55 degrees to the horizontal.
//!
//! With the pole ([`Ledge::with_pole`], test 3): a vertical cylinder of radius [`POLE_RADIUS_M`] = 0.25 m
//! standing on the top face at [`POLE_CENTRE_XY`] = (-2.5, 0) (the middle of the ledge top) and rising
//! [`POLE_HEIGHT_M`] = 6 m above it (to z = 10 m). Assumptions, since the paper gives no numbers: "tall" is taken as
//! higher than the root anchors of tests 1-3 (z = 6.35 m), so a taut tether wraps around the pole's side and never
//! slips over its cap; 0.25 m is a stout post a tether can wrap.
//!
//! # Distance, gradient, rays
//! The terrain's boundary is a union of planar faces (ground outside the ledge's footprint, top, back, two sides,
//! slope) plus, with the pole, the pole's side and cap (and the top face gets a hole under the pole). The unsigned
//! distance is the exact minimum over these faces (computed in f64); its sign comes from an exact inside test;
//! the gradient is `(q - c) / |q - c|` (outside) or `(c - q) / |q - c|` (inside), with `c` the closest boundary
//! point, so it always points away from the terrain; on the surface itself it is the face normal.
//! Ray casts intersect every face exactly; a ray starting inside the terrain hits at distance 0.

use firmware::geom::p3::{dist, dot, norm, sub, P3};
use firmware::geom::{is_finite3, Real, Vec3};
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

/// A point or vector in f64, metres.
type P = P3;

/// Squared distance.
fn dist2(a: P, b: P) -> f64 {
    let v = sub(a, b);
    dot(v, v)
}

/// `tan(55 deg)`.
fn slope_tan() -> f64 {
    libm::tan(SLOPE_DEG.to_radians())
}

/// x of the slope's toe (where the slope meets the ground), metres.
pub fn toe_x() -> f64 {
    LEDGE_HEIGHT_M / slope_tan()
}

/// A planar quadrilateral face of the ledge.
#[derive(Debug, Clone, Copy)]
pub struct Face {
    /// Vertices, counter-clockwise seen from outside.
    pub verts: [[f64; 3]; 4],
    /// Outward unit normal.
    pub normal: [f64; 3],
}

/// The edges `(a, b)` of a face, in order (the last one closes the loop).
fn edges(v: &[P; 4]) -> [(P, P); 4] {
    let [a, b, c, d] = *v;
    [(a, b), (b, c), (c, d), (d, a)]
}

impl Face {
    fn new(verts: [P; 4]) -> Self {
        // Newell's method for the normal.
        let mut n = [0.0; 3];
        for (a, b) in edges(&verts) {
            n[0] += (a[1] - b[1]) * (a[2] + b[2]);
            n[1] += (a[2] - b[2]) * (a[0] + b[0]);
            n[2] += (a[0] - b[0]) * (a[1] + b[1]);
        }
        let l = norm(n);
        Face { verts, normal: [n[0] / l, n[1] / l, n[2] / l] }
    }

    fn contains_projection(&self, q: P) -> bool {
        let n = self.normal;
        edges(&self.verts).iter().all(|&(a, b)| {
            let e = sub(b, a);
            let w = sub(q, a);
            // (e x w) . n >= 0 for a point left of the edge (CCW seen from outside).
            let c = [e[1] * w[2] - e[2] * w[1], e[2] * w[0] - e[0] * w[2], e[0] * w[1] - e[1] * w[0]];
            dot(c, n) >= -1e-12
        })
    }

    fn closest(&self, q: P) -> P {
        let [a0, ..] = self.verts;
        let h = dot(sub(q, a0), self.normal);
        let proj = [q[0] - h * self.normal[0], q[1] - h * self.normal[1], q[2] - h * self.normal[2]];
        if self.contains_projection(proj) {
            return proj;
        }
        let mut best = a0;
        let mut bd = f64::INFINITY;
        for (a, b) in edges(&self.verts) {
            let c = closest_on_segment(q, a, b);
            let d = dist2(q, c);
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
        let [a0, ..] = self.verts;
        let t = dot(sub(a0, o), self.normal) / den;
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

/// Closest point to `q` on the plane z = 0 outside the rectangle [x0, x1] x [-w, w].
fn closest_outside_rect(q: P, x0: f64, x1: f64, w: f64) -> P {
    let (x, y) = (q[0], q[1]);
    if x < x0 || x > x1 || y.abs() > w {
        return [x, y, 0.0];
    }
    // Inside the rectangle: move to the nearest edge.
    let cands = [(x - x0, [x0, y]), (x1 - x, [x1, y]), (w - y, [x, w]), (y + w, [x, -w])];
    let [mut best, ..] = cands;
    for c in cands {
        if c.0 < best.0 {
            best = c;
        }
    }
    [best.1[0], best.1[1], 0.0]
}

/// The ledge, optionally with the test-3 pole: an exact [`DistanceField`] (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct Ledge {
    faces: [Face; 4],
    toe_x: f64,
    slope_tan: f64,
    pole: bool,
}

impl Default for Ledge {
    fn default() -> Self {
        Self::new()
    }
}

impl Ledge {
    /// Flat ground plus the ledge with its 55-degree slope (tests 1 and 2).
    pub fn new() -> Self {
        Self::build(false)
    }

    /// The ledge plus the tall pole in the middle of its top (test 3).
    pub fn with_pole() -> Self {
        Self::build(true)
    }

    fn build(pole: bool) -> Self {
        let h = LEDGE_HEIGHT_M;
        let w = LEDGE_HALF_WIDTH_M;
        let xb = -LEDGE_DEPTH_M;
        let xt = toe_x();
        let faces = [
            // slope (normal +x, +z)
            Face::new([[0.0, w, h], [0.0, -w, h], [xt, -w, 0.0], [xt, w, 0.0]]),
            // back wall (normal -x)
            Face::new([[xb, -w, h], [xb, w, h], [xb, w, 0.0], [xb, -w, 0.0]]),
            // side y = +w (normal +y)
            Face::new([[xb, w, h], [0.0, w, h], [xt, w, 0.0], [xb, w, 0.0]]),
            // side y = -w (normal -y)
            Face::new([[0.0, -w, h], [xb, -w, h], [xb, -w, 0.0], [xt, -w, 0.0]]),
        ];
        Ledge { faces, toe_x: xt, slope_tan: slope_tan(), pole }
    }

    /// True when the ledge has the test-3 pole.
    pub fn has_pole(&self) -> bool {
        self.pole
    }

    /// The four planar faces of the prism (slope, back wall, side `y = +w`, side `y = -w`); the ground and the
    /// top are rectangles handled apart.
    pub fn faces(&self) -> &[Face; 4] {
        &self.faces
    }

    /// Exact inside test (closed solid, points on the surface count as inside).
    pub fn inside(&self, q: [f64; 3]) -> bool {
        if q[2] <= 0.0 {
            return true;
        }
        if self.pole && in_pole(q) {
            return true;
        }
        let in_y = q[1].abs() <= LEDGE_HALF_WIDTH_M;
        let in_x = q[0] >= -LEDGE_DEPTH_M;
        let under = q[2] <= LEDGE_HEIGHT_M && q[2] <= LEDGE_HEIGHT_M - q[0] * self.slope_tan;
        in_y && in_x && under
    }

    /// The closest boundary point to `q` and the outward normal of the face it lies on.
    fn closest_boundary(&self, q: P) -> (P, P) {
        let mut best = ([0.0; 3], [0.0, 0.0, 1.0]);
        let mut bd = f64::INFINITY;
        // candidates compared by squared distance: one square root per query (in `sdf`), not one per candidate
        let mut consider = |c: P, n: P| {
            let d = dist2(q, c);
            if d < bd {
                bd = d;
                best = (c, n);
            }
        };
        for f in &self.faces {
            consider(f.closest(q), f.normal);
        }
        // Ground outside the footprint rectangle [xb, xt] x [-w, w].
        let (xb, xt, w) = (-LEDGE_DEPTH_M, self.toe_x, LEDGE_HALF_WIDTH_M);
        consider(closest_outside_rect(q, xb, xt, w), [0.0, 0.0, 1.0]);
        // Top rectangle [xb, 0] x [-w, w] at z = h, minus the pole's disk.
        let h = LEDGE_HEIGHT_M;
        let top = [q[0].clamp(xb, 0.0), q[1].clamp(-w, w), h];
        let [cx, cy] = POLE_CENTRE_XY;
        let r = POLE_RADIUS_M;
        let (dx, dy) = (top[0] - cx, top[1] - cy);
        let rho = libm::sqrt(dx * dx + dy * dy);
        if self.pole && rho < r {
            let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
            consider([cx + r * ux, cy + r * uy, h], [0.0, 0.0, 1.0]);
        } else {
            consider(top, [0.0, 0.0, 1.0]);
        }
        if self.pole {
            let (dx, dy) = (q[0] - cx, q[1] - cy);
            let rho = libm::sqrt(dx * dx + dy * dy);
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
    pub fn sdf(&self, q: [f64; 3]) -> (f64, [f64; 3]) {
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

    /// Exact ray cast in f64: distance along the unit `d` from `o` to the first surface point, up to `max_range`.
    pub fn raycast(&self, o: [f64; 3], d: [f64; 3], max_range: f64) -> Option<f64> {
        if self.inside(o) {
            return Some(0.0);
        }
        let mut best = f64::INFINITY;
        for f in &self.faces {
            if let Some(t) = f.ray(o, d) {
                best = best.min(t);
            }
        }
        let (xb, xt, w, h) = (-LEDGE_DEPTH_M, self.toe_x, LEDGE_HALF_WIDTH_M, LEDGE_HEIGHT_M);
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
                    let t = (-b - libm::sqrt(disc)) / (2.0 * a);
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
    pub fn height(&self, x: f64, y: f64) -> f64 {
        let [cx, cy] = POLE_CENTRE_XY;
        let (dx, dy) = (x - cx, y - cy);
        if self.pole && dx * dx + dy * dy <= POLE_RADIUS_M * POLE_RADIUS_M {
            return LEDGE_HEIGHT_M + POLE_HEIGHT_M;
        }
        if y.abs() > LEDGE_HALF_WIDTH_M || x < -LEDGE_DEPTH_M {
            return 0.0;
        }
        if x <= 0.0 {
            LEDGE_HEIGHT_M
        } else {
            (LEDGE_HEIGHT_M - x * self.slope_tan).max(0.0)
        }
    }
}

/// Inside the test-3 pole (closed cylinder)?
fn in_pole(q: P) -> bool {
    let dx = q[0] - POLE_CENTRE_XY[0];
    let dy = q[1] - POLE_CENTRE_XY[1];
    dx * dx + dy * dy <= POLE_RADIUS_M * POLE_RADIUS_M
        && q[2] >= LEDGE_HEIGHT_M
        && q[2] <= LEDGE_HEIGHT_M + POLE_HEIGHT_M
}

impl DistanceField for Ledge {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        if !is_finite3(p) {
            return DistanceQuery::Unknown;
        }
        let (d, g) = self.sdf([f64::from(p.x), f64::from(p.y), f64::from(p.z)]);
        DistanceQuery::Known {
            distance: d as Real,
            gradient: Vec3::new(g[0] as Real, g[1] as Real, g[2] as Real),
        }
    }

    /// An exact signed distance (the union's is the minimum of the parts'): 1-Lipschitz, known everywhere.
    fn lipschitz_bound(&self) -> Option<Real> {
        Some(1.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(w: &Ledge, q: P) -> f64 {
        w.sdf(q).0
    }

    /// The bound the field declares (`lipschitz_bound`, which lets the tether's sweep lines skip samples) holds:
    /// 200 000 pairs of points 1 mm to 1 m apart, over the whole world and packed round the lip and the pole.
    #[test]
    fn the_field_is_one_lipschitz() {
        let w = Ledge::with_pole();
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut unit = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let centres = [[0.0, 0.0, 4.0], [-2.5, 0.0, 5.0], [-2.5, 0.25, 4.1], [3.0, 0.0, 0.0], [-6.0, 3.0, 4.0]];
        let mut worst: f64 = 0.0;
        for k in 0..200_000 {
            let c = centres[k % centres.len()];
            let spread = if k % 2 == 0 { 0.5 } else { 8.0 };
            let p = [c[0] + spread * (unit() - 0.5), c[1] + spread * (unit() - 0.5), c[2] + spread * (unit() - 0.5)];
            let step = 1e-3 + unit();
            let dir = [unit() - 0.5, unit() - 0.5, unit() - 0.5];
            let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt().max(1e-9);
            let q = [p[0] + step * dir[0] / n, p[1] + step * dir[1] / n, p[2] + step * dir[2] / n];
            worst = worst.max((d(&w, p) - d(&w, q)).abs() / step);
        }
        assert!(worst <= 1.0 + 1e-9, "|d(p) - d(q)| / |p - q| reached {worst}");
    }

    /// Hand-computed distances at points whose nearest face is obvious.
    #[test]
    fn distances_at_probe_points() {
        let w = Ledge::with_pole();
        let e = 1e-12;
        assert!((d(&w, [4.0, 0.0, 1.5]) - 1.5).abs() < e); // above the ground in front of the toe
        assert!((d(&w, [-4.0, 3.0, 5.0]) - 1.0).abs() < e); // above the top, away from the pole
        assert!((d(&w, [-2.5, 1.0, 7.0]) - 0.75).abs() < e); // beside the pole: 1 m from its axis
        assert!((d(&w, [-2.5, 0.0, 12.0]) - 2.0).abs() < e); // above the cap
        assert!((d(&w, [-7.0, 0.0, 2.0]) - 2.0).abs() < e); // behind the back wall
        assert!((d(&w, [-1.0, 0.0, 3.0]) + 1.0).abs() < e); // inside the ledge, 1 m below the top
        // on the slope: distance to the plane through the lip with normal (sin 55, 0, cos 55)
        let a = SLOPE_DEG.to_radians();
        let q = [1.0, 0.0, 4.0];
        assert!((d(&w, q) - libm::sin(a)).abs() < 1e-9, "{}", d(&w, q));
        // the gradient on the slope is its normal
        let g = w.sdf(q).1;
        assert!((g[0] - libm::sin(a)).abs() < 1e-9 && (g[2] - libm::cos(a)).abs() < 1e-9);
        assert!(matches!(w.query(&Vec3::new(f32::NAN, 0.0, 0.0)), DistanceQuery::Unknown));
    }
}
