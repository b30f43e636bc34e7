//! Ground-truth checks of the onboard map: drive a scan sequence through a world, integrate every scan into
//! `firmware::map` exactly as the flight software does (chunk by chunk, then one ESDF update per scan), and
//! compare the ESDF with the world's true signed distance.
//!
//! Error figures are over observed voxel centres (every `sample_stride`-th voxel of the allocated blocks, in
//! pool order): `map ESDF - clamp(true SD, -D, D)` with `D = esdf_max_distance` (the map saturates there by
//! design). "Near" = voxels whose true |SD| is below `near_m` (default 0.25 m), the band the settler and the
//! tether sweep use.

use crate::sensor::{scan, RangeSensorParams};
use crate::world::World;
use firmware::config::map::MapConfig;
use firmware::geom::{Pose3, Real, Rot3, Vec3};
use firmware::map::{Block, DistanceField, DistanceQuery, Map, SurfaceCursor, SurfacePoint};
use std::time::Instant;

/// CPU time of the calling thread, nanoseconds (Linux `/proc/thread-self/schedstat`); `None` elsewhere.
/// Timing figures use it because wall time on a shared machine counts other processes' work.
pub fn thread_cpu_ns() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// Runs `f` and returns its result with (wall ms, thread CPU ms; CPU falls back to wall).
pub fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let c0 = thread_cpu_ns();
    let t0 = Instant::now();
    let r = f();
    let wall = t0.elapsed().as_secs_f64() * 1e3;
    let c1 = thread_cpu_ns();
    let cpu = match (c0, c1) {
        (Some(a), Some(b)) => (b - a) as f64 / 1e6,
        _ => wall,
    };
    (r, wall, cpu)
}

/// Error statistics, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ErrorStats {
    /// Samples.
    pub n: usize,
    /// Mean signed error (bias).
    pub mean: f64,
    /// Root mean square error.
    pub rms: f64,
    /// 95th percentile of |error|.
    pub p95: f64,
    /// Largest |error|.
    pub max: f64,
}

impl ErrorStats {
    /// Statistics of a list of signed errors.
    pub fn of(errors: &[f64]) -> ErrorStats {
        if errors.is_empty() {
            return ErrorStats::default();
        }
        let n = errors.len();
        let mean = errors.iter().sum::<f64>() / n as f64;
        let rms = (errors.iter().map(|e| e * e).sum::<f64>() / n as f64).sqrt();
        let mut abs: Vec<f64> = errors.iter().map(|e| e.abs()).collect();
        abs.sort_by(f64::total_cmp);
        let p95 = abs[((n as f64 * 0.95).ceil() as usize).clamp(1, n) - 1];
        ErrorStats { n, mean, rms, p95, max: abs[n - 1] }
    }
}

impl core::fmt::Display for ErrorStats {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(
            f,
            "n={:>7}  rms={:.4} m  p95={:.4} m  max={:.4} m  bias={:+.4} m",
            self.n, self.rms, self.p95, self.max, self.mean
        )
    }
}

/// Settings of a check run.
#[derive(Debug, Clone)]
pub struct CheckConfig {
    /// Map parameters (voxel size etc.).
    pub map: MapConfig,
    /// Pool size in blocks (the host boxes it).
    pub pool_blocks: usize,
    /// The sensor.
    pub sensor: RangeSensorParams,
    /// Seed of the sensor noise.
    pub seed: u64,
    /// Points per protocol chunk.
    pub chunk_points: usize,
    /// Evaluate every n-th voxel.
    pub sample_stride: usize,
    /// "Near the surface" threshold, metres.
    pub near_m: f64,
}

impl CheckConfig {
    /// Defaults at a voxel size: pool of 16384 blocks, default sensor, seed 1, 128-point chunks, stride 7,
    /// near = 0.25 m.
    pub fn at_voxel_size(voxel: Real) -> CheckConfig {
        CheckConfig {
            map: MapConfig::with_voxel_size(voxel),
            pool_blocks: 16384 * 512 / firmware::config::map::BLOCK_VOXELS,
            sensor: RangeSensorParams::default(),
            seed: 1,
            chunk_points: 128,
            sample_stride: 7,
            near_m: 0.25,
        }
    }
}

/// Figures of a check run.
#[derive(Debug, Clone, Default)]
pub struct CheckReport {
    /// Scans integrated.
    pub scans: usize,
    /// Points integrated.
    pub points: usize,
    /// Non-finite points dropped on the host before sending (the flight side would Nack their chunks).
    pub non_finite_points: usize,
    /// Scans that could not be chunked (too many points, or a non-finite sensor pose).
    pub scans_refused: usize,
    /// Total TSDF integration time, seconds (thread CPU time).
    pub integrate_s: f64,
    /// Total TSDF integration wall time, seconds.
    pub integrate_wall_s: f64,
    /// ESDF update CPU time per scan, milliseconds: mean and max.
    pub esdf_ms_mean: f64,
    /// See `esdf_ms_mean`.
    pub esdf_ms_max: f64,
    /// ESDF update wall time per scan, mean, milliseconds.
    pub esdf_wall_ms_mean: f64,
    /// Every ESDF update converged within its sweep budget.
    pub esdf_all_converged: bool,
    /// Blocks in use at the end.
    pub blocks_used: usize,
    /// Voxel updates dropped for lack of blocks.
    pub voxels_dropped: u64,
    /// Surface area observed (from the TSDF zero crossings), m^2.
    pub surface_m2: f64,
    /// Errors over all sampled observed voxels.
    pub all: ErrorStats,
    /// Errors over sampled voxels with true |SD| < near_m.
    pub near: ErrorStats,
    /// Sampled voxels that are free in the map but inside the terrain by more than one voxel, or occupied in
    /// the map but outside by more than one voxel (sign errors). The TSDF writes negative values up to the
    /// truncation distance behind each hit, so at convex edges and thin rocks such errors exist by construction
    /// (as in Voxblox); they must stay within `truncation + voxel` of the surface.
    pub sign_errors: usize,
    /// Sign errors farther than `truncation + voxel` from the surface (must be 0).
    pub sign_errors_far: usize,
}

impl CheckReport {
    /// Integration throughput, points per second.
    pub fn points_per_s(&self) -> f64 {
        self.points as f64 / self.integrate_s.max(1e-12)
    }
    /// Memory of the blocks in use.
    pub fn bytes_used(&self) -> usize {
        self.blocks_used * Map::block_bytes()
    }
}

/// Rover poses on a straight drive from `(x0, y0)` to `(x1, y1)`: one station every `step_m`, the rover origin
/// `clearance_m` above the terrain, and at each station one pose per yaw offset (degrees) from the drive direction.
pub fn drive_poses(world: &dyn World, from: [f64; 2], to: [f64; 2], step_m: f64, clearance_m: f64, yaws_deg: &[f64]) -> Vec<Pose3> {
    let d = [to[0] - from[0], to[1] - from[1]];
    let len = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let n = (len / step_m).floor() as usize + 1;
    let heading = d[1].atan2(d[0]);
    let mut out = Vec::new();
    for k in 0..n {
        let t = if n > 1 { k as f64 / (n - 1) as f64 } else { 0.0 };
        let (x, y) = (from[0] + d[0] * t, from[1] + d[1] * t);
        let Some(h) = world.height_at(x as Real, y as Real) else { continue };
        for yaw in yaws_deg {
            out.push(Pose3::from_parts(
                Vec3::new(x as Real, y as Real, h + clearance_m as Real).into(),
                Rot3::from_euler_angles(0.0, 0.0, (heading + yaw.to_radians()) as Real),
            ));
        }
    }
    out
}

/// Empty host-side storage for a pool of `blocks` blocks (index = next power of two of 2 x blocks).
pub fn host_storage(blocks: usize) -> (Vec<Block>, Vec<u32>) {
    (vec![Block::EMPTY; blocks], vec![0u32; (2 * blocks).next_power_of_two()])
}

/// Integrates scans from `poses` into `map` (chunked, one ESDF update per scan); returns the timing figures.
pub fn build_map(world: &dyn World, poses: &[Pose3], cfg: &CheckConfig, map: &mut Map<'_>) -> CheckReport {
    let mut rng = rand_pcg::Pcg64::new(cfg.seed as u128, 0x5851_f42d_4c95_7f2d_1405_7b7e_f767_814f);
    let mut rep = CheckReport { esdf_all_converged: true, ..Default::default() };
    let mut esdf_ms = Vec::new();
    let mut esdf_wall = Vec::new();
    for (k, pose) in poses.iter().enumerate() {
        let s = scan(world, &cfg.sensor, pose, &mut rng);
        rep.non_finite_points += s.non_finite_points();
        let Ok(chunks) = s.to_chunks(k as u32, cfg.chunk_points) else {
            rep.scans_refused += 1;
            continue;
        };
        let chunks: Vec<(Pose3, Vec<Vec3>)> = chunks
            .iter()
            .map(|c| (c.sensor_pose.to_isometry(), c.points.iter().map(|p| Vec3::new(p.x, p.y, p.z)).collect()))
            .collect();
        let ((), wall, cpu) = timed(|| {
            for (pose, pts) in &chunks {
                let o = map.integrate_points(pose, pts);
                rep.points += o.points_integrated as usize;
                rep.voxels_dropped += o.voxels_dropped as u64;
            }
        });
        rep.integrate_s += cpu / 1e3;
        rep.integrate_wall_s += wall / 1e3;
        let (e, wall, cpu) = timed(|| map.update_esdf());
        esdf_ms.push(cpu);
        esdf_wall.push(wall);
        if std::env::var_os("TETHERBOT_ESDF_TRACE").is_some() {
            eprintln!("scan {k}: {cpu:.1} ms CPU {e:?} blocks {}", map.blocks_used());
        }
        if std::env::var_os("TETHERBOT_ESDF_DIGEST").is_some() {
            eprintln!("scan {k}: esdf digest {:016x} tsdf digest {:016x}", esdf_digest(map), tsdf_digest(map));
        }
        if let Some(dir) = std::env::var_os("TETHERBOT_ESDF_DUMP") {
            let _ = std::fs::write(std::path::Path::new(&dir).join(format!("esdf_{k:03}.bin")), esdf_dump(map));
        }
        rep.esdf_all_converged &= e.converged;
        rep.scans += 1;
    }
    rep.esdf_ms_mean = esdf_ms.iter().sum::<f64>() / esdf_ms.len().max(1) as f64;
    rep.esdf_ms_max = esdf_ms.iter().copied().fold(0.0, f64::max);
    rep.esdf_wall_ms_mean = esdf_wall.iter().sum::<f64>() / esdf_wall.len().max(1) as f64;
    rep.blocks_used = map.blocks_used();
    rep
}

/// Every voxel of the blocks in use, in slot order, then z, y, x within a block.
pub fn voxels_in_use<'m>(map: &'m Map<'_>) -> impl Iterator<Item = [i32; 3]> + 'm {
    let e = firmware::config::map::BLOCK_EDGE as i32;
    (0..map.blocks_used()).map_while(|slot| map.block_coord(slot)).flat_map(move |c| {
        (0..e * e * e).map(move |k| [c[0] * e + k % e, c[1] * e + (k / e) % e, c[2] * e + k / (e * e)])
    })
}

/// FNV-1a over the little-endian bytes of `words`.
fn fnv1a(words: impl Iterator<Item = u32>) -> u64 {
    words.flat_map(u32::to_le_bytes).fold(0xcbf2_9ce4_8422_2325, |h, b| (h ^ b as u64).wrapping_mul(0x0100_0000_01b3))
}

/// FNV-1a digest of every voxel's ESDF value and site distance (bit patterns) over the blocks in use, in slot
/// order: two maps built by the same calls have the same digest exactly when their ESDFs are bit-identical
/// (`TETHERBOT_ESDF_DIGEST=1 tetherbot map-check ...` prints it after every scan, with [`tsdf_digest`]).
pub fn esdf_digest(map: &Map<'_>) -> u64 {
    fnv1a(voxels_in_use(map).flat_map(|g| {
        [map.esdf_voxel(g).map_or(u32::MAX, f32::to_bits), map.site_distance_voxels(g).map_or(u32::MAX, f32::to_bits)]
    }))
}

/// FNV-1a digest of every voxel's TSDF value and weight (bit patterns) over the blocks in use, in slot order, as
/// [`esdf_digest`] for the ESDF: equal exactly when the integrations left bit-identical TSDFs.
pub fn tsdf_digest(map: &Map<'_>) -> u64 {
    fnv1a(voxels_in_use(map).flat_map(|g| {
        map.tsdf_voxel(g).map_or([u32::MAX; 2], |(t, w)| [t.to_bits(), w.to_bits()])
    }))
}

/// Every voxel of the blocks in use, slot order: coordinates (3 x i32), ESDF value and site distance (f32 bits,
/// `u32::MAX` = none), little endian (`TETHERBOT_ESDF_DUMP=DIR` writes one file per scan).
pub fn esdf_dump(map: &Map<'_>) -> Vec<u8> {
    let mut out = Vec::new();
    for g in voxels_in_use(map) {
        for v in g {
            out.extend_from_slice(&v.to_le_bytes());
        }
        out.extend_from_slice(&map.esdf_voxel(g).map_or(u32::MAX, f32::to_bits).to_le_bytes());
        out.extend_from_slice(&map.site_distance_voxels(g).map_or(u32::MAX, f32::to_bits).to_le_bytes());
    }
    out
}

/// Observed surface area from the TSDF zero crossings: each crossing along axis `a` stands for
/// `voxel^2 / (|n_x| + |n_y| + |n_z|)` of surface with normal `n`.
pub fn observed_surface_m2(map: &Map<'_>) -> f64 {
    let vs = map.config().voxel_size as f64;
    let mut cur = SurfaceCursor::default();
    let mut buf = vec![SurfacePoint { position: Vec3::zeros(), normal: Vec3::zeros() }; 4096];
    let mut area = 0.0;
    while !cur.is_done() {
        let n = map.extract_surface(&mut cur, &mut buf);
        for sp in &buf[..n] {
            let l1 = (sp.normal.x.abs() + sp.normal.y.abs() + sp.normal.z.abs()) as f64;
            area += vs * vs / l1.max(1.0);
        }
    }
    area
}

/// Compares the map's ESDF with the world's true signed distance (see the module docs).
pub fn esdf_errors(world: &dyn World, map: &Map<'_>, cfg: &CheckConfig, rep: &mut CheckReport) {
    let d = map.config().esdf_max_distance as f64;
    let vs = map.config().voxel_size as f64;
    let mut all = Vec::new();
    let mut near = Vec::new();
    let e = firmware::config::map::BLOCK_EDGE as i32;
    let mut k = 0usize;
    for slot in 0..map.blocks_used() {
        let Some(bc) = map.block_coord(slot) else { break };
        for z in 0..e {
            for y in 0..e {
                for x in 0..e {
                    k += 1;
                    if !k.is_multiple_of(cfg.sample_stride) {
                        continue;
                    }
                    let g = [bc[0] * e + x, bc[1] * e + y, bc[2] * e + z];
                    let Some(m) = map.esdf_voxel(g) else { continue };
                    let c = map.voxel_center(g);
                    let DistanceQuery::Known { distance: t, .. } = world.query(&c) else { continue };
                    let t = t as f64;
                    let err = m as f64 - t.clamp(-d, d);
                    all.push(err);
                    if t.abs() < cfg.near_m {
                        near.push(err);
                    }
                    if (m < 0.0 && t > vs) || (m >= 0.0 && t < -vs) {
                        rep.sign_errors += 1;
                        if t.abs() > map.config().truncation as f64 + vs {
                            rep.sign_errors_far += 1;
                        }
                    }
                }
            }
        }
    }
    rep.all = ErrorStats::of(&all);
    rep.near = ErrorStats::of(&near);
}

/// Builds the map over host storage and runs [`build_map`], [`esdf_errors`] and [`observed_surface_m2`].
pub fn run_check(world: &dyn World, poses: &[Pose3], cfg: &CheckConfig) -> CheckReport {
    let (mut blocks, mut index) = host_storage(cfg.pool_blocks);
    let Ok(mut map) = Map::from_slices(cfg.map, &mut blocks, &mut index) else {
        return CheckReport::default();
    };
    let mut rep = build_map(world, poses, cfg, &mut map);
    esdf_errors(world, &map, cfg, &mut rep);
    rep.surface_m2 = observed_surface_m2(&map);
    rep
}

/// The standard scan sequences of the checks, by world name: `crater_wall` (descend the wall from the rim to the
/// floor), `ledge` / `ledge_pole` (top of the ledge down the slope to the goal), `marsyard` (a 20 m diagonal
/// across the yard). Three yaws (-30, 0, +30 degrees) per station; stations every 0.5 m (1 m on the Mars Yard).
pub fn standard_poses(world: &dyn World, kind: &str) -> Vec<Pose3> {
    let yaws = [-30.0, 0.0, 30.0];
    match kind {
        "crater_wall" => drive_poses(world, [-3.0, 0.0], [7.0, 0.0], 0.5, 0.35, &yaws),
        "ledge" | "ledge_pole" => drive_poses(world, [-3.5, 0.0], [6.0, 0.0], 0.5, 0.35, &yaws),
        _ => drive_poses(world, [-10.0, -10.0], [10.0, 10.0], 1.0, 0.35, &yaws),
    }
}

/// A quick signed-distance probe for reports.
pub fn query_distance(f: &dyn DistanceField, p: Vec3) -> Option<Real> {
    match f.query(&p) {
        DistanceQuery::Known { distance, .. } => Some(distance),
        DistanceQuery::Unknown => None,
    }
}

/// A synthetic occupancy grid for the distance-transform comparisons: a rolling solid ground (a quarter of the
/// height, +-n/10 undulation) and random single-voxel obstacles above it with probability `density`. Index
/// `x + n (y + n z)`.
pub fn reference_grid(n: usize, density: f64, seed: u64) -> Vec<bool> {
    use rand_core::Rng;
    let mut rng = rand_pcg::Pcg64::new(seed as u128, 0x5851_f42d_4c95_7f2d);
    let mut g = vec![false; n * n * n];
    let tau = core::f64::consts::TAU;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let ground = n as f64 / 4.0
                    + n as f64 / 10.0 * (tau * x as f64 / n as f64).sin() * (tau * y as f64 / n as f64).cos();
                let r = (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
                g[x + n * (y + n * z)] = (z as f64) < ground || r < density;
            }
        }
    }
    g
}

/// Writes a grid for `host-sim/bench-ref/edt3d`: u32 n (LE), then n^3 bytes.
pub fn write_grid(path: &std::path::Path, grid: &[bool], n: usize) -> std::io::Result<()> {
    let mut bytes = Vec::with_capacity(4 + grid.len());
    bytes.extend_from_slice(&(n as u32).to_le_bytes());
    bytes.extend(grid.iter().map(|o| *o as u8));
    std::fs::write(path, bytes)
}

/// Runs the onboard ESDF on an occupancy grid (occupied voxels are sites of value 0, everything observed, cap
/// 127 voxels) and returns the thread CPU time of the full `update_esdf` in milliseconds and the distances in voxel units
/// (127 where beyond the cap), in grid order.
pub fn full_esdf_on_grid(grid: &[bool], n: usize) -> Result<(f64, Vec<f32>), String> {
    let mut cfg = MapConfig::with_voxel_size(0.1);
    cfg.esdf_max_distance = 12.7;
    cfg.esdf_max_sweeps = firmware::config::map::ESDF_SWEEPS_LIMIT;
    let blocks = (n / firmware::config::map::BLOCK_EDGE + 1).pow(3);
    let (mut b, mut i) = host_storage(blocks);
    let mut map = Map::from_slices(cfg, &mut b, &mut i).map_err(|e| format!("{e:?}"))?;
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                let occ = grid[x + n * (y + n * z)];
                map.set_voxel([x as i32, y as i32, z as i32], if occ { 0.0 } else { cfg.truncation }, 1.0)
                    .map_err(|e| format!("{e:?}"))?;
            }
        }
    }
    let (out, _, ms) = timed(|| map.update_esdf());
    if !out.converged {
        return Err("ESDF did not converge".into());
    }
    let mut d = Vec::with_capacity(n * n * n);
    for z in 0..n {
        for y in 0..n {
            for x in 0..n {
                d.push(map.site_distance_voxels([x as i32, y as i32, z as i32]).unwrap_or(127.0));
            }
        }
    }
    Ok((ms, d))
}

/// Where a map's blocks go: each block in use classified by the smallest |ESDF| among its observed voxels, and the
/// work area it covers (voxel columns, seen from above, that hold a TSDF zero crossing).
#[derive(Debug, Clone, Default)]
pub struct MapCensus {
    /// Blocks in use.
    pub blocks: usize,
    /// Blocks by the smallest |ESDF| of their observed voxels: `[< 0.25, 0.25-0.5, 0.5-1.0, >= 1.0 m, none
    /// observed]`.
    pub by_min_distance: [usize; 5],
    /// Unknown voxels in the blocks in use, fraction.
    pub unknown_fraction: f64,
    /// Plan-view area of the voxel columns with a surface crossing, m^2.
    pub footprint_m2: f64,
    /// Observed voxels by TSDF: `[within the truncation band, free space at +truncation, inside at -truncation]`
    /// (what a compact encoding could store with fewer bits).
    pub voxels_by_tsdf: [usize; 3],
    /// Blocks with observed voxels, all of them free space at +truncation (no surface, no site, no inside).
    pub free_only_blocks: usize,
}

/// Counts [`MapCensus`] over the blocks in use.
pub fn census(map: &Map<'_>) -> MapCensus {
    let e = firmware::config::map::BLOCK_EDGE as i32;
    let vs = map.config().voxel_size as f64;
    let mut c = MapCensus { blocks: map.blocks_used(), ..Default::default() };
    let mut unknown = 0usize;
    let mut columns = std::collections::BTreeSet::new();
    let trunc = map.config().truncation;
    // a TSDF within a thousandth of the truncation counts as saturated (its quantisation step is 1/32767 of it)
    let saturated = |t: f32| (t.abs() - trunc).abs() <= 1e-3 * trunc;
    for slot in 0..map.blocks_used() {
        let Some(b) = map.block_coord(slot) else { break };
        let mut min_d = f64::INFINITY;
        let (mut observed, mut free_only) = (false, true);
        for z in 0..e {
            for y in 0..e {
                for x in 0..e {
                    let g = [b[0] * e + x, b[1] * e + y, b[2] * e + z];
                    match map.esdf_voxel(g) {
                        Some(d) => min_d = min_d.min((d as f64).abs()),
                        None => unknown += 1,
                    }
                    let here = map.tsdf_voxel(g);
                    if let Some((t, _)) = here {
                        let k = match (saturated(t), t > 0.0) {
                            (false, _) => 0,
                            (true, true) => 1,
                            (true, false) => 2,
                        };
                        c.voxels_by_tsdf[k] += 1;
                        observed = true;
                        free_only &= k == 1;
                    }
                    if let (Some((t, _)), Some((u, _))) = (here, map.tsdf_voxel([g[0], g[1], g[2] + 1])) {
                        if (t < 0.0) != (u < 0.0) {
                            columns.insert((g[0], g[1]));
                        }
                    }
                }
            }
        }
        let k = match min_d {
            d if d < 0.25 => 0,
            d if d < 0.5 => 1,
            d if d < 1.0 => 2,
            d if d.is_finite() => 3,
            _ => 4,
        };
        c.by_min_distance[k] += 1;
        c.free_only_blocks += usize::from(observed && free_only);
    }
    c.unknown_fraction = unknown as f64 / (c.blocks.max(1) * (e * e * e) as usize) as f64;
    c.footprint_m2 = columns.len() as f64 * vs * vs;
    c
}

#[cfg(test)]
mod tests {
    use super::*;
    use firmware::geom::Pose3;

    /// A level floor scanned from 1 m above: the census finds band voxels at every column of the floor, free space
    /// above each, and blocks of free space only (the air under the sensor); with the unknown voxels the counts add
    /// up to the blocks' voxels.
    #[test]
    fn the_census_sorts_a_scanned_floor_into_band_and_free_space() {
        let (mut b, mut i) = host_storage(4096);
        let cfg = firmware::config::map::MapConfig::with_voxel_size(0.05);
        let mut map = Map::from_slices(cfg, &mut b, &mut i).unwrap();
        let pts: Vec<Vec3> = (0..40 * 40)
            .map(|k| Vec3::new(-1.0 + 0.05 * (k % 40) as f32, -1.0 + 0.05 * (k / 40) as f32, -1.0))
            .collect();
        let out = map.integrate_points(&Pose3::identity(), &pts);
        assert_eq!(out.points_integrated, 1600);
        map.update_esdf();
        let c = census(&map);
        let [band, free, inside] = c.voxels_by_tsdf;
        assert!(band > 1600 && free > 1600 && inside == 0, "{:?}", c.voxels_by_tsdf);
        let unknown = (c.unknown_fraction * (c.blocks * 64) as f64).round() as usize;
        assert_eq!(band + free + inside + unknown, c.blocks * 64);
        assert!(c.free_only_blocks > 0 && c.free_only_blocks < c.blocks, "{} of {}", c.free_only_blocks, c.blocks);
    }
}
