//! CMSDK APB watchdog (at 0x4000_8000 on the mps2 boards), implementing [`hal::Watchdog`].
//!
//! The counter runs down from WDOGLOAD on WDOGCLK (25 MHz in QEMU). Reaching zero raises the watchdog interrupt,
//! which QEMU's mps2 wires to the **NMI**; the board's NMI handler (`fault.rs`) reports "watchdog expired" over
//! semihosting and ends the run with a failure status, so a stalled flight loop never hangs silently. The reset
//! output (RESEN) is left off: a silent reboot would hide the stall from the test. A kick writes WDOGINTCLR, which
//! reloads the counter.
//!
//! | offset | name       | use |
//! |--------|------------|-----|
//! | 0x000  | WDOGLOAD   | timeout in WDOGCLK ticks |
//! | 0x008  | WDOGCONTROL| bit0 INTEN, bit1 RESEN |
//! | 0x00C  | WDOGINTCLR | any write: clear interrupt, reload |
//! | 0xC00  | WDOGLOCK   | 0x1ACCE551 unlocks writes, anything else locks |

use core::ptr::write_volatile;
use core::sync::atomic::{AtomicU32, Ordering};

const BASE: usize = 0x4000_8000;
const LOAD: usize = 0x000;
const CONTROL: usize = 0x008;
const INTCLR: usize = 0x00C;
const LOCK: usize = 0xC00;
const UNLOCK_KEY: u32 = 0x1ACC_E551;
const CONTROL_INTEN: u32 = 1;
/// WDOGCLK frequency in QEMU's mps2 boards, Hz.
pub const WDOGCLK_HZ: u32 = 25_000_000;
/// Default timeout: 2 s. The flight loop kicks every iteration and wakes at least every SysTick wrap (1 ms),
/// so only a loop stuck for more than 2 s (a missing budget, a livelock) bites.
pub const TIMEOUT_TICKS: u32 = 2 * WDOGCLK_HZ;
/// Timeout in lockstep (the host steps the executive): 30 s. Without `-icount` QEMU's virtual clock follows the
/// host's wall clock, so on a loaded 2-core CI host one bounded step (a scan integration) can take more than 2 s of
/// it; in lockstep the watchdog only has to catch a wedged board, before the host's 60 s reply timeout does.
pub const LOCKSTEP_TIMEOUT_TICKS: u32 = 30 * WDOGCLK_HZ;

/// The timeout in force, for the NMI report.
static ACTIVE_TIMEOUT_TICKS: AtomicU32 = AtomicU32::new(0);

/// Milliseconds of the timeout in force.
pub fn active_timeout_ms() -> u64 {
    u64::from(ACTIVE_TIMEOUT_TICKS.load(Ordering::Relaxed)) * 1000 / u64::from(WDOGCLK_HZ)
}

/// The started watchdog. Infallible: the register writes cannot fail.
pub struct CmsdkWatchdog(());

fn wr(offset: usize, value: u32) {
    // SAFETY: BASE + offset is a register of the CMSDK APB watchdog on the mps2-an500 (QEMU `info mtree`);
    // aligned 32-bit volatile writes are what the device expects. Only `CmsdkWatchdog` writes these registers.
    unsafe { write_volatile((BASE + offset) as *mut u32, value) }
}

impl CmsdkWatchdog {
    /// Starts the watchdog with `timeout_ticks` (WDOGCLK ticks).
    ///
    /// # Safety
    /// Call once: the value owns the watchdog registers.
    pub unsafe fn start(timeout_ticks: u32) -> Self {
        ACTIVE_TIMEOUT_TICKS.store(timeout_ticks, Ordering::Relaxed);
        wr(LOCK, UNLOCK_KEY);
        wr(LOAD, timeout_ticks);
        wr(INTCLR, 1);
        wr(CONTROL, CONTROL_INTEN);
        wr(LOCK, 0);
        Self(())
    }
}

/// Kicks the started watchdog. Also used by the board's own waits outside the executive (the lockstep control
/// port), where the `CmsdkWatchdog` value is owned by the executive; a kick is an idempotent register write.
pub fn kick() {
    wr(LOCK, UNLOCK_KEY);
    wr(INTCLR, 1);
    wr(LOCK, 0);
}

impl hal::Watchdog for CmsdkWatchdog {
    type Error = core::convert::Infallible;

    fn kick(&mut self) -> Result<(), Self::Error> {
        kick();
        Ok(())
    }
}
