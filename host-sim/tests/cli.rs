//! The `tetherbot` binary end to end: run, record, replay (identical -> exit 0; a changed output byte -> exit 1
//! naming the record and byte; a damaged log -> exit 1 with the damage offset), inspect, export.

use std::process::Command;

use host_sim::fieldlog::{self, Direction};

fn tetherbot(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_tetherbot"))
        .args(args)
        .output()
        .unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

#[test]
fn record_replay_inspect_export_and_mismatch_exit_codes() {
    let dir = std::env::temp_dir().join(format!("tetherbot-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let log = dir.join("run.fieldlog");
    let log_s = log.to_str().unwrap();

    let (code, out) = tetherbot(&[
        "record",
        "protocol",
        "-o",
        log_s,
        "--created-at-ms",
        "0",
        "--seed",
        "4",
    ]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("result: PASS"), "{out}");
    let (code, out) = tetherbot(&["replay", log_s]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("identical"), "{out}");

    // change byte 5 of the second flight -> host record, keeping the record's checksum valid
    let parsed = fieldlog::read_file(&log).unwrap();
    let k = parsed
        .records
        .iter()
        .enumerate()
        .filter(|(_, r)| r.direction == Direction::FlightToHost)
        .nth(1)
        .unwrap()
        .0;
    let mut w = fieldlog::Writer::new(Vec::new(), &parsed.header).unwrap();
    for (i, r) in parsed.records.iter().enumerate() {
        let mut b = r.bytes.clone();
        if i == k {
            b[5] ^= 0x01;
        }
        w.append(r.direction, r.t_us, &b).unwrap();
    }
    let changed = dir.join("changed.fieldlog");
    std::fs::write(&changed, w.into_inner()).unwrap();
    let (code, out) = tetherbot(&["replay", changed.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains(&format!("record #{k}, byte 5 ")), "{out}");

    // flip a byte inside the last record: inspect and replay report the damage at that record's offset
    let mut bytes = std::fs::read(&log).unwrap();
    let last = parsed.records.last().unwrap().offset;
    bytes[last as usize + 14] ^= 0xFF;
    let damaged = dir.join("damaged.fieldlog");
    std::fs::write(&damaged, &bytes).unwrap();
    let (code, out) = tetherbot(&["inspect", damaged.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(
        out.contains(&format!("DAMAGED at byte {last} (BadChecksum)")),
        "{out}"
    );
    let (code, out) = tetherbot(&["replay", damaged.to_str().unwrap()]);
    assert_eq!(code, 1, "{out}");
    assert!(out.contains(&format!("damaged at byte {last}")), "{out}");

    let mcap = dir.join("run.mcap");
    let (code, out) = tetherbot(&["export", log_s, "--mcap", mcap.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}");
    let m = std::fs::read(&mcap).unwrap();
    assert_eq!(&m[..8], b"\x89MCAP0\r\n", "MCAP magic");
    assert!(
        out.contains("1 undecodable"),
        "the scenario's damaged frame is exported as an error: {out}"
    );

    let (code, out) = tetherbot(&["run", "no-such-scenario"]);
    assert_eq!(code, 2, "{out}");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A scenario's `[faults]` section faults the mission's uplink as `--faults` does (the faults are in the field log
/// and accounted for); `--faults none` replaces it with a clean link.
#[test]
fn a_scenarios_faults_section_faults_the_mission_and_the_command_line_replaces_it() {
    let dir = std::env::temp_dir().join(format!("tetherbot-cli-faults-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/mission_faults.toml");
    let text = std::fs::read_to_string(&base).unwrap();
    // a built-in world: the copy needs no terrain file beside it
    let scen = dir.join("faulty.toml");
    std::fs::write(&scen, format!("{text}\n[faults]\ndrop = 1e-4\nduplicate = 1e-4\nseed = 3\n")).unwrap();
    let s = |p: &std::path::Path| p.to_str().unwrap().to_string();
    let (code, out) = tetherbot(&["mission", &s(&scen), "--quiet", "--out", &s(&dir.join("a")), "--created-at-ms", "0"]);
    assert_eq!(code, 0, "{out}");
    assert!(out.contains("faults drop") && out.contains("faults duplicate"), "{out}");
    assert!(out.contains("fault accounting balanced"), "{out}");
    let log = fieldlog::parse(&std::fs::read(dir.join("a/mission_faults.fieldlog")).unwrap()).unwrap();
    assert!(!log.faults.is_empty(), "no fault records in the log");

    let (code, out) =
        tetherbot(&["mission", &s(&scen), "--quiet", "--faults", "none", "--out", &s(&dir.join("b")), "--created-at-ms", "0"]);
    assert_eq!(code, 0, "{out}");
    assert!(!out.contains("injected") && !out.contains("fault accounting"), "{out}");
    let log = fieldlog::parse(&std::fs::read(dir.join("b/mission_faults.fieldlog")).unwrap()).unwrap();
    assert!(log.faults.is_empty(), "{} fault records with --faults none", log.faults.len());
    std::fs::remove_dir_all(&dir).ok();
}
