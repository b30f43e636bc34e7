//! Host timings of the traversability checks (Paton et al. IV): `settle`, `predict_anchors`, stability solves.
//! Run: `cargo bench -p host-sim --bench traversability`. Problems: the analytic 55-degree ledge
//! (`host_sim::world::ledge`), exact signed distance as the map. Measured numbers: see the `firmware::stability`
//! module docs.

use core::hint::black_box;
use criterion::{criterion_group, criterion_main, Criterion};
use firmware::config::rover::RoverParams;
use firmware::geom::Vec3;
use firmware::geom::p3::to_vec3;
use firmware::rover::{
    boom_in_contact, boom_inline_angle, check_pose_stability, settle, stability_problem, SettleOutcome,
};
use firmware::stability::check_stability;
use firmware::tether::{predict_anchors, Anchor, AnchorHistory};
use host_sim::world::ledge::{LedgeWorld, ROOT_ANCHOR_TEST1};

fn benches(c: &mut Criterion) {
    let w = LedgeWorld::new();
    let params = RoverParams::AXEL;
    let top = Vec3::new(-1.5, 0.0, 4.0);
    let slope = Vec3::new(1.4, 0.0, w.height_f64(1.4, 0.0) as f32);
    c.bench_function("settle/ledge_top", |b| b.iter(|| settle(&w, black_box(&top), 0.0, &params)));
    c.bench_function("settle/slope55", |b| b.iter(|| settle(&w, black_box(&slope), 0.0, &params)));

    let SettleOutcome::Settled(s) = settle(&w, &slope, 0.0, &params) else { panic!("settle") };
    let lip = Vec3::new(0.0, 0.0, 4.0);
    let beta = boom_inline_angle(&s, &lip);
    let prob = stability_problem(&s, beta, None, Some(&lip), &params);
    c.bench_function("stability/lp_solve_2_contacts", |b| b.iter(|| check_stability(black_box(&prob))));
    // the boom resting on the slope: three contacts (two wheels with moments, the boom tip as a point contact)
    if let Some(bc) = boom_in_contact(&w, &s, beta, &params) {
        let prob3 = stability_problem(&s, bc.angle_rad, Some(&bc), Some(&lip), &params);
        c.bench_function("stability/lp_solve_3_contacts", |b| b.iter(|| check_stability(black_box(&prob3))));
    }
    c.bench_function("stability/check_pose_inline_and_contact", |b| {
        b.iter(|| check_pose_stability(&w, black_box(&s), Some(&lip), &params))
    });

    let root = AnchorHistory::new(Anchor::root(to_vec3(ROOT_ANCHOR_TEST1)));
    // a 10 cm step on the ledge top (no contact) and the step on the slope where the lip anchor attaches
    let (a0, a1) = (Vec3::new(-1.0, 0.3, 4.35), Vec3::new(-0.9, 0.3, 4.35));
    c.bench_function("predict_anchors/free_step", |b| {
        b.iter(|| {
            let mut out = AnchorHistory::default();
            predict_anchors(&w, black_box(&root), &a0, &a1, &mut out)
        })
    });
    let (b0, b1) = (Vec3::new(0.2, 0.3, 4.0), Vec3::new(0.6, 0.3, 3.6));
    c.bench_function("predict_anchors/lip_attach_step", |b| {
        b.iter(|| {
            let mut out = AnchorHistory::default();
            predict_anchors(&w, black_box(&root), &b0, &b1, &mut out)
        })
    });
}

criterion_group!(traversability, benches);
criterion_main!(traversability);
