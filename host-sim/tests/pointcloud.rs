//! The point-cloud readers and the voxel thinning on real data nobody here made: `simple.las` / `simple.laz` from
//! the PyPI package laspy 2.7.0 (BSD-2-Clause; `tests/data/pointcloud/README.md`).
//!
//! The expected count and bounds come from the file's own header bytes, read here by hand (LAS 1.2 header layout:
//! legacy point count at byte 107, scale at 131, offset at 155, max/min x, y, z at 179), not from the reader under
//! test. Python's `struct` on the same bytes gave: 1065 points, x 635619.85..638982.55, y 848899.70..853535.43,
//! z 406.59..586.38, first point (637012.24, 849028.31, 431.66).
//!
//!     cargo test -p host-sim --test pointcloud -- --nocapture   # prints the thinning counts

use host_sim::terrain::pointcloud::thin::{thin_to_capacity, Representative, ThinOptions};
use host_sim::terrain::pointcloud::{load_point_cloud, PointCloudOptions, FLIGHT_SCAN_CAPACITY};
use std::path::{Path, PathBuf};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/pointcloud").join(name)
}

fn f64_at(b: &[u8], at: usize) -> f64 {
    f64::from_le_bytes(b[at..at + 8].try_into().unwrap())
}

/// (point count, min, max, scale) from a LAS 1.2 header.
fn header(b: &[u8]) -> (usize, [f64; 3], [f64; 3], [f64; 3]) {
    assert_eq!(&b[..4], b"LASF");
    let n = u32::from_le_bytes(b[107..111].try_into().unwrap()) as usize;
    let scale = [0, 1, 2].map(|k| f64_at(b, 131 + 8 * k));
    // max x, min x, max y, min y, max z, min z
    let max = [0, 1, 2].map(|k| f64_at(b, 179 + 16 * k));
    let min = [0, 1, 2].map(|k| f64_at(b, 187 + 16 * k));
    (n, min, max, scale)
}

#[test]
fn real_las_and_laz_match_their_header() {
    let las_path = data("simple.las");
    let bytes = std::fs::read(&las_path).unwrap();
    let (n, min, max, scale) = header(&bytes);
    assert_eq!(n, 1065);
    let las = load_point_cloud(&las_path, &PointCloudOptions::default()).unwrap();
    assert_eq!(las.points.len(), n);
    assert_eq!(las.non_finite_skipped, 0);
    let (lo, hi) = las.bounds().unwrap();
    for k in 0..3 {
        assert!((lo[k] - min[k]).abs() <= scale[k] / 2.0, "axis {k}: min {} vs header {}", lo[k], min[k]);
        assert!((hi[k] - max[k]).abs() <= scale[k] / 2.0, "axis {k}: max {} vs header {}", hi[k], max[k]);
    }
    let first = las.points[0];
    for (got, want) in first.iter().zip([637012.24, 849028.31, 431.66]) {
        assert!((got - want).abs() < 1e-6, "{first:?}");
    }
    let laz_path = data("simple.laz");
    let laz_bytes = std::fs::read(&laz_path).unwrap();
    assert_eq!(header(&laz_bytes).0, n);
    let laz = load_point_cloud(&laz_path, &PointCloudOptions::default()).unwrap();
    assert_eq!(laz.points, las.points, "LAZ decodes to the LAS file's points");
}

#[test]
fn real_cloud_thins_to_capacity() {
    let cloud = load_point_cloud(&data("simple.las"), &PointCloudOptions::default()).unwrap();
    // 1065 points fit the flight scan: kept as they are
    let kept = thin_to_capacity(&cloud.points, &ThinOptions::default()).unwrap();
    assert_eq!((kept.points.len(), kept.voxel_edge), (1065, None));
    const { assert!(FLIGHT_SCAN_CAPACITY >= 1065) };
    for rep in [Representative::NearestToCentre, Representative::Centroid] {
        for capacity in [512, 100, 10, 1] {
            let t = thin_to_capacity(&cloud.points, &ThinOptions { capacity, representative: rep }).unwrap();
            let edge = t.voxel_edge.unwrap();
            println!("simple.las -> capacity {capacity} ({rep:?}): {} points, voxel edge {edge:.3} m", t.points.len());
            assert!(!t.points.is_empty() && t.points.len() <= capacity);
            let half_diagonal = edge * 3f64.sqrt() / 2.0;
            for p in &t.points {
                let d = cloud.points.iter().map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt());
                assert!(d.fold(f64::INFINITY, f64::min) <= half_diagonal * (1.0 + 1e-12), "{p:?}");
            }
            let again = thin_to_capacity(&cloud.points, &ThinOptions { capacity, representative: rep }).unwrap();
            assert_eq!(again, t, "deterministic");
        }
    }
}

/// Regression (fuzz target `las`): `simple.laz` with 13 bytes changed (header, chunk data) made the `laz`
/// crate's arithmetic decoder fail a `debug_assert` (decoders.rs:284, a symbol out of range): the reader returns
/// an error (the caught panic as `DecoderPanic` where debug assertions are on, else the crate's error), and never
/// unwinds into the caller.
#[test]
fn corrupt_laz_chunk_data_is_an_error() {
    let mut b = std::fs::read(data("simple.laz")).unwrap();
    let changes: [(usize, u8); 13] = [
        (7, 1),
        (14, 14),
        (2913, 10),
        (2914, 132),
        (2915, 157),
        (2916, 151),
        (9320, 94),
        (9321, 130),
        (9322, 131),
        (9323, 93),
        (9324, 87),
        (9325, 41),
        (12509, 41),
    ];
    for (at, v) in changes {
        b[at] = v;
    }
    let r = host_sim::terrain::pointcloud::las::parse_las(&b, &PointCloudOptions::default());
    let e = r.expect_err("corrupt LAZ accepted");
    println!("corrupt simple.laz: {e}");
}
