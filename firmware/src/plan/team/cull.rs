//! Culling, Morad et al. section V-A.5 and VI: sort the anchor points by ascending score and keep the best
//! fraction (the paper keeps 15 % and drops the other 85 % "to improve performance").
//!
//! Parameter: `keep_permille` (default 150). The kept set is also capped by the graph's vertex capacity; the
//! outcome says when the cap cut it ([`CullOutcome::truncated`]). Ties are broken by vertex index so the result is
//! deterministic.

use crate::config::team::{TeamParams, SURFACE_MAX_VERTICES};
use crate::geom::Real;

/// What culling kept.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CullOutcome {
    /// Candidates (finite scores).
    pub candidates: usize,
    /// Kept (written to the front of `order`).
    pub kept: usize,
    /// The capacity `cap` cut the kept set below the requested fraction.
    pub truncated: bool,
}

/// Sort candidate indices by (score, index) into `order` and return how many to keep (at most `cap`).
pub fn cull(scores: &[Real; SURFACE_MAX_VERTICES], params: &TeamParams, cap: usize, order: &mut [u16; SURFACE_MAX_VERTICES]) -> CullOutcome {
    let mut n = 0usize;
    for (k, s) in scores.iter().enumerate() {
        if s.is_finite() {
            if let Some(o) = order.get_mut(n) {
                *o = k as u16;
                n += 1;
            }
        }
    }
    let slice = order.get_mut(..n).unwrap_or(&mut []);
    slice.sort_unstable_by(|&a, &b| {
        let sa = scores.get(a as usize).copied().unwrap_or(Real::INFINITY);
        let sb = scores.get(b as usize).copied().unwrap_or(Real::INFINITY);
        sa.total_cmp(&sb).then(a.cmp(&b))
    });
    let want = (n * params.keep_permille as usize).div_ceil(1000).min(n);
    CullOutcome { candidates: n, kept: want.min(cap), truncated: want > cap }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keeps_the_best_fraction_in_score_order() {
        let mut scores = [Real::INFINITY; SURFACE_MAX_VERTICES];
        for (k, s) in scores.iter_mut().enumerate().take(1000) {
            *s = ((k * 7919) % 1000) as Real; // a permutation of 0..1000
        }
        let mut order = [0u16; SURFACE_MAX_VERTICES];
        let out = cull(&scores, &TeamParams::DEFAULT, 512, &mut order);
        assert_eq!(out, CullOutcome { candidates: 1000, kept: 150, truncated: false });
        for (rank, &k) in order.iter().take(150).enumerate() {
            assert_eq!(scores[k as usize], rank as Real);
        }
        let out = cull(&scores, &TeamParams::DEFAULT, 100, &mut order);
        assert_eq!(out, CullOutcome { candidates: 1000, kept: 100, truncated: true });
    }
}
