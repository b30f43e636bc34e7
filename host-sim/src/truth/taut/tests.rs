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
    // Brute force: the shortest path (A*) over points 4 cm apart on every edge, no tightening.
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


/// On a variant (a 45-degree, 3 m ledge with two poles), the general tether over the lip and round the smaller,
/// off-centre pole matches the closed forms with the variant's own lip height and pole.
#[test]
fn a_variants_lip_and_second_pole_match_the_closed_forms() {
    use crate::truth::tether::around;
    use crate::world::ledge::{LedgeShape, Pole};
    let shape = LedgeShape { slope_deg: 45.0, height_m: 3.0, ..LedgeShape::PATON };
    let poles = [
        Pole { centre_xy: [-2.5, 1.5], radius_m: 0.25, height_m: 6.0 },
        Pole { centre_xy: [-3.0, -1.5], radius_m: 0.15, height_m: 6.0 },
    ];
    let world = LedgeWorld::custom(shape, &poles).expect("a valid variant");
    let w = WrapEdges::new(&world.exact_geometry(), ALL).expect("edges");
    // over the lip, test 1's root lowered with the top
    let root = [-6.4, 0.0, 5.35];
    let start = [-1.5, 0.0, 3.35];
    for end in [[1.0, 0.0, 2.35], [2.0, 1.0, 1.35]] {
        let t = drive(&w, root, &[start, [-0.3, 0.0, 3.35], [0.4, 0.0, 3.0], end]);
        let oracle = true_tether(&world, root, end, None).expect("closed form");
        assert_eq!(t.contacts.len(), 1, "{end:?}: {t:?}");
        assert!((oracle.contacts[0][2] - 3.0).abs() < 1e-12, "the lip is at the variant's height");
        assert!(dist(t.last_anchor(&w), oracle.contacts[0]) < 0.003, "{end:?}");
        assert!((t.length(&w) - oracle.length).abs() < 0.002, "{end:?}: {} vs {}", t.length(&w), oracle.length);
    }
    // round the second pole (south of the centre line): from the front root, behind it on its north side
    let root = [6.7, 0.0, 5.35];
    let path = [start, [-2.0, -0.8, 3.35], [-3.6, -0.8, 3.35], [-3.6, -1.5, 3.35], [-3.4, -2.2, 3.35]];
    let t = drive(&w, root, &path);
    let end = path[path.len() - 1];
    let oracle = around(&world, &poles[1], root, end, Wrap::Ccw).expect("closed form");
    assert!(t.contacts.len() >= 2, "wrapped on several polygon edges: {t:?}");
    assert!((t.length(&w) - oracle.length).abs() < 0.005, "{} vs {}", t.length(&w), oracle.length);
    // The exit point: in plan, a corner of the 64-gon at most one side from the tangent point; in height within
    // 5 cm (the contacts' heights along a wrap converge slowly under the tightening, and the length, checked above
    // to 5 mm, depends on them only to second order).
    let side = 2.0 * 0.15 * (core::f64::consts::PI / 64.0).tan();
    let (e, o) = (t.last_anchor(&w), oracle.contacts[1]);
    assert!(dist([e[0], e[1], 0.0], [o[0], o[1], 0.0]) < side && (e[2] - o[2]).abs() < 0.05, "{e:?} vs {o:?}");
    // and the closed form's best candidate over both poles is that wrap
    let best = true_tether(&world, root, end, Some(Wrap::Ccw)).expect("closed form");
    assert!((best.length - oracle.length).abs() < 1e-12);
}
