//! The onboard map (firmware::map) against the simulator's ground truth (host-sim worlds), through the same path
//! as flight: sensor scans -> protocol chunks -> TSDF integration -> ESDF.

use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery, Map};
use host_sim::mapcheck::{build_map, drive_poses, esdf_errors, host_storage, CheckConfig, CheckReport};
use host_sim::world::crater::{CraterWall, CraterWallParams};
use host_sim::world::ledge::LedgeWorld;
use host_sim::world::World;

fn check(world: &dyn World, from: [f64; 2], to: [f64; 2], voxel: Real) -> CheckReport {
    let mut cfg = CheckConfig::at_voxel_size(voxel);
    cfg.pool_blocks = 8192;
    cfg.sample_stride = 5;
    cfg.sensor.resolution_deg = 1.5;
    let poses = drive_poses(world, from, to, 1.5, 0.35, &[-30.0, 30.0]);
    let (mut b, mut i) = host_storage(cfg.pool_blocks);
    let mut map = Map::from_slices(cfg.map, &mut b, &mut i).unwrap();
    let mut rep = build_map(world, &poses, &cfg, &mut map);
    esdf_errors(world, &map, &cfg, &mut rep);
    eprintln!("{}: all {}\n  near {}\n  scans {} points {} sign errors {} far {}", world.name(), rep.all, rep.near, rep.scans, rep.points, rep.sign_errors, rep.sign_errors_far);
    // Unknown space stays unknown: deep inside the terrain, nothing has been observed.
    let deep = Vec3::new(from[0] as Real, from[1] as Real, world.height_at(from[0] as Real, from[1] as Real).unwrap() - 1.0);
    assert_eq!(map.query(&deep), DistanceQuery::Unknown);
    rep
}

/// Error budget, from the map's construction (not from its output): the TSDF is a projective distance averaged
/// over rays (a voxel-scale error on slopes), sites sit on voxel centres within one voxel of the surface, and
/// sensor noise is 5 mm. Near the surface the ESDF must be within one voxel RMS and two voxels at the 95th
/// percentile. Negative TSDF is written only within the truncation distance behind a hit, so a sign error can
/// only occur within `truncation + voxel` of the surface (at convex edges and thin rocks), and must be rare.
fn assert_budget(rep: &CheckReport, voxel: f64, what: &str) {
    assert!(rep.esdf_all_converged, "{what}: ESDF did not converge");
    assert_eq!(rep.voxels_dropped, 0, "{what}: pool too small");
    assert!(rep.near.n > 1000, "{what}: only {} near-surface samples", rep.near.n);
    assert!(rep.near.rms < voxel, "{what}: near-surface {}", rep.near);
    assert!(rep.near.p95 < 2.0 * voxel, "{what}: near-surface {}", rep.near);
    assert_eq!(rep.sign_errors_far, 0, "{what}: sign errors far from the surface");
    assert!(rep.sign_errors * 100 < rep.all.n, "{what}: {} sign errors in {}", rep.sign_errors, rep.all.n);
}

#[test]
fn crater_wall_esdf_matches_ground_truth_at_10cm() {
    let w = CraterWall::new(CraterWallParams::default()).unwrap();
    let rep = check(&w, [-3.0, 0.0], [6.0, 0.0], 0.1);
    assert_budget(&rep, 0.1, "crater wall");
}

#[test]
fn ledge_esdf_matches_ground_truth_at_10cm() {
    let w = LedgeWorld::new();
    let rep = check(&w, [-3.5, 0.0], [6.0, 0.0], 0.1);
    assert_budget(&rep, 0.1, "ledge");
}
