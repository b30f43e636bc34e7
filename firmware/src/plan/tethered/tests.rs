use super::*;
use crate::config::rover::RoverParams;
use crate::config::tethered::{SURFACE_MIN_STEP_M, SURFACE_UNKNOWN_STEPS, SURFACE_UNKNOWN_STEP_M};
use crate::geom::{Real, Vec3};
use crate::map::{DistanceField, DistanceQuery};
use crate::tether::{Anchor, AnchorHistory};

/// The plane z = 0 (exact signed distance).
struct Ground;
impl DistanceField for Ground {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        DistanceQuery::Known { distance: p.z, gradient: Vec3::z() }
    }
}
struct Nothing;
impl DistanceField for Nothing {
    fn query(&self, _: &Vec3) -> DistanceQuery {
        DistanceQuery::Unknown
    }
}
const BOUNDS: PlanBounds = PlanBounds { min: [-10.0, -10.0, -1.0], max: [10.0, 10.0, 5.0] };

fn history(points: &[[Real; 3]]) -> AnchorHistory {
    let mut h = AnchorHistory::default();
    for p in points {
        h.push(Anchor { point: Vec3::new(p[0], p[1], p[2]), gradient: Vec3::z() }).unwrap();
    }
    h
}

/// The plane z = 0 observed only below `observed_above` metres (unknown higher up: a floor seen from a rim).
struct ObservedBelow(Real);
impl DistanceField for ObservedBelow {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        if p.z > self.0 { DistanceQuery::Unknown } else { Ground.query(p) }
    }
}

#[test]
fn surface_point_finds_the_observed_surface_under_unknown_space_and_refuses_a_column_without_one() {
    let p = surface_point(&Ground, 1.0, 2.0, 5.0, -1.0).unwrap();
    assert!(p.z.abs() <= SURFACE_MIN_STEP_M * 0.5, "{p:?}");
    assert_eq!((p.x, p.y), (1.0, 2.0));
    assert_eq!(surface_point(&Nothing, 1.0, 2.0, 5.0, -1.0), None);
    // the surface is below the search range
    assert_eq!(surface_point(&Ground, 0.0, 0.0, 5.0, 1.0), None);
    // 4.8 m of unknown space above a band observed 0.2 m up: stepped through, the surface found
    let p = surface_point(&ObservedBelow(0.2), 1.0, 2.0, 5.0, -1.0).unwrap();
    assert!(p.z.abs() <= SURFACE_MIN_STEP_M * 0.5, "{p:?}");
    // more unknown space than the budget (`SURFACE_UNKNOWN_STEPS` x `SURFACE_UNKNOWN_STEP_M`): refused
    let top = 0.2 + SURFACE_UNKNOWN_STEP_M * (SURFACE_UNKNOWN_STEPS + 2) as Real;
    assert_eq!(surface_point(&ObservedBelow(0.2), 1.0, 2.0, top, -1.0), None);
}

#[test]
fn tether_bend_is_the_sum_of_turning_angles() {
    let straight = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    assert!(tether_bend(&straight, &Vec3::new(2.0, 0.0, 0.0)).abs() < 1e-5);
    let right = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]);
    let b = tether_bend(&right, &Vec3::new(1.0, 1.0, 0.0));
    assert!((b - core::f32::consts::FRAC_PI_2).abs() < 1e-5, "{b}");
    // two right angles in a row: a U-turn around a post
    let u = history(&[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [1.0, 1.0, 0.0]]);
    let b = tether_bend(&u, &Vec3::new(0.0, 1.0, 0.0));
    assert!((b - core::f32::consts::PI).abs() < 1e-5, "{b}");
}

#[test]
fn wraps_merge_close_anchors_and_compatibility_follows_them() {
    let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
    // root, then three anchors 0.1 m apart around a post, then a lip 3 m away
    let fine = history(&[[9.0, 0.0, 6.0], [0.0, 0.25, 4.5], [-0.1, 0.2, 4.5], [-0.2, 0.1, 4.5], [3.0, -0.5, 4.0]]);
    let coarse = history(&[[9.0, 0.0, 6.0], [0.0, 0.25, 4.5], [-0.18, 0.12, 4.5], [3.0, -0.5, 4.0]]);
    let w = wraps(&fine, space.params().anchor_cluster_m);
    assert_eq!(w.len(), 3);
    assert_eq!(w[1], Vec3::new(-0.2, 0.1, 4.5));
    assert!(space.histories_match(&fine, &coarse));
    // the same post wrapped on its other side (last anchor 0.5 m away) is another history
    let other_side = history(&[[9.0, 0.0, 6.0], [0.0, -0.25, 4.5], [-0.2, -0.3, 4.5], [3.0, -0.5, 4.0]]);
    assert!(!space.histories_match(&fine, &other_side));
    // one wrap more or less is another history
    let root_only = history(&[[9.0, 0.0, 6.0]]);
    assert!(!space.histories_match(&root_only, &coarse));
    assert!(space.histories_match(&root_only, &root_only.clone()));
}

#[test]
fn motion_plan_turns_the_short_way_and_drives_backwards_when_cheaper() {
    let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
    let a = space.settle_state(0.0, 0.0, 0.0).unwrap();
    let b = space.settle_state(2.0, 0.0, 0.0).unwrap();
    let p = MotionPlan::new(&a, &b, space.params());
    assert_eq!((p.turn_a_rad, p.turn_b_rad), (0.0, 0.0));
    // 2 m at 0.2 m: 10 drive states, the last of which is followed by the end state
    assert_eq!(p.total_states(), 11);
    assert_eq!(p.state(11), MotionPoint::End);
    assert!(matches!(p.state(10), MotionPoint::Drive { x, .. } if (x - 2.0).abs() < 1e-5));
    // facing away from the target: Axel reverses instead of turning around
    let c = space.settle_state(-2.0, 0.0, 0.0).unwrap();
    let p = MotionPlan::new(&a, &c, space.params());
    assert!(p.turn_a_rad.abs() < 1e-5 && p.turn_b_rad.abs() < 1e-5, "{p:?}");
    // a quarter turn at the end, in ceil((pi/2) / 0.5) = 4 steps
    let d = space.settle_state(2.0, 0.0, core::f32::consts::FRAC_PI_2).unwrap();
    let p = MotionPlan::new(&a, &d, space.params());
    assert!((p.turn_b_rad.abs() - core::f32::consts::FRAC_PI_2).abs() < 1e-5);
    assert_eq!(p.total_states(), 10 + 4);
}

#[test]
fn flat_ground_motion_is_valid_and_keeps_a_straight_tether() {
    let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
    let a = space.settle_state(0.0, 0.0, 0.0).unwrap();
    let b = space.settle_state(3.0, 1.0, 0.5).unwrap();
    let root = history(&[[-6.0, 0.0, 2.0]]);
    let h = space.check(&a, &root, &b).unwrap();
    assert_eq!(h.len(), 1);
    let s = space.stats();
    assert_eq!((s.motions, s.motions_valid), (1, 1));
    assert!(s.stability_checks as usize >= MotionPlan::new(&a, &b, space.params()).total_states() as usize);
}

#[test]
fn off_map_goal_connects_only_near_the_edge() {
    let space = TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
    let goal = space.goal_state(Vec3::new(30.0, 0.0, 0.35), 0.0).unwrap();
    assert!(goal.off_map);
    let root = history(&[[-6.0, 0.0, 2.0]]);
    let near = space.settle_state(9.5, 0.0, 0.0).unwrap();
    let far = space.settle_state(0.0, 0.0, 0.0).unwrap();
    assert!(space.check(&near, &root, &goal).is_ok());
    assert_eq!(space.check(&far, &root, &goal), Err(MotionFailure::OffMap));
    assert_eq!(space.check(&goal, &root, &near), Err(MotionFailure::OffMap));
}

#[test]
fn bad_parameters_and_bounds_are_named() {
    let mut p = TetherSpaceParams::DEFAULT;
    p.drive_resolution_m = 0.0;
    assert_eq!(TetherSpace::new(&Ground, BOUNDS, RoverParams::AXEL, p).err().map(|e| e.0), Some("drive_resolution_m/turn_resolution_rad"));
    let mut b = BOUNDS;
    b.max[2] = b.min[2];
    assert_eq!(TetherSpace::new(&Ground, b, RoverParams::AXEL, TetherSpaceParams::DEFAULT).err().map(|e| e.0), Some("bounds"));
}

/// A plane through the origin with unit normal `n` (exact signed distance).
struct Plane(Vec3);
impl DistanceField for Plane {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        DistanceQuery::Known { distance: p.dot(&self.0), gradient: self.0 }
    }
}

/// A wheel's contact normal that reads steeper than the limit (a map bump moved its rim point) on a 55-degree face is
/// not a steep contact: the face's own gradient is not steep. Against a wall both are steep; an unobserved contact
/// point counts as steep; a contact normal within the limit is never steep, whatever the field says there.
#[test]
fn a_steep_contact_needs_a_steep_surface_too() {
    use crate::rover::WheelContact;
    let incline = |deg: Real| {
        let r = deg.to_radians();
        Vec3::new(libm::sinf(r), 0.0, libm::cosf(r))
    };
    let wheel = |normal: Vec3| WheelContact { point: Vec3::zeros(), normal, gap_m: 0.0 };
    let limit_deg = crate::config::tethered::MAX_WHEEL_CONTACT_INCLINE_RAD.to_degrees();
    let tilted = wheel(incline(limit_deg + 10.0));
    assert!(!space::rests_on_steep_surface(&Plane(incline(55.0)), &tilted));
    assert!(space::rests_on_steep_surface(&Plane(incline(90.0)), &tilted));
    assert!(space::rests_on_steep_surface(&Plane(incline(limit_deg + 2.0)), &tilted));
    assert!(space::rests_on_steep_surface(&Nothing, &tilted));
    let level = wheel(incline(limit_deg - 5.0));
    assert!(!space::rests_on_steep_surface(&Plane(incline(90.0)), &level));
    assert!(!space::rests_on_steep_surface(&Nothing, &level));
}

/// The plane z = 0 and a ball of radius 5 cm floating at `0` (exact signed distance): an obstacle at the body's
/// height between the wheels.
struct GroundAndBall(Vec3);
impl DistanceField for GroundAndBall {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        let d = p - self.0;
        let ball = d.norm() - 0.05;
        if ball < p.z {
            DistanceQuery::Known { distance: ball, gradient: d / d.norm() }
        } else {
            Ground.query(p)
        }
    }
}

/// A start within the extra clearance of an obstacle (not within the rover's own) settles only through the escape
/// zone, and so do states within the zone's radius of it; a state as near the obstacle outside the zone still
/// collides, and so does one in the zone that collides with the rover's own clearance.
#[test]
fn a_start_escape_relaxes_the_clearance_only_round_the_start() {
    let own = RoverParams::AXEL;
    let mut padded = own;
    padded.body_clearance_m += 0.1;
    let axle = own.wheel_radius_m;
    let settles = |rover, x: Real| {
        let ball = GroundAndBall(Vec3::new(x, 0.0, axle));
        TetherSpace::new(&ball, BOUNDS, rover, TetherSpaceParams::ONBOARD).unwrap().settle_state(0.0, 0.0, 0.0)
    };
    // the nearest ball ahead (1 cm steps) with which the rover settles with its own clearance
    let x = (0..200).map(|i| 0.05 + 0.01 * i as Real).find(|&x| settles(own, x).is_ok()).unwrap();
    assert_eq!(settles(padded, x), Err(SettleFailure::Collision), "ball at {x}");
    let ball = GroundAndBall(Vec3::new(x, 0.0, axle));
    let escape = StartEscape { x: 0.0, y: 0.0, radius_m: 0.1, rover: own, steep_ok: false };
    let relaxed = TetherSpace::new(&ball, BOUNDS, padded, TetherSpaceParams::ONBOARD).unwrap().with_start_escape(Some(escape));
    assert!(relaxed.settle_state(0.0, 0.0, 0.0).is_ok());
    assert!(relaxed.settle_state(-0.05, 0.05, 0.0).is_ok(), "inside the zone");
    assert_eq!(relaxed.settle_state(2.0 * x, 0.0, 0.0), Err(SettleFailure::Collision), "outside the zone, as near");
    assert_eq!(relaxed.settle_state(0.05, 0.0, 0.0), Err(SettleFailure::Collision), "nearer than its own clearance");
}

/// On a 35-degree plane a pose estimate's axle settled as a surface point puts the axle about `r sin(35 deg)` =
/// 0.20 m downhill of where it was asked (the offset along the normal, which leans downhill), and the heading off the asked one except along the
/// fall line or the contour; `settle_under_axle` puts the axle where it is (within `AXLE_SETTLE_TOLERANCE_M`) with
/// the asked heading, for every heading round the compass.
#[test]
fn a_pose_estimate_settles_with_its_own_axle_and_heading() {
    use crate::config::tethered::{AXLE_SETTLE_HEADING_RAD, AXLE_SETTLE_TOLERANCE_M};
    let slope: Real = 35.0_f32.to_radians();
    // the plane descends towards +x: its normal leans towards +x
    let plane = Plane(Vec3::new(libm::sinf(slope), 0.0, libm::cosf(slope)));
    let space = TetherSpace::new(&plane, BOUNDS, RoverParams::AXEL, TetherSpaceParams::DEFAULT).unwrap();
    let r = RoverParams::AXEL.wheel_radius_m;
    let (x, y) = (0.4, -0.3);
    for k in 0..12 {
        let heading = crate::geom::wrap_angle(k as Real * core::f32::consts::PI / 6.0 - 2.0);
        let naive = space.settle_state(x, y, heading).unwrap();
        let miss = libm::hypotf(naive.axle().x - x, naive.axle().y - y);
        assert!(miss > 0.75 * r * libm::sinf(slope), "heading {heading}: the surface point's axle misses by {miss} only");
        let st = space.settle_under_axle(x, y, heading).unwrap();
        let a = st.axle();
        assert!(libm::hypotf(a.x - x, a.y - y) <= AXLE_SETTLE_TOLERANCE_M, "heading {heading}: axle at {a:?}");
        assert!(crate::geom::angle_diff(st.heading(), heading).abs() <= AXLE_SETTLE_HEADING_RAD, "heading {heading}: {}", st.heading());
        // the axle stands a wheel radius off the plane, downhill of its surface point
        assert!((a.dot(&plane.0) - r).abs() < 0.01, "axle {} off the plane", a.dot(&plane.0));
        assert!(st.ground.x < x, "the surface point lies uphill of the axle");
    }
}

/// A state whose margin is positive but below `min_stability_margin` is refused, except inside a margin escape
/// zone that accepts its margin; a state as thin outside the zone, or thinner than the zone's minimum inside it,
/// is still refused.
#[test]
fn a_margin_escape_accepts_the_start_s_own_margin_only_round_the_start() {
    use crate::plan::tethered::MarginEscape;
    let params = TetherSpaceParams::DEFAULT;
    // the slope (descending towards +x, slack tether) on which a settled state's margin is thin
    let mut thin = None;
    for tenth in 0..900 {
        let slope: Real = (tenth as Real * 0.1).to_radians();
        let plane = Plane(Vec3::new(libm::sinf(slope), 0.0, libm::cosf(slope)));
        let space = TetherSpace::new(&plane, BOUNDS, RoverParams::AXEL, params).unwrap();
        let Ok(st) = space.settle_state(0.0, 0.0, 0.0) else { continue };
        let hist = history(&[]); // slack: the brakes' friction alone holds the rover
        let pull = tether_pull_anchor(&st.settled, &hist, &RoverParams::AXEL);
        if let Ok((crate::stability::StabilityOutcome::Stable(r), _)) =
            crate::rover::check_pose_stability(&plane, &st.settled, pull.as_ref(), &RoverParams::AXEL)
        {
            if r.margin > 0.2 * params.min_stability_margin && r.margin < 0.8 * params.min_stability_margin {
                thin = Some((slope, r.margin, hist));
                break;
            }
        }
    }
    let (slope, margin, hist) = thin.expect("a slope with a thin margin");
    let plane = Plane(Vec3::new(libm::sinf(slope), 0.0, libm::cosf(slope)));
    let space = TetherSpace::new(&plane, BOUNDS, RoverParams::AXEL, params).unwrap();
    let st = space.settle_state(0.0, 0.0, 0.0).unwrap();
    assert_eq!(space.stable_with(&st.settled, &hist), Err(MotionFailure::Unstable), "margin {margin} at {slope} rad");
    let a = st.axle();
    let zone = |min_margin| MarginEscape { x: a.x, y: a.y, radius_m: 0.2, min_margin };
    let relaxed = TetherSpace::new(&plane, BOUNDS, RoverParams::AXEL, params).unwrap().with_margin_escape(Some(zone(margin)));
    assert_eq!(relaxed.stable_with(&st.settled, &hist), Ok(margin));
    assert!(relaxed.stable_enough(&st.settled, &hist).is_ok());
    // the same pose 0.5 m along the contour (the same margin on a plane) is outside the zone
    let far = relaxed.settle_state(0.0, 0.5, 0.0).unwrap();
    assert_eq!(relaxed.stable_with(&far.settled, &hist.clone()), Err(MotionFailure::Unstable));
    // a zone asking for more than the state has refuses it
    let strict = TetherSpace::new(&plane, BOUNDS, RoverParams::AXEL, params).unwrap().with_margin_escape(Some(zone(margin + 1e-3)));
    assert_eq!(strict.stable_with(&st.settled, &hist), Err(MotionFailure::Unstable));
    assert_eq!(relaxed.min_margin_at(&far.settled), params.min_stability_margin);
}
