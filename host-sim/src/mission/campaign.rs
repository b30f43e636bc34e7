//! Mission campaigns (issue 18, item 6): N seeds of one scenario in parallel (threads; each mission is a pure
//! function of its seed, so the result does not depend on the threads) and the table: arrived, safe stops by
//! reason, falls, autonomy by distance, distance, replans, minimum true margin, maximum tension and payout,
//! planning time and iterations per plan, map memory high-water.
//!
//! **Autonomy by distance** (Paton et al. VII: 44 of 46 m): the distance the flight software drove, over that
//! distance plus, for every mission that did not arrive, the straight-line distance from where it stopped to the
//! goal (what an operator would still have had to drive).

use core::sync::atomic::{AtomicUsize, Ordering};
use std::collections::BTreeMap;
use core::fmt::Write as _;
use std::sync::Mutex;

use firmware::protocol::Tracking;

use super::run::{run_mission, MissionOptions, MissionReport, Verdict};
use crate::scenario::Scenario;

/// Stack of a mission worker thread (the flight software's storage is built before it is boxed).
const WORKER_STACK: usize = 64 << 20;

/// Runs `seeds` missions of `sc` on `threads` threads (in-process links); reports in seed order. `tick` is called
/// after each mission (progress bar).
pub fn run_seeds(
    sc: &Scenario,
    seeds: &[u64],
    tracking: Tracking,
    threads: usize,
    tick: &(dyn Fn(&MissionReport) + Sync),
) -> Vec<Result<MissionReport, String>> {
    let next = AtomicUsize::new(0);
    let out: Mutex<Vec<(usize, Result<MissionReport, String>)>> = Mutex::new(Vec::new());
    std::thread::scope(|scope| {
        for _ in 0..threads.max(1) {
            let builder = std::thread::Builder::new().stack_size(WORKER_STACK);
            let spawned = builder.spawn_scoped(scope, || loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(&seed) = seeds.get(i) else { break };
                let opts = MissionOptions { seed, tracking, noiseless: false, live: false };
                let r = match super::link::mission_link(sc) {
                    Ok(link) => run_mission(link, sc, &opts).map_err(|e| e.to_string()),
                    Err(e) => Err(e),
                };
                if let Ok(rep) = &r {
                    tick(rep);
                }
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
    let arrived = reports.iter().filter(|r| r.verdict == Verdict::Arrived).count();
    let falls = reports.iter().filter(|r| r.verdict == Verdict::Fell).count();
    let mut stops: BTreeMap<String, usize> = BTreeMap::new();
    for r in reports {
        if !matches!(r.verdict, Verdict::Arrived | Verdict::Fell) {
            *stops.entry(r.verdict.name()).or_default() += 1;
        }
    }
    let (auto, rest) = reports.iter().map(MissionReport::autonomy_m).fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    let autonomy = if auto + rest > 0.0 { 100.0 * auto / (auto + rest) } else { 0.0 };
    let mean = |f: &dyn Fn(&MissionReport) -> f64| reports.iter().map(f).sum::<f64>() / n;
    let plans: Vec<_> = reports.iter().flat_map(|r| r.plans.iter()).collect();
    let pn = plans.len().max(1) as f64;
    let plan_s = plans.iter().map(|p| p.host_s).sum::<f64>() / pn;
    let plan_it = plans.iter().map(|p| f64::from(p.iterations)).sum::<f64>() / pn;
    let min_margin = reports.iter().map(|r| r.min_true_margin_n).fold(f64::INFINITY, f64::min);
    let max_t = reports.iter().map(|r| r.max_tension_n).fold(0.0, f64::max);
    let max_p = reports.iter().map(|r| r.max_payout_m).fold(0.0, f64::max);
    let blocks = reports.iter().map(|r| r.map_blocks).max().unwrap_or(0);
    let cap = reports.iter().map(|r| r.map_blocks_capacity).max().unwrap_or(0);
    let block_bytes = core::mem::size_of::<firmware::map::Block>() as f64;
    let mut s = String::new();
    let _ = writeln!(s, "mission campaign: {name}, {} missions", reports.len());
    let _ = writeln!(s, "  arrived                      {arrived} / {} ({:.0} %)", reports.len(), 100.0 * arrived as f64 / n);
    let stop_text: Vec<String> = stops.iter().map(|(k, v)| format!("{k} {v}")).collect();
    let _ = writeln!(s, "  safe stops by reason         {}", if stop_text.is_empty() { "none".into() } else { stop_text.join(", ") });
    let _ = writeln!(s, "  falls                        {falls}");
    let _ = writeln!(s, "  autonomy by distance         {autonomy:.1} % ({auto:.2} m driven, {rest:.2} m left to an operator)");
    let _ = writeln!(s, "  distance per mission         {:.2} m (mean)", mean(&|r| r.distance_m));
    let _ = writeln!(s, "  replans per mission          {:.2} (mean)", mean(&|r| f64::from(r.replans)));
    let _ = writeln!(s, "  motions per mission          {:.1} (mean; {:.1} stalled, {:.1} slipped)", mean(&|r| f64::from(r.motions)), mean(&|r| f64::from(r.stalls)), mean(&|r| f64::from(r.slips)));
    let _ = writeln!(s, "  min true margin on the path  {min_margin:.1} N");
    let _ = writeln!(s, "  max tension / payout         {max_t:.0} N / {max_p:.2} m");
    let _ = writeln!(s, "  cross-track from the plan    {:.3} m mean, {:.3} m max (true axle, horizontal)", mean(&|r| r.mean_cross_track_m), reports.iter().map(|r| r.max_cross_track_m).fold(0.0, f64::max));
    let _ = writeln!(s, "  goal error (true)            {:.3} m mean", mean(&|r| r.goal_error_m));
    let _ = writeln!(s, "  plans                        {} ({plan_it:.0} iterations, {plan_s:.2} s host time per plan)", plans.len());
    let _ = writeln!(
        s,
        "  map memory high-water        {blocks} of {cap} blocks ({:.1} MiB)",
        f64::from(blocks) * block_bytes / (1024.0 * 1024.0)
    );
    let _ = writeln!(s, "  link time per mission        {:.0} s (mean); host time {:.1} s (mean)", mean(&|r| r.link_s), mean(&|r| r.host_s));
    s
}
