//! `tetherbot run <scenario>` and `tetherbot record <scenario> -o LOG`.

use std::path::PathBuf;
use std::process::ExitCode;

use crate::fieldlog::{self, Writer};
use crate::link::inproc::DEFAULT_STEP_US;
use crate::link::recording::RecordingLink;
use crate::link::{FlightLink, LinkKind};
use crate::replay::RunConfig;
use crate::scripted::{self, ScenarioReport};

/// Arguments of `run` / `record`.
#[derive(Debug, Clone, clap::Args)]
pub struct RunArgs {
    /// Scenario to run (built in: protocol).
    #[arg(default_value = "protocol")]
    pub scenario: String,
    /// Seed of the run (planner RNG, synthetic sensor noise).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Record every byte into this field log.
    #[arg(long, short = 'o', value_name = "LOG")]
    pub log: Option<PathBuf>,
    /// Executive period of the in-process link, microseconds.
    #[arg(long, default_value_t = DEFAULT_STEP_US)]
    pub step_us: u64,
    /// Creation time written into the log header, Unix milliseconds (default: now). Fix it for byte-identical logs.
    #[arg(long)]
    pub created_at_ms: Option<u64>,
    /// Flight software to run against: the in-process executive, or the board binary in QEMU (lockstep).
    #[arg(long, value_enum, default_value_t = LinkKind::Inproc)]
    pub link: LinkKind,
    /// Overwrite an existing field log (without it, `-o EXISTING` is refused).
    #[arg(long)]
    pub force: bool,
}

/// Runs a scenario on the in-process link, optionally recording it.
pub fn run_scenario(args: &RunArgs) -> Result<ScenarioReport, Box<dyn core::error::Error>> {
    if let Some(path) = &args.log {
        // Checked before the link starts (a QEMU boot or a board build would be wasted).
        super::check_output(path, args.force, &[])?;
    }
    if !scripted::SCENARIOS.contains(&args.scenario.as_str()) {
        return Err(format!(
            "unknown scenario '{}'; built in: {}",
            args.scenario,
            scripted::SCENARIOS.join(", ")
        )
        .into());
    }
    super::board::with_link(args.link, args.step_us, |link| run_on(link, args))
}

/// Runs a scenario on `link`, optionally recording it.
pub fn run_on(
    link: &mut dyn FlightLink,
    args: &RunArgs,
) -> Result<ScenarioReport, Box<dyn core::error::Error>> {
    let Some(path) = &args.log else {
        return Ok(scripted::run_protocol(link, args.seed)?);
    };
    let config = RunConfig {
        scenario: args.scenario.clone(),
        link: link.name().into(),
        step_us: args.step_us,
    };
    let created = args.created_at_ms.unwrap_or_else(|| {
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.as_millis() as u64)
    });
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: created,
        seed: args.seed,
        config: serde_json::to_string(&config)?,
    };
    let file = std::fs::File::create(path)
        .map_err(|e| format!("cannot create {}: {e}", path.display()))?;
    let writer = Writer::new(std::io::BufWriter::new(file), &header)?;
    let mut rec = RecordingLink::new(link, writer);
    let report = scripted::run_protocol(&mut rec, args.seed)?;
    rec.finish()?;
    Ok(report)
}

/// `run` / `record` entry point.
pub fn main(args: &RunArgs) -> ExitCode {
    match run_scenario(args) {
        Ok(report) => {
            println!(
                "scenario {} (seed {}) on the {} link",
                args.scenario,
                args.seed,
                match args.link {
                    LinkKind::Inproc => "in-process",
                    LinkKind::Qemu => "emulated board (QEMU)",
                }
            );
            println!("{report}");
            if let Some(p) = &args.log {
                println!("field log: {}", p.display());
            }
            if report.passed() {
                ExitCode::SUCCESS
            } else {
                ExitCode::from(super::EXIT_FAILED)
            }
        }
        Err(e) => super::fail(e),
    }
}
