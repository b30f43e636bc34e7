//! On-board goal planning end to end over the in-process link: the host configures the flight software, sends
//! range scans of a flat world (the flight map's 5 cm voxels) and a goal; the executive's navigator plans it with
//! the tethered ABIT* on the onboard map and answers `PlanStatus(ExactSolution)`, the `Plan` and the drive
//! commands. The drive commands, dead-reckoned on the ground plane from the plan's first waypoint, must end within
//! the goal tolerance (an oracle independent of the planner). A goal the navigator cannot set up is refused. The
//! same exchange on the emulated board (QEMU mps2-an500, lockstep) gives the same messages: planning is
//! equivalent in-process and on the flight computer.

use firmware::protocol::{
    DriveCommand, GoalRequest, Message, MissionState, Mode, Motion, MotionOutcome, MotionReport, NackReason, PlanState, PlanStatus,
    PlannerChoice, Point3, Pose, Quat, SensorChunk,
};
use firmware::config::protocol::{
    MAX_POINTS_PER_CHUNK,
};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::FlightLink;
use host_sim::scripted::default_configure;
use host_sim::session::HostSession;

const Z0: f32 = 0.03;
const SENSOR_H: f32 = 6.0;
const STEP: f32 = 0.025; // two rays per 5 cm voxel

/// A scan looking down from `SENSOR_H` above `(cx, 0)` at flat ground `z = Z0`, as protocol chunks: 25 x 65 rays
/// 2.5 cm apart over `x in cx + [-0.3, 0.3]`, `y in [-0.8, 0.8]`. (About 1600 points: the executive integrates a scan
/// within one step, and an 8000-point scan takes seconds of emulated time on QEMU.) The sensor is high
/// so that the columns between two scans 0.4 m apart are observed well above the ground by slanted rays: the
/// planner's surface search starts at the top of the planning bounds, which must be observed space.
fn scan(id: u32, cx: f32) -> Vec<SensorChunk> {
    let mut pts = Vec::new();
    for i in -12..=12 {
        for j in -32..=32 {
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

/// Configures the flight software and maps the flat world with scans along `xs`; the rover is at the origin.
fn session_with_map<L: FlightLink>(link: L, xs: &[f32]) -> HostSession<L> {
    let mut s = HostSession::new(link);
    s.recv().expect("boot telemetry");
    let mut cfg = default_configure(3);
    // a root anchor inside the mapped volume: the tether sweep must see known space
    cfg.tether.root_anchor = Point3::new(-1.0, 0.0, 1.5);
    s.exchange(&Message::Configure(cfg)).expect("configure");
    // the scans, then one from the rover at the origin (its pose for planning)
    let mut id = 0;
    for cx in xs {
        id += 1;
        for c in scan(id, *cx) {
            s.send(&Message::SensorChunk(c)).expect("send chunk");
            s.recv().expect("chunk replies");
        }
    }
    id += 1;
    for c in scan(id, 0.0) {
        s.send(&Message::SensorChunk(c)).expect("send chunk");
        s.recv().expect("chunk replies");
    }
    let t = s.telemetry().expect("telemetry");
    assert_eq!(t.map.scans_integrated, id);
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
        allow_approximate: true,
    }
}

/// Scans every 0.4 m along x in [-1.2, 4].
const XS: [f32; 14] = [-1.2, -0.8, -0.4, 0.0, 0.4, 0.8, 1.2, 1.6, 2.0, 2.4, 2.8, 3.2, 3.6, 4.0];

/// Sends `goal` and lets the flight software plan and drive; returns everything it sent from the goal on. Protocol
/// v2: each drive command is answered with a `MotionReport` of the commanded motion executed exactly, the pose
/// dead-reckoned on the ground plane from the plan's first waypoint (a stand-in for the simulator).
fn plan_goal<L: FlightLink>(s: &mut HostSession<L>, goal: GoalRequest) -> Vec<Message> {
    let mut got = s.exchange(&Message::GoalRequest(goal)).expect("goal");
    let mut seen = 0;
    let mut pose: Option<(f32, f32, f32, f32)> = None; // x, y, z, yaw
    // let the executive plan (8 iterations per 1 ms step) and send plan and drive commands
    for _ in 0..400 {
        let t = s.link().now_us() + 10_000;
        got.extend(s.advance_to(t).expect("advance"));
        while seen < got.len() {
            let m = got[seen].clone();
            seen += 1;
            match m {
                Message::Plan(p) if pose.is_none() => {
                    if let Some(w) = p.waypoints.first() {
                        let o = w.pose.orientation;
                        let yaw = (2.0 * (o.w * o.z + o.x * o.y)).atan2(1.0 - 2.0 * (o.y * o.y + o.z * o.z));
                        pose = Some((w.pose.position.x, w.pose.position.y, w.pose.position.z, yaw));
                    }
                }
                Message::DriveCommand(DriveCommand { command_id, motion }) if !matches!(motion, Motion::Stop { .. }) => {
                    let (mut x, mut y, z, mut yaw) = pose.expect("a plan before the first drive command");
                    let (mut dyaw, mut dist) = (0.0, 0.0);
                    match motion {
                        Motion::Turn { yaw_rad } => {
                            yaw += yaw_rad;
                            dyaw = yaw_rad;
                        }
                        Motion::Straight { distance_m } => {
                            x += distance_m * yaw.cos();
                            y += distance_m * yaw.sin();
                            dist = distance_m;
                        }
                        Motion::Stop { .. } => {}
                    }
                    pose = Some((x, y, z, yaw));
                    let report = MotionReport {
                        command_id,
                        outcome: MotionOutcome::Completed,
                        achieved_yaw_rad: dyaw,
                        achieved_distance_m: dist,
                        pose: Pose {
                            position: Point3::new(x, y, z),
                            orientation: Quat { x: 0.0, y: 0.0, z: (0.5 * yaw).sin(), w: (0.5 * yaw).cos() },
                        },
                    };
                    got.extend(s.exchange(&Message::MotionReport(report)).expect("report"));
                }
                _ => {}
            }
        }
        if got.iter().any(|m| matches!(m, Message::DriveCommand(_))) && s.telemetry().expect("t").mode == Mode::Mapping {
            break;
        }
    }
    got
}

#[test]
fn goal_over_the_link_is_planned_on_board_and_driven() {
    let mut s = session_with_map(InProcLink::new(DEFAULT_STEP_US), &XS);
    let got = plan_goal(&mut s, goal(3.0, 40));
    let finals: Vec<&PlanStatus> = got
        .iter()
        .filter_map(|m| if let Message::PlanStatus(p) = m { Some(p) } else { None })
        .filter(|p| !matches!(p.state, PlanState::Accepted | PlanState::Searching))
        .collect();
    assert_eq!(finals.len(), 1, "{got:?}");
    assert_eq!(finals[0].state, PlanState::ExactSolution, "{:?}", s.link().executive().autonomy().plan_stats());
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
                Motion::Stop { .. } => {}
            }
        }
    }
    assert!(drives >= 1);
    let d = ((x - 3.0).powi(2) + y * y).sqrt();
    assert!(d <= 0.5 + 0.05, "drive commands end at ({x}, {y}), {d} m from the goal");
    assert_eq!(s.telemetry().expect("t").mode, Mode::Mapping);
    // protocol v2: the mission status went Planning -> Driving -> ... -> Arrived
    let states: Vec<MissionState> =
        got.iter().filter_map(|m| if let Message::MissionStatus(st) = m { Some(st.state) } else { None }).collect();
    assert!(states.contains(&MissionState::Planning) && states.contains(&MissionState::Driving), "{states:?}");
    assert_eq!(states.last(), Some(&MissionState::Arrived), "{states:?}");
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
    // protocol v8: a team goal needs a `TeamConfigure` first; without one it is refused with that reason
    let mut g = goal(3.0, 10);
    g.planner = PlannerChoice::Team;
    let r = s.exchange(&Message::GoalRequest(g)).expect("goal");
    assert!(r.iter().any(|m| matches!(m, Message::Nack(n) if n.reason == NackReason::NoTeam)), "{r:?}");
    assert!(!r.iter().any(|m| matches!(m, Message::PlanStatus(_))), "{r:?}");
}

/// The emulated flight computer plans the same goal to the same messages (a smaller map and budget: QEMU runs the
/// stability LPs at ~8 M instructions each).
#[test]
fn goal_is_planned_identically_on_the_board() {
    let Some(elf) = host_sim::qemu::board_for_tests("on-board planning equivalence").unwrap_or_else(|e| panic!("{e}"))
    else {
        return;
    };
    let xs = [-0.8, -0.4, 0.0, 0.4, 0.8, 1.2, 1.6];
    let g = goal(1.0, 16);
    let mut inproc = session_with_map(InProcLink::new(DEFAULT_STEP_US), &xs);
    let a = plan_goal(&mut inproc, g);
    let link = host_sim::link::qemu::QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
    let t0 = std::time::Instant::now();
    let mut board = session_with_map(link, &xs);
    let t1 = std::time::Instant::now();
    let b = plan_goal(&mut board, g);
    println!("board: mapping {:?}, planning {:?}", t1 - t0, t1.elapsed());
    let state = |m: &[Message]| {
        m.iter().rev().find_map(|m| if let Message::PlanStatus(p) = m { Some(p.state) } else { None })
    };
    assert_eq!(state(&a), Some(PlanState::ExactSolution), "{a:?}");
    assert_eq!(a, b, "in-process and board outputs differ");
    let exit = board.into_link().quit(core::time::Duration::from_secs(30)).unwrap_or_else(|e| panic!("{e}"));
    assert!(exit.status.success(), "board exit: {:?}\n{}", exit.status, exit.output.both());
    let value = |k: &str| -> usize { exit.output.value(k).and_then(|v| v.parse().ok()).unwrap_or(0) };
    let (hw, size) = (value("stack_high_water_bytes"), value("stack_size_bytes"));
    assert!(hw > 0 && hw < size, "stack high-water {hw} of {size}: {}", exit.output.both());
    println!("board: {}", exit.output.both());
}
