//! Motions: the interpolation of a turn-drive-turn motion ([`MotionPlan`]), its validation state by state
//! (settling, anchor prediction, tether bend, stability), and the [`MotionValidator`] implementation.

use crate::config::rover::RoverParams;
use crate::config::tethered::{BOOM_REACH_CLEARANCE_M, MAX_MOTION_STATES, MAX_REFINE_SUBSTEPS};
use crate::geom::{angle_diff, norm3, Real, Vec3};
use crate::map::DistanceField;
use crate::plan::space::{MotionCheck, MotionValidator};
use crate::rover::{check_pose_stability, check_pose_stability_at_least, SettledPose};
use crate::stability::StabilityOutcome;
use crate::tether::{AnchorHistory, TetherError};

use super::phases::Phase;
use super::{RoverState, SettleFailure, TetherSpace, TetherSpaceParams};

impl<D: DistanceField> TetherSpace<'_, D> {
    /// The stability of a settled state with the last anchor of `history` (counted). `Ok(margin)` when stable
    /// with at least `min_stability_margin` ([`Self::min_margin_at`]: a margin escape's minimum in its zone).
    pub fn stable_with(&self, st: &SettledPose, history: &AnchorHistory) -> Result<f64, MotionFailure> {
        self.count(|s| s.stability_checks += 1);
        let pull = tether_pull_anchor(st, history, &self.rover);
        match self.timed(Phase::Stability, || check_pose_stability(self.map, st, pull.as_ref(), &self.rover)) {
            Ok((StabilityOutcome::Stable(r), _)) if r.margin >= self.min_margin_at(st) => Ok(r.margin),
            Ok((StabilityOutcome::Unknown(_), _)) => Err(MotionFailure::Unknown),
            _ => Err(MotionFailure::Unstable),
        }
    }

    /// [`Self::stable_with`]'s verdict alone (counted the same): `Ok` when stable with at least
    /// `min_stability_margin` (as there), with one stability LP instead of two whenever the inline boom holds.
    pub fn stable_enough(&self, st: &SettledPose, history: &AnchorHistory) -> Result<(), MotionFailure> {
        self.count(|s| s.stability_checks += 1);
        let pull = tether_pull_anchor(st, history, &self.rover);
        let min = self.min_margin_at(st);
        match self.timed(Phase::Stability, || check_pose_stability_at_least(self.map, st, pull.as_ref(), &self.rover, min)) {
            Ok((StabilityOutcome::Stable(r), _)) if r.margin >= min => Ok(()),
            Ok((StabilityOutcome::Unknown(_), _)) => Err(MotionFailure::Unknown),
            _ => Err(MotionFailure::Unstable),
        }
    }

    /// Check a motion (see the module docs) and return the anchor history at its end.
    pub fn check(&self, from: &RoverState, history: &AnchorHistory, to: &RoverState) -> Result<AnchorHistory, MotionFailure> {
        self.count(|s| s.motions += 1);
        let r = self.check_inner(from, history, to);
        self.count(|s| match &r {
            Ok(_) => s.motions_valid += 1,
            Err(MotionFailure::Settle(SettleFailure::UnknownSpace)) | Err(MotionFailure::Unknown) => {
                s.fail_unknown += 1
            }
            Err(MotionFailure::Settle(f)) => {
                s.fail_settle += 1;
                match f {
                    SettleFailure::Collision => s.settle_collision += 1,
                    SettleFailure::SteepContact => s.settle_steep += 1,
                    _ => {}
                }
            }
            Err(MotionFailure::Tether(TetherError::UnknownSpace)) => s.fail_unknown += 1,
            Err(MotionFailure::Tether(_)) | Err(MotionFailure::TetherBend) => s.fail_tether += 1,
            Err(MotionFailure::Unstable) => s.fail_unstable += 1,
            Err(MotionFailure::TooLong) | Err(MotionFailure::OffMap) => s.fail_too_long += 1,
        });
        r
    }

    fn check_inner(&self, from: &RoverState, history: &AnchorHistory, to: &RoverState) -> Result<AnchorHistory, MotionFailure> {
        if from.off_map {
            return Err(MotionFailure::OffMap);
        }
        if to.off_map {
            let a = from.axle();
            // An off-map goal inside the bounds is an unobserved one (see `TetherSpace::goal_or_unobserved`): no
            // motion reaches it; the plan is the approximate one that ends nearest to it.
            let inside = self.bounds.contains_xy(to.ground.x, to.ground.y);
            return if !inside && self.bounds.edge_distance_xy(a.x, a.y) <= self.params.off_map_edge_m {
                Ok(history.clone())
            } else {
                Err(MotionFailure::OffMap)
            };
        }
        let plan = MotionPlan::new(from, to, &self.params);
        if plan.total_states() > MAX_MOTION_STATES {
            return Err(MotionFailure::TooLong);
        }
        let mut walk = TetherWalk { hist: history.clone(), scratch: AnchorHistory::default(), tether_end: from.axle() };
        let mut prev = *from;
        for k in 1..=plan.total_states() {
            let point = plan.state(k);
            let mut refined = false;
            let st = match point {
                MotionPoint::Turn { at_end, theta } => {
                    let base = if at_end { to } else { from };
                    self.settle_state(base.ground.x, base.ground.y, theta).map_err(MotionFailure::Settle)?
                }
                MotionPoint::Drive { x, y, theta } => {
                    let st = self.settle_state(x, y, theta).map_err(MotionFailure::Settle)?;
                    // Over an edge (the lip of a ledge) the margin can dip to zero within a few centimetres, less
                    // than one drive step: where the rover frame tilts a lot between two drive states, the states
                    // in between are checked too.
                    if tilt_between(&prev.settled, &st.settled) > self.params.refine_tilt_rad {
                        let n = self.params.refine_substeps.min(MAX_REFINE_SUBSTEPS);
                        for j in 1..n {
                            let t = j as Real / n as Real;
                            let g = prev.ground + (st.ground - prev.ground) * t;
                            let mid = self.settle_state(g.x, g.y, theta).map_err(MotionFailure::Settle)?;
                            self.advance(&mut walk, &mid)?;
                            self.stable_nearby(&mid, &(st.ground - prev.ground), &walk.hist)?;
                        }
                        refined = true;
                    }
                    st
                }
                MotionPoint::End => *to,
            };
            self.advance(&mut walk, &st)?;
            if refined {
                self.stable_nearby(&st, &(st.ground - prev.ground), &walk.hist)?;
            }
            prev = st;
        }
        Ok(walk.hist)
    }

    /// A state on an edge must also be stable where the true terrain may put it: settled `surface_uncertainty_m`
    /// ahead and behind along the drive direction `along`, with the same anchor history (the map's rounded edge sits
    /// up to half a voxel from the true one, and the margin over an edge changes within centimetres).
    fn stable_nearby(&self, st: &RoverState, along: &Vec3, hist: &AnchorHistory) -> Result<(), MotionFailure> {
        let u = self.params.surface_uncertainty_m;
        let len = libm::sqrtf(along.x * along.x + along.y * along.y);
        if u <= 0.0 || len <= 1e-6 {
            return Ok(());
        }
        for sign in [-1.0, 1.0] {
            let (dx, dy) = (sign * u * along.x / len, sign * u * along.y / len);
            let near = self.settle_state(st.ground.x + dx, st.ground.y + dy, st.theta).map_err(MotionFailure::Settle)?;
            self.stable_enough(&near.settled, hist)?;
        }
        Ok(())
    }

    /// One interpolated state of a motion: predict the anchors up to it, bound the tether's bend, check stability.
    fn advance(&self, walk: &mut TetherWalk, st: &RoverState) -> Result<(), MotionFailure> {
        let end = st.axle();
        if norm3(&(end - walk.tether_end)) >= self.params.tether_still_m {
            self.count(|s| s.anchor_predictions += 1);
            self.predict(&walk.hist, &walk.tether_end, &end, &mut walk.scratch).map_err(MotionFailure::Tether)?;
            core::mem::swap(&mut walk.hist, &mut walk.scratch);
            walk.tether_end = end;
            if tether_bend(&walk.hist, &end) > self.params.max_tether_bend_rad {
                return Err(MotionFailure::TetherBend);
            }
        }
        self.stable_enough(&st.settled, &walk.hist)
    }
}

/// The tether along a motion being checked: the anchor history so far and where the tether ended when it was
/// last predicted.
struct TetherWalk {
    hist: AnchorHistory,
    scratch: AnchorHistory,
    tether_end: Vec3,
}

/// Angle between the up axes (rover z) of two settled poses, radians.
fn tilt_between(a: &SettledPose, b: &SettledPose) -> Real {
    let (ua, ub) = (a.pose.rotation * Vec3::z(), b.pose.rotation * Vec3::z());
    libm::acosf(ua.dot(&ub).clamp(-1.0, 1.0))
}

/// Total bend of the tether, radians: the sum over the intermediate anchors of the angle between the incoming and
/// the outgoing tether segment (the last segment ends at `end`).
pub fn tether_bend(h: &AnchorHistory, end: &Vec3) -> Real {
    let a = h.as_slice();
    let mut total = 0.0;
    for (i, mid) in a.iter().enumerate().skip(1) {
        let (Some(prev), next) = (a.get(i - 1), a.get(i + 1).map_or(*end, |n| n.point)) else { continue };
        let (u, v) = (mid.point - prev.point, next - mid.point);
        let (nu, nv) = (norm3(&u), norm3(&v));
        if nu > 1e-6 && nv > 1e-6 {
            total += libm::acosf((u.dot(&v) / (nu * nv)).clamp(-1.0, 1.0));
        }
    }
    total
}

/// The anchor the tether pulls the rover towards: the most recent anchor farther from the axle than the boom
/// reaches (`boom_length_m + BOOM_REACH_CLEARANCE_M`). An anchor within the boom's reach (the lip of a ledge just
/// after the rover went over it) lies between the axle and the boom tip, so the tether leaving the tip runs over it
/// towards the anchor before it; the boom then rests on that edge, which the in-contact boom configuration models.
/// `None` for an empty history.
pub fn tether_pull_anchor(st: &SettledPose, history: &AnchorHistory, rover: &RoverParams) -> Option<Vec3> {
    let axle = st.pose.translation.vector;
    let reach = rover.boom_length_m + BOOM_REACH_CLEARANCE_M;
    let anchors = history.as_slice();
    anchors
        .iter()
        .rev()
        .find(|a| norm3(&(a.point - axle)) > reach)
        .or(anchors.first())
        .map(|a| a.point)
}

/// Why a motion is invalid.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MotionFailure {
    /// An interpolated state did not settle.
    Settle(SettleFailure),
    /// Anchor prediction failed.
    Tether(TetherError),
    /// An interpolated state is unstable (or below the margin).
    Unstable,
    /// The stability problem had no reliable answer (treated as unsafe).
    Unknown,
    /// More interpolated states than `MAX_MOTION_STATES`.
    TooLong,
    /// The tether would bend more than `max_tether_bend_rad` over its anchors.
    TetherBend,
    /// A motion from an off-map goal, or to one from too far from the bounds' edge.
    OffMap,
}

/// One interpolated state of a motion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MotionPoint {
    /// A heading of an in-place turn, at the start (`at_end = false`) or the end state.
    Turn {
        /// At the end state.
        at_end: bool,
        /// Settler yaw.
        theta: Real,
    },
    /// A point of the straight drive.
    Drive {
        /// x of the ground point.
        x: Real,
        /// y of the ground point.
        y: Real,
        /// Settler yaw (the drive heading).
        theta: Real,
    },
    /// The end state itself.
    End,
}

/// The interpolation of one motion: `turn_a` headings at the start (the last one is the drive heading), `drive`
/// points (the last one is the end state's ground point), `turn_b - 1` headings at the end, then the end state.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionPlan {
    a_ground: Vec3,
    b_ground: Vec3,
    a_theta: Real,
    drive_theta: Real,
    turn_a: u32,
    drive: u32,
    turn_b: u32,
    /// Radians turned at the start.
    pub turn_a_rad: Real,
    /// Radians turned at the end.
    pub turn_b_rad: Real,
}

fn steps(amount: Real, resolution: Real) -> u32 {
    let n = libm::ceilf(libm::fabsf(amount) / resolution);
    if n.is_finite() && n < (MAX_MOTION_STATES * 2) as Real {
        n as u32
    } else {
        MAX_MOTION_STATES * 2
    }
}

impl MotionPlan {
    /// The interpolation of the motion `a -> b`. Settler yaws are used as headings (on level ground they are the
    /// same; on a slope the settler measures yaw from the world x axis projected on the slope).
    pub fn new(a: &RoverState, b: &RoverState, p: &TetherSpaceParams) -> Self {
        let d = b.ground - a.ground;
        let len = libm::sqrtf(d.x * d.x + d.y * d.y);
        let psi = if len > 1e-6 { libm::atan2f(d.y, d.x) } else { a.theta };
        let cost_of = |h: Real| libm::fabsf(angle_diff(h, a.theta)) + libm::fabsf(angle_diff(b.theta, h));
        let back = psi + core::f32::consts::PI;
        let drive_theta = if cost_of(back) < cost_of(psi) { back } else { psi };
        let turn_a_rad = angle_diff(drive_theta, a.theta);
        let turn_b_rad = angle_diff(b.theta, drive_theta);
        MotionPlan {
            a_ground: a.ground,
            b_ground: b.ground,
            a_theta: a.theta,
            drive_theta,
            turn_a: steps(turn_a_rad, p.turn_resolution_rad),
            drive: steps(len, p.drive_resolution_m),
            turn_b: steps(turn_b_rad, p.turn_resolution_rad),
            turn_a_rad,
            turn_b_rad,
        }
    }
    /// Interpolated states, the end state included.
    pub fn total_states(&self) -> u32 {
        self.turn_a.saturating_add(self.drive).saturating_add(self.turn_b.max(1))
    }
    /// The `k`-th interpolated state, `1 ..= total_states()` (the start state is `k = 0`, not checked again).
    /// Turns end at the drive heading; the drive's last point is the end state's ground, at the drive heading.
    pub fn state(&self, k: u32) -> MotionPoint {
        if k <= self.turn_a {
            let t = k as Real / self.turn_a.max(1) as Real;
            return MotionPoint::Turn { at_end: false, theta: self.a_theta + t * self.turn_a_rad };
        }
        let k = k - self.turn_a;
        if k <= self.drive {
            let t = k as Real / self.drive.max(1) as Real;
            let p = self.a_ground + (self.b_ground - self.a_ground) * t;
            return MotionPoint::Drive { x: p.x, y: p.y, theta: self.drive_theta };
        }
        let k = k - self.drive;
        if k < self.turn_b {
            let t = k as Real / self.turn_b.max(1) as Real;
            return MotionPoint::Turn { at_end: true, theta: self.drive_theta + t * self.turn_b_rad };
        }
        MotionPoint::End
    }
}

/// The motion validator (see the module docs); the work counters live in the space ([`TetherSpace::stats`]).
#[derive(Debug, Clone, Copy, Default)]
pub struct TetherMotionValidator;

impl<D: DistanceField> MotionValidator<TetherSpace<'_, D>> for TetherMotionValidator {
    fn check_motion(
        &mut self,
        space: &TetherSpace<'_, D>,
        from: &RoverState,
        from_attachment: &AnchorHistory,
        to: &RoverState,
    ) -> MotionCheck<AnchorHistory> {
        match space.check(from, from_attachment, to) {
            Ok(attachment) => MotionCheck::Valid { attachment },
            Err(_) => MotionCheck::Invalid,
        }
    }
}
