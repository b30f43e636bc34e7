//! `tetherbot homotopy SCENARIO`: homotopy planning on a tether-demand plane (Abad-Manterola et al.; Tanner et al.).
//!
//! Scenarios: `b` (scenario B: pre-plan, every class with its Alg. 2 verdict), `c` (scenario C pre-plan),
//! `c-online` (scenario C with a wrong map, closed loop with the range sensor), `random` (a seeded random field,
//! closed loop with `--hidden` of its obstacles left out of the map). Pictures go to `--out` (SVG).
//! Exit code 0 when the run ends as the scenario expects (a plan, or the goal reached), 1 otherwise.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use firmware::plan::homotopy::classes::{enumerate_classes, outcome_label, SearchStart};
use firmware::plan::status::Status;
use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::geo::Pt;
use firmware::plan::homotopy::lvalue::LValue;
use firmware::plan::homotopy::plan::{feasibility_check, preplan, PlanReport, HomotopyParams, Workspace};
use firmware::plan::homotopy::sleeve::{anchors, shortest_homotopic_path};
use rand_core::SeedableRng;

use crate::homotopy::dem::{self as demrun, DemScenario};
use crate::homotopy::scenarios::{self, Scenario};
use firmware::plan::homotopy::dem::HeightTile;
use crate::homotopy::sim::{self, SimConfig, SimOutcome};
use crate::homotopy::svg::{self, write, Svg};

/// Arguments of `homotopy`.
#[derive(Debug, Clone, clap::Args)]
pub struct HomotopyArgs {
    /// Scenario: b, c, c-online, random, dem.
    pub scenario: String,
    /// Directory for the SVG pictures.
    #[arg(long, default_value = "homotopy-out")]
    pub out: PathBuf,
    /// Seed (sensor noise; the random field).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Obstacles of the random field.
    #[arg(long, default_value_t = 8)]
    pub obstacles: usize,
    /// Obstacles of the random field missing from the rover's map.
    #[arg(long, default_value_t = 3)]
    pub hidden: usize,
    /// Soil friction coefficient of the random field (default 0.91: theta_max = 50 deg at alpha = 50 deg), or of a
    /// DEM descent (default: the preset's).
    #[arg(long)]
    pub mu: Option<f64>,
    /// DEM descent (scenario `dem`): a preset (shackleton, kepler, hirise, marsyard) whose fields the options
    /// below override.
    #[arg(long)]
    pub preset: Option<String>,
    /// DEM descent: the DEM file (GeoTIFF, or .npy with --npy-spacing).
    #[arg(long)]
    pub dem: Option<PathBuf>,
    /// DEM descent: post spacing of a .npy DEM (m).
    #[arg(long)]
    pub npy_spacing: Option<f64>,
    /// DEM descent: window "x0,y0,side" in DEM metres (before scaling).
    #[arg(long)]
    pub window: Option<String>,
    /// DEM descent: take every N-th post.
    #[arg(long)]
    pub stride: Option<usize>,
    /// DEM descent: scale to rover scale (horizontal and vertical alike, so slopes are kept).
    #[arg(long)]
    pub scale: Option<f64>,
    /// DEM descent: root anchor "x,y" in tile metres (after scaling).
    #[arg(long)]
    pub a0: Option<String>,
    /// DEM descent: goal "x,y" in tile metres.
    #[arg(long)]
    pub goal: Option<String>,
    /// DEM descent: corridor half width (m).
    #[arg(long)]
    pub half_width: Option<f64>,
    /// DEM descent: tether payout limit (m).
    #[arg(long)]
    pub max_payout: Option<f64>,
    /// DEM descent: print the tile's slope map instead of planning.
    #[arg(long)]
    pub survey: bool,
}

fn floats<const N: usize>(s: &str, what: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = s.split(',').map(|x| x.trim().parse::<f64>()).collect::<Result<_, _>>().map_err(|e| format!("{what}: {e}"))?;
    v.try_into().map_err(|_| format!("{what}: expected {N} comma-separated numbers"))
}

fn dem_scenario(a: &HomotopyArgs) -> Result<DemScenario, String> {
    let mut s = match (&a.preset, &a.dem) {
        (Some(p), _) => demrun::preset(p).ok_or_else(|| format!("unknown preset {p:?}: shackleton, kepler, hirise, marsyard"))?,
        (None, Some(_)) => demrun::preset("marsyard").ok_or("no base preset")?,
        (None, None) => return Err("scenario dem needs --preset or --dem".into()),
    };
    if let Some(f) = &a.dem {
        s.file = f.clone();
        s.name = f.file_stem().map_or("dem".into(), |x| x.to_string_lossy().into_owned());
        s.npy_spacing_m = a.npy_spacing;
    }
    if let Some(w) = &a.window {
        s.window = floats::<3>(w, "--window")?;
    }
    if let Some(v) = &a.a0 {
        s.a0 = floats::<2>(v, "--a0")?;
    }
    if let Some(v) = &a.goal {
        s.g = floats::<2>(v, "--goal")?;
    }
    s.stride = a.stride.unwrap_or(s.stride);
    s.scale = a.scale.unwrap_or(s.scale);
    s.half_width_m = a.half_width.unwrap_or(s.half_width_m);
    s.mu = a.mu.unwrap_or(s.mu);
    s.max_payout_m = a.max_payout.unwrap_or(s.max_payout_m);
    Ok(s)
}

/// A character slope map of the window (north up): ' ' < 15 deg, '.' < atan(mu), ':' < 45, '#' < 60, '@' steeper.
fn survey(s: &DemScenario) -> Result<bool, String> {
    let hm = demrun::load_dem(s)?;
    println!("{}: {} x {} posts at {:.3} m", s.file.display(), hm.width, hm.height, hm.spacing_m);
    let (h, rows, cols, res) = demrun::cut_window(&hm, s.window, s.stride, s.scale);
    println!("window {:?} stride {} scale {}: tile {rows} x {cols} at {res:.3} m ({:.1} x {:.1} m)", s.window, s.stride, s.scale, cols as f64 * res, rows as f64 * res);
    let mut tile = Box::new(HeightTile::new());
    tile.load([0.0, 0.0], res, rows, cols, &h).map_err(|e| format!("tile refused: {e:?}"))?;
    let step = (rows.max(cols) / 64).max(1);
    let demand = s.mu.atan().to_degrees();
    for r in (0..rows).rev().step_by(step) {
        let mut line = format!("{:7.1} ", r as f64 * res);
        for c in (0..cols).step_by(step) {
            let (gx, gy) = tile.gradient(r, c).unwrap_or((0.0, 0.0));
            let a = gx.hypot(gy).atan().to_degrees();
            line.push(if a < 15.0 { ' ' } else if a < demand { '.' } else if a < 45.0 { ':' } else if a < 60.0 { '#' } else { '@' });
        }
        println!("{line}");
    }
    println!("        x from 0 to {:.1} m, one character per {:.2} m; z from {:.1} to {:.1} m", cols as f64 * res, step as f64 * res,
        h.iter().copied().fold(f32::MAX, f32::min), h.iter().copied().fold(f32::MIN, f32::max));
    Ok(true)
}

fn build(s: &Scenario) -> Result<Box<Btm>, String> {
    let mut btm = Box::new(Btm::new());
    let obs: Vec<&[Pt]> = s.known.iter().map(|o| o.as_slice()).collect();
    btm.build(&s.plane, &obs).map_err(|e| format!("cannot triangulate the plane: {e:?}"))?;
    Ok(btm)
}


fn offline(s: &Scenario, out: &Path) -> Result<bool, String> {
    let btm = build(s)?;
    let mut ws = Box::new(Workspace::default());
    println!("scenario {}: {} triangles, {} obstacles", s.name, btm.triangle_count(), s.known.len());
    // Every class, with Alg. 2's verdict.
    let mut classes = heapless::Vec::new();
    let st = SearchStart { point: s.a0, l0: LValue::default(), prefix: &[] };
    let o = enumerate_classes(&btm, &mut ws.search, &st, s.g, &[], 16, &mut classes);
    if let Status::InvalidInput(e) = o {
        return Err(format!("{e:?}"));
    }
    println!("  A* enumerated {} homotopy classes ({})", classes.len(), outcome_label(&o));
    let mut sv = Svg::for_plane(&btm, 30.0);
    svg::draw_btm(&mut sv, &btm);
    for (i, c) in classes.iter().enumerate() {
        let shp = shortest_homotopic_path(&btm, &c.sleeve, s.a0, s.g).map_err(|e| format!("{e:?}"))?;
        let an = anchors(&btm, &shp);
        let f = feasibility_check(&btm, &s.model, &shp, &an, &mut ws.grid);
        println!("  class {i}: SHP {:.2} m, {} anchors, {:?}", shp.length(), an.len(), f);
        sv.polyline(&shp.pts, "#bbbbbb", 1.0, "");
        // One picture per class: its sleeve and SHP (Fig. 8).
        let mut cs = Svg::for_plane(&btm, 20.0);
        svg::draw_btm(&mut cs, &btm);
        svg::draw_sleeve(&mut cs, &btm, &c.sleeve, "#9e9e9e");
        cs.polyline(&shp.pts, "#1a9a2a", 2.0, "");
        for a in an.iter() {
            cs.circle(a.p, 5.0, "none", "#1a9a2a");
        }
        svg::draw_ends(&mut cs, s.a0, s.g);
        let verdict = match &f {
            firmware::plan::homotopy::plan::Feasibility::Feasible { .. } => "feasible".to_string(),
            firmware::plan::homotopy::plan::Feasibility::Infeasible { anchor_index, reason } => {
                format!("infeasible at a{anchor_index}: {reason:?}")
            }
        };
        write(out, &format!("{}_class{i}.svg", s.name.to_lowercase()), &cs, &format!("class {i}: SHP {:.2} m, {} anchors, {verdict}", shp.length(), an.len()))?;
    }
    let mut lc = heapless::Vec::new();
    let mut rep = PlanReport::default();
    let plan = preplan(&btm, &s.model, &HomotopyParams::default(), &mut ws, s.a0, s.g, &mut lc, &mut rep)
        .map_err(|e| format!("{e:?}"))?;
    for v in rep.examined.iter() {
        println!("  Alg. 1 examined: SHP {:.2} m, {} anchors -> {:?}", v.shp_length, v.anchors, v.verdict);
    }
    svg::draw_soil(&mut sv, &btm, &s.model);
    if let Some(p) = &plan {
        svg::draw_sleeve(&mut sv, &btm, &p.class.sleeve, "#7bd389");
        // The naive shortest path in red (Fig. 13).
        sv.polyline(&[s.a0, s.g], "#d62728", 1.5, "");
        svg::draw_plan(&mut sv, p);
    }
    svg::draw_ends(&mut sv, s.a0, s.g);
    let lname = s.name.to_lowercase();
    write(out, &format!("{lname}_btm_sleeve_shp.svg"), &sv, &format!("Scenario {}: BTM, sleeve of the chosen class, SHP (green), naive path (red), descent (orange)", s.name))?;
    if let Some(p) = &plan {
        let mut cs = Svg::for_plane(&btm, 30.0);
        svg::draw_btm(&mut cs, &btm);
        svg::draw_soil(&mut cs, &btm, &s.model);
        svg::draw_controllable_sets(&mut cs, &btm, &s.model, p, s.a0, s.g);
        svg::draw_plan(&mut cs, p);
        svg::draw_ends(&mut cs, s.a0, s.g);
        write(out, &format!("{lname}_controllable_sets.svg"), &cs, &format!("Scenario {}: controllable sets C_k..C_1, SHP edges (dotted), hand-offs", s.name))?;
        println!("  chosen: SHP {:.2} m through anchors {:?}", p.shp.length(), p.anchors.iter().map(|a| (a.p.x, a.p.y)).collect::<Vec<_>>());
    } else {
        println!("  no feasible ascent/descent pair");
    }
    Ok(plan.is_some())
}

fn closed_loop(s: &Scenario, out: &Path, seed: u64) -> Result<bool, String> {
    let cfg = SimConfig { seed, ..SimConfig::default() };
    let r = sim::run(s, &cfg);
    println!("scenario {} closed loop (seed {seed}): {:?} after {} steps, {} replanning events, {} collisions, tether in plan class: {}",
        s.name, r.outcome, r.path.len() - 1, r.events.len(), r.collisions, r.tether_in_plan_class);
    for (i, e) in r.events.iter().enumerate() {
        println!("  event {i} at step {} ({:.2}, {:.2}): {:?}, triangles touched {:?} -> {:?}", e.step, e.robot.x, e.robot.y, e.changes, e.touched, e.action);
        for (tag, b, shp) in [("before", &e.before, &e.shp_before), ("after", &e.after, &e.shp_after)] {
            let mut sv = Svg::for_plane(b, 30.0);
            svg::draw_btm(&mut sv, b);
            for o in s.truth.iter() {
                sv.polygon(o, "none", "#d62728", 1.0, 0.0);
            }
            sv.polyline(shp, "#1a9a2a", 2.5, "");
            let upto: Vec<Pt> = r.path.iter().take(e.step + 1).copied().collect();
            sv.polyline(&upto, "#d62728", 2.0, "");
            sv.circle(e.robot, 5.0, "#d62728", "black");
            svg::draw_ends(&mut sv, s.a0, s.g);
            write(out, &format!("{}_event{i}_{tag}.svg", s.name.to_lowercase()), &sv, &format!("{} event {i} {tag}: {:?} -> {:?}", s.name, e.changes, e.action))?;
        }
    }
    let mut sv = Svg::for_plane(&r.btm, 30.0);
    svg::draw_btm(&mut sv, &r.btm);
    if let Some(p) = &r.planner.plan {
        svg::draw_sleeve(&mut sv, &r.btm, &p.class.sleeve, "#7bd389");
        sv.polyline(&p.shp.pts, "#1a9a2a", 2.5, "");
    }
    sv.polyline(&r.path, "#d62728", 2.0, "");
    svg::draw_ends(&mut sv, s.a0, s.g);
    write(out, &format!("{}_final.svg", s.name.to_lowercase()), &sv, &format!("{}: driven path (red), final sleeve and SHP", s.name))?;
    Ok(r.outcome == SimOutcome::ReachedGoal && r.collisions == 0 && r.tether_in_plan_class)
}

/// `homotopy` entry point.
pub fn main(a: &HomotopyArgs) -> ExitCode {
    let res = match a.scenario.as_str() {
        "b" | "B" => offline(&scenarios::scenario_b(), &a.out),
        "c" | "C" => offline(&scenarios::scenario_c(), &a.out),
        "c-online" | "C-online" => closed_loop(&scenarios::scenario_c_online(), &a.out, a.seed),
        "random" => {
            let mut rng = rand_pcg::Pcg64::seed_from_u64(a.seed);
            let mut s = scenarios::random_field(&mut rng, a.obstacles, 20.0);
            let keep = s.truth.len().saturating_sub(a.hidden);
            s.known.truncate(keep);
            if let Some(mu) = a.mu {
                s.model.soil = firmware::plan::homotopy::planes::SoilMap::uniform(mu);
            }
            closed_loop(&s, &a.out, a.seed)
        }
        "dem" => match dem_scenario(a) {
            Ok(s) if a.survey => survey(&s),
            Ok(s) => crate::homotopy::dem_report::report(&s, &a.out),
            Err(e) => Err(e),
        },
        other => return super::fail(format!("unknown scenario {other:?}: use b, c, c-online, random or dem")),
    };
    match res {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::from(super::EXIT_FAILED),
        Err(e) => super::fail(e),
    }
}
