//! True surfaces for the team simulation: a height field (DEM) and a triangle mesh (shape model), each with a ray
//! cast (for the range sensors and for landing) and a surface normal.

use crate::terrain::obj::TriMesh;
use crate::terrain::Heightmap;
use firmware::geom::p3::{add, cross, dist, dot, scale, sub, unit_or};

/// A 3-vector in f64 (the simulator's truth works in f64); the vector helpers are [`firmware::geom::p3`]'s.
pub use firmware::geom::p3::P3;

/// `a / |a|`, straight up (`+z`) for a zero vector.
pub fn unit(a: P3) -> P3 {
    unit_or(a, [0.0, 0.0, 1.0])
}

/// A true surface.
pub trait Surface: Sync {
    /// Name for reports and pictures.
    fn name(&self) -> &str;
    /// Distance along unit `dir` from `origin` to the first hit, up to `max`.
    fn raycast(&self, origin: P3, dir: P3, max: f64) -> Option<f64>;
    /// Outward unit normal of the surface near `p`.
    fn normal_near(&self, p: P3) -> P3;
    /// Cast many rays from one origin.
    fn scan(&self, o: P3, dirs: &[P3], max: f64) -> Vec<Option<f64>> {
        dirs.iter().map(|&d| self.raycast(o, d, max)).collect()
    }
    /// The point of the surface nearest to `p`, if one lies within `reach` (to about 1 % of `reach`).
    fn closest_point(&self, p: P3, reach: f64) -> Option<P3>;
}

/// A height field z = h(x, y), bilinear between posts, x east = column * spacing, y north = row * spacing.
pub struct HeightSurface {
    name: String,
    /// The grid (heights in metres).
    pub hm: Heightmap,
}

impl HeightSurface {
    /// Wrap a heightmap; `None` values are not allowed (fill them first).
    pub fn new(name: &str, hm: Heightmap) -> Self {
        Self { name: name.to_string(), hm }
    }

    /// Bilinear height, `None` outside the grid or on missing data.
    pub fn height(&self, x: f64, y: f64) -> Option<f64> {
        let s = self.hm.spacing_m;
        let (fx, fy) = (x / s, y / s);
        if fx < 0.0 || fy < 0.0 {
            return None;
        }
        let (ix, iy) = (fx.floor() as usize, fy.floor() as usize);
        if ix + 1 >= self.hm.width || iy + 1 >= self.hm.height {
            return None;
        }
        let (tx, ty) = (fx - ix as f64, fy - iy as f64);
        let h00 = self.hm.get(ix, iy)?;
        let h10 = self.hm.get(ix + 1, iy)?;
        let h01 = self.hm.get(ix, iy + 1)?;
        let h11 = self.hm.get(ix + 1, iy + 1)?;
        Some(h00 * (1.0 - tx) * (1.0 - ty) + h10 * tx * (1.0 - ty) + h01 * (1.0 - tx) * ty + h11 * tx * ty)
    }

    /// The point of the surface above (x, y).
    pub fn point(&self, x: f64, y: f64) -> Option<P3> {
        self.height(x, y).map(|z| [x, y, z])
    }
}

impl Surface for HeightSurface {
    /// Sampled: heights on a grid of `reach / 30` (at most a quarter post) over the square within `reach` of `p`,
    /// then a grid ten times finer around the best sample.
    fn closest_point(&self, p: P3, reach: f64) -> Option<P3> {
        let mut step = (reach / 30.0).min(self.hm.spacing_m * 0.25);
        if !(step > 0.0 && reach.is_finite()) {
            return None;
        }
        let mut best: Option<(f64, P3)> = None;
        let mut centre = [p[0], p[1]];
        let mut half = (reach / step).ceil() as i64;
        for _ in 0..2 {
            for i in -half..=half {
                for j in -half..=half {
                    let (x, y) = (centre[0] + i as f64 * step, centre[1] + j as f64 * step);
                    if let Some(z) = self.height(x, y) {
                        let q = [x, y, z];
                        let d = dist(q, p);
                        if best.is_none_or(|(b, _)| d < b) {
                            best = Some((d, q));
                        }
                    }
                }
            }
            let (_, q) = best?;
            centre = [q[0], q[1]];
            step /= 10.0;
            half = 10;
        }
        best.filter(|(d, _)| *d <= reach).map(|(_, q)| q)
    }


    fn name(&self) -> &str {
        &self.name
    }

    fn raycast(&self, o: P3, d: P3, max: f64) -> Option<f64> {
        let step = self.hm.spacing_m * 0.25;
        let above = |t: f64| -> Option<bool> {
            let p = add(o, scale(d, t));
            self.height(p[0], p[1]).map(|h| p[2] > h)
        };
        let mut t0 = 0.0;
        if above(0.0) != Some(true) {
            return None;
        }
        let n = (max / step).ceil() as usize;
        for i in 1..=n {
            let t1 = (i as f64 * step).min(max);
            match above(t1) {
                None => return None,
                Some(true) => t0 = t1,
                Some(false) => {
                    let (mut lo, mut hi) = (t0, t1);
                    for _ in 0..30 {
                        let mid = 0.5 * (lo + hi);
                        if above(mid) == Some(true) {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    return Some(0.5 * (lo + hi));
                }
            }
        }
        None
    }

    fn normal_near(&self, p: P3) -> P3 {
        let e = self.hm.spacing_m * 0.5;
        let hx = match (self.height(p[0] + e, p[1]), self.height(p[0] - e, p[1])) {
            (Some(a), Some(b)) => (a - b) / (2.0 * e),
            _ => 0.0,
        };
        let hy = match (self.height(p[0], p[1] + e), self.height(p[0], p[1] - e)) {
            (Some(a), Some(b)) => (a - b) / (2.0 * e),
            _ => 0.0,
        };
        unit([-hx, -hy, 1.0])
    }
}

/// A closed triangle mesh (outward counter-clockwise faces).
pub struct MeshSurface {
    name: String,
    /// The mesh, metres.
    pub mesh: TriMesh,
    centers: Vec<(P3, f64)>,
}

impl MeshSurface {
    /// Wrap a mesh.
    pub fn new(name: &str, mesh: TriMesh) -> Self {
        let centers = (0..mesh.triangles.len())
            .filter_map(|t| mesh.triangle(t))
            .map(|[a, b, c]| {
                let m = scale(add(add(a, b), c), 1.0 / 3.0);
                let r = dist(m, a).max(dist(m, b)).max(dist(m, c));
                (m, r)
            })
            .collect();
        Self { name: name.to_string(), mesh, centers }
    }

    fn hit(&self, t: usize, o: P3, d: P3) -> Option<f64> {
        // Moller-Trumbore, both sides
        let [a, b, c] = self.mesh.triangle(t)?;
        let e1 = sub(b, a);
        let e2 = sub(c, a);
        let p = cross(d, e2);
        let det = dot(e1, p);
        if det.abs() < 1e-12 {
            return None;
        }
        let inv = 1.0 / det;
        let s = sub(o, a);
        let u = dot(s, p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = cross(s, e1);
        let v = dot(d, q) * inv;
        if v < 0.0 || u + v > 1.0 {
            return None;
        }
        let t = dot(e2, q) * inv;
        (t > 1e-9).then_some(t)
    }

    /// Triangles whose bounding sphere reaches within `r` of `p` (a per-scan prefilter).
    pub fn near(&self, p: P3, r: f64) -> Vec<usize> {
        self.centers.iter().enumerate().filter(|(_, (m, rad))| dist(*m, p) <= r + rad).map(|(i, _)| i).collect()
    }

    /// Ray cast against a candidate list.
    pub fn raycast_in(&self, cands: &[usize], o: P3, d: P3, max: f64) -> Option<f64> {
        cands.iter().filter_map(|&t| self.hit(t, o, d)).filter(|&t| t <= max).min_by(|a, b| a.total_cmp(b))
    }

    /// Index of the triangle whose centre is closest to `p`.
    pub fn closest_triangle(&self, p: P3) -> Option<usize> {
        self.centers.iter().enumerate().min_by(|a, b| dist(a.1 .0, p).total_cmp(&dist(b.1 .0, p))).map(|(i, _)| i)
    }
}

impl Surface for MeshSurface {
    fn name(&self) -> &str {
        &self.name
    }

    fn raycast(&self, o: P3, d: P3, max: f64) -> Option<f64> {
        let c = self.near(o, max);
        self.raycast_in(&c, o, d, max)
    }

    fn scan(&self, o: P3, dirs: &[P3], max: f64) -> Vec<Option<f64>> {
        let c = self.near(o, max);
        dirs.iter().map(|&d| self.raycast_in(&c, o, d, max)).collect()
    }

    fn closest_point(&self, p: P3, reach: f64) -> Option<P3> {
        self.near(p, reach)
            .into_iter()
            .filter_map(|t| self.mesh.triangle(t))
            .map(|tri| closest_on_triangle(p, tri))
            .map(|q| (dist(q, p), q))
            .filter(|(d, _)| *d <= reach)
            .min_by(|a, b| a.0.total_cmp(&b.0))
            .map(|(_, q)| q)
    }

    fn normal_near(&self, p: P3) -> P3 {
        match self.closest_triangle(p).and_then(|t| self.mesh.triangle(t)) {
            Some([a, b, c]) => unit(cross(sub(b, a), sub(c, a))),
            None => [0.0, 0.0, 1.0],
        }
    }
}

/// The point of triangle `[a, b, c]` nearest to `p` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_on_triangle(p: P3, [a, b, c]: [P3; 3]) -> P3 {
    let (ab, ac, ap) = (sub(b, a), sub(c, a), sub(p, a));
    let (d1, d2) = (dot(ab, ap), dot(ac, ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let (d3, d4) = (dot(ab, bp), dot(ac, bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return add(a, scale(ab, d1 / (d1 - d3)));
    }
    let cp = sub(p, c);
    let (d5, d6) = (dot(ab, cp), dot(ac, cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return add(a, scale(ac, d2 / (d2 - d6)));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return add(b, scale(sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6))));
    }
    let denom = 1.0 / (va + vb + vc);
    add(a, add(scale(ab, vb * denom), scale(ac, vc * denom)))
}

#[cfg(test)]
mod closest_tests {
    use super::*;
    use crate::team::worlds::team_rng;
    use rand_core::Rng;

    fn uniform(rng: &mut impl Rng) -> f64 {
        (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Against brute force: the nearest of ~20 k points spread over the triangle (barycentric lattice).
    #[test]
    fn the_closest_point_on_a_triangle_is_the_nearest_of_a_dense_lattice() {
        let mut rng = team_rng(5);
        let tri = [[0.0, 0.0, 0.0], [3.0, 0.5, 0.2], [1.0, 2.5, -0.4]];
        let n = 200;
        for _ in 0..40 {
            let p = [uniform(&mut rng) * 6.0 - 1.5, uniform(&mut rng) * 6.0 - 1.5, uniform(&mut rng) * 4.0 - 2.0];
            let q = closest_on_triangle(p, tri);
            let mut best = f64::INFINITY;
            for i in 0..=n {
                for j in 0..=n - i {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let s = add(tri[0], add(scale(sub(tri[1], tri[0]), u), scale(sub(tri[2], tri[0]), v)));
                    best = best.min(dist(s, p));
                }
            }
            assert!(dist(q, p) <= best + 1e-12 && dist(q, p) >= best - 0.02, "{p:?}: {} vs lattice {best}", dist(q, p));
        }
    }

    /// On a plane z = 0.7 x (35 degrees) as a 1 m DEM the nearest point is the orthogonal projection (closed
    /// form), to 1 % of the reach; beyond the reach there is none.
    #[test]
    fn the_closest_point_on_a_sloped_dem_is_the_orthogonal_projection() {
        let n = 30;
        let heights_m = (0..n * n).map(|i| Some(0.7 * (i % n) as f64)).collect();
        let s = HeightSurface::new("slope", Heightmap { width: n, height: n, spacing_m: 1.0, heights_m });
        let normal = unit([-0.7, 0.0, 1.0]);
        let mut rng = team_rng(6);
        for _ in 0..40 {
            let foot = [10.0 + 8.0 * uniform(&mut rng), 10.0 + 8.0 * uniform(&mut rng), 0.0];
            let foot = [foot[0], foot[1], 0.7 * foot[0]];
            let off = 2.5 * uniform(&mut rng) - 1.25;
            let p = add(foot, scale(normal, off));
            let q = s.closest_point(p, 3.0).expect("within reach");
            assert!(dist(q, foot) <= 0.03, "{p:?}: {q:?} vs {foot:?}");
        }
        let far = add([15.0, 15.0, 10.5], scale(normal, 3.5));
        assert_eq!(s.closest_point(far, 3.0), None);
    }
}
