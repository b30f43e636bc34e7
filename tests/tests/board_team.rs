//! The climbing team's mission on the emulated board (issue 21): the hub's flight executive runs on the board in
//! QEMU, lockstep, over protocol v8, on the team storage the board lends at boot (`storage::TEAM_PLANNER`,
//! `TEAM_DSTAR`), and the run is the in-process run, hop for hop.

use firmware::geom::p3::dist;
use firmware::plan::team::mission::MissionOutcome;
use host_sim::qemu;
use host_sim::team::grip::GripModel;
use host_sim::team::worlds::{team_rng, team_scenario};
use host_sim::team::{simulate_on_board, simulate_over, TeamLink};
use std::path::PathBuf;

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data")
}

/// Itokawa, 30 m hops, robot 1's tether cut at its third turn (development seed 3): on the board the mission
/// gives the in-process run exactly (outcome, every hop, the hub path, the losses, the scenes, the rounds, hops
/// and walls the `Done` order reports) and reaches the goal with no violation; the board reports what its
/// executive steps cost and a stack high-water mark within its region.
#[test]
fn the_team_mission_on_the_board_is_the_in_process_mission() {
    let Some(elf) = qemu::board_for_tests("board team").unwrap_or_else(|e| panic!("{e}")) else {
        return;
    };
    let seed = 3;
    let (surf, start, mut cfg, _, _) = team_scenario("itokawa", &data(), Some((1, 2)), seed).unwrap();
    cfg.grip = GripModel::never_slips(cfg.params.h_max as f64);
    // the unoptimised test profile's frames need more than a test thread's 2 MiB (`tests/tests/team.rs`)
    let (inproc, (board, report)) = std::thread::scope(|sc| {
        let inproc = std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn_scoped(sc, || simulate_over(surf.as_ref(), &start, &cfg, &mut team_rng(seed), TeamLink::Inproc))
            .unwrap();
        let board = simulate_on_board(surf.as_ref(), &start, &cfg, &mut team_rng(seed), &elf, true);
        (inproc.join().unwrap().unwrap(), board.unwrap_or_else(|e| panic!("{e}")))
    });
    assert_eq!(board.outcome, Some(MissionOutcome::GoalReached), "{:?}", board.stats);
    assert!(board.success(), "{:?}", board.violations);
    assert_eq!(board.outcome, inproc.outcome);
    assert_eq!(board.hops, inproc.hops);
    assert_eq!(board.hub_path, inproc.hub_path);
    assert_eq!(board.lost, inproc.lost);
    assert_eq!(board.rounds, inproc.rounds);
    assert_eq!(board.visited, inproc.visited, "the scenes from the hub path are the mission's own");
    assert_eq!((board.stats.rounds, board.stats.hops, board.stats.walls), (inproc.stats.rounds, inproc.stats.hops, inproc.stats.walls));
    assert!(dist(*board.hub_path.last().unwrap(), cfg.goal) <= cfg.goal_tol);
    let fig = |k: &str| report.figure(k).unwrap_or_else(|| panic!("no {k} in {:?}", report.report));
    assert!(fig("lockstep_steps") > 0 && fig("lockstep_step_ticks_max") > 0);
    assert!(fig("lockstep_step_ticks_total") >= fig("lockstep_step_ticks_max"));
    assert!(fig("stack_high_water_bytes") < fig("stack_size_bytes"));
}
