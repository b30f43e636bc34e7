//! The three-plane crater wall (shared/SCENARIOS.md; Abad-Manterola et al.'s tether-free / tether-demand /
//! tether-free planes): a flat rim at height `rim_height_m` for `x <= 0`, a steep wall descending in +x at
//! `wall_angle_deg`, a flat floor at z = 0, extruded along y, with polygonal rocks (vertical prisms on convex
//! polygonal bases, partly buried).
//!
//! Signed distance: exact for the wall profile (2D distance to the polyline, sign from the side) and for each
//! rock (exact SDF of an extruded convex polygon). The world is their union, taken as the minimum: **exact
//! outside the terrain**; inside, the magnitude is a lower bound where a rock overlaps the ground (conservative).
//! Ray casts sphere-trace that SDF (exact outside, so no surface is skipped).

use super::geometry::{convex_polygon_sdf, segment_distance_2d, sphere_trace, P3};
use super::{Aabb, World};
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};
use rand_core::Rng;

use crate::truth::solid::{ExactGeometry, Solid};

/// Parameters of [`CraterWall`]; defaults in [`CraterWallParams::default`].
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct CraterWallParams {
    /// Rim height above the floor, metres. Default 6.0.
    pub rim_height_m: f64,
    /// Wall slope, degrees from horizontal (0 < angle < 90). Default 60.
    pub wall_angle_deg: f64,
    /// Length of rim behind the lip (x < 0), metres. Default 6.0.
    pub rim_length_m: f64,
    /// Length of floor beyond the foot of the wall, metres. Default 8.0.
    pub floor_length_m: f64,
    /// Width along y, metres. Default 10.0.
    pub width_m: f64,
    /// Number of rocks. Default 12.
    pub rocks: usize,
    /// Smallest and largest rock radius, metres. Default [0.15, 0.5].
    pub rock_radius_m: [f64; 2],
    /// Seed of the rock layout. Default 1.
    pub rock_seed: u64,
}

impl Default for CraterWallParams {
    fn default() -> Self {
        CraterWallParams {
            rim_height_m: 6.0,
            wall_angle_deg: 60.0,
            rim_length_m: 6.0,
            floor_length_m: 8.0,
            width_m: 10.0,
            rocks: 12,
            rock_radius_m: [0.15, 0.5],
            rock_seed: 1,
        }
    }
}

impl CraterWallParams {
    /// Checks the parameters; the error names the field and the reason.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let pos = |v: f64| v.is_finite() && v > 0.0;
        if !pos(self.rim_height_m) {
            return Err(("rim_height_m", format!("must be > 0, got {}", self.rim_height_m)));
        }
        if !(self.wall_angle_deg.is_finite() && self.wall_angle_deg > 0.0 && self.wall_angle_deg < 90.0) {
            return Err(("wall_angle_deg", format!("must be in (0, 90), got {}", self.wall_angle_deg)));
        }
        for (f, v) in [("rim_length_m", self.rim_length_m), ("floor_length_m", self.floor_length_m), ("width_m", self.width_m)] {
            if !pos(v) {
                return Err((f, format!("must be > 0, got {v}")));
            }
        }
        let [lo, hi] = self.rock_radius_m;
        if !(pos(lo) && hi.is_finite() && hi >= lo) {
            return Err(("rock_radius_m", format!("need 0 < min <= max, got [{lo}, {hi}]")));
        }
        if self.rocks > 1000 {
            return Err(("rocks", format!("at most 1000, got {}", self.rocks)));
        }
        Ok(())
    }
}

/// A rock: vertical prism over a convex polygon (counter-clockwise), between `z0` and `z1`.
#[derive(Debug, Clone, PartialEq)]
pub struct Rock {
    /// Base polygon, counter-clockwise, metres.
    pub polygon: Vec<[f64; 2]>,
    /// Bottom height.
    pub z0: f64,
    /// Top height.
    pub z1: f64,
}

impl Rock {
    fn sdf(&self, p: P3) -> f64 {
        let d2 = convex_polygon_sdf([p[0], p[1]], &self.polygon);
        let zc = 0.5 * (self.z0 + self.z1);
        let dz = (p[2] - zc).abs() - 0.5 * (self.z1 - self.z0);
        let o = [d2.max(0.0), dz.max(0.0)];
        (o[0] * o[0] + o[1] * o[1]).sqrt() + d2.max(dz).min(0.0)
    }
}

/// The crater wall world.
#[derive(Debug, Clone)]
pub struct CraterWall {
    params: CraterWallParams,
    foot_x: f64,
    rocks: Vec<Rock>,
}

impl CraterWall {
    /// Builds the world; the rocks are placed with a PCG generator seeded by `rock_seed`.
    pub fn new(params: CraterWallParams) -> Result<CraterWall, (&'static str, String)> {
        params.validate()?;
        let foot_x = params.rim_height_m / params.wall_angle_deg.to_radians().tan();
        let mut w = CraterWall { params: params.clone(), foot_x, rocks: Vec::new() };
        let mut rng = rand_pcg::Pcg64::new(0xcafe_f00d_d15e_a5e5 ^ params.rock_seed as u128, 0xa02b_dbf7_bb3c_0a7a_c28f_a6a6_1c2d_0b8b);
        let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        let x_lo = -params.rim_length_m + 1.0;
        let x_hi = foot_x + params.floor_length_m - 1.0;
        for _ in 0..params.rocks {
            let cx = x_lo + (x_hi - x_lo) * unit();
            let cy = (unit() - 0.5) * (params.width_m - 2.0);
            let [rlo, rhi] = params.rock_radius_m;
            let r = rlo + (rhi - rlo) * unit();
            let k = 5 + (unit() * 3.0) as usize;
            let mut angles: Vec<f64> = (0..k)
                .map(|i| (i as f64 + 0.8 * (unit() - 0.5)) * core::f64::consts::TAU / k as f64)
                .collect();
            angles.sort_by(f64::total_cmp);
            let polygon = angles.iter().map(|a| [cx + r * a.cos(), cy + r * a.sin()]).collect();
            let ground = w.profile_height(cx);
            let h = r * (0.8 + 0.8 * unit());
            w.rocks.push(Rock { polygon, z0: ground - 0.4 * h - r, z1: ground + 0.6 * h });
        }
        Ok(w)
    }

    /// The parameters.
    pub fn params(&self) -> &CraterWallParams {
        &self.params
    }

    /// x of the foot of the wall (the lip is at x = 0).
    pub fn foot_x(&self) -> f64 {
        self.foot_x
    }

    /// The rocks.
    pub fn rocks(&self) -> &[Rock] {
        &self.rocks
    }

    /// Height of the bare three-plane profile at `x`.
    pub fn profile_height(&self, x: f64) -> f64 {
        let h = self.params.rim_height_m;
        if x <= 0.0 {
            h
        } else if x >= self.foot_x {
            0.0
        } else {
            h * (1.0 - x / self.foot_x)
        }
    }

    fn profile_sdf(&self, p: P3) -> f64 {
        let h = self.params.rim_height_m;
        let q = [p[0], p[2]];
        let far = 1e9;
        let d = segment_distance_2d(q, [-far, h], [0.0, h])
            .min(segment_distance_2d(q, [0.0, h], [self.foot_x, 0.0]))
            .min(segment_distance_2d(q, [self.foot_x, 0.0], [far, 0.0]));
        if p[2] >= self.profile_height(p[0]) {
            d
        } else {
            -d
        }
    }

    /// Signed distance in `f64` (see the module docs for exactness).
    pub fn sdf(&self, p: P3) -> f64 {
        self.rocks.iter().fold(self.profile_sdf(p), |d, r| d.min(r.sdf(p)))
    }
}

impl DistanceField for CraterWall {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        let q = [p.x as f64, p.y as f64, p.z as f64];
        let d = self.sdf(q);
        let e = 1e-4;
        let g = [
            self.sdf([q[0] + e, q[1], q[2]]) - self.sdf([q[0] - e, q[1], q[2]]),
            self.sdf([q[0], q[1] + e, q[2]]) - self.sdf([q[0], q[1] - e, q[2]]),
            self.sdf([q[0], q[1], q[2] + e]) - self.sdf([q[0], q[1], q[2] - e]),
        ];
        let n = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        let gradient = if n > 1e-12 {
            Vec3::new((g[0] / n) as Real, (g[1] / n) as Real, (g[2] / n) as Real)
        } else {
            Vec3::zeros()
        };
        DistanceQuery::Known { distance: d as Real, gradient }
    }
}

impl World for CraterWall {
    fn name(&self) -> &str {
        "crater_wall"
    }

    fn bounds(&self) -> Aabb {
        let p = &self.params;
        Aabb {
            min: Vec3::new(-p.rim_length_m as Real, (-p.width_m / 2.0) as Real, -1.0),
            max: Vec3::new(
                (self.foot_x + p.floor_length_m) as Real,
                (p.width_m / 2.0) as Real,
                (p.rim_height_m + 2.0) as Real,
            ),
        }
    }

    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
        let o = [origin.x as f64, origin.y as f64, origin.z as f64];
        let d = [dir.x as f64, dir.y as f64, dir.z as f64];
        sphere_trace(|p| self.sdf(p), o, d, max_range as f64, 4096).map(|t| t as Real)
    }

    fn height_at(&self, x: Real, y: Real) -> Option<Real> {
        let (x, y) = (x as f64, y as f64);
        let top = self
            .rocks
            .iter()
            .filter(|r| convex_polygon_sdf([x, y], &r.polygon) <= 0.0)
            .fold(self.profile_height(x), |h, r| h.max(r.z1));
        Some(top as Real)
    }

    fn exact_geometry(&self) -> ExactGeometry {
        // The profile is unbounded in x < 0 and along y; 100 m beyond the world's bounds stands for that.
        let p = &self.params;
        let (far_x, far_y) = (-p.rim_length_m - 100.0, p.width_m / 2.0 + 100.0);
        let h = p.rim_height_m;
        let mut solids = vec![
            Solid::Ground { z: 0.0 },
            Solid::xz_prism(&[[far_x, 0.0], [self.foot_x, 0.0], [0.0, h], [far_x, h]], -far_y, far_y),
        ];
        solids.extend(self.rocks.iter().map(|r| Solid::vertical_prism(&r.polygon, r.z0, r.z1)));
        ExactGeometry { solids }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn profile_distance_is_analytic_on_the_wall() {
        let w = CraterWall::new(CraterWallParams { rocks: 0, ..Default::default() }).unwrap();
        let a = 60f64.to_radians();
        // A point on the wall's mid-line, offset along its outward normal by 0.7 m.
        let mid = [w.foot_x() / 2.0, 0.0, 3.0];
        let n = [a.sin(), 0.0, a.cos()];
        let p = [mid[0] + 0.7 * n[0], 0.0, mid[2] + 0.7 * n[2]];
        assert!((w.sdf(p) - 0.7).abs() < 1e-9);
        let p = [mid[0] - 0.4 * n[0], 0.0, mid[2] - 0.4 * n[2]];
        assert!((w.sdf(p) + 0.4).abs() < 1e-9);
        // Above the rim, distance is height above it; ray straight down hits it.
        assert!((w.sdf([-3.0, 1.0, 8.0]) - 2.0).abs() < 1e-9);
        let t = w.raycast(&Vec3::new(-3.0, 1.0, 8.0), &Vec3::new(0.0, 0.0, -1.0), 10.0).unwrap();
        assert!((t - 2.0).abs() < 1e-3);
    }

    #[test]
    fn raycast_hits_agree_with_the_sdf() {
        let w = CraterWall::new(CraterWallParams::default()).unwrap();
        assert_eq!(w.rocks().len(), 12);
        let o = Vec3::new(-2.0, 0.0, 8.0);
        for k in 0..50 {
            let a = k as Real * 0.11;
            let dir = Vec3::new(a.cos() * 0.8, a.sin() * 0.5, -0.6).normalize();
            if let Some(t) = w.raycast(&o, &dir, 30.0) {
                let p = o + dir * t;
                match w.query(&p) {
                    DistanceQuery::Known { distance, .. } => assert!(distance.abs() < 1e-3),
                    DistanceQuery::Unknown => unreachable!(),
                }
            }
        }
    }

    #[test]
    fn bad_params_name_the_field() {
        let e = CraterWall::new(CraterWallParams { wall_angle_deg: 95.0, ..Default::default() }).unwrap_err();
        assert_eq!(e.0, "wall_angle_deg");
        let e = CraterWall::new(CraterWallParams { rim_height_m: f64::NAN, ..Default::default() }).unwrap_err();
        assert_eq!(e.0, "rim_height_m");
    }
}
