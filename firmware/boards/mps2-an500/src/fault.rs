//! Fault reporting: panic, hard fault, watchdog bite (NMI) and unexpected interrupts all print a report over
//! semihosting (to QEMU's standard error) and end QEMU with exit status 1. Nothing hangs silently under QEMU. If
//! the exit call returns (a debugger that ignores it), the core resets (`SCB::sys_reset`), which a ground station
//! sees as a reboot and a second ready frame. On hardware without any semihosting host the semihosting calls
//! themselves would fault: this binary is built for the emulated board.
//!
//! Report format, one line each, so the host and tests can grep them:
//! `board: PANIC <message> at <file>:<line>:<col>`, `board: HARDFAULT pc=0x... lr=0x... xpsr=0x... cfsr=0x...
//! hfsr=0x... mmfar=0x... bfar=0x...`, `board: STACK OVERFLOW into the guard [0x..., 0x...): psp=0x...
//! mmfar=0x... cfsr=0x... hfsr=0x...` (MemManage from the MPU guard, `stack_guard.rs`, or the same escalated to
//! HardFault), `board: MEMMANAGE ...` (any other MPU fault), `board: WATCHDOG expired ...`,
//! `board: UNEXPECTED interrupt irqn=N`.
//!
//! **No panic in the flight build, proven at link time.** With feature `panic-never` (only `.ci/run` sets it, on
//! the flight build `--release --no-default-features`) the panic handler calls
//! `board_flight_build_has_a_reachable_panic_path`, which is defined nowhere. Fat LTO removes the handler when no
//! panic path survives optimisation, and with it the reference; if one survives, the link fails with that
//! symbol's name. `.ci/run` then lists the functions that call into `core::panicking` (see the board README).
//! The test build keeps the reporting handler: the `tetherbot.probe=panic` probe panics on purpose.

use core::panic::PanicInfo;
use core::ptr::read_volatile;
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::debug;

use crate::uart::{Uart, UART_IRQS};

/// Ends the run with a failure status, after the caller printed its report.
pub fn fail() -> ! {
    debug::exit(debug::EXIT_FAILURE);
    // Only reached without a semihosting host: reset rather than hang.
    cortex_m::peripheral::SCB::sys_reset()
}

#[cfg(feature = "panic-never")]
extern "C" {
    /// Defined nowhere: referenced only by the panic handler of the no-panic proof build.
    fn board_flight_build_has_a_reachable_panic_path() -> !;
}

#[cfg(feature = "panic-never")]
#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    // SAFETY: never linked; a binary that could reach this line does not link (see the module docs).
    unsafe { board_flight_build_has_a_reachable_panic_path() }
}

#[cfg(not(feature = "panic-never"))]
#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    match info.location() {
        Some(loc) => host_eprintln!(
            "board: PANIC {} at {}:{}:{}",
            info.message(),
            loc.file(),
            loc.line(),
            loc.column()
        ),
        None => host_eprintln!("board: PANIC {} at <unknown location>", info.message()),
    }
    fail()
}

/// Reads a System Control Block fault register.
fn scb_reg(addr: usize) -> u32 {
    // SAFETY: CFSR (0xE000_ED28), HFSR (0xE000_ED2C), MMFAR (0xE000_ED34) and BFAR (0xE000_ED38) are architected
    // ARMv7-M registers, always mapped, and reading them has no side effect.
    unsafe { read_volatile(addr as *const u32) }
}

const CFSR: usize = 0xE000_ED28;
const HFSR: usize = 0xE000_ED2C;
const MMFAR: usize = 0xE000_ED34;

/// Prints the stack-overflow report and ends the run, if the fault status shows an overflow into the guard.
fn report_if_stack_overflow() {
    let (cfsr, mmfar, psp) = (
        scb_reg(CFSR),
        scb_reg(MMFAR),
        cortex_m::register::psp::read(),
    );
    if crate::stack_guard::is_overflow(cfsr, mmfar, psp) {
        let (start, end) = crate::stack_guard::guard();
        host_eprintln!(
            "board: STACK OVERFLOW into the guard [0x{:08x}, 0x{:08x}): psp=0x{:08x} mmfar=0x{:08x} cfsr=0x{:08x} \
             hfsr=0x{:08x}",
            start,
            end,
            psp,
            mmfar,
            cfsr,
            scb_reg(HFSR)
        );
        fail()
    }
}

/// MemManage: the MPU refused an access. Runs on the handler stack (`stack_guard.rs`), so it can report an
/// overflow of the flight stack. The exception frame is not read: after an overflow it lies in the guard.
#[exception]
fn MemoryManagement() {
    report_if_stack_overflow();
    host_eprintln!(
        "board: MEMMANAGE psp=0x{:08x} mmfar=0x{:08x} cfsr=0x{:08x}",
        cortex_m::register::psp::read(),
        scb_reg(MMFAR),
        scb_reg(CFSR)
    );
    fail()
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    // A MemManage fault taken while it could not preempt (PRIMASK set, or in a handler) escalates to here.
    report_if_stack_overflow();
    host_eprintln!(
        "board: HARDFAULT pc=0x{:08x} lr=0x{:08x} xpsr=0x{:08x} cfsr=0x{:08x} hfsr=0x{:08x} mmfar=0x{:08x} bfar=0x{:08x}",
        frame.pc(),
        frame.lr(),
        frame.xpsr(),
        scb_reg(CFSR),
        scb_reg(HFSR),
        scb_reg(MMFAR),
        scb_reg(0xE000_ED38)
    );
    fail()
}

/// The CMSDK watchdog's interrupt is wired to the NMI on QEMU's mps2 boards.
///
/// cortex-m-rt makes NMI handlers `unsafe fn` because they can preempt critical sections; this one shares no
/// data with other contexts (it only prints and exits).
#[exception]
unsafe fn NonMaskableInt() {
    #[cfg(feature = "test-probes")]
    if crate::watchdog::LET_RESET_ACT.load(core::sync::atomic::Ordering::Relaxed) {
        host_eprintln!("board: WATCHDOG expired: probe lets the reset output act");
        crate::watchdog::await_reset();
        host_eprintln!("board: WATCHDOG reset output did not reset the board");
        fail()
    }
    host_eprintln!(
        "board: WATCHDOG expired: the flight loop did not kick for {} ms",
        crate::watchdog::active_timeout_ms()
    );
    fail()
}

#[exception]
fn SysTick() {
    crate::clock::on_systick();
}

#[exception]
unsafe fn DefaultHandler(irqn: i16) {
    if UART_IRQS.contains(&irqn) {
        // The UART interrupts only end a `wfi`; data moves in thread mode.
        Uart::clear_interrupts();
        return;
    }
    host_eprintln!("board: UNEXPECTED interrupt irqn={}", irqn);
    fail()
}
