//! SysTick-based [`hal::MonotonicClock`].
//!
//! SysTick counts down on the core clock (QEMU's mps2 boards: 25 MHz, `SYSCLK_FRQ` in `hw/arm/mps2.c`) and wraps
//! every millisecond (reload 24 999): the SysTick exception counts wraps (and wakes the idle loop, so timers such
//! as the telemetry period are served within 1 ms); `now` combines the wrap count with the current value
//! (re-reading when a wrap raced the read). 64-bit ticks never wrap in a mission.
//!
//! Under `qemu-system-arm -icount shift=0` each instruction advances virtual time by exactly 1 ns, so one SysTick
//! tick is [`INSTRUCTIONS_PER_TICK`] instructions and tick counts repeat exactly from run to run: this is how the
//! benchmark command counts on-target instructions (`bench/`).
//!
//! [`BoardClock`] is the executive's clock, shared by the flight loop and the executive benchmark: SysTick when
//! free-running, the host's step time in lockstep.

use core::sync::atomic::{AtomicU32, Ordering};
use cortex_m::peripheral::{syst::SystClkSource, SYST};

/// Core clock of the mps2 boards in QEMU, Hz.
pub const CORE_HZ: u64 = 25_000_000;
/// Instructions per SysTick tick under `-icount shift=0` (1 ns per instruction, 40 ns per 25 MHz tick).
pub const INSTRUCTIONS_PER_TICK: u64 = 1_000_000_000 / CORE_HZ;
/// SysTick reload: one wrap per millisecond.
const RELOAD: u32 = (CORE_HZ / 1000) as u32 - 1;
/// Retries of the wrap-consistent read; a second wrap within two register reads is impossible (1 ms apart).
const READ_RETRIES: u32 = 3;

static WRAPS: AtomicU32 = AtomicU32::new(0);

/// Called from the SysTick exception: one more wrap of the 24-bit counter.
pub fn on_systick() {
    WRAPS.fetch_add(1, Ordering::Relaxed);
}

/// The monotonic clock: SysTick plus the wrap count.
pub struct SysTickClock {
    syst: SYST,
}

impl SysTickClock {
    /// Starts SysTick on the core clock with the wrap interrupt enabled.
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        Self { syst }
    }

    /// A handle that reads the already started SysTick without owning it (for a second executive in the
    /// benchmark mode). Reading the counter has no side effect.
    pub fn detached() -> Self {
        // SAFETY: only `ticks` touches `syst`, and it only reads the current value (`SYST::get_current` is a
        // static read); no configuration is changed through this second handle.
        Self {
            syst: unsafe { cortex_m::Peripherals::steal() }.SYST,
        }
    }

    /// Core-clock ticks since `new`.
    pub fn ticks(&mut self) -> u64 {
        let mut result = 0;
        for _ in 0..READ_RETRIES {
            let before = WRAPS.load(Ordering::Acquire);
            let current = SYST::get_current();
            let after = WRAPS.load(Ordering::Acquire);
            result = u64::from(after) * (u64::from(RELOAD) + 1) + u64::from(RELOAD - current);
            if before == after {
                break;
            }
        }
        let _ = &mut self.syst;
        result
    }
}

impl hal::MonotonicClock for SysTickClock {
    fn now(&mut self) -> hal::Instant {
        hal::Instant::from_micros(self.ticks() / (CORE_HZ / 1_000_000))
    }
}

/// The executive's clock: SysTick when free-running, the host's step time in lockstep.
pub struct BoardClock {
    /// The free-running clock.
    pub systick: SysTickClock,
    /// Lockstep only: the host's time of the current step (then `now` returns it, not SysTick).
    pub lockstep_now: Option<hal::Instant>,
}

impl hal::MonotonicClock for BoardClock {
    fn now(&mut self) -> hal::Instant {
        match self.lockstep_now {
            Some(t) => t,
            None => self.systick.now(),
        }
    }
}
