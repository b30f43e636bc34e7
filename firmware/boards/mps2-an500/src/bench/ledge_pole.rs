//! The opt-in ledge-with-pole planning workload on target (boot words `tetherbot.mode=bench
//! tetherbot.workload=tethered_test3 [tetherbot.iterations=N]`): `workloads::ledge_pole::run_ledge_pole`, Paton et
//! al. Table I test 3, timed by [`super::measure::measure`] over its ABIT* iterations, its phases (settle,
//! stability, anchors, distance-field queries) timed on [`PhaseTickClock`] and printed as `bench: phases
//! name=tethered_test3 settle_ticks=...`. First it prints the storage's size: `bench: test3_storage_bytes=<B>
//! arena_bytes=<A> path_bytes=<P>`.
//!
//! The storage (~1.5 MB) is in SRAM's `.uninit` (NOLOAD, not zeroed at boot; zeroed when taken,
//! `UninitSlot::take_zeroed`), because the flight map's blocks leave under 1 MiB of `.psram`.

use workloads::ledge_pole::{LedgePoleArena, LedgePolePath, LedgePoleStorage};

use super::measure::Board;
use crate::clock::{PhaseTickClock, SysTickClock};
use crate::storage::{UninitSlot, ZeroIsEmpty};

// SAFETY: `LedgePoleStorage` is an ABIT* arena (four `heapless::Vec`s) and a `heapless::Vec` path: all-zero bytes
// are four empty vectors and an empty path (a zero length, an uninitialised buffer).
unsafe impl ZeroIsEmpty for LedgePoleStorage {}

// The workload's arena and path: in SRAM's `.uninit` (see the module docs).
#[link_section = ".uninit.LEDGE_POLE"]
static LEDGE_POLE: UninitSlot<LedgePoleStorage> = UninitSlot::new();

/// Runs the workload (`iterations` ABIT* iterations) on its storage, after printing the storage's size.
pub fn run(clock: &mut SysTickClock, iterations: u32) {
    let Some(storage) = LEDGE_POLE.take_zeroed() else {
        return;
    };
    host_println!(
        "bench: test3_storage_bytes={} arena_bytes={} path_bytes={}",
        core::mem::size_of::<LedgePoleStorage>(),
        core::mem::size_of::<LedgePoleArena>(),
        core::mem::size_of::<LedgePolePath>()
    );
    workloads::ledge_pole::run_ledge_pole(
        storage,
        iterations,
        &mut Board {
            clock,
            iterations: iterations.max(1),
        },
        Some(&PhaseTickClock),
    );
}
