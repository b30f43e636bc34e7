//! Campaigns split over a cluster (issue 23, item 3): a planning campaign run whole and as 4 shards (`--shard K/N`,
//! trial i in shard i mod N), then `campaign merge`, writes the same `results.json`, `results.csv` and `paths.svg`
//! byte for byte; the merge refuses missing, duplicate and foreign shards and corrupt files, naming them. The same
//! for a mission campaign. Every run here is the command's own code (`host_sim::cli::*::main` / `merge`), on the
//! real planner, physics judge and flight software.

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::OnceLock;

use host_sim::cli::campaign::{merge, CampaignArgs, MergeArgs};
use host_sim::cli::mission::{merge as mission_merge, MissionArgs, MissionMergeArgs, TrackingArg};
use host_sim::link::LinkKind;
use host_sim::shard::Shard;

/// The planning campaign of these tests: the ledge with the pole, the rover behind the pole and the root anchor
/// behind the rover, so the straight descent hits the pole; 150 iterations, so that trials differ (on seeds 1-5: three
/// found at different costs and judged by the physics judge, two not found; 25 iterations found only one once the
/// stability LP's friction became the octagon inscribed in Coulomb's cone, and 50 only one once a wheel tilted
/// against its face became a point contact) and stay cheap in a debug build.
const SCENARIO: &str = r#"
name = "behind_pole"
[world]
kind = "ledge_pole"
[rover]
start = [-4.0, 0.0, 4.35]
[tether]
root_anchor = [-6.4, 0.0, 6.35]
[goal]
position = [6.0, 0.0, 0.35]
[seeds]
planner = 1
trials = 5
[budgets]
planner_iterations = 150
[plan]
bounds_min = [-5.0, -5.0, -0.5]
bounds_max = [7.5, 5.0, 7.5]
"#;
const TRIALS: u32 = 5;
const SHARDS: u32 = 4;

fn tmp(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tetherbot-shard-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

fn campaign_args(scenario: &Path, out: &Path, shard: Option<Shard>, threads: usize) -> CampaignArgs {
    CampaignArgs {
        threads: Some(threads),
        out: Some(out.to_path_buf()),
        shard,
        ..CampaignArgs::new(scenario.to_str().expect("utf-8 temp path"))
    }
}

/// The whole campaign's directory and the 4 shards' directories (run once for all tests of this file).
struct Runs {
    whole: PathBuf,
    shards: Vec<PathBuf>,
    root: PathBuf,
}

fn runs() -> &'static Runs {
    static RUNS: OnceLock<Runs> = OnceLock::new();
    RUNS.get_or_init(|| {
        let root = tmp("campaign");
        let scenario = root.join("behind_pole.toml");
        std::fs::write(&scenario, SCENARIO).expect("scenario");
        let whole = root.join("whole");
        // the whole campaign on 2 threads, the shards on 1 each, two at a time: threads must not matter either
        assert_eq!(host_sim::cli::campaign::main(&campaign_args(&scenario, &whole, None, 2)), ExitCode::SUCCESS);
        let shards: Vec<PathBuf> = (0..SHARDS).map(|k| root.join(format!("shard-{k}"))).collect();
        for pair in [[0, 2], [1, 3]] {
            std::thread::scope(|s| {
                for k in pair {
                    let a = campaign_args(&scenario, &shards[k as usize], Some(Shard { index: k, count: SHARDS }), 1);
                    s.spawn(move || assert_eq!(host_sim::cli::campaign::main(&a), ExitCode::SUCCESS, "shard {k}"));
                }
            });
        }
        Runs { whole, shards, root }
    })
}

fn read(p: &Path) -> Vec<u8> {
    std::fs::read(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn json(p: &Path) -> serde_json::Value {
    serde_json::from_slice(&read(p)).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn merge_into(out: &Path, shards: &[PathBuf]) -> Result<host_sim::campaign::CampaignResult, String> {
    merge(&MergeArgs { out: out.to_path_buf(), shards: shards.to_vec(), force: false })
}

#[test]
fn four_shards_merge_to_the_unsharded_files_byte_for_byte() {
    let r = runs();
    // each shard holds exactly its trials, i mod 4 == K, with their own seeds (first seed 1 + i)
    for (k, d) in r.shards.iter().enumerate() {
        let v = json(&d.join("results.json"));
        assert_eq!(v["shard"], serde_json::json!({ "index": k, "count": SHARDS }));
        let trials: Vec<(u64, u64)> = v["trials"]
            .as_array()
            .expect("trials")
            .iter()
            .map(|t| (t["trial"].as_u64().unwrap_or(99), t["seed"].as_u64().unwrap_or(99)))
            .collect();
        let want: Vec<(u64, u64)> = (0..u64::from(TRIALS)).filter(|i| i % u64::from(SHARDS) == k as u64).map(|i| (i, i + 1)).collect();
        assert_eq!(trials, want, "shard {k}");
    }
    let out = r.root.join("merged");
    // the shards in any order, as files or directories
    let given = vec![r.shards[2].clone(), r.shards[0].join("results.json"), r.shards[3].clone(), r.shards[1].clone()];
    let merged = merge_into(&out, &given).expect("merge");
    assert_eq!(merged.trials.len(), TRIALS as usize);
    for f in ["results.json", "results.csv", "paths.svg"] {
        let (a, b) = (read(&r.whole.join(f)), read(&out.join(f)));
        assert!(a == b, "{f}: the merge differs from the unsharded run ({} vs {} bytes)", a.len(), b.len());
    }
    // the campaign is not trivial: trials differ (found and not, different costs), so order and content matter
    let whole = json(&r.whole.join("results.json"));
    let trials = whole["trials"].as_array().expect("trials");
    let costs: std::collections::BTreeSet<String> = trials.iter().map(|t| t["final_cost"].to_string()).collect();
    assert!(costs.len() >= 3, "trials too alike to show anything: {costs:?}");
    assert!(trials.iter().any(|t| t["physics"]["poses"].as_u64().is_some_and(|n| n > 0)), "no path was judged");
    assert!(whole.get("shard").is_none() && whole["campaign"]["trials"] == TRIALS);
    // no wall-clock field in the byte-compared file; they are all in timing.json
    let text = String::from_utf8(read(&r.whole.join("results.json"))).expect("utf8");
    for k in ["first_time_s", "total_time_s", "wall_s", "map_build_s", "threads"] {
        assert!(!text.contains(k), "results.json holds {k}");
    }
    let timing = json(&out.join("timing.json"));
    assert_eq!(timing["runs"].as_array().map(Vec::len), Some(SHARDS as usize));
    let timed: Vec<u64> = timing["trials"].as_array().expect("trials").iter().filter_map(|t| t["trial"].as_u64()).collect();
    assert_eq!(timed, (0..u64::from(TRIALS)).collect::<Vec<_>>());
    assert!(timing["trials"][0]["total_time_s"].as_f64().is_some_and(|s| s > 0.0));
}

#[test]
fn merge_refuses_missing_duplicate_foreign_and_corrupt_shards() {
    let r = runs();
    let dir = tmp("refusals");
    let out = dir.join("out");
    let s = &r.shards;
    let refuse = |shards: Vec<PathBuf>, want: &str| {
        let e = merge_into(&out, &shards).err().unwrap_or_else(|| panic!("merged {shards:?}; wanted: {want}"));
        assert!(e.contains(want), "wanted {want:?} in: {e}");
        assert!(!out.join("results.json").exists(), "a refused merge wrote {}", out.display());
        e
    };
    let e = refuse(vec![s[0].clone(), s[1].clone(), s[3].clone()], "missing shard(s) 2/4 of the 4");
    assert!(e.contains("run the missing shards"), "{e}");
    let e = refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), s[3].clone(), s[1].join("results.json")], "shard 1/4 is given twice");
    assert!(e.contains(&s[1].join("results.json").display().to_string()), "{e}");
    // another first seed, other parameters, another split, trials of another shard: made from a real shard file
    let edit = |name: &str, f: &dyn Fn(&mut serde_json::Value)| {
        let mut v = json(&s[3].join("results.json"));
        f(&mut v);
        let p = dir.join(name);
        std::fs::write(&p, serde_json::to_string_pretty(&v).expect("json")).expect("write");
        p
    };
    let p = edit("seed.json", &|v| v["campaign"]["first_seed"] = serde_json::json!(2));
    let e = refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), p.clone()], "shards of different campaigns (first_seed: 1 vs 2)");
    assert!(e.contains(&p.display().to_string()) && e.contains(&s[0].join("results.json").display().to_string()), "{e}");
    let p = edit("rewire.json", &|v| v["campaign"]["rewire_factor"] = serde_json::json!(1.5));
    refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), p], "(rewire_factor: null vs 1.5)");
    let p = edit("scenario.json", &|v| v["campaign"]["scenario_fingerprint"] = serde_json::json!("0000000000000000"));
    refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), p], "scenario_fingerprint");
    let p = edit("split.json", &|v| v["shard"] = serde_json::json!({ "index": 3, "count": 5 }));
    refuse(vec![s[0].clone(), p], "split in two different ways");
    let p = edit("stolen.json", &|v| {
        v["trials"][0]["trial"] = serde_json::json!(1);
        v["trials"][0]["seed"] = serde_json::json!(2);
    });
    refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), p], "shard 3/4 of 5 trials should hold trials [3], it holds [1]");
    let p = edit("reseeded.json", &|v| v["trials"][0]["seed"] = serde_json::json!(9));
    refuse(vec![s[0].clone(), s[1].clone(), s[2].clone(), p], "trial 3 has seed 9, not the campaign's 1 + 3");
    // corrupt: cut short, not JSON, an unsharded result
    let whole = read(&s[2].join("results.json"));
    let cut = dir.join("cut.json");
    std::fs::write(&cut, &whole[..whole.len() / 2]).expect("write");
    refuse(vec![s[0].clone(), s[1].clone(), cut, s[3].clone()], "not a campaign shard's results.json (corrupt, truncated");
    let junk = dir.join("junk.json");
    std::fs::write(&junk, b"\x00\x01 not json").expect("write");
    refuse(vec![junk, s[1].clone()], "junk.json: not a campaign shard's results.json");
    refuse(vec![r.whole.clone(), s[1].clone()], "the result of a whole campaign (no \"shard\" field)");
    refuse(vec![dir.join("no-such-file.json")], "cannot read it");
    // the output may not be an input, nor overwrite an earlier merge unless --force
    let e = merge(&MergeArgs { out: s[0].clone(), shards: s.clone(), force: true }).err().unwrap_or_default();
    assert!(e.contains("is the input"), "{e}");
    merge_into(&out, s).expect("a complete set merges");
    let e = merge_into(&out, s).err().unwrap_or_default();
    assert!(e.contains("exists") && e.contains("--force"), "{e}");
    merge(&MergeArgs { out: out.clone(), shards: s.clone(), force: true }).expect("--force replaces it");
}

#[test]
fn a_split_that_leaves_a_shard_empty_is_refused_before_any_work() {
    let d = tmp("empty-shard");
    let scenario = d.join("behind_pole.toml");
    std::fs::write(&scenario, SCENARIO).expect("scenario");
    let a = campaign_args(&scenario, &d.join("out"), Some(Shard { index: 0, count: TRIALS + 1 }), 1);
    let e = host_sim::cli::campaign::spec_from(&a).err().unwrap_or_default();
    assert!(e.contains("would leave a shard empty; use at most 5 shards"), "{e}");
    assert_ne!(host_sim::cli::campaign::main(&a), ExitCode::SUCCESS);
    assert!(!d.join("out").exists(), "the refused run wrote {}", d.join("out").display());
}

/// The mission campaign of these tests: `mission_smoke.toml`, a 1.2 m drive along a crater rim: real whole
/// missions (scans, plans, the physics judge), cheap ones.
fn mission_args(out: &Path, seeds: u32, shard: Option<Shard>) -> MissionArgs {
    MissionArgs {
        scenario: Some(PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/mission_smoke.toml")),
        link: LinkKind::Inproc,
        seeds,
        seed: 41,
        shard,
        tracking: TrackingArg::Closed,
        log: None,
        out: out.to_path_buf(),
        threads: Some(2),
        created_at_ms: Some(0),
        quiet: true,
        physics_falls: false,
        live: None,
        live_wait: 0.0,
        faults: None,
        fault_campaign: false,
        fault_rates: Vec::new(),
        fault_kinds: Vec::new(),
        fault_downlink: false,
        charge_host_time: false,
        reset_after_motions: None,
        reset_when_wrapped: false,
        watchdog_bite_in_motion: None,
        watchdog_bite_when_wrapped: false,
    }
}

#[test]
fn mission_campaign_shards_merge_to_the_unsharded_file_byte_for_byte() {
    let d = tmp("mission");
    let seeds = 4;
    assert_eq!(host_sim::cli::mission::main(&mission_args(&d.join("whole"), seeds, None)), ExitCode::SUCCESS);
    let whole = d.join("whole").join("mission_smoke-campaign.json");
    let shards_dir = d.join("shards");
    for k in 0..2 {
        let a = mission_args(&shards_dir, seeds, Some(Shard { index: k, count: 2 }));
        assert_eq!(host_sim::cli::mission::main(&a), ExitCode::SUCCESS, "shard {k}");
    }
    let shard = |k: u32| shards_dir.join(format!("mission_smoke-campaign-shard-{k}-of-2.json"));
    let v = json(&shard(1));
    let seeds_of_1: Vec<u64> = v["missions"].as_array().expect("missions").iter().filter_map(|m| m["seed"].as_u64()).collect();
    assert_eq!(seeds_of_1, [42, 44], "mission i (seed 41 + i) goes to shard i mod 2");
    let out = d.join("merged");
    let merged = mission_merge(&MissionMergeArgs { out: out.clone(), shards: vec![shard(1), shard(0)], force: false }).expect("merge");
    assert_eq!(merged.missions.len(), seeds as usize);
    let (a, b) = (read(&whole), read(&out.join("mission_smoke-campaign.json")));
    assert!(a == b, "the merge differs from the unsharded run:\n{}\n---\n{}", String::from_utf8_lossy(&a), String::from_utf8_lossy(&b));
    assert!(!String::from_utf8_lossy(&a).contains("host_s"), "wall-clock time in the campaign file");
    // refusals: a missing shard, a shard twice, a corrupt file, a shard of another campaign
    let merge = |shards: Vec<PathBuf>| {
        mission_merge(&MissionMergeArgs { out: d.join("refused"), shards, force: false }).err().unwrap_or_default()
    };
    assert!(merge(vec![shard(0)]).contains("missing shard(s) 1/2 of the 2"));
    assert!(merge(vec![shard(0), shard(1), shard(0)]).contains("shard 0/2 is given twice"));
    let cut = d.join("cut.json");
    let bytes = read(&shard(1));
    std::fs::write(&cut, &bytes[..bytes.len() - 20]).expect("write");
    let e = merge(vec![shard(0), cut]);
    assert!(e.contains("cut.json: not a mission campaign shard's"), "{e}");
    let mut other = json(&shard(1));
    other["campaign"]["seeds"] = serde_json::json!(6);
    let p = d.join("other.json");
    std::fs::write(&p, serde_json::to_string_pretty(&other).expect("json")).expect("write");
    let e = merge(vec![shard(0), p]);
    assert!(e.contains("shards of different campaigns (seeds: 4 vs 6)"), "{e}");
    assert!(!d.join("refused").join("mission_smoke-campaign.json").exists());
}
