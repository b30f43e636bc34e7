//! Pictures like Morad et al. Figs. 15-16: the terrain (shaded by height along the view direction), the first
//! hop graph of robot 1 (yellow vertices and edges), the four robots' paths (blue, black, brown, purple) and the
//! hub's path (red), projected on the plane perpendicular to `view`.

use super::surface::{unit, P3};
use firmware::geom::p3::{cross, dot, sub};
use super::SimReport;
use core::fmt::Write as _;

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
    let mut pts: Vec<(f64, f64)> = rep.paths.iter().flatten().map(|&p| proj(p)).map(|(x, y, _)| (x, y)).collect();
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
    let _ = writeln!(
        out,
        r#"<text x="10" y="20" fill="white" font-family="sans-serif" font-size="14">{}: {} hops, {} rounds, lost {:?}, reached {}, violations {}</text>"#,
        rep.world,
        rep.hops.len(),
        rep.rounds,
        rep.lost,
        rep.reached,
        rep.violations.len()
    );
    out.push_str("</svg>\n");
    out
}
