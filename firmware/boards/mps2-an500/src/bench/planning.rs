//! On-target planning workloads: `firmware::workload::run_all` with static arenas, each workload timed by
//! [`crate::bench::measure`] (one iteration each) and its outcome printed as
//! `bench: result name=<workload> summary=<one line>`; the host (`tetherbot board bench`) runs the same workloads
//! and compares the summaries. Finally the stack high-water mark of the whole bench run:
//! `bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`.
//!
//! Arenas: all in `.psram` (16 MiB, zeroed at boot, never loaded), so the flight mode's SRAM layout and boot are
//! those of a board without these workloads; except the opt-in test-3 workload's storage ([`run_test3`]), which is
//! in SRAM's `.uninit` (NOLOAD, not zeroed at boot; zeroed when taken), because the flight map leaves too little
//! `.psram`. The ABIT* arena (~1.7 MiB) and the scan start all-zero (`Lent`);
//! the local planner, D* Lite arena, BTM and homotopy workspace have non-zero empty states and are initialised in
//! place from their `const` images in flash when the bench takes them (`UninitSlot::take_init`).

use cortex_m_semihosting::hprintln;
use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::geom::Vec3;
use firmware::plan::homotopy::control::ControlGrid;
use firmware::plan::homotopy::{Btm, SearchArena, Workspace};
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::DefaultLocalPlanner;
use firmware::workload::test3::{Test3Arena, Test3Path, Test3Storage};
use firmware::workload::{Arenas, Harness, WallGapArena, SCAN_POINTS};

use crate::clock::SysTickClock;
use crate::storage::{ConstInit, Lent, UninitSlot, ZeroIsEmpty};

impl ConstInit for DefaultLocalPlanner {
    const INIT: Self = DefaultLocalPlanner::new();
}
impl ConstInit for DStarArena<GLOBAL_GRID_MAX_CELLS> {
    const INIT: Self = DStarArena::new();
}
impl ConstInit for Btm {
    const INIT: Self = Btm::new();
}
impl ConstInit for Workspace {
    const INIT: Self = Workspace {
        search: SearchArena::new(),
        grid: ControlGrid::new(),
        classes: heapless::Vec::new(),
    };
}

// The ABIT* arena's empty state is all zero bytes (empty `heapless` vectors): a plain `Lent` in `.psram`.
#[link_section = ".psram"]
static ABIT: Lent<WallGapArena> = Lent::new(WallGapArena::new());
// SAFETY: `Test3Storage` is an ABIT* arena (four `heapless::Vec`s) and a `heapless::Vec` path: all-zero bytes are
// four empty vectors and an empty path (a zero length, an uninitialised buffer).
unsafe impl ZeroIsEmpty for Test3Storage {}

// The opt-in test-3 workload's arena and path (~1.5 MB): in SRAM's `.uninit` (not zeroed at boot), because the
// flight map's blocks leave under 1 MiB of `.psram`; zeroed when the workload takes it.
#[link_section = ".uninit.TEST3"]
static TEST3: UninitSlot<Test3Storage> = UninitSlot::new();
#[link_section = ".psram"]
static SCAN: Lent<[Vec3; SCAN_POINTS]> = Lent::new([Vec3::new(0.0, 0.0, 0.0); SCAN_POINTS]);
#[link_section = ".psram"]
static LOCAL: UninitSlot<DefaultLocalPlanner> = UninitSlot::new();
#[link_section = ".psram"]
static DSTAR: UninitSlot<DStarArena<GLOBAL_GRID_MAX_CELLS>> = UninitSlot::new();
#[link_section = ".psram"]
static BTM: UninitSlot<Btm> = UninitSlot::new();
#[link_section = ".psram"]
static HOMOTOPY: UninitSlot<Workspace> = UninitSlot::new();

struct Board<'a> {
    clock: &'a mut SysTickClock,
    /// Iterations the measured work stands for (the per-iteration figure of the `bench: name=` line).
    iterations: u32,
}

impl Harness for Board<'_> {
    fn measure(&mut self, name: &'static str, work: &mut dyn FnMut()) {
        crate::bench::measure(self.clock, name, self.iterations, work);
    }
    fn result(&mut self, name: &'static str, summary: &str) {
        hprintln!("bench: result name={} summary={}", name, summary);
        hprintln!(
            "bench: stack name={} high_water_bytes={}",
            name,
            crate::stack::usage().high_water_bytes
        );
    }
}

/// Runs the planning workloads (once; a second call finds the arenas taken and does nothing).
pub fn run(clock: &mut SysTickClock) {
    let (Some(abit), Some(local), Some(scan), Some(dstar), Some(btm), Some(homotopy)) = (
        ABIT.take(),
        LOCAL.take_init(),
        SCAN.take(),
        DSTAR.take_init(),
        BTM.take_init(),
        HOMOTOPY.take_init(),
    ) else {
        return;
    };
    let mut arenas = Arenas {
        abit,
        local,
        scan,
        dstar,
        btm,
        homotopy,
    };
    firmware::workload::run_all(
        &mut arenas,
        &mut Board {
            clock,
            iterations: 1,
        },
    );
}

/// Runs the opt-in test-3 workload (`iterations` ABIT* iterations) on its `.psram` storage and prints the
/// storage's size: `bench: test3_storage_bytes=<B> arena_bytes=<A> path_bytes=<P>`.
pub fn run_test3(clock: &mut SysTickClock, iterations: u32) {
    let Some(storage) = TEST3.take_zeroed() else {
        return;
    };
    hprintln!(
        "bench: test3_storage_bytes={} arena_bytes={} path_bytes={}",
        core::mem::size_of::<Test3Storage>(),
        core::mem::size_of::<Test3Arena>(),
        core::mem::size_of::<Test3Path>()
    );
    firmware::workload::test3::run_test3(
        storage,
        iterations,
        &mut Board {
            clock,
            iterations: iterations.max(1),
        },
    );
}
