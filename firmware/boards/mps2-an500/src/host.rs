//! Talking to the emulator host over semihosting: the boot command line (`qemu-system-arm -append "..."`) and
//! machine-readable report lines.
//!
//! Boot words recognised on the command line (QEMU passes `<kernel path> <append string>`):
//! - `tetherbot.mode=bench`: run the on-target benchmark workloads (`bench.rs`), print them, exit 0;
//! - `tetherbot.probe=panic` / `hardfault` / `watchdog`: force that fault at boot, to test that faults end the run
//!   with a failure status and a report (used by the host's tests; harmless in flight: no semihosting host, no
//!   command line).
//! - nothing: the flight loop over UART0.

use cortex_m_semihosting::nr;

/// Capacity of the command line copy; longer command lines are truncated (the boot words are short).
const CMDLINE_CAPACITY: usize = 512;

/// What the board does after boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BootMode {
    /// The flight loop over UART0.
    Flight,
    /// The benchmark workloads.
    Bench,
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
    let status = unsafe { cortex_m_semihosting::syscall1(nr::GET_CMDLINE, block.as_mut_ptr() as usize) };
    if status != 0 {
        return BootMode::Flight;
    }
    let len = block[1].min(buf.len());
    let line = buf.get(..len).unwrap_or(&[]);
    let has = |word: &[u8]| line.windows(word.len()).any(|w| w == word);
    if has(b"tetherbot.mode=bench") {
        BootMode::Bench
    } else if has(b"tetherbot.probe=panic") {
        BootMode::ProbePanic
    } else if has(b"tetherbot.probe=hardfault") {
        BootMode::ProbeHardFault
    } else if has(b"tetherbot.probe=watchdog") {
        BootMode::ProbeWatchdog
    } else {
        BootMode::Flight
    }
}
