//! Benchmarks of the climbing-team planners (Morad et al.): time per local plan (scene -> score -> cull -> graph
//! -> bounded-leg A*) on one scan of the HiRISE cliff and of Itokawa, and D* Lite Moving AI scenarios per second.
//! Run: `cargo bench -p host-sim --bench team`.

use criterion::{criterion_group, criterion_main, Criterion};
use firmware::geom::{Real, Vec3};
use firmware::plan::team::DefaultLocalPlanner;
use host_sim::team::worlds::team_scenario;
use host_sim::movingai::{load_map, load_scen, run_scenarios};
use firmware::geom::p3::{add, scale};
use std::path::PathBuf;

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data")
}

fn local_plan(c: &mut Criterion) {
    for world in ["cliff", "itokawa"] {
        let (surf, start, cfg, _, _) = team_scenario(world, &data(), None, 1).unwrap();
        let pos = start[0];
        let n = surf.normal_near(pos);
        let sensor = add(pos, scale(n, cfg.sensor.height));
        let dirs = cfg.sensor.directions();
        let pts: Vec<Vec3> = dirs
            .iter()
            .zip(surf.scan(sensor, &dirs, cfg.sensor.range))
            .filter_map(|(d, t)| t.map(|t| add(sensor, scale(*d, t))))
            .map(|p| Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real))
            .collect();
        let v = |p: [f64; 3]| Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real);
        let mut planner: Box<DefaultLocalPlanner> = Box::default();
        let hub = (v(start[0]) + v(start[1]) + v(start[2]) + v(start[3])) / 4.0;
        let leg = v(pos) - hub;
        let goal = v(cfg.goal) + leg;
        c.bench_function(&format!("team local plan {world} ({} points)", pts.len()), |b| {
            b.iter(|| planner.plan(&pts, &v(n), &v(pos), &leg, &goal, 4.0, &cfg.params).unwrap())
        });
    }
}

fn dstar_movingai(c: &mut Criterion) {
    let m = load_map(&data().join("movingai/arena2.map")).unwrap();
    let s = load_scen(&data().join("movingai/arena2.map.scen")).unwrap();
    let mut g = c.benchmark_group("dstar_lite movingai");
    g.sample_size(10);
    g.throughput(criterion::Throughput::Elements(s.len() as u64));
    g.bench_function("arena2 all 910 scenarios", |b| b.iter(|| run_scenarios(&m, &s, |_, _| true).unwrap()));
    g.finish();
}

criterion_group!(benches, local_plan, dstar_movingai);
criterion_main!(benches);
