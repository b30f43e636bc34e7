//! Terrain tiles for the flight software's homotopy planner (issue 20 item 4, protocol v7 `TileChunk`): a host tool
//! that resamples a scenario's terrain (the "orbital DEM": the base terrain, without the rocks a scenario hides)
//! onto a regular grid of posts and cuts it into chunks of `MAX_HEIGHTS_PER_TILE_CHUNK` heights.

use firmware::config::protocol::MAX_HEIGHTS_PER_TILE_CHUNK;
use firmware::geom::Real;
use firmware::protocol::TileChunk;
use serde::{Deserialize, Serialize};

use crate::world::World;

/// `[mission.homotopy]`: the tile a mission uploads before its `PlannerChoice::Homotopy` goal.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TileSpec {
    /// World x, y of post (0, 0), metres.
    pub origin: [f64; 2],
    /// Post spacing, metres (0.02 ..= 5).
    pub resolution_m: f64,
    /// Posts along x and along y (each 1 ..= 128).
    pub posts: [u16; 2],
}

/// The tile's heights, row-major from the smallest y; a post the world has no height for is NaN (the flight software
/// refuses such a tile with `Nack(NonFinite)`).
pub fn tile_heights(world: &dyn World, spec: &TileSpec) -> Vec<f32> {
    let [cols, rows] = spec.posts;
    let mut h = Vec::with_capacity(usize::from(rows) * usize::from(cols));
    for r in 0..rows {
        for c in 0..cols {
            let x = spec.origin[0] + f64::from(c) * spec.resolution_m;
            let y = spec.origin[1] + f64::from(r) * spec.resolution_m;
            h.push(world.height_at(x as Real, y as Real).unwrap_or(f32::NAN));
        }
    }
    h
}

/// The chunks of tile `tile_id` (in order; every chunk full but the last).
pub fn tile_chunks(tile_id: u32, spec: &TileSpec, heights: &[f32]) -> Vec<TileChunk> {
    let count = heights.len().div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK);
    heights
        .chunks(MAX_HEIGHTS_PER_TILE_CHUNK)
        .enumerate()
        .map(|(i, part)| TileChunk {
            tile_id,
            chunk_index: i as u16,
            chunk_count: count as u16,
            origin_x_m: spec.origin[0] as f32,
            origin_y_m: spec.origin[1] as f32,
            resolution_m: spec.resolution_m as f32,
            rows: spec.posts[1],
            cols: spec.posts[0],
            heights: part.iter().copied().collect(),
        })
        .collect()
}

/// The mission scenario whose tile the board's `homotopy_tile_*` workloads plan on (`workloads::homotopy_tile`).
pub const HIRISE_SCENARIO: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/scenarios/mission_homotopy_hirise.toml");

/// The tile `mission_homotopy_hirise.toml` uploads (its `[mission.homotopy]` spec on its terrain): the input of the
/// `homotopy_tile_*` workloads on the host, and what the board embeds (`firmware/boards/mps2-an500/data/`).
pub fn hirise_tile() -> Result<(TileSpec, Vec<f32>), String> {
    let sc = crate::scenario::load(std::path::Path::new(HIRISE_SCENARIO)).map_err(|e| e.to_string())?;
    let spec = sc.mission.homotopy.ok_or_else(|| format!("{HIRISE_SCENARIO}: no [mission.homotopy]"))?;
    let world = sc.build_world().map_err(|e| e.to_string())?;
    Ok((spec, tile_heights(world.as_ref(), &spec)))
}
