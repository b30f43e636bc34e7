//! On-target benchmark workloads, counted in instructions under `qemu-system-arm -icount shift=0`.
//!
//! Each workload runs a fixed number of iterations between two SysTick reads; with `-icount shift=0` one
//! instruction is 1 ns of virtual time and a SysTick tick is 40 ns, so `instructions = ticks * 40` (resolution
//! 40 instructions per measurement, well below the totals reported). The `calibration` workload is a loop of
//! exactly `2 * N + 1` instructions, printed next to its measured count so the conversion can be checked on
//! every run. Output, one line per workload on semihosting stdout:
//! `bench: name=<workload> iterations=<N> ticks=<T> instructions=<I> instructions_per_iteration=<I/N>`.
//! Without `-icount` the figures are real-time based and vary; the host command always passes it.
//! Then the planning workloads (`bench: result ...` lines) and the stack high-water mark of the run
//! (`bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`).
//!
//! Opt-in (boot words `tetherbot.mode=bench tetherbot.workload=tethered_test3 [tetherbot.iterations=N]`): only the
//! calibration and the ledge-with-pole planning workload (Table I test 3, [`run_ledge_pole`]).
//!
//! Modules: `measure` (the SysTick measurement and the planning workloads' harness), `protocol` (the flight code's
//! link path: encode, deframe + decode, executive dispatch), `planning` (the `workloads` crate's planning
//! workloads, `run_all`, on static arenas), `ledge_pole` (the opt-in Table I test 3). The bench uses the flight code and the board's shared
//! pieces (`clock`, `storage`, `stack`); the flight loop (`flight.rs`) does not use the bench.

mod ledge_pole;
mod measure;
mod planning;
mod protocol;


use crate::clock::SysTickClock;
use measure::measure;

/// Iterations of the calibration loop.
const CALIBRATION_LOOPS: u32 = 1_000_000;

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

/// Runs every workload (boot word `tetherbot.mode=bench`).
pub fn run(clock: &mut SysTickClock) {
    host_println!(
        "bench: calibration expected_instructions={}",
        2 * u64::from(CALIBRATION_LOOPS) + 1
    );
    measure(clock, "calibration", CALIBRATION_LOOPS, || {
        calibration_loop(CALIBRATION_LOOPS)
    });
    protocol::run(clock);
    planning::run(clock);
    let stack = crate::stack::usage();
    host_println!(
        "bench: stack_high_water_bytes={} stack_size_bytes={}",
        stack.high_water_bytes,
        stack.size_bytes
    );
}

/// The opt-in ledge-with-pole planning workload (`ledge_pole::run`, `iterations` ABIT* iterations) after the
/// calibration loop.
pub fn run_ledge_pole(clock: &mut SysTickClock, iterations: u32) {
    host_println!(
        "bench: calibration expected_instructions={}",
        2 * u64::from(CALIBRATION_LOOPS) + 1
    );
    measure(clock, "calibration", CALIBRATION_LOOPS, || {
        calibration_loop(CALIBRATION_LOOPS)
    });
    ledge_pole::run(clock, iterations);
    let stack = crate::stack::usage();
    host_println!(
        "bench: stack_high_water_bytes={} stack_size_bytes={}",
        stack.high_water_bytes,
        stack.size_bytes
    );
}
