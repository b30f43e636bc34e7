//! Scenario files (TOML): the world, the rover's start, the tether's root anchor, the goal, the sensor, seeds,
//! budgets and map parameters. The schema is documented in `host-sim/doc/scenario.md`; files live in
//! `host-sim/scenarios/`.
//!
//! [`load`] parses, builds the world and checks the scenario against it; every rejection is a [`ScenarioError`]
//! naming the file, the field and the reason (syntax errors, unknown fields and kinds, NaN or infinite numbers,
//! a missing terrain file, a start or goal outside the world's bounds, a start or root anchor inside the terrain).

use crate::sensor::RangeSensorParams;
use crate::terrain::asc::load_asc;
use crate::terrain::geotiff::{load_geotiff, GeoTiffOptions};
use crate::terrain::npy::{load_npy, FirstRow, NpyOptions};
use crate::terrain::obj::{load_obj, ObjOptions};
use crate::world::crater::{CraterWall, CraterWallParams};
use crate::world::heightmap::HeightmapWorld;
use crate::world::ledge::{LedgeError, LedgeParams, LedgeShape, LedgeWorld, Pole};
use crate::world::mesh::MeshWorld;
use crate::world::World;
use firmware::config::map::MapConfig;
use firmware::geom::{Real, Vec3};
use firmware::map::DistanceQuery;
use serde::Deserialize;
use std::path::{Path, PathBuf};

/// A rejected scenario: file, field (dotted TOML path) and reason.
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioError {
    /// The scenario file.
    pub file: PathBuf,
    /// Dotted path of the offending field (`"(syntax)"` for TOML syntax or type errors, with line/column).
    pub field: String,
    /// What is wrong, in words a user can act on.
    pub reason: String,
}

impl core::fmt::Display for ScenarioError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}: {}: {}", self.file.display(), self.field, self.reason)
    }
}

impl core::error::Error for ScenarioError {}

/// `[world.terrain]`: a DEM file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TerrainSection {
    /// Path of the DEM, relative to the scenario file.
    pub file: PathBuf,
    /// `geotiff`, `asc` or `npy`; default from the extension (`.tif`, `.tiff`, `.asc`, `.npy`).
    #[serde(default)]
    pub format: Option<String>,
    /// Stored sample to metres (e.g. 0.5 for the LOLA Kepler file). Default 1.
    #[serde(default = "one")]
    pub height_scale: f64,
    /// Multiplies the post spacing. Default 1.
    #[serde(default = "one")]
    pub horizontal_scale: f64,
    /// Multiplies the heights (after `height_scale`). Default 1.
    #[serde(default = "one")]
    pub vertical_scale: f64,
    /// Post spacing override, metres (GeoTIFF without a pixel-scale tag). Default: from the file. Required for
    /// `npy` (the format carries no georeferencing).
    #[serde(default)]
    pub spacing_m: Option<f64>,
    /// "No data" stored value (GeoTIFF: overrides the GDAL_NODATA tag; npy: a sentinel besides NaN).
    #[serde(default)]
    pub nodata: Option<f64>,
    /// `npy` only: which map edge the array's first row is, `north` (image convention, default) or `south`.
    #[serde(default)]
    pub first_row: Option<String>,
}

/// `[world.mesh]`: a closed triangle mesh (OBJ shape model).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSection {
    /// Path of the mesh, relative to the scenario file.
    pub file: PathBuf,
    /// `obj` (the only mesh format); default from the extension.
    #[serde(default)]
    pub format: Option<String>,
    /// Unit of the file's coordinates: `m` (default) or `km` (the asteroid shape models).
    #[serde(default)]
    pub units: Option<String>,
    /// Extra scale after the unit conversion (e.g. 0.1 makes a 535 m asteroid a 53 m rock field). Default 1.
    #[serde(default = "one")]
    pub scale: f64,
}

fn one() -> f64 {
    1.0
}

/// `[world]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSection {
    /// `crater_wall`, `ledge`, `ledge_pole`, `terrain` or `mesh`.
    pub kind: String,
    /// Parameters when `kind = "crater_wall"` (all optional, defaults in [`CraterWallParams`]).
    #[serde(default)]
    pub crater_wall: Option<CraterWallParams>,
    /// A variant of the ledge when `kind = "ledge"` or `"ledge_pole"` (all optional, defaults in [`LedgeParams`]).
    #[serde(default)]
    pub ledge: Option<LedgeParams>,
    /// The DEM when `kind = "terrain"`.
    #[serde(default)]
    pub terrain: Option<TerrainSection>,
    /// The mesh when `kind = "mesh"`.
    #[serde(default)]
    pub mesh: Option<MeshSection>,
    /// Render the analytic world (`crater_wall`, `ledge`, `ledge_pole`) as a DEM with this post spacing, metres,
    /// and use the DEM as the world ([`HeightmapWorld::render`]): the same experiment on a height field. Default:
    /// the analytic world itself.
    #[serde(default)]
    pub dem_spacing_m: Option<f64>,
}

/// `[rover]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RoverSection {
    /// Start position of the rover reference point (axle centre), metres.
    pub start: [f64; 3],
    /// Start heading, degrees from +x. Default 0.
    #[serde(default)]
    pub yaw_deg: f64,
}

/// `[tether]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TetherSection {
    /// Root anchor, metres.
    pub root_anchor: [f64; 3],
    /// Tether length available, metres. Default 100.
    #[serde(default = "hundred")]
    pub length_m: f64,
}

fn hundred() -> f64 {
    100.0
}

/// `[goal]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GoalSection {
    /// Goal position, metres.
    pub position: [f64; 3],
    /// Goal region radius, metres. Default 0.5.
    #[serde(default = "half")]
    pub tolerance_m: f64,
}

fn half() -> f64 {
    0.5
}

/// `[seeds]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Seeds {
    /// Sensor noise and dropouts. Default 1.
    pub sensor: u64,
    /// Planner sampling. Default 1.
    pub planner: u64,
    /// Trials of a campaign use seeds `planner .. planner + trials`. Default 1.
    pub trials: u32,
}

impl Default for Seeds {
    fn default() -> Self {
        Seeds { sensor: 1, planner: 1, trials: 1 }
    }
}

/// `[plan]`: where the tether-aware planner samples (Paton et al. V). Both corners or neither.
#[derive(Debug, Clone, PartialEq, Deserialize, Default)]
#[serde(deny_unknown_fields, default)]
pub struct PlanSection {
    /// Lower corner of the planning box, metres. Default: the world's bounds.
    pub bounds_min: Option<[f64; 3]>,
    /// Upper corner of the planning box, metres. Default: the world's bounds.
    pub bounds_max: Option<[f64; 3]>,
}

/// `[budgets]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Budgets {
    /// Planner iterations per plan. Default 750 (Paton et al. VI-A).
    pub planner_iterations: u32,
    /// ESDF budget per update, in sweeps of `firmware::config::map::ESDF_VISITS_PER_BLOCK` voxel visits per block in
    /// use. Default 32.
    pub esdf_max_sweeps: usize,
    /// Voxels per integrated ray. Default 128 (at 5 cm).
    pub max_ray_voxels: usize,
}

impl Default for Budgets {
    fn default() -> Self {
        Budgets { planner_iterations: 750, esdf_max_sweeps: 32, max_ray_voxels: 128 }
    }
}

/// `[map]`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct MapSection {
    /// Voxel edge, metres. Default 0.05.
    pub voxel_size_m: f64,
    /// TSDF truncation, metres. Default 3 voxels.
    pub truncation_m: Option<f64>,
    /// ESDF saturation distance, metres. Default 1.5.
    pub esdf_max_distance_m: f64,
    /// Pool size in blocks. Default `FLIGHT_BLOCKS` (the flight board's pool, 23,040 blocks of 4^3 voxels).
    pub pool_blocks: usize,
    /// Free space carved along each ray in front of its return, metres (`MapConfig::max_carve_length`). Default
    /// 4.0; bounded by `budgets.max_ray_voxels` voxels per ray.
    pub max_carve_length_m: Option<f64>,
    /// ESDF hysteresis, voxels (`MapConfig::esdf_site_tolerance`): a surface voxel whose TSDF moves by less keeps
    /// its ESDF value. Default 0.1; at most 0.5. Larger is faster and adds at most this much ESDF error
    /// (`host-sim/doc/map.md`).
    pub esdf_site_tolerance_voxels: Option<f64>,
}

impl Default for MapSection {
    fn default() -> Self {
        MapSection {
            voxel_size_m: 0.05,
            truncation_m: None,
            esdf_max_distance_m: 1.5,
            pool_blocks: firmware::config::map::FLIGHT_BLOCKS,
            max_carve_length_m: None,
            esdf_site_tolerance_voxels: None,
        }
    }
}

/// `[faults]`: a fault profile for the mission's link (`host-sim/doc/faults.md`), the same keys as
/// `--faults` (the kind keys are the uplink's; `[faults.down]`, or `down.KIND = RATE` in `[faults]`, the downlink's): a rate per byte in [0, 1] for each kind (`bitflip`, `drop`, `duplicate`, `reorder`, `truncate`,
/// `delay`, `stall`; `all` sets every kind first, the named ones then override it), `delay_us` (default 200 ms),
/// `stall_us` (500 ms), `reorder_hold_us` (200 ms) and the injector's `seed` (0; a campaign's mission `s` uses
/// `seed ^ s`).
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FaultsSection {
    /// Every kind's rate per byte (before the named kinds).
    pub all: Option<f64>,
    /// Bit flips per byte.
    pub bitflip: Option<f64>,
    /// Lost frames per byte.
    pub drop: Option<f64>,
    /// Duplicated frames per byte.
    pub duplicate: Option<f64>,
    /// Reordered frames per byte.
    pub reorder: Option<f64>,
    /// Truncated frames per byte.
    pub truncate: Option<f64>,
    /// Delayed frames per byte.
    pub delay: Option<f64>,
    /// Stalls per byte.
    pub stall: Option<f64>,
    /// Hold of a delayed frame, microseconds.
    pub delay_us: Option<u64>,
    /// Length of a stall, microseconds.
    pub stall_us: Option<u64>,
    /// Longest hold of a frame waiting for one to swap with, microseconds.
    pub reorder_hold_us: Option<u64>,
    /// Seed of the injector.
    pub seed: Option<u64>,
    /// The downlink's rates (`[faults.down]`: the kind keys and `all` only).
    pub down: Option<Box<FaultsSection>>,
}

/// Fills `rates` from `all` then each kind's given rate ([`FaultKind::ALL`] order); errors name `prefix.KEY`.
fn fill_rates(
    rates: &mut [f64; 7],
    prefix: &str,
    all: Option<f64>,
    given: [Option<f64>; 7],
) -> Result<(), (String, String)> {
    use crate::link::faults::FaultKind;
    let rate = |key: &str, r: f64| {
        if (0.0..=1.0).contains(&r) {
            Ok(r)
        } else {
            Err((format!("{prefix}.{key}"), format!("a rate per byte must be in [0, 1], got {r}")))
        }
    };
    if let Some(r) = all {
        *rates = [rate("all", r)?; 7];
    }
    for ((kind, given), slot) in FaultKind::ALL.iter().zip(given).zip(rates.iter_mut()) {
        if let Some(r) = given {
            *slot = rate(kind.name(), r)?;
        }
    }
    Ok(())
}

impl FaultsSection {
    /// The injector's profile; errors name the field (`faults.KIND`) and the reason.
    pub fn profile(&self) -> Result<crate::link::faults::FaultProfile, (String, String)> {
        use crate::link::faults::FaultProfile;
        let mut p = FaultProfile::default();
        // in `FaultKind::ALL` order
        let up = [self.bitflip, self.drop, self.duplicate, self.reorder, self.truncate, self.delay, self.stall];
        fill_rates(&mut p.rates, "faults", self.all, up)?;
        if let Some(d) = &self.down {
            let shared = [
                ("delay_us", d.delay_us.is_some()),
                ("stall_us", d.stall_us.is_some()),
                ("reorder_hold_us", d.reorder_hold_us.is_some()),
                ("seed", d.seed.is_some()),
                ("down", d.down.is_some()),
            ];
            if let Some((key, _)) = shared.iter().find(|(_, given)| *given) {
                return Err((
                    format!("faults.down.{key}"),
                    "only rates per byte go here; the delays and the seed are the [faults] section's, for both directions".into(),
                ));
            }
            let down = [d.bitflip, d.drop, d.duplicate, d.reorder, d.truncate, d.delay, d.stall];
            fill_rates(&mut p.down_rates, "faults.down", d.all, down)?;
        }
        p.delay_us = self.delay_us.unwrap_or(p.delay_us);
        p.stall_us = self.stall_us.unwrap_or(p.stall_us);
        p.reorder_hold_us = self.reorder_hold_us.unwrap_or(p.reorder_hold_us);
        p.seed = self.seed.unwrap_or(p.seed);
        Ok(p)
    }
}

/// A parsed scenario file.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scenario {
    /// Short name.
    pub name: String,
    /// What the scenario is for.
    #[serde(default)]
    pub description: String,
    /// The world.
    pub world: WorldSection,
    /// The rover's start.
    pub rover: RoverSection,
    /// The tether.
    pub tether: TetherSection,
    /// The goal.
    pub goal: GoalSection,
    /// The range sensor (all fields optional).
    #[serde(default)]
    pub sensor: RangeSensorParams,
    /// Seeds.
    #[serde(default)]
    pub seeds: Seeds,
    /// Budgets.
    #[serde(default)]
    pub budgets: Budgets,
    /// Map parameters.
    #[serde(default)]
    pub map: MapSection,
    /// Planning region (the `campaign` command and the onboard planner's bounds).
    #[serde(default)]
    pub plan: PlanSection,
    /// The closed-loop mission's models (`tetherbot mission`; all optional, defaults in
    /// [`crate::mission::params::MissionSection`]).
    #[serde(default)]
    pub mission: crate::mission::params::MissionSection,
    /// Link faults injected on the mission's uplink (`tetherbot mission`; `--faults` on the command line replaces
    /// the whole section). Absent: a clean link.
    #[serde(default)]
    pub faults: Option<FaultsSection>,
    /// The file it came from (set by [`load`]).
    #[serde(skip)]
    pub file: PathBuf,
    /// Dotted paths of the `[tether]`, `[goal]`, `[sensor]` and `[map]` fields the file gives (set by [`parse`]):
    /// a command that cannot apply one says so instead of ignoring it ([`Scenario::gives`]).
    #[serde(skip)]
    given: Vec<String>,
}

/// A world description, resolved (paths absolute).
#[derive(Debug, Clone, PartialEq)]
pub enum WorldSpec {
    /// The three-plane crater wall.
    CraterWall(CraterWallParams),
    /// Paton et al.'s ledge or a variant of it: its shape and the poles on its top (test 3: one, [`Pole::TEST3`]).
    Ledge {
        /// The prism.
        shape: LedgeShape,
        /// The poles.
        poles: Vec<Pole>,
    },
    /// A DEM.
    Terrain(TerrainSection),
    /// A closed triangle mesh.
    Mesh(MeshSection),
    /// An analytic world rendered as a DEM (`[world] dem_spacing_m`).
    Rendered {
        /// The analytic world.
        of: Box<WorldSpec>,
        /// Post spacing, metres.
        spacing_m: f64,
    },
}

impl WorldSpec {
    /// The built-in worlds by name: `crater_wall`, `ledge`, `ledge_pole`, `marsyard` (the ERC Mars Yard DEM),
    /// `hirise_cliff` (the HiRISE NumPy crop at 1.01 m) and `itokawa` (the shape model in km, scaled by 0.2), with
    /// file paths relative to the shared data directory; the same worlds as the shipped scenario files.
    pub fn by_name(name: &str) -> Option<WorldSpec> {
        Some(match name {
            "crater_wall" => WorldSpec::CraterWall(CraterWallParams::default()),
            "ledge" => WorldSpec::Ledge { shape: LedgeShape::PATON, poles: vec![] },
            "ledge_pole" => WorldSpec::Ledge { shape: LedgeShape::PATON, poles: vec![Pole::TEST3] },
            "marsyard" => WorldSpec::Terrain(TerrainSection {
                file: PathBuf::from("terrain/erc_marsyard2021_hm.tif"),
                format: None,
                height_scale: 1.0,
                horizontal_scale: 1.0,
                vertical_scale: 1.0,
                spacing_m: None,
                nodata: None,
                first_row: None,
            }),
            "hirise_cliff" => WorldSpec::Terrain(TerrainSection {
                file: PathBuf::from("terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy"),
                format: Some("npy".into()),
                height_scale: 1.0,
                horizontal_scale: 1.0,
                vertical_scale: 1.0,
                spacing_m: Some(1.01),
                nodata: None,
                first_row: None,
            }),
            "itokawa" => WorldSpec::Mesh(MeshSection {
                file: PathBuf::from("asteroids/itokawa.obj"),
                format: None,
                units: Some("km".into()),
                scale: 0.2,
            }),
            _ => return None,
        })
    }

    /// Builds the world; relative terrain paths are resolved against `base`. Errors: `(field, reason)`.
    pub fn build(&self, base: &Path) -> Result<Box<dyn World>, (String, String)> {
        match self {
            WorldSpec::CraterWall(p) => CraterWall::new(p.clone())
                .map(|w| Box::new(w) as Box<dyn World>)
                .map_err(|(f, r)| (format!("world.crater_wall.{f}"), r)),
            WorldSpec::Ledge { shape, poles } => LedgeWorld::custom(*shape, poles)
                .map(|w| Box::new(w) as Box<dyn World>)
                .map_err(|e| ledge_error(&e)),
            WorldSpec::Rendered { of, spacing_m } => {
                let analytic = of.build(base)?;
                let name = format!("{}-dem{spacing_m}", analytic.name());
                HeightmapWorld::render(&name, analytic.as_ref(), *spacing_m)
                    .map(|w| Box::new(w) as Box<dyn World>)
                    .map_err(|e| ("world.dem_spacing_m".to_string(), e.0))
            }
            WorldSpec::Terrain(t) => {
                let f = |r: String| ("world.terrain".to_string(), r);
                let path = base.join(&t.file);
                if !path.is_file() {
                    return Err(("world.terrain.file".into(), format!("no such file: {}", path.display())));
                }
                let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
                let format = t.format.clone().unwrap_or_else(|| match ext.as_str() {
                    "tif" | "tiff" => "geotiff".into(),
                    other => other.to_string(),
                });
                let hm = match format.as_str() {
                    "geotiff" => load_geotiff(
                        &path,
                        &GeoTiffOptions { height_scale: t.height_scale, spacing_m: t.spacing_m, nodata: t.nodata },
                    )
                    .map_err(|e| f(format!("{}: {e}", path.display())))?,
                    "asc" => load_asc(&path, t.height_scale).map_err(|e| f(format!("{}: {e}", path.display())))?,
                    "npy" => {
                        let Some(spacing_m) = t.spacing_m else {
                            return Err((
                                "world.terrain.spacing_m".into(),
                                "a .npy grid carries no post spacing: give spacing_m (1.01 for the HiRISE crop)".into(),
                            ));
                        };
                        if !(spacing_m.is_finite() && spacing_m > 0.0) {
                            return Err(("world.terrain.spacing_m".into(), format!("must be finite and > 0, got {spacing_m}")));
                        }
                        if !(t.height_scale.is_finite() && t.height_scale > 0.0) {
                            return Err((
                                "world.terrain.height_scale".into(),
                                format!("must be finite and > 0, got {}", t.height_scale),
                            ));
                        }
                        let first_row = match t.first_row.as_deref() {
                            None | Some("north") => FirstRow::North,
                            Some("south") => FirstRow::South,
                            Some(other) => {
                                return Err((
                                    "world.terrain.first_row".into(),
                                    format!("unknown edge {other:?}: use north or south"),
                                ))
                            }
                        };
                        let opts = NpyOptions { spacing_m, height_scale: t.height_scale, nodata: t.nodata, first_row };
                        load_npy(&path, &opts).map_err(|e| f(format!("{}: {e}", path.display())))?
                    }
                    "obj" => {
                        return Err((
                            "world.terrain.format".into(),
                            "an OBJ mesh is not a height field: use kind = \"mesh\" with a [world.mesh] table".into(),
                        ))
                    }
                    other => {
                        return Err((
                            "world.terrain.format".into(),
                            format!("unknown format {other:?}: use geotiff, asc or npy"),
                        ))
                    }
                };
                if format != "npy" && t.first_row.is_some() {
                    return Err(("world.terrain.first_row".into(), "only applies to format = \"npy\"".into()));
                }
                let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("terrain").to_string();
                HeightmapWorld::new(&name, &hm, t.horizontal_scale, t.vertical_scale)
                    .map(|w| Box::new(w) as Box<dyn World>)
                    .map_err(|e| f(e.0))
            }
            WorldSpec::Mesh(m) => {
                let path = base.join(&m.file);
                if !path.is_file() {
                    return Err(("world.mesh.file".into(), format!("no such file: {}", path.display())));
                }
                let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("").to_ascii_lowercase();
                let format = m.format.clone().unwrap_or(ext);
                if format != "obj" {
                    return Err(("world.mesh.format".into(), format!("unknown mesh format {format:?}: use obj")));
                }
                let unit = match m.units.as_deref() {
                    None | Some("m") => ObjOptions::METRES,
                    Some("km") => ObjOptions::KILOMETRES,
                    Some(other) => {
                        return Err(("world.mesh.units".into(), format!("unknown unit {other:?}: use m or km")))
                    }
                };
                if !(m.scale.is_finite() && m.scale > 0.0) {
                    return Err(("world.mesh.scale".into(), format!("must be finite and > 0, got {}", m.scale)));
                }
                let mesh = load_obj(&path, &unit).map_err(|e| ("world.mesh".to_string(), format!("{}: {e}", path.display())))?;
                let name = path.file_stem().and_then(|s| s.to_str()).unwrap_or("mesh").to_string();
                MeshWorld::new(&name, &mesh, m.scale)
                    .map(|w| Box::new(w) as Box<dyn World>)
                    .map_err(|e| ("world.mesh".to_string(), e.0))
            }
        }
    }
}

/// A ledge variant's error as `(field, reason)`: `world.ledge.slope_deg`, `world.ledge.poles[1].radius_m`.
fn ledge_error(e: &LedgeError) -> (String, String) {
    let field = match e.pole {
        Some(i) => format!("world.ledge.poles[{i}].{}", e.field),
        None => format!("world.ledge.{}", e.field),
    };
    (field, e.reason.to_string())
}

impl Scenario {
    /// The world kind as written.
    pub fn world_kind(&self) -> String {
        self.world.kind.clone()
    }

    /// Whether the file gives `dotted` (e.g. `"map.voxel_size_m"`, or `"sensor"` for any field of `[sensor]`)
    /// rather than leaving it at its default. Tracked for the `[tether]`, `[goal]`, `[sensor]` and `[map]` tables.
    pub fn gives(&self, dotted: &str) -> bool {
        self.given.iter().any(|g| g == dotted || g.strip_prefix(dotted).is_some_and(|rest| rest.starts_with('.')))
    }

    /// The scenario's name made safe as one path component of an output directory: characters other than ASCII
    /// letters, digits, `-`, `_` and `.` become `_`, and a name that is empty or only dots becomes `_` followed by
    /// it, so neither an absolute name (`/etc`) nor `..` can leave the output directory.
    pub fn file_safe_name(&self) -> String {
        file_safe(&self.name)
    }

    fn err(&self, field: &str, reason: impl Into<String>) -> ScenarioError {
        ScenarioError { file: self.file.clone(), field: field.into(), reason: reason.into() }
    }

    /// The world spec of this scenario.
    pub fn world_spec(&self) -> Result<WorldSpec, ScenarioError> {
        let w = &self.world;
        let spec = match w.kind.as_str() {
            "crater_wall" => Ok(WorldSpec::CraterWall(w.crater_wall.clone().unwrap_or_default())),
            "ledge" | "ledge_pole" => {
                let default_poles: &[Pole] = if w.kind == "ledge" { &[] } else { &[Pole::TEST3] };
                let (shape, poles) = w.ledge.clone().unwrap_or_default().resolve(default_poles);
                // refused here, with the field, rather than when the world is built
                LedgeWorld::custom(shape, &poles).map_err(|e| {
                    let (field, reason) = ledge_error(&e);
                    self.err(&field, reason)
                })?;
                Ok(WorldSpec::Ledge { shape, poles })
            }
            "terrain" => w
                .terrain
                .clone()
                .map(WorldSpec::Terrain)
                .ok_or_else(|| self.err("world.terrain", "kind = \"terrain\" needs a [world.terrain] table with `file`")),
            "mesh" => w
                .mesh
                .clone()
                .map(WorldSpec::Mesh)
                .ok_or_else(|| self.err("world.mesh", "kind = \"mesh\" needs a [world.mesh] table with `file`")),
            other => Err(self.err(
                "world.kind",
                format!("unknown world kind {other:?}: use crater_wall, ledge, ledge_pole, terrain or mesh"),
            )),
        }?;
        // a table for another kind would be read and then ignored
        for (table, given, kinds) in [
            ("world.crater_wall", w.crater_wall.is_some(), &["crater_wall"][..]),
            ("world.ledge", w.ledge.is_some(), &["ledge", "ledge_pole"][..]),
            ("world.terrain", w.terrain.is_some(), &["terrain"][..]),
            ("world.mesh", w.mesh.is_some(), &["mesh"][..]),
        ] {
            if given && !kinds.contains(&w.kind.as_str()) {
                return Err(self.err(table, format!("applies to kind = {:?}, not {:?}", kinds.join(" or "), w.kind)));
            }
        }
        match w.dem_spacing_m {
            None => Ok(spec),
            Some(_) if matches!(spec, WorldSpec::Terrain(_) | WorldSpec::Mesh(_)) => Err(self.err(
                "world.dem_spacing_m",
                format!("renders an analytic world (crater_wall, ledge, ledge_pole) as a DEM, not kind = {:?}", w.kind),
            )),
            Some(spacing_m) => Ok(WorldSpec::Rendered { of: Box::new(spec), spacing_m }),
        }
    }

    /// Builds the world (terrain paths relative to the scenario file).
    pub fn build_world(&self) -> Result<Box<dyn World>, ScenarioError> {
        let base = self.file.parent().unwrap_or(Path::new("."));
        self.world_spec()?.build(base).map_err(|(f, r)| self.err(&f, r))
    }

    /// The map configuration of this scenario.
    pub fn map_config(&self) -> Result<MapConfig, ScenarioError> {
        let mut c = MapConfig::with_voxel_size(self.map.voxel_size_m as Real);
        if let Some(t) = self.map.truncation_m {
            c.truncation = t as Real;
        }
        c.esdf_max_distance = self.map.esdf_max_distance_m as Real;
        if let Some(l) = self.map.max_carve_length_m {
            c.max_carve_length = l as Real;
        }
        if let Some(t) = self.map.esdf_site_tolerance_voxels {
            c.esdf_site_tolerance = t as Real;
        }
        c.esdf_max_sweeps = self.budgets.esdf_max_sweeps;
        c.max_ray_voxels = self.budgets.max_ray_voxels;
        c.validate().map_err(|e| {
            let field = match e.field {
                "voxel_size" => "map.voxel_size_m".to_string(),
                "truncation" => "map.truncation_m".to_string(),
                "esdf_max_distance" => "map.esdf_max_distance_m".to_string(),
                "esdf_max_sweeps" => "budgets.esdf_max_sweeps".to_string(),
                "max_ray_voxels" => "budgets.max_ray_voxels".to_string(),
                "max_carve_length" => "map.max_carve_length_m".to_string(),
                "esdf_site_tolerance" => "map.esdf_site_tolerance_voxels".to_string(),
                f => format!("map.{f}"),
            };
            self.err(&field, e.reason)
        })?;
        Ok(c)
    }

    /// Checks numbers, then the geometry against `world`.
    pub fn check(&self, world: &dyn World) -> Result<(), ScenarioError> {
        let finite3 = |field: &str, v: &[f64; 3]| {
            if v.iter().all(|x| x.is_finite()) {
                Ok(())
            } else {
                Err(self.err(field, format!("must be three finite numbers, got {v:?}")))
            }
        };
        finite3("rover.start", &self.rover.start)?;
        finite3("tether.root_anchor", &self.tether.root_anchor)?;
        finite3("goal.position", &self.goal.position)?;
        if !self.rover.yaw_deg.is_finite() {
            return Err(self.err("rover.yaw_deg", "must be finite"));
        }
        if !(self.goal.tolerance_m.is_finite() && self.goal.tolerance_m > 0.0) {
            return Err(self.err("goal.tolerance_m", format!("must be > 0, got {}", self.goal.tolerance_m)));
        }
        if !(self.tether.length_m.is_finite() && self.tether.length_m > 0.0) {
            return Err(self.err("tether.length_m", format!("must be > 0, got {}", self.tether.length_m)));
        }
        if self.seeds.trials == 0 {
            return Err(self.err("seeds.trials", "must be >= 1"));
        }
        if self.budgets.planner_iterations == 0 {
            return Err(self.err("budgets.planner_iterations", "must be >= 1"));
        }
        if !(self.map.pool_blocks > 0 && self.map.pool_blocks <= 1 << 20) {
            return Err(self.err("map.pool_blocks", format!("must be in 1..=1048576, got {}", self.map.pool_blocks)));
        }
        self.sensor.validate().map_err(|(f, r)| self.err(&format!("sensor.{f}"), r))?;
        self.mission.validate().map_err(|(f, r)| self.err(&format!("mission.{f}"), r))?;
        self.map_config()?;
        match (&self.plan.bounds_min, &self.plan.bounds_max) {
            (None, None) => {}
            (Some(lo), Some(hi)) => {
                finite3("plan.bounds_min", lo)?;
                finite3("plan.bounds_max", hi)?;
                if !(0..3).all(|i| lo[i] < hi[i]) {
                    return Err(self.err("plan.bounds_max", format!("must exceed plan.bounds_min on every axis: {lo:?} vs {hi:?}")));
                }
            }
            _ => return Err(self.err("plan.bounds_min", "give both plan.bounds_min and plan.bounds_max, or neither")),
        }
        let b = world.bounds();
        let inside_xy = |p: &[f64; 3]| {
            p[0] >= b.min.x as f64 && p[0] <= b.max.x as f64 && p[1] >= b.min.y as f64 && p[1] <= b.max.y as f64
        };
        for (field, p) in [("rover.start", &self.rover.start), ("goal.position", &self.goal.position)] {
            if !inside_xy(p) {
                return Err(self.err(
                    field,
                    format!(
                        "({:.2}, {:.2}) is outside the world's bounds x [{:.2}, {:.2}], y [{:.2}, {:.2}]",
                        p[0], p[1], b.min.x, b.max.x, b.min.y, b.max.y
                    ),
                ));
            }
        }
        let sd = |p: &[f64; 3]| match world.query(&Vec3::new(p[0] as Real, p[1] as Real, p[2] as Real)) {
            DistanceQuery::Known { distance, .. } => Some(distance),
            DistanceQuery::Unknown => None,
        };
        for (field, p) in [("rover.start", &self.rover.start), ("tether.root_anchor", &self.tether.root_anchor), ("goal.position", &self.goal.position)] {
            if let Some(d) = sd(p) {
                if d < -0.01 {
                    return Err(self.err(field, format!("{p:?} is inside the terrain (signed distance {d:.3} m)")));
                }
            }
        }
        Ok(())
    }
}

/// `name` as one safe path component (see [`Scenario::file_safe_name`]).
pub fn file_safe(name: &str) -> String {
    let s: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || matches!(c, '-' | '_' | '.') { c } else { '_' })
        .collect();
    if s.chars().all(|c| c == '.') {
        format!("_{s}")
    } else {
        s
    }
}

/// Parses a scenario from text (`file` is used in errors and to resolve terrain paths); does not build the world.
pub fn parse(text: &str, file: &Path) -> Result<Scenario, ScenarioError> {
    let syntax = |e: toml::de::Error| ScenarioError {
        file: file.to_path_buf(),
        field: "(syntax)".into(),
        reason: e.to_string().trim().replace('\n', " "),
    };
    let mut sc: Scenario = toml::from_str(text).map_err(syntax)?;
    sc.file = file.to_path_buf();
    if let Some(Err((field, reason))) = sc.faults.as_ref().map(FaultsSection::profile) {
        return Err(sc.err(&field, reason));
    }
    let table: toml::Table = toml::from_str(text).map_err(syntax)?;
    for section in ["tether", "goal", "sensor", "map"] {
        if let Some(toml::Value::Table(t)) = table.get(section) {
            sc.given.extend(t.keys().map(|k| format!("{section}.{k}")));
        }
    }
    Ok(sc)
}

/// Reads, parses, builds the world and checks the scenario.
pub fn load(file: &Path) -> Result<Scenario, ScenarioError> {
    let text = std::fs::read_to_string(file).map_err(|e| ScenarioError {
        file: file.to_path_buf(),
        field: "(file)".into(),
        reason: format!("cannot read: {e}"),
    })?;
    let sc = parse(&text, file)?;
    let world = sc.build_world()?;
    sc.check(world.as_ref())?;
    Ok(sc)
}

#[cfg(test)]
mod tests {
    use super::*;

    const CRATER: &str = r#"
name = "crater"
[world]
kind = "crater_wall"
[world.crater_wall]
wall_angle_deg = 55.0
rocks = 4
[rover]
start = [-2.0, 0.0, 6.4]
[tether]
root_anchor = [-5.0, 0.0, 8.0]
[goal]
position = [7.0, 0.0, 0.4]
"#;

    fn dir() -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("scenarios")
    }

    /// The shipped scenario files: `scenarios/*.toml` and the ledge variants `scenarios/variants/*.toml`.
    pub(super) fn shipped() -> Vec<PathBuf> {
        let mut files = Vec::new();
        for d in [dir(), dir().join("variants")] {
            for entry in std::fs::read_dir(d).unwrap() {
                let p = entry.unwrap().path();
                if p.extension().is_some_and(|e| e == "toml") {
                    files.push(p);
                }
            }
        }
        files.sort();
        files
    }

    const LEDGE: &str = r#"
name = "ledge variant"
[world]
kind = "ledge"
[world.ledge]
slope_deg = 45.0
height_m = 3.0
[[world.ledge.poles]]
centre_xy = [-2.5, 1.0]
radius_m = 0.4
[[world.ledge.poles]]
centre_xy = [-1.0, -1.5]
radius_m = 0.1
height_m = 3.0
[rover]
start = [-4.0, 0.0, 3.35]
[tether]
root_anchor = [6.0, 0.0, 5.0]
[goal]
position = [6.0, 0.0, 0.35]
"#;

    /// A ledge variant is a file: its slope, height and poles are the world's; impossible variants and a table
    /// for another kind are refused with the field.
    #[test]
    fn ledge_variants_are_files() {
        let sc = check_text(LEDGE).unwrap();
        let w = sc.build_world().unwrap();
        let h = |x: f64, y: f64| f64::from(w.height_at(x as Real, y as Real).unwrap());
        assert_eq!(h(-4.0, 0.0), 3.0);
        assert_eq!(h(-2.5, 1.0), 9.0); // the first pole: the default height, 6 m
        assert_eq!(h(-1.0, -1.5), 6.0);
        assert!((h(1.0, 0.0) - 2.0).abs() < 1e-6, "45 degrees: {}", h(1.0, 0.0));
        assert_eq!(w.name(), "ledge45-2poles");
        let WorldSpec::Ledge { poles, .. } = sc.world_spec().unwrap() else { panic!("a ledge") };
        assert_eq!(poles.len(), 2);
        // kind = "ledge_pole" without poles is test 3's pole; with `[world.ledge]` poles, those
        let pole = check_text(&LEDGE.replace("kind = \"ledge\"", "kind = \"ledge_pole\"")).unwrap();
        assert_eq!(pole.world_spec().unwrap(), sc.world_spec().unwrap());
        let no_table = LEDGE.split("[world.ledge]").next().unwrap().to_string() + "[rover]\nstart = [-4.0, 0.0, 4.35]\n[tether]\nroot_anchor = [6.0, 0.0, 5.0]\n[goal]\nposition = [6.0, 0.0, 0.35]\n";
        let paton = check_text(&no_table.replace("kind = \"ledge\"", "kind = \"ledge_pole\"")).unwrap();
        assert_eq!(paton.world_spec().unwrap(), WorldSpec::by_name("ledge_pole").unwrap());
        let cases: Vec<(String, &str, &str)> = vec![
            (LEDGE.replace("slope_deg = 45.0", "slope_deg = 90.0"), "world.ledge.slope_deg", "between 5 and 85"),
            (LEDGE.replace("height_m = 3.0\n[[", "height_m = -3.0\n[["), "world.ledge.height_m", "above 0"),
            (LEDGE.replace("centre_xy = [-1.0, -1.5]", "centre_xy = [-2.5, 0.6]"), "world.ledge.poles[1].centre_xy", "earlier pole"),
            (LEDGE.replace("centre_xy = [-1.0, -1.5]", "centre_xy = [1.0, -1.5]"), "world.ledge.poles[1].centre_xy", "inside the ledge top"),
            (LEDGE.replace("radius_m = 0.1", "radius_m = nan"), "world.ledge.poles[1].radius_m", "finite"),
            (LEDGE.replace("radius_m = 0.4", "radius = 0.4"), "(syntax)", "unknown field"),
            (LEDGE.replace("kind = \"ledge\"", "kind = \"crater_wall\""), "world.ledge", "applies to kind"),
            (CRATER.replace("kind = \"crater_wall\"", "kind = \"ledge\""), "world.crater_wall", "applies to kind"),
        ];
        for (text, field, reason) in cases {
            let e = check_text(&text).unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert!(e.reason.contains(reason), "{e}");
        }
    }

    /// `dem_spacing_m` renders the analytic world as a DEM: the same heights at the posts, a height-field world.
    #[test]
    fn an_analytic_world_rendered_as_a_dem() {
        let text = LEDGE.replace("kind = \"ledge\"", "kind = \"ledge\"\ndem_spacing_m = 0.05");
        let sc = check_text(&text).unwrap();
        assert!(matches!(sc.world_spec().unwrap(), WorldSpec::Rendered { spacing_m: 0.05, .. }));
        let (dem, exact) = (sc.build_world().unwrap(), check_text(LEDGE).unwrap().build_world().unwrap());
        assert_eq!(dem.name(), "ledge45-2poles-dem0.05");
        assert!(dem.exact_geometry().solids.iter().any(|s| matches!(s, crate::truth::solid::Solid::HeightGrid { .. })));
        // at posts (multiples of 0.05 m) the DEM is the analytic height, the off-centre poles included
        for (x, y) in [(-4.0, 0.0), (-2.5, 1.0), (-1.0, -1.5), (1.0, 0.0), (0.0, 2.0), (6.0, -3.0)] {
            let (a, b) = (dem.height_at(x, y).unwrap(), exact.height_at(x, y).unwrap());
            assert!((a - b).abs() < 1e-5, "({x}, {y}): DEM {a} vs analytic {b}");
        }
        let cases: Vec<(String, &str, &str)> = vec![
            (text.replace("dem_spacing_m = 0.05", "dem_spacing_m = 0.0"), "world.dem_spacing_m", "at least"),
            (text.replace("dem_spacing_m = 0.05", "dem_spacing_m = 0.002"), "world.dem_spacing_m", "coarser"),
            (HIRISE.replace("kind = \"terrain\"", "kind = \"terrain\"\ndem_spacing_m = 0.5"), "world.dem_spacing_m", "analytic"),
        ];
        for (text, field, reason) in cases {
            let e = check_text(&text).unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert!(e.reason.contains(reason), "{e}");
        }
    }

    fn check_text(text: &str) -> Result<Scenario, ScenarioError> {
        let sc = parse(text, &dir().join("inline.toml"))?;
        let w = sc.build_world()?;
        sc.check(w.as_ref())?;
        Ok(sc)
    }

    #[test]
    fn a_valid_scenario_loads_with_defaults() {
        let sc = check_text(CRATER).unwrap();
        assert_eq!(sc.world.crater_wall.as_ref().unwrap().wall_angle_deg, 55.0);
        assert_eq!(sc.world.crater_wall.as_ref().unwrap().rim_height_m, 6.0);
        assert_eq!(sc.budgets.planner_iterations, 750);
        assert_eq!(sc.sensor, RangeSensorParams::default());
    }

    /// The map section's keys reach the flight software's map configuration (not validated and then ignored).
    #[test]
    fn the_map_section_sets_the_map_configuration() {
        let sc = parse(
            &format!("{CRATER}[map]\nvoxel_size_m = 0.1\nesdf_site_tolerance_voxels = 0.25\nmax_carve_length_m = 6.0\n"),
            Path::new("x.toml"),
        )
        .unwrap();
        let c = sc.map_config().unwrap();
        assert_eq!((c.voxel_size, c.esdf_site_tolerance, c.max_carve_length), (0.1, 0.25, 6.0));
        let d = parse(CRATER, Path::new("x.toml")).unwrap().map_config().unwrap();
        assert_eq!(d.esdf_site_tolerance, MapConfig::DEFAULT.esdf_site_tolerance);
    }

    #[test]
    fn bad_scenarios_name_file_field_and_reason() {
        let cases: Vec<(String, &str, &str)> = vec![
            (CRATER.replace("start = [-2.0, 0.0, 6.4]", "start = [-2.0, 0.0, 5.0]"), "rover.start", "inside the terrain"),
            (CRATER.replace("position = [7.0, 0.0, 0.4]", "position = [70.0, 0.0, 0.4]"), "goal.position", "outside the world's bounds"),
            (CRATER.replace("start = [-2.0, 0.0, 6.4]", "start = [-2.0, nan, 6.4]"), "rover.start", "finite"),
            (CRATER.replace("kind = \"crater_wall\"", "kind = \"volcano\""), "world.kind", "unknown world kind"),
            (CRATER.replace("wall_angle_deg = 55.0", "wall_angle_deg = 91.0"), "world.crater_wall.wall_angle_deg", "(0, 90)"),
            (CRATER.replace("rocks = 4", "rocks = 4\ncolour = 3"), "(syntax)", "unknown field"),
            (CRATER.replace("[goal]\nposition = [7.0, 0.0, 0.4]", ""), "(syntax)", "goal"),
            (CRATER.replace("root_anchor = [-5.0, 0.0, 8.0]", "root_anchor = [-5.0, 0.0, 3.0]"), "tether.root_anchor", "inside the terrain"),
            (format!("{CRATER}[sensor]\ndropout_probability = 1.5\n"), "sensor.dropout_probability", "[0, 1]"),
            (format!("{CRATER}[map]\nvoxel_size_m = 0.001\n"), "map.esdf_max_distance_m", "127 voxels"),
            (format!("{CRATER}[map]\nesdf_site_tolerance_voxels = 0.7\n"), "map.esdf_site_tolerance_voxels", "[0, 0.5]"),
            (format!("{CRATER}[faults]\ndrop = 1.5\n"), "faults.drop", "[0, 1]"),
            (format!("{CRATER}[faults]\nall = nan\n"), "faults.all", "[0, 1]"),
            (format!("{CRATER}[faults]\ndrops = 1e-4\n"), "(syntax)", "unknown field"),
            (format!("{CRATER}[faults]\nseed = -1\n"), "(syntax)", "expected u64"),
            (format!("{CRATER}[faults.down]\ndrop = 2.0\n"), "faults.down.drop", "[0, 1]"),
            (format!("{CRATER}[faults.down]\nseed = 3\n"), "faults.down.seed", "[faults] section"),
            (format!("{CRATER}[faults.down]\ndrops = 1e-4\n"), "(syntax)", "unknown field"),
            (
                // (without the crater's table, which would be refused first: it applies to another kind)
                CRATER
                    .replace("[world.crater_wall]\nwall_angle_deg = 55.0\nrocks = 4\n", "")
                    .replace("kind = \"crater_wall\"", "kind = \"terrain\"\n[world.terrain]\nfile = \"no/such.tif\""),
                "world.terrain.file",
                "no such file",
            ),
        ];
        for (text, field, reason) in cases {
            let e = check_text(&text).unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert!(e.reason.contains(reason), "{e}");
            assert!(e.to_string().contains("inline.toml"), "{e}");
        }
    }

    /// `[faults]` gives the same profile as `--faults` with the same keys: `all` first, named kinds over it.
    #[test]
    fn a_faults_section_is_the_command_lines_profile() {
        use crate::link::faults::FaultProfile;
        let text = format!("{CRATER}[faults]\nall = 1e-5\ndrop = 1e-3\nstall_us = 1000\nseed = 7\n");
        let sc = check_text(&text).unwrap();
        let p = sc.faults.as_ref().unwrap().profile().unwrap();
        assert_eq!(p, FaultProfile::parse("all=1e-5,drop=1e-3,stall_us=1000,seed=7").unwrap());
        assert!(p.any());
        assert_eq!(check_text(CRATER).unwrap().faults, None);
        // the downlink: `[faults.down]` or dotted keys in `[faults]`, the old keys still the uplink's
        let text = format!("{CRATER}[faults]\ndrop = 1e-3\nseed = 7\n[faults.down]\nall = 1e-5\nstall = 1e-4\n");
        let p = check_text(&text).unwrap().faults.unwrap().profile().unwrap();
        assert_eq!(p, FaultProfile::parse("drop=1e-3,down.all=1e-5,down.stall=1e-4,seed=7").unwrap());
        let text = format!("{CRATER}[faults]\ndown.drop = 2e-4\n");
        let p = check_text(&text).unwrap().faults.unwrap().profile().unwrap();
        assert_eq!(p, FaultProfile::parse("down.drop=2e-4").unwrap());
    }

    const HIRISE: &str = r#"
name = "h"
[world]
kind = "terrain"
[world.terrain]
file = "../../../shared/data/terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy"
spacing_m = 1.01
[rover]
start = [10.0, 10.0, 35.09]
[tether]
root_anchor = [14.0, 14.0, 35.48]
[goal]
position = [-10.0, -10.0, 19.40]
"#;

    const ITOKAWA: &str = r#"
name = "i"
[world]
kind = "mesh"
[world.mesh]
file = "../../../shared/data/asteroids/itokawa.obj"
units = "km"
scale = 0.2
[rover]
start = [-10.0, -10.0, 21.18]
[tether]
root_anchor = [-14.0, -14.0, 19.76]
[goal]
position = [10.0, 10.0, 21.67]
"#;

    #[test]
    fn built_in_names_match_the_shipped_scenarios() {
        let data = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data");
        for name in ["hirise_cliff", "itokawa"] {
            let by_name = WorldSpec::by_name(name).unwrap().build(&data).unwrap();
            let sc = load(&dir().join(format!("{name}.toml"))).unwrap();
            let from_file = sc.build_world().unwrap();
            assert_eq!(by_name.bounds(), from_file.bounds(), "{name}");
            let p = Vec3::new(1.0, 2.0, 30.0);
            assert_eq!(by_name.query(&p), from_file.query(&p), "{name}");
        }
    }

    #[test]
    fn npy_and_mesh_rejections_name_field_and_reason() {
        let cases: Vec<(String, &str, &str)> = vec![
            (HIRISE.replace("spacing_m = 1.01", ""), "world.terrain.spacing_m", "no post spacing"),
            (HIRISE.replace("spacing_m = 1.01", "spacing_m = -1.0"), "world.terrain.spacing_m", "> 0"),
            (HIRISE.replace("spacing_m = 1.01", "spacing_m = 1.01\nfirst_row = \"west\""), "world.terrain.first_row", "north or south"),
            (HIRISE.replace("spacing_m = 1.01", "spacing_m = 1.01\nheight_scale = 0.0"), "world.terrain.height_scale", "> 0"),
            (HIRISE.replace("spacing_m = 1.01", "spacing_m = 1.01\nvertical_scale = inf"), "world.terrain", "vertical_scale"),
            (
                HIRISE.replace("terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy", "asteroids/itokawa.obj"),
                "world.terrain.format",
                "kind = \"mesh\"",
            ),
            (HIRISE.replace("spacing_m = 1.01", "spacing_m = 1.01\nformat = \"png\""), "world.terrain.format", "geotiff, asc or npy"),
            (HIRISE.replace("start = [10.0, 10.0, 35.09]", "start = [10.0, 10.0, 30.0]"), "rover.start", "inside the terrain"),
            (ITOKAWA.replace("units = \"km\"", "units = \"au\""), "world.mesh.units", "m or km"),
            (ITOKAWA.replace("scale = 0.2", "scale = 0.0"), "world.mesh.scale", "> 0"),
            (ITOKAWA.replace("scale = 0.2", "scale = nan"), "world.mesh.scale", "> 0"),
            (ITOKAWA.replace("itokawa.obj\"", "itokawa.obj\"\nformat = \"stl\""), "world.mesh.format", "use obj"),
            (ITOKAWA.replace("asteroids/itokawa.obj", "asteroids/nope.obj"), "world.mesh.file", "no such file"),
            (ITOKAWA.replace("asteroids/itokawa.obj", "terrain/erc_marsyard2021_hm.tif"), "world.mesh.format", "use obj"),
            (ITOKAWA.replace("[world.mesh]", "[world.other]"), "(syntax)", "unknown field"),
            (ITOKAWA.replace("kind = \"mesh\"", "kind = \"terrain\""), "world.terrain", "[world.terrain]"),
            (ITOKAWA.replace("start = [-10.0, -10.0, 21.18]", "start = [0.0, 0.0, 0.0]"), "rover.start", "inside the terrain"),
            (ITOKAWA.replace("position = [10.0, 10.0, 21.67]", "position = [100.0, 10.0, 21.67]"), "goal.position", "outside the world's bounds"),
        ];
        assert!(check_text(HIRISE).is_ok());
        assert!(check_text(ITOKAWA).is_ok());
        for (text, field, reason) in cases {
            let e = check_text(&text).unwrap_err();
            assert_eq!(e.field, field, "{e}");
            assert!(e.reason.contains(reason), "{e}");
        }
    }

    #[test]
    fn given_fields_are_tracked_and_names_are_made_path_safe() {
        let sc = check_text(&format!("{CRATER}[map]\nvoxel_size_m = 0.2\n[sensor]\nmax_range_m = 5.0\n")).unwrap();
        assert!(sc.gives("map.voxel_size_m") && sc.gives("map") && sc.gives("sensor"));
        assert!(!sc.gives("map.pool_blocks") && !sc.gives("tether.length_m") && !sc.gives("ma"));
        let plain = check_text(CRATER).unwrap();
        assert!(!plain.gives("map") && !plain.gives("sensor"));
        for (name, safe) in [("/etc/passwd", "_etc_passwd"), ("..", "_.."), ("", "_"), ("a/../b", "a_.._b"), ("ledge_test3", "ledge_test3")] {
            assert_eq!(file_safe(name), safe, "{name:?}");
        }
    }

    #[test]
    fn shipped_scenarios_load() {
        let mut n = 0;
        for p in shipped() {
            load(&p).unwrap_or_else(|e| panic!("{e}"));
            n += 1;
        }
        assert!(n >= 4, "{n} scenarios");
    }
}

#[cfg(test)]
mod placement {
    use super::*;

    /// The shipped scenarios put the rover on the ground (axle 0.2 - 0.6 m above the terrain) and the goal
    /// within 1 m of it.
    #[test]
    fn shipped_scenarios_start_and_goal_are_on_the_ground() {
        for p in super::tests::shipped() {
            let text = std::fs::read_to_string(&p).unwrap();
            let sc = parse(&text, &p).unwrap();
            let w = sc.build_world().unwrap();
            let h = |q: &[f64; 3]| w.height_at(q[0] as Real, q[1] as Real).unwrap() as f64;
            let (s, g, a) = (sc.rover.start, sc.goal.position, sc.tether.root_anchor);
            let msg = format!("{}: ground under start {:.3}, goal {:.3}, anchor {:.3}", p.display(), h(&s), h(&g), h(&a));
            assert!((0.2..0.6).contains(&(s[2] - h(&s))), "{msg}");
            assert!((0.0..1.0).contains(&(g[2] - h(&g))), "{msg}");
        }
    }
}
