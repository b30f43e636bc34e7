//! Fuzz target: the field-log reader (`host_sim::fieldlog::parse`).
//!
//! First byte even: the rest is read as a log as it stands. Every record read must be the exact bytes at its
//! offset, and offsets must increase. Random bytes rarely carry a valid CRC-32, so first byte odd: the rest
//! describes records (`direction | time step | length | payload`), a `Writer` writes them with correct
//! checksums, and the log is read back whole (every record, complete), cut short (never "complete": the end
//! record is what tells a cut at a record boundary), or with one bit flipped (reported as damage; every record
//! before the flip kept).
#![no_main]

use host_sim::fieldlog::{
    parse, record_bytes, Completeness, Direction, FieldLog, Header, Writer, RECORD_OVERHEAD,
};
use libfuzzer_sys::fuzz_target;

fn check_records_are_the_bytes(log: &FieldLog, b: &[u8]) {
    let mut last = None;
    for r in &log.records {
        assert!(
            last.is_none_or(|l| r.offset > l),
            "record offsets do not increase"
        );
        last = Some(r.offset);
        let enc = record_bytes(r.direction, r.t_us, &r.bytes);
        let at = usize::try_from(r.offset).expect("offset fits");
        assert_eq!(
            b.get(at..at + enc.len()),
            Some(&enc[..]),
            "record at {at} is not the bytes there"
        );
    }
}

fuzz_target!(|data: &[u8]| {
    let Some(([mode, damage, cut_or_flip, c0, c1], rest)) = firmware_fuzz::split::<5>(data) else {
        return;
    };
    if mode % 2 == 0 {
        if let Ok(log) = parse(rest) {
            check_records_are_the_bytes(&log, rest);
        }
        return;
    }
    // build a log from the description
    let header = Header {
        protocol_version: 3,
        created_at_unix_ms: 0,
        seed: u64::from(mode),
        config: String::from_utf8_lossy(&rest[..rest.len().min(usize::from(c0 % 16))]).into_owned(),
    };
    let mut w = Writer::new(Vec::new(), &header).expect("in memory");
    let mut written = Vec::new();
    let (mut t, mut p) = (0u64, &rest[rest.len().min(usize::from(c0 % 16))..]);
    while let [dir, dt, len, tail @ ..] = p {
        let direction = if dir % 2 == 0 {
            Direction::HostToFlight
        } else {
            Direction::FlightToHost
        };
        t += u64::from(*dt);
        let (payload, next) = tail.split_at(tail.len().min(usize::from(*len)));
        w.append(direction, t, payload).expect("in memory");
        if !payload.is_empty() {
            written.push((direction, t, payload.to_vec()));
        }
        p = next;
    }
    let finished = c1 % 2 == 0;
    let b = if finished {
        w.finish().expect("in memory")
    } else {
        w.into_inner()
    };
    let read = |log: &FieldLog| {
        log.records
            .iter()
            .map(|r| (r.direction, r.t_us, r.bytes.clone()))
            .collect::<Vec<_>>()
    };
    match damage % 3 {
        0 => {
            let log = parse(&b).expect("a written log reads");
            assert_eq!(read(&log), written);
            let want = if finished {
                Completeness::Complete
            } else {
                Completeness::NoEndRecord
            };
            assert_eq!(log.completeness(), want);
        }
        1 => {
            let cut = (usize::from(cut_or_flip) | usize::from(c1) << 8) % b.len();
            if let Ok(log) = parse(&b[..cut]) {
                check_records_are_the_bytes(&log, &b[..cut]);
                assert_ne!(
                    log.completeness(),
                    Completeness::Complete,
                    "a log cut at byte {cut} reads as complete"
                );
            }
        }
        _ => {
            let bit = (usize::from(cut_or_flip) | usize::from(c1) << 8) % (b.len() * 8);
            let mut d = b.clone();
            d[bit / 8] ^= 1 << (bit % 8);
            if let Ok(log) = parse(&d) {
                check_records_are_the_bytes(&log, &d);
                assert_ne!(
                    log.completeness(),
                    Completeness::Complete,
                    "a flipped bit at {bit} went unnoticed"
                );
                // the written records that end before the flipped byte
                let mut end = 36 + header.config.len();
                let intact = written
                    .iter()
                    .take_while(|(_, _, p)| {
                        end += RECORD_OVERHEAD + p.len();
                        end <= bit / 8
                    })
                    .count();
                assert_eq!(
                    read(&log).get(..intact),
                    Some(&written[..intact]),
                    "a record before the flip was lost"
                );
            }
        }
    }
});
