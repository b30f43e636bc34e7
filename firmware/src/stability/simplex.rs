//! The stability LP by a dense primal simplex on a condensed (Tucker) tableau: the flight core's first solver for
//! the margin LP of the module docs, with the interior-point method of [`super::lp`] as its fallback.
//!
//! Why a simplex here: the margin LP is small (at most [`LP_VARS`] variables, [`LP_EQS`] equations and
//! [`LP_INEQS`] inequalities, 14 x 6 x 27 for Axel's two wheel contacts) and its optimum is a vertex, so a few
//! dozen exchange steps on a table of a few hundred numbers replace ten to twenty interior-point iterations, each a
//! sparse Cholesky plus refinement (Chvatal, *Linear Programming*, 1983, ch. 2-3 and 8; the condensed tableau and its
//! exchange step: Dantzig and Thapa, *Linear Programming 1*, 1997, section 3.3).
//!
//! # Method
//! Problem: minimise `c'x` subject to `A x = b`, `G x <= h`, every `x` free. Each inequality row gets a slack
//! `g_i >= 0` (`G_i x + g_i = h_i`) and each equation an artificial `a_p >= 0`; the table holds one row per basic
//! variable and one column per nonbasic variable, `x_B(i) + sum_j T_ij x_N(j) = rhs_i`.
//! 1. **Compaction**: variables no constraint and no cost mentions (unused contact slots) and rows `0 <= h` with
//!    `h >= 0` are left out; a row `0 <= h` with `h < 0` or `0 = b` with `b != 0` is infeasible at once.
//! 2. **Phase 0**: the free variables enter the basis, first on the equations (complete pivoting: the largest
//!    `|T|` over equation rows and free columns each time, i.e. Gaussian elimination of `A`), then on the
//!    inequalities (largest `|T|` again). An equation left without a pivot is a dependent row: dropped if its
//!    right-hand side is zero to `EQ_TOL`, infeasible otherwise. A free variable's row is never a ratio-test row.
//!    The artificials pivoted out are then dropped from the table. The free variables' rows then leave the table's active part: they are never ratio-test rows, and each
//!    variable is read off its row at the end from the final values of phase 0's nonbasic slacks.
//! 3. **Phase 1** (only if a slack is negative): one artificial column `t`, `-1` in every violated row, enters on
//!    the most violated row, which makes every row feasible; the primal simplex then minimises `t`. A positive
//!    minimum means no equilibrium exists ([`LpStatus::Infeasible`]).
//! 4. **Phase 2**: the primal simplex on `c'x`. Entering column: the most negative reduced cost (Dantzig); after
//!    `DEGENERATE_RUN` degenerate exchanges in a row, Bland's rule (smallest index) until a step makes progress, so
//!    the method cannot cycle. Leaving row: the smallest ratio, ties to the largest pivot (Bland: smallest index).
//! 5. **Check**: the solution's residuals are computed from the original `A, b, G, h`; if an equation is off by
//!    more than `CHECK_TOL (1 + |b|)` or an inequality by more than `CHECK_TOL (1 + |h|)`, the solve reports
//!    [`LpStatus::NumericalFailure`] and the caller falls back to the interior-point method.
//!
//! Every loop is bounded: phase 0 by the number of variables, phases 1 and 2 by the pivot budget
//! (`config::stability::SIMPLEX_MAX_PIVOTS`, default 200; [`LpStatus::BudgetExhausted`] when it runs out).
//! Tolerances (absolute: the LP's numbers are O(1) because forces are in rover weights): `PIVOT_TOL = 1e-9`,
//! `FEAS_TOL = 1e-10`, `OPT_TOL = 1e-11`, `EQ_TOL = 1e-9`, `CHECK_TOL = 1e-7`; `DEGENERATE_RUN = 8`.
//! Storage: the table, `LP_EQS + LP_INEQS` rows of `LP_VARS + 1` `f64` rounded up to a multiple of four (73 x 28,
//! 16.0 KiB), on the stack and zeroed once per solve; no heap.
//!
//! # Cost
//! The LP's dense `A` and `G` are read once, in the compaction: each live variable's column is written into the
//! table as it is scanned (four zero coefficients in a row are passed over by one test), and the rows nothing was
//! written to are then left out. From there on only the table's active part is touched (`nr` rows, `nc`
//! columns). An exchange divides the pivot row by the pivot once (one reciprocal), then updates every other row
//! whose pivot-column entry is nonzero: by the pivot row's nonzeros when they are few (under 30 % of the columns),
//! otherwise four columns a step over whole groups of four (the pivot row is zero past column `nc`, so the padding
//! entries stay as they are). Phase 1's objective row is updated only while phase 1 runs, and the residual check
//! skips zero coefficients. Per solve on the emulated board: `host-sim/doc/board_test3.md`.

use super::lp::{LpSolution, LpStatus};
use super::{StabilityLp, LP_EQS, LP_INEQS, LP_VARS};
use nalgebra::SVector;

const ROWS: usize = LP_EQS + LP_INEQS;
/// The `LP_VARS + 1` columns a table can use, rounded up to whole groups of four (the exchange updates four
/// columns a step; the pivot row is zero in the columns past the table's last).
const COLS: usize = (LP_VARS + 1).div_ceil(4) * 4;

/// Smallest `|T|` accepted as a pivot.
const PIVOT_TOL: f64 = 1e-9;
/// A basic nonnegative variable above `-FEAS_TOL` counts as feasible.
const FEAS_TOL: f64 = 1e-10;
/// A reduced cost below `-OPT_TOL` can still improve the objective.
const OPT_TOL: f64 = 1e-11;
/// A dependent equation whose right-hand side is within this of zero is dropped, otherwise infeasible.
const EQ_TOL: f64 = 1e-9;
/// Residual check of the solution against the original data (relative to `1 + |rhs|`).
const CHECK_TOL: f64 = 1e-7;
/// Degenerate exchanges in a row before Bland's rule takes over.
const DEGENERATE_RUN: u32 = 8;

/// A variable of the table: an LP variable (free), the slack of an inequality, the artificial of an equation, or
/// the phase-1 artificial.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Var {
    X(u16),
    Slack(u16),
    Art(u16),
    T,
    /// A column or row slot not in use.
    None,
}

impl Var {
    /// Bland's order.
    fn key(self) -> usize {
        match self {
            Var::X(j) => usize::from(j),
            Var::Slack(i) => LP_VARS + usize::from(i),
            Var::Art(p) => LP_VARS + LP_INEQS + usize::from(p),
            Var::T => LP_VARS + LP_INEQS + LP_EQS,
            Var::None => usize::MAX,
        }
    }
}

/// The `LP_VARS` columns of a column-major matrix with `rows` rows (as `chunks_exact`, whose length division is
/// a panic path the flight build refuses).
fn columns(m: &[f64], rows: usize) -> impl Iterator<Item = &[f64]> {
    (0..LP_VARS).map(move |j| m.get(j * rows..(j + 1) * rows).unwrap_or(&[]))
}

/// `v != 0.0` by its bits (both zeros have only the sign bit set at most).
fn nonzero(v: f64) -> bool {
    v.to_bits() << 1 != 0
}

/// `f(i, col[i])` for each nonzero entry of `col`, in order; four zeros in a row (most of a column of the LP) are
/// passed over by one test.
#[inline(always)]
fn for_nonzeros(col: &[f64], mut f: impl FnMut(usize, f64)) {
    let (c4, c1) = col.as_chunks::<4>();
    for (g, c) in c4.iter().enumerate() {
        if (c[0].to_bits() | c[1].to_bits() | c[2].to_bits() | c[3].to_bits()) << 1 != 0 {
            for (i, v) in c.iter().enumerate() {
                if nonzero(*v) {
                    f(4 * g + i, *v);
                }
            }
        }
    }
    let base = 4 * c4.len();
    for (i, v) in c1.iter().enumerate() {
        if nonzero(*v) {
            f(base + i, *v);
        }
    }
}

fn u16_of(i: usize) -> u16 {
    u16::try_from(i).unwrap_or(u16::MAX)
}

/// The condensed tableau with its two objective rows.
struct Tableau<'a> {
    /// Lent by [`solve_until`] (a 16 KiB table is not moved around): `ROWS` rows.
    t: &'a mut [[f64; COLS]],
    rhs: [f64; ROWS],
    basic: [Var; ROWS],
    nonbasic: [Var; COLS],
    /// Nonbasic columns fixed at zero for good (an artificial that left the basis).
    dead: [bool; COLS],
    /// Phase-2 objective row: `-w + sum_j cost_j x_N(j) = cost_rhs`.
    cost: [f64; COLS],
    cost_rhs: f64,
    /// Phase-1 objective row (the artificial `t`).
    p1: [f64; COLS],
    p1_rhs: f64,
    /// Phase 1 is running: its objective row is updated (zero before, not read after).
    p1_live: bool,
    nr: usize,
    nc: usize,
    pivots: u32,
    /// The current exchange's pivot row (kept here: not zeroed again for every exchange).
    prow: PivotRow,
}

/// Why a phase stopped before its optimum.
enum Stop {
    /// Phase 2 reached a vertex with the objective at most the target.
    Target,
    Budget,
    Unbounded,
}

fn get(v: &[f64], i: usize) -> f64 {
    v.get(i).copied().unwrap_or(0.0)
}

/// The pivot row of an exchange, divided by the pivot, with the pivot column's entry left out (the other rows'
/// pivot column is set apart): dense (`v`, columns `..nc`) and as its nonzeros (`idx`, `val`, `m` of them), so
/// that a sparse pivot row updates only the columns it touches.
struct PivotRow {
    v: [f64; COLS],
    idx: [u8; COLS],
    val: [f64; COLS],
    m: usize,
    /// Groups of four columns covering the columns in use (`Tableau::nc`); `v` is zero past `nc`.
    q: usize,
    /// Update by the nonzeros (`true`) or the whole row.
    sparse: bool,
    k: usize,
    inv_p: f64,
    rhs: f64,
}

impl PivotRow {
    const EMPTY: Self =
        PivotRow { v: [0.0; COLS], idx: [0; COLS], val: [0.0; COLS], m: 0, q: 0, sparse: false, k: 0, inv_p: 0.0, rhs: 0.0 };

    /// `row -= f * pivot_row` with `f = row_k`, and `row_k = -f / p`. A column where the pivot row is zero is
    /// left as it is (`a - f 0 = a`). Inlined into [`Self::apply_rows`], its one caller.
    #[inline(always)]
    fn apply(&self, row: &mut [f64; COLS], rhs: &mut f64) {
        let f = get(row, self.k);
        if f == 0.0 {
            return;
        }
        if self.sparse {
            let (idx, val) = (self.idx.get(..self.m).unwrap_or(&[]), self.val.get(..self.m).unwrap_or(&[]));
            for (j, b) in idx.iter().zip(val) {
                if let Some(a) = row.get_mut(usize::from(*j)) {
                    *a -= f * b;
                }
            }
        } else if let (Some(row4), Some(v4)) =
            (row.as_chunks_mut::<4>().0.get_mut(..self.q), self.v.as_chunks::<4>().0.get(..self.q))
        {
            // four columns a step (the loads and stores pair up, the loop's bookkeeping is shared); past the
            // table's last column `v` is zero, which leaves those entries as they are
            for (a, b) in row4.iter_mut().zip(v4) {
                a[0] -= f * b[0];
                a[1] -= f * b[1];
                a[2] -= f * b[2];
                a[3] -= f * b[3];
            }
        }
        if let Some(a) = row.get_mut(self.k) {
            *a = -f * self.inv_p;
        }
        *rhs -= f * self.rhs;
    }

    /// [`Self::apply`] to every row of `rows` (right-hand sides `rhs`).
    fn apply_rows(&self, rows: &mut [[f64; COLS]], rhs: &mut [f64]) {
        for (row, b) in rows.iter_mut().zip(rhs.iter_mut()) {
            self.apply(row, b);
        }
    }
}

impl Tableau<'_> {
    fn entry(&self, r: usize, k: usize) -> f64 {
        self.t.get(r).and_then(|row| row.get(k)).copied().unwrap_or(0.0)
    }

    fn basic_of(&self, r: usize) -> Var {
        self.basic.get(r).copied().unwrap_or(Var::None)
    }

    fn nonbasic_of(&self, k: usize) -> Var {
        self.nonbasic.get(k).copied().unwrap_or(Var::None)
    }

    fn is_dead(&self, k: usize) -> bool {
        self.dead.get(k).copied().unwrap_or(true)
    }

    /// Exchange the basic variable of row `r` with the nonbasic variable of column `k`.
    fn pivot(&mut self, r: usize, k: usize) {
        let nc = self.nc.min(COLS);
        let inv_p = 1.0 / self.entry(r, k);
        let prow = &mut self.prow;
        prow.q = nc.div_ceil(4);
        prow.k = k;
        prow.inv_p = inv_p;
        prow.rhs = get(&self.rhs, r) * inv_p;
        prow.m = 0;
        if let Some(row) = self.t.get_mut(r) {
            for (j, (a, v)) in row.iter_mut().zip(prow.v.iter_mut()).enumerate().take(nc) {
                *a *= inv_p;
                *v = *a;
                if j != k && nonzero(*a) {
                    if let (Some(i), Some(w)) = (prow.idx.get_mut(prow.m), prow.val.get_mut(prow.m)) {
                        *i = u8::try_from(j).unwrap_or(u8::MAX);
                        *w = *a;
                        prow.m += 1;
                    }
                }
            }
            if let Some(a) = prow.v.get_mut(k) {
                *a = 0.0;
            }
            for a in prow.v.iter_mut().take(4 * prow.q).skip(nc) {
                *a = 0.0;
            }
            if let Some(a) = row.get_mut(k) {
                *a = inv_p;
            }
        }
        // a sparse update costs about three times as much per entry as a dense one
        prow.sparse = 10 * prow.m < 12 * prow.q;
        if let Some(v) = self.rhs.get_mut(r) {
            *v = prow.rhs;
        }
        let nr = self.nr.min(ROWS);
        if let (Some(t), Some(rhs)) = (self.t.get_mut(..nr), self.rhs.get_mut(..nr)) {
            if let (Some((t_lo, t_hi)), Some((rhs_lo, rhs_hi))) = (t.split_at_mut_checked(r), rhs.split_at_mut_checked(r)) {
                prow.apply_rows(t_lo, rhs_lo);
                if let (Some(t_hi), Some(rhs_hi)) = (t_hi.get_mut(1..), rhs_hi.get_mut(1..)) {
                    prow.apply_rows(t_hi, rhs_hi);
                }
            }
        }
        prow.apply_rows(core::slice::from_mut(&mut self.cost), core::slice::from_mut(&mut self.cost_rhs));
        if self.p1_live {
            prow.apply_rows(core::slice::from_mut(&mut self.p1), core::slice::from_mut(&mut self.p1_rhs));
        }
        let leaving = self.basic_of(r);
        let entering = self.nonbasic_of(k);
        if let Some(b) = self.basic.get_mut(r) {
            *b = entering;
        }
        if let Some(n) = self.nonbasic.get_mut(k) {
            *n = leaving;
        }
        if let Some(d) = self.dead.get_mut(k) {
            *d = matches!(leaving, Var::Art(_) | Var::T);
        }
        self.pivots = self.pivots.saturating_add(1);
    }

    /// Append a row (its coefficients are filled in afterwards).
    fn push_row(&mut self, rhs: f64, var: Var) {
        if let (Some(r), Some(b)) = (self.rhs.get_mut(self.nr), self.basic.get_mut(self.nr)) {
            *r = rhs;
            *b = var;
            self.nr += 1;
        }
    }

    /// Remove the dead columns (the artificials phase 0 pivoted out), so that later exchanges do not update them.
    fn drop_dead_columns(&mut self) {
        let mut keep = [0usize; COLS];
        let mut n = 0;
        for (k, d) in self.dead.iter().enumerate().take(self.nc) {
            if !*d {
                if let Some(slot) = keep.get_mut(n) {
                    *slot = k;
                    n += 1;
                }
            }
        }
        let keep = keep.get(..n).unwrap_or(&[]);
        // kept columns only move left (`dst <= src`), so one forward pass is enough
        let squeeze = |row: &mut [f64; COLS]| {
            for (dst, src) in keep.iter().enumerate() {
                let v = get(row, *src);
                if let Some(e) = row.get_mut(dst) {
                    *e = v;
                }
            }
        };
        for row in self.t.iter_mut().take(self.nr) {
            squeeze(row);
        }
        squeeze(&mut self.cost);
        squeeze(&mut self.p1);
        for (dst, src) in keep.iter().enumerate() {
            let v = self.nonbasic_of(*src);
            if let Some(e) = self.nonbasic.get_mut(dst) {
                *e = v;
            }
        }
        self.dead = [false; COLS];
        self.nc = n;
    }

    /// Exchange rows `a` and `b` (table, right-hand side, basic variable); nothing when either is out of range.
    fn swap_rows(&mut self, a: usize, b: usize) {
        if a < ROWS && b < ROWS && a < self.t.len() && b < self.t.len() {
            self.t.swap(a, b);
            self.rhs.swap(a, b);
            self.basic.swap(a, b);
        }
    }

    /// Remove row `r` (a dependent equation), keeping the others in place order-free.
    fn drop_row(&mut self, r: usize) {
        let last = self.nr.saturating_sub(1);
        if r < last {
            self.swap_rows(r, last);
        }
        self.nr = last;
    }

    /// Is row `r` a ratio-test row (its basic variable is nonnegative)?
    fn bounded_row(&self, r: usize) -> bool {
        matches!(self.basic_of(r), Var::Slack(_) | Var::T)
    }

    /// The equation row and free column with the largest `|T_rk|` (complete pivoting over the equations).
    fn best_equation_pivot(&self) -> Option<(usize, usize)> {
        let mut free = [false; COLS];
        for (f, v) in free.iter_mut().zip(self.nonbasic.iter()).take(self.nc) {
            *f = matches!(v, Var::X(_));
        }
        let mut best = (PIVOT_TOL, None);
        for (r, (row, b)) in self.t.iter().zip(self.basic.iter()).enumerate().take(self.nr) {
            if !matches!(b, Var::Art(_)) {
                continue;
            }
            for (k, (v, f)) in row.iter().zip(free.iter()).enumerate().take(self.nc) {
                if *f && v.abs() > best.0 {
                    best = (v.abs(), Some((r, k)));
                }
            }
        }
        best.1
    }

    /// The inequality row with the largest `|T_rk|` in column `k` (partial pivoting).
    fn best_inequality_row(&self, k: usize) -> Option<usize> {
        let mut best = (PIVOT_TOL, None);
        for (r, (row, b)) in self.t.iter().zip(self.basic.iter()).enumerate().take(self.nr) {
            let v = row.get(k).copied().unwrap_or(0.0).abs();
            if matches!(b, Var::Slack(_)) && v > best.0 {
                best = (v, Some(r));
            }
        }
        best.1
    }

    /// Primal simplex on the phase-1 (`phase1`) or phase-2 objective row, from a feasible basis. Stops at an
    /// optimum (`Ok`), when `t` leaves the basis in phase 1 (`Ok`), or with the reason.
    fn optimise(&mut self, phase1: bool, max_pivots: u32, target: Option<f64>) -> Result<(), Stop> {
        let mut degenerate = 0u32;
        loop {
            if phase1 && !self.basic.iter().take(self.nr).any(|b| *b == Var::T) {
                return Ok(());
            }
            // the vertex's objective is `-cost_rhs` (all nonbasic variables at zero)
            if matches!(target, Some(t) if -self.cost_rhs <= t) {
                return Err(Stop::Target);
            }
            let bland = degenerate >= DEGENERATE_RUN;
            // entering column
            let obj = if phase1 { &self.p1 } else { &self.cost };
            let mut enter: Option<usize> = None;
            let mut best = -OPT_TOL;
            for (k, d) in obj.iter().enumerate().take(self.nc) {
                if self.is_dead(k) || !matches!(self.nonbasic_of(k), Var::Slack(_)) || *d >= -OPT_TOL {
                    continue;
                }
                let better = match enter {
                    None => true,
                    Some(e) if bland => self.nonbasic_of(k).key() < self.nonbasic_of(e).key(),
                    Some(_) => *d < best,
                };
                if better {
                    best = *d;
                    enter = Some(k);
                }
            }
            let Some(k) = enter else { return Ok(()) };
            // leaving row
            let mut leave: Option<(usize, f64, f64)> = None;
            let rows = self.t.iter().zip(self.rhs.iter()).zip(self.basic.iter()).enumerate().take(self.nr);
            for (r, ((row, rhs), b)) in rows {
                if !matches!(b, Var::Slack(_) | Var::T) {
                    continue;
                }
                let a = get(row, k);
                if a <= PIVOT_TOL {
                    continue;
                }
                let ratio = rhs.max(0.0) / a;
                let better = match leave {
                    None => true,
                    Some((lr, lratio, la)) => {
                        if ratio < lratio - 1e-12 {
                            true
                        } else if ratio <= lratio + 1e-12 {
                            if bland {
                                self.basic_of(r).key() < self.basic_of(lr).key()
                            } else {
                                a > la
                            }
                        } else {
                            false
                        }
                    }
                };
                if better {
                    leave = Some((r, ratio, a));
                }
            }
            let Some((r, ratio, _)) = leave else { return Err(Stop::Unbounded) };
            if self.pivots >= max_pivots {
                return Err(Stop::Budget);
            }
            if ratio <= FEAS_TOL {
                degenerate = degenerate.saturating_add(1);
            } else {
                degenerate = 0;
            }
            self.pivot(r, k);
        }
    }
}

/// Solve the stability LP `lp` with at most `max_pivots` exchanges (see the module docs). Never panics; every
/// non-optimal end is a status.
pub fn solve(lp: &StabilityLp, max_pivots: u32) -> LpSolution<LP_VARS> {
    solve_until(lp, max_pivots, None)
}

/// [`solve`], but phase 2 stops at the first vertex whose objective is at most `target`
/// ([`LpStatus::TargetReached`]: a feasible point, checked like an optimum, not necessarily optimal). Phase 2
/// never raises the objective, so when the optimum is above the target the answer is [`solve`]'s.
pub fn solve_until(lp: &StabilityLp, max_pivots: u32, target: Option<f64>) -> LpSolution<LP_VARS> {
    // one flat array: zeroed in one piece
    let mut flat = [0.0; ROWS * COLS];
    let (table, _) = flat.as_chunks_mut::<COLS>();
    let mut tab = Tableau {
        t: table,
        rhs: [0.0; ROWS],
        basic: [Var::None; ROWS],
        nonbasic: [Var::None; COLS],
        dead: [false; COLS],
        cost: [0.0; COLS],
        cost_rhs: 0.0,
        p1: [0.0; COLS],
        p1_rhs: 0.0,
        p1_live: false,
        nr: 0,
        nc: 0,
        pivots: 0,
        prow: PivotRow::EMPTY,
    };
    let fail = |status: LpStatus, pivots: u32| LpSolution {
        status,
        x: SVector::<f64, LP_VARS>::zeros(),
        objective: 0.0,
        iterations: pivots,
    };
    // 1. compaction and fill in one pass over the dense data (column-major: one slice chunk per variable). Table
    // row `p` is equation `p` (its sign chosen so that the artificial starts nonnegative), row `LP_EQS + i`
    // inequality `i`; a variable's column is written at the next free slot and kept if the variable is live (a
    // dead column wrote nothing). Then the rows nothing was written to are left out, the others moved up in order.
    let mut sign = [1.0; LP_EQS];
    for (s, b) in sign.iter_mut().zip(lp.b.as_slice()) {
        if *b < 0.0 {
            *s = -1.0;
        }
    }
    let mut row_live = [false; ROWS];
    let (eq_live, in_live) = row_live.split_at_mut(LP_EQS);
    let (eq_rows, in_rows) = tab.t.split_at_mut(LP_EQS);
    for (j, ((ac, gc), c)) in columns(lp.a.as_slice(), LP_EQS)
        .zip(columns(lp.g.as_slice(), LP_INEQS))
        .zip(lp.c.as_slice())
        .enumerate()
    {
        let k = tab.nc;
        let mut live = *c != 0.0;
        for_nonzeros(ac, |p, v| {
            if let Some(e) = eq_rows.get_mut(p).and_then(|row| row.get_mut(k)) {
                *e = get(&sign, p) * v;
            }
            if let Some(l) = eq_live.get_mut(p) {
                *l = true;
            }
            live = true;
        });
        for_nonzeros(gc, |i, v| {
            if let Some(e) = in_rows.get_mut(i).and_then(|row| row.get_mut(k)) {
                *e = v;
            }
            if let Some(l) = in_live.get_mut(i) {
                *l = true;
            }
            live = true;
        });
        if live {
            if let (Some(n), Some(cst)) = (tab.nonbasic.get_mut(k), tab.cost.get_mut(k)) {
                *n = Var::X(u16_of(j));
                *cst = *c;
            }
            tab.nc += 1;
        }
    }
    for (src, live) in row_live.iter().enumerate() {
        let (rhs, var) = match src.checked_sub(LP_EQS) {
            None => (get(&sign, src) * get(lp.b.as_slice(), src), Var::Art(u16_of(src))),
            Some(i) => (get(lp.h.as_slice(), i), Var::Slack(u16_of(i))),
        };
        if !*live {
            let bad = match var {
                Var::Art(_) => rhs.abs() > EQ_TOL,
                _ => rhs < -FEAS_TOL,
            };
            if bad {
                return fail(LpStatus::Infeasible, 0);
            }
            continue;
        }
        if src != tab.nr {
            // a later row moves up; its old slot is past the table's rows from now on
            if let Some(row) = tab.t.get(src).copied() {
                if let Some(dst) = tab.t.get_mut(tab.nr) {
                    *dst = row;
                }
            }
        }
        tab.push_row(rhs, var);
    }
    // 2. phase 0: free variables into the basis, equations first (complete pivoting)
    while let Some((r, k)) = tab.best_equation_pivot() {
        tab.pivot(r, k);
    }
    let mut r = 0;
    while r < tab.nr {
        if matches!(tab.basic_of(r), Var::Art(_)) {
            if get(&tab.rhs, r).abs() > EQ_TOL {
                return fail(LpStatus::Infeasible, tab.pivots);
            }
            tab.drop_row(r);
        } else {
            r += 1;
        }
    }
    tab.drop_dead_columns();
    for k in 0..tab.nc {
        if matches!(tab.nonbasic_of(k), Var::X(_)) {
            if let Some(r) = tab.best_inequality_row(k) {
                tab.pivot(r, k);
            }
        }
    }
    // a free variable left nonbasic has a zero column: with a cost the LP is unbounded
    for k in 0..tab.nc {
        if matches!(tab.nonbasic_of(k), Var::X(_)) && get(&tab.cost, k).abs() > OPT_TOL {
            return fail(LpStatus::NumericalFailure, tab.pivots);
        }
    }
    // The free variables' rows are never ratio-test rows: set them apart at the end of the table, out of the
    // exchanges of phases 1 and 2, and read the variables off them at the end (in terms of phase 0's nonbasic
    // variables, whose final values are then known).
    let mut end = tab.nr;
    let mut r = 0;
    while r < end {
        if matches!(tab.basic_of(r), Var::X(_)) {
            end -= 1;
            tab.swap_rows(r, end);
        } else {
            r += 1;
        }
    }
    let frozen = end..tab.nr;
    tab.nr = end;
    let (labels0, nc0) = (tab.nonbasic, tab.nc);
    let max_pivots = max_pivots.saturating_add(tab.pivots);
    // 3. phase 1
    let mut worst: Option<(usize, f64)> = None;
    for r in 0..tab.nr {
        let v = get(&tab.rhs, r);
        if tab.bounded_row(r) && v < -FEAS_TOL && worst.is_none_or(|(_, w)| v < w) {
            worst = Some((r, v));
        }
    }
    if let Some((wr, _)) = worst {
        let kt = tab.nc;
        if kt >= COLS {
            return fail(LpStatus::NumericalFailure, tab.pivots);
        }
        tab.nc += 1;
        for (r, row) in tab.t.iter_mut().enumerate().take(tab.nr) {
            let violated = matches!(tab.basic.get(r), Some(Var::Slack(_))) && get(&tab.rhs, r) < -FEAS_TOL;
            if let Some(e) = row.get_mut(kt) {
                *e = if violated { -1.0 } else { 0.0 };
            }
        }
        if let Some(n) = tab.nonbasic.get_mut(kt) {
            *n = Var::T;
        }
        if let Some(e) = tab.p1.get_mut(kt) {
            *e = 1.0;
        }
        tab.p1_live = true;
        tab.pivot(wr, kt);
        let phase1 = tab.optimise(true, max_pivots, None);
        tab.p1_live = false;
        match phase1 {
            Ok(()) | Err(Stop::Target) => {}
            Err(Stop::Budget) => return fail(LpStatus::BudgetExhausted, tab.pivots),
            Err(Stop::Unbounded) => return fail(LpStatus::NumericalFailure, tab.pivots),
        }
        // `t` still basic: infeasible if positive, else pivot it out (or drop its row if it has no live entry)
        if let Some(rt) = (0..tab.nr).find(|r| tab.basic_of(*r) == Var::T) {
            if get(&tab.rhs, rt) > FEAS_TOL {
                return fail(LpStatus::Infeasible, tab.pivots);
            }
            let mut best = (PIVOT_TOL, None);
            for k in 0..tab.nc {
                let a = tab.entry(rt, k).abs();
                if !tab.is_dead(k) && matches!(tab.nonbasic_of(k), Var::Slack(_)) && a > best.0 {
                    best = (a, Some(k));
                }
            }
            match best.1 {
                Some(k) => tab.pivot(rt, k),
                None => tab.drop_row(rt),
            }
        }
    }
    // 4. phase 2
    let status = match tab.optimise(false, max_pivots, target) {
        Ok(()) => LpStatus::Optimal,
        Err(Stop::Target) => LpStatus::TargetReached,
        Err(Stop::Budget) => return fail(LpStatus::BudgetExhausted, tab.pivots),
        Err(Stop::Unbounded) => return fail(LpStatus::NumericalFailure, tab.pivots),
    };
    let mut slack = [0.0; LP_INEQS];
    for r in 0..tab.nr {
        if let Var::Slack(i) = tab.basic_of(r) {
            if let Some(e) = slack.get_mut(usize::from(i)) {
                *e = get(&tab.rhs, r);
            }
        }
    }
    let mut x = SVector::<f64, LP_VARS>::zeros();
    for r in frozen {
        if let Var::X(j) = tab.basic_of(r) {
            let mut v = get(&tab.rhs, r);
            if let Some(row) = tab.t.get(r) {
                for (a, label) in row.iter().zip(labels0.iter()).take(nc0) {
                    if let Var::Slack(i) = label {
                        v -= a * get(&slack, usize::from(*i));
                    }
                }
            }
            if let Some(e) = x.get_mut(usize::from(j)) {
                *e = v;
            }
        }
    }
    // 5. check against the original data
    let mut r_a = [0.0; LP_EQS];
    let mut r_g = [0.0; LP_INEQS];
    for (r, b) in r_a.iter_mut().zip(lp.b.as_slice()).chain(r_g.iter_mut().zip(lp.h.as_slice())) {
        *r = -b;
    }
    for ((ac, gc), xj) in columns(lp.a.as_slice(), LP_EQS).zip(columns(lp.g.as_slice(), LP_INEQS)).zip(x.as_slice()) {
        // zero coefficients (most of them) leave the residual as it is
        if *xj != 0.0 {
            for_nonzeros(ac, |p, a| {
                if let Some(r) = r_a.get_mut(p) {
                    *r += a * xj;
                }
            });
            for_nonzeros(gc, |i, a| {
                if let Some(r) = r_g.get_mut(i) {
                    *r += a * xj;
                }
            });
        }
    }
    let ok_eq = r_a.iter().zip(lp.b.as_slice()).all(|(r, b)| r.abs() <= CHECK_TOL * (1.0 + b.abs()));
    let ok_in = r_g.iter().zip(lp.h.as_slice()).all(|(r, h)| *r <= CHECK_TOL * (1.0 + h.abs()));
    let objective = lp.c.dot(&x);
    if !(ok_eq && ok_in && objective.is_finite()) {
        return fail(LpStatus::NumericalFailure, tab.pivots);
    }
    if status == LpStatus::TargetReached && objective > target.unwrap_or(f64::NEG_INFINITY) {
        // read back from the rows, the vertex's objective missed the target by round-off: finish the solve
        return solve_until(lp, max_pivots, None);
    }
    LpSolution { status, x, objective, iterations: tab.pivots }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn set(m: &mut StabilityLp, row: usize, coeffs: &[f64], h: f64) {
        for (j, v) in coeffs.iter().enumerate() {
            m.g[(row, j)] = *v;
        }
        m.h[row] = h;
    }

    /// Beale's example (1955), on which Dantzig's rule with the smallest-index tie-break cycles for ever, must reach
    /// its optimum -1/20 at x = (1/25, 0, 1, 0). (It does so here even without the switch to Bland's rule: the
    /// largest-pivot tie-break and phase 0's start avoid that cycle.)
    #[test]
    fn beales_cycling_example_reaches_its_optimum() {
        let mut lp = StabilityLp::zeros();
        lp.c[0] = -0.75;
        lp.c[1] = 150.0;
        lp.c[2] = -0.02;
        lp.c[3] = 6.0;
        set(&mut lp, 0, &[0.25, -60.0, -0.04, 9.0], 0.0);
        set(&mut lp, 1, &[0.5, -90.0, -0.02, 3.0], 0.0);
        set(&mut lp, 2, &[0.0, 0.0, 1.0, 0.0], 1.0);
        for j in 0..4 {
            lp.g[(3 + j, j)] = -1.0;
        }
        let sol = solve(&lp, 200);
        assert_eq!(sol.status, LpStatus::Optimal, "{sol:?}");
        assert!((sol.objective + 0.05).abs() < 1e-12, "{}", sol.objective);
        for (j, want) in [0.04, 0.0, 1.0, 0.0].iter().enumerate() {
            assert!((sol.x[j] - want).abs() < 1e-12, "x{j} = {}", sol.x[j]);
        }
    }

    /// `x + y = 1`, `x, y >= 0`, `x >= 2`: no point; and `0 = 1` (a variable-free equation).
    #[test]
    fn an_infeasible_lp_is_reported_infeasible() {
        let mut lp = StabilityLp::zeros();
        lp.a[(0, 0)] = 1.0;
        lp.a[(0, 1)] = 1.0;
        lp.b[0] = 1.0;
        lp.c[0] = 1.0;
        set(&mut lp, 0, &[-1.0, 0.0], 0.0);
        set(&mut lp, 1, &[0.0, -1.0], 0.0);
        set(&mut lp, 2, &[-1.0, 0.0], -2.0);
        assert_eq!(solve(&lp, 200).status, LpStatus::Infeasible);
        let mut lp = StabilityLp::zeros();
        lp.b[3] = 1.0;
        assert_eq!(solve(&lp, 200).status, LpStatus::Infeasible);
    }

    /// max x + y s.t. x + 2y <= 4, 3x + y <= 6, x, y >= 0 (written -10x <= 0, -10y <= 0 so that phase 0 starts
    /// at the origin): optimum 2.8 at (1.6, 1.2).
    fn two_variable_lp() -> StabilityLp {
        let mut lp = StabilityLp::zeros();
        lp.c[0] = -1.0;
        lp.c[1] = -1.0;
        set(&mut lp, 0, &[1.0, 2.0], 4.0);
        set(&mut lp, 1, &[3.0, 1.0], 6.0);
        set(&mut lp, 2, &[-10.0, 0.0], 0.0);
        set(&mut lp, 3, &[0.0, -10.0], 0.0);
        lp
    }

    /// [`two_variable_lp`]: with a target of -1 the solve stops early at a feasible vertex
    /// at least that good; with a target below the optimum it solves to the optimum.
    #[test]
    fn solve_until_stops_at_the_first_vertex_that_meets_the_target() {
        let lp = two_variable_lp();
        let full = solve(&lp, 200);
        assert_eq!(full.status, LpStatus::Optimal);
        assert!((full.objective + 2.8).abs() < 1e-12 && (full.x[0] - 1.6).abs() < 1e-12 && (full.x[1] - 1.2).abs() < 1e-12);
        let early = solve_until(&lp, 200, Some(-1.0));
        assert_eq!(early.status, LpStatus::TargetReached, "{early:?}");
        assert!(early.objective <= -1.0 && early.objective > full.objective - 1e-12, "{}", early.objective);
        let (x, y) = (early.x[0], early.x[1]);
        assert!(x >= -1e-12 && y >= -1e-12 && x + 2.0 * y <= 4.0 + 1e-12 && 3.0 * x + y <= 6.0 + 1e-12);
        assert!(early.iterations < full.iterations);
        let unreachable = solve_until(&lp, 200, Some(-3.0));
        assert_eq!(unreachable.status, LpStatus::Optimal);
        assert_eq!(unreachable.objective, full.objective);
    }

    /// A budget too small for phase 2 is reported, not a wrong optimum.
    #[test]
    fn budget_exhaustion_is_reported() {
        assert_eq!(solve(&two_variable_lp(), 0).status, LpStatus::BudgetExhausted);
    }
}
