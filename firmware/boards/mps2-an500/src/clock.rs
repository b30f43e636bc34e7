//! SysTick-based [`hal::MonotonicClock`].
//!
//! SysTick counts down on the core clock (QEMU's mps2 boards: 25 MHz, `SYSCLK_FRQ` in `hw/arm/mps2.c`) and wraps
//! every millisecond (reload 24 999): the SysTick exception counts wraps (and wakes the idle loop, so timers such
//! as the telemetry period are served within 1 ms); `now` combines the wrap count with the current value
//! (re-reading when a wrap raced the read).
//!
//! The wrap count is 64 bits wide, kept as two `AtomicU32` halves (ARMv7-M has no 64-bit atomics): the SysTick
//! exception is their only writer and carries into the high half when the low half wraps; a reader takes the low
//! half, the high half and SysTick's current value, and retries when the low half changed meanwhile (an exception
//! ran in between). 2^64 ms is 584 million years, and the ticks (`wraps * 25 000`, u64) and microseconds last
//! 23 000 years. Until issue 24 the count was a single `AtomicU32`: after 2^32 ms (49.7 days) the clock fell back
//! to 0, `Instant::micros_since` saturated at 0 and periodic telemetry stopped for another 49.7 days. The boot
//! word `tetherbot.clock_start_ms=N` (test build) starts the count at N: `tests/tests/board.rs` runs the flight
//! loop across 2^32 ms and checks telemetry keeps its period.
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

/// Low and high halves of the 64-bit wrap count (milliseconds since the clock started, plus its start).
static WRAPS_LO: AtomicU32 = AtomicU32::new(0);
static WRAPS_HI: AtomicU32 = AtomicU32::new(0);

/// Called from the SysTick exception (the only writer of the count): one more wrap of the 24-bit counter.
pub fn on_systick() {
    let lo = WRAPS_LO.load(Ordering::Relaxed).wrapping_add(1);
    if lo == 0 {
        WRAPS_HI.store(
            WRAPS_HI.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }
    WRAPS_LO.store(lo, Ordering::Release);
}

/// The wrap count (64 bits) and SysTick's current value, read consistently: an exception between the first and
/// the last read changes the low half (it always increments it), and then the read is repeated.
fn wraps_and_current() -> (u64, u32) {
    let mut result = (0, 0);
    for _ in 0..READ_RETRIES {
        let lo = WRAPS_LO.load(Ordering::Acquire);
        let hi = WRAPS_HI.load(Ordering::Acquire);
        let current = SYST::get_current();
        result = ((u64::from(hi) << 32) | u64::from(lo), current);
        if WRAPS_LO.load(Ordering::Acquire) == lo {
            break;
        }
    }
    result
}

/// Core-clock ticks of `wraps` whole wraps plus a SysTick current value (counting down from [`RELOAD`]).
fn ticks_of(wraps: u64, current: u32) -> u64 {
    wraps
        .saturating_mul(u64::from(RELOAD) + 1)
        .saturating_add(u64::from(RELOAD.saturating_sub(current)))
}

/// The benchmarks' phase clock (`firmware::plan::tethered::PhaseClock`): the same ticks as
/// [`SysTickClock::ticks`], read through shared references (the planner's space times its phases with it).
/// SysTick must already run (a [`SysTickClock`] started it).
#[cfg(feature = "bench")]
pub struct PhaseTickClock;

#[cfg(feature = "bench")]
impl firmware::plan::tethered::PhaseClock for PhaseTickClock {
    fn ticks(&self) -> u64 {
        let (wraps, current) = wraps_and_current();
        ticks_of(wraps, current)
    }
}

/// The monotonic clock: SysTick plus the wrap count.
pub struct SysTickClock {
    syst: SYST,
}

impl SysTickClock {
    /// Starts SysTick on the core clock with the wrap interrupt enabled, at `start_ms` milliseconds (0 in flight;
    /// the boot word `tetherbot.clock_start_ms` sets it in the test build).
    pub fn new(mut syst: SYST, start_ms: u64) -> Self {
        // Truncations intended: the two halves of the 64-bit count. SysTick is not running yet: no writer races.
        WRAPS_LO.store(start_ms as u32, Ordering::Relaxed);
        WRAPS_HI.store((start_ms >> 32) as u32, Ordering::Relaxed);
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_interrupt();
        syst.enable_counter();
        Self { syst }
    }

    /// A handle that reads the already started SysTick without owning it (for a second executive in the
    /// benchmark mode). Reading the counter has no side effect.
    #[cfg(feature = "bench")]
    pub fn detached() -> Self {
        // SAFETY: only `ticks` touches `syst`, and it only reads the current value (`SYST::get_current` is a
        // static read); no configuration is changed through this second handle.
        Self {
            syst: unsafe { cortex_m::Peripherals::steal() }.SYST,
        }
    }

    /// Core-clock ticks since the start (`start_ms` included).
    pub fn ticks(&mut self) -> u64 {
        let (wraps, current) = wraps_and_current();
        let _ = &mut self.syst;
        ticks_of(wraps, current)
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
