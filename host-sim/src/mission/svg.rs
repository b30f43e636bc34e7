//! The mission picture (SVG): a top view and a profile of the terrain with the executed path (coloured by the true
//! static margin), the pose estimates, the planned and replanned paths, the rocks (dashed: invisible to the
//! sensor), the root anchor, the true tether at key moments with its contacts, and a chart of the true margin and
//! tension along the distance driven.

use core::fmt::Write as _;

use firmware::geom::p3::P3;
use firmware::geom::Real;

use super::run::MissionReport;
use crate::world::World;

const W: f64 = 560.0;
const H: f64 = 420.0;
const PAD: f64 = 30.0;

fn margin_colour(m: f64) -> &'static str {
    if m < 0.0 {
        "#d00000"
    } else if m < 20.0 {
        "#ff8c00"
    } else if m < 50.0 {
        "#e0c000"
    } else {
        "#1a9a1a"
    }
}

struct Frame {
    lo: [f64; 2],
    scale: f64,
    ox: f64,
    oy: f64,
    h: f64,
}

impl Frame {
    fn new(lo: [f64; 2], hi: [f64; 2], ox: f64, oy: f64, w: f64, h: f64) -> Frame {
        let sx = w / (hi[0] - lo[0]).max(1e-6);
        let sy = h / (hi[1] - lo[1]).max(1e-6);
        Frame { lo, scale: sx.min(sy), ox, oy, h }
    }
    fn pt(&self, u: f64, v: f64) -> (f64, f64) {
        (self.ox + (u - self.lo[0]) * self.scale, self.oy + self.h - (v - self.lo[1]) * self.scale)
    }
}

fn polyline(out: &mut String, f: &Frame, pts: &[(f64, f64)], style: &str) {
    if pts.len() < 2 {
        return;
    }
    let s: Vec<String> = pts.iter().map(|(u, v)| {
        let (x, y) = f.pt(*u, *v);
        format!("{x:.1},{y:.1}")
    }).collect();
    let _ = writeln!(out, r#"<polyline points="{}" fill="none" {style}/>"#, s.join(" "));
}

/// The picture of `rep` over `world`.
pub fn render(rep: &MissionReport, world: &dyn World) -> String {
    let mut pts: Vec<P3> = vec![rep.root, rep.start, rep.goal];
    pts.extend(rep.trace.iter().map(|t| t.axle));
    for p in &rep.plans {
        pts.extend(p.waypoints.iter().copied());
    }
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for p in &pts {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    for k in 0..2 {
        lo[k] -= 1.5;
        hi[k] += 1.5;
    }
    let mut out = String::new();
    let total_w = 2.0 * W + 3.0 * PAD;
    let total_h = H + 260.0 + 3.0 * PAD;
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{total_w}" height="{total_h}" font-family="sans-serif" font-size="11">"#
    );
    let _ = writeln!(out, r#"<rect width="100%" height="100%" fill="white"/>"#);
    let _ = writeln!(
        out,
        r#"<text x="{PAD}" y="18" font-size="13">{} seed {} ({}): {} after {:.2} m, {} replans, min true margin {:.1} N, max tension {:.0} N</text>"#,
        rep.scenario,
        rep.seed,
        rep.tracking,
        rep.verdict.name(),
        rep.distance_m,
        rep.replans,
        rep.min_true_margin_n,
        rep.max_tension_n
    );
    // ---- top view
    let top = Frame::new([lo[0], lo[1]], [hi[0], hi[1]], PAD, PAD, W, H);
    let n = 80usize;
    let (dx, dy) = ((hi[0] - lo[0]) / n as f64, (hi[1] - lo[1]) / n as f64);
    let (zlo, zhi) = (lo[2] - 0.5, hi[2] + 0.5);
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (lo[0] + (i as f64 + 0.5) * dx, lo[1] + (j as f64 + 0.5) * dy);
            let Some(h) = world.height_at(x as Real, y as Real) else { continue };
            let g = (((f64::from(h) - zlo) / (zhi - zlo)).clamp(0.0, 1.0) * 160.0 + 80.0) as u8;
            let (px, py) = top.pt(x - dx / 2.0, y + dy / 2.0);
            let _ = writeln!(
                out,
                r#"<rect x="{px:.1}" y="{py:.1}" width="{:.2}" height="{:.2}" fill="rgb({g},{g},{g})"/>"#,
                dx * top.scale + 0.3,
                dy * top.scale + 0.3
            );
        }
    }
    for (c, r, visible) in &rep.rocks {
        let (x, y) = top.pt(c[0], c[1]);
        let dash = if *visible { "" } else { r#" stroke-dasharray="3,2""# };
        let _ = writeln!(out, r##"<circle cx="{x:.1}" cy="{y:.1}" r="{:.1}" fill="none" stroke="#7a4a00"{dash}/>"##, r * top.scale);
    }
    for (_, tp) in &rep.tethers {
        let p: Vec<(f64, f64)> = tp.iter().map(|q| (q[0], q[1])).collect();
        polyline(&mut out, &top, &p, r##"stroke="#8a2be2" stroke-width="0.8" stroke-opacity="0.6""##);
        for q in tp.iter().skip(1).take(tp.len().saturating_sub(2)) {
            let (x, y) = top.pt(q[0], q[1]);
            let _ = writeln!(out, r##"<circle cx="{x:.1}" cy="{y:.1}" r="2.5" fill="#8a2be2"/>"##);
        }
    }
    for (k, p) in rep.plans.iter().enumerate() {
        let pp: Vec<(f64, f64)> = p.waypoints.iter().map(|q| (q[0], q[1])).collect();
        let colour = if k == 0 { "#1f5fd0" } else { "#ff7f0e" };
        polyline(&mut out, &top, &pp, &format!(r#"stroke="{colour}" stroke-width="1.2" stroke-dasharray="5,3""#));
    }
    let est: Vec<(f64, f64)> = rep.trace.iter().map(|t| (t.estimate[0], t.estimate[1])).collect();
    polyline(&mut out, &top, &est, r##"stroke="#555" stroke-width="0.7""##);
    for w in rep.trace.windows(2) {
        let (a, b) = top.pt(w[0].axle[0], w[0].axle[1]);
        let (c, d) = top.pt(w[1].axle[0], w[1].axle[1]);
        let _ = writeln!(out, r#"<line x1="{a:.1}" y1="{b:.1}" x2="{c:.1}" y2="{d:.1}" stroke="{}" stroke-width="2.5"/>"#, margin_colour(w[1].margin_n));
    }
    let (rx, ry) = top.pt(rep.root[0], rep.root[1]);
    let _ = writeln!(out, r#"<path d="M{:.1},{:.1} l5,9 l-10,0 z" fill="black"/>"#, rx, ry - 6.0);
    let (gx, gy) = top.pt(rep.goal[0], rep.goal[1]);
    let _ = writeln!(out, r##"<circle cx="{gx:.1}" cy="{gy:.1}" r="{:.1}" fill="none" stroke="#1f5fd0" stroke-width="1.5"/>"##, rep.tolerance_m * top.scale);
    let (sx, sy) = top.pt(rep.start[0], rep.start[1]);
    let _ = writeln!(out, r#"<circle cx="{sx:.1}" cy="{sy:.1}" r="4" fill="black"/>"#);
    let _ = writeln!(out, r#"<text x="{PAD}" y="{}">top view (x right, y up); grey = height</text>"#, PAD + H + 14.0);
    // ---- profile along the start -> goal direction
    let (ux, uy) = {
        let (a, b) = (rep.goal[0] - rep.start[0], rep.goal[1] - rep.start[1]);
        let l = (a * a + b * b).sqrt().max(1e-9);
        (a / l, b / l)
    };
    let s_of = |p: &P3| (p[0] - rep.start[0]) * ux + (p[1] - rep.start[1]) * uy;
    let ss: Vec<f64> = pts.iter().map(s_of).collect();
    let (slo, shi) = (ss.iter().copied().fold(f64::INFINITY, f64::min) - 1.0, ss.iter().copied().fold(f64::NEG_INFINITY, f64::max) + 1.0);
    let prof = Frame::new([slo, zlo], [shi, zhi + 0.5], 2.0 * PAD + W, PAD, W, H);
    let mut ground = Vec::new();
    for k in 0..=200 {
        let s = slo + (shi - slo) * k as f64 / 200.0;
        let (x, y) = (rep.start[0] + ux * s, rep.start[1] + uy * s);
        if let Some(h) = world.height_at(x as Real, y as Real) {
            ground.push((s, f64::from(h)));
        }
    }
    polyline(&mut out, &prof, &ground, r##"stroke="#444" stroke-width="1.5""##);
    for (_, tp) in &rep.tethers {
        let p: Vec<(f64, f64)> = tp.iter().map(|q| (s_of(q), q[2])).collect();
        polyline(&mut out, &prof, &p, r##"stroke="#8a2be2" stroke-width="0.8" stroke-opacity="0.6""##);
    }
    for (k, p) in rep.plans.iter().enumerate() {
        let pp: Vec<(f64, f64)> = p.waypoints.iter().map(|q| (s_of(q), q[2])).collect();
        let colour = if k == 0 { "#1f5fd0" } else { "#ff7f0e" };
        polyline(&mut out, &prof, &pp, &format!(r#"stroke="{colour}" stroke-width="1.2" stroke-dasharray="5,3""#));
    }
    for w in rep.trace.windows(2) {
        let (a, b) = prof.pt(s_of(&w[0].axle), w[0].axle[2]);
        let (c, d) = prof.pt(s_of(&w[1].axle), w[1].axle[2]);
        let _ = writeln!(out, r#"<line x1="{a:.1}" y1="{b:.1}" x2="{c:.1}" y2="{d:.1}" stroke="{}" stroke-width="2.5"/>"#, margin_colour(w[1].margin_n));
    }
    let (rx, ry) = prof.pt(s_of(&rep.root), rep.root[2]);
    let _ = writeln!(out, r#"<path d="M{:.1},{:.1} l5,9 l-10,0 z" fill="black"/>"#, rx, ry - 6.0);
    let _ = writeln!(
        out,
        r#"<text x="{}" y="{}">profile along start -&gt; goal; path colour = true margin (green >= 50 N, yellow >= 20, orange >= 0, red &lt; 0); blue dashed = plan, orange dashed = replans; purple = true tether</text>"#,
        2.0 * PAD + W,
        PAD + H + 14.0
    );
    // ---- margin and tension along the distance driven
    let cy = 2.0 * PAD + H + 20.0;
    let ch = 200.0;
    let cw = 2.0 * W + PAD;
    let dmax = rep.trace.last().map_or(1.0, |t| t.driven_m).max(1e-3);
    let mmax = rep.trace.iter().map(|t| t.margin_n.max(t.tension_n)).fold(1.0, f64::max);
    let chart = Frame { lo: [0.0, 0.0], scale: 1.0, ox: PAD, oy: cy, h: ch };
    let to = |d: f64, v: f64| (chart.ox + d / dmax * cw, chart.oy + ch - v / mmax * ch);
    let _ = writeln!(out, r##"<rect x="{PAD}" y="{cy}" width="{cw}" height="{ch}" fill="none" stroke="#999"/>"##);
    for (series, colour) in [(0, "#1a9a1a"), (1, "#d62728")] {
        let p: Vec<String> = rep
            .trace
            .iter()
            .map(|t| {
                let (x, y) = to(t.driven_m, if series == 0 { t.margin_n.max(0.0) } else { t.tension_n });
                format!("{x:.1},{y:.1}")
            })
            .collect();
        let _ = writeln!(out, r#"<polyline points="{}" fill="none" stroke="{colour}" stroke-width="1.2"/>"#, p.join(" "));
    }
    let _ = writeln!(
        out,
        r##"<text x="{PAD}" y="{}">true margin (green) and tension (red) along {dmax:.2} m driven; full scale {mmax:.0} N</text>"##,
        cy + ch + 14.0
    );
    let _ = writeln!(out, "</svg>");
    out
}
