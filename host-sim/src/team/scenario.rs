//! Team scenario files: `tetherbot team SCENARIO.toml` (schema in `host-sim/doc/team.md`, "Scenario files").
//!
//! A file names a world — a built-in one (`cliff`, `itokawa`, `bennu`, `crevasse`), an OBJ mesh, a DEM (`.npy`)
//! or a point cloud (PLY, PCD, LAS, LAZ) with a scale — and the team's mission on it: start, goal, scene size,
//! h_max, r_max, landing error, the grip-slip model on or off, seeds. Every field is checked before a world is
//! built; a field that cannot be used is an error that names it (`team.h_max: must be a positive finite number,
//! got -3`). Unknown fields are errors too (a misspelt field must not silently fall back to a default).

use super::surface::{unit, HeightSurface, MeshSurface, Surface, P3};
use super::{x_start, RangeSensor, SimConfig};
use super::worlds::{centroid, team_scenario, TeamScenario};
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// The whole file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamScenarioFile {
    /// Short name (reports, pictures).
    pub name: String,
    /// One line for people.
    #[serde(default)]
    pub description: Option<String>,
    /// Where the terrain comes from.
    pub world: WorldSpec,
    /// The mission.
    #[serde(default)]
    pub team: TeamSpec,
    /// Seeds run.
    #[serde(default)]
    pub seeds: SeedSpec,
}

/// `[world]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// `builtin`, `obj`, `dem` or `pointcloud`.
    pub source: String,
    /// For `builtin`: `cliff`, `itokawa`, `bennu` or `crevasse`.
    #[serde(default)]
    pub builtin: Option<String>,
    /// For `obj`, `dem`, `pointcloud`: the file, relative to the scenario file (or absolute).
    #[serde(default)]
    pub file: Option<PathBuf>,
    /// Metres per file unit (`obj`: e.g. 1000 for kilometres; `pointcloud`: all three axes). Default 1.
    #[serde(default)]
    pub scale: Option<f64>,
    /// Extra factor on heights (`dem`, `pointcloud`), e.g. to steepen a gentle scan into a wall. Default 1.
    #[serde(default)]
    pub vertical_scale: Option<f64>,
    /// `dem`: post spacing of the `.npy` grid in metres (the format has none). `pointcloud`: the spacing of the
    /// height grid the cloud is resampled to. Default 1 m.
    #[serde(default)]
    pub spacing_m: Option<f64>,
}

/// `[team]`: every field optional for a built-in world (its own set-up is the default), `start` and `goal`
/// required for the others.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TeamSpec {
    /// The hub's start (x, y, z; metres): the team grips in an "x" around the surface point under it.
    pub start: Option<[f64; 3]>,
    /// The hub's goal (metres), projected on the surface like the start.
    pub goal: Option<[f64; 3]>,
    /// Scene (cell) size of the global grid, metres. Default 2 h_max.
    pub scene_m: Option<f64>,
    /// Cells of margin around the start and the goal. Default 2.
    pub scene_margin: Option<u32>,
    /// Hop length h_max, metres. Default 10.
    pub h_max: Option<f64>,
    /// Tether length r_max, metres. Default 1.5 h_max.
    pub r_max: Option<f64>,
    /// Landing error radius, metres. Default 0.03 h_max.
    pub landing_error_m: Option<f64>,
    /// The planner's margin for the landing error, metres. Default 0.1 h_max.
    pub landing_margin_m: Option<f64>,
    /// Goal tolerance of the hub, metres. Default 0.8 h_max.
    pub goal_tolerance_m: Option<f64>,
    /// Grips slip with the grip model (`false`: never). Default true.
    pub slip: Option<bool>,
    /// Range sensor's reach, metres. Default 2.2 h_max.
    pub sensor_range_m: Option<f64>,
    /// Half-diagonal of the starting "x", metres. Default 0.6 h_max.
    pub spread_m: Option<f64>,
    /// Round budget. Default 100.
    pub max_rounds: Option<u32>,
}

/// `[seeds]`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SeedSpec {
    /// First seed. Default 1.
    #[serde(default = "one")]
    pub first: u64,
    /// Seeds run. Default 1.
    #[serde(default = "one")]
    pub count: u64,
}

fn one() -> u64 {
    1
}

impl Default for SeedSpec {
    fn default() -> Self {
        Self { first: 1, count: 1 }
    }
}

/// A scenario file read and checked, with the directory its paths are relative to.
#[derive(Debug, Clone)]
pub struct LoadedScenario {
    /// The file's contents.
    pub file: TeamScenarioFile,
    /// The file's directory.
    pub dir: PathBuf,
    /// The file itself (for messages).
    pub path: PathBuf,
}

fn field_err(path: &Path, field: &str, why: impl core::fmt::Display) -> String {
    format!("team scenario {}: field `{field}`: {why}", path.display())
}

fn positive(path: &Path, field: &str, v: Option<f64>) -> Result<(), String> {
    match v {
        Some(x) if !(x.is_finite() && x > 0.0) => Err(field_err(
            path,
            field,
            format!("must be a positive finite number, got {x}"),
        )),
        _ => Ok(()),
    }
}

fn finite3(path: &Path, field: &str, v: Option<[f64; 3]>) -> Result<(), String> {
    match v {
        Some(p) if !p.iter().all(|c| c.is_finite()) => Err(field_err(
            path,
            field,
            format!("must be three finite numbers, got {p:?}"),
        )),
        _ => Ok(()),
    }
}

/// The built-in worlds.
pub const BUILTIN: [&str; 4] = ["cliff", "itokawa", "bennu", "crevasse"];

/// Parse and check a scenario from its text (`path` is used for messages and relative file names).
pub fn parse(text: &str, path: &Path) -> Result<LoadedScenario, String> {
    let file: TeamScenarioFile =
        toml::from_str(text).map_err(|e| format!("team scenario {}: {}", path.display(), e.to_string().trim_end()))?;
    let w = &file.world;
    let t = &file.team;
    match w.source.as_str() {
        "builtin" => {
            let b = w.builtin.as_deref().ok_or_else(|| {
                field_err(
                    path,
                    "world.builtin",
                    "missing (source = \"builtin\" needs one of cliff, itokawa, bennu, crevasse)",
                )
            })?;
            if !BUILTIN.contains(&b) {
                return Err(field_err(
                    path,
                    "world.builtin",
                    format!("unknown world {b:?} (cliff, itokawa, bennu, crevasse)"),
                ));
            }
            for (name, given) in [
                ("world.file", w.file.is_some()),
                ("team.start", t.start.is_some()),
                ("team.goal", t.goal.is_some()),
                ("team.scene_m", t.scene_m.is_some()),
                ("team.scene_margin", t.scene_margin.is_some()),
                ("team.spread_m", t.spread_m.is_some()),
            ] {
                if given {
                    return Err(field_err(path, name, "not used with a built-in world (its start, goal and grid of scenes are fixed; use source = \"dem\", \"obj\" or \"pointcloud\" to choose them)"));
                }
            }
        }
        "obj" | "dem" | "pointcloud" => {
            if w.file.is_none() {
                return Err(field_err(
                    path,
                    "world.file",
                    format!("missing (source = {:?} reads a file)", w.source),
                ));
            }
            if w.builtin.is_some() {
                return Err(field_err(
                    path,
                    "world.builtin",
                    format!("only with source = \"builtin\", not {:?}", w.source),
                ));
            }
            if t.start.is_none() {
                return Err(field_err(path, "team.start", "missing"));
            }
            if t.goal.is_none() {
                return Err(field_err(path, "team.goal", "missing"));
            }
        }
        other => {
            return Err(field_err(
                path,
                "world.source",
                format!("unknown source {other:?} (builtin, obj, dem, pointcloud)"),
            ))
        }
    }
    positive(path, "world.scale", w.scale)?;
    positive(path, "world.vertical_scale", w.vertical_scale)?;
    positive(path, "world.spacing_m", w.spacing_m)?;
    finite3(path, "team.start", t.start)?;
    finite3(path, "team.goal", t.goal)?;
    for (name, v) in [
        ("team.scene_m", t.scene_m),
        ("team.h_max", t.h_max),
        ("team.r_max", t.r_max),
        ("team.goal_tolerance_m", t.goal_tolerance_m),
        ("team.sensor_range_m", t.sensor_range_m),
        ("team.spread_m", t.spread_m),
    ] {
        positive(path, name, v)?;
    }
    for (name, v) in [
        ("team.landing_error_m", t.landing_error_m),
        ("team.landing_margin_m", t.landing_margin_m),
    ] {
        if let Some(x) = v {
            if !(x.is_finite() && x >= 0.0) {
                return Err(field_err(path, name, format!("must be a finite number >= 0, got {x}")));
            }
        }
    }
    if let (Some(h), Some(r)) = (t.h_max, t.r_max) {
        if r < h / 2.0 {
            return Err(field_err(
                path,
                "team.r_max",
                format!("{r} m is less than half of h_max ({h} m): no hop could keep the tether"),
            ));
        }
    }
    if let (Some(h), Some(m)) = (t.h_max, t.landing_margin_m) {
        if m >= h {
            return Err(field_err(
                path,
                "team.landing_margin_m",
                format!("{m} m leaves no hop within h_max ({h} m)"),
            ));
        }
    }
    if t.max_rounds == Some(0) {
        return Err(field_err(path, "team.max_rounds", "must be at least 1"));
    }
    if file.seeds.count == 0 {
        return Err(field_err(path, "seeds.count", "must be at least 1"));
    }
    let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    Ok(LoadedScenario {
        file,
        dir,
        path: path.to_path_buf(),
    })
}

/// Read, parse and check a scenario file.
pub fn load(path: &Path) -> Result<LoadedScenario, String> {
    let text = std::fs::read_to_string(path).map_err(|e| format!("team scenario {}: {e}", path.display()))?;
    parse(&text, path)
}

/// A point cloud resampled to a height grid of `spacing` metres: each post takes the inverse-distance-weighted
/// height of the cloud's points within 3 posts of it; posts with none take the mean of their known neighbours
/// (grown for at most 16 passes; past that, no data).
pub fn cloud_to_heightmap(points: &[P3], spacing: f64) -> Result<crate::terrain::Heightmap, String> {
    let (lo, hi) = crate::terrain::pointcloud::bounds(points).ok_or("empty point cloud")?;
    let width = ((hi[0] - lo[0]) / spacing).floor() as usize + 1;
    let height = ((hi[1] - lo[1]) / spacing).floor() as usize + 1;
    if width < 8 || height < 8 || width * height > 4_000_000 {
        return Err(format!("the cloud resamples to {width} x {height} posts at {spacing} m (want 8..2000 per side): change world.scale or world.spacing_m"));
    }
    let mut sum = vec![0.0f64; width * height];
    let mut wsum = vec![0.0f64; width * height];
    let reach = 3i64;
    for p in points {
        let (fx, fy) = ((p[0] - lo[0]) / spacing, (p[1] - lo[1]) / spacing);
        let (cx, cy) = (fx.round() as i64, fy.round() as i64);
        for y in (cy - reach).max(0)..=(cy + reach).min(height as i64 - 1) {
            for x in (cx - reach).max(0)..=(cx + reach).min(width as i64 - 1) {
                let d2 = (x as f64 - fx).powi(2) + (y as f64 - fy).powi(2);
                if d2 <= (reach * reach) as f64 {
                    let w = 1.0 / (d2 + 0.05);
                    let k = y as usize * width + x as usize;
                    sum[k] += w * (p[2] - lo[2]);
                    wsum[k] += w;
                }
            }
        }
    }
    let mut heights_m: Vec<Option<f64>> = sum.iter().zip(&wsum).map(|(s, w)| (*w > 0.0).then(|| s / w)).collect();
    // posts farther than 3 posts from every return (gaps between scan lines): the mean of their known
    // neighbours, grown inwards for at most 16 passes; what is left stays "no data"
    for _ in 0..16 {
        let prev = heights_m.clone();
        let mut changed = false;
        for y in 0..height {
            for x in 0..width {
                if prev[y * width + x].is_some() {
                    continue;
                }
                let (mut s, mut n) = (0.0, 0);
                for (dx, dy) in [(-1i64, 0i64), (1, 0), (0, -1), (0, 1)] {
                    let (nx, ny) = (x as i64 + dx, y as i64 + dy);
                    if nx >= 0 && ny >= 0 && (nx as usize) < width && (ny as usize) < height {
                        if let Some(h) = prev[ny as usize * width + nx as usize] {
                            s += h;
                            n += 1;
                        }
                    }
                }
                if n > 0 {
                    heights_m[y * width + x] = Some(s / n as f64);
                    changed = true;
                }
            }
        }
        if !changed {
            break;
        }
    }
    Ok(crate::terrain::Heightmap {
        width,
        height,
        spacing_m: spacing,
        heights_m,
    })
}

impl LoadedScenario {
    /// The seeds the file asks for (first, count).
    pub fn seeds(&self) -> (u64, u64) {
        (self.file.seeds.first, self.file.seeds.count)
    }

    fn resolve(&self, f: &Path) -> PathBuf {
        if f.is_absolute() {
            f.to_path_buf()
        } else {
            self.dir.join(f)
        }
    }

    /// Build the world and the mission for `seed` (`data`: the shared data directory, for built-in worlds).
    pub fn build(&self, data: &Path, seed: u64) -> Result<TeamScenario, String> {
        let w = &self.file.world;
        let t = &self.file.team;
        let mut out = if w.source == "builtin" {
            let b = w.builtin.as_deref().unwrap_or("cliff");
            team_scenario(b, data, None, seed)?
        } else {
            self.build_from_file(seed)?
        };
        let cfg = &mut out.2;
        if let Some(h) = t.h_max {
            cfg.params.h_max = h as f32;
        }
        if let Some(r) = t.r_max {
            cfg.params.r_max = r as f32;
        }
        if let Some(m) = t.landing_margin_m {
            cfg.params.landing_margin = m as f32;
        }
        if let Some(e) = t.landing_error_m {
            cfg.landing_error = e;
        }
        if let Some(g) = t.goal_tolerance_m {
            cfg.goal_tol = g;
        }
        if let Some(s) = t.sensor_range_m {
            cfg.sensor.range = s;
        }
        if let Some(n) = t.max_rounds {
            cfg.mission.max_rounds = n;
        }
        let h = cfg.params.h_max as f64;
        cfg.grip = if t.slip == Some(false) {
            super::grip::GripModel::never_slips(h)
        } else {
            super::grip::GripModel::for_hop(h)
        };
        if cfg.params.landing_margin >= cfg.params.h_max || cfg.params.r_max < cfg.params.h_max / 2.0 {
            return Err(field_err(
                &self.path,
                "team.h_max",
                format!(
                    "h_max {} m, r_max {} m and landing margin {} m leave no hop",
                    cfg.params.h_max, cfg.params.r_max, cfg.params.landing_margin
                ),
            ));
        }
        Ok(out)
    }

    fn build_from_file(&self, seed: u64) -> Result<TeamScenario, String> {
        use firmware::config::team::{MissionParams, TeamParams};
        let w = &self.file.world;
        let t = &self.file.team;
        let file = self.resolve(w.file.as_deref().unwrap_or(Path::new("")));
        let fe = |e: String| field_err(&self.path, "world.file", e);
        let scale = w.scale.unwrap_or(1.0);
        let vscale = w.vertical_scale.unwrap_or(1.0);
        let spacing = w.spacing_m.unwrap_or(1.0);
        let (start_xyz, goal_xyz) = (t.start.unwrap_or_default(), t.goal.unwrap_or_default());
        // (surface, the body's centre or None for a height field, background)
        let (surf, body, bg): (Box<dyn Surface>, Option<P3>, Vec<P3>) = match w.source.as_str() {
            "obj" => {
                use crate::terrain::obj::{load_obj, ObjOptions};
                let m = load_obj(&file, &ObjOptions { scale }).map_err(|e| fe(format!("{}: {e}", file.display())))?;
                let (lo, hi) = m.bounds().ok_or_else(|| fe("empty mesh".into()))?;
                let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
                let bg = m.vertices.clone();
                (Box::new(MeshSurface::new(&self.file.name, m)), Some(c), bg)
            }
            "dem" => {
                use crate::terrain::npy::{load_npy, NpyOptions};
                let mut hm = load_npy(&file, &NpyOptions::metres(spacing))
                    .map_err(|e| fe(format!("{}: {e}", file.display())))?;
                for h in hm.heights_m.iter_mut().flatten() {
                    *h *= vscale;
                }
                let s = HeightSurface::new(&self.file.name, hm);
                let bg = heights_of(&s);
                (Box::new(s), None, bg)
            }
            _ => {
                use crate::terrain::pointcloud::{load_point_cloud, PointCloudOptions};
                let pc = load_point_cloud(&file, &PointCloudOptions::default())
                    .map_err(|e| fe(format!("{}: {e}", file.display())))?;
                let (lo, _) = pc.bounds().ok_or_else(|| fe("empty point cloud".into()))?;
                // metres, the cloud's lowest corner at the origin
                let pts: Vec<P3> = pc
                    .points
                    .iter()
                    .map(|p| {
                        [
                            (p[0] - lo[0]) * scale,
                            (p[1] - lo[1]) * scale,
                            (p[2] - lo[2]) * scale * vscale,
                        ]
                    })
                    .collect();
                let hm = cloud_to_heightmap(&pts, spacing).map_err(|e| field_err(&self.path, "world.spacing_m", e))?;
                let s = HeightSurface::new(&self.file.name, hm);
                let bg = heights_of(&s);
                (Box::new(s), None, bg)
            }
        };
        let h_max = t.h_max.unwrap_or(10.0);
        let r_max = t.r_max.unwrap_or(1.5 * h_max);
        // a point of the surface "under" p: along z for a height field, towards the body's centre for a mesh
        let on_surface = |p: P3, field: &str| -> Result<(P3, P3), String> {
            let (o, d, body_c) = match body {
                None => ([p[0], p[1], p[2] + 1.0e4], [0.0, 0.0, -1.0], [p[0], p[1], p[2] - 1.0e4]),
                Some(c) => {
                    let u = unit([p[0] - c[0], p[1] - c[1], p[2] - c[2]]);
                    (
                        [c[0] + u[0] * 1.0e5, c[1] + u[1] * 1.0e5, c[2] + u[2] * 1.0e5],
                        [-u[0], -u[1], -u[2]],
                        c,
                    )
                }
            };
            let hit = surf
                .raycast(o, d, 2.0e5)
                .ok_or_else(|| field_err(&self.path, field, format!("{p:?} is not over the surface")))?;
            Ok(([o[0] + d[0] * hit, o[1] + d[1] * hit, o[2] + d[2] * hit], body_c))
        };
        let (center, body_c) = on_surface(start_xyz, "team.start")?;
        let (goal, _) = on_surface(goal_xyz, "team.goal")?;
        let spread = t.spread_m.unwrap_or(0.6 * h_max);
        let start = x_start(surf.as_ref(), center, body_c, spread).ok_or_else(|| {
            field_err(
                &self.path,
                "team.start",
                "the starting \"x\" of the team does not fit on the surface there",
            )
        })?;
        let hub = centroid(&start);
        let up = unit([hub[0] - body_c[0], hub[1] - body_c[1], hub[2] - body_c[2]]);
        let scene_m = t.scene_m.unwrap_or(2.0 * h_max);
        let grid = super::scene_grid(hub, goal, up, scene_m, t.scene_margin.unwrap_or(2));
        let params = TeamParams {
            h_max: h_max as f32,
            r_max: r_max as f32,
            landing_margin: t.landing_margin_m.unwrap_or(0.1 * h_max) as f32,
            ..TeamParams::DEFAULT
        };
        let cfg = SimConfig {
            params,
            mission: MissionParams {
                max_rounds: t.max_rounds.unwrap_or(100),
                ..MissionParams::DEFAULT
            },
            grid,
            blocked: Vec::new(),
            sensor: RangeSensor {
                rays: 3000,
                range: t.sensor_range_m.unwrap_or(2.2 * h_max),
                noise: 0.03,
                height: 0.3,
            },
            goal,
            goal_tol: t.goal_tolerance_m.unwrap_or(0.8 * h_max),
            landing_error: t.landing_error_m.unwrap_or(0.03 * h_max),
            grip: super::grip::GripModel::for_hop(h_max),
            fail: None,
            seed,
        };
        let view = if body.is_some() { up } else { [0.0, 0.0, 1.0] };
        Ok((surf, start, cfg, view, bg))
    }
}

fn heights_of(s: &HeightSurface) -> Vec<P3> {
    let hm = &s.hm;
    (0..hm.height)
        .flat_map(|y| (0..hm.width).map(move |x| (x, y)))
        .filter_map(|(x, y)| {
            hm.get(x, y)
                .map(|z| [x as f64 * hm.spacing_m, y as f64 * hm.spacing_m, z])
        })
        .collect()
}
