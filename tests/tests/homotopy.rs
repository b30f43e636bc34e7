//! Homotopy planning on tether-demand planes: scenarios B and C, oracle-checked properties.
use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::plan::{preplan, PlanReport, PlannerParams, Workspace};
use host_sim::homotopy::scenarios::*;

#[test]
fn explore_b() {
    for s in [scenario_b(), scenario_c()] {
    let mut btm = Box::new(Btm::new());
    let obs: Vec<&[_]> = s.known.iter().map(|o| o.as_slice()).collect();
    let r = btm.build(&s.plane, &obs).unwrap();
    println!("build {:?} tris {}", r, btm.triangle_count());
    btm.check_invariants().unwrap();
    let mut ws = Box::new(Workspace::default());
    let mut lc = heapless::Vec::new();
    let mut rep = PlanReport::default();
    let plan = preplan(&btm, &s.model, &PlannerParams::default(), &mut ws, s.a0, s.g, &mut lc, &mut rep).unwrap();
    for v in rep.examined.iter() {
        println!("{:?}", v);
    }
    println!("{:?}", rep.search);
    if let Some(p) = plan {
        println!("shp {:?}\nanchors {:?}\ndescent {:?}", p.shp.pts, p.anchors, p.descent);
    }
    }
}
#[test]
fn debug_b() {
    let s = scenario_b();
    let mut btm = Box::new(Btm::new());
    let obs: Vec<&[_]> = s.known.iter().map(|o| o.as_slice()).collect();
    btm.build(&s.plane, &obs).unwrap();
    for v in 0..10u16 { println!("{} {:?} nb {:?}", v, btm.vertex(v).map(|x| x.p), btm.neighbours(v)); }
    for (i,t) in btm.triangles() { println!("t{} {:?} {:?}", i, t.v, t.nbr); }
}
