//! `tetherbot soak [SCENARIO] [--link qemu|inproc] [--first-seq N] [--link-time-s S] [-o LOG]`: a long mission with
//! the host's sequence numbers started near 2^32, judged from its field log ([`crate::soak`]; figures in
//! `host-sim/doc/soak.md`). Prints the mission's summary, the soak's figures (frames, telemetry at the start, the
//! middle and the end) and its problems; exit status 1 when there is any.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::fieldlog::{self, Writer};
use crate::link::recording::RecordingLink;
use crate::link::{FlightLink, LinkKind};
use crate::mission::run::{run_mission_from, MissionOptions};
use crate::replay::RunConfig;
use crate::soak::{analyse, DEFAULT_FIRST_SEQ};

/// Arguments of `soak`.
#[derive(Debug, Clone, clap::Args)]
pub struct SoakArgs {
    /// Scenario file (default: the embedded crater-wall descent, as `mission`).
    pub scenario: Option<PathBuf>,
    /// Flight software: the board binary in QEMU (the soak proper), or the in-process executive.
    #[arg(long, value_enum, default_value_t = LinkKind::Qemu)]
    pub link: LinkKind,
    /// Mission seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Sequence number of the host's first frame (default 2^32 - 1000: the count wraps early in the mission).
    #[arg(long, default_value_t = DEFAULT_FIRST_SEQ)]
    pub first_seq: u32,
    /// End the mission after this much link time, seconds (default: the scenario's `[mission] time_limit_s`).
    #[arg(long)]
    pub link_time_s: Option<f64>,
    /// Field log path (written, then read back for the analysis).
    #[arg(long, short = 'o', value_name = "LOG", default_value = "soak.fieldlog")]
    pub log: PathBuf,
    /// Replace an existing log.
    #[arg(long)]
    pub force: bool,
}

/// Runs the soak; exit 0 passed, 1 a problem was found, 2 it could not run.
pub fn main(args: &SoakArgs) -> ExitCode {
    super::check_outcome(soak(args))
}

fn soak(args: &SoakArgs) -> Result<bool, Box<dyn core::error::Error>> {
    super::check_output(&args.log, args.force, &[])?;
    let mut sc = super::mission::load_scenario(args.scenario.as_deref())?;
    if let Some(s) = args.link_time_s {
        if !(s.is_finite() && s > 0.0) {
            return Err(
                format!("--link-time-s must be a positive number of seconds, got {s}").into(),
            );
        }
        sc.mission.time_limit_s = s;
    }
    let opts = MissionOptions {
        seed: args.seed,
        tracking: firmware::protocol::Tracking::ClosedLoop,
        noiseless: false,
        live: false,
        reset: None,
    };
    let link_name = match args.link {
        LinkKind::Inproc => "inproc",
        LinkKind::Qemu => "qemu",
    };
    let config = RunConfig {
        scenario: sc.name.clone(),
        link: link_name.into(),
        step_us: crate::link::inproc::DEFAULT_STEP_US,
    };
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: args.seed,
        config: serde_json::to_string(&config)?,
    };
    let file = std::fs::File::create(&args.log)
        .map_err(|e| format!("cannot create {}: {e}", args.log.display()))?;
    let writer = Writer::new(std::io::BufWriter::new(file), &header)?;
    let t0 = std::time::Instant::now();
    let run = |link: &mut dyn FlightLink| -> Result<_, Box<dyn core::error::Error>> {
        let mut rec = RecordingLink::new(link, writer);
        let rep = run_mission_from(&mut rec, &sc, &opts, args.first_seq)?;
        rec.finish()?;
        Ok(rep)
    };
    let rep = match args.link {
        LinkKind::Inproc => run(&mut crate::mission::link::mission_link(&sc)?)?,
        LinkKind::Qemu => {
            super::board::with_link(LinkKind::Qemu, crate::link::inproc::DEFAULT_STEP_US, run)?
        }
    };
    let wall = t0.elapsed();
    print!("{}", super::mission::summary(&rep));
    let log = fieldlog::read_file(&args.log)?;
    let report = analyse(&log);
    println!(
        "soak on {link_name}: wall time {:.1} s; first host seq {}",
        wall.as_secs_f64(),
        args.first_seq
    );
    print!("{report}");
    let problems = report.problems(args.first_seq > u32::MAX - 1_000_000);
    for p in &problems {
        println!("problem: {p}");
    }
    println!(
        "soak: {}",
        if problems.is_empty() {
            "passed"
        } else {
            "FAILED"
        }
    );
    Ok(problems.is_empty())
}
