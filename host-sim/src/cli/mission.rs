//! `tetherbot mission [SCENARIO] [--link inproc|qemu] [--seeds N] [-o LOG] [--tracking open|closed]`: a closed-loop
//! mission with the flight software in the loop (issue 18; `host-sim/doc/mission.md`).
//!
//! With one seed: a live progress line (state, distance, payout, tension, margin), a closing summary, and in the
//! output directory (`--out`, default `mission-out/`) the field log (`<name>.fieldlog`, or `-o LOG`), its MCAP
//! export (`<name>.mcap`), the picture (`<name>.svg`) and the JSON summary (`<name>.json`). With `--seeds N`: N
//! seeds in parallel (in-process) and the campaign table, plus `<name>-campaign.json`.
//! Without a scenario: the embedded default, `host-sim/scenarios/mission_crater_rocks.toml` (a crater wall with
//! rocks hidden until seen). The real-terrain Mars Yard descent (`mission_marsyard.toml`) is refused by today's
//! onboard map (`host-sim/doc/mission.md`, "What the onboard map must observe"), so it is not the default.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use firmware::protocol::Tracking;

use crate::fieldlog::{self, Writer};
use crate::link::recording::RecordingLink;
use crate::link::{FlightLink, LinkKind};
use crate::mission::run::{run_mission, MissionOptions, MissionReport, Verdict};
use crate::replay::RunConfig;
use crate::scenario::{self, Scenario};

/// The embedded default scenario (its terrain path is relative to `host-sim/scenarios/`).
pub const DEFAULT_SCENARIO: &str = include_str!("../../scenarios/mission_crater_rocks.toml");
/// The file name the embedded default stands for.
pub const DEFAULT_SCENARIO_FILE: &str = "mission_crater_rocks.toml";

/// Tracking mode on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum TrackingArg {
    /// The plan's motions as they are (the comparison baseline).
    Open,
    /// The flight software's tether-aware path-tracking controller.
    Closed,
}

impl From<TrackingArg> for Tracking {
    fn from(t: TrackingArg) -> Self {
        match t {
            TrackingArg::Open => Tracking::OpenLoop,
            TrackingArg::Closed => Tracking::ClosedLoop,
        }
    }
}

/// Arguments of `mission`.
#[derive(Debug, Clone, clap::Args)]
pub struct MissionArgs {
    /// Scenario file (default: the embedded crater-wall descent, `host-sim/scenarios/mission_crater_rocks.toml`).
    pub scenario: Option<PathBuf>,
    /// Flight software: the in-process executive, or the board binary in QEMU (lockstep; one seed only).
    #[arg(long, value_enum, default_value_t = LinkKind::Inproc)]
    pub link: LinkKind,
    /// Run this many seeds (a campaign, in parallel, in-process), starting at `--seed`.
    #[arg(long, default_value_t = 1)]
    pub seeds: u32,
    /// The (first) seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Tracking mode sent in `MissionConfig`.
    #[arg(long, value_enum, default_value_t = TrackingArg::Closed)]
    pub tracking: TrackingArg,
    /// Field log path (default `<out>/<scenario>.fieldlog`).
    #[arg(long, short = 'o', value_name = "LOG")]
    pub log: Option<PathBuf>,
    /// Directory for the log, MCAP, picture and JSON.
    #[arg(long, default_value = "mission-out")]
    pub out: PathBuf,
    /// Worker threads of a campaign (default: the machine's cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Creation time written into the log header, Unix milliseconds (default: now). Fix it for byte-identical logs.
    #[arg(long)]
    pub created_at_ms: Option<u64>,
    /// No live progress line.
    #[arg(long)]
    pub quiet: bool,
}

/// Loads the scenario of `args` (the embedded default when none is given).
pub fn load_scenario(path: Option<&Path>) -> Result<Scenario, scenario::ScenarioError> {
    match path {
        Some(p) => scenario::load(p),
        None => {
            let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(DEFAULT_SCENARIO_FILE);
            let sc = scenario::parse(DEFAULT_SCENARIO, &file)?;
            let world = sc.build_world()?;
            sc.check(world.as_ref())?;
            Ok(sc)
        }
    }
}

/// The closing summary of one mission.
pub fn summary(rep: &MissionReport) -> String {
    let mut s = String::new();
    let status = rep.last_status.map_or("no mission status received".to_string(), |st| {
        format!("flight software: {:?} ({:?}), {} motions, {} replans, {:.2} m driven (its count)", st.state, st.reason, st.motions_done, st.replans, st.distance_driven_m)
    });
    s.push_str(&format!("mission {} seed {} ({}): {}\n", rep.scenario, rep.seed, rep.tracking, rep.verdict.name()));
    s.push_str(&format!("  {status}\n"));
    s.push_str(&format!(
        "  truth: {:.2} m driven, {:.2} m from the goal (tolerance {:.2} m), {} motions ({} stalled, {} slipped)\n",
        rep.distance_m, rep.goal_error_m, rep.tolerance_m, rep.motions, rep.stalls, rep.slips
    ));
    s.push_str(&format!(
        "  min true margin {:.1} N, max tension {:.0} N, max payout {:.2} m, cross-track from the plan {:.3} m mean / {:.3} m max\n",
        rep.min_true_margin_n, rep.max_tension_n, rep.max_payout_m, rep.mean_cross_track_m, rep.max_cross_track_m
    ));
    for (k, p) in rep.plans.iter().enumerate() {
        s.push_str(&format!(
            "  plan {k}: {} at t {:.1} s, {} iterations, {:.2} s host time, {} waypoints\n",
            p.state,
            p.t_s,
            p.iterations,
            p.host_s,
            p.waypoints.len()
        ));
    }
    s.push_str(&format!(
        "  map high-water {} of {} blocks; {} nacks; link time {:.1} s, host time {:.1} s\n",
        rep.map_blocks, rep.map_blocks_capacity, rep.nacks, rep.link_s, rep.host_s
    ));
    s
}

fn one(args: &MissionArgs, sc: &Scenario) -> Result<(MissionReport, Vec<PathBuf>), Box<dyn core::error::Error>> {
    std::fs::create_dir_all(&args.out).map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let log_path = args.log.clone().unwrap_or_else(|| args.out.join(format!("{}.fieldlog", sc.name)));
    let opts = MissionOptions { seed: args.seed, tracking: args.tracking.into(), noiseless: false, live: !args.quiet };
    sc.map_config()?;
    let config = RunConfig {
        scenario: sc.name.clone(),
        link: match args.link {
            LinkKind::Inproc => "inproc".into(),
            LinkKind::Qemu => "qemu".into(),
        },
        step_us: crate::link::inproc::DEFAULT_STEP_US,
    };
    let created = args.created_at_ms.unwrap_or_else(|| {
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_millis() as u64)
    });
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: created,
        seed: args.seed,
        config: serde_json::to_string(&config)?,
    };
    let file = std::fs::File::create(&log_path).map_err(|e| format!("cannot create {}: {e}", log_path.display()))?;
    let writer = Writer::new(std::io::BufWriter::new(file), &header)?;
    let run = |link: &mut dyn FlightLink| -> Result<MissionReport, Box<dyn core::error::Error>> {
        let mut rec = RecordingLink::new(link, writer);
        let rep = run_mission(&mut rec, sc, &opts)?;
        rec.finish()?;
        Ok(rep)
    };
    let rep = match args.link {
        LinkKind::Inproc => {
            let mut link = crate::mission::link::mission_link(sc)?;
            let rep = run(&mut link)?;
            if let (Some(l), false) = (link.longest_step(), args.quiet) {
                println!(
                    "  longest executive step {:.3} s host time (link time {:.3} s, {:?}; host-dependent, not logged)",
                    l.wall.as_secs_f64(),
                    l.t_us as f64 * 1e-6,
                    l.mode
                );
            }
            if std::env::var_os("TETHERBOT_PLAN_STATS").is_some() {
                eprintln!("navigator planning counters: {:?}", link.executive().autonomy().plan_stats());
            }
            rep
        }
        LinkKind::Qemu => {
            super::board::with_link(LinkKind::Qemu, crate::link::inproc::DEFAULT_STEP_US, run)?
        }
    };
    let mut written = vec![log_path.clone()];
    let log = fieldlog::read_file(&log_path)?;
    let mcap_path = args.out.join(format!("{}.mcap", sc.name));
    let f = std::fs::File::create(&mcap_path).map_err(|e| format!("cannot create {}: {e}", mcap_path.display()))?;
    crate::mcap_export::export(&log, std::io::BufWriter::new(f))?;
    written.push(mcap_path);
    let world = crate::mission::run::truth_for(sc, &crate::mission::run::mission_configure(sc, &opts), &sc.mission)?;
    let svg_path = args.out.join(format!("{}.svg", sc.name));
    std::fs::write(&svg_path, crate::mission::svg::render(&rep, &world.world.truth()))?;
    written.push(svg_path);
    let json_path = args.out.join(format!("{}.json", sc.name));
    std::fs::write(&json_path, serde_json::to_string_pretty(&rep)?)?;
    written.push(json_path);
    Ok((rep, written))
}

fn campaign(args: &MissionArgs, sc: &Scenario) -> Result<Vec<MissionReport>, Box<dyn core::error::Error>> {
    if args.link != LinkKind::Inproc {
        return Err("a campaign (--seeds > 1) runs in-process; run one seed at a time on the board".into());
    }
    let seeds: Vec<u64> = (0..u64::from(args.seeds)).map(|k| args.seed + k).collect();
    let threads = args.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let bar = indicatif::ProgressBar::new(seeds.len() as u64);
    let tick = |_: &MissionReport| bar.inc(1);
    let results = crate::mission::campaign::run_seeds(sc, &seeds, args.tracking.into(), threads, &tick);
    bar.finish_and_clear();
    let mut reports = Vec::new();
    for (seed, r) in seeds.iter().zip(results) {
        match r {
            Ok(rep) => reports.push(rep),
            Err(e) => eprintln!("seed {seed}: could not run: {e}"),
        }
    }
    Ok(reports)
}

/// `mission` entry point: exit 0 when every mission arrived or stopped safe with a reason and none fell, 1 on a
/// fall or a false arrival, 2 when it could not run.
pub fn main(args: &MissionArgs) -> ExitCode {
    let sc = match load_scenario(args.scenario.as_deref()) {
        Ok(s) => s,
        Err(e) => return super::fail(e),
    };
    let bad = |v: &Verdict| matches!(v, Verdict::Fell | Verdict::FalseArrival);
    if args.seeds <= 1 {
        match one(args, &sc) {
            Ok((rep, written)) => {
                print!("{}", summary(&rep));
                for p in written {
                    println!("  wrote {}", p.display());
                }
                if bad(&rep.verdict) {
                    ExitCode::from(super::EXIT_FAILED)
                } else {
                    ExitCode::SUCCESS
                }
            }
            Err(e) => super::fail(e),
        }
    } else {
        match campaign(args, &sc) {
            Ok(reports) => {
                for r in &reports {
                    println!(
                        "  seed {:>4}: {:<28} {:6.2} m, {} replans, min margin {:7.1} N, goal error {:.2} m",
                        r.seed,
                        r.verdict.name(),
                        r.distance_m,
                        r.replans,
                        r.min_true_margin_n,
                        r.goal_error_m
                    );
                }
                print!("{}", crate::mission::campaign::table(&sc.name, &reports));
                let _ = std::fs::create_dir_all(&args.out);
                let path = args.out.join(format!("{}-campaign.json", sc.name));
                let rows: Vec<serde_json::Value> = reports
                    .iter()
                    .map(|r| {
                        serde_json::json!({
                            "seed": r.seed, "verdict": r.verdict.name(), "distance_m": r.distance_m,
                            "replans": r.replans, "min_true_margin_n": r.min_true_margin_n,
                            "max_tension_n": r.max_tension_n, "max_payout_m": r.max_payout_m,
                            "goal_error_m": r.goal_error_m, "mean_cross_track_m": r.mean_cross_track_m,
                            "max_cross_track_m": r.max_cross_track_m, "plans": r.plans.len(),
                            "map_blocks": r.map_blocks, "host_s": r.host_s,
                        })
                    })
                    .collect();
                if let Ok(text) = serde_json::to_string_pretty(&rows) {
                    let _ = std::fs::write(&path, text);
                    println!("  wrote {}", path.display());
                }
                if reports.iter().any(|r| bad(&r.verdict)) || reports.len() < args.seeds as usize {
                    ExitCode::from(super::EXIT_FAILED)
                } else {
                    ExitCode::SUCCESS
                }
            }
            Err(e) => super::fail(e),
        }
    }
}
