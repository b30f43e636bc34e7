//! The emulated flight computer (QEMU mps2-an500): faults end the run with a failure status and a report (a stack
//! overflow as it happens, through the MPU guard), the watchdog's reset output reboots the board, the clock and
//! periodic telemetry run on across the 32-bit millisecond wrap, the benchmark mode counts instructions exactly,
//! the ELF's memory layout is what `memory.x` promises.
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

/// The `0x...` number after `key` in `text`.
fn hex_after(text: &str, key: &str) -> Option<u64> {
    let rest = &text[text.find(key)? + key.len()..];
    let digits: String = rest
        .trim_start_matches("0x")
        .chars()
        .take_while(char::is_ascii_hexdigit)
        .collect();
    u64::from_str_radix(&digits, 16).ok()
}

#[test]
fn stack_overflow_is_trapped_by_the_mpu_guard_as_it_happens() {
    // The probe recurses with 1 KiB frames; without the guard it runs through the guard's 128 KiB and returns
    // (measured with the guard switched off: "stack probe returned after ... frames: the overflow was NOT
    // trapped").
    let Some(text) = failed_probe("tetherbot.probe=stack") else {
        return;
    };
    assert!(
        text.contains("board: STACK OVERFLOW into the guard [0x"),
        "no stack-overflow report in: {text}"
    );
    assert!(!text.contains("NOT trapped"), "output: {text}");
    // The fault is the first access in the guard: the faulting address (or, for a failed exception entry, the
    // stack pointer) lies in the guard's top frame, not somewhere below it.
    let (start, end) = (
        hex_after(&text, "guard [0x").unwrap_or_else(|| panic!("{text}")),
        hex_after(&text, ", 0x").unwrap_or_else(|| panic!("{text}")),
    );
    assert_eq!(end - start, 128 * 1024, "guard size: {text}");
    let psp = hex_after(&text, "psp=0x").unwrap_or_else(|| panic!("{text}"));
    assert!(
        psp < end && psp + 2048 >= end,
        "the stack pointer 0x{psp:x} is not in the guard's top 2 KiB [0x{start:x}, 0x{end:x}): {text}"
    );
    let cfsr = hex_after(&text, "cfsr=0x").unwrap_or_else(|| panic!("{text}"));
    if cfsr & 0x80 != 0 {
        let mmfar = hex_after(&text, "mmfar=0x").unwrap_or_else(|| panic!("{text}"));
        assert!((start..end).contains(&mmfar), "mmfar 0x{mmfar:x} outside the guard: {text}");
    }
}

#[test]
fn watchdog_reset_output_reboots_the_board() {
    // The probe's NMI handler lets the bite pass; the second expiry (RESEN) resets the machine, and the rebooted
    // board finds the probe's mark in `.uninit`.
    let Some(text) = failed_probe("tetherbot.probe=watchdog-reset") else {
        return;
    };
    let bite = text.find("board: WATCHDOG expired: probe lets the reset output act");
    let reboot = text.find("board: REBOOTED by the watchdog's reset output");
    assert!(
        matches!((bite, reboot), (Some(b), Some(r)) if b < r),
        "no bite then reboot in: {text}"
    );
    assert!(!text.contains("did not reset"), "output: {text}");
}

#[test]
fn telemetry_keeps_its_period_across_the_32_bit_millisecond_wrap() {
    use firmware::protocol::{self, Deframer, Message};
    // Regression (issue 24): the board's millisecond count was a u32; at 2^32 ms (49.7 days) the clock fell back
    // to 0 and periodic telemetry (every 1 s by default) stopped. Start the clock 1.5 s before the wrap and
    // watch four telemetry frames go by, free-running (QEMU's virtual clock follows the host's).
    let Some(elf) = board("clock wrap") else {
        return;
    };
    const WRAP_MS: u64 = 1 << 32;
    let mut cfg = QemuConfig::new(elf);
    cfg.boot_words = Some(format!("tetherbot.clock_start_ms={}", WRAP_MS - 1500));
    let mut board = qemu::QemuBoard::start(&cfg).unwrap_or_else(|e| panic!("{e}"));
    let mut deframer = Deframer::new();
    let mut times = Vec::new();
    let deadline = std::time::Instant::now() + Duration::from_secs(20);
    let mut buf = [0u8; 4096];
    while times.len() < 4 && std::time::Instant::now() < deadline {
        let n = board
            .recv(&mut buf, Duration::from_millis(100))
            .unwrap_or_else(|e| panic!("{e}: {}", board.output().both()));
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let (used, event) = deframer.push(rest);
            rest = &rest[used.max(1).min(rest.len())..];
            if let Some(Ok(frame)) = event {
                if let Ok((_, Message::Telemetry(t))) = protocol::decode_frame(frame) {
                    times.push(t.time_us);
                }
            }
        }
    }
    let exit = board
        .quit(Duration::from_secs(10))
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(times.len(), 4, "telemetry times (us) {times:?}; {}", exit.output.both());
    assert!(
        times[0] >= (WRAP_MS - 1500) * 1000 && times[0] < WRAP_MS * 1000,
        "boot telemetry at {} us, before the wrap expected",
        times[0]
    );
    assert!(
        times[3] > WRAP_MS * 1000 + 1_000_000,
        "telemetry stopped at the wrap: {times:?}"
    );
    for w in times.windows(2) {
        let dt = w[1].saturating_sub(w[0]);
        assert!(
            (1_000_000..2_000_000).contains(&dt),
            "telemetry period {dt} us, 1 s expected: {times:?}"
        );
    }
    // The quit report carries both stacks' high-water marks; neither is exhausted.
    let value = |k: &str| -> u64 {
        exit.output
            .value(k)
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("no {k} in {}", exit.output.both()))
    };
    assert!(exit.status.success(), "{}", exit.output.both());
    for (hw, size) in [
        ("stack_high_water_bytes", "stack_size_bytes"),
        ("handler_stack_high_water_bytes", "handler_stack_size_bytes"),
    ] {
        let (hw, size) = (value(hw), value(size));
        assert!(hw > 0 && hw < size, "{hw} of {size}");
    }
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
    // 13 planning workloads and the homotopy planner's three phases on the HiRISE mission tile
    assert_eq!(host.len(), 16, "{host:?}");
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
