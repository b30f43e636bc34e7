//! Talking to the emulator host over semihosting: the boot command line (`qemu-system-arm -append "..."`) and
//! machine-readable report lines.
//!
//! Boot words recognised on the command line (QEMU passes `<kernel path> <append string>`):
//! - `tetherbot.mode=bench`: run the on-target benchmark workloads (`bench/`), print them, exit 0;
//!   with `tetherbot.workload=tethered_test3` instead only the opt-in ledge-with-pole planning workload
//!   (Table I test 3, `workloads::ledge_pole`), for `tetherbot.iterations=N` iterations (default 750, Table I);
//! - `tetherbot.probe=panic` / `hardfault` / `watchdog`: force that fault at boot, to test that faults end the run
//!   with a failure status and a report (used by the host's tests; harmless in flight: no semihosting host, no
//!   command line).
//! - `tetherbot.clock=lockstep`: the flight loop with the executive stepped by the host over the control port
//!   (UART1) on the host's simulated clock, exactly like the in-process link (see `flight.rs`);
//! - nothing: the flight loop over UART0 on the board's own SysTick clock (free-running, as in flight).

use cortex_m_semihosting::nr;

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
    Bench,
    /// Only the opt-in ledge-with-pole (Table I test 3) planning workload, this many ABIT* iterations.
    BenchLedgePole {
        /// Planner iterations.
        iterations: u32,
    },
    /// Panic at boot.
    ProbePanic,
    /// Execute an undefined instruction at boot (UsageFault escalated to HardFault).
    ProbeHardFault,
    /// Stop kicking the watchdog.
    ProbeWatchdog,
}

/// Reads the command line from the semihosting host and picks the boot mode.
pub fn boot_mode() -> BootMode {
    let mut buf = [0u8; CMDLINE_CAPACITY];
    let mut block = [buf.as_mut_ptr() as usize, buf.len()];
    // SAFETY: SYS_GET_CMDLINE writes at most block[1] bytes into the buffer block[0] points to, and updates
    // block[1] to the length written. Both live on this stack frame for the duration of the call.
    let status =
        unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status != 0 {
        return BootMode::Flight { lockstep: false };
    }
    let len = block[1].min(buf.len());
    let line = buf.get(..len).unwrap_or(&[]);
    let has = |word: &[u8]| line.windows(word.len()).any(|w| w == word);
    if has(b"tetherbot.mode=bench") && has(b"tetherbot.workload=tethered_test3") {
        BootMode::BenchLedgePole {
            iterations: number_after(line, b"tetherbot.iterations=")
                .unwrap_or(workloads::ledge_pole::ITERATIONS),
        }
    } else if has(b"tetherbot.mode=bench") {
        BootMode::Bench
    } else if has(b"tetherbot.probe=panic") {
        BootMode::ProbePanic
    } else if has(b"tetherbot.probe=hardfault") {
        BootMode::ProbeHardFault
    } else if has(b"tetherbot.probe=watchdog") {
        BootMode::ProbeWatchdog
    } else {
        BootMode::Flight {
            lockstep: has(b"tetherbot.clock=lockstep"),
        }
    }
}

/// The decimal number right after `key` in `line` (`None` when absent, empty or over `u32::MAX`).
fn number_after(line: &[u8], key: &[u8]) -> Option<u32> {
    let at = line.windows(key.len()).position(|w| w == key)?;
    let digits = line.get(at + key.len()..)?;
    let mut n: u32 = 0;
    let mut any = false;
    for &c in digits.iter().take_while(|c| c.is_ascii_digit()) {
        n = n.checked_mul(10)?.checked_add(u32::from(c - b'0'))?;
        any = true;
    }
    any.then_some(n)
}
