//! Terrain model (Abad-Manterola et al. III, Fig. 4; Tanner et al. II, Fig. 5): intersecting planes classified as
//! tether-free or tether-demand, convex or non-convex polygonal obstacles, and soil regions split by a line.
//!
//! Parameters (all given by the caller, no hidden defaults):
//! - `slope_rad` (alpha): plane inclination from horizontal.
//! - `traction_mu`: the rover's wheel-soil friction coefficient on that plane; a plane is *tether-demand* when a
//!   point mass cannot hold on it without the tether, i.e. `mu cot(alpha) < 1` (slope steeper than `atan(mu)`).
//! - [`SoilMap`]: two soil regions (compact soil `mu_c`, loose sand `mu_s`) split by a line, as in Fig. 11.

use super::geo::{orient, Pt, EPS};

/// How a plane is used by the rover (Abad-Manterola III).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaneClass {
    /// The wheels alone hold and propel the rover (`mu cot alpha >= 1`).
    TetherFree,
    /// Tether forces are essential for mobility (`mu cot alpha < 1`).
    TetherDemand,
}

/// One plane of the terrain: a unit normal (z up) through a point, in world coordinates (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TerrainPlane {
    /// A point on the plane (world frame, m).
    pub origin: [f64; 3],
    /// Upward unit normal (world frame).
    pub normal: [f64; 3],
    /// Rover-soil friction coefficient on this plane.
    pub traction_mu: f64,
}

impl TerrainPlane {
    /// Plane inclination alpha from horizontal (rad), in [0, pi/2].
    pub fn slope_rad(&self) -> f64 {
        let [nx, ny, nz] = self.normal;
        let n = libm::sqrt(nx * nx + ny * ny + nz * nz);
        if n <= 0.0 {
            return 0.0;
        }
        libm::acos((nz / n).clamp(-1.0, 1.0))
    }
    /// Classification by the point-mass holding condition `mu cot alpha >= 1` (Abad-Manterola VI).
    pub fn classify(&self) -> PlaneClass {
        classify_slope(self.slope_rad(), self.traction_mu)
    }
    /// Maps a world point onto this plane's 2D frame: `y` up the steepest ascent, `x` across (right-handed with
    /// the normal). A horizontal plane uses world x/y.
    pub fn to_plane_frame(&self, p: [f64; 3]) -> Pt {
        let [nx, ny, nz] = self.normal;
        let h = libm::sqrt(nx * nx + ny * ny);
        let d = [p[0] - self.origin[0], p[1] - self.origin[1], p[2] - self.origin[2]];
        if h < EPS {
            return Pt { x: d[0], y: d[1] };
        }
        // Steepest ascent direction on the plane: minus the horizontal part of the normal, tilted up.
        let n = libm::sqrt(nx * nx + ny * ny + nz * nz);
        let (ux, uy, uz) = (-nx * nz / (h * n), -ny * nz / (h * n), h / n);
        // Across-slope direction: horizontal, perpendicular to the ascent (up x normal gives right-handed x).
        let (rx, ry) = (-ny / h, nx / h);
        Pt { x: d[0] * rx + d[1] * ry, y: d[0] * ux + d[1] * uy + d[2] * uz }
    }
}

/// Tether-free when `mu cot(alpha) >= 1`, tether-demand otherwise.
pub fn classify_slope(slope_rad: f64, mu: f64) -> PlaneClass {
    if slope_rad <= 0.0 || mu * libm::cos(slope_rad) >= libm::sin(slope_rad) {
        PlaneClass::TetherFree
    } else {
        PlaneClass::TetherDemand
    }
}

/// Maximum holding angle between the upslope direction and the tether (Abad-Manterola VI):
/// `theta_max = asin(mu cot alpha)`, or `pi` (any angle) when `mu cot alpha >= 1`.
pub fn theta_max(slope_rad: f64, mu: f64) -> f64 {
    let s = libm::sin(slope_rad);
    if s <= 0.0 {
        return core::f64::consts::PI;
    }
    let k = mu * libm::cos(slope_rad) / s;
    if k >= 1.0 {
        core::f64::consts::PI
    } else if k <= 0.0 {
        0.0
    } else {
        libm::asin(k)
    }
}

/// Intersection line of two planes (the rim / wall / floor edges of the three-plane crater model, Fig. 4):
/// a point on the line and its unit direction, or `None` for parallel planes.
pub fn plane_intersection(a: &TerrainPlane, b: &TerrainPlane) -> Option<([f64; 3], [f64; 3])> {
    let (n1, n2) = (a.normal, b.normal);
    let d = [n1[1] * n2[2] - n1[2] * n2[1], n1[2] * n2[0] - n1[0] * n2[2], n1[0] * n2[1] - n1[1] * n2[0]];
    let dn = libm::sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    if dn < 1e-12 {
        return None;
    }
    let dot = |u: [f64; 3], v: [f64; 3]| u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    let (h1, h2) = (dot(n1, a.origin), dot(n2, b.origin));
    let (n11, n22, n12) = (dot(n1, n1), dot(n2, n2), dot(n1, n2));
    let det = n11 * n22 - n12 * n12;
    let (c1, c2) = ((h1 * n22 - h2 * n12) / det, (h2 * n11 - h1 * n12) / det);
    let p = [c1 * n1[0] + c2 * n2[0], c1 * n1[1] + c2 * n2[1], c1 * n1[2] + c2 * n2[2]];
    Some((p, [d[0] / dn, d[1] / dn, d[2] / dn]))
}

/// Two soil regions split by a line (Abad-Manterola Fig. 11: compact soil and loose sand).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SoilMap {
    /// A point on the dividing line (plane frame, m).
    pub line_point: Pt,
    /// Direction of the dividing line; the region to its left has `mu_left`.
    pub line_dir: Pt,
    /// Friction coefficient left of the line.
    pub mu_left: f64,
    /// Friction coefficient right of (or on) the line.
    pub mu_right: f64,
}

impl SoilMap {
    /// One soil everywhere.
    pub fn uniform(mu: f64) -> Self {
        SoilMap { line_point: Pt::default(), line_dir: Pt { x: 1.0, y: 0.0 }, mu_left: mu, mu_right: mu }
    }
    /// Friction coefficient at `p`.
    pub fn mu_at(&self, p: Pt) -> f64 {
        if orient(self.line_point, self.line_point + self.line_dir, p) > 0.0 {
            self.mu_left
        } else {
            self.mu_right
        }
    }
}

/// Which robot the holding condition is for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HoldLimit {
    /// The paper's point mass with Coulomb friction: `theta_max = asin(mu cot alpha)` (Abad-Manterola VI).
    PointMass,
    /// A rover whose largest holding angle per soil region was found by the core's static-stability check
    /// ([`super::axel::axel_hold_limit`]): `theta_max` left and right of the soil line, rad. A negative value means
    /// the rover holds at no tether angle there.
    Measured {
        /// `theta_max` left of the soil line (rad).
        left_rad: f64,
        /// `theta_max` right of (or on) the soil line (rad).
        right_rad: f64,
    },
}

/// The holding model on one tether-demand plane (Abad-Manterola VI), optionally with tether-free zones (the rim and
/// floor of an unfolded DEM descent, [`super::dem`]) where the wheels hold alone.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HoldModel {
    /// Plane inclination alpha (rad).
    pub slope_rad: f64,
    /// Soil regions.
    pub soil: SoilMap,
    /// Point mass (the paper's baseline) or a measured rover limit.
    pub limit: HoldLimit,
    /// Tether-free half-planes: a point strictly left of the directed line `a -> b` holds at any tether angle.
    pub tether_free: [Option<(Pt, Pt)>; 2],
}

impl HoldModel {
    /// The paper's point-mass model on one plane (no tether-free zones).
    pub const fn point_mass(slope_rad: f64, soil: SoilMap) -> Self {
        HoldModel { slope_rad, soil, limit: HoldLimit::PointMass, tether_free: [None, None] }
    }
    /// `theta_max` at `p`.
    pub fn theta_max_at(&self, p: Pt) -> f64 {
        if self.tether_free.iter().flatten().any(|(a, b)| orient(*a, *b, p) > 0.0) {
            return core::f64::consts::PI;
        }
        match self.limit {
            HoldLimit::PointMass => theta_max(self.slope_rad, self.soil.mu_at(p)),
            HoldLimit::Measured { left_rad, right_rad } => {
                if orient(self.soil.line_point, self.soil.line_point + self.soil.line_dir, p) > 0.0 {
                    left_rad
                } else {
                    right_rad
                }
            }
        }
    }
    /// True when a point mass at `robot` holds position on a taut tether to `anchor`: the angle between the upslope
    /// direction `+y` and the tether segment robot->anchor is at most `theta_max` (any angle if the soil alone holds).
    pub fn holds(&self, robot: Pt, anchor: Pt) -> bool {
        let tmax = self.theta_max_at(robot);
        if tmax >= core::f64::consts::PI {
            return true;
        }
        let d = anchor - robot;
        let n = d.norm();
        if n < EPS {
            return true;
        }
        let angle = libm::acos((d.y / n).clamp(-1.0, 1.0));
        angle <= tmax + 1e-12
    }
}
