//! Judging a planned path with the physics judge: every pose along it, interpolated finely, must hold with the
//! true tether.
//!
//! A path is a list of states (axle centre, world heading). Each motion between two states is executed the way
//! Paton et al.'s planner commands it (section V: in-place turns and straight drives): turn in place to the drive
//! heading (the direction of travel, or its reverse when that needs less turning), drive straight, turn to the
//! next state's heading. Poses are taken every [`POSE_STEP_M`] (5 cm) of driving and every [`TURN_STEP_RAD`]
//! (0.1 rad: each wheel moves `track / 2 * 0.1` = 5 cm) of turning, both ends included.
//!
//! The true tether ([`crate::truth::taut`]) follows the **boom tip** (where the tether leaves the rover) from the
//! first pose on: at each pose the inline boom is aimed at the tether's last anchor, the tether's end moved to
//! that tip, the boom re-aimed at the new last anchor (twice at most, until the anchor moves less than 1 mm). The
//! judge's rope then runs from that true last anchor to the boom tip, taut ([`super::PhysicsJudge::hold`]; its
//! resting-boom settings keep this anchor). The path is
//! **stable** iff every pose holds. A pose that cannot be placed or a tether that cannot be computed is a failure
//! with its reason (unsafe, never skipped).

use serde::{Deserialize, Serialize};

use super::{GroundPose, HoldOutcome, PhysicsJudge, TetherSpec};
use crate::truth::taut::{TautTether, WrapEdges, SHORTEST_SAMPLE_M};
use firmware::geom::p3::P3;

/// Largest drive between two judged poses, metres.
pub const POSE_STEP_M: f64 = 0.05;
/// Largest turn between two judged poses, radians.
pub const TURN_STEP_RAD: f64 = 0.1;

/// A planned state as the judge reads it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PathPose {
    /// Axle centre, world frame.
    pub axle: P3,
    /// World heading of the rover's x axis, radians.
    pub heading: f64,
}

/// The physics judge's verdict on a path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PathJudgement {
    /// Every pose holds.
    pub stable: bool,
    /// Poses judged (up to and including the first failure).
    pub poses: u32,
    /// The first failure: where and why.
    pub failure: Option<String>,
    /// Largest slide over the poses judged, metres.
    pub max_slide_m: f64,
    /// The true tether's contact points at the last pose judged (root excluded).
    pub final_contacts: Vec<P3>,
}

fn wrap(a: f64) -> f64 {
    let t = core::f64::consts::TAU;
    let r = (a + core::f64::consts::PI).rem_euclid(t) - core::f64::consts::PI;
    if r <= -core::f64::consts::PI {
        r + t
    } else {
        r
    }
}

/// The interpolated poses of a path (see the module docs): (x, y, heading).
pub fn interpolate(path: &[PathPose]) -> Vec<(f64, f64, f64)> {
    let mut out = Vec::new();
    let Some(first) = path.first() else { return out };
    out.push((first.axle[0], first.axle[1], first.heading));
    let turn = |out: &mut Vec<(f64, f64, f64)>, x: f64, y: f64, from: f64, to: f64| {
        let d = wrap(to - from);
        let n = (d.abs() / TURN_STEP_RAD).ceil() as usize;
        for k in 1..=n {
            out.push((x, y, from + d * k as f64 / n as f64));
        }
    };
    for w in path.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (dx, dy) = (b.axle[0] - a.axle[0], b.axle[1] - a.axle[1]);
        let len = (dx * dx + dy * dy).sqrt();
        let psi = if len > 1e-6 { dy.atan2(dx) } else { a.heading };
        let cost = |h: f64| wrap(h - a.heading).abs() + wrap(b.heading - h).abs();
        let back = psi + core::f64::consts::PI;
        let drive = if cost(back) < cost(psi) { back } else { psi };
        turn(&mut out, a.axle[0], a.axle[1], a.heading, drive);
        let n = (len / POSE_STEP_M).ceil() as usize;
        for k in 1..=n {
            let t = k as f64 / n as f64;
            out.push((a.axle[0] + t * dx, a.axle[1] + t * dy, drive));
        }
        turn(&mut out, b.axle[0], b.axle[1], drive, b.heading);
    }
    out
}

/// Judge `path` with the tether from `root` (see the module docs).
pub fn judge_path(judge: &PhysicsJudge, edges: &WrapEdges, root: P3, path: &[PathPose]) -> PathJudgement {
    let poses = interpolate(path);
    let mut j = PathJudgement { stable: false, poses: 0, failure: None, max_slide_m: 0.0, final_contacts: Vec::new() };
    let mut tether: Option<TautTether> = None;
    for (k, &(x, y, heading)) in poses.iter().enumerate() {
        j.poses += 1;
        let pose = GroundPose { x, y, yaw: heading };
        // The tether ends at the boom tip, and the inline boom points at the tether's last anchor: start from the
        // previous last anchor (the root at first), move the tether's end to the tip, re-aim.
        let first = tether.as_ref().map_or(root, |t| t.last_anchor(edges));
        let aimed = judge.aim_tether(pose, first, |tip| {
            match tether.as_mut() {
                None => TautTether::shortest(edges, root, tip, SHORTEST_SAMPLE_M).map(|t| tether = Some(t)),
                Some(t) => t.update(edges, tip),
            }
            .map_err(|e| e.to_string())?;
            tether.as_ref().map(|t| t.last_anchor(edges)).ok_or_else(|| "no tether".to_string())
        });
        let why = match aimed {
            Ok(Some(_)) => None,
            Ok(None) => {
                j.failure = Some(format!("pose {k} ({x:.2}, {y:.2}, heading {:.1} deg): the rover cannot be placed (no ground, or the body or boom meets the terrain)", heading.to_degrees()));
                return j;
            }
            Err(why) => Some(why),
        };
        let Some(t) = tether.as_ref().filter(|_| why.is_none()) else {
            let why = why.unwrap_or_else(|| "no tether".to_string());
            j.failure = Some(format!("pose {k} ({x:.2}, {y:.2}): the true tether: {why}"));
            return j;
        };
        j.final_contacts = t.points(edges).iter().skip(1).take(t.contacts.len()).copied().collect();
        let v = judge.hold(pose, &TetherSpec { anchor: t.last_anchor(edges), free_length_m: None });
        j.max_slide_m = j.max_slide_m.max(v.slide_m);
        if v.outcome != HoldOutcome::Holds {
            j.failure = Some(format!(
                "pose {k} ({x:.2}, {y:.2}, heading {:.1} deg): {:?}, slid {:.3} m, tilted {:.1} deg",
                heading.to_degrees(),
                v.outcome,
                v.slide_m,
                v.tilt_deg
            ));
            return j;
        }
    }
    j.stable = !poses.is_empty();
    if poses.is_empty() {
        j.failure = Some("empty path".into());
    }
    j
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn interpolation_steps_are_at_most_5_cm_and_0_1_rad() {
        let path = [
            PathPose { axle: [0.0, 0.0, 0.35], heading: 0.0 },
            PathPose { axle: [1.0, 1.0, 0.35], heading: 2.0 },
            PathPose { axle: [1.0, 1.0, 0.35], heading: -2.5 },
        ];
        let p = interpolate(&path);
        assert_eq!(p.first(), Some(&(0.0, 0.0, 0.0)));
        let last = p.last().copied().expect("poses");
        assert!((last.0 - 1.0).abs() < 1e-12 && (wrap(last.2 + 2.5)).abs() < 1e-12, "{last:?}");
        for w in p.windows(2) {
            let d = ((w[1].0 - w[0].0).powi(2) + (w[1].1 - w[0].1).powi(2)).sqrt();
            assert!(d <= POSE_STEP_M + 1e-12 && wrap(w[1].2 - w[0].2).abs() <= TURN_STEP_RAD + 1e-12, "{w:?}");
            // a pose either turns in place or drives along its heading (or its reverse)
            if d > 1e-9 {
                let dir = (w[1].1 - w[0].1).atan2(w[1].0 - w[0].0);
                assert!(wrap(dir - w[1].2).abs() < 1e-9 || (wrap(dir - w[1].2).abs() - core::f64::consts::PI).abs() < 1e-9);
            }
        }
    }
}
