//! The general true tether against the closed forms of `truth::tether` (lip, pole) and against brute force.

use super::*;
use crate::terrain::Heightmap;
use crate::truth::tether::{around_pole, true_tether, Wrap};
use crate::world::heightmap::HeightmapWorld;
use crate::world::ledge::{LedgeWorld, ROOT_ANCHOR_TEST1, ROOT_ANCHOR_TEST2, START_AXLE};
use crate::world::World;

const ALL: ([f64; 3], [f64; 3]) = ([-1e9; 3], [1e9; 3]);

/// Drive the tether's end through `waypoints` (after starting straight from the root at the first).
fn drive(w: &WrapEdges, root: P3, waypoints: &[P3]) -> TautTether {
    let mut t = TautTether::shortest(w, root, waypoints[0], SHORTEST_SAMPLE_M).expect("start");
    for p in &waypoints[1..] {
        t.update(w, *p).expect("update");
    }
    t
}

#[test]
fn over_the_lip_matches_the_closed_form() {
    let world = LedgeWorld::new();
    let w = WrapEdges::new(&world.exact_geometry(), ALL).expect("edges");
    for end in [[1.0, 0.0, 3.0], [1.6, 1.5, 2.1], [2.2, -2.0, 1.3], [4.0, 0.5, 0.35]] {
        let t = drive(&w, ROOT_ANCHOR_TEST1, &[START_AXLE, [-0.3, 0.0, 4.35], [0.4, 0.0, 3.95], end]);
        let oracle = true_tether(&world, ROOT_ANCHOR_TEST1, end, None).expect("closed form");
        assert_eq!(t.contacts.len(), 1, "{end:?}: {t:?}");
        let c = t.last_anchor(&w);
        // Tolerances: the 1 mm contact offset; the closed form's contact is on the edge itself.
        assert!(dist(c, oracle.contacts[0]) < 0.003, "{end:?}: contact {c:?} vs {:?}", oracle.contacts[0]);
        assert!((t.length(&w) - oracle.length).abs() < 0.002, "{end:?}: {} vs {}", t.length(&w), oracle.length);
    }
}

#[test]
fn round_the_pole_matches_the_closed_form() {
    let world = LedgeWorld::with_pole();
    let w = WrapEdges::new(&world.exact_geometry(), ALL).expect("edges");
    // From the start, north of the pole, behind it, then south behind it: the tether is dragged round the pole's
    // north side (counter-clockwise seen from above, going from the root).
    let path = [START_AXLE, [-1.5, 1.0, 4.35], [-3.5, 1.0, 4.35], [-3.5, 0.0, 4.35], [-3.2, -0.8, 4.35]];
    let t = drive(&w, ROOT_ANCHOR_TEST2, &path);
    let end = path[path.len() - 1];
    let oracle = around_pole(&world, ROOT_ANCHOR_TEST2, end, Wrap::Ccw).expect("closed form");
    assert!(t.contacts.len() >= 2, "wrapped on several polygon edges: {t:?}");
    // Tolerance: the 64-gon (0.12 % of the wrapped arc, under 1 mm here) and the 1 mm offsets.
    assert!((t.length(&w) - oracle.length).abs() < 0.005, "{} vs {}", t.length(&w), oracle.length);
    // The exit point: a corner of the 64-gon, at most one side (2 r tan(pi / 64) = 2.5 cm) from the tangent point.
    let side = 2.0 * 0.25 * (core::f64::consts::PI / 64.0).tan();
    assert!(dist(t.last_anchor(&w), oracle.contacts[1]) < side, "{:?} vs {:?}", t.last_anchor(&w), oracle.contacts[1]);
    // Going back the same way unwraps it again.
    let mut back = t.clone();
    for p in path.iter().rev().skip(1) {
        back.update(&w, *p).expect("update");
    }
    assert!(back.contacts.is_empty(), "{back:?}");
}

#[test]
fn shortest_matches_brute_force_among_rocks() {
    // Ground and two boxes; the straight tether to the rover is blocked by both.
    let geom = ExactGeometry {
        solids: vec![
            Solid::Ground { z: 0.0 },
            Solid::vertical_prism(&[[1.0, -0.5], [2.0, -0.5], [2.0, 0.6], [1.0, 0.6]], -0.2, 1.5),
            Solid::vertical_prism(&[[3.0, -0.3], [3.6, -0.4], [3.8, 0.5], [3.1, 0.4]], -0.2, 1.0),
        ],
    };
    let w = WrapEdges::new(&geom, ALL).expect("edges");
    let (root, end) = ([0.0, 0.1, 1.2], [5.0, 0.0, 0.35]);
    assert!(!w.free(root, end));
    let t = TautTether::shortest(&w, root, end, SHORTEST_SAMPLE_M).expect("tether");
    // Brute force: Dijkstra over points 4 cm apart on every edge, no tightening.
    let brute = TautTether::shortest_untightened(&w, root, end, 0.04).expect("brute");
    let len = t.length(&w);
    assert!(len <= brute + 0.003, "{len} vs brute force {brute}");
    assert!(brute - len < 0.03, "{len} vs brute force {brute}");
    assert!(t.points(&w).windows(2).all(|p| w.free(p[0], p[1])));
}

#[test]
fn dem_rendering_of_the_lip_matches_the_closed_form() {
    // The ledge rendered as a 0.25 m DEM whose post columns include x = 0 (the lip).
    let s = 0.25;
    let (nx, ny) = (65usize, 49usize);
    let ledge = LedgeWorld::new();
    let mut heights = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (-8.0 + i as f64 * s, -6.0 + j as f64 * s);
            heights.push(Some(ledge.height_f64(x, y)));
        }
    }
    let hm = Heightmap { width: nx, height: ny, spacing_m: s, heights_m: heights };
    let world = HeightmapWorld::new("ledge-dem", &hm, 1.0, 1.0).expect("dem");
    // The DEM is centred on the origin: x = -8 becomes -8.0 + 8.0 - 8.0 ... its post 32 is at x = 0.
    let w = WrapEdges::new(&world.exact_geometry(), ([-7.5, -3.0, -1.0], [4.0, 3.0, 8.0])).expect("edges");
    let end = [1.6, 0.5, 2.1];
    let t = drive(&w, ROOT_ANCHOR_TEST1, &[START_AXLE, [-0.3, 0.0, 4.35], [0.4, 0.0, 3.95], end]);
    let oracle = true_tether(&ledge, ROOT_ANCHOR_TEST1, end, None).expect("closed form");
    assert!((t.length(&w) - oracle.length).abs() < 0.003, "{} vs {}", t.length(&w), oracle.length);
    assert!(dist(t.last_anchor(&w), oracle.contacts[0]) < 0.01, "{:?} vs {:?}", t.last_anchor(&w), oracle.contacts[0]);
}

