//! Homotopy planner benchmarks: funnel time against sleeve size, homotopy classes enumerated per second against
//! obstacle count, local BTM update against a full rebuild. Run: `cargo bench -p host-sim --bench homotopy`.

use core::hint::black_box;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use firmware::plan::homotopy::classes::{enumerate_classes, SearchArena, SearchStart};
use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::geo::{pt, Pt};
use firmware::plan::homotopy::lvalue::LValue;
use firmware::plan::homotopy::sleeve::shortest_homotopic_path;
use firmware::plan::status::Status;
use host_sim::homotopy::scenarios::{random_field, Scenario};
use rand_core::SeedableRng;

fn build(plane: &[Pt], obstacles: &[Vec<Pt>]) -> Box<Btm> {
    let mut btm = Box::new(Btm::new());
    let obs: Vec<&[Pt]> = obstacles.iter().map(|o| o.as_slice()).collect();
    btm.build(plane, &obs).expect("build");
    btm
}

/// A tall "ladder": rows of rocks alternating left and right, so the SHP zig-zags and its sleeve grows with rows.
fn ladder(rows: usize) -> (Vec<Pt>, Vec<Vec<Pt>>, Pt, Pt) {
    let h = 4.0 * rows as f64 + 4.0;
    let plane = vec![pt(0.0, 0.0), pt(10.0, 0.0), pt(10.0, h), pt(0.0, h)];
    let obstacles = (0..rows)
        .map(|r| {
            let y = 2.0 + 4.0 * r as f64 + 2.0;
            let x0 = if r % 2 == 0 { 0.8 } else { 3.2 };
            vec![pt(x0, y), pt(x0 + 6.0, y - 0.3), pt(x0 + 6.0, y + 0.3), pt(x0 + 0.2, y + 0.5)]
        })
        .collect();
    (plane, obstacles, pt(5.0, h - 0.5), pt(5.0, 0.5))
}

fn funnel(c: &mut Criterion) {
    let mut g = c.benchmark_group("homotopy/funnel_vs_sleeve");
    let mut arena = Box::new(SearchArena::new());
    for rows in [2usize, 4, 8, 16, 23] {
        let (plane, obs, a0, goal) = ladder(rows);
        let btm = build(&plane, &obs);
        let mut classes = heapless::Vec::new();
        let st = SearchStart { point: a0, l0: LValue::default(), prefix: &[] };
        assert!(!matches!(enumerate_classes(&btm, &mut arena, &st, goal, &[], 1, &mut classes), Status::InvalidInput(_)), "search");
        let sleeve = classes[0].sleeve.clone();
        g.throughput(Throughput::Elements(sleeve.len() as u64));
        g.bench_with_input(BenchmarkId::new("sleeve_triangles", sleeve.len()), &sleeve, |b, s| {
            b.iter(|| shortest_homotopic_path(&btm, black_box(s), a0, goal).expect("shp"))
        });
    }
    g.finish();
}

fn classes_per_second(c: &mut Criterion) {
    let mut g = c.benchmark_group("homotopy/classes_vs_obstacles");
    let mut arena = Box::new(SearchArena::new());
    for n in [2usize, 4, 8, 16] {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(n as u64);
        let s: Scenario = random_field(&mut rng, n, 20.0);
        let btm = build(&s.plane, &s.known);
        let st = SearchStart { point: s.a0, l0: LValue::default(), prefix: &[] };
        let mut out = heapless::Vec::new();
        assert!(!matches!(enumerate_classes(&btm, &mut arena, &st, s.g, &[], 16, &mut out), Status::InvalidInput(_)), "search");
        g.throughput(Throughput::Elements(out.len() as u64));
        g.bench_with_input(BenchmarkId::new("obstacles", s.known.len()), &n, |b, _| {
            b.iter(|| {
                let mut out = heapless::Vec::new();
                assert!(!matches!(enumerate_classes(&btm, &mut arena, &st, s.g, &[], 16, &mut out), Status::InvalidInput(_)), "search");
                out.len()
            })
        });
    }
    g.finish();
}

fn local_vs_rebuild(c: &mut Criterion) {
    let mut g = c.benchmark_group("homotopy/update");
    for n in [8usize, 16] {
        let mut rng = rand_pcg::Pcg64::seed_from_u64(77 + n as u64);
        let s: Scenario = random_field(&mut rng, n + 1, 20.0);
        let (extra, rest) = s.known.split_last().expect("obstacles");
        let mut btm = build(&s.plane, rest);
        let (k, r1) = btm.add_obstacle(extra).expect("add");
        let r2 = btm.remove_obstacle(k).expect("remove");
        eprintln!(
            "n={n}: {} triangles; add touched {} (region {} corners), remove touched {}",
            btm.triangle_count(),
            r1.touched(),
            r1.region_vertices,
            r2.touched()
        );
        g.bench_function(BenchmarkId::new("local_add_then_remove", n), |b| {
            b.iter(|| {
                let (k, _) = btm.add_obstacle(black_box(extra)).expect("add");
                btm.remove_obstacle(k).expect("remove")
            })
        });
        let mut full = build(&s.plane, &s.known);
        g.bench_function(BenchmarkId::new("full_rebuild", n + 1), |b| b.iter(|| full.rebuild().expect("rebuild")));
    }
    g.finish();
}

criterion_group!(benches, funnel, classes_per_second, local_vs_rebuild);
criterion_main!(benches);
