//! The flight software over the in-process link: the bad-input matrix, record -> replay identity, replay
//! mismatch reporting, and damaged field logs.

use host_sim::fieldlog::{self, DamageReason, Direction};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::recording::RecordingLink;
use host_sim::replay::{replay, ReplayOutcome, RunConfig};
use host_sim::scripted as scenario;
use host_sim::testkit::bad_input_matrix;

#[test]
fn bad_input_matrix_over_the_inproc_link() {
    let mut link = InProcLink::new(DEFAULT_STEP_US);
    let report = bad_input_matrix(&mut link).unwrap();
    println!("{report}");
    assert!(
        report.cases.len() >= 20,
        "matrix has {} cases",
        report.cases.len()
    );
    for c in &report.cases {
        assert!(c.passed(), "case '{}' failed: {c:?}", c.name);
    }
    assert!(report.scan_completed_after);
    // every rejection reason the matrix expects is distinct where the inputs differ in kind of fault
    let reasons: std::collections::BTreeSet<_> = report.cases.iter().map(|c| c.expected).collect();
    assert!(reasons.len() >= 18);
}

/// Records the protocol scenario into memory; returns the log bytes.
fn record(seed: u64) -> Vec<u8> {
    let config = RunConfig {
        scenario: "protocol".into(),
        link: "inproc".into(),
        step_us: DEFAULT_STEP_US,
    };
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 1_700_000_000_000,
        seed,
        config: serde_json_string(&config),
    };
    let writer = fieldlog::Writer::new(Vec::new(), &header).unwrap();
    let mut rec = RecordingLink::new(InProcLink::new(DEFAULT_STEP_US), writer);
    let report = scenario::run_protocol(&mut rec, seed).unwrap();
    assert!(report.passed(), "{report}");
    rec.finish().unwrap().1
}

fn serde_json_string(c: &RunConfig) -> String {
    format!(
        "{{\"scenario\":\"{}\",\"link\":\"{}\",\"step_us\":{}}}",
        c.scenario, c.link, c.step_us
    )
}

#[test]
fn record_then_replay_is_byte_identical_and_runs_are_deterministic() {
    let a = record(7);
    let b = record(7);
    assert_eq!(a, b, "two runs with the same seed give the same log bytes");
    assert_ne!(a, record(8), "the seed reaches the bytes");
    let log = fieldlog::parse(&a).unwrap();
    assert!(log.damage.is_none());
    let f2h: usize = log
        .records
        .iter()
        .filter(|r| r.direction == Direction::FlightToHost)
        .map(|r| r.bytes.len())
        .sum();
    let h2f = log
        .records
        .iter()
        .filter(|r| r.direction == Direction::HostToFlight)
        .count();
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert_eq!(
        out,
        ReplayOutcome::Identical {
            records_fed: h2f,
            bytes_compared: f2h
        }
    );
    assert!(f2h > 500);
}

#[test]
fn replay_reports_the_first_differing_record_and_byte() {
    let log = fieldlog::parse(&record(3)).unwrap();
    // change byte 5 of the third flight -> host record; the replay must point exactly there
    let (idx, _) = log
        .records
        .iter()
        .enumerate()
        .filter(|(_, r)| r.direction == Direction::FlightToHost)
        .nth(2)
        .unwrap();
    let mut bad = log.clone();
    bad.records[idx].bytes[5] ^= 0x20;
    let stream_offset: usize = log.records[..idx]
        .iter()
        .filter(|r| r.direction == Direction::FlightToHost)
        .map(|r| r.bytes.len())
        .sum::<usize>()
        + 5;
    let out = replay(&bad, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert_eq!(
        out,
        ReplayOutcome::Differs {
            record: idx,
            offset_in_record: 5,
            stream_offset,
            expected: Some(log.records[idx].bytes[5] ^ 0x20),
            got: Some(log.records[idx].bytes[5]),
        }
    );
    // a changed input byte changes the output too (the replay really runs the flight software)
    let mut bad_in = log.clone();
    let first_h2f = bad_in
        .records
        .iter()
        .position(|r| r.direction == Direction::HostToFlight)
        .unwrap();
    bad_in.records[first_h2f].bytes[3] ^= 0x01;
    let out = replay(&bad_in, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Differs { .. }), "{out}");
}

#[test]
fn corrupted_log_skips_only_the_damaged_record_and_reports_its_position() {
    let bytes = record(5);
    let log = fieldlog::parse(&bytes).unwrap();
    let k = log.records.len() / 2;
    let target = &log.records[k];
    // flip a byte in the payload of record k
    let mut flipped = bytes.clone();
    flipped[target.offset as usize + 13] ^= 0xFF;
    let damaged = fieldlog::parse(&flipped).unwrap();
    let d = damaged.damage.expect("damage found");
    assert_eq!(d.offset, target.offset);
    assert_eq!(d.reason, DamageReason::BadChecksum);
    // Issue 24: the reader resynchronises at the next record, so the damage is exactly record k's bytes...
    assert_eq!(d.unread_bytes, (fieldlog::RECORD_OVERHEAD + target.bytes.len()) as u64);
    // ...every record before and after it is kept intact, and the end record counts the one lost.
    let mut kept = log.records.clone();
    kept.remove(k);
    assert_eq!(damaged.records, kept, "every record but the damaged one is kept intact");
    assert_eq!(
        damaged.completeness(),
        fieldlog::Completeness::Damaged { spans: 1, lost: Some(1) }
    );

    // cut the file in the middle of record k
    let cut = &bytes[..target.offset as usize + 7];
    let truncated = fieldlog::parse(cut).unwrap();
    let d = truncated.damage.expect("truncation found");
    assert_eq!(
        (d.offset, d.reason),
        (target.offset, DamageReason::Truncated)
    );
    assert_eq!(truncated.records, log.records[..k]);

    // a length field that lies (huge) is reported as such, not allocated
    let mut huge = bytes.clone();
    let len_at = target.offset as usize + 9;
    huge[len_at..len_at + 4].copy_from_slice(&u32::MAX.to_le_bytes());
    let d = fieldlog::parse(&huge).unwrap().damage.unwrap();
    assert_eq!(
        (d.offset, d.reason),
        (target.offset, DamageReason::LengthTooLarge)
    );

    // a damaged header is an error, not a guess
    let mut bad_header = bytes.clone();
    bad_header[14] ^= 1;
    assert_eq!(
        fieldlog::parse(&bad_header).unwrap_err(),
        fieldlog::HeaderError::BadChecksum
    );
    assert_eq!(
        fieldlog::parse(b"NOTALOG!xxxxxxxx").unwrap_err(),
        fieldlog::HeaderError::BadMagic
    );
}
