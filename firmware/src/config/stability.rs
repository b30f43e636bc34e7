//! Capacities and budgets for [`crate::stability`] (Paton et al. section IV-C).

/// Most contacts in one stability problem. Default 4: the two wheel contacts, the boom's ground contact
/// (Fig. 6: P1, P2, P3) and one spare (a wheel touching an edge at a second point).
pub const MAX_CONTACTS: usize = 4;

/// Interior-point iteration budget of the LP solver. Default 50: the Mehrotra method converges in 10-25
/// iterations on the stability LPs (measured on 10,000 random instances, see `tests/tests/stability.rs`); running
/// out is reported as `Unknown` (treated as unstable).
pub const SOLVER_MAX_ITERATIONS: u32 = 50;

/// Exchange budget of the simplex ([`crate::stability::simplex`]), phases 1 and 2 (phase 0 adds one exchange per
/// variable). Default 200: the margin LPs took at most 71 exchanges in all, phase 0 included, on 12,022 random
/// instances (`tests/tests/stability.rs`); running out falls back to the interior-point method.
pub const SIMPLEX_MAX_PIVOTS: u32 = 200;

/// Relative tolerance on the residuals and the duality gap. Default 1e-9 (forces are normalised by the rover's
/// weight, so this is a nano-weight).
pub const SOLVER_TOLERANCE: f64 = 1e-9;

/// Smallest friction margin (fraction of the rover's weight, see the `stability` module docs) at which a pose
/// counts as stable. Default 0.0: exactly at the boundary of the friction octagons; raise it for a safety buffer
/// against uncertain friction.
pub const MIN_MARGIN: f64 = 0.0;

/// Upper bound of the margin variable (fraction of weight) that keeps the LP bounded. Default 1.0.
pub const MARGIN_CAP: f64 = 1.0;

/// Largest normal force one contact may carry, in rover weights. Default 10.0: far above any load a static
/// two-wheeled rover puts on one wheel (at most ~1 weight plus the tether's pull), yet it removes the unbounded
/// "squeeze" directions of wedge contacts, which otherwise make the LP ill-conditioned.
pub const NORMAL_FORCE_CAP: f64 = 10.0;
