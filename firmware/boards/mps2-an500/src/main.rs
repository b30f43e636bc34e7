//! # board-mps2-an500 — the flight computer: QEMU's `mps2-an500` (Cortex-M7)
//!
//! Boot: cortex-m-rt paints the stack, zeroes `.bss`, copies `.data`, then `main` starts SysTick (the monotonic
//! clock), reads the boot words from the semihosting command line (`host.rs`) and runs the flight loop
//! (`flight.rs`): UART0 is the host link, the CMSDK watchdog guards the loop, arenas are static (`storage.rs`).
//!
//! Modules: `uart` (CMSDK UART as `hal::ByteLink`), `clock` (SysTick as `hal::MonotonicClock`), `watchdog` (CMSDK
//! APB watchdog as `hal::Watchdog`, bite = NMI), `fault` (panic / HardFault / NMI reports over semihosting and a
//! failure exit), `stack` (high-water mark from the paint), `storage` (statics lent once, the executive's storage),
//! `host` (semihosting command line), `flight` (the flight loop), `bench` (on-target instruction counts: the flight
//! code's link path and the `workloads` crate's planning workloads; boot word `tetherbot.mode=bench`). `flight` and
//! `bench` share `clock` and `storage`; neither uses the other.
//!
//! `unsafe` is confined to this crate (register access, the one-time static borrow, the semihosting call) and
//! each use carries its justification. See README.md for building, running and the measured figures.
#![no_std]
#![no_main]

mod bench;
mod clock;
mod fault;
mod flight;
mod host;
mod stack;
mod storage;
mod uart;
mod watchdog;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, heprintln};

use host::BootMode;

#[entry]
fn main() -> ! {
    let Some(core) = cortex_m::Peripherals::take() else {
        heprintln!("board: core peripherals taken twice");
        fault::fail()
    };
    storage::zero_psram();
    let mut clock = clock::SysTickClock::new(core.SYST);
    match host::boot_mode() {
        BootMode::Flight { lockstep } => flight::run(clock, lockstep),
        BootMode::Bench => {
            bench::run(&mut clock);
            debug::exit(debug::EXIT_SUCCESS);
            fault::fail()
        }
        BootMode::BenchLedgePole { iterations } => {
            bench::run_ledge_pole(&mut clock, iterations);
            debug::exit(debug::EXIT_SUCCESS);
            fault::fail()
        }
        BootMode::ProbePanic => panic!("fault probe: panic requested on the boot command line"),
        BootMode::ProbeHardFault => cortex_m::asm::udf(),
        BootMode::ProbeWatchdog => {
            // SAFETY: the only watchdog instance; it is deliberately never kicked. A 10 ms timeout keeps the
            // probe quick under `-icount shift=0` (where 1 s of virtual time is ~4 s of host time).
            let _wdog = unsafe { watchdog::CmsdkWatchdog::start(watchdog::WDOGCLK_HZ / 100) };
            loop {
                cortex_m::asm::nop();
            }
        }
    }
}
