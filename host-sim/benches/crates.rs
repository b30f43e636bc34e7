//! Our hand-written code against maintained crates, side by side (issue 23, item 4; the decisions are in
//! `host-sim/doc/crates.md`, the agreement tests in `tests/crate_oracles.rs`):
//!
//! - COBS encode + decode of a 1 KiB and a 64 KiB frame: `firmware::protocol::cobs` vs `cobs` 0.3.0;
//! - OBJ parse of the Itokawa text (16 220 triangles): `parse_obj` vs `tobj` 4 (`use_f64`);
//! - `.npy` parse of the HiRISE crop bytes (120 x 70 `<f4`): `parse_npy` (to a `Heightmap`) vs `npyz` 0.9 (to a
//!   `Vec<f32>`);
//! - mesh on Itokawa at full size: world build (ours: BVH + pseudo-normals; parry: BVH + pseudo-normals,
//!   `TriMeshFlags::ORIENTED`), 1000 signed-distance queries, 1000 ray casts;
//! - priority queue: 1024 pushes, 1024 decrease-keys and 1024 pops on the planners' `IndexedHeap` vs std's
//!   `BinaryHeap` with lazy deletion (the heap-allocating queue a host program would reach for).
//!
//! Run: `cargo bench -p host-sim --bench crates -- --warm-up-time 1 --measurement-time 3`.

use core::hint::black_box;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use firmware::plan::heap::{IndexedHeap, NOT_IN_HEAP};
use firmware::protocol::cobs as ours_cobs;
use host_sim::terrain::npy::{parse_npy, NpyOptions};
use host_sim::terrain::obj::{parse_obj, ObjOptions};
use host_sim::world::mesh::MeshWorld;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use rand_core::{Rng, SeedableRng};

#[path = "../tests/oracles/mod.rs"]
mod oracles;
use oracles::{parry_mesh, pv, shared_bytes, tobj_parse, Entry, HIRISE};

fn unit(rng: &mut impl Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

fn cobs(c: &mut Criterion) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(1);
    let mut g = c.benchmark_group("crates/cobs_encode_decode");
    for n in [1024usize, 65536] {
        // one zero in about 40 bytes, as in a postcard-encoded frame of small integers and floats
        let data: Vec<u8> = (0..n)
            .map(|_| {
                if rng.next_u64() % 40 == 0 {
                    0
                } else {
                    (rng.next_u64() % 255) as u8 + 1
                }
            })
            .collect();
        let mut enc = vec![0u8; ours_cobs::max_encoded_len(n)];
        let mut dec = vec![0u8; n];
        g.throughput(Throughput::Bytes(n as u64));
        g.bench_with_input(BenchmarkId::new("ours", n), &data, |b, data| {
            b.iter(|| {
                let m = ours_cobs::encode(black_box(data), &mut enc).expect("room");
                ours_cobs::decode(&enc[..m], &mut dec).expect("decodes")
            })
        });
        g.bench_with_input(BenchmarkId::new("cobs_0.3.0", n), &data, |b, data| {
            b.iter(|| {
                let m = cobs::try_encode(black_box(data), &mut enc).expect("room");
                cobs::decode(&enc[..m], &mut dec).expect("decodes")
            })
        });
    }
    g.finish();
}

fn obj(c: &mut Criterion) {
    let text = String::from_utf8(shared_bytes("asteroids/itokawa.obj")).expect("UTF-8");
    let mut g = c.benchmark_group("crates/obj_parse_itokawa");
    g.throughput(Throughput::Bytes(text.len() as u64));
    g.bench_function("ours", |b| {
        b.iter(|| parse_obj(black_box(&text), &ObjOptions::KILOMETRES).expect("parses"))
    });
    g.bench_function("tobj_4.0.5", |b| {
        b.iter(|| tobj_parse(black_box(&text)).expect("parses"))
    });
    g.finish();
}

fn npy(c: &mut Criterion) {
    let bytes = shared_bytes(HIRISE);
    let mut g = c.benchmark_group("crates/npy_parse_hirise");
    g.throughput(Throughput::Bytes(bytes.len() as u64));
    g.bench_function("ours", |b| {
        b.iter(|| parse_npy(black_box(&bytes), &NpyOptions::metres(1.0)).expect("parses"))
    });
    g.bench_function("npyz_0.9.1", |b| {
        b.iter(|| {
            npyz::NpyFile::new(black_box(&bytes[..]))
                .and_then(|f| f.into_vec::<f32>())
                .expect("parses")
        })
    });
    g.finish();
}

fn mesh(c: &mut Criterion) {
    let text = String::from_utf8(shared_bytes("asteroids/itokawa.obj")).expect("UTF-8");
    let mesh = parse_obj(&text, &ObjOptions::KILOMETRES).expect("itokawa");
    let ours = MeshWorld::new("itokawa", &mesh, 1.0).expect("world");
    let theirs = parry_mesh(&mesh);
    let (lo, hi) = mesh.bounds().expect("bounds");
    let mut rng = rand_pcg::Pcg64::seed_from_u64(2);
    let in_box = |rng: &mut rand_pcg::Pcg64| -> [f64; 3] {
        core::array::from_fn(|k| lo[k] - 0.15 * (hi[k] - lo[k]) + 1.3 * (hi[k] - lo[k]) * unit(rng))
    };
    let points: Vec<[f64; 3]> = (0..1000).map(|_| in_box(&mut rng)).collect();
    let rays: Vec<([f64; 3], [f64; 3])> = (0..1000)
        .map(|_| {
            let o = in_box(&mut rng);
            let d: [f64; 3] = core::array::from_fn(|_| unit(&mut rng) - 0.5);
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
            (o, d.map(|x| x / n))
        })
        .collect();
    let mut g = c.benchmark_group("crates/mesh_itokawa");
    g.bench_function("build/ours", |b| {
        b.iter(|| MeshWorld::new("itokawa", black_box(&mesh), 1.0).expect("world"))
    });
    g.bench_function("build/parry3d-f64_0.31.1", |b| {
        b.iter(|| parry_mesh(black_box(&mesh)))
    });
    g.bench_function("sdf_1000/ours", |b| {
        b.iter(|| points.iter().map(|p| ours.sdf_closest(*p).0).sum::<f64>())
    });
    g.bench_function("sdf_1000/parry3d-f64_0.31.1", |b| {
        b.iter(|| {
            points
                .iter()
                .map(|p| {
                    let proj = theirs.project_local_point(pv(*p), false);
                    let d = (pv(*p) - proj.point).length();
                    if proj.is_inside {
                        -d
                    } else {
                        d
                    }
                })
                .sum::<f64>()
        })
    });
    g.bench_function("ray_1000/ours", |b| {
        b.iter(|| {
            rays.iter()
                .filter_map(|(o, d)| ours.first_hit(*o, *d, 1000.0))
                .sum::<f64>()
        })
    });
    g.bench_function("ray_1000/parry3d-f64_0.31.1", |b| {
        b.iter(|| {
            rays.iter()
                .filter_map(|(o, d)| {
                    theirs.cast_local_ray(&Ray::new(pv(*o), pv(*d)), 1000.0, false)
                })
                .sum::<f64>()
        })
    });
    g.finish();
}

const QUEUED: usize = 1024;

fn priority_queue(c: &mut Criterion) {
    let mut rng = rand_pcg::Pcg64::seed_from_u64(3);
    let keys: Vec<u64> = (0..QUEUED).map(|_| rng.next_u64() % 100_000).collect();
    let cuts: Vec<(u32, u64)> = (0..QUEUED)
        .map(|_| {
            (
                (rng.next_u64() % QUEUED as u64) as u32,
                rng.next_u64() % 1000,
            )
        })
        .collect();
    let mut g = c.benchmark_group("crates/priority_queue_1024_push_decrease_pop");
    g.bench_function("ours_IndexedHeap", |b| {
        let mut heap: IndexedHeap<QUEUED> = IndexedHeap::new();
        b.iter(|| {
            let mut items: Vec<Entry> = keys
                .iter()
                .map(|&key| Entry {
                    key,
                    pos: NOT_IN_HEAP,
                })
                .collect();
            heap.clear();
            for id in 0..QUEUED as u32 {
                heap.push(id, &mut items[..]).expect("room");
            }
            for &(id, cut) in &cuts {
                items[id as usize].key = items[id as usize].key.saturating_sub(cut);
                heap.update(id, &mut items[..]);
            }
            let mut last = 0;
            while let Some(id) = heap.pop(&mut items[..]) {
                last = id;
            }
            last
        })
    });
    g.bench_function("std_BinaryHeap_lazy", |b| {
        b.iter(|| {
            let mut key = keys.clone();
            let mut heap = std::collections::BinaryHeap::with_capacity(2 * QUEUED);
            for (id, &k) in key.iter().enumerate() {
                heap.push(core::cmp::Reverse((k, id as u32)));
            }
            for &(id, cut) in &cuts {
                key[id as usize] = key[id as usize].saturating_sub(cut);
                heap.push(core::cmp::Reverse((key[id as usize], id)));
            }
            let mut done = vec![false; QUEUED];
            let mut last = 0;
            while let Some(core::cmp::Reverse((k, id))) = heap.pop() {
                if !done[id as usize] && key[id as usize] == k {
                    done[id as usize] = true;
                    last = id;
                }
            }
            last
        })
    });
    g.finish();
}

criterion_group!(crates, cobs, obj, npy, mesh, priority_queue);
criterion_main!(crates);
