//! Pictures like Morad et al. Figs. 12, 15-16: the terrain (shaded by height along the view direction), the grid of
//! scenes (thin grey), D* Lite's route at the start (dashed green) and at the end (cyan), the walls the team found
//! (thick red, across the blocked crossing), the first hop graph of robot 1 (yellow vertices and edges), the four
//! robots' hops (blue, black, brown, purple; a cross where a grip slipped), the hub's path (red dashed) and the
//! final tethers (white), projected on the plane perpendicular to `view`.

use super::surface::{unit, P3};
use firmware::geom::p3::{cross, dot, sub};
use super::SimReport;
use core::fmt::Write as _;
use firmware::geom::p3::from_vec3;
use firmware::geom::Real;
use firmware::plan::team::mission::{Cell, SceneGrid};

/// A point of the scene plane at the start hub's height.
fn grid_point(g: &SceneGrid, a: f64, b: f64, h: f64) -> P3 {
    from_vec3(&g.point(a as Real, b as Real, h as Real))
}

fn cell_centre(g: &SceneGrid, c: Cell, h: f64) -> P3 {
    let (a, b) = g.centre(c);
    grid_point(g, a as f64, b as f64, h)
}

const COLOURS: [&str; 4] = ["#1f4fff", "#000000", "#8b4513", "#800080"];

/// SVG text. `background`: terrain sample points (e.g. DEM posts or mesh vertices).
pub fn render(rep: &SimReport, view: P3, background: &[P3]) -> String {
    let n = unit(view);
    let a = unit(if n[2].abs() < 0.9 { cross([0.0, 0.0, 1.0], n) } else { cross([0.0, 1.0, 0.0], n) });
    let b = cross(n, a);
    let origin = rep.hub_path.first().copied().unwrap_or([0.0; 3]);
    let proj = |p: P3| -> (f64, f64, f64) {
        let d = sub(p, origin);
        (dot(d, a), dot(d, b), dot(d, n))
    };
    let h0 = rep.grid.map(|g| g.height_of(&firmware::geom::p3::to_vec3(origin)) as f64).unwrap_or(0.0);
    let mut pts: Vec<(f64, f64)> = rep.paths.iter().flatten().map(|&p| proj(p)).map(|(x, y, _)| (x, y)).collect();
    if let Some(g) = &rep.grid {
        pts.extend(rep.routes.0.iter().chain(&rep.routes.1).map(|&c| proj(cell_centre(g, c, h0))).map(|(x, y, _)| (x, y)));
    }
    pts.extend(rep.first_graph.0.iter().map(|&p| proj(p)).map(|(x, y, _)| (x, y)));
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in &pts {
        x0 = x0.min(*x);
        x1 = x1.max(*x);
        y0 = y0.min(*y);
        y1 = y1.max(*y);
    }
    // a square window centred on the content
    let half = 0.5 * (x1 - x0).max(y1 - y0).max(10.0) * 1.15;
    let (cx, cy) = (0.5 * (x0 + x1), 0.5 * (y0 + y1));
    let (x0, x1, y0, y1) = (cx - half, cx + half, cy - half, cy + half);
    let size = 800.0;
    let s = size / (x1 - x0).max(y1 - y0);
    let sx = |x: f64| (x - x0) * s;
    let sy = |y: f64| size - (y - y0) * s;
    let mut out = String::new();
    let _ = writeln!(out, r#"<svg xmlns="http://www.w3.org/2000/svg" width="{size}" height="{size}" viewBox="0 0 {size} {size}">"#);
    let _ = writeln!(out, r##"<rect width="100%" height="100%" fill="#222"/>"##);
    // background: inside the window and on the viewer's side (a closed mesh also has a far side)
    let depth_lo = rep.paths.iter().flatten().map(|&p| proj(p).2).fold(f64::MAX, f64::min) - half;
    let bg: Vec<(f64, f64, f64)> = background
        .iter()
        .map(|&p| proj(p))
        .filter(|(x, y, z)| *x >= x0 && *x <= x1 && *y >= y0 && *y <= y1 && *z >= depth_lo)
        .collect();
    let (zmin, zmax) = bg.iter().fold((f64::MAX, f64::MIN), |(lo, hi), p| (lo.min(p.2), hi.max(p.2)));
    let dot_r = (2.0f64).max(size / 120.0);
    for (x, y, z) in &bg {
        let t = if zmax > zmin { (z - zmin) / (zmax - zmin) } else { 0.5 };
        let g = (40.0 + 200.0 * t) as u8;
        let _ = writeln!(out, r#"<rect x="{:.1}" y="{:.1}" width="{dot_r:.1}" height="{dot_r:.1}" fill="rgb({g},{g},{g})"/>"#, sx(*x), sy(*y));
    }
    let line = |out: &mut String, p: P3, q: P3, style: &str| {
        let (p, q) = (proj(p), proj(q));
        let _ = writeln!(out, r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" {style}/>"#, sx(p.0), sy(p.1), sx(q.0), sy(q.1));
    };
    if let Some(g) = &rep.grid {
        let (w, h, c) = (g.width as f64, g.height as f64, g.cell as f64);
        for i in 0..=g.width {
            let a = i as f64 * c;
            line(&mut out, grid_point(g, a, 0.0, h0), grid_point(g, a, h * c, h0), r##"stroke="#888" stroke-width="0.8""##);
        }
        for j in 0..=g.height {
            let b = j as f64 * c;
            line(&mut out, grid_point(g, 0.0, b, h0), grid_point(g, w * c, b, h0), r##"stroke="#888" stroke-width="0.8""##);
        }
        for (route, style) in [(&rep.routes.0, r##"stroke="#3c3" stroke-width="3" stroke-dasharray="10,6""##), (&rep.routes.1, r##"stroke="cyan" stroke-width="3""##)] {
            for pair in route.windows(2) {
                line(&mut out, cell_centre(g, pair[0], h0), cell_centre(g, pair[1], h0), style);
            }
        }
        for &(a, b) in &rep.walls {
            let (pa, pb) = (g.centre(a), g.centre(b));
            let (ma, mb) = (0.5 * (pa.0 + pb.0) as f64, 0.5 * (pa.1 + pb.1) as f64);
            let (da, db) = ((pb.0 - pa.0) as f64, (pb.1 - pa.1) as f64);
            let l = da.hypot(db).max(1e-9);
            let (qa, qb) = (-db / l * 0.5 * c, da / l * 0.5 * c);
            line(&mut out, grid_point(g, ma - qa, mb - qb, h0), grid_point(g, ma + qa, mb + qb, h0), r##"stroke="red" stroke-width="6""##);
        }
    }
    let (verts, edges) = &rep.first_graph;
    for &(i, j) in edges {
        if let (Some(&p), Some(&q)) = (verts.get(i), verts.get(j)) {
            let (p, q) = (proj(p), proj(q));
            let _ = writeln!(out, r#"<line x1="{:.1}" y1="{:.1}" x2="{:.1}" y2="{:.1}" stroke="gold" stroke-opacity="0.25" stroke-width="0.5"/>"#, sx(p.0), sy(p.1), sx(q.0), sy(q.1));
        }
    }
    for &p in verts {
        let p = proj(p);
        let _ = writeln!(out, r#"<circle cx="{:.1}" cy="{:.1}" r="2" fill="gold"/>"#, sx(p.0), sy(p.1));
    }
    let poly = |ps: &[P3]| ps.iter().map(|&p| proj(p)).map(|(x, y, _)| format!("{:.1},{:.1}", sx(x), sy(y))).collect::<Vec<_>>().join(" ");
    for (k, path) in rep.paths.iter().enumerate() {
        let c = COLOURS[k % 4];
        let _ = writeln!(out, r#"<polyline points="{}" fill="none" stroke="{c}" stroke-width="2.5"/>"#, poly(path));
        for &p in path {
            let p = proj(p);
            let _ = writeln!(out, r#"<circle cx="{:.1}" cy="{:.1}" r="3.5" fill="{c}" stroke="white" stroke-width="0.8"/>"#, sx(p.0), sy(p.1));
        }
    }
    let _ = writeln!(out, r#"<polyline points="{}" fill="none" stroke="red" stroke-width="1.5" stroke-dasharray="6,3"/>"#, poly(&rep.hub_path));
    for h in rep.hops.iter().filter(|h| h.slipped) {
        let p = proj(h.to);
        let _ = writeln!(out, r#"<text x="{:.1}" y="{:.1}" fill="red" font-size="18" text-anchor="middle">x</text>"#, sx(p.0), sy(p.1) + 6.0);
    }
    if let Some(&hub) = rep.hub_path.last() {
        let lost: Vec<usize> = rep.lost.iter().map(|l| l.0).collect();
        for (k, path) in rep.paths.iter().enumerate().filter(|(k, _)| !lost.contains(k)) {
            if let Some(&p) = path.last() {
                let _ = k;
                line(&mut out, hub, p, r#"stroke="white" stroke-width="1.2""#);
            }
        }
    }
    let _ = writeln!(
        out,
        r#"<text x="10" y="20" fill="white" font-family="sans-serif" font-size="14">{}: {}, {} hops, {} rounds, {} walls, lost {:?}, reached {}, violations {}</text>"#,
        rep.world,
        rep.outcome.map(|o| o.label()).unwrap_or("none"),
        rep.hops.len(),
        rep.rounds,
        rep.walls.len(),
        rep.lost.iter().map(|l| l.0).collect::<Vec<_>>(),
        rep.reached,
        rep.violations.len()
    );
    out.push_str("</svg>\n");
    out
}
