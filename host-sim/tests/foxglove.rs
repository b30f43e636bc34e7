//! The Foxglove output checked by readers nobody here wrote (issue 23, item 2): a mission's MCAP read by the
//! Python `mcap` library and decoded with Foxglove's published schemas (`foxglove-schemas-protobuf`,
//! `jsonschema`), its channels, counts and poses compared with the field log; and the `--live` view received by
//! a Python `websockets` client on loopback. Both run `host-sim/tests/foxglove_check.py`.
//!
//! Python: `$TETHERBOT_PYTHON`, else the venv `.ci/run` makes (`<target dir>/foxglove-venv/bin/python`), else
//! `python3`, if it imports the packages. Without them the tests say why and pass, except under `CI=true`,
//! where they fail.

use std::path::{Path, PathBuf};
use std::process::Command;

use firmware::protocol::{self, Deframer, Message};
use host_sim::fieldlog::{self, Direction};

/// A short mission: the lateral-tether descent, 5 minutes of link time at most.
const SCENARIO: &str = "scenarios/mission_lateral.toml";
const MODULES: &str =
    "import mcap, mcap_protobuf, foxglove_schemas_protobuf, jsonschema, websockets";

fn python() -> Option<PathBuf> {
    let bin = PathBuf::from(env!("CARGO_BIN_EXE_tetherbot"));
    let venv = bin
        .parent()
        .and_then(Path::parent)
        .map(|t| t.join("foxglove-venv/bin/python"));
    let candidates = std::env::var_os("TETHERBOT_PYTHON")
        .map(PathBuf::from)
        .into_iter()
        .chain(venv)
        .chain([PathBuf::from("python3")]);
    candidates.into_iter().find(|p| Command::new(p).args(["-c", MODULES]).output().is_ok_and(|o| o.status.success()))
}

/// The Python with the packages, or `None` after saying why (a failure under `CI=true`).
fn python_or_skip(test: &str) -> Option<PathBuf> {
    let p = python();
    if p.is_none() {
        let why = "no python with mcap, mcap-protobuf-support, foxglove-schemas-protobuf, jsonschema and websockets \
                   (bash .ci/run makes the venv <target>/foxglove-venv; or set TETHERBOT_PYTHON)";
        assert!(
            std::env::var("CI").as_deref() != Ok("true"),
            "{test}: {why}"
        );
        eprintln!("{test}: skipped: {why}");
    }
    p
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("tetherbot-foxglove-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn scenario() -> String {
    s(&Path::new(env!("CARGO_MANIFEST_DIR")).join(SCENARIO)).to_string()
}

/// What the field log says, counted here with the protocol's own decoder (not the exporter's code), for the
/// checker to compare with the MCAP; the raw bytes of each direction go beside it as `<stem>-h2f.bin` / `-f2h.bin`.
fn expectations(log_path: &Path, summary: &Path, out: &Path) {
    let log = fieldlog::read_file(log_path).unwrap();
    let mut records = [0usize; 2];
    let mut frames = [0usize; 2];
    let mut raw = [Vec::new(), Vec::new()];
    let mut deframers = [Deframer::new(), Deframer::new()];
    let (
        mut bad,
        mut scans,
        mut points,
        mut plans,
        mut logs,
        mut readings,
        mut status,
        mut telemetry,
    ) = (0, 0, 0, 0, 0, 0, 0, 0);
    let mut poses = Vec::new();
    let mut scan: Option<(u32, u16, u16, usize)> = None;
    for r in &log.records {
        let side = usize::from(r.direction == Direction::FlightToHost);
        records[side] += 1;
        raw[side].extend_from_slice(&r.bytes);
        let mut rest = &r.bytes[..];
        while !rest.is_empty() {
            let (n, ev) = deframers[side].push(rest);
            rest = &rest[n..];
            let Some(ev) = ev else { continue };
            frames[side] += 1;
            let Ok((_, m)) = ev
                .map_err(protocol::NackReason::from)
                .and_then(protocol::decode_frame)
            else {
                bad += 1;
                continue;
            };
            let t_ns = r.t_us * 1000;
            match m {
                Message::MotionReport(m) => {
                    let (p, q) = (m.pose.position, m.pose.orientation);
                    let v = [p.x, p.y, p.z, q.x, q.y, q.z, q.w].map(f64::from);
                    poses.push(serde_json::json!([
                        t_ns, v[0], v[1], v[2], v[3], v[4], v[5], v[6]
                    ]));
                }
                Message::SensorChunk(c) => {
                    scan = match scan {
                        _ if c.chunk_index == 0 => {
                            Some((c.scan_id, 1, c.chunk_count, c.points.len()))
                        }
                        Some((id, next, count, n))
                            if id == c.scan_id
                                && next == c.chunk_index
                                && count == c.chunk_count =>
                        {
                            Some((id, next + 1, count, n + c.points.len()))
                        }
                        _ => None,
                    };
                    if let Some((_, next, count, n)) = scan {
                        if next == count {
                            scans += 1;
                            points += n;
                            scan = None;
                        }
                    }
                }
                Message::Plan(p) if p.part + 1 == p.parts => plans += 1,
                Message::Log(_) => logs += 1,
                Message::TetherReading(_) => readings += 1,
                Message::MissionStatus(_) => status += 1,
                Message::Telemetry(_) => telemetry += 1,
                _ => {}
            }
        }
    }
    let n_poses = poses.len();
    let rep: serde_json::Value = serde_json::from_slice(&std::fs::read(summary).unwrap()).unwrap();
    let exp = serde_json::json!({
        "seed": log.header.seed,
        "summary": s(summary),
        "records": {"h2f": records[0], "f2h": records[1]},
        "frames": {"h2f": frames[0], "f2h": frames[1]},
        "bad_frames": bad,
        "scans": scans,
        "scan_points": points,
        "plans": plans,
        "log_frames": logs,
        "tether_readings": readings,
        "mission_status": status,
        "telemetry": telemetry,
        "poses": poses,
        "tether_snapshots": rep["tethers"].as_array().unwrap().len(),
        "layout": s(&Path::new(env!("CARGO_MANIFEST_DIR")).join("doc/foxglove/tetherbot-layout.json")),
    });
    assert!(
        n_poses > 0 && scans > 0 && plans > 0,
        "the mission drove, scanned and planned: {exp:?}"
    );
    std::fs::write(out, serde_json::to_vec(&exp).unwrap()).unwrap();
    let stem = out.with_extension("");
    std::fs::write(format!("{}-h2f.bin", s(&stem)), &raw[0]).unwrap();
    std::fs::write(format!("{}-f2h.bin", s(&stem)), &raw[1]).unwrap();
}

fn run(cmd: &mut Command) -> (i32, String) {
    let out = cmd.output().unwrap();
    let text =
        String::from_utf8_lossy(&out.stdout).to_string() + &String::from_utf8_lossy(&out.stderr);
    (out.status.code().unwrap_or(-1), text)
}

fn checker() -> String {
    s(&Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/foxglove_check.py")).to_string()
}

/// One test for both readers: a mission run twice (plain, then `--live`) is the costly part.
#[test]
fn a_missions_mcap_and_live_view_decode_with_foxglove_published_schemas_and_match_the_field_log() {
    let Some(py) = python_or_skip("foxglove checks") else {
        return;
    };
    let d = dir("mcap");
    let bin = env!("CARGO_BIN_EXE_tetherbot");
    let sc = scenario();
    let plain = d.join("plain");
    let (code, out) = run(Command::new(bin).args([
        "mission",
        &sc,
        "--quiet",
        "--out",
        s(&plain),
        "--created-at-ms",
        "0",
    ]));
    assert_eq!(code, 0, "{out}");
    let stem = plain.join("mission_lateral");
    let (log, mcap, summary) = (
        stem.with_extension("fieldlog"),
        stem.with_extension("mcap"),
        stem.with_extension("json"),
    );
    let exp = d.join("expected.json");
    expectations(&log, &summary, &exp);
    let (code, out) = run(Command::new(&py).args([&checker(), "mcap", s(&mcap), s(&exp)]));
    println!("{out}");
    assert_eq!(
        code,
        0,
        "the Python reader found faults in {}:\n{out}",
        mcap.display()
    );
    assert!(out.contains(" passed, 0 failed"), "{out}");

    // the export of the field log alone (what the wire says): the wire checks pass, the truth's fail
    let wire = d.join("wire.mcap");
    let (code, out) = run(Command::new(bin).args(["export", s(&log), "--mcap", s(&wire)]));
    assert_eq!(code, 0, "{out}");
    let (code, out) = run(Command::new(&py).args([&checker(), "mcap", s(&wire), s(&exp)]));
    assert_ne!(code, 0, "a field log alone has no truth channels: {out}");
    assert!(
        out.contains("FAIL: /tf rover_true") && !out.contains("FAIL: /tf rover:"),
        "{out}"
    );

    // the live view, received by a WebSocket client on loopback
    let live = d.join("live");
    let (code, out) = run(Command::new(&py).args([
        &checker(),
        "live",
        "--",
        bin,
        "mission",
        &sc,
        "--quiet",
        "--out",
        s(&live),
        "--created-at-ms",
        "0",
        "--live",
        "127.0.0.1:0",
        "--live-wait",
        "60",
    ]));
    println!("{out}");
    assert_eq!(code, 0, "the WebSocket client found faults:\n{out}");
    assert!(out.contains(" passed, 0 failed"), "{out}");
    // the live view observes the link and changes nothing in it: the field log is the one written without it
    let a = std::fs::read(&log).unwrap();
    let b = std::fs::read(live.join("mission_lateral.fieldlog")).unwrap();
    assert!(
        a == b,
        "the field log with --live differs from the one without"
    );
    std::fs::remove_dir_all(&d).unwrap();
}
