//! The simulator's grip model: whether a robot's grip holds where it landed, from the **true** surface around the
//! grip point (the simulator's own geometry, independent of the flight code's anchor scores).
//!
//! Quality of a grip point p with true outward normal n: cast `SAMPLES_PER_AXIS`^2 = 25 rays along -n onto the
//! true surface from a square of half-side R in the tangent plane, lifted R above p; fit a plane to the hits
//! (least squares, smallest eigenvalue of the scatter matrix) and take
//!
//! ```text
//! q = rms_residual / R + missing_fraction        (missing: a ray that found no surface within 2R: an edge, a hole)
//! p_slip = p_min + (p_max - p_min) * clamp((q - q_good) / (q_bad - q_good), 0, 1)
//! ```
//!
//! A grip on ground the gripper conforms to (q <= q_good: residual up to 5 % of the footprint, e.g. gentle
//! curvature) slips with `p_min`; one as rough as `q_bad` (residual of a quarter of the radius, or a quarter of the
//! footprint over nothing) or worse slips with `p_max`; linear in between. Defaults ([`GripModel::for_hop`]):
//! R = h_max / 10 (1 m for 10 m hops, 3 m for 30 m: the scaled worlds' robots are scaled with their hops),
//! p_min = 0.001, p_max = 0.5, q_good = 0.05, q_bad = 0.25. These are a model's choice, not a measurement:
//! SphereX's gripper was not characterised in the paper (see `host-sim/doc/team.md` for the first version of the
//! model and why it changed). A slip is a grip failure: the robot falls, its tether is cut (node loss).

use super::surface::{unit, Surface, P3};
use firmware::geom::p3::{add, cross, scale, sub};

/// Rays per axis of the footprint sample.
pub const SAMPLES_PER_AXIS: usize = 5;

/// Grip-slip model parameters.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GripModel {
    /// Footprint half-side R, metres.
    pub radius: f64,
    /// Slip probability on a perfect anchor.
    pub p_min: f64,
    /// Slip probability on an anchor at least as bad as `q_bad`.
    pub p_max: f64,
    /// Quality up to which the slip probability is `p_min` (the gripper conforms).
    pub q_good: f64,
    /// Quality at which the slip probability reaches `p_max`.
    pub q_bad: f64,
}

impl GripModel {
    /// The defaults for a team hopping at most `h_max` metres.
    pub fn for_hop(h_max: f64) -> Self {
        Self { radius: 0.1 * h_max, p_min: 0.001, p_max: 0.5, q_good: 0.05, q_bad: 0.25 }
    }

    /// A model whose grip never slips (for tests that need the whole team).
    pub fn never_slips(h_max: f64) -> Self {
        Self { radius: 0.1 * h_max, p_min: 0.0, p_max: 0.0, q_good: 0.5, q_bad: 1.0 }
    }

    /// The quality q of a grip at `p` (0 = a perfect plane fully under the footprint).
    pub fn quality(&self, surface: &dyn Surface, p: P3) -> f64 {
        self.footprint(surface, p).0
    }

    /// The quality q of a grip at `p` and the normal of the plane fitted to the footprint (the robot's attitude
    /// when it grips there; the surface normal at `p` when fewer than 3 rays hit).
    pub fn footprint(&self, surface: &dyn Surface, p: P3) -> (f64, P3) {
        let n = surface.normal_near(p);
        let a = unit(if n[2].abs() < 0.9 { cross(n, [0.0, 0.0, 1.0]) } else { cross(n, [1.0, 0.0, 0.0]) });
        let b = cross(n, a);
        let r = self.radius;
        let k = SAMPLES_PER_AXIS;
        let mut hits = Vec::with_capacity(k * k);
        for i in 0..k {
            for j in 0..k {
                let (s, t) = (r * (2.0 * i as f64 / (k - 1) as f64 - 1.0), r * (2.0 * j as f64 / (k - 1) as f64 - 1.0));
                let o = add(add(add(p, scale(a, s)), scale(b, t)), scale(n, r));
                if let Some(d) = surface.raycast(o, scale(n, -1.0), 2.0 * r) {
                    hits.push(add(o, scale(n, -d)));
                }
            }
        }
        let missing = 1.0 - hits.len() as f64 / (k * k) as f64;
        if hits.len() < 3 {
            return (missing + 1.0, n);
        }
        let m = hits.iter().fold([0.0; 3], |acc, h| add(acc, *h));
        let m = scale(m, 1.0 / hits.len() as f64);
        let mut c = nalgebra::Matrix3::<f64>::zeros();
        for h in &hits {
            let d = sub(*h, m);
            let v = nalgebra::Vector3::new(d[0], d[1], d[2]);
            c += v * v.transpose();
        }
        let eig = c.symmetric_eigen();
        let (k_min, lmin) = eig.eigenvalues.iter().enumerate().fold((0, f64::MAX), |b, (k, &l)| if l < b.1 { (k, l) } else { b });
        let e = eig.eigenvectors.column(k_min);
        let fit = [e[0], e[1], e[2]];
        let fit = if firmware::geom::p3::dot(fit, n) < 0.0 { scale(fit, -1.0) } else { fit };
        ((lmin.max(0.0) / hits.len() as f64).sqrt() / r + missing, unit(fit))
    }

    /// Slip probability for quality `q`.
    pub fn p_slip(&self, q: f64) -> f64 {
        let span = self.q_bad - self.q_good;
        let t = if span > 0.0 { ((q - self.q_good) / span).clamp(0.0, 1.0) } else if q > self.q_good { 1.0 } else { 0.0 };
        self.p_min + (self.p_max - self.p_min) * t
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::team::surface::HeightSurface;
    use crate::terrain::Heightmap;

    fn surf(f: impl Fn(f64, f64) -> f64) -> HeightSurface {
        let n = 40;
        let heights = (0..n * n).map(|i| Some(f((i % n) as f64 * 0.5, (i / n) as f64 * 0.5))).collect();
        HeightSurface::new("t", Heightmap { width: n, height: n, spacing_m: 0.5, heights_m: heights })
    }

    #[test]
    fn smooth_slope_grips_well_rough_ground_and_an_edge_grip_badly() {
        let g = GripModel::for_hop(10.0);
        // a plane tilted 40 degrees: residual ~0, fully supported
        let plane = surf(|x, _| 0.84 * x);
        let q = g.quality(&plane, [10.0, 10.0, 8.4]);
        assert!(q < 0.02, "{q}");
        assert!((g.p_slip(q) - g.p_min).abs() < 0.01);
        // a 2 m wavelength, 1 m amplitude egg-crate: rough at the footprint's scale
        let rough = surf(|x, y| (x * core::f64::consts::PI).sin() * (y * core::f64::consts::PI).sin());
        let q = g.quality(&rough, [10.0, 10.0, rough.height(10.0, 10.0).unwrap()]);
        assert!(q > 0.25, "{q}");
        assert_eq!(g.p_slip(q), g.p_max);
        // at the edge of the map half the footprint is over nothing
        let q = g.quality(&plane, [0.2, 10.0, 0.168]);
        assert!(q > 0.3, "{q}");
    }
}
