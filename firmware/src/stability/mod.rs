//! Tether-based static stability (Paton et al., *Navigation on the Line*, section IV-C, Fig. 6, eqs. 1-9).
//!
//! Given a settled pose's ground contacts, the two body masses and the tether (exit point on the boom and the
//! direction to the most recent anchor of the anchor history), decide whether contact and tether forces exist that
//! hold the rover in static equilibrium, and how much friction headroom the best such forces leave.
//!
//! # Model (eqs. 1-8)
//! Each contact `i` carries a full wrench `(lambda_i, M_i)` in its contact frame (z along the contact normal, x and y
//! tangent): `lambda_z >= 0` (1), friction (2, 3), moment limits
//! `|M_x|, |M_y|, |M_z| <= mu_m lambda_z` (4-6) (a contact patch; a contact with `mu_m = 0` is a point
//! contact and carries no moment). A wheel's contact is a **line** ([`Contact::line`]): a rigid rim touches the
//! ground along a line parallel to the axle (contact-frame y), which carries moments about the rolling direction
//! (its width) and the normal but none about the axle, so `M_y = 0` (eq. 5 with `mu_m = 0`). Paton's patch moment
//! about the axle is the resistance of grousers dug into soil, which rigid wheels on rock do not have; poses the
//! planner held only by it slid in the physics judge (`host-sim/doc/physics_judge.md`). A wheel whose axle is
//! tilted against its contact plane touches it on one rim edge, a point: `rover::stability_problem` gives it no
//! moments (the rim lies flat when its far edge is within the settle's contact threshold). The tether pulls at
//! the exit point `r_t` along the unit direction to the last anchor with tension `0 <= T <= T_max` (a slack
//! tether has `T = 0`). Force (7) and moment (8) balance include both body masses `m_1 g`, `m_2 g` at their
//! centres of mass `r_1`, `r_2`. Moments are taken about the combined centre
//! of mass; all forces are divided by the total weight `W = (m_1 + m_2) |g|`, so the numbers are O(1).
//!
//! # Friction: an octagon inscribed in Coulomb's cone
//! Coulomb's law bounds the tangential force by a cone, `|lambda_t| <= mu lambda_z`. Paton's eqs. 2-3 bound each
//! tangent component alone, `|lambda_x|, |lambda_y| <= mu lambda_z`: a square pyramid whose corners reach `sqrt(2)
//! mu lambda_z`, 41 % beyond the cone, wherever the friction the pose needs points diagonally in the contact frame
//! (a rover standing across a slope). The physics judge (Coulomb cones) found planner-stable Mars Yard poses that
//! slid for exactly that reason, so the LP uses the **inscribed octagon** instead: `u_k . lambda_t <= cos(pi/8) mu
//! lambda_z` for the eight directions `u_k = (cos k pi/4, sin k pi/4)`. It lies between the cone shrunk to `cos(pi/8)
//! mu` (0.924) and the cone itself, so the LP never claims friction Coulomb's law does not give and loses at most
//! 7.6 % of it (`tests/tests/stability.rs` checks both bounds against a second-order-cone solve).
//!
//! # Objective: a convex replacement of (9)
//! The paper's objective (9), `sum (lambda_x^2 + lambda_y^2) / mu^2 - 2 lambda_z^2 + sum |M|^2 / mu_m^2 -
//! 3 lambda_z^2`, is not convex (the `-lambda_z^2` terms), so a local solver can stop anywhere. We keep its intent —
//! prefer the forces with the most headroom on the friction octagons and moment boxes — with a linear program:
//!
//! maximise `s` subject to (1), (7), (8), `0 <= T <= T_max`, and for every contact
//! `u_k . lambda_t <= cos(pi/8) (mu lambda_z - s)` (the octagon), `+-M_k <= mu_m lambda_z - l s` with
//! `l = mu_m / mu` (metres, so that moment headroom is measured in the same units), `lambda_z <= NORMAL_FORCE_CAP`
//! (a load limit of 10 rover weights per contact: without it, two opposed contacts (a wedge) admit unbounded
//! squeezing forces and the LP becomes badly conditioned), and `s <= 1`.
//!
//! `s*` (the **margin**, a fraction of the rover's weight) is the largest friction headroom that every octagon facet
//! of every contact can keep at once. The boom's tip ([`Contact::tip`]) is held to its octagon without `s`: it
//! carries about the boom's share of the weight, and headroom taken from it would cap every margin of a rover resting
//! on its boom at `mu` times that share (`host-sim/doc/physics_judge.md`). The verdict (`s* >= 0`) is the same
//! either way; the LP is then infeasible when the tip cannot hold with its own friction (unstable too). The pose is statically stable exactly when `s* >= 0` (the feasibility problem of
//! eqs. 1-8 is the `s = 0` slice), and the pose is stable with a safety buffer when `s* >= MIN_MARGIN`. A larger margin
//! means the pose tolerates a larger error in the friction coefficients: lowering every `mu lambda_z` limit by
//! `s* W` newtons keeps it stable. The LP is always feasible when the equilibrium equations can be met (take `s`
//! very negative), and bounded (`s <= 1`), so "no optimum" can only mean bad numerics or a problem with no
//! equilibrium at all; both end as [`StabilityOutcome::Unknown`], which callers must treat as unstable.
//! Because moment headroom is scaled by `l = mu_m / mu`, a larger `mu` never lowers a non-negative margin (a stable
//! pose stays stable with more friction), but negative margins are not monotone in `mu`; compare margins only among
//! poses with the same friction parameters.
//! The report also gives the cone utilisation of the solution, `max |lambda_t| / (mu lambda_z)` over loaded
//! contacts (the quantity (9) tries to keep small).
//!
//! # Solver
//! [`simplex`] first: a dense primal simplex on a condensed tableau. The LP is small (at most [`LP_VARS`]
//! variables, [`LP_EQS`] equations and [`LP_INEQS`] inequalities, 14 x 6 x 35 for two wheel contacts) and its
//! optimum is a vertex, so a few dozen exchanges on a table of a few hundred numbers decide it. The simplex proves
//! "no equilibrium at all" (phase 1 ends positive: [`UnknownReason::NoEquilibrium`]) and checks every answer's
//! residuals against the LP; when it runs out of exchanges (`config::stability::SIMPLEX_MAX_PIVOTS`) or fails that
//! check, [`lp`], a Mehrotra primal-dual interior-point method (`SOLVER_MAX_ITERATIONS`), solves the LP instead.
//! Callers that need only a verdict ([`check_stability_at_least`]) let the simplex stop at the first vertex with
//! the margin they ask for. Both solvers work in `f64`: the margins must agree with clarabel to `1e-6 (1 + |s|)`.
//! Agreement with clarabel on 10,000 random problems: `tests/tests/stability.rs`; the cost of both solvers on
//! the board, side by side: `host-sim/doc/board_test3.md` ("The margin LP by a simplex").
//!
//! # Parameters (`config::stability`)
//! - `MAX_CONTACTS = 4`: contacts per problem.
//! - `SIMPLEX_MAX_PIVOTS = 200`: exchange budget of the simplex (phases 1 and 2).
//! - `SOLVER_MAX_ITERATIONS = 50`, `SOLVER_TOLERANCE = 1e-9`: budget and tolerance of the interior-point fallback.
//! - `MIN_MARGIN = 0.0`: margin needed to call a pose stable.
//! - `MARGIN_CAP = 1.0`: upper bound of `s` (keeps the LP bounded).
//! - `NORMAL_FORCE_CAP = 10.0`: largest normal load per contact, in rover weights.
//!
//! Friction coefficients come with the contacts (`Contact::mu`, `Contact::mu_m`); Axel's defaults live in
//! `config::rover`.

pub mod lp;
pub mod simplex;

use crate::config::stability::{
    MARGIN_CAP, MAX_CONTACTS, MIN_MARGIN, NORMAL_FORCE_CAP, SIMPLEX_MAX_PIVOTS, SOLVER_MAX_ITERATIONS,
    SOLVER_TOLERANCE,
};
use crate::geom::{Real, Vec3};
use lp::{LinearProgram, LpStatus};
use nalgebra::{Matrix3, Vector3};

/// Variables of the stability LP: 6 per contact slot, the tension and the margin.
pub const LP_VARS: usize = 6 * MAX_CONTACTS + 2;
/// Equations of the stability LP: force and moment balance.
pub const LP_EQS: usize = 6;
/// Inequalities of the stability LP: 12 per contact slot, tension bounds and the margin cap.
pub const LP_INEQS: usize = ROWS_PER_CONTACT * MAX_CONTACTS + 3;
/// Inequality rows per contact slot: `lambda_z >= 0`, the 8 friction facets, 6 moment limits, the normal-load cap.
const ROWS_PER_CONTACT: usize = 16;
/// `cos(pi / 8)`: the inscribed octagon's facets sit at this fraction of the friction cone's radius.
const OCTAGON_INSET: f64 = 0.923_879_532_511_286_7;
/// The inscribed octagon's facet directions in the tangent plane, `(cos k pi/4, sin k pi/4)`.
const OCTAGON: [(f64, f64); 8] = [
    (1.0, 0.0),
    (core::f64::consts::FRAC_1_SQRT_2, core::f64::consts::FRAC_1_SQRT_2),
    (0.0, 1.0),
    (-core::f64::consts::FRAC_1_SQRT_2, core::f64::consts::FRAC_1_SQRT_2),
    (-1.0, 0.0),
    (-core::f64::consts::FRAC_1_SQRT_2, -core::f64::consts::FRAC_1_SQRT_2),
    (0.0, -1.0),
    (core::f64::consts::FRAC_1_SQRT_2, -core::f64::consts::FRAC_1_SQRT_2),
];
/// The stability LP's type.
pub type StabilityLp = LinearProgram<LP_VARS, LP_EQS, LP_INEQS>;

const T_COL: usize = 6 * MAX_CONTACTS;
const S_COL: usize = 6 * MAX_CONTACTS + 1;

/// One ground contact (a wheel's contact patch or the boom's tip).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Contact {
    /// Contact point, world frame, metres.
    pub position: Vec3,
    /// Contact normal (unit, pointing out of the terrain into the rover).
    pub normal: Vec3,
    /// Contact-frame x axis (unit, tangent): orientation of the friction octagon. For a wheel, the rolling
    /// direction.
    pub tangent: Vec3,
    /// Coulomb friction coefficient (eqs. 2, 3: the octagon inscribed in its cone).
    pub mu: Real,
    /// Moment coefficient about the contact-frame x and z axes, metres (eqs. 4, 6); 0 for a point contact.
    pub mu_m: Real,
    /// Moment coefficient about the contact-frame y axis, metres (eq. 5). For a wheel (x the rolling direction) y
    /// is the axle, and a rigid rim touches the ground along a line parallel to it, which carries no moment about
    /// it: 0 (see [`Contact::line`]).
    pub mu_m_y: Real,
    /// Whether the margin's headroom is taken from this contact's friction (the wheels) or the contact only has to
    /// hold with plain friction (the boom's tip, [`Contact::tip`]).
    pub in_margin: bool,
}

impl Contact {
    /// A contact whose contact-frame x axis is the projection of `hint` onto the tangent plane (or any tangent if `hint`
    /// is parallel to the normal).
    pub fn new(position: Vec3, normal: Vec3, hint: Vec3, mu: Real, mu_m: Real) -> Self {
        let n = crate::geom::normalize3(&normal, 1e-9).unwrap_or(Vec3::z());
        let t = hint - n * n.dot(&hint);
        let t = crate::geom::normalize3(&t, 1e-6).unwrap_or_else(|| {
            let alt = if libm::fabsf(n.x) < 0.9 { Vec3::x() } else { Vec3::y() };
            let t = alt - n * n.dot(&alt);
            crate::geom::normalize3(&t, 1e-9).unwrap_or(Vec3::x())
        });
        Contact { position, normal: n, tangent: t, mu, mu_m, mu_m_y: mu_m, in_margin: true }
    }

    /// The boom's tip on the ground: a point contact (no moments) that must hold with plain friction but gives no
    /// headroom to the margin. It carries a small share of the weight (about the boom's), and headroom taken from it
    /// would cap every margin at `mu` times that share, so poses the rover holds with its boom down would all look
    /// thin.
    pub fn tip(position: Vec3, normal: Vec3, hint: Vec3, mu: Real) -> Self {
        Contact { in_margin: false, ..Contact::new(position, normal, hint, mu, 0.0) }
    }

    /// The contact of a rigid wheel's rim: a line along the contact-frame y axis (the axle; x along `hint`, the
    /// rolling direction), `mu_m` about x (the line's width) and z, none about the line itself.
    pub fn line(position: Vec3, normal: Vec3, hint: Vec3, mu: Real, mu_m: Real) -> Self {
        Contact { mu_m_y: 0.0, ..Contact::new(position, normal, hint, mu, mu_m) }
    }

    /// The moment coefficient about contact-frame axis `k` (0 x, 1 y, 2 z).
    fn mu_m_about(&self, k: usize) -> f64 {
        f64::from(if k == 1 { self.mu_m_y } else { self.mu_m })
    }
}

/// A point mass of the rover model (body or wheel assembly).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyMass {
    /// Mass, kg.
    pub mass_kg: Real,
    /// Centre of mass, world frame, metres.
    pub com: Vec3,
}

/// The tether's pull on the rover.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum TetherForce {
    /// No tension (tether paid out, or no anchor).
    Slack,
    /// Taut tether from the exit orifice towards the most recent anchor.
    Taut {
        /// Tether exit orifice (end of the boom), world frame.
        exit: Vec3,
        /// Unit direction from the exit towards the last anchor.
        direction: Vec3,
        /// Largest tension the winch holds, newtons (> 0).
        max_tension_n: Real,
    },
}

/// A static-stability question (section IV-C).
#[derive(Debug, Clone, PartialEq)]
pub struct StabilityProblem {
    /// Ground contacts (at most `MAX_CONTACTS`).
    pub contacts: heapless::Vec<Contact, MAX_CONTACTS>,
    /// The two body masses (eqs. 7, 8: `m_1`, `m_2`).
    pub masses: [BodyMass; 2],
    /// Gravity acceleration vector, m/s^2 (e.g. `(0, 0, -3.71)` on Mars).
    pub gravity: Vec3,
    /// The tether force.
    pub tether: TetherForce,
}

/// Why a problem was rejected before solving.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StabilityError {
    /// Total mass or gravity is zero, negative or not finite.
    NoWeight,
    /// A contact has a non-finite position or normal, `mu <= 0`, or `mu_m < 0`.
    BadContact,
    /// The tether direction is not a unit vector, or its maximum tension is not positive and finite.
    BadTether,
}

/// Why the solver could not decide.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UnknownReason {
    /// `SOLVER_MAX_ITERATIONS` ran out.
    BudgetExhausted,
    /// A factorisation failed or an iterate became non-finite.
    NumericalFailure,
    /// The simplex proved that no contact and tether forces balance the weight at all (eqs. 1-8 have no
    /// solution for any margin): the pose cannot be held.
    NoEquilibrium,
}

/// Numbers describing a solved stability problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StabilityReport {
    /// Optimal margin `s*`, fraction of the rover's weight (see the module docs).
    pub margin: f64,
    /// Largest friction/moment cone utilisation of the optimal forces over loaded contacts (1 = at the limit).
    pub max_utilisation: f64,
    /// Tether tension of the optimal forces, newtons.
    pub tension_n: f64,
    /// Solver iterations used.
    pub iterations: u32,
}

/// The answer of [`check_stability`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StabilityOutcome {
    /// `margin >= MIN_MARGIN`.
    Stable(StabilityReport),
    /// `margin < MIN_MARGIN`.
    Unstable(StabilityReport),
    /// The solver could not decide: treat as unstable.
    Unknown(UnknownReason),
}

impl StabilityOutcome {
    /// True only for [`StabilityOutcome::Stable`].
    pub fn is_stable(&self) -> bool {
        matches!(self, StabilityOutcome::Stable(_))
    }
    /// The margin, if solved.
    pub fn margin(&self) -> Option<f64> {
        match self {
            StabilityOutcome::Stable(r) | StabilityOutcome::Unstable(r) => Some(r.margin),
            StabilityOutcome::Unknown(_) => None,
        }
    }
}

fn mat_set<const R: usize, const C: usize>(m: &mut nalgebra::SMatrix<f64, R, C>, i: usize, j: usize, v: f64) {
    if let Some(e) = m.get_mut((i, j)) {
        *e = v;
    }
}

fn vec_set<const R: usize>(m: &mut nalgebra::SVector<f64, R>, i: usize, v: f64) {
    if let Some(e) = m.get_mut(i) {
        *e = v;
    }
}

fn mat_get(m: &Matrix3<f64>, i: usize, j: usize) -> f64 {
    m.get((i, j)).copied().unwrap_or(0.0)
}

fn vec_get<const R: usize>(m: &nalgebra::SVector<f64, R>, i: usize) -> f64 {
    m.get(i).copied().unwrap_or(0.0)
}

fn v64(v: &Vec3) -> Vector3<f64> {
    Vector3::new(f64::from(v.x), f64::from(v.y), f64::from(v.z))
}

fn finite(v: &Vec3) -> bool {
    crate::geom::is_finite3(v)
}

impl StabilityProblem {
    /// Validate and build the margin LP described in the module docs (also used by host-side oracles).
    pub fn to_lp(&self) -> Result<StabilityLp, StabilityError> {
        let mtot = f64::from(self.masses[0].mass_kg) + f64::from(self.masses[1].mass_kg);
        let g = v64(&self.gravity);
        let gn = g.norm();
        let weight = mtot * gn;
        if !(weight.is_finite() && weight > 0.0 && self.masses.iter().all(|m| m.mass_kg >= 0.0 && finite(&m.com))) {
            return Err(StabilityError::NoWeight);
        }
        let ghat = g / gn;
        let com = (v64(&self.masses[0].com) * f64::from(self.masses[0].mass_kg)
            + v64(&self.masses[1].com) * f64::from(self.masses[1].mass_kg))
            / mtot;
        let mut lp = StabilityLp::zeros();
        // Rows of unused contact slots (and moment rows of point contacts) stay `0 <= 1`: trivially true, with an
        // interior, so they do not disturb the interior-point iterates. Used rows set their `h` to 0 below.
        lp.h = nalgebra::SVector::repeat(1.0);
        // Equations: sum of forces = -ghat (weight units), sum of moments about com = 0 (gravity has no moment
        // about the combined centre of mass).
        vec_set(&mut lp.b, 0, -ghat.x);
        vec_set(&mut lp.b, 1, -ghat.y);
        vec_set(&mut lp.b, 2, -ghat.z);
        for (i, c) in self.contacts.iter().enumerate() {
            let ok = finite(&c.position)
                && finite(&c.normal)
                && finite(&c.tangent)
                && c.mu.is_finite()
                && c.mu > 0.0
                && c.mu_m.is_finite()
                && c.mu_m >= 0.0
                && c.mu_m_y.is_finite()
                && c.mu_m_y >= 0.0;
            if !ok {
                return Err(StabilityError::BadContact);
            }
            let z = v64(&c.normal).try_normalize(1e-9).ok_or(StabilityError::BadContact)?;
            let xt = v64(&c.tangent);
            let x = (xt - z * z.dot(&xt)).try_normalize(1e-6).ok_or(StabilityError::BadContact)?;
            let y = z.cross(&x);
            let r = Matrix3::from_columns(&[x, y, z]);
            let p = v64(&c.position) - com;
            let pr = p.cross_matrix() * r;
            let col = 6 * i;
            let mu = f64::from(c.mu);
            for k in 0..3 {
                for row in 0..3 {
                    mat_set(&mut lp.a, row, col + k, mat_get(&r, row, k));
                    mat_set(&mut lp.a, row + 3, col + k, mat_get(&pr, row, k));
                    // a moment the contact cannot carry has no variable: it is 0
                    if c.mu_m_about(k) > 0.0 {
                        mat_set(&mut lp.a, row + 3, col + 3 + k, mat_get(&r, row, k));
                    }
                }
            }
            let r0 = ROWS_PER_CONTACT * i;
            // (1) lambda_z >= 0
            mat_set(&mut lp.g, r0, col + 2, -1.0);
            vec_set(&mut lp.h, r0, 0.0);
            // normal-load cap (physical load limit; keeps the LP well conditioned in wedge configurations)
            mat_set(&mut lp.g, r0 + 15, col + 2, 1.0);
            vec_set(&mut lp.h, r0 + 15, NORMAL_FORCE_CAP);
            // (2), (3) with margin: u . lambda_t <= cos(pi/8) (mu lambda_z - s) for the octagon's 8 facets u
            for (j, (ux, uy)) in OCTAGON.iter().enumerate() {
                mat_set(&mut lp.g, r0 + 1 + j, col, *ux);
                mat_set(&mut lp.g, r0 + 1 + j, col + 1, *uy);
                mat_set(&mut lp.g, r0 + 1 + j, col + 2, -OCTAGON_INSET * mu);
                if c.in_margin {
                    mat_set(&mut lp.g, r0 + 1 + j, S_COL, OCTAGON_INSET);
                }
                vec_set(&mut lp.h, r0 + 1 + j, 0.0);
            }
            // (4)-(6) with margin, only for the moments the contact carries
            for j in 0..6 {
                let mu_m = c.mu_m_about(j / 2);
                if mu_m > 0.0 {
                    let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
                    mat_set(&mut lp.g, r0 + 9 + j, col + 3 + j / 2, sign);
                    mat_set(&mut lp.g, r0 + 9 + j, col + 2, -mu_m);
                    mat_set(&mut lp.g, r0 + 9 + j, S_COL, mu_m / mu);
                    vec_set(&mut lp.h, r0 + 9 + j, 0.0);
                }
            }
        }
        let tr = ROWS_PER_CONTACT * MAX_CONTACTS;
        mat_set(&mut lp.g, tr, T_COL, -1.0);
        vec_set(&mut lp.h, tr, 0.0);
        mat_set(&mut lp.g, tr + 1, T_COL, 1.0);
        vec_set(&mut lp.h, tr + 1, 1.0);
        if let TetherForce::Taut { exit, direction, max_tension_n } = self.tether {
            let d = v64(&direction);
            let tmax = f64::from(max_tension_n);
            if !(finite(&exit) && finite(&direction) && (d.norm() - 1.0).abs() < 1e-3 && tmax.is_finite() && tmax > 0.0)
            {
                return Err(StabilityError::BadTether);
            }
            let d = d / d.norm();
            let m = (v64(&exit) - com).cross(&d);
            for row in 0..3 {
                mat_set(&mut lp.a, row, T_COL, d.get(row).copied().unwrap_or(0.0));
                mat_set(&mut lp.a, row + 3, T_COL, m.get(row).copied().unwrap_or(0.0));
            }
            vec_set(&mut lp.h, tr + 1, tmax / weight);
        }
        mat_set(&mut lp.g, tr + 2, S_COL, 1.0);
        vec_set(&mut lp.h, tr + 2, MARGIN_CAP);
        vec_set(&mut lp.c, S_COL, -1.0);
        Ok(lp)
    }

    fn weight(&self) -> f64 {
        (f64::from(self.masses[0].mass_kg) + f64::from(self.masses[1].mass_kg)) * v64(&self.gravity).norm()
    }
}

/// Solve the margin LP: the simplex first; the interior-point method when the simplex runs out of exchanges or
/// fails its residual check (an answer of "infeasible" from the simplex is final). With `at_least`, the simplex
/// may stop at the first vertex whose margin reaches it (see [`check_stability_at_least`]).
pub fn solve_margin_lp(lp: &StabilityLp, at_least: Option<f64>) -> lp::LpSolution<LP_VARS> {
    let sol = simplex::solve_until(lp, SIMPLEX_MAX_PIVOTS, at_least.map(|m| -m));
    match sol.status {
        LpStatus::BudgetExhausted | LpStatus::NumericalFailure => lp.solve(SOLVER_MAX_ITERATIONS, SOLVER_TOLERANCE),
        LpStatus::Optimal | LpStatus::AlmostOptimal | LpStatus::Infeasible | LpStatus::TargetReached => sol,
    }
}

/// Decide static stability (section IV-C) with the convex margin LP of the module docs.
pub fn check_stability(problem: &StabilityProblem) -> Result<StabilityOutcome, StabilityError> {
    let lp = problem.to_lp()?;
    Ok(outcome(problem, &solve_margin_lp(&lp, None)))
}

/// [`check_stability`] for callers that need only the verdict "stable with a margin of at least `min_margin`":
/// the simplex stops at the first vertex that proves it, so a `Stable` answer's margin is then at least
/// `min_margin` but not necessarily the largest. Every other answer is [`check_stability`]'s.
pub fn check_stability_at_least(problem: &StabilityProblem, min_margin: f64) -> Result<StabilityOutcome, StabilityError> {
    let lp = problem.to_lp()?;
    // a vertex at or above both the asked margin and `MIN_MARGIN` is a `Stable` answer with at least that margin
    Ok(outcome(problem, &solve_margin_lp(&lp, Some(min_margin.max(MIN_MARGIN)))))
}

/// The outcome of a solved margin LP.
fn outcome(problem: &StabilityProblem, sol: &lp::LpSolution<LP_VARS>) -> StabilityOutcome {
    match sol.status {
        LpStatus::Optimal | LpStatus::AlmostOptimal | LpStatus::TargetReached => {}
        LpStatus::BudgetExhausted => return StabilityOutcome::Unknown(UnknownReason::BudgetExhausted),
        LpStatus::NumericalFailure => return StabilityOutcome::Unknown(UnknownReason::NumericalFailure),
        LpStatus::Infeasible => return StabilityOutcome::Unknown(UnknownReason::NoEquilibrium),
    }
    let x = sol.x;
    let margin = -sol.objective;
    let mut util: f64 = 0.0;
    for (i, c) in problem.contacts.iter().enumerate() {
        let col = 6 * i;
        let fz = vec_get(&x, col + 2);
        if fz > 1e-9 {
            util = util.max(libm::hypot(vec_get(&x, col), vec_get(&x, col + 1)) / (f64::from(c.mu) * fz));
            for k in 0..3 {
                let mu_m = c.mu_m_about(k);
                if mu_m > 0.0 {
                    util = util.max(vec_get(&x, col + 3 + k).abs() / (mu_m * fz));
                }
            }
        }
    }
    let report = StabilityReport {
        margin,
        max_utilisation: util,
        tension_n: vec_get(&x, T_COL) * problem.weight(),
        iterations: sol.iterations,
    };
    if margin >= MIN_MARGIN {
        StabilityOutcome::Stable(report)
    } else {
        StabilityOutcome::Unstable(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Point mass on an incline of angle alpha (rad), tether in the slope plane at angle theta from upslope. The
    /// contact frame's x axis is turned by `twist` from the in-plane direction perpendicular to the tether (the
    /// direction the friction force must take).
    fn pm(mu: Real, twist: Real) -> impl Fn(Real, Real) -> StabilityOutcome {
        move |alpha: Real, theta: Real| {
            let n = Vec3::new(libm::sinf(alpha), 0.0, libm::cosf(alpha));
            let up = Vec3::new(-libm::cosf(alpha), 0.0, libm::sinf(alpha));
            let side = n.cross(&up);
            let d = up * libm::cosf(theta) + side * libm::sinf(theta);
            let across = n.cross(&d);
            let tangent = across * libm::cosf(twist) + d * libm::sinf(twist);
            let mut contacts = heapless::Vec::new();
            let _ = contacts.push(Contact {
                position: Vec3::zeros(),
                normal: n,
                tangent,
                mu,
                mu_m: 0.0,
                mu_m_y: 0.0,
                in_margin: true,
            });
            let p = StabilityProblem {
                contacts,
                masses: [
                    BodyMass { mass_kg: 1.0, com: Vec3::zeros() },
                    BodyMass { mass_kg: 0.0, com: Vec3::zeros() },
                ],
                gravity: Vec3::new(0.0, 0.0, -9.81),
                tether: TetherForce::Taut { exit: Vec3::zeros(), direction: d, max_tension_n: 1e3 },
            };
            match check_stability(&p) {
                Ok(o) => o,
                Err(e) => panic!("{e:?}"),
            }
        }
    }

    /// The stable tether angles of [`pm`] are `|theta| <= theta_max` (checked on a grid), and the boundary found by
    /// bisection is `theta_max` within 2e-4 rad.
    fn holds_up_to(mu: Real, twist: Real, alpha: Real, theta_max: Real) {
        let f = pm(mu, twist);
        for k in 0..=20 {
            let th = -1.4 + 2.8 * k as f32 / 20.0;
            let o = f(alpha, th);
            let expect = libm::fabsf(th) <= theta_max;
            if libm::fabsf(libm::fabsf(th) - theta_max) > 1e-3 {
                assert_eq!(o.is_stable(), expect, "mu {mu} alpha {alpha} theta {th} tmax {theta_max} {o:?}");
            }
        }
        let (mut lo, mut hi) = (0.0f32, 1.5f32);
        for _ in 0..30 {
            let m = 0.5 * (lo + hi);
            if f(alpha, m).is_stable() {
                lo = m
            } else {
                hi = m
            }
        }
        assert!((lo - theta_max).abs() < 2e-4, "mu {mu} alpha {alpha} twist {twist}: boundary {lo} vs {theta_max}");
    }

    #[test]
    fn point_mass_on_incline_holds_up_to_theta_max() {
        // Abad-Manterola et al. section VI: |theta_max| = asin(mu cot alpha) for Coulomb's cone. The LP's friction
        // octagon is inscribed in the cone: where the friction force points at one of its corners (the frame turned
        // by pi/8) the boundary is the cone's; where it points at a facet's middle (the frame along it) the reach
        // is cos(pi/8) mu, and the boundary is asin(cos(pi/8) mu cot alpha): inside the cone's, never beyond it.
        let inset = libm::cosf(core::f32::consts::PI / 8.0);
        for (mu, alpha_deg) in [(0.5f32, 45.0f32), (0.6, 55.0), (0.3, 40.0), (0.8, 70.0)] {
            let alpha = alpha_deg.to_radians();
            holds_up_to(mu, core::f32::consts::PI / 8.0, alpha, libm::asinf(mu / libm::tanf(alpha)));
            holds_up_to(mu, 0.0, alpha, libm::asinf(inset * mu / libm::tanf(alpha)));
        }
    }

    /// Two rims on flat ground, slack tether, the combined centre of mass `offset` ahead of the contact line
    /// (along the rolling direction x). Nothing but a moment about the axle can hold the weight's torque
    /// `W offset` about that line: a patch holds it while `|offset| <= mu_m`, a rim's line contact never (the
    /// braked rover rolls over its wheels), and with the mass over the line both hold.
    #[test]
    fn a_rim_line_contact_carries_no_moment_about_the_axle() {
        let problem = |line: bool, offset: Real| {
            let mut contacts = heapless::Vec::new();
            for y in [-0.5f32, 0.5] {
                let p = Vec3::new(0.0, y, 0.0);
                let c = if line { Contact::line } else { Contact::new };
                let _ = contacts.push(c(p, Vec3::z(), Vec3::x(), 0.6, 0.05));
            }
            StabilityProblem {
                contacts,
                masses: [
                    BodyMass { mass_kg: 40.0, com: Vec3::new(offset, 0.0, 0.35) },
                    BodyMass { mass_kg: 10.0, com: Vec3::new(offset, 0.0, 0.3) },
                ],
                gravity: Vec3::new(0.0, 0.0, -3.71),
                tether: TetherForce::Slack,
            }
        };
        let stable = |line, offset| matches!(check_stability(&problem(line, offset)), Ok(o) if o.is_stable());
        for offset in [-0.04f32, -0.01, 0.02, 0.045] {
            assert!(stable(false, offset), "a patch holds {offset}");
            assert!(!stable(true, offset), "a line holds {offset}");
        }
        assert!(!stable(false, 0.06), "a patch beyond mu_m");
        assert!(stable(true, 0.0) && stable(false, 0.0), "the mass over the line");
    }

    #[test]
    fn slack_tether_on_flat_ground_is_stable_and_steep_slope_is_not() {
        let mk = |normal: Vec3| {
            let mut contacts = heapless::Vec::new();
            for y in [-0.5f32, 0.5] {
                let _ = contacts.push(Contact::new(Vec3::new(0.0, y, 0.0), normal, Vec3::x(), 0.6, 0.05));
            }
            StabilityProblem {
                contacts,
                masses: [
                    BodyMass { mass_kg: 30.0, com: Vec3::new(0.0, 0.0, 0.35) },
                    BodyMass { mass_kg: 20.0, com: Vec3::new(-0.1, 0.0, 0.3) },
                ],
                gravity: Vec3::new(0.0, 0.0, -3.71),
                tether: TetherForce::Slack,
            }
        };
        let flat = check_stability(&mk(Vec3::z()));
        assert!(matches!(flat, Ok(StabilityOutcome::Stable(_))), "{flat:?}");
        // 45 degrees with mu 0.6 and no tether: tan 45 = 1 > 0.6, must slide
        let n = Vec3::new(libm::sinf(0.785), 0.0, libm::cosf(0.785));
        let steep = check_stability(&mk(n));
        assert!(matches!(steep, Ok(StabilityOutcome::Unstable(_))), "{steep:?}");
    }

    #[test]
    fn bad_input_is_rejected() {
        let p = StabilityProblem {
            contacts: heapless::Vec::new(),
            masses: [BodyMass { mass_kg: 0.0, com: Vec3::zeros() }; 2],
            gravity: Vec3::new(0.0, 0.0, -9.81),
            tether: TetherForce::Slack,
        };
        assert_eq!(check_stability(&p), Err(StabilityError::NoWeight));
    }
}
