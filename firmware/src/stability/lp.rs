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

fn at<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>, i: usize, j: usize) -> f64 {
    m.get((i, j)).copied().unwrap_or(0.0)
}

fn at_mut<const R: usize, const C: usize>(m: &mut SMatrix<f64, R, C>, i: usize, j: usize) -> Option<&mut f64> {
    m.get_mut((i, j))
}

fn el<const K: usize>(v: &SVector<f64, K>, i: usize) -> f64 {
    v.get(i).copied().unwrap_or(0.0)
}

fn el_mut<const K: usize>(v: &mut SVector<f64, K>, i: usize) -> Option<&mut f64> {
    v.get_mut(i)
}

/// Indices of a sparsity pattern: a list of at most `K` column (or row) indices.
#[derive(Clone, Copy)]
struct Pattern<const K: usize> {
    idx: [u16; K],
    len: u16,
}

impl<const K: usize> Pattern<K> {
    const EMPTY: Self = Pattern { idx: [0; K], len: 0 };
    fn push(&mut self, i: usize) {
        if let (Some(e), Ok(i)) = (self.idx.get_mut(usize::from(self.len)), u16::try_from(i)) {
            *e = i;
            self.len += 1;
        }
    }
    fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        self.idx.get(..usize::from(self.len)).unwrap_or(&[]).iter().map(|i| usize::from(*i))
    }
    fn prefix(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        self.idx.get(..n.min(usize::from(self.len))).unwrap_or(&[]).iter().map(|i| usize::from(*i))
    }
}

/// The sparsity structure of a problem, computed once per solve: the nonzero columns of every row of `G` and `A`,
/// the elimination order of `H = G' W G` (ascending degree in the graph of `G'G`) and the pattern of its Cholesky
/// factor (symbolic elimination, fill included). The pattern of `H` does not depend on `W > 0`, so it holds for
/// every iteration.
struct Structure<const N: usize, const P: usize, const M: usize> {
    g_rows: [Pattern<N>; M],
    a_rows: [Pattern<N>; P],
    /// `perm[k]`: the variable eliminated `k`-th; `pos[j]`: the elimination step of variable `j`.
    perm: [u16; N],
    pos: [u16; N],
    /// `l_cols[k]`: the steps `i > k` with `L[i, k]` structurally nonzero (ascending).
    l_cols: [Pattern<N>; N],
    /// Per elimination step: the variable appears in no constraint (pinned by a unit diagonal).
    unused: [bool; N],
    /// Equation rows that are identically zero.
    zero_a_row: [bool; P],
}

impl<const N: usize, const P: usize, const M: usize> Structure<N, P, M> {
    fn new(lp: &LinearProgram<N, P, M>) -> Self {
        let mut g_rows = [Pattern::<N>::EMPTY; M];
        for (i, pat) in g_rows.iter_mut().enumerate() {
            for j in 0..N {
                if at(&lp.g, i, j) != 0.0 {
                    pat.push(j);
                }
            }
        }
        let mut a_rows = [Pattern::<N>::EMPTY; P];
        let mut zero_a_row = [false; P];
        for ((i, pat), z) in a_rows.iter_mut().enumerate().zip(zero_a_row.iter_mut()) {
            for j in 0..N {
                if at(&lp.a, i, j) != 0.0 {
                    pat.push(j);
                }
            }
            *z = pat.len == 0;
        }
        // graph of G'G (original indices) and degrees
        let mut adj = [[false; N]; N];
        let mut used = [false; N];
        for pat in g_rows.iter() {
            for a in pat.iter() {
                for b in pat.iter() {
                    if let Some(e) = adj.get_mut(a).and_then(|r| r.get_mut(b)) {
                        *e = true;
                    }
                }
                if let Some(u) = used.get_mut(a) {
                    *u = true;
                }
            }
        }
        for pat in a_rows.iter() {
            for a in pat.iter() {
                if let Some(u) = used.get_mut(a) {
                    *u = true;
                }
            }
        }
        let mut degree = [0usize; N];
        for (d, row) in degree.iter_mut().zip(adj.iter()) {
            *d = row.iter().filter(|x| **x).count();
        }
        // static minimum-degree order (stable insertion sort)
        let mut perm = [0u16; N];
        for (k, p) in perm.iter_mut().enumerate() {
            *p = u16::try_from(k).unwrap_or(0);
        }
        for k in 1..N {
            let mut j = k;
            while j > 0 {
                let (Some(&pa), Some(&pb)) = (perm.get(j - 1), perm.get(j)) else { break };
                let (da, db) =
                    (degree.get(usize::from(pa)).copied().unwrap_or(0), degree.get(usize::from(pb)).copied().unwrap_or(0));
                if da <= db {
                    break;
                }
                perm.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut pos = [0u16; N];
        let mut unused = [false; N];
        for (k, p) in perm.iter().enumerate() {
            if let Some(e) = pos.get_mut(usize::from(*p)) {
                *e = u16::try_from(k).unwrap_or(0);
            }
            if let Some(u) = unused.get_mut(k) {
                *u = !used.get(usize::from(*p)).copied().unwrap_or(true);
            }
        }
        // symbolic elimination in the permuted order
        let mut e = [[false; N]; N];
        for (a, row) in adj.iter().enumerate() {
            for (b, x) in row.iter().enumerate() {
                if *x {
                    let pa = pos.get(a).copied().map(usize::from).unwrap_or(0);
                    let pb = pos.get(b).copied().map(usize::from).unwrap_or(0);
                    if let Some(v) = e.get_mut(pa).and_then(|r| r.get_mut(pb)) {
                        *v = true;
                    }
                }
            }
        }
        let mut l_cols = [Pattern::<N>::EMPTY; N];
        for (k, col) in l_cols.iter_mut().enumerate() {
            for i in (k + 1)..N {
                if e.get(i).and_then(|r| r.get(k)).copied().unwrap_or(false) {
                    col.push(i);
                }
            }
            for i in col.iter() {
                for j in col.iter() {
                    if let Some(v) = e.get_mut(i).and_then(|r| r.get_mut(j)) {
                        *v = true;
                    }
                }
            }
        }
        Structure { g_rows, a_rows, perm, pos, l_cols, unused, zero_a_row }
    }

    fn pos(&self, j: usize) -> usize {
        self.pos.get(j).copied().map(usize::from).unwrap_or(0)
    }
}

/// The factorised reduced KKT system of one iteration.
struct Kkt<const N: usize, const P: usize> {
    /// Cholesky factor of `H` in elimination order (lower triangle; only the structural nonzeros are meaningful).
    l: SMatrix<f64, N, N>,
    /// `H^-1 A'`.
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

    /// `G x` over the nonzeros of `G`.
    fn g_mul(&self, st: &Structure<N, P, M>, x: &SVector<f64, N>) -> SVector<f64, M> {
        let mut out = SVector::<f64, M>::zeros();
        for ((i, pat), o) in st.g_rows.iter().enumerate().zip(out.iter_mut()) {
            let mut acc = 0.0;
            for j in pat.iter() {
                acc += at(&self.g, i, j) * el(x, j);
            }
            *o = acc;
        }
        out
    }

    /// `G' z` over the nonzeros of `G`.
    fn g_tr_mul(&self, st: &Structure<N, P, M>, z: &SVector<f64, M>) -> SVector<f64, N> {
        let mut out = SVector::<f64, N>::zeros();
        for ((i, pat), zi) in st.g_rows.iter().enumerate().zip(z.iter()) {
            for j in pat.iter() {
                if let Some(o) = el_mut(&mut out, j) {
                    *o += at(&self.g, i, j) * zi;
                }
            }
        }
        out
    }

    /// `A x` over the nonzeros of `A`.
    fn a_mul(&self, st: &Structure<N, P, M>, x: &SVector<f64, N>) -> SVector<f64, P> {
        let mut out = SVector::<f64, P>::zeros();
        for ((i, pat), o) in st.a_rows.iter().enumerate().zip(out.iter_mut()) {
            let mut acc = 0.0;
            for j in pat.iter() {
                acc += at(&self.a, i, j) * el(x, j);
            }
            *o = acc;
        }
        out
    }

    /// `A' y` over the nonzeros of `A`.
    fn a_tr_mul(&self, st: &Structure<N, P, M>, y: &SVector<f64, P>) -> SVector<f64, N> {
        let mut out = SVector::<f64, N>::zeros();
        for ((i, pat), yi) in st.a_rows.iter().enumerate().zip(y.iter()) {
            for j in pat.iter() {
                if let Some(o) = el_mut(&mut out, j) {
                    *o += at(&self.a, i, j) * yi;
                }
            }
        }
        out
    }

    /// Assemble `H = G' W G` (permuted, lower triangle, on the factor's pattern) into `l`, pin unused variables
    /// with a unit diagonal and add `reg` to the diagonal of used ones. Returns the largest `|H_jj|` (at least 1).
    fn assemble(&self, st: &Structure<N, P, M>, w: &SVector<f64, M>, l: &mut SMatrix<f64, N, N>, reg: f64) -> f64 {
        for (k, col) in st.l_cols.iter().enumerate() {
            if let Some(e) = at_mut(l, k, k) {
                *e = 0.0;
            }
            for i in col.iter() {
                if let Some(e) = at_mut(l, i, k) {
                    *e = 0.0;
                }
            }
        }
        for ((r, pat), wi) in st.g_rows.iter().enumerate().zip(w.iter()) {
            for a in pat.iter() {
                let wa = wi * at(&self.g, r, a);
                let pa = st.pos(a);
                for b in pat.iter() {
                    let pb = st.pos(b);
                    if pb <= pa {
                        if let Some(e) = at_mut(l, pa, pb) {
                            *e += wa * at(&self.g, r, b);
                        }
                    }
                }
            }
        }
        let mut scale = 1.0f64;
        for (k, unused) in st.unused.iter().enumerate() {
            if let Some(e) = at_mut(l, k, k) {
                scale = scale.max(e.abs());
                *e += if *unused { 1.0 } else { reg };
            }
        }
        scale
    }

    /// In-place sparse Cholesky `H = L L'` on the symbolic pattern; false if a pivot is not positive.
    fn cholesky(st: &Structure<N, P, M>, l: &mut SMatrix<f64, N, N>) -> bool {
        for (k, col) in st.l_cols.iter().enumerate() {
            let d = at(l, k, k);
            if !(d > 0.0) {
                return false;
            }
            let d = libm::sqrt(d);
            if let Some(e) = at_mut(l, k, k) {
                *e = d;
            }
            for i in col.iter() {
                if let Some(e) = at_mut(l, i, k) {
                    *e /= d;
                }
            }
            for (n, i) in col.iter().enumerate() {
                let lik = at(l, i, k);
                for j in col.prefix(n + 1) {
                    let ljk = at(l, j, k);
                    if let Some(e) = at_mut(l, i, j) {
                        *e -= lik * ljk;
                    }
                }
            }
        }
        true
    }

    /// Solve `H x = b` with the sparse factor.
    fn h_solve(st: &Structure<N, P, M>, l: &SMatrix<f64, N, N>, b: &SVector<f64, N>) -> SVector<f64, N> {
        let mut y = SVector::<f64, N>::zeros();
        for (yk, p) in y.iter_mut().zip(st.perm.iter()) {
            *yk = el(b, usize::from(*p));
        }
        for (k, col) in st.l_cols.iter().enumerate() {
            let yk = el(&y, k) / at(l, k, k);
            if let Some(e) = el_mut(&mut y, k) {
                *e = yk;
            }
            for i in col.iter() {
                if let Some(e) = el_mut(&mut y, i) {
                    *e -= at(l, i, k) * yk;
                }
            }
        }
        for (k, col) in st.l_cols.iter().enumerate().rev() {
            let mut v = el(&y, k);
            for i in col.iter() {
                v -= at(l, i, k) * el(&y, i);
            }
            if let Some(e) = el_mut(&mut y, k) {
                *e = v / at(l, k, k);
            }
        }
        let mut out = SVector::<f64, N>::zeros();
        for (yk, p) in y.iter().zip(st.perm.iter()) {
            if let Some(e) = el_mut(&mut out, usize::from(*p)) {
                *e = *yk;
            }
        }
        out
    }

    fn factor(&self, st: &Structure<N, P, M>, w: &SVector<f64, M>) -> Option<Kkt<N, P>> {
        // H = G' W G from the nonzeros of G (the stability LP has at most three per row).
        let mut l = SMatrix::<f64, N, N>::zeros();
        let scale = self.assemble(st, w, &mut l, 0.0);
        // Unregularised first (exact Newton steps); a tiny diagonal only if that factorisation fails.
        if !Self::cholesky(st, &mut l) {
            self.assemble(st, w, &mut l, 1e-12 * scale);
            if !Self::cholesky(st, &mut l) {
                return None;
            }
        }
        let mut v = SMatrix::<f64, N, P>::zeros();
        for (i, pat) in st.a_rows.iter().enumerate() {
            let mut ai = SVector::<f64, N>::zeros();
            for j in pat.iter() {
                if let Some(e) = el_mut(&mut ai, j) {
                    *e = at(&self.a, i, j);
                }
            }
            v.set_column(i, &Self::h_solve(st, &l, &ai));
        }
        // Schur complement A H^-1 A' (symmetric: lower triangle computed, mirrored)
        let mut s = SMatrix::<f64, P, P>::zeros();
        for (i, pat) in st.a_rows.iter().enumerate() {
            for k in 0..=i {
                let mut acc = 0.0;
                for j in pat.iter() {
                    acc += at(&self.a, i, j) * at(&v, j, k);
                }
                if let Some(e) = at_mut(&mut s, i, k) {
                    *e = acc;
                }
                if let Some(e) = at_mut(&mut s, k, i) {
                    *e = acc;
                }
            }
        }
        let sscale = s.diagonal().iter().fold(0.0f64, |m, x| m.max(x.abs()));
        for (i, zero_row) in st.zero_a_row.iter().enumerate() {
            if *zero_row {
                if let Some(e) = at_mut(&mut s, i, i) {
                    *e += 1.0;
                }
            }
        }
        let schur = match Cholesky::new(s) {
            Some(c) => c,
            None => {
                for i in 0..P {
                    if let Some(e) = at_mut(&mut s, i, i) {
                        *e += 1e-13 * sscale;
                    }
                }
                Cholesky::new(s)?
            }
        };
        Some(Kkt { l, v, schur })
    }

    #[allow(clippy::too_many_arguments)]
    fn direction_once(
        &self,
        st: &Structure<N, P, M>,
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
        let q = -r_d - self.g_tr_mul(st, &t);
        let u = Self::h_solve(st, &kkt.l, &q);
        let dy = kkt.schur.solve(&(self.a_mul(st, &u) + r_p));
        let dx = u - kkt.v * dy;
        let dz = w.component_mul(&(self.g_mul(st, &dx) + r_g)) - r_c.component_div(s);
        let ds = (-r_c - s.component_mul(&dz)).component_div(z);
        (dx, dy, dz, ds)
    }

    /// Newton direction with one step of iterative refinement on the full (unreduced) system: the reduced
    /// normal equations lose digits once `z / s` spans many orders of magnitude.
    #[allow(clippy::too_many_arguments)]
    fn direction(
        &self,
        st: &Structure<N, P, M>,
        kkt: &Kkt<N, P>,
        w: &SVector<f64, M>,
        s: &SVector<f64, M>,
        z: &SVector<f64, M>,
        r_d: &SVector<f64, N>,
        r_p: &SVector<f64, P>,
        r_g: &SVector<f64, M>,
        r_c: &SVector<f64, M>,
    ) -> Step<N, P, M> {
        let (dx, dy, dz, ds) = self.direction_once(st, kkt, w, s, z, r_d, r_p, r_g, r_c);
        // residuals of: A'dy + G'dz = -r_d; A dx = -r_p; G dx + ds = -r_g; Z ds + S dz = -r_c
        let e1 = r_d + self.a_tr_mul(st, &dy) + self.g_tr_mul(st, &dz);
        let e2 = r_p + self.a_mul(st, &dx);
        let e3 = r_g + self.g_mul(st, &dx) + ds;
        let e4 = r_c + z.component_mul(&ds) + s.component_mul(&dz);
        let (cx, cy, cz, cs) = self.direction_once(st, kkt, w, s, z, &e1, &e2, &e3, &e4);
        (dx + cx, dy + cy, dz + cz, ds + cs)
    }

    /// Solve with at most `max_iterations` interior-point iterations to relative tolerance `tol`.
    pub fn solve(&self, max_iterations: u32, tol: f64) -> LpSolution<N> {
        let st = Structure::new(self);
        let mut x = SVector::<f64, N>::zeros();
        let mut y = SVector::<f64, P>::zeros();
        let mut s = (self.h - self.g_mul(&st, &x)).map(|v| if v > 1.0 { v } else { 1.0 });
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
            let r_d = self.c + self.a_tr_mul(&st, &y) + self.g_tr_mul(&st, &z);
            let r_p = self.a_mul(&st, &x) - self.b;
            let r_g = self.g_mul(&st, &x) + s - self.h;
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
            let Some(kkt) = self.factor(&st, &w) else {
                return end(best_x, best_merit, it, LpStatus::NumericalFailure);
            };
            // predictor (affine scaling)
            let r_c = s.component_mul(&z);
            let (_, _, dz_a, ds_a) = self.direction(&st, &kkt, &w, &s, &z, &r_d, &r_p, &r_g, &r_c);
            let ap = max_step(&s, &ds_a);
            let ad = max_step(&z, &dz_a);
            let mu_aff = (s + ds_a * ap).dot(&(z + dz_a * ad)) / (M.max(1) as f64);
            let ratio = mu_aff / mu;
            let sigma = (ratio * ratio * ratio).clamp(0.0, 1.0);
            // corrector
            let r_c = s.component_mul(&z) + ds_a.component_mul(&dz_a) - SVector::<f64, M>::repeat(sigma * mu);
            let (dx, dy, dz, ds) = self.direction(&st, &kkt, &w, &s, &z, &r_d, &r_p, &r_g, &r_c);
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
