//! The 55-degree ledge worlds of Paton et al. section VI-A (Fig. 8; `shared/SCENARIOS.md` section A), with exact
//! signed distance and exact ray casts: host-sim's [`World`] around the one ledge geometry of the project,
//! [`workloads::ledge::Ledge`] (its module docs give the geometry, the pole's assumptions and how distance,
//! gradient and rays are computed). The `tethered_test3` board workload plans on the same code, so the campaign's
//! `--field truth` and the board see the same bits.
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
//! The world's bounds are x in [-10, 12], y in [-10, 10], z from 0 to the ledge top (the pole's top with the pole).
//!
//! # Variants
//! A scenario's `[world.ledge]` table ([`LedgeParams`]) gives another slope, height, depth or length and any poles
//! (up to [`MAX_POLES`], each with position, radius and height), so variants of Paton's experiment are files:
//! `host-sim/scenarios/variants/`. Tests 1-3's start, goal and root anchors above are Paton's; a variant's file
//! gives its own.

use super::{Aabb, World};
use firmware::geom::{Real, Vec3};
use firmware::geom::p3::from_vec3;
use firmware::map::{DistanceField, DistanceQuery};
use workloads::ledge::Ledge;

use crate::truth::solid::{ExactGeometry, Solid};

pub use workloads::ledge::{
    toe_x, LedgeError, LedgeShape, Pole, LEDGE_DEPTH_M, LEDGE_HALF_WIDTH_M, LEDGE_HEIGHT_M, MAX_POLES, POLE_CENTRE_XY,
    POLE_HEIGHT_M, POLE_RADIUS_M, SLOPE_DEG,
};

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

/// `[world.ledge]` of a scenario file: a variant of the ledge (Paton et al.'s when the table is absent). Every
/// field optional; defaults are Paton's ([`LedgeShape::PATON`]), and `poles` defaults to none for `kind = "ledge"`
/// and to the test-3 pole ([`Pole::TEST3`]) for `kind = "ledge_pole"`.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct LedgeParams {
    /// Slope of the front face, degrees from the horizontal (5-85). Default 55.
    pub slope_deg: f64,
    /// Height of the top above the ground, metres. Default 4.
    pub height_m: f64,
    /// Depth of the top from the back wall to the lip (at x = 0), metres. Default 5.
    pub depth_m: f64,
    /// Half the ledge's length along y, metres. Default 5.
    pub half_width_m: f64,
    /// Poles on the top (at most [`MAX_POLES`]); `None`: the kind's default.
    pub poles: Option<Vec<PoleParams>>,
}

/// One `[[world.ledge.poles]]` entry.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct PoleParams {
    /// Axis position on the top, (x, y) metres.
    pub centre_xy: [f64; 2],
    /// Radius, metres. Default 0.25 (the test-3 pole's).
    #[serde(default = "test3_radius")]
    pub radius_m: f64,
    /// Height above the top, metres. Default 6 (the test-3 pole's).
    #[serde(default = "test3_height")]
    pub height_m: f64,
}

fn test3_radius() -> f64 {
    POLE_RADIUS_M
}

fn test3_height() -> f64 {
    POLE_HEIGHT_M
}

impl Default for LedgeParams {
    fn default() -> Self {
        let LedgeShape { slope_deg, height_m, depth_m, half_width_m } = LedgeShape::PATON;
        LedgeParams { slope_deg, height_m, depth_m, half_width_m, poles: None }
    }
}

impl LedgeParams {
    /// The shape and poles, with `default_poles` where the table names none.
    pub fn resolve(&self, default_poles: &[Pole]) -> (LedgeShape, Vec<Pole>) {
        let shape = LedgeShape {
            slope_deg: self.slope_deg,
            height_m: self.height_m,
            depth_m: self.depth_m,
            half_width_m: self.half_width_m,
        };
        let poles = match &self.poles {
            Some(ps) => ps
                .iter()
                .map(|p| Pole { centre_xy: p.centre_xy, radius_m: p.radius_m, height_m: p.height_m })
                .collect(),
            None => default_poles.to_vec(),
        };
        (shape, poles)
    }
}

/// The ledge world, optionally with poles on its top. See the module docs for the geometry.
#[derive(Debug, Clone)]
pub struct LedgeWorld {
    name: String,
    ledge: Ledge,
}

impl LedgeWorld {
    /// Flat ground plus the ledge with its 55-degree slope (tests 1 and 2).
    pub fn new() -> Self {
        LedgeWorld { name: "ledge55".into(), ledge: Ledge::new() }
    }

    /// The ledge plus a tall pole in the middle of its top (test 3).
    pub fn with_pole() -> Self {
        LedgeWorld { name: "ledge55-pole".into(), ledge: Ledge::with_pole() }
    }

    /// A variant ([`Ledge::custom`]'s rules); Paton's two worlds keep their names, a variant is named by its
    /// slope and pole count (`ledge40-2poles`).
    pub fn custom(shape: LedgeShape, poles: &[Pole]) -> Result<Self, LedgeError> {
        let ledge = Ledge::custom(shape, poles)?;
        let name = match poles {
            _ if shape != LedgeShape::PATON => format!("ledge{}-{}poles", shape.slope_deg, poles.len()),
            [] => "ledge55".into(),
            [p] if *p == Pole::TEST3 => "ledge55-pole".into(),
            _ => format!("ledge55-{}poles", poles.len()),
        };
        Ok(LedgeWorld { name, ledge })
    }

    /// The analytic geometry this world wraps.
    pub fn ledge(&self) -> &Ledge {
        &self.ledge
    }

    /// True when the world has a pole.
    pub fn has_pole(&self) -> bool {
        self.ledge.has_pole()
    }

    /// Exact inside test (closed solid, points on the surface count as inside).
    pub fn inside(&self, q: P) -> bool {
        self.ledge.inside(q)
    }

    /// Exact signed distance (negative inside) and gradient (away from the terrain), in f64.
    pub fn sdf(&self, q: P) -> (f64, P) {
        self.ledge.sdf(q)
    }

    /// Exact ray cast in f64: distance along the unit `dir` to the first surface point, up to `max_range`.
    pub fn raycast_f64(&self, o: P, d: P, max_range: f64) -> Option<f64> {
        self.ledge.raycast(o, d, max_range)
    }

    /// Top-surface height under (x, y), f64.
    pub fn height_f64(&self, x: f64, y: f64) -> f64 {
        self.ledge.height(x, y)
    }
}

impl Default for LedgeWorld {
    fn default() -> Self {
        Self::new()
    }
}

impl DistanceField for LedgeWorld {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        self.ledge.query(p)
    }

    fn lipschitz_bound(&self) -> Option<Real> {
        self.ledge.lipschitz_bound()
    }
}

impl World for LedgeWorld {
    fn name(&self) -> &str {
        &self.name
    }

    /// Paton's worlds: x in [-10, 12], y in [-10, 10]; a variant: at least 5 m of ground behind the back wall,
    /// 9 m in front of the toe and 5 m beside the sides.
    fn bounds(&self) -> Aabb {
        let shape = self.ledge.shape();
        let x0 = (-shape.depth_m - 5.0).min(-10.0);
        let x1 = (self.ledge.toe_x() + 9.0).max(12.0);
        let y = (shape.half_width_m + 5.0).max(10.0);
        let top = self.ledge.top_z();
        Aabb { min: Vec3::new(x0 as Real, -y as Real, 0.0), max: Vec3::new(x1 as Real, y as Real, top as Real) }
    }

    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
        self.raycast_f64(from_vec3(origin), from_vec3(dir), f64::from(max_range)).map(|t| t as Real)
    }

    fn height_at(&self, x: Real, y: Real) -> Option<Real> {
        Some(self.height_f64(f64::from(x), f64::from(y)) as Real)
    }

    fn exact_geometry(&self) -> ExactGeometry {
        // The ground, the ledge body (its x-z section: back wall, top, lip, slope, toe) and the poles.
        let shape = self.ledge.shape();
        let (h, xb, w) = (shape.height_m, -shape.depth_m, shape.half_width_m);
        let mut solids = vec![
            Solid::Ground { z: 0.0 },
            Solid::xz_prism(&[[xb, 0.0], [self.ledge.toe_x(), 0.0], [0.0, h], [xb, h]], -w, w),
        ];
        for p in self.ledge.poles() {
            solids.push(Solid::Cylinder { centre: p.centre_xy, radius: p.radius_m, z0: h, z1: h + p.height_m });
        }
        ExactGeometry { solids }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::Rng;
    use rand_pcg::Pcg64;

    use firmware::geom::p3::{dist, sub};

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
                if !(w.has_pole() && (x + 2.5).powi(2) + y * y < POLE_RADIUS_M.powi(2)) {
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
        if w.has_pole() {
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
            let gn = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
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
        for f in w.ledge().faces() {
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
