//! Reusable checks over any [`FlightLink`] (in-process now, the QEMU board later).
//!
//! [`bad_input_matrix`] sends one bad input of every kind the protocol must survive (bit flip, truncation,
//! oversize, unknown kind, wrong version, wrong direction, duplicate / out-of-order / mixed / too many chunks,
//! NaN and infinite floats, lengths that lie, malformed enum, out-of-range values, pose mismatch) and checks for
//! each: exactly one `Nack` with the specific reason and no `Ack`; that reason's counter went up by one and no
//! other rejection counter moved; the flight state (mode, configuration, scan reassembly, scan / tether / goal
//! counters, plan state) did not change; and the next valid frame (a telemetry request) was processed. At the
//! end the scan that was in progress throughout is completed, proving the reassembly state survived.

use firmware::config::protocol::{
    PROTOCOL_VERSION,
    MAX_CHUNKS_PER_SCAN, MAX_ENCODED_FRAME_LEN, MAX_POINTS_PER_CHUNK,
};
use firmware::protocol::*;

use crate::link::FlightLink;
use crate::scripted::default_configure;
use crate::session::{HostSession, SessionError};

/// Result of one bad input.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseResult {
    /// Short name of the case.
    pub name: &'static str,
    /// The reason the flight software must give.
    pub expected: NackReason,
    /// The Nack reasons it gave.
    pub nacks: Vec<NackReason>,
    /// It acknowledged the bad frame (must be false).
    pub acked: bool,
    /// Only the expected rejection counter went up, by one.
    pub counters_ok: bool,
    /// Mode, configuration, reassembly and other state counters unchanged.
    pub state_unchanged: bool,
    /// The following telemetry request was acknowledged and answered.
    pub next_valid_processed: bool,
}

impl CaseResult {
    /// Every check of this case held.
    pub fn passed(&self) -> bool {
        self.nacks == [self.expected]
            && !self.acked
            && self.counters_ok
            && self.state_unchanged
            && self.next_valid_processed
    }
}

/// Result of the whole matrix.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// One entry per bad input.
    pub cases: Vec<CaseResult>,
    /// The scan in progress during the matrix was completed afterwards.
    pub scan_completed_after: bool,
}

impl Report {
    /// Every case passed and the scan survived.
    pub fn passed(&self) -> bool {
        self.scan_completed_after && self.cases.iter().all(CaseResult::passed)
    }
}

impl core::fmt::Display for Report {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        for c in &self.cases {
            writeln!(
                f,
                "{:<5} {:<28} expected {:<22} got {:?}{}{}{}{}",
                if c.passed() { "ok" } else { "FAIL" },
                c.name,
                format!("{:?}", c.expected),
                c.nacks,
                if c.acked { " ACKED" } else { "" },
                if c.counters_ok { "" } else { " counters-wrong" },
                if c.state_unchanged {
                    ""
                } else {
                    " STATE-CHANGED"
                },
                if c.next_valid_processed {
                    ""
                } else {
                    " next-frame-lost"
                },
            )?;
        }
        write!(
            f,
            "scan in progress completed afterwards: {}",
            self.scan_completed_after
        )
    }
}

/// The part of telemetry that is flight state (not traffic statistics).
fn state_of(t: &Telemetry) -> impl PartialEq + core::fmt::Debug {
    (
        t.mode,
        t.configured,
        t.scans_completed,
        t.scans_abandoned,
        t.scan_in_progress,
        t.scan_chunks_received,
        t.tether_readings,
        t.goals_received,
        t.plan_state,
        t.illegal_transitions,
    )
}

const SCAN: u32 = 77;
const SCAN_CHUNKS: u16 = 3;

fn scan_chunk(index: u16) -> SensorChunk {
    let mut points = heapless::Vec::new();
    for i in 0..10u16 {
        let _ = points.push(Point3::new(
            1.0 + f32::from(i) * 0.1,
            f32::from(index),
            -0.5,
        ));
    }
    SensorChunk {
        scan_id: SCAN,
        chunk_index: index,
        chunk_count: SCAN_CHUNKS,
        sensor_pose: Pose::IDENTITY,
        points,
    }
}

fn wire(frame: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; MAX_ENCODED_FRAME_LEN + 16];
    let n = stuff(frame, &mut out).unwrap_or(0);
    out.truncate(n);
    out
}

fn raw_frame(version: u8, kind: u8, seq: u32, body: &[u8]) -> Vec<u8> {
    let mut f = vec![0u8; body.len() + 16];
    let n = build_raw(Header { version, kind, seq }, body, &mut f).unwrap_or(0);
    f.truncate(n);
    f
}

fn body_of(m: &Message) -> Vec<u8> {
    let mut b = vec![0u8; 4096];
    let n = m.encode_body(&mut b).unwrap_or(0);
    b.truncate(n);
    b
}

/// Body of a SensorChunk of scan `SCAN`, chunk 1, up to (excluding) the point count.
fn chunk_prefix() -> Vec<u8> {
    let mut c = scan_chunk(1);
    c.points.clear();
    let mut b = body_of(&Message::SensorChunk(c));
    b.pop(); // the empty point count
    b
}

/// Builds the wire bytes of every case for sequence number `seq`.
fn cases(seq: u32) -> Vec<(&'static str, NackReason, Vec<u8>)> {
    let h2f = |kind: MessageKind, body: &[u8]| raw_frame(PROTOCOL_VERSION, kind as u8, seq, body);
    let tick = body_of(&Message::TimeTick(TimeTick {
        host_time_us: 123_456,
    }));
    let mut v = Vec::new();

    let mut flipped = h2f(MessageKind::TimeTick, &tick);
    flipped[7] ^= 0x01;
    v.push(("bit flip", NackReason::BadCrc, wire(&flipped)));

    let mut big_chunk = scan_chunk(1);
    big_chunk.points.clear();
    for _ in 0..MAX_POINTS_PER_CHUNK {
        let _ = big_chunk.points.push(Point3::new(1.1, 2.2, 3.3)); // no zero bytes: long COBS blocks
    }
    let full = wire(&h2f(
        MessageKind::SensorChunk,
        &body_of(&Message::SensorChunk(big_chunk)),
    ));
    // cut inside the first 254-byte COBS block: the block runs past the delimiter
    let mut cut = full[..150].to_vec();
    cut.push(0);
    v.push(("truncated in a COBS block", NackReason::Truncated, cut));
    let short = h2f(MessageKind::TimeTick, &tick);
    v.push((
        "truncated below header+crc",
        NackReason::Truncated,
        wire(&short[..7]),
    ));

    let mut oversize = vec![0x55u8; MAX_ENCODED_FRAME_LEN + 500];
    oversize.push(0);
    v.push(("oversize", NackReason::Oversize, oversize));

    v.push((
        "unknown kind",
        NackReason::UnknownKind,
        wire(&raw_frame(PROTOCOL_VERSION, 0x42, seq, &tick)),
    ));
    v.push((
        "wrong version (a version-1 frame)",
        NackReason::WrongVersion,
        wire(&raw_frame(1, 0x01, seq, &tick)),
    ));
    v.push((
        "wrong direction (Ack to flight)",
        NackReason::WrongDirection,
        wire(&h2f(
            MessageKind::Ack,
            &body_of(&Message::Ack(Ack { seq: 1 })),
        )),
    ));

    let chunk = |c: SensorChunk| {
        wire(&h2f(
            MessageKind::SensorChunk,
            &body_of(&Message::SensorChunk(c)),
        ))
    };
    v.push((
        "duplicate chunk",
        NackReason::DuplicateChunk,
        chunk(scan_chunk(0)),
    ));
    let mut older = scan_chunk(2);
    older.scan_id = SCAN - 1;
    v.push((
        "chunk of an older scan",
        NackReason::OutOfOrderChunk,
        chunk(older),
    ));
    let mut other = scan_chunk(1);
    other.chunk_count = SCAN_CHUNKS + 1;
    v.push(("another chunk count in the scan", NackReason::MixedScan, chunk(other)));
    let mut too_many = scan_chunk(1);
    too_many.chunk_count = MAX_CHUNKS_PER_SCAN + 1;
    v.push((
        "too many chunks",
        NackReason::TooManyChunks,
        chunk(too_many),
    ));
    let mut past = scan_chunk(1);
    past.chunk_index = SCAN_CHUNKS;
    v.push((
        "chunk index past count",
        NackReason::ChunkIndexOutOfRange,
        chunk(past),
    ));
    let mut moved = scan_chunk(1);
    moved.sensor_pose.position.z = 0.25;
    v.push(("chunk pose differs", NackReason::PoseMismatch, chunk(moved)));
    let mut skew = scan_chunk(1);
    skew.sensor_pose.orientation.w = 0.9;
    v.push((
        "non-unit quaternion",
        NackReason::NotUnitQuaternion,
        chunk(skew),
    ));
    let mut nan_point = scan_chunk(1);
    nan_point.points[3].y = f32::NAN;
    v.push(("NaN point", NackReason::NonFinite, chunk(nan_point)));

    let reading = TetherReading {
        time_us: 1,
        payout_m: 2.0,
        tension_n: f32::NAN,
        boom_angle_rad: 0.0,
    };
    v.push((
        "NaN tension",
        NackReason::NonFinite,
        wire(&h2f(
            MessageKind::TetherReading,
            &body_of(&Message::TetherReading(reading)),
        )),
    ));
    let goal = GoalRequest {
        goal_id: 5,
        position: Point3::new(f32::INFINITY, 0.0, 0.0),
        tolerance_m: 0.5,
        planner: PlannerChoice::Abit,
        max_iterations: 10,
        time_budget_ms: 0,
        allow_approximate: false,
    };
    v.push((
        "infinite goal",
        NackReason::NonFinite,
        wire(&h2f(
            MessageKind::GoalRequest,
            &body_of(&Message::GoalRequest(goal)),
        )),
    ));
    let negative = GoalRequest {
        position: Point3::new(1.0, 0.0, 0.0),
        tolerance_m: -1.0,
        ..goal
    };
    v.push((
        "negative tolerance",
        NackReason::OutOfRange,
        wire(&h2f(
            MessageKind::GoalRequest,
            &body_of(&Message::GoalRequest(negative)),
        )),
    ));
    let mut bad_enum = body_of(&Message::GoalRequest(negative));
    // layout: goal_id varint (1) | position (12) | tolerance (4) | planner enum index (1) | ...
    bad_enum[17] = 7;
    v.push((
        "malformed enum index",
        NackReason::MalformedBody,
        wire(&h2f(MessageKind::GoalRequest, &bad_enum)),
    ));

    let point = [0u8; 12];
    let mut claims_more = chunk_prefix();
    claims_more.push(3);
    claims_more.extend_from_slice(&point);
    v.push((
        "length claims more",
        NackReason::BodyTooShort,
        wire(&h2f(MessageKind::SensorChunk, &claims_more)),
    ));
    let mut claims_less = chunk_prefix();
    claims_less.push(1);
    claims_less.extend_from_slice(&point);
    claims_less.extend_from_slice(&point);
    v.push((
        "length claims less",
        NackReason::BodyTooLong,
        wire(&h2f(MessageKind::SensorChunk, &claims_less)),
    ));
    let mut over_cap = chunk_prefix();
    let n = MAX_POINTS_PER_CHUNK + 1;
    over_cap.extend_from_slice(&[(n as u8 & 0x7F) | 0x80, (n >> 7) as u8]);
    for _ in 0..n {
        over_cap.extend_from_slice(&point);
    }
    v.push((
        "length over capacity",
        NackReason::LengthOverLimit,
        wire(&h2f(MessageKind::SensorChunk, &over_cap)),
    ));
    v
}

/// Runs the matrix over `link` (a freshly booted flight software). See the module docs.
pub fn bad_input_matrix(link: &mut impl FlightLink) -> Result<Report, SessionError> {
    let mut s = HostSession::new(link);
    s.recv()?; // boot telemetry
    let cfg = default_configure(1);
    s.exchange(&Message::Configure(cfg))?;
    s.exchange(&Message::SensorChunk(scan_chunk(0)))?;
    let mut report = Report::default();
    let count = cases(0).len();
    for i in 0..count {
        let before = s.telemetry()?;
        let seq = s.take_seq();
        let Some((name, expected, bytes)) = cases(seq).into_iter().nth(i) else {
            break;
        };
        s.send_raw(&bytes)?;
        let replies = s.recv()?;
        let nacks: Vec<NackReason> = replies
            .iter()
            .filter_map(|m| {
                if let Message::Nack(n) = m {
                    Some(n.reason)
                } else {
                    None
                }
            })
            .collect();
        let acked = replies
            .iter()
            .any(|m| matches!(m, Message::Ack(a) if a.seq == seq));
        let req_seq = s.next_seq();
        let replies = s.exchange(&Message::TelemetryRequest(TelemetryRequest))?;
        let ack_at = replies
            .iter()
            .position(|m| *m == Message::Ack(Ack { seq: req_seq }));
        let after = ack_at.and_then(|a| {
            replies[a..].iter().find_map(|m| {
                if let Message::Telemetry(t) = m {
                    Some(*t)
                } else {
                    None
                }
            })
        });
        let (counters_ok, state_unchanged) = match after {
            Some(after) => {
                let counters_ok = NackReason::ALL.iter().all(|r| {
                    let d = after.frames_rejected[r.index()] - before.frames_rejected[r.index()];
                    d == u32::from(*r == expected)
                }) && after.frames_accepted == before.frames_accepted + 1;
                (counters_ok, state_of(&after) == state_of(&before))
            }
            None => (false, false),
        };
        report.cases.push(CaseResult {
            name,
            expected,
            nacks,
            acked,
            counters_ok,
            state_unchanged,
            next_valid_processed: after.is_some(),
        });
    }
    s.exchange(&Message::SensorChunk(scan_chunk(1)))?;
    s.exchange(&Message::SensorChunk(scan_chunk(2)))?;
    let t = s.telemetry()?;
    report.scan_completed_after = t.scans_completed == 1 && t.scan_in_progress == 0;
    Ok(report)
}
