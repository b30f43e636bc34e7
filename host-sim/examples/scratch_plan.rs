use firmware::map::DistanceField;
use host_sim::link::FlightLink;
use firmware::protocol::*;
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::mission::executor::*;
use host_sim::mission::sensing::*;
use host_sim::mission::truth::Body;
use host_sim::mission::world::MissionWorld;
use host_sim::session::HostSession;
use host_sim::sensor::to_wire_pose;

fn main() {
    let path = std::env::args().nth(1).unwrap();
    let sc = host_sim::scenario::load(std::path::Path::new(&path)).unwrap();
    let m = sc.mission.clone();
    let base = sc.build_world().unwrap();
    let ledge = match sc.world.kind.as_str() { "ledge" => Some(host_sim::world::ledge::LedgeWorld::new()), "ledge_pole" => Some(host_sim::world::ledge::LedgeWorld::with_pole()), _ => None };
    let world = MissionWorld::new(base, ledge, m.obstacles.clone());
    let mut rover = firmware::config::rover::RoverParams::AXEL;
    rover.track_m = 0.9; rover.boom_length_m = 0.6; rover.wheel_mu = 0.7;
    let truth = MissionTruth { world, root: sc.tether.root_anchor, tether_length_m: sc.tether.length_m, rover, body: Body { mass_kg: 45.0, gravity: 3.71, mu: 0.7, pretension_n: 20.0, winch_limit_n: 2000.0 }, drift_coeff: 0.15 };
    if std::env::var("PROF").is_ok() { for k in 0..30 { let y = 14.0 + 0.25 * k as f32; print!("{y:.2}:{:.2} ", truth.world.base().height_at(12.0, y).unwrap()); } println!(); return; }
    let st = truth.settle(sc.rover.start[0], sc.rover.start[1], sc.rover.yaw_deg.to_radians()).unwrap();
    let r = truth.place(st, None, 0.0).unwrap();
    println!("start axle {:?} tension {:.1} margin {:.1}", r.axle(), r.statics.tension_n, r.statics.margin_n);
    let mc = sc.map_config().unwrap();
    let nav = firmware::nav::Navigator::new(mc, vec![firmware::map::Block::EMPTY; firmware::config::map::FLIGHT_BLOCKS], vec![0u32; firmware::config::map::FLIGHT_INDEX], Box::<firmware::nav::NavPlanStorage>::default()).unwrap();
    let mut s = HostSession::new(InProcLink::with_autonomy(nav, DEFAULT_STEP_US));
    s.recv().unwrap();
    let mut cfg = host_sim::scripted::default_configure(1);
    let ra = sc.tether.root_anchor;
    cfg.tether.root_anchor = Point3::new(ra[0] as f32, ra[1] as f32, ra[2] as f32);
    s.exchange(&Message::Configure(cfg)).unwrap();
    let mut rng = rand_pcg::Pcg64::new(1, 1);
    let t0 = std::time::Instant::now();
    let mut m2 = m.clone(); m2.overview_resolution_deg = std::env::var("RES").map(|v| v.parse().unwrap()).unwrap_or(0.5);
    for (i, (op, opose)) in overview_sensor(sc.tether.root_anchor, sc.goal.position, &sc.sensor, &m2).iter().enumerate() {
        let ov = overview_scan(&truth.world.sensed(), op, opose, &mut rng);
        println!("overview tile {} points", ov.points.len());
        for c in ov.to_chunks(10 + i as u32, 256).unwrap() { s.send(&Message::SensorChunk(c)).unwrap(); }
        s.recv().unwrap();
    }
    println!("after overview {:?}", s.telemetry().unwrap().map);
    let pose = r.state.settled.pose;
    let sc2 = rover_scan(&truth.world.sensed(), &sc.sensor, &pose, &pose, &mut rng);
    println!("rover scan {} points", sc2.points.len());
    for c in sc2.to_chunks(2, 256).unwrap() { s.send(&Message::SensorChunk(c)).unwrap(); }
    s.recv().unwrap();
    let t = s.telemetry().unwrap();
    println!("map {:?} in {:?}", t.map, t0.elapsed());
    let _ = to_wire_pose(&pose);
    {
        let link = s.link_mut();
        let nav = link.executive_mut().autonomy_mut();
        let map = nav.map().unwrap();
        let a = if std::env::var("COLGOAL").is_ok() { sc.goal.position } else { r.axle() };
        for k in 0..30 { let z = a[2] as f32 - 0.6 + 0.1 * k as f32; let q = map.query(&firmware::geom::Vec3::new(a[0] as f32, a[1] as f32, z)); print!("{z:.2}:{} ", match q { firmware::map::DistanceQuery::Known{distance,..} => format!("{distance:.2}"), _ => "U".into() }); }
        println!();
        { let edge = map.config().voxel_size * 8.0; let near = 0.5 * edge * 3f32.sqrt(); let mut hz = f32::NEG_INFINITY; let mut arg = [0i32;3];
          for slot in 0..map.blocks_used() { let Some(c) = map.block_coord(slot) else { break }; let centre = firmware::geom::Vec3::new((c[0] as f32 + 0.5) * edge, (c[1] as f32 + 0.5) * edge, (c[2] as f32 + 0.5) * edge);
            if let firmware::map::DistanceQuery::Known { distance, .. } = map.query(&centre) { if distance.abs() <= near && (c[2]+1) as f32 * edge > hz { hz = (c[2]+1) as f32 * edge; arg = c; } } }
          println!("surface top {hz} at block {arg:?} (centre x {} y {})", (arg[0] as f32 + 0.5) * edge, (arg[1] as f32 + 0.5) * edge); }
        let az = a[2] as f32; let b = firmware::plan::tethered::PlanBounds { min: [-100.0, -100.0, az - 3.0], max: [100.0, 100.0, az + 1.2] };
        let mut rp = firmware::config::rover::RoverParams::AXEL; rp.track_m = 0.9; rp.boom_length_m = 0.6;
        println!("settle {:?}", firmware::plan::tethered::settle_at(&map, &b, &rp, a[0] as f32, a[1] as f32, 0.0).map(|s| s.axle()));
        let g = r.state.ground;
        let mut unk = 0; let mut tot = 0; for i in -10..=10 { for j in -10..=10 { for k in 0..20 { let p = g + firmware::geom::Vec3::new(i as f32 * 0.05, j as f32 * 0.05, k as f32 * 0.05); let h = truth.world.base().height_at(p.x, p.y).unwrap(); if p.z < h + 0.05 { continue; } tot += 1; if matches!(map.query(&p), firmware::map::DistanceQuery::Unknown) { unk += 1; if unk < 15 { print!("({:.2},{:.2},{:.2} h{:.2}) ", p.x, p.y, p.z, h); } } } } } println!("unknown {unk} of {tot} around start");
        println!("raw settle {:?}", firmware::rover::settle(&map, &g, 0.0, &rp));
    }
    let g = sc.goal.position;
    let goal = GoalRequest { goal_id: 1, position: Point3::new(g[0] as f32, g[1] as f32, g[2] as f32), tolerance_m: 0.5, planner: PlannerChoice::Abit, max_iterations: 750, time_budget_ms: 0 };
    let mut got = s.exchange(&Message::GoalRequest(goal)).unwrap();
    let t1 = std::time::Instant::now();
    for _ in 0..2000 {
        let t = s.link().now_us() + 10_000;
        got.extend(s.advance_to(t).unwrap());
        if got.iter().any(|m| matches!(m, Message::PlanStatus(p) if !matches!(p.state, PlanState::Accepted | PlanState::Searching))) { break; }
    }
    for m in &got { match m { Message::PlanStatus(p) => println!("{p:?}"), Message::DriveCommand(d) => println!("{d:?}"), Message::Log(l) => println!("{l:?}"), _ => {} } }
    println!("planning {:?}; stats {:?}", t1.elapsed(), s.link().executive().autonomy().plan_stats());
}
#[allow(dead_code)]
fn profile() {}
