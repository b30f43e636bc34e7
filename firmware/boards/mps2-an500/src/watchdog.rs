//! CMSDK APB watchdog (at 0x4000_8000 on the mps2 boards), implementing [`hal::Watchdog`].
//!
//! The counter runs down from WDOGLOAD on WDOGCLK (25 MHz in QEMU). Reaching zero raises the watchdog interrupt
//! (INTEN), which QEMU's mps2 wires to the **NMI**, and reloads the counter; reaching zero a second time with the
//! interrupt still uncleared asserts the reset output (RESEN) and stops the counter (CMSDK TRM, ARM DDI 0479,
//! "APB watchdog"). Both are enabled (`WDOGCONTROL` = INTEN | RESEN): the NMI handler (`fault.rs`) reports
//! "watchdog expired" over semihosting and ends the run with a failure status, so under QEMU a stalled flight
//! loop never hangs silently; and if the handler itself cannot finish (no semihosting host on real hardware, a
//! wedged report), the second expiry, one timeout later, resets the computer. A kick writes WDOGINTCLR, which
//! clears the interrupt and reloads the counter. Until issue 24 RESEN was off, so real hardware would never have
//! reset.
//!
//! QEMU (`hw/watchdog/cmsdk-apb-watchdog.c`) models the same: with RESEN set the second expiry calls
//! `watchdog_perform_action()`, which by default (`-action watchdog=reset`) resets the whole machine: QEMU
//! reloads the ELF's loaded sections and restarts at the reset vector; RAM outside them (the `.uninit` section)
//! keeps its bytes. The boot probe `tetherbot.probe=watchdog-reset` lets the interrupt pass without ending the run
//! and leaves a mark in `.uninit`; the rebooted board finds the mark and prints `board: REBOOTED by the
//! watchdog's reset output` (`tests/tests/board.rs`).
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
const CONTROL_RESEN: u32 = 1 << 1;
/// WDOGCLK frequency in QEMU's mps2 boards, Hz.
pub const WDOGCLK_HZ: u32 = 25_000_000;
/// Default timeout: 2 s (the reset follows one more timeout later, 4 s after the last kick). The flight loop kicks every iteration and wakes at least every SysTick wrap (1 ms),
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
        wr(CONTROL, CONTROL_INTEN | CONTROL_RESEN);
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

/// Test build: the NMI handler lets the bite pass instead of ending the run, so the reset output acts (boot probe
/// `tetherbot.probe=watchdog-reset`).
#[cfg(feature = "test-probes")]
pub static LET_RESET_ACT: core::sync::atomic::AtomicBool = core::sync::atomic::AtomicBool::new(false);

/// The mark the watchdog-reset probe leaves in `.uninit` (not zeroed at boot, not reloaded by QEMU's reset).
#[cfg(feature = "test-probes")]
const RESET_MARK: u32 = 0x5744_5253; // "WDRS"

#[cfg(feature = "test-probes")]
#[link_section = ".uninit.board_watchdog_reset_mark"]
static mut RESET_MARK_SLOT: core::mem::MaybeUninit<u32> = core::mem::MaybeUninit::uninit();

/// Reads and clears the watchdog-reset probe's mark: true when the previous boot left it (this boot is the reset).
#[cfg(feature = "test-probes")]
pub fn take_reset_mark() -> bool {
    let slot = core::ptr::addr_of_mut!(RESET_MARK_SLOT).cast::<u32>();
    // SAFETY: a 4-aligned word of `.uninit` used by nothing else; any bit pattern is a valid u32 and only thread
    // mode touches it, once at boot.
    unsafe {
        let was = core::ptr::read_volatile(slot) == RESET_MARK;
        core::ptr::write_volatile(slot, 0);
        was
    }
}

/// Leaves the watchdog-reset probe's mark for the next boot.
#[cfg(feature = "test-probes")]
pub fn set_reset_mark() {
    let slot = core::ptr::addr_of_mut!(RESET_MARK_SLOT).cast::<u32>();
    // SAFETY: as in `take_reset_mark`.
    unsafe { core::ptr::write_volatile(slot, RESET_MARK) }
}

/// Timeout of a bite on command (control byte `W`): 10 ms, so the reset comes 20 ms after the last kick.
#[cfg(feature = "test-probes")]
const BITE_TICKS: u32 = WDOGCLK_HZ / 100;

/// Test build: the flight loop stops kicking (control byte `W`, a watchdog bite in the middle of a mission): the
/// timeout is cut to `BITE_TICKS`, the NMI handler lets the bite pass and the second expiry's reset output reboots
/// the board, which finds the mark and says so. Returns only if no reset came.
#[cfg(feature = "test-probes")]
pub fn stop_kicking() {
    set_reset_mark();
    LET_RESET_ACT.store(true, Ordering::Relaxed);
    ACTIVE_TIMEOUT_TICKS.store(BITE_TICKS, Ordering::Relaxed);
    wr(LOCK, UNLOCK_KEY);
    wr(LOAD, BITE_TICKS);
    wr(INTCLR, 1);
    wr(LOCK, 0);
    await_reset();
}

/// Spins (bounded: 10^9 iterations, seconds on the emulator) while the reset output comes; returns if it did not.
#[cfg(feature = "test-probes")]
pub fn await_reset() {
    for _ in 0..1_000_000_000u32 {
        cortex_m::asm::nop();
    }
}
