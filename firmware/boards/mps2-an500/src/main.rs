//! # board-mps2-an500 — the flight computer: QEMU's `mps2-an500` (Cortex-M7)
//!
//! Boot: cortex-m-rt paints the flight stack, zeroes `.bss`, copies `.data`; `main` moves thread mode to the
//! process stack and exceptions to their own handler stack (`stack_guard.rs`), turns on the MPU's stack guard,
//! reads the boot words from the semihosting command line (`host.rs`), starts SysTick (the monotonic clock) and
//! runs the flight loop (`flight.rs`): UART0 is the host link, the CMSDK watchdog guards the loop, arenas are
//! static (`storage.rs`).
//!
//! Modules: `uart` (CMSDK UART as `hal::ByteLink`), `clock` (SysTick as `hal::MonotonicClock`), `watchdog` (CMSDK
//! APB watchdog as `hal::Watchdog`, bite = NMI, then reset), `fault` (panic / HardFault / MemManage / NMI reports
//! over semihosting and a failure exit), `stack_guard` (MPU guard below the flight stack, the two stacks),
//! `stack` (high-water marks from the paint), `storage` (statics lent once, the executive's storage),
//! `host` (semihosting command line), `flight` (the flight loop), `bench` (on-target instruction counts: the flight
//! code's link path and the `workloads` crate's planning workloads; boot word `tetherbot.mode=bench`). `flight` and
//! `bench` share `clock` and `storage`; neither uses the other.
//!
//! Builds: the default features (`test-probes`, `bench`) make the test build the host's tests and benchmarks
//! run; `--no-default-features` is the flight build, which `.ci/run` proves free of reachable panics (feature
//! `panic-never`, `fault.rs`). The stack guard is on in both.
//!
//! `unsafe` is confined to this crate (register access, the one-time static borrow, the semihosting call, the
//! stack switch) and each use carries its justification. See README.md for building, running and the measured
//! figures.
#![no_std]
#![no_main]

#[macro_use]
mod host;
#[cfg(feature = "bench")]
mod bench;
mod clock;
mod fault;
mod flight;
mod stack;
mod stack_guard;
mod storage;
mod uart;
mod watchdog;

use cortex_m_rt::entry;

use host::BootMode;

#[entry]
fn main() -> ! {
    // SAFETY: first thing at boot, nothing on the reset stack is needed later.
    unsafe { stack_guard::run_on_process_stack(boot) }
}

/// Everything after the stack switch: thread mode on the guarded flight stack.
extern "C" fn boot() -> ! {
    let Some(mut core) = cortex_m::Peripherals::take() else {
        host_eprintln!("board: core peripherals taken twice");
        fault::fail()
    };
    if let Err(e) = stack_guard::enable(&mut core.MPU, &mut core.SCB) {
        match e {
            stack_guard::GuardError::NoMpu => host_eprintln!("board: stack guard not enabled: no MPU"),
            stack_guard::GuardError::BadRegion { start, end } => host_eprintln!(
                "board: stack guard not enabled: [0x{:08x}, 0x{:08x}) is no MPU region",
                start,
                end
            ),
        }
        fault::fail()
    }
    storage::zero_psram();
    let words = host::boot_words();
    #[cfg_attr(not(feature = "bench"), allow(unused_mut))]
    let mut clock = clock::SysTickClock::new(core.SYST, words.clock_start_ms);
    match words.mode {
        BootMode::Flight { lockstep } => flight::run(clock, lockstep),
        #[cfg(feature = "bench")]
        BootMode::Bench => {
            bench::run(&mut clock);
            cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
            fault::fail()
        }
        #[cfg(feature = "bench")]
        BootMode::BenchLedgePole { iterations } => {
            bench::run_ledge_pole(&mut clock, iterations);
            cortex_m_semihosting::debug::exit(cortex_m_semihosting::debug::EXIT_SUCCESS);
            fault::fail()
        }
        #[cfg(feature = "test-probes")]
        BootMode::ProbePanic => panic!("fault probe: panic requested on the boot command line"),
        #[cfg(feature = "test-probes")]
        BootMode::ProbeHardFault => cortex_m::asm::udf(),
        #[cfg(feature = "test-probes")]
        BootMode::ProbeWatchdog => {
            // SAFETY: the only watchdog instance; it is deliberately never kicked. A 10 ms timeout keeps the
            // probe quick under `-icount shift=0` (where 1 s of virtual time is ~4 s of host time).
            let _wdog = unsafe { watchdog::CmsdkWatchdog::start(watchdog::WDOGCLK_HZ / 100) };
            loop {
                cortex_m::asm::nop();
            }
        }
        #[cfg(feature = "test-probes")]
        BootMode::ProbeWatchdogReset => {
            if watchdog::take_reset_mark() {
                host_eprintln!("board: REBOOTED by the watchdog's reset output");
                fault::fail()
            }
            watchdog::set_reset_mark();
            watchdog::LET_RESET_ACT.store(true, core::sync::atomic::Ordering::Relaxed);
            // SAFETY: as for `ProbeWatchdog`.
            let _wdog = unsafe { watchdog::CmsdkWatchdog::start(watchdog::WDOGCLK_HZ / 100) };
            loop {
                cortex_m::asm::nop();
            }
        }
        #[cfg(feature = "test-probes")]
        BootMode::ProbeStackOverflow => {
            let frames = stack_guard::overflow_probe();
            host_eprintln!(
                "board: stack probe returned after {} frames: the overflow was NOT trapped",
                frames
            );
            fault::fail()
        }
    }
}
