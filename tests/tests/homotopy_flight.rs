//! Issue 20 item 4 end to end over the in-process link: a mission on real terrain (the HiRISE scarp) uploads a tile
//! of the DTM and asks for `PlannerChoice::Homotopy`; the flight software plans the global route on the tile, reports
//! it, and drives it leg by leg with tethered ABIT* on its onboard map, judged by the simulator's truth. And the bad
//! tiles of protocol v7 through the link: each refused with its reason and counted, the tile in use kept.

use firmware::config::protocol::MAX_HEIGHTS_PER_TILE_CHUNK;
use firmware::protocol::{Message, NackReason, StopReason, TileChunk, Tracking};
use host_sim::homotopy::tile::{tile_chunks, TileSpec};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::mission::link::mission_link;
use host_sim::mission::run::{run_mission, MissionOptions, Verdict};
use host_sim::scenario::{self, Scenario};
use host_sim::session::HostSession;

fn load(name: &str) -> Scenario {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios").join(name);
    scenario::load(&p).unwrap_or_else(|e| panic!("{e}"))
}

/// The homotopy goal on the HiRISE scarp is accepted, its route (the leg goals on the DTM) is the first plan
/// reported, and the rover drives it with tethered ABIT* legs; the truth never sees a fall or a false arrival.
#[test]
fn a_homotopy_goal_on_the_hirise_scarp_is_planned_on_the_tile_and_driven_leg_by_leg() {
    let sc = load("mission_homotopy_hirise.toml");
    assert!(sc.mission.homotopy.is_some());
    let opts = MissionOptions { seed: 7, tracking: Tracking::ClosedLoop, noiseless: false, live: false, reset: None };
    let rep = run_mission(mission_link(&sc).expect("link"), &sc, &opts).expect("mission runs");
    println!(
        "{:?} after {:.2} m, {} motions, {} plans, {} replans, goal error {:.2} m",
        rep.verdict,
        rep.distance_m,
        rep.motions,
        rep.plans.len(),
        rep.replans,
        rep.goal_error_m
    );
    for p in &rep.plans {
        println!("  plan {} ({} iterations, {} waypoints)", p.state, p.iterations, p.waypoints.len());
    }
    assert_eq!(rep.nacks, 0, "the flight software refused a frame of the upload or the mission");
    assert_ne!(rep.verdict, Verdict::Fell, "the rover fell: {:?}", rep.trace.last());
    assert_ne!(rep.verdict, Verdict::FalseArrival, "arrival reported {:.2} m from the goal", rep.goal_error_m);
    assert!(rep.trace.iter().all(|t| t.margin_n >= 0.0), "a pose below zero true margin was held");
    // the first plan is the global route: exact, its last waypoint the goal, the others legs of at most 5 m
    let route = rep.plans.first().expect("the route is reported");
    assert_eq!(route.state, "ExactSolution");
    let last = route.waypoints.last().unwrap();
    let g = sc.goal.position;
    assert!((last[0] - g[0]).hypot(last[1] - g[1]) < 1e-3, "{last:?} vs {g:?}");
    assert!(route.waypoints.len() >= 2, "{:?}", route.waypoints);
    // then the legs' ABIT* plans, and the truth executed what they commanded
    assert!(rep.plans.len() >= 2, "no leg was planned");
    assert!(rep.motions >= 1 && rep.distance_m > 0.5, "{} motions, {:.2} m", rep.motions, rep.distance_m);
    if let Verdict::SafeStop(reason) = rep.verdict {
        assert_ne!(reason, StopReason::None, "a safe stop without a reason");
    }
    // the legs end at the route's waypoints, not at the goal: more than one leg was planned after the route, and the
    // rover went most of the way down (the route is ~9 m; 14 of 20 seeds arrive, host-sim/doc/homotopy.md
    // 2026-12-04, so arrival is not asserted for this one seed)
    assert!(rep.plans.len() >= 3, "{} plans", rep.plans.len());
    assert!(rep.distance_m > 5.0, "{:.2} m driven", rep.distance_m);
    if rep.verdict == Verdict::Arrived {
        assert!(rep.goal_error_m <= rep.tolerance_m + 0.25, "{}", rep.goal_error_m);
    }
}

fn chunks(tile_id: u32, rows: u16, cols: u16, resolution_m: f64, h: impl Fn(usize) -> f32) -> Vec<TileChunk> {
    let spec = TileSpec { origin: [-5.0, -5.0], resolution_m, posts: [cols, rows] };
    let heights: Vec<f32> = (0..usize::from(rows) * usize::from(cols)).map(h).collect();
    tile_chunks(tile_id, &spec, &heights)
}

fn nacks(replies: &[Message]) -> Vec<NackReason> {
    replies.iter().filter_map(|m| if let Message::Nack(n) = m { Some(n.reason) } else { None }).collect()
}

/// Protocol v7 over the link, as the ground would send it: a good tile, then NaN heights, a spacing out of range,
/// chunks out of order, a duplicate, another tile's chunk, a tile larger than the limit; each refused with its own
/// reason and counted in `Telemetry.frames_rejected`; the tile in use stays the first one.
#[test]
fn bad_tiles_over_the_link_are_refused_with_their_reasons_and_the_tile_is_kept() {
    let mut s = HostSession::new(InProcLink::new(DEFAULT_STEP_US));
    s.recv().unwrap();
    let send = |s: &mut HostSession<InProcLink>, cs: &[TileChunk]| {
        let mut got = vec![];
        for c in cs {
            s.send(&Message::TileChunk(c.clone())).unwrap();
            got.extend(nacks(&s.recv().unwrap()));
        }
        got
    };
    let good = chunks(1, 40, 40, 0.5, |i| (i % 40) as f32 * 0.1);
    assert_eq!(good.len(), 1600usize.div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK));
    assert!(send(&mut s, &good).is_empty());
    let t = s.telemetry().unwrap();
    assert_eq!((t.map.tiles_loaded, t.map.tile_id), (1, 1));

    let mut nan = chunks(2, 40, 40, 0.5, |_| 1.0);
    nan[3].heights[10] = f32::NAN;
    assert_eq!(send(&mut s, &nan[..5]), [NackReason::NonFinite, NackReason::OutOfOrderChunk]);
    assert_eq!(send(&mut s, &chunks(3, 40, 40, 7.5, |_| 1.0)[..1]), [NackReason::TileResolution]);
    let ooo = chunks(4, 40, 40, 0.5, |_| 1.0);
    assert_eq!(send(&mut s, &[ooo[0].clone(), ooo[2].clone()]), [NackReason::OutOfOrderChunk]);
    assert_eq!(send(&mut s, &[ooo[1].clone(), ooo[1].clone()]), [NackReason::DuplicateChunk]);
    assert_eq!(send(&mut s, &chunks(5, 40, 40, 0.5, |_| 1.0)[3..4]), [NackReason::TileMismatch]);
    assert_eq!(send(&mut s, &chunks(6, 200, 20, 0.5, |_| 1.0)[..1]), [NackReason::TileTooLarge]);
    let t = s.telemetry().unwrap();
    for (reason, n) in [
        (NackReason::NonFinite, 1),
        (NackReason::OutOfOrderChunk, 2),
        (NackReason::TileResolution, 1),
        (NackReason::DuplicateChunk, 1),
        (NackReason::TileMismatch, 1),
        (NackReason::TileTooLarge, 1),
    ] {
        assert_eq!(t.frames_rejected[reason.index()], n, "{reason:?}");
    }
    assert_eq!((t.map.tiles_loaded, t.map.tile_id), (1, 1), "the tile in use is still the first");
}
