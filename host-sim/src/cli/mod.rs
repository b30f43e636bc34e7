//! Implementations of the `tetherbot` subcommands. `main.rs` only parses arguments and dispatches here; each
//! subcommand returns its process exit code (0 success, 1 the check failed, 2 the command could not run).

pub mod abit_bench;
pub mod campaign;
pub mod board;
pub mod export;
pub mod homotopy;
pub mod inspect;
pub mod judge_agreement;
pub mod map;
pub mod mission;
pub mod replay;
pub mod run;
pub mod soak;
pub mod team;
pub mod stability_map;

use std::process::ExitCode;

/// Exit code when the command could not run (bad input file, I/O error).
pub const EXIT_ERROR: u8 = 2;
/// Exit code when a check failed (scenario expectation, replay mismatch, damaged log).
pub const EXIT_FAILED: u8 = 1;

/// Refuses an output path that exists (unless `force`) or that is one of `inputs` (never, even with `force`: the
/// output is created before the input is read to the end). The error says what to do.
pub fn check_output(out: &std::path::Path, force: bool, inputs: &[&std::path::Path]) -> Result<(), String> {
    let same = |a: &std::path::Path, b: &std::path::Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b,
    };
    if let Some(input) = inputs.iter().find(|i| same(out, i)) {
        return Err(format!("output {} is the input {}: choose another output file", out.display(), input.display()));
    }
    if !force && out.exists() {
        return Err(format!("{} exists: refusing to overwrite it (give --force to replace it)", out.display()));
    }
    Ok(())
}

/// Prints an error and returns [`EXIT_ERROR`].
pub fn fail(msg: impl core::fmt::Display) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(EXIT_ERROR)
}

/// Maps a check-style command result (`Ok(true)` passed, `Ok(false)` the check failed, `Err` could not run) to
/// the CLI's exit codes.
pub fn check_outcome<E: core::fmt::Display>(result: Result<bool, E>) -> ExitCode {
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(EXIT_FAILED),
        Err(e) => fail(e),
    }
}

/// Maps a command result (`Ok(())` done, `Err` could not run) to the CLI's exit codes.
pub fn done<E: core::fmt::Display>(result: Result<(), E>) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => fail(e),
    }
}

/// Prints a report-style command's text (`Ok(text)`) or its error, and maps that to the CLI's exit codes.
pub fn printed<E: core::fmt::Display>(result: Result<String, E>) -> ExitCode {
    match result {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => fail(e),
    }
}

struct StderrLogger;

impl log::Log for StderrLogger {
    fn enabled(&self, _: &log::Metadata<'_>) -> bool {
        true
    }
    fn log(&self, record: &log::Record<'_>) {
        if self.enabled(record.metadata()) {
            eprintln!(
                "[{:<5} {}] {}",
                record.level(),
                record.target(),
                record.args()
            );
        }
    }
    fn flush(&self) {}
}

static LOGGER: StderrLogger = StderrLogger;

/// Installs a logger that prints records to stderr at the level named by `TETHERBOT_LOG`
/// (`error`, `warn`, `info`, `debug`, `trace`; unset = off). The flight core's `log` calls appear here.
pub fn install_stderr_logger() {
    let level = match std::env::var("TETHERBOT_LOG").ok().as_deref() {
        Some("error") => log::LevelFilter::Error,
        Some("warn") => log::LevelFilter::Warn,
        Some("info") => log::LevelFilter::Info,
        Some("debug") => log::LevelFilter::Debug,
        Some("trace") => log::LevelFilter::Trace,
        _ => return,
    };
    if log::set_logger(&LOGGER).is_ok() {
        log::set_max_level(level);
    }
}
