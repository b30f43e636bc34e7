//! The tether-aware state space of Paton et al. (*Navigation on the Line*, IROS 2020) sections IV-V: settled
//! SE(3) states on the terrain, motions of in-place turns plus straight drives, validated by settling, body
//! collision, anchor prediction (Alg. 1) and static stability at every interpolated state, with the anchor history
//! as the non-Markovian attachment of [`crate::plan::space`]. Plug it into [`crate::plan::abit::AbitStar`].
//!
//! Files: `params.rs` ([`TetherSpaceParams`], [`PlanBounds`]), `space.rs` (states, surface trace, settling,
//! sampling, history compatibility, the [`StateSpace`](crate::plan::space::StateSpace) implementation),
//! `motion.rs` ([`MotionPlan`], the motion check, [`TetherMotionValidator`]), `objective.rs` ([`TetherObjective`]).
//!
//! # States ([`RoverState`])
//! A state is the surface point it was settled from (`ground`), the yaw about the surface normal given to the
//! settler (`theta`), and the settled pose ([`crate::rover::settle`], Fig. 2). A sample (section V): draw `(x, y)`
//! uniformly in the planning bounds, find the terrain surface below it by sphere tracing down the ESDF from the top
//! of the bounds ([`surface_point`]), perturb `(x, y)` by up to `sample_perturbation_m`, draw a yaw, settle.
//! The yaw is uniform on surfaces tilted up to `fall_line_tilt_rad`; on steeper ones it is the downhill fall line
//! plus a uniform perturbation of up to `fall_line_yaw_spread_rad` ([`fall_line_theta`]). Axel holds a steep slope
//! only along the fall line (on the 55-degree slope of Paton et al. VI-A a pose turned 15 degrees off it is already
//! unstable), so a uniformly drawn yaw would waste eleven samples in twelve there; and facing downhill loses nothing,
//! because the rover is symmetric and drives either way. A failed settle (no ground, body collision, unknown space,
//! budget, a wheel on a surface steeper than 75 degrees such as a pole's side) is a failed draw.
//! **Catch-boundary samples** ([`StateSpace::sample_catch_boundary`], a fraction of the planner's draws): the
//! Gaussian (bridge) sampling of obstacle boundaries applied to the tether's line of sight. Two surface points at
//! most `catch_pair_radius_m` apart are drawn; when exactly one of them is in the shadow of the history's last anchor
//! (a straight tether from it to the point's axle height would touch terrain, [`crate::tether::tether_touches`]), the
//! sample is settled at their midpoint. These are the places where the tether starts to wrap an obstacle (behind
//! the pole of Paton et al. VI-A, test 3), which uniform samples rarely straddle. The planner only ever sees settled
//! states, so state validity is settledness; the
//! attachment-dependent checks belong to the motion, except for a sample that copied a neighbour's anchor history
//! (Paton et al. V-A), which must be stable with it (`StateSpace::valid_with_attachment`).
//!
//! # Motions ([`TetherMotionValidator`])
//! From `a` to `b`: turn in place at `a` to the drive heading, drive the straight line from `a.ground` to
//! `b.ground` (its `(x, y)` projection; the surface under each point found by the same trace), turn in place at
//! `b` to `b`'s yaw. Axel drives either way, so the drive heading is the one of `{psi, psi + pi}` that needs less
//! turning. Interpolated states are `drive_resolution_m` apart along the drive and `turn_resolution_rad` apart in
//! the turns; where two consecutive drive states tilt more than `refine_tilt_rad` apart (an edge such as the lip of
//! the ledge, over which the margin of the straddling pose dips to zero within ~0.1 m, less than a drive step),
//! the step between them is also checked at `refine_substeps` evenly spaced points, and each of these states must
//! also be stable settled `surface_uncertainty_m` ahead and behind along the drive (the map's edge is not where the
//! true edge is); each is settled (body collision included), its tether end (the axle centre) is moved from the
//! previous state's with [`predict_anchors`] (skipped when it moved less than `tether_still_m`), and it must be
//! statically stable ([`check_pose_stability`]) with a margin of at least `min_stability_margin`, the tether pulling
//! towards the last anchor of the history that lies beyond the boom's reach ([`tether_pull_anchor`]: an anchor
//! closer than the boom, e.g. the lip right after the rover went over it, is under the boom, which rests on it). The motion's attachment is the anchor history at `b`. Every failure is counted by
//! reason ([`MotionStats`]). A tether that bends more than `max_tether_bend_rad` in total over its anchors
//! ([`tether_bend`]) makes the motion invalid: the stability model treats anchors as frictionless, while a real
//! tether wrapped by an angle `phi` carries a tension ratio of up to `exp(mu phi)` (the capstan equation) across the
//! wrap; the limit also keeps the planner from exploring paths that circle an obstacle again and again.
//!
//! # Objective ([`TetherObjective`])
//! `cost = w_length * |axle_b - axle_a| + w_yaw * (|turn at a| + |turn at b|) + w_roll * |axle_b - axle_a| *
//! (|roll_a| + |roll_b|) / 2` (roll: the angle of the axle above the horizontal). The heuristic is
//! `w_length * |axle_b - axle_a|`, a lower bound of the cost. Informed samples are drawn in the 2D ellipse of the
//! `(x, y)` projection (which contains the informed set, because the heuristic only grows with the third
//! coordinate) and kept when the settled state's heuristic sum is below the best cost.
//!
//! # Off-map goals (section VI-B)
//! A goal outside the planning bounds ([`RoverState::off_map`]) connects from any state within `off_map_edge_m` of
//! the bounds (in `x, y`), at the cost of the straight-line distance.
//!
//! # Anchor-history compatibility (section V-A)
//! Rewiring is only allowed between compatible histories. Anchor prediction discretises a tether wrapped around a
//! curved obstacle into many anchors (about one per 0.4 rad on the 0.25 m pole), so two tree vertices reached around
//! the same side of the same pole rarely hold identical lists. Histories are therefore compared by their wraps
//! ([`wraps`]: runs of consecutive anchors closer than `anchor_cluster_m`, each represented by its last anchor):
//! compatible when they have as many wraps and the representatives lie within `anchor_match_m`
//! ([`TetherSpace::histories_match`]). Every returned path is re-checked from the root anchor when it is
//! re-validated, so this tolerance cannot hide an unstable path.
//!
//! # Parameters ([`TetherSpaceParams::DEFAULT`], `config::tethered::defaults`)
//! | parameter | default |
//! |---|---|
//! | `w_length`, `w_yaw`, `w_roll` | 1.0 /m, 0.25 /rad, 1.0 /(rad m) |
//! | `drive_resolution_m` | 0.2 m |
//! | `turn_resolution_rad` | 0.5 rad |
//! | `tether_still_m` | 0.01 m |
//! | `min_stability_margin` | 0.02 rover weights |
//! | `sample_perturbation_m` | 0.05 m |
//! | `off_map_edge_m` | 1.0 m |
//! | `anchor_match_m` | 0.3 m |
//! | `anchor_cluster_m` | 0.6 m |
//! | `max_tether_bend_rad` | 4.71 rad (270 degrees) |
//! | `fall_line_tilt_rad` | 0.35 rad (20 degrees) |
//! | `fall_line_yaw_spread_rad` | 0.15 rad (8.6 degrees) |
//! | `refine_tilt_rad` | 0.1 rad (6 degrees) |
//! | `refine_substeps` | 8 (0.025 m sub-steps; at most `MAX_REFINE_SUBSTEPS = 16`) |
//! | `surface_uncertainty_m` | 0 m (exact field; the campaign sets half a voxel when planning on the map) |
//! | `catch_pair_radius_m` | 0.5 m |
//!
//! Budgets (`config::tethered`): `SURFACE_TRACE_STEPS = 64` (minimum step `SURFACE_MIN_STEP_M = 0.05`),
//! `MAX_MOTION_STATES = 256` interpolated states per motion, `CATCH_PAIR_ATTEMPTS = 512` point pairs per
//! catch-boundary sample.
//!
//! [`StateSpace::sample_catch_boundary`]: crate::plan::space::StateSpace::sample_catch_boundary
//! [`predict_anchors`]: crate::tether::predict_anchors
//! [`check_pose_stability`]: crate::rover::check_pose_stability

mod motion;
mod objective;
mod params;
mod phases;
mod space;
#[cfg(test)]
mod tests;

pub use motion::{tether_bend, tether_pull_anchor, MotionFailure, MotionPlan, MotionPoint, TetherMotionValidator};
pub use objective::TetherObjective;
pub use params::{PlanBounds, TetherSpaceParams};
pub use phases::{PhaseClock, PhaseTicks};
pub use space::{
    fall_line_theta, settle_at, settle_under_axle_with, surface_point, wraps, MarginEscape, MotionStats, RoverState, SettleFailure, StartEscape,
    TetherSpace, TetherValidity,
};
