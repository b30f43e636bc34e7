//! Exact distance helpers in `f64` for the ground-truth worlds.

//! The vector helpers are [`firmware::geom::p3`]'s.

pub use firmware::geom::p3::P3;
use firmware::geom::p3::{add_scaled, dot, sub};

/// Closest point to `p` on triangle `(a, b, c)` (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(p: P3, a: P3, b: P3, c: P3) -> P3 {
    let ab = sub(b, a);
    let ac = sub(c, a);
    let ap = sub(p, a);
    let d1 = dot(ab, ap);
    let d2 = dot(ac, ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = sub(p, b);
    let d3 = dot(ab, bp);
    let d4 = dot(ac, bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return add_scaled(a, ab, d1 / (d1 - d3));
    }
    let cp = sub(p, c);
    let d5 = dot(ab, cp);
    let d6 = dot(ac, cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return add_scaled(a, ac, d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return add_scaled(b, sub(c, b), (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    add_scaled(add_scaled(a, ab, v), ac, w)
}

/// Distance from 2D point `p` to segment `a`-`b`.
pub fn segment_distance_2d(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let ab = [b[0] - a[0], b[1] - a[1]];
    let ap = [p[0] - a[0], p[1] - a[1]];
    let l2 = ab[0] * ab[0] + ab[1] * ab[1];
    let t = if l2 > 0.0 { ((ap[0] * ab[0] + ap[1] * ab[1]) / l2).clamp(0.0, 1.0) } else { 0.0 };
    let d = [ap[0] - ab[0] * t, ap[1] - ab[1] * t];
    (d[0] * d[0] + d[1] * d[1]).sqrt()
}

/// Signed distance from `p` to a convex polygon given counter-clockwise (negative inside). Exact.
pub fn convex_polygon_sdf(p: [f64; 2], poly: &[[f64; 2]]) -> f64 {
    let n = poly.len();
    let mut d = f64::INFINITY;
    let mut inside = n >= 3;
    for i in 0..n {
        let a = poly[i];
        let b = poly[(i + 1) % n];
        d = d.min(segment_distance_2d(p, a, b));
        let cr = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        if cr < 0.0 {
            inside = false;
        }
    }
    if inside {
        -d
    } else {
        d
    }
}

/// Sphere tracing along unit `dir` from `origin` on an SDF that never overestimates the distance outside the
/// solid. Returns the first `t` with `sdf < eps`, bounded by `max_steps`.
pub fn sphere_trace(sdf: impl Fn(P3) -> f64, origin: P3, dir: P3, max_range: f64, max_steps: usize) -> Option<f64> {
    let mut t = 0.0;
    for _ in 0..max_steps {
        let d = sdf(add_scaled(origin, dir, t));
        if d < 1e-5 {
            return Some(t);
        }
        t += d;
        if t > max_range {
            return None;
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::geom::p3::norm;

    #[test]
    fn triangle_closest_point_matches_dense_sampling() {
        let (a, b, c) = ([0.0, 0.0, 0.0], [2.0, 0.0, 0.5], [0.3, 1.5, -0.2]);
        for p in [[0.5, 0.5, 1.0], [-1.0, -1.0, 0.0], [3.0, 0.0, 0.0], [1.0, 2.0, 3.0], [0.2, 0.2, -0.3]] {
            let q = closest_point_on_triangle(p, a, b, c);
            let d = norm(sub(p, q));
            let mut best = f64::INFINITY;
            let n = 400;
            for i in 0..=n {
                for j in 0..=(n - i) {
                    let (u, v) = (i as f64 / n as f64, j as f64 / n as f64);
                    let s = add_scaled(add_scaled(a, sub(b, a), u), sub(c, a), v);
                    best = best.min(norm(sub(p, s)));
                }
            }
            assert!(d <= best + 1e-12 && best - d < 0.01, "{p:?}: {d} vs sampled {best}");
        }
    }

    #[test]
    fn square_sdf() {
        let sq = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
        assert!((convex_polygon_sdf([0.5, 0.5], &sq) + 0.5).abs() < 1e-12);
        assert!((convex_polygon_sdf([2.0, 0.5], &sq) - 1.0).abs() < 1e-12);
        assert!((convex_polygon_sdf([2.0, 2.0], &sq) - 2f64.sqrt()).abs() < 1e-12);
    }
}
