//! Host timings of the ground-truth worlds: mesh world build, signed-distance queries and ray casts on the
//! Itokawa shape model at the `itokawa.toml` scale (0.2), and a full sensor scan (5551 rays) into it.
//! Run: `cargo bench -p host-sim --bench worlds`.

use core::hint::black_box;
use criterion::{criterion_group, criterion_main, Criterion};
use firmware::geom::{Pose3, Rot3, Vec3};
use firmware::map::DistanceField;
use host_sim::sensor::{scan, RangeSensorParams};
use host_sim::terrain::obj::{load_obj, ObjOptions};
use host_sim::world::mesh::MeshWorld;
use host_sim::world::World;
use std::path::PathBuf;

fn benches(c: &mut Criterion) {
    let file = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/asteroids/itokawa.obj");
    let mesh = load_obj(&file, &ObjOptions::KILOMETRES).expect("itokawa.obj");
    c.bench_function("mesh/build_itokawa_16k_triangles", |b| b.iter(|| MeshWorld::new("itokawa", black_box(&mesh), 0.2)));
    let w = MeshWorld::new("itokawa", &mesh, 0.2).expect("mesh world");
    let near = Vec3::new(0.0, 0.0, w.height_at(0.0, 0.0).expect("ground") + 0.5);
    let far = Vec3::new(0.0, 0.0, 60.0);
    c.bench_function("mesh/sdf_query_0.5m_above", |b| b.iter(|| w.query(black_box(&near))));
    c.bench_function("mesh/sdf_query_35m_above", |b| b.iter(|| w.query(black_box(&far))));
    let dir = Vec3::new(0.3, 0.2, -0.93).normalize();
    c.bench_function("mesh/raycast_down_8m", |b| b.iter(|| w.raycast(black_box(&near), black_box(&dir), 8.0)));
    let params = RangeSensorParams::default();
    let pose = Pose3::from_parts(near.into(), Rot3::identity());
    let mut rng = rand_pcg::Pcg64::new(1, 0x5851_f42d_4c95_7f2d);
    c.bench_function("mesh/scan_5551_rays", |b| b.iter(|| scan(&w, &params, black_box(&pose), &mut rng)));
}

criterion_group!(worlds, benches);
criterion_main!(worlds);
