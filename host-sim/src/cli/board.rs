//! `tetherbot board ...` (the emulated flight computer) and the `--link qemu` choice of `run` / `replay`.
//!
//! - `tetherbot board report`: flash and RAM by section of the board binary, then the `protocol` scenario on the
//!   board (lockstep) and its on-target resource report: stack high-water mark (paint) and the peak use of each
//!   executive buffer / arena.
//! - `tetherbot board bench`: instruction counts of the fixed on-target workloads under `-icount shift=0`, and the
//!   planning workloads of `firmware::workload` with their outcomes next to the host's (exit status 1 unless equal)
//!   and the run's stack high-water mark.
//! - `tetherbot board perf`: boot-to-ready time, round-trip latency and sustained frame throughput over the
//!   emulated UART (free-running board, host wall clock).
//!
//! Each builds the board binary first when it is missing (`--build` forces a rebuild check), see
//! `firmware/boards/mps2-an500/README.md`.

use std::path::PathBuf;
use std::process::ExitCode;

use core::time::Duration;

use crate::link::FlightLink;
use crate::qemu::{self, link::QemuLink, perf, report};

/// Which flight software a run talks to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum LinkKind {
    /// The executive linked into the host, stepped on a simulated clock (fast; the default).
    #[default]
    Inproc,
    /// The cross-compiled board binary in QEMU (mps2-an500, Cortex-M7) over an emulated UART, stepped in
    /// lockstep on the same simulated clock (byte-identical output to `inproc`).
    Qemu,
}

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
    Bench,
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
        eprintln!(
            "building the board binary (cargo build --release in {}) ...",
            qemu::BOARD_DIR
        );
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

fn bench_cmd(elf: &std::path::Path) -> Result<(), Box<dyn core::error::Error>> {
    let (results, text) = report::run_bench(elf, Duration::from_secs(300))?;
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

/// `board` entry point.
pub fn main(args: &BoardArgs) -> ExitCode {
    let elf = match board_elf(args.elf.as_ref(), args.build) {
        Ok(e) => e,
        Err(e) => return super::fail(e),
    };
    let result = match &args.command {
        BoardCommand::Report => report_cmd(&elf),
        BoardCommand::Bench => bench_cmd(&elf),
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
