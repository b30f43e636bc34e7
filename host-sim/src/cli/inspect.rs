//! `tetherbot inspect LOG`: header, record counts, decoded frames, damage.

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::process::ExitCode;

use firmware::protocol::{self, Deframer};

use crate::fieldlog::{self, Completeness, Direction};

/// Arguments of `inspect`.
#[derive(Debug, Clone, clap::Args)]
pub struct InspectArgs {
    /// The field log.
    pub log: PathBuf,
    /// List every decoded frame.
    #[arg(long)]
    pub frames: bool,
}

/// `inspect` entry point: exit 1 if the log is damaged or has no end record (it may be truncated).
pub fn main(args: &InspectArgs) -> ExitCode {
    let log = match fieldlog::read_file(&args.log) {
        Ok(l) => l,
        Err(e) => return super::fail(e),
    };
    let h = &log.header;
    println!("field log {}", args.log.display());
    println!(
        "  format {}, protocol {}, seed {}, created at {} ms (Unix)",
        log.format_version,
        h.protocol_version,
        h.seed,
        h.created_at_unix_ms
    );
    println!("  config {}", h.config);
    let mut deframers = [Deframer::new(), Deframer::new()];
    let mut kinds: BTreeMap<(&str, String), u32> = BTreeMap::new();
    let mut bytes = [0usize; 2];
    for r in &log.records {
        let (side, name) = match r.direction {
            Direction::HostToFlight => (0, "host->flight"),
            Direction::FlightToHost => (1, "flight->host"),
        };
        bytes[side] += r.bytes.len();
        let mut rest = &r.bytes[..];
        while !rest.is_empty() {
            let (n, ev) = deframers[side].push(rest);
            rest = &rest[n..];
            let Some(ev) = ev else { continue };
            let decoded = ev
                .map_err(protocol::NackReason::from)
                .and_then(protocol::decode_frame);
            let key = match &decoded {
                Ok((_, m)) => format!("{:?}", m.kind()),
                Err(reason) => format!("undecodable ({reason:?})"),
            };
            if args.frames {
                match &decoded {
                    Ok((hd, m)) => println!("  {:>12} us {name} seq {:>5} {m:?}", r.t_us, hd.seq),
                    Err(reason) => {
                        println!("  {:>12} us {name} undecodable frame: {reason:?}", r.t_us)
                    }
                }
            }
            *kinds.entry((name, key)).or_default() += 1;
        }
    }
    println!(
        "  records {}, host->flight {} B, flight->host {} B",
        log.records.len(),
        bytes[0],
        bytes[1]
    );
    for ((dir, kind), n) in &kinds {
        println!("  {dir} {kind}: {n}");
    }
    if !log.faults.is_empty() {
        let mut by_kind: BTreeMap<String, u32> = BTreeMap::new();
        for f in &log.faults {
            match crate::link::faults::FaultEvent::from_bytes(f.t_us, &f.bytes) {
                Some(e) => {
                    if args.frames {
                        println!("  fault: {e}");
                    }
                    let name = match e.direction {
                        crate::link::faults::LinkDirection::Up => e.kind.name().to_string(),
                        crate::link::faults::LinkDirection::Down => format!("down.{}", e.kind.name()),
                    };
                    *by_kind.entry(name).or_default() += 1;
                }
                None if crate::link::ResetCause::from_record(&f.bytes).is_some() => {
                    if args.frames {
                        let how = String::from_utf8_lossy(&f.bytes);
                        println!("  {how} at t {:.6} s", f.t_us as f64 / 1e6);
                    }
                    *by_kind.entry("flight reset".into()).or_default() += 1;
                }
                None => *by_kind.entry("unreadable".into()).or_default() += 1,
            }
        }
        let text: Vec<String> = by_kind.iter().map(|(k, n)| format!("{k} {n}")).collect();
        println!(
            "  injected link faults (fault records): {} ({})",
            log.faults.len(),
            text.join(", ")
        );
    }
    for d in &log.damaged {
        println!(
            "  DAMAGED at byte {} ({:?}); {} bytes skipped to the next valid record",
            d.offset, d.reason, d.unread_bytes
        );
    }
    match log.completeness() {
        Completeness::Complete => {
            println!("  no damage; end record: {} records, all read", log.records.len());
            ExitCode::SUCCESS
        }
        other => {
            println!("  {} valid records read; INCOMPLETE: {other}", log.records.len());
            ExitCode::from(super::EXIT_FAILED)
        }
    }
}
