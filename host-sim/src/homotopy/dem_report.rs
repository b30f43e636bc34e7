//! `tetherbot homotopy dem`: the report and pictures of a DEM descent (issue 20): planes, fold lines, inflated
//! obstacles, the point-mass and Axel routes with their passable anchors and controllable sets, and the chosen
//! route in the world frame.

use std::path::Path;

use firmware::plan::homotopy::dem::{dist3, DemDescent, RouteError, WorldRoute};
use firmware::plan::homotopy::geo::Pt;
use firmware::plan::homotopy::planes::HoldLimit;

use super::dem::{self as demrun, DemRun, DemScenario, ModelRun};
use super::svg::{self, Svg};

use super::svg::write;

fn theta_label(m: &HoldLimit, slope: f64, mu: f64) -> String {
    match m {
        HoldLimit::PointMass => format!("{:.1}", firmware::plan::homotopy::planes::theta_max(slope, mu).to_degrees()),
        HoldLimit::Measured { left_rad, .. } => format!("{:.1}", left_rad.to_degrees()),
    }
}

fn route_line(r: &ModelRun) -> String {
    match (&r.plan, &r.route) {
        (None, _) => "no feasible ascent/descent pair".into(),
        (Some(p), Some(Ok(w))) => format!(
            "SHP {:.2} m unfolded, tether {:.2} m in 3D, {} anchors, descent {} waypoints ({:.2} m on the DEM)",
            p.shp.length(),
            w.tether_length_m,
            p.anchors.len(),
            w.waypoints.len(),
            w.waypoints.windows(2).map(|x| dist3(x[0], x[1])).sum::<f64>()
        ),
        (Some(p), Some(Err(RouteError::TetherTooLong { needed_m, max_payout_m }))) => {
            format!("refused: tether {needed_m:.2} m > max payout {max_payout_m:.2} m (SHP {} anchors)", p.anchors.len())
        }
        (Some(_), Some(Err(e))) => format!("refused: {e:?}"),
        (Some(_), None) => "plan without route".into(),
    }
}

/// Draws the unfolded descent: BTM, fold images, edge obstacles (red dashed).
fn draw_unfolded(sv: &mut Svg, run: &DemRun) {
    svg::draw_btm(sv, &run.btm);
    for f in run.descent.folds.iter() {
        sv.polyline(&[f.right_2d, f.left_2d], "#8a5a00", 1.6, "5 3");
    }
    for o in run.descent.edge_obstacles.iter() {
        let mut l = o.to_vec();
        l.extend(o.first().copied());
        sv.polyline(&l, "#d62728", 1.0, "3 2");
    }
}

fn draw_route(sv: &mut Svg, r: &ModelRun, color: &str, width: f64) {
    if let Some(p) = &r.plan {
        sv.polyline(&p.shp.pts, color, width, "");
        for (i, a) in p.anchors.iter().enumerate() {
            sv.circle(a.p, 6.0, "none", color);
            sv.text(a.p, &format!("a{}", i + 1), 11.0);
        }
    }
}

/// World top view: slope-shaded posts, corridor, fold lines, obstacles, the route and its expected anchors.
fn world_svg(run: &DemRun, route: Option<&WorldRoute>) -> Svg {
    let t = &run.tile;
    let (rows, cols) = t.shape();
    let res = t.resolution_m();
    let max = Pt { x: (cols - 1) as f64 * res, y: (rows - 1) as f64 * res };
    let mut sv = Svg::for_bounds(Pt { x: 0.0, y: 0.0 }, max, (900.0 / max.x.max(max.y)).min(60.0));
    // Slope shading in blocks of `step` posts (at most 48 per side: the pictures stay small).
    let step = rows.max(cols).div_ceil(48).max(1);
    for r in (0..rows).step_by(step) {
        for c in (0..cols).step_by(step) {
            let (gx, gy) = t.gradient(r, c).unwrap_or((0.0, 0.0));
            let a = gx.hypot(gy).atan().to_degrees();
            let g = (255.0 - a.min(80.0) * 2.6) as u8;
            let [x, y] = t.post_xy(r, c);
            let h = 0.5 * res * step as f64;
            let sq = [Pt { x: x - h, y: y - h }, Pt { x: x + h, y: y - h }, Pt { x: x + h, y: y + h }, Pt { x: x - h, y: y + h }];
            sv.polygon(&sq, &format!("#{g:02x}{g:02x}{g:02x}"), "none", 0.0, 1.0);
        }
    }
    let back = |d: &DemDescent, ps: &[Pt]| -> Vec<Pt> {
        ps.iter().filter_map(|p| d.fold_back(*p)).map(|w| Pt { x: w[0], y: w[1] }).collect()
    };
    let d = &run.descent;
    let mut outline = back(d, &d.outline);
    outline.extend(outline.first().copied());
    sv.polyline(&outline, "black", 1.5, "");
    for f in d.folds.iter() {
        sv.polyline(&[Pt { x: f.right[0], y: f.right[1] }, Pt { x: f.left[0], y: f.left[1] }], "#8a5a00", 2.0, "5 3");
    }
    for o in d.obstacles.iter().chain(d.edge_obstacles.iter()) {
        // Octagon corners folded back one by one (an octagon across a fold line is drawn with straight edges).
        let w = back(d, o);
        sv.polygon(&w, "#4a78c2", "#1d3f7a", 1.0, 0.5);
    }
    if let Some(w) = route {
        let pts: Vec<Pt> = w.waypoints.iter().map(|p| Pt { x: p[0], y: p[1] }).collect();
        sv.polyline(&pts, "#f08a00", 2.0, "6 3");
        let teth: Vec<Pt> = w.tether.iter().map(|p| Pt { x: p[0], y: p[1] }).collect();
        sv.polyline(&teth, "#1a9a2a", 2.5, "");
        for (i, a) in w.anchors.iter().enumerate() {
            let p = Pt { x: a[0], y: a[1] };
            sv.circle(p, 6.0, "none", "#1a9a2a");
            sv.text(p, &format!("a{} z={:.1}", i + 1, a[2]), 11.0);
        }
    }
    svg::draw_ends(&mut sv, Pt { x: d.a0_world[0], y: d.a0_world[1] }, Pt { x: d.g_world[0], y: d.g_world[1] });
    sv
}

/// Runs a DEM scenario, prints the report and writes the pictures; `Ok(true)` when a route within the payout was
/// found with Axel.
pub fn report(s: &DemScenario, out: &Path) -> Result<bool, String> {
    let run = demrun::run(s)?;
    let d = &run.descent;
    let (rows, cols) = run.tile.shape();
    println!(
        "{}: tile {rows} x {cols} at {:.3} m (scale {}), a0 {:?} -> g {:?}, corridor +-{} m, mu {}",
        s.name,
        run.tile.resolution_m(),
        s.scale,
        s.a0,
        s.g,
        s.half_width_m,
        s.mu
    );
    for (i, p) in d.planes.iter().enumerate() {
        println!(
            "  plane {i}{}: {:?}, slope {:.1} deg, normal ({:.3}, {:.3}, {:.3}), {} posts, rms {:.3} m, profile run s {:.1}..{:.1} m",
            if i == d.reference { " (reference)" } else { "" },
            p.class,
            p.plane.slope_rad().to_degrees(),
            p.plane.normal[0],
            p.plane.normal[1],
            p.plane.normal[2],
            p.posts,
            p.rms_m,
            p.s_range.0,
            p.s_range.1
        );
    }
    for (k, f) in d.folds.iter().enumerate() {
        println!("  fold {k}: {:.1} deg, from ({:.1}, {:.1}, {:.1}) to ({:.1}, {:.1}, {:.1})", f.angle_rad.to_degrees(), f.right[0], f.right[1], f.right[2], f.left[0], f.left[1], f.left[2]);
    }
    println!(
        "  obstacles: {} posts, {} components, {} merges -> {} in the BTM, {} on the edge; BTM {} triangles",
        d.blocked_posts,
        d.components,
        d.merges,
        d.obstacles.len(),
        d.edge_obstacles.len(),
        run.btm.triangle_count()
    );
    let slope = d.planes.get(d.reference).map_or(0.0, |p| p.plane.slope_rad());
    println!("  Axel limit on the wall: theta_max {:.1} deg ({} stability checks); point mass asin(mu cot alpha): {} deg",
        run.axel.theta_max_rad.to_degrees(), run.axel.checks, theta_label(&HoldLimit::PointMass, slope, s.mu));
    let (rows, cols) = run.tile.shape();
    println!(
        "  flight phases (host wall time, one call each, {rows} x {cols} posts): segment + BTM {:.2} ms, Axel limit {:.2} ms, Alg. 1 (Axel) + route {:.2} ms",
        run.phase_s[0] * 1e3,
        run.phase_s[1] * 1e3,
        run.phase_s[2] * 1e3
    );
    for r in run.runs.iter() {
        println!("  {:>10}: {} classes examined ({} chosen): {}", r.label, r.report.examined.len(), demrun::count_verdicts(&r.report, true), route_line(r));
        for v in r.report.examined.iter() {
            println!("      SHP {:.2} m, {} anchors -> {:?}", v.shp_length, v.anchors, v.verdict);
        }
        if let (Some(p), Some(Ok(w))) = (&r.plan, &r.route) {
            for (a, wa) in p.anchors.iter().zip(w.anchors.iter()) {
                println!("      anchor on obstacle {:?}: unfolded ({:.2}, {:.2}) -> world ({:.2}, {:.2}, {:.2})", a.obstacle, a.p.x, a.p.y, wa[0], wa[1], wa[2]);
            }
        }
    }
    let scale = (900.0 / run.btm.plane().iter().fold(0.0f64, |m, p| m.max(p.x.abs()).max(p.y.abs())).max(1.0)).min(60.0);
    let name = s.name.to_lowercase();
    // Unfolded: both models' SHPs.
    let mut sv = Svg::for_plane(&run.btm, scale);
    draw_unfolded(&mut sv, &run);
    let [pm, ax] = &run.runs;
    draw_route(&mut sv, pm, "#7f7f7f", 2.0);
    draw_route(&mut sv, ax, "#1a9a2a", 2.5);
    if let Some(p) = &ax.plan {
        sv.polyline(&p.descent, "#f08a00", 1.6, "6 3");
    }
    svg::draw_ends(&mut sv, d.a0, d.g);
    write(out, &format!("{name}_unfolded.svg"), &sv, &format!("{}: unfolded planes (folds brown), inflated obstacles, SHP point mass (grey) vs Axel (green), Axel descent (orange)", s.name))?;
    for r in run.runs.iter() {
        let Some(p) = &r.plan else { continue };
        let mut cs = Svg::for_plane(&run.btm, scale);
        draw_unfolded(&mut cs, &run);
        svg::draw_controllable_sets(&mut cs, &run.btm, &r.model, p, d.a0, d.g);
        svg::draw_plan(&mut cs, p);
        svg::draw_ends(&mut cs, d.a0, d.g);
        let tag = if r.label == "Axel" { "axel" } else { "point_mass" };
        write(out, &format!("{name}_controllable_{tag}.svg"), &cs, &format!("{}: controllable sets and passable anchors, {} (theta_max {} deg on the wall)", s.name, r.label, theta_label(&r.model.limit, slope, s.mu)))?;
    }
    let chosen = ax.route.as_ref().and_then(|r| r.as_ref().ok());
    let wsv = world_svg(&run, chosen);
    write(out, &format!("{name}_world.svg"), &wsv, &format!("{}: world top view (slope shaded), corridor, folds, obstacles, Axel route and expected anchors", s.name))?;
    Ok(chosen.is_some())
}
