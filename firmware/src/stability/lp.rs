//! A dense, fixed-size linear-program solver for the flight core: Mehrotra predictor-corrector primal-dual interior
//! point method (Wright, *Primal-Dual Interior-Point Methods*, SIAM 1997, ch. 10; Vandenberghe, *The CVXOPT
//! linear and quadratic cone program solvers*, 2010, section 3 for the reduced KKT system).
//!
//! Problem: minimise `c'x` subject to `A x = b` (`P` rows) and `G x <= h` (`M` rows), `x` in R^`N`.
//! All sizes are const generics, all storage is on the stack (nalgebra `SMatrix`, `f64`), no heap.
//!
//! Each iteration eliminates the slacks and duals of the inequalities and solves the normal equations
//! `H = G' W G` (`W = diag(z / s)`) by Cholesky and the `P x P` Schur complement `A H^-1 A'` by Cholesky.
//! A variable that no constraint mentions (a zero column of `A` and `G`, e.g. an unused contact slot) and an
//! equation row that is identically zero (`0 = 0`) are pinned by a unit diagonal, so callers can leave slots of the
//! fixed-size problem unused. The method starts from an infeasible point (`x = 0`, `s = max(h - Gx, 1)`, `z = 1`).
//!
//! Iterates are scored by a merit (the largest relative residual or gap); if round-off makes the merit grow
//! 10^4-fold past its best, or the budget ends, the best iterate is returned, as [`LpStatus::AlmostOptimal`] when
//! its merit is below `100 tol`.
//!
//! It does not detect infeasibility or unboundedness by certificate: a problem that does not converge within the
//! iteration budget returns [`LpStatus::BudgetExhausted`], and a failed factorisation or a non-finite iterate
//! returns [`LpStatus::NumericalFailure`]. Callers treat both as "unknown" (unsafe).
//!
//! Convergence: primal residuals and the complementarity gap `s'z` below `tol` (relative), dual residual below `1000 tol`.
//!
//! Parameters: `max_iterations` (budget, see `config::stability::SOLVER_MAX_ITERATIONS`, default 50) and `tol`
//! (relative residual and gap tolerance, `config::stability::SOLVER_TOLERANCE`, default 1e-9).

use nalgebra::{Cholesky, SMatrix, SVector};

/// A linear program in fixed-size dense storage: minimise `c'x` s.t. `A x = b`, `G x <= h`.
#[derive(Debug, Clone, PartialEq)]
pub struct LinearProgram<const N: usize, const P: usize, const M: usize> {
    /// Objective.
    pub c: SVector<f64, N>,
    /// Equality matrix.
    pub a: SMatrix<f64, P, N>,
    /// Equality right-hand side.
    pub b: SVector<f64, P>,
    /// Inequality matrix.
    pub g: SMatrix<f64, M, N>,
    /// Inequality right-hand side.
    pub h: SVector<f64, M>,
}

/// How an LP solve ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum LpStatus {
    /// Converged: residuals and duality gap below tolerance.
    Optimal,
    /// The iterates stopped improving (or began to diverge from round-off) after reaching residuals and gap below
    /// `ALMOST_FACTOR * tol`; the best iterate is returned.
    AlmostOptimal,
    /// The iteration budget ran out before convergence (the last iterate is returned).
    BudgetExhausted,
    /// A factorisation failed or an iterate became non-finite.
    NumericalFailure,
}

/// The result of an LP solve.
#[derive(Debug, Clone, PartialEq)]
pub struct LpSolution<const N: usize> {
    /// How the solve ended.
    pub status: LpStatus,
    /// Last primal iterate.
    pub x: SVector<f64, N>,
    /// `c'x` at the last iterate.
    pub objective: f64,
    /// Iterations used.
    pub iterations: u32,
}

/// The dual residual is accepted at `DUAL_TOL_FACTOR * tol`: the normal-equations elimination loses a few digits
/// of the dual residual once `z / s` spans many orders of magnitude (measured stalls at 4e-9 to 1.5e-8 with `tol = 1e-9`).
const DUAL_TOL_FACTOR: f64 = 1000.0;

/// Accuracy accepted as [`LpStatus::AlmostOptimal`], as a multiple of `tol`.
pub const ALMOST_FACTOR: f64 = 100.0;

fn add_diag<const K: usize>(m: &mut SMatrix<f64, K, K>, i: usize, v: f64) {
    if let Some(e) = m.get_mut((i, i)) {
        *e += v;
    }
}

fn inf_norm<const K: usize>(v: &SVector<f64, K>) -> f64 {
    v.iter().fold(0.0, |m, x| if x.abs() > m { x.abs() } else { m })
}

fn max_step<const K: usize>(v: &SVector<f64, K>, dv: &SVector<f64, K>) -> f64 {
    let mut a: f64 = 1.0;
    for (vi, di) in v.iter().zip(dv.iter()) {
        if *di < 0.0 {
            let t = -vi / di;
            if t < a {
                a = t;
            }
        }
    }
    a
}

type Step<const N: usize, const P: usize, const M: usize> =
    (SVector<f64, N>, SVector<f64, P>, SVector<f64, M>, SVector<f64, M>);

struct Kkt<const N: usize, const P: usize> {
    h: Cholesky<f64, nalgebra::Const<N>>,
    v: SMatrix<f64, N, P>,
    schur: Cholesky<f64, nalgebra::Const<P>>,
}

impl<const N: usize, const P: usize, const M: usize> LinearProgram<N, P, M> {
    /// An all-zero problem (fill in the fields).
    pub fn zeros() -> Self {
        LinearProgram {
            c: SVector::zeros(),
            a: SMatrix::zeros(),
            b: SVector::zeros(),
            g: SMatrix::zeros(),
            h: SVector::zeros(),
        }
    }

    fn factor(&self, w: &SVector<f64, M>) -> Option<Kkt<N, P>> {
        // H = G' W G assembled row by row from the nonzeros of G (the stability LP has at most a few per row)
        let mut hm = SMatrix::<f64, N, N>::zeros();
        for (row, wi) in self.g.row_iter().zip(w.iter()) {
            let mut nz = [(0usize, 0.0f64); N];
            let mut k = 0;
            for (j, v) in row.iter().enumerate() {
                if *v != 0.0 {
                    if let Some(e) = nz.get_mut(k) {
                        *e = (j, *v);
                    }
                    k += 1;
                }
            }
            let nz = nz.get(..k).unwrap_or(&[]);
            for (a, va) in nz {
                for (b, vb) in nz {
                    if let Some(e) = hm.get_mut((*a, *b)) {
                        *e += wi * va * vb;
                    }
                }
            }
        }
        let scale = hm.diagonal().iter().fold(1.0f64, |m, x| m.max(x.abs()));
        let mut used = [false; N];
        for (j, u) in used.iter_mut().enumerate() {
            *u = self.g.column(j).iter().any(|x| *x != 0.0) || self.a.column(j).iter().any(|x| *x != 0.0);
            if !*u {
                add_diag(&mut hm, j, 1.0);
            }
        }
        // Unregularised first (exact Newton steps); a tiny diagonal only if that factorisation fails.
        let h = match Cholesky::new(hm) {
            Some(h) => h,
            None => {
                for (j, u) in used.iter().enumerate() {
                    if *u {
                        add_diag(&mut hm, j, 1e-12 * scale);
                    }
                }
                Cholesky::new(hm)?
            }
        };
        let v = h.solve(&self.a.transpose());
        let mut s = self.a * v;
        let sscale = s.diagonal().iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for i in 0..P {
            let zero_row = self.a.row(i).iter().all(|x| *x == 0.0);
            if zero_row {
                add_diag(&mut s, i, 1.0);
            }
        }
        let schur = match Cholesky::new(s) {
            Some(c) => c,
            None => {
                for i in 0..P {
                    add_diag(&mut s, i, 1e-13 * sscale);
                }
                Cholesky::new(s)?
            }
        };
        Some(Kkt { h, v, schur })
    }

    #[allow(clippy::too_many_arguments)]
    fn direction_once(
        &self,
        kkt: &Kkt<N, P>,
        w: &SVector<f64, M>,
        s: &SVector<f64, M>,
        z: &SVector<f64, M>,
        r_d: &SVector<f64, N>,
        r_p: &SVector<f64, P>,
        r_g: &SVector<f64, M>,
        r_c: &SVector<f64, M>,
    ) -> Step<N, P, M> {
        let t = w.component_mul(r_g) - r_c.component_div(s);
        let q = -r_d - self.g.tr_mul(&t);
        let u = kkt.h.solve(&q);
        let dy = kkt.schur.solve(&(self.a * u + r_p));
        let dx = u - kkt.v * dy;
        let dz = w.component_mul(&(self.g * dx + r_g)) - r_c.component_div(s);
        let ds = (-r_c - s.component_mul(&dz)).component_div(z);
        (dx, dy, dz, ds)
    }

    /// Newton direction with one step of iterative refinement on the full (unreduced) system: the reduced
    /// normal equations lose digits once `z / s` spans many orders of magnitude.
    #[allow(clippy::too_many_arguments)]
    fn direction(
        &self,
        kkt: &Kkt<N, P>,
        w: &SVector<f64, M>,
        s: &SVector<f64, M>,
        z: &SVector<f64, M>,
        r_d: &SVector<f64, N>,
        r_p: &SVector<f64, P>,
        r_g: &SVector<f64, M>,
        r_c: &SVector<f64, M>,
    ) -> Step<N, P, M> {
        let (dx, dy, dz, ds) = self.direction_once(kkt, w, s, z, r_d, r_p, r_g, r_c);
        // residuals of: A'dy + G'dz = -r_d; A dx = -r_p; G dx + ds = -r_g; Z ds + S dz = -r_c
        let e1 = r_d + self.a.tr_mul(&dy) + self.g.tr_mul(&dz);
        let e2 = r_p + self.a * dx;
        let e3 = r_g + self.g * dx + ds;
        let e4 = r_c + z.component_mul(&ds) + s.component_mul(&dz);
        let (cx, cy, cz, cs) = self.direction_once(kkt, w, s, z, &e1, &e2, &e3, &e4);
        (dx + cx, dy + cy, dz + cz, ds + cs)
    }

    /// Solve with at most `max_iterations` interior-point iterations to relative tolerance `tol`.
    pub fn solve(&self, max_iterations: u32, tol: f64) -> LpSolution<N> {
        let mut x = SVector::<f64, N>::zeros();
        let mut y = SVector::<f64, P>::zeros();
        let mut s = (self.h - self.g * x).map(|v| if v > 1.0 { v } else { 1.0 });
        let mut z = SVector::<f64, M>::repeat(1.0);
        let bn = 1.0 + inf_norm(&self.b);
        let cn = 1.0 + inf_norm(&self.c);
        let hn = 1.0 + inf_norm(&self.h);
        let mut it = 0;
        let mut best_x = x;
        let mut best_merit = f64::INFINITY;
        let end = |x: SVector<f64, N>, merit: f64, it: u32, otherwise: LpStatus| {
            let status = if merit <= ALMOST_FACTOR * tol { LpStatus::AlmostOptimal } else { otherwise };
            LpSolution { status, objective: self.c.dot(&x), x, iterations: it }
        };
        loop {
            let r_d = self.c + self.a.tr_mul(&y) + self.g.tr_mul(&z);
            let r_p = self.a * x - self.b;
            let r_g = self.g * x + s - self.h;
            let mu = s.dot(&z) / (M.max(1) as f64);
            let pobj = self.c.dot(&x);
            let merit = (inf_norm(&r_p) / bn)
                .max(inf_norm(&r_g) / hn)
                .max(inf_norm(&r_d) / (DUAL_TOL_FACTOR * cn))
                .max(s.dot(&z) / (1.0 + pobj.abs()));
            if !merit.is_finite() {
                return end(best_x, best_merit, it, LpStatus::NumericalFailure);
            }
            if merit <= tol {
                return LpSolution { status: LpStatus::Optimal, objective: pobj, x, iterations: it };
            }
            if merit < best_merit {
                best_merit = merit;
                best_x = x;
            } else if merit > 1e4 * best_merit {
                // round-off has taken over: stop with the best iterate
                return end(best_x, best_merit, it, LpStatus::NumericalFailure);
            }
            if it >= max_iterations {
                return end(best_x, best_merit, it, LpStatus::BudgetExhausted);
            }
            it += 1;
            let w = z.component_div(&s);
            let Some(kkt) = self.factor(&w) else {
                return end(best_x, best_merit, it, LpStatus::NumericalFailure);
            };
            // predictor (affine scaling)
            let r_c = s.component_mul(&z);
            let (_, _, dz_a, ds_a) = self.direction(&kkt, &w, &s, &z, &r_d, &r_p, &r_g, &r_c);
            let ap = max_step(&s, &ds_a);
            let ad = max_step(&z, &dz_a);
            let mu_aff = (s + ds_a * ap).dot(&(z + dz_a * ad)) / (M.max(1) as f64);
            let ratio = mu_aff / mu;
            let sigma = (ratio * ratio * ratio).clamp(0.0, 1.0);
            // corrector
            let r_c = s.component_mul(&z) + ds_a.component_mul(&dz_a) - SVector::<f64, M>::repeat(sigma * mu);
            let (dx, dy, dz, ds) = self.direction(&kkt, &w, &s, &z, &r_d, &r_p, &r_g, &r_c);
            let ap = (0.99 * max_step(&s, &ds)).min(1.0);
            let ad = (0.99 * max_step(&z, &dz)).min(1.0);
            x += dx * ap;
            s += ds * ap;
            y += dy * ad;
            z += dz * ad;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn small_lp_with_known_optimum() {
        // min -x0 - x1  s.t. x0 + x1 + x2 = 2 (x2 free but x2 >= 0.5), x0 <= 1, x1 <= 1, x >= 0
        let mut lp = LinearProgram::<3, 1, 6>::zeros();
        lp.c = SVector::from([-1.0, -1.0, 0.0]);
        lp.a = SMatrix::from_row_slice(&[1.0, 1.0, 1.0]);
        lp.b = SVector::from([2.0]);
        lp.g = SMatrix::from_row_slice(&[
            1.0, 0.0, 0.0, //
            0.0, 1.0, 0.0, //
            -1.0, 0.0, 0.0, //
            0.0, -1.0, 0.0, //
            0.0, 0.0, -1.0, //
            0.0, 0.0, 0.0,
        ]);
        lp.h = SVector::from([1.0, 1.0, 0.0, 0.0, -0.5, 1.0]);
        let sol = lp.solve(50, 1e-10);
        assert_eq!(sol.status, LpStatus::Optimal);
        assert!((sol.objective + 1.5).abs() < 1e-8, "{}", sol.objective);
        assert!((sol.x[2] - 0.5).abs() < 1e-7);
    }

    #[test]
    fn budget_exhaustion_is_reported() {
        let mut lp = LinearProgram::<2, 1, 2>::zeros();
        lp.c = SVector::from([1.0, 1.0]);
        lp.a = SMatrix::from_row_slice(&[1.0, -1.0]);
        lp.b = SVector::from([0.3]);
        lp.g = SMatrix::from_row_slice(&[-1.0, 0.0, 0.0, -1.0]);
        let sol = lp.solve(1, 1e-10);
        assert_eq!(sol.status, LpStatus::BudgetExhausted);
        let sol = lp.solve(50, 1e-10);
        assert_eq!(sol.status, LpStatus::Optimal);
        assert!((sol.objective - 0.3).abs() < 1e-8);
    }
}
