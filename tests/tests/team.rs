//! Integration tests of the tethered climbing team (Morad et al.): the global planner against the Moving AI
//! benchmark's published optimal lengths, incremental replanning against planning from scratch, and the team
//! simulation on real terrain.

use host_sim::movingai::{load_map, load_scen, run_scenarios};
use std::path::PathBuf;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data").join(rel)
}

/// Run every `stride`-th scenario of the map (stride 1 = all), stratified over buckets because the file is
/// sorted by bucket (path length), and require each planned cost to equal the published optimum (within 1e-6).
fn check(map: &str, stride: usize) {
    let m = load_map(&data(&format!("movingai/{map}"))).unwrap();
    let s = load_scen(&data(&format!("movingai/{map}.scen"))).unwrap();
    let t = std::time::Instant::now();
    let r = run_scenarios(&m, &s, |i, _| i % stride == 0).unwrap();
    eprintln!("{map}: {} scenarios, {} mismatches, max err {:.3e}, {} expansions, {:?}", r.run, r.mismatches.len(), r.max_abs_error, r.expansions, t.elapsed());
    assert_eq!(r.run, s.len().div_ceil(stride));
    if stride > 1 {
        let buckets: std::collections::BTreeSet<u32> = s.iter().map(|x| x.bucket).collect();
        let run_buckets: std::collections::BTreeSet<u32> = s.iter().step_by(stride).map(|x| x.bucket).collect();
        assert_eq!(buckets, run_buckets, "the subset must cover every bucket");
    }
    assert!(r.mismatches.is_empty(), "{:#?}", &r.mismatches[..r.mismatches.len().min(5)]);
}

#[test]
fn dstar_lite_matches_movingai_arena2_all_scenarios() {
    check("arena2.map", 1);
}

/// Every 8th scenario of 8room_000 (268 of 2140, all buckets); the full set runs in
/// `dstar_lite_matches_movingai_8room_all_scenarios` (ignored: ~40 s in the test profile) and from the CLI
/// (`tetherbot movingai ../shared/data/movingai/8room_000.map ../shared/data/movingai/8room_000.map.scen`).
#[test]
fn dstar_lite_matches_movingai_8room_stratified_subset() {
    check("8room_000.map", 8);
}

#[test]
#[ignore = "~40 s in the test profile; run with --ignored, or use the CLI in release"]
fn dstar_lite_matches_movingai_8room_all_scenarios() {
    check("8room_000.map", 1);
}
