//! Regression tests for the bad-input defects of issue 24, each driving the `tetherbot` binary the way the sweep
//! did: every bad input ends (no hang) with a non-zero exit and a reason a person can act on, and nothing valid is
//! lost or overwritten. (They live in host-sim, not in `tests/`: only the crate that owns the binary gets
//! `CARGO_BIN_EXE_tetherbot`.)

use std::path::{Path, PathBuf};
use std::process::Command;

use host_sim::fieldlog::{self, Direction, Header, Writer};

fn tetherbot(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tetherbot")).args(args).output().unwrap();
    let text = String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tetherbot-bad-input-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn data(rel: &str) -> String {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data").join(rel);
    p.canonicalize().unwrap().to_str().unwrap().to_string()
}

const LEDGE: &str = r#"
name = "NAME"
[world]
kind = "ledge"
[rover]
start = [-1.5, 0.0, 4.35]
[tether]
root_anchor = [-6.4, 0.0, 6.35]
[goal]
position = [6.0, 0.0, 0.35]
[plan]
bounds_min = [-5.0, -5.0, -0.5]
bounds_max = [7.5, 5.0, 7.5]
"#;

fn scenario(d: &Path, file: &str, text: &str) -> PathBuf {
    let p = d.join(file);
    std::fs::write(&p, text).unwrap();
    p
}

fn record(d: &Path, name: &str) -> PathBuf {
    let log = d.join(name);
    let (code, out) = tetherbot(&["record", "protocol", "-o", s(&log), "--created-at-ms", "0", "--seed", "3"]);
    assert_eq!(code, 0, "{out}");
    log
}

#[test]
fn replay_of_a_record_stamped_u64_max_is_refused_not_run_for_ever() {
    let d = dir("replay-time");
    let header = Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: 1,
        config: r#"{"scenario":"protocol","link":"inproc","step_us":1000}"#.into(),
    };
    let mut w = Writer::new(Vec::new(), &header).unwrap();
    w.append(Direction::HostToFlight, 10, &[0]).unwrap();
    w.append(Direction::HostToFlight, u64::MAX, &[0]).unwrap();
    let log = d.join("late.fieldlog");
    std::fs::write(&log, w.finish().unwrap()).unwrap();
    let (code, out) = tetherbot(&["replay", s(&log)]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("record #1") && out.contains("--max-link-time-s"), "{out}");
}

#[test]
fn a_log_cut_at_a_record_boundary_is_not_identical_nor_undamaged() {
    let d = dir("cut");
    let log = record(&d, "run.fieldlog");
    let bytes = std::fs::read(&log).unwrap();
    let parsed = fieldlog::parse(&bytes).unwrap();
    let end = parsed.end.expect("a recorded log has an end record").offset as usize;
    // Cut exactly before the end record, and exactly before the last data record.
    for cut in [end, parsed.records.last().unwrap().offset as usize] {
        let p = d.join(format!("cut{cut}.fieldlog"));
        std::fs::write(&p, &bytes[..cut]).unwrap();
        let (code, out) = tetherbot(&["replay", s(&p)]);
        assert_eq!(code, 1, "{out}");
        assert!(out.contains("NOT VERIFIED") && out.contains("no end record: truncated?"), "{out}");
        assert!(!out.contains("identical"), "{out}");
        let (code, out) = tetherbot(&["inspect", s(&p)]);
        assert_eq!(code, 1, "{out}");
        assert!(out.contains("INCOMPLETE: no end record: truncated?") && !out.contains("no damage"), "{out}");
    }
    let (code, out) = tetherbot(&["inspect", s(&log)]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains(&format!("no damage; end record: {} records, all read", parsed.records.len())), "{out}");
}

#[test]
fn one_flipped_payload_bit_loses_one_record_not_the_rest() {
    let d = dir("flip");
    let log = record(&d, "run.fieldlog");
    let mut bytes = std::fs::read(&log).unwrap();
    let parsed = fieldlog::parse(&bytes).unwrap();
    let k = parsed.records.len() / 3;
    let at = parsed.records[k].offset;
    bytes[at as usize + 13] ^= 0x10;
    let p = d.join("flipped.fieldlog");
    std::fs::write(&p, &bytes).unwrap();
    let (code, out) = tetherbot(&["inspect", s(&p)]);
    assert_eq!(code, 1, "{out}");
    let n = parsed.records.len();
    assert!(out.contains(&format!("DAMAGED at byte {at} (BadChecksum)")), "{out}");
    assert!(out.contains(&format!("{} valid records read; INCOMPLETE: 1 damaged span(s) skipped; 1 record(s) lost", n - 1)), "{out}");
    let reread = fieldlog::parse(&bytes).unwrap();
    assert_eq!(reread.records.last(), parsed.records.last(), "the records after the damage are kept");
}

#[test]
fn export_and_record_refuse_to_overwrite() {
    let d = dir("overwrite");
    let log = record(&d, "run.fieldlog");
    let before = std::fs::read(&log).unwrap();
    let (code, out) = tetherbot(&["export", s(&log), "--mcap", s(&log)]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("is the input"), "{out}");
    let (code, out) = tetherbot(&["export", s(&log), "--mcap", s(&log), "--force"]);
    assert_eq!(code, 2, "{out}");
    let (code, out) = tetherbot(&["record", "protocol", "-o", s(&log), "--seed", "9"]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("exists") && out.contains("--force"), "{out}");
    assert_eq!(std::fs::read(&log).unwrap(), before, "the log is untouched");
    let mcap = d.join("out.mcap");
    std::fs::write(&mcap, b"keep").unwrap();
    let (code, out) = tetherbot(&["export", s(&log), "--mcap", s(&mcap)]);
    assert_eq!((code, std::fs::read(&mcap).unwrap()), (2, b"keep".to_vec()), "{out}");
    let (code, out) = tetherbot(&["export", s(&log), "--mcap", s(&mcap), "--force"]);
    assert_eq!(code, 0, "{out}");
    let (code, out) = tetherbot(&["record", "protocol", "-o", s(&log), "--seed", "9", "--force"]);
    assert_eq!(code, 0, "{out}");
}

#[test]
fn campaign_options_are_checked_before_any_work() {
    let cases: [(&[&str], &str); 5] = [
        (&["--seed", "18446744073709551615", "--trials", "2"], "passes u64::MAX"),
        (&["--trials", "1", "--rewire-factor", "nan"], "rewire_factor must be positive and finite"),
        (&["--trials", "1", "--copy-fraction", "2"], "attachment_copy_fraction must be in [0, 1]"),
        (&["--trials", "1", "--samples-per-batch", "0"], "samples_per_batch must be at least 1"),
        (&["--trials", "1", "--iterations", "0"], "--iterations must be at least 1"),
    ];
    for (extra, want) in cases {
        let mut args = vec!["campaign", "ledge_test1", "--threads", "1"];
        args.extend_from_slice(extra);
        let (code, out) = tetherbot(&args);
        assert_eq!(code, 2, "{extra:?}: {out}");
        assert!(out.contains(want), "{extra:?}: {out}");
        assert!(!out.contains("found stable"), "{extra:?} ran: {out}");
    }
    // The last seed that fits runs.
    let out_dir = dir("campaign-seed");
    let (code, out) = tetherbot(&[
        "campaign", "ledge_test1", "--seed", "18446744073709551614", "--trials", "2", "--iterations", "1",
        "--threads", "1", "--field", "truth", "--out", s(&out_dir),
    ]);
    assert_eq!(code, 0, "{out}");
}

#[test]
fn campaign_applies_the_scenarios_map_voxel_pool_and_tether_length() {
    let d = dir("campaign-fields");
    let run = |sc: &Path| {
        tetherbot(&["campaign", s(sc), "--trials", "1", "--iterations", "5", "--threads", "1", "--out", s(&d)])
    };
    let base = LEDGE.replace("NAME", "fields");
    let (code, out) = run(&scenario(&d, "plain.toml", &base));
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("(0.10 m voxels") && out.contains("| 1 | 0 | 0 |"), "{out}");
    let (code, out) = run(&scenario(&d, "voxel.toml", &format!("{base}[map]\nvoxel_size_m = 0.15\n")));
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("(0.15 m voxels"), "{out}");
    let (code, out) = run(&scenario(&d, "pool.toml", &format!("{base}[map]\npool_blocks = 4\n")));
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("the pool of 4 blocks (map.pool_blocks)"), "{out}");
    let short = base.replace("root_anchor = [-6.4, 0.0, 6.35]", "root_anchor = [-6.4, 0.0, 6.35]\nlength_m = 3.0");
    let (code, out) = run(&scenario(&d, "tether.toml", &short));
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("| 0 | 1 | 0 |") && out.contains("(tether.length_m)"), "{out}");
    let noted = format!("{base}[sensor]\nmax_range_m = 5.0\n").replace("position = [6.0, 0.0, 0.35]", "position = [6.0, 0.0, 0.35]\ntolerance_m = 0.3");
    let (code, out) = run(&scenario(&d, "noted.toml", &noted));
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("note: [sensor] does not apply to campaign"), "{out}");
    assert!(out.contains("note: goal.tolerance_m (0.3) does not apply to campaign"), "{out}");
}

#[test]
fn a_scenario_name_cannot_write_outside_the_output_directory() {
    let d = dir("campaign-name");
    let sc = scenario(&d, "escape.toml", &LEDGE.replace("NAME", "../../../escape"));
    let (code, out) = tetherbot(&["campaign", s(&sc), "--trials", "1", "--iterations", "1", "--threads", "1", "--field", "truth"]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("target/campaign/.._.._.._escape/{results.json"), "{out}");
}

#[test]
fn map_check_uses_the_scenarios_map_and_sensor() {
    let d = dir("map-check");
    let base = LEDGE.replace("NAME", "coarse");
    let sc = scenario(&d, "coarse.toml", &format!("{base}[map]\nvoxel_size_m = 5.0\n[sensor]\nresolution_deg = 5.0\n"));
    let (code, out) = tetherbot(&["map-check", "--world", s(&sc)]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("voxel 5 m, truncation 15 m"), "{out}");
    assert!(out.contains("sensor 247 rays/scan"), "{out}");
    // A sensor that sees nothing: no integrated point is an error, not a pass.
    let blind = scenario(&d, "blind.toml", &format!("{base}[sensor]\nresolution_deg = 5.0\nmin_range_m = 0.0\nmax_range_m = 0.01\n"));
    let (code, out) = tetherbot(&["map-check", "--world", s(&blind)]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("no point was integrated"), "{out}");
}

#[test]
fn dem_scales_and_infinite_heights_are_rejected_at_load() {
    let d = dir("dem");
    let terrain = |file: &str, extra: &str| {
        format!(
            "name = \"t\"\n[world]\nkind = \"terrain\"\n[world.terrain]\nfile = \"{file}\"\n{extra}\n\
             [rover]\nstart = [0.0, 0.0, 30.0]\n[tether]\nroot_anchor = [1.0, 1.0, 30.0]\n[goal]\nposition = [2.0, 2.0, 30.0]\n"
        )
    };
    let npy = data("terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy");
    let mut asc = String::from("ncols 4\nnrows 4\ncellsize 1.0\n");
    for r in 0..4 {
        asc += &format!("{} 1 2 3\n", if r == 2 { "inf" } else { "0" });
    }
    let asc_file = d.join("inf.asc");
    std::fs::write(&asc_file, asc).unwrap();
    let cases = [
        // this one never ended (3e10 ray-cast steps per ray)
        (terrain(&npy, "spacing_m = 1.01\nhorizontal_scale = 1e-9"), "is below 0.001 m"),
        (terrain(&npy, "spacing_m = 1.01\nvertical_scale = 1e308"), "every height must be finite"),
        (terrain(&npy, "spacing_m = 1.01\nvertical_scale = 1e4"), "above the ray-cast budget"),
        (terrain(s(&asc_file), ""), "(file row 2, column 0) is inf"),
    ];
    for (i, (text, want)) in cases.iter().enumerate() {
        let sc = scenario(&d, &format!("t{i}.toml"), text);
        let (code, out) = tetherbot(&["map-check", "--world", s(&sc)]);
        assert_eq!(code, 2, "{want}: {out}");
        assert!(out.contains(want), "{want}: {out}");
    }
}

#[test]
fn a_degenerate_obj_is_an_error() {
    let d = dir("obj");
    let obj = d.join("flat.obj");
    std::fs::write(&obj, "v 0 0 0\nv 1 1 1\nv 2 2 2\nv 3 3 3\nf 1 2 3\nf 2 3 4\n").unwrap();
    let text = format!(
        "name = \"m\"\n[world]\nkind = \"mesh\"\n[world.mesh]\nfile = \"{}\"\n[rover]\nstart = [0.0, 0.0, 0.0]\n\
         [tether]\nroot_anchor = [0.0, 0.0, 0.0]\n[goal]\nposition = [0.0, 0.0, 0.0]\n",
        s(&obj)
    );
    let sc = scenario(&d, "m.toml", &text);
    let (code, out) = tetherbot(&["map-check", "--world", s(&sc)]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("degenerate"), "{out}");
}

#[test]
fn a_truncated_moving_ai_scen_file_is_an_error() {
    let d = dir("scen");
    let text = std::fs::read_to_string(data("movingai/arena2.map.scen")).unwrap();
    let cut = d.join("cut.scen");
    std::fs::write(&cut, &text[..text.len() - 5]).unwrap();
    let (code, out) = tetherbot(&["movingai", &data("movingai/arena2.map"), s(&cut)]);
    assert_eq!(code, 2, "{out}");
    assert!(out.contains("truncated"), "{out}");
}

#[test]
fn mission_campaign_seeds_past_u64_max_are_refused_before_any_mission() {
    let d = dir("mission-seed");
    let out = d.join("out");
    let (code, text) = tetherbot(&["mission", "--seed", "18446744073709551615", "--seeds", "2", "--quiet", "--out", s(&out)]);
    assert_eq!(code, 2, "{text}");
    assert!(text.contains("passes u64::MAX; use a seed of at most 18446744073709551614"), "{text}");
    assert!(!text.contains("mission campaign") && !out.exists(), "it ran: {text}");
}

#[test]
fn a_mission_scenario_name_cannot_write_outside_the_output_directory() {
    let d = dir("mission-name");
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/mission_ledge_test3.toml")).unwrap();
    assert!(text.contains("name = \"mission_ledge_test3\""));
    let sc = scenario(&d, "escape.toml", &text.replace("name = \"mission_ledge_test3\"", "name = \"../../escape\""));
    let out = d.join("a").join("b");
    // one mission (field log, MCAP, picture, JSON) and a campaign of two, as a shard too
    let (code, text) = tetherbot(&["mission", s(&sc), "--quiet", "--created-at-ms", "0", "--out", s(&out)]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = tetherbot(&["mission", s(&sc), "--seeds", "2", "--threads", "1", "--out", s(&out)]);
    assert_eq!(code, 0, "{text}");
    let (code, text) = tetherbot(&["mission", s(&sc), "--seeds", "2", "--shard", "1/2", "--threads", "1", "--out", s(&out)]);
    assert_eq!(code, 0, "{text}");
    let mut names: Vec<String> = std::fs::read_dir(&out).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    assert_eq!(
        names,
        [
            ".._.._escape-campaign-shard-1-of-2-timing.json",
            ".._.._escape-campaign-shard-1-of-2.json",
            ".._.._escape-campaign-timing.json",
            ".._.._escape-campaign.json",
            ".._.._escape.fieldlog",
            ".._.._escape.json",
            ".._.._escape.mcap",
            ".._.._escape.svg",
        ]
    );
    assert_eq!(std::fs::read_dir(&d).unwrap().count(), 2, "only escape.toml and a/ in {}", d.display());
}

#[test]
fn shard_options_and_merge_inputs_are_checked_with_a_reason() {
    let d = dir("shard");
    let cases: [(&[&str], &str); 6] = [
        (&["campaign", "ledge_test1", "--shard", "4/4"], "K must be below N"),
        (&["campaign", "ledge_test1", "--shard", "2"], "no '/'"),
        (&["campaign", "ledge_test1", "--trials", "3", "--shard", "0/4"], "4 shards for 3 trials would leave a shard empty"),
        (&["mission", "--seeds", "2", "--shard", "0/3"], "3 shards for 2 missions would leave a shard empty"),
        (&["campaign", "merge", "OUT", "/no/such/results.json"], "/no/such/results.json: cannot read it"),
        (&["mission", "merge", "OUT", "/no/such/x-campaign-shard-0-of-2.json"], "cannot read it"),
    ];
    for (args, want) in cases {
        let args: Vec<String> = args.iter().map(|a| if *a == "OUT" { s(&d.join("merged")).to_string() } else { a.to_string() }).collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (code, out) = tetherbot(&args);
        assert_eq!(code, 2, "{args:?}: {out}");
        assert!(out.contains(want), "{args:?}: {out}");
        assert!(!out.contains("found stable") && !out.contains("mission campaign"), "{args:?} ran: {out}");
    }
    let junk = d.join("junk.json");
    std::fs::write(&junk, "{\"trials\": [").unwrap();
    for kind in ["campaign", "mission"] {
        let (code, out) = tetherbot(&[kind, "merge", s(&d.join("merged")), s(&junk)]);
        assert_eq!(code, 2, "{out}");
        assert!(out.contains("junk.json: not a") && out.contains("(corrupt, truncated or another kind of file)"), "{out}");
    }
    assert!(!d.join("merged").exists());
}
