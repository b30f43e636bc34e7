//! The physics judge on poses whose answer follows from statics alone (no planner code involved).

use super::*;
use crate::world::crater::{CraterWall, CraterWallParams};
use crate::world::ledge::LedgeWorld;

fn judge(world: &dyn World) -> PhysicsJudge {
    PhysicsJudge::new(world, RoverParams::AXEL).expect("judge")
}

#[test]
fn flat_ground_holds_without_a_tether_pull() {
    let w = LedgeWorld::new();
    let j = judge(&w);
    // On the flat ground in front of the ledge, the tether slack from an anchor far above.
    let anchor = [6.0, 0.0, 3.0];
    let v = j.hold(GroundPose { x: 6.0, y: 2.0, yaw: 0.3 }, &TetherSpec { anchor, free_length_m: Some(10.0) });
    assert!(v.holds(), "{v:?}");
    let pl = v.placement.expect("placed");
    assert!((pl.axle[2] - 0.35).abs() < 0.01, "axle at {:?}", pl.axle);
}

#[test]
fn steep_slope_without_tether_falls_and_with_a_pull_from_above_holds() {
    // The 55-degree slope: tan 55 = 1.43 > mu 0.6, so a braked rover slides without help...
    let w = LedgeWorld::new();
    let j = judge(&w);
    let pose = GroundPose { x: 1.4, y: 0.0, yaw: 0.0 };
    let slack = TetherSpec { anchor: [-6.4, 0.0, 6.35], free_length_m: Some(50.0) };
    let v = j.hold(pose, &slack);
    assert_eq!(v.outcome, HoldOutcome::Falls, "{v:?}");
    assert!(v.slide_m > HOLD_SLIDE_M);
    // ...and a taut tether over the lip (the true anchor is on the lip, straight up-slope) holds it.
    let taut = TetherSpec { anchor: [0.0, 0.0, 4.0], free_length_m: None };
    let v = j.hold(pose, &taut);
    assert!(v.holds(), "{v:?}");
    let pl = v.placement.expect("placed");
    assert!(pl.tip[0] < pl.axle[0], "the boom trails up-slope towards the lip: {pl:?}");
}

#[test]
fn friction_decides_a_moderate_slope() {
    // A 25-degree crater wall without rocks: tan 25 = 0.47, below the wheels' 0.6 and the boom's 0.4 combined
    // as long as the wheels carry most of the load; with 0.3 everywhere it slides.
    let params = CraterWallParams { wall_angle_deg: 25.0, rocks: 0, ..CraterWallParams::default() };
    let w = CraterWall::new(params).expect("world");
    let x = 0.5 * w.foot_x();
    let pose = GroundPose { x, y: 0.0, yaw: 0.0 };
    let slack = TetherSpec { anchor: [-20.0, 0.0, 30.0], free_length_m: Some(100.0) };
    let v = judge(&w).hold(pose, &slack);
    // Facing down the fall line the braked wheels hold by friction alone (the boom rests on the ground too).
    assert!(v.holds(), "mu 0.6 on 25 degrees: {v:?}");
    let mut slippery = RoverParams::AXEL;
    slippery.wheel_mu = 0.3;
    slippery.boom_mu = 0.3;
    let v = PhysicsJudge::new(&w, slippery).expect("judge").hold(pose, &slack);
    assert_eq!(v.outcome, HoldOutcome::Falls, "mu 0.3 on 25 degrees: {v:?}");
}

#[test]
fn hold_is_deterministic() {
    let w = LedgeWorld::with_pole();
    let j = judge(&w);
    let pose = GroundPose { x: 0.9, y: 0.4, yaw: 0.2 };
    let t = TetherSpec { anchor: [0.0, 0.3, 4.0], free_length_m: None };
    assert_eq!(j.hold(pose, &t), j.hold(pose, &t));
}

#[test]
fn drive_straight_on_flat_ground_arrives_and_off_the_lip_falls() {
    let w = LedgeWorld::new();
    let j = judge(&w);
    let slack = TetherSpec { anchor: [6.0, 0.0, 3.0], free_length_m: Some(30.0) };
    let d = j.drive(GroundPose { x: 5.0, y: 0.0, yaw: 0.0 }, &slack, DriveCommand::Straight { distance_m: 1.0, speed_mps: 0.3 });
    assert!(d.placed && d.completed && !d.fell, "{d:?}");
    assert!((d.end_axle[0] - 6.0).abs() < 0.1 && d.end_axle[1].abs() < 0.05, "{d:?}");
    // Turning in place on flat ground.
    let d = j.drive(GroundPose { x: 5.0, y: 0.0, yaw: 0.0 }, &slack, DriveCommand::Turn { angle_rad: 1.0, rate_radps: 0.5 });
    assert!(d.completed && !d.fell && (d.end_yaw - 1.0).abs() < 0.15, "{d:?}");
    // Driving from the ledge top over the lip with a slack tether: the rover slides down the slope.
    let loose = TetherSpec { anchor: [-6.4, 0.0, 6.35], free_length_m: Some(40.0) };
    let d = j.drive(GroundPose { x: -0.5, y: 0.0, yaw: 0.0 }, &loose, DriveCommand::Straight { distance_m: 1.2, speed_mps: 0.3 });
    assert!(d.placed && d.fell, "{d:?}");
}


#[test]
fn a_dem_pose_is_placed_like_the_analytic_one() {
    use crate::terrain::Heightmap;
    use crate::world::heightmap::HeightmapWorld;
    // The ledge as a 0.25 m DEM whose posts include the lip: on the slope the heights are the same planes.
    let ledge = LedgeWorld::new();
    let s = 0.25;
    let (nx, ny) = (89usize, 81usize);
    let hs = (0..nx * ny).map(|k| Some(ledge.height_f64(-11.0 + (k % nx) as f64 * s, -10.0 + (k / nx) as f64 * s))).collect();
    let dem = HeightmapWorld::new("ledge-dem", &Heightmap { width: nx, height: ny, spacing_m: s, heights_m: hs }, 1.0, 1.0).expect("dem");
    let pose = GroundPose { x: 1.4, y: 0.0, yaw: 0.0 };
    let (a, b) = (judge(&dem).axle_at(pose).expect("dem"), judge(&ledge).axle_at(pose).expect("analytic"));
    assert!((a[2] - b[2]).abs() < 1e-6, "{a:?} vs {b:?}");
}

/// The pose's heading is the rolling direction's, as the flight software's (`RoverState::heading`): on the
/// ledge's 55-degree face a rover headed 10 and 40 degrees off the fall line stands with its axle in the face
/// (both wheels on it) and perpendicular to the rolling direction that has that horizontal heading. The face's
/// normal is the closed form `(sin 55, 0, cos 55)`. (The judge once kept the rover's x axis horizontal instead,
/// which on the face turned the axle 11 degrees away from the planner's pose at 10 degrees off the fall line.)
#[test]
fn a_heading_across_the_face_is_the_rolling_direction() {
    let w = LedgeWorld::new();
    let j = judge(&w);
    let a = 55f64.to_radians();
    let n = [a.sin(), 0.0, a.cos()];
    for off_deg in [10.0f64, -40.0, 170.0] {
        let yaw = off_deg.to_radians();
        let pl = j.place(GroundPose { x: 1.4, y: 0.0, yaw }, [-6.4, 0.0, 6.35], BoomSetting::Inline).expect("placed");
        let ax = pl.axle_dir;
        let in_face = ax[0] * n[0] + ax[1] * n[1] + ax[2] * n[2];
        assert!(in_face.abs() < 0.01, "{off_deg} deg: axle {ax:?} leaves the face ({in_face})");
        // rolling direction = axle x n
        let f = [ax[1] * n[2] - ax[2] * n[1], ax[2] * n[0] - ax[0] * n[2], ax[0] * n[1] - ax[1] * n[0]];
        let heading = f[1].atan2(f[0]);
        let err = (heading - yaw + core::f64::consts::PI).rem_euclid(core::f64::consts::TAU) - core::f64::consts::PI;
        assert!(err.abs() < 0.5f64.to_radians(), "{off_deg} deg: rolling heading {} deg", heading.to_degrees());
    }
}

#[test]
fn just_over_the_lip_the_boom_reaches_back_past_it_and_the_tether_runs_to_the_root() {
    // The axle 0.6 m down the 55-degree slope, facing down it: a tether ending at the axle wraps the lip
    // (x = 0, z = 4), 0.65 m away, less than the 1 m boom. The tether leaves at the boom tip, over the ledge top.
    let w = LedgeWorld::new();
    let j = judge(&w);
    let root = [-6.4, 0.0, 6.35];
    let pose = GroundPose { x: 0.6, y: 0.0, yaw: 0.0 };
    let to = |end: P3| crate::truth::tether::true_tether(&w, root, end, None).expect("a tether");
    let axle = j.place(pose, root, BoomSetting::Inline).expect("placed").axle;
    let lip = *to(axle).contacts.last().expect("a tether to the axle wraps the lip");
    assert!(lip[0].abs() < 1e-9 && (lip[2] - 4.0).abs() < 1e-9, "{lip:?}");
    assert!(firmware::geom::p3::dist(axle, lip) < f64::from(RoverParams::AXEL.boom_length_m), "{axle:?}");
    let aimed = j.aim_tether(pose, lip, |tip| Ok::<_, ()>(to(tip).contacts.last().copied().unwrap_or(root)));
    assert_eq!(aimed, Ok(Some(root)), "the tether from the tip clears the lip");
    // Pulled from the tip towards the root the rover holds; pulled back down to the lip it would not be.
    assert!(j.hold(pose, &TetherSpec { anchor: root, free_length_m: None }).holds());
    let to_lip = j.hold(pose, &TetherSpec { anchor: lip, free_length_m: None });
    assert_eq!(to_lip.outcome, HoldOutcome::Falls, "{to_lip:?}");
}

/// Regression: on the 0.05 m DEM rendering of the ledge (`scenarios/variants/ledge_test1_dem.toml`) the judge
/// could not place the rover at x = -1.25 or -1.2 on the flat top (parry's height-field ray cast missed the
/// vertical rays along those post columns), so every test-1 path on the rendering was counted unstable at its
/// sixth pose. Every post position along test 1's start row now places, at the top's height.
#[test]
fn the_rover_is_placed_on_a_dem_rendering_at_every_post() {
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/variants/ledge_test1_dem.toml");
    let world = crate::scenario::load(&file).expect("scenario").build_world().expect("world");
    let j = judge(world.as_ref());
    for k in 0..=40 {
        let x = -2.0 + 0.05 * f64::from(k);
        let axle = j.axle_at(GroundPose { x, y: 0.0, yaw: 0.0 });
        let z = axle.unwrap_or_else(|| panic!("no placement at x = {x}"))[2];
        assert!((z - 4.35).abs() < 0.01, "x = {x}: axle at z = {z}");
    }
}

#[test]
fn a_rover_straddling_the_lip_rests_on_both_wheels() {
    // Axle across the lip (heading along y): the -x wheel on the top, the +x wheel hanging against the 55-degree
    // face. The ground under the hanging wheel's centre is 1.2 m below the top, so re-rolling through the heights
    // under the wheel centres clamps the axle at 82 degrees with one wheel in the air; the pivot from level rests
    // the hanging wheel's rim on the face.
    let w = LedgeWorld::new();
    let j = judge(&w);
    let r = f64::from(RoverParams::AXEL.wheel_radius_m);
    let pose = GroundPose { x: 0.35, y: 0.0, yaw: -core::f64::consts::FRAC_PI_2 };
    let pl = j.place(pose, [-6.4, 0.0, 6.35], BoomSetting::Inline).expect("placed");
    let tilt = pl.axle_dir[2].abs().asin().to_degrees();
    assert!((20.0..70.0).contains(&tilt), "axle tilt {tilt:.1} degrees: {pl:?}");
    // both wheels touch: each wheel's cylinder, cast down from the placed pose, meets the terrain within the gap
    let rot = PhysicsJudge::rotation(pl.frame_yaw, pl.axle_dir[2].asin());
    let ht = 0.5 * f64::from(RoverParams::AXEL.track_m);
    for side in [1.0, -1.0] {
        let at = v3(pl.axle) + rot * Vector::new(0.0, side * ht, 0.0);
        let drop = j.terrain().cast_shape(&Pose::from_parts(at, rot), j.wheel_shape().as_ref(), [0.0, 0.0, -1.0], 1.0);
        let drop = drop.expect("ground under the wheel");
        assert!(drop <= 2.0 * PLACE_GAP_M + 1e-6, "wheel {side}: {drop:.4} m above the terrain (r {r})");
    }
}
