//! Tether-aware traversability on the 55-degree ledge (Paton et al. section VI-A, `shared/SCENARIOS.md` A):
//! anchor prediction against the simulator's true tether, and stability of tests 1-3.

use firmware::config::rover::RoverParams;
use firmware::geom::p3::{dist, dot, from_vec3, norm, sub, to_vec3};
use firmware::geom::{Real, Vec3};
use firmware::rover::{check_pose_stability, settle, SettleOutcome, SettledPose};
use firmware::tether::{predict_anchors, Anchor, AnchorHistory};
use host_sim::truth::tether::{true_tether, Wrap};
use host_sim::world::ledge::{
    toe_x, LedgeWorld, POLE_CENTRE_XY, POLE_RADIUS_M, ROOT_ANCHOR_TEST1, ROOT_ANCHOR_TEST2, START_GROUND,
};

type P = [f64; 3];

/// A tether end point 0.35 m off the surface above ground point (x, y).
fn tether_point(w: &LedgeWorld, x: f64, y: f64) -> P {
    let h = w.height_f64(x, y);
    let (_, g) = w.sdf([x, y, h + 0.01]);
    [x + 0.35 * g[0], y + 0.35 * g[1], h + 0.35 * g[2]]
}

/// Bend angle of the true tether at its single contact (0 when straight), degrees.
fn bend_deg(root: P, c: P, x: P) -> f64 {
    let (a, b) = (sub(c, root), sub(x, c));
    let cosv = dot(a, b) / (norm(a) * norm(b));
    cosv.clamp(-1.0, 1.0).acos().to_degrees()
}

#[test]
fn lip_attach_and_detach_match_the_true_tether() {
    let w = LedgeWorld::new();
    let root = ROOT_ANCHOR_TEST1;
    let y = 0.3;
    let xs: Vec<f64> = (0..=41).map(|k| -1.5 + 0.1 * k as f64).collect();
    let mut path: Vec<P> = xs.iter().map(|&x| tether_point(&w, x, y)).collect();
    let (mut attached_at, mut compared) = (None, 0);
    let mut max_drift: f64 = 0.0;
    for pass in 0..2 {
        let mut hist = AnchorHistory::new(Anchor::root(to_vec3(root)));
        if pass == 1 {
            // climb back from the bottom, starting with the true history there
            path.reverse();
            let t = true_tether(&w, root, path[0], None).expect("true tether");
            for c in &t.contacts {
                let (_, g) = w.sdf(*c);
                assert!(hist.push(Anchor { point: to_vec3(*c), gradient: to_vec3(g) }).is_ok());
            }
        }
        for (k, win) in path.windows(2).enumerate() {
            let mut out = AnchorHistory::default();
            predict_anchors(&w, &hist, &to_vec3(win[0]), &to_vec3(win[1]), &mut out).unwrap_or_else(|e| panic!("{e:?}"));
            hist = out;
            let t = true_tether(&w, root, win[1], None).expect("true tether");
            let predicted = hist.len() - 1;
            let bend = t.contacts.first().map(|c| bend_deg(root, *c, win[1])).unwrap_or(0.0);
            if predicted != t.contacts.len() {
                // only in the transition, where the true tether is bent by less than 1 degree
                assert!(bend < 1.0, "pass {pass} step {k}: predicted {predicted} anchors, true {:?} bend {bend}", t);
                continue;
            }
            if let (Some(c), Some(a)) = (t.contacts.first(), hist.last()) {
                // the predicted anchor is on the lip edge; it stays where it attached (Paton's fixed anchors) while
                // the true frictionless tether slides along the edge, so along the edge they may drift apart
                let ap = from_vec3(&a.point);
                assert!(ap[0].abs() < 0.01 && (ap[2] - 4.0).abs() < 0.01, "anchor off the lip: {ap:?}");
                if pass == 0 && attached_at.is_none() {
                    attached_at = Some(k);
                    assert!(dist(*c, ap) < 0.03, "lip anchor at attachment {ap:?} vs true {c:?}");
                }
                max_drift = max_drift.max(dist(*c, ap));
            }
            let len = f64::from(hist.length_to(&to_vec3(win[1])));
            assert!((len - t.length).abs() < 0.01, "length {len} vs true {}", t.length);
            compared += 1;
        }
        // at the end of the descent the tether runs over the lip; at the end of the climb it is straight again
        assert_eq!(hist.len(), if pass == 0 { 2 } else { 1 }, "pass {pass}: {hist:?}");
    }
    println!("lip: attached at step {attached_at:?}, {compared} steps compared, max drift along the edge {max_drift:.3} m");
    assert!(attached_at.is_some() && compared > 70, "attached at {attached_at:?}, compared {compared}");
}

#[test]
fn pole_wrap_matches_the_true_tether() {
    let w = LedgeWorld::with_pole();
    let root = ROOT_ANCHOR_TEST2;
    let [cx, cy] = POLE_CENTRE_XY;
    let radius = 1.5;
    let mut hist = AnchorHistory::new(Anchor::root(to_vec3(root)));
    let pos = |deg: f64| [cx + radius * deg.to_radians().cos(), cy + radius * deg.to_radians().sin(), 4.6];
    let mut wrapped_steps = 0;
    let (mut max_exit_err, mut max_exit_dz, mut max_len_err): (f64, f64, f64) = (0.0, 0.0, 0.0);
    let mut deg = 90.0;
    while deg < 235.0 {
        let (a, b) = (pos(deg), pos(deg + 2.5));
        deg += 2.5;
        let mut out = AnchorHistory::default();
        predict_anchors(&w, &hist, &to_vec3(a), &to_vec3(b), &mut out).unwrap_or_else(|e| panic!("at {deg}: {e:?}"));
        hist = out;
        let truth = true_tether(&w, root, b, None).or_else(|| true_tether(&w, root, b, Some(Wrap::Ccw)));
        let wrap = host_sim::truth::tether::around_pole(&w, root, b, Wrap::Ccw);
        let straight_free = host_sim::truth::tether::segment_free(&w, root, b);
        if straight_free && wrap.is_none() {
            assert_eq!(hist.len(), 1, "at {deg}: tether should be straight: {hist:?}");
            continue;
        }
        let t = wrap.expect("wrapped class");
        let _ = truth;
        // the predicted anchors lie on the pole, within the true contact helix's height range
        let (p1, p2) = (t.contacts[0], t.contacts[1]);
        // the predicted anchors lie on the pole, within the true contact arc (angles, seen from above); their
        // heights are where they attached (fixed anchors), while the true frictionless tether slides
        let ang = |q: P| (q[1] - cy).atan2(q[0] - cx);
        let (t1, t2) = (ang(p1), ang(p2));
        let span = (t2 - t1).rem_euclid(core::f64::consts::TAU);
        // one anchor spacing on the pole (see `firmware::tether` docs): the discretisation of the wrap
        let spacing = 2.0 * (f64::from(firmware::config::tether::PIVOT_EXCLUSION_M) / (2.0 * POLE_RADIUS_M)).asin();
        for a in hist.as_slice().iter().skip(1) {
            let ap = from_vec3(&a.point);
            let r = ((ap[0] - cx).powi(2) + (ap[1] - cy).powi(2)).sqrt();
            assert!((r - POLE_RADIUS_M).abs() < 0.01, "anchor off the pole: r {r}");
            let rel = (ang(ap) - t1 + spacing).rem_euclid(core::f64::consts::TAU) - spacing;
            assert!(rel > -0.02 && rel < span + spacing, "at {deg}: anchor angle {rel} outside the true arc [0, {span}]");
        }
        if hist.len() > 1 {
            let last = from_vec3(&hist.last().expect("anchor").point);
            let horiz = ((last[0] - p2[0]).powi(2) + (last[1] - p2[1]).powi(2)).sqrt();
            max_exit_err = max_exit_err.max(horiz);
            max_exit_dz = max_exit_dz.max((last[2] - p2[2]).abs());
            assert!(horiz < POLE_RADIUS_M * spacing + 0.01, "at {deg}: last anchor {last:?} vs true exit {p2:?}");
            let len = f64::from(hist.length_to(&to_vec3(b)));
            max_len_err = max_len_err.max((len - t.length).abs());
            assert!((len - t.length).abs() < 0.02, "at {deg}: length {len} vs true {}", t.length);
            wrapped_steps += 1;
        } else {
            // not yet attached: only while the true wrap is below 2 degrees
            let [ax, ay] = [p1[0] - cx, p1[1] - cy];
            let [bx, by] = [p2[0] - cx, p2[1] - cy];
            let wrap_deg = (ax * by - ay * bx).atan2(ax * bx + ay * by).to_degrees();
            assert!(wrap_deg < 2.0, "at {deg}: not attached but true wrap {wrap_deg} deg");
        }
    }
    println!(
        "pole: {wrapped_steps} wrapped steps, {} anchors at the end; last anchor vs true exit: horizontal {max_exit_err:.3} m, \
         height {max_exit_dz:.3} m; tether length error {max_len_err:.4} m",
        hist.len()
    );
    assert!(wrapped_steps > 15, "wrapped steps {wrapped_steps}");
}

fn settle_on(w: &LedgeWorld, x: f64, y: f64, yaw: Real) -> SettledPose {
    let g = [x, y, w.height_f64(x, y)];
    match settle(w, &to_vec3(g), yaw, &RoverParams::AXEL) {
        SettleOutcome::Settled(s) => s,
        other => panic!("no settle at ({x}, {y}): {other:?}"),
    }
}

fn stable_with(w: &LedgeWorld, s: &SettledPose, last_anchor: P) -> bool {
    let (o, _) = check_pose_stability(w, s, Some(&to_vec3(last_anchor)), &RoverParams::AXEL).expect("valid problem");
    o.is_stable()
}

#[test]
fn ledge_test1_slope_stable_test2_unstable() {
    let w = LedgeWorld::new();
    let mut n = 0;
    // test 1 along the direct descent (y = 0), test 2 over the whole slope
    for x in [0.6, 1.0, 1.4, 1.8, 2.2] {
        for y in [-2.0, -1.0, 0.0, 1.0, 2.0] {
            let s = settle_on(&w, x, y, 0.0);
            let axle = from_vec3(&s.pose.translation.vector);
            // slope: the rover's up axis is the slope normal
            let up = s.pose.rotation * Vec3::z();
            assert!((f64::from(up.z).acos().to_degrees() - 55.0).abs() < 1.0, "tilt at {x},{y}");
            // test 1: root behind -> the true tether runs over the lip, which is the last anchor
            let t1 = true_tether(&w, ROOT_ANCHOR_TEST1, axle, None).expect("tether");
            assert_eq!(t1.contacts.len(), 1);
            if y == 0.0 {
                assert!(stable_with(&w, &s, t1.last_anchor(ROOT_ANCHOR_TEST1)), "test 1 unstable at {x},{y}");
            }
            // test 2: root in front -> straight tether to the root, the slope is unstable
            let t2 = true_tether(&w, ROOT_ANCHOR_TEST2, axle, None).expect("tether");
            assert!(t2.contacts.is_empty());
            assert!(!stable_with(&w, &s, ROOT_ANCHOR_TEST2), "test 2 stable at {x},{y}");
            n += 1;
        }
    }
    // the start pose on the ledge top is stable in both tests
    let s = settle_on(&w, START_GROUND[0], START_GROUND[1], 0.0);
    assert!(stable_with(&w, &s, ROOT_ANCHOR_TEST1) && stable_with(&w, &s, ROOT_ANCHOR_TEST2));
    assert_eq!(n, 25);
}

#[test]
fn ledge_test3_anchoring_on_the_pole_makes_the_slope_stable() {
    let w = LedgeWorld::with_pole();
    let root = ROOT_ANCHOR_TEST2;
    let [cx, cy] = POLE_CENTRE_XY;
    // loop behind the pole (counter-clockwise seen from above), then drive to the lip and down the slope at y = yd
    let yd = -0.8;
    let mut path: Vec<P> = Vec::new();
    let mut deg: f64 = 60.0;
    while deg <= 250.0 {
        let r = 1.5;
        path.push([cx + r * deg.to_radians().cos(), cy + r * deg.to_radians().sin(), 4.6]);
        deg += 2.5;
    }
    let last = *path.last().expect("path");
    let target = tether_point(&w, -0.3, yd);
    for k in 1..=30 {
        let t = k as f64 / 30.0;
        path.push([last[0] + t * (target[0] - last[0]), last[1] + t * (target[1] - last[1]), 4.6 + t * (target[2] - 4.6)]);
    }
    for k in 1..=25 {
        path.push(tether_point(&w, -0.3 + 0.1 * k as f64, yd));
    }
    let mut hist = AnchorHistory::new(Anchor::root(to_vec3(root)));
    let mut stable_looped = 0;
    let mut checked = 0;
    let mut direct_refused = 0;
    for (k, win) in path.windows(2).enumerate() {
        let mut out = AnchorHistory::default();
        predict_anchors(&w, &hist, &to_vec3(win[0]), &to_vec3(win[1]), &mut out).unwrap_or_else(|e| panic!("step {k}: {e:?}"));
        hist = out;
        let x = win[1][0];
        // poses whose boom (1 m) can reach the lip are outside the inline / in-contact boom model: skip them
        let lip_dist = dist(from_vec3(&settle_on(&w, x.clamp(0.0, 2.7), yd, 0.0).pose.translation.vector), [0.0, yd, 4.0]);
        if x > 0.5 && x < 2.4 && lip_dist > f64::from(RoverParams::AXEL.boom_length_m) + 0.2 {
            let s = settle_on(&w, x, yd, 0.0);
            let last_anchor = from_vec3(&hist.last().expect("anchor").point);
            // the history holds the pole contacts and the lip
            assert!(hist.len() >= 3, "history {hist:?}");
            let on_lip = last_anchor[0].abs() < 0.03 && (last_anchor[2] - 4.0).abs() < 0.03;
            assert!(on_lip, "last anchor {last_anchor:?}");
            let looped = stable_with(&w, &s, last_anchor);
            // Without the pole the slope is not traversable (the premise of test 3) while the boom cannot reach
            // the floor: a boom resting on the floor beyond the toe holds the rover (the physics judge agrees, e.g.
            // `tetherbot judge-agreement ledge_test2 --region 2.2,-0.9,2.35,-0.7 --yaw 0 --explain 0`).
            let axle = from_vec3(&s.pose.translation.vector);
            let toe_dist = dist(axle, [toe_x(), yd, 0.0]);
            if toe_dist > f64::from(RoverParams::AXEL.boom_length_m) + 0.2 {
                assert!(!stable_with(&w, &s, root), "root-only history stable at x {x}");
                direct_refused += 1;
            }
            // independent expectation (Abad-Manterola et al. VI): stable while the tether's angle from upslope in
            // the slope plane is below asin(mu cot alpha) (5 degrees of slack for the rover's extent and boom)
            let params = RoverParams::AXEL;
            let tip = firmware::rover::boom_tip(&s, firmware::rover::boom_inline_angle(&s, &to_vec3(last_anchor)), &params);
            let d = {
                let t = from_vec3(&tip);
                let e = [last_anchor[0] - t[0], last_anchor[1] - t[1], last_anchor[2] - t[2]];
                let n = dist(e, [0.0; 3]);
                [e[0] / n, e[1] / n, e[2] / n]
            };
            let a = 55f64.to_radians();
            let (nrm, up) = ([a.sin(), 0.0, a.cos()], [-a.cos(), 0.0, a.sin()]);
            let dn = d[0] * nrm[0] + d[2] * nrm[2];
            let dt = [d[0] - dn * nrm[0], d[1], d[2] - dn * nrm[2]];
            let angle = ((dt[0] * up[0] + dt[2] * up[2]) / dist(dt, [0.0; 3])).acos().to_degrees();
            let theta_max = (f64::from(params.wheel_mu) / a.tan()).asin().to_degrees();
            println!("test 3: x {x:.2}: tether {angle:.1} deg from upslope (max {theta_max:.1}), stable {looped}");
            if angle < theta_max - 5.0 {
                assert!(looped, "unstable at x {x:.2} with tether {angle:.1} deg from upslope");
                stable_looped += 1;
            }
            checked += 1;
        }
    }
    assert!(checked >= 15 && stable_looped >= checked * 3 / 4, "stable {stable_looped} of {checked}");
    assert!(direct_refused >= 12, "root-only checked at {direct_refused} poses");
}


