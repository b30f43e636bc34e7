//! `tetherbot campaign SCENARIO`: Paton et al.'s Table I for any scenario (see [`crate::campaign`] and
//! `host-sim/doc/campaign.md`).

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use firmware::config::rover::RoverParams;
use firmware::geom::Real;
use firmware::plan::abit::AbitParams;
use firmware::plan::tethered::{PlanBounds, TetherSpaceParams};
use indicatif::{ProgressBar, ProgressStyle};

use crate::campaign::{self, CampaignSpec, PlanningField};

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
    /// Seed of the first trial (default: the scenario's `seeds.planner`).
    #[arg(long)]
    pub seed: Option<u64>,
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
    /// Output directory for results.json, results.csv and paths.svg (default target/campaign/<scenario>).
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
        threads,
        field,
        params,
        rover,
        abit,
        physics_judge: !a.no_physics,
    })
}

/// Run the command.
pub fn main(a: &CampaignArgs) -> ExitCode {
    match run(a) {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(1),
        Err(e) => super::fail(e),
    }
}

fn run(a: &CampaignArgs) -> Result<bool, String> {
    let sc = crate::scenario::load(&scenario_file(&a.scenario)).map_err(|e| e.to_string())?;
    let spec = spec_from_scenario(&sc, a)?;
    for note in unused_scenario_fields(&sc) {
        eprintln!("note: {note}");
    }
    let bar = ProgressBar::new(u64::from(spec.trials));
    if let Ok(style) = ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} trials, {elapsed} elapsed, eta {eta}") {
        bar.set_style(style.progress_chars("=> "));
    }
    bar.set_prefix(spec.name.clone());
    let result = campaign::run(&spec, &|done, _| bar.set_position(done as u64))?;
    bar.finish_and_clear();
    print!("{}", result.table());
    if let Some(p) = paper_row(&result.name) {
        println!("{p}");
    }
    let out = a.out.clone().unwrap_or_else(|| {
        // The name comes from the scenario file: made one safe path component, so it cannot leave target/campaign.
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../target/campaign").join(crate::scenario::file_safe(&result.name))
    });
    std::fs::create_dir_all(&out).map_err(|e| format!("{}: {e}", out.display()))?;
    let json = serde_json::to_string_pretty(&result).map_err(|e| e.to_string())?;
    let write = |name: &str, text: &str| {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("results.json", &json)?;
    write("results.csv", &result.csv())?;
    write("paths.svg", &campaign::paths_svg(spec.world.as_ref(), &spec, &result))?;
    println!("wrote {}/{{results.json,results.csv,paths.svg}}", out.display());
    Ok(a.require_stable.is_none_or(|n| result.found_stable() >= n))
}
