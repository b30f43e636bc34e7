//! Capacities and budgets for [`crate::map`], the onboard TSDF -> ESDF map (Paton et al. section IV, after
//! Voxblox, Oleynikova et al. 2017).
//!
//! Compile-time capacities (block edge, pool sizes, probe bound) are `const`s; per-mission numbers (voxel size,
//! truncation distance, budgets) live in [`MapConfig`], whose [`MapConfig::DEFAULT`] lists every default.

use crate::geom::Real;

/// Voxels along one edge of a voxel block. Default 4 (Voxblox's default is 8): a block of 4^3 = 64 voxels is
/// 544 B at [`crate::map::VOXEL_BYTES`] = 8 bytes per voxel plus 32 B of header. Terrain is a thin shell: in 8^3
/// blocks 56-60 % of the voxels of the blocks in use were never observed (the inside of the terrain under the
/// surface band); 4^3 blocks bring that to 37-39 % and the map's memory down by 26-32 % at the same ESDF error and
/// no slower integration, ESDF update or queries (`host-sim/doc/map.md`, 2026-12-03). Must be a power of two >= 4
/// (the ESDF's 4^3 pull cells).
pub const BLOCK_EDGE: usize = 4;
/// Voxels per block (`BLOCK_EDGE^3`).
pub const BLOCK_VOXELS: usize = BLOCK_EDGE * BLOCK_EDGE * BLOCK_EDGE;

/// Default number of blocks in the flight computer's pool. 23,040 blocks x 544 B = 11.95 MiB of the mps2-an500
/// board's 16 MiB PSRAM (with the index, 12.2 MiB: no more than the 3072 blocks of 8^3 voxels it replaced), leaving
/// ~3.8 MiB of PSRAM for the planners' arenas (the board's `bench` mode places the ABIT*, homotopy and team arenas
/// there). At 5 cm voxels a block is 0.2 m on a side; observed terrain costs 62-84 kB per m^2 of surface
/// (host-sim/doc/map.md), so the pool holds ~150-200 m^2 of terrain at 5 cm.
pub const FLIGHT_BLOCKS: usize = 23_040;
/// Default size of the block index (open addressing, power of two, at least 2x the pool so probes stay short).
pub const FLIGHT_INDEX: usize = 65_536;

/// Largest block pool a [`crate::map::Map`] accepts (`Map::from_slices` and `Map::reattach` refuse a longer one
/// with `MapError::BadStorage`): 2^24 - 1 blocks (9.1 GB at 544 B), so a slot fits the 24-bit link of the ESDF's
/// FIFO of blocks with spilled voxels (`map::esdf`) with one value left for "none".
pub const MAX_POOL_BLOCKS: usize = (1 << 24) - 1;

/// Longest probe sequence in the block index before an insert gives up with
/// [`crate::map::MapError::IndexProbeExhausted`]. Default 32: at load factor <= 0.5 linear probing needs ~1.5
/// probes on average; 32 is a generous bound that keeps every lookup O(1) and bounded.
pub const MAX_PROBE: usize = 32;

/// Unknown space below an observed surface (`Map::esdf_filled`): an unknown voxel whose first known
/// voxel above, within this many voxels, is occupied is taken as inside the terrain. Default 8 (0.4 m at 5 cm,
/// 0.8 m at 10 cm: deeper than the settler's wheel rims and drops reach under a surface). Each query that meets
/// unknown space looks up at most this many voxels per cell corner.
pub const BELOW_SURFACE_FILL_VOXELS: i32 = 8;

/// Map bounds: the largest |voxel coordinate| on any axis that [`crate::map::Map::integrate_points`] accepts for a
/// sensor origin or a point. Default 2^22 voxels (210 km at 5 cm). A point or sensor pose beyond it (a pose of
/// 1e30 m, a corrupted transform) is rejected and counted in
/// [`crate::map::IntegrationOutcome::points_out_of_bounds`]: voxel indices are `i32`, and below 2^24 they and their
/// centres are exact in `f32`, so every index a ray then visits (at most `max_ray_voxels` steps on) stays far from
/// overflow.
pub const MAX_VOXEL_COORD: Real = 4_194_304.0;

/// Smallest cosine between a ray and the surface normal by which TSDF integration scales the ray's projective
/// distances (`map::tsdf`, `incidence_cosine`). Default 0.1: a ray within 6 degrees of the surface is scaled as if
/// at 6 degrees, so a normal estimated from a few voxels cannot turn a whole ray's free space into near-surface.
pub const MIN_INCIDENCE_COSINE: Real = 0.1;

/// Largest [`MapConfig::max_ray_voxels`] accepted: 1024 voxels per ray (51 m at 5 cm). A map configuration can
/// come over the link (`Configure.map`); this keeps the work per point, and so per executive step, bounded.
pub const MAX_RAY_VOXELS_LIMIT: usize = 1024;
/// Largest [`MapConfig::esdf_max_sweeps`] accepted: 256 sweeps (of [`ESDF_VISITS_PER_BLOCK`] voxel visits per
/// block in use) per ESDF update, 8 times the default, for the same reason.
pub const ESDF_SWEEPS_LIMIT: usize = 256;

/// Capacity of the ESDF's lower queue (the wavefront of voxels whose site just improved), in voxels: a fixed array
/// of this many `u32` on the stack of [`crate::map::Map::update_esdf`]. Default 8192 (32 KiB of stack, a quarter
/// of the board's stack guard). A voxel that finds the queue full is not lost: it waits in a bit of its block, and
/// its block in a first-in first-out list of such blocks that refills the queue when it runs dry (`map::esdf`), so
/// a full queue costs a little time, not correctness.
pub const ESDF_QUEUE_CAPACITY: usize = 8192;

/// The unit of the ESDF budget [`MapConfig::esdf_max_sweeps`]: one "sweep" of the wavefront is this many voxel
/// visits (a pull or a pop, each comparing one voxel with its 26 neighbours) per block in use, and at least
/// [`ESDF_QUEUE_CAPACITY`] visits. Default `BLOCK_VOXELS / 8`, 8 at the default edge (an eighth of a block's
/// voxels: the wavefront touches only changed voxels, where a raster sweep visited all of them), so the default
/// budget of 32 is 256 visits per block in use, 5.9 M visits for the full flight pool.
pub const ESDF_VISITS_PER_BLOCK: usize = BLOCK_VOXELS / 8;

/// Per-mission map parameters (runtime). Every field is validated by [`MapConfig::validate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MapConfig {
    /// Voxel edge, metres. Default 0.05 (5 cm, Voxblox's and Paton et al.'s resolution scale).
    pub voxel_size: Real,
    /// TSDF truncation distance, metres. Default 0.15 (3 voxels; Voxblox recommends 2-4 voxels).
    pub truncation: Real,
    /// Cap of the accumulated TSDF weight. Default 100 observations: old observations still count, but a moved
    /// surface is re-learned within ~100 frames.
    pub max_weight: Real,
    /// Free-space carving: TSDF voxels are updated along at most this length of each ray in front of the surface
    /// (metres). Default 4.0. Together with `max_ray_voxels` this bounds the work per point.
    pub max_carve_length: Real,
    /// Hard bound on voxels visited by one ray (the integration budget per point). Default 128.
    pub max_ray_voxels: usize,
    /// Points farther than this from the sensor origin are ignored (metres). Default 20.0.
    pub max_range: Real,
    /// Points closer than this are ignored (the rover's own body). Default 0.1 m.
    pub min_range: Real,
    /// ESDF fixed band, in voxels: voxels with |TSDF| below `esdf_band * voxel_size` are ESDF sites whose
    /// distance is their TSDF value (Voxblox's "fixed band"). Default 1.0. Must be <= 1.25 (site values are stored as
    /// signed hundredths of a voxel in an `i8`).
    pub esdf_band: Real,
    /// ESDF hysteresis, in voxels: a fixed-band site whose TSDF moves by less than this keeps its old value, so
    /// sensor noise on an already-seen surface does not trigger ESDF updates. Default 0.1 (5 mm at 5 cm); it adds
    /// at most this much to the ESDF error. 0 = update on every change.
    pub esdf_site_tolerance: Real,
    /// ESDF saturation distance, metres: beyond it the ESDF reports exactly this value (a lower bound on the true
    /// distance). Default 1.5 (covers Axel's 1 m wheel base and the tether sweep). At most 127 voxels.
    pub esdf_max_distance: Real,
    /// ESDF budget per [`crate::map::Map::update_esdf`] call, in sweeps of [`ESDF_VISITS_PER_BLOCK`] voxel visits
    /// per block in use (the name is the link protocol's, from the raster sweeps the wavefront replaced). Default
    /// 32. A call that runs out returns `converged: false` and the next call continues from where it stopped.
    pub esdf_max_sweeps: usize,
}

impl MapConfig {
    /// The defaults listed on each field.
    pub const DEFAULT: MapConfig = MapConfig {
        voxel_size: 0.05,
        truncation: 0.15,
        max_weight: 100.0,
        max_carve_length: 4.0,
        max_ray_voxels: 128,
        max_range: 20.0,
        min_range: 0.1,
        esdf_band: 1.0,
        esdf_site_tolerance: 0.1,
        esdf_max_distance: 1.5,
        esdf_max_sweeps: 32,
    };

    /// Same defaults at another voxel size: truncation 3 voxels, carving and ray budget scaled to keep 4 m.
    pub fn with_voxel_size(voxel_size: Real) -> MapConfig {
        let mut c = MapConfig::DEFAULT;
        c.voxel_size = voxel_size;
        c.truncation = 3.0 * voxel_size;
        // saturating: a tiny voxel size saturates the cast; validate() then refuses the config with a reason
        c.max_ray_voxels = ((c.max_carve_length / voxel_size) as usize).saturating_add(16);
        c
    }

    /// Checks every field; the error names the field and why.
    pub fn validate(&self) -> Result<(), ConfigError> {
        let pos = |v: Real| v.is_finite() && v > 0.0;
        if !pos(self.voxel_size) {
            return Err(ConfigError { field: "voxel_size", reason: "must be finite and > 0" });
        }
        if !pos(self.truncation) || self.truncation < self.voxel_size {
            return Err(ConfigError { field: "truncation", reason: "must be finite and >= voxel_size" });
        }
        if !pos(self.max_weight) || self.max_weight > 1000.0 {
            return Err(ConfigError { field: "max_weight", reason: "must be in (0, 1000]" });
        }
        if !pos(self.max_carve_length) {
            return Err(ConfigError { field: "max_carve_length", reason: "must be finite and > 0" });
        }
        if self.max_ray_voxels == 0 || self.max_ray_voxels > MAX_RAY_VOXELS_LIMIT {
            return Err(ConfigError { field: "max_ray_voxels", reason: "must be in 1..=1024" });
        }
        if !pos(self.max_range) || self.min_range.is_nan() || self.min_range < 0.0 || self.min_range >= self.max_range {
            return Err(ConfigError { field: "max_range", reason: "need 0 <= min_range < max_range, finite" });
        }
        if !pos(self.esdf_band) || self.esdf_band > 1.25 {
            return Err(ConfigError { field: "esdf_band", reason: "must be in (0, 1.25] voxels" });
        }
        if !(self.esdf_site_tolerance >= 0.0 && self.esdf_site_tolerance <= 0.5) {
            return Err(ConfigError { field: "esdf_site_tolerance", reason: "must be in [0, 0.5] voxels" });
        }
        if !pos(self.esdf_max_distance) || self.esdf_max_distance / self.voxel_size > 127.0 {
            return Err(ConfigError {
                field: "esdf_max_distance",
                reason: "must be > 0 and at most 127 voxels (site offsets are stored as i8)",
            });
        }
        if self.esdf_max_sweeps == 0 || self.esdf_max_sweeps > ESDF_SWEEPS_LIMIT {
            return Err(ConfigError { field: "esdf_max_sweeps", reason: "must be in 1..=256" });
        }
        Ok(())
    }
}

impl Default for MapConfig {
    fn default() -> Self {
        MapConfig::DEFAULT
    }
}

/// A rejected [`MapConfig`]: which field and why.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ConfigError {
    /// The field name.
    pub field: &'static str,
    /// What is wrong with it.
    pub reason: &'static str,
}

/// Points of a scan converted and integrated per batch by [`crate::nav::Navigator`] (its only stack buffer:
/// 12 bytes a point). Default 256 (3 KiB of stack).
pub const NAV_POINT_BATCH: usize = 256;

#[cfg(test)]
mod tests {
    use super::*;

    /// Found by the `scenario` fuzz target (`voxel_size_m = 0.0`): the ray budget's `+ 16` overflowed after the
    /// cast saturated. Now such sizes give a configuration that `validate` refuses with its reason.
    #[test]
    fn a_zero_or_tiny_voxel_size_is_refused_not_overflowed() {
        for v in [0.0, 1e-30, -0.0, Real::MIN_POSITIVE] {
            assert!(MapConfig::with_voxel_size(v).validate().is_err(), "{v}");
        }
        assert_eq!(MapConfig::with_voxel_size(0.05).validate(), Ok(()));
    }
}
