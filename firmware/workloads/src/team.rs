//! Deterministic workloads of the climbing-team planners ([`firmware::plan::team`], Morad et al.) for on-target
//! cost figures (instruction counts on the emulated Cortex-M7) and host benchmarks: a synthetic scan of a rough
//! 60-degree slope for one local plan, and the crevasse replan of Fig. 12 on a 64 x 64 grid of scenes for D* Lite.
//! Everything is computed with `libm`, so the inputs are bit-identical on every target. A board calls these with
//! its static arenas (a [`DefaultLocalPlanner`](firmware::plan::team::DefaultLocalPlanner) is ~0.6 MiB, a
//! [`DStarArena`] of 4096 cells ~210 KiB).

use firmware::config::team::{TeamParams, GLOBAL_GRID_MAX_CELLS};
use firmware::geom::{Real, Vec3};
use firmware::plan::team::dstar_lite::{DStarArena, DStarError, DStarLite, DStarOutcome};
use firmware::plan::team::scene::SceneError;
use firmware::plan::team::{LocalPlan, LocalPlanner};

/// Points per side of the synthetic scan (48 x 48 = 2304 points, 1 m apart).
pub const SCAN_SIDE: usize = 48;

/// Fill `out` with a scan of a rough slope (z rises 1.7 m per metre of y: 60 degrees), returns the count.
pub fn synthetic_scan(out: &mut [Vec3]) -> usize {
    let mut n = 0;
    for (k, slot) in out.iter_mut().enumerate().take(SCAN_SIDE * SCAN_SIDE) {
        let (i, j) = ((k % SCAN_SIDE) as Real, (k / SCAN_SIDE) as Real);
        let (x, y) = (i - 24.0, j - 24.0);
        let z = 1.732 * y + 0.6 * libm::sinf(0.7 * x) * libm::cosf(0.5 * y) + 0.2 * libm::sinf(2.3 * x + 1.1 * y);
        *slot = Vec3::new(x, y, z);
        n += 1;
    }
    n
}

/// One local plan on the synthetic scan: the robot near the bottom, the goal 40 m up the slope (in 3-D).
pub fn local_plan_workload<const P: usize, const V: usize, const E: usize>(
    planner: &mut LocalPlanner<P, V, E>,
    scan: &[Vec3],
) -> Result<LocalPlan, SceneError> {
    let up = Vec3::new(0.0, -0.866, 0.5);
    let robot = Vec3::new(0.0, -20.0, -34.64);
    let goal = Vec3::new(0.0, 0.0, 0.0);
    let leg = Vec3::new(3.0, -3.0, 0.0);
    planner.plan(scan, &up, &robot, &leg, &goal, 2.0, &TeamParams::DEFAULT)
}

/// D* Lite on a 64 x 64 grid: plan corner to corner, move three cells, wall a 50-cell crevasse across the path,
/// replan incrementally. Returns the final outcome.
pub fn dstar_workload(arena: &mut DStarArena<GLOBAL_GRID_MAX_CELLS>) -> Result<DStarOutcome, DStarError> {
    let mut d = DStarLite::new(64, 64, arena.storage())?;
    for k in 8..56 {
        if k % 9 != 0 {
            d.set_blocked(k, 40, true)?;
        }
    }
    d.plan((2, 2), (60, 60), 1_000_000)?;
    let mut cur = (2, 2);
    for _ in 0..3 {
        if let Some(n) = d.next_cell(cur) {
            cur = n;
            d.move_start(cur)?;
        }
    }
    for x in 0..50 {
        d.add_wall((x, 20), (x, 21))?;
    }
    d.replan(1_000_000)
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::plan::status::{Ended, Status};
    use firmware::plan::team::dstar_lite::Found;
    use firmware::plan::team::DefaultLocalPlanner;
    use std::boxed::Box;

    #[test]
    fn workloads_do_real_work() {
        let mut scan = std::vec![Vec3::zeros(); SCAN_SIDE * SCAN_SIDE];
        let n = synthetic_scan(&mut scan);
        let mut p: Box<DefaultLocalPlanner> = Box::default();
        let plan = local_plan_workload(&mut p, &scan[..n]).unwrap();
        assert!(matches!(plan.status, Status::Exact(()) | Status::Approximate(Ended::SearchComplete)), "{:?}", plan.status);
        // 40 m with 9.5 m hops needs at least 5 anchors (start included); the end is near the goal
        assert!(plan.hops.len() >= 5, "{} anchors", plan.hops.len());
        let end = plan.hops.last().unwrap();
        assert!(firmware::geom::norm3(end) < 6.0, "ends {} m from the goal", firmware::geom::norm3(end));
        let mut a: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let out = dstar_workload(&mut a).unwrap();
        std::eprintln!("dstar workload: {out:?}");
        // the crevasse forces a detour: the replan expands vertices and the cost exceeds the octile distance
        // from the cell reached after three moves, (5, 5), to (60, 60) (55 diagonal moves)
        match out {
            Status::Exact(Found { cost, expansions }) => {
                assert!(expansions > 0);
                assert!(cost > 55.0 * core::f64::consts::SQRT_2 + 1.0, "{cost}");
            }
            other => panic!("{other:?}"),
        }
    }
}
#[cfg(test)]
mod regression {
    use super::*;
    use firmware::plan::status::Status;
    use firmware::plan::team::dstar_lite::Found;
    use std::boxed::Box;

    /// Found by the workloads' determinism test (`workloads_do_real_work` in the crate root): a second planner on a reused arena saw the first
    /// planner's epoch stamps as its own and returned `NoPath` with zero expansions.
    #[test]
    fn reused_arena_gives_the_same_answer() {
        let mut a: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let first = dstar_workload(&mut a).unwrap();
        let second = dstar_workload(&mut a).unwrap();
        assert_eq!(first, second);
        assert!(matches!(first, Status::Exact(_)), "{first:?}");
    }

    /// Found by the on-target workload: after the robot moved and a 50-cell crevasse was walled across its path,
    /// the incremental replan returned the old cost with zero expansions (a rounding-broken tie in the first key
    /// component ended the search). The replan must equal planning from scratch.
    #[test]
    fn km_tie_rounding_hid_a_wall() {
        let mut a: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let inc = match dstar_workload(&mut a).unwrap() {
            Status::Exact(Found { cost, .. }) => cost,
            other => panic!("{other:?}"),
        };
        let mut b: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let mut d = DStarLite::new(64, 64, b.storage()).unwrap();
        for k in 8..56 {
            if k % 9 != 0 {
                d.set_blocked(k, 40, true).unwrap();
            }
        }
        for x in 0..50 {
            d.add_wall((x, 20), (x, 21)).unwrap();
        }
        // the workload's start after three moves along its first path
        let mut c: Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> = Box::default();
        let mut d0 = DStarLite::new(64, 64, c.storage()).unwrap();
        for k in 8..56 {
            if k % 9 != 0 {
                d0.set_blocked(k, 40, true).unwrap();
            }
        }
        d0.plan((2, 2), (60, 60), 1_000_000).unwrap();
        let mut cur = (2, 2);
        for _ in 0..3 {
            cur = d0.next_cell(cur).unwrap();
        }
        let scratch = match d.plan(cur, (60, 60), 1_000_000).unwrap() {
            Status::Exact(Found { cost, .. }) => cost,
            other => panic!("{other:?}"),
        };
        assert!((inc - scratch).abs() < 1e-9, "incremental {inc} vs scratch {scratch}");
    }
}
