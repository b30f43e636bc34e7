//! On-target benchmark workloads, counted in instructions under `qemu-system-arm -icount shift=0`.
//!
//! Each workload runs a fixed number of iterations between two SysTick reads; with `-icount shift=0` one
//! instruction is 1 ns of virtual time and a SysTick tick is 40 ns, so `instructions = ticks * 40` (resolution
//! 40 instructions per measurement, well below the totals reported). The `calibration` workload is a loop of
//! exactly `2 * N + 1` instructions, printed next to its measured count so the conversion can be checked on
//! every run. Output, one line per workload on semihosting stdout:
//! `bench: name=<workload> iterations=<N> ticks=<T> instructions=<I> instructions_per_iteration=<I/N>`.
//! Without `-icount` the figures are real-time based and vary; the host command always passes it.
//! Then the planning workloads (`planning.rs`: `bench: result ...` lines) and the stack high-water mark of the run
//! (`bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`).
//!
//! Opt-in (boot words `tetherbot.mode=bench tetherbot.workload=tethered_test3 [tetherbot.iterations=N]`): only the
//! calibration and the test-3 planning workload ([`run_test3`]).

use cortex_m_semihosting::hprintln;

use crate::clock::{SysTickClock, INSTRUCTIONS_PER_TICK};

/// Iterations of the calibration loop.
const CALIBRATION_LOOPS: u32 = 1_000_000;

/// Runs `work` once and prints its cost per iteration.
pub fn measure(clock: &mut SysTickClock, name: &str, iterations: u32, work: impl FnOnce()) {
    let start = clock.ticks();
    work();
    let ticks = clock.ticks().saturating_sub(start);
    let instructions = ticks * INSTRUCTIONS_PER_TICK;
    hprintln!(
        "bench: name={} iterations={} ticks={} instructions={} instructions_per_iteration={}",
        name,
        iterations,
        ticks,
        instructions,
        instructions / u64::from(iterations.max(1))
    );
}

fn calibration_loop(n: u32) {
    // SAFETY: a register-only countdown loop: `subs` + `bne` per iteration, no memory access, no stack use.
    unsafe {
        core::arch::asm!(
            "2:",
            "subs {n}, {n}, #1",
            "bne 2b",
            n = inout(reg) n => _,
            options(nomem, nostack),
        );
    }
}

/// Runs every workload.
pub fn run(clock: &mut SysTickClock) {
    hprintln!(
        "bench: calibration expected_instructions={}",
        2 * u64::from(CALIBRATION_LOOPS) + 1
    );
    measure(clock, "calibration", CALIBRATION_LOOPS, || {
        calibration_loop(CALIBRATION_LOOPS)
    });
    crate::flight::bench_workloads(clock);
    crate::planning::run(clock);
    let stack = crate::stack::usage();
    hprintln!(
        "bench: stack_high_water_bytes={} stack_size_bytes={}",
        stack.high_water_bytes,
        stack.size_bytes
    );
}

/// The opt-in test-3 planning workload (`planning::run_test3`) after the calibration loop.
pub fn run_test3(clock: &mut SysTickClock, iterations: u32) {
    hprintln!(
        "bench: calibration expected_instructions={}",
        2 * u64::from(CALIBRATION_LOOPS) + 1
    );
    measure(clock, "calibration", CALIBRATION_LOOPS, || {
        calibration_loop(CALIBRATION_LOOPS)
    });
    crate::planning::run_test3(clock, iterations);
    let stack = crate::stack::usage();
    hprintln!(
        "bench: stack_high_water_bytes={} stack_size_bytes={}",
        stack.high_water_bytes,
        stack.size_bytes
    );
}
