//! The fallback of the stability LP (the simplex, [`super::simplex`], solves it first; this method when the
//! simplex runs out of exchanges or fails its residual check): a fixed-size, sparsity-exploiting linear-program
//! solver, Mehrotra predictor-corrector
//! primal-dual interior point method (Wright, *Primal-Dual Interior-Point Methods*, SIAM 1997, ch. 10;
//! Vandenberghe, *The CVXOPT linear and quadratic cone program solvers*, 2010, section 3 for the reduced KKT system).
//!
//! Problem: minimise `c'x` subject to `A x = b` (`P` rows) and `G x <= h` (`M` rows), `x` in R^`N`.
//! All sizes are const generics (`N`, `M` below 65,536), all storage is on the stack (`f64`), no heap.
//! The problem is given in dense nalgebra matrices; the solver works on their nonzeros only.
//!
//! # Compaction and sparsity (once per solve)
//! - Variables that no constraint mentions and that have no cost (`x_j = 0` throughout, e.g. an unused contact
//!   slot) are dropped; a variable with a cost but no constraint is kept and pinned by a unit diagonal (the
//!   problem is then unbounded and the solve ends as budget exhausted or numerical failure).
//! - Inequality rows `0 <= h_i` with `h_i >= 0` (always slack, e.g. the rows of an unused slot) are dropped; a
//!   violated zero row is kept, so an infeasible problem cannot report an optimum.
//! - The rows of `G` and `A` are kept as (column, value) lists (the stability LP has at most 3 nonzeros per row of
//!   `G`), so `G x`, `G' z`, `A x`, `A' y` cost their nonzeros.
//! - `H = G' W G` (`W = diag(z / s)`) has the pattern of `G'G` whatever `W > 0` is: an elimination order
//!   (ascending degree in that graph) and the pattern of its Cholesky factor (symbolic elimination, fill included)
//!   are computed once. For the stability LP (each friction/moment row touches one force, the normal force and the
//!   margin) the order puts the tangential forces and moments first, and the factor has almost no fill.
//!
//! # Each iteration
//! The slacks and duals of the inequalities are eliminated; `H` is assembled from the rows of `G` and factorised
//! by a sparse Cholesky on the symbolic pattern, then the `P x P` Schur complement `A H^-1 A'` by a dense Cholesky.
//! An equation row that is identically zero (`0 = 0`) is pinned by a unit diagonal. Reciprocals of `s`, `z` and of
//! the factor's diagonal replace divisions (software floating point on the board). The predictor (affine-scaling)
//! direction is used as solved (it only steers the centring); the corrector direction gets `REFINE_STEPS = 3` steps of
//! iterative refinement on the full (unreduced) system once `max w / min w` exceeds `REFINE_SPREAD = 1e6` (the reduced
//! normal equations lose digits once `z / s` spans many orders of magnitude). The method starts from an infeasible
//! point (`x = 0`, `s = max(h - Gx, 1)`, `z = 1`), and the centring measure is `s'z / m` over the `m` kept rows.
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
//! (relative residual and gap tolerance, `config::stability::SOLVER_TOLERANCE`, default 1e-9); internal constants
//! `DUAL_TOL_FACTOR = 1000`, `ALMOST_FACTOR = 100`, `REFINE_SPREAD = 1e6`, `REFINE_STEPS = 3`.
//!
//! Cost against the simplex, per solve on the emulated board: `host-sim/doc/board_test3.md`.

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
    /// No point satisfies the constraints (the simplex's phase 1 ended with a positive infeasibility, or an
    /// equation reduced to `0 = b` with `b != 0`); the interior-point method never reports it.
    Infeasible,
    /// A feasible point whose objective is at most the target asked for (`simplex::solve_until`); not
    /// necessarily optimal.
    TargetReached,
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

/// The corrector direction is refined once `max w / min w` (`w = z / s`) exceeds this spread.
const REFINE_SPREAD: f64 = 1e6;

/// Refinement steps on the corrector once the spread is past `REFINE_SPREAD`. One step was not enough: near the
/// optimum the corrected step could still carry a primal residual of order 1 (the 10,000-instance oracle's case
/// 6549, `tests/tests/stability.rs`); each further step costs one more pair of triangular solves.
const REFINE_STEPS: usize = 3;

/// Accuracy accepted as [`LpStatus::AlmostOptimal`], as a multiple of `tol`.
pub const ALMOST_FACTOR: f64 = 100.0;

fn mat_get<const R: usize, const C: usize>(m: &SMatrix<f64, R, C>, i: usize, j: usize) -> f64 {
    m.get((i, j)).copied().unwrap_or(0.0)
}

fn at_mut<const R: usize, const C: usize>(m: &mut SMatrix<f64, R, C>, i: usize, j: usize) -> Option<&mut f64> {
    m.get_mut((i, j))
}

fn vec_get(v: &[f64], i: usize) -> f64 {
    v.get(i).copied().unwrap_or(0.0)
}

fn vec_set(v: &mut [f64], i: usize, x: f64) {
    if let Some(e) = v.get_mut(i) {
        *e = x;
    }
}

fn vec_add(v: &mut [f64], i: usize, x: f64) {
    if let Some(e) = v.get_mut(i) {
        *e += x;
    }
}

fn inf_norm(v: &[f64]) -> f64 {
    v.iter().fold(0.0, |m, x| if x.abs() > m { x.abs() } else { m })
}

/// Sum starting from the first term (`Iterator::sum` starts from `-0.0`: one soft-float addition more per sum).
fn sum(mut terms: impl Iterator<Item = f64>) -> f64 {
    match terms.next() {
        Some(first) => terms.fold(first, |a, b| a + b),
        None => 0.0,
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    sum(a.iter().zip(b.iter()).map(|(x, y)| x * y))
}

fn max_step(v: &[f64], dv: &[f64]) -> f64 {
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

fn u16_of(i: usize) -> u16 {
    u16::try_from(i).unwrap_or(u16::MAX)
}

/// Indices of a sparsity pattern: a list of at most `K` indices.
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
    fn len(&self) -> usize {
        usize::from(self.len)
    }
    fn iter(&self) -> impl Iterator<Item = usize> + '_ {
        self.prefix(self.len())
    }
    fn prefix(&self, n: usize) -> impl Iterator<Item = usize> + '_ {
        self.idx.get(..n.min(self.len())).unwrap_or(&[]).iter().map(|i| usize::from(*i))
    }
}

/// A sparse row: at most `K` (index, value) entries.
#[derive(Clone, Copy)]
struct SparseRow<const K: usize> {
    idx: [u16; K],
    val: [f64; K],
    len: u16,
}

impl<const K: usize> SparseRow<K> {
    const EMPTY: Self = SparseRow { idx: [0; K], val: [0.0; K], len: 0 };
    fn push(&mut self, i: usize, v: f64) {
        let n = usize::from(self.len);
        if let (Some(e), Some(x), Ok(i)) = (self.idx.get_mut(n), self.val.get_mut(n), u16::try_from(i)) {
            *e = i;
            *x = v;
            self.len += 1;
        }
    }
    fn iter(&self) -> impl Iterator<Item = (usize, f64)> + '_ {
        let n = usize::from(self.len);
        self.idx.get(..n).unwrap_or(&[]).iter().zip(self.val.get(..n).unwrap_or(&[]).iter()).map(|(i, v)| (usize::from(*i), *v))
    }
    fn dot(&self, x: &[f64]) -> f64 {
        sum(self.iter().map(|(k, v)| v * vec_get(x, k)))
    }
    fn axpy(&self, a: f64, out: &mut [f64]) {
        for (k, v) in self.iter() {
            vec_add(out, k, v * a);
        }
    }
}

/// The compacted problem, computed once per solve. Variables that no constraint mentions and that have no cost
/// (`x_j = 0` throughout) and inequality rows `0 <= h_i` with `h_i >= 0` (always slack) are dropped; the rest is
/// renumbered densely (`nv` variables, `nr` inequalities). Kept: the nonzero (compact) columns of every row of `G`
/// and `A`, the elimination order of `H = G' W G` (ascending degree in the graph of `G'G`) and the pattern of its
/// Cholesky factor (symbolic elimination, fill included). The pattern of `H` does not depend on `W > 0`, so it
/// holds for every iteration.
struct Structure<const N: usize, const P: usize, const M: usize> {
    nv: usize,
    /// Compact variable -> original column.
    var: [u16; N],
    nr: usize,
    /// Compact inequality -> original row.
    row: [u16; M],
    /// Rows of `G` (compact rows and columns) and of `A` (compact columns), with their values.
    g_rows: [SparseRow<N>; M],
    a_rows: [SparseRow<N>; P],
    /// `perm[k]`: the compact variable eliminated `k`-th; `pos[j]`: the elimination step of compact variable `j`.
    perm: [u16; N],
    pos: [u16; N],
    /// `l_cols[k]`: the steps `i > k` with `L[i, k]` structurally nonzero (ascending).
    l_cols: [Pattern<N>; N],
    /// Per elimination step: the variable appears in no constraint (kept for its cost; pinned by a unit diagonal).
    unused: [bool; N],
    /// Equation rows that are identically zero.
    zero_a_row: [bool; P],
}

impl<const N: usize, const P: usize, const M: usize> Structure<N, P, M> {
    fn new(lp: &LinearProgram<N, P, M>) -> Self {
        let mut used = [false; N];
        let mut keep_row = [false; M];
        for (i, k) in keep_row.iter_mut().enumerate() {
            for (j, u) in used.iter_mut().enumerate() {
                if mat_get(&lp.g, i, j) != 0.0 {
                    *u = true;
                    *k = true;
                }
            }
            // a zero row `0 <= h` stays unless it is violated (then the problem is infeasible: keep it so the
            // solver cannot report an optimum)
            let hi = lp.h.get(i).copied().unwrap_or(0.0);
            if hi.is_nan() || hi < 0.0 {
                *k = true;
            }
        }
        let mut zero_a_row = [true; P];
        for (i, z) in zero_a_row.iter_mut().enumerate() {
            for (j, u) in used.iter_mut().enumerate() {
                if mat_get(&lp.a, i, j) != 0.0 {
                    *u = true;
                    *z = false;
                }
            }
        }
        let mut var = [0u16; N];
        let mut compact = [u16::MAX; N];
        let mut nv = 0;
        let mut unused_c = [false; N];
        for (j, u) in used.iter().enumerate() {
            let cj = lp.c.get(j).copied().unwrap_or(0.0);
            if *u || cj != 0.0 {
                put_u16(&mut var, nv, u16_of(j));
                put_u16(&mut compact, j, u16_of(nv));
                if let Some(e) = unused_c.get_mut(nv) {
                    *e = !*u;
                }
                nv += 1;
            }
        }
        let mut row = [0u16; M];
        let mut nr = 0;
        let mut g_rows = [SparseRow::<N>::EMPTY; M];
        for (i, k) in keep_row.iter().enumerate() {
            if !*k {
                continue;
            }
            put_u16(&mut row, nr, u16_of(i));
            if let Some(pat) = g_rows.get_mut(nr) {
                for (j, cj) in compact.iter().enumerate() {
                    let v = mat_get(&lp.g, i, j);
                    if v != 0.0 {
                        pat.push(usize::from(*cj), v);
                    }
                }
            }
            nr += 1;
        }
        let mut a_rows = [SparseRow::<N>::EMPTY; P];
        for (i, pat) in a_rows.iter_mut().enumerate() {
            for (j, cj) in compact.iter().enumerate() {
                let v = mat_get(&lp.a, i, j);
                if v != 0.0 {
                    pat.push(usize::from(*cj), v);
                }
            }
        }
        // graph of G'G (compact indices) and degrees
        let mut adj = [[false; N]; N];
        for pat in g_rows.iter().take(nr) {
            for (a, _) in pat.iter() {
                for (b, _) in pat.iter() {
                    if let Some(e) = adj.get_mut(a).and_then(|r| r.get_mut(b)) {
                        *e = true;
                    }
                }
            }
        }
        let mut degree = [0usize; N];
        for (d, r) in degree.iter_mut().zip(adj.iter()) {
            *d = r.iter().filter(|x| **x).count();
        }
        // static minimum-degree order (stable insertion sort)
        let mut perm = [0u16; N];
        for (k, p) in perm.iter_mut().enumerate() {
            *p = u16_of(k);
        }
        let deg = |p: u16| degree.get(usize::from(p)).copied().unwrap_or(0);
        for k in 1..nv {
            let mut j = k;
            while j > 0 {
                let (Some(&pa), Some(&pb)) = (perm.get(j - 1), perm.get(j)) else { break };
                if deg(pa) <= deg(pb) {
                    break;
                }
                perm.swap(j - 1, j);
                j -= 1;
            }
        }
        let mut pos = [0u16; N];
        let mut unused = [false; N];
        for (k, p) in perm.iter().enumerate().take(nv) {
            put_u16(&mut pos, usize::from(*p), u16_of(k));
            if let Some(u) = unused.get_mut(k) {
                *u = unused_c.get(usize::from(*p)).copied().unwrap_or(false);
            }
        }
        // symbolic elimination in the permuted order
        let mut e = [[false; N]; N];
        for (a, r) in adj.iter().enumerate().take(nv) {
            for (b, x) in r.iter().enumerate().take(nv) {
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
        for (k, col) in l_cols.iter_mut().enumerate().take(nv) {
            for i in (k + 1)..nv {
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
        Structure { nv, var, nr, row, g_rows, a_rows, perm, pos, l_cols, unused, zero_a_row }
    }

    fn pos(&self, j: usize) -> usize {
        self.pos.get(j).copied().map(usize::from).unwrap_or(0)
    }
    fn var(&self, j: usize) -> usize {
        self.var.get(j).copied().map(usize::from).unwrap_or(0)
    }
    fn row(&self, i: usize) -> usize {
        self.row.get(i).copied().map(usize::from).unwrap_or(0)
    }
    /// The compact inequality rows with their index.
    fn g_rows(&self) -> impl Iterator<Item = &SparseRow<N>> + '_ {
        self.g_rows.iter().take(self.nr)
    }
}

fn put_u16(v: &mut [u16], i: usize, x: u16) {
    if let Some(e) = v.get_mut(i) {
        *e = x;
    }
}

/// The factorised reduced KKT system of one iteration.
struct Kkt<const N: usize, const P: usize> {
    /// Cholesky factor of `H` in elimination order (lower triangle; only the structural nonzeros are meaningful).
    l: SMatrix<f64, N, N>,
    /// Reciprocals of the factor's diagonal (multiplications instead of divisions in the solves).
    inv_diag: [f64; N],
    /// `H^-1 A'` (compact rows).
    v: SMatrix<f64, N, P>,
    schur: Option<Cholesky<f64, nalgebra::Const<P>>>,
}

impl<const N: usize, const P: usize> Kkt<N, P> {
    fn new() -> Self {
        Kkt { l: SMatrix::zeros(), inv_diag: [0.0; N], v: SMatrix::zeros(), schur: None }
    }
    fn schur_solve(&self, b: &SVector<f64, P>) -> SVector<f64, P> {
        match &self.schur {
            Some(c) => c.solve(b),
            None => SVector::zeros(),
        }
    }
}

/// The scaling of one iteration: slacks `s`, duals `z`, `w = z / s` and the reciprocals of `s` and `z`.
struct Scaling<const M: usize> {
    w: [f64; M],
    s: [f64; M],
    z: [f64; M],
    inv_s: [f64; M],
    inv_z: [f64; M],
}

/// Residuals (or right-hand sides) of the Newton system, in compact numbering.
struct Rhs<'a, const N: usize, const P: usize, const M: usize> {
    d: &'a [f64; N],
    p: &'a SVector<f64, P>,
    g: &'a [f64; M],
    c: &'a [f64; M],
}

/// A Newton step `(dx, dy, dz, ds)` in compact numbering.
struct Step<const N: usize, const P: usize, const M: usize> {
    dx: [f64; N],
    dy: SVector<f64, P>,
    dz: [f64; M],
    ds: [f64; M],
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
    fn g_mul(st: &Structure<N, P, M>, x: &[f64; N]) -> [f64; M] {
        let mut out = [0.0; M];
        for (row, o) in st.g_rows().zip(out.iter_mut()) {
            *o = row.dot(x);
        }
        out
    }

    /// `G' z` over the nonzeros of `G`.
    fn g_tr_mul(st: &Structure<N, P, M>, z: &[f64; M]) -> [f64; N] {
        let mut out = [0.0; N];
        for (row, zr) in st.g_rows().zip(z.iter()) {
            row.axpy(*zr, &mut out);
        }
        out
    }

    /// `A x` over the nonzeros of `A`.
    fn a_mul(st: &Structure<N, P, M>, x: &[f64; N]) -> SVector<f64, P> {
        let mut out = SVector::<f64, P>::zeros();
        for (row, o) in st.a_rows.iter().zip(out.iter_mut()) {
            *o = row.dot(x);
        }
        out
    }

    /// `A' y` over the nonzeros of `A`.
    fn a_tr_mul(st: &Structure<N, P, M>, y: &SVector<f64, P>) -> [f64; N] {
        let mut out = [0.0; N];
        for (row, yi) in st.a_rows.iter().zip(y.iter()) {
            row.axpy(*yi, &mut out);
        }
        out
    }

    /// Assemble `H = G' W G` (permuted, lower triangle, on the factor's pattern) into `l`, pin cost-only variables
    /// with a unit diagonal and add `reg` to the diagonal of the others. Returns the largest `|H_jj|` (at least 1).
    fn assemble(&self, st: &Structure<N, P, M>, w: &[f64; M], l: &mut SMatrix<f64, N, N>, reg: f64) -> f64 {
        for (k, col) in st.l_cols.iter().enumerate().take(st.nv) {
            if let Some(e) = at_mut(l, k, k) {
                *e = 0.0;
            }
            for i in col.iter() {
                if let Some(e) = at_mut(l, i, k) {
                    *e = 0.0;
                }
            }
        }
        for (row, wr) in st.g_rows().zip(w.iter()) {
            for (a, va) in row.iter() {
                let wa = wr * va;
                let pa = st.pos(a);
                for (b, vb) in row.iter() {
                    let pb = st.pos(b);
                    if pb <= pa {
                        if let Some(e) = at_mut(l, pa, pb) {
                            *e += wa * vb;
                        }
                    }
                }
            }
        }
        let mut scale = 1.0f64;
        for (k, unused) in st.unused.iter().enumerate().take(st.nv) {
            if let Some(e) = at_mut(l, k, k) {
                scale = scale.max(e.abs());
                *e += if *unused { 1.0 } else { reg };
            }
        }
        scale
    }

    /// In-place sparse Cholesky `H = L L'` on the symbolic pattern; false if a pivot is not positive.
    fn cholesky(st: &Structure<N, P, M>, l: &mut SMatrix<f64, N, N>) -> bool {
        for (k, col) in st.l_cols.iter().enumerate().take(st.nv) {
            let d = mat_get(l, k, k);
            if d.is_nan() || d <= 0.0 {
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
                let lik = mat_get(l, i, k);
                for j in col.prefix(n + 1) {
                    let ljk = mat_get(l, j, k);
                    if let Some(e) = at_mut(l, i, j) {
                        *e -= lik * ljk;
                    }
                }
            }
        }
        true
    }

    /// Solve `H x = b` with the sparse factor (compact numbering).
    fn h_solve(st: &Structure<N, P, M>, l: &SMatrix<f64, N, N>, inv_diag: &[f64; N], b: &[f64; N]) -> [f64; N] {
        let nv = st.nv;
        let mut y = [0.0; N];
        for (yk, p) in y.iter_mut().zip(st.perm.iter()).take(nv) {
            *yk = vec_get(b, usize::from(*p));
        }
        for (k, col) in st.l_cols.iter().enumerate().take(nv) {
            let yk = vec_get(&y, k) * vec_get(inv_diag, k);
            vec_set(&mut y, k, yk);
            for i in col.iter() {
                vec_add(&mut y, i, -(mat_get(l, i, k) * yk));
            }
        }
        for (k, col) in st.l_cols.iter().enumerate().take(nv).rev() {
            let mut v = vec_get(&y, k);
            for i in col.iter() {
                v -= mat_get(l, i, k) * vec_get(&y, i);
            }
            vec_set(&mut y, k, v * vec_get(inv_diag, k));
        }
        let mut out = [0.0; N];
        for (yk, p) in y.iter().zip(st.perm.iter()).take(nv) {
            vec_set(&mut out, usize::from(*p), *yk);
        }
        out
    }

    /// Factorise the reduced KKT system for `w` into `kkt` (reused across iterations: no large copies); false if
    /// a factorisation failed.
    fn factor(&self, st: &Structure<N, P, M>, w: &[f64; M], kkt: &mut Kkt<N, P>) -> bool {
        // H = G' W G from the nonzeros of G (the stability LP has at most three per row).
        let Kkt { l, inv_diag, v, schur: schur_out } = kkt;
        *schur_out = None;
        let scale = self.assemble(st, w, l, 0.0);
        // Unregularised first (exact Newton steps); a tiny diagonal only if that factorisation fails.
        if !Self::cholesky(st, l) {
            self.assemble(st, w, l, 1e-12 * scale);
            if !Self::cholesky(st, l) {
                return false;
            }
        }
        for (k, e) in inv_diag.iter_mut().enumerate().take(st.nv) {
            *e = 1.0 / mat_get(l, k, k);
        }
        for (i, pat) in st.a_rows.iter().enumerate() {
            let mut ai = [0.0; N];
            for (k, v) in pat.iter() {
                vec_set(&mut ai, k, v);
            }
            let col = Self::h_solve(st, l, inv_diag, &ai);
            for (k, x) in col.iter().enumerate().take(st.nv) {
                if let Some(e) = at_mut(v, k, i) {
                    *e = *x;
                }
            }
        }
        // Schur complement A H^-1 A' (symmetric: lower triangle computed, mirrored)
        let mut s = SMatrix::<f64, P, P>::zeros();
        for (i, pat) in st.a_rows.iter().enumerate() {
            for k in 0..=i {
                let acc = sum(pat.iter().map(|(j, a)| a * mat_get(v, j, k)));
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
        *schur_out = match Cholesky::new(s) {
            Some(c) => Some(c),
            None => {
                for i in 0..P {
                    if let Some(e) = at_mut(&mut s, i, i) {
                        *e += 1e-13 * sscale;
                    }
                }
                Cholesky::new(s)
            }
        };
        schur_out.is_some()
    }

    fn direction_once(
        &self,
        st: &Structure<N, P, M>,
        kkt: &Kkt<N, P>,
        sc: &Scaling<M>,
        r: &Rhs<'_, N, P, M>,
    ) -> Step<N, P, M> {
        let (nv, nr) = (st.nv, st.nr);
        let w = &sc.w;
        // r_c / s, used twice
        let mut cs = [0.0; M];
        for ((o, rc), si) in cs.iter_mut().zip(r.c.iter()).zip(sc.inv_s.iter()).take(nr) {
            *o = rc * si;
        }
        let mut t = [0.0; M];
        for (((o, wi), rg), ci) in t.iter_mut().zip(w.iter()).zip(r.g.iter()).zip(cs.iter()).take(nr) {
            *o = wi * rg - ci;
        }
        let mut q = Self::g_tr_mul(st, &t);
        for (qi, rd) in q.iter_mut().zip(r.d.iter()).take(nv) {
            *qi = -rd - *qi;
        }
        let u = Self::h_solve(st, &kkt.l, &kkt.inv_diag, &q);
        let dy = kkt.schur_solve(&(Self::a_mul(st, &u) + r.p));
        let mut dx = u;
        for (k, e) in dx.iter_mut().enumerate().take(nv) {
            let vd = sum(dy.iter().enumerate().map(|(i, d)| mat_get(&kkt.v, k, i) * d));
            *e -= vd;
        }
        let gdx = Self::g_mul(st, &dx);
        let mut dz = [0.0; M];
        let mut ds = [0.0; M];
        for i in 0..nr {
            let dzi = vec_get(w, i) * (vec_get(&gdx, i) + vec_get(r.g, i)) - vec_get(&cs, i);
            vec_set(&mut dz, i, dzi);
            vec_set(&mut ds, i, (-vec_get(r.c, i) - vec_get(&sc.s, i) * dzi) * vec_get(&sc.inv_z, i));
        }
        Step { dx, dy, dz, ds }
    }

    /// Newton direction, with `REFINE_STEPS` steps of iterative refinement on the full (unreduced) system if `refine`: the
    /// reduced normal equations lose digits once `z / s` spans many orders of magnitude.
    fn direction(
        &self,
        st: &Structure<N, P, M>,
        kkt: &Kkt<N, P>,
        sc: &Scaling<M>,
        r: &Rhs<'_, N, P, M>,
        refine: bool,
    ) -> Step<N, P, M> {
        let (nv, nr) = (st.nv, st.nr);
        let (s, z) = (&sc.s, &sc.z);
        let mut out = self.direction_once(st, kkt, sc, r);
        if !refine {
            return out;
        }
        for _ in 0..REFINE_STEPS {
            // residuals of: A'dy + G'dz = -r_d; A dx = -r_p; G dx + ds = -r_g; Z ds + S dz = -r_c
            let mut e1 = Self::a_tr_mul(st, &out.dy);
            let gdz = Self::g_tr_mul(st, &out.dz);
            for ((e, g), rd) in e1.iter_mut().zip(gdz.iter()).zip(r.d.iter()).take(nv) {
                *e = rd + *e + g;
            }
            let e2 = r.p + Self::a_mul(st, &out.dx);
            let mut e3 = Self::g_mul(st, &out.dx);
            let mut e4 = [0.0; M];
            for i in 0..nr {
                let v = vec_get(r.g, i) + vec_get(&e3, i) + vec_get(&out.ds, i);
                vec_set(&mut e3, i, v);
                vec_set(&mut e4, i, vec_get(r.c, i) + vec_get(z, i) * vec_get(&out.ds, i) + vec_get(s, i) * vec_get(&out.dz, i));
            }
            let c = self.direction_once(st, kkt, sc, &Rhs { d: &e1, p: &e2, g: &e3, c: &e4 });
            for (a, b) in out.dx.iter_mut().zip(c.dx.iter()).take(nv) {
                *a += b;
            }
            out.dy += c.dy;
            for (a, b) in out.dz.iter_mut().zip(c.dz.iter()).take(nr) {
                *a += b;
            }
            for (a, b) in out.ds.iter_mut().zip(c.ds.iter()).take(nr) {
                *a += b;
            }
        }
        out
    }

    /// Solve with at most `max_iterations` interior-point iterations to relative tolerance `tol`.
    pub fn solve(&self, max_iterations: u32, tol: f64) -> LpSolution<N> {
        let st = Structure::new(self);
        let (nv, nr) = (st.nv, st.nr);
        let mut c = [0.0; N];
        for (k, ck) in c.iter_mut().enumerate().take(nv) {
            *ck = self.c.get(st.var(k)).copied().unwrap_or(0.0);
        }
        let mut h = [0.0; M];
        for (i, hi) in h.iter_mut().enumerate().take(nr) {
            *hi = self.h.get(st.row(i)).copied().unwrap_or(0.0);
        }
        let mut x = [0.0; N];
        let mut y = SVector::<f64, P>::zeros();
        // x = 0: s = max(h - G x, 1)
        let mut s = [0.0; M];
        let mut z = [0.0; M];
        for ((si, zi), hi) in s.iter_mut().zip(z.iter_mut()).zip(h.iter()).take(nr) {
            *si = if *hi > 1.0 { *hi } else { 1.0 };
            *zi = 1.0;
        }
        let bn = 1.0 + inf_norm(self.b.as_slice());
        let cn = 1.0 + inf_norm(self.c.as_slice());
        let hn = 1.0 + inf_norm(self.h.as_slice());
        let rows = nr.max(1) as f64;
        let mut it = 0;
        let mut best_x = x;
        let mut best_merit = f64::INFINITY;
        let mut kkt = Kkt::<N, P>::new();
        let end = |xc: &[f64; N], merit: f64, it: u32, otherwise: LpStatus| {
            let status = if merit <= ALMOST_FACTOR * tol { LpStatus::AlmostOptimal } else { otherwise };
            let x = self.expand(&st, xc);
            LpSolution { status, objective: self.c.dot(&x), x, iterations: it }
        };
        loop {
            let mut r_d = Self::a_tr_mul(&st, &y);
            let gz = Self::g_tr_mul(&st, &z);
            for ((r, g), ck) in r_d.iter_mut().zip(gz.iter()).zip(c.iter()).take(nv) {
                *r = ck + *r + g;
            }
            let r_p = Self::a_mul(&st, &x) - self.b;
            let mut r_g = Self::g_mul(&st, &x);
            for ((r, si), hi) in r_g.iter_mut().zip(s.iter()).zip(h.iter()).take(nr) {
                *r = *r + si - hi;
            }
            let sz = dot(s.get(..nr).unwrap_or(&[]), z.get(..nr).unwrap_or(&[]));
            let mu = sz / rows;
            let pobj = dot(&c, &x);
            let merit = (inf_norm(r_p.as_slice()) / bn)
                .max(inf_norm(&r_g) / hn)
                .max(inf_norm(&r_d) / (DUAL_TOL_FACTOR * cn))
                .max(sz / (1.0 + pobj.abs()));
            if !merit.is_finite() {
                return end(&best_x, best_merit, it, LpStatus::NumericalFailure);
            }
            if merit <= tol {
                let x = self.expand(&st, &x);
                return LpSolution { status: LpStatus::Optimal, objective: pobj, x, iterations: it };
            }
            if merit < best_merit {
                best_merit = merit;
                best_x = x;
            } else if merit > 1e4 * best_merit {
                // round-off has taken over: stop with the best iterate
                return end(&best_x, best_merit, it, LpStatus::NumericalFailure);
            }
            if it >= max_iterations {
                return end(&best_x, best_merit, it, LpStatus::BudgetExhausted);
            }
            it += 1;
            let mut sc = Scaling { w: [0.0; M], s, z, inv_s: [0.0; M], inv_z: [0.0; M] };
            let mut r_c = [0.0; M];
            let (mut w_min, mut w_max) = (f64::INFINITY, 0.0f64);
            for i in 0..nr {
                let (si, zi) = (vec_get(&s, i), vec_get(&z, i));
                let inv_s = 1.0 / si;
                vec_set(&mut sc.inv_s, i, inv_s);
                vec_set(&mut sc.inv_z, i, 1.0 / zi);
                let wi = zi * inv_s;
                vec_set(&mut sc.w, i, wi);
                vec_set(&mut r_c, i, si * zi);
                if wi < w_min {
                    w_min = wi;
                }
                if wi > w_max {
                    w_max = wi;
                }
            }
            // refine the corrector only once the scaling is badly spread (or not finite): before that the normal
            // equations keep enough digits
            let refine = !matches!(
                w_max.partial_cmp(&(REFINE_SPREAD * w_min)),
                Some(core::cmp::Ordering::Less | core::cmp::Ordering::Equal)
            );
            if !self.factor(&st, &sc.w, &mut kkt) {
                return end(&best_x, best_merit, it, LpStatus::NumericalFailure);
            }
            // predictor (affine scaling)
            // (its accuracy only steers the centring: no refinement)
            let aff = self.direction(&st, &kkt, &sc, &Rhs { d: &r_d, p: &r_p, g: &r_g, c: &r_c }, false);
            let ap = max_step(s.get(..nr).unwrap_or(&[]), aff.ds.get(..nr).unwrap_or(&[]));
            let ad = max_step(z.get(..nr).unwrap_or(&[]), aff.dz.get(..nr).unwrap_or(&[]));
            let mut mu_aff = 0.0;
            for i in 0..nr {
                mu_aff += (vec_get(&s, i) + vec_get(&aff.ds, i) * ap) * (vec_get(&z, i) + vec_get(&aff.dz, i) * ad);
            }
            let mu_aff = mu_aff / rows;
            let ratio = mu_aff / mu;
            let sigma = (ratio * ratio * ratio).clamp(0.0, 1.0);
            // corrector
            for i in 0..nr {
                vec_set(&mut r_c, i, vec_get(&s, i) * vec_get(&z, i) + vec_get(&aff.ds, i) * vec_get(&aff.dz, i) - sigma * mu);
            }
            let d = self.direction(&st, &kkt, &sc, &Rhs { d: &r_d, p: &r_p, g: &r_g, c: &r_c }, refine);
            let ap = (0.99 * max_step(s.get(..nr).unwrap_or(&[]), d.ds.get(..nr).unwrap_or(&[]))).min(1.0);
            let ad = (0.99 * max_step(z.get(..nr).unwrap_or(&[]), d.dz.get(..nr).unwrap_or(&[]))).min(1.0);
            for (xi, dxi) in x.iter_mut().zip(d.dx.iter()).take(nv) {
                *xi += dxi * ap;
            }
            for (si, dsi) in s.iter_mut().zip(d.ds.iter()).take(nr) {
                *si += dsi * ap;
            }
            y += d.dy * ad;
            for (zi, dzi) in z.iter_mut().zip(d.dz.iter()).take(nr) {
                *zi += dzi * ad;
            }
        }
    }

    /// A compact primal vector in the original numbering (dropped variables are 0).
    fn expand(&self, st: &Structure<N, P, M>, xc: &[f64; N]) -> SVector<f64, N> {
        let mut x = SVector::<f64, N>::zeros();
        for (k, v) in xc.iter().enumerate().take(st.nv) {
            if let Some(e) = x.get_mut(st.var(k)) {
                *e = *v;
            }
        }
        x
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
