//! The measurement of one benchmark (SysTick ticks around the work, converted to instructions) and the harness
//! through which the `workloads` crate's planning workloads are timed and reported on target.

use workloads::Harness;

use crate::clock::{SysTickClock, INSTRUCTIONS_PER_TICK};

/// Runs `work` once and prints its cost per iteration.
pub fn measure(clock: &mut SysTickClock, name: &str, iterations: u32, work: impl FnOnce()) {
    let start = clock.ticks();
    work();
    let ticks = clock.ticks().saturating_sub(start);
    let instructions = ticks * INSTRUCTIONS_PER_TICK;
    host_println!(
        "bench: name={} iterations={} ticks={} instructions={} instructions_per_iteration={}",
        name,
        iterations,
        ticks,
        instructions,
        instructions / u64::from(iterations.max(1))
    );
}

/// The planning workloads' [`Harness`] on the board: [`measure`] times the work, the result goes out as
/// `bench: result name=<workload> summary=<one line>` followed by `bench: stack name=<workload> high_water_bytes=<B>`.
pub struct Board<'a> {
    /// The clock that times the work.
    pub clock: &'a mut SysTickClock,
    /// Iterations the measured work stands for (the per-iteration figure of the `bench: name=` line).
    pub iterations: u32,
}

impl Harness for Board<'_> {
    fn measure(&mut self, name: &'static str, work: &mut dyn FnMut()) {
        measure(self.clock, name, self.iterations, work);
    }
    fn phases(&mut self, name: &'static str, phases: &str) {
        host_println!("bench: phases name={} {}", name, phases);
    }
    fn result(&mut self, name: &'static str, summary: &str) {
        host_println!("bench: result name={} summary={}", name, summary);
        host_println!(
            "bench: stack name={} high_water_bytes={}",
            name,
            crate::stack::usage().high_water_bytes
        );
    }
}
