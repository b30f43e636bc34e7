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
    heap_sort(slice, |a, b| {
        let sa = scores.get(a as usize).copied().unwrap_or(Real::INFINITY);
        let sb = scores.get(b as usize).copied().unwrap_or(Real::INFINITY);
        sa.total_cmp(&sb).then(a.cmp(&b)).is_lt()
    });
    let want = (n * params.keep_permille as usize).div_ceil(1000).min(n);
    CullOutcome { candidates: n, kept: want.min(cap), truncated: want > cap }
}

/// Sorts `v` ascending by `less` (a strict total order): heapsort, `O(n log n)` and in place, with checked
/// indexing only, so the flight build keeps no panic path (the library sorts panic on an inconsistent order).
fn heap_sort(v: &mut [u16], less: impl Fn(u16, u16) -> bool) {
    let n = v.len();
    let get = |v: &[u16], i: usize| v.get(i).copied().unwrap_or(0);
    let swap = |v: &mut [u16], i: usize, j: usize| {
        let (a, b) = (get(v, i), get(v, j));
        if let Some(x) = v.get_mut(i) {
            *x = b;
        }
        if let Some(x) = v.get_mut(j) {
            *x = a;
        }
    };
    // sift `root` down within the first `end` elements (a max-heap by `less`); at most log2(n) levels
    let sift = |v: &mut [u16], mut root: usize, end: usize| {
        while 2 * root + 1 < end {
            let mut child = 2 * root + 1;
            if child + 1 < end && less(get(v, child), get(v, child + 1)) {
                child += 1;
            }
            if !less(get(v, root), get(v, child)) {
                return;
            }
            swap(v, root, child);
            root = child;
        }
    };
    for root in (0..n / 2).rev() {
        sift(v, root, n);
    }
    for end in (1..n).rev() {
        swap(v, 0, end);
        sift(v, 0, end);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heap_sort_orders_as_the_library_sort_does() {
        // a fixed pseudo-random sequence with repeats; the order is by key, ties by index (a strict total order)
        let keys: [u32; 97] = core::array::from_fn(|i| ((i as u32).wrapping_mul(2_654_435_761) >> 7) % 23);
        let mut ours: [u16; 97] = core::array::from_fn(|i| i as u16);
        let mut lib = ours;
        let less = |a: u16, b: u16| (keys[a as usize], a) < (keys[b as usize], b);
        heap_sort(&mut ours, less);
        lib.sort_unstable_by_key(|&a| (keys[a as usize], a));
        assert_eq!(ours, lib);
        for n in 0..4 {
            let mut short: [u16; 3] = [2, 0, 1];
            heap_sort(short.get_mut(..n.min(3)).unwrap_or(&mut []), |a, b| a < b);
            assert!(short.get(..n.min(3)).unwrap_or(&[]).windows(2).all(|w| w[0] <= w[1]), "{n}: {short:?}");
        }
    }

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
