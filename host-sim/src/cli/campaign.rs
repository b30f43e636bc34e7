//! `tetherbot campaign SCENARIO`: Paton et al.'s Table I for any scenario (see [`crate::campaign`] and
//! `host-sim/doc/campaign.md`); `--shard K/N` runs trials `i` with `i mod N == K` only ([`crate::shard`]), and
//! `tetherbot campaign merge OUT SHARD...` joins the N shards' results into the files the unsharded run writes
//! (`results.json`, `results.csv` and `paths.svg` byte for byte; `timing.json` keeps each shard's wall-clock
//! figures). `merge` is a word the scenario argument cannot take: a scenario file `merge.toml` is given as its path.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use firmware::config::rover::RoverParams;
use firmware::geom::Real;
use firmware::plan::abit::AbitParams;
use firmware::plan::tethered::{PlanBounds, TetherSpaceParams};
use indicatif::{ProgressBar, ProgressStyle};
use serde::{Deserialize, Serialize};

use crate::campaign::{self, CampaignResult, CampaignSpec, CampaignTiming, PlanningField};
use crate::shard::{self, Shard, ShardFile};

/// `tetherbot campaign`: run a campaign (or one shard of it), or merge the shards' results.
#[derive(Debug, Clone, clap::Args)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct CampaignCli {
    /// `merge`, or nothing to run a campaign.
    #[command(subcommand)]
    pub command: Option<CampaignCommand>,
    /// The campaign to run.
    #[command(flatten)]
    pub run: Option<CampaignArgs>,
}

/// Subcommands of `campaign`.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum CampaignCommand {
    /// Join the results of the N shards of one campaign (`--shard K/N` runs) into OUT: results.json, results.csv
    /// and paths.svg as the unsharded run writes them, byte for byte, and timing.json with every shard's timing.
    Merge(MergeArgs),
}

/// Arguments of `campaign merge`.
#[derive(Debug, Clone, clap::Args)]
pub struct MergeArgs {
    /// Output directory.
    pub out: PathBuf,
    /// Each shard's results.json, or the directory that holds it (its timing.json is read from beside it).
    #[arg(required = true, num_args = 1..)]
    pub shards: Vec<PathBuf>,
    /// Replace an existing OUT/results.json.
    #[arg(long)]
    pub force: bool,
}

/// Arguments of `campaign`.
#[derive(Debug, Clone, clap::Args)]
pub struct CampaignArgs {
    /// A scenario name from `host-sim/scenarios/` (e.g. `ledge_test3`) or a path to a `.toml` scenario.
    pub scenario: String,
    /// Trials (default: the scenario's `seeds.trials`).
    #[arg(long)]
    pub trials: Option<u32>,
    /// Planner iterations per trial (default: the scenario's `budgets.planner_iterations`).
    #[arg(long)]
    pub iterations: Option<u32>,
    /// Seed of the first trial (default: the scenario's `seeds.planner`); trial i uses seed + i, which must not
    /// pass u64::MAX.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run only trials i with i mod N == K (0 <= K < N, N at most the trials; default: all, 0/1); each trial keeps
    /// its seed, so `campaign merge` of the N shards gives the unsharded run's files.
    #[arg(long, value_name = "K/N")]
    pub shard: Option<Shard>,
    /// Worker threads (default: the machine's cores).
    #[arg(long)]
    pub threads: Option<usize>,
    /// Voxel edge of the planning map, metres (default: the scenario's `map.voxel_size_m` when it gives one,
    /// else 0.1).
    #[arg(long)]
    pub voxel: Option<f64>,
    /// Plan on the onboard `map` (filled from the world's signed distance) or the exact world (`truth`).
    #[arg(long, default_value = "map")]
    pub field: String,
    /// Output directory for results.json, results.csv, paths.svg and timing.json (default
    /// target/campaign/<scenario>, or target/campaign/<scenario>-shard-K-of-N with --shard).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// ABIT* samples per batch (default: OMPL's 100).
    #[arg(long)]
    pub samples_per_batch: Option<u32>,
    /// ABIT* rewire factor (default: OMPL's 1.1).
    #[arg(long)]
    pub rewire_factor: Option<f64>,
    /// Fraction of new samples that copy a neighbour's anchor history (default `config::abit`'s 0.25).
    #[arg(long)]
    pub copy_fraction: Option<f64>,
    /// Switch off the history twins of `plan::abit` (Paton et al.'s planner has none).
    #[arg(long)]
    pub no_twins: bool,
    /// Switch off the goal edges of `plan::abit` (every vertex queues its edge to the goal; OMPL has none).
    #[arg(long)]
    pub no_goal_edges: bool,
    /// Switch off the revealing edges of `plan::abit` (edges between tree vertices queued because the tether
    /// would catch on something between them; OMPL has none).
    #[arg(long)]
    pub no_reveal: bool,
    /// Fraction of sample draws taken near the edge of a tether shadow, where the tether starts to catch on
    /// terrain (default `config::abit`'s 0.1; 0 switches catch-boundary sampling off; OMPL has none).
    #[arg(long)]
    pub catch_fraction: Option<f64>,
    /// Smallest stability margin of a planned state (default `config::tethered::defaults::MIN_STABILITY_MARGIN`).
    #[arg(long)]
    pub min_margin: Option<f64>,
    /// BIT*'s edge-queue pruning as the paper states it: edges that can no longer improve their child leave the
    /// queue without an iteration (OMPL discards them at the front, one iteration each). Not OMPL's count.
    #[arg(long)]
    pub drop_dead_edges: bool,
    /// Wheel-terrain friction coefficient of the rover, for planning and re-validation alike (default
    /// `RoverParams::AXEL`'s 0.6); a sensitivity knob: the width of test 3's stable corridor depends on it.
    #[arg(long)]
    pub wheel_mu: Option<f32>,
    /// Half-width of the yaw perturbation about the fall line for samples on steep ground, degrees (default
    /// `config::tethered::defaults::FALL_LINE_YAW_SPREAD_RAD`); 180 draws the yaw uniformly, as Paton et al. do.
    #[arg(long)]
    pub yaw_spread_deg: Option<f32>,
    /// Exit with status 1 unless at least this many trials are found stable.
    #[arg(long)]
    pub require_stable: Option<usize>,
    /// Skip the physics judge (rigid bodies on the exact terrain with the true tether); found paths are then
    /// judged by the model-on-truth re-check alone.
    #[arg(long)]
    pub no_physics: bool,
}

impl CampaignArgs {
    /// `scenario` with every option at its default.
    pub fn new(scenario: &str) -> Self {
        Self {
            scenario: scenario.into(),
            trials: None,
            iterations: None,
            seed: None,
            shard: None,
            threads: None,
            voxel: None,
            field: "map".into(),
            out: None,
            samples_per_batch: None,
            rewire_factor: None,
            copy_fraction: None,
            no_twins: false,
            no_goal_edges: false,
            no_reveal: false,
            catch_fraction: None,
            min_margin: None,
            drop_dead_edges: false,
            wheel_mu: None,
            yaw_spread_deg: None,
            require_stable: None,
            no_physics: false,
        }
    }
}

/// Resolve a scenario argument to a file.
pub fn scenario_file(arg: &str) -> PathBuf {
    if arg.ends_with(".toml") {
        PathBuf::from(arg)
    } else {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios").join(format!("{arg}.toml"))
    }
}

/// The paper's Table I row for the ledge tests, for side-by-side printing.
pub fn paper_row(name: &str) -> Option<&'static str> {
    match name {
        "ledge_test1" => Some("paper (Paton et al. Table I): 100 stable / 0 unstable, 0.29 s (0.05), 1 (0) iterations"),
        "ledge_test2" => Some("paper (Paton et al. Table I): 0 stable / 0 unstable"),
        "ledge_test3" => Some("paper (Paton et al. Table I): 84 stable / 0 unstable, 12.8 s (10.3), 188 (141) iterations"),
        _ => None,
    }
}

/// Planning-map voxel of a campaign when neither `--voxel` nor the scenario's `map.voxel_size_m` gives one, metres.
pub const DEFAULT_CAMPAIGN_VOXEL_M: f64 = 0.1;

/// The scenario fields a campaign cannot apply, each with the reason (printed on stderr by the command, so a
/// field is never silently ignored): the planning map is filled from the world's true signed distance
/// (Paton et al. VI-A), so no `[sensor]` is simulated and the TSDF's own parameters do not enter; ABIT* (as
/// OMPL's BIT*) plans to the goal state itself, so a goal radius does not change the search.
pub fn unused_scenario_fields(sc: &crate::scenario::Scenario) -> Vec<String> {
    let mut out = Vec::new();
    if sc.gives("sensor") {
        out.push("[sensor] does not apply to campaign: the planning map is filled from the world's true signed distance, not from scans (map-check uses it)".to_string());
    }
    for f in ["map.truncation_m", "map.esdf_max_distance_m"] {
        if sc.gives(f) {
            out.push(format!("{f} does not apply to campaign: the planning map holds exact distances (truncation 3 voxels, ESDF cap 1.5 m) (map-check uses it)"));
        }
    }
    if sc.faults.is_some() {
        out.push("[faults] does not apply to campaign: it plans on the world with no link (tetherbot mission uses it)".to_string());
    }
    if sc.gives("goal.tolerance_m") {
        out.push(format!(
            "goal.tolerance_m ({}) does not apply to campaign: ABIT* plans to the goal state itself (OMPL's GoalState sample), so the radius does not change the search",
            sc.goal.tolerance_m
        ));
    }
    out
}

/// Build the campaign spec from a scenario and the arguments. Every option is checked here, before any work,
/// with the reason in the error.
pub fn spec_from(a: &CampaignArgs) -> Result<CampaignSpec, String> {
    let file = scenario_file(&a.scenario);
    let sc = crate::scenario::load(&file).map_err(|e| e.to_string())?;
    spec_from_scenario(&sc, a)
}

/// [`spec_from`] on a loaded scenario.
pub fn spec_from_scenario(sc: &crate::scenario::Scenario, a: &CampaignArgs) -> Result<CampaignSpec, String> {
    let world = sc.build_world().map_err(|e| e.to_string())?;
    let wb = world.bounds();
    let lo = sc.plan.bounds_min.unwrap_or([f64::from(wb.min.x), f64::from(wb.min.y), f64::from(wb.min.z) - 1.0]);
    let hi = sc.plan.bounds_max.unwrap_or([f64::from(wb.max.x), f64::from(wb.max.y), f64::from(wb.max.z) + 1.0]);
    let bounds = PlanBounds {
        min: [lo[0] as Real, lo[1] as Real, lo[2] as Real],
        max: [hi[0] as Real, hi[1] as Real, hi[2] as Real],
    };
    let field = match a.field.as_str() {
        "map" => PlanningField::Map,
        "truth" => PlanningField::Truth,
        f => return Err(format!("--field {f:?}: use map or truth")),
    };
    let voxel = match a.voxel {
        Some(v) => v,
        None if sc.gives("map.voxel_size_m") => sc.map.voxel_size_m,
        None => DEFAULT_CAMPAIGN_VOXEL_M,
    };
    if !(voxel > 0.0 && voxel.is_finite()) {
        return Err(format!("--voxel {voxel}: must be > 0"));
    }
    let trials = a.trials.unwrap_or(sc.seeds.trials);
    if trials == 0 {
        return Err("--trials must be at least 1".into());
    }
    let iterations = a.iterations.unwrap_or(sc.budgets.planner_iterations);
    if iterations == 0 {
        return Err("--iterations must be at least 1".into());
    }
    let first_seed = a.seed.unwrap_or(sc.seeds.planner);
    if first_seed.checked_add(u64::from(trials - 1)).is_none() {
        return Err(format!(
            "--seed {first_seed} with --trials {trials}: trial i uses seed {first_seed} + i, which passes u64::MAX; \
             use a seed of at most {}",
            u64::MAX - u64::from(trials - 1)
        ));
    }
    let mut abit = AbitParams::ompl_defaults();
    if let Some(n) = a.samples_per_batch {
        abit.samples_per_batch = n;
    }
    if let Some(r) = a.rewire_factor {
        abit.rewire_factor = r;
    }
    if let Some(f) = a.copy_fraction {
        abit.attachment_copy_fraction = f;
    }
    abit.history_twins = !a.no_twins;
    abit.drop_dead_edges = a.drop_dead_edges;
    abit.goal_edges = !a.no_goal_edges;
    abit.reveal_attachments = !a.no_reveal;
    if let Some(f) = a.catch_fraction {
        abit.catch_sample_fraction = f;
    }
    abit.validate().map_err(|e| {
        let why = match e {
            firmware::plan::space::InvalidInput::Parameter(p) => p.to_string(),
            other => format!("{other:?}"),
        };
        format!(
            "planner parameters: {why} (--samples-per-batch {:?}, --rewire-factor {:?}, --copy-fraction {:?}, --catch-fraction {:?})",
            a.samples_per_batch, a.rewire_factor, a.copy_fraction, a.catch_fraction
        )
    })?;
    let mut params = TetherSpaceParams::DEFAULT;
    if let Some(m) = a.min_margin {
        params.min_stability_margin = m;
    }
    if let Some(d) = a.yaw_spread_deg {
        params.fall_line_yaw_spread_rad = d.to_radians();
    }
    params.validate().map_err(|(f, r)| format!("{f}: {r}"))?;
    let mut rover = RoverParams::AXEL;
    if let Some(mu) = a.wheel_mu {
        if !(mu > 0.0 && mu.is_finite()) {
            return Err(format!("--wheel-mu {mu}: must be > 0"));
        }
        rover.wheel_mu = mu;
    }
    let shard = a.shard.unwrap_or(Shard::WHOLE);
    shard.check_fits(trials, "trials")?;
    let threads = a.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get())).max(1);
    Ok(CampaignSpec {
        name: sc.name.clone(),
        world,
        root: sc.tether.root_anchor,
        start: sc.rover.start,
        start_yaw_deg: sc.rover.yaw_deg,
        goal: sc.goal.position,
        goal_tolerance_m: sc.goal.tolerance_m,
        bounds,
        voxel_m: voxel,
        pool_blocks: sc.gives("map.pool_blocks").then_some(sc.map.pool_blocks),
        tether_length_m: sc.tether.length_m,
        iterations,
        trials,
        first_seed,
        shard,
        threads,
        field,
        params,
        rover,
        abit,
        physics_judge: !a.no_physics,
    })
}

/// What makes two runs the same campaign (recorded as `campaign` in `results.json`): the scenario as given and
/// the fingerprint of its file's bytes, the resolved counts and seeds, and every option that changes a trial's
/// result. Not in it: `--threads`, `--out`, `--shard` and `--require-stable` (they change no trial).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignIdentity {
    /// The scenario argument (a name from `host-sim/scenarios/` or a path).
    pub scenario: String,
    /// [`shard::fingerprint`] of the scenario file.
    pub scenario_fingerprint: String,
    /// Trials of the whole campaign.
    pub trials: u32,
    /// Seed of trial 0.
    pub first_seed: u64,
    /// Planner iterations per trial.
    pub iterations: u32,
    /// `--field`.
    pub field: String,
    /// Planning-map voxel, metres.
    pub voxel_m: f64,
    /// `--samples-per-batch`.
    pub samples_per_batch: Option<u32>,
    /// `--rewire-factor`.
    pub rewire_factor: Option<f64>,
    /// `--copy-fraction`.
    pub copy_fraction: Option<f64>,
    /// `--no-twins`.
    pub no_twins: bool,
    /// `--no-goal-edges`.
    pub no_goal_edges: bool,
    /// `--no-reveal`.
    pub no_reveal: bool,
    /// `--catch-fraction`.
    pub catch_fraction: Option<f64>,
    /// `--min-margin`.
    pub min_margin: Option<f64>,
    /// `--drop-dead-edges`.
    pub drop_dead_edges: bool,
    /// `--wheel-mu`.
    pub wheel_mu: Option<f32>,
    /// `--yaw-spread-deg`.
    pub yaw_spread_deg: Option<f32>,
    /// `--no-physics`.
    pub no_physics: bool,
}

impl CampaignIdentity {
    /// The identity of the campaign `a` asks for, with the counts and seeds `spec` resolved.
    pub fn of(a: &CampaignArgs, spec: &CampaignSpec, scenario_bytes: &[u8]) -> CampaignIdentity {
        CampaignIdentity {
            scenario: a.scenario.clone(),
            scenario_fingerprint: shard::fingerprint(scenario_bytes),
            trials: spec.trials,
            first_seed: spec.first_seed,
            iterations: spec.iterations,
            field: a.field.clone(),
            voxel_m: spec.voxel_m,
            samples_per_batch: a.samples_per_batch,
            rewire_factor: a.rewire_factor,
            copy_fraction: a.copy_fraction,
            no_twins: a.no_twins,
            no_goal_edges: a.no_goal_edges,
            no_reveal: a.no_reveal,
            catch_fraction: a.catch_fraction,
            min_margin: a.min_margin,
            drop_dead_edges: a.drop_dead_edges,
            wheel_mu: a.wheel_mu,
            yaw_spread_deg: a.yaw_spread_deg,
            no_physics: a.no_physics,
        }
    }

    /// The arguments that run this campaign again (whole, on the machine's cores).
    pub fn args(&self) -> CampaignArgs {
        CampaignArgs {
            trials: Some(self.trials),
            iterations: Some(self.iterations),
            seed: Some(self.first_seed),
            voxel: Some(self.voxel_m),
            field: self.field.clone(),
            samples_per_batch: self.samples_per_batch,
            rewire_factor: self.rewire_factor,
            copy_fraction: self.copy_fraction,
            no_twins: self.no_twins,
            no_goal_edges: self.no_goal_edges,
            no_reveal: self.no_reveal,
            catch_fraction: self.catch_fraction,
            min_margin: self.min_margin,
            drop_dead_edges: self.drop_dead_edges,
            wheel_mu: self.wheel_mu,
            yaw_spread_deg: self.yaw_spread_deg,
            no_physics: self.no_physics,
            ..CampaignArgs::new(&self.scenario)
        }
    }
}

/// `results.json`: the campaign's identity, then its result (a shard's carries `shard`).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct ResultsFile {
    /// Which campaign.
    pub campaign: CampaignIdentity,
    /// The result.
    #[serde(flatten)]
    pub result: CampaignResult,
}

/// `tetherbot campaign ...` entry point.
pub fn cli_main(c: &CampaignCli) -> ExitCode {
    match (&c.command, &c.run) {
        (Some(CampaignCommand::Merge(m)), _) => match merge(m) {
            Ok(_) => ExitCode::SUCCESS,
            Err(e) => super::fail(e),
        },
        (None, Some(a)) => main(a),
        (None, None) => super::fail("campaign needs a SCENARIO (or `campaign merge OUT SHARD...`); see `tetherbot campaign --help`"),
    }
}

/// Run the command.
pub fn main(a: &CampaignArgs) -> ExitCode {
    match run(a) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => super::fail(e),
    }
}

/// Writes a campaign's files into `out`: `results.json`, `results.csv`, `paths.svg` (when drawn) and
/// `timing.json`.
fn write_outputs(out: &Path, file: &ResultsFile, timing: &CampaignTiming, svg: Option<&str>) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let write = |name: &str, text: &str| {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("results.json", &serde_json::to_string_pretty(file).map_err(|e| e.to_string())?)?;
    write("results.csv", &file.result.csv())?;
    if let Some(svg) = svg {
        write("paths.svg", svg)?;
    }
    write("timing.json", &serde_json::to_string_pretty(timing).map_err(|e| e.to_string())?)?;
    let names = if svg.is_some() { "results.json,results.csv,paths.svg,timing.json" } else { "results.json,results.csv,timing.json" };
    println!("wrote {}/{{{names}}}", out.display());
    Ok(())
}

fn run(a: &CampaignArgs) -> Result<bool, String> {
    let file = scenario_file(&a.scenario);
    let sc = crate::scenario::load(&file).map_err(|e| e.to_string())?;
    let spec = spec_from_scenario(&sc, a)?;
    let bytes = std::fs::read(&file).map_err(|e| format!("{}: {e}", file.display()))?;
    let identity = CampaignIdentity::of(a, &spec, &bytes);
    for note in unused_scenario_fields(&sc) {
        eprintln!("note: {note}");
    }
    let bar = ProgressBar::new(spec.shard.indices(spec.trials).len() as u64);
    if let Ok(style) = ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} trials, {elapsed} elapsed, eta {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(if spec.shard.is_whole() { spec.name.clone() } else { format!("{} shard {}", spec.name, spec.shard) });
    let result = campaign::run(&spec, &|done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    if !spec.shard.is_whole() {
        println!("shard {} of the campaign: trials i with i mod {} == {}", spec.shard, spec.shard.count, spec.shard.index);
    }
    print!("{}", result.table());
    if let Some(p) = paper_row(&result.name) {
        println!("{p}");
    }
    let out = a.out.clone().unwrap_or_else(|| {
        // The name comes from the scenario file: made one safe path component, so it cannot leave target/campaign.
        let mut dir = crate::scenario::file_safe(&result.name);
        if !spec.shard.is_whole() {
            dir += &format!("-shard-{}-of-{}", spec.shard.index, spec.shard.count);
        }
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/campaign").join(dir)
    });
    let svg = campaign::paths_svg(spec.world.as_ref(), &spec, &result);
    let timing = result.timing();
    let stable = result.found_stable();
    write_outputs(&out, &ResultsFile { campaign: identity, result }, &timing, Some(&svg))?;
    Ok(a.require_stable.is_none_or(|n| stable >= n))
}

/// `campaign merge`: checks that the files are the N shards of one campaign ([`shard::check_set`],
/// [`campaign::merge`]), then writes the merged files into `m.out` and prints the table. `paths.svg` needs the
/// scenario (and its world) again: when it cannot be loaded, or its file changed since the shards ran, the merge
/// says so and writes the other files. Returns the merged result.
pub fn merge(m: &MergeArgs) -> Result<CampaignResult, String> {
    let mut files = Vec::new();
    for p in &m.shards {
        let path = if p.is_dir() { p.join("results.json") } else { p.clone() };
        let f: ResultsFile = shard::read_json(&path, "a campaign shard's results.json")?;
        let Some(sh) = f.result.shard else {
            return Err(format!(
                "{}: the result of a whole campaign (no \"shard\" field), not a shard's: merge the files of --shard K/N runs",
                path.display()
            ));
        };
        files.push(ShardFile { path, identity: f.campaign, shard: sh, body: f.result });
    }
    let files = shard::check_set(files)?;
    let count = files.len();
    let results = m.out.join("results.json");
    let inputs: Vec<&Path> = files.iter().map(|f| f.path.as_path()).collect();
    super::check_output(&results, m.force, &inputs)?;
    let identity = files[0].identity.clone();
    let mut timing = CampaignTiming { runs: Vec::new(), trials: Vec::new() };
    let mut parts = Vec::new();
    for f in files {
        let tp = f.path.with_file_name("timing.json");
        match shard::read_json::<CampaignTiming>(&tp, "a campaign's timing.json") {
            Ok(t) => {
                timing.runs.extend(t.runs);
                timing.trials.extend(t.trials);
            }
            Err(e) => eprintln!("note: no timing for shard {}: {e}", f.shard),
        }
        parts.push((f.path.display().to_string(), f.body));
    }
    timing.trials.sort_by_key(|t| t.trial);
    let mut merged = campaign::merge(parts, identity.trials, identity.first_seed)?;
    merged.apply_timing(&timing);
    let svg = (|| {
        let a = identity.args();
        let file = scenario_file(&a.scenario);
        let bytes = std::fs::read(&file).map_err(|e| format!("{}: {e}", file.display()))?;
        if shard::fingerprint(&bytes) != identity.scenario_fingerprint {
            return Err(format!("{} changed since the shards ran (fingerprint)", file.display()));
        }
        let spec = spec_from(&a)?;
        Ok::<_, String>(campaign::paths_svg(spec.world.as_ref(), &spec, &merged))
    })();
    let svg = match svg {
        Ok(s) => Some(s),
        Err(e) => {
            eprintln!("note: paths.svg not drawn: {e}");
            None
        }
    };
    println!("merged {count} shards of {} trials", identity.trials);
    print!("{}", merged.table());
    let file = ResultsFile { campaign: identity, result: merged };
    write_outputs(&m.out, &file, &timing, svg.as_deref())?;
    Ok(file.result)
}
