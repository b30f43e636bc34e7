//! Mission campaigns (issue 18, item 6): N seeds of one scenario in parallel (threads; each mission is a pure
//! function of its seed, so the result does not depend on the threads) and the table: arrived, safe stops by
//! reason, falls, autonomy by distance, distance, replans, minimum true margin, maximum tension and payout,
//! planning time and iterations per plan, map memory high-water.
//!
//! **Autonomy by distance** (Paton et al. VII: 44 of 46 m): the distance the flight software drove, over that
//! distance plus, for every mission that did not arrive, the straight-line distance from where it stopped to the
//! goal (what an operator would still have had to drive).
//!
//! **The campaign file** (`<name>-campaign.json`, [`CampaignFile`]): the campaign's identity, the shard (when the
//! run was one, [`crate::shard`]), one row per mission in seed order ([`MissionRow`]) and the seeds that could not
//! run. It holds nothing measured in wall-clock time (the host time of each mission is in
//! `<name>-campaign-timing.json`, [`CampaignTiming`]), so the same campaign gives the same bytes on any machine,
//! thread count and split; [`merge`] joins the shards' files into the unsharded run's.

use core::fmt::Write as _;
use core::sync::atomic::{AtomicUsize, Ordering};
use std::collections::BTreeMap;
use std::sync::Mutex;

use firmware::protocol::Tracking;
use serde::{Deserialize, Serialize};

use super::run::{run_mission, MissionOptions, MissionReport, Verdict};
use crate::link::faults::{FaultAccount, FaultLink, FaultProfile};
use crate::scenario::Scenario;
use crate::shard::{RunTiming, Shard, ShardFile};

/// Stack of a mission worker thread (the flight software's storage is built before it is boxed).
const WORKER_STACK: usize = 64 << 20;

/// Runs `seeds` missions of `sc` on `threads` threads (in-process links); reports in seed order. `tick` is called
/// after each mission (progress bar). With `faults`, each mission's uplink is faulted by the profile seeded with
/// `faults.seed ^ seed` (`link::faults`); with `charge_host_time` the executive measures its steps in host time.
pub fn run_seeds(
    sc: &Scenario,
    seeds: &[u64],
    tracking: Tracking,
    threads: usize,
    faults: Option<&FaultProfile>,
    charge_host_time: bool,
    tick: &(dyn Fn(&MissionReport) + Sync),
) -> Vec<Result<(MissionReport, Option<FaultAccount>), String>> {
    run_parallel(seeds.len(), threads, &|i| {
        let seed = seeds.get(i).copied().unwrap_or_default();
        let r = run_one(sc, seed, tracking, faults, charge_host_time);
        if let Ok((rep, _)) = &r {
            tick(rep);
        }
        r
    })
}

/// One in-process mission of a campaign (see [`run_seeds`]).
pub fn run_one(
    sc: &Scenario,
    seed: u64,
    tracking: Tracking,
    faults: Option<&FaultProfile>,
    charge_host_time: bool,
) -> Result<(MissionReport, Option<FaultAccount>), String> {
    let opts = MissionOptions {
        seed,
        tracking,
        noiseless: false,
        live: false,
        reset: None,
    };
    let mut link = super::link::mission_link(sc)?;
    link.charge_host_time(charge_host_time);
    match faults {
        None => Ok((
            run_mission(link, sc, &opts).map_err(|e| e.to_string())?,
            None,
        )),
        Some(p) => {
            let profile = FaultProfile {
                seed: p.seed ^ seed,
                ..p.clone()
            };
            let mut faulty = FaultLink::new(link, profile);
            let rep = run_mission(&mut faulty, sc, &opts).map_err(|e| e.to_string())?;
            let acc = faulty.account().with_host(rep.downlink, &rep.command_seqs);
            Ok((rep, Some(acc)))
        }
    }
}

/// Runs `job(0..n)` on `threads` threads (each with a large stack: the flight software's storage is built before
/// it is boxed); results in index order.
pub fn run_parallel<T: Send>(
    n: usize,
    threads: usize,
    job: &(dyn Fn(usize) -> T + Sync),
) -> Vec<T> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<(usize, T)>> = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            let builder = std::thread::Builder::new().stack_size(WORKER_STACK);
            let spawned = builder.spawn_scoped(scope, || loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                if i >= n {
                    break;
                }
                let r = job(i);
                if let Ok(mut v) = out.lock() {
                    v.push((i, r));
                }
            });
            if let Err(e) = spawned {
                log::error!("cannot start a mission worker: {e}");
            }
        }
    });
    let mut v = out.into_inner().unwrap_or_default();
    v.sort_by_key(|(i, _)| *i);
    v.into_iter().map(|(_, r)| r).collect()
}

/// The campaign table (module docs) of `reports`.
pub fn table(name: &str, reports: &[MissionReport]) -> String {
    let n = reports.len().max(1) as f64;
    let arrived = reports
        .iter()
        .filter(|r| r.verdict == Verdict::Arrived)
        .count();
    let falls = reports
        .iter()
        .filter(|r| r.verdict == Verdict::Fell)
        .count();
    let mut stops: BTreeMap<String, usize> = BTreeMap::new();
    for r in reports {
        if !matches!(r.verdict, Verdict::Arrived | Verdict::Fell) {
            *stops.entry(r.verdict.name()).or_default() += 1;
        }
    }
    let (auto, rest) = reports
        .iter()
        .map(MissionReport::autonomy_m)
        .fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let autonomy = if auto + rest > 0.0 {
        100.0 * auto / (auto + rest)
    } else {
        0.0
    };
    let mean = |f: &dyn Fn(&MissionReport) -> f64| reports.iter().map(f).sum::<f64>() / n;
    let plans: Vec<_> = reports.iter().flat_map(|r| r.plans.iter()).collect();
    let pn = plans.len().max(1) as f64;
    let plan_s = plans.iter().map(|p| p.host_s).sum::<f64>() / pn;
    let plan_it = plans.iter().map(|p| f64::from(p.iterations)).sum::<f64>() / pn;
    let min_margin = reports
        .iter()
        .map(|r| r.min_true_margin_n)
        .fold(f64::INFINITY, f64::min);
    let max_t = reports.iter().map(|r| r.max_tension_n).fold(0.0, f64::max);
    let max_p = reports.iter().map(|r| r.max_payout_m).fold(0.0, f64::max);
    let blocks = reports.iter().map(|r| r.map_blocks).max().unwrap_or(0);
    let cap = reports
        .iter()
        .map(|r| r.map_blocks_capacity)
        .max()
        .unwrap_or(0);
    let block_bytes = core::mem::size_of::<firmware::map::Block>() as f64;
    let mut s = String::new();
    let _ = writeln!(s, "mission campaign: {name}, {} missions", reports.len());
    let _ = writeln!(
        s,
        "  arrived                      {arrived} / {} ({:.0} %)",
        reports.len(),
        100.0 * arrived as f64 / n
    );
    let stop_text: Vec<String> = stops.iter().map(|(k, v)| format!("{k} {v}")).collect();
    let _ = writeln!(
        s,
        "  safe stops by reason         {}",
        if stop_text.is_empty() {
            "none".into()
        } else {
            stop_text.join(", ")
        }
    );
    let checks: u32 = reports.iter().map(|r| r.physics_checks).sum();
    if checks > 0 {
        let blocked: u32 = reports.iter().map(|r| r.physics_blocked).sum();
        let by_physics = reports.iter().filter(|r| r.physics_fall.is_some()).count();
        let overruled: u32 = reports.iter().map(|r| r.statics_overruled).sum();
        let _ = writeln!(
            s,
            "  falls                        {falls} ({by_physics} by the physics judge: {checks} poses judged, {blocked} not placeable; {overruled} increments the simple statics could not hold and the judge held)"
        );
    } else {
        let _ = writeln!(s, "  falls                        {falls} (simple statics; --physics-falls for the physics judge)");
    }
    let _ = writeln!(s, "  autonomy by distance         {autonomy:.1} % ({auto:.2} m driven, {rest:.2} m left to an operator)");
    let _ = writeln!(
        s,
        "  distance per mission         {:.2} m (mean)",
        mean(&|r| r.distance_m)
    );
    let _ = writeln!(
        s,
        "  replans per mission          {:.2} (mean)",
        mean(&|r| f64::from(r.replans))
    );
    let _ = writeln!(
        s,
        "  motions per mission          {:.1} (mean; {:.1} stalled, {:.1} slipped)",
        mean(&|r| f64::from(r.motions)),
        mean(&|r| f64::from(r.stalls)),
        mean(&|r| f64::from(r.slips))
    );
    let _ = writeln!(s, "  min true margin on the path  {min_margin:.1} N");
    let fallbacks: u32 = reports.iter().map(|r| r.truth_tether_fallbacks).sum();
    if fallbacks > 0 {
        let why = "closed forms or vertical profile; mission::truth";
        let _ = writeln!(s, "  true tether fallbacks        {fallbacks} increments ({why})");
    }
    let _ = writeln!(
        s,
        "  max tension / payout         {max_t:.0} N / {max_p:.2} m"
    );
    let _ = writeln!(
        s,
        "  cross-track from the plan    {:.3} m mean, {:.3} m max (true axle, horizontal)",
        mean(&|r| r.mean_cross_track_m),
        reports
            .iter()
            .map(|r| r.max_cross_track_m)
            .fold(0.0, f64::max)
    );
    let _ = writeln!(
        s,
        "  goal error (true)            {:.3} m mean",
        mean(&|r| r.goal_error_m)
    );
    let _ = writeln!(s, "  plans                        {} ({plan_it:.0} iterations, {plan_s:.2} s host time per plan)", plans.len());
    let _ = writeln!(
        s,
        "  map memory high-water        {blocks} of {cap} blocks ({:.1} MiB)",
        f64::from(blocks) * block_bytes / (1024.0 * 1024.0)
    );
    let _ = writeln!(
        s,
        "  link time per mission        {:.0} s (mean); host time {:.1} s (mean)",
        mean(&|r| r.link_s),
        mean(&|r| r.host_s)
    );
    let _ = writeln!(
        s,
        "  executive steps (telemetry)  max {:.3} s, {} slips over the {:.3} s budget (simulated clock: 0 unless host time is charged)",
        f64::from(reports.iter().map(|r| r.max_step_us).max().unwrap_or(0)) * 1e-6,
        reports.iter().map(|r| u64::from(r.step_slips)).sum::<u64>(),
        firmware::config::exec::STEP_BUDGET_US as f64 * 1e-6
    );
    let _ = writeln!(
        s,
        "  retransmitted frames         {}, scan chunks sent again {} ({} given up)",
        reports.iter().map(|r| r.retransmits).sum::<u64>(),
        reports.iter().map(|r| r.chunks_resent).sum::<u64>(),
        reports.iter().map(|r| r.given_up).sum::<u64>()
    );
    s
}

/// What makes two runs the same mission campaign: the scenario as given (a path, or the embedded default) and
/// the fingerprint of its text, the seeds and the tracking mode.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignIdentity {
    /// The scenario argument (`(default)` for the embedded crater-wall descent).
    pub scenario: String,
    /// The scenario's `name`.
    pub scenario_name: String,
    /// [`crate::shard::fingerprint`] of the scenario's text.
    pub scenario_fingerprint: String,
    /// Missions of the whole campaign.
    pub seeds: u32,
    /// Seed of mission 0 (mission `i` uses `first_seed + i`).
    pub first_seed: u64,
    /// Tracking mode.
    pub tracking: String,
}

/// One mission of a campaign file. Non-finite figures (a margin never measured) are `null`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionRow {
    /// Seed.
    pub seed: u64,
    /// [`Verdict::name`].
    pub verdict: String,
    /// Distance driven (truth), metres.
    pub distance_m: Option<f64>,
    /// Replans.
    pub replans: u32,
    /// Smallest true stability margin on the path, newtons.
    pub min_true_margin_n: Option<f64>,
    /// Largest tension, newtons.
    pub max_tension_n: Option<f64>,
    /// Largest payout, metres.
    pub max_payout_m: Option<f64>,
    /// Distance from the goal at the end (truth), metres.
    pub goal_error_m: Option<f64>,
    /// Mean cross-track from the plan, metres.
    pub mean_cross_track_m: Option<f64>,
    /// Largest cross-track from the plan, metres.
    pub max_cross_track_m: Option<f64>,
    /// Plans made.
    pub plans: usize,
    /// Onboard map high-water, blocks.
    pub map_blocks: u32,
    /// The physics judge's words when it ended the mission as a fall (`--physics-falls`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub physics_fall: Option<String>,
    /// The flight software's last warning when the mission did not arrive (a refused goal's reason, ...).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub flight_warning: Option<String>,
}

impl MissionRow {
    /// The row of `r`.
    pub fn of(r: &MissionReport) -> MissionRow {
        let fin = |x: f64| x.is_finite().then_some(x);
        MissionRow {
            seed: r.seed,
            verdict: r.verdict.name(),
            distance_m: fin(r.distance_m),
            replans: r.replans,
            min_true_margin_n: fin(r.min_true_margin_n),
            max_tension_n: fin(r.max_tension_n),
            max_payout_m: fin(r.max_payout_m),
            goal_error_m: fin(r.goal_error_m),
            mean_cross_track_m: fin(r.mean_cross_track_m),
            max_cross_track_m: fin(r.max_cross_track_m),
            plans: r.plans.len(),
            map_blocks: r.map_blocks,
            physics_fall: r.physics_fall.clone(),
            flight_warning: r.flight_warning.clone().filter(|_| r.verdict != Verdict::Arrived),
        }
    }
}

/// A seed whose mission could not run, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FailedMission {
    /// Seed.
    pub seed: u64,
    /// The error.
    pub error: String,
}

/// `<name>-campaign.json` (module docs).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CampaignFile {
    /// Which campaign.
    pub campaign: CampaignIdentity,
    /// The part of the campaign (absent for the whole campaign, and so in a merge's file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// The missions that ran, in seed order.
    pub missions: Vec<MissionRow>,
    /// The seeds that could not run, in seed order.
    pub failed: Vec<FailedMission>,
}

/// `<name>-campaign-timing.json`: the wall-clock side of a mission campaign.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct CampaignTiming {
    /// One entry per run (the unsharded run, or each shard of a merge).
    pub runs: Vec<RunTiming>,
    /// Host seconds per mission, in seed order.
    pub missions: Vec<MissionTiming>,
}

/// The host time of one mission.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MissionTiming {
    /// Seed.
    pub seed: u64,
    /// Host seconds.
    pub host_s: f64,
}

/// The seeds of `shard` of a campaign of `seeds` missions from `first_seed` (mission `i` uses `first_seed + i`),
/// or the reason they pass `u64::MAX`.
pub fn shard_seeds(first_seed: u64, seeds: u32, shard: Shard) -> Result<Vec<u64>, String> {
    if first_seed.checked_add(u64::from(seeds.saturating_sub(1))).is_none() {
        return Err(format!(
            "--seed {first_seed} with --seeds {seeds}: mission i uses seed {first_seed} + i, which passes u64::MAX; use a seed of at most {}",
            u64::MAX - u64::from(seeds.saturating_sub(1))
        ));
    }
    shard.check_fits(seeds, "missions")?;
    Ok(shard.indices(seeds).into_iter().map(|i| first_seed + u64::from(i)).collect())
}

/// Joins the files of the N shards of one campaign, already checked to be one complete set
/// ([`crate::shard::check_set`], in shard order): the rows and failures in seed order, the shard mark removed.
/// Refuses a shard whose seeds are not exactly its own (a file edited by hand or cut short).
pub fn merge(shards: Vec<ShardFile<CampaignIdentity, CampaignFile>>) -> Result<CampaignFile, String> {
    let Some(first) = shards.first() else { return Err("no shard files given".into()) };
    let campaign = first.identity.clone();
    let (mut missions, mut failed) = (Vec::new(), Vec::new());
    for f in shards {
        let want = shard_seeds(campaign.first_seed, campaign.seeds, f.shard)?;
        let mut got: Vec<u64> = f.body.missions.iter().map(|r| r.seed).chain(f.body.failed.iter().map(|r| r.seed)).collect();
        got.sort_unstable();
        if got != want {
            return Err(format!(
                "{}: shard {} should hold seeds {want:?}, it holds {got:?} (an incomplete or edited file)",
                f.path.display(),
                f.shard
            ));
        }
        missions.extend(f.body.missions);
        failed.extend(f.body.failed);
    }
    missions.sort_by_key(|r| r.seed);
    failed.sort_by_key(|r| r.seed);
    Ok(CampaignFile { campaign, shard: None, missions, failed })
}
