//! SVG pictures of BTMs, sleeves, SHPs, anchors and controllable sets (like Figs. 7, 8, 11-13 of the papers).
//! Plane frame: x to the right, upslope (+y) up the page.

use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::control::ControlGrid;
use firmware::plan::homotopy::geo::Pt;
use firmware::plan::homotopy::plan::Plan;
use firmware::plan::homotopy::planes::HoldModel;
use core::fmt::Write as _;

/// An SVG document under construction.
pub struct Svg {
    body: String,
    scale: f64,
    min: Pt,
    max: Pt,
}

impl Svg {
    /// A canvas for the plane's bounding box at `scale` pixels per metre.
    pub fn for_plane(btm: &Btm, scale: f64) -> Svg {
        let (mut min, mut max) = (Pt { x: f64::MAX, y: f64::MAX }, Pt { x: f64::MIN, y: f64::MIN });
        for p in btm.plane() {
            min = Pt { x: min.x.min(p.x), y: min.y.min(p.y) };
            max = Pt { x: max.x.max(p.x), y: max.y.max(p.y) };
        }
        Svg { body: String::new(), scale, min, max }
    }
    /// A canvas for the box `min..max` at `scale` pixels per metre.
    pub fn for_bounds(min: Pt, max: Pt, scale: f64) -> Svg {
        Svg { body: String::new(), scale, min, max }
    }
    fn xy(&self, p: Pt) -> (f64, f64) {
        (20.0 + (p.x - self.min.x) * self.scale, 20.0 + (self.max.y - p.y) * self.scale)
    }
    fn pts(&self, pts: &[Pt]) -> String {
        pts.iter().map(|p| self.xy(*p)).map(|(x, y)| format!("{x:.2},{y:.2}")).collect::<Vec<_>>().join(" ")
    }
    /// A filled polygon.
    pub fn polygon(&mut self, pts: &[Pt], fill: &str, stroke: &str, width: f64, opacity: f64) {
        let s = self.pts(pts);
        let _ = writeln!(
            self.body,
            r#"<polygon points="{s}" fill="{fill}" fill-opacity="{opacity}" stroke="{stroke}" stroke-width="{width}"/>"#
        );
    }
    /// A polyline; `dash` like "4 3" or "".
    pub fn polyline(&mut self, pts: &[Pt], stroke: &str, width: f64, dash: &str) {
        let s = self.pts(pts);
        let _ = writeln!(
            self.body,
            r#"<polyline points="{s}" fill="none" stroke="{stroke}" stroke-width="{width}" stroke-dasharray="{dash}"/>"#
        );
    }
    /// A circle of `r` pixels.
    pub fn circle(&mut self, p: Pt, r: f64, fill: &str, stroke: &str) {
        let (x, y) = self.xy(p);
        let _ = writeln!(self.body, r#"<circle cx="{x:.2}" cy="{y:.2}" r="{r}" fill="{fill}" stroke="{stroke}"/>"#);
    }
    /// Text at a point.
    pub fn text(&mut self, p: Pt, s: &str, size: f64) {
        let (x, y) = self.xy(p);
        let _ = writeln!(self.body, r#"<text x="{:.2}" y="{:.2}" font-size="{size}" font-family="sans-serif">{s}</text>"#, x + 4.0, y - 4.0);
    }
    /// The finished document.
    pub fn finish(&self, title: &str) -> String {
        let w = (self.max.x - self.min.x) * self.scale + 40.0;
        let h = (self.max.y - self.min.y) * self.scale + 60.0;
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w:.0}\" height=\"{h:.0}\">\n<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n{}<text x=\"20\" y=\"{:.0}\" font-size=\"13\" font-family=\"sans-serif\">{title}</text>\n</svg>\n",
            self.body,
            h - 12.0
        )
    }
}

/// Writes `svg` with `title` to `out/name` (creating `out`) and says so.
pub fn write(out: &std::path::Path, name: &str, svg: &Svg, title: &str) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let p = out.join(name);
    std::fs::write(&p, svg.finish(title)).map_err(|e| format!("{}: {e}", p.display()))?;
    println!("  wrote {}", p.display());
    Ok(())
}

/// The plane, obstacles (blue) and BTM edges (dashed).
pub fn draw_btm(svg: &mut Svg, btm: &Btm) {
    svg.polygon(btm.plane(), "#f4efe6", "black", 1.5, 1.0);
    for (i, _) in btm.triangles() {
        if let Some(t) = btm.tri_points(i) {
            let mut l = t.to_vec();
            l.push(t[0]);
            svg.polyline(&l, "#777", 0.7, "4 3");
        }
    }
    for (k, o) in btm.obstacles() {
        svg.polygon(&o.corners, "#4a78c2", "#1d3f7a", 1.2, 0.9);
        svg.text(o.rep, &format!("O{k}"), 10.0);
    }
}

/// A sleeve (triangles shaded).
pub fn draw_sleeve(svg: &mut Svg, btm: &Btm, sleeve: &[u16], color: &str) {
    for t in sleeve {
        if let Some(p) = btm.tri_points(*t) {
            svg.polygon(&p, color, "none", 0.0, 0.35);
        }
    }
}

/// The soil dividing line (dotted), when the two soils differ.
pub fn draw_soil(svg: &mut Svg, btm: &Btm, model: &HoldModel) {
    let s = model.soil;
    if s.mu_left == s.mu_right {
        return;
    }
    let span = btm.plane().iter().map(|p| p.dist(s.line_point)).fold(0.0, f64::max);
    let a = s.line_point + s.line_dir * (-span);
    let b = s.line_point + s.line_dir * span;
    svg.polyline(&[a, b], "#8a5a00", 1.5, "2 4");
    svg.text(s.line_point + s.line_dir * 1.0, &format!("mu={} | mu={}", s.mu_left, s.mu_right), 10.0);
}

/// A plan: SHP (green), descent (orange), anchors (circled), a0 and g.
pub fn draw_plan(svg: &mut Svg, plan: &Plan) {
    svg.polyline(&plan.shp.pts, "#1a9a2a", 2.5, "");
    svg.polyline(&plan.descent, "#f08a00", 1.6, "6 3");
    for (i, a) in plan.anchors.iter().enumerate() {
        svg.circle(a.p, 6.0, "none", "#1a9a2a");
        svg.text(a.p, &format!("a{}", i + 1), 11.0);
    }
}

/// Start and goal markers.
pub fn draw_ends(svg: &mut Svg, a0: Pt, g: Pt) {
    svg.circle(a0, 4.0, "black", "black");
    svg.text(a0, "a0", 12.0);
    svg.circle(g, 4.0, "red", "red");
    svg.text(g, "g", 12.0);
}

/// Controllable sets C_k .. C_1 of a plan's anchors, from g upward along its hand-offs (Fig. 12).
pub fn draw_controllable_sets(svg: &mut Svg, btm: &Btm, model: &HoldModel, plan: &Plan, a0: Pt, g: Pt) {
    let colors = ["#e34a33", "#fdbb84", "#9ebcda", "#8856a7", "#99d8c9"];
    let mut grid = Box::new(ControlGrid::new());
    let chain: Vec<Pt> = core::iter::once(a0).chain(plan.anchors.iter().map(|a| a.p)).collect();
    let mut q = g;
    for j in (1..chain.len()).rev() {
        let cs = grid.controllable_set(btm, model, q, chain[j - 1], chain[j]);
        let h = grid.cell_size() * 0.5;
        let color = colors[j % colors.len()];
        for c in grid.cells() {
            let sq = [Pt { x: c.x - h, y: c.y - h }, Pt { x: c.x + h, y: c.y - h }, Pt { x: c.x + h, y: c.y + h }, Pt { x: c.x - h, y: c.y + h }];
            svg.polygon(&sq, color, "none", 0.0, 0.45);
        }
        // SHP edge: the ray from a_j continuing a_{j-1} -> a_j.
        let d = chain[j] - chain[j - 1];
        let n = d.norm().max(1e-9);
        svg.polyline(&[chain[j], chain[j] + d * (6.0 / n)], "black", 1.2, "1 3");
        match cs.crossing {
            Some(x) => {
                svg.circle(x, 3.0, "black", "black");
                q = x;
            }
            None => break,
        }
    }
}
