use super::*;
use crate::protocol::*;
use std::boxed::Box;
use std::collections::VecDeque;
use std::vec::Vec as StdVec;

#[derive(Default)]
struct QueueLink {
    to_flight: VecDeque<u8>,
    to_host: StdVec<u8>,
}

impl ByteLink for QueueLink {
    type Error = core::convert::Infallible;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let n = buf.len().min(self.to_flight.len());
        for b in buf.iter_mut().take(n) {
            *b = self.to_flight.pop_front().unwrap();
        }
        Ok(n)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.to_host.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.to_flight.is_empty())
    }
    fn write_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(true)
    }
}

/// Time, and how far each read moves it on (0: it stands still between the test's own advances).
struct Clock(u64, u64);
impl MonotonicClock for Clock {
    fn now(&mut self) -> Instant {
        let t = self.0;
        self.0 += self.1;
        Instant::from_micros(t)
    }
}
struct Dog;
impl Watchdog for Dog {
    type Error = core::convert::Infallible;
    fn kick(&mut self) -> Result<(), Self::Error> {
        Ok(())
    }
}

type Exec<A> = Executive<QueueLink, Clock, Dog, A, Box<ExecStorage>>;

fn exec<A: Autonomy>(a: A) -> Exec<A> {
    Executive::new(
        QueueLink::default(),
        Clock(0, 0),
        Dog,
        a,
        Box::new(ExecStorage::new()),
    )
}

fn configure() -> Configure {
    Configure {
        rover: RoverConfig {
            mass_kg: 20.0,
            wheel_radius_m: 0.25,
            axle_length_m: 0.6,
            boom_length_m: 0.5,
            friction_coefficient: 0.8,
        },
        tether: TetherConfig {
            root_anchor: Point3::new(0.0, 0.0, 2.0),
            max_payout_m: 50.0,
            max_tension_n: 500.0,
        },
        planner: PlannerConfig {
            rng_seed: 7,
            max_iterations: 750,
            batch_size: 100,
            goal_bias: 0.05,
        },
        telemetry: TelemetryConfig {
            period_ms: 0,
            forward_log_level: LogLevel::Info,
        },
        mission: MissionConfig::DEFAULT,
        map: None,
    }
}

fn goal() -> GoalRequest {
    GoalRequest {
        goal_id: 9,
        position: Point3::new(5.0, 0.0, 0.0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Abit,
        max_iterations: 100,
        time_budget_ms: 0,
        allow_approximate: false,
    }
}

/// Sends `msgs` (seq 100, 101, ...), steps until quiet, returns the decoded replies.
fn exchange<A: Autonomy>(e: &mut Exec<A>, msgs: &[Message]) -> StdVec<Message> {
    exchange_from(e, 100, msgs)
}

/// As [`exchange`] from sequence number `first` (a message sent again is a new frame with its own seq: the same
/// seq and CRC again is a duplicate, protocol v4).
fn exchange_from<A: Autonomy>(e: &mut Exec<A>, first: u32, msgs: &[Message]) -> StdVec<Message> {
    for (i, m) in msgs.iter().enumerate() {
        let mut buf = [0u8; 2100];
        let n = encode(first + i as u32, m, &mut buf).unwrap();
        e.link_mut().to_flight.extend(&buf[..n]);
    }
    for _ in 0..100 {
        e.clock_mut().0 += 1000;
        if !e.step().busy {
            break;
        }
    }
    let bytes = core::mem::take(&mut e.link_mut().to_host);
    let mut d = Deframer::new();
    let mut out = StdVec::new();
    let mut rest = &bytes[..];
    while !rest.is_empty() {
        let (n, ev) = d.push(rest);
        if let Some(ev) = ev {
            out.push(decode_frame(ev.unwrap()).unwrap().1);
        }
        rest = &rest[n..];
    }
    out
}

#[test]
fn boot_telemetry_then_goal_without_planner_is_reported_honestly() {
    let mut e = exec(NoAutonomy);
    let boot = exchange(&mut e, &[]);
    assert!(
        matches!(boot.as_slice(), [Message::Telemetry(t)] if t.mode == Mode::Idle && !t.configured)
    );
    let early = exchange(&mut e, &[Message::GoalRequest(goal())]);
    assert_eq!(
        early,
        [Message::Nack(Nack {
            seq: 100,
            reason: NackReason::NotConfigured
        })]
    );
    let r = exchange(
        &mut e,
        &[
            Message::Configure(configure()),
            Message::GoalRequest(goal()),
        ],
    );
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    assert_eq!(r[1], Message::Ack(Ack { seq: 101 }));
    assert_eq!(
        r[2],
        Message::PlanStatus(PlanStatus {
            goal_id: 9,
            state: PlanState::PlannerUnavailable,
            iterations: 0,
            best_cost: None
        })
    );
    assert_eq!(e.mode(), Mode::Idle);
    // forwarded log records follow (level Info configured)
    assert!(r[3..].iter().all(|m| matches!(m, Message::Log(_))));
}

/// Refuses every goal, or (with `at_step`) accepts it and stops its planning with `InvalidInput`, giving a reason.
struct Refuser {
    at_step: bool,
    why: &'static str,
}

const SHORT_REASON: &str = "the rover does not settle on the map at its pose";
const LONG_REASON: &str = "the tile's descent from the root anchor to the goal was not segmented (see the log): move \
                           the goal or upload a tile covering the corridor";

impl Autonomy for Refuser {
    fn goal(&mut self, _g: &GoalRequest, _now: Instant) -> PlanState {
        if self.at_step { PlanState::Accepted } else { PlanState::InvalidInput }
    }
    fn plan_step(&mut self, _now: Instant, _iterations: u32, _plan: &mut PlanBuffer) -> PlanProgress {
        PlanProgress::Finished { state: PlanState::InvalidInput, iterations: 0, best_cost: None }
    }
    fn refusal(&self) -> Option<&'static str> {
        Some(self.why)
    }
}

/// The ground learns why: a refused goal's reason, and the reason a planning stopped with `InvalidInput`, come in a
/// `Warn` log record with the `PlanStatus` (before, only "goal 9: InvalidInput").
#[test]
fn a_refused_goal_and_a_refused_plan_are_reported_with_their_reason() {
    for (at_step, want) in [
        (false, "goal 9 refused: the rover does not settle on the map at its pose"),
        (true, "goal 9: planning stopped: the rover does not settle on the map at its pose"),
    ] {
        let mut e = exec(Refuser { at_step, why: SHORT_REASON });
        let r = exchange(&mut e, &[Message::Configure(configure()), Message::GoalRequest(goal())]);
        assert!(
            r.iter().any(|m| matches!(m, Message::PlanStatus(p) if p.state == PlanState::InvalidInput)),
            "{r:?}"
        );
        let said: StdVec<_> = r
            .iter()
            .filter_map(|m| match m {
                Message::Log(l) if l.level == LogLevel::Warn => Some(l.text.as_str()),
                _ => None,
            })
            .collect();
        assert_eq!(said, [want], "at_step {at_step}: {r:?}");
    }
    // a reason longer than a log record is cut at the record's capacity, not dropped
    let mut e = exec(Refuser { at_step: false, why: LONG_REASON });
    let r = exchange(&mut e, &[Message::Configure(configure()), Message::GoalRequest(goal())]);
    let text = r
        .iter()
        .find_map(|m| match m {
            Message::Log(l) if l.level == LogLevel::Warn => Some(l.text.as_str()),
            _ => None,
        })
        .unwrap();
    assert_eq!(text.len(), crate::config::protocol::MAX_LOG_TEXT, "{text}");
    assert!(text.starts_with("goal 9 refused: the tile's descent"), "{text}");
    // an autonomy that gives no reason keeps the plain record
    let mut e = exec(NoAutonomy);
    let r = exchange(&mut e, &[Message::Configure(configure()), Message::GoalRequest(goal())]);
    assert!(r.iter().any(|m| matches!(m, Message::Log(l) if l.text.as_str() == "goal 9: PlannerUnavailable")));
}

/// A scripted planner: searches for two steps, then returns a 14-waypoint plan and two motions.
#[derive(Default)]
struct Scripted {
    steps: u32,
    motions: u32,
    scans: StdVec<(u32, usize)>,
    parts: StdVec<(u32, usize)>,
}

impl Autonomy for Scripted {
    fn scan_part(&mut self, part: &Scan<'_>, _now: Instant) {
        self.parts.push((part.scan_id, part.points.len()));
    }
    fn scan_complete(&mut self, scan: &Scan<'_>, _now: Instant) {
        self.scans.push((scan.scan_id, scan.points.len()));
    }
    fn goal(&mut self, _g: &GoalRequest, _now: Instant) -> PlanState {
        PlanState::Accepted
    }
    fn plan_step(&mut self, _now: Instant, iterations: u32, plan: &mut PlanBuffer) -> PlanProgress {
        self.steps += 1;
        if self.steps < 3 {
            return PlanProgress::Searching {
                iterations: self.steps * iterations,
                best_cost: None,
            };
        }
        for i in 0..14 {
            let mut pose = Pose::IDENTITY;
            pose.position.x = i as f32;
            plan.push(Waypoint {
                pose,
                anchors: heapless::Vec::new(),
                stability_margin: 1.0,
            })
            .unwrap();
        }
        PlanProgress::Finished {
            state: PlanState::ExactSolution,
            iterations: 24,
            best_cost: Some(14.0),
        }
    }
    fn next_motion(&mut self, _now: Instant) -> Option<Motion> {
        self.motions += 1;
        (self.motions <= 2).then_some(Motion::Straight { distance_m: 1.0 })
    }
}

#[test]
fn planning_sends_status_plan_parts_and_drive_commands_then_returns_to_mapping() {
    let mut e = exec(Scripted::default());
    let mut cfg = configure();
    cfg.telemetry.forward_log_level = LogLevel::Off;
    exchange(&mut e, &[Message::Configure(cfg)]);
    let r = exchange(&mut e, &[Message::GoalRequest(goal())]);
    let states: StdVec<PlanState> = r
        .iter()
        .filter_map(|m| {
            if let Message::PlanStatus(s) = m {
                Some(s.state)
            } else {
                None
            }
        })
        .collect();
    assert_eq!(
        states,
        [
            PlanState::Accepted,
            PlanState::Searching,
            PlanState::ExactSolution
        ]
    );
    let parts: StdVec<(u16, u16, usize)> = r
        .iter()
        .filter_map(|m| {
            if let Message::Plan(p) = m {
                Some((p.part, p.parts, p.waypoints.len()))
            } else {
                None
            }
        })
        .collect();
    assert_eq!(parts, [(0, 2, 12), (1, 2, 2)]);
    // v2: one drive command, then nothing until its report
    let drives = drive_ids(&r);
    assert_eq!(drives.len(), 1);
    assert_eq!(e.mode(), Mode::Driving);
    let r = exchange(&mut e, &[report(drives[0])]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    let second = drive_ids(&r);
    assert_eq!(second, [drives[0] + 1]);
    let r = exchange(&mut e, &[report(second[0])]);
    assert!(drive_ids(&r).is_empty());
    assert_eq!(e.mode(), Mode::Mapping);
    assert_eq!(e.telemetry().motion_reports, 2);
}

fn drive_ids(r: &[Message]) -> StdVec<u32> {
    r.iter()
        .filter_map(|m| match m {
            Message::DriveCommand(d) if !matches!(d.motion, Motion::Stop { .. }) => Some(d.command_id),
            _ => None,
        })
        .collect()
}

fn report(command_id: u32) -> Message {
    Message::MotionReport(MotionReport {
        command_id,
        outcome: MotionOutcome::Completed,
        achieved_yaw_rad: 0.0,
        achieved_distance_m: 1.0,
        pose: Pose::IDENTITY,
    })
}

/// Plans like [`Scripted`] and drives forever; records what the v2 hooks saw.
#[derive(Default)]
struct Mission {
    inner: Scripted,
    reports: StdVec<(u32, Motion)>,
    timeouts: StdVec<u32>,
    cancels: StdVec<u32>,
    goals: StdVec<u32>,
    /// `stop_in_flight` answers true this many times.
    stops_wanted: u32,
    stop_asks: u32,
}

impl Autonomy for Mission {
    fn stop_in_flight(&mut self, _now: Instant) -> bool {
        self.stop_asks += 1;
        let stop = self.stops_wanted > 0;
        self.stops_wanted = self.stops_wanted.saturating_sub(1);
        stop
    }
    fn goal(&mut self, g: &GoalRequest, _now: Instant) -> PlanState {
        self.goals.push(g.goal_id);
        self.inner.steps = 0;
        PlanState::Accepted
    }
    fn plan_step(&mut self, now: Instant, iterations: u32, plan: &mut PlanBuffer) -> PlanProgress {
        self.inner.plan_step(now, iterations, plan)
    }
    fn next_motion(&mut self, _now: Instant) -> Option<Motion> {
        Some(Motion::Turn { yaw_rad: 0.5 })
    }
    fn motion_report(&mut self, r: &MotionReport, m: Motion, _now: Instant) {
        self.reports.push((r.command_id, m));
    }
    fn motion_timeout(&mut self, id: u32, _now: Instant) {
        self.timeouts.push(id);
    }
    fn cancel(&mut self, goal_id: u32, _now: Instant) -> Result<(), Refused> {
        self.cancels.push(goal_id);
        Ok(())
    }
    fn mission_status(&self) -> Option<MissionStatus> {
        Some(MissionStatus {
            goal_id: self.goals.last().copied().unwrap_or(0),
            state: if self.cancels.is_empty() {
                MissionState::Driving
            } else {
                MissionState::Safe
            },
            reason: if self.cancels.is_empty() {
                StopReason::None
            } else {
                StopReason::Cancelled
            },
            distance_driven_m: 0.0,
            predicted_payout_m: 0.0,
            measured_payout_m: 0.0,
            tension_n: 0.0,
            margin_n: 0.0,
            cross_track_m: 0.0,
            replans: 0,
            anchors: 1,
            motions_done: self.reports.len() as u32,
            tether_rejected: 0,
            pose_jumps: 0,
            scans_rejected: 0,
            tether_reestimates: 0,
        })
    }
}

fn mission_exec() -> (Exec<Mission>, u32) {
    let mut e = exec(Mission::default());
    let mut cfg = configure();
    cfg.telemetry.forward_log_level = LogLevel::Off;
    exchange(&mut e, &[Message::Configure(cfg)]);
    let r = exchange(&mut e, &[Message::GoalRequest(goal())]);
    let ids = drive_ids(&r);
    assert_eq!(ids.len(), 1, "{r:?}");
    (e, ids[0])
}

#[test]
fn reports_for_unknown_or_reported_commands_are_refused_and_counted() {
    let (mut e, id) = mission_exec();
    let r = exchange(&mut e, &[report(id + 7)]);
    assert_eq!(
        r,
        [Message::Nack(Nack {
            seq: 100,
            reason: NackReason::UnknownCommand
        })]
    );
    assert!(e.autonomy().reports.is_empty());
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    assert!(matches!(r[1], Message::MissionStatus(m) if m.motions_done == 1));
    assert_eq!(e.autonomy().reports, [(id, Motion::Turn { yaw_rad: 0.5 })]);
    let next = drive_ids(&r);
    assert_eq!(next, [id + 1]);
    // the same report again (a new frame): already reported
    let r = exchange_from(&mut e, 200, &[report(id)]);
    assert_eq!(
        r[0],
        Message::Nack(Nack {
            seq: 200,
            reason: NackReason::UnknownCommand
        })
    );
    let t = e.telemetry();
    assert_eq!(t.frames_rejected[NackReason::UnknownCommand.index()], 2);
    assert_eq!(t.motion_reports, 1);
}

/// The autonomy asks for the motion in flight to stop (the map changed under it): one `Stop` goes out, the
/// executive asks no more for that motion and waits for its report, and the next motion follows the report.
#[test]
fn a_stop_asked_for_in_flight_is_sent_once_and_the_report_still_awaited() {
    let (mut e, id) = mission_exec();
    let stops = |r: &[Message]| r.iter().filter(|m| matches!(m, Message::DriveCommand(d) if matches!(d.motion, Motion::Stop { .. }))).count();
    e.autonomy_mut().stops_wanted = 5;
    let r = exchange(&mut e, &[]);
    assert_eq!(stops(&r), 1, "{r:?}");
    assert!(drive_ids(&r).is_empty());
    let asked = e.autonomy().stop_asks;
    let r = exchange(&mut e, &[]);
    assert_eq!((stops(&r), e.autonomy().stop_asks), (0, asked), "asked again for a motion already stopping");
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(e.autonomy().reports, [(id, Motion::Turn { yaw_rad: 0.5 })]);
    // the next motion (the stop took a command id of its own)
    assert_eq!(drive_ids(&r), [id + 2]);
}

#[test]
fn a_missing_report_times_out_with_a_stop() {
    let (mut e, id) = mission_exec();
    e.clock_mut().0 += MOTION_REPORT_TIMEOUT_US;
    let r = exchange(&mut e, &[]);
    assert_eq!(stops_of(&r), [(id + 1, id)], "the stop names the motion given up: {r:?}");
    assert_eq!(e.autonomy().timeouts, [id]);
    assert_eq!(e.telemetry().motion_report_timeouts, 1);
    // the late report is refused
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(
        r[0],
        Message::Nack(Nack {
            seq: 100,
            reason: NackReason::UnknownCommand
        })
    );
}

#[test]
fn a_goal_while_driving_replaces_it_and_stops_the_motion_in_flight() {
    let (mut e, id) = mission_exec();
    let mut g2 = goal();
    g2.goal_id = 10;
    let r = exchange(&mut e, &[Message::GoalRequest(g2)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    assert!(matches!(r[1], Message::PlanStatus(p) if p.goal_id == 10 && p.state == PlanState::Accepted));
    assert!(matches!(
        r[2],
        Message::DriveCommand(DriveCommand {
            motion: Motion::Stop { .. },
            ..
        })
    ));
    assert_eq!(e.autonomy().goals, [9, 10]);
    // the new plan is sent, but no drive command before the interrupted motion is reported
    assert!(r.iter().any(|m| matches!(m, Message::Plan(p) if p.goal_id == 10)));
    assert!(drive_ids(&r).is_empty());
    assert_eq!(e.mode(), Mode::Driving);
    let mut stopped = report(id);
    if let Message::MotionReport(m) = &mut stopped {
        m.outcome = MotionOutcome::Stopped;
    }
    let r = exchange(&mut e, &[stopped]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    assert_eq!(drive_ids(&r).len(), 1);
    assert_eq!(e.telemetry().illegal_transitions, 0);
}

#[test]
fn a_cancel_stops_and_returns_to_mapping() {
    let (mut e, _id) = mission_exec();
    let r = exchange(&mut e, &[Message::GoalCancel(GoalCancel { goal_id: 3 })]);
    assert_eq!(
        r,
        [Message::Nack(Nack {
            seq: 100,
            reason: NackReason::UnknownGoal
        })]
    );
    let r = exchange(&mut e, &[Message::GoalCancel(GoalCancel { goal_id: 9 })]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    assert!(matches!(
        r[1],
        Message::DriveCommand(DriveCommand {
            motion: Motion::Stop { .. },
            ..
        })
    ));
    assert!(r.iter().any(|m| matches!(m, Message::MissionStatus(s) if s.reason == StopReason::Cancelled)));
    assert_eq!(e.mode(), Mode::Mapping);
    assert_eq!(e.autonomy().cancels, [9]);
    assert_eq!(e.telemetry().goal_cancels, 1);
    // nothing more to cancel (the same cancel again, a new frame)
    let r = exchange_from(&mut e, 200, &[Message::GoalCancel(GoalCancel { goal_id: 9 })]);
    assert_eq!(
        r[0],
        Message::Nack(Nack {
            seq: 200,
            reason: NackReason::UnknownGoal
        })
    );
}

#[test]
fn without_a_mission_cancel_is_refused_and_no_mission_status_is_sent() {
    let mut e = exec(NoAutonomy);
    exchange(&mut e, &[Message::Configure(configure())]);
    let r = exchange(
        &mut e,
        &[
            Message::GoalCancel(GoalCancel { goal_id: 9 }),
            Message::TelemetryRequest(TelemetryRequest),
        ],
    );
    assert_eq!(
        r[0],
        Message::Nack(Nack {
            seq: 100,
            reason: NackReason::UnknownGoal
        })
    );
    assert!(!r.iter().any(|m| matches!(m, Message::MissionStatus(_))));
}

#[test]
fn a_version_1_frame_is_wrong_version_and_changes_nothing() {
    let mut e = exec(NoAutonomy);
    exchange(&mut e, &[Message::Configure(configure())]);
    let before = e.telemetry();
    // the v1 document's TimeTick example, byte for byte
    let v1 = [0x01u8, 0x01, 0x01, 0x00, 0x00, 0x00, 0xE8, 0x07, 0xA1, 0xEB, 0x60, 0xCC];
    let mut w = [0u8; 32];
    let n = stuff(&v1, &mut w).unwrap();
    e.link_mut().to_flight.extend(&w[..n]);
    let r = exchange(&mut e, &[]);
    assert_eq!(
        r,
        [Message::Nack(Nack {
            seq: 1,
            reason: NackReason::WrongVersion
        })]
    );
    let after = e.telemetry();
    assert_eq!(after.frames_rejected[NackReason::WrongVersion.index()], 1);
    assert_eq!(after.frames_accepted, before.frames_accepted);
    assert_eq!(after.mode, before.mode);
}

#[test]
fn shutdown_stops_and_safe_mode_refuses_work() {
    let mut e = exec(NoAutonomy);
    exchange(&mut e, &[Message::Configure(configure())]);
    let r = exchange(&mut e, &[Message::Shutdown(Shutdown)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    // v6: no motion was ever sent: the stop names its own command id (no motion)
    assert_eq!(stops_of(&r), [(0, 0)]);
    assert!(matches!(r[1], Message::DriveCommand(_)));
    assert_eq!(e.mode(), Mode::Safe);
    let r = exchange(
        &mut e,
        &[
            Message::GoalRequest(goal()),
            Message::TelemetryRequest(TelemetryRequest),
        ],
    );
    assert_eq!(
        r[0],
        Message::Nack(Nack {
            seq: 100,
            reason: NackReason::NotAllowedInMode
        })
    );
    assert_eq!(r[1], Message::Ack(Ack { seq: 101 }));
    assert!(matches!(r[2], Message::Telemetry(t) if t.mode == Mode::Safe));
}

#[test]
fn a_scan_in_three_chunks_reaches_the_part_hook_per_chunk_and_the_complete_hook_once() {
    let mut e = exec(Scripted::default());
    exchange(&mut e, &[Message::Configure(configure())]);
    let chunk = |i: u16| {
        let mut points = heapless::Vec::new();
        for k in 0..100 {
            points.push(Point3::new(k as f32, i as f32, 1.0)).unwrap();
        }
        Message::SensorChunk(SensorChunk {
            scan_id: 4,
            chunk_index: i,
            chunk_count: 3,
            sensor_pose: Pose::IDENTITY,
            points,
        })
    };
    // chunk 1 twice (the second is a duplicate, Nacked) and chunk 2 before chunk 1 (out of order, Nacked):
    // neither reaches the autonomy
    let r = exchange(&mut e, &[chunk(0), chunk(2), chunk(1), chunk(1), chunk(2)]);
    assert_eq!(r.iter().filter(|m| matches!(m, Message::Ack(_))).count(), 3);
    assert_eq!(r.iter().filter(|m| matches!(m, Message::Nack(_))).count(), 2);
    assert_eq!(e.autonomy().parts, [(4, 100), (4, 100), (4, 100)]);
    assert_eq!(e.autonomy().scans, [(4, 300)]);
    assert_eq!(e.mode(), Mode::Mapping);
}

#[test]
fn log_frames_are_rate_limited_and_the_queue_is_bounded() {
    let mut e = exec(NoAutonomy);
    let mut cfg = configure();
    cfg.telemetry.forward_log_level = LogLevel::Debug;
    exchange(&mut e, &[Message::Configure(cfg)]);
    // drain the "configured" record
    for _ in 0..1000 {
        e.clock_mut().0 += 1000;
        e.step();
    }
    e.link_mut().to_host.clear();
    let mut queued = 0;
    for i in 0..20 {
        if e.forward_log(LogLevel::Info, format_args!("record {i}")) {
            queued += 1;
        }
    }
    assert_eq!(queued, LOG_QUEUE_LEN);
    assert_eq!(e.telemetry().log_dropped, 20 - LOG_QUEUE_LEN as u32);
    // within 100 ms only the burst goes out
    let mut logs = 0;
    for _ in 0..100 {
        e.clock_mut().0 += 1000;
        e.step();
    }
    let bytes = core::mem::take(&mut e.link_mut().to_host);
    let mut d = Deframer::new();
    let mut rest = &bytes[..];
    while !rest.is_empty() {
        let (n, ev) = d.push(rest);
        if let Some(Ok(f)) = ev {
            if let Ok((_, Message::Log(_))) = decode_frame(f) {
                logs += 1;
            }
        }
        rest = &rest[n..];
    }
    // burst of LOG_BURST plus at most one refill within 100 ms at 10/s
    assert!(
        logs >= LOG_BURST as usize && logs <= LOG_BURST as usize + 1,
        "{logs}"
    );
}

#[test]
fn a_safe_stop_between_reports_stops_the_motion_in_flight() {
    let (mut e, id) = mission_exec();
    // the autonomy decides to stop (here: its status turns Safe) while the motion is in flight
    e.autonomy_mut().cancels.push(9);
    let r = exchange(&mut e, &[]);
    assert!(r.iter().any(|m| matches!(m, Message::MissionStatus(s) if s.state == MissionState::Safe)));
    assert_eq!(stops_of(&r), [(id + 1, id)]);
    // the interrupted motion's report is still accepted
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
}

/// The `Stop`s in `r`: (its command id, the motion it stops).
fn stops_of(r: &[Message]) -> std::vec::Vec<(u32, u32)> {
    r.iter()
        .filter_map(|m| match m {
            Message::DriveCommand(DriveCommand { command_id, motion: Motion::Stop { motion_id } }) => {
                Some((*command_id, *motion_id))
            }
            _ => None,
        })
        .collect()
}

/// Protocol v6: a `Stop` names the motion in flight and, like a drive command, goes again unchanged every
/// `DRIVE_COMMAND_RESEND_US` until that motion's report (the downlink may have lost it); the motion itself is not
/// resent once stopped. The report ends the resends.
#[test]
fn a_stop_names_its_motion_and_is_sent_again_until_the_report() {
    let (mut e, id) = mission_exec();
    e.autonomy_mut().cancels.push(9);
    let r = exchange(&mut e, &[]);
    assert_eq!(stops_of(&r), [(id + 1, id)]);
    let r = exchange(&mut e, &[]);
    assert!(stops_of(&r).is_empty(), "again before its period: {r:?}");
    for resends in 1..=2 {
        e.clock_mut().0 += DRIVE_COMMAND_RESEND_US;
        let r = exchange(&mut e, &[]);
        assert_eq!(stops_of(&r), [(id + 1, id)], "{r:?}");
        assert!(drive_ids(&r).is_empty(), "the stopped motion is not resent: {r:?}");
        assert_eq!(e.telemetry().drive_resends, resends);
    }
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 100 }));
    e.clock_mut().0 += DRIVE_COMMAND_RESEND_US;
    let r = exchange(&mut e, &[]);
    // (this test autonomy drives on: the next motion's own resend may follow, never the stop)
    assert!(stops_of(&r).is_empty() && !drive_ids(&r).contains(&id), "{r:?}");
}

/// Protocol v4: the same frame twice (seq and CRC) is refused `DuplicateFrame` and not acted on; lost, late and
/// far-off sequence numbers are counted.
#[test]
fn duplicates_are_refused_and_sequence_gaps_and_late_frames_counted() {
    let (mut e, id) = mission_exec();
    let before = e.telemetry();
    let mut buf = [0u8; 2100];
    let n = encode(300, &report(id), &mut buf).unwrap();
    e.link_mut().to_flight.extend(&buf[..n]);
    e.link_mut().to_flight.extend(&buf[..n]);
    let r = exchange(&mut e, &[]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 300 }));
    assert!(r.contains(&Message::Nack(Nack { seq: 300, reason: NackReason::DuplicateFrame })));
    // acted on once: one report, no UnknownCommand for the copy
    assert_eq!(e.autonomy().reports.len(), 1);
    let t = e.telemetry();
    assert_eq!(t.frames_rejected[NackReason::DuplicateFrame.index()], 1);
    assert_eq!(t.frames_rejected[NackReason::UnknownCommand.index()], 0);
    // mission_exec's frames were 100, 101, ...: 300 skipped the ones in between
    let gaps = t.seq_gaps - before.seq_gaps;
    assert!(gaps > 0, "{gaps}");
    // 305 after 300: four lost; then 303 arrives late
    exchange_from(&mut e, 305, &[Message::TimeTick(TimeTick { host_time_us: 1 })]);
    exchange_from(&mut e, 303, &[Message::TimeTick(TimeTick { host_time_us: 2 })]);
    let t2 = e.telemetry();
    assert_eq!((t2.seq_gaps - t.seq_gaps, t2.seq_late - t.seq_late, t2.seq_resyncs), (4, 1, 0));
    // a jump ahead of more than SEQ_WINDOW is a loss burst: every frame in between is counted lost
    let w = crate::config::exec::SEQ_WINDOW;
    exchange_from(&mut e, 305 + 2 * w, &[Message::TimeTick(TimeTick { host_time_us: 3 })]);
    let t3 = e.telemetry();
    assert_eq!((t3.seq_gaps - t2.seq_gaps, t3.seq_late, t3.seq_resyncs), (2 * w - 1, t2.seq_late, 0));
    // a host restarted from 0 is far behind: a new host session, nothing counted lost or late
    exchange_from(&mut e, 0, &[Message::TimeTick(TimeTick { host_time_us: 4 })]);
    let t4 = e.telemetry();
    assert_eq!((t4.seq_gaps, t4.seq_late, t4.seq_resyncs), (t3.seq_gaps, t3.seq_late, 1));
}

/// A host whose numbering starts just below the wrap (the soak) is a new session at boot: its frames are neither
/// late nor lost, across the wrap too.
#[test]
fn a_host_numbering_from_near_the_wrap_is_neither_late_nor_lost() {
    let mut e = exec(Mission::default());
    let first = u32::MAX - 2;
    for k in 0..6u32 {
        exchange_from(&mut e, first.wrapping_add(k), &[Message::TimeTick(TimeTick { host_time_us: u64::from(k) + 1 })]);
    }
    let t = e.telemetry();
    assert_eq!((t.seq_gaps, t.seq_late, t.seq_resyncs), (0, 0, 1));
}

/// Cycle accounting: a clock that moves during a step gives the step's duration, the maximum and the slips over
/// `STEP_BUDGET_US`; the period maximum restarts with each `Telemetry` frame; the first slip is logged once.
#[test]
fn cycle_accounting_measures_steps_on_the_clock_and_counts_slips() {
    use crate::config::exec::STEP_BUDGET_US;
    let mut e = exec(NoAutonomy);
    exchange(&mut e, &[Message::Configure(configure())]);
    assert_eq!(e.telemetry().cycle.max_step_us, 0, "a clock that stands still gives zero-length steps");
    // every read of this clock moves it on: a step lasts `d`
    for d in [STEP_BUDGET_US / 2, STEP_BUDGET_US + 7, 3 * STEP_BUDGET_US, STEP_BUDGET_US] {
        e.clock_mut().1 = d;
        e.step();
        e.clock_mut().1 = 0;
    }
    let t = e.telemetry();
    assert_eq!(t.cycle.budget_us as u64, STEP_BUDGET_US);
    assert_eq!(t.cycle.max_step_us as u64, 3 * STEP_BUDGET_US);
    assert_eq!(t.cycle.period_max_step_us as u64, 3 * STEP_BUDGET_US);
    assert_eq!(t.cycle.slips, 2, "two steps over budget; one exactly at it is not a slip");
    // a telemetry request: the frame carries the period maximum, then it restarts
    let r = exchange_from(&mut e, 101, &[Message::TelemetryRequest(TelemetryRequest)]);
    let sent = r.iter().find_map(|m| if let Message::Telemetry(t) = m { Some(*t) } else { None }).unwrap();
    assert_eq!(sent.cycle.period_max_step_us as u64, 3 * STEP_BUDGET_US);
    assert_eq!(e.telemetry().cycle.period_max_step_us, 0);
    // the throttle: one `Warn` record for the two slips of the period
    let slip_logs = r.iter().filter(|m| matches!(m, Message::Log(l) if l.text.contains("cycle slip"))).count();
    assert_eq!(slip_logs, 1);
    assert_eq!(e.telemetry().cycle.max_step_us as u64, 3 * STEP_BUDGET_US);
}

/// Protocol v5 (issue 24): a `GoalRequest` or `Configure` sent again under a new sequence number with the same
/// body (its `Ack` was lost on the downlink, so the host resent it) is answered `Ack` and not applied again: the
/// goal is not replaced (no `PlanStatus`, no `Stop`, no replanning), the navigator not reconfigured; a changed
/// request is applied.
#[test]
fn a_resent_request_already_acted_on_is_answered_but_not_applied_again() {
    let (mut e, id) = mission_exec();
    let goals = e.autonomy().goals.clone();
    let before = e.telemetry();
    let r = exchange_from(&mut e, 300, &[Message::GoalRequest(goal())]);
    assert_eq!(r.first(), Some(&Message::Ack(Ack { seq: 300 })), "{r:?}");
    assert!(!r.iter().any(|m| matches!(m, Message::PlanStatus(_) | Message::DriveCommand(_))), "{r:?}");
    assert_eq!(e.autonomy().goals, goals, "the goal was applied again");
    assert_eq!(e.mode(), Mode::Driving);
    // the Configure of mission_exec again: answered, even while driving (where a new one is refused)
    let mut cfg = configure();
    cfg.telemetry.forward_log_level = LogLevel::Off;
    let r = exchange_from(&mut e, 301, &[Message::Configure(cfg)]);
    assert_eq!(r.first(), Some(&Message::Ack(Ack { seq: 301 })), "{r:?}");
    let t = e.telemetry();
    assert_eq!(t.requests_repeated, 2);
    assert_eq!(t.frames_accepted, before.frames_accepted + 2);
    // nothing was disturbed: the motion in flight is still awaited and its report taken once
    let r = exchange_from(&mut e, 302, &[report(id)]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 302 }));
    assert_eq!(e.autonomy().reports, [(id, Motion::Turn { yaw_rad: 0.5 })]);
    // a changed request is a new one: another goal id is applied
    let mut g2 = goal();
    g2.goal_id = 10;
    let r = exchange_from(&mut e, 303, &[Message::GoalRequest(g2)]);
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(p) if p.goal_id == 10)), "{r:?}");
    assert_eq!(e.autonomy().goals.last(), Some(&10));
    // a changed Configure is refused while driving, as before (and not remembered)
    cfg.planner.rng_seed += 1;
    let r = exchange_from(&mut e, 304, &[Message::Configure(cfg)]);
    assert_eq!(r[0], Message::Nack(Nack { seq: 304, reason: NackReason::NotAllowedInMode }));
    assert_eq!(e.telemetry().requests_repeated, 2);
}

/// A refused request changed nothing and is not remembered: its resend is handled afresh (here accepted once the
/// reason is gone).
#[test]
fn a_resent_request_that_was_refused_is_handled_afresh() {
    let mut e = exec(NoAutonomy);
    exchange(&mut e, &[]);
    let r = exchange(&mut e, &[Message::GoalRequest(goal())]);
    assert_eq!(r[0], Message::Nack(Nack { seq: 100, reason: NackReason::NotConfigured }));
    exchange_from(&mut e, 101, &[Message::Configure(configure())]);
    let r = exchange_from(&mut e, 102, &[Message::GoalRequest(goal())]);
    assert_eq!(r[0], Message::Ack(Ack { seq: 102 }));
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(_))), "{r:?}");
    assert_eq!(e.telemetry().requests_repeated, 0);
}

/// Protocol v5: a drive command whose report is late is sent again unchanged (the downlink may have lost it), once
/// per `DRIVE_COMMAND_RESEND_US`, counted; its report ends the resends and the next command has a new id.
#[test]
fn a_drive_command_without_its_report_is_sent_again_unchanged() {
    let (mut e, id) = mission_exec();
    let r = exchange(&mut e, &[]);
    assert!(drive_ids(&r).is_empty(), "{r:?}");
    e.clock_mut().0 += DRIVE_COMMAND_RESEND_US;
    let r = exchange(&mut e, &[]);
    assert_eq!(drive_ids(&r), [id]);
    assert!(r.contains(&Message::DriveCommand(DriveCommand { command_id: id, motion: Motion::Turn { yaw_rad: 0.5 } })));
    assert_eq!(e.telemetry().drive_resends, 1);
    let r = exchange(&mut e, &[]);
    assert!(drive_ids(&r).is_empty(), "again before its period: {r:?}");
    e.clock_mut().0 += DRIVE_COMMAND_RESEND_US;
    assert_eq!(drive_ids(&exchange(&mut e, &[])), [id]);
    let r = exchange(&mut e, &[report(id)]);
    assert_eq!(e.autonomy().reports, [(id, Motion::Turn { yaw_rad: 0.5 })]);
    assert_eq!(drive_ids(&r), [id + 1]);
    assert_eq!(e.telemetry().drive_resends, 2);
    assert_eq!(e.telemetry().motion_report_timeouts, 0);
}

/// The chunks of a `rows x cols` tile whose post `i` (row-major) has height `h(i)`.
fn tile_chunks(tile_id: u32, rows: u16, cols: u16, resolution_m: f32, h: impl Fn(usize) -> f32) -> StdVec<TileChunk> {
    use crate::config::protocol::MAX_HEIGHTS_PER_TILE_CHUNK;
    let cells = usize::from(rows) * usize::from(cols);
    let count = cells.div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK) as u16;
    (0..count)
        .map(|idx| {
            let start = usize::from(idx) * MAX_HEIGHTS_PER_TILE_CHUNK;
            let mut heights = heapless::Vec::new();
            for i in start..cells.min(start + MAX_HEIGHTS_PER_TILE_CHUNK) {
                heights.push(h(i)).unwrap();
            }
            TileChunk {
                tile_id,
                chunk_index: idx,
                chunk_count: count,
                origin_x_m: -1.0,
                origin_y_m: -2.0,
                resolution_m,
                rows,
                cols,
                heights,
            }
        })
        .collect()
}

type TestNav = crate::nav::Navigator<StdVec<crate::map::Block>, StdVec<u32>, Box<crate::nav::NavPlanStorage>>;

fn nav_exec() -> Exec<TestNav> {
    let nav = crate::nav::Navigator::new(
        crate::config::map::MapConfig::with_voxel_size(0.1),
        std::vec![crate::map::Block::EMPTY; 64],
        std::vec![0u32; 128],
        Box::<crate::nav::NavPlanStorage>::default(),
    )
    .unwrap();
    exec(nav)
}

fn nacks(r: &[Message]) -> StdVec<NackReason> {
    r.iter().filter_map(|m| if let Message::Nack(n) = m { Some(n.reason) } else { None }).collect()
}

fn telemetry_of(r: &[Message]) -> Telemetry {
    r.iter().rev().find_map(|m| if let Message::Telemetry(t) = m { Some(*t) } else { None }).unwrap()
}

/// Protocol v7: a tile in chunks is swapped in whole once its last chunk arrived; every bad upload (NaN heights, a
/// spacing out of range, chunks out of order, duplicated or of another tile, a tile larger than the limit) is refused
/// with its own reason, counted in `Telemetry.frames_rejected`, and leaves the tile in use as it was.
#[test]
fn a_tile_is_swapped_in_only_whole_and_valid_and_every_bad_upload_keeps_the_previous_one() {
    let mut e = nav_exec();
    let good = |i: usize| 0.01 * i as f32;
    // 20 x 30 posts: 3 chunks; before the last one the navigator has no tile
    let chunks = tile_chunks(1, 20, 30, 0.5, good);
    let first: StdVec<Message> = chunks[..2].iter().cloned().map(Message::TileChunk).collect();
    let r = exchange_from(&mut e, 0, &first);
    assert!(nacks(&r).is_empty(), "{r:?}");
    assert!(e.autonomy().terrain_tile().is_none());
    let r = exchange_from(&mut e, 2, &[Message::TileChunk(chunks[2].clone()), Message::TelemetryRequest(TelemetryRequest)]);
    assert!(nacks(&r).is_empty(), "{r:?}");
    let t = telemetry_of(&r);
    assert_eq!((t.map.tiles_loaded, t.map.tile_id), (1, 1));
    let check_tile = |e: &Exec<TestNav>| {
        let tile = e.autonomy().terrain_tile().unwrap();
        assert_eq!(tile.shape(), (20, 30));
        assert_eq!(tile.resolution_m(), 0.5);
        assert_eq!(tile.post_xy(0, 0), [-1.0, -2.0]);
        assert_eq!(tile.height(19, 29), Some(f64::from(good(19 * 30 + 29))));
        assert_eq!(tile.height(3, 4), Some(f64::from(good(3 * 30 + 4))));
    };
    check_tile(&e);

    let mut seq = 10;
    let mut send = |e: &mut Exec<TestNav>, msgs: StdVec<TileChunk>| {
        let mut msgs: StdVec<Message> = msgs.into_iter().map(Message::TileChunk).collect();
        msgs.push(Message::TelemetryRequest(TelemetryRequest));
        let r = exchange_from(e, seq, &msgs);
        seq += msgs.len() as u32;
        (nacks(&r), telemetry_of(&r))
    };
    // NaN heights in the second chunk of tile 2: refused there; the rest cannot complete it
    let mut nan = tile_chunks(2, 20, 30, 0.5, |i| 1.0 + i as f32);
    nan[1].heights[7] = f32::NAN;
    let (n, t) = send(&mut e, nan.clone());
    assert_eq!(n, [NackReason::NonFinite, NackReason::OutOfOrderChunk]);
    assert_eq!(t.frames_rejected[NackReason::NonFinite.index()], 1);
    let mut inf = tile_chunks(3, 20, 30, 0.5, |i| 1.0 + i as f32);
    inf[0].heights[0] = f32::INFINITY;
    let (n, _) = send(&mut e, inf);
    assert_eq!(n, [NackReason::NonFinite, NackReason::TileMismatch, NackReason::TileMismatch]);
    // a spacing out of range, either way
    for res in [10.0, 0.001] {
        let (n, _) = send(&mut e, tile_chunks(4, 20, 30, res, good));
        assert_eq!(n, [NackReason::TileResolution; 3]);
    }
    // out of order: chunk 2 before chunk 1
    let ooo = tile_chunks(5, 20, 30, 0.5, good);
    let (n, t) = send(&mut e, std::vec![ooo[0].clone(), ooo[2].clone()]);
    assert_eq!(n, [NackReason::OutOfOrderChunk]);
    assert_eq!(t.frames_rejected[NackReason::OutOfOrderChunk.index()], 2);
    // duplicated: chunk 1 twice (tile 5 still in progress)
    let (n, _) = send(&mut e, std::vec![ooo[1].clone(), ooo[1].clone()]);
    assert_eq!(n, [NackReason::DuplicateChunk]);
    // another tile's chunk in the middle of tile 5
    let other = tile_chunks(6, 20, 30, 0.5, good);
    let (n, t) = send(&mut e, std::vec![other[2].clone()]);
    assert_eq!(n, [NackReason::TileMismatch]);
    assert_eq!(t.map.tiles_loaded, 1);
    // larger than the limit
    let (n, t) = send(&mut e, tile_chunks(7, 129, 10, 0.5, good));
    assert!(n.iter().all(|r| *r == NackReason::TileTooLarge) && n.len() == 6, "{n:?}");
    assert_eq!(t.frames_rejected[NackReason::TileTooLarge.index()], 6);
    // the tile in use is tile 1, unchanged; tile 5 (3 chunks: two arrived) was never completed
    assert_eq!((t.map.tiles_loaded, t.map.tile_id), (1, 1));
    check_tile(&e);
    // a chunk 0 of another tile abandons tile 5 (counted: the second, after tile 2 that tile 5 abandoned), and the
    // new tile completes
    let (n, t) = send(&mut e, tile_chunks(8, 10, 10, 2.0, |_| 3.0));
    assert!(n.is_empty(), "{n:?}");
    assert_eq!((t.map.tiles_loaded, t.map.tile_id, t.map.tiles_abandoned), (2, 8, 2));
    assert_eq!(e.autonomy().terrain_tile().unwrap().shape(), (10, 10));
}

/// Without a map and planner (`NoAutonomy`) tiles are reassembled and dropped, with the same checks; in `Safe` mode
/// tiles are refused.
#[test]
fn tiles_are_checked_without_a_navigator_and_refused_in_safe_mode() {
    let mut e = exec(NoAutonomy);
    let chunks: StdVec<Message> = tile_chunks(1, 4, 4, 1.0, |_| 0.0).into_iter().map(Message::TileChunk).collect();
    let r = exchange_from(&mut e, 0, &chunks);
    assert!(nacks(&r).is_empty());
    let r = exchange_from(&mut e, 1, &[Message::Shutdown(Shutdown)]);
    assert!(nacks(&r).is_empty());
    let chunks: StdVec<Message> = tile_chunks(2, 4, 4, 1.0, |_| 0.0).into_iter().map(Message::TileChunk).collect();
    let r = exchange_from(&mut e, 2, &chunks);
    assert_eq!(nacks(&r), [NackReason::NotAllowedInMode]);
}

// ---- protocol v8: the team mission ----

fn team_configure() -> TeamConfigure {
    TeamConfigure::example()
}

fn team_goal() -> GoalRequest {
    GoalRequest { planner: PlannerChoice::Team, position: Point3::new(40.0, 0.0, 0.0), tolerance_m: 5.0, ..goal() }
}

fn team_lend() -> TeamLend {
    team_lend_of(Box::leak(Box::<crate::plan::team::dstar_lite::DStarArena<{ crate::config::team::GLOBAL_GRID_MAX_CELLS }>>::default()).storage())
}

/// Team storage with the D* Lite storage `dstar`.
fn team_lend_of(dstar: crate::plan::team::dstar_lite::DStarStorage<'static>) -> TeamLend {
    use crate::config::protocol::TEAM_SCAN_POINTS_CAPACITY;
    TeamLend {
        dstar,
        planner: Box::leak(Box::default()),
        points: Box::leak(Box::new([crate::geom::Vec3::zeros(); TEAM_SCAN_POINTS_CAPACITY])),
        mission: Box::leak(Box::new(None)),
    }
}

fn team_orders(r: &[Message]) -> StdVec<TeamCommand> {
    r.iter().filter_map(|m| if let Message::TeamCommand(c) = m { Some(*c) } else { None }).collect()
}

/// A flat patch of the plane z = 0 around `(x, y)`, 1 m lattice, as scan chunks answering order `id`.
fn flat_scan(id: u32, robot: u8, at: Point3, hub: Point3) -> StdVec<TeamScanChunk> {
    let pts: StdVec<Point3> = (0..30 * 30).map(|i| Point3::new(at.x - 15.0 + (i % 30) as f32, at.y - 15.0 + (i / 30) as f32, 0.0)).collect();
    let parts: StdVec<&[Point3]> = pts.chunks(128).collect();
    parts
        .iter()
        .enumerate()
        .map(|(i, p)| TeamScanChunk {
            command_id: id,
            robot,
            chunk_index: i as u16,
            chunk_count: parts.len() as u16,
            grip: at,
            up: Point3::new(0.0, 0.0, 1.0),
            hub,
            points: heapless::Vec::from_slice(p).unwrap(),
        })
        .collect()
}

/// A team goal before any `TeamConfigure` is refused `NoTeam` (counted), as are team scans and reports with no
/// mission; configured but with no team storage lent, the goal is `PlannerUnavailable`.
#[test]
fn a_team_goal_without_a_team_configuration_is_refused_clearly() {
    let mut e = exec(NoAutonomy);
    let r = exchange(&mut e, &[Message::GoalRequest(team_goal())]);
    assert_eq!(nacks(&r), [NackReason::NoTeam]);
    assert!(team_orders(&r).is_empty());
    let state = TeamState { grip: [GripState::Gripping; 4], legs_m: [5.0; 4] };
    let r = exchange_from(
        &mut e,
        200,
        &[
            Message::TeamReport(TeamReport { command_id: 0, event: TeamEvent::HubAt { pos: Point3::new(0.0, 0.0, 0.0) }, state }),
            Message::TeamScanChunk(flat_scan(0, 0, Point3::new(4.0, 4.0, 0.0), Point3::new(0.0, 0.0, 0.0)).remove(0)),
            Message::TelemetryRequest(TelemetryRequest),
        ],
    );
    assert_eq!(nacks(&r), [NackReason::NoTeam, NackReason::NoTeam]);
    assert_eq!(telemetry_of(&r).frames_rejected[NackReason::NoTeam.index()], 3);
    // configured, but this flight computer lent no team storage
    let r = exchange_from(&mut e, 300, &[Message::TeamConfigure(team_configure()), Message::GoalRequest(team_goal())]);
    assert!(nacks(&r).is_empty());
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::PlannerUnavailable)));
}

/// The executive runs the team mission: a team goal after a `TeamConfigure` is accepted and the first order
/// follows; answers out of order, for another robot or another order are refused with their reasons and change
/// nothing; a complete scan steps the mission (a new order, a new id); a copy of the last chunk is answered, not
/// applied; a robot lost moves the mission on; an unanswered order is sent again unchanged.
#[test]
fn the_executive_runs_the_team_mission_and_refuses_answers_out_of_order() {
    let mut e = exec(NoAutonomy);
    assert!(e.lend_team(team_lend()).is_none());
    let r = exchange(&mut e, &[Message::TeamConfigure(team_configure()), Message::GoalRequest(team_goal())]);
    assert!(nacks(&r).is_empty(), "{r:?}");
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::Accepted)));
    let first = team_orders(&r);
    assert_eq!(first.len(), 1);
    let TeamOrder::Scan { robot } = first[0].order else { panic!("{first:?}") };
    let id = first[0].command_id;
    let hub = Point3::new(0.0, 0.0, 0.0);
    let at = team_configure().start[usize::from(robot)];
    let chunks = flat_scan(id, robot, at, hub);
    let state = TeamState { grip: [GripState::Gripping; 4], legs_m: [5.66; 4] };
    let other = (robot + 1) % 4;
    let r = exchange_from(
        &mut e,
        200,
        &[
            Message::TeamScanChunk(TeamScanChunk { command_id: id + 7, ..chunks[0].clone() }),
            Message::TeamScanChunk(TeamScanChunk { robot: other, ..chunks[0].clone() }),
            Message::TeamScanChunk(chunks[1].clone()),
            Message::TeamReport(TeamReport { command_id: id, event: TeamEvent::HubAt { pos: hub }, state }),
            Message::TeamConfigure(team_configure()),
        ],
    );
    assert_eq!(
        nacks(&r),
        [NackReason::UnknownCommand, NackReason::UnknownRobot, NackReason::OutOfOrderChunk, NackReason::UnknownCommand, NackReason::NoTeam]
    );
    assert!(team_orders(&r).is_empty());
    // the whole scan, in order: the mission plans the robot's hop and orders the next step
    let msgs: StdVec<Message> = chunks.iter().cloned().map(Message::TeamScanChunk).collect();
    let r = exchange_from(&mut e, 300, &msgs);
    assert!(nacks(&r).is_empty(), "{r:?}");
    let next = team_orders(&r);
    assert_eq!(next.len(), 1, "{r:?}");
    assert!(next[0].command_id != id);
    // the last chunk again (its Ack lost): answered, not applied, no new order
    let r = exchange_from(&mut e, 400, &[msgs[msgs.len() - 1].clone()]);
    assert!(nacks(&r).is_empty() && team_orders(&r).is_empty(), "{r:?}");
    // no answer: the pending order goes again, unchanged, after TEAM_COMMAND_RESEND_US
    e.clock_mut().0 += crate::config::exec::TEAM_COMMAND_RESEND_US;
    let r = exchange_from(&mut e, 500, &[]);
    assert_eq!(team_orders(&r), next);
    // the robot of the pending order is lost: the mission moves on to another order
    let lost_robot = match next[0].order {
        TeamOrder::Scan { robot } | TeamOrder::Hop { robot, .. } => robot,
        o => panic!("{o:?}"),
    };
    let r = exchange_from(
        &mut e,
        600,
        &[Message::TeamReport(TeamReport { command_id: next[0].command_id, event: TeamEvent::Lost { robot: lost_robot, cause: TeamLoss::TetherCut }, state })],
    );
    assert!(nacks(&r).is_empty(), "{r:?}");
    let after = team_orders(&r);
    assert_eq!(after.len(), 1);
    assert!(after[0].command_id != next[0].command_id);
    assert!(!matches!(after[0].order, TeamOrder::Scan { robot } | TeamOrder::Hop { robot, .. } if robot == lost_robot));
    assert!(e.team_mission().is_some_and(|m| m.lost()[usize::from(lost_robot)].is_some()));
}

/// Loses every robot of the running team mission (answering its pending order first): the mission ends
/// `TeamLost`; the frames from `seq`.
fn lose_the_team(e: &mut Exec<NoAutonomy>, seq: u32, first: TeamCommand) -> StdVec<Message> {
    let state = TeamState { grip: [GripState::Gripping; 4], legs_m: [5.66; 4] };
    let mut out = StdVec::new();
    let mut pending = first.command_id;
    for (k, robot) in (0..4u8).enumerate() {
        let lost = TeamReport { command_id: pending, event: TeamEvent::Lost { robot, cause: TeamLoss::GripFailure }, state };
        let r = exchange_from(e, seq + 10 * k as u32, &[Message::TeamReport(lost)]);
        if let Some(c) = team_orders(&r).last() {
            pending = c.command_id;
        }
        out.extend(r);
    }
    out
}

/// One lending serves mission after mission: once a team mission has ended, the next team goal takes its storage
/// back and starts on it (the same configuration gives the same first order), and `reclaim_team` hands the storage
/// back to the lender only while no mission runs; a grid larger than the lent D* Lite storage is `InvalidInput`
/// and keeps the storage.
#[test]
fn a_team_lending_serves_one_mission_after_another_and_comes_back() {
    let mut e = exec(NoAutonomy);
    assert!(e.lend_team(team_lend()).is_none());
    // a second lending before any mission replaces the first, which comes back (nothing is dropped)
    let small: &'static mut crate::plan::team::dstar_lite::DStarArena<4> = Box::leak(Box::default());
    assert!(e.lend_team(team_lend_of(small.storage())).is_some_and(|old| old.dstar.cells() > 4));
    assert!(e.lend_team(team_lend()).is_some_and(|old| old.dstar.cells() == 4));
    let r = exchange(&mut e, &[Message::TeamConfigure(team_configure()), Message::GoalRequest(team_goal())]);
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::Accepted)), "{r:?}");
    let first = team_orders(&r)[0];
    // running: neither a second lending nor a reclaim takes the storage away
    assert!(e.lend_team(team_lend()).is_some());
    assert!(e.reclaim_team().is_none());
    let r = lose_the_team(&mut e, 100, first);
    assert!(
        team_orders(&r).iter().any(|c| matches!(c.order, TeamOrder::Done { outcome: TeamOutcome::TeamLost, .. })),
        "{r:?}"
    );
    assert!(e.team_mission().is_some_and(|m| m.outcome().is_some()), "the ended mission stays readable");
    // a second goal on the same lending: accepted, and it starts as the first did
    let second_goal = GoalRequest { goal_id: team_goal().goal_id + 1, ..team_goal() };
    let r = exchange_from(&mut e, 200, &[Message::GoalRequest(second_goal)]);
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::Accepted)), "{r:?}");
    let again = team_orders(&r);
    assert_eq!(again.len(), 1);
    assert_eq!(again[0].order, first.order);
    assert!(e.reclaim_team().is_none());
    lose_the_team(&mut e, 300, again[0]);
    // ended: the storage comes back, and team goals wait for a lending
    let lend = e.reclaim_team().expect("the ended mission's storage");
    assert!(e.team_mission().is_none());
    let third = GoalRequest { goal_id: team_goal().goal_id + 2, ..team_goal() };
    let r = exchange_from(&mut e, 400, &[Message::GoalRequest(third)]);
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::PlannerUnavailable)), "{r:?}");
    // lent again to another executive, it runs a mission there
    let mut other = exec(NoAutonomy);
    assert!(other.lend_team(lend).is_none());
    let r = exchange(&mut other, &[Message::TeamConfigure(team_configure()), Message::GoalRequest(team_goal())]);
    assert_eq!(team_orders(&r)[0].order, first.order);
    // a D* Lite storage of 4 scenes refuses the example's larger grid and keeps the storage
    let small: &'static mut crate::plan::team::dstar_lite::DStarArena<4> = Box::leak(Box::default());
    let mut e = exec(NoAutonomy);
    assert!(e.lend_team(team_lend_of(small.storage())).is_none());
    let r = exchange(&mut e, &[Message::TeamConfigure(team_configure()), Message::GoalRequest(team_goal())]);
    assert!(r.iter().any(|m| matches!(m, Message::PlanStatus(s) if s.state == PlanState::InvalidInput)), "{r:?}");
    assert!(team_orders(&r).is_empty());
    assert!(e.reclaim_team().is_some_and(|l| l.dstar.cells() == 4));
}
