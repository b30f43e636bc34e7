//! Homotopy routes on real DEMs (issue 20): the flight code's planes, unfolding and obstacles from a real tile, the
//! route mapped back to the world, its tether checked here against the payout by summing the 3D polyline.

use firmware::plan::homotopy::dem::RouteError;
use host_sim::homotopy::dem::{preset, run, DemRun};

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

fn axel_route(r: &DemRun) -> &firmware::plan::homotopy::dem::WorldRoute {
    let ax = &r.runs[1];
    assert_eq!(ax.label, "Axel");
    match &ax.route {
        Some(Ok(w)) => w,
        other => panic!("no Axel route: {other:?}"),
    }
}

/// The HiRISE scarp: rim and wall found, a route whose taut tether wraps two different obstacles, its 3D tether
/// length (summed here) within the payout and equal to the unfolded SHP length (unfolding is an isometry), every
/// tether point on its plane within the DEM's relief, and a payout below that length refused with the length.
#[test]
fn hirise_route_wraps_two_obstacles_within_the_payout() {
    let s = preset("hirise").unwrap();
    let r = run(&s).unwrap();
    assert!(r.descent.planes.len() >= 2);
    let w = axel_route(&r);
    let plan = r.runs[1].plan.as_ref().unwrap();
    let summed: f64 = w.tether.windows(2).map(|p| dist(p[0], p[1])).sum();
    assert!(summed <= s.max_payout_m, "{summed} > {}", s.max_payout_m);
    assert!((summed - plan.shp.length()).abs() < 1e-6, "{summed} vs {}", plan.shp.length());
    let mut obstacles: Vec<u8> = plan.anchors.iter().filter_map(|a| a.obstacle).collect();
    obstacles.dedup();
    assert!(obstacles.len() >= 2, "anchors {:?}", plan.anchors);
    assert_eq!(w.anchors.len(), plan.anchors.len());
    // Ends of the tether: a0 and g in the world.
    assert!(dist(w.tether[0], r.descent.a0_world) < 1e-6);
    assert!(dist(*w.tether.last().unwrap(), r.descent.g_world) < 1e-6);
    // Waypoints lie on the DEM.
    for p in w.waypoints.iter() {
        let z = r.tile.height_at(p[0], p[1]).unwrap();
        assert!((p[2] - z).abs() < 1e-9);
    }
    let short = run(&host_sim::homotopy::dem::DemScenario { max_payout_m: 0.9 * summed, ..s }).unwrap();
    match &short.runs[1].route {
        Some(Err(RouteError::TetherTooLong { needed_m, max_payout_m })) => {
            assert!((needed_m - summed).abs() < 1e-6 && *max_payout_m < *needed_m);
        }
        other => panic!("expected a payout refusal, got {other:?}"),
    }
}

/// Kepler's west wall at 1:400: rim, wall and floor with the wall tether-demand at mu 0.4 and steeper than both
/// tether-free planes; a route within the payout; Axel's holding limit never beyond the point mass's (Coulomb's cone,
/// `asin(mu cot alpha)`) and within 2 deg of `asin(cos(pi/8) mu cot alpha)`: Axel faces along the tether, so the
/// lateral friction it needs points at a facet of the stability LP's friction octagon, which reaches `cos(pi/8) mu`
/// there (`firmware::stability`).
#[test]
fn kepler_rim_wall_floor_route() {
    let s = preset("kepler").unwrap();
    let r = run(&s).unwrap();
    let d = &r.descent;
    assert_eq!(d.planes.len(), 3);
    assert_eq!(d.reference, 1);
    let wall = d.planes[1].plane.slope_rad();
    assert!(wall > s.mu.atan() && wall > d.planes[0].plane.slope_rad() && wall > d.planes[2].plane.slope_rad());
    let w = axel_route(&r);
    let summed: f64 = w.tether.windows(2).map(|p| dist(p[0], p[1])).sum();
    assert!(summed <= s.max_payout_m);
    let pm = firmware::plan::homotopy::planes::theta_max(wall, s.mu);
    let facet = firmware::plan::homotopy::planes::theta_max(wall, s.mu * (core::f64::consts::PI / 8.0).cos());
    let axel = r.axel.theta_max_rad;
    assert!(axel <= pm, "Axel {axel} beyond the point mass {pm}");
    assert!((axel - facet).abs() < 2f64.to_radians(), "Axel {axel} vs the octagon's facet limit {facet} (point mass {pm})");
}

/// The Mars Yard's slopes stay below atan(mu) over 2 m bands: a stated refusal, not a route.
#[test]
fn marsyard_is_refused_for_want_of_tether_demand() {
    let err = run(&preset("marsyard").unwrap()).err().unwrap();
    assert!(err.contains("NoTetherDemand"), "{err}");
}
