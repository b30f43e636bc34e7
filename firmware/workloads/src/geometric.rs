//! Geometric planning problems in R^n with axis-aligned box obstacles: the shared benchmark problems of the
//! ABIT* side-by-side with OMPL (issue 6, "a wall with a narrow offset gap in R^2, R^4 and R^8 and a 3D box
//! world") and the planner's own tests (`firmware/workloads/tests/abit_geometric.rs`). Test problems, not flight
//! code: they implement `firmware::plan::space`'s traits from outside the flight crate.
//!
//! - [`RealVectorSpace`]: R^N in a box, Euclidean metric, linear interpolation, uniform sampling and the direct
//!   informed sampler of the prolate hyperspheroid (Gammell, Barfoot, Srinivasa, IROS 2014 / TPAMI 2018), with
//!   OMPL's rule: when the hyperspheroid is larger than the box, rejection-sample the box instead.
//! - [`BoxObstacles`]: state validity (inside the bounds, outside every box) and an exact motion validator
//!   (segment-box slab test, end states included) — no discretisation, so both planners of the comparison see
//!   exactly the same obstacles.
//! - [`GeometricProblem`]: start, goal, space, obstacles; [`wall_gap`] and [`box_world_3d`] build the shared
//!   problems; [`GeometricProblem::write_text`] writes the plain-text description read by the OMPL driver
//!   (`host-sim/bench-ref/ompl_abit.cpp`).

use heapless::Vec;
use rand_core::Rng;

use firmware::geom::unit_ball_measure;
use firmware::plan::space::{
    standard_normal, uniform01, InformedSample, MotionCheck, MotionValidator, StateSpace, StateValidityChecker,
};

/// Most boxes in one problem.
pub const MAX_BOXES: usize = 16;

/// R^N inside `[lo, hi]` (OMPL `RealVectorStateSpace` with bounds).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RealVectorSpace<const N: usize> {
    /// Lower bounds.
    pub lo: [f64; N],
    /// Upper bounds.
    pub hi: [f64; N],
}

impl<const N: usize> RealVectorSpace<N> {
    /// The box `[lo, hi]^N`.
    pub const fn cube(lo: f64, hi: f64) -> Self {
        Self { lo: [lo; N], hi: [hi; N] }
    }
    /// Is `x` inside the bounds (closed)?
    pub fn contains(&self, x: &[f64; N]) -> bool {
        x.iter().zip(self.lo.iter().zip(self.hi.iter())).all(|(v, (l, h))| *v >= *l && *v <= *h)
    }
}

impl<const N: usize> StateSpace for RealVectorSpace<N> {
    type State = [f64; N];
    type Attachment = ();

    fn dimension(&self) -> usize {
        N
    }
    fn measure(&self) -> f64 {
        self.lo.iter().zip(self.hi.iter()).map(|(l, h)| h - l).product()
    }
    fn distance(&self, a: &[f64; N], b: &[f64; N]) -> f64 {
        libm::sqrt(a.iter().zip(b.iter()).map(|(x, y)| (x - y) * (x - y)).sum())
    }
    fn interpolate(&self, a: &[f64; N], b: &[f64; N], t: f64) -> [f64; N] {
        let mut out = *a;
        for (o, (x, y)) in out.iter_mut().zip(a.iter().zip(b.iter())) {
            *o = x + (y - x) * t;
        }
        out
    }
    fn sample_uniform<R: Rng + ?Sized>(&mut self, rng: &mut R) -> Option<[f64; N]> {
        let mut out = [0.0; N];
        for (o, (l, h)) in out.iter_mut().zip(self.lo.iter().zip(self.hi.iter())) {
            *o = l + (h - l) * uniform01(rng);
        }
        Some(out)
    }
    fn sample_informed_path_length<R: Rng + ?Sized>(
        &mut self,
        rng: &mut R,
        start: &[f64; N],
        goal: &[f64; N],
        max_length: f64,
    ) -> InformedSample<[f64; N]> {
        let c_min = self.distance(start, goal);
        if !max_length.is_finite() {
            return match self.sample_uniform(rng) {
                Some(x) => InformedSample::Sampled(x),
                None => InformedSample::Rejected,
            };
        }
        if max_length <= c_min || c_min <= 0.0 {
            return InformedSample::Rejected;
        }
        let r1 = max_length / 2.0;
        let r_other = libm::sqrt(max_length * max_length - c_min * c_min) / 2.0;
        let phs_measure = unit_ball_measure(N) * r1 * libm::pow(r_other, N as f64 - 1.0);
        if phs_measure >= self.measure() {
            // OMPL's rule: the informed set is not smaller than the space; rejection-sample the space.
            let Some(x) = self.sample_uniform(rng) else {
                return InformedSample::Rejected;
            };
            return if self.distance(start, &x) + self.distance(&x, goal) <= max_length {
                InformedSample::Sampled(x)
            } else {
                InformedSample::Rejected
            };
        }
        // Uniform in the unit ball: a normalised Gaussian direction, radius u^(1/N).
        let mut ball = [0.0; N];
        let mut norm2 = 0.0;
        for b in ball.iter_mut() {
            *b = standard_normal(rng);
            norm2 += *b * *b;
        }
        if norm2 <= 0.0 {
            return InformedSample::Rejected;
        }
        let radius = libm::pow(uniform01(rng), 1.0 / N as f64) / libm::sqrt(norm2);
        // Scale to the hyperspheroid's axes (transverse axis first).
        for (i, b) in ball.iter_mut().enumerate() {
            *b *= radius * if i == 0 { r1 } else { r_other };
        }
        // Rotate e1 onto the start-goal direction with a Householder reflection H = I - 2 v v^T / (v^T v),
        // v = e1 - a1 (the other axes have equal radii, so a reflection is as good as a rotation).
        let mut v = [0.0; N];
        for (i, (vi, (s, g))) in v.iter_mut().zip(start.iter().zip(goal.iter())).enumerate() {
            *vi = if i == 0 { 1.0 } else { 0.0 } - (g - s) / c_min;
        }
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let mut out = ball;
        if vv > 1e-24 {
            let vb: f64 = v.iter().zip(ball.iter()).map(|(a, b)| a * b).sum();
            let f = 2.0 * vb / vv;
            for (o, vi) in out.iter_mut().zip(v.iter()) {
                *o -= f * vi;
            }
        }
        for (o, (s, g)) in out.iter_mut().zip(start.iter().zip(goal.iter())) {
            *o += (s + g) / 2.0;
        }
        if self.contains(&out) {
            InformedSample::Sampled(out)
        } else {
            InformedSample::Rejected
        }
    }
}

/// An axis-aligned box in R^N.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb<const N: usize> {
    /// Lower corner.
    pub lo: [f64; N],
    /// Upper corner.
    pub hi: [f64; N],
}

impl<const N: usize> Aabb<N> {
    /// Is `x` inside (closed box)?
    pub fn contains(&self, x: &[f64; N]) -> bool {
        x.iter().zip(self.lo.iter().zip(self.hi.iter())).all(|(v, (l, h))| *v >= *l && *v <= *h)
    }
    /// Does the closed segment `a -> b` touch the closed box (slab test)?
    pub fn intersects_segment(&self, a: &[f64; N], b: &[f64; N]) -> bool {
        let mut t_enter = 0.0_f64;
        let mut t_exit = 1.0_f64;
        for i in 0..N {
            let (Some(p), Some(q), Some(l), Some(h)) = (a.get(i), b.get(i), self.lo.get(i), self.hi.get(i)) else {
                return true;
            };
            let d = q - p;
            if d == 0.0 {
                if *p < *l || *p > *h {
                    return false;
                }
            } else {
                let t1 = (l - p) / d;
                let t2 = (h - p) / d;
                let (near, far) = if t1 < t2 { (t1, t2) } else { (t2, t1) };
                t_enter = t_enter.max(near);
                t_exit = t_exit.min(far);
                if t_enter > t_exit {
                    return false;
                }
            }
        }
        true
    }
}

/// Box obstacles: state validity and exact motion validation.
#[derive(Debug, Clone, PartialEq)]
pub struct BoxObstacles<const N: usize> {
    /// The bounds (states outside are invalid).
    pub bounds: RealVectorSpace<N>,
    /// The obstacles.
    pub boxes: Vec<Aabb<N>, MAX_BOXES>,
}

impl<const N: usize> StateValidityChecker<RealVectorSpace<N>> for BoxObstacles<N> {
    fn is_valid(&mut self, x: &[f64; N]) -> bool {
        self.bounds.contains(x) && !self.boxes.iter().any(|b| b.contains(x))
    }
}

impl<const N: usize> MotionValidator<RealVectorSpace<N>> for BoxObstacles<N> {
    fn check_motion(
        &mut self,
        _space: &RealVectorSpace<N>,
        from: &[f64; N],
        _: &(),
        to: &[f64; N],
    ) -> MotionCheck<()> {
        let inside = self.bounds.contains(from) && self.bounds.contains(to);
        if inside && !self.boxes.iter().any(|b| b.intersects_segment(from, to)) {
            MotionCheck::Valid { attachment: () }
        } else {
            MotionCheck::Invalid
        }
    }
}

/// A geometric benchmark problem.
#[derive(Debug, Clone, PartialEq)]
pub struct GeometricProblem<const N: usize> {
    /// Short name (used in tables and by the OMPL driver).
    pub name: &'static str,
    /// The space.
    pub space: RealVectorSpace<N>,
    /// The obstacles.
    pub obstacles: BoxObstacles<N>,
    /// Start.
    pub start: [f64; N],
    /// Goal (a single state).
    pub goal: [f64; N],
}

/// Wall thickness of [`wall_gap`].
pub const WALL_HALF_THICKNESS: f64 = 0.05;
/// Gap of [`wall_gap`]: `x1` in `[GAP_LO, GAP_HI]`, off the start-goal line (`x1 = 0`).
pub const GAP_LO: f64 = 0.30;
/// Upper edge of the gap.
pub const GAP_HI: f64 = 0.36;

/// A wall with a narrow offset gap in `[-1, 1]^N`: the wall is the slab `|x0| <= 0.05`, open only where
/// `x1` is in `[0.30, 0.36]` (6 % of the wall's extent in `x1`, off the start-goal line); start
/// `(-0.8, 0, ...)`, goal `(0.8, 0, ...)`. The optimum passes the gap's lower edge: cost
/// `2 sqrt(0.75^2 + 0.3^2) + 0.1 = 1.7155` (see [`wall_gap_optimal_cost`]). Needs `N >= 2`.
pub fn wall_gap<const N: usize>(name: &'static str) -> GeometricProblem<N> {
    let space = RealVectorSpace::<N>::cube(-1.0, 1.0);
    let mut below = Aabb { lo: [-1.5; N], hi: [1.5; N] };
    let mut above = below;
    if let (Some(l), Some(h)) = (below.lo.get_mut(0), below.hi.get_mut(0)) {
        *l = -WALL_HALF_THICKNESS;
        *h = WALL_HALF_THICKNESS;
    }
    if let (Some(l), Some(h)) = (above.lo.get_mut(0), above.hi.get_mut(0)) {
        *l = -WALL_HALF_THICKNESS;
        *h = WALL_HALF_THICKNESS;
    }
    if let Some(h) = below.hi.get_mut(1) {
        *h = GAP_LO;
    }
    if let Some(l) = above.lo.get_mut(1) {
        *l = GAP_HI;
    }
    let mut boxes = Vec::new();
    // Capacity 16 >= 2: cannot fail.
    let _ = boxes.push(below);
    let _ = boxes.push(above);
    let mut start = [0.0; N];
    let mut goal = [0.0; N];
    if let (Some(s), Some(g)) = (start.get_mut(0), goal.get_mut(0)) {
        *s = -0.8;
        *g = 0.8;
    }
    GeometricProblem { name, space, obstacles: BoxObstacles { bounds: space, boxes }, start, goal }
}

/// Optimal cost of [`wall_gap`] (analytic: two straight segments to the gap's lower corners plus the crossing).
pub fn wall_gap_optimal_cost() -> f64 {
    let leg = libm::sqrt((0.8 - WALL_HALF_THICKNESS) * (0.8 - WALL_HALF_THICKNESS) + GAP_LO * GAP_LO);
    2.0 * leg + 2.0 * WALL_HALF_THICKNESS
}

/// A 3D box world in `[0, 10]^3`: seven boxes that block the straight line and force detours around and over
/// them; start `(1, 1, 1)`, goal `(9, 9, 9)`.
pub fn box_world_3d() -> GeometricProblem<3> {
    let space = RealVectorSpace::<3>::cube(0.0, 10.0);
    let list: [([f64; 3], [f64; 3]); 7] = [
        ([2.0, 0.0, 0.0], [3.0, 7.0, 10.0]),
        ([5.0, 3.0, 0.0], [6.0, 10.0, 10.0]),
        ([7.5, 0.0, 0.0], [8.5, 6.0, 6.0]),
        ([3.0, 6.0, 0.0], [5.0, 7.0, 6.0]),
        ([6.0, 6.5, 6.5], [10.0, 7.5, 7.5]),
        ([0.0, 3.0, 3.0], [2.0, 4.0, 10.0]),
        ([3.5, 1.0, 4.0], [4.5, 4.0, 10.0]),
    ];
    let mut boxes = Vec::new();
    for (lo, hi) in list {
        let _ = boxes.push(Aabb { lo, hi });
    }
    GeometricProblem {
        name: "box3d",
        space,
        obstacles: BoxObstacles { bounds: space, boxes },
        start: [1.0, 1.0, 1.0],
        goal: [9.0, 9.0, 9.0],
    }
}

impl<const N: usize> GeometricProblem<N> {
    /// Write the plain-text description read by the OMPL driver:
    /// `name NAME`, `dim N`, `lo ...`, `hi ...`, `start ...`, `goal ...`, then one `box lo... hi...` per box.
    pub fn write_text<W: core::fmt::Write>(&self, w: &mut W) -> core::fmt::Result {
        writeln!(w, "name {}", self.name)?;
        writeln!(w, "dim {N}")?;
        let row = |w: &mut W, tag: &str, v: &[f64]| -> core::fmt::Result {
            write!(w, "{tag}")?;
            for x in v {
                write!(w, " {x:?}")?;
            }
            writeln!(w)
        };
        row(w, "lo", &self.space.lo)?;
        row(w, "hi", &self.space.hi)?;
        row(w, "start", &self.start)?;
        row(w, "goal", &self.goal)?;
        for b in &self.obstacles.boxes {
            write!(w, "box")?;
            for x in b.lo.iter().chain(b.hi.iter()) {
                write!(w, " {x:?}")?;
            }
            writeln!(w)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_core::SeedableRng;

    #[test]
    fn slab_test_matches_dense_sampling_of_the_segment() {
        let b = Aabb { lo: [0.0, 0.0], hi: [1.0, 1.0] };
        let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
        for _ in 0..2000 {
            let a = [uniform01(&mut rng) * 4.0 - 1.5, uniform01(&mut rng) * 4.0 - 1.5];
            let c = [uniform01(&mut rng) * 4.0 - 1.5, uniform01(&mut rng) * 4.0 - 1.5];
            let dense = (0..=20000).any(|i| {
                let t = i as f64 / 20000.0;
                b.contains(&[a[0] + (c[0] - a[0]) * t, a[1] + (c[1] - a[1]) * t])
            });
            // Dense sampling can only miss grazing hits; never report a hit the slab test denies.
            if dense {
                assert!(b.intersects_segment(&a, &c), "{a:?} {c:?}");
            }
        }
    }

    #[test]
    fn informed_samples_lie_in_the_hyperspheroid_and_fill_it() {
        let mut space = RealVectorSpace::<4>::cube(-10.0, 10.0);
        let s = [-1.0, 0.5, 0.0, 0.0];
        let g = [1.0, -0.5, 0.3, 0.0];
        let c_min = space.distance(&s, &g);
        let c_max = 1.3 * c_min;
        let mut rng = rand_pcg::Pcg64::seed_from_u64(9);
        let mut inner = 0usize;
        let mut n = 0usize;
        for _ in 0..20000 {
            if let InformedSample::Sampled(x) = space.sample_informed_path_length(&mut rng, &s, &g, c_max) {
                let f = space.distance(&s, &x) + space.distance(&x, &g);
                assert!(f <= c_max * (1.0 + 1e-9));
                n += 1;
                // The PHS of cost c_mid holds (r(c_mid)/r(c_max)) measure fraction; check uniformity coarsely.
                let c_mid = 1.15 * c_min;
                if f <= c_mid {
                    inner += 1;
                }
            }
        }
        assert_eq!(n, 20000, "bounds are far: no rejection expected");
        // Analytic fraction: r1 * r_other^3 ratio.
        let r = |c: f64| (c / 2.0) * libm::pow(libm::sqrt(c * c - c_min * c_min) / 2.0, 3.0);
        let expected = r(1.15 * c_min) / r(c_max);
        let got = inner as f64 / n as f64;
        assert!((got - expected).abs() < 0.02, "fraction {got} vs analytic {expected}");
    }

    #[test]
    fn wall_gap_optimum_is_the_gap_corner_path() {
        let p = wall_gap::<2>("w2");
        let mut o = p.obstacles.clone();
        let c1 = [-WALL_HALF_THICKNESS - 1e-9, GAP_LO + 1e-9];
        let c2 = [WALL_HALF_THICKNESS + 1e-9, GAP_LO + 1e-9];
        let space = p.space;
        assert!(matches!(o.check_motion(&space, &p.start, &(), &c1), MotionCheck::Valid { .. }));
        assert!(matches!(o.check_motion(&space, &c1, &(), &c2), MotionCheck::Valid { .. }));
        assert!(matches!(o.check_motion(&space, &c2, &(), &p.goal), MotionCheck::Valid { .. }));
        assert!(matches!(o.check_motion(&space, &p.start, &(), &p.goal), MotionCheck::Invalid));
        let len = space.distance(&p.start, &c1) + space.distance(&c1, &c2) + space.distance(&c2, &p.goal);
        assert!((len - wall_gap_optimal_cost()).abs() < 1e-6);
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        #[test]
        fn informed_samples_respect_bound_and_bounds(
            s in proptest::array::uniform3(-1.0f64..1.0),
            g in proptest::array::uniform3(-1.0f64..1.0),
            slack in 1.0001f64..3.0,
            seed in 0u64..1000,
        ) {
            let mut space = RealVectorSpace::<3>::cube(-1.0, 1.0);
            let c_min = space.distance(&s, &g);
            proptest::prop_assume!(c_min > 1e-3);
            let c_max = slack * c_min;
            let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
            for _ in 0..50 {
                if let InformedSample::Sampled(x) = space.sample_informed_path_length(&mut rng, &s, &g, c_max) {
                    proptest::prop_assert!(space.contains(&x));
                    proptest::prop_assert!(space.distance(&s, &x) + space.distance(&x, &g) <= c_max * (1.0 + 1e-9));
                }
            }
        }

        #[test]
        fn metric_laws(
            a in proptest::array::uniform4(-5.0f64..5.0),
            b in proptest::array::uniform4(-5.0f64..5.0),
            c in proptest::array::uniform4(-5.0f64..5.0),
            t in 0.0f64..1.0,
        ) {
            let space = RealVectorSpace::<4>::cube(-5.0, 5.0);
            proptest::prop_assert_eq!(space.distance(&a, &b), space.distance(&b, &a));
            proptest::prop_assert!(space.distance(&a, &c) <= space.distance(&a, &b) + space.distance(&b, &c) + 1e-12);
            let m = space.interpolate(&a, &b, t);
            let d = space.distance(&a, &m) + space.distance(&m, &b) - space.distance(&a, &b);
            proptest::prop_assert!(d.abs() < 1e-9);
            proptest::prop_assert_eq!(space.interpolate(&a, &b, 0.0), a);
        }
    }
}
