//! Unit tests of the closed-loop mission: the navigator driven through its `Autonomy` hooks against a tiny
//! kinematic world written here (flat ground mapped by synthetic downward scans; turns exact, straight drives moved
//! along the heading plus an optional lateral drift toward the tether's side computed by the test's own model: a
//! straight tether to the root, not the navigator's anchor history).

use super::*;
use crate::protocol::{
    LogLevel, MissionConfig, MissionState, MotionOutcome, PlannerConfig, Point3, Quat, StopReason,
    TelemetryConfig, TetherConfig, Tracking,
};
use std::boxed::Box;
use std::vec;
use std::vec::Vec;

type TestNav = Navigator<Vec<Block>, Vec<u32>, Box<NavPlanStorage>>;

const VOXEL: f32 = 0.1;
const SENSOR_H: f32 = 4.0;
const Z0: f32 = 0.03;
/// Axle height above the flat ground reported in the test world's poses (the wheel radius).
const AXLE_H: f32 = 0.35;

fn configure(root: Point3, mission: MissionConfig) -> Configure {
    Configure {
        rover: super::tests::TEST_ROVER,
        tether: TetherConfig { root_anchor: root, max_payout_m: 50.0, max_tension_n: 2000.0 },
        planner: PlannerConfig { rng_seed: 11, max_iterations: 750, batch_size: 100, goal_bias: 0.0 },
        telemetry: TelemetryConfig { period_ms: 0, forward_log_level: LogLevel::Off },
        mission,
        map: None,
    }
}

fn goal(id: u32, x: f32, y: f32) -> GoalRequest {
    GoalRequest {
        goal_id: id,
        position: Point3 { x, y, z: Z0 },
        tolerance_m: 0.4,
        planner: PlannerChoice::Abit,
        max_iterations: 120,
        time_budget_ms: 0,
        allow_approximate: false,
    }
}

fn scan_down(nav: &mut TestNav, id: u32, cx: f32) {
    scan_ground(nav, id, cx, &|_| true);
}

/// A downward scan from above `(cx, 0)` of the flat ground where `seen(x)` (elsewhere no return: unknown).
fn scan_ground(nav: &mut TestNav, id: u32, cx: f32, seen: &dyn Fn(f32) -> bool) {
    let step = 0.5 * VOXEL;
    let mut pts = Vec::new();
    for i in -20..=20 {
        for j in -44..=44 {
            let (x, y) = (i as f32 * step, j as f32 * step);
            if seen(cx + x) {
                pts.push(Point3 { x, y, z: Z0 - SENSOR_H });
            }
        }
    }
    let pose = Pose { position: Point3 { x: cx, y: 0.0, z: SENSOR_H }, orientation: Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 } };
    nav.integrate_scan(&Scan { scan_id: id, sensor_pose: pose, points: &pts }, Instant::from_micros(0));
}

/// A navigator configured with `root` and `mission`, the flat world mapped over x in [-1, 5], y in [-2.2, 2.2]; the
/// last scan from above the origin (the rover's first pose).
fn mapped(root: Point3, mission: MissionConfig) -> TestNav {
    mapped_where(root, mission, &|_| true)
}

fn mapped_where(root: Point3, mission: MissionConfig, seen: &dyn Fn(f32) -> bool) -> TestNav {
    let mut nav =
        Navigator::new(MapConfig::with_voxel_size(VOXEL), vec![Block::EMPTY; 4096], vec![0u32; 8192], Box::default())
            .unwrap();
    nav.configure(&configure(root, mission)).unwrap();
    let mut id = 0;
    let mut x = -1.0;
    while x <= 5.0 + 1e-3 {
        id += 1;
        scan_ground(&mut nav, id, x, seen);
        x += 0.5;
    }
    scan_ground(&mut nav, id + 1, 0.0, seen);
    assert_eq!(nav.map_status().pool_errors, 0);
    nav
}

const ROOT: Point3 = Point3 { x: -1.0, y: 0.0, z: 1.5 };

/// The test's kinematic world: the true pose, and a lateral drift gain (metres per metre driven per unit of the
/// sine between the drive direction and the straight line to the root).
struct World {
    x: f32,
    y: f32,
    yaw: f32,
    drift: f32,
    root: Point3,
}

impl World {
    fn new(root: Point3, drift: f32) -> Self {
        World { x: 0.0, y: 0.0, yaw: 0.0, drift, root }
    }
    fn execute(&mut self, m: Motion) -> (f32, f32) {
        match m {
            Motion::Turn { yaw_rad } => {
                self.yaw += yaw_rad;
                (yaw_rad, 0.0)
            }
            Motion::Straight { distance_m } => {
                // 5 cm increments, the drift re-evaluated at each
                let n = (libm::fabsf(distance_m) / 0.05).ceil().max(1.0) as i32;
                let d = distance_m / n as f32;
                for _ in 0..n {
                    let s = d.signum();
                    let (dx, dy) = (s * self.yaw.cos(), s * self.yaw.sin());
                    let (tx, ty) = (self.root.x - self.x, self.root.y - self.y);
                    let tn = (tx * tx + ty * ty).sqrt().max(1e-6);
                    let pull = (dx * ty - dy * tx) / tn;
                    let lat = self.drift * pull * d.abs();
                    self.x += d * self.yaw.cos() - lat * dy;
                    self.y += d * self.yaw.sin() + lat * dx;
                }
                (0.0, distance_m)
            }
            Motion::Stop { .. } => (0.0, 0.0),
        }
    }
    fn pose(&self) -> Pose {
        Pose {
            position: Point3 { x: self.x, y: self.y, z: Z0 + AXLE_H },
            orientation: Quat { x: 0.0, y: 0.0, z: (0.5 * self.yaw).sin(), w: (0.5 * self.yaw).cos() },
        }
    }
    fn report(&mut self, command_id: u32, m: Motion) -> MotionReport {
        let (yaw, dist) = self.execute(m);
        MotionReport { command_id, outcome: MotionOutcome::Completed, achieved_yaw_rad: yaw, achieved_distance_m: dist, pose: self.pose() }
    }
}

fn plan(nav: &mut TestNav) -> PlanProgress {
    let mut buf = PlanBuffer::new();
    for k in 0..2000u64 {
        let p = nav.plan_step(Instant::from_micros(k * 1000), 8, &mut buf);
        if matches!(p, PlanProgress::Finished { .. }) {
            return p;
        }
    }
    panic!("planning did not finish");
}

/// What a run of the loop saw.
#[derive(Default, Debug)]
struct Run {
    motions: u32,
    max_cross_track: f32,
    replans: u32,
}

/// Runs the loop like the executive: plan, then drive steps; each motion executed in `world` and reported (after
/// `hook(k, nav, world)`, which may inject input). At most `max_steps` drive steps.
fn drive(nav: &mut TestNav, world: &mut World, max_steps: u32, hook: &mut dyn FnMut(u32, &mut TestNav, &mut World)) -> Run {
    let mut run = Run::default();
    let mut planning = true;
    let mut id = 0;
    for _ in 0..max_steps {
        if planning {
            plan(nav);
            planning = false;
        }
        match nav.drive_step(Instant::from_micros(0)) {
            DriveStep::Motion(m) => {
                let r = world.report(id, m);
                id += 1;
                run.motions += 1;
                nav.motion_report(&r, m, Instant::from_micros(0));
                hook(run.motions, nav, world);
                let (dist, _, _, _) = off_path(world, 0.0, 4.0);
                run.max_cross_track = run.max_cross_track.max(dist);
            }
            DriveStep::Wait => {}
            DriveStep::Replan => {
                run.replans += 1;
                planning = true;
            }
            DriveStep::Finished => break,
        }
    }
    run
}

/// The true distance of the world's rover from the straight line y = y0 between x = 0 and x = x1 (the test's
/// own judge of tracking, independent of the navigator's cross-track).
fn off_path(w: &World, y0: f32, x1: f32) -> (f32, f32, f32, f32) {
    let cx = w.x.clamp(0.0, x1);
    let d = ((w.x - cx).powi(2) + (w.y - y0).powi(2)).sqrt();
    (d, w.x, w.y, w.yaw)
}

fn horizontal(a: &Pose, x: f32, y: f32) -> f32 {
    ((a.position.x - x).powi(2) + (a.position.y - y).powi(2)).sqrt()
}

#[test]
fn a_mission_plans_drives_and_arrives() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    assert_eq!(nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0)), PlanState::Accepted);
    assert_eq!(nav.mission().state().0, MissionState::Planning);
    let mut world = World::new(ROOT, 0.0);
    let run = drive(&mut nav, &mut world, 400, &mut |_, _, _| {});
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Arrived, StopReason::None), "{run:?} {st:?}");
    // the world's rover (not the navigator's belief) is in the goal region
    assert!(horizontal(&world.pose(), 3.0, 0.0) <= 0.4, "rover at ({}, {})", world.x, world.y);
    assert_eq!(st.motions_done, run.motions);
    assert!(st.distance_driven_m >= 2.5, "{st:?}");
    // the tracked tether: its length to the true axle equals the straight line to the root (no obstacle)
    let p = world.pose().position;
    let straight = ((p.x - ROOT.x).powi(2) + (p.y - ROOT.y).powi(2) + (p.z - ROOT.z).powi(2)).sqrt();
    assert!((st.predicted_payout_m - straight).abs() < 0.05, "{} vs {straight}", st.predicted_payout_m);
    assert_eq!(st.anchors, 1);
    assert!(st.margin_n > 0.0, "{st:?}");
    assert!(nav.mission().counters.rechecks > 0);
}

#[test]
fn a_cancel_while_driving_stops_safe() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut world = World::new(ROOT, 0.0);
    let run = drive(&mut nav, &mut world, 400, &mut |k, nav, _| {
        if k == 2 {
            nav.cancel(1, Instant::from_micros(0)).unwrap();
        }
    });
    assert_eq!(run.motions, 2, "no motion after the cancel");
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::Cancelled));
    assert_eq!(nav.drive_step(Instant::from_micros(0)), DriveStep::Finished);
}

#[test]
fn a_new_goal_while_driving_replaces_the_old_one() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut world = World::new(ROOT, 0.0);
    let mut changed = false;
    let run = drive(&mut nav, &mut world, 600, &mut |k, nav, _| {
        if k == 3 && !changed {
            changed = true;
            assert_eq!(nav.goal(&goal(2, 2.0, 1.0), Instant::from_micros(0)), PlanState::Accepted);
        }
    });
    // the drive loop planned anew after the goal (the hook's goal put the mission in Planning: drive_step says
    // Finished until planned, so drive again)
    let mut run2 = Run::default();
    if nav.mission().state().0 == MissionState::Planning {
        run2 = drive(&mut nav, &mut world, 600, &mut |_, _, _| {});
    }
    let st = nav.mission_status().unwrap();
    assert_eq!(st.goal_id, 2);
    assert_eq!((st.state, st.reason), (MissionState::Arrived, StopReason::None), "{run:?} {run2:?} {st:?}");
    assert!(horizontal(&world.pose(), 2.0, 1.0) <= 0.4, "rover at ({}, {})", world.x, world.y);
    // the new plan started where the rover was, not at the origin
    let start = nav.plan_start().unwrap().axle();
    assert!(start.x > 0.3 || start.y.abs() > 0.05, "replanned start {start:?}");
}

#[test]
fn a_disagreeing_tether_reading_is_re_estimated_then_stops_safe() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut world = World::new(ROOT, 0.0);
    let mut t = 1_000_000u64;
    let run = drive(&mut nav, &mut world, 400, &mut |k, nav, w| {
        let p = w.pose().position;
        let truth = ((p.x - ROOT.x).powi(2) + (p.y - ROOT.y).powi(2) + (p.z - ROOT.z).powi(2)).sqrt();
        t += 10_000_000;
        // agreeing readings first; after the third motion the tether snags: the encoder pays out 2 m more
        // (slowly: not a jump)
        let snag = if k >= 3 { 2.0 } else { 0.0 };
        let r = TetherReading { time_us: t, payout_m: truth + snag, tension_n: 100.0, boom_angle_rad: 0.0 };
        nav.tether_reading(&r, Instant::from_micros(0));
    });
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::TetherInconsistent), "{run:?} {st:?}");
    assert_eq!(st.tether_reestimates, 1, "re-estimated once before stopping");
    assert_eq!(run.motions, 3);
    assert_eq!(nav.drive_step(Instant::from_micros(0)), DriveStep::Finished);
}

#[test]
fn a_payout_jump_is_rejected_and_counted_and_tension_over_the_limit_stops() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let r = |t: u64, p: f32, n: f32| TetherReading { time_us: t, payout_m: p, tension_n: n, boom_angle_rad: 0.0 };
    nav.tether_reading(&r(1_000_000, 2.0, 50.0), Instant::from_micros(0));
    // 5 m in 0.1 s: not physically possible
    nav.tether_reading(&r(1_100_000, 7.0, 50.0), Instant::from_micros(0));
    let st = nav.mission_status().unwrap();
    assert_eq!(st.tether_rejected, 1);
    assert_eq!(st.measured_payout_m, 2.0, "the jump was not taken");
    nav.tether_reading(&r(1_200_000, 2.05, 2500.0), Instant::from_micros(0));
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::TensionLimit));
}

#[test]
fn a_pose_that_jumps_against_odometry_is_rejected_and_counted() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut world = World::new(ROOT, 0.0);
    plan(&mut nav);
    let mut id = 0;
    let mut jumped = None;
    for _ in 0..100 {
        match nav.drive_step(Instant::from_micros(0)) {
            DriveStep::Motion(m) => {
                let mut rep = world.report(id, m);
                id += 1;
                if jumped.is_none() && matches!(m, Motion::Straight { .. }) {
                    // the localisation says 3 m to the side
                    rep.pose.position.y += 3.0;
                    jumped = Some(world.pose());
                }
                nav.motion_report(&rep, m, Instant::from_micros(0));
                if jumped.is_some() {
                    break;
                }
            }
            DriveStep::Wait => {}
            other => panic!("{other:?}"),
        }
    }
    let truth = jumped.expect("a straight drive was commanded");
    let st = nav.mission_status().unwrap();
    assert_eq!(st.pose_jumps, 1);
    assert_ne!(st.state, MissionState::Safe, "one jump is rejected, not fatal");
    let b = nav.mission().body().unwrap();
    assert!((b.position.y - truth.position.y).abs() < 0.05, "odometry kept: {b:?} vs {truth:?}");
}

#[test]
fn closed_loop_tracking_corrects_a_lateral_tether_drift_that_open_loop_does_not() {
    // the root off to the side: the tether pulls left of the drive to the goal
    let root = Point3 { x: -1.0, y: 1.2, z: 1.5 };
    let run_with = |tracking: Tracking| {
        // no replans on cross-track: compare the trackers alone
        let mission = MissionConfig { tracking, replan_cross_track_m: 10.0, ..MissionConfig::DEFAULT };
        let mut nav = mapped(root, mission);
        let mut g = goal(1, 4.0, 0.0);
        g.tolerance_m = 0.3;
        assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
        assert!(matches!(plan(&mut nav), PlanProgress::Finished { state: PlanState::ExactSolution, .. }));
        let planned: Vec<Vec3> = nav.plan_path().iter().map(|(s, _)| s.axle()).collect();
        let mut world = World::new(root, 0.3);
        let run = drive(&mut nav, &mut world, 600, &mut |_, _, _| {});
        std::println!("{tracking:?}: {:?}", nav.mission_status());
        (run, world, nav.mission().drift_gain(), planned)
    };
    let (open, w_open, _, p_open) = run_with(Tracking::OpenLoop);
    let (closed, w_closed, gain, p_closed) = run_with(Tracking::ClosedLoop);
    // both first plans run (nearly) straight along y = 0 (the test judges against that line)
    for p in p_open.iter().chain(&p_closed) {
        assert!(p.y.abs() < 0.35, "plan leaves the line: {p:?}");
    }
    std::println!("open {open:?} end ({}, {}); closed {closed:?} end ({}, {}); learned gain {gain}", w_open.x, w_open.y, w_closed.x, w_closed.y);
    assert!(open.max_cross_track > 0.3, "open loop drifted only {open:?}");
    assert!(closed.max_cross_track < 0.2, "closed loop left the path: {closed:?}");
    assert!(open.max_cross_track > 2.0 * closed.max_cross_track, "open {open:?} closed {closed:?}");
    assert!(gain > 0.0, "the drift toward the tether was learned: {gain}");
    assert!(horizontal(&w_closed.pose(), 4.0, 0.0) <= 0.3);
}

#[test]
fn a_scan_whose_pose_disagrees_with_odometry_is_not_integrated() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut world = World::new(ROOT, 0.0);
    plan(&mut nav);
    // one motion, so the navigator has a body pose from a report
    let DriveStep::Motion(m) = nav.drive_step(Instant::from_micros(0)) else { panic!("no motion") };
    let r = world.report(0, m);
    nav.motion_report(&r, m, Instant::from_micros(0));
    let before = nav.map_status().scans_integrated;
    // a scan said to be taken 10 m away from where odometry puts the rover
    scan_down(&mut nav, 99, 10.0);
    assert_eq!(nav.map_status().scans_integrated, before, "the disagreeing scan was integrated");
    assert_eq!(nav.mission_status().unwrap().scans_rejected, 1);
    // a scan from above the rover is integrated
    scan_down(&mut nav, 100, world.x);
    assert_eq!(nav.map_status().scans_integrated, before + 1);
    assert_ne!(nav.mission_status().unwrap().state, MissionState::Safe);
}

#[test]
fn a_scan_along_the_drive_in_flight_is_integrated_and_one_past_it_is_not() {
    let t0 = Instant::from_micros(0);
    let mut nav = mapped(ROOT, MissionConfig { tracking: Tracking::OpenLoop, ..MissionConfig::DEFAULT });
    assert_eq!(nav.goal(&goal(1, 4.0, 0.0), t0), PlanState::Accepted);
    assert!(matches!(plan(&mut nav), PlanProgress::Finished { state: PlanState::ExactSolution, .. }));
    let mut world = World::new(ROOT, 0.0);
    // report motions until a straight drive longer than the scan tolerance is in flight
    let mut long = None;
    for _ in 0..40 {
        match nav.drive_step(t0) {
            DriveStep::Motion(Motion::Straight { distance_m }) if distance_m > 2.6 => {
                long = Some(distance_m);
                break;
            }
            DriveStep::Motion(m) => {
                let r = world.report(0, m);
                nav.motion_report(&r, m, t0);
            }
            DriveStep::Wait => {}
            other => panic!("driving ended: {other:?}"),
        }
    }
    let Some(d) = long else { panic!("no straight drive over 2.6 m in the open-loop plan") };
    let before = nav.map_status().scans_integrated;
    // taken 2.5 m along the drive: more than the 2 m tolerance from the pose it started at, on the drive
    scan_down(&mut nav, 200, world.x + 2.5);
    assert_eq!(nav.map_status().scans_integrated, before + 1, "a scan along the drive was rejected");
    // 2.5 m past the drive's end: rejected
    scan_down(&mut nav, 201, world.x + d + 2.5);
    assert_eq!(nav.map_status().scans_integrated, before + 1, "a scan past the drive's end was integrated");
    assert_eq!(nav.mission_status().unwrap().scans_rejected, 1);
}

/// Replaces the planned path by states settled on the map at `xs` along y = 0, yaw 0 (the first state's anchor
/// history for each), and its motions by theirs.
fn replace_plan(nav: &mut TestNav, xs: &[f32]) {
    use core::borrow::BorrowMut;
    let problem = nav.problem.unwrap();
    let map = Map::reattach(nav.cfg, nav.blocks.borrow_mut(), nav.index.borrow_mut(), nav.used).unwrap();
    let params = crate::plan::tethered::TetherSpaceParams::ONBOARD;
    let space = crate::plan::tethered::TetherSpace::new(&map, problem.bounds, problem.rover, params).unwrap();
    let store = &mut nav.storage;
    let h = store.path[0].1.clone();
    store.path.clear();
    store.motions.clear();
    for &x in xs {
        store.path.push((space.settle_state(x, 0.0, 0.0).unwrap(), h.clone())).unwrap();
    }
    for w in store.path.clone().windows(2) {
        for m in segment_motions(&w[0].0, &w[1].0, &params).into_iter().flatten() {
            store.motions.push(m).unwrap();
        }
    }
}

/// A rock seen on a later segment of the plan: the segments before it passed the re-check on the same map, so the
/// plan ends before the failing segment (driven, then planned again there), instead of a replan from here.
#[test]
fn a_later_segment_that_fails_its_re_check_ends_the_plan_before_it() {
    let t0 = Instant::from_micros(0);
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    assert_eq!(nav.goal(&goal(1, 4.0, 0.0), t0), PlanState::Accepted);
    assert!(matches!(plan(&mut nav), PlanProgress::Finished { state: PlanState::ExactSolution, .. }));
    // the stored plan as five states along the line, settled every metre (four segments)
    replace_plan(&mut nav, &[0.0, 1.0, 2.0, 3.0, 4.0]);
    // one motion, so the navigator has a body pose
    let mut world = World::new(ROOT, 0.0);
    let DriveStep::Motion(m) = nav.drive_step(t0) else { panic!("no motion") };
    let r = world.report(0, m);
    nav.motion_report(&r, m, t0);
    // a rock 0.5 m high between the wheels on the fourth segment (x 3.6-3.9), seen from above it
    let rock = |x: f32, y: f32| if (3.6..=3.9).contains(&x) && y.abs() <= 0.3 { Z0 + 0.5 } else { Z0 };
    // the sensor within the scan pose tolerance of the rover, the rays on x 2.5-4.5
    let (sx, step) = (world.x + 1.9, 0.5 * VOXEL);
    let mut pts = Vec::new();
    for i in 0..=40 {
        for j in -30..=30 {
            let (x, y) = (2.5 + i as f32 * step, j as f32 * step);
            pts.push(Point3 { x: x - sx, y, z: rock(x, y) - SENSOR_H });
        }
    }
    let pose = Pose { position: Point3 { x: sx, y: 0.0, z: SENSOR_H }, orientation: Quat::IDENTITY };
    // the TSDF averages: enough looks at the rock to outweigh the free space seen there before
    for id in 900..912 {
        nav.integrate_scan(&Scan { scan_id: id, sensor_pose: pose, points: &pts }, t0);
    }
    assert_eq!(nav.mission().state().0, MissionState::Verifying);
    let mut next = None;
    for _ in 0..20 {
        match nav.drive_step(t0) {
            DriveStep::Wait => {}
            other => {
                next = Some(other);
                break;
            }
        }
    }
    assert!(nav.mission().counters.recheck_failures >= 1, "the rock did not fail a re-check");
    assert!(matches!(next, Some(DriveStep::Motion(_))), "after the failed re-check: {next:?}");
    assert_eq!(nav.plan_path().len(), 4, "the plan ends at the state before the rock's segment");
    assert_eq!(nav.mission_status().unwrap().replans, 0);
}

/// The check of a motion in flight after a scan runs from where that motion started, as the re-check after its
/// report runs from where the rover stands: a rock seen on the part of the segment already driven does not stop
/// the motion; one ahead of it on the segment does. (Checked from the segment's planned start, the first case
/// stopped every new motion of the segment while the re-check from the rover passed it: a rover stopped without
/// end.)
#[test]
fn a_motion_in_flight_stops_for_a_rock_ahead_on_its_segment_not_for_one_behind() {
    use core::borrow::BorrowMut;
    let t0 = Instant::from_micros(0);
    for (rock_x, stops) in [(0.6_f32, false), (3.0, true)] {
        let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
        assert_eq!(nav.goal(&goal(1, 4.0, 0.0), t0), PlanState::Accepted);
        assert!(matches!(plan(&mut nav), PlanProgress::Finished { state: PlanState::ExactSolution, .. }));
        // the stored plan as one straight segment, x 0 -> 3.8
        replace_plan(&mut nav, &[0.0, 3.8]);
        // drive (closed loop: short pieces of the segment) until the rover is 1.5 m along it, the next motion in
        // flight
        let mut world = World::new(ROOT, 0.0);
        let mut in_flight = None;
        for id in 0..60 {
            match nav.drive_step(t0) {
                DriveStep::Motion(m) if world.x >= 1.5 => {
                    in_flight = Some(m);
                    break;
                }
                DriveStep::Motion(m) => {
                    let r = world.report(id, m);
                    nav.motion_report(&r, m, t0);
                }
                DriveStep::Wait => {}
                other => panic!("driving ended: {other:?}"),
            }
        }
        assert!(in_flight.is_some(), "never 1.5 m along the segment: x {}", world.x);
        // a rock 0.5 m high in the corridor at x rock_x .. rock_x + 0.3, seen from above the rover
        let rock = |x: f32, y: f32| if (rock_x..=rock_x + 0.3).contains(&x) && y.abs() <= 0.3 { Z0 + 0.5 } else { Z0 };
        let (sx, step) = (world.x, 0.5 * VOXEL);
        let mut pts = Vec::new();
        for i in 0..=20 {
            for j in -30..=30 {
                let (x, y) = (rock_x - 0.35 + i as f32 * step, j as f32 * step);
                pts.push(Point3 { x: x - sx, y, z: rock(x, y) - SENSOR_H });
            }
        }
        let pose = Pose { position: Point3 { x: sx, y: 0.0, z: SENSOR_H }, orientation: Quat::IDENTITY };
        let before = nav.map_status().scans_integrated;
        // the TSDF averages: enough looks at the rock to outweigh the free space seen there before
        let mut stopped = false;
        for id in 900..912 {
            nav.integrate_scan(&Scan { scan_id: id, sensor_pose: pose, points: &pts }, t0);
            stopped |= nav.stop_in_flight(t0);
        }
        assert_eq!(stopped, stops, "rock at x {rock_x}");
        assert_eq!(nav.map_status().scans_integrated, before + 12);
        // the rock is on the map: the segment from its planned start now fails (the old in-flight check)
        let problem = nav.problem.unwrap();
        let map = Map::reattach(nav.cfg, nav.blocks.borrow_mut(), nav.index.borrow_mut(), nav.used).unwrap();
        let space = problem.space(&map).unwrap();
        let path = &nav.storage.path;
        assert!(space.check(&path[0].0, &path[0].1, &path[1].0).is_err(), "rock at x {rock_x} not on the map");
    }
}

#[test]
fn no_waypoint_below_the_minimum_margin_is_sent_or_driven() {
    // a minimum margin no state on this map can have (the rover's whole weight)
    let mission = MissionConfig { min_margin_n: 1.0e6, ..MissionConfig::DEFAULT };
    let mut nav = mapped(ROOT, mission);
    assert_eq!(nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0)), PlanState::Accepted);
    let mut buf = PlanBuffer::new();
    let mut last = None;
    for k in 0..2000u64 {
        let p = nav.plan_step(Instant::from_micros(k * 1000), 8, &mut buf);
        if let PlanProgress::Finished { state, .. } = p {
            last = Some(state);
            break;
        }
    }
    assert_eq!(last, Some(PlanState::NoSolutionWithinBudget));
    assert!(buf.is_empty(), "{} waypoints sent", buf.len());
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::NoSolution));
    assert_eq!(nav.drive_step(Instant::from_micros(0)), DriveStep::Finished);
    // the same world with the default minimum plans and every sent waypoint has a margin at or above it
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.goal(&goal(1, 3.0, 0.0), Instant::from_micros(0));
    let mut buf = PlanBuffer::new();
    for k in 0..2000u64 {
        if let PlanProgress::Finished { state, .. } = nav.plan_step(Instant::from_micros(k * 1000), 8, &mut buf) {
            assert_eq!(state, PlanState::ExactSolution);
            break;
        }
    }
    assert!(buf.len() >= 2);
    assert!(buf.iter().all(|w| w.stability_margin >= 0.0), "{buf:?}");
}

#[test]
fn an_approximate_solution_is_driven_only_when_allowed_and_only_to_its_last_state() {
    // ground unobserved for x in [1.2, 2.4]: the goal at x = 3.5 cannot be reached
    let seen = |x: f32| !(1.2..=2.4).contains(&x);
    for allow in [false, true] {
        let mut nav = mapped_where(ROOT, MissionConfig::DEFAULT, &seen);
        let mut g = goal(1, 3.5, 0.0);
        g.allow_approximate = allow;
        g.max_iterations = 48;
        assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
        let p = plan(&mut nav);
        let PlanProgress::Finished { state, .. } = p else { unreachable!() };
        // 48 iterations: enough for the search to get off the start, so the allowed case really drives (24 left it
        // within 0.25 m of the start on some maps that differ from this one only in the last ESDF bits)
        assert_eq!(state, PlanState::ApproximateSolution);
        let mut world = World::new(ROOT, 0.0);
        let run = drive(&mut nav, &mut world, 400, &mut |_, _, _| {});
        let st = nav.mission_status().unwrap();
        std::println!("allow {allow}: {state:?} {run:?} {st:?}");
        assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::NoSolution));
        if state == PlanState::ApproximateSolution && allow {
            assert!(run.motions > 0, "an allowed approximate plan is driven");
            assert!(world.x < 1.2, "driven past the last safe state: x = {}", world.x);
        } else {
            assert_eq!(run.motions, 0, "{state:?} driven without allow_approximate");
        }
    }
}

/// A navigator over fresh storage, as after a reset, given `block` before anything else (the board's boot order).
fn rebooted(block: &retained::RetainedBlock) -> TestNav {
    let mut nav =
        Navigator::new(MapConfig::with_voxel_size(VOXEL), vec![Block::EMPTY; 4096], vec![0u32; 8192], Box::default())
            .unwrap();
    nav.recover_retained(block);
    nav
}

#[test]
fn a_reset_recovers_the_wrapped_tether_and_never_plans_with_a_straight_one() {
    use crate::tether::Anchor;
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    let mut block = [0u8; retained::RETAINED_BYTES];
    nav.keep_retained(&mut block);
    // a wrapped tether: root, then a contact on a pole the rover passed (written as the mission would track it)
    let pole = Anchor { point: Vec3::new(1.0, 0.6, 0.4), gradient: Vec3::new(0.0, -1.0, 0.0) };
    let mut wrapped = nav.mission.tracked().clone();
    wrapped.push(pole).unwrap();
    nav.mission.tracked = wrapped.clone();
    nav.keep_retained(&mut block);
    let written = nav.mission.generation;
    nav.keep_retained(&mut block);
    assert_eq!(nav.mission.generation, written, "nothing changed: nothing written");

    let mut nav = rebooted(&block);
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason, st.anchors), (MissionState::Safe, StopReason::Reset, 2));
    // the same root: the mission continues from the recovered history, and the plan starts from it
    nav.configure(&configure(ROOT, MissionConfig::DEFAULT)).unwrap();
    assert_eq!(nav.mission.tracked(), &wrapped);
    scan_down(&mut nav, 1, 0.0);
    assert_eq!(nav.goal(&goal(2, 3.0, 0.0), Instant::from_micros(0)), PlanState::Accepted);
    assert_eq!(nav.storage.start_history, wrapped, "the plan must start from the wrapped tether");

    // another root is another deployment: straight from that root
    let mut nav = rebooted(&block);
    let other = Point3 { x: -3.0, y: 0.0, z: 1.5 };
    nav.configure(&configure(other, MissionConfig::DEFAULT)).unwrap();
    assert_eq!(nav.mission.tracked().len(), 1);
}

#[test]
fn after_a_reset_the_ground_under_the_rover_comes_back_from_the_checkpoint() {
    // the rover stands at the origin of the mapped world; its last complete scan gives the checkpoint the ground
    // round it (`retained::GroundPatch`)
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    nav.mission.body = Some(BodyPose { position: Vec3::new(0.0, 0.0, Z0 + AXLE_H), yaw: 0.0 });
    scan_down(&mut nav, 100, 0.0);
    let mut block = [0u8; retained::RETAINED_BYTES];
    nav.keep_retained(&mut block);
    let patch = nav.mission.ground.clone().expect("a patch after a complete scan");
    let cells = patch.points().count();
    assert!(cells >= crate::config::tether::GROUND_PATCH_CELLS * 9 / 10, "{cells} cells with ground");
    for p in patch.points() {
        assert!((p.z - Z0).abs() <= 0.5 * VOXEL, "ground at {p:?}, the flat world is at {Z0}");
    }

    // rebooted, configured again, no scan at all (the survey cannot see under the rover): the start settles on
    // the ground the checkpoint brought back, and the goal is planned from the recovered state
    let mut nav = rebooted(&block);
    nav.configure(&configure(ROOT, MissionConfig::DEFAULT)).unwrap();
    let restored = nav.map().map(|m| crate::plan::tethered::surface_point(&m, 0.0, 0.0, 1.0, -1.0));
    assert!(restored.flatten().is_some_and(|p| (p.z - Z0).abs() <= 0.5 * VOXEL), "{restored:?}");
    assert_eq!(nav.goal(&goal(2, 1.0, 0.0), Instant::from_micros(0)), PlanState::Accepted);

    // the same checkpoint without its patch: the map is empty under the rover and the goal is refused
    let mut bare = match retained::read(&block) {
        retained::Recovered::Valid(cp) => cp,
        other => panic!("{other:?}"),
    };
    bare.ground = None;
    bare.generation += 1;
    retained::write(&mut block, &bare);
    let mut nav = rebooted(&block);
    nav.configure(&configure(ROOT, MissionConfig::DEFAULT)).unwrap();
    assert_eq!(nav.goal(&goal(3, 1.0, 0.0), Instant::from_micros(0)), PlanState::InvalidInput);
}

#[test]
fn an_unreadable_checkpoint_stops_safe_and_refuses_goals() {
    let mut nav = mapped(ROOT, MissionConfig::DEFAULT);
    let mut block = [0u8; retained::RETAINED_BYTES];
    nav.keep_retained(&mut block);
    // the slot written (generation 1: slot 1) damaged, as by a reset in the middle of the write on real memory
    block[retained::SLOT_BYTES + 9] ^= 0x40;
    let mut nav = rebooted(&block);
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::TetherStateLost));
    nav.configure(&configure(ROOT, MissionConfig::DEFAULT)).unwrap();
    scan_down(&mut nav, 1, 0.0);
    assert_eq!(nav.goal(&goal(2, 3.0, 0.0), Instant::from_micros(0)), PlanState::InvalidInput);
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::TetherStateLost));
    // a power-on (no checkpoint ever written) is a new deployment, not a lost state
    let nav = rebooted(&[0u8; retained::RETAINED_BYTES]);
    assert_ne!(nav.mission_status().map(|s| s.reason), Some(StopReason::TetherStateLost));
}


#[test]
fn a_search_with_nothing_to_drive_goes_on_to_the_plan_cap_before_no_solution() {
    // the goal behind unobserved ground (as above): every round ends approximate; not allowed, it is nothing the
    // mission can drive, so the search goes on in rounds of the goal's budget up to MAX_PLAN_ITERATIONS
    let seen = |x: f32| !(1.2..=2.4).contains(&x);
    let mut nav = mapped_where(ROOT, MissionConfig::DEFAULT, &seen);
    let mut g = goal(1, 3.5, 0.0);
    g.allow_approximate = false;
    g.max_iterations = 200;
    assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
    let mut buf = PlanBuffer::new();
    let mut searching_after_first_round = false;
    let mut finished = None;
    for k in 0..20_000u64 {
        match nav.plan_step(Instant::from_micros(k * 1000), 8, &mut buf) {
            PlanProgress::Finished { state, iterations, .. } => {
                finished = Some((state, iterations));
                break;
            }
            PlanProgress::Searching { iterations, .. } => searching_after_first_round |= iterations > 200,
        }
    }
    let (state, iterations) = finished.expect("planning finished");
    assert!(searching_after_first_round, "the search did not go on after its first round");
    assert_eq!((state, iterations), (PlanState::ApproximateSolution, MAX_PLAN_ITERATIONS));
    // 200 -> 400 -> 600 -> 750: three more rounds, the last one cut at the cap
    assert_eq!(nav.stats.search_extensions, 3);
    let st = nav.mission_status().unwrap();
    assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::NoSolution));
    assert_eq!(nav.drive_step(Instant::from_micros(0)), DriveStep::Finished, "an approximate plan not allowed is driven");

    // allowed and making progress, the first round's approximate plan is driven: no further round
    let mut nav = mapped_where(ROOT, MissionConfig::DEFAULT, &seen);
    g.allow_approximate = true;
    assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
    let PlanProgress::Finished { state, iterations, .. } = plan(&mut nav) else { unreachable!() };
    assert_eq!((state, iterations, nav.stats.search_extensions), (PlanState::ApproximateSolution, 200, 0));
    assert_eq!(nav.mission_status().unwrap().state, MissionState::Driving);
}

#[test]
fn with_nothing_to_drive_the_rover_turns_to_look_at_an_unobserved_goal_behind_it() {
    // A band of ground unobserved across x in [-1.7, -1.3] (no scan comes in the run); the rover at the origin faces
    // +x. The goal in that band behind the rover: no plan reaches it, and the rover turns to face it (the next scan
    // would look there), plans again from there and stops. The same band ahead of the rover, the goal in it: it
    // faces the goal already, and stops without turning.
    for (band, gx, behind) in [((-1.7, -1.3), -1.5, true), ((1.3, 1.7), 1.5, false)] {
        let seen = |x: f32| !(band.0..=band.1).contains(&x);
        let mut nav = mapped_where(ROOT, MissionConfig::DEFAULT, &seen);
        let mut g = goal(1, gx, 0.0);
        g.max_iterations = 60;
        assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
        let mut world = World::new(ROOT, 0.0);
        let run = drive(&mut nav, &mut world, 400, &mut |_, _, _| {});
        let st = nav.mission_status().unwrap();
        let looks = nav.stats.looks;
        std::println!("goal x {gx}: {run:?}, looks {looks}, pose ({}, {}, {}), {st:?}", world.x, world.y, world.yaw);
        assert_eq!((st.state, st.reason), (MissionState::Safe, StopReason::NoSolution));
        assert_eq!((world.x, world.y), (0.0, 0.0), "the rover drove");
        if behind {
            assert_eq!((nav.stats.looks, run.replans), (1, 1), "no look at the goal behind the rover");
            // facing the goal (bearing pi), or turned at least a quarter of the way (the part the map allows)
            let off = libm::fabsf(crate::geom::wrap_angle(core::f32::consts::PI - world.yaw));
            assert!(off <= 0.75 * core::f32::consts::PI + 1e-3, "the look turned away: yaw {}", world.yaw);
        } else {
            assert_eq!((nav.stats.looks, run.motions, world.yaw), (0, 0, 0.0), "a look at a goal the rover faces");
        }
    }
}
