//! `tetherbot replay LOG`: feed the recorded input to a fresh executive, compare every output byte.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::fieldlog;
use crate::link::LinkKind;
use crate::fieldlog::Completeness;
use crate::replay::{check_replayable, replay, ReplayOutcome, RunConfig};

/// Arguments of `replay`.
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayArgs {
    /// The field log.
    pub log: PathBuf,
    /// Flight software to replay against (default: in-process; logs recorded on either link replay on either,
    /// because the board runs in lockstep on the same simulated clock).
    #[arg(long, value_enum, default_value_t = LinkKind::Inproc)]
    pub link: LinkKind,
    /// Longest link time to replay, seconds: the replay steps the executive every `step_us` up to the last
    /// record's time, so a log whose time stamps run past this is refused instead of running for ever.
    #[arg(long, default_value_t = 3600)]
    pub max_link_time_s: u64,
}

/// `replay` entry point: exit 0 when identical and the log complete, 1 on a mismatch, a damaged log or one
/// without an end record (it may be truncated), 2 if it cannot run.
pub fn main(args: &ReplayArgs) -> ExitCode {
    let log = match fieldlog::read_file(&args.log) {
        Ok(l) => l,
        Err(e) => return super::fail(e),
    };
    let config: RunConfig = match serde_json::from_str(&log.header.config) {
        Ok(c) => c,
        Err(e) => return super::fail(format!("log configuration is not a run configuration: {e}")),
    };
    if config.link != "inproc" && config.link != "qemu" {
        return super::fail(format!(
            "replay of '{}' links is not supported; only inproc and qemu",
            config.link
        ));
    }
    if let Err(e) = check_replayable(&log, config.step_us, args.max_link_time_s.saturating_mul(1_000_000)) {
        return super::fail(format!("{}: {e}", args.log.display()));
    }
    let run = |mut link: &mut dyn crate::link::FlightLink| -> Result<ReplayOutcome, Box<dyn core::error::Error>> {
        Ok(replay(&log, &mut link)?)
    };
    let outcome = super::board::with_link(args.link, config.step_us, run);
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => return super::fail(e),
    };
    let completeness = log.completeness();
    let ok = matches!(outcome, ReplayOutcome::Identical { .. }) && completeness == Completeness::Complete;
    match (&outcome, completeness) {
        (ReplayOutcome::Identical { records_fed, bytes_compared }, c) if c != Completeness::Complete => println!(
            "{}: NOT VERIFIED: the {records_fed} host->flight records read replay to the {bytes_compared} \
             flight->host bytes recorded, but the log is incomplete",
            args.log.display()
        ),
        _ => println!("{}: {outcome}", args.log.display()),
    }
    for d in &log.damaged {
        println!(
            "log damaged at byte {} ({:?}); {} bytes skipped to the next valid record",
            d.offset, d.reason, d.unread_bytes
        );
    }
    if completeness != Completeness::Complete {
        println!("log incomplete: {completeness}");
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(super::EXIT_FAILED)
    }
}
