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
//! Variants ([`Ledge::custom`], the scenario file's `[world.ledge]`): any slope angle, height, depth and length
//! ([`LedgeShape`]; the lip stays at `x = 0`, the top at `z = height`) and up to [`MAX_POLES`] poles ([`Pole`]:
//! position, radius, height), each inside the top and clear of the others.
//!
//! With the pole ([`Ledge::with_pole`], test 3): a vertical cylinder of radius [`POLE_RADIUS_M`] = 0.25 m
//! standing on the top face at [`POLE_CENTRE_XY`] = (-2.5, 0) (the middle of the ledge top) and rising
//! [`POLE_HEIGHT_M`] = 6 m above it (to z = 10 m). Assumptions, since the paper gives no numbers: "tall" is taken as
//! higher than the root anchors of tests 1-3 (z = 6.35 m), so a taut tether wraps around the pole's side and never
//! slips over its cap; 0.25 m is a stout post a tether can wrap.
//!
//! # Distance, gradient, rays
//! The terrain's boundary is a union of planar faces (ground outside the ledge's footprint, top, back, two sides,
//! slope) plus each pole's side and cap (and the top face gets a hole under each pole; the holes are disjoint). The unsigned
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
/// Most poles a ledge world stands on its top. Default 4 (a fixed array: the field stays `Copy` and heap-free).
pub const MAX_POLES: usize = 4;

/// The prism's dimensions: a variant of Paton et al.'s ledge ([`LedgeShape::PATON`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LedgeShape {
    /// Slope angle of the front face, degrees from the horizontal. Paton: 55.
    pub slope_deg: f64,
    /// Height of the top above the ground, metres. Paton: 4.
    pub height_m: f64,
    /// Depth of the top along x, from the back wall to the lip at x = 0, metres. Paton: 5.
    pub depth_m: f64,
    /// Half of the ledge's length along y, metres. Paton: 5 (10 m long).
    pub half_width_m: f64,
}

impl LedgeShape {
    /// Paton et al.'s ledge: 55 degrees, 4 m high, 5 m deep, 10 m long.
    pub const PATON: LedgeShape =
        LedgeShape { slope_deg: SLOPE_DEG, height_m: LEDGE_HEIGHT_M, depth_m: LEDGE_DEPTH_M, half_width_m: LEDGE_HALF_WIDTH_M };
}

/// A vertical cylindrical pole standing on the ledge top.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pole {
    /// Axis position on the top, (x, y) metres.
    pub centre_xy: [f64; 2],
    /// Radius, metres.
    pub radius_m: f64,
    /// Height above the top, metres.
    pub height_m: f64,
}

impl Pole {
    /// The test-3 pole ([`POLE_CENTRE_XY`], [`POLE_RADIUS_M`], [`POLE_HEIGHT_M`]).
    pub const TEST3: Pole = Pole { centre_xy: POLE_CENTRE_XY, radius_m: POLE_RADIUS_M, height_m: POLE_HEIGHT_M };

    /// Squared horizontal distance of `(x, y)` from the axis.
    fn rho2(&self, x: f64, y: f64) -> f64 {
        let (dx, dy) = (x - self.centre_xy[0], y - self.centre_xy[1]);
        dx * dx + dy * dy
    }
}

/// Why a [`LedgeShape`] and its poles do not make a world: the field (`slope_deg`, `poles[1].radius_m`, ...) and
/// what it must be.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LedgeError {
    /// The parameter at fault (`poles` for the list as a whole).
    pub field: &'static str,
    /// Which pole, for a pole's field.
    pub pole: Option<usize>,
    /// What it must be.
    pub reason: &'static str,
}

/// A point or vector in f64, metres.
type P = P3;

/// Squared distance.
fn dist2(a: P, b: P) -> f64 {
    let v = sub(a, b);
    dot(v, v)
}

/// x of Paton's slope's toe (where the slope meets the ground), metres: [`Ledge::toe_x`] of [`Ledge::new`].
pub fn toe_x() -> f64 {
    LEDGE_HEIGHT_M / libm::tan(SLOPE_DEG.to_radians())
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

/// The ledge, optionally with poles on its top: an exact [`DistanceField`] (see the module docs).
#[derive(Debug, Clone, Copy)]
pub struct Ledge {
    faces: [Face; 4],
    toe_x: f64,
    slope_tan: f64,
    shape: LedgeShape,
    poles: [Pole; MAX_POLES],
    pole_count: usize,
}

impl Default for Ledge {
    fn default() -> Self {
        Self::new()
    }
}

impl Ledge {
    /// Flat ground plus the ledge with its 55-degree slope (tests 1 and 2).
    pub fn new() -> Self {
        Self::build(LedgeShape::PATON, &[])
    }

    /// The ledge plus the tall pole in the middle of its top (test 3).
    pub fn with_pole() -> Self {
        Self::build(LedgeShape::PATON, &[Pole::TEST3])
    }

    /// A variant: any slope, height, depth and length, and up to [`MAX_POLES`] poles. Each value finite; the slope
    /// within 5-85 degrees; the dimensions and the poles' radii and heights positive; each pole's disk inside the
    /// top and clear of the others (disjoint disks keep the distance exact, see the module docs).
    pub fn custom(shape: LedgeShape, poles: &[Pole]) -> Result<Self, LedgeError> {
        let bad = |field, reason| Err(LedgeError { field, pole: None, reason });
        let LedgeShape { slope_deg, height_m, depth_m, half_width_m } = shape;
        if !(slope_deg.is_finite() && (5.0..=85.0).contains(&slope_deg)) {
            return bad("slope_deg", "must be between 5 and 85 degrees");
        }
        for (field, v) in [("height_m", height_m), ("depth_m", depth_m), ("half_width_m", half_width_m)] {
            if !(v.is_finite() && v > 0.0 && v <= 1000.0) {
                return bad(field, "must be finite, above 0 and at most 1000 m");
            }
        }
        if poles.len() > MAX_POLES {
            return bad("poles", "at most 4 poles (MAX_POLES)");
        }
        for (i, p) in poles.iter().enumerate() {
            let pole_err = |field, reason| Err(LedgeError { field, pole: Some(i), reason });
            let [x, y] = p.centre_xy;
            if !(x.is_finite() && y.is_finite()) {
                return pole_err("centre_xy", "must be finite");
            }
            for (field, v) in [("radius_m", p.radius_m), ("height_m", p.height_m)] {
                if !(v.is_finite() && v > 0.0 && v <= 1000.0) {
                    return pole_err(field, "must be finite, above 0 and at most 1000 m");
                }
            }
            let r = p.radius_m;
            if x - r <= -depth_m || x + r >= 0.0 || y - r <= -half_width_m || y + r >= half_width_m {
                return pole_err("centre_xy", "the pole's disk must lie inside the ledge top (x from -depth_m to 0, |y| below half_width_m)");
            }
            for q in poles.iter().take(i) {
                let reach = r + q.radius_m;
                if p.rho2(q.centre_xy[0], q.centre_xy[1]) <= reach * reach {
                    return pole_err("centre_xy", "the pole touches an earlier pole: poles must stand apart");
                }
            }
        }
        Ok(Self::build(shape, poles))
    }

    fn build(shape: LedgeShape, poles: &[Pole]) -> Self {
        let h = shape.height_m;
        let w = shape.half_width_m;
        let xb = -shape.depth_m;
        let slope_tan = libm::tan(shape.slope_deg.to_radians());
        let xt = h / slope_tan;
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
        let mut stood = [Pole::TEST3; MAX_POLES];
        let pole_count = poles.len().min(MAX_POLES);
        for (slot, p) in stood.iter_mut().zip(poles) {
            *slot = *p;
        }
        Ledge { faces, toe_x: xt, slope_tan, shape, poles: stood, pole_count }
    }

    /// The prism's dimensions.
    pub fn shape(&self) -> LedgeShape {
        self.shape
    }

    /// The poles on the top.
    pub fn poles(&self) -> &[Pole] {
        self.poles.get(..self.pole_count).unwrap_or(&self.poles)
    }

    /// True when the ledge has at least one pole.
    pub fn has_pole(&self) -> bool {
        self.pole_count > 0
    }

    /// x of the slope's toe (where the slope meets the ground), metres.
    pub fn toe_x(&self) -> f64 {
        self.toe_x
    }

    /// The highest point of the world: the top of the tallest pole, or the ledge top.
    pub fn top_z(&self) -> f64 {
        self.poles().iter().fold(self.shape.height_m, |z, p| z.max(self.shape.height_m + p.height_m))
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
        let h = self.shape.height_m;
        if self.poles().iter().any(|p| in_pole(p, h, q)) {
            return true;
        }
        let in_y = q[1].abs() <= self.shape.half_width_m;
        let in_x = q[0] >= -self.shape.depth_m;
        let under = q[2] <= h && q[2] <= h - q[0] * self.slope_tan;
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
        let (xb, xt, w) = (-self.shape.depth_m, self.toe_x, self.shape.half_width_m);
        consider(closest_outside_rect(q, xb, xt, w), [0.0, 0.0, 1.0]);
        // Top rectangle [xb, 0] x [-w, w] at z = h, minus the poles' disks (disjoint and inside it, so a point
        // whose projection falls in one disk is nearest to that disk's rim).
        let h = self.shape.height_m;
        // max / min, not clamp: the bounds are parameters now, and clamp has a panic path for crossed bounds
        let top = [q[0].max(xb).min(0.0), q[1].max(-w).min(w), h];
        match self.poles().iter().find(|p| p.rho2(top[0], top[1]) < p.radius_m * p.radius_m) {
            Some(p) => {
                let [cx, cy] = p.centre_xy;
                let (dx, dy) = (top[0] - cx, top[1] - cy);
                let rho = libm::sqrt(dx * dx + dy * dy);
                let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
                consider([cx + p.radius_m * ux, cy + p.radius_m * uy, h], [0.0, 0.0, 1.0]);
            }
            None => consider(top, [0.0, 0.0, 1.0]),
        }
        for p in self.poles() {
            let ([cx, cy], r) = (p.centre_xy, p.radius_m);
            let (dx, dy) = (q[0] - cx, q[1] - cy);
            let rho = libm::sqrt(dx * dx + dy * dy);
            let (ux, uy) = if rho > 1e-12 { (dx / rho, dy / rho) } else { (1.0, 0.0) };
            // side
            let z = q[2].max(h).min(h + p.height_m);
            consider([cx + r * ux, cy + r * uy, z], [ux, uy, 0.0]);
            // cap
            let s = rho.min(r);
            consider([cx + s * ux, cy + s * uy, h + p.height_m], [0.0, 0.0, 1.0]);
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
        let (xb, xt, w, h) = (-self.shape.depth_m, self.toe_x, self.shape.half_width_m, self.shape.height_m);
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
        for p in self.poles() {
            let ([cx, cy], r, top) = (p.centre_xy, p.radius_m, h + p.height_m);
            let (ox, oy) = (o[0] - cx, o[1] - cy);
            let a = d[0] * d[0] + d[1] * d[1];
            if a > 1e-15 {
                let b = 2.0 * (ox * d[0] + oy * d[1]);
                let c = ox * ox + oy * oy - r * r;
                let disc = b * b - 4.0 * a * c;
                if disc >= 0.0 {
                    let t = (-b - libm::sqrt(disc)) / (2.0 * a);
                    let z = o[2] + t * d[2];
                    if t >= 0.0 && z >= h && z <= top {
                        best = best.min(t);
                    }
                }
            }
            if d[2].abs() > 1e-15 {
                let t = (top - o[2]) / d[2];
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
        let h = self.shape.height_m;
        if let Some(p) = self.poles().iter().find(|p| p.rho2(x, y) <= p.radius_m * p.radius_m) {
            return h + p.height_m;
        }
        if y.abs() > self.shape.half_width_m || x < -self.shape.depth_m {
            return 0.0;
        }
        if x <= 0.0 {
            h
        } else {
            (h - x * self.slope_tan).max(0.0)
        }
    }
}

/// Inside `pole` (a closed cylinder standing on a top at height `h`)?
fn in_pole(pole: &Pole, h: f64, q: P) -> bool {
    pole.rho2(q[0], q[1]) <= pole.radius_m * pole.radius_m && q[2] >= h && q[2] <= h + pole.height_m
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

    /// Largest `|d(p) - d(q)| / |p - q|` over 200 000 pairs of points 1 mm to 1 m apart, half spread over the
    /// whole world and half packed round `centres`.
    fn worst_lipschitz(w: &Ledge, centres: &[P]) -> f64 {
        let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut unit = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut worst: f64 = 0.0;
        for k in 0..200_000 {
            let c = centres[k % centres.len()];
            let spread = if k % 2 == 0 { 0.5 } else { 8.0 };
            let p = [c[0] + spread * (unit() - 0.5), c[1] + spread * (unit() - 0.5), c[2] + spread * (unit() - 0.5)];
            let step = 1e-3 + unit();
            let dir = [unit() - 0.5, unit() - 0.5, unit() - 0.5];
            let n = (dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]).sqrt().max(1e-9);
            let q = [p[0] + step * dir[0] / n, p[1] + step * dir[1] / n, p[2] + step * dir[2] / n];
            worst = worst.max((d(w, p) - d(w, q)).abs() / step);
        }
        worst
    }

    /// The bound the field declares (`lipschitz_bound`, which lets the tether's sweep lines skip samples) holds:
    /// 200 000 pairs of points 1 mm to 1 m apart, over the whole world and packed round the lip and the pole.
    #[test]
    fn the_field_is_one_lipschitz() {
        let w = Ledge::with_pole();
        let centres = [[0.0, 0.0, 4.0], [-2.5, 0.0, 5.0], [-2.5, 0.25, 4.1], [3.0, 0.0, 0.0], [-6.0, 3.0, 4.0]];
        let worst = worst_lipschitz(&w, &centres);
        assert!(worst <= 1.0 + 1e-9, "|d(p) - d(q)| / |p - q| reached {worst}");
    }

    /// Two poles of different sizes on a 40-degree, 3 m ledge.
    fn two_pole_variant() -> Ledge {
        let shape = LedgeShape { slope_deg: 40.0, height_m: 3.0, depth_m: 6.0, half_width_m: 4.0 };
        let poles = [
            Pole { centre_xy: [-2.0, 1.5], radius_m: 0.4, height_m: 5.0 },
            Pole { centre_xy: [-3.0, -1.0], radius_m: 0.1, height_m: 2.0 },
        ];
        Ledge::custom(shape, &poles).expect("a valid variant")
    }

    /// A variant's field is exact where the nearest face is obvious, 1-Lipschitz, signed by its inside test, and
    /// its ray casts agree with its distances: a ray down the negative gradient from an outside point hits at the
    /// point's distance.
    #[test]
    fn a_variant_with_two_poles_is_an_exact_field() {
        let w = two_pole_variant();
        let e = 1e-12;
        assert!((d(&w, [-2.0, 1.5, 9.5]) - 1.5).abs() < e); // above the big pole's cap (top 3 + 5 = 8)
        assert!((d(&w, [-2.0, 2.9, 6.0]) - 1.0).abs() < e); // beside it: 1.4 m from its axis
        assert!((d(&w, [-3.0, -1.0, 5.5]) - 0.5).abs() < e); // above the thin pole's cap (top 5)
        assert!((d(&w, [-3.0, -0.6, 4.0]) - 0.3).abs() < e); // beside the thin pole
        assert!((d(&w, [-5.0, -3.0, 3.7]) - 0.7).abs() < e); // above the top, away from the poles
        assert!((d(&w, [-7.0, 0.0, 1.0]) - 1.0).abs() < e); // behind the back wall at x = -6
        let a = 40f64.to_radians();
        assert!((d(&w, [1.0, 0.0, 3.0]) - libm::sin(a)).abs() < 1e-9); // the 40-degree slope through the lip
        assert!((w.toe_x() - 3.0 / libm::tan(a)).abs() < e);
        assert!((w.height(-2.0, 1.5) - 8.0).abs() < e && (w.height(-3.0, -1.0) - 5.0).abs() < e);
        assert!((w.top_z() - 8.0).abs() < e);
        let centres = [[0.0, 0.0, 3.0], [-2.0, 1.5, 4.0], [-3.0, -1.0, 3.2], [-2.5, 0.2, 3.5], [3.5, 0.0, 0.0]];
        let worst = worst_lipschitz(&w, &centres);
        assert!(worst <= 1.0 + 1e-9, "|d(p) - d(q)| / |p - q| reached {worst}");
        // sign and ray casts at 2 000 points round the poles and the lip
        let mut state: u64 = 0x2545_F491_4F6C_DD1D;
        let mut unit = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut rays = 0;
        for k in 0..2000 {
            let c = centres[k % centres.len()];
            let q = [c[0] + 3.0 * (unit() - 0.5), c[1] + 3.0 * (unit() - 0.5), c[2] + 3.0 * (unit() - 0.5)];
            let (dq, g) = w.sdf(q);
            assert_eq!(dq <= 0.0, w.inside(q), "sign at {q:?}: {dq}");
            if dq > 1e-3 {
                let hit = w.raycast(q, [-g[0], -g[1], -g[2]], 100.0).expect("the nearest point is on the surface");
                assert!((hit - dq).abs() < 1e-9, "ray {hit} vs distance {dq} at {q:?}");
                rays += 1;
            }
        }
        assert!(rays > 500, "only {rays} outside points");
    }

    /// Variants that are not a world are refused with the field at fault.
    #[test]
    fn impossible_variants_are_refused_with_the_field() {
        let ok = LedgeShape::PATON;
        let field = |shape: LedgeShape, poles: &[Pole]| Ledge::custom(shape, poles).err().map(|e| (e.field, e.pole));
        assert_eq!(field(LedgeShape { slope_deg: 90.0, ..ok }, &[]), Some(("slope_deg", None)));
        assert_eq!(field(LedgeShape { height_m: f64::NAN, ..ok }, &[]), Some(("height_m", None)));
        assert_eq!(field(LedgeShape { depth_m: 0.0, ..ok }, &[]), Some(("depth_m", None)));
        let pole = |x: f64, y: f64, r: f64| Pole { centre_xy: [x, y], radius_m: r, height_m: 6.0 };
        // off the top (over the lip), touching another, too many, a zero radius
        assert_eq!(field(ok, &[pole(-0.1, 0.0, 0.25)]), Some(("centre_xy", Some(0))));
        assert_eq!(field(ok, &[pole(-2.5, 0.0, 0.25), pole(-2.5, 0.5, 0.25)]), Some(("centre_xy", Some(1))));
        assert_eq!(field(ok, &[pole(-1.0, 0.0, 0.1); 5]), Some(("poles", None)));
        assert_eq!(field(ok, &[pole(-2.5, 0.0, 0.0)]), Some(("radius_m", Some(0))));
        // Paton's test-3 world as a variant is the same field
        let (v, t3) = (Ledge::custom(ok, &[Pole::TEST3]).expect("valid"), Ledge::with_pole());
        for q in [[0.3, 0.2, 4.1], [-2.5, 0.3, 6.0], [-4.0, 4.0, 1.0]] {
            assert_eq!(v.sdf(q), t3.sdf(q));
        }
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
