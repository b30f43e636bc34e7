//! Protocol round trips and robustness: every message kind through encode -> deframe -> decode, and 100,000+
//! random byte strings into the deframer and decoder without a panic.

use firmware::config::protocol::{
    MAX_ENCODED_FRAME_LEN, MAX_POINTS_PER_CHUNK, MAX_WAYPOINTS_PER_PLAN_FRAME, PROTOCOL_VERSION,
};
use firmware::protocol::*;
use proptest::prelude::*;

fn pose(x: f32) -> Pose {
    // 90 degrees about z: (0, 0, sin 45, cos 45)
    Pose {
        position: Point3::new(x, -2.5, 0.125),
        orientation: Quat {
            x: 0.0,
            y: 0.0,
            z: 0.707_106_77,
            w: 0.707_106_77,
        },
    }
}

/// One message of every kind, with non-default values in every field and full-size variable parts.
fn one_of_every_kind() -> Vec<Message> {
    let mut points = heapless::Vec::new();
    for i in 0..MAX_POINTS_PER_CHUNK {
        points
            .push(Point3::new(i as f32 * 0.5, -(i as f32), 1e-3))
            .unwrap();
    }
    let mut waypoints = heapless::Vec::new();
    for i in 0..MAX_WAYPOINTS_PER_PLAN_FRAME {
        let mut anchors = heapless::Vec::new();
        for k in 0..=(i % 8) {
            anchors.push(Point3::new(k as f32, 2.0, 3.0)).unwrap();
        }
        waypoints
            .push(Waypoint {
                pose: pose(i as f32),
                anchors,
                stability_margin: 0.25 * i as f32,
            })
            .unwrap();
    }
    let mut rejected = [0u32; NACK_REASON_COUNT];
    for (i, r) in rejected.iter_mut().enumerate() {
        *r = (i * 1000 + 7) as u32;
    }
    vec![
        Message::TimeTick(TimeTick {
            host_time_us: u64::MAX - 1,
        }),
        Message::SensorChunk(SensorChunk {
            scan_id: 70_000,
            chunk_index: 3,
            chunk_count: 64,
            sensor_pose: pose(1.0),
            points,
        }),
        Message::TetherReading(TetherReading {
            time_us: 12_345_678,
            payout_m: 12.5,
            tension_n: 310.0,
            boom_angle_rad: -0.4,
        }),
        Message::GoalRequest(GoalRequest {
            goal_id: 4,
            position: Point3::new(8.0, 1.0, -4.0),
            tolerance_m: 0.3,
            planner: PlannerChoice::Homotopy,
            max_iterations: 750,
            time_budget_ms: 2000,
            allow_approximate: false,
        }),
        Message::Configure(Configure {
            rover: RoverConfig {
                mass_kg: 45.0,
                wheel_radius_m: 0.35,
                axle_length_m: 0.9,
                boom_length_m: 0.6,
                friction_coefficient: 0.7,
            },
            tether: TetherConfig {
                root_anchor: Point3::new(-4.9, 0.0, 6.0),
                max_payout_m: 100.0,
                max_tension_n: 800.0,
            },
            planner: PlannerConfig {
                rng_seed: 0xDEAD_BEEF_0123_4567,
                max_iterations: 750,
                batch_size: 100,
                goal_bias: 0.05,
            },
            telemetry: TelemetryConfig {
                period_ms: 250,
                forward_log_level: LogLevel::Debug,
            },
            mission: MissionConfig::DEFAULT,
            map: Some(MapSettings::from(firmware::config::map::MapConfig::DEFAULT)),
        }),
        Message::Shutdown(Shutdown),
        Message::TelemetryRequest(TelemetryRequest),
        Message::Ack(Ack { seq: 0xFFFF_FFFF }),
        Message::Nack(Nack {
            seq: 17,
            reason: NackReason::PoseMismatch,
        }),
        Message::PlanStatus(PlanStatus {
            goal_id: 4,
            state: PlanState::ApproximateSolution,
            iterations: 188,
            best_cost: Some(12.75),
        }),
        Message::Plan(Plan {
            goal_id: 4,
            part: 1,
            parts: 2,
            waypoints,
        }),
        Message::DriveCommand(DriveCommand {
            command_id: 9,
            motion: Motion::Turn { yaw_rad: -1.5 },
        }),
        Message::Telemetry(Telemetry {
            time_us: 99,
            mode: Mode::Driving,
            configured: true,
            frames_accepted: 1,
            frames_rejected: rejected,
            frames_sent: 2,
            bytes_received: 3,
            bytes_sent: 4,
            steps: 5,
            steps_rx_budget_exhausted: 6,
            steps_frame_budget_exhausted: 7,
            scans_completed: 8,
            scans_abandoned: 9,
            scan_in_progress: 10,
            scan_chunks_received: 11,
            tether_readings: 12,
            goals_received: 13,
            motion_reports: 33,
            motion_report_timeouts: 34,
            goal_cancels: 35,
            plan_state: PlanState::Searching,
            log_dropped: 14,
            tx_dropped: 15,
            device_errors: 16,
            illegal_transitions: 17,
            high_water: HighWater {
                tx_queue: 18,
                rx_staging: 19,
                frame_len: 20,
                scan_points: 21,
                log_queue: 22,
                frames_per_step: 23,
                rx_bytes_per_step: 24,
            },
            map: MapStatus {
                blocks_used: 25,
                blocks_capacity: 26,
                scans_integrated: 27,
                points_integrated: 28,
                points_rejected: 29,
                voxels_dropped: 30,
                pool_errors: 31,
                esdf_budget_exhausted: 32,
                tiles_loaded: 45,
                tile_id: 46,
                tiles_abandoned: 47,
            },
            seq_gaps: 36,
            seq_late: 37,
            seq_resyncs: 38,
            cycle: CycleStats { budget_us: 39, max_step_us: 40, period_max_step_us: 41, slips: 42 },
            requests_repeated: 43,
            drive_resends: 44,
        }),
        Message::Log(Log {
            level: LogLevel::Warn,
            text: heapless::String::try_from("scan 3 abandoned: ünïcode ok").unwrap(),
        }),
        Message::MotionReport(MotionReport {
            command_id: 9,
            outcome: MotionOutcome::Stalled,
            achieved_yaw_rad: -1.2,
            achieved_distance_m: 0.0,
            pose: Pose::IDENTITY,
        }),
        Message::GoalCancel(GoalCancel { goal_id: 4 }),
        Message::TileChunk(TileChunk {
            tile_id: 3,
            chunk_index: 63,
            chunk_count: 64,
            origin_x_m: -12.5,
            origin_y_m: 40.0,
            resolution_m: 0.36,
            rows: 128,
            cols: 128,
            // a full chunk: the largest frame of the kind
            heights: (0..256).map(|i| i as f32 * 0.25 - 7.0).collect(),
        }),
        Message::MissionStatus(MissionStatus {
            goal_id: 4,
            state: MissionState::Driving,
            reason: StopReason::None,
            distance_driven_m: 1.0,
            predicted_payout_m: 2.0,
            measured_payout_m: 2.1,
            tension_n: 30.0,
            margin_n: 5.0,
            cross_track_m: 0.1,
            replans: 1,
            anchors: 2,
            motions_done: 3,
            tether_rejected: 4,
            pose_jumps: 5,
            scans_rejected: 6,
            tether_reestimates: 7,
        }),
        Message::TeamConfigure(TeamConfigure {
            grid: TeamGrid {
                origin: Point3::new(-12.5, 40.0, 3.0),
                u: Point3::new(0.6, 0.8, 0.0),
                v: Point3::new(-0.8, 0.6, 0.0),
                cell_m: 30.0,
                width: 64,
                height: 64,
            },
            start: [Point3::new(1.0, 2.0, 3.0), Point3::new(-1.0, 2.0, 3.0), Point3::new(1.0, -2.0, 3.0), Point3::new(-1.0, -2.0, 3.0)],
            planner: firmware::config::team::TeamParams::DEFAULT.into(),
            mission: firmware::config::team::MissionParams::DEFAULT.into(),
            // the most blocked scenes one configuration holds
            blocked: (0..32).map(|i| (i, 63 - i)).collect(),
        }),
        Message::TeamScanChunk(TeamScanChunk {
            command_id: 70_000,
            robot: 3,
            chunk_index: 31,
            chunk_count: 32,
            grip: Point3::new(1.0, 2.0, 3.0),
            up: Point3::new(0.0, 0.6, 0.8),
            hub: Point3::new(0.5, 0.5, 4.0),
            // a full chunk: the largest frame of the kind
            points: (0..MAX_POINTS_PER_CHUNK).map(|i| Point3::new(i as f32, -(i as f32), 0.5)).collect(),
        }),
        Message::TeamReport(TeamReport {
            command_id: 70_001,
            event: TeamEvent::Lost { robot: 2, cause: TeamLoss::GripFailure },
            state: TeamState { grip: [GripState::Gripping, GripState::Released, GripState::Lost, GripState::Gripping], legs_m: [3.0, 4.5, 0.0, 14.9] },
        }),
        Message::TeamCommand(TeamCommand {
            command_id: 70_002,
            goal_id: 4,
            order: TeamOrder::Hop { robot: 1, target: Point3::new(9.5, -3.0, 1.25), scene_normal: Point3::new(0.0, 0.0, 1.0) },
        }),
    ]
}

fn deframe_all(wire: &[u8]) -> Vec<Result<Vec<u8>, DeframeError>> {
    let mut d = Deframer::new();
    let mut out = Vec::new();
    let mut rest = wire;
    while !rest.is_empty() {
        let (n, ev) = d.push(rest);
        if let Some(ev) = ev {
            out.push(ev.map(|f| f.to_vec()));
        }
        rest = &rest[n..];
    }
    out
}

#[test]
fn every_kind_round_trips_through_frame_and_deframe() {
    let msgs = one_of_every_kind();
    let mut kinds: Vec<MessageKind> = msgs.iter().map(Message::kind).collect();
    kinds.sort();
    assert_eq!(
        kinds,
        MessageKind::ALL.to_vec(),
        "the sample set covers every kind exactly once"
    );
    let mut wire = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
        let n = encode(1000 + i as u32, m, &mut buf).unwrap();
        assert!(
            n <= MAX_ENCODED_FRAME_LEN,
            "{:?} frame is {n} bytes",
            m.kind()
        );
        assert_eq!(buf[n - 1], 0, "delimiter");
        assert!(!buf[..n - 1].contains(&0), "COBS removed every zero");
        wire.extend_from_slice(&buf[..n]);
    }
    // one stream, split at an awkward place, must give back the same messages in order
    let frames = deframe_all(&wire);
    assert_eq!(frames.len(), msgs.len());
    for (i, (f, m)) in frames.iter().zip(&msgs).enumerate() {
        let (h, back) = decode_frame(f.as_ref().unwrap()).unwrap();
        assert_eq!(h.version, PROTOCOL_VERSION);
        assert_eq!(h.kind, m.kind() as u8);
        assert_eq!(h.seq, 1000 + i as u32);
        assert_eq!(&back, m);
    }
}

#[test]
fn kind_codes_are_exactly_the_documented_ones() {
    let documented = [
        0x01u8, 0x02, 0x03, 0x04, 0x05, 0x06, 0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C, 0x0D, 0x81, 0x82, 0x83,
        0x84, 0x85, 0x86, 0x87, 0x88, 0x89,
    ];
    for b in 0..=255u8 {
        assert_eq!(
            MessageKind::from_u8(b).is_some(),
            documented.contains(&b),
            "kind byte {b:#04x}"
        );
    }
}

fn check_bytes(bytes: &[u8]) {
    let mut d = Deframer::new();
    let mut rest = bytes;
    // bounded: each push consumes at least one byte unless the input is empty
    while !rest.is_empty() {
        let before = rest.len();
        let (n, ev) = d.push(rest);
        assert!(n >= 1 && n <= before);
        if let Some(Ok(frame)) = ev {
            if let Ok((h, m)) = decode_frame(frame) {
                // law: whatever decodes re-encodes to something that decodes to the same message
                let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
                let n2 = encode(h.seq, &m, &mut buf).unwrap();
                let again = deframe_all(&buf[..n2]);
                let (_, m2) = decode_frame(again[0].as_ref().unwrap()).unwrap();
                assert_eq!(m2, m);
            }
        }
        assert!(d.needs() >= 1);
        rest = &rest[n..];
    }
}

fn byte_strings() -> impl Strategy<Value = Vec<u8>> {
    // zeros are frequent so delimiters split the input often; sizes reach past the frame limit
    let byte = prop_oneof![3 => Just(0u8), 10 => any::<u8>(), 1 => Just(1u8), 1 => Just(0xFFu8)];
    prop_oneof![
        20 => proptest::collection::vec(byte.clone(), 0..64),
        4 => proptest::collection::vec(byte.clone(), 64..600),
        1 => proptest::collection::vec(any::<u8>(), 2000..2600),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 100_000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    #[cfg_attr(miri, ignore)]
    fn random_bytes_never_panic_the_deframer_or_decoder(bytes in byte_strings()) {
        check_bytes(&bytes);
    }
}

fn mutated_frames() -> impl Strategy<Value = Vec<u8>> {
    let msgs = one_of_every_kind();
    (
        0..msgs.len(),
        proptest::collection::vec((any::<usize>(), any::<u8>()), 1..4),
        any::<bool>(),
    )
        .prop_map(move |(which, edits, whole_frame)| {
            let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
            let n = encode(1, &msgs[which], &mut buf).unwrap();
            if whole_frame {
                // edit the decoded frame and fix nothing: CRC catches it (or the edit was a no-op)
                let mut f = deframe_all(&buf[..n]).remove(0).unwrap();
                for (at, v) in edits {
                    let i = at % f.len();
                    f[i] = v;
                }
                let mut out = vec![0u8; MAX_ENCODED_FRAME_LEN + 8];
                let m = stuff(&f, &mut out).unwrap();
                out.truncate(m);
                out
            } else {
                let mut w = buf[..n].to_vec();
                for (at, v) in edits {
                    let i = at % w.len();
                    w[i] = v;
                }
                w
            }
        })
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 20_000, failure_persistence: None, ..ProptestConfig::default() })]

    #[test]
    #[cfg_attr(miri, ignore)]
    fn mutated_valid_frames_never_panic(bytes in mutated_frames()) {
        check_bytes(&bytes);
    }

    #[test]
    #[cfg_attr(miri, ignore)]
    fn deframing_does_not_depend_on_the_split(bytes in byte_strings(), split in any::<usize>()) {
        let whole = deframe_all(&bytes);
        let at = if bytes.is_empty() { 0 } else { split % bytes.len() };
        let mut d = Deframer::new();
        let mut got = Vec::new();
        for part in [&bytes[..at], &bytes[at..]] {
            let mut rest = part;
            while !rest.is_empty() {
                let (n, ev) = d.push(rest);
                if let Some(ev) = ev {
                    got.push(ev.map(|f| f.to_vec()));
                }
                rest = &rest[n..];
            }
        }
        prop_assert_eq!(got, whole);
    }
}
