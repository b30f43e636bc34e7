//! Implementations of the `tetherbot` subcommands. `main.rs` only parses arguments and dispatches here; each
//! subcommand returns its process exit code (0 success, 1 the check failed, 2 the command could not run).

pub mod export;
pub mod inspect;
pub mod map;
pub mod replay;
pub mod run;

use std::process::ExitCode;

/// Exit code when the command could not run (bad input file, I/O error).
pub const EXIT_ERROR: u8 = 2;
/// Exit code when a check failed (scenario expectation, replay mismatch, damaged log).
pub const EXIT_FAILED: u8 = 1;

/// Prints an error and returns [`EXIT_ERROR`].
pub fn fail(msg: impl core::fmt::Display) -> ExitCode {
    eprintln!("error: {msg}");
    ExitCode::from(EXIT_ERROR)
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
