//! Unit tests of the map against independent oracles (brute force, analytic planes).

use super::*;
use crate::config::map::MapConfig;
use crate::geom::{Pose3, Rot3};
use rand_core::Rng;

extern crate std;
use std::boxed::Box;
use std::vec;
use std::vec::Vec;

fn slices(blocks: usize, index: usize) -> (Vec<Block>, Vec<u32>) {
    (vec![Block::EMPTY; blocks], vec![0u32; index])
}

#[test]
fn bad_storage_and_config_are_typed_errors() {
    let (mut b, mut i) = slices(8, 6);
    assert_eq!(Map::from_slices(MapConfig::DEFAULT, &mut b, &mut i).err(), Some(MapError::BadStorage));
    let (mut b, mut i) = slices(8, 16);
    let mut cfg = MapConfig::DEFAULT;
    cfg.truncation = Real::NAN;
    match Map::from_slices(cfg, &mut b, &mut i) {
        Err(MapError::Config(e)) => assert_eq!(e.field, "truncation"),
        _ => panic!("NaN truncation accepted"),
    }
}

#[test]
fn static_storage_builds() {
    let mut st: Box<MapStorage<4, 8>> = Box::default();
    let map = Map::new(MapConfig::DEFAULT, &mut st);
    assert!(map.is_ok());
}

#[test]
fn full_pool_is_an_outcome_and_keeps_work() {
    let (mut b, mut i) = slices(2, 4);
    let mut map = Map::from_slices(MapConfig::DEFAULT, &mut b, &mut i).unwrap();
    // A long ray crosses many blocks; only two can be allocated.
    let pts = [Vec3::new(3.0, 0.01, 0.01)];
    let out = map.integrate_points(&Pose3::identity(), &pts);
    assert_eq!(out.points_integrated, 1);
    assert!(out.voxels_dropped > 0);
    assert!(out.voxels_updated > 0);
    assert_eq!(out.pool_error, Some(MapError::PoolFull));
    assert_eq!(map.blocks_used(), 2);
}

/// Regression (issue 24): a sensor pose of 1e30 m overflowed the voxel index (`i32` saturating, then `+ 1`). Points
/// and origins beyond the map bounds are rejected and counted; nothing is written; a valid point alongside still
/// lands; a sensor exactly inside the bound integrates.
#[test]
fn sensor_pose_beyond_the_map_bounds_is_rejected_and_counted() {
    use crate::config::map::MAX_VOXEL_COORD;
    let (mut b, mut i) = slices(16, 32);
    let mut map = Map::from_slices(MapConfig::DEFAULT, &mut b, &mut i).unwrap();
    let vs = map.config().voxel_size;
    // 2e8 m: the voxel index (4e9) saturates i32 while the point, 16 m ahead, has a valid depth; this is the
    // path that overflowed (`(ga + 1)` on i32::MAX).
    let out = map.integrate_points(&Pose3::translation(2e8, 0.0, 0.0), &[Vec3::new(16.0, 0.0, 0.0)]);
    assert_eq!((out.points_rejected, out.points_out_of_bounds, out.voxels_updated), (1, 1, 0));
    let far = Pose3::translation(1e30, -1e30, 1e30);
    let out = map.integrate_points(&far, &[Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 2.0, 0.0)]);
    assert_eq!((out.points_rejected, out.points_out_of_bounds, out.points_integrated), (2, 2, 0));
    assert_eq!((out.voxels_updated, map.blocks_used()), (0, 0));
    // The point beyond the bound is rejected, the near one integrated (the sensor is at the origin).
    let beyond = Vec3::new(0.0, 0.0, 1.01 * MAX_VOXEL_COORD * vs);
    let out = map.integrate_points(&Pose3::identity(), &[beyond, Vec3::new(1.0, 0.0, 0.0)]);
    assert_eq!((out.points_rejected, out.points_out_of_bounds, out.points_integrated), (1, 1, 1));
    assert!(out.voxels_updated > 0);
    // A sensor near the bound (inside it) with a point 1 m ahead integrates; the indices do not wrap.
    let edge = 0.999 * MAX_VOXEL_COORD * vs;
    let (mut b, mut i) = slices(16, 32);
    let mut map = Map::from_slices(MapConfig::DEFAULT, &mut b, &mut i).unwrap();
    let out = map.integrate_points(&Pose3::translation(edge, edge, -edge), &[Vec3::new(1.0, 0.0, 0.0)]);
    assert_eq!((out.points_rejected, out.points_integrated), (0, 1));
    let slot = map.blocks_used().checked_sub(1).unwrap();
    let c = map.block_coord(slot).unwrap();
    assert!(c[0] > 0 && c[1] > 0 && c[2] < 0, "{c:?}");
    // NaN is rejected as not finite, not as out of bounds.
    let out = map.integrate_points(&Pose3::identity(), &[Vec3::new(Real::NAN, 0.0, 1.0)]);
    assert_eq!((out.points_rejected, out.points_out_of_bounds), (1, 0));
}

/// Points on the plane z = 0 seen from a sensor at `origin`, on a grid of directions (a synthetic scan).
fn plane_scan(origin: Vec3, n: usize) -> Vec<Vec3> {
    let mut pts = Vec::new();
    for a in 0..n {
        for b in 0..n {
            let x = -1.5 + 3.0 * a as Real / (n - 1) as Real;
            let y = -1.5 + 3.0 * b as Real / (n - 1) as Real;
            pts.push(Vec3::new(x, y, 0.0) - origin);
        }
    }
    pts
}

#[test]
fn plane_distance_and_gradient_match_analytic_plane() {
    let (mut b, mut i) = slices(2048, 4096);
    let cfg = MapConfig::with_voxel_size(0.05);
    let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
    let origin = Vec3::new(0.0, 0.0, 1.2);
    let pose = Pose3::from_parts(origin.into(), Rot3::identity());
    for _ in 0..3 {
        let out = map.integrate_points(&pose, &plane_scan(origin, 120));
        assert_eq!(out.pool_error, None);
    }
    let e = map.update_esdf();
    assert!(e.converged, "{e:?}");
    // Analytic truth: distance to z = 0 is z. Check a column of heights over the central part.
    let mut worst: Real = 0.0;
    for k in 0..40 {
        let z = -0.1 + 0.9 * k as Real / 40.0; // inside the sensor cone for the columns below
        for &(x, y) in &[(0.0, 0.0), (0.21, -0.17), (-0.27, 0.13)] {
            match map.query(&Vec3::new(x, y, z)) {
                DistanceQuery::Known { distance, gradient } => {
                    worst = worst.max((distance - z).abs());
                    if z > 0.1 {
                        assert!(gradient.z > 0.95, "gradient {gradient:?} at z {z}");
                    }
                }
                DistanceQuery::Unknown => panic!("unknown at ({x}, {y}, {z})"),
            }
        }
    }
    // Half a voxel covers the TSDF quantisation of the sign change plus interpolation.
    assert!(worst < 0.5 * cfg.voxel_size, "worst error {worst}");
    // Deep under the plane, below the observed band and the fill depth (`BELOW_SURFACE_FILL_VOXELS`): unknown.
    assert_eq!(map.query(&Vec3::new(0.0, 0.0, -0.7)), DistanceQuery::Unknown);
    // Never observed (outside the sensor's cone, far away): unknown.
    assert_eq!(map.query(&Vec3::new(10.0, 10.0, 0.5)), DistanceQuery::Unknown);
    assert_eq!(map.voxel_state(map.voxel_index(&Vec3::new(0.0, 0.0, 0.6))), VoxelState::Free);
    assert_eq!(map.voxel_state(map.voxel_index(&Vec3::new(0.0, 0.0, -0.06))), VoxelState::Occupied);

    // Surface points lie on the plane with upward normals; chunked extraction equals one-shot extraction.
    let mut all = vec![SurfacePoint { position: Vec3::zeros(), normal: Vec3::zeros() }; 20000];
    let mut cur = SurfaceCursor::default();
    let n = map.extract_surface(&mut cur, &mut all);
    assert!(cur.is_done());
    assert!(n > 1000, "only {n} surface points");
    // The edge of the observed patch (grazing, one-sided rays) is excluded: check the interior.
    for sp in all.iter().take(n).filter(|s| s.position.x.abs() < 1.3 && s.position.y.abs() < 1.3) {
        assert!(sp.position.z.abs() < 0.02, "{sp:?}");
        assert!(sp.normal.z > 0.9, "{sp:?}");
    }
    let mut cur = SurfaceCursor::default();
    let mut chunked = Vec::new();
    let mut buf = [SurfacePoint { position: Vec3::zeros(), normal: Vec3::zeros() }; 37];
    for _ in 0..10_000 {
        let k = map.extract_surface(&mut cur, &mut buf);
        chunked.extend_from_slice(&buf[..k]);
        if cur.is_done() {
            break;
        }
    }
    assert_eq!(&chunked[..], &all[..n]);
}

/// A plane through the origin sloping down in +x at `slope` (radians), seen at a grazing angle: points on a grid
/// of the plane (1.2 m square around the origin) from a sensor 2.5 m up-slope and `eye_m` above the plane.
fn grazing_plane_map(map: &mut Map<'_>, slope: Real, eye_m: Real) {
    let t1 = Vec3::new(libm::cosf(slope), 0.0, -libm::sinf(slope));
    let n = Vec3::new(libm::sinf(slope), 0.0, libm::cosf(slope));
    let origin = t1 * -2.5 + n * eye_m;
    let mut pts = Vec::new();
    for a in 0..100 {
        for b in 0..100 {
            let (u, v) = (-0.6 + 1.2 * a as Real / 99.0, -0.6 + 1.2 * b as Real / 99.0);
            pts.push(t1 * u + Vec3::y() * v - origin);
        }
    }
    let pose = Pose3::from_parts(origin.into(), Rot3::identity());
    for _ in 0..3 {
        assert_eq!(map.integrate_points(&pose, &pts).pool_error, None);
    }
    assert!(map.update_esdf().converged);
}

/// Unknown space below an observed surface (`Map::esdf_filled`): a surface seen at a grazing angle has
/// a thin observed band behind it (the truncation along the ray); under it the query answers "inside", never
/// free, and no deeper than the fill allows. On level ground the fill is the true depth; on a slope it is deeper
/// than the true distance (conservative). Free or unobserved columns stay unknown.
#[test]
fn unknown_space_under_an_observed_surface_is_inside() {
    let cfg = MapConfig::with_voxel_size(0.05);
    let vs = cfg.voxel_size;
    for (slope_deg, level) in [(0.0 as Real, true), (35.0, false)] {
        let (mut b, mut i) = slices(2048, 4096);
        let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
        let slope = slope_deg.to_radians();
        grazing_plane_map(&mut map, slope, 0.4);
        let n = Vec3::new(libm::sinf(slope), 0.0, libm::cosf(slope));
        let mut filled = 0;
        for &(x, y) in &[(0.0 as Real, 0.0 as Real), (0.2, -0.15), (-0.25, 0.1)] {
            let surface_z = -libm::tanf(slope) * x;
            for k in 1..=6 {
                let depth = 0.05 * k as Real; // vertical depth under the plane
                let p = Vec3::new(x, y, surface_z - depth);
                let truth = -depth * libm::cosf(slope); // signed distance to the plane
                let DistanceQuery::Known { distance, gradient } = map.query(&p) else {
                    panic!("{slope_deg} deg: unknown {depth} m under the surface at ({x}, {y})");
                };
                if map.esdf_voxel(map.voxel_index(&p)).is_none() {
                    filled += 1;
                }
                assert!(distance < 0.0, "{slope_deg} deg: {distance} at depth {depth}");
                if level {
                    assert!((distance - truth).abs() < 0.5 * vs, "level: {distance} vs {truth} at depth {depth}");
                } else {
                    // no shallower than the plane, up to the observed band's own grazing-angle error (a voxel)
                    assert!(distance < truth + vs, "slope: {distance} vs {truth} at depth {depth}");
                }
                assert!(gradient.dot(&n) > 0.5, "{slope_deg} deg: gradient {gradient:?} at depth {depth}");
            }
            // on level ground, at the surface and just above it (the grazing rays observe no more) the field is
            // the plane's distance: the fill moved no zero crossing. (On the grazing slope the projective TSDF is
            // itself off by more than a voxel there, fill or no fill.)
            for k in (0..=2).filter(|_| level) {
                let h = 0.02 * k as Real;
                let p = Vec3::new(x, y, surface_z) + n * h;
                let DistanceQuery::Known { distance, .. } = map.query(&p) else { panic!("unknown {h} m above") };
                assert!((distance - h).abs() < 0.5 * vs + 0.01, "level: {distance} at {h} m above");
            }
        }
        // the grazing view leaves voxels under the surface unobserved: the fill answered for them
        assert!(filled > 0, "{slope_deg} deg: every queried voxel was observed; the test does not reach the fill");
    }
    // A column with only free space observed above unknown space stays unknown (a hole could be anything), and
    // so does a column nobody observed.
    let (mut b, mut i) = slices(2048, 4096);
    let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
    let origin = Vec3::new(0.0, 0.0, 1.0);
    let pose = Pose3::from_parts(origin.into(), Rot3::identity());
    // rays straight down that end at z = 0.5 (a surface there), and a 2 m sideways ray carving free space only
    let pts = [Vec3::new(0.0, 0.0, -0.5), Vec3::new(2.0, 0.0, -0.01)];
    map.integrate_points(&pose, &pts);
    map.update_esdf();
    let under_free = Vec3::new(1.0, 0.0, 0.85);
    assert_eq!(map.voxel_state(map.voxel_index(&(under_free + Vec3::z() * 0.1))), VoxelState::Free);
    assert_eq!(map.esdf_filled(map.voxel_index(&under_free)), None);
    assert_eq!(map.esdf_filled(map.voxel_index(&Vec3::new(5.0, 5.0, 0.0))), None);
    assert_eq!(map.query(&Vec3::new(5.0, 5.0, 0.0)), DistanceQuery::Unknown);
}

/// A gap between rays (`Map::esdf_filled`): level ground observed everywhere but one column of voxels
/// (x index 0) reads across the gap as the plane's distance; a two-voxel gap stays unknown.
#[test]
fn a_one_voxel_gap_between_observed_voxels_is_bridged_and_a_wider_one_is_not() {
    let cfg = MapConfig::with_voxel_size(0.05);
    let vs = cfg.voxel_size;
    for gap in [1, 2] {
        let (mut b, mut i) = slices(256, 512);
        let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
        for x in -6..6 {
            if (0..gap).contains(&x) {
                continue;
            }
            for y in -6..6 {
                for z in -4..8 {
                    let centre_z = (z as Real + 0.5) * vs;
                    map.set_voxel([x, y, z], centre_z, 1.0).unwrap();
                }
            }
        }
        assert!(map.update_esdf().converged);
        // points whose interpolation cell holds the unobserved voxel x = 0 (centres at x = 0.025)
        for &(x, z) in &[(0.02 as Real, 0.1 as Real), (0.03, 0.04), (0.0, 0.2), (0.04, -0.05)] {
            let q = map.query(&Vec3::new(x, 0.0, z));
            if gap == 1 {
                let DistanceQuery::Known { distance, .. } = q else { panic!("one-voxel gap: unknown at ({x}, {z})") };
                assert!((distance - z).abs() < 0.5 * vs, "one-voxel gap: {distance} at ({x}, {z})");
            } else {
                assert_eq!(q, DistanceQuery::Unknown, "two-voxel gap at ({x}, {z})");
            }
        }
    }
}

/// Brute force: for every voxel of the grid, min over sites of (|c - c_s| + sign_v * site value), capped; the
/// voxel is inside (sign -1) only if it is itself a site with a negative value.
fn brute_force(sites: &[([i32; 3], i8)], g: [i32; 3], dmax: Real) -> Option<Real> {
    brute_force_signed(sites, g, false, dmax)
}

/// The configuration of the brute-force comparisons: 0.1 m voxels, distances up to 1.2 m, every site exact.
fn brute_force_config() -> MapConfig {
    let mut cfg = MapConfig::with_voxel_size(0.1);
    cfg.esdf_max_distance = 1.2;
    cfg.esdf_site_tolerance = 0.0;
    cfg
}

/// Builds a map over a `n`^3 voxel cube with random sites; every other voxel free (TSDF = truncation).
fn random_site_map<'a>(
    map: &mut Map<'a>,
    rng: &mut impl Rng,
    n: i32,
    nsites: usize,
) -> Vec<([i32; 3], i8)> {
    let vs = map.config().voxel_size;
    let t = map.config().truncation;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                map.set_voxel([x - n / 2, y - n / 2, z - n / 2], t, 1.0).unwrap();
            }
        }
    }
    let mut sites = Vec::new();
    for _ in 0..nsites {
        let g = [
            (rng.next_u32() % n as u32) as i32 - n / 2,
            (rng.next_u32() % n as u32) as i32 - n / 2,
            (rng.next_u32() % n as u32) as i32 - n / 2,
        ];
        // signed site value in [-0.99, 0.99] voxels, inside the band; negative = behind the surface
        let hundredths = (rng.next_u32() % 199) as i32 - 99;
        let hundredths = hundredths as i8;
        let sdf = hundredths as Real * 0.01 * vs;
        map.set_voxel(g, sdf, 1.0).unwrap();
        sites.retain(|(s, _)| *s != g);
        sites.push((g, hundredths));
    }
    sites
}

/// Vector propagation is exact except in rare configurations: the map's distances are within a tenth of a voxel
/// of the brute force's, and at most 1 % of the voxels are inexact.
fn assert_close_to_brute_force(map: &Map<'_>, sites: &[([i32; 3], i8)], n: i32, what: &str) {
    let (max_err, inexact, total) = compare_with_brute_force(map, sites, n);
    std::eprintln!("{what}: max error {max_err} voxels, {inexact} of {total} voxels inexact");
    assert!(max_err < 0.1, "{what}: max error {max_err} voxels");
    assert!(inexact * 100 <= total, "{what}: {inexact} of {total} voxels inexact");
}

fn compare_with_brute_force(map: &Map<'_>, sites: &[([i32; 3], i8)], n: i32) -> (Real, usize, usize) {
    let dmax = map.config().esdf_max_distance / map.config().voxel_size;
    compare_over_cube(map, n, |g| brute_force(sites, g, dmax))
}

/// Max error (voxels), count of inexact voxels and voxels compared: the map's site distance against `want` over the
/// `n`^3 cube centred on the origin; a voxel that one side has and the other has not fails the test.
fn compare_over_cube(map: &Map<'_>, n: i32, want: impl Fn([i32; 3]) -> Option<Real>) -> (Real, usize, usize) {
    compare_over_cube_at(map, [0, 0, 0], n, want)
}

/// [`compare_over_cube`] over the `n`^3 cube centred on voxel `o`.
fn compare_over_cube_at(
    map: &Map<'_>,
    o: [i32; 3],
    n: i32,
    want: impl Fn([i32; 3]) -> Option<Real>,
) -> (Real, usize, usize) {
    let (mut max_err, mut inexact, mut total) = (0.0 as Real, 0, 0);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let g = [o[0] + x - n / 2, o[1] + y - n / 2, o[2] + z - n / 2];
                total += 1;
                match (want(g), map.site_distance_voxels(g)) {
                    (Some(a), Some(b)) => {
                        let e = (a - b).abs();
                        max_err = max_err.max(e);
                        if e > 1e-4 {
                            inexact += 1;
                        }
                    }
                    (None, None) => {}
                    (a, b) => panic!("voxel {g:?}: brute force {a:?}, map {b:?}"),
                }
            }
        }
    }
    (max_err, inexact, total)
}

#[test]
fn esdf_matches_brute_force_on_random_small_grids() {
    let mut rng = rand_pcg::Pcg32::new(7, 11);
    for trial in 0..6 {
        let (mut b, mut i) = slices(256, 512);
        let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
        let n = 24;
        let sites = random_site_map(&mut map, &mut rng, n, 3 + trial * 4);
        let e = map.update_esdf();
        assert!(e.converged);
        assert_close_to_brute_force(&map, &sites, n, &std::format!("trial {trial}"));
    }
}

#[test]
fn incremental_update_matches_brute_force_after_sites_vanish_and_appear() {
    let mut rng = rand_pcg::Pcg32::new(3, 5);
    let (mut b, mut i) = slices(256, 512);
    let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
    let n = 24;
    let mut sites = random_site_map(&mut map, &mut rng, n, 10);
    assert!(map.update_esdf().converged);
    // Remove half the sites (they become free space) and add new ones.
    let t = map.config().truncation;
    for (g, _) in sites.iter().take(5) {
        map.set_voxel(*g, t, 1.0).unwrap();
    }
    sites.drain(..5);
    // Move the values of two remaining sites (raise and lower through a value change).
    for (g, w) in sites.iter_mut().take(2) {
        *w = if *w > 0 { *w - 60 } else { *w + 60 };
        map.set_voxel(*g, *w as Real * 0.01 * map.config().voxel_size, 1.0).unwrap();
    }
    for _ in 0..4 {
        let g = [
            (rng.next_u32() % n as u32) as i32 - n / 2,
            (rng.next_u32() % n as u32) as i32 - n / 2,
            (rng.next_u32() % n as u32) as i32 - n / 2,
        ];
        map.set_voxel(g, 0.0, 1.0).unwrap();
        sites.retain(|(s, _)| *s != g);
        sites.push((g, 0));
    }
    let e = map.update_esdf();
    assert!(e.converged);
    assert_close_to_brute_force(&map, &sites, n, "after the changes");
}

#[test]
fn esdf_budget_exhaustion_is_resumable() {
    let mut rng = rand_pcg::Pcg32::new(1, 2);
    let (mut b, mut i) = slices(256, 512);
    let mut cfg = brute_force_config();
    cfg.esdf_max_sweeps = 1;
    let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
    let n = 24;
    let sites = random_site_map(&mut map, &mut rng, n, 2);
    let first = map.update_esdf();
    assert!(!first.converged, "one sweep should not reach the far corners: {first:?}");
    let mut calls = 1;
    while !map.update_esdf().converged {
        calls += 1;
        assert!(calls < 50);
    }
    let (max_err, _, _) = compare_with_brute_force(&map, &sites, n);
    assert!(max_err < 0.1);
}

/// Brute force with the voxel's own sign: `inside` voxels (TSDF < 0) count a site's value negatively.
fn brute_force_signed(sites: &[([i32; 3], i8)], g: [i32; 3], inside: bool, dmax: Real) -> Option<Real> {
    if let Some((_, w)) = sites.iter().find(|(s, _)| *s == g) {
        return Some((*w as Real * 0.01).abs());
    }
    let sign = if inside { -1.0 } else { 1.0 };
    let mut best = Real::INFINITY;
    for (s, w) in sites {
        let d = [(g[0] - s[0]) as f64, (g[1] - s[1]) as f64, (g[2] - s[2]) as f64];
        let v = ((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() + sign * *w as f64 * 0.01).max(0.0);
        best = best.min(v as Real);
    }
    if best <= dmax { Some(best) } else { None }
}

/// Max error (voxels) and count of inexact voxels against [`brute_force_signed`], over the `n`^3 cube.
fn compare_signed(map: &Map<'_>, sites: &[([i32; 3], i8)], n: i32) -> (Real, usize, usize) {
    let dmax = map.config().esdf_max_distance / map.config().voxel_size;
    compare_over_cube(map, n, |g| {
        let inside = map.tsdf_voxel(g).is_some_and(|(d, _)| d < 0.0);
        brute_force_signed(sites, g, inside, dmax)
    })
}

fn random_voxel(rng: &mut impl Rng, n: i32) -> [i32; 3] {
    [
        (rng.next_u32() % n as u32) as i32 - n / 2,
        (rng.next_u32() % n as u32) as i32 - n / 2,
        (rng.next_u32() % n as u32) as i32 - n / 2,
    ]
}

/// The wavefront's raise and lower steps, one scan after another: each step removes sites (raise), adds sites
/// (lower), moves site values both ways, and turns free voxels into inside voxels and back (a sign change re-pulls
/// the voxel); after every update the ESDF matches the brute force: at most 1 % of the voxels inexact, none by a
/// voxel or more. (An inside voxel next to sites of both signs can miss its optimum by part of a voxel with
/// 26-neighbour vector propagation: step 1 of this seed has one voxel 0.54 voxel off, exactly as with the raster
/// sweeps this wavefront replaced, checked on 2026-12-03.)
#[test]
fn incremental_raise_and_lower_match_brute_force_step_by_step() {
    let mut rng = rand_pcg::Pcg32::new(21, 8);
    let (mut b, mut i) = slices(256, 512);
    let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
    let n = 24;
    let vs = map.config().voxel_size;
    let t = map.config().truncation;
    let mut sites = random_site_map(&mut map, &mut rng, n, 12);
    assert!(map.update_esdf().converged);
    let mut flipped: Vec<[i32; 3]> = Vec::new();
    for step in 0..8 {
        for _ in 0..2 {
            if sites.len() > 4 {
                let k = (rng.next_u32() as usize) % sites.len();
                let (g, _) = sites.remove(k);
                map.set_voxel(g, t, 1.0).unwrap();
            }
        }
        for (g, w) in sites.iter_mut().take(2) {
            *w = if *w > 0 { *w - 50 } else { *w + 50 };
            map.set_voxel(*g, *w as Real * 0.01 * vs, 1.0).unwrap();
        }
        for _ in 0..2 {
            let g = random_voxel(&mut rng, n);
            let w = ((rng.next_u32() % 199) as i32 - 99) as i8;
            map.set_voxel(g, w as Real * 0.01 * vs, 1.0).unwrap();
            sites.retain(|(s, _)| *s != g);
            flipped.retain(|f| *f != g);
            sites.push((g, w));
        }
        // sign changes of non-site voxels: some inside, the previous ones back to free
        for g in flipped.drain(..) {
            if !sites.iter().any(|(s, _)| *s == g) {
                map.set_voxel(g, t, 1.0).unwrap();
            }
        }
        for _ in 0..6 {
            let g = random_voxel(&mut rng, n);
            if !sites.iter().any(|(s, _)| *s == g) {
                map.set_voxel(g, -t, 1.0).unwrap();
                flipped.push(g);
            }
        }
        let e = map.update_esdf();
        assert!(e.converged, "step {step}: {e:?}");
        let (max_err, inexact, total) = compare_signed(&map, &sites, n);
        std::eprintln!("step {step}: {e:?}, max error {max_err} voxels, {inexact} of {total} inexact");
        assert!(max_err < 1.0, "step {step}: max error {max_err} voxels");
        assert!(inexact * 100 <= total, "step {step}: {inexact} of {total} voxels inexact");
    }
}

/// More voxels improve at once than the lower queue holds (`ESDF_QUEUE_CAPACITY`): the overflow waits in the
/// blocks' spill bits, nothing is lost, and the result matches the brute force; with a budget of one sweep's worth
/// of voxel visits the same grid takes several calls and ends at the same values.
#[test]
fn esdf_queue_overflow_spills_and_stays_exact() {
    use crate::config::map::ESDF_QUEUE_CAPACITY;
    let n = 40;
    let mut rng = rand_pcg::Pcg32::new(5, 17);
    let blocks = (n as usize / BLOCK_EDGE + 1).pow(3);
    let (mut b, mut i) = slices(blocks, (2 * blocks).next_power_of_two());
    let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
    let sites = random_site_map(&mut map, &mut rng, n, ESDF_QUEUE_CAPACITY / 8);
    let e = map.update_esdf();
    assert!(e.converged, "{e:?}");
    assert!(e.queue_overflows > 0, "the queue never overflowed: {e:?}");
    let (max_err, inexact, total) = compare_signed(&map, &sites, n);
    std::eprintln!("{e:?}: max error {max_err} voxels, {inexact} of {total} inexact");
    assert!(max_err < 0.1 && inexact * 100 <= total, "{max_err} {inexact}");
    let first: Vec<Option<Real>> = (0..n * n * n)
        .map(|k| map.site_distance_voxels([k % n - n / 2, (k / n) % n - n / 2, k / (n * n) - n / 2]))
        .collect();

    // The same grid with a budget of one sweep (esdf_max_sweeps = 1): resumable, same values at the end.
    let mut rng = rand_pcg::Pcg32::new(5, 17);
    let (mut b, mut i) = slices(blocks, (2 * blocks).next_power_of_two());
    let mut cfg = brute_force_config();
    cfg.esdf_max_sweeps = 1;
    let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
    let again = random_site_map(&mut map, &mut rng, n, ESDF_QUEUE_CAPACITY / 8);
    assert_eq!(again, sites);
    let mut calls = 1;
    let mut e = map.update_esdf();
    assert!(!e.converged, "{e:?}");
    while !e.converged {
        e = map.update_esdf();
        calls += 1;
        assert!(calls < 100, "{e:?}");
    }
    let (max_err, inexact, _) = compare_signed(&map, &sites, n);
    std::eprintln!("budget 1: {calls} calls, max error {max_err} voxels, {inexact} inexact");
    assert!(max_err < 0.1 && inexact * 100 <= total, "{max_err} {inexact}");
    let resumed: Vec<Option<Real>> = (0..n * n * n)
        .map(|k| map.site_distance_voxels([k % n - n / 2, (k / n) % n - n / 2, k / (n * n) - n / 2]))
        .collect();
    let differ = first.iter().zip(resumed.iter()).filter(|(a, b)| a != b).count();
    assert!(differ * 100 <= total, "{differ} voxels differ between one call and resumed calls");
}

/// Every compact box of blocks fills an index twice its size without running out of probes: the block hash
/// spreads neighbouring coordinates over the whole index (the index takes its low bits, so they must mix all
/// three coordinates). Boxes of 1-32 blocks a side, anywhere within +-1000 blocks of the origin (with the old
/// XOR of products alone, a box of 23 x 20 x 16 blocks at load 0.45 ran out of probes).
#[test]
fn compact_boxes_of_blocks_fit_an_index_twice_their_size() {
    let mut worst = 0usize;
    let mut state: u32 = 0x1234_5678;
    let mut next = move || {
        state ^= state << 13;
        state ^= state >> 17;
        state ^= state << 5;
        state
    };
    for case in 0..400 {
        let side = |r: u32| 1 + (r % 32) as i32;
        let (sx, sy, sz) = (side(next()), side(next()), side(next()));
        let origin = |r: u32| (r % 2001) as i32 - 1000;
        let o = [origin(next()), origin(next()), origin(next())];
        let n = (sx * sy * sz) as usize;
        let index_len = (2 * n).next_power_of_two();
        let (mut b, mut i) = slices(n, index_len);
        let mut map = Map::from_slices(MapConfig::DEFAULT, &mut b, &mut i).unwrap();
        for x in 0..sx {
            for y in 0..sy {
                for z in 0..sz {
                    let c = [o[0] + x, o[1] + y, o[2] + z];
                    let r = map.find_or_alloc_block(c);
                    assert!(r.is_ok(), "case {case}: box {sx} x {sy} x {sz} at {o:?}: {r:?} at {c:?}");
                }
            }
        }
        worst = worst.max(n);
    }
    assert!(worst > 10_000, "{worst}");
}

/// A long traverse keeps the map round the rover when its pool fills (`Map::forget_beyond`): the blocks beyond the
/// radius are gone from the index and the pool (their slots reused, every kept block still found at its slot), and
/// after the next ESDF update every kept voxel's distance is the brute force's over the kept sites only: no voxel
/// keeps a forgotten site.
#[test]
fn forgetting_far_blocks_keeps_the_index_and_the_esdf_exact_for_what_stays() {
    let mut rng = rand_pcg::Pcg32::new(17, 23);
    for trial in 0..4 {
        let (mut b, mut i) = slices(256, 512);
        let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
        let n = 24;
        let sites = random_site_map(&mut map, &mut rng, n, 12 + 4 * trial);
        assert!(map.update_esdf().converged);
        let before = map.blocks_used();
        let edge = BLOCK_EDGE as Real * map.config().voxel_size;
        let centre = Vec3::new(0.3 * trial as Real, -0.2, 5.0);
        let radius = 0.9 + 0.1 * trial as Real;
        let kept = |c: [i32; 3]| {
            let (x, y) = ((c[0] as Real + 0.5) * edge - centre.x, (c[1] as Real + 0.5) * edge - centre.y);
            x * x + y * y <= radius * radius
        };
        let block_of = |g: [i32; 3]| [split(g[0]).0, split(g[1]).0, split(g[2]).0];
        let coords: Vec<[i32; 3]> = (0..before).filter_map(|s| map.block_coord(s)).collect();
        // a centre or radius that is not a number forgets nothing (it would otherwise be farther than everything)
        assert_eq!(map.forget_beyond(&Vec3::new(Real::NAN, 0.0, 0.0), radius), 0);
        assert_eq!(map.forget_beyond(&centre, Real::NAN), 0);
        assert_eq!(map.blocks_used(), before);
        let forgotten = map.forget_beyond(&centre, radius);
        assert!(forgotten > 0 && forgotten < before, "trial {trial}: {forgotten} of {before}");
        assert_eq!(map.blocks_used(), before - forgotten);
        assert_eq!(coords.iter().filter(|c| !kept(**c)).count(), forgotten);
        for s in 0..map.blocks_used() {
            let c = map.block_coord(s).unwrap();
            assert!(kept(c), "block {c:?} should be gone");
            assert_eq!(map.find_block(c), Some(s), "block {c:?} not found at its slot");
        }
        for c in coords.iter().filter(|c| !kept(**c)) {
            assert_eq!(map.find_block(*c), None, "forgotten block {c:?} still indexed");
        }
        assert!(map.update_esdf().converged);
        let left: Vec<_> = sites.iter().copied().filter(|(g, _)| kept(block_of(*g))).collect();
        let dmax = map.config().esdf_max_distance / map.config().voxel_size;
        let (max_err, inexact, total) =
            compare_over_cube(&map, n, |g| if kept(block_of(g)) { brute_force(&left, g, dmax) } else { None });
        assert!(max_err < 0.1, "trial {trial}: max error {max_err} voxels");
        assert!(inexact * 100 <= total, "trial {trial}: {inexact} of {total} voxels inexact");
        // and the map goes on: a voxel can be observed again where a block was forgotten
        let far = coords.iter().copied().find(|c| !kept(*c)).unwrap();
        map.set_voxel([far[0] * BLOCK_EDGE as i32, far[1] * BLOCK_EDGE as i32, far[2] * BLOCK_EDGE as i32], 0.0, 1.0).unwrap();
        assert!(map.find_block(far).is_some());
    }
}

/// The raise region is marked on a coarse bit map over the changed blocks' bounding box, with coarser cells when the
/// box is large: two clusters of sites ~120 blocks apart on every axis (cells of 4 blocks), each with sites that
/// vanish, move and appear; after the update every voxel of both clusters matches the brute force over its own
/// cluster's sites (a region that missed a changed block would leave its voxels on vanished sites).
#[test]
fn far_apart_changes_are_raised_exactly_through_the_coarse_region_map() {
    let mut rng = rand_pcg::Pcg32::new(31, 4);
    let (mut b, mut i) = slices(1024, 2048);
    let mut map = Map::from_slices(brute_force_config(), &mut b, &mut i).unwrap();
    let (vs, t) = (map.config().voxel_size, map.config().truncation);
    let dmax = map.config().esdf_max_distance / vs;
    let n = 16;
    let origins = [[0, 0, 0], [480, 400, 440]];
    let mut sites: Vec<Vec<([i32; 3], i8)>> = vec![Vec::new(), Vec::new()];
    let at = |o: [i32; 3], g: [i32; 3]| [o[0] + g[0] - n / 2, o[1] + g[1] - n / 2, o[2] + g[2] - n / 2];
    for (o, cluster) in origins.iter().zip(sites.iter_mut()) {
        for k in 0..n * n * n {
            map.set_voxel(at(*o, [k % n, (k / n) % n, k / (n * n)]), t, 1.0).unwrap();
        }
        for _ in 0..8 {
            let g = at(*o, random_voxel(&mut rng, n).map(|c| c + n / 2));
            let w = ((rng.next_u32() % 199) as i32 - 99) as i8;
            map.set_voxel(g, w as Real * 0.01 * vs, 1.0).unwrap();
            cluster.retain(|(s, _)| *s != g);
            cluster.push((g, w));
        }
    }
    assert!(map.update_esdf().converged);
    for (o, cluster) in origins.iter().zip(sites.iter_mut()) {
        for _ in 0..3 {
            let (g, _) = cluster.remove(0);
            map.set_voxel(g, t, 1.0).unwrap();
        }
        for (g, w) in cluster.iter_mut().take(2) {
            *w = if *w > 0 { *w - 50 } else { *w + 50 };
            map.set_voxel(*g, *w as Real * 0.01 * vs, 1.0).unwrap();
        }
        let g = at(*o, random_voxel(&mut rng, n).map(|c| c + n / 2));
        map.set_voxel(g, 0.0, 1.0).unwrap();
        cluster.retain(|(s, _)| *s != g);
        cluster.push((g, 0));
    }
    let e = map.update_esdf();
    assert!(e.converged, "{e:?}");
    for (o, cluster) in origins.iter().zip(sites.iter()) {
        let (max_err, inexact, total) = compare_over_cube_at(&map, *o, n, |g| {
            let inside = map.tsdf_voxel(g).is_some_and(|(d, _)| d < 0.0);
            brute_force_signed(cluster, g, inside, dmax)
        });
        std::eprintln!("cluster at {o:?}: {e:?}, max error {max_err} voxels, {inexact} of {total} inexact");
        assert!(max_err < 1.0 && inexact * 100 <= total, "cluster at {o:?}: {max_err} {inexact}");
    }
}

/// The cell bound (`DistanceField::query_with_cell_bound`), which lets the tether's sweep lines skip samples: on a
/// grazing slope's map (cells observed, filled under the surface and between rays, and unknown), every point of a
/// sample's cell is of the same kind as the sample (known or unknown), and no known point of the cell is closer
/// than the bound; so also through `UnobservedAsFree`, where an unknown cell reads free throughout.
#[test]
fn the_cell_bound_holds_everywhere_in_the_cell() {
    let cfg = MapConfig::with_voxel_size(0.05);
    let vs = cfg.voxel_size;
    let (mut b, mut i) = slices(2048, 4096);
    let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
    grazing_plane_map(&mut map, (35.0 as Real).to_radians(), 0.4);
    let mut rng = rand_pcg::Pcg32::new(5, 9);
    let mut unit = || (rng.next_u32() >> 8) as Real / (1u32 << 24) as Real;
    let (mut known, mut unknown, mut filled) = (0, 0, 0);
    for _ in 0..3000 {
        // around the observed square, above and below the plane and beyond it
        let p = Vec3::new(-0.9 + 1.8 * unit(), -0.9 + 1.8 * unit(), -0.8 + 1.3 * unit());
        let Some(key) = map.cell_key(&p) else { panic!("{p:?} has no cell") };
        let (q, lower) = map.query_with_cell_bound(&p);
        assert_eq!(q, map.query(&p));
        let free = UnobservedAsFree(&map);
        let (qf, lower_free) = free.query_with_cell_bound(&p);
        assert_eq!((qf, free.cell_key(&p)), (free.query(&p), Some(key)));
        match q {
            DistanceQuery::Known { .. } => known += 1,
            DistanceQuery::Unknown => unknown += 1,
        }
        filled += usize::from(
            (0..8).any(|k| map.esdf_voxel([key[0] + (k & 1), key[1] + ((k >> 1) & 1), key[2] + (k >> 2)]).is_none())
                && matches!(q, DistanceQuery::Known { .. }),
        );
        assert_eq!(lower.is_some(), matches!(q, DistanceQuery::Known { .. }), "{p:?}");
        assert!(lower_free.is_some(), "{p:?}: every cell is known through UnobservedAsFree");
        for _ in 0..20 {
            // a point of the same cell: between the voxel centres of its lowest and highest corners
            let at = |c: i32, f: Real| (c as Real + 0.5 + f) * vs;
            let p2 = Vec3::new(at(key[0], unit()), at(key[1], unit()), at(key[2], unit()));
            assert_eq!(map.cell_key(&p2), Some(key), "{p2:?}");
            for (q2, q, lower) in [(map.query(&p2), q, lower), (free.query(&p2), qf, lower_free)] {
                match (q2, q) {
                    (DistanceQuery::Known { distance, .. }, DistanceQuery::Known { .. }) => {
                        let lower = lower.unwrap_or(Real::INFINITY);
                        assert!(distance >= lower, "{p2:?}: {distance} below the cell's bound {lower} from {p:?}");
                    }
                    (DistanceQuery::Unknown, DistanceQuery::Unknown) => {}
                    _ => panic!("{p2:?} is {q2:?}, {p:?} in the same cell is {q:?}"),
                }
            }
        }
    }
    std::eprintln!("{known} known ({filled} of them on filled cells), {unknown} unknown samples");
    assert!(known > 300 && unknown > 300 && filled > 10, "{known} known, {filled} filled, {unknown} unknown");
}

/// The site distances' square roots (`esdf::integer_sqrt`: a compile-time table, then `libm::sqrtf`) have the bits
/// of `libm::sqrtf` for every squared offset up to 3 * 127^2 (the largest an `i8` offset can make), and the
/// table's own rounding (`rounded_sqrt`) is right up to 2^24.
#[test]
fn the_site_square_roots_are_libms_bit_for_bit() {
    for n in 0..=3 * 127 * 127 {
        let (got, want) = (esdf::integer_sqrt(n), libm::sqrtf(n as Real));
        assert_eq!(got.to_bits(), want.to_bits(), "sqrt({n}): {got} vs {want}");
    }
    for n in (1..1u32 << 24).step_by(997).chain([(1 << 24) - 1, 4_194_303, 16_769_025]) {
        let (got, want) = (esdf::rounded_sqrt(n), libm::sqrtf(n as Real));
        assert_eq!(got.to_bits(), want.to_bits(), "rounded_sqrt({n}): {got} vs {want}");
    }
    // outside its domain it returns at once: 0 for 0, NaN from 2^24 on
    assert_eq!(esdf::rounded_sqrt(0).to_bits(), 0);
    assert!(esdf::rounded_sqrt(1 << 24).is_nan() && esdf::rounded_sqrt(u32::MAX).is_nan());
}
