//! Ground-truth worlds from the real data files: the triangle-mesh world against brute force on the asteroid
//! shape models, and every terrain and shape-model file in `shared/data` loaded through the scenario path.

use firmware::geom::p3::{norm, sub, to_vec3};
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};
use host_sim::scenario;
use host_sim::terrain::obj::{load_obj, ObjOptions};
use host_sim::world::geometry::{closest_point_on_triangle, P3};
use host_sim::world::mesh::{ray_triangle, MeshWorld, SignMode};
use host_sim::world::World;
use std::path::PathBuf;

fn data() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data")
}

fn scenarios() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios")
}

/// SplitMix64 uniform numbers (independent of the code under test).
struct Uni(u64);
impl Uni {
    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        lo + (hi - lo) * ((z >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn point(&mut self, lo: P3, hi: P3, margin: f64) -> P3 {
        [0, 1, 2].map(|k| self.range(lo[k] - margin, hi[k] + margin))
    }
}


fn bounds(w: &MeshWorld) -> (P3, P3) {
    let b = w.bounds();
    ([b.min.x as f64, b.min.y as f64, b.min.z as f64], [b.max.x as f64, b.max.y as f64, b.max.z as f64])
}

/// Distance by brute force over every triangle.
fn brute_distance(w: &MeshWorld, p: P3) -> f64 {
    (0..w.triangle_count())
        .map(|t| {
            let [a, b, c] = w.triangle(t).unwrap();
            norm(sub(p, closest_point_on_triangle(p, a, b, c)))
        })
        .fold(f64::INFINITY, f64::min)
}

/// Inside by the majority of three ray-parity tests, counting crossings by brute force over every triangle.
fn brute_inside(w: &MeshWorld, p: P3) -> bool {
    let dirs: [P3; 3] = [[0.31, 0.52, 0.79], [-0.62, 0.18, -0.76], [0.11, -0.93, 0.35]];
    let votes = dirs
        .iter()
        .filter(|d| {
            let n = (0..w.triangle_count())
                .filter(|&t| {
                    let [a, b, c] = w.triangle(t).unwrap();
                    ray_triangle(p, **d, a, b, c).is_some()
                })
                .count();
            n % 2 == 1
        })
        .count();
    votes >= 2
}

fn shape_model(name: &str, scale: f64) -> MeshWorld {
    let mesh = load_obj(&data().join("asteroids").join(name), &ObjOptions::KILOMETRES).unwrap();
    MeshWorld::new(name, &mesh, scale).unwrap()
}

fn distance_and_sign_against_brute_force(w: &MeshWorld, n: usize, seed: u64) {
    let (lo, hi) = bounds(w);
    let margin = 0.1 * norm(sub(hi, lo));
    let mut rng = Uni(seed);
    let mut inside = 0;
    for _ in 0..n {
        let p = rng.point(lo, hi, margin);
        let (sd, q) = w.sdf_closest(p);
        let b = brute_distance(w, p);
        assert!((sd.abs() - b).abs() <= 1e-9 * (1.0 + b), "{}: {p:?}: {sd} vs brute {b}", w.name());
        assert!((norm(sub(p, q)) - b).abs() <= 1e-9 * (1.0 + b));
        let bi = brute_inside(w, p);
        assert_eq!(sd < 0.0, bi, "{}: {p:?}: sd {sd}, parity inside {bi}", w.name());
        inside += usize::from(bi);
    }
    // The sample must exercise both signs (points in the bounding box, the body fills a good part of it).
    assert!(inside > n / 10 && inside < n * 9 / 10, "{inside} of {n} inside");
}

#[test]
fn itokawa_distance_and_sign_match_brute_force() {
    let w = shape_model("itokawa.obj", 1.0);
    assert_eq!(w.open_edges(), 0, "the shape model is closed");
    assert_eq!(w.sign_mode(), SignMode::PseudoNormal);
    distance_and_sign_against_brute_force(&w, 300, 11);
}

#[test]
fn bennu_distance_and_sign_match_brute_force() {
    let w = shape_model("bennu.obj", 1.0);
    assert_eq!(w.open_edges(), 0, "the shape model is closed");
    distance_and_sign_against_brute_force(&w, 150, 12);
}

#[test]
fn itokawa_raycasts_match_brute_force() {
    let w = shape_model("itokawa.obj", 0.2);
    let (lo, hi) = bounds(&w);
    let mut rng = Uni(5);
    let mut hits = 0;
    for _ in 0..300 {
        let o = rng.point(lo, hi, 10.0);
        let d = {
            let v = [rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), rng.range(-1.0, 1.0)];
            let l = norm(v);
            [v[0] / l, v[1] / l, v[2] / l]
        };
        let max = 60.0;
        let brute = (0..w.triangle_count())
            .filter_map(|t| {
                let [a, b, c] = w.triangle(t).unwrap();
                ray_triangle(o, d, a, b, c)
            })
            .filter(|&t| t <= max)
            .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
        let got = w.raycast(&to_vec3(o), &to_vec3(d), max as Real);
        match (got, brute) {
            // The World interface is f32: compare to f32 resolution at ~100 m.
            (Some(a), Some(b)) => assert!((a as f64 - b).abs() < 1e-3, "{o:?} {d:?}: {a} vs {b}"),
            (None, None) => {}
            _ => panic!("{o:?} {d:?}: {got:?} vs brute {brute:?}"),
        }
        hits += usize::from(brute.is_some());
        // The hit point is on the surface.
        if let Some(t) = got {
            let p = [o[0] + d[0] * t as f64, o[1] + d[1] * t as f64, o[2] + d[2] * t as f64];
            assert!(w.sdf_closest(p).0.abs() < 1e-3);
        }
    }
    assert!(hits > 30 && hits < 270, "{hits} hits");
}

#[test]
fn itokawa_gradient_matches_finite_differences() {
    let w = shape_model("itokawa.obj", 0.2);
    let (lo, hi) = bounds(&w);
    let mut rng = Uni(9);
    let mut n = 0;
    while n < 200 {
        let p = rng.point(lo, hi, 5.0);
        let DistanceQuery::Known { distance, gradient } = w.query(&to_vec3(p)) else { panic!("mesh worlds know everywhere") };
        if distance.abs() < 0.2 {
            continue;
        }
        let h = 1e-4;
        let fd = [0, 1, 2].map(|k| {
            let mut a = p;
            let mut b = p;
            a[k] += h;
            b[k] -= h;
            (w.sdf_closest(a).0 - w.sdf_closest(b).0) / (2.0 * h)
        });
        let err = norm(sub(fd, [gradient.x as f64, gradient.y as f64, gradient.z as f64]));
        // Where the closest point is unique the SDF is differentiable; skip the medial set (|fd| < 1).
        if (norm(fd) - 1.0).abs() < 1e-3 {
            assert!(err < 1e-3, "{p:?}: gradient {gradient:?} vs finite differences {fd:?}");
            n += 1;
        }
    }
}

/// A scenario for `file` (relative to host-sim/scenarios), with the rover 0.4 m above the ground at the
/// world's centre, the anchor 2 m above the ground 1 m behind, the goal at the ground 1 m ahead.
fn scenario_for(rel: &str, world: &str) -> String {
    format!("name = \"probe\"\n{world}\n[rover]\nstart = [0.0, 0.0, 0.0]\n[tether]\nroot_anchor = [0.0, 0.0, 0.0]\n[goal]\nposition = [0.0, 0.0, 0.0]\n")
        .replace("FILE", rel)
}

#[test]
fn every_shared_terrain_and_shape_model_loads_through_a_scenario() {
    let mut loaded = Vec::new();
    for sub_dir in ["terrain", "asteroids"] {
        let mut files: Vec<PathBuf> = std::fs::read_dir(data().join(sub_dir)).unwrap().map(|e| e.unwrap().path()).collect();
        files.sort();
        for f in files {
            let name = f.file_name().unwrap().to_str().unwrap().to_string();
            let rel = format!("../../../shared/data/{sub_dir}/{name}");
            let ext = f.extension().and_then(|e| e.to_str()).unwrap_or("");
            let world = match ext {
                "tif" | "asc" => "[world]\nkind = \"terrain\"\n[world.terrain]\nfile = \"FILE\"".to_string(),
                "npy" => "[world]\nkind = \"terrain\"\n[world.terrain]\nfile = \"FILE\"\nspacing_m = 1.01".to_string(),
                "obj" => "[world]\nkind = \"mesh\"\n[world.mesh]\nfile = \"FILE\"\nunits = \"km\"".to_string(),
                other => panic!("{}: no scenario form for .{other} files", f.display()),
            };
            let file = scenarios().join("probe.toml");
            let mut sc = scenario::parse(&scenario_for(&rel, &world), &file).unwrap_or_else(|e| panic!("{e}"));
            let w = sc.build_world().unwrap_or_else(|e| panic!("{e}"));
            let b = w.bounds();
            assert!((b.max - b.min).iter().all(|e| e.is_finite() && *e > 0.0), "{name}: bounds {b:?}");
            let ground = |x: f64, y: f64| w.height_at(x as Real, y as Real).unwrap_or_else(|| panic!("{name}: no ground at ({x}, {y})")) as f64;
            let h0 = ground(0.0, 0.0);
            assert!(h0 >= b.min.z as f64 - 1e-3 && h0 <= b.max.z as f64 + 1e-3, "{name}: h(0,0) {h0} outside {b:?}");
            // An independent ray cast from above agrees with the ground height.
            let top = b.max.z + 5.0;
            let t = w.raycast(&Vec3::new(0.0, 0.0, top), &Vec3::new(0.0, 0.0, -1.0), 1e6).unwrap();
            assert!(((top - t) as f64 - h0).abs() < 1e-2 * (1.0 + h0.abs()), "{name}: raycast {} vs height {h0}", top - t);
            sc.rover.start = [0.0, 0.0, h0 + 0.4];
            sc.tether.root_anchor = [-1.0, 0.0, ground(-1.0, 0.0) + 2.0];
            sc.goal.position = [1.0, 0.0, ground(1.0, 0.0) + 0.3];
            sc.check(w.as_ref()).unwrap_or_else(|e| panic!("{e}"));
            // Just under the ground is inside the terrain.
            let below = sd(w.as_ref(), [0.0, 0.0, h0 - 0.5]);
            assert!(below < 0.0, "{name}: 0.5 m under the ground, signed distance {below}");
            loaded.push(name);
        }
    }
    assert!(loaded.len() >= 6, "{loaded:?}");
}

fn sd(w: &dyn World, p: P3) -> f64 {
    match w.query(&to_vec3(p)) {
        DistanceQuery::Known { distance, .. } => distance as f64,
        DistanceQuery::Unknown => f64::NAN,
    }
}

#[test]
fn shipped_npy_and_mesh_scenarios_load_and_validate() {
    for (file, kind) in [("hirise_cliff.toml", "terrain"), ("itokawa.toml", "mesh")] {
        let path = scenarios().join(file);
        let sc = scenario::load(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(sc.world_kind(), kind);
        let w = sc.build_world().unwrap();
        // The rover starts above the ground and outside the terrain, the goal is reachable ground.
        let s = sc.rover.start;
        let g = w.height_at(s[0] as Real, s[1] as Real).unwrap() as f64;
        assert!(s[2] > g && sd(w.as_ref(), s) > 0.0, "{file}: start {s:?}, ground {g}");
        assert!(sd(w.as_ref(), sc.goal.position) > 0.0);
    }
    // The HiRISE crop is 70 x 120 posts at 1.01 m.
    let sc = scenario::load(&scenarios().join("hirise_cliff.toml")).unwrap();
    let b = sc.build_world().unwrap().bounds();
    assert!(((b.max.x - b.min.x) as f64 - 69.0 * 1.01).abs() < 1e-3, "{b:?}");
    assert!(((b.max.y - b.min.y) as f64 - 119.0 * 1.01).abs() < 1e-3, "{b:?}");
}

/// The truncated query that fills planning maps (`World::query_up_to`) on the Mars Yard DEM, over the box of the
/// `marsyard_descent` scenario (a 4 m wall at 40-50 degrees): exact wherever the true distance is within the limit,
/// of the right sign and beyond the limit elsewhere, so a TSDF truncated at the limit is the same either way.
#[test]
fn marsyard_truncated_query_is_exact_within_its_limit() {
    let sc = scenario::load(&scenarios().join("marsyard_descent.toml")).unwrap_or_else(|e| panic!("{e}"));
    let w = sc.build_world().unwrap();
    let (Some(lo), Some(hi)) = (sc.plan.bounds_min, sc.plan.bounds_max) else { panic!("marsyard_descent has [plan] bounds") };
    let mut u = Uni(7);
    let (mut near, mut far) = (0, 0);
    for i in 0..3000 {
        // Half the points within 0.5 m of the ground, where the limit matters; the rest anywhere in the box.
        let mut p = u.point(lo, hi, 0.0);
        if i % 2 == 0 {
            let h = w.height_at(p[0] as Real, p[1] as Real).unwrap() as f64;
            p[2] = h + u.range(-0.5, 0.5);
        }
        let exact = sd(w.as_ref(), p);
        for limit in [0.15f32, 0.3] {
            let DistanceQuery::Known { distance, .. } = w.query_up_to(&to_vec3(p), limit) else { panic!("{p:?}: unknown") };
            let (d, l) = (distance as f64, limit as f64);
            if exact.abs() <= l {
                assert_eq!(distance, exact as f32, "{p:?} limit {limit}: {d} vs exact {exact}");
                near += 1;
            } else {
                assert!(d.signum() == exact.signum() && d.abs() > l, "{p:?} limit {limit}: {d} vs exact {exact}");
                far += 1;
            }
        }
    }
    assert!(near > 1000 && far > 1000, "near {near}, far {far}");
}
