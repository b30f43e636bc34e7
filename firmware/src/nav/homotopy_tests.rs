//! Homotopy goals on board (issue 20 item 4): a synthetic crater tile (rim, 45-degree wall, floor), the global route
//! reported, the first leg set up with tethered ABIT* on the onboard map, every refusal counted, and a bad upload
//! that keeps the tile and the route.

use super::*;
use crate::config::protocol::MAX_HEIGHTS_PER_TILE_CHUNK;
use crate::protocol::{
    LogLevel, MissionConfig, PlannerConfig, Point3, Quat, TelemetryConfig, TetherConfig,
};
use std::boxed::Box;
use std::vec;
use std::vec::Vec;

type TestNav = Navigator<Vec<Block>, Vec<u32>, Box<NavPlanStorage>, Box<HomotopyStorage>>;

const RES: f32 = 0.2;
const ROWS: u16 = 100;
const COLS: u16 = 80;
const RIM_Y: f32 = 14.0;
const FLOOR_Y: f32 = 6.0;
const RIM_Z: f32 = 20.03;

/// Rim (flat, y > 14), a 45-degree wall rising with y, a flat floor (y < 6); 16 x 20 m.
fn crater_z(_x: f32, y: f32) -> f32 {
    RIM_Z - (RIM_Y - y.clamp(FLOOR_Y, RIM_Y))
}

fn nav() -> TestNav {
    Navigator::new(MapConfig::with_voxel_size(0.1), vec![Block::EMPTY; 4096], vec![0u32; 8192], Box::default())
        .unwrap()
        .with_homotopy(Box::new(HomotopyStorage::new()))
}

fn configure(max_payout_m: f32) -> Configure {
    Configure {
        rover: super::tests::TEST_ROVER,
        tether: TetherConfig { root_anchor: Point3::new(8.0, 18.5, RIM_Z + 0.5), max_payout_m, max_tension_n: 2000.0 },
        planner: PlannerConfig { rng_seed: 3, max_iterations: 300, batch_size: 100, goal_bias: 0.0 },
        telemetry: TelemetryConfig { period_ms: 0, forward_log_level: LogLevel::Off },
        mission: MissionConfig::DEFAULT,
        map: None,
    }
}

fn goal(x: f32, y: f32) -> GoalRequest {
    GoalRequest {
        goal_id: 4,
        position: Point3::new(x, y, crater_z(x, y)),
        tolerance_m: 0.5,
        planner: PlannerChoice::Homotopy,
        max_iterations: 300,
        time_budget_ms: 0,
        allow_approximate: true,
    }
}

/// Uploads a tile through the hooks (as the executive hands the chunks over); returns the completion's result.
fn upload(nav: &mut TestNav, tile_id: u32, h: &dyn Fn(f32, f32) -> f32) -> Result<(), Refused> {
    let cells = usize::from(ROWS) * usize::from(COLS);
    let header = TileHeader {
        tile_id,
        origin: [0.0, 0.0],
        resolution_m: RES,
        rows: ROWS,
        cols: COLS,
        chunk_count: cells.div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK) as u16,
    };
    let heights: Vec<f32> = (0..cells)
        .map(|i| h((i % usize::from(COLS)) as f32 * RES, (i / usize::from(COLS)) as f32 * RES))
        .collect();
    for (k, chunk) in heights.chunks(MAX_HEIGHTS_PER_TILE_CHUNK).enumerate() {
        nav.tile_part(&header, k * MAX_HEIGHTS_PER_TILE_CHUNK, chunk, Instant::from_micros(0));
    }
    nav.tile_complete(&header, Instant::from_micros(0))
}

/// A scan looking down at the rim round the rover at (8, 17.5).
fn scan_rim(nav: &mut TestNav) {
    let (cx, cy, top) = (8.0f32, 17.5f32, RIM_Z + 4.0);
    let mut pts = Vec::new();
    for i in -40..=40 {
        for j in -30..=30 {
            let (x, y) = (cx + 0.05 * i as f32, cy + 0.05 * j as f32);
            pts.push(Point3::new(x - cx, y - cy, crater_z(x, y) - top));
        }
    }
    let pose = Pose { position: Point3::new(cx, cy, top), orientation: Quat::IDENTITY };
    nav.integrate_scan(&Scan { scan_id: 1, sensor_pose: pose, points: &pts }, Instant::from_micros(0));
}

/// Runs `plan_step` until it finishes (at most `calls`); the final progress and the plan.
fn run(nav: &mut TestNav, calls: u32) -> (PlanProgress, PlanBuffer, u32) {
    let mut plan = PlanBuffer::new();
    for k in 0..calls {
        let p = nav.plan_step(Instant::from_micros(u64::from(k)), 50, &mut plan);
        if let PlanProgress::Finished { .. } = p {
            return (p, plan, k + 1);
        }
    }
    panic!("planning did not finish in {calls} steps");
}

fn refusals(nav: &TestNav, why: GoalRefusal) -> u32 {
    nav.plan_stats().refusals[why as usize]
}

/// With a tile, a homotopy goal is planned in three bounded steps (segment, Axel's limit, Alg. 1 and the world
/// route); the route is reported as the plan (leg goals on the DEM, the last the goal), and the first drive step sets
/// up tethered ABIT* to the first leg from the tracked pose and the root anchor's history.
#[test]
fn a_homotopy_goal_reports_its_route_and_drives_the_first_leg_with_abit() {
    let mut nav = nav();
    nav.configure(&configure(50.0)).unwrap();
    upload(&mut nav, 1, &crater_z).unwrap();
    scan_rim(&mut nav);
    let g = goal(8.0, 3.0);
    assert_eq!(nav.goal(&g, Instant::from_micros(0)), PlanState::Accepted);
    assert_eq!(nav.mission().status().state, crate::protocol::MissionState::Planning);
    let (p, plan, steps) = run(&mut nav, 10);
    assert_eq!(steps, 3, "segment, hold, route: one phase per step: {p:?} {:?}", nav.plan_stats().refusals);
    let PlanProgress::Finished { state: PlanState::ExactSolution, best_cost: Some(cost), iterations } = p else {
        panic!("{p:?}")
    };
    assert!(iterations >= 1, "classes examined");
    // the taut tether from the root over the rim and down the wall: about 1 + 8 sqrt(2) + 3 m
    let closed = (18.5 - RIM_Y) + (RIM_Y - FLOOR_Y) * core::f32::consts::SQRT_2 + (FLOOR_Y - 3.0);
    assert!((cost - closed).abs() < 0.5, "{cost} vs {closed}");
    let legs = nav.homotopy_legs().to_vec();
    assert_eq!(plan.len(), legs.len());
    assert!(legs.len() >= 4, "about 17 m in legs of at most 5 m: {legs:?}");
    let last = plan.last().unwrap();
    assert_eq!((last.pose.position.x, last.pose.position.y), (8.0, 3.0));
    let mut prev = [8.0f32, 17.5];
    for w in plan.iter() {
        let p = w.pose.position;
        let d = libm::hypotf(p.x - prev[0], p.y - prev[1]);
        assert!(d <= crate::config::nav::HOMOTOPY_LEG_MAX_M + 1e-3, "leg of {d} m");
        assert!((p.z - crater_z(p.x, p.y)).abs() < 0.05, "{p:?} off the DEM");
        assert_eq!(w.anchors.first(), Some(&Point3::new(8.0, 18.5, RIM_Z + 0.5)));
        prev = [p.x, p.y];
    }
    assert_eq!(nav.homotopy_stats().routes, 1);
    // driving: the first drive step sets up leg 1 with ABIT* (the executive then plans it like a replan)
    assert_eq!(nav.drive_step(Instant::from_micros(10)), DriveStep::Replan);
    assert_eq!(nav.homotopy_leg(), Some(0));
    assert_eq!(nav.homotopy_stats().legs_started, 1);
    let start = nav.plan_start().unwrap().axle();
    assert!(libm::hypotf(start.x - 8.0, start.y - 17.5) < 0.5, "leg 1 starts at the rover: {start:?}");
    assert_eq!(nav.mission().status().replans, 0, "a leg is not a replan");
    // the leg's ABIT* runs on the onboard map (the rim patch: the leg goal beyond it is approached)
    let (p, leg_plan, _) = run(&mut nav, 2000);
    assert!(
        matches!(p, PlanProgress::Finished { state: PlanState::ExactSolution | PlanState::ApproximateSolution, .. }),
        "{p:?}"
    );
    assert!(leg_plan.len() >= 2);
}

/// Refusals are `InvalidInput` with a counted reason: no tile; a tile whose descent has no tether-demand stretch
/// (flat); a corridor outside the tile; a route longer than the spool. Another planner is still unavailable.
#[test]
fn homotopy_refusals_are_counted_with_their_reason() {
    let mut nav = nav();
    nav.configure(&configure(50.0)).unwrap();
    scan_rim(&mut nav);
    assert_eq!(nav.goal(&goal(8.0, 3.0), Instant::from_micros(0)), PlanState::InvalidInput);
    assert_eq!(refusals(&nav, GoalRefusal::NoTile), 1);
    assert_eq!(nav.mission().status().reason, crate::protocol::StopReason::GoalRefused);
    // flat: nothing demands the tether
    upload(&mut nav, 1, &|_, _| RIM_Z).unwrap();
    assert_eq!(nav.goal(&goal(8.0, 3.0), Instant::from_micros(0)), PlanState::Accepted);
    let (p, plan, _) = run(&mut nav, 5);
    assert!(matches!(p, PlanProgress::Finished { state: PlanState::InvalidInput, .. }), "{p:?}");
    assert!(plan.is_empty());
    assert_eq!(refusals(&nav, GoalRefusal::DescentNotSegmented), 1);
    // the crater, a goal whose corridor leaves the tile
    upload(&mut nav, 2, &crater_z).unwrap();
    nav.goal(&goal(30.0, 3.0), Instant::from_micros(0));
    let (p, _, _) = run(&mut nav, 5);
    assert!(matches!(p, PlanProgress::Finished { state: PlanState::InvalidInput, .. }), "{p:?}");
    assert_eq!(refusals(&nav, GoalRefusal::DescentNotSegmented), 2);
    // a 10 m spool for a 15 m tether
    nav.configure(&configure(10.0)).unwrap();
    nav.goal(&goal(8.0, 3.0), Instant::from_micros(0));
    let (p, _, _) = run(&mut nav, 5);
    assert!(matches!(p, PlanProgress::Finished { state: PlanState::InvalidInput, .. }), "{p:?}");
    assert_eq!(refusals(&nav, GoalRefusal::PayoutExceeded), 1);
    assert_eq!(nav.mission().status().reason, crate::protocol::StopReason::GoalRefused);
    let team = GoalRequest { planner: PlannerChoice::Team, ..goal(8.0, 3.0) };
    assert_eq!(nav.goal(&team, Instant::from_micros(0)), PlanState::PlannerUnavailable);
}

/// A bad upload after a route was planned (NaN heights reach the navigator only if the executive let them, so here:
/// an upload abandoned halfway, and one whose shape does not match what was staged) keeps the tile and the route.
#[test]
fn a_bad_upload_keeps_the_tile_and_the_route() {
    let mut nav = nav();
    nav.configure(&configure(50.0)).unwrap();
    upload(&mut nav, 1, &crater_z).unwrap();
    scan_rim(&mut nav);
    nav.goal(&goal(8.0, 3.0), Instant::from_micros(0));
    run(&mut nav, 10);
    let legs = nav.homotopy_legs().to_vec();
    let route_len = nav.homotopy_route().unwrap().tether_length_m;
    // half a flat tile, then another tile's chunk 0 abandons it; the second's completion claims more than arrived
    let header = |id: u32| TileHeader { tile_id: id, origin: [0.0, 0.0], resolution_m: RES, rows: ROWS, cols: COLS, chunk_count: 32 };
    let flat = [0.0f32; MAX_HEIGHTS_PER_TILE_CHUNK];
    nav.tile_part(&header(2), 0, &flat, Instant::from_micros(0));
    nav.tile_part(&header(2), MAX_HEIGHTS_PER_TILE_CHUNK, &flat, Instant::from_micros(0));
    nav.tile_part(&header(3), 0, &flat, Instant::from_micros(0));
    assert_eq!(nav.map_status().tiles_abandoned, 1);
    assert_eq!(nav.tile_complete(&header(3), Instant::from_micros(0)), Err(Refused));
    assert_eq!((nav.map_status().tiles_loaded, nav.map_status().tile_id), (1, 1));
    let tile = nav.terrain_tile().unwrap();
    assert_eq!(tile.height(0, 0), Some(f64::from(crater_z(0.0, 0.0))));
    assert_eq!(nav.homotopy_legs(), &legs[..]);
    assert_eq!(nav.homotopy_route().unwrap().tether_length_m, route_len);
}

/// A navigator with the crater's route planned (goal on the floor) and its first leg set up.
fn first_leg_set_up() -> TestNav {
    let mut nav = nav();
    nav.configure(&configure(50.0)).unwrap();
    upload(&mut nav, 1, &crater_z).unwrap();
    scan_rim(&mut nav);
    nav.goal(&goal(8.0, 3.0), Instant::from_micros(0));
    run(&mut nav, 10);
    assert_eq!(nav.drive_step(Instant::from_micros(10)), DriveStep::Replan);
    nav
}

/// A second blocked region that overlaps the first (the detour's first leg fails too, its goal within two block
/// radii of the first blocked goal) merges with it into one obstacle and the route is planned again round both;
/// before, the BTM refused the overlapping region (`OverlapsObstacle`) and the mission stopped.
#[test]
fn a_blocked_region_that_overlaps_an_earlier_one_merges_with_it() {
    let mut nav = first_leg_set_up();
    let first = nav.homotopy_legs()[0];
    let mut plan = PlanBuffer::new();
    nav.homotopy_leg_failed(PlanState::NoSolutionWithinBudget, &mut plan).expect("the first global replan");
    assert_eq!(nav.drive_step(Instant::from_micros(20)), DriveStep::Replan);
    let second = nav.homotopy_legs()[0];
    let apart = libm::hypotf(second[0] - first[0], second[1] - first[1]);
    let r = crate::config::nav::HOMOTOPY_BLOCK_RADIUS_M as f32;
    assert!(apart < 2.0 * r, "the test needs overlapping regions: {first:?} and {second:?} are {apart} m apart");
    let obstacles = |nav: &TestNav| nav.global.global_ref().unwrap().btm.obstacles().count();
    assert_eq!(obstacles(&nav), 1);
    let p = nav.homotopy_leg_failed(PlanState::NoSolutionWithinBudget, &mut plan).expect("a second global replan");
    assert!(matches!(p, PlanProgress::Finished { state: PlanState::ExactSolution, .. }), "{p:?}");
    assert_eq!(nav.homotopy_stats().global_replans, 2);
    assert_eq!(nav.homotopy_stats().global_replan_failures, 0);
    assert_eq!(obstacles(&nav), 1, "the two regions are one obstacle");
    for l in nav.homotopy_legs() {
        for b in [first, second] {
            let d = libm::hypotf(l[0] - b[0], l[1] - b[1]);
            assert!(d >= 0.9, "leg goal {l:?} inside the blocked region round {b:?} ({d} m)");
        }
    }
}

/// Tanner et al. Alg. 3 on board (reduced): a leg whose ABIT* finds no path blocks its goal region in the BTM and
/// the route is planned again, reported like the first (a new `Plan` of leg goals, none inside the blocked region),
/// counted; the next drive step sets up the new route's first leg. The last leg is never blocked (it is the goal).
#[test]
fn a_leg_without_a_path_blocks_its_region_and_the_route_is_planned_again() {
    let mut nav = first_leg_set_up();
    let blocked = nav.homotopy_legs()[0];
    let before = nav.homotopy_route().unwrap().tether_length_m;
    let mut plan = PlanBuffer::new();
    let p = nav.homotopy_leg_failed(PlanState::NoSolutionWithinBudget, &mut plan).expect("a global replan");
    let PlanProgress::Finished { state: PlanState::ExactSolution, best_cost: Some(cost), .. } = p else { panic!("{p:?}") };
    assert_eq!(nav.homotopy_stats().global_replans, 1);
    assert!(f64::from(cost) >= before - 1e-3, "a detour is not shorter: {cost} vs {before}");
    assert_eq!(plan.len(), nav.homotopy_legs().len());
    for l in nav.homotopy_legs() {
        let d = libm::hypotf(l[0] - blocked[0], l[1] - blocked[1]);
        assert!(d >= 0.9, "leg goal {l:?} inside the blocked region round {blocked:?} ({d} m)");
    }
    assert_eq!(nav.homotopy_leg(), Some(0));
    assert_eq!(nav.drive_step(Instant::from_micros(20)), DriveStep::Replan, "the new route's first leg is set up");
    // a solved leg, or any failure of the last leg, is no global replan
    assert!(nav.homotopy_leg_failed(PlanState::ExactSolution, &mut plan).is_none());
    assert_eq!(nav.homotopy_stats().global_replans, 1);
}
