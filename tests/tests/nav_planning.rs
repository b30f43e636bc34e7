//! On-board goal planning end to end over the in-process link: the host configures the flight software, sends
//! range scans of a flat world (the flight map's 5 cm voxels) and a goal; the executive's navigator plans it with
//! the tethered ABIT* on the onboard map and answers `PlanStatus(ExactSolution)`, the `Plan` and the drive
//! commands. The drive commands, dead-reckoned on the ground plane from the plan's first waypoint, must end within
//! the goal tolerance (an oracle independent of the planner). A goal the navigator cannot set up is refused.

use firmware::protocol::{
    DriveCommand, GoalRequest, Message, Mode, Motion, PlanState, PlanStatus, PlannerChoice, Point3, Pose, Quat,
    SensorChunk,
};
use firmware::config::protocol::{
    MAX_POINTS_PER_CHUNK,
};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::FlightLink;
use host_sim::scripted::default_configure;
use host_sim::session::HostSession;

const Z0: f32 = 0.03;
const SENSOR_H: f32 = 3.0;
const STEP: f32 = 0.025; // two rays per 5 cm voxel

/// A scan looking down from `SENSOR_H` above `(cx, 0)` at flat ground `z = Z0`, as protocol chunks.
fn scan(id: u32, cx: f32) -> Vec<SensorChunk> {
    let mut pts = Vec::new();
    for i in -40..=40 {
        for j in -48..=48 {
            pts.push(Point3::new(i as f32 * STEP, j as f32 * STEP, Z0 - SENSOR_H));
        }
    }
    let pose = Pose { position: Point3::new(cx, 0.0, SENSOR_H), orientation: Quat { x: 0.0, y: 0.0, z: 0.0, w: 1.0 } };
    let chunks: Vec<&[Point3]> = pts.chunks(MAX_POINTS_PER_CHUNK).collect();
    chunks
        .iter()
        .enumerate()
        .map(|(k, c)| SensorChunk {
            scan_id: id,
            chunk_index: k as u16,
            chunk_count: chunks.len() as u16,
            sensor_pose: pose,
            points: heapless::Vec::from_slice(c).expect("chunk fits"),
        })
        .collect()
}

fn session_with_map() -> HostSession<InProcLink> {
    let mut s = HostSession::new(InProcLink::new(DEFAULT_STEP_US));
    s.recv().expect("boot telemetry");
    let mut cfg = default_configure(3);
    // a root anchor inside the mapped volume: the tether sweep must see known space
    cfg.tether.root_anchor = Point3::new(-1.0, 0.0, 1.5);
    s.exchange(&Message::Configure(cfg)).expect("configure");
    // scans every half metre along x in [-1, 4], the last one from the rover's position x = 0
    let xs = [-1.0, -0.5, 0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0, 3.5, 4.0, 0.0];
    for (id, cx) in xs.iter().enumerate() {
        for c in scan(id as u32 + 1, *cx) {
            s.send(&Message::SensorChunk(c)).expect("send chunk");
            s.recv().expect("chunk replies");
        }
    }
    let t = s.telemetry().expect("telemetry");
    assert_eq!(t.map.scans_integrated, xs.len() as u32);
    assert_eq!(t.map.pool_errors, 0);
    s
}

fn goal(x: f32, max_iterations: u32) -> GoalRequest {
    GoalRequest {
        goal_id: 7,
        position: Point3::new(x, 0.0, Z0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Abit,
        max_iterations,
        time_budget_ms: 0,
    }
}

#[test]
fn goal_over_the_link_is_planned_on_board_and_driven() {
    let mut s = session_with_map();
    let mut got = s.exchange(&Message::GoalRequest(goal(3.0, 40))).expect("goal");
    // let the executive plan (8 iterations per 1 ms step) and send plan and drive commands
    for _ in 0..200 {
        let t = s.link().now_us() + 10_000;
        got.extend(s.advance_to(t).expect("advance"));
        if got.iter().any(|m| matches!(m, Message::DriveCommand(_))) && s.telemetry().expect("t").mode == Mode::Mapping {
            break;
        }
    }
    let finals: Vec<&PlanStatus> = got
        .iter()
        .filter_map(|m| if let Message::PlanStatus(p) = m { Some(p) } else { None })
        .filter(|p| !matches!(p.state, PlanState::Accepted | PlanState::Searching))
        .collect();
    assert_eq!(finals.len(), 1, "{got:?}");
    assert_eq!(finals[0].state, PlanState::ExactSolution);
    assert!(finals[0].iterations <= 40);
    let waypoints: Vec<_> = got
        .iter()
        .filter_map(|m| if let Message::Plan(p) = m { Some(p.waypoints.clone()) } else { None })
        .flatten()
        .collect();
    assert!(waypoints.len() >= 2);
    let (first, last) = (waypoints[0].pose.position, waypoints[waypoints.len() - 1].pose.position);
    assert!(first.x.abs() < 0.1 && first.y.abs() < 0.1, "{first:?}");
    let d = ((last.x - 3.0).powi(2) + last.y.powi(2)).sqrt();
    assert!(d <= 0.5 + 0.02, "last waypoint {last:?}");
    // dead reckoning of the drive commands from the first waypoint's heading
    let o = waypoints[0].pose.orientation;
    let mut yaw = (2.0 * (o.w * o.z + o.x * o.y)).atan2(1.0 - 2.0 * (o.y * o.y + o.z * o.z));
    let (mut x, mut y) = (first.x, first.y);
    let mut drives = 0;
    for m in &got {
        if let Message::DriveCommand(DriveCommand { motion, .. }) = m {
            match *motion {
                Motion::Turn { yaw_rad } => yaw += yaw_rad,
                Motion::Straight { distance_m } => {
                    drives += 1;
                    x += distance_m * yaw.cos();
                    y += distance_m * yaw.sin();
                }
                Motion::Stop => {}
            }
        }
    }
    assert!(drives >= 1);
    let d = ((x - 3.0).powi(2) + y * y).sqrt();
    assert!(d <= 0.5 + 0.05, "drive commands end at ({x}, {y}), {d} m from the goal");
    assert_eq!(s.telemetry().expect("t").mode, Mode::Mapping);
}

#[test]
fn goal_before_any_scan_is_refused_over_the_link() {
    let mut s = HostSession::new(InProcLink::new(DEFAULT_STEP_US));
    s.recv().expect("boot");
    s.exchange(&Message::Configure(default_configure(1))).expect("configure");
    // no scan yet: the executive takes goals in Idle, the navigator knows no pose
    let r = s.exchange(&Message::GoalRequest(goal(3.0, 10))).expect("goal");
    let state = r.iter().find_map(|m| if let Message::PlanStatus(p) = m { Some(p.state) } else { None });
    assert_eq!(state, Some(PlanState::InvalidInput), "{r:?}");
    let mut g = goal(3.0, 10);
    g.planner = PlannerChoice::Team;
    let r = s.exchange(&Message::GoalRequest(g)).expect("goal");
    let state = r.iter().find_map(|m| if let Message::PlanStatus(p) = m { Some(p.state) } else { None });
    assert_eq!(state, Some(PlanState::PlannerUnavailable), "{r:?}");
}
