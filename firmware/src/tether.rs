//! Anchor-point prediction (Paton et al., *Navigation on the Line*, section IV-B, Alg. 1, Figs. 3-5).
//!
//! The tether runs from the root anchor `a_0` over intermediate anchors (points where it touches the terrain) to
//! the rover. The **anchor history** `A = {a_0, ..., a_N}` is a stack of (point, ESDF gradient) pairs; anchors are
//! removed in reverse order only. [`predict_anchors`] computes the anchor history `A_1` of the rover at `x_1` from
//! the history `A_0` at an adjacent position `x_0`, under the paper's assumptions: small motion, taut massless
//! straight tether between anchors, stack order.
//!
//! Positions `x` are the tether's end on the rover (the caller chooses: the boom tip, or the axle centre).
//!
//! # Attachment (IV-B a, Fig. 4)
//! The tether sweeps the triangle `(a, x_0, x_1)` (pivot `a` = the last anchor). The triangle is sampled on
//! `SWEEP_SAMPLES_ACROSS` sweep lines `a -> x(t)`, `x(t) = (1 - t) x_0 + t x_1`, with `SWEEP_SAMPLES_ALONG` points
//! each; a sample within `TETHER_CONTACT_DISTANCE_M` of the terrain (or inside it) is an obstacle. The angle
//! between the current tether `x_0 - a` and `p - a` grows monotonically with `t`, so the obstacle at the smallest
//! angle lies on the first blocked sweep line; `SWEEP_REFINE_STEPS` bisection steps refine that line, and its
//! closest-to-terrain sample, projected onto the surface, becomes the new anchor (with its gradient). The tether
//! is then inline with the new anchor at `x(t*)`, and the search repeats with the new anchor as pivot over the
//! triangle `(a_new, x(t*), x_1)` until no obstacle is found (at most `MAX_ATTACH_PER_SWEEP` times).
//! Samples within `PIVOT_EXCLUSION_M` of the pivot are skipped (the pivot is on the surface); `NEAR_PIVOT_SAMPLES`
//! extra samples cover `[PIVOT_EXCLUSION_M, NEAR_PIVOT_RANGE_M]` from the pivot, so a tether wrapping a curved
//! surface (a pole) is caught as soon as it cuts in beyond the exclusion: successive anchors on a cylinder of radius
//! `r` are then about `2 asin(PIVOT_EXCLUSION_M / 2r)` apart (0.4 rad on the 0.25 m test pole... see the tests).
//! On a field that declares itself known everywhere and `L`-Lipschitz (`DistanceField::lipschitz_bound`: an exact
//! world, not the onboard map), a sample at distance `d` proves the points within `(d - c) / L` of it clear: the
//! samples of the same line and of the next sweep lines (which differ by a fraction of the motion) that lie there
//! are not queried. The same samples block, so the same anchors, with a fraction of the queries. On the onboard map
//! (`DistanceField::cell_key`: trilinear cells) a query also bounds the distance over its interpolation cell; a
//! sample of the next sweep line, or the next sample of the same line, in a cell bounded beyond the contact
//! distance is not queried either (same anchors: the test `the_maps_cell_bounds_give_the_same_anchors_...`).
//!
//! # Detachment (IV-B b, Fig. 5)
//! Frame `F_d` at anchor `a_N`: `b` = unit(`a_N - a_{N-1}`) (the incoming tether), `z` = the anchor's gradient made
//! orthogonal to `b`. The XY plane of `F_d` contains the incoming tether's straight continuation; if the rover is
//! above it, `(x - a_N) . z > 0`, the tether no longer bends at `a_N`: detachment. The detachment position on the
//! motion is where `(x(t) - a_N) . z = 0` (linear in `t`).
//!
//! # Parameters (`config::tether`)
//! `ANCHOR_HISTORY_CAPACITY = 32`, `SWEEP_SAMPLES_ALONG = 48`, `SWEEP_SAMPLES_ACROSS = 24`, `SWEEP_REFINE_STEPS =
//! 14`, `MAX_ATTACH_PER_SWEEP = 16`, `MAX_DETACH_ITERATIONS = 32`, `TETHER_CONTACT_DISTANCE_M = 0.005`,
//! `PIVOT_EXCLUSION_M = 0.1`, `NEAR_PIVOT_SAMPLES = 16`, `NEAR_PIVOT_RANGE_M = 1.0`.

use crate::config::tether::{
    ANCHOR_HISTORY_CAPACITY, MAX_ATTACH_PER_SWEEP, MAX_DETACH_ITERATIONS, NEAR_PIVOT_RANGE_M, NEAR_PIVOT_SAMPLES,
    PIVOT_EXCLUSION_M, SWEEP_REFINE_STEPS,
    SWEEP_SAMPLES_ACROSS, SWEEP_SAMPLES_ALONG, TETHER_CONTACT_DISTANCE_M,
};
use crate::geom::{normalize3, Real, Vec3};
use crate::map::{CellKey, DistanceField, DistanceQuery};

/// A tether-terrain contact point: the point and the ESDF gradient there (Paton: `a_i = (p, g)`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Anchor {
    /// Contact point, world frame.
    pub point: Vec3,
    /// ESDF gradient at the contact (away from the terrain). Zero for a root anchor in free space.
    pub gradient: Vec3,
}

impl Anchor {
    /// A root anchor (lander, mast): a point with no surface gradient.
    pub fn root(point: Vec3) -> Self {
        Anchor { point, gradient: Vec3::zeros() }
    }
}

/// The anchor history: a bounded stack, root anchor first.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct AnchorHistory {
    anchors: heapless::Vec<Anchor, ANCHOR_HISTORY_CAPACITY>,
}

impl AnchorHistory {
    /// An empty history (const, for storage in `.bss`).
    pub const fn empty() -> Self {
        AnchorHistory { anchors: heapless::Vec::new() }
    }
    /// A history holding only the root anchor.
    pub fn new(root: Anchor) -> Self {
        let mut anchors = heapless::Vec::new();
        let _ = anchors.push(root);
        AnchorHistory { anchors }
    }
    /// Push an anchor; a full stack hands it back.
    pub fn push(&mut self, a: Anchor) -> Result<(), Anchor> {
        self.anchors.push(a)
    }
    /// Pop the most recent anchor.
    pub fn pop(&mut self) -> Option<Anchor> {
        self.anchors.pop()
    }
    /// The most recent anchor (the one the tether leaves towards the rover).
    pub fn last(&self) -> Option<&Anchor> {
        self.anchors.last()
    }
    /// Number of anchors, root included.
    pub fn len(&self) -> usize {
        self.anchors.len()
    }
    /// True when empty (no root anchor).
    pub fn is_empty(&self) -> bool {
        self.anchors.is_empty()
    }
    /// The anchors, root first.
    pub fn as_slice(&self) -> &[Anchor] {
        &self.anchors
    }
    /// Tether length along the anchors to `x`.
    pub fn length_to(&self, x: &Vec3) -> Real {
        let mut len = 0.0;
        let mut prev: Option<&Anchor> = None;
        for a in self.anchors.iter() {
            if let Some(p) = prev {
                len += crate::geom::norm3(&(a.point - p.point));
            }
            prev = Some(a);
        }
        if let Some(p) = prev {
            len += crate::geom::norm3(&(x - p.point));
        }
        len
    }
}

/// Why anchor prediction stopped early. The output history holds the work done so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TetherError {
    /// The input history has no root anchor.
    EmptyHistory,
    /// The anchor history reached `ANCHOR_HISTORY_CAPACITY`.
    HistoryFull,
    /// A sample of the sweep triangle was in unobserved space (unsafe).
    UnknownSpace,
    /// `MAX_DETACH_ITERATIONS` or `MAX_ATTACH_PER_SWEEP` ran out.
    BudgetExhausted,
    /// A position is not finite.
    InvalidInput,
}

/// Counters of one prediction.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PredictStats {
    /// Anchors attached.
    pub attached: u32,
    /// Anchors detached.
    pub detached: u32,
    /// ESDF queries made.
    pub queries: u32,
}

fn lerp(a: &Vec3, b: &Vec3, t: Real) -> Vec3 {
    a * (1.0 - t) + b * t
}

/// Samples on one sweep line: the near-pivot ones, then the uniform ones.
const LINE_SAMPLES: usize = (NEAR_PIVOT_SAMPLES + SWEEP_SAMPLES_ALONG) as usize;

/// What the sweep lines of one prediction have learnt on a Lipschitz field (`DistanceField::lipschitz_bound`): for
/// each sample of a line, by its index, a point queried and the distance there (the sample's own last query, or the
/// query whose clearance covered it). A sample within `(d - c) / L` of its witness cannot be within the contact
/// distance `c`: consecutive sweep lines share the pivot and differ by a fraction of the motion, so the line before
/// proves most of a line's samples clear. Without a bound no witness is kept.
///
/// On a field that is piecewise over cells (`DistanceField::cell_key`: the onboard map's interpolation cells) it
/// remembers, for each sample index, the last cell queried there and the lower bound on the distance over it: a
/// sample of the next sweep line in the same cell, bounded beyond the contact distance, is clear (the samples of
/// neighbouring lines are a fraction of a voxel apart).
struct SweepMemo {
    lipschitz: Option<Real>,
    /// (witness point, its distance); the distance is minus infinity where there is none.
    witness: [(Vec3, Real); LINE_SAMPLES],
    /// (cell, lower bound of the distance in it); the bound is minus infinity where there is none.
    cells: [(CellKey, Real); LINE_SAMPLES],
}

impl SweepMemo {
    fn new(map: &impl DistanceField) -> Self {
        SweepMemo {
            lipschitz: crate::map::usable_lipschitz_bound(map),
            witness: [(Vec3::zeros(), Real::NEG_INFINITY); LINE_SAMPLES],
            cells: [([0; 3], Real::NEG_INFINITY); LINE_SAMPLES],
        }
    }
}

/// The lower bound on the distance at `p` that a witness `(at, d)` gives on an `l`-Lipschitz field.
fn witnessed(l: Real, (at, d): &(Vec3, Real), p: &Vec3) -> Real {
    crate::map::lipschitz_lower_bound(l, *d, crate::geom::norm3(&(p - at)))
}

/// Closest-to-terrain sample on the sweep line `pivot -> end` (its line parameter `s`, gradient and distance), if
/// any sample is an obstacle.
fn blocked_line(
    map: &impl DistanceField,
    pivot: &Vec3,
    end: &Vec3,
    memo: &mut SweepMemo,
    stats: &mut PredictStats,
) -> Result<Option<(Real, Vec3, Real)>, TetherError> {
    let len = crate::geom::norm3(&(end - pivot));
    let mut best: Option<(Real, Vec3, Real)> = None;
    // on a Lipschitz field the last sample queried clears a stretch of the line around it: (line parameter,
    // half-width, the sample, its distance), shrunk by 0.1 % for rounding; samples inside it, and samples whose
    // witness from an earlier line proves them clear, cannot be within the contact distance and are not queried
    // (the same answer with fewer queries)
    let lipschitz = memo.lipschitz;
    let mut cleared: Option<(Real, Real, Vec3, Real)> = None;
    // the cell of the last sample queried or skipped on this line, with its bound
    let mut last_cell: (CellKey, Real) = ([0; 3], Real::NEG_INFINITY);
    let near = NEAR_PIVOT_SAMPLES;
    for k in 1..=(SWEEP_SAMPLES_ALONG + near) {
        // the first `near` samples cover [PIVOT_EXCLUSION_M, NEAR_PIVOT_RANGE_M] from the pivot finely (a tether
        // wrapping a curved surface next to its pivot); the rest are uniform along the whole line
        let s = if k <= near {
            let dist = PIVOT_EXCLUSION_M + (NEAR_PIVOT_RANGE_M - PIVOT_EXCLUSION_M) * (k - 1) as Real / near as Real;
            if len > 0.0 { dist / len } else { 1.0 }
        } else {
            (k - near) as Real / SWEEP_SAMPLES_ALONG as Real
        };
        if s * len < PIVOT_EXCLUSION_M || s > 1.0 {
            continue;
        }
        let p = lerp(pivot, end, s);
        let witness = memo.witness.get_mut((k - 1) as usize);
        if let (Some(l), Some(w)) = (lipschitz, witness) {
            if witnessed(l, w, &p) > TETHER_CONTACT_DISTANCE_M {
                continue;
            }
            if let Some((_, _, at, d)) = cleared.filter(|(sc, half, _, _)| libm::fabsf(s - sc) * len < *half) {
                *w = (at, d);
                continue;
            }
        }
        // the same cell as this sample's on an earlier line (or the previous sample's on this one), bounded clear
        let key = map.cell_key(&p);
        let memo_cell = memo.cells.get_mut((k - 1) as usize);
        if let (Some(key), Some(cell)) = (key, memo_cell) {
            let clear = |(c, lower): &(CellKey, Real)| *c == key && *lower > TETHER_CONTACT_DISTANCE_M;
            if clear(cell) {
                last_cell = *cell;
                continue;
            }
            if clear(&last_cell) {
                *cell = last_cell;
                continue;
            }
        }
        stats.queries += 1;
        let (query, lower) = map.query_with_cell_bound(&p);
        if let (Some(key), Some(cell)) = (key, memo.cells.get_mut((k - 1) as usize)) {
            *cell = (key, lower.unwrap_or(Real::NEG_INFINITY));
            last_cell = *cell;
        }
        match query {
            DistanceQuery::Unknown => return Err(TetherError::UnknownSpace),
            DistanceQuery::Known { distance, gradient } => {
                if distance <= TETHER_CONTACT_DISTANCE_M && best.is_none_or(|b| distance < b.2) {
                    best = Some((s, gradient, distance));
                }
                if let Some(l) = lipschitz {
                    cleared = Some((s, 0.999 * (distance - TETHER_CONTACT_DISTANCE_M) / l, p, distance));
                    if let Some(w) = memo.witness.get_mut((k - 1) as usize) {
                        *w = (p, distance);
                    }
                }
            }
        }
    }
    Ok(best)
}

/// Does the straight tether from `pivot` to `end` touch the terrain (the sweep-line test of the attachment
/// search, one line)? Used to find where the tether starts to catch (`plan::tethered`'s catch-boundary samples).
pub fn tether_touches(map: &impl DistanceField, pivot: &Vec3, end: &Vec3) -> Result<bool, TetherError> {
    if !(pivot.iter().all(|v| v.is_finite()) && end.iter().all(|v| v.is_finite())) {
        return Err(TetherError::InvalidInput);
    }
    let mut stats = PredictStats::default();
    Ok(blocked_line(map, pivot, end, &mut SweepMemo::new(map), &mut stats)?.is_some())
}

/// Attachment search (IV-B a) for the tether pivoting about `pivot` while its end moves `x0 -> x1`. New anchors are
/// pushed onto `out` in order; returns how many.
pub fn attach_anchors(
    map: &impl DistanceField,
    x0: &Vec3,
    x1: &Vec3,
    pivot: &Anchor,
    out: &mut AnchorHistory,
    stats: &mut PredictStats,
) -> Result<u32, TetherError> {
    let mut memo = SweepMemo::new(map);
    let mut piv = pivot.point;
    let mut start = *x0;
    for added in 0..MAX_ATTACH_PER_SWEEP as u32 {
        // first blocked sweep line (smallest angle from the current tether)
        let mut first: Option<(Real, Real)> = None; // (t_free, t_blocked)
        let mut t_prev = 0.0;
        for k in 0..=SWEEP_SAMPLES_ACROSS {
            let t = k as Real / SWEEP_SAMPLES_ACROSS as Real;
            if blocked_line(map, &piv, &lerp(&start, x1, t), &mut memo, stats)?.is_some() {
                first = Some((t_prev, t));
                break;
            }
            t_prev = t;
        }
        let Some((mut lo, mut hi)) = first else {
            return Ok(added);
        };
        if hi == 0.0 {
            // already blocked at the start: the contact is at the current tether itself
            lo = 0.0;
        } else {
            for _ in 0..SWEEP_REFINE_STEPS {
                let mid = 0.5 * (lo + hi);
                if blocked_line(map, &piv, &lerp(&start, x1, mid), &mut memo, stats)?.is_some() {
                    hi = mid;
                } else {
                    lo = mid;
                }
            }
        }
        let _ = lo;
        let end = lerp(&start, x1, hi);
        let Some((s_best, g, d)) = blocked_line(map, &piv, &end, &mut memo, stats)? else {
            return Ok(added);
        };
        // refine the contact along the line: ternary search for the distance minimum between the neighbours
        let ds = 1.0 / SWEEP_SAMPLES_ALONG as Real;
        let (mut s_lo, mut s_hi) = ((s_best - ds).max(0.0), (s_best + ds).min(1.0));
        let mut best = (lerp(&piv, &end, s_best), g, d);
        for _ in 0..SWEEP_REFINE_STEPS {
            let m1 = s_lo + (s_hi - s_lo) / 3.0;
            let m2 = s_hi - (s_hi - s_lo) / 3.0;
            let (p1, p2) = (lerp(&piv, &end, m1), lerp(&piv, &end, m2));
            stats.queries += 2;
            let (DistanceQuery::Known { distance: d1, gradient: g1 }, DistanceQuery::Known { distance: d2, gradient: g2 }) =
                (map.query(&p1), map.query(&p2))
            else {
                return Err(TetherError::UnknownSpace);
            };
            if d1 < d2 {
                s_hi = m2;
                if d1 < best.2 {
                    best = (p1, g1, d1);
                }
            } else {
                s_lo = m1;
                if d2 < best.2 {
                    best = (p2, g2, d2);
                }
            }
        }
        let (p, g, d) = best;
        let n = normalize3(&g, 1e-6).unwrap_or(g);
        let anchor = Anchor { point: p - n * d, gradient: n };
        out.push(anchor).map_err(|_| TetherError::HistoryFull)?;
        stats.attached += 1;
        piv = anchor.point;
        start = end;
    }
    Err(TetherError::BudgetExhausted)
}

/// The detachment normal `z` of frame `F_d` at `a` with predecessor `prev`, or `None` if degenerate.
fn detach_axis(prev: &Anchor, a: &Anchor) -> Option<Vec3> {
    let b = normalize3(&(a.point - prev.point), 1e-6)?;
    normalize3(&(a.gradient - b * b.dot(&a.gradient)), 1e-6)
}

/// Detachment test (IV-B b): is the tether at `x` no longer bent at `a` (predecessor `prev`)?
pub fn is_detached(prev: &Anchor, a: &Anchor, x: &Vec3) -> bool {
    match detach_axis(prev, a) {
        Some(z) => (x - a.point).dot(&z) > 0.0,
        // no usable normal (root-like anchor): it cannot hold the tether
        None => true,
    }
}

/// Position on the motion `x0 -> x1` at which the tether detaches from `a` (IV-B b, `detach_line`).
pub fn detach_line(prev: &Anchor, a: &Anchor, x0: &Vec3, x1: &Vec3) -> Vec3 {
    let Some(z) = detach_axis(prev, a) else {
        return *x0;
    };
    let f0 = (x0 - a.point).dot(&z);
    let f1 = (x1 - a.point).dot(&z);
    let den = f1 - f0;
    let t = if libm::fabsf(den) > 1e-9 { (-f0 / den).clamp(0.0, 1.0) } else { 0.0 };
    lerp(x0, x1, t)
}

/// Alg. 1: the anchor history of the rover at `x1`, given history `a0` at the adjacent position `x0`. `out` is
/// overwritten with the result; on error it holds the work done so far.
pub fn predict_anchors(
    map: &impl DistanceField,
    a0: &AnchorHistory,
    x0: &Vec3,
    x1: &Vec3,
    out: &mut AnchorHistory,
) -> Result<PredictStats, TetherError> {
    let mut stats = PredictStats::default();
    out.clone_from(a0);
    if a0.is_empty() {
        return Err(TetherError::EmptyHistory);
    }
    if !(crate::geom::is_finite3(x0) && crate::geom::is_finite3(x1)) {
        return Err(TetherError::InvalidInput);
    }
    let mut xn = *x0;
    for _ in 0..MAX_DETACH_ITERATIONS {
        let Some(ax) = out.pop() else {
            return Err(TetherError::EmptyHistory);
        };
        let detached = match out.last() {
            Some(prev) => is_detached(prev, &ax, x1).then_some(*prev),
            None => None, // the root anchor never detaches
        };
        match detached {
            Some(prev) => {
                let xn1 = detach_line(&prev, &ax, &xn, x1);
                // sweep about ax up to the detachment position; anchors found there keep ax
                let mut scratch = AnchorHistory::default();
                let n = attach_anchors(map, &xn, &xn1, &ax, &mut scratch, &mut stats)?;
                if n > 0 {
                    out.push(ax).map_err(|_| TetherError::HistoryFull)?;
                    for a in scratch.as_slice() {
                        out.push(*a).map_err(|_| TetherError::HistoryFull)?;
                    }
                } else {
                    stats.detached += 1;
                }
                xn = xn1;
            }
            None => {
                out.push(ax).map_err(|_| TetherError::HistoryFull)?;
                attach_anchors(map, &xn, x1, &ax, out, &mut stats)?;
                return Ok(stats);
            }
        }
    }
    Err(TetherError::BudgetExhausted)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A "step" terrain: solid where z < 0, or where x < 0 and z < 4 (a vertical cliff with a lip at x=0, z=4).
    struct Cliff;
    impl DistanceField for Cliff {
        fn query(&self, p: &Vec3) -> DistanceQuery {
            // exact SDF of the union of half-space z<0 and quadrant {x<0, z<4}
            let (x, z) = (p.x, p.z);
            let inside = z < 0.0 || (x < 0.0 && z < 4.0);
            let (d, g) = if inside {
                // distance to the boundary
                let dz0 = z; // to z=0 plane (only where x>0 matters) ...
                let cands = [
                    (if x > 0.0 { dz0 } else { Real::INFINITY }, Vec3::z()),
                    (if x < 0.0 { 4.0 - z } else { Real::INFINITY }, Vec3::z()),
                    (if z > 0.0 && z < 4.0 { -x } else { Real::INFINITY }, Vec3::x()),
                ];
                let mut best = (Real::INFINITY, Vec3::z());
                for c in cands {
                    if c.0 < best.0 {
                        best = c;
                    }
                }
                (-best.0, best.1)
            } else if x >= 0.0 && z >= 4.0 {
                let v = Vec3::new(x, 0.0, z - 4.0);
                let n = crate::geom::norm3(&v);
                (n, if n > 1e-9 { v / n } else { Vec3::new(core::f32::consts::FRAC_1_SQRT_2, 0.0, core::f32::consts::FRAC_1_SQRT_2) })
            } else if x >= 0.0 {
                // right of the cliff, below the lip: nearest is the wall or the ground
                if x < z { (x, Vec3::x()) } else { (z, Vec3::z()) }
            } else {
                (z - 4.0, Vec3::z())
            };
            DistanceQuery::Known { distance: d, gradient: g }
        }
    }

    #[test]
    fn tether_attaches_on_the_lip_and_detaches_when_the_rover_climbs_back() {
        let root = Anchor::root(Vec3::new(-5.0, 0.0, 6.0));
        let a0 = AnchorHistory::new(root);
        let mut a1 = AnchorHistory::default();
        // rover on the ground at x=2 moving to x=1 (under the line from root over the lip)
        let x0 = Vec3::new(3.0, 0.0, 4.5);
        let x1 = Vec3::new(1.0, 0.0, 0.5);
        let stats = predict_anchors(&Cliff, &a0, &x0, &x1, &mut a1).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(a1.len(), 2, "{a1:?} {stats:?}");
        let lip = a1.last().map(|a| a.point).unwrap_or_default();
        assert!((lip - Vec3::new(0.0, 0.0, 4.0)).norm() < 0.02, "lip anchor {lip:?}");
        // moving back up and out over the lip line detaches it
        let mut a2 = AnchorHistory::default();
        predict_anchors(&Cliff, &a1, &x1, &x0, &mut a2).unwrap_or_else(|e| panic!("{e:?}"));
        assert_eq!(a2.len(), 1, "{a2:?}");
    }

    /// The cliff, declaring what it is: an exact signed distance field (1-Lipschitz, known everywhere).
    struct LipschitzCliff;
    impl DistanceField for LipschitzCliff {
        fn query(&self, p: &Vec3) -> DistanceQuery {
            Cliff.query(p)
        }
        fn lipschitz_bound(&self) -> Option<Real> {
            Some(1.0)
        }
    }

    #[test]
    fn a_lipschitz_field_gives_the_same_anchors_with_fewer_queries() {
        // motions over the lip, along the top, down the wall and back, from roots behind and above the cliff
        let roots = [Vec3::new(-5.0, 0.0, 6.0), Vec3::new(-2.0, 1.0, 9.0), Vec3::new(-8.0, -2.0, 4.5)];
        let ends = [
            Vec3::new(3.0, 0.0, 4.5),
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(0.5, 1.5, 0.5),
            Vec3::new(6.0, -1.0, 0.5),
            Vec3::new(-1.0, 0.0, 4.5),
            Vec3::new(2.0, 2.0, 3.0),
        ];
        let (mut attached, mut fewer) = (0, 0);
        for root in roots {
            let (mut plain, mut bounded) = (AnchorHistory::new(Anchor::root(root)), AnchorHistory::new(Anchor::root(root)));
            for w in ends.windows(2) {
                let (x0, x1) = (w[0], w[1]);
                let (mut a, mut b) = (AnchorHistory::default(), AnchorHistory::default());
                let ra = predict_anchors(&Cliff, &plain, &x0, &x1, &mut a);
                let rb = predict_anchors(&LipschitzCliff, &bounded, &x0, &x1, &mut b);
                match (ra, rb) {
                    (Ok(sa), Ok(sb)) => {
                        assert_eq!((sa.attached, sa.detached), (sb.attached, sb.detached), "{root:?} {x0:?} -> {x1:?}");
                        assert!(sb.queries <= sa.queries);
                        attached += sa.attached;
                        fewer += u32::from(sb.queries < sa.queries);
                    }
                    (ra, rb) => assert_eq!(ra.err(), rb.err(), "{root:?} {x0:?} -> {x1:?}"),
                }
                assert_eq!(a.as_slice(), b.as_slice(), "{root:?} {x0:?} -> {x1:?}");
                (plain, bounded) = (a, b);
            }
        }
        assert!(attached > 0 && fewer > 0, "attached {attached}, fewer queries in {fewer} motions");
    }

    /// The cliff as the onboard map sees it: 0.2 m voxels over x in [-2, 4), y in [-1.2, 1.2), z in [-1, 6), the
    /// voxels beyond x = `known_x` unobserved.
    fn cliff_map<'a>(blocks: &'a mut [crate::map::Block], index: &'a mut [u32], known_x: Real) -> crate::map::Map<'a> {
        let cfg = crate::config::map::MapConfig::with_voxel_size(0.2);
        crate::map::map_of_field(&Cliff, cfg, (blocks, index), ([-10, -6, -5], [20, 6, 30]), |c| c.x <= known_x)
    }

    /// A field that hides its cells (`DistanceField::cell_key`): every sample is queried.
    struct NoCells<'a, D>(&'a D);
    impl<D: DistanceField> DistanceField for NoCells<'_, D> {
        fn query(&self, p: &Vec3) -> DistanceQuery {
            self.0.query(p)
        }
    }

    /// The onboard map's cell bounds skip sweep-line samples (`SweepMemo::cells`): the same anchors (and the same
    /// errors in unknown space) as querying every sample, with fewer queries; so also through `UnobservedAsFree`
    /// on a map that has not seen all of the sweep.
    #[test]
    fn the_maps_cell_bounds_give_the_same_anchors_with_fewer_queries() {
        let ends = [
            Vec3::new(3.0, 0.0, 4.5),
            Vec3::new(1.0, 0.0, 0.5),
            Vec3::new(0.5, 0.6, 0.5),
            Vec3::new(2.8, -0.5, 0.5),
            Vec3::new(-1.0, 0.0, 4.5),
            Vec3::new(2.0, 0.6, 3.0),
        ];
        let (mut attached, mut fewer, mut motions) = (0, 0, 0);
        for known_x in [4.0 as Real, 2.0] {
            let (mut blocks, mut index) = (std::vec![crate::map::Block::EMPTY; 1024], std::vec![0u32; 2048]);
            let map = cliff_map(&mut blocks, &mut index, known_x);
            let free = crate::map::UnobservedAsFree(&map);
            let free_plain = crate::map::UnobservedAsFree(&NoCells(&map));
            for root in [Vec3::new(-1.5, 0.0, 5.5), Vec3::new(-1.0, 0.8, 5.8)] {
                let mut h = [AnchorHistory::new(Anchor::root(root)), AnchorHistory::new(Anchor::root(root))];
                let mut hf = h.clone();
                for w in ends.windows(2) {
                    let (x0, x1) = (w[0], w[1]);
                    let mut out: [AnchorHistory; 4] = Default::default();
                    let [o0, o1, o2, o3] = &mut out;
                    let results = [
                        (
                            predict_anchors(&NoCells(&map), &h[0], &x0, &x1, o0),
                            predict_anchors(&map, &h[1], &x0, &x1, o1),
                        ),
                        (
                            predict_anchors(&free_plain, &hf[0], &x0, &x1, o2),
                            predict_anchors(&free, &hf[1], &x0, &x1, o3),
                        ),
                    ];
                    let mut ok = [false; 2];
                    for ((ra, rb), ok) in results.into_iter().zip(ok.iter_mut()) {
                        motions += 1;
                        match (ra, rb) {
                            (Ok(sa), Ok(sb)) => {
                                let at = (x0, x1);
                                assert_eq!((sa.attached, sa.detached), (sb.attached, sb.detached), "{at:?}");
                                assert!(sb.queries <= sa.queries);
                                attached += sa.attached;
                                fewer += u32::from(sb.queries < sa.queries);
                                *ok = true;
                            }
                            (ra, rb) => assert_eq!(ra.err(), rb.err(), "{root:?} {x0:?} -> {x1:?}"),
                        }
                    }
                    assert_eq!(out[0].as_slice(), out[1].as_slice(), "{known_x} {root:?} {x0:?} -> {x1:?}");
                    assert_eq!(out[2].as_slice(), out[3].as_slice(), "{known_x} {root:?} {x0:?} -> {x1:?}");
                    // after an error the next motion starts from the history before it
                    let [o0, o1, o2, o3] = out;
                    if ok[0] {
                        h = [o0, o1];
                    }
                    if ok[1] {
                        hf = [o2, o3];
                    }
                }
            }
        }
        std::eprintln!("{motions} motions, {attached} anchors attached, fewer queries in {fewer}");
        assert!(attached > 0 && fewer * 2 > motions, "attached {attached}, fewer queries in {fewer} of {motions}");
    }

    /// The cliff, but nobody has observed the space above x > 2.
    struct HalfKnown;
    impl DistanceField for HalfKnown {
        fn query(&self, p: &Vec3) -> DistanceQuery {
            if p.x > 2.0 {
                DistanceQuery::Unknown
            } else {
                Cliff.query(p)
            }
        }
    }

    #[test]
    fn unknown_space_in_the_sweep_is_an_error() {
        let a0 = AnchorHistory::new(Anchor::root(Vec3::new(-5.0, 0.0, 6.0)));
        let mut out = AnchorHistory::default();
        let r = predict_anchors(&HalfKnown, &a0, &Vec3::new(1.0, 0.0, 4.5), &Vec3::new(3.0, 0.0, 4.5), &mut out);
        assert_eq!(r, Err(TetherError::UnknownSpace));
    }

    #[test]
    fn full_history_is_a_typed_error() {
        let mut h = AnchorHistory::new(Anchor::root(Vec3::zeros()));
        for _ in 1..ANCHOR_HISTORY_CAPACITY {
            assert!(h.push(Anchor::root(Vec3::x())).is_ok());
        }
        assert!(h.push(Anchor::root(Vec3::y())).is_err());
        let mut out = AnchorHistory::default();
        assert_eq!(
            predict_anchors(&Cliff, &AnchorHistory::default(), &Vec3::zeros(), &Vec3::x(), &mut out),
            Err(TetherError::EmptyHistory)
        );
    }
}
