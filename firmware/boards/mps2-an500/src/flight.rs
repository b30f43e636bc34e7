//! The flight loop on the board: UART0 bytes in, the flight executive, UART0 bytes out.
//! (Phase 1 placeholder: echo. Replaced by the executive once `firmware::exec` exists.)

use cortex_m::peripheral::NVIC;
use cortex_m_semihosting::{debug, hprintln};
use hal::{ByteLink, Watchdog};

use crate::clock::SysTickClock;
use crate::storage::Lent;
use crate::uart::{Uart, UART0_RX_IRQ, UART0_TX_IRQ};
use crate::watchdog::{CmsdkWatchdog, TIMEOUT_TICKS};

#[derive(Clone, Copy)]
struct Irq(u16);
// SAFETY: the numbers are the mps2-an500's UART0 RX/TX lines, valid NVIC interrupt numbers (< 240).
unsafe impl cortex_m::interrupt::InterruptNumber for Irq {
    fn number(self) -> u16 {
        self.0
    }
}

/// Receive scratch buffer, lent once to the flight loop.
static RX_SCRATCH: Lent<[u8; 64]> = Lent::new([0; 64]);

/// Sends all of `bytes`, kicking the watchdog while the transmitter is busy.
fn write_all(uart: &mut Uart, wdog: &mut CmsdkWatchdog, mut bytes: &[u8]) {
    while !bytes.is_empty() {
        let _ = wdog.kick();
        // An overrun error is counted by the UART and cleared; the bytes not accepted are retried.
        if let Ok(n) = uart.write(bytes) {
            bytes = bytes.get(n..).unwrap_or(&[]);
        }
    }
}

/// Sleeps until an interrupt (UART byte, transmitter free, SysTick wrap) unless a byte is already waiting.
fn idle(uart: &mut Uart) {
    cortex_m::interrupt::free(|_| {
        if !uart.read_ready().unwrap_or(true) {
            cortex_m::asm::wfi();
        }
    });
}

/// The flight loop. Never returns: the run ends with a semihosting exit.
pub fn run(mut clock: SysTickClock) -> ! {
    // SAFETY: called once from `main`; owns UART0 and the watchdog from here on.
    let mut uart = unsafe { Uart::uart0() };
    // SAFETY: unmasking the UART interrupts is sound: their handler (DefaultHandler in fault.rs) only clears the
    // UART's interrupt status and shares no data with thread mode.
    unsafe {
        NVIC::unmask(Irq(UART0_RX_IRQ as u16));
        NVIC::unmask(Irq(UART0_TX_IRQ as u16));
    }
    // SAFETY: called once.
    let mut wdog = unsafe { CmsdkWatchdog::start(TIMEOUT_TICKS) };
    let ready_at = clock.ticks();
    write_all(&mut uart, &mut wdog, b"READY\n");
    let Some(buf) = RX_SCRATCH.take() else { crate::fault::fail() };
    loop {
        let _ = wdog.kick();
        let n = uart.read(buf).unwrap_or(0);
        let got = buf.get(..n).unwrap_or(&[]);
        if got.contains(&0x04) {
            let s = crate::stack::usage();
            hprintln!("board: ready_ticks={} stack_high_water_bytes={} stack_size_bytes={}", ready_at, s.high_water_bytes, s.size_bytes);
            debug::exit(debug::EXIT_SUCCESS);
        }
        write_all(&mut uart, &mut wdog, got);
        if n == 0 {
            idle(&mut uart);
        }
    }
}

/// Workloads of the flight code for `bench.rs`.
pub fn bench_workloads(_clock: &mut SysTickClock) {}
