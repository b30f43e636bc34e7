//! `tetherbot mission [SCENARIO] [--link inproc|qemu] [--seeds N] [-o LOG] [--tracking open|closed]`: a closed-loop
//! mission with the flight software in the loop (issue 18; `host-sim/doc/mission.md`).
//!
//! With one seed: a live progress line (state, distance, payout, tension, margin), a closing summary, and in the
//! output directory (`--out`, default `mission-out/`) the field log (`<name>.fieldlog`, or `-o LOG`), its MCAP
//! export (`<name>.mcap`), the picture (`<name>.svg`) and the JSON summary (`<name>.json`). With `--seeds N`: N
//! seeds in parallel (in-process) and the campaign table, plus `<name>-campaign.json` (no wall-clock figures; those
//! are in `<name>-campaign-timing.json`). `--shard K/N` runs the missions `i` (seed `--seed + i`) with
//! `i mod N == K` and writes `<name>-campaign-shard-K-of-N.json` (and its `-timing.json`);
//! `tetherbot mission merge OUT SHARD...` joins the N shards' files into `OUT/<name>-campaign.json`, byte for byte
//! the unsharded run's ([`crate::shard`], [`crate::mission::campaign::merge`]). Output files are named after the
//! scenario's `name` made one safe path component ([`crate::scenario::file_safe`]), so a name such as `../x` or
//! `/etc/x` cannot write outside `--out`.
//! Without a scenario: the embedded default, `host-sim/scenarios/mission_crater_rocks.toml` (a crater wall with
//! rocks hidden until seen). The real-terrain Mars Yard descent (`mission_marsyard.toml`) is refused by today's
//! onboard map (`host-sim/doc/mission.md`, "What the onboard map must observe"), so it is not the default.
//!
//! Link faults (issue 24, `host-sim/doc/faults.md`): `--faults PROFILE` faults the uplink of the mission (or of
//! each mission of a campaign, seeded `seed ^ mission seed`) and prints the fault accounting; the field log then
//! holds the fault records and replays byte for byte. `--fault-campaign` runs the scenario at each of
//! `--fault-rates` for each of `--fault-kinds`, `--seeds` missions each, and prints the fault campaign table.
//! `--charge-host-time` lets the in-process executive measure its steps in host time (cycle accounting; such a
//! run's log does not replay byte for byte).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use firmware::protocol::Tracking;

use crate::fieldlog::{self, Writer};
use crate::link::faults::{FaultKind, FaultLink, FaultProfile, LinkDirection};
use crate::link::recording::RecordingLink;
use crate::link::{FlightLink, LinkKind};
use crate::mission::campaign::{
    CampaignFile, CampaignIdentity, CampaignTiming, MissionRow, MissionTiming,
};
use crate::mcap_export::SceneLink;
use crate::mission::run::{run_mission, MissionOptions, MissionReport, ResetAt, Verdict};
use crate::replay::RunConfig;
use crate::scenario::{self, Scenario};
use crate::shard::{self, RunTiming, Shard, ShardFile};

/// `tetherbot mission`: run a mission or a mission campaign (or one shard of it), or merge the shards' files.
#[derive(Debug, Clone, clap::Args)]
#[command(args_conflicts_with_subcommands = true)]
pub struct MissionCli {
    /// `merge`, or nothing to run missions.
    #[command(subcommand)]
    pub command: Option<MissionCommand>,
    /// The mission(s) to run.
    #[command(flatten)]
    pub run: MissionArgs,
}

/// Subcommands of `mission`.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum MissionCommand {
    /// Join the files of the N shards of one mission campaign (`--seeds S --shard K/N` runs) into
    /// OUT/<name>-campaign.json (byte for byte the unsharded run's) and OUT/<name>-campaign-timing.json.
    Merge(MissionMergeArgs),
}

/// Arguments of `mission merge`.
#[derive(Debug, Clone, clap::Args)]
pub struct MissionMergeArgs {
    /// Output directory.
    pub out: PathBuf,
    /// Each shard's `<name>-campaign-shard-K-of-N.json` (its `-timing.json` is read from beside it).
    #[arg(required = true, num_args = 1..)]
    pub shards: Vec<PathBuf>,
    /// Replace an existing campaign file in OUT.
    #[arg(long)]
    pub force: bool,
}

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
    /// The (first) seed; mission i of a campaign uses seed + i, which must not pass u64::MAX.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Run only the campaign's missions i with i mod N == K (0 <= K < N, N at most --seeds; default: all); each
    /// keeps its seed, so `mission merge` of the N shards' files gives the unsharded campaign file.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
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
    /// Falls are judged by the physics judge (rapier3d, `host-sim/src/physics`): after every motion it holds the
    /// rover at its true pose with the true tether, and a pose it cannot hold is a fall; where the simple statics
    /// cannot hold an increment, the judge decides (a pose it holds goes on, counted). Sets the scenario's
    /// `[mission] physics_falls`.
    #[arg(long)]
    pub physics_falls: bool,
    /// Fault the link with this profile: `KIND=RATE,...` per byte on the uplink (kinds bitflip, drop, duplicate,
    /// reorder, truncate, delay, stall; `all=RATE`), `down.KIND=RATE` (`down.all=`) on the downlink, `delay_us=`, `stall_us=`, `reorder_hold_us=`, `seed=`. Replaces the
    /// scenario's `[faults]` section (`--faults none`: a clean link whatever the scenario says).
    #[arg(long, value_name = "PROFILE", value_parser = FaultProfile::parse)]
    pub faults: Option<FaultProfile>,
    /// Run the fault campaign: each of --fault-rates for each of --fault-kinds, --seeds missions each (in-process);
    /// --faults, if given, sets the delays and the seed.
    #[arg(long)]
    pub fault_campaign: bool,
    /// Rates per byte of the fault campaign.
    #[arg(long, value_delimiter = ',', default_values_t = crate::mission::faults::DEFAULT_RATES)]
    pub fault_rates: Vec<f64>,
    /// Kinds of the fault campaign (default: all).
    #[arg(long, value_delimiter = ',', value_parser = parse_kind)]
    pub fault_kinds: Vec<FaultKind>,
    /// The fault campaign faults the downlink (flight -> host; the host detects) instead of the uplink.
    #[arg(long)]
    pub fault_downlink: bool,
    /// In-process: the executive measures its steps in host time (cycle accounting in telemetry); the log of such
    /// a run does not replay byte for byte.
    #[arg(long)]
    pub charge_host_time: bool,
    /// Reset the flight computer once, after this many motions (issue 24 item 2): it must come back safe, recover
    /// its tether state from retained memory and continue when the ground configures it again. One mission only.
    #[arg(long, value_name = "N", conflicts_with = "reset_when_wrapped")]
    pub reset_after_motions: Option<u32>,
    /// Reset the flight computer once, after the first motion that leaves the tether wrapped (the simulator's true
    /// tether touches the terrain and the flight software tracks an anchor besides the root); no reset if it never
    /// wraps. One mission only.
    #[arg(long, conflicts_with = "watchdog_bite_in_motion")]
    pub reset_when_wrapped: bool,
    /// The flight computer's watchdog bites once, during the motion after N executed motions (the rover stops
    /// where it is, the motion's report is lost): on the emulated board the CMSDK watchdog reboots it; in-process
    /// the flight software is reset. One mission only.
    #[arg(long, value_name = "N", conflicts_with = "reset_after_motions")]
    pub watchdog_bite_in_motion: Option<u32>,
    /// The watchdog bites once, during the first motion that starts with the tether wrapped (as
    /// `--reset-when-wrapped` judges it); no bite if it never wraps. One mission only.
    #[arg(long, conflicts_with_all = ["reset_after_motions", "reset_when_wrapped", "watchdog_bite_in_motion"])]
    pub watchdog_bite_when_wrapped: bool,
    /// Serve the running mission to the Foxglove app over the Foxglove SDK's WebSocket server at HOST:PORT
    /// (default 127.0.0.1:8765; port 0 picks a free one); one seed only. The line `live view: ws://HOST:PORT`
    /// on stdout names the address.
    #[arg(long, value_name = "HOST:PORT", num_args = 0..=1, default_missing_value = "127.0.0.1:8765")]
    pub live: Option<String>,
    /// With `--live`: seconds to wait for a viewer to subscribe before the mission starts, and for the viewers
    /// to disconnect after it ends (the server then stops).
    #[arg(long, default_value_t = 120.0, value_name = "SECONDS")]
    pub live_wait: f64,
}

fn parse_kind(s: &str) -> Result<FaultKind, String> {
    FaultKind::ALL
        .iter()
        .copied()
        .find(|k| k.name() == s)
        .ok_or_else(|| {
            let names: Vec<&str> = FaultKind::ALL.iter().map(|k| k.name()).collect();
            format!("unknown fault kind `{s}` (kinds: {})", names.join(", "))
        })
}

/// The live view of one mission: the scene's channels in a context whose sink is the WebSocket server.
struct Live {
    server: foxglove::WebSocketServerHandle,
    scene: crate::mcap_export::Scene,
    /// Keeps the channels' context alive while the server runs.
    _ctx: std::sync::Arc<foxglove::Context>,
}

/// Starts the WebSocket server at `addr` (HOST:PORT) and prints its address.
fn start_live(addr: &str) -> Result<Live, String> {
    let (host, port) = addr
        .rsplit_once(':')
        .and_then(|(h, p)| Some((h.trim_matches(['[', ']']), p.parse::<u16>().ok()?)))
        .ok_or_else(|| format!("--live {addr}: expected HOST:PORT, such as 127.0.0.1:8765"))?;
    let ctx = foxglove::Context::new();
    let scene = crate::mcap_export::Scene::new(&ctx).map_err(|e| format!("live view: {e}"))?;
    let server = ctx
        .websocket_server()
        .name("tetherbot mission")
        .bind(host, port)
        .start_blocking()
        .map_err(|e| format!("live view: cannot serve on {addr}: {e}"))?;
    println!("live view: ws://{host}:{} (Foxglove: Open connection, Foxglove WebSocket)", server.port());
    let _ = std::io::Write::flush(&mut std::io::stdout());
    Ok(Live { server, scene, _ctx: ctx })
}

/// Waits up to `secs` of wall time while `busy` holds, looking every 50 ms.
fn wait_while(secs: f64, busy: impl Fn() -> bool) {
    let t0 = std::time::Instant::now();
    while busy() && t0.elapsed().as_secs_f64() < secs {
        std::thread::sleep(core::time::Duration::from_millis(50));
    }
}

/// Loads the scenario of `args` (the embedded default when none is given).
pub fn load_scenario(path: Option<&Path>) -> Result<Scenario, scenario::ScenarioError> {
    match path {
        Some(p) => scenario::load(p),
        None => {
            let file = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
                .join("scenarios")
                .join(DEFAULT_SCENARIO_FILE);
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
    if let Some(w) = rep.flight_warning.as_ref().filter(|_| !matches!(rep.verdict, Verdict::Arrived)) {
        s.push_str(&format!("  flight software's last warning: {w}\n"));
    }
    s.push_str(&format!(
        "  truth: {:.2} m driven, {:.2} m from the goal (tolerance {:.2} m), {} motions ({} stalled, {} slipped)\n",
        rep.distance_m, rep.goal_error_m, rep.tolerance_m, rep.motions, rep.stalls, rep.slips
    ));
    s.push_str(&format!(
        "  min true margin {:.1} N, max tension {:.0} N, max payout {:.2} m, cross-track from the plan {:.3} m mean / {:.3} m max\n",
        rep.min_true_margin_n, rep.max_tension_n, rep.max_payout_m, rep.mean_cross_track_m, rep.max_cross_track_m
    ));
    if rep.truth_tether_fallbacks > 0 {
        s.push_str(&format!(
            "  true tether: {} increments fell back from the taut tether to the closed forms or the vertical profile\n",
            rep.truth_tether_fallbacks
        ));
    }
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
    for r in &rep.resets {
        s.push_str(&format!(
            "  reset ({}) at t {:.1} s after {} motions: {} anchors tracked before, {} recovered ({}); true tether {} contacts\n",
            r.cause, r.t_s, r.after_motions, r.anchors_before, r.anchors_recovered, r.reason, r.true_contacts
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
    let name = sc.file_safe_name();
    let log_path = args.log.clone().unwrap_or_else(|| args.out.join(format!("{name}.fieldlog")));
    let opts = MissionOptions {
        seed: args.seed,
        tracking: args.tracking.into(),
        noiseless: false,
        live: !args.quiet,
        reset: match (args.reset_after_motions, args.reset_when_wrapped, args.watchdog_bite_in_motion) {
            (Some(n), _, _) => Some(ResetAt::Motions(n)),
            (None, true, _) => Some(ResetAt::Wrapped),
            (None, false, Some(n)) => Some(ResetAt::BiteInMotion(n)),
            (None, false, None) if args.watchdog_bite_when_wrapped => Some(ResetAt::BiteWhenWrapped),
            (None, false, None) => None,
        },
    };
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
    let world = crate::mission::run::truth_for(sc, &crate::mission::run::mission_configure(sc, &opts), &sc.mission)?;
    let mut live = match &args.live {
        Some(addr) => {
            let live = start_live(addr)?;
            println!("  waiting up to {:.0} s for a viewer to subscribe", args.live_wait);
            let t0 = std::time::Instant::now();
            wait_while(args.live_wait, || !live.scene.subscribed());
            if live.scene.subscribed() {
                println!("  a viewer subscribed after {:.1} s; the mission starts", t0.elapsed().as_secs_f64());
            } else {
                println!("  no viewer subscribed; the mission starts");
            }
            let pts = [sc.tether.root_anchor, sc.rover.start, sc.goal.position];
            live.scene.terrain(&world.world.truth(), &pts, 0);
            Some(live)
        }
        None => None,
    };
    let file = std::fs::File::create(&log_path)
        .map_err(|e| format!("cannot create {}: {e}", log_path.display()))?;
    let writer = Writer::new(std::io::BufWriter::new(file), &header)?;
    let run = |link: &mut dyn FlightLink| -> Result<MissionReport, Box<dyn core::error::Error>> {
        let mut shown;
        let link: &mut dyn FlightLink = match live.as_mut() {
            Some(l) => {
                shown = SceneLink::new(link, &mut l.scene);
                &mut shown
            }
            None => link,
        };
        let rec = RecordingLink::new(link, writer);
        // The recorder inside the injector: the log holds what the flight software received, and the faults.
        let Some(profile) = args.faults.as_ref().filter(|p| p.any()) else {
            let mut rec = rec;
            let rep = run_mission(&mut rec, sc, &opts)?;
            rec.finish()?;
            return Ok(rep);
        };
        let mut faulty = FaultLink::new(rec, profile.clone());
        let rep = run_mission(&mut faulty, sc, &opts)?;
        let acc = faulty.account().with_host(rep.downlink, &rep.command_seqs);
        print!("{}", fault_summary(&acc));
        faulty.into_inner().finish()?;
        Ok(rep)
    };
    let rep = match args.link {
        LinkKind::Inproc => {
            let mut link = crate::mission::link::mission_link(sc)?;
            link.charge_host_time(args.charge_host_time);
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
    if let Some(mut l) = live {
        l.scene.truth(&rep, &world.world.truth());
        println!("  mission over; serving until the viewers disconnect (at most {:.0} s)", args.live_wait);
        wait_while(args.live_wait, || l.server.client_count() > 0);
        l.server.stop().wait_blocking();
    }
    let mut written = vec![log_path.clone()];
    let log = fieldlog::read_file(&log_path)?;
    let mcap_path = args.out.join(format!("{name}.mcap"));
    let f = std::fs::File::create(&mcap_path).map_err(|e| format!("cannot create {}: {e}", mcap_path.display()))?;
    crate::mcap_export::export_with(&log, Some((&rep, &world.world.truth())), std::io::BufWriter::new(f))?;
    written.push(mcap_path);
    let svg_path = args.out.join(format!("{name}.svg"));
    std::fs::write(&svg_path, crate::mission::svg::render(&rep, &world.world.truth()))?;
    written.push(svg_path);
    let json_path = args.out.join(format!("{name}.json"));
    std::fs::write(&json_path, serde_json::to_string_pretty(&rep)?)?;
    written.push(json_path);
    Ok((rep, written))
}

/// The identity of the campaign `args` asks for on `sc`.
fn identity(args: &MissionArgs, sc: &Scenario) -> Result<CampaignIdentity, String> {
    let (scenario, text) = match &args.scenario {
        Some(p) => (
            p.display().to_string(),
            std::fs::read(p).map_err(|e| format!("{}: {e}", p.display()))?,
        ),
        None => (
            "(default)".to_string(),
            DEFAULT_SCENARIO.as_bytes().to_vec(),
        ),
    };
    Ok(CampaignIdentity {
        scenario,
        scenario_name: sc.name.clone(),
        scenario_fingerprint: shard::fingerprint(&text),
        seeds: args.seeds,
        first_seed: args.seed,
        tracking: format!("{:?}", Tracking::from(args.tracking)),
    })
}

/// The campaign file's path for `name` (the scenario's name, made one safe path component) and `shard`, and its
/// timing file's.
pub fn campaign_paths(out: &Path, name: &str, shard: Option<Shard>) -> (PathBuf, PathBuf) {
    let stem = match shard {
        Some(s) => format!("{}-campaign-shard-{}-of-{}", scenario::file_safe(name), s.index, s.count),
        None => format!("{}-campaign", scenario::file_safe(name)),
    };
    (out.join(format!("{stem}.json")), out.join(format!("{stem}-timing.json")))
}

/// One mission's line of a campaign's listing.
fn row_line(r: &MissionRow) -> String {
    let f = |x: Option<f64>, w: usize, p: usize| x.map_or(format!("{:>w$}", "-"), |v| format!("{v:w$.p$}"));
    let line = format!(
        "  seed {:>4}: {:<28} {} m, {} replans, min margin {} N, goal error {} m",
        r.seed,
        r.verdict,
        f(r.distance_m, 6, 2),
        r.replans,
        f(r.min_true_margin_n, 7, 1),
        f(r.goal_error_m, 0, 2)
    );
    match &r.flight_warning {
        Some(w) => format!("{line}\n             flight software: {w}"),
        None => line,
    }
}

/// Whether a campaign file holds a fall, a false arrival or a mission that could not run.
fn campaign_failed(f: &CampaignFile) -> bool {
    !f.failed.is_empty() || f.missions.iter().any(|r| r.verdict == Verdict::Fell.name() || r.verdict == Verdict::FalseArrival.name())
}

fn write_campaign(json: &Path, timing_path: &Path, file: &CampaignFile, timing: &CampaignTiming) -> Result<(), String> {
    let write = |p: &Path, text: Result<String, serde_json::Error>| {
        std::fs::write(p, text.map_err(|e| e.to_string())?).map_err(|e| format!("cannot write {}: {e}", p.display()))
    };
    write(json, serde_json::to_string_pretty(file))?;
    write(timing_path, serde_json::to_string_pretty(timing))?;
    println!("  wrote {}", json.display());
    println!("  wrote {}", timing_path.display());
    Ok(())
}

/// Runs the campaign (or its shard) and writes its files; `Ok(true)` when no mission fell, arrived falsely or
/// could not run.
fn campaign(args: &MissionArgs, sc: &Scenario) -> Result<bool, String> {
    if args.link != LinkKind::Inproc {
        return Err(
            "a campaign (--seeds > 1) runs in-process; run one seed at a time on the board".into(),
        );
    }
    let shard = args.shard.unwrap_or(Shard::WHOLE);
    let seeds = crate::mission::campaign::shard_seeds(args.seed, args.seeds, shard)?;
    let identity = identity(args, sc)?;
    std::fs::create_dir_all(&args.out)
        .map_err(|e| format!("cannot create {}: {e}", args.out.display()))?;
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let t0 = std::time::Instant::now();
    let bar = indicatif::ProgressBar::new(seeds.len() as u64);
    let tick = |_: &MissionReport| bar.inc(1);
    let results = crate::mission::campaign::run_seeds(
        sc,
        &seeds,
        args.tracking.into(),
        threads,
        args.faults.as_ref().filter(|p| p.any()),
        args.charge_host_time,
        &tick,
    );
    bar.finish_and_clear();
    let mut reports = Vec::new();
    let mut failed = Vec::new();
    for (seed, r) in seeds.iter().zip(results) {
        match r {
            Ok((rep, acc)) => {
                if let Some(acc) = acc {
                    print!("seed {seed}: {}", fault_summary(&acc));
                }
                reports.push(rep)
            }
            Err(e) => {
                eprintln!("seed {seed}: could not run: {e}");
                failed.push(crate::mission::campaign::FailedMission {
                    seed: *seed,
                    error: e,
                });
            }
        }
    }
    let shard = (!shard.is_whole()).then_some(shard);
    let file = CampaignFile {
        campaign: identity,
        shard,
        missions: reports.iter().map(MissionRow::of).collect(),
        failed,
    };
    let timing = CampaignTiming {
        runs: vec![RunTiming {
            shard,
            threads,
            wall_s: t0.elapsed().as_secs_f64(),
            map_build_s: None,
        }],
        missions: reports
            .iter()
            .map(|r| MissionTiming {
                seed: r.seed,
                host_s: r.host_s,
            })
            .collect(),
    };
    for r in &file.missions {
        println!("{}", row_line(r));
    }
    if let Some(s) = shard {
        println!(
            "shard {s} of the campaign: missions i (seed {} + i) with i mod {} == {}",
            args.seed, s.count, s.index
        );
    }
    print!("{}", crate::mission::campaign::table(&sc.name, &reports));
    let (json, timing_path) = campaign_paths(&args.out, &sc.name, shard);
    write_campaign(&json, &timing_path, &file, &timing)?;
    Ok(!campaign_failed(&file) && reports.len() == seeds.len())
}

/// The fault accounting of one mission, one line per kind injected in each direction.
fn fault_summary(acc: &crate::link::faults::FaultAccount) -> String {
    use crate::link::faults::DetectionGroup;
    let mut s = String::new();
    for d in [LinkDirection::Up, LinkDirection::Down] {
        let (injected, harmless, by) = match d {
            LinkDirection::Up => (&acc.injected, &acc.harmless, "telemetry"),
            LinkDirection::Down => (&acc.down_injected, &acc.down_harmless, "the host"),
        };
        if injected.iter().all(|&n| n == 0) {
            continue;
        }
        for (k, (inj, h)) in FaultKind::ALL.iter().zip(injected.iter().zip(harmless)) {
            if *inj > 0 {
                s.push_str(&format!("  {} faults {:<9} injected {inj}, harmless {h}\n", d.name(), k.name()));
            }
        }
        for g in DetectionGroup::ALL {
            let (inj, h) = acc.totals_in(d, g);
            let detected = match d {
                LinkDirection::Up => acc.detected(g),
                LinkDirection::Down => acc.down_detected(g),
            };
            if let Some(det) = detected {
                s.push_str(&format!("  detected by {by} ({g:?}): {det} (injected {inj} = detected {det} + harmless {h}?)\n"));
            }
        }
    }
    if acc.down_injected.iter().any(|&n| n > 0) {
        s.push_str(&format!("  drive commands executed from damaged downlink frames: {}\n", acc.executed_damaged));
    }
    if let Some(t) = &acc.telemetry {
        s.push_str(&format!(
            "  flight software: resent requests answered without acting {}, drive commands resent {}\n",
            t.requests_repeated, t.drive_resends
        ));
    }
    s.push_str(&match acc.check() {
        Ok(()) => format!(
            "  fault accounting balanced; {} damaged frames acknowledged\n",
            acc.acked_damaged
        ),
        Err(e) => format!("  FAULT ACCOUNTING UNBALANCED: {e}\n"),
    });
    s
}

/// `--fault-campaign`: the table (`mission::faults`); `Ok(true)` when every mission ended arrived or safe with
/// balanced accounting and no damaged frame acknowledged.
fn fault_campaign(args: &MissionArgs, sc: &Scenario) -> Result<bool, String> {
    if args.link != LinkKind::Inproc {
        return Err(
            "a fault campaign runs in-process; use --faults with one seed on the board".into(),
        );
    }
    let seeds = crate::mission::campaign::shard_seeds(args.seed, args.seeds, Shard::WHOLE)?;
    let kinds = if args.fault_kinds.is_empty() {
        FaultKind::ALL.to_vec()
    } else {
        args.fault_kinds.clone()
    };
    if let Some(r) = args.fault_rates.iter().find(|r| !(0.0..=1.0).contains(*r)) {
        return Err(format!(
            "--fault-rates: {r} is not a rate per byte in [0, 1]"
        ));
    }
    let base = args.faults.clone().unwrap_or_default();
    let threads = args
        .threads
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let t0 = std::time::Instant::now();
    let bar =
        indicatif::ProgressBar::new((seeds.len() * kinds.len() * args.fault_rates.len()) as u64);
    let tick = || bar.inc(1);
    let cells = crate::mission::faults::run(
        sc,
        &seeds,
        &args.fault_rates,
        &kinds,
        &base,
        if args.fault_downlink { LinkDirection::Down } else { LinkDirection::Up },
        args.tracking.into(),
        threads,
        args.charge_host_time,
        &tick,
    );
    bar.finish_and_clear();
    print!(
        "{}",
        crate::mission::faults::table(&sc.name, &seeds, &cells)
    );
    println!(
        "host time {:.0} s on {threads} threads",
        t0.elapsed().as_secs_f64()
    );
    Ok(crate::mission::faults::passed(&cells))
}

/// `mission merge`: checks that the files are the N shards of one mission campaign ([`shard::check_set`]), joins
/// them ([`crate::mission::campaign::merge`]), writes `OUT/<name>-campaign.json` and its timing file, and prints
/// the missions. Returns the merged file.
pub fn merge(m: &MissionMergeArgs) -> Result<CampaignFile, String> {
    let mut files = Vec::new();
    for path in &m.shards {
        let f: CampaignFile = shard::read_json(
            path,
            "a mission campaign shard's <name>-campaign-shard-K-of-N.json",
        )?;
        let Some(sh) = f.shard else {
            return Err(format!(
                "{}: the file of a whole campaign (no \"shard\" field), not a shard's: merge the files of --shard K/N runs",
                path.display()
            ));
        };
        files.push(ShardFile {
            path: path.clone(),
            identity: f.campaign.clone(),
            shard: sh,
            body: f,
        });
    }
    let files = shard::check_set(files)?;
    let count = files.len();
    let (json, timing_path) = campaign_paths(&m.out, &files[0].identity.scenario_name, None);
    let inputs: Vec<&Path> = files.iter().map(|f| f.path.as_path()).collect();
    super::check_output(&json, m.force, &inputs)?;
    let mut timing = CampaignTiming::default();
    for f in &files {
        let tp = PathBuf::from(f.path.to_string_lossy().trim_end_matches(".json").to_string() + "-timing.json");
        match shard::read_json::<CampaignTiming>(&tp, "a mission campaign's timing file") {
            Ok(t) => {
                timing.runs.extend(t.runs);
                timing.missions.extend(t.missions);
            }
            Err(e) => eprintln!("note: no timing for shard {}: {e}", f.shard),
        }
    }
    timing.missions.sort_by_key(|t| t.seed);
    let merged = crate::mission::campaign::merge(files)?;
    std::fs::create_dir_all(&m.out).map_err(|e| format!("cannot create {}: {e}", m.out.display()))?;
    for r in &merged.missions {
        println!("{}", row_line(r));
    }
    for f in &merged.failed {
        println!("  seed {:>4}: could not run: {}", f.seed, f.error);
    }
    let arrived = merged.missions.iter().filter(|r| r.verdict == Verdict::Arrived.name()).count();
    let fell = merged.missions.iter().filter(|r| r.verdict == Verdict::Fell.name()).count();
    println!(
        "merged {count} shards of mission campaign {}: {} missions, {arrived} arrived, {fell} fell, {} could not run",
        merged.campaign.scenario_name,
        merged.campaign.seeds,
        merged.failed.len()
    );
    write_campaign(&json, &timing_path, &merged, &timing)?;
    Ok(merged)
}

/// `tetherbot mission ...` entry point.
pub fn cli_main(c: &MissionCli) -> ExitCode {
    match &c.command {
        Some(MissionCommand::Merge(m)) => match merge(m) {
            Ok(f) if campaign_failed(&f) => ExitCode::from(super::EXIT_FAILED),
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => super::fail(e),
        },
        None => main(&c.run),
    }
}

/// `mission` entry point: exit 0 when every mission arrived or stopped safe with a reason and none fell, 1 on a
/// fall, a false arrival or a campaign's mission that could not run, 2 when it could not run at all.
pub fn main(args: &MissionArgs) -> ExitCode {
    let mut sc = match load_scenario(args.scenario.as_deref()) {
        Ok(s) => s,
        Err(e) => return super::fail(e),
    };
    sc.mission.physics_falls |= args.physics_falls;
    // the scenario's `[faults]` unless --faults replaces it (checked when the scenario was parsed)
    let mut args = args.clone();
    if args.faults.is_none() {
        args.faults = sc.faults.as_ref().and_then(|f| f.profile().ok());
    }
    let args = &args;
    let bad = |v: &Verdict| matches!(v, Verdict::Fell | Verdict::FalseArrival);
    if args.live.is_some() && (args.seeds > 1 || args.shard.is_some()) {
        return super::fail("--live shows one mission: drop --seeds / --shard");
    }
    let resets = args.reset_after_motions.is_some()
        || args.reset_when_wrapped
        || args.watchdog_bite_in_motion.is_some()
        || args.watchdog_bite_when_wrapped;
    if resets && (args.seeds > 1 || args.shard.is_some() || args.fault_campaign) {
        return super::fail("a reset (--reset-after-motions / --reset-when-wrapped / --watchdog-bite-in-motion) is for one mission: drop --seeds / --shard / --fault-campaign");
    }
    if args.fault_campaign {
        return match fault_campaign(args, &sc) {
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::from(super::EXIT_FAILED),
            Err(e) => super::fail(e),
        };
    }
    if args.seeds <= 1 && args.shard.is_none() {
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
            Ok(true) => ExitCode::SUCCESS,
            Ok(false) => ExitCode::from(super::EXIT_FAILED),
            Err(e) => super::fail(e),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_scenario_name_cannot_put_campaign_files_outside_the_output_directory() {
        let out = Path::new("/tmp/mission-out");
        for name in ["../../escape", "/etc/passwd", "..", "a/b"] {
            for shard in [None, Some(Shard { index: 1, count: 4 })] {
                let (json, timing) = campaign_paths(out, name, shard);
                for p in [&json, &timing] {
                    assert_eq!(p.parent(), Some(out), "{name:?}: {}", p.display());
                    assert!(!p.components().any(|c| c == std::path::Component::ParentDir), "{name:?}: {}", p.display());
                }
            }
        }
    }

    #[test]
    fn campaign_seeds_that_pass_u64_max_are_refused_not_wrapped() {
        use crate::mission::campaign::shard_seeds;
        let e = shard_seeds(u64::MAX, 2, Shard::WHOLE).expect_err("wraps");
        assert!(e.contains("passes u64::MAX") && e.contains(&format!("at most {}", u64::MAX - 1)), "{e}");
        assert_eq!(shard_seeds(u64::MAX - 1, 2, Shard::WHOLE), Ok(vec![u64::MAX - 1, u64::MAX]));
        assert_eq!(shard_seeds(10, 5, Shard { index: 1, count: 2 }), Ok(vec![11, 13]));
        assert!(shard_seeds(10, 2, Shard { index: 0, count: 3 }).is_err_and(|e| e.contains("leave a shard empty")));
    }
}
