//! Homotopy routes on real DEMs (issue 20): a DEM window is cut into a flight [`HeightTile`] (scaled to rover scale,
//! the same factor horizontally and vertically, so slopes are kept), segmented into unfolded planes by the flight
//! code ([`DemDescent::segment`]), planned with the point mass (the paper's baseline) and with Axel
//! ([`axel_model`]), and each plan mapped back to the world ([`DemDescent::route_to_world`]).
//!
//! Presets ([`preset`]): Shackleton (LOLA south polar) and Kepler (LOLA orthographic) at the same scale
//! [`CRATER_SCALE`], the HiRISE crop and the Mars Yard at 1:1.

use std::path::{Path, PathBuf};

use firmware::config::rover::RoverParams;
use firmware::plan::homotopy::axel::{axel_model, AxelLimit};
use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::dem::{DemDescent, DemParams, DemScratch, HeightTile, RouteError, WorldRoute};
use firmware::plan::homotopy::plan::{preplan, HomotopyParams, Plan, PlanReport, Verdict, Workspace};
use firmware::plan::homotopy::planes::HoldModel;

use crate::terrain::geotiff::{load_geotiff, GeoTiffOptions};
use crate::terrain::npy::{load_npy, NpyOptions};
use crate::terrain::Heightmap;

/// The common scale of the two lunar craters: 1:400 (Kepler's 47.7 m posts become 0.12 m, Shackleton's 1600 m posts
/// 4 m, the tile's coarsest accepted spacing is 5 m; a 2.6 km crater wall becomes 6.5 m high; slopes unchanged).
pub const CRATER_SCALE: f64 = 0.0025;

/// Soil friction of every preset: 0.4, between the paper's loose sand (0.25) and compact soil (0.65) (Abad-Manterola
/// VI); tether-demand above atan(0.4) = 21.8 deg, so the lunar walls (up to 34 and 44 deg) demand the tether.
pub const MU: f64 = 0.4;

/// A descent on a DEM.
#[derive(Clone, Debug, PartialEq)]
pub struct DemScenario {
    /// Name (file names of the pictures).
    pub name: String,
    /// DEM file.
    pub file: PathBuf,
    /// `.npy` post spacing (m); GeoTIFFs carry theirs.
    pub npy_spacing_m: Option<f64>,
    /// GeoTIFF height multiplier (LOLA Kepler stores half-metres).
    pub height_scale: f64,
    /// Window's south-west corner in the DEM (m, before scaling) and its side (m).
    pub window: [f64; 3],
    /// Take every `stride`-th post.
    pub stride: usize,
    /// Horizontal and vertical scale to rover scale.
    pub scale: f64,
    /// Root anchor a0 and goal g, tile metres (after scaling).
    pub a0: [f64; 2],
    /// Goal.
    pub g: [f64; 2],
    /// Corridor half width (m).
    pub half_width_m: f64,
    /// Soil friction.
    pub mu: f64,
    /// Tether payout limit (m).
    pub max_payout_m: f64,
}

fn shared_terrain(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/terrain").join(name)
}

/// Preset scenarios: `shackleton`, `kepler`, `hirise`, `marsyard`.
pub fn preset(name: &str) -> Option<DemScenario> {
    let base = DemScenario {
        name: name.to_string(),
        file: PathBuf::new(),
        npy_spacing_m: None,
        height_scale: 1.0,
        window: [0.0, 0.0, 0.0],
        stride: 1,
        scale: 1.0,
        a0: [0.0; 2],
        g: [0.0; 2],
        half_width_m: 6.0,
        mu: MU,
        max_payout_m: 100.0,
    };
    Some(match name {
        // The east wall of Shackleton (the crater spans ~13 posts of the polar DEM), rim -> floor, 1:400.
        "shackleton" => DemScenario {
            file: shared_terrain("lola_ldem256_south_polar_1600m.tif"),
            window: [577_600.0, 577_600.0, 64_000.0],
            scale: CRATER_SCALE,
            a0: [134.0, 62.0],
            g: [102.0, 62.0],
            ..base
        },
        // Kepler's west wall, rim -> floor, 1:400, every 3rd post (0.36 m).
        "kepler" => DemScenario {
            file: shared_terrain("lola_kepler_crater_orthographic_47m.tif"),
            height_scale: 0.5,
            window: [2_000.0, 16_000.0, 12_000.0],
            stride: 3,
            scale: CRATER_SCALE,
            a0: [3.0, 20.0],
            g: [22.0, 20.0],
            ..base
        },
        // The HiRISE scarp at 1:1 (1.01 m posts): from the flat top down the wall to the south-west.
        "hirise" => DemScenario {
            file: shared_terrain("hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy"),
            npy_spacing_m: Some(1.01),
            window: [0.0, 0.0, 1e9],
            a0: [50.0, 102.0],
            g: [25.0, 58.0],
            half_width_m: 13.0,
            ..base
        },
        // The Mars Yard's hill at 1:1, every 4th post (0.38 m).
        "marsyard" => DemScenario {
            file: shared_terrain("erc_marsyard2021_hm.tif"),
            window: [0.0, 0.0, 1e9],
            stride: 4,
            a0: [2.0, 30.0],
            g: [12.0, 30.0],
            half_width_m: 3.0,
            ..base
        },
        _ => return None,
    })
}

/// Loads the DEM of a scenario.
pub fn load_dem(s: &DemScenario) -> Result<Heightmap, String> {
    let shown = s.file.display();
    match s.npy_spacing_m {
        Some(sp) => load_npy(&s.file, &NpyOptions::metres(sp)).map_err(|e| format!("{shown}: {e:?}")),
        None => load_geotiff(&s.file, &GeoTiffOptions { height_scale: s.height_scale, ..Default::default() })
            .map_err(|e| format!("{shown}: {e}")),
    }
}

/// Heights of the window (rows south to north), scaled; `None` heights become NaN (the tile refuses them).
/// Returns (heights, rows, cols, post spacing after scaling).
pub fn cut_window(hm: &Heightmap, window: [f64; 3], stride: usize, scale: f64) -> (Vec<f32>, usize, usize, f64) {
    let stride = stride.max(1);
    let sp = hm.spacing_m;
    let (c0, r0) = ((window[0] / sp).floor().max(0.0) as usize, (window[1] / sp).floor().max(0.0) as usize);
    let n = ((window[2] / sp / stride as f64).ceil() as usize).max(1);
    let cols = n.min(hm.width.saturating_sub(c0).div_ceil(stride));
    let rows = n.min(hm.height.saturating_sub(r0).div_ceil(stride));
    let mut h = Vec::with_capacity(rows * cols);
    for r in 0..rows {
        for c in 0..cols {
            let v = hm.get(c0 + c * stride, r0 + r * stride).map_or(f32::NAN, |z| (z * scale) as f32);
            h.push(v);
        }
    }
    (h, rows, cols, sp * stride as f64 * scale)
}

/// One model's planning result.
#[derive(Clone, Debug)]
pub struct ModelRun {
    /// "point mass" or "Axel".
    pub label: &'static str,
    /// The holding model used.
    pub model: HoldModel,
    /// The plan, if any.
    pub plan: Option<Plan>,
    /// Classes examined.
    pub report: PlanReport,
    /// The world route (or why not), when there is a plan.
    pub route: Option<Result<WorldRoute, RouteError>>,
}

/// Everything a DEM run produced.
pub struct DemRun {
    /// The tile.
    pub tile: Box<HeightTile>,
    /// The segmented descent.
    pub descent: DemDescent,
    /// The BTM of the unfolded descent.
    pub btm: Box<Btm>,
    /// Point mass, then Axel.
    pub runs: [ModelRun; 2],
    /// Axel's measured limit on the wall.
    pub axel: AxelLimit,
    /// Host wall time of the flight software's three homotopy phases (`firmware::nav::homotopy`: segmentation with
    /// `check_ends` and the BTM; Axel's limit; Alg. 1 with Axel and the world route), seconds.
    pub phase_s: [f64; 3],
}

/// Cuts, segments and plans a scenario (both models).
pub fn run(s: &DemScenario) -> Result<DemRun, String> {
    let hm = load_dem(s)?;
    let (h, rows, cols, res) = cut_window(&hm, s.window, s.stride, s.scale);
    let mut tile = Box::new(HeightTile::new());
    tile.load([0.0, 0.0], res, rows, cols, &h).map_err(|e| format!("tile refused: {e:?}"))?;
    plan_tile(tile, s)
}

/// Segments and plans on a loaded tile.
pub fn plan_tile(tile: Box<HeightTile>, s: &DemScenario) -> Result<DemRun, String> {
    let rover = RoverParams::AXEL;
    let params = DemParams::for_rover(&rover, s.mu, s.half_width_m);
    let mut scratch = Box::new(DemScratch::new());
    let t0 = std::time::Instant::now();
    let descent = DemDescent::segment(&tile, s.a0, s.g, &params, &mut scratch).map_err(|e| format!("segmentation: {e:?}"))?;
    descent.check_ends().map_err(|e| {
        let planes: Vec<String> = descent.planes.iter().map(|p| format!("{:?} {:.1} deg", p.class, p.plane.slope_rad().to_degrees())).collect();
        format!("{e:?} (planes {planes:?}, {} obstacle posts, {} obstacles, {} on the edge)", descent.blocked_posts, descent.obstacles.len(), descent.edge_obstacles.len())
    })?;
    let mut btm = Box::new(Btm::new());
    descent.build_btm(&mut btm).map_err(|e| format!("BTM: {e:?}"))?;
    let segment_s = t0.elapsed().as_secs_f64();
    let pm = descent.hold_model();
    let t1 = std::time::Instant::now();
    let (ax, limits) = axel_model(&pm, &rover);
    let hold_s = t1.elapsed().as_secs_f64();
    let mut ws = Box::new(Workspace::default());
    let mut one = |label: &'static str, model: HoldModel| -> Result<ModelRun, String> {
        let (mut lc, mut report) = (heapless::Vec::new(), PlanReport::default());
        let plan = preplan(&btm, &model, &HomotopyParams::default(), &mut ws, descent.a0, descent.g, &mut lc, &mut report)
            .map_err(|e| format!("{label}: {e:?}"))?;
        let route = plan.as_ref().map(|p| descent.route_to_world(&tile, p, s.max_payout_m));
        Ok(ModelRun { label, model, plan, report, route })
    };
    let pm_run = one("point mass", pm)?;
    let t2 = std::time::Instant::now();
    let ax_run = one("Axel", ax)?;
    let route_s = t2.elapsed().as_secs_f64();
    Ok(DemRun { tile, descent, btm, runs: [pm_run, ax_run], axel: limits[0], phase_s: [segment_s, hold_s, route_s] })
}

/// Number of examined classes with a given verdict kind.
pub fn count_verdicts(r: &PlanReport, chosen: bool) -> usize {
    r.examined.iter().filter(|v| (v.verdict == Verdict::Chosen) == chosen).count()
}
