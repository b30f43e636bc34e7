use firmware::config::rover::RoverParams;
use firmware::geom::{Real, Vec3};
use firmware::plan::tethered::*;
use firmware::tether::{Anchor, AnchorHistory};
use host_sim::campaign::Truth;
use host_sim::world::ledge::*;

#[test]
fn debug_direct() {
    let w = LedgeWorld::new();
    let t = Truth(&w);
    let b = PlanBounds { min: [-5.0, -5.0, -0.5], max: [7.5, 5.0, 7.5] };
    let mut p = TetherSpaceParams::DEFAULT;
    p.min_stability_margin = 0.0;
    let sp = TetherSpace::new(&t, b, RoverParams::AXEL, p).unwrap();
    let a = sp.settle_state(-1.5, 0.0, 0.0).unwrap();
    let g = sp.settle_state(6.0, 0.0, 0.0).unwrap();
    for (name, root) in [("t1", ROOT_ANCHOR_TEST1), ("t2", ROOT_ANCHOR_TEST2)] {
        let mut h = AnchorHistory::new(Anchor::root(Vec3::new(root[0] as Real, root[1] as Real, root[2] as Real)));
        // walk along
        let mut prev = a;
        for i in 1..=38 {
            let x = -1.5 + 0.2 * i as f32;
            let s = match sp.settle_state(x, 0.0, 0.0) { Ok(s) => s, Err(e) => { eprintln!("{name} x {x}: settle {e:?}"); continue } };
            match sp.check(&prev, &h, &s) {
                Ok(nh) => { let m = sp.stable_with(&s.settled, &nh); eprintln!("{name} x {x:.1}: ok anchors {} margin {:?}", nh.len(), m); h = nh; }
                Err(e) => { eprintln!("{name} x {x:.1}: {e:?} margin {:?}", sp.stable_with(&s.settled, &h)); }
            }
            prev = s;
        }
        eprintln!("{name} direct: {:?}", sp.check(&a, &AnchorHistory::new(Anchor::root(Vec3::new(root[0] as Real, root[1] as Real, root[2] as Real))), &g).map(|h| h.len()));
    }
}
