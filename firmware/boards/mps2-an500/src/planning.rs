//! On-target planning workloads: `firmware::workload::run_all` with static arenas, each workload timed by
//! [`crate::bench::measure`] (one iteration each) and its outcome printed as
//! `bench: result name=<workload> summary=<one line>`; the host (`tetherbot board bench`) runs the same workloads
//! and compares the summaries. Finally the stack high-water mark of the whole bench run:
//! `bench: stack_high_water_bytes=<B> stack_size_bytes=<S>`.
//!
//! Arenas: the ABIT* arena (~1.5 MiB, all-zero initial value: empty `heapless` vectors) lives in `.psram`; the
//! others are in SRAM (`.bss`, or `.data` for the homotopy BTM and workspace, whose empty state is not all zero).

use cortex_m_semihosting::hprintln;
use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::geom::Vec3;
use firmware::plan::homotopy::{Btm, SearchArena, Workspace};
use firmware::plan::homotopy::control::ControlGrid;
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::DefaultLocalPlanner;
use firmware::workload::{Arenas, Harness, WallGapArena, SCAN_POINTS};

use crate::clock::SysTickClock;
use crate::storage::Lent;

#[link_section = ".psram"]
static ABIT: Lent<WallGapArena> = Lent::new(WallGapArena::new());
static LOCAL: Lent<DefaultLocalPlanner> = Lent::new(DefaultLocalPlanner::new());
static SCAN: Lent<[Vec3; SCAN_POINTS]> = Lent::new([Vec3::new(0.0, 0.0, 0.0); SCAN_POINTS]);
static DSTAR: Lent<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Lent::new(DStarArena::new());
static BTM: Lent<Btm> = Lent::new(Btm::new());
static HOMOTOPY: Lent<Workspace> = Lent::new(Workspace {
    search: SearchArena::new(),
    grid: ControlGrid::new(),
    classes: heapless::Vec::new(),
});

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
    let (Some(abit), Some(local), Some(scan), Some(dstar), Some(btm), Some(homotopy)) =
        (ABIT.take(), LOCAL.take(), SCAN.take(), DSTAR.take(), BTM.take(), HOMOTOPY.take())
    else {
        return;
    };
    let mut arenas = Arenas { abit, local, scan, dstar, btm, homotopy };
    firmware::workload::run_all(&mut arenas, &mut Board { clock });
}
