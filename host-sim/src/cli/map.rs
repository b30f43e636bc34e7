//! `tetherbot map-check`, `render-map` and `edt-bench`: the onboard map against ground truth, pictures of it,
//! and the distance transform against `libdynamicedt3d` (see `host-sim/doc/map.md`).

use crate::mapcheck::{build_map, census, esdf_errors, host_storage, observed_surface_m2, standard_poses, CheckConfig};
use crate::world::World;
use firmware::geom::Real;
use firmware::config::map::{FLIGHT_BLOCKS, FLIGHT_INDEX};
use firmware::map::{Map, VoxelState};
use std::path::PathBuf;

/// Exit code of a map subcommand: 0, or [`super::EXIT_ERROR`] with the message on stderr.
pub fn exit(r: Result<(), String>) -> std::process::ExitCode {
    match r {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => super::fail(e),
    }
}

/// Arguments of `map-check`.
#[derive(Debug, Clone, clap::Args)]
pub struct MapCheckArgs {
    /// World: crater_wall, ledge, ledge_pole, marsyard, hirise_cliff, itokawa, or a scenario file (.toml).
    #[arg(long, default_value = "crater_wall")]
    pub world: String,
    /// Voxel size, metres (default: a scenario's `[map]` configuration, else 0.05). With a scenario, the flag
    /// overrides `map.voxel_size_m` only.
    #[arg(long)]
    pub voxel: Option<Real>,
    /// Sensor noise seed (default: a scenario's `seeds.sensor`, else 1).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Evaluate every n-th voxel.
    #[arg(long, default_value_t = 7)]
    pub stride: usize,
    /// Free-space carving length per ray, metres (MapConfig::max_carve_length).
    #[arg(long)]
    pub carve: Option<Real>,
}

/// Arguments of `render-map`.
#[derive(Debug, Clone, clap::Args)]
pub struct RenderMapArgs {
    /// World: as for map-check.
    #[arg(long, default_value = "crater_wall")]
    pub world: String,
    /// Voxel size, metres.
    #[arg(long, default_value_t = 0.1)]
    pub voxel: Real,
    /// Output PNG file.
    #[arg(long, default_value = "map.png")]
    pub out: PathBuf,
    /// Vertical slice at this y (metres) instead of the top view.
    #[arg(long)]
    pub slice_y: Option<Real>,
    /// Pixels per voxel.
    #[arg(long, default_value_t = 4)]
    pub px: usize,
}

/// Arguments of `edt-bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct EdtBenchArgs {
    /// Edge of the cubic grid, voxels (a multiple of 8).
    #[arg(long, default_value_t = 128)]
    pub size: usize,
    /// Obstacle density of the random part of the grid.
    #[arg(long, default_value_t = 0.001)]
    pub density: f64,
    /// The reference binary (built by host-sim/bench-ref/build.sh).
    #[arg(long, default_value = "target/bench-ref/edt3d")]
    pub reference: PathBuf,
}

/// Directory of the shared terrain data (compile-time default, overridable with TETHERBOT_DATA).
pub fn data_dir() -> PathBuf {
    std::env::var_os("TETHERBOT_DATA")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../shared/data"))
}

/// A world by name, or from a scenario file.
pub fn world_by_name(name: &str) -> Result<(Box<dyn World>, String), String> {
    if name.ends_with(".toml") {
        let sc = crate::scenario::load(std::path::Path::new(name)).map_err(|e| e.to_string())?;
        let kind = sc.world_kind();
        let w = sc.build_world().map_err(|e| e.to_string())?;
        return Ok((w, kind));
    }
    let spec = crate::scenario::WorldSpec::by_name(name).ok_or_else(|| {
        format!("unknown world {name:?}: use crater_wall, ledge, ledge_pole, marsyard, hirise_cliff, itokawa or a .toml scenario")
    })?;
    let w = spec.build(&data_dir()).map_err(|(f, r)| format!("{f}: {r}"))?;
    Ok((w, name.to_string()))
}

/// Voxel edge of `map-check` without a scenario or `--voxel`, metres.
pub const DEFAULT_CHECK_VOXEL_M: Real = 0.05;

/// The check configuration of `map-check`: a scenario's `[map]`, `[budgets]`, `[sensor]`, `seeds.sensor` and
/// `map.pool_blocks` when the world is a scenario file (`--voxel`, `--seed` override), else the defaults.
pub fn check_config(a: &MapCheckArgs) -> Result<CheckConfig, String> {
    let mut cfg = if a.world.ends_with(".toml") {
        let sc = crate::scenario::load(std::path::Path::new(&a.world)).map_err(|e| e.to_string())?;
        let mut m = sc.map_config().map_err(|e| e.to_string())?;
        if let Some(v) = a.voxel {
            // The flag replaces the voxel; the truncation and ray budget keep their proportions unless given.
            let scaled = firmware::config::map::MapConfig::with_voxel_size(v);
            m.voxel_size = v;
            if sc.map.truncation_m.is_none() {
                m.truncation = scaled.truncation;
            }
            if !sc.gives("budgets.max_ray_voxels") {
                m.max_ray_voxels = scaled.max_ray_voxels;
            }
        }
        let mut cfg = CheckConfig::at_voxel_size(m.voxel_size);
        cfg.map = m;
        cfg.sensor = sc.sensor.clone();
        cfg.seed = sc.seeds.sensor;
        cfg.pool_blocks = sc.map.pool_blocks;
        cfg
    } else {
        CheckConfig::at_voxel_size(a.voxel.unwrap_or(DEFAULT_CHECK_VOXEL_M))
    };
    if let Some(s) = a.seed {
        cfg.seed = s;
    }
    cfg.sample_stride = a.stride.max(1);
    if let Some(c) = a.carve {
        cfg.map.max_carve_length = c;
    }
    cfg.map.validate().map_err(|e| format!("map configuration: {}: {}", e.field, e.reason))?;
    Ok(cfg)
}

/// `map-check`: prints ESDF error, timing and memory figures. No integrated point, or an error figure that is
/// not a number, is an error (a map-check that measured nothing has not passed).
pub fn map_check(a: &MapCheckArgs) -> Result<(), String> {
    let (world, kind) = world_by_name(&a.world)?;
    let cfg = check_config(a)?;
    let poses = standard_poses(world.as_ref(), &kind);
    let (mut blocks, mut index) = host_storage(cfg.pool_blocks);
    let mut map = Map::from_slices(cfg.map, &mut blocks, &mut index).map_err(|e| format!("{e:?}"))?;
    let mut rep = build_map(world.as_ref(), &poses, &cfg, &mut map);
    esdf_errors(world.as_ref(), &map, &cfg, &mut rep);
    rep.surface_m2 = observed_surface_m2(&map);
    if rep.points == 0 {
        return Err(format!(
            "no point was integrated in {} scans of {} ({} sensor rays each): the sensor saw no surface from the \
             standard poses (a degenerate mesh, or a scale that makes the world too small or too far?)",
            rep.scans,
            world.name(),
            cfg.sensor.ray_count()
        ));
    }
    for (what, e) in [("all observed voxels", &rep.all), ("near the surface", &rep.near)] {
        if !(e.rms.is_finite() && e.mean.is_finite() && e.max.is_finite()) {
            return Err(format!(
                "the ESDF error over {what} is not a number ({e}): the world's distances overflow (a height or \
                 mesh scale too large?)"
            ));
        }
    }
    let bb = Map::block_bytes();
    println!(
        "world {} ({kind}), voxel {} m, truncation {} m, ESDF cap {} m, carving {} m, ESDF hysteresis {} voxel",
        world.name(),
        cfg.map.voxel_size,
        cfg.map.truncation,
        cfg.map.esdf_max_distance,
        cfg.map.max_carve_length,
        cfg.map.esdf_site_tolerance
    );
    println!("scans {}  points {}  sensor {} rays/scan  seed {}", rep.scans, rep.points, cfg.sensor.ray_count(), cfg.seed);
    if rep.non_finite_points > 0 || rep.scans_refused > 0 {
        println!(
            "dropped on the host: {} non-finite points, {} scans that could not be chunked",
            rep.non_finite_points, rep.scans_refused
        );
    }
    println!(
        "integration (thread CPU time): {:.3} s total, {:.0} points/s, {:.2} ms/scan (wall {:.3} s)",
        rep.integrate_s,
        rep.points_per_s(),
        1e3 * rep.integrate_s / rep.scans.max(1) as f64,
        rep.integrate_wall_s
    );
    println!(
        "ESDF update per scan (thread CPU time): mean {:.2} ms, max {:.2} ms (wall mean {:.2} ms), all converged: {}",
        rep.esdf_ms_mean, rep.esdf_ms_max, rep.esdf_wall_ms_mean, rep.esdf_all_converged
    );
    println!("ESDF error, all observed voxels:  {}", rep.all);
    println!("ESDF error, near (|SD| < {} m): {}", cfg.near_m, rep.near);
    println!(
        "sign errors beyond one voxel: {} of {} samples ({} beyond truncation + voxel)",
        rep.sign_errors, rep.all.n, rep.sign_errors_far
    );
    let mib = |b: f64| b / (1024.0 * 1024.0);
    println!(
        "memory: {} blocks x {} B = {:.2} MiB (dropped voxel updates: {}); observed surface {:.1} m^2 -> {:.0} B/m^2",
        rep.blocks_used,
        bb,
        mib(rep.bytes_used() as f64),
        rep.voxels_dropped,
        rep.surface_m2,
        rep.bytes_used() as f64 / rep.surface_m2.max(1e-9)
    );
    let c = census(&map);
    println!(
        "blocks by the smallest |ESDF| in them: < 0.25 m {}, 0.25-0.5 m {}, 0.5-1 m {}, >= 1 m {}, none observed {}; \
         unknown voxels {:.1} %; plan-view footprint {:.1} m^2 -> {:.0} B/m^2",
        c.by_min_distance[0],
        c.by_min_distance[1],
        c.by_min_distance[2],
        c.by_min_distance[3],
        c.by_min_distance[4],
        100.0 * c.unknown_fraction,
        c.footprint_m2,
        rep.bytes_used() as f64 / c.footprint_m2.max(1e-9)
    );
    let known = c.voxels_by_tsdf.iter().sum::<usize>().max(1) as f64;
    println!(
        "observed voxels by TSDF: within the band {:.1} %, free at +truncation {:.1} %, inside at -truncation {:.1} %; \
         blocks with free space only {} ({:.1} %)",
        100.0 * c.voxels_by_tsdf[0] as f64 / known,
        100.0 * c.voxels_by_tsdf[1] as f64 / known,
        100.0 * c.voxels_by_tsdf[2] as f64 / known,
        c.free_only_blocks,
        100.0 * c.free_only_blocks as f64 / c.blocks.max(1) as f64
    );
    // sized by the plan-view footprint: a work area is measured from above
    let need = rep.bytes_used() as f64 / c.footprint_m2.max(1e-9) * 400.0;
    let pool = (FLIGHT_BLOCKS * bb + FLIGHT_INDEX * 4) as f64;
    println!(
        "20 m x 20 m at this density: {:.1} MiB of blocks vs the flight pool's {:.1} MiB (FLIGHT_BLOCKS {} + index): {}",
        mib(need),
        mib(pool),
        FLIGHT_BLOCKS,
        if need <= FLIGHT_BLOCKS as f64 * bb as f64 { "fits" } else { "does NOT fit" }
    );
    Ok(())
}

fn colour(d: Real, dmax: Real) -> [u8; 3] {
    // Blue (inside) through white (surface) to red-yellow (far).
    let t = (d / dmax).clamp(-1.0, 1.0);
    if t < 0.0 {
        let s = -t;
        [(255.0 * (1.0 - s)) as u8, (255.0 * (1.0 - s)) as u8, 255]
    } else {
        [255, (255.0 * t) as u8, (255.0 * (1.0 - t) * 0.6) as u8]
    }
}

/// `render-map`: a PNG of the map built from the world's standard scan sequence. Top view: the height of the
/// highest occupied voxel in each column (dark low, light high), grey where no surface was observed. Slice at
/// `y`: ESDF colour (blue inside the terrain, white at the surface, red to yellow up to the ESDF cap), black on the
/// surface (|ESDF| < half a voxel), grey where unknown.
pub fn render_map(a: &RenderMapArgs) -> Result<(), String> {
    let (world, kind) = world_by_name(&a.world)?;
    let cfg = CheckConfig::at_voxel_size(a.voxel);
    let poses = standard_poses(world.as_ref(), &kind);
    let (mut blocks, mut index) = host_storage(cfg.pool_blocks);
    let mut map = Map::from_slices(cfg.map, &mut blocks, &mut index).map_err(|e| format!("{e:?}"))?;
    build_map(world.as_ref(), &poses, &cfg, &mut map);
    let b = world.bounds();
    let vs = a.voxel;
    let dmax = cfg.map.esdf_max_distance;
    let (w, h, pixels) = match a.slice_y {
        Some(y) => {
            let gx0 = (b.min.x / vs).floor() as i32;
            let gz0 = (b.min.z / vs).floor() as i32;
            let w = ((b.max.x - b.min.x) / vs).ceil() as usize;
            let h = ((b.max.z - b.min.z) / vs).ceil() as usize;
            let gy = (y / vs).floor() as i32;
            let mut px = Vec::with_capacity(w * h * 3);
            for r in 0..h {
                for c in 0..w {
                    let g = [gx0 + c as i32, gy, gz0 + (h - 1 - r) as i32];
                    let rgb = match (map.voxel_state(g), map.esdf_voxel(g)) {
                        (VoxelState::Unknown, _) | (_, None) => [128, 128, 128],
                        (_, Some(d)) if d.abs() < 0.5 * vs => [0, 0, 0],
                        (_, Some(d)) => colour(d, dmax),
                    };
                    px.extend_from_slice(&rgb);
                }
            }
            (w, h, px)
        }
        None => {
            let gx0 = (b.min.x / vs).floor() as i32;
            let gy0 = (b.min.y / vs).floor() as i32;
            let w = ((b.max.x - b.min.x) / vs).ceil() as usize;
            let h = ((b.max.y - b.min.y) / vs).ceil() as usize;
            let gz_top = (b.max.z / vs).ceil() as i32 + 4;
            let gz_bot = (b.min.z / vs).floor() as i32 - 4;
            let mut px = Vec::with_capacity(w * h * 3);
            for r in 0..h {
                for c in 0..w {
                    let (gx, gy) = (gx0 + c as i32, gy0 + (h - 1 - r) as i32);
                    // From the top down: the first occupied voxel is the surface; shade by height, and mark
                    // columns whose surface was never seen as unknown.
                    let mut rgb = [128, 128, 128];
                    for gz in (gz_bot..=gz_top).rev() {
                        if map.voxel_state([gx, gy, gz]) == VoxelState::Occupied {
                            let t = ((gz as Real * vs - b.min.z) / (b.max.z - b.min.z)).clamp(0.0, 1.0);
                            rgb = [(60.0 + 195.0 * t) as u8, (40.0 + 150.0 * t) as u8, (30.0 + 80.0 * t) as u8];
                            break;
                        }
                    }
                    px.extend_from_slice(&rgb);
                }
            }
            (w, h, px)
        }
    };
    let k = a.px.clamp(1, 16);
    let mut big = Vec::with_capacity(pixels.len() * k * k);
    for r in 0..h {
        let row = &pixels[r * w * 3..(r + 1) * w * 3];
        for _ in 0..k {
            for c in 0..w {
                for _ in 0..k {
                    big.extend_from_slice(&row[c * 3..c * 3 + 3]);
                }
            }
        }
    }
    let (w, h, pixels) = (w * k, h * k, big);
    let f = std::fs::File::create(&a.out).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let mut enc = png::Encoder::new(std::io::BufWriter::new(f), w as u32, h as u32);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let mut wr = enc.write_header().map_err(|e| e.to_string())?;
    wr.write_image_data(&pixels).map_err(|e| e.to_string())?;
    println!("wrote {} ({w} x {h} px, {} blocks)", a.out.display(), map.blocks_used());
    Ok(())
}

/// `edt-bench`: a full distance transform of the same occupancy grid by the onboard ESDF (all blocks dirty,
/// sites = occupied voxels) and by `libdynamicedt3d` (`host-sim/bench-ref/edt3d.cpp`), timed in one run.
pub fn edt_bench(a: &EdtBenchArgs) -> Result<(), String> {
    let n = (a.size / 8).max(1) * 8;
    let grid = crate::mapcheck::reference_grid(n, a.density, 42);
    let (ms_ours, ours) = crate::mapcheck::full_esdf_on_grid(&grid, n)?;
    let path = std::env::temp_dir().join(format!("tetherbot-edt-{}.bin", std::process::id()));
    let dpath = path.with_extension("dist");
    crate::mapcheck::write_grid(&path, &grid, n).map_err(|e| e.to_string())?;
    let out = std::process::Command::new(&a.reference)
        .arg(&path)
        .arg(&dpath)
        .output()
        .map_err(|e| format!("cannot run {} ({e}); build it with host-sim/bench-ref/build.sh", a.reference.display()))?;
    std::fs::remove_file(&path).ok();
    if !out.status.success() {
        return Err(format!("reference failed: {}", String::from_utf8_lossy(&out.stderr)));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let ms_ref: f64 = text
        .split_whitespace()
        .find_map(|t| t.strip_prefix("cpu_ms="))
        .and_then(|v| v.parse().ok())
        .ok_or_else(|| format!("unexpected reference output: {text}"))?;
    let reference: Vec<f32> = std::fs::read(&dpath)
        .map_err(|e| format!("reference distances: {e}"))?
        .chunks_exact(4)
        .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]))
        .collect();
    std::fs::remove_file(&dpath).ok();
    let mut max_diff: f32 = 0.0;
    let mut differ = 0usize;
    for (o, r) in ours.iter().zip(&reference) {
        if *o < 126.0 && *r < 126.0 {
            let d = (o - r).abs();
            max_diff = max_diff.max(d);
            if d > 1e-3 {
                differ += 1;
            }
        }
    }
    let occupied = grid.iter().filter(|o| **o).count();
    println!("grid {n}^3 = {} voxels, {occupied} occupied", n * n * n);
    println!("thread CPU time, full transform from occupancy (cap 127 voxels):");
    println!("  onboard ESDF (update_esdf: site rebuild + vector propagation wavefront): {ms_ours:.1} ms");
    println!("  libdynamicedt3d (DynamicEDT3D initializeMap + update):              {ms_ref:.1} ms");
    println!("ratio onboard / dynamicedt3d: {:.2}", ms_ours / ms_ref);
    println!("agreement: {differ} of {} voxels differ by > 0.001 voxel, max difference {max_diff:.4} voxel", ours.len());
    Ok(())
}
