//! Fault reporting: panic, hard fault, watchdog bite (NMI) and unexpected interrupts all print a report over
//! semihosting (to QEMU's standard error) and end QEMU with exit status 1. Nothing hangs silently under QEMU. If
//! the exit call returns (a debugger that ignores it), the core resets (`SCB::sys_reset`), which a ground station
//! sees as a reboot and a second ready frame. On hardware without any semihosting host the semihosting calls
//! themselves would fault: this binary is built for the emulated board.
//!
//! Report format, one line each, so the host and tests can grep them:
//! `board: PANIC <message> at <file>:<line>:<col>`, `board: HARDFAULT pc=0x... lr=0x... xpsr=0x... cfsr=0x...
//! hfsr=0x... mmfar=0x... bfar=0x...`, `board: WATCHDOG expired ...`, `board: UNEXPECTED interrupt irqn=N`.

use core::panic::PanicInfo;
use core::ptr::read_volatile;
use cortex_m_rt::{exception, ExceptionFrame};
use cortex_m_semihosting::{debug, heprintln};

use crate::uart::{Uart, UART_IRQS};

/// Ends the run with a failure status, after the caller printed its report.
pub fn fail() -> ! {
    debug::exit(debug::EXIT_FAILURE);
    // Only reached without a semihosting host: reset rather than hang.
    cortex_m::peripheral::SCB::sys_reset()
}

#[panic_handler]
fn panic(info: &PanicInfo) -> ! {
    match info.location() {
        Some(loc) => heprintln!(
            "board: PANIC {} at {}:{}:{}",
            info.message(),
            loc.file(),
            loc.line(),
            loc.column()
        ),
        None => heprintln!("board: PANIC {} at <unknown location>", info.message()),
    }
    fail()
}

/// Reads a System Control Block fault register.
fn scb_reg(addr: usize) -> u32 {
    // SAFETY: CFSR (0xE000_ED28), HFSR (0xE000_ED2C), MMFAR (0xE000_ED34) and BFAR (0xE000_ED38) are architected
    // ARMv7-M registers, always mapped, and reading them has no side effect.
    unsafe { read_volatile(addr as *const u32) }
}

#[exception]
unsafe fn HardFault(frame: &ExceptionFrame) -> ! {
    heprintln!(
        "board: HARDFAULT pc=0x{:08x} lr=0x{:08x} xpsr=0x{:08x} cfsr=0x{:08x} hfsr=0x{:08x} mmfar=0x{:08x} bfar=0x{:08x}",
        frame.pc(),
        frame.lr(),
        frame.xpsr(),
        scb_reg(0xE000_ED28),
        scb_reg(0xE000_ED2C),
        scb_reg(0xE000_ED34),
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
    heprintln!(
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
    heprintln!("board: UNEXPECTED interrupt irqn={}", irqn);
    fail()
}
