//! Byte fixtures: the examples written in `firmware/PROTOCOL.md` (derived there by hand: CRC from zlib's crc32,
//! COBS blocks counted by hand) must equal the encoder's output, and decode back.

use super::*;
use crate::config::protocol::MAX_POINTS_PER_CHUNK;

const SPEC: &str = include_str!("../../PROTOCOL.md");

/// The hex bytes on the spec line starting with `` `name`: ``.
fn spec_bytes(name: &str) -> std::vec::Vec<u8> {
    let tag = std::format!("`{name}`:");
    let line = SPEC
        .lines()
        .find(|l| l.trim_start().starts_with(&tag))
        .unwrap_or_else(|| panic!("{name} not in spec"));
    let hex = &line.trim_start()[tag.len()..];
    hex.split_whitespace()
        .map(|h| u8::from_str_radix(h.trim_matches('`'), 16).unwrap())
        .collect()
}

fn wire(seq: u32, m: &Message) -> std::vec::Vec<u8> {
    let mut out = [0u8; 2100];
    let n = encode(seq, m, &mut out).unwrap();
    out[..n].to_vec()
}

#[test]
fn spec_example_time_tick() {
    let m = Message::TimeTick(TimeTick { host_time_us: 1000 });
    assert_eq!(wire(1, &m), spec_bytes("example-time-tick-wire"));
    let mut raw = [0u8; 64];
    let n = build_raw(
        Header {
            version: 8,
            kind: 1,
            seq: 1,
        },
        &[0xE8, 0x07],
        &mut raw,
    )
    .unwrap();
    assert_eq!(&raw[..n], &spec_bytes("example-time-tick-frame")[..]);
    let (h, back) = decode_frame(&raw[..n]).unwrap();
    assert_eq!((h.seq, back), (1, m));
}

#[test]
fn spec_example_ack() {
    let m = Message::Ack(Ack { seq: 1 });
    assert_eq!(wire(0, &m), spec_bytes("example-ack-wire"));
}

#[test]
fn frame_view_accessors_never_panic_on_short_buffers() {
    for len in 0..12 {
        let b = std::vec![0xA5u8; len];
        let f = Frame::new_unchecked(&b[..]);
        let _ = (
            f.version(),
            f.kind(),
            f.seq(),
            f.body(),
            f.crc(),
            f.header(),
        );
        assert!(Frame::new_checked(&b[..]).is_err());
    }
}

fn frame_with_body(kind: MessageKind, body: &[u8]) -> std::vec::Vec<u8> {
    let mut raw = [0u8; 2100];
    let n = build_raw(
        Header {
            version: crate::config::protocol::PROTOCOL_VERSION,
            kind: kind as u8,
            seq: 3,
        },
        body,
        &mut raw,
    )
    .unwrap();
    raw[..n].to_vec()
}

#[test]
fn lying_lengths_have_their_own_reasons() {
    // SensorChunk body: scan_id 1, index 0, count 1, identity pose, then a point count.
    let mut body = std::vec![1u8, 0, 1];
    for v in [0.0f32, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0] {
        body.extend_from_slice(&v.to_le_bytes());
    }
    let mut claims_two_has_one = body.clone();
    claims_two_has_one.push(2);
    claims_two_has_one.extend_from_slice(&[0u8; 12]);
    assert_eq!(
        decode_frame(&frame_with_body(
            MessageKind::SensorChunk,
            &claims_two_has_one
        ))
        .map(|_| ()),
        Err(NackReason::BodyTooShort)
    );
    let mut claims_one_has_two = body.clone();
    claims_one_has_two.push(1);
    claims_one_has_two.extend_from_slice(&[0u8; 24]);
    assert_eq!(
        decode_frame(&frame_with_body(
            MessageKind::SensorChunk,
            &claims_one_has_two
        ))
        .map(|_| ()),
        Err(NackReason::BodyTooLong)
    );
    // A count one above the capacity, with that many points present.
    let mut over = body.clone();
    over.extend_from_slice(&[0x81, 0x01]); // varint 129
    over.extend(core::iter::repeat_n(0u8, 12 * (MAX_POINTS_PER_CHUNK + 1)));
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::SensorChunk, &over)).map(|_| ()),
        Err(NackReason::LengthOverLimit)
    );
    // A huge varint count with no points is cut short quickly (no allocation, no loop over the claim).
    let mut huge = body.clone();
    huge.extend_from_slice(&[0xFF, 0xFF, 0xFF, 0xFF, 0x0F]);
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::SensorChunk, &huge)).map(|_| ()),
        Err(NackReason::BodyTooShort)
    );
}

#[test]
fn header_errors_and_nonfinite_values() {
    let good = frame_with_body(MessageKind::TimeTick, &[0xE8, 0x07]);
    assert!(decode_frame(&good).is_ok());
    let mut flipped = good.clone();
    flipped[7] ^= 0x10;
    assert_eq!(decode_frame(&flipped).map(|_| ()), Err(NackReason::BadCrc));
    assert_eq!(
        decode_frame(&good[..9]).map(|_| ()),
        Err(NackReason::Truncated)
    );
    let mut raw = [0u8; 64];
    for version in [0u8, 1, 2, 3, 4, 5, 6, 7, 9, 0xFF] {
        let n = build_raw(
            Header {
                version,
                kind: 1,
                seq: 0,
            },
            &[0],
            &mut raw,
        )
        .unwrap();
        assert_eq!(
            decode_frame(&raw[..n]).map(|_| ()),
            Err(NackReason::WrongVersion),
            "version {version}"
        );
    }
    let n = build_raw(
        Header {
            version: crate::config::protocol::PROTOCOL_VERSION,
            kind: 0x42,
            seq: 0,
        },
        &[0],
        &mut raw,
    )
    .unwrap();
    assert_eq!(
        decode_frame(&raw[..n]).map(|_| ()),
        Err(NackReason::UnknownKind)
    );
    let mut tr = std::vec::Vec::new();
    tr.push(5u8); // time varint
    for v in [1.0f32, f32::NAN, 0.0] {
        tr.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::TetherReading, &tr)).map(|_| ()),
        Err(NackReason::NonFinite)
    );
    let mut neg = std::vec![5u8];
    for v in [-1.0f32, 1.0, 0.0] {
        neg.extend_from_slice(&v.to_le_bytes());
    }
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::TetherReading, &neg)).map(|_| ()),
        Err(NackReason::OutOfRange)
    );
}

#[test]
fn bad_enum_index_is_malformed_not_a_length_problem() {
    // GoalRequest: goal_id varint | position 12 | tolerance 4 | planner enum index | ...
    let g = Message::GoalRequest(GoalRequest {
        goal_id: 1,
        position: Point3::new(1.0, 2.0, 3.0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Team,
        max_iterations: 3,
        time_budget_ms: 0,
        allow_approximate: false,
    });
    let mut b = [0u8; 64];
    let n = g.encode_body(&mut b).unwrap();
    assert_eq!(b[17], 2, "Team is variant 2");
    b[17] = 3;
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::GoalRequest, &b[..n])).map(|_| ()),
        Err(NackReason::MalformedBody)
    );
    // Log text longer than its capacity
    let mut log = std::vec![3u8, 121];
    log.extend(core::iter::repeat_n(b'a', 121));
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::Log, &log)).map(|_| ()),
        Err(NackReason::LengthOverLimit)
    );
}

#[test]
fn periodic_telemetry_faster_than_the_limit_is_out_of_range() {
    let mut c = Configure {
        rover: RoverConfig {
            mass_kg: 1.0,
            wheel_radius_m: 0.1,
            axle_length_m: 0.5,
            boom_length_m: 0.4,
            friction_coefficient: 0.5,
        },
        tether: TetherConfig {
            root_anchor: Point3::new(0.0, 0.0, 0.0),
            max_payout_m: 10.0,
            max_tension_n: 100.0,
        },
        planner: PlannerConfig {
            rng_seed: 1,
            max_iterations: 1,
            batch_size: 1,
            goal_bias: 0.0,
        },
        telemetry: TelemetryConfig {
            period_ms: 0,
            forward_log_level: LogLevel::Off,
        },
        mission: MissionConfig::DEFAULT,
        map: None,
    };
    for (period, ok) in [
        (0, true),
        (1, false),
        (99, false),
        (100, true),
        (1000, true),
    ] {
        c.telemetry.period_ms = period;
        assert_eq!(c.validate().is_ok(), ok, "period {period} ms");
    }
}

fn sample_configure() -> Configure {
    Configure {
        rover: RoverConfig {
            mass_kg: 50.0,
            wheel_radius_m: 0.25,
            axle_length_m: 0.6,
            boom_length_m: 0.5,
            friction_coefficient: 0.8,
        },
        tether: TetherConfig {
            root_anchor: Point3::new(0.0, 0.0, 2.0),
            max_payout_m: 40.0,
            max_tension_n: 500.0,
        },
        planner: PlannerConfig {
            rng_seed: 3,
            max_iterations: 750,
            batch_size: 100,
            goal_bias: 0.0,
        },
        telemetry: TelemetryConfig {
            period_ms: 0,
            forward_log_level: LogLevel::Off,
        },
        mission: MissionConfig {
            tracking: Tracking::OpenLoop,
            replan_cross_track_m: 0.25,
            payout_tolerance_m: 0.4,
            min_margin_n: 1.5,
        },
        map: Some(MapSettings::from(crate::config::map::MapConfig::with_voxel_size(0.1))),
    }
}

fn round_trip(m: &Message) -> Message {
    let w = wire(11, m);
    let mut d = Deframer::new();
    let (n, ev) = d.push(&w);
    assert_eq!(n, w.len());
    let (h, back) = decode_frame(ev.unwrap().unwrap()).unwrap();
    assert_eq!(h.version, 8);
    assert_eq!(h.kind, m.kind() as u8);
    back
}

#[test]
fn v2_messages_round_trip() {
    let pose = Pose {
        position: Point3::new(1.5, -2.0, 0.25),
        orientation: Quat {
            x: 0.0,
            y: 0.0,
            z: 0.6,
            w: 0.8,
        },
    };
    let msgs = [
        Message::Configure(sample_configure()),
        Message::GoalRequest(GoalRequest {
            goal_id: 5,
            position: Point3::new(4.0, 1.0, -1.0),
            tolerance_m: 0.5,
            planner: PlannerChoice::Abit,
            max_iterations: 700,
            time_budget_ms: 0,
            allow_approximate: true,
        }),
        Message::MotionReport(MotionReport {
            command_id: 17,
            outcome: MotionOutcome::Slipped,
            achieved_yaw_rad: -0.1,
            achieved_distance_m: 0.9,
            pose,
        }),
        Message::GoalCancel(GoalCancel { goal_id: 5 }),
        Message::MissionStatus(MissionStatus {
            goal_id: 5,
            state: MissionState::Safe,
            reason: StopReason::TetherInconsistent,
            distance_driven_m: 3.5,
            predicted_payout_m: 6.0,
            measured_payout_m: 7.1,
            tension_n: 120.0,
            margin_n: 4.0,
            cross_track_m: 0.05,
            replans: 2,
            anchors: 3,
            motions_done: 9,
            tether_rejected: 1,
            pose_jumps: 0,
            scans_rejected: 2,
            tether_reestimates: 1,
        }),
    ];
    for m in &msgs {
        assert_eq!(&round_trip(m), m);
    }
    // every kind is listed once, and each new kind has its documented code and direction
    assert_eq!(MessageKind::from_u8(0x08), Some(MessageKind::MotionReport));
    assert_eq!(MessageKind::from_u8(0x09), Some(MessageKind::GoalCancel));
    assert_eq!(MessageKind::from_u8(0x88), Some(MessageKind::MissionStatus));
    assert_eq!(MessageKind::MotionReport.direction(), Direction::HostToFlight);
    assert_eq!(MessageKind::MissionStatus.direction(), Direction::FlightToHost);
    // v7's tile chunk is the next host kind; the one after it is none
    assert_eq!(MessageKind::from_u8(0x0A), Some(MessageKind::TileChunk));
    assert_eq!(MessageKind::TileChunk.direction(), Direction::HostToFlight);
    // v8's team kinds follow; the ones after them are none
    assert_eq!(MessageKind::from_u8(0x0B), Some(MessageKind::TeamConfigure));
    assert_eq!(MessageKind::from_u8(0x0D), Some(MessageKind::TeamReport));
    assert_eq!(MessageKind::from_u8(0x89), Some(MessageKind::TeamCommand));
    assert_eq!(MessageKind::TeamCommand.direction(), Direction::FlightToHost);
    assert_eq!(MessageKind::TeamScanChunk.direction(), Direction::HostToFlight);
    assert_eq!(MessageKind::from_u8(0x0E), None);
    assert_eq!(MessageKind::from_u8(0x8A), None);
}

#[test]
fn spec_examples_v2() {
    assert_eq!(
        wire(2, &Message::GoalCancel(GoalCancel { goal_id: 7 })),
        spec_bytes("example-goal-cancel-wire")
    );
    let report = Message::MotionReport(MotionReport {
        command_id: 3,
        outcome: MotionOutcome::Completed,
        achieved_yaw_rad: 0.0,
        achieved_distance_m: 1.0,
        pose: Pose {
            position: Point3::new(1.0, 0.0, 0.0),
            orientation: Quat::IDENTITY,
        },
    });
    let frame = spec_bytes("example-motion-report-frame");
    let (h, back) = decode_frame(&frame).unwrap();
    assert_eq!((h.seq, &back), (3, &report));
    // the encoder's wire bytes un-stuff to the same frame
    let w = wire(3, &report);
    let mut d = Deframer::new();
    let (_, ev) = d.push(&w);
    assert_eq!(ev.unwrap().unwrap(), &frame[..]);
    // real version-1 to -7 frames (the earlier documents' example) are a wrong version, not a CRC or kind
    // error
    for old in [
        "example-v1-time-tick-frame",
        "example-v2-time-tick-frame",
        "example-v3-time-tick-frame",
        "example-v4-time-tick-frame",
        "example-v5-time-tick-frame",
        "example-v6-time-tick-frame",
        "example-v7-time-tick-frame",
    ] {
        assert_eq!(decode_frame(&spec_bytes(old)).map(|_| ()), Err(NackReason::WrongVersion));
    }
}

/// v6: a `Stop` names the motion it stops.
#[test]
fn spec_example_v6_stop() {
    let stop = Message::DriveCommand(DriveCommand { command_id: 5, motion: Motion::Stop { motion_id: 4 } });
    assert_eq!(wire(4, &stop), spec_bytes("example-stop-wire"));
    assert_eq!(round_trip(&stop), stop);
}

/// v7: a terrain-tile chunk, byte for byte as the spec derives it, and its bad values' reasons.
#[test]
fn spec_example_v7_tile_chunk() {
    let mut heights = heapless::Vec::new();
    heights.extend_from_slice(&[0.5, 1.5]).unwrap();
    let tile = TileChunk {
        tile_id: 1,
        chunk_index: 0,
        chunk_count: 1,
        origin_x_m: -2.0,
        origin_y_m: 3.0,
        resolution_m: 0.5,
        rows: 1,
        cols: 2,
        heights,
    };
    let m = Message::TileChunk(tile.clone());
    assert_eq!(wire(5, &m), spec_bytes("example-tile-chunk-wire"));
    assert_eq!(round_trip(&m), m);
    let bad = |f: &dyn Fn(&mut TileChunk)| {
        let mut t = tile.clone();
        f(&mut t);
        t.validate()
    };
    assert_eq!(bad(&|t| t.heights[1] = f32::NAN), Err(Invalid::NonFinite));
    assert_eq!(bad(&|t| t.origin_y_m = f32::INFINITY), Err(Invalid::NonFinite));
    assert_eq!(bad(&|t| t.resolution_m = f32::NAN), Err(Invalid::NonFinite));
    assert_eq!(bad(&|t| t.resolution_m = 5.5), Err(Invalid::TileResolution));
    assert_eq!(bad(&|t| t.resolution_m = 0.01), Err(Invalid::TileResolution));
    assert_eq!(bad(&|t| t.rows = 129), Err(Invalid::TileTooLarge));
    assert_eq!(bad(&|t| t.cols = 0), Err(Invalid::OutOfRange));
    assert_eq!(NackReason::from(Invalid::TileTooLarge), NackReason::TileTooLarge);
    // a heights length prefix over the capacity (257 heights, all sent) is its own reason
    let mut raw = [0u8; 2100];
    let mut body = std::vec![1u8, 0, 1, 0, 0, 0, 0xC0, 0, 0, 0x40, 0x40, 0, 0, 0, 0x3F, 1, 2, 0x81, 0x02];
    body.extend(core::iter::repeat_n(0u8, 257 * 4));
    let n = build_raw(Header { version: 8, kind: 0x0A, seq: 0 }, &body, &mut raw).unwrap();
    assert_eq!(decode_frame(&raw[..n]).map(|_| ()), Err(NackReason::LengthOverLimit));
}

#[test]
fn v2_bad_values_have_their_reasons() {
    let mut c = sample_configure();
    assert!(c.validate().is_ok());
    for (field, v, want) in [
        (0, 0.0, Invalid::OutOfRange),
        (0, -0.1, Invalid::OutOfRange),
        (0, f32::NAN, Invalid::NonFinite),
        (1, 0.0, Invalid::OutOfRange),
        (1, f32::INFINITY, Invalid::NonFinite),
        (2, -1.0, Invalid::OutOfRange),
        (2, f32::NAN, Invalid::NonFinite),
    ] {
        let mut bad = c;
        match field {
            0 => bad.mission.replan_cross_track_m = v,
            1 => bad.mission.payout_tolerance_m = v,
            _ => bad.mission.min_margin_n = v,
        }
        assert_eq!(bad.validate(), Err(want), "field {field} = {v}");
    }
    c.mission.min_margin_n = 0.0;
    assert!(c.validate().is_ok(), "a zero minimum margin is allowed");
    // over the wire: a Configure with a NaN tolerance is NonFinite
    let mut nan = sample_configure();
    nan.mission.payout_tolerance_m = f32::NAN;
    let mut b = [0u8; 256];
    let n = Message::Configure(nan).encode_body(&mut b).unwrap();
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::Configure, &b[..n])).map(|_| ()),
        Err(NackReason::NonFinite)
    );
    // v3 map settings: each out-of-range or non-finite field is refused with its reason
    let good = sample_configure();
    let with_map = |f: &dyn Fn(&mut MapSettings)| {
        let mut c = good;
        if let Some(m) = c.map.as_mut() {
            f(m);
        }
        c.validate()
    };
    assert_eq!(with_map(&|_| ()), Ok(()));
    assert_eq!(with_map(&|m| m.voxel_size_m = 0.0), Err(Invalid::OutOfRange));
    assert_eq!(with_map(&|m| m.truncation_m = f32::NAN), Err(Invalid::NonFinite));
    assert_eq!(with_map(&|m| m.truncation_m = 0.01), Err(Invalid::OutOfRange), "truncation below a voxel");
    assert_eq!(with_map(&|m| m.max_ray_voxels = 5000), Err(Invalid::OutOfRange), "unbounded work per point");
    assert_eq!(with_map(&|m| m.esdf_max_sweeps = 0), Err(Invalid::OutOfRange));
    assert_eq!(with_map(&|m| m.esdf_max_distance_m = f32::INFINITY), Err(Invalid::NonFinite));
    // a v2 Configure body (no map byte) under a v3 header is cut short
    let mut v2 = sample_configure();
    v2.map = None;
    let n = Message::Configure(v2).encode_body(&mut b).unwrap();
    assert_eq!(b[n - 1], 0, "None is one zero byte, the body's last");
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::Configure, &b[..n - 1])).map(|_| ()),
        Err(NackReason::BodyTooShort)
    );
    // a motion report with a non-unit quaternion, a NaN distance, and an unknown outcome index
    let mut r = MotionReport {
        command_id: 1,
        outcome: MotionOutcome::Completed,
        achieved_yaw_rad: 0.0,
        achieved_distance_m: 0.5,
        pose: Pose::IDENTITY,
    };
    r.pose.orientation.w = 0.9;
    let n = Message::MotionReport(r).encode_body(&mut b).unwrap();
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::MotionReport, &b[..n])).map(|_| ()),
        Err(NackReason::NotUnitQuaternion)
    );
    r.pose = Pose::IDENTITY;
    r.achieved_distance_m = f32::NAN;
    let n = Message::MotionReport(r).encode_body(&mut b).unwrap();
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::MotionReport, &b[..n])).map(|_| ()),
        Err(NackReason::NonFinite)
    );
    r.achieved_distance_m = 0.5;
    let n = Message::MotionReport(r).encode_body(&mut b).unwrap();
    b[1] = 4; // MotionOutcome has 4 variants
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::MotionReport, &b[..n])).map(|_| ()),
        Err(NackReason::MalformedBody)
    );
    // a GoalRequest whose allow_approximate byte is not a bool
    let g = GoalRequest {
        goal_id: 1,
        position: Point3::new(1.0, 2.0, 3.0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Abit,
        max_iterations: 3,
        time_budget_ms: 0,
        allow_approximate: true,
    };
    let n = Message::GoalRequest(g).encode_body(&mut b).unwrap();
    assert_eq!(b[n - 1], 1);
    b[n - 1] = 2;
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::GoalRequest, &b[..n])).map(|_| ()),
        Err(NackReason::MalformedBody)
    );
    // a v1 GoalRequest body (no allow_approximate byte) under a v3 header is cut short
    assert_eq!(
        decode_frame(&frame_with_body(MessageKind::GoalRequest, &b[..n - 1])).map(|_| ()),
        Err(NackReason::BodyTooShort)
    );
}

/// v8: a team order, byte for byte as the spec derives it.
#[test]
fn spec_example_v8_team_command() {
    let m = Message::TeamCommand(TeamCommand { command_id: 6, goal_id: 1, order: TeamOrder::Scan { robot: 2 } });
    assert_eq!(wire(6, &m), spec_bytes("example-team-scan-command-wire"));
    assert_eq!(round_trip(&m), m);
}

fn sample_team_configure() -> TeamConfigure {
    let mut c = TeamConfigure::example();
    c.blocked.push((0, 2)).unwrap();
    c
}

/// v8: every team message round-trips, and each bad value has its reason (NaN, robot out of range, axes, counts).
#[test]
fn v8_team_messages_round_trip_and_bad_values_have_their_reasons() {
    let c = sample_team_configure();
    let state = TeamState { grip: [GripState::Gripping; 4], legs_m: [1.5; 4] };
    let report = TeamReport { command_id: 3, event: TeamEvent::Landed { robot: 1, pos: Point3::new(1.0, 2.0, 3.0) }, state };
    let mut points = heapless::Vec::new();
    points.extend_from_slice(&[Point3::new(0.0, 0.0, 1.0); 128]).unwrap();
    let scan = TeamScanChunk {
        command_id: 2,
        robot: 3,
        chunk_index: 31,
        chunk_count: 32,
        grip: Point3::new(1.0, 1.0, 0.0),
        up: Point3::new(0.0, 0.0, 1.0),
        hub: Point3::new(0.0, 0.0, 0.0),
        points,
    };
    let hop = TeamCommand {
        command_id: 4,
        goal_id: 1,
        order: TeamOrder::Hop { robot: 0, target: Point3::new(3.0, 0.0, 0.0), scene_normal: Point3::new(0.0, 0.0, 1.0) },
    };
    let done = TeamCommand {
        command_id: 5,
        goal_id: 1,
        order: TeamOrder::Done { outcome: TeamOutcome::GoalReached, rounds: 12, hops: 40, walls: 1 },
    };
    for m in [
        Message::TeamConfigure(c.clone()),
        Message::TeamReport(report),
        Message::TeamScanChunk(scan.clone()),
        Message::TeamCommand(hop),
        Message::TeamCommand(done),
    ] {
        assert_eq!(round_trip(&m), m);
    }
    let bad_c = |f: &dyn Fn(&mut TeamConfigure)| {
        let mut x = c.clone();
        f(&mut x);
        x.validate()
    };
    assert_eq!(bad_c(&|x| x.start[2].y = f32::NAN), Err(Invalid::NonFinite));
    assert_eq!(bad_c(&|x| x.grid.cell_m = 0.0), Err(Invalid::OutOfRange));
    assert_eq!(bad_c(&|x| x.grid.u = Point3::new(2.0, 0.0, 0.0)), Err(Invalid::OutOfRange));
    assert_eq!(bad_c(&|x| x.grid.v = Point3::new(1.0, 0.0, 0.0)), Err(Invalid::OutOfRange));
    assert_eq!(bad_c(&|x| x.grid.width = 65 * 64), Err(Invalid::OutOfRange));
    assert_eq!(bad_c(&|x| x.blocked[0] = (4, 0)), Err(Invalid::OutOfRange));
    assert_eq!(bad_c(&|x| x.planner.h_max_m = f32::INFINITY), Err(Invalid::NonFinite));
    assert_eq!(bad_c(&|x| x.mission.max_rounds = 0), Err(Invalid::OutOfRange));
    let mut r = report;
    r.event = TeamEvent::Lost { robot: 4, cause: TeamLoss::TetherCut };
    assert_eq!(r.validate(), Err(Invalid::UnknownRobot));
    r.event = TeamEvent::HubAt { pos: Point3::new(f32::NAN, 0.0, 0.0) };
    assert_eq!(r.validate(), Err(Invalid::NonFinite));
    r.event = TeamEvent::HubAt { pos: Point3::new(0.0, 0.0, 0.0) };
    r.state.legs_m[3] = -1.0;
    assert_eq!(r.validate(), Err(Invalid::OutOfRange));
    let bad_s = |f: &dyn Fn(&mut TeamScanChunk)| {
        let mut x = scan.clone();
        f(&mut x);
        x.validate()
    };
    assert_eq!(bad_s(&|x| x.robot = 4), Err(Invalid::UnknownRobot));
    assert_eq!(bad_s(&|x| x.points[7].z = f32::NAN), Err(Invalid::NonFinite));
    assert_eq!(bad_s(&|x| x.up = Point3::new(0.0, 0.0, 0.5)), Err(Invalid::OutOfRange));
    assert_eq!(bad_s(&|x| x.chunk_count = 33), Err(Invalid::TooManyChunks));
    assert_eq!(bad_s(&|x| x.chunk_index = 32), Err(Invalid::ChunkIndexOutOfRange));
    assert_eq!(NackReason::from(Invalid::UnknownRobot), NackReason::UnknownRobot);
    // a points length prefix over the capacity (129 points) is its own reason
    let mut raw = [0u8; 2100];
    let mut body = std::vec![2u8, 3, 31, 32];
    body.extend(core::iter::repeat_n(0u8, 36));
    body.extend([0x81, 0x01]);
    body.extend(core::iter::repeat_n(0u8, 129 * 12));
    let n = build_raw(Header { version: 8, kind: 0x0C, seq: 0 }, &body, &mut raw).unwrap();
    assert_eq!(decode_frame(&raw[..n]).map(|_| ()), Err(NackReason::LengthOverLimit));
}
