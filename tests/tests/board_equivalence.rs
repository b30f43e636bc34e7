//! Equivalence of the flight software in-process and on the emulated flight computer (QEMU mps2-an500,
//! Cortex-M7, the cross-compiled board binary behind an emulated UART): the same scenario and seed give
//! byte-identical flight -> host output. Both runs are recorded as field logs; the logs' records must be equal,
//! and `replay` of the board's log on a fresh in-process executive must report it identical. The bad-input matrix
//! of the foundation runs over the board link too.
//!
//! Later issues add their scenarios to `SCENARIO_SEEDS` (or their own functions below).
//!
//! Cost: the board binary is built on first use (about a minute cold, under a second when up to date); each
//! board run boots QEMU (tens of ms) and steps the executive in lockstep, one control round trip per host call.
//! Skips with a plain message when `qemu-system-arm` is absent, unless `CI=true`.

use core::time::Duration;

use host_sim::fieldlog::{self, Header, Writer};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::qemu::QemuLink;
use host_sim::link::recording::RecordingLink;
use host_sim::link::FlightLink;
use host_sim::qemu;
use host_sim::replay::{replay, ReplayOutcome};
use host_sim::scripted as scenario;

/// (scenario, seed) pairs run on both links.
const SCENARIO_SEEDS: &[(&str, u64)] = &[("protocol", 1), ("protocol", 7)];

fn board(test: &str) -> Option<std::path::PathBuf> {
    qemu::board_for_tests(test).unwrap_or_else(|e| panic!("{e}"))
}

fn header(seed: u64, link: &str) -> Header {
    Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed,
        config: format!(r#"{{"scenario":"protocol","link":"{link}","step_us":{DEFAULT_STEP_US}}}"#),
    }
}

/// Runs `scenario` over `link` while recording; returns the parsed log and whether the scenario passed.
fn record<L: FlightLink>(link: L, name: &str, seed: u64) -> (fieldlog::FieldLog, bool, L) {
    let writer = Writer::new(Vec::new(), &header(seed, link.name())).expect("in-memory log");
    let mut rec = RecordingLink::new(link, writer);
    assert_eq!(name, "protocol", "only the protocol scenario exists so far");
    let report = scenario::run_protocol(&mut rec, seed)
        .unwrap_or_else(|e| panic!("{name} seed {seed}: {e}"));
    let (link, bytes) = rec.finish().expect("flush in-memory log");
    let log = fieldlog::parse(&bytes).expect("own log parses");
    assert!(log.damage.is_none(), "fresh log damaged: {:?}", log.damage);
    (log, report.passed(), link)
}

#[test]
fn scenarios_give_identical_flight_output_in_process_and_on_the_board() {
    let Some(elf) = board("board equivalence") else {
        return;
    };
    for &(name, seed) in SCENARIO_SEEDS {
        let (inproc_log, inproc_ok, _) = record(InProcLink::new(DEFAULT_STEP_US), name, seed);
        let board_link = QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
        let (board_log, board_ok, board_link) = record(board_link, name, seed);
        let exit = board_link
            .quit(Duration::from_secs(10))
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            exit.status.success(),
            "board exit: {:?}\n{}",
            exit.status,
            exit.output.both()
        );

        assert!(
            inproc_ok && board_ok,
            "{name}/{seed}: scenario expectations in-process {inproc_ok}, board {board_ok}"
        );
        let out = |log: &fieldlog::FieldLog| -> Vec<u8> {
            log.records
                .iter()
                .filter(|r| r.direction == fieldlog::Direction::FlightToHost)
                .flat_map(|r| r.bytes.iter().copied())
                .collect()
        };
        let (a, b) = (out(&inproc_log), out(&board_log));
        assert!(!a.is_empty(), "{name}/{seed}: no flight output recorded");
        if let Some(i) = a.iter().zip(&b).position(|(x, y)| x != y) {
            panic!(
                "{name}/{seed}: flight->host streams differ at byte {i} of {} / {}",
                a.len(),
                b.len()
            );
        }
        assert_eq!(
            a.len(),
            b.len(),
            "{name}/{seed}: flight->host stream lengths differ"
        );
        // Same bytes at the same link times, both directions.
        let strip = |log: &fieldlog::FieldLog| -> Vec<(fieldlog::Direction, u64, Vec<u8>)> {
            log.records
                .iter()
                .map(|r| (r.direction, r.t_us, r.bytes.clone()))
                .collect()
        };
        assert_eq!(
            strip(&inproc_log),
            strip(&board_log),
            "{name}/{seed}: records differ"
        );
        // The replay tool agrees: the board's log replays identically on a fresh in-process executive.
        let outcome = replay(&board_log, &mut InProcLink::new(DEFAULT_STEP_US))
            .unwrap_or_else(|e| panic!("{e}"));
        assert!(
            matches!(outcome, ReplayOutcome::Identical { .. }),
            "{name}/{seed}: replay {outcome}"
        );
    }
}

#[test]
fn bad_input_matrix_over_the_emulated_uart() {
    let Some(elf) = board("bad-input matrix over QEMU") else {
        return;
    };
    let mut link = QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
    let report = host_sim::testkit::bad_input_matrix(&mut link).unwrap_or_else(|e| panic!("{e}"));
    // Same verdict, case by case, as the in-process executive ...
    let inproc = host_sim::testkit::bad_input_matrix(&mut InProcLink::new(DEFAULT_STEP_US))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        format!("{report}"),
        format!("{inproc}"),
        "board and in-process disagree on the bad-input matrix"
    );
    // ... and every case handled as the protocol specifies.
    assert!(report.passed(), "bad-input matrix on the board:\n{report}");
    let exit = link
        .quit(Duration::from_secs(10))
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(
        exit.status.success(),
        "board exit: {:?}\n{}",
        exit.status,
        exit.output.both()
    );
    // The board survived every bad input and reports its resources at the end.
    let hw: usize = exit
        .output
        .value("stack_high_water_bytes")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    let size: usize = exit
        .output
        .value("stack_size_bytes")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    assert!(
        hw > 0 && hw < size,
        "stack high-water {hw} of {size}: {}",
        exit.output.both()
    );
}

#[test]
fn free_running_board_sends_ready_telemetry_and_acks_every_frame() {
    // The board as it flies: its own SysTick clock, stepping continuously, sleeping when idle.
    let Some(elf) = board("free-running board") else {
        return;
    };
    let perf = qemu::perf::measure(&elf, 5, 50).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(perf.round_trips.len(), 5);
    assert!(perf.boot_to_telemetry >= perf.boot_to_hello);
    assert!(perf.exit.status.success(), "{}", perf.exit.output.both());
    let accepted: u32 = perf
        .exit
        .output
        .value("frames_accepted")
        .and_then(|v| v.parse().ok())
        .unwrap_or(0);
    assert_eq!(
        accepted,
        5 + 50,
        "frames accepted by the board: {}",
        perf.exit.output.both()
    );
}
