//! L-values: homotopy invariants of paths from the Cauchy integral (Tanner et al. II-B, after Bhattacharya et al.).
//!
//! `L(tau) = integral over tau of f0(z) / ((z - zeta_1) ... (z - zeta_N)) dz`, one pole `zeta_i` per obstacle
//! (its representative point [`super::btm::Obstacle::rep`]). By partial fractions the integrand is
//! `sum_i r_i / (z - zeta_i)` with residues `r_i = f0(zeta_i) / prod_{j != i}(zeta_i - zeta_j)`. With `f0 = 1`
//! the residues span hundreds of orders of magnitude for a few dozen obstacles, so we use the freedom the theorem
//! gives (any analytic `f0`): `f0` is the interpolating polynomial that makes the residues `r_i = w_i`, fixed
//! unit-scale complex weights per obstacle slot (golden-ratio angles, radii in [1, 1.5)). Then
//! `L(tau) = sum_i w_i (ln|b - zeta_i| - ln|a - zeta_i| + i * dtheta_i)` where `dtheta_i` is the continuously tracked
//! argument change around `zeta_i` (the complex logarithm with branch tracking: each straight segment adds its
//! principal angle in (-pi, pi], so crossing the branch cut never loses a turn).
//!
//! Two paths with the same end points have equal L-values iff they wind the same way around every pole, i.e. are
//! homotopic in the plane minus the obstacles; equality is tested with tolerance [`L_TOLERANCE`] (1e-6). Distinct
//! classes differ by `2 pi i sum_i k_i w_i` for integers `k_i`; with these weights such a sum is smaller than the
//! tolerance only for winding vectors the planner never builds (measure-zero coincidences). `f64` is needed: the
//! logarithms and accumulated angles of a 100-segment path lose the 1e-6 resolution in `f32`.

use super::btm::Btm;
use super::geo::Pt;

/// Equality tolerance for L-values (absolute). Default 1e-6.
pub const L_TOLERANCE: f64 = 1e-6;

/// A complex L-value.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LValue {
    /// Real part (depends only on the end points).
    pub re: f64,
    /// Imaginary part (carries the winding).
    pub im: f64,
}

impl LValue {
    /// Sum.
    pub fn plus(self, o: LValue) -> LValue {
        LValue { re: self.re + o.re, im: self.im + o.im }
    }
    /// Difference.
    pub fn minus(self, o: LValue) -> LValue {
        LValue { re: self.re - o.re, im: self.im - o.im }
    }
    /// Equal within [`L_TOLERANCE`].
    pub fn same_class(self, o: LValue) -> bool {
        let d = self.minus(o);
        libm::sqrt(d.re * d.re + d.im * d.im) <= L_TOLERANCE
    }
}

/// Residue weight `w_k` of obstacle slot `k`.
pub fn weight(k: u8) -> LValue {
    const GOLDEN: f64 = 0.618_033_988_749_894_8;
    const SQRT2_FRAC: f64 = 0.414_213_562_373_095_1;
    let kf = f64::from(k) + 1.0;
    let phi = 2.0 * core::f64::consts::PI * libm::fmod(kf * GOLDEN, 1.0);
    let r = 1.0 + 0.5 * libm::fmod(kf * SQRT2_FRAC, 1.0);
    LValue { re: r * libm::cos(phi), im: r * libm::sin(phi) }
}

/// `ln((b - zeta) / (a - zeta))` along the straight segment `a -> b` (principal angle: the segment turns by less
/// than pi around `zeta` unless it passes through it).
pub fn segment_log(a: Pt, b: Pt, zeta: Pt) -> LValue {
    let (u, v) = (a - zeta, b - zeta);
    let (nu, nv) = (u.norm(), v.norm());
    if nu <= 0.0 || nv <= 0.0 {
        return LValue::default();
    }
    LValue { re: libm::log(nv / nu), im: libm::atan2(u.cross(v), u.dot(v)) }
}

/// L-value of the straight segment `a -> b` with the BTM's obstacles as poles.
pub fn segment_lvalue(btm: &Btm, a: Pt, b: Pt) -> LValue {
    let mut l = LValue::default();
    for (k, o) in btm.obstacles() {
        let w = weight(k);
        let s = segment_log(a, b, o.rep);
        l = l.plus(LValue { re: w.re * s.re - w.im * s.im, im: w.re * s.im + w.im * s.re });
    }
    l
}

/// L-value of a polyline.
pub fn polyline_lvalue(btm: &Btm, pts: &[Pt]) -> LValue {
    pts.windows(2).fold(LValue::default(), |acc, w| match w {
        [a, b] => acc.plus(segment_lvalue(btm, *a, *b)),
        _ => acc,
    })
}
