//! Anchor-point scoring, Morad et al. section V-A.4 and VI: every surface vertex gets a non-negative risk score,
//! zero being the safest.
//!
//! r = w_relative_height * r_h + w_flatness * r_f (+ unobserved_penalty for a vertex the reconstruction filled in)
//!
//! - **Relative height** r_h in [0, 1]: within `score_radius`, (z_max - z) / (z_max - z_min) of the scene heights
//!   (along the scene normal). Depressions — pits, valleys, craters, where regolith collects and microspines
//!   fail — score high; a local top scores 0 (and gives the better vantage point the paper mentions).
//! - **Flatness** r_f in [0, 1]: RMS distance of the neighbours within `score_radius` from the plane through the
//!   vertex with the vertex's (kNN) normal, divided by `flatness_scale`, clamped to 1. A hop that misses lands on
//!   flat ground rather than in a hole or on a jagged edge.
//!
//! Parameters (from [`TeamParams`], defaults): `w_relative_height` 1.0, `w_flatness` 1.0, `flatness_scale` 0.5 m,
//! `score_radius` 3 m, `unobserved_penalty` 0.5.
//!
//! [`TeamParams`]: crate::config::team::TeamParams

use super::scene::{CellState, Scene};
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
                let n = scene.cell_normal.get(k).copied().unwrap_or(scene.frame.n);
                let z = scene.height.get(k).copied().unwrap_or(0.0);
                let (i, j) = ((k % N) as i64, (k / N) as i64);
                let (mut zmin, mut zmax) = (z, z);
                let (mut ss, mut cnt) = (0.0 as Real, 0u32);
                for y in (j - reach).max(0)..=(j + reach).min(N as i64 - 1) {
                    for x in (i - reach).max(0)..=(i + reach).min(N as i64 - 1) {
                        let q = y as usize * N + x as usize;
                        if scene.state.get(q).copied().unwrap_or_default() == CellState::Empty {
                            continue;
                        }
                        let pq = scene.vertex(q);
                        if (pq - p).norm_squared() > r2 {
                            continue;
                        }
                        let zq = scene.height.get(q).copied().unwrap_or(0.0);
                        zmin = zmin.min(zq);
                        zmax = zmax.max(zq);
                        let d = (pq - p).dot(&n);
                        ss += d * d;
                        cnt += 1;
                    }
                }
                let r_h = if zmax - zmin > 1e-6 { (zmax - z) / (zmax - zmin) } else { 0.0 };
                let rms = if cnt > 0 { libm::sqrtf(ss / cnt as Real) } else { 0.0 };
                let r_f = (rms / params.flatness_scale.max(1e-6)).min(1.0);
                let pen = if st == CellState::Filled { params.unobserved_penalty } else { 0.0 };
                params.w_relative_height * r_h + params.w_flatness * r_f + pen
            }
        };
        if let Some(s) = scores.get_mut(k) {
            *s = out;
        }
    }
}
