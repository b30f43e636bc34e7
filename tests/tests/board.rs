//! The emulated flight computer (QEMU mps2-an500): faults end the run with a failure status and a report, the
//! benchmark mode counts instructions exactly, the ELF's memory layout is what `memory.x` promises.
//!
//! These tests build the board binary on first use (about a minute cold, under a second when up to date) and
//! skip with a plain message when `qemu-system-arm` is absent, unless `CI=true`.

use core::time::Duration;

use host_sim::qemu::{self, report, QemuConfig};

fn board(test: &str) -> Option<std::path::PathBuf> {
    match qemu::board_for_tests(test) {
        Ok(elf) => elf,
        Err(e) => panic!("{e}"),
    }
}

/// Boots the board with a fault probe and checks that the run failed (QEMU exit status 1); returns its output.
/// `None` when QEMU is absent outside CI (the skip was printed).
fn failed_probe(words: &str) -> Option<String> {
    let elf = board(words)?;
    let mut cfg = QemuConfig::new(elf);
    cfg.boot_words = Some(words.into());
    let exit = qemu::run_to_exit(&cfg, Duration::from_secs(20)).unwrap_or_else(|e| panic!("{e}"));
    let text = exit.output.both();
    assert_eq!(exit.status.code(), Some(1), "output: {text}");
    Some(text)
}

#[test]
fn panic_on_target_is_reported_with_location_and_fails_the_run() {
    let Some(text) = failed_probe("tetherbot.probe=panic") else {
        return;
    };
    assert!(
        text.contains("board: PANIC fault probe"),
        "no panic report in: {text}"
    );
    assert!(
        text.contains("src/main.rs:"),
        "panic report lacks its location: {text}"
    );
}

#[test]
fn hard_fault_on_target_is_reported_with_registers_and_fails_the_run() {
    let Some(text) = failed_probe("tetherbot.probe=hardfault") else {
        return;
    };
    assert!(
        text.contains("board: HARDFAULT pc=0x"),
        "no hard-fault report in: {text}"
    );
    // An undefined instruction is a UsageFault (CFSR.UNDEFINSTR, bit 16) escalated to HardFault (HFSR.FORCED).
    assert!(
        text.contains("cfsr=0x00010000") && text.contains("hfsr=0x40000000"),
        "wrong fault status: {text}"
    );
}

#[test]
fn stalled_loop_is_caught_by_the_watchdog_and_fails_the_run() {
    let Some(text) = failed_probe("tetherbot.probe=watchdog") else {
        return;
    };
    assert!(text.contains("board: WATCHDOG expired"), "output: {text}");
}

#[test]
fn calibration_loop_instruction_count_matches_its_length() {
    let Some(elf) = board("bench calibration") else {
        return;
    };
    let (results, text) =
        report::run_bench(&elf, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"));
    let cal = results
        .iter()
        .find(|r| r.name == "calibration")
        .unwrap_or_else(|| panic!("no calibration in {text}"));
    // The loop is `subs` + `bne` per iteration plus the final fall-through: 2N + 1 instructions, counted in
    // SysTick ticks of 40 instructions, plus a handful for the clock reads around it.
    let expected = 2 * cal.iterations + 1;
    assert!(
        cal.instructions + 40 >= expected && cal.instructions <= expected + 200,
        "calibration counted {} instructions for a loop of {expected}",
        cal.instructions
    );
}

#[test]
fn elf_places_code_in_flash_and_state_in_sram() {
    let Some(elf) = board("elf layout") else {
        return;
    };
    let sections = report::elf_sections(&elf).unwrap_or_else(|e| panic!("{e}"));
    let find = |n: &str| sections.iter().find(|s| s.name == n);
    let text = find(".text").unwrap_or_else(|| panic!("no .text in {sections:?}"));
    assert_eq!(text.region, report::Region::Flash);
    assert_eq!(
        find(".vector_table").map(|s| s.addr),
        Some(0),
        "vector table must sit at the reset address"
    );
    for s in sections
        .iter()
        .filter(|s| s.name == ".bss" || s.name == ".data")
    {
        assert_eq!(s.region, report::Region::Sram, "{s:?}");
    }
    let (flash, _, _) = report::totals(&sections);
    assert!(
        flash >= u64::from(text.size),
        "flash total {flash} below .text {}",
        text.size
    );
}

#[test]
fn missing_board_binary_is_a_clear_error_naming_the_build_command() {
    let cfg = QemuConfig::new(std::path::PathBuf::from("/nonexistent/board-mps2-an500"));
    let err = match qemu::QemuBoard::start(&cfg) {
        Ok(_) => panic!("a board started from a missing ELF"),
        Err(e) => e,
    };
    assert!(matches!(err, qemu::QemuError::ElfMissing(_)), "{err:?}");
    let msg = err.to_string();
    assert!(
        msg.contains("cargo build --release") && msg.contains(qemu::BOARD_DIR),
        "{msg}"
    );
}

#[test]
fn lockstep_board_reports_a_fault_instead_of_hanging() {
    // A board that panics at boot never says hello: starting the link fails with its report, within the bound.
    let Some(elf) = board("lockstep fault") else {
        return;
    };
    let mut cfg = QemuConfig::new(elf);
    cfg.boot_words = Some("tetherbot.clock=lockstep tetherbot.probe=panic".into());
    cfg.ready_timeout = Duration::from_secs(10);
    let err = match host_sim::link::qemu::QemuLink::with_config(&cfg, 1000) {
        Ok(_) => panic!("a panicking board completed the handshake"),
        Err(e) => e,
    };
    let msg = err.to_string();
    assert!(
        msg.contains("board: PANIC"),
        "the failure does not carry the board's report: {msg}"
    );
}

#[test]
fn on_target_workloads_do_their_work_and_count_identically_twice() {
    let Some(elf) = board("bench determinism") else {
        return;
    };
    let (first, text) =
        report::run_bench(&elf, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"));
    let (second, _) =
        report::run_bench(&elf, Duration::from_secs(60)).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        first, second,
        "instruction counts under -icount shift=0 must repeat exactly"
    );
    for name in [
        "deframe_decode_time_tick",
        "deframe_decode_tether_reading",
        "deframe_decode_sensor_chunk_128_points",
    ] {
        let line = text
            .lines()
            .find(|l| l.starts_with(&format!("bench: check name={name} ")));
        assert!(
            line.is_some_and(|l| l.ends_with(" decoded=200")),
            "{name}: {text}"
        );
    }
    // The executive acknowledged every frame of its workload (200 frames, 4 per step).
    let line = text
        .lines()
        .find(|l| l.starts_with("bench: check name=exec_dispatch_time_tick "));
    assert!(
        line.is_some_and(|l| l.contains(" frames_accepted=200 ")),
        "{text}"
    );
    assert!(first.iter().all(|r| r.instructions > 0), "{first:?}");
}

#[test]
fn absent_qemu_skips_with_install_hint_outside_ci_and_fails_under_ci() {
    use qemu::{absent_qemu_policy, AbsentQemu};
    assert_eq!(absent_qemu_policy(true, Some("true"), "t"), AbsentQemu::Run);
    assert_eq!(absent_qemu_policy(true, None, "t"), AbsentQemu::Run);
    assert_eq!(
        absent_qemu_policy(false, Some("true"), "t"),
        AbsentQemu::Fail
    );
    assert_eq!(absent_qemu_policy(false, Some("1"), "t"), AbsentQemu::Fail);
    for ci in [None, Some("false"), Some("")] {
        match absent_qemu_policy(false, ci, "equivalence") {
            AbsentQemu::Skip(note) => {
                assert!(
                    note.contains("did NOT run") && note.contains("equivalence"),
                    "{note}"
                );
                assert!(
                    note.contains("apt-get install -y --no-install-recommends qemu-system-arm"),
                    "{note}"
                );
            }
            other => panic!("CI={ci:?}: {other:?}"),
        }
    }
}

#[test]
fn planning_workloads_give_the_host_answers_on_target_within_the_stack() {
    let Some(elf) = board("planning workloads") else {
        return;
    };
    let (results, text) =
        report::run_bench(&elf, Duration::from_secs(120)).unwrap_or_else(|e| panic!("{e}"));
    let board = qemu::bench::board_summaries(&text);
    let host = qemu::bench::host_summaries();
    assert_eq!(host.len(), 8, "{host:?}");
    // Same code, same inputs, IEEE arithmetic on both (libm, soft f64 on the board): identical outcomes.
    assert_eq!(board, host, "board vs host planning outcomes:\n{text}");
    for (name, _) in &host {
        assert!(
            results
                .iter()
                .any(|r| &r.name == name && r.instructions > 0),
            "{name} not measured: {text}"
        );
    }
    // The paint must survive somewhere: a high-water mark equal to the region means the stack overflowed.
    let v = |k: &str| -> u64 {
        text.lines()
            .find_map(|l| l.strip_prefix("bench: stack_high_water_bytes="))
            .and_then(|rest| {
                if k == "hw" {
                    rest.split_whitespace().next()
                } else {
                    rest.split("stack_size_bytes=").nth(1)
                }
            })
            .and_then(|s| s.trim().parse().ok())
            .unwrap_or_else(|| panic!("no stack line in {text}"))
    };
    let (hw, size) = (v("hw"), v("size"));
    assert!(hw > 0 && hw < size, "stack high-water {hw} of {size}");
}
