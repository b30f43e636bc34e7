//! `tetherbot replay LOG`: feed the recorded input to a fresh executive, compare every output byte.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::fieldlog;
use crate::link::LinkKind;
use crate::replay::{replay, ReplayOutcome, RunConfig};

/// Arguments of `replay`.
#[derive(Debug, Clone, clap::Args)]
pub struct ReplayArgs {
    /// The field log.
    pub log: PathBuf,
    /// Flight software to replay against (default: in-process; logs recorded on either link replay on either,
    /// because the board runs in lockstep on the same simulated clock).
    #[arg(long, value_enum, default_value_t = LinkKind::Inproc)]
    pub link: LinkKind,
}

/// `replay` entry point: exit 0 when identical, 1 on a mismatch or a damaged log, 2 if it cannot run.
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
    let run = |mut link: &mut dyn crate::link::FlightLink| -> Result<ReplayOutcome, Box<dyn core::error::Error>> {
        Ok(replay(&log, &mut link)?)
    };
    let outcome = match (config.map, args.link) {
        // a mission on a scenario's own map configuration: the same navigator in-process
        (Some(map), LinkKind::Inproc) => crate::mission::link::inproc_with_map(map.into(), config.step_us)
            .map_err(Into::into)
            .and_then(|mut link| run(&mut link)),
        (Some(_), LinkKind::Qemu) => Err("this log's navigator used a non-default map configuration; the board runs \
                                          MapConfig::DEFAULT: replay it with --link inproc"
            .into()),
        (None, kind) => super::board::with_link(kind, config.step_us, run),
    };
    let outcome = match outcome {
        Ok(o) => o,
        Err(e) => return super::fail(e),
    };
    println!("{}: {outcome}", args.log.display());
    let mut ok = matches!(outcome, ReplayOutcome::Identical { .. });
    if let Some(d) = log.damage {
        println!(
            "log damaged at byte {} ({:?}); {} bytes after it not replayed",
            d.offset, d.reason, d.unread_bytes
        );
        ok = false;
    }
    if ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(super::EXIT_FAILED)
    }
}
