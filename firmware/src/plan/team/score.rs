//! Anchor-point scoring, Morad et al. section V-A.4 and VI: every surface vertex gets a non-negative risk score,
//! zero being the safest.
//!
//! r = w_relative_height * r_h + w_flatness * r_f (+ unobserved_penalty for a vertex the reconstruction filled in)
//!
//! Both terms use the *local plane*: the least-squares plane of the surface vertices within `score_radius`
//! (centroid + smallest-eigenvalue eigenvector, oriented like the scene normal), so a uniform slope of any
//! steepness — a cliff — scores like flat ground.
//!
//! - **Relative height** r_h in [0, 1]: how far the vertex lies *below* its local plane, divided by
//!   `relief_scale`, clamped. Depressions — pits, valleys, craters, where regolith collects and microspines fail —
//!   score high; a vertex on or above its surroundings (a top, with the better vantage point the paper mentions)
//!   scores 0.
//! - **Flatness** r_f in [0, 1]: RMS distance of the neighbours from the local plane divided by `flatness_scale`,
//!   clamped. A hop that misses lands on flat ground rather than in a hole or on a jagged edge.
//!
//! Parameters (from [`TeamParams`], defaults): `w_relative_height` 1.0, `w_flatness` 1.0, `relief_scale` 1 m,
//! `flatness_scale` 0.5 m, `score_radius` 3 m, `unobserved_penalty` 0.5.
//!
//! [`TeamParams`]: crate::config::team::TeamParams

use super::scene::{smallest_eigenvector, CellState, Scene};
use crate::geom::{normalize3, Vec3};
use nalgebra::Matrix3;
use crate::config::team::{TeamParams, SURFACE_CELLS_PER_AXIS, SURFACE_MAX_VERTICES};
use crate::geom::Real;

const N: usize = SURFACE_CELLS_PER_AXIS;

/// Score every non-empty surface vertex into `scores` (empty cells get `Real::INFINITY`).
pub fn score_vertices<const P: usize>(scene: &Scene<P>, params: &TeamParams, scores: &mut [Real; SURFACE_MAX_VERTICES]) {
    let reach = (params.score_radius / scene.cell) as i64;
    let reach = reach.clamp(1, N as i64);
    let r2 = params.score_radius * params.score_radius;
    for k in 0..SURFACE_MAX_VERTICES {
        let st = scene.state.get(k).copied().unwrap_or_default();
        let out = match st {
            CellState::Empty => Real::INFINITY,
            _ => {
                let p = scene.vertex(k);
                let (i, j) = ((k % N) as i64, (k / N) as i64);
                // pass 1: centroid and covariance of the neighbourhood
                let mut c = Vec3::zeros();
                let mut cnt = 0u32;
                let nbrs = |f: &mut dyn FnMut(Vec3)| {
                    for y in (j - reach).max(0)..=(j + reach).min(N as i64 - 1) {
                        for x in (i - reach).max(0)..=(i + reach).min(N as i64 - 1) {
                            let q = y as usize * N + x as usize;
                            if scene.state.get(q).copied().unwrap_or_default() == CellState::Empty {
                                continue;
                            }
                            let pq = scene.vertex(q);
                            if (pq - p).norm_squared() <= r2 {
                                f(pq);
                            }
                        }
                    }
                };
                nbrs(&mut |pq| {
                    c += pq;
                    cnt += 1;
                });
                let (r_h, r_f) = if cnt >= 3 {
                    c /= cnt as Real;
                    let mut m = Matrix3::<Real>::zeros();
                    nbrs(&mut |pq| {
                        let d = pq - c;
                        m += d * d.transpose();
                    });
                    m /= cnt as Real;
                    let n = smallest_eigenvector([[m.m11, m.m12, m.m13], [m.m21, m.m22, m.m23], [m.m31, m.m32, m.m33]])
                        .and_then(|(n, _)| normalize3(&n, 1e-9))
                        .map(|n| if n.dot(&scene.frame.n) < 0.0 { -n } else { n })
                        .unwrap_or(scene.frame.n);
                    let depth = (c - p).dot(&n);
                    let mut ss = 0.0 as Real;
                    nbrs(&mut |pq| {
                        let d = (pq - c).dot(&n);
                        ss += d * d;
                    });
                    let rms = libm::sqrtf(ss / cnt as Real);
                    (
                        (depth / params.relief_scale.max(1e-6)).clamp(0.0, 1.0),
                        (rms / params.flatness_scale.max(1e-6)).min(1.0),
                    )
                } else {
                    (0.0, 1.0)
                };
                let pen = if st == CellState::Filled { params.unobserved_penalty } else { 0.0 };
                params.w_relative_height * r_h + params.w_flatness * r_f + pen
            }
        };
        if let Some(s) = scores.get_mut(k) {
            *s = out;
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::config::team::SCENE_MAX_POINTS;
    use std::boxed::Box;
    use std::vec::Vec;

    #[test]
    fn pits_score_worse_than_tops_and_rough_worse_than_flat() {
        // a 30 x 30 m plane with a 2 m deep pit at (8, 8), a 2 m bump at (22, 22) and a rough patch at (22, 8)
        let mut pts = Vec::new();
        for j in 0..60 {
            for i in 0..60 {
                let (x, y) = (i as Real * 0.5, j as Real * 0.5);
                let r_pit = libm::sqrtf((x - 8.0) * (x - 8.0) + (y - 8.0) * (y - 8.0));
                let r_top = libm::sqrtf((x - 22.0) * (x - 22.0) + (y - 22.0) * (y - 22.0));
                let mut z = 0.0;
                if r_pit < 3.0 {
                    z -= 2.0 * (1.0 - r_pit / 3.0);
                }
                if r_top < 3.0 {
                    z += 2.0 * (1.0 - r_top / 3.0);
                }
                if (x - 22.0).abs() < 3.0 && (y - 8.0).abs() < 3.0 {
                    z += if (i + j) % 2 == 0 { 0.6 } else { -0.6 };
                }
                pts.push(Vec3::new(x, y, z));
            }
        }
        let p = TeamParams::DEFAULT;
        let mut s: Box<Scene<SCENE_MAX_POINTS>> = Box::default();
        s.build(&pts, &Vec3::z(), &p).unwrap();
        let mut scores = [0.0; SURFACE_MAX_VERTICES];
        score_vertices(&s, &p, &mut scores);
        let at = |x: Real, y: Real| {
            let l = s.frame.to_local(&Vec3::new(x, y, 0.0));
            scores[s.cell_of(l.x, l.y).unwrap()]
        };
        let (pit, top, rough, flat) = (at(8.0, 8.0), at(22.0, 22.0), at(22.0, 8.0), at(8.0, 22.0));
        assert!(pit > top + 0.5, "pit {pit} top {top}");
        assert!(rough > flat + 0.5, "rough {rough} flat {flat}");
        assert!(flat < 0.05, "flat {flat}");
        assert!(scores.iter().all(|r| r.is_infinite() || *r >= 0.0));
    }
}
