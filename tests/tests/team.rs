//! Integration tests of the tethered climbing team (Morad et al.): the global planner against the Moving AI
//! benchmark's published optimal lengths, incremental replanning against planning from scratch, and the team
//! simulation on real terrain.

use host_sim::movingai::{load_map, load_scen, run_astar_reference, run_scenarios};
use std::path::PathBuf;

fn data(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data").join(rel)
}

/// Run every `stride`-th scenario of the map (stride 1 = all), stratified over buckets because the file is
/// sorted by bucket (path length), and require each planned cost to equal the published optimum (within 1e-6).
fn check(map: &str, stride: usize) {
    let m = load_map(&data(&format!("movingai/{map}"))).unwrap();
    let s = load_scen(&data(&format!("movingai/{map}.scen"))).unwrap();
    let t = std::time::Instant::now();
    let r = run_scenarios(&m, &s, |i, _| i % stride == 0).unwrap();
    eprintln!("{map}: {} scenarios, {} mismatches, max err {:.3e}, {} expansions, {:?}", r.run, r.mismatches.len(), r.max_abs_error, r.expansions, t.elapsed());
    assert_eq!(r.run, s.len().div_ceil(stride));
    if stride > 1 {
        let buckets: std::collections::BTreeSet<u32> = s.iter().map(|x| x.bucket).collect();
        let run_buckets: std::collections::BTreeSet<u32> = s.iter().step_by(stride).map(|x| x.bucket).collect();
        assert_eq!(buckets, run_buckets, "the subset must cover every bucket");
    }
    assert!(r.mismatches.is_empty(), "{:#?}", &r.mismatches[..r.mismatches.len().min(5)]);
}

/// The reference `tetherbot movingai` times D* Lite against (the `pathfinding` crate's A*, with Moving AI's
/// no-corner-cutting moves written again in the host crate) finds the published optimum of every arena2 scenario
/// too, so the two are timed on the same problems and the same answers.
#[test]
fn the_astar_reference_matches_movingai_arena2_all_scenarios() {
    let m = load_map(&data("movingai/arena2.map")).unwrap();
    let s = load_scen(&data("movingai/arena2.map.scen")).unwrap();
    let r = run_astar_reference(&m, &s, |_, _| true);
    assert_eq!(r.run, s.len());
    assert!(r.mismatches.is_empty(), "{:#?}", &r.mismatches[..r.mismatches.len().min(5)]);
    assert!(r.expansions >= r.run as u64, "every scenario expands at least its start");
}

#[test]
fn dstar_lite_matches_movingai_arena2_all_scenarios() {
    check("arena2.map", 1);
}

/// Every 8th scenario of 8room_000 (268 of 2140, all buckets); the full set runs in
/// `dstar_lite_matches_movingai_8room_all_scenarios` (ignored: ~40 s in the test profile) and from the CLI
/// (`tetherbot movingai ../shared/data/movingai/8room_000.map ../shared/data/movingai/8room_000.map.scen`).
#[test]
fn dstar_lite_matches_movingai_8room_stratified_subset() {
    check("8room_000.map", 8);
}

#[test]
#[ignore = "~40 s in the test profile; run with --ignored, or use the CLI in release"]
fn dstar_lite_matches_movingai_8room_all_scenarios() {
    check("8room_000.map", 1);
}

use firmware::geom::p3::dist;
use host_sim::team::worlds::{team_rng, team_scenario};
use host_sim::team::grip::GripModel;
use host_sim::team::{simulate, SimReport};
use firmware::plan::team::mission::{Blocked, MissionOutcome};

/// The referee's checks again, from the report alone (independent of both the planner and the simulator's own
/// checks): every hop <= h_max, every landing within r_max of the hub held during the hop.
fn check_hops(r: &SimReport, h_max: f64, r_max: f64) {
    assert!(r.violations.is_empty(), "{:?}", r.violations);
    for h in &r.hops {
        assert!(dist(h.from, h.to) <= h_max + 1e-4, "hop {:.3} > {h_max}", dist(h.from, h.to));
        assert!(dist(h.to, h.hub) <= r_max + 1e-4, "leg {:.3} > {r_max}", dist(h.to, h.hub));
    }
}

/// One closed-loop mission on a named world; `grip_slips = false` replaces the grip model by one that never
/// slips (for a test about the route, not about losses).
fn mission(world: &str, fail: Option<(usize, usize)>, seed: u64, grip_slips: bool) -> (SimReport, [f64; 3], f64, f64, f64) {
    let (surf, start, mut cfg, _, _) = team_scenario(world, &data(""), fail, seed).unwrap();
    if !grip_slips {
        cfg.grip = GripModel::never_slips(cfg.params.h_max as f64);
    }
    let r = simulate(surf.as_ref(), &start, &cfg, &mut team_rng(seed)).unwrap();
    (r, cfg.goal, cfg.params.h_max as f64, cfg.params.r_max as f64, cfg.goal_tol)
}

/// The closed loop climbs the HiRISE cliff to the top: the flight code says GoalReached and the referee's own
/// distance check of the true hub agrees; every hop within h_max and r_max; all four robots climbed.
#[test]
fn hirise_cliff_closed_loop_reaches_the_goal() {
    let (r, goal, h, rm, tol) = mission("cliff", None, 3, false);
    check_hops(&r, h, rm);
    assert_eq!(r.outcome, Some(MissionOutcome::GoalReached), "{:?}", r.stats);
    assert!(dist(*r.hub_path.last().unwrap(), goal) <= tol);
    assert!(r.reached && r.success());
    for k in 0..4 {
        assert!(r.hops.iter().any(|x| x.robot == k && dist(x.from, x.to) > 0.5), "robot {k} never hopped");
    }
}

/// Itokawa with 30 m hops and a node loss: robot 1's tether is cut at its third turn; the others carry on and
/// the hub still reaches the goal.
#[test]
fn itokawa_closed_loop_with_node_loss_reaches_the_goal() {
    let (r, goal, h, rm, tol) = mission("itokawa", Some((1, 2)), 3, false);
    check_hops(&r, h, rm);
    assert_eq!(r.lost.first().map(|l| l.0), Some(1));
    assert!(r.hops.iter().filter(|x| x.robot == 1).count() <= 2, "robot 1 hopped after its tether was cut");
    assert_eq!(r.outcome, Some(MissionOutcome::GoalReached), "{:?}", r.stats);
    assert!(dist(*r.hub_path.last().unwrap(), goal) <= tol && r.reached);
    // the 30 m hop limit is used: some hop is longer than the 10 m cliff limit
    assert!(r.hops.iter().any(|x| dist(x.from, x.to) > 10.0));
}

/// Crevasse seeds 1001 and 1003 (report seeds of 2026-12-05), grips that never slip: the referee found hops of
/// 10.667 m and 10.174 m here (h_max 10). Robots at the crevasse's end aimed at anchors the map had filled in over
/// the crevasse, and the simulator's landing ray (along the scene normal, then the true normal: both nearly
/// horizontal there) skimmed the ground and put them 2.5-2.7 m from their anchors. A robot now grips the ground
/// nearest to its aim (or none: the hop fails): every hop within h_max and r_max, every landing within the
/// landing reach of its anchor.
#[test]
fn hops_over_the_crevasse_end_break_no_hop_limit() {
    for seed in [1001, 1003] {
        let (r, _, h, rm, _) = mission("crevasse", None, seed, false);
        check_hops(&r, h, rm);
        // the case is still there: some hop commanded over the crevasse (x < 68, 82 < y < 98; `team::worlds`)
        assert!(r.hops.iter().any(|x| x.commanded[0] < 68.0 && (82.0..98.0).contains(&x.commanded[1])), "seed {seed}");
        for x in r.hops.iter().filter(|x| x.to != x.from) {
            // the aim is within the landing error (0.3 m) of the anchor, the grip within the reach of the aim
            assert!(dist(x.to, x.commanded) <= 0.3 + host_sim::team::LANDING_REACH_M + 1e-6, "{x:?}");
        }
    }
}

/// Fig. 12 by the closed loop: the true world has a 16 m crevasse between scenes (1,2) and (1,3) (nothing is
/// scripted: the team finds it by failing to get across); the flight code walls that crossing and D* Lite
/// reroutes, and the team's scene goes (1,1), (1,2), (2,2), (2,3), (1,3). Seeds 1 and 2 of the development seeds
/// (the reroute came out on 8 of seeds 1-10; the goal itself, 7 m past the crevasse's lip, was reached on 3 of
/// them: see `host-sim/doc/team.md`), so this asserts the reroute, not the arrival.
#[test]
fn crevasse_reroute_of_fig_12_in_closed_loop() {
    for seed in [1, 2] {
        let (r, _, h, rm, _) = mission("crevasse", None, seed, false);
        check_hops(&r, h, rm);
        assert_eq!(r.routes.0, vec![(1, 1), (1, 2), (1, 3)], "the first route goes straight south");
        assert_eq!(r.walls, vec![((1, 2), (1, 3))], "seed {seed}: {:?}", r.stats);
        assert_eq!(r.visited, vec![(1, 1), (1, 2), (2, 2), (2, 3), (1, 3)], "seed {seed}");
        // nobody landed in the crevasse (beyond the 1 m band of its lips where the posts' bilinear surface slopes)
        assert!(r.hops.iter().all(|x| !(x.to[0] < 67.0 && x.to[1] > 83.0 && x.to[1] < 97.0)), "seed {seed}: landed in the crevasse");
    }
}

/// A goal beyond a crevasse that cuts the whole grid: the flight code walls crossings until D* Lite has no route
/// left and reports Blocked; the CLI's success (and exit status) is false.
#[test]
fn blocked_goal_is_reported_as_not_reached() {
    let (surf, start, mut cfg, _, _) = team_scenario("crevasse", &data(""), None, 1).unwrap();
    cfg.grip = GripModel::never_slips(cfg.params.h_max as f64);
    // the same crevasse world, but the team may not go round (columns 2.. are off the map too)
    cfg.blocked.extend((0..5).flat_map(|y| (2..5).map(move |x| (x, y))));
    let r = simulate(surf.as_ref(), &start, &cfg, &mut team_rng(1)).unwrap();
    assert_eq!(r.outcome, Some(MissionOutcome::Blocked(Blocked::NoRoute)), "{:?}", r.stats);
    assert_eq!(r.walls, vec![((1, 2), (1, 3))]);
    assert!(!r.reached && !r.success());
    assert!(r.violations.is_empty(), "{:?}", r.violations);
}

use firmware::plan::status::{Ended, Status};
use firmware::plan::team::dstar_lite::{DStarLite, DStarOutcome, Found, NoPath, DIRS};
use host_sim::movingai::OwnedDStarStorage;
use proptest::prelude::*;

/// Independent oracle: Dijkstra on the same octile rules (no corner cutting, walls close an edge and any diagonal
/// whose detours use it), written from the rules, not from the planner.
type Cell = (i64, i64);

fn dijkstra(w: i64, h: i64, blocked: &[bool], walls: &[(Cell, Cell)], s: Cell, g: Cell) -> f64 {
    let free = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && !blocked[(y * w + x) as usize];
    let walled = |a: (i64, i64), b: (i64, i64)| walls.iter().any(|&(p, q)| (p == a && q == b) || (p == b && q == a));
    let step = |a: (i64, i64), b: (i64, i64)| -> Option<f64> {
        if !free(a.0, a.1) || !free(b.0, b.1) || walled(a, b) {
            return None;
        }
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        if dx == 0 || dy == 0 {
            return Some(1.0);
        }
        let (c1, c2) = ((a.0 + dx, a.1), (a.0, a.1 + dy));
        if !free(c1.0, c1.1) || !free(c2.0, c2.1) || walled(a, c1) || walled(c1, b) || walled(a, c2) || walled(c2, b) {
            return None;
        }
        Some(core::f64::consts::SQRT_2)
    };
    let n = (w * h) as usize;
    let mut dist = vec![f64::INFINITY; n];
    let mut done = vec![false; n];
    if !free(s.0, s.1) || !free(g.0, g.1) {
        return f64::INFINITY;
    }
    dist[(s.1 * w + s.0) as usize] = 0.0;
    while let Some(u) = (0..n).filter(|&i| !done[i] && dist[i].is_finite()).min_by(|&a, &b| dist[a].total_cmp(&dist[b])) {
        done[u] = true;
        let a = (u as i64 % w, u as i64 / w);
        for &(dx, dy) in &DIRS {
            let b = (a.0 + dx as i64, a.1 + dy as i64);
            if let Some(c) = step(a, b) {
                let v = (b.1 * w + b.0) as usize;
                if dist[u] + c < dist[v] {
                    dist[v] = dist[u] + c;
                }
            }
        }
    }
    dist[(g.1 * w + g.0) as usize]
}

fn cost(o: DStarOutcome) -> f64 {
    match o {
        Status::Exact(Found { cost, .. }) => cost,
        Status::NoSolution(NoPath { ended: Ended::SearchComplete, .. }) => f64::INFINITY,
        Status::NoSolution(NoPath { .. }) => panic!("budget"),
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 256, ..ProptestConfig::default() })]
    /// Incremental replanning (move along the path, then add walls and blocked cells) gives the same cost as a
    /// fresh D* Lite search on the changed map, and both equal the Dijkstra oracle.
    #[test]
    fn incremental_replanning_equals_planning_from_scratch(
        seed_blocks in proptest::collection::vec((0i64..12, 0i64..10), 0..25),
        new_walls in proptest::collection::vec((0i64..12, 0i64..10, 0usize..8), 1..12),
        new_blocks in proptest::collection::vec((0i64..12, 0i64..10), 0..6),
        moves in 0usize..4,
    ) {
        let (w, h) = (12i64, 10i64);
        let (s, g) = ((0i64, 0i64), (11i64, 9i64));
        let mut blocked = vec![false; (w * h) as usize];
        for &(x, y) in &seed_blocks { if (x, y) != s && (x, y) != g { blocked[(y * w + x) as usize] = true; } }
        let mut st = OwnedDStarStorage::new((w * h) as usize);
        let mut d = DStarLite::new(w as u32, h as u32, st.storage()).unwrap();
        for y in 0..h { for x in 0..w { if blocked[(y * w + x) as usize] { d.set_blocked(x, y, true).unwrap(); } } }
        let c0 = cost(d.plan(s, g, 1_000_000).unwrap());
        prop_assert!((c0 - dijkstra(w, h, &blocked, &[], s, g)).abs() < 1e-9 || (c0.is_infinite() && dijkstra(w, h, &blocked, &[], s, g).is_infinite()));
        // the robot moves a few cells along its path
        let mut cur = s;
        for _ in 0..moves { if let Some(n) = d.next_cell(cur) { cur = n; d.move_start(cur).unwrap(); } }
        // the world changes: crevasses (walls) and newly seen obstacles
        let mut walls = Vec::new();
        for &(x, y, k) in &new_walls {
            let (dx, dy) = DIRS[k];
            let b = (x + dx as i64, y + dy as i64);
            if b.0 >= 0 && b.1 >= 0 && b.0 < w && b.1 < h { d.add_wall((x, y), b).unwrap(); walls.push(((x, y), b)); }
        }
        for &(x, y) in &new_blocks { if (x, y) != cur && (x, y) != g { d.set_blocked(x, y, true).unwrap(); blocked[(y * w + x) as usize] = true; } }
        let inc = cost(d.replan(1_000_000).unwrap());
        let oracle = dijkstra(w, h, &blocked, &walls, cur, g);
        // from scratch on a fresh planner with the same map
        let mut st2 = OwnedDStarStorage::new((w * h) as usize);
        let mut d2 = DStarLite::new(w as u32, h as u32, st2.storage()).unwrap();
        for y in 0..h { for x in 0..w { if blocked[(y * w + x) as usize] { d2.set_blocked(x, y, true).unwrap(); } } }
        for &(a, b) in &walls { d2.add_wall(a, b).unwrap(); }
        let scratch = cost(d2.plan(cur, g, 1_000_000).unwrap());
        if oracle.is_infinite() {
            prop_assert!(inc.is_infinite() && scratch.is_infinite(), "inc {inc} scratch {scratch}");
        } else {
            prop_assert!((inc - scratch).abs() < 1e-9, "inc {inc} scratch {scratch}");
            prop_assert!((inc - oracle).abs() < 1e-9, "inc {inc} oracle {oracle}");
        }
    }
}

use firmware::config::team::TeamParams;
use firmware::geom::{Real, Vec3};
use firmware::plan::team::DefaultLocalPlanner;

/// Section V, Fig. 12, end to end: a grid of 30 m scenes; D* Lite routes (1,1) -> (1,2) -> (1,3) ("south" =
/// +y); the local planner (the real scene pipeline and bounded-leg A* on range points) hops through the scenes;
/// between (1,2) and (1,3) a 16 m crevasse (h_max = 10 m) stops it; the failure becomes a wall and D* Lite
/// replans incrementally to (1,2), (2,2), (2,3), (1,3), which the robot then climbs.
#[test]
fn crevasse_reroute_with_the_local_planner_in_the_loop() {
    const CELL: f64 = 30.0;
    // gently undulating ground; the crevasse spans y in (82, 98) for x < 68 (beyond what the robot sees from (1,2))
    let ground = |x: f64, y: f64| -> f64 {
        if y > 82.0 && y < 98.0 && x < 68.0 {
            -40.0
        } else {
            0.4 * (x / 3.0).sin() * (y / 4.0).cos()
        }
    };
    let range = 22.0;
    let scan = |at: [f64; 2]| -> Vec<Vec3> {
        let mut pts = Vec::new();
        let n = (range as i64) + 1;
        for j in -n..=n {
            for i in -n..=n {
                let (x, y) = (at[0] + i as f64, at[1] + j as f64);
                if (x - at[0]).hypot(y - at[1]) <= range && x >= 0.0 && y >= 0.0 {
                    pts.push(Vec3::new(x as Real, y as Real, ground(x, y) as Real));
                }
            }
        }
        pts
    };
    let centre = |c: (i64, i64)| [(c.0 as f64 + 0.5) * CELL, (c.1 as f64 + 0.5) * CELL];
    let cell_of = |p: [f64; 2]| ((p[0] / CELL).floor() as i64, (p[1] / CELL).floor() as i64);

    let mut st = OwnedDStarStorage::new(5 * 5);
    let mut d = DStarLite::new(5, 5, st.storage()).unwrap();
    for y in 0..5 {
        d.set_blocked(0, y, true).unwrap(); // the map edge, as in the figure
    }
    let goal = (1, 3);
    assert!(matches!(d.plan((1, 1), goal, 10_000).unwrap(), Status::Exact(Found { cost, .. }) if cost == 2.0));
    let params = TeamParams::DEFAULT;
    let mut planner: Box<DefaultLocalPlanner> = Box::default();
    let mut pos = centre((1, 1));
    let mut visited = vec![(1i64, 1i64)];
    let mut walls = Vec::new();
    let mut stuck = 0;
    for _ in 0..200 {
        let here = *visited.last().unwrap();
        if here == goal {
            break;
        }
        let next = d.next_cell(here).expect("D* Lite has a path");
        let target = centre(next);
        let pts = scan(pos);
        let z = ground(pos[0], pos[1]);
        let robot = Vec3::new(pos[0] as Real, pos[1] as Real, z as Real);
        let tgt = Vec3::new(target[0] as Real, target[1] as Real, ground(target[0], target[1]) as Real);
        // a single robot: the leg c_m = 0 (the hub is on it), so only h_max binds
        let plan = planner.plan(&pts, &Vec3::z(), &robot, &Vec3::zeros(), &tgt, 3.0, &params).unwrap();
        let before = (pos[0] - target[0]).hypot(pos[1] - target[1]);
        let hop = plan.hops.get(1).map(|h| [h.x as f64, h.y as f64]);
        let progress = hop.map(|h| before - (h[0] - target[0]).hypot(h[1] - target[1])).unwrap_or(0.0);
        if matches!(plan.status, Status::NoSolution(_)) || progress < 0.5 {
            stuck += 1;
            if stuck >= 2 {
                // bounded-leg A* cannot cross: the edge between the two scenes becomes a wall
                d.add_wall(here, next).unwrap();
                walls.push((here, next));
                assert!(matches!(d.replan(10_000).unwrap(), Status::Exact(_)));
                stuck = 0;
            }
            continue;
        }
        stuck = 0;
        let h = hop.unwrap();
        let len = ((h[0] - pos[0]).powi(2) + (h[1] - pos[1]).powi(2) + (ground(h[0], h[1]) - z).powi(2)).sqrt();
        assert!(len <= params.h_max as f64 + 1e-3, "hop {len:.2} m");
        assert!(ground(h[0], h[1]) > -1.0, "landed in the crevasse at {h:?}");
        pos = h;
        let c = cell_of(pos);
        if c != here && (pos[0] - target[0]).hypot(pos[1] - target[1]) < 8.0 && c == next {
            visited.push(c);
            d.move_start(c).unwrap();
            assert!(matches!(d.replan(10_000).unwrap(), Status::Exact(_)));
        }
    }
    assert_eq!(walls, vec![((1, 2), (1, 3))]);
    assert_eq!(visited, vec![(1, 1), (1, 2), (2, 2), (2, 3), (1, 3)]);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, ..ProptestConfig::default() })]
    /// As above on a 40 x 40 grid with long crevasses (runs of walls) crossing the path after the robot has
    /// moved up to 12 cells: the case where rounding-broken f64 key ties once hid a wall (now exact: `dstar_lite::Cost`).
    #[test]
    fn incremental_replanning_with_long_crevasses(
        runs in proptest::collection::vec((0i64..40, 1i64..39, 5i64..30, proptest::bool::ANY), 1..5),
        moves in 0usize..12,
    ) {
        let (w, h) = (40i64, 40i64);
        let (s, g) = ((1i64, 1i64), (38i64, 38i64));
        let blocked = vec![false; (w * h) as usize];
        let mut st = OwnedDStarStorage::new((w * h) as usize);
        let mut d = DStarLite::new(w as u32, h as u32, st.storage()).unwrap();
        cost(d.plan(s, g, 1_000_000).unwrap());
        let mut cur = s;
        for _ in 0..moves { if let Some(n) = d.next_cell(cur) { cur = n; d.move_start(cur).unwrap(); } }
        let mut walls = Vec::new();
        for &(x0, y, len, horizontal) in &runs {
            for k in 0..len {
                let (a, b) = if horizontal { ((x0 + k, y), (x0 + k, y + 1)) } else { ((y, x0 + k), (y + 1, x0 + k)) };
                if a.0 < w && a.1 < h && b.0 < w && b.1 < h { d.add_wall(a, b).unwrap(); walls.push((a, b)); }
            }
        }
        let inc = cost(d.replan(1_000_000).unwrap());
        let oracle = dijkstra(w, h, &blocked, &walls, cur, g);
        prop_assert!((inc - oracle).abs() < 1e-9 || (inc.is_infinite() && oracle.is_infinite()), "inc {inc} oracle {oracle}");
    }
}

/// The crevasse of Fig. 12 crossed by the closed loop to the goal itself (7 m past the far lip), nothing scripted:
/// the team fails to cross (1,2)-(1,3), walls it, goes round by (2,2), (2,3) and arrives; the flight code says
/// GoalReached and the referee's distance check agrees. Development seed 1 (grips never slip): the arrival comes
/// out on 3 of development seeds 1-20 only (1, 10 and 20; `host-sim/doc/team.md`, "Landing on the nearest
/// ground"), so this pins one seed where it does, to catch a regression of the whole chain (scan, wall, reroute,
/// arrival). It pinned seed 7 until the simulator's landing changed on 2026-12-06 (a landing ray could put a robot
/// 2.7 m from its anchor); with the nearest-ground landing seed 7 ends `Blocked(GoalUnreachable)`.
#[test]
fn crevasse_closed_loop_reaches_the_goal_past_the_far_lip() {
    let (r, goal, h, rm, tol) = mission("crevasse", None, 1, false);
    check_hops(&r, h, rm);
    assert_eq!(r.outcome, Some(MissionOutcome::GoalReached), "{:?}", r.stats);
    assert!(r.reached && r.success());
    assert!(dist(*r.hub_path.last().unwrap(), goal) <= tol);
    assert!(r.walls.contains(&((1, 2), (1, 3))), "the crevasse crossing was walled: {:?}", r.walls);
    assert!(r.visited.contains(&(2, 2)) && r.visited.contains(&(2, 3)), "went round: {:?}", r.visited);
    assert_eq!(r.visited.last(), Some(&(1, 3)));
}

fn scenario_file(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/team").join(name)
}

/// `tetherbot team SCENARIO.toml` on a real scanned point cloud (laspy's simple.las, read by the LAS reader,
/// resampled to a height grid): the mission reaches the goal with grips that slip, and every hop is within
/// h_max and r_max.
#[test]
fn scenario_file_point_cloud_mission_reaches_the_goal() {
    use host_sim::team::scenario::load;
    let s = load(&scenario_file("team_pointcloud_las.toml")).unwrap();
    assert_eq!(s.file.world.source, "pointcloud");
    let (first, count) = s.seeds();
    assert_eq!((first, count), (1, 1));
    let (surf, start, cfg, _, bg) = s.build(&data(""), first).unwrap();
    assert!(bg.len() > 1000, "the cloud became a height grid");
    assert_eq!((cfg.params.h_max, cfg.params.r_max), (10.0, 15.0));
    let r = simulate(surf.as_ref(), &start, &cfg, &mut team_rng(first)).unwrap();
    check_hops(&r, cfg.params.h_max as f64, cfg.params.r_max as f64);
    assert_eq!(r.outcome, Some(MissionOutcome::GoalReached), "{:?}", r.stats);
    assert!(r.reached && r.success());
    assert!(dist(*r.hub_path.last().unwrap(), cfg.goal) <= cfg.goal_tol);
}

/// Every shipped team scenario file parses and its world builds (the built-in ones, the OBJ and the point cloud).
#[test]
fn shipped_team_scenario_files_build() {
    use host_sim::team::scenario::load;
    for f in ["team_cliff.toml", "team_itokawa.toml", "team_bennu.toml", "team_crevasse.toml", "team_itokawa_obj.toml", "team_pointcloud_las.toml"] {
        let s = load(&scenario_file(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
        let (_, start, cfg, _, _) = s.build(&data(""), 1).unwrap_or_else(|e| panic!("{f}: {e}"));
        assert!(start.iter().flatten().all(|c| c.is_finite()), "{f}");
        assert!(cfg.grid.cell_of(&firmware::geom::p3::to_vec3(cfg.goal)).is_some(), "{f}: goal outside the grid");
    }
    // the file's slip switch reaches the grip model
    let s = load(&scenario_file("team_crevasse.toml")).unwrap();
    let (_, _, cfg, _, _) = s.build(&data(""), 1).unwrap();
    assert_eq!(cfg.grip.p_slip(10.0), 0.0);
}

/// Impossible scenario files are refused before any world is built, with a message that names the field.
#[test]
fn malformed_team_scenario_files_are_rejected_naming_the_field() {
    use host_sim::team::scenario::parse;
    let p = std::path::Path::new("bad.toml");
    let dem = |team: &str| format!("name = \"x\"\n[world]\nsource = \"dem\"\nfile = \"a.npy\"\n[team]\n{team}\n");
    let cases: Vec<(String, &str)> = vec![
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nh_max = -3.0"), "team.h_max"),
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nr_max = 0.0"), "team.r_max"),
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nh_max = 10.0\nr_max = 4.0"), "team.r_max"),
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nlanding_error_m = -0.1"), "team.landing_error_m"),
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nscene_m = nan"), "team.scene_m"),
        (dem("goal = [1.0, 0.0, 0.0]"), "team.start"),
        (dem("start = [0.0, 0.0, 0.0]"), "team.goal"),
        (dem("start = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\nhmax = 10.0"), "hmax"),
        ("name = \"x\"\n[world]\nsource = \"lidar\"\n".into(), "world.source"),
        ("name = \"x\"\n[world]\nsource = \"builtin\"\nbuiltin = \"mars\"\n".into(), "world.builtin"),
        ("name = \"x\"\n[world]\nsource = \"builtin\"\nbuiltin = \"cliff\"\n[team]\nstart = [0.0, 0.0, 0.0]\n".into(), "team.start"),
        ("name = \"x\"\n[world]\nsource = \"pointcloud\"\n[team]\nstart = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\n".into(), "world.file"),
        ("name = \"x\"\n[world]\nsource = \"pointcloud\"\nfile = \"a.las\"\nscale = -1.0\n[team]\nstart = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\n".into(), "world.scale"),
        ("name = \"x\"\n[world]\nsource = \"builtin\"\nbuiltin = \"cliff\"\n[seeds]\ncount = 0\n".into(), "seeds.count"),
    ];
    for (text, field) in cases {
        let e = parse(&text, p).expect_err(&text);
        assert!(e.contains(field) && e.contains("bad.toml"), "expected an error naming {field}, got: {e}\n--- file:\n{text}");
    }
    // a file that names a point cloud that does not exist: the field and the path
    let text = "name = \"x\"\n[world]\nsource = \"pointcloud\"\nfile = \"no_such.las\"\n[team]\nstart = [0.0, 0.0, 0.0]\ngoal = [1.0, 0.0, 0.0]\n";
    let s = parse(text, p).unwrap();
    let e = s.build(&data(""), 1).err().expect("missing file");
    assert!(e.contains("world.file") && e.contains("no_such.las"), "{e}");
    // a good file parses
    assert!(parse("name = \"x\"\n[world]\nsource = \"builtin\"\nbuiltin = \"crevasse\"\n[team]\nslip = false\n", p).is_ok());
}

// ---- issue 21 item 1: the team mission in the flight executive, over protocol v8 ----

use host_sim::team::{simulate_over, TeamLink};

/// One mission run twice with the same seed: the flight crate's mission called directly, and the flight executive
/// in-process over protocol v8. Returns both reports.
fn direct_and_link(world: &str, fail: Option<(usize, usize)>, seed: u64, grip_slips: bool) -> (SimReport, SimReport) {
    let (surf, start, mut cfg, _, _) = team_scenario(world, &data(""), fail, seed).unwrap();
    if !grip_slips {
        cfg.grip = GripModel::never_slips(cfg.params.h_max as f64);
    }
    let direct = simulate_over(surf.as_ref(), &start, &cfg, &mut team_rng(seed), TeamLink::Direct).unwrap();
    // The in-process executive steps the mission inside its frame dispatch; unoptimised (the test profile) its
    // frames overflowed the 2 MiB of a test thread (found 2026-12-05), so the link run gets the 8 MiB a main
    // thread has. The release build and the board's flight build are measured by `tools/max-frame.sh`.
    let link = std::thread::scope(|sc| {
        std::thread::Builder::new()
            .stack_size(8 << 20)
            .spawn_scoped(sc, || simulate_over(surf.as_ref(), &start, &cfg, &mut team_rng(seed), TeamLink::Inproc))
            .unwrap()
            .join()
            .unwrap()
    })
    .unwrap();
    (direct, link)
}

fn assert_same_run(world: &str, seed: u64, d: &SimReport, l: &SimReport) {
    assert_eq!(d.outcome, l.outcome, "{world} seed {seed}: outcome");
    assert_eq!(d.hops, l.hops, "{world} seed {seed}: hops");
    assert_eq!(d.rounds, l.rounds, "{world} seed {seed}: rounds");
    assert_eq!(d.hub_path, l.hub_path, "{world} seed {seed}: hub path");
    assert_eq!(d.lost, l.lost, "{world} seed {seed}: robots lost");
    assert_eq!(d.walls, l.walls, "{world} seed {seed}: walls");
    assert_eq!(d.stats, l.stats, "{world} seed {seed}: mission counters");
}

/// The same seed gives the identical run through the link as direct on the HiRISE cliff (the outcome, every hop,
/// the rounds, the hub path), and the link run reaches the goal (flight code and referee agree).
#[test]
fn team_over_the_link_equals_direct_on_the_cliff_and_reaches_the_goal() {
    let (d, l) = direct_and_link("cliff", None, 3, true);
    assert_same_run("cliff", 3, &d, &l);
    assert_eq!(l.outcome, Some(MissionOutcome::GoalReached), "{:?}", l.stats);
    assert!(l.success(), "{:?}", l.violations);
    assert!(!l.hops.is_empty());
}

/// The same on Itokawa (30 m hops) with a node loss: robot 1's tether cut at its third turn goes up as a
/// `TeamReport{Lost}`; the run is identical to direct and still reaches the goal.
#[test]
fn team_over_the_link_equals_direct_on_itokawa_with_node_loss() {
    let (d, l) = direct_and_link("itokawa", Some((1, 2)), 3, true);
    assert_same_run("itokawa", 3, &d, &l);
    assert_eq!(l.lost.first().map(|x| x.0), Some(1));
    assert_eq!(l.outcome, Some(MissionOutcome::GoalReached), "{:?}", l.stats);
}

/// Fig. 12's crevasse through the link (grips never slip, as in `crevasse_reroute_of_fig_12_in_closed_loop`): the wall the flight executive adds and D* Lite's reroute are the same as
/// direct (the scenes blocked beforehand go up in the `TeamConfigure`).
#[test]
fn team_over_the_link_equals_direct_on_the_crevasse_reroute() {
    let (d, l) = direct_and_link("crevasse", None, 1, false);
    assert_same_run("crevasse", 1, &d, &l);
    assert_eq!(l.walls, vec![((1, 2), (1, 3))]);
    assert_eq!(l.visited, vec![(1, 1), (1, 2), (2, 2), (2, 3), (1, 3)]);
}

/// The in-process executive hands its team storage back when its run ends, and the next run on the thread gets it
/// (a board lends its statics once, so one lending must serve mission after mission): three runs on one thread
/// make one storage, not three, and a run on storage that served another world first (the crevasse, another grid)
/// is identical to the run on fresh storage.
#[test]
fn in_process_team_runs_reuse_one_team_storage_and_the_reuse_changes_nothing() {
    let run = |world: &str, fail: Option<(usize, usize)>, seed: u64| {
        let (surf, start, mut cfg, _, _) = team_scenario(world, &data(""), fail, seed).unwrap();
        cfg.grip = GripModel::never_slips(cfg.params.h_max as f64);
        simulate_over(surf.as_ref(), &start, &cfg, &mut team_rng(seed), TeamLink::Inproc).unwrap()
    };
    // the 8 MiB stack of `direct_and_link`, for the unoptimised test profile
    let (first, second, third, made) = std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || {
            let made_before = host_sim::team::flight::team_lends_made();
            let first = run("itokawa", Some((1, 2)), 3);
            let second = run("crevasse", None, 1);
            let third = run("itokawa", Some((1, 2)), 3);
            (first, second, third, host_sim::team::flight::team_lends_made() - made_before)
        })
        .unwrap()
        .join()
        .unwrap();
    assert_eq!(made, 1, "each in-process run made its own team storage");
    assert_same_run("itokawa", 3, &first, &third);
    assert_eq!(first.outcome, Some(MissionOutcome::GoalReached), "{:?}", first.stats);
    assert_eq!(second.visited, vec![(1, 1), (1, 2), (2, 2), (2, 3), (1, 3)]);
}
