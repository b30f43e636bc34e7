//! Built-in scenarios. For now one: `protocol`, a scripted conversation that exercises every host -> flight
//! message kind (configure, time ticks, tether readings, a chunked synthetic range scan, telemetry requests, a goal
//! request, one deliberately damaged frame, shutdown) and checks every reply. Worlds and planners replace the
//! synthetic data in later scenarios.

use std::collections::BTreeMap;

use firmware::config::protocol::MAX_POINTS_PER_CHUNK;
use firmware::protocol::*;
use rand_core::Rng;

use crate::link::FlightLink;
use crate::session::{HostSession, SessionError};

/// Names of the built-in scenarios.
pub const SCENARIOS: &[&str] = &["protocol"];

/// What a scenario run saw.
#[derive(Debug, Clone, Default)]
pub struct ScenarioReport {
    /// Host frames sent.
    pub frames_sent: u32,
    /// Replies received, by kind name.
    pub received: BTreeMap<String, u32>,
    /// Nacks received, with reason.
    pub nacks: Vec<(u32, NackReason)>,
    /// The final telemetry.
    pub final_telemetry: Option<Telemetry>,
    /// Final state of the goal.
    pub plan_state: Option<PlanState>,
    /// Expectations that failed (empty = pass).
    pub failures: Vec<String>,
    /// Link time at the end, microseconds.
    pub end_us: u64,
}

impl ScenarioReport {
    /// True when every expectation held.
    pub fn passed(&self) -> bool {
        self.failures.is_empty()
    }
}

impl core::fmt::Display for ScenarioReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        writeln!(f, "frames sent: {}", self.frames_sent)?;
        let recv: Vec<String> = self
            .received
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect();
        writeln!(f, "frames received: {}", recv.join(", "))?;
        for (seq, r) in &self.nacks {
            writeln!(f, "nack: seq {seq} {r:?}")?;
        }
        if let Some(s) = self.plan_state {
            writeln!(f, "plan state: {s:?}")?;
        }
        if let Some(t) = &self.final_telemetry {
            let rejected: u32 = t.frames_rejected.iter().sum();
            writeln!(
                f,
                "final telemetry: mode {:?}, accepted {}, rejected {}, scans {}, map: {} points in {} of {} blocks, \
                 tether readings {}, steps {}, tx high water {} B, largest frame {} B",
                t.mode,
                t.frames_accepted,
                rejected,
                t.scans_completed,
                t.map.points_integrated,
                t.map.blocks_used,
                t.map.blocks_capacity,
                t.tether_readings,
                t.steps,
                t.high_water.tx_queue,
                t.high_water.frame_len
            )?;
        }
        writeln!(f, "link time: {:.3} s", self.end_us as f64 / 1e6)?;
        if self.passed() {
            write!(f, "result: PASS")
        } else {
            write!(f, "result: FAIL\n  {}", self.failures.join("\n  "))
        }
    }
}

/// The configuration the scenarios send.
pub fn default_configure(seed: u64) -> Configure {
    Configure {
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
            rng_seed: seed,
            max_iterations: 750,
            batch_size: 100,
            goal_bias: 0.05,
        },
        telemetry: TelemetryConfig {
            period_ms: 500,
            forward_log_level: LogLevel::Info,
        },
        mission: MissionConfig::DEFAULT,
        map: None,
    }
}

/// A synthetic scan: `n` returns of a sensor 1 m above flat ground, looking down-forward, with seeded range noise.
/// Split into chunks of `MAX_POINTS_PER_CHUNK`.
pub fn synthetic_scan(scan_id: u32, n: usize, rng: &mut impl Rng) -> Vec<SensorChunk> {
    let pose = Pose {
        position: Point3::new(0.0, 0.0, 1.0),
        // 30 degrees pitch down about y: q = (0, sin 15deg, 0, cos 15deg)
        orientation: Quat {
            x: 0.0,
            y: 0.258_819_04,
            z: 0.0,
            w: 0.965_925_8,
        },
    };
    let mut points = Vec::with_capacity(n);
    for i in 0..n {
        let az = (i as f32 / n as f32 - 0.5) * 1.5;
        let noise = (rng.next_u32() as f32 / u32::MAX as f32 - 0.5) * 0.02;
        let r = 2.0 + noise;
        points.push(Point3::new(r * az.cos(), r * az.sin(), -0.2 * r));
    }
    let chunks: Vec<&[Point3]> = points.chunks(MAX_POINTS_PER_CHUNK).collect();
    let count = chunks.len() as u16;
    chunks
        .iter()
        .enumerate()
        .map(|(i, c)| SensorChunk {
            scan_id,
            chunk_index: i as u16,
            chunk_count: count,
            sensor_pose: pose,
            points: heapless::Vec::from_slice(c).unwrap_or_default(),
        })
        .collect()
}

fn expect(rep: &mut ScenarioReport, ok: bool, what: &str) {
    if !ok {
        rep.failures.push(what.to_string());
    }
}

fn acked(replies: &[Message], seq: u32) -> bool {
    replies.iter().any(|m| *m == Message::Ack(Ack { seq }))
}

fn kind_name(m: &Message) -> String {
    format!("{:?}", m.kind())
}

/// Runs the `protocol` scenario over `link`.
pub fn run_protocol(link: impl FlightLink, seed: u64) -> Result<ScenarioReport, SessionError> {
    let mut s = HostSession::new(link);
    let mut rep = ScenarioReport::default();
    let mut rng = rand_pcg::Pcg64Mcg::new(u128::from(seed) | 1);
    let boot = s.recv()?;
    expect(
        &mut rep,
        matches!(boot.first(), Some(Message::Telemetry(_))),
        "boot telemetry first",
    );

    let cfg = default_configure(seed);
    let seq = s.send(&Message::Configure(cfg))?;
    let r = s.recv()?;
    expect(&mut rep, acked(&r, seq), "configure acked");

    for k in 0..5u64 {
        let t = s.link().now_us();
        let seq = s.send(&Message::TimeTick(TimeTick { host_time_us: t }))?;
        let r = s.recv()?;
        expect(&mut rep, acked(&r, seq), "time tick acked");
        let reading = TetherReading {
            time_us: t,
            payout_m: 3.0 + 0.1 * k as f32,
            tension_n: 120.0 + (rng.next_u32() % 100) as f32 * 0.1,
            boom_angle_rad: 0.3,
        };
        let seq = s.send(&Message::TetherReading(reading))?;
        let r = s.recv()?;
        expect(&mut rep, acked(&r, seq), "tether reading acked");
    }

    let chunks = synthetic_scan(1, 1000, &mut rng);
    let mut seqs = Vec::new();
    for c in &chunks {
        seqs.push(s.send(&Message::SensorChunk(c.clone()))?);
    }
    let r = s.recv()?;
    expect(
        &mut rep,
        seqs.iter().all(|&q| acked(&r, q)),
        "every scan chunk acked",
    );

    let t = s.telemetry()?;
    expect(&mut rep, t.scans_completed == 1, "scan reassembled");
    expect(
        &mut rep,
        t.map.scans_integrated == 1 && t.map.points_integrated > 0 && t.map.blocks_used > 0,
        "scan integrated into the onboard map",
    );
    expect(
        &mut rep,
        t.map.pool_errors == 0 && t.map.voxels_dropped == 0,
        "map pool had room for the scan",
    );
    expect(
        &mut rep,
        t.mode == Mode::Mapping,
        "mapping after the first scan",
    );
    expect(
        &mut rep,
        t.tether_readings == 5,
        "five tether readings counted",
    );

    let goal = GoalRequest {
        goal_id: 1,
        position: Point3::new(8.0, 0.0, -4.0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Abit,
        max_iterations: 750,
        time_budget_ms: 0,
        allow_approximate: false,
    };
    let seq = s.send(&Message::GoalRequest(goal))?;
    let r = s.recv()?;
    expect(&mut rep, acked(&r, seq), "goal acked");
    rep.plan_state = r.iter().find_map(|m| {
        if let Message::PlanStatus(p) = m {
            Some(p.state)
        } else {
            None
        }
    });
    let has_status = rep.plan_state.is_some();
    expect(&mut rep, has_status, "plan status after goal");

    // One damaged frame: a time tick with a flipped bit. It must be rejected with BadCrc and change nothing.
    let before = s.telemetry()?;
    let mut frame = vec![0u8; 64];
    let seq = s.take_seq();
    let body = [0xE8, 0x07];
    let n = build_raw(
        Header {
            version: firmware::config::protocol::PROTOCOL_VERSION,
            kind: MessageKind::TimeTick as u8,
            seq,
        },
        &body,
        &mut frame,
    )
    .map_err(SessionError::Encode)?;
    frame[7] ^= 0x04;
    let mut wire = vec![0u8; 80];
    let w = stuff(&frame[..n], &mut wire).map_err(SessionError::Encode)?;
    s.send_raw(&wire[..w])?;
    let r = s.recv()?;
    expect(
        &mut rep,
        r.contains(&Message::Nack(Nack {
            seq,
            reason: NackReason::BadCrc,
        })),
        "damaged frame nacked BadCrc",
    );
    let after = s.telemetry()?;
    expect(
        &mut rep,
        after.mode == before.mode,
        "damaged frame left the mode",
    );
    expect(
        &mut rep,
        after.frames_accepted == before.frames_accepted + 1,
        "only the telemetry request accepted",
    );

    // Let periodic telemetry run for a second of link time.
    let until = s.link().now_us() + 1_000_000;
    s.advance_to(until)?;

    let seq = s.send(&Message::Shutdown(Shutdown))?;
    let r = s.recv()?;
    expect(&mut rep, acked(&r, seq), "shutdown acked");
    expect(
        &mut rep,
        r.iter().any(|m| {
            matches!(
                m,
                Message::DriveCommand(DriveCommand {
                    motion: Motion::Stop { .. },
                    ..
                })
            )
        }),
        "stop commanded at shutdown",
    );
    let t = s.telemetry()?;
    expect(&mut rep, t.mode == Mode::Safe, "safe mode after shutdown");
    rep.final_telemetry = Some(t);

    for m in s.log.iter().map(|r| &r.message) {
        *rep.received.entry(kind_name(m)).or_default() += 1;
        if let Message::Nack(n) = m {
            rep.nacks.push((n.seq, n.reason));
        }
    }
    rep.frames_sent = s.next_seq();
    rep.end_us = s.link().now_us();
    Ok(rep)
}
