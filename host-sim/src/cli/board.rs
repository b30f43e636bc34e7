//! `tetherbot board ...` (the emulated flight computer) and the `--link qemu` choice of `run` / `replay`.
//!
//! - `tetherbot board report`: flash and RAM by section of the board binary, then the `protocol` scenario on the
//!   board (lockstep) and its on-target resource report: stack high-water mark (paint) and the peak use of each
//!   executive buffer / arena.
//! - `tetherbot board bench`: instruction counts of the fixed on-target workloads under `-icount shift=0`, and the
//!   planning workloads of the `workloads` crate with their outcomes next to the host's (exit status 1 unless equal)
//!   and the run's stack high-water mark (the default set includes the homotopy planning phases on the embedded
//!   HiRISE scarp tile, `workloads::homotopy_tile`: `homotopy_tile_segment` / `_hold` / `_route`). `--workload tethered_test3 [--iterations N]` runs instead only the opt-in
//!   test-3 planning workload (`workloads::ledge_pole`: ABIT* over the tether-aware space, Paton et al.
//!   Table I test 3, 750 iterations by default) on the board and on the host, compares the summaries and reports
//!   instructions in total, per iteration, per settle and per stability LP, the wall time, the stack high-water
//!   mark and the storage's bytes (see `host-sim/doc/board_test3.md`).
//! - `tetherbot board perf`: boot-to-ready time, round-trip latency and sustained frame throughput over the
//!   emulated UART (free-running board, host wall clock).
//!
//! Each builds the board binary first when it is missing (`--build` forces a rebuild check), see
//! `firmware/boards/mps2-an500/README.md`.

use std::path::PathBuf;
use std::process::ExitCode;

use core::time::Duration;

use crate::link::qemu::QemuLink;
use crate::link::{FlightLink, LinkKind};
use crate::qemu::{self, perf, report};

/// Arguments of `board`.
#[derive(Debug, Clone, clap::Args)]
pub struct BoardArgs {
    /// What to do.
    #[command(subcommand)]
    pub command: BoardCommand,
    /// The board ELF (default: the release build in firmware/boards/mps2-an500, or $TETHERBOT_BOARD_ELF).
    #[arg(long, global = true)]
    pub elf: Option<PathBuf>,
    /// Run `cargo build --release` in the board directory first (default: only when the ELF is missing).
    #[arg(long, global = true)]
    pub build: bool,
}

/// `board` subcommands.
#[derive(Debug, Clone, clap::Subcommand)]
pub enum BoardCommand {
    /// Flash / RAM by section, on-target stack high-water mark and arena peaks.
    Report,
    /// On-target instruction counts of fixed workloads (-icount shift=0).
    Bench {
        /// Run only this opt-in workload instead of the default set: `tethered_test3` (Table I test 3, ABIT*
        /// over the tether-aware space; tens of billions of instructions, minutes of QEMU time).
        #[arg(long)]
        workload: Option<String>,
        /// ABIT* iterations of `--workload tethered_test3` (default 750, Table I).
        #[arg(long)]
        iterations: Option<u32>,
        /// Give up on the board after this many seconds (default 300; 3600 with `--workload`).
        #[arg(long)]
        timeout_s: Option<u64>,
    },
    /// Boot-to-ready, round-trip latency and throughput over the emulated UART.
    Perf {
        /// Round trips to time.
        #[arg(long, default_value_t = 200)]
        samples: usize,
        /// Frames in the throughput burst.
        #[arg(long, default_value_t = 2000)]
        burst: usize,
    },
}

/// The board ELF to use: `explicit`, else the default path, building it if missing or if `build` is set.
pub fn board_elf(explicit: Option<&PathBuf>, build: bool) -> Result<PathBuf, qemu::QemuError> {
    if let Some(p) = explicit {
        return Ok(p.clone());
    }
    let path = qemu::board_elf_path();
    if build || !path.is_file() {
        if std::env::var_os("TETHERBOT_BOARD_ELF").is_some() {
            return Ok(path);
        }
        if build {
            eprintln!("building the board binary (cargo build --release in {}) ...", qemu::BOARD_DIR);
        } else {
            // Say so before a build nobody asked for starts (it takes minutes on a loaded machine).
            eprintln!(
                "the board binary {} is missing: building it now (cargo build --release in {}; set TETHERBOT_BOARD_ELF \
                 to use another binary) ...",
                path.display(),
                qemu::BOARD_DIR
            );
        }
        return qemu::build_board_elf();
    }
    Ok(path)
}

/// Starts the board in lockstep for `run --link qemu`.
pub fn start_board_link(step_us: u64) -> Result<QemuLink, Box<dyn core::error::Error>> {
    let elf = board_elf(None, false)?;
    Ok(QemuLink::start(&elf, step_us)?)
}

/// Shuts a board link down and prints its on-target resource report.
pub fn finish_board_link(link: QemuLink) -> Result<qemu::QemuExit, Box<dyn core::error::Error>> {
    let (steps, round_trips, wall) = link.stats();
    let boot = link.boot_to_ready().unwrap_or_default();
    let exit = link.quit(Duration::from_secs(10))?;
    if !exit.status.success() {
        return Err(format!(
            "the board failed: {:?}\n{}",
            exit.status,
            exit.output.both()
        )
        .into());
    }
    println!(
        "board: boot to ready {:.1} ms; {steps} executive steps in {round_trips} lockstep round trips, {:.1} ms",
        boot.as_secs_f64() * 1e3,
        wall.as_secs_f64() * 1e3
    );
    for line in exit
        .output
        .stdout
        .lines()
        .filter(|l| l.starts_with("board:"))
    {
        println!("{line}");
    }
    Ok(exit)
}

fn report_cmd(elf: &std::path::Path) -> Result<(), Box<dyn core::error::Error>> {
    let sections = report::elf_sections(elf)?;
    println!("board binary: {}", elf.display());
    print!("{}", report::format_sections(&sections));
    println!("\non-target run: protocol scenario, seed 1, lockstep");
    let mut link = QemuLink::start(elf, crate::link::inproc::DEFAULT_STEP_US)?;
    let rep = crate::scripted::run_protocol(&mut link, 1)?;
    if !rep.passed() {
        println!("{rep}");
    }
    let _ = link.now_us();
    let exit = finish_board_link(link)?;
    let v = |k: &str| exit.output.value(k).unwrap_or_else(|| "?".into());
    println!(
        "stack high-water mark: {} of {} bytes\nexecutive storage (static, lent): {} bytes; scan points peak {} of {}; \
         tx queue peak {} of {} bytes; rx staging peak {} bytes; largest frame {} bytes; log queue peak {}\n\
         onboard map (static, PSRAM): {} bytes; blocks peak {} of {}",
        v("stack_high_water_bytes"),
        v("stack_size_bytes"),
        v("exec_storage_bytes"),
        v("scan_points_peak"),
        v("scan_points_capacity"),
        v("tx_queue_peak"),
        v("tx_queue_capacity"),
        v("rx_staging_peak"),
        v("frame_len_peak"),
        v("log_queue_peak"),
        v("map_storage_bytes"),
        v("map_blocks_peak"),
        v("map_blocks_capacity")
    );
    Ok(())
}

fn bench_cmd(elf: &std::path::Path, timeout: Duration) -> Result<(), Box<dyn core::error::Error>> {
    let (results, text) = report::run_bench(elf, timeout)?;
    println!(
        "on-target instruction counts (qemu-system-arm -icount shift=0, mps2-an500 Cortex-M7)"
    );
    print!("{}", report::format_bench(&results));
    for line in text
        .lines()
        .filter(|l| l.starts_with("bench: check") || l.contains("expected_instructions"))
    {
        println!("{line}");
    }
    // Planning workloads: the board's outcome next to the host's (same code, same inputs).
    let board = qemu::bench::board_summaries(&text);
    let host = qemu::bench::host_summaries();
    println!("\nplanning workloads (one run each; result summary on the board, checked against the host)");
    println!("{:<28} {:>14}  result", "workload", "instructions");
    let mut mismatches = 0;
    for (name, b, h) in qemu::bench::compare(&board, &host) {
        let ins = results
            .iter()
            .find(|r| r.name == name)
            .map_or_else(|| "-".to_owned(), |r| r.instructions.to_string());
        println!(
            "{name:<28} {ins:>14}  board: {}",
            b.as_deref().unwrap_or("(missing)")
        );
        if b == h {
            println!("{:<28} {:>14}  host:  same", "", "");
        } else {
            mismatches += 1;
            println!(
                "{:<28} {:>14}  host:  {}   <-- MISMATCH",
                "",
                "",
                h.as_deref().unwrap_or("(missing)")
            );
        }
    }
    for line in text.lines().filter(|l| l.starts_with("bench: stack")) {
        println!("{line}");
    }
    if mismatches > 0 {
        return Err(format!(
            "{mismatches} planning workload(s) differ between the board and the host"
        )
        .into());
    }
    Ok(())
}

/// `board bench --workload NAME`: one opt-in workload on the board and on the host (concurrently).
fn bench_workload_cmd(
    elf: &std::path::Path,
    workload: &str,
    iterations: Option<u32>,
    timeout: Duration,
) -> Result<(), Box<dyn core::error::Error>> {
    use workloads::ledge_pole;
    let name = ledge_pole::NAME;
    if workload != name {
        return Err(format!("--workload {workload:?}: the opt-in workloads are: {name}").into());
    }
    let iterations = iterations.unwrap_or(ledge_pole::ITERATIONS);
    if iterations == 0 {
        return Err("--iterations must be at least 1".into());
    }
    let words = format!(
        "tetherbot.mode=bench tetherbot.workload={name} tetherbot.iterations={iterations}"
    );
    println!(
        "{name}: {iterations} ABIT* iterations on the emulated board (qemu-system-arm -icount shift=0, \
         mps2-an500 Cortex-M7) and on the host ..."
    );
    let host = std::thread::spawn(move || {
        let t0 = std::time::Instant::now();
        qemu::bench::host_ledge_pole_summary(iterations).map(|s| (s, t0.elapsed()))
    });
    let t0 = std::time::Instant::now();
    let (results, text) = report::run_bench_with(elf, &words, timeout)?;
    let wall = t0.elapsed();
    let ((_, host_summary), host_wall) = host
        .join()
        .map_err(|_| "the host twin panicked")??;
    let board = qemu::bench::board_summaries(&text);
    let board_summary = board
        .iter()
        .find(|(n, _)| n == name)
        .map(|(_, s)| s.clone());
    let ins = results
        .iter()
        .find(|r| r.name == name)
        .map(|r| r.instructions)
        .ok_or("the board printed no instruction count for the workload")?;
    let field = |s: &str, k: &str| -> Option<u64> { report::field(s, k)?.parse().ok() };
    let summary = board_summary.clone().unwrap_or_default();
    let per = |k: &str| {
        field(&summary, k)
            .filter(|&n| n > 0)
            .map_or_else(|| "-".to_owned(), |n| (ins / n).to_string())
    };
    for line in text
        .lines()
        .filter(|l| l.contains("expected_instructions") || l.starts_with("bench: name=calibration"))
    {
        println!("{line}");
    }
    println!("board: {}", board_summary.as_deref().unwrap_or("(missing)"));
    let same = board_summary.as_deref() == Some(host_summary.as_str());
    if same {
        println!("host:  same");
    } else {
        println!("host:  {host_summary}   <-- MISMATCH");
    }
    println!("instructions: {ins} total");
    println!(
        "  per iteration {} ({} iterations); per settle {}, per stability LP {}, per edge evaluated {} \
         (amortised: all the work divided by the count)",
        per("iterations"),
        field(&summary, "iterations").unwrap_or(0),
        per("settles"),
        per("lps"),
        per("edges"),
    );
    if let Some(phases) = text.lines().find_map(|l| l.strip_prefix(&format!("bench: phases name={name} "))) {
        print_phases(phases, ins);
    }
    println!(
        "wall time: board {:.1} s (QEMU, this machine), host twin {:.2} s",
        wall.as_secs_f64(),
        host_wall.as_secs_f64()
    );
    for line in text
        .lines()
        .filter(|l| l.starts_with("bench: stack_high") || l.starts_with("bench: test3_storage"))
    {
        println!("{line}");
    }
    if !same {
        return Err(format!("{name} differs between the board and the host").into());
    }
    Ok(())
}

/// The board's per-phase profile of the test-3 workload (`bench: phases` line: SysTick ticks per phase, and the
/// distance-field queries), as instructions and shares of the workload's `total`.
fn print_phases(line: &str, total: u64) {
    let get = |k: &str| report::field(line, k).and_then(|v| v.parse::<u64>().ok()).unwrap_or(0);
    let ins = |k: &str| get(k).saturating_mul(report::INSTRUCTIONS_PER_TICK);
    let share = |n: u64| if total > 0 { 100.0 * n as f64 / total as f64 } else { 0.0 };
    let (settle, stability, anchors) = (ins("settle_ticks"), ins("stability_ticks"), ins("anchors_ticks"));
    let (field, queries) = (ins("field_ticks"), get("field_queries"));
    println!(
        "phases on the board (SysTick under -icount: {} instructions per tick; each phase includes the \
         distance-field queries made inside it):",
        report::INSTRUCTIONS_PER_TICK
    );
    for (what, n) in [
        ("settle", settle),
        ("stability (margin LPs)", stability),
        ("anchor prediction (Alg. 1)", anchors),
        ("the rest (ABIT*: sampling, queues, graph; phase timer reads)", total.saturating_sub(settle + stability + anchors)),
    ] {
        println!("  {what:<62} {n:>15} instructions {:>5.1} %", share(n));
    }
    println!(
        "  {:<62} {field:>15} instructions {:>5.1} % ({queries} queries, {} per query)",
        "of which distance-field queries (all phases)",
        share(field),
        field / queries.max(1)
    );
}

/// `board` entry point.
pub fn main(args: &BoardArgs) -> ExitCode {
    let elf = match board_elf(args.elf.as_ref(), args.build) {
        Ok(e) => e,
        Err(e) => return super::fail(e),
    };
    let result = match &args.command {
        BoardCommand::Report => report_cmd(&elf),
        BoardCommand::Bench {
            workload: None,
            timeout_s,
            ..
        } => bench_cmd(&elf, Duration::from_secs(timeout_s.unwrap_or(300))),
        BoardCommand::Bench {
            workload: Some(w),
            iterations,
            timeout_s,
        } => bench_workload_cmd(
            &elf,
            w,
            *iterations,
            Duration::from_secs(timeout_s.unwrap_or(3600)),
        ),
        BoardCommand::Perf { samples, burst } => perf::measure(&elf, *samples, (*burst).max(1))
            .map(|p| {
                print!("{p}");
                for line in p
                    .exit
                    .output
                    .stdout
                    .lines()
                    .filter(|l| l.starts_with("board:"))
                {
                    println!("{line}");
                }
            })
            .map_err(Into::into),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => super::fail(e),
    }
}

/// Runs `f` over a fresh link of the chosen kind (the board is shut down afterwards and its report printed).
pub fn with_link<T>(
    kind: LinkKind,
    step_us: u64,
    f: impl FnOnce(&mut dyn FlightLink) -> Result<T, Box<dyn core::error::Error>>,
) -> Result<T, Box<dyn core::error::Error>> {
    match kind {
        LinkKind::Inproc => {
            let mut link = crate::link::inproc::InProcLink::new(step_us);
            f(&mut link)
        }
        LinkKind::Qemu => {
            let mut link = start_board_link(step_us)?;
            let out = f(&mut link)?;
            finish_board_link(link)?;
            Ok(out)
        }
    }
}
