//! The planning workloads of the `workloads` crate on the host, for `tetherbot board bench`: the board prints one
//! `bench: result name=<workload> summary=<line>` per workload, the host runs the same code on boxed arenas, and
//! the two summaries must be equal (the floats in them are printed shortest-round-trip, so equal text means equal
//! bits).

use firmware::config::team::GLOBAL_GRID_MAX_CELLS;
use firmware::geom::Vec3;
use firmware::plan::homotopy::{Btm, Workspace};
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::DefaultLocalPlanner;
use workloads::ledge_pole::{run_ledge_pole, LedgePoleStorage};
use workloads::{homotopy_tile, run_all, Arenas, Harness, WallGapArena, SCAN_POINTS};

struct Collect(Vec<(String, String)>);

impl Harness for Collect {
    fn measure(&mut self, _: &'static str, work: &mut dyn FnMut()) {
        work()
    }
    fn result(&mut self, name: &'static str, summary: &str) {
        self.0.push((name.to_owned(), summary.to_owned()));
    }
}

/// `(workload, summary)` of every planning workload, computed on the host.
pub fn host_summaries() -> Vec<(String, String)> {
    on_twin_stack(host_summaries_here)
        .unwrap_or_else(|e| vec![("host twin".to_owned(), e)])
}

/// The host twin's stack (bytes): its arenas are built before they are boxed and the planners recurse into the
/// stability LP, more than a test thread's 2 MiB holds (the board's stack is measured on the board).
const HOST_TWIN_STACK_BYTES: usize = 64 << 20;

/// Runs `f` on a thread with the host twin's stack.
fn on_twin_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> Result<T, String> {
    std::thread::Builder::new()
        .stack_size(HOST_TWIN_STACK_BYTES)
        .spawn(f)
        .map_err(|e| format!("cannot start the host twin: {e}"))?
        .join()
        .map_err(|_| "the host twin panicked".to_string())
}

fn host_summaries_here() -> Vec<(String, String)> {
    let mut abit: Box<WallGapArena> = Box::default();
    let mut local: Box<DefaultLocalPlanner> = Box::default();
    let mut scan: Box<[Vec3; SCAN_POINTS]> = Box::new([Vec3::zeros(); SCAN_POINTS]);
    let mut dstar: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
    let mut btm: Box<Btm> = Box::default();
    let mut ws: Box<Workspace> = Box::default();
    let mut arenas = Arenas {
        abit: &mut abit,
        local: &mut local,
        scan: &mut scan,
        dstar: &mut dstar,
        btm: &mut btm,
        homotopy: &mut ws,
    };
    let mut h = Collect(Vec::new());
    run_all(&mut arenas, &mut h);
    // The homotopy phases on the HiRISE tile (the board embeds the same heights).
    match crate::homotopy::tile::hirise_tile() {
        Ok((_, heights)) => {
            let mut store: Box<homotopy_tile::TileStorage> = Box::default();
            homotopy_tile::run(&mut store, &mut btm, &mut ws, &heights, &mut h);
        }
        Err(e) => h.0.push((homotopy_tile::SEGMENT.to_owned(), format!("host tile unavailable: {e}"))),
    }
    h.0
}

/// The opt-in `tethered_test3` workload on the host (`iterations` iterations): `(name, summary)`, on the host
/// twin's stack.
pub fn host_ledge_pole_summary(iterations: u32) -> Result<(String, String), String> {
    on_twin_stack(move || {
        let mut storage: Box<LedgePoleStorage> = Box::default();
        let mut h = Collect(Vec::new());
        run_ledge_pole(&mut storage, iterations, &mut h, None);
        h.0.into_iter().next().unwrap_or_default()
    })
}

/// `(workload, summary)` from the board's bench output.
pub fn board_summaries(text: &str) -> Vec<(String, String)> {
    text.lines()
        .filter_map(|l| l.strip_prefix("bench: result name="))
        .filter_map(|rest| {
            let (name, summary) = rest.split_once(" summary=")?;
            Some((name.to_owned(), summary.to_owned()))
        })
        .collect()
}

/// Pairs board and host summaries by workload: `(name, board, host)`; a workload missing on one side has `None`
/// there.
pub fn compare(
    board: &[(String, String)],
    host: &[(String, String)],
) -> Vec<(String, Option<String>, Option<String>)> {
    let mut out: Vec<(String, Option<String>, Option<String>)> = host
        .iter()
        .map(|(n, h)| {
            let b = board.iter().find(|(k, _)| k == n).map(|(_, s)| s.clone());
            (n.clone(), b, Some(h.clone()))
        })
        .collect();
    for (n, b) in board {
        if !host.iter().any(|(k, _)| k == n) {
            out.push((n.clone(), Some(b.clone()), None));
        }
    }
    out
}
