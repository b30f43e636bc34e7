//! On-target planning workloads: `firmware::workload::run_all` with static arenas, each workload timed by
//! [`crate::bench::measure`] (one iteration each) and its outcome printed as
//! `bench: result name=<workload> summary=<one line>`; the host (`tetherbot board bench`) runs the same workloads
//! and compares the summaries. Finally the stack high-water mark of the whole bench run:
//! `bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`.
//!
//! Arenas: all in `.psram` (16 MiB, zeroed at boot, never loaded), so the flight mode's SRAM layout and boot are
//! those of a board without these workloads. The ABIT* arena (~1.7 MiB) and the scan start all-zero (`Lent`);
//! the local planner, D* Lite arena, BTM and homotopy workspace have non-zero empty states and are initialised in
//! place from their `const` images in flash when the bench takes them (`PsramSlot`).

use cortex_m_semihosting::hprintln;
use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::geom::Vec3;
use firmware::plan::homotopy::control::ControlGrid;
use firmware::plan::homotopy::{Btm, SearchArena, Workspace};
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::DefaultLocalPlanner;
use firmware::workload::{Arenas, Harness, WallGapArena, SCAN_POINTS};

use crate::clock::SysTickClock;
use crate::storage::{ConstInit, Lent, PsramSlot};

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
#[link_section = ".psram"]
static SCAN: Lent<[Vec3; SCAN_POINTS]> = Lent::new([Vec3::new(0.0, 0.0, 0.0); SCAN_POINTS]);
#[link_section = ".psram"]
static LOCAL: PsramSlot<DefaultLocalPlanner> = PsramSlot::new();
#[link_section = ".psram"]
static DSTAR: PsramSlot<DStarArena<GLOBAL_GRID_MAX_CELLS>> = PsramSlot::new();
#[link_section = ".psram"]
static BTM: PsramSlot<Btm> = PsramSlot::new();
#[link_section = ".psram"]
static HOMOTOPY: PsramSlot<Workspace> = PsramSlot::new();

struct Board<'a> {
    clock: &'a mut SysTickClock,
}

impl Harness for Board<'_> {
    fn measure(&mut self, name: &'static str, work: &mut dyn FnMut()) {
        crate::bench::measure(self.clock, name, 1, work);
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
        LOCAL.take(),
        SCAN.take(),
        DSTAR.take(),
        BTM.take(),
        HOMOTOPY.take(),
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
    firmware::workload::run_all(&mut arenas, &mut Board { clock });
}
