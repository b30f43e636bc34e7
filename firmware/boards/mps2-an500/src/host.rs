//! Talking to the emulator host over semihosting: the boot command line (`qemu-system-arm -append "..."`) and
//! machine-readable report lines.
//!
//! Boot words recognised on the command line (QEMU passes `<kernel path> <append string>`):
//! - `tetherbot.mode=bench`: run the on-target benchmark workloads (`bench/`), print them, exit 0;
//!   with `tetherbot.workload=tethered_test3` instead only the opt-in ledge-with-pole planning workload
//!   (Table I test 3, `workloads::ledge_pole`), for `tetherbot.iterations=N` iterations (default 750, Table I);
//! - `tetherbot.probe=panic` / `hardfault` / `watchdog` / `stack`: force that fault at boot (`stack`: recurse
//!   until the stack runs into its guard region, `stack_guard.rs`), to test that faults end the run with a failure
//!   status and a report;
//! - `tetherbot.probe=watchdog-reset`: stop kicking the watchdog and do not end the run on its interrupt, so the
//!   watchdog's second expiry resets the board (RESEN, `watchdog.rs`); the board boots again and says so;
//! - `tetherbot.clock_start_ms=N`: start the SysTick clock at N ms instead of 0 (a clock near 2^32 ms tests
//!   the wrap that stalled telemetry after 49.7 days, `clock.rs`).
//!
//! Bench words need feature `bench`, probe words and the clock preset feature `test-probes`; both are in the
//! default (test) build and neither is in the flight build (`--no-default-features`), where those words are
//! ignored (and in flight there is no semihosting host and no command line at all).
//! - `tetherbot.clock=lockstep`: the flight loop with the executive stepped by the host over the control port
//!   (UART1) on the host's simulated clock, exactly like the in-process link (see `flight.rs`);
//! - nothing: the flight loop over UART0 on the board's own SysTick clock (free-running, as in flight).

use core::fmt::Write;

use cortex_m_semihosting::{hio, nr};

/// Prints a line on the semihosting host's standard output (like cortex-m-semihosting's `hprintln!`).
///
/// The crate's own macros keep the host stream in a `RefCell` shared by all contexts; a fault report from the
/// NMI or HardFault (which preempt critical sections) while thread mode prints would find it borrowed and panic,
/// a real panic path in the flight build. These open the stream for each line instead (one more semihosting
/// call; reports are rare) and share nothing.
macro_rules! host_println {
    ($($arg:tt)*) => {
        $crate::host::print_line(false, format_args!($($arg)*))
    };
}

/// Prints a line on the semihosting host's standard error (see [`host_println!`]).
macro_rules! host_eprintln {
    ($($arg:tt)*) => {
        $crate::host::print_line(true, format_args!($($arg)*))
    };
}

/// Writes `args` and a newline to the host's standard error (`to_stderr`) or output; nothing without a host.
pub fn print_line(to_stderr: bool, args: core::fmt::Arguments) {
    let stream = if to_stderr {
        hio::hstderr()
    } else {
        hio::hstdout()
    };
    if let Ok(mut stream) = stream {
        let _ = stream.write_fmt(args);
        let _ = stream.write_str("\n");
    }
}

/// Capacity of the command line copy; longer command lines are truncated (the boot words are short).
const CMDLINE_CAPACITY: usize = 512;

/// What the board does after boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BootMode {
    /// The flight loop over UART0; `lockstep`: stepped by the host on its clock.
    Flight {
        /// Stepped by the host over UART1 instead of free-running on SysTick.
        lockstep: bool,
    },
    /// The benchmark workloads.
    #[cfg(feature = "bench")]
    Bench,
    /// Only the opt-in ledge-with-pole (Table I test 3) planning workload, this many ABIT* iterations.
    #[cfg(feature = "bench")]
    BenchLedgePole {
        /// Planner iterations.
        iterations: u32,
    },
    /// Panic at boot.
    #[cfg(feature = "test-probes")]
    ProbePanic,
    /// Execute an undefined instruction at boot (UsageFault escalated to HardFault).
    #[cfg(feature = "test-probes")]
    ProbeHardFault,
    /// Stop kicking the watchdog.
    #[cfg(feature = "test-probes")]
    ProbeWatchdog,
    /// Stop kicking the watchdog and let its second expiry reset the board.
    #[cfg(feature = "test-probes")]
    ProbeWatchdogReset,
    /// Recurse until the stack overflows into its guard region.
    #[cfg(feature = "test-probes")]
    ProbeStackOverflow,
}

/// The boot words: the mode, and the clock's start (`tetherbot.clock_start_ms=N`, test builds only; 0 otherwise).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BootWords {
    /// What to run.
    pub mode: BootMode,
    /// Milliseconds the SysTick clock starts at.
    pub clock_start_ms: u64,
}

/// Reads the command line from the semihosting host and picks the boot mode.
pub fn boot_words() -> BootWords {
    let flight = BootWords {
        mode: BootMode::Flight { lockstep: false },
        clock_start_ms: 0,
    };
    let mut buf = [0u8; CMDLINE_CAPACITY];
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most block[1] bytes into the buffer block[0] points to, and updates
    // block[1] to the length written. Both live on this stack frame for the duration of the call.
    let status =
        unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status != 0 {
        return flight;
    }
    let len = block[1].min(buf.len());
    let line = buf.get(..len).unwrap_or(&[]);
    #[cfg_attr(not(feature = "test-probes"), allow(unused_mut))]
    let mut words = BootWords {
        mode: mode(line),
        ..flight
    };
    #[cfg(feature = "test-probes")]
    {
        words.clock_start_ms = number_after(line, b"tetherbot.clock_start_ms=").unwrap_or(0);
    }
    words
}

fn has(line: &[u8], word: &[u8]) -> bool {
    line.windows(word.len()).any(|w| w == word)
}

fn mode(line: &[u8]) -> BootMode {
    #[cfg(feature = "bench")]
    if has(line, b"tetherbot.mode=bench") {
        if has(line, b"tetherbot.workload=tethered_test3") {
            return BootMode::BenchLedgePole {
                iterations: number_after(line, b"tetherbot.iterations=")
                    .and_then(|n| u32::try_from(n).ok())
                    .unwrap_or(workloads::ledge_pole::ITERATIONS),
            };
        }
        return BootMode::Bench;
    }
    #[cfg(feature = "test-probes")]
    {
        // `watchdog-reset` before `watchdog`, which is its prefix.
        let probes = [
            (&b"tetherbot.probe=panic"[..], BootMode::ProbePanic),
            (b"tetherbot.probe=hardfault", BootMode::ProbeHardFault),
            (b"tetherbot.probe=watchdog-reset", BootMode::ProbeWatchdogReset),
            (b"tetherbot.probe=watchdog", BootMode::ProbeWatchdog),
            (b"tetherbot.probe=stack", BootMode::ProbeStackOverflow),
        ];
        if let Some((_, probe)) = probes.iter().find(|(word, _)| has(line, word)) {
            return *probe;
        }
    }
    BootMode::Flight {
        lockstep: has(line, b"tetherbot.clock=lockstep"),
    }
}

/// The decimal number right after `key` in `line` (`None` when absent, empty or over `u64::MAX`).
#[cfg(any(feature = "bench", feature = "test-probes"))]
fn number_after(line: &[u8], key: &[u8]) -> Option<u64> {
    let at = line.windows(key.len()).position(|w| w == key)?;
    let digits = line.get(at.checked_add(key.len())?..)?;
    let mut n: u64 = 0;
    let mut any = false;
    for &c in digits.iter().take_while(|c| c.is_ascii_digit()) {
        n = n.checked_mul(10)?.checked_add(u64::from(c - b'0'))?;
        any = true;
    }
    any.then_some(n)
}
