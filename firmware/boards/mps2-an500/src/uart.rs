//! CMSDK APB UART driver (UART0 of the mps2-an500), implementing [`hal::ByteLink`].
//!
//! Registers (ARM DDI0479C, checked against QEMU's `hw/char/cmsdk-apb-uart.c`):
//!
//! | offset | name      | use here |
//! |--------|-----------|----------|
//! | 0x00   | DATA      | one byte in / out |
//! | 0x04   | STATE     | bit0 TX full, bit1 RX full, bit2 TX overrun, bit3 RX overrun (write 1 to clear) |
//! | 0x08   | CTRL      | bit0 TX enable, bit1 RX enable, bit2 TX interrupt enable, bit3 RX interrupt enable |
//! | 0x0C   | INTSTATUS | bit0 TX, bit1 RX (write 1 to clear) |
//! | 0x10   | BAUDDIV   | must be >= 16; QEMU ignores the rate (the socket runs at host speed) |
//!
//! The UART has a one-byte receive holding register. QEMU stops taking bytes from the socket while it is full,
//! so nothing is lost: the host's socket buffer is the FIFO. Both interrupts are enabled only to wake the core
//! from `wfi` (see `main.rs`); the handler just clears INTSTATUS, all data moves in thread mode.
//!
//! Pitfall (measured, see `shared/EMBEDDED.md`): bytes the host sends before RX is enabled can stall for about a
//! second; `init` does one dummy DATA read after enabling RX, and the board sends its ready frame before the host
//! may talk.

use core::ptr::{read_volatile, write_volatile};

/// Base address of UART0 on the mps2-an500 (the protocol link to the host).
pub const UART0_BASE: usize = 0x4000_4000;
/// Base address of UART1 (the test-harness control port, see `flight.rs`).
pub const UART1_BASE: usize = 0x4000_5000;
/// NVIC interrupt numbers of UART0 and UART1 (RX, TX, RX, TX) on the mps2 boards.
pub const UART_IRQS: [i16; 4] = [0, 1, 2, 3];

const DATA: usize = 0x00;
const STATE: usize = 0x04;
const CTRL: usize = 0x08;
const INTSTATUS: usize = 0x0C;
const BAUDDIV: usize = 0x10;

const STATE_TX_FULL: u32 = 1 << 0;
const STATE_RX_FULL: u32 = 1 << 1;
const STATE_TX_OVERRUN: u32 = 1 << 2;
const STATE_RX_OVERRUN: u32 = 1 << 3;
const CTRL_TX_EN: u32 = 1 << 0;
const CTRL_RX_EN: u32 = 1 << 1;
const CTRL_TX_INT_EN: u32 = 1 << 2;
const CTRL_RX_INT_EN: u32 = 1 << 3;

/// A UART error: the only one the CMSDK UART reports is an overrun (a byte arrived while the holding register
/// was full, or was written while the transmitter was full).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum UartError {
    /// Receive overrun: at least one byte was lost. The flag is cleared when reported.
    RxOverrun,
    /// Transmit overrun: a written byte was dropped. The flag is cleared when reported.
    TxOverrun,
}

impl hal::Error for UartError {
    fn kind(&self) -> hal::ErrorKind {
        hal::ErrorKind::Fault
    }
}

/// The CMSDK UART at a fixed base address. Only one instance per UART may exist (`Uart::uart0` is called once
/// by `main`).
pub struct Uart {
    base: usize,
}

impl Uart {
    /// Takes the UART at `base` ([`UART0_BASE`] or [`UART1_BASE`]), enables TX and RX (and their wake-up
    /// interrupts) and discards any stale receive byte.
    ///
    /// # Safety
    /// Call once per UART: the returned value owns its registers.
    pub unsafe fn take(base: usize) -> Self {
        let uart = Self { base };
        uart.wr(BAUDDIV, 16);
        uart.wr(
            CTRL,
            CTRL_TX_EN | CTRL_RX_EN | CTRL_TX_INT_EN | CTRL_RX_INT_EN,
        );
        // The dummy read after enabling RX (EMBEDDED.md): unblocks QEMU's receive path immediately.
        let _ = uart.rd(DATA);
        uart.wr(STATE, STATE_TX_OVERRUN | STATE_RX_OVERRUN);
        uart
    }

    /// Clears the interrupt status of UART0 and UART1. Called from the interrupt handler, which only exists to
    /// end a `wfi`.
    pub fn clear_interrupts() {
        for base in [UART0_BASE, UART1_BASE] {
            // SAFETY: INTSTATUS is write-1-to-clear; clearing both bits has no effect on data or on the
            // thread-mode owner's view of STATE.
            unsafe { write_volatile((base + INTSTATUS) as *mut u32, 0b11) }
        }
    }

    fn rd(&self, offset: usize) -> u32 {
        // SAFETY: `base + offset` is a register of the CMSDK UART mapped by the board (see the table above);
        // 32-bit aligned volatile access is what the device expects.
        unsafe { read_volatile((self.base + offset) as *const u32) }
    }

    fn wr(&self, offset: usize, value: u32) {
        // SAFETY: as in `rd`.
        unsafe { write_volatile((self.base + offset) as *mut u32, value) }
    }

    fn check_overrun(&mut self) -> Result<(), UartError> {
        let state = self.rd(STATE);
        if state & STATE_RX_OVERRUN != 0 {
            self.wr(STATE, STATE_RX_OVERRUN);
            return Err(UartError::RxOverrun);
        }
        if state & STATE_TX_OVERRUN != 0 {
            self.wr(STATE, STATE_TX_OVERRUN);
            return Err(UartError::TxOverrun);
        }
        Ok(())
    }
}

impl hal::ByteLink for Uart {
    type Error = UartError;

    fn read(&mut self, buf: &mut [u8]) -> Result<usize, UartError> {
        self.check_overrun()?;
        let mut n = 0;
        for slot in buf.iter_mut() {
            if self.rd(STATE) & STATE_RX_FULL == 0 {
                break;
            }
            *slot = (self.rd(DATA) & 0xFF) as u8;
            n += 1;
        }
        Ok(n)
    }

    fn write(&mut self, buf: &[u8]) -> Result<usize, UartError> {
        self.check_overrun()?;
        let mut n = 0;
        for &byte in buf {
            if self.rd(STATE) & STATE_TX_FULL != 0 {
                break;
            }
            self.wr(DATA, u32::from(byte));
            n += 1;
        }
        Ok(n)
    }

    fn read_ready(&mut self) -> Result<bool, UartError> {
        self.check_overrun()?;
        Ok(self.rd(STATE) & STATE_RX_FULL != 0)
    }

    fn write_ready(&mut self) -> Result<bool, UartError> {
        self.check_overrun()?;
        Ok(self.rd(STATE) & STATE_TX_FULL == 0)
    }
}
