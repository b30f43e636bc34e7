//! The ledge + pole world of Paton et al. section VI-A, test 3 (Fig. 8; `shared/SCENARIOS.md` section A) as an
//! exact analytic distance field for the on-target planning workload: a test fixture, `no_std`, `libm` only.
//!
//! Geometry (the same as host-sim's `ledge_pole` world, `host-sim/src/world/ledge.rs`, and computed with the same
//! f64 operations in the same order so the two fields agree to the last bit wherever `libm` and the host's maths
//! library agree; `tests/tests/board_test3.rs` checks them against each other at many points):
//! - flat ground `z = 0`, solid below;
//! - the ledge: top `z = 4` over `x in [-5, 0]`, `y in [-5, 5]`; vertical back wall `x = -5` and side walls
//!   `y = +-5`; the 55-degree slope from the lip `(0, *, 4)` down to the toe `x = 4 / tan 55 deg = 2.8008 m`;
//! - the pole: a vertical cylinder of radius [`POLE_RADIUS_M`] = 0.25 m centred at [`POLE_CENTRE_XY`] =
//!   (-2.5, 0) on the ledge top, rising [`POLE_HEIGHT_M`] = 6 m above it (to z = 10 m).
//!
//! Distance: the exact minimum over the boundary faces (slope, back, two sides, the ground outside the ledge's
//! footprint, the top minus the pole's disk, the pole's side and cap), signed by an exact inside test; the gradient
//! is the unit vector from the closest boundary point (away from the terrain), the face normal on the surface.

use crate::geom::{is_finite3, Real, Vec3};
use crate::map::{DistanceField, DistanceQuery};

/// Slope angle of the ledge's front face, degrees.
pub const SLOPE_DEG: f64 = 55.0;
/// Height of the ledge top above the ground, metres.
pub const LEDGE_HEIGHT_M: f64 = 4.0;
/// Depth of the ledge top along x (back wall at x = -5, lip at x = 0), metres.
pub const LEDGE_DEPTH_M: f64 = 5.0;
/// Half of the ledge's length along y, metres.
pub const LEDGE_HALF_WIDTH_M: f64 = 5.0;
/// Radius of the pole, metres.
pub const POLE_RADIUS_M: f64 = 0.25;
/// Height of the pole above the ledge top, metres.
pub const POLE_HEIGHT_M: f64 = 6.0;
/// Centre of the pole on the ledge top, (x, y) metres.
pub const POLE_CENTRE_XY: [f64; 2] = [-2.5, 0.0];

type P = [f64; 3];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn dist(a: P, b: P) -> f64 {
    let d = sub(a, b);
    libm::sqrt(dot(d, d))
}

/// `tan(55 deg)`.
fn slope_tan() -> f64 {
    libm::tan(SLOPE_DEG.to_radians())
}

/// x of the slope's toe, metres.
pub fn toe_x() -> f64 {
    LEDGE_HEIGHT_M / slope_tan()
}

/// A planar quadrilateral face: vertices counter-clockwise seen from outside, outward unit normal.
#[derive(Debug, Clone, Copy)]
struct Face {
    verts: [P; 4],
    normal: P,
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
        let l = libm::sqrt(dot(n, n));
        Face { verts, normal: [n[0] / l, n[1] / l, n[2] / l] }
    }

    fn contains_projection(&self, q: P) -> bool {
        let n = self.normal;
        edges(&self.verts).iter().all(|&(a, b)| {
            let e = sub(b, a);
            let w = sub(q, a);
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
            let d = dist(q, c);
            if d < bd {
                bd = d;
                best = c;
            }
        }
        best
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
    let cands = [(x - x0, [x0, y]), (x1 - x, [x1, y]), (w - y, [x, w]), (y + w, [x, -w])];
    let [mut best, ..] = cands;
    for c in cands {
        if c.0 < best.0 {
            best = c;
        }
    }
    [best.1[0], best.1[1], 0.0]
}

/// The ledge with the test-3 pole, an exact [`DistanceField`] (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct LedgePole {
    faces: [Face; 4],
    toe_x: f64,
    slope_tan: f64,
}

impl Default for LedgePole {
    fn default() -> Self {
        Self::new()
    }
}

impl LedgePole {
    /// The world of test 3.
    pub fn new() -> Self {
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
        LedgePole { faces, toe_x: xt, slope_tan: slope_tan() }
    }

    /// Exact inside test (points on the surface count as inside).
    pub fn inside(&self, q: P) -> bool {
        if q[2] <= 0.0 {
            return true;
        }
        let dx = q[0] - POLE_CENTRE_XY[0];
        let dy = q[1] - POLE_CENTRE_XY[1];
        if dx * dx + dy * dy <= POLE_RADIUS_M * POLE_RADIUS_M
            && q[2] >= LEDGE_HEIGHT_M
            && q[2] <= LEDGE_HEIGHT_M + POLE_HEIGHT_M
        {
            return true;
        }
        let in_y = q[1].abs() <= LEDGE_HALF_WIDTH_M;
        let in_x = q[0] >= -LEDGE_DEPTH_M;
        let under = q[2] <= LEDGE_HEIGHT_M && q[2] <= LEDGE_HEIGHT_M - q[0] * self.slope_tan;
        in_y && in_x && under
    }

    /// The closest boundary point to `q` and the outward normal of its face.
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
        let (xb, xt, w) = (-LEDGE_DEPTH_M, self.toe_x, LEDGE_HALF_WIDTH_M);
        consider(closest_outside_rect(q, xb, xt, w), [0.0, 0.0, 1.0]);
        // the top rectangle minus the pole's disk
        let h = LEDGE_HEIGHT_M;
        let top = [q[0].clamp(xb, 0.0), q[1].clamp(-w, w), h];
        let [cx, cy] = POLE_CENTRE_XY;
        let r = POLE_RADIUS_M;
        let (dx, dy) = (top[0] - cx, top[1] - cy);
        let rho = libm::sqrt(dx * dx + dy * dy);
        if rho < r {
            let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
            consider([cx + r * ux, cy + r * uy, h], [0.0, 0.0, 1.0]);
        } else {
            consider(top, [0.0, 0.0, 1.0]);
        }
        // the pole: side and cap
        let (dx, dy) = (q[0] - cx, q[1] - cy);
        let rho = libm::sqrt(dx * dx + dy * dy);
        let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
        let z = q[2].clamp(h, h + POLE_HEIGHT_M);
        consider([cx + r * ux, cy + r * uy, z], [ux, uy, 0.0]);
        let s = rho.min(r);
        consider([cx + s * ux, cy + s * uy, h + POLE_HEIGHT_M], [0.0, 0.0, 1.0]);
        best
    }

    /// Exact signed distance (negative inside) and gradient (away from the terrain), in f64.
    pub fn sdf(&self, q: P) -> (f64, P) {
        let (c, n) = self.closest_boundary(q);
        let d = dist(q, c);
        if d < 1e-9 {
            return (0.0, n);
        }
        let v = sub(q, c);
        let s = if self.inside(q) { -1.0 } else { 1.0 };
        (s * d, [s * v[0] / d, s * v[1] / d, s * v[2] / d])
    }
}

impl DistanceField for LedgePole {
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
}

#[cfg(test)]
mod tests {
    use super::*;

    fn d(w: &LedgePole, q: P) -> f64 {
        w.sdf(q).0
    }

    /// Hand-computed distances at points whose nearest face is obvious.
    #[test]
    fn distances_at_probe_points() {
        let w = LedgePole::new();
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
