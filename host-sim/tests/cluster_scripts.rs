//! The cluster scripts of `host-sim/cluster/` run as the schedulers would run them: the Slurm array task script
//! with `SLURM_ARRAY_TASK_ID` set for each K and then the merge job script; the Kubernetes pods' command
//! (`run-shard.sh` with the `JOB_COMPLETION_INDEX` as K, then `run-merge.sh`). The loop over K below stands in
//! for the scheduler (no Slurm or Kubernetes here). Each merge must equal the unsharded run, byte for byte.
//! (Here, not in `tests/`: only the crate that owns the binary gets `CARGO_BIN_EXE_tetherbot`.)

use std::path::{Path, PathBuf};
use std::process::Command;

fn cluster() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cluster")
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tetherbot-cluster-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `bash script args` with `env`, as the scheduler would; returns its output, panicking on failure.
fn bash(script: &Path, args: &[&str], env: &[(&str, &str)]) -> String {
    let out = Command::new("bash")
        .arg(script)
        .args(args)
        .envs(env.iter().copied())
        .env("TETHERBOT", env!("CARGO_BIN_EXE_tetherbot"))
        .env("TETHERBOT_CLUSTER", cluster())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{} {args:?}: {text}", script.display());
    text
}

fn tetherbot(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_tetherbot")).args(args).output().unwrap();
    assert!(out.status.success(), "{args:?}: {}", String::from_utf8_lossy(&out.stderr));
}

fn same(a: &Path, b: &Path) {
    let (x, y) = (std::fs::read(a).unwrap(), std::fs::read(b).unwrap());
    assert!(x == y, "{} and {} differ ({} vs {} bytes)", a.display(), b.display(), x.len(), y.len());
}

/// Ledge test 3 on the exact world, 10 iterations, no physics judge: cheap, and the trials differ (their work
/// counters), so a merge in the wrong order or with a trial missing shows.
const CAMPAIGN: [&str; 8] = ["--trials", "3", "--iterations", "10", "--field", "truth", "--no-physics", "--threads=1"];

#[test]
fn the_slurm_array_task_and_merge_scripts_give_the_unsharded_campaign() {
    let d = dir("slurm");
    let whole = d.join("whole");
    let mut args = vec!["campaign", "ledge_test3", "-o", whole.to_str().unwrap()];
    args.extend(CAMPAIGN);
    tetherbot(&args);
    let runs = d.join("runs");
    let runs_s = runs.to_str().unwrap();
    for k in ["0", "1", "2"] {
        let mut a = vec!["campaign", "3", runs_s, "ledge_test3", "--"];
        a.extend(&CAMPAIGN[..CAMPAIGN.len() - 1]);
        bash(&cluster().join("slurm/shard.sbatch"), &a, &[("SLURM_ARRAY_TASK_ID", k), ("SLURM_CPUS_PER_TASK", "1")]);
        assert!(runs.join(format!("shard-{k}/results.json")).exists());
    }
    let text = bash(&cluster().join("slurm/merge.sbatch"), &["campaign", "3", runs_s], &[]);
    assert!(text.contains("merged 3 shards of 3 trials"), "{text}");
    for f in ["results.json", "results.csv", "paths.svg"] {
        same(&whole.join(f), &runs.join("merged").join(f));
    }
    // the array task script refuses to run outside an array
    let out = Command::new("bash").arg(cluster().join("slurm/shard.sbatch")).args(["campaign", "3", runs_s, "ledge_test3"]).output().unwrap();
    assert!(!out.status.success() && String::from_utf8_lossy(&out.stderr).contains("run as a job array task"));
}

#[test]
fn the_kubernetes_pod_commands_give_the_unsharded_mission_campaign() {
    let d = dir("k8s");
    let sc = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/mission_smoke.toml");
    let sc = sc.to_str().unwrap();
    let whole = d.join("whole");
    tetherbot(&["mission", sc, "--seeds", "3", "--seed", "5", "--threads", "1", "--out", whole.to_str().unwrap()]);
    let out = d.join("results");
    let out_s = out.to_str().unwrap();
    for k in ["0", "1", "2"] {
        // the pod's command line of k8s/campaign-shards.yaml, JOB_COMPLETION_INDEX = k
        bash(&cluster().join("run-shard.sh"), &["mission", k, "3", out_s, sc, "--", "--seeds", "3", "--seed", "5"], &[("THREADS", "1")]);
    }
    let text = bash(&cluster().join("run-merge.sh"), &["mission", "3", out_s], &[]);
    assert!(text.contains("merged 3 shards of mission campaign mission_smoke: 3 missions"), "{text}");
    same(&whole.join("mission_smoke-campaign.json"), &out.join("merged/mission_smoke-campaign.json"));
    // a second merge refuses to overwrite the first, FORCE=1 replaces it
    let again = Command::new("bash").arg(cluster().join("run-merge.sh")).args(["mission", "3", out_s])
        .env("TETHERBOT", env!("CARGO_BIN_EXE_tetherbot")).output().unwrap();
    assert!(!again.status.success() && String::from_utf8_lossy(&again.stderr).contains("--force"));
    bash(&cluster().join("run-merge.sh"), &["mission", "3", out_s], &[("FORCE", "1")]);
}

/// The value of the `name: NAME` env entry, or of the `key:` line, in a manifest (text; no YAML parser in the
/// workspace: `kubernetes-validate` checked the schema, see `host-sim/doc/campaign.md`).
fn manifest_value(text: &str, key: &str) -> Option<String> {
    let mut lines = text.lines().map(str::trim);
    while let Some(l) = lines.next() {
        if l == format!("- name: {key}") {
            return lines.next()?.strip_prefix("value: ").map(|v| v.trim_matches('"').to_string());
        }
        if let Some(v) = l.strip_prefix(&format!("{key}: ")) {
            return Some(v.to_string());
        }
    }
    None
}

#[test]
fn the_kubernetes_manifests_agree_on_the_split() {
    let shards = std::fs::read_to_string(cluster().join("k8s/campaign-shards.yaml")).unwrap();
    let merge = std::fs::read_to_string(cluster().join("k8s/campaign-merge.yaml")).unwrap();
    let pvc = std::fs::read_to_string(cluster().join("k8s/results-pvc.yaml")).unwrap();
    assert_eq!(manifest_value(&shards, "completionMode").as_deref(), Some("Indexed"));
    let n = manifest_value(&shards, "completions");
    assert!(n.is_some());
    assert_eq!(manifest_value(&shards, "SHARDS"), n, "SHARDS must be the Job's completions");
    assert_eq!(manifest_value(&merge, "SHARDS"), n, "the merge must expect as many shards");
    assert_eq!(manifest_value(&shards, "KIND"), manifest_value(&merge, "KIND"));
    assert!(shards.contains("run-shard.sh") && shards.contains("$JOB_COMPLETION_INDEX") && merge.contains("run-merge.sh"));
    let claim = manifest_value(&pvc, "name");
    assert_eq!(manifest_value(&shards, "claimName"), claim);
    assert_eq!(manifest_value(&merge, "claimName"), claim);
}
