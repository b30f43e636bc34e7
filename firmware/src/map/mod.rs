//! The onboard terrain map: TSDF integration into a fixed pool of voxel blocks, an ESDF with distance and gradient
//! queries, and surface points with normals (Paton et al., section IV, which plans on a Voxblox map: Oleynikova et
//! al., "Voxblox: Incremental 3D Euclidean Signed Distance Fields for On-Board MAV Planning", IROS 2017).
//!
//! The rover, tether and planners program against [`DistanceField`]; the simulator's ground-truth worlds implement
//! it too, so every check can run on exact geometry and on the onboard map alike.
//!
//! ## Layout
//! - [`Block`]: `BLOCK_EDGE`^3 voxels (4^3 by default), [`VOXEL_BYTES`] = 8 bytes per voxel: quantised TSDF
//!   (`i16`, units of truncation / 32767), weight (`u16`, 1/64 units), the ESDF site (`[i8; 3]` offset to the
//!   nearest fixed-band voxel) and that site's signed TSDF (`i8`, hundredths of a voxel); plus the ESDF
//!   wavefront's bookkeeping, a 64-bit mask of cells to pull, one bit per voxel for the
//!   queue's overflow and a 24-bit link for the list of blocks with overflowed voxels (544 B a block at the
//!   default edge, 32 B of it header).
//! - [`MapStorage`]: the block pool plus the block index, owned by the caller (`static` on the board, `Box` on the
//!   host) and lent to [`Map::new`]. The index is open addressing with linear probing, bounded by
//!   [`MAX_PROBE`](crate::config::map::MAX_PROBE). Blocks are allocated on demand and freed only by
//!   [`Map::forget_beyond`] (the navigator's room-making on long traverses): a full pool or an exhausted probe is
//!   reported in [`IntegrationOutcome::pool_error`], and the voxels that fell into unallocated blocks are counted in
//!   [`IntegrationOutcome::voxels_dropped`] (the rest of the frame still lands).
//!
//! ## TSDF integration ([`Map::integrate_points`], Voxblox's ray-casting integrator)
//! Each point of a sensor frame is a ray from the sensor origin. Voxels along the ray from `depth -
//! max_carve_length` to `depth + truncation` (at most `max_ray_voxels` of them, the ones nearest the surface
//! first kept) get the projective signed distance `depth - (c - o).d`, truncated to `[-truncation, truncation]`,
//! averaged with weight 1 (linearly dropping to 0 between one voxel and `truncation` behind the surface, as in
//! Voxblox). Voxels with weight 0 are **unknown**; observed voxels with TSDF >= 0 are free, < 0 occupied.
//! Deviation from Voxblox's "fast" integrator: no per-scan ray merging; the carving length budget bounds the cost
//! per point instead, which is what a flight budget needs.
//! Points that are not finite, outside `min_range..=max_range`, or (with their sensor origin) beyond the map bounds
//! [`MAX_VOXEL_COORD`](crate::config::map::MAX_VOXEL_COORD) are rejected and counted
//! ([`IntegrationOutcome::points_rejected`], of them [`IntegrationOutcome::points_out_of_bounds`]).
//!
//! ## ESDF ([`Map::update_esdf`])
//! Sites are the observed voxels inside the fixed band `|TSDF| < esdf_band` voxels; a site's distance is its own
//! `|TSDF|`. Every other voxel `v` gets `min over sites s (|c_v - c_s| + sign_v * TSDF_s)`, capped at
//! `esdf_max_distance`, with the sign `sign_v` of its own TSDF. Both cases of the sum are upper bounds of the
//! true distance: a site on the same side as `v` is `|TSDF_s|` from the surface, so the surface is within
//! `|c_v - c_s| + |TSDF_s|`; a site on the other side is `|TSDF_s|` beyond the surface along the segment from
//! `v`, so the surface is within `|c_v - c_s| - |TSDF_s|` (Voxblox's fixed band, with the opposite-side case made
//! tight; without it the ESDF is biased by up to two band widths). The minimum is found by vector propagation (each
//! voxel stores the offset of its nearest site and takes the best site of its 26 neighbours), run as a queue-based
//! incremental wavefront (Voxblox; FIESTA, Han et al. 2019) that touches only the voxels whose site changed and
//! their neighbours, within the budget `esdf_max_sweeps` (then the next call continues; see `map::esdf` for the
//! steps, the fixed-capacity queue and its overflow into per-voxel bits of the lent blocks).
//! Fixed-band sites keep their own value (they are never overwritten by propagation). Updates are incremental:
//! a TSDF update marks its block only if it changes what the ESDF uses (observed, sign, band membership, or the
//! site value by more than `esdf_site_tolerance`), and a voxel whose sign changed marks its cell; the sites of
//! marked blocks are rebuilt; voxels within `esdf_max_distance` of a block whose sites moved or vanished are
//! checked against their site and reset if it is gone (Voxblox's "raise" wave, done directly since each voxel knows
//! its site); the wavefront lowers the rest. Vector propagation with 26 neighbours is not
//! guaranteed exact in every configuration (Danielsson 1980; Cuisenaire & Macq 1999); the tests measure it
//! against brute force.
//!
//! ## Queries
//! [`DistanceField::query`] interpolates trilinearly between the 8 voxel centres around the point, with the
//! analytic gradient of that interpolant (normalised). If any of the 8 voxels is unknown, the answer is
//! [`DistanceQuery::Unknown`]. [`Map::extract_surface`] fills a caller's slice with surface points (zero
//! crossings of the TSDF between neighbouring observed voxels) and normals (TSDF gradient), resumable through a
//! [`SurfaceCursor`].
//!
//! Parameters and their defaults: see [`MapConfig`](crate::config::map::MapConfig).

mod esdf;
mod query;
mod tsdf;

pub use esdf::EsdfOutcome;
pub use query::{SurfaceCursor, SurfacePoint, VoxelState};
pub use tsdf::IntegrationOutcome;

use crate::config::map::{ConfigError, MapConfig, BLOCK_EDGE, BLOCK_VOXELS, MAX_POOL_BLOCKS, MAX_PROBE};
use crate::geom::{Real, Vec3};

/// What a signed-distance query can say about a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DistanceQuery {
    /// The point is in observed space: signed distance to the nearest surface (metres, negative inside terrain)
    /// and the distance gradient (points away from the terrain, unit length where defined).
    Known {
        /// Signed distance, metres.
        distance: Real,
        /// Gradient of the distance field.
        gradient: Vec3,
    },
    /// Nobody has observed this point: neither free nor occupied. Callers treat it as unsafe.
    Unknown,
}

/// A Euclidean signed distance field: the onboard ESDF implements it, and so do the simulator's ground-truth worlds
/// and analytic test scenes, so rover settling, anchor prediction and planning can be tested on exact geometry.
pub trait DistanceField {
    /// Signed distance and gradient at `p`.
    fn query(&self, p: &Vec3) -> DistanceQuery;

    /// `Some(L)` when the field is known everywhere (never `Unknown` at a finite point) and `L`-Lipschitz:
    /// `|d(p) - d(q)| <= L |p - q|` (an exact signed distance field has `L = 1`). A sample at distance `d` then
    /// proves every point closer than `(d - c) / L` farther than `c` from the terrain, and the tether's sweep lines
    /// skip them ([`crate::tether`]). Default `None` (the onboard map: its unknown space must be seen, and its
    /// interpolated field carries no such bound; it bounds each cell instead, [`Self::query_with_cell_bound`]).
    fn lipschitz_bound(&self) -> Option<Real> {
        None
    }

    /// The key of the cell that holds `p` when the field is piecewise over cells: inside a cell, whether a query is
    /// `Unknown` depends only on the cell, and a known distance is a convex combination of values fixed per cell
    /// (the onboard map's trilinear interpolation cells). `None` (the default) when `p` lies in no such cell.
    fn cell_key(&self, _p: &Vec3) -> Option<CellKey> {
        None
    }

    /// [`Self::query`] at `p`, with a lower bound on the distance everywhere in `p`'s cell ([`Self::cell_key`])
    /// when the cell is known, already shrunk for rounding. A sample whose cell an earlier query bounded beyond the
    /// contact distance cannot block the tether's sweep line ([`crate::tether`]): the same answer, without the
    /// query. Default: the query and `None`.
    fn query_with_cell_bound(&self, p: &Vec3) -> (DistanceQuery, Option<Real>) {
        (self.query(p), None)
    }
}

/// A cell of a field that is piecewise over cells ([`DistanceField::cell_key`]): the onboard map's interpolation
/// cell, by its lowest voxel.
pub type CellKey = [i32; 3];

/// `map`'s [`DistanceField::lipschitz_bound`] when it can be used (finite and positive), else `None`.
pub fn usable_lipschitz_bound(map: &impl DistanceField) -> Option<Real> {
    map.lipschitz_bound().filter(|l| l.is_finite() && *l > 0.0)
}

/// The slack of [`lipschitz_lower_bound`] for `f32` rounding: the bound `L` is taken 0.1 % larger.
pub const LIPSCHITZ_SLACK: Real = 1.001;
/// The margin of [`lipschitz_lower_bound`] for `f32` rounding of positions and distances: 0.1 mm.
pub const LIPSCHITZ_MARGIN_M: Real = 1e-4;

/// A lower bound on the distance at a point `moved` metres from one where it was `d`, on an `l`-Lipschitz field:
/// `d - l moved`, shrunk by [`LIPSCHITZ_SLACK`] and [`LIPSCHITZ_MARGIN_M`]. The settle, the boom sweep and the
/// tether's sweep lines skip the queries this proves cannot change their answers.
pub fn lipschitz_lower_bound(l: Real, d: Real, moved: Real) -> Real {
    d - LIPSCHITZ_SLACK * l * moved - LIPSCHITZ_MARGIN_M
}

/// A distance field whose unobserved space reads as free, [`UNOBSERVED_FREE_DISTANCE_M`] from any surface: for
/// the tether's anchor prediction only, where the tether physically runs through space the sensor did not see
/// (see `TetherSpaceParams::tether_through_unobserved`). Never for the rover's own footprint.
pub struct UnobservedAsFree<'a, D>(pub &'a D);

/// The distance [`UnobservedAsFree`] reports for unobserved space, metres: farther than any contact distance.
pub const UNOBSERVED_FREE_DISTANCE_M: Real = 1.0e3;

impl<D: DistanceField> DistanceField for UnobservedAsFree<'_, D> {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        match self.0.query(p) {
            DistanceQuery::Unknown if crate::geom::is_finite3(p) => {
                DistanceQuery::Known { distance: UNOBSERVED_FREE_DISTANCE_M, gradient: Vec3::zeros() }
            }
            q => q,
        }
    }

    fn cell_key(&self, p: &Vec3) -> Option<CellKey> {
        self.0.cell_key(p)
    }

    /// The inner field's bound; a cell the inner field does not know at all reads as free throughout.
    fn query_with_cell_bound(&self, p: &Vec3) -> (DistanceQuery, Option<Real>) {
        match self.0.query_with_cell_bound(p) {
            (DistanceQuery::Unknown, _) if crate::geom::is_finite3(p) => (
                DistanceQuery::Known { distance: UNOBSERVED_FREE_DISTANCE_M, gradient: Vec3::zeros() },
                self.0.cell_key(p).map(|_| UNOBSERVED_FREE_DISTANCE_M),
            ),
            q => q,
        }
    }
}

/// Bytes of voxel payload per voxel (TSDF 2 + weight 2 + site offset 3 + site distance 1).
pub const VOXEL_BYTES: usize = 8;

/// Site-distance value meaning "no site within `esdf_max_distance`".
pub(crate) const NO_SITE: i8 = i8::MIN;

const FLAG_IN_USE: u8 = 1;
const FLAG_TSDF_DIRTY: u8 = 2;
/// Allocated since the last ESDF update: its voxels have not heard of the sites around it yet.
const FLAG_ESDF_NEW: u8 = 4;
/// Some bit of `queued` is set.
const FLAG_QUEUED: u8 = 8;
const FLAG_REGION: u8 = 16;
const FLAG_SITES_CHANGED: u8 = 32;
/// Some voxel lost its site in this ESDF update (its offset holds `esdf::RESET`) and is still to be pulled.
const FLAG_RESET: u8 = 64;
/// To be forgotten by the running [`Map::forget_beyond`] (never set outside it).
const FLAG_FORGET: u8 = 128;

/// Words of a block's `queued` bit set.
const QUEUED_WORDS: usize = BLOCK_VOXELS.div_ceil(64);

/// Voxel coordinate shift from a voxel to its pull cell: a block has 4^3 = 64 cells (of 2^3 voxels at the default
/// edge of 8), one bit each in [`Block`]'s `pending` mask.
const CELL_SHIFT: u32 = {
    assert!(BLOCK_EDGE >= 4 && BLOCK_EDGE.is_power_of_two(), "a block needs 4^3 pull cells");
    BLOCK_EDGE.trailing_zeros() - 2
};

/// The bit of `pending` for the cell of local voxel `i`.
#[inline]
pub(crate) fn cell_bit(i: usize) -> u64 {
    let l = local_coords(i);
    let c = (l[0] >> CELL_SHIFT) + 4 * ((l[1] >> CELL_SHIFT) + 4 * (l[2] >> CELL_SHIFT));
    1u64 << (c & 63)
}

/// One voxel block: `BLOCK_EDGE`^3 voxels, structure of arrays, voxel `(x, y, z)` at `x + E * (y + E * z)`.
#[derive(Clone, Copy)]
pub struct Block {
    coord: [i32; 3],
    flags: u8,
    /// Cells (see [`cell_bit`]) whose voxels the ESDF must compare with their neighbours again: a voxel changed
    /// sign, the block is new, or an ESDF update ran out of budget before pulling them.
    pending: u64,
    /// Voxels whose improved site is still to be offered to their neighbours and that found the ESDF's lower queue
    /// full (one bit per voxel): the queue's overflow, in the lent storage.
    queued: [u64; QUEUED_WORDS],
    /// The next block in the ESDF update's FIFO of blocks with `queued` bits (24-bit slot, little-endian;
    /// scratch of one update, rebuilt in slot order at the start of the next one).
    qnext: [u8; 3],
    tsdf: [i16; BLOCK_VOXELS],
    weight: [u16; BLOCK_VOXELS],
    /// Each voxel's ESDF site: offset and value together, as the wavefront reads and writes them together.
    esdf: [Site; BLOCK_VOXELS],
}

/// A voxel's ESDF site: the offset (voxels) from the voxel to its site, and the site's signed value in hundredths of
/// a voxel ([`NO_SITE`]: none).
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) struct Site {
    pub(crate) off: [i8; 3],
    pub(crate) w: i8,
}

impl Block {
    /// An unused block (for building storage).
    pub const EMPTY: Block = Block {
        coord: [0; 3],
        flags: 0,
        pending: 0,
        queued: [0; QUEUED_WORDS],
        qnext: [0; 3],
        tsdf: [0; BLOCK_VOXELS],
        weight: [0; BLOCK_VOXELS],
        esdf: [Site { off: [0; 3], w: NO_SITE }; BLOCK_VOXELS],
    };

    /// An unused block whose bytes are all zero: the initial value of storage in memory the board zeroes itself
    /// (its NOLOAD PSRAM section). Equivalent to [`Block::EMPTY`] for the map: a block's `flags` say it is unused,
    /// and allocation overwrites the whole block.
    pub const ZEROED: Block = Block {
        coord: [0; 3],
        flags: 0,
        pending: 0,
        queued: [0; QUEUED_WORDS],
        qnext: [0; 3],
        tsdf: [0; BLOCK_VOXELS],
        weight: [0; BLOCK_VOXELS],
        esdf: [Site { off: [0; 3], w: 0 }; BLOCK_VOXELS],
    };
}

impl core::fmt::Debug for Block {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_struct("Block").field("coord", &self.coord).field("flags", &self.flags).finish()
    }
}

/// The map's memory: a pool of `B` blocks and an index of `I` slots (`I` a power of two, `I >= B`). Owned by the
/// caller: `static mut`-free on the board via a `static` cell, `Box` on the host (see [`MapStorage::new`]).
pub struct MapStorage<const B: usize, const I: usize> {
    /// The block pool.
    pub blocks: [Block; B],
    /// The block index: 0 = empty, else pool slot + 1.
    pub index: [u32; I],
}

impl<const B: usize, const I: usize> MapStorage<B, I> {
    /// Empty storage. Checked at compile time: `I` is a power of two and at least `B`.
    pub const fn new() -> Self {
        const {
            assert!(I.is_power_of_two() && I >= B && B > 0, "index must be a power of two >= pool size");
        }
        MapStorage { blocks: [Block::EMPTY; B], index: [0; I] }
    }

    /// Bytes of this storage (what a board must reserve).
    pub const fn bytes() -> usize {
        core::mem::size_of::<Self>()
    }
}

impl<const B: usize, const I: usize> Default for MapStorage<B, I> {
    fn default() -> Self {
        Self::new()
    }
}

/// Why the map could not be built or a block could not be allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MapError {
    /// A configuration field is invalid.
    Config(ConfigError),
    /// The index length is not a power of two, or is smaller than the pool, or the pool is empty.
    BadStorage,
    /// Every block of the pool is in use.
    PoolFull,
    /// The index probe bound ([`MAX_PROBE`]) ran out before a free slot was found.
    IndexProbeExhausted,
}

/// Global voxel index.
pub type VoxelIndex = [i32; 3];

/// The onboard map over lent storage.
pub struct Map<'a> {
    cfg: MapConfig,
    blocks: &'a mut [Block],
    index: &'a mut [u32],
    used: usize,
}

/// Floor division by the block edge (a power of two) and the local coordinate.
#[inline]
pub(crate) fn split(g: i32) -> (i32, usize) {
    const SHIFT: u32 = BLOCK_EDGE.trailing_zeros();
    (g >> SHIFT, (g & (BLOCK_EDGE as i32 - 1)) as usize)
}

#[inline]
pub(crate) fn local_index(l: [usize; 3]) -> usize {
    l[0] + BLOCK_EDGE * (l[1] + BLOCK_EDGE * l[2])
}

#[inline]
fn local_coords(i: usize) -> [usize; 3] {
    [i % BLOCK_EDGE, (i / BLOCK_EDGE) % BLOCK_EDGE, i / (BLOCK_EDGE * BLOCK_EDGE)]
}

#[inline]
fn hash(c: [i32; 3]) -> usize {
    let h = (c[0] as u32).wrapping_mul(73_856_093) ^ (c[1] as u32).wrapping_mul(19_349_663)
        ^ (c[2] as u32).wrapping_mul(83_492_791);
    // The index takes the low bits, and the low bits of the products above depend only on the coordinates' low
    // bits: a dense box of 23 x 20 x 16 blocks in an index at load 0.45 ran past `MAX_PROBE`. MurmurHash3's
    // 32-bit finaliser mixes every bit into the low ones (the slots, and so the map, are the same: only probing
    // changes).
    let h = (h ^ (h >> 16)).wrapping_mul(0x85eb_ca6b);
    let h = (h ^ (h >> 13)).wrapping_mul(0xc2b2_ae35);
    (h ^ (h >> 16)) as usize
}

impl<'a> Map<'a> {
    /// A map over `storage`, which is cleared.
    pub fn new<const B: usize, const I: usize>(
        cfg: MapConfig,
        storage: &'a mut MapStorage<B, I>,
    ) -> Result<Map<'a>, MapError> {
        Map::from_slices(cfg, &mut storage.blocks, &mut storage.index)
    }

    /// A map over separately lent slices (the host can `vec!` them). `index.len()` must be a power of two
    /// `>= blocks.len() > 0`. Both are cleared.
    pub fn from_slices(cfg: MapConfig, blocks: &'a mut [Block], index: &'a mut [u32]) -> Result<Map<'a>, MapError> {
        cfg.validate().map_err(MapError::Config)?;
        if blocks.is_empty()
            || blocks.len() > MAX_POOL_BLOCKS
            || !index.len().is_power_of_two()
            || index.len() < blocks.len()
        {
            return Err(MapError::BadStorage);
        }
        index.iter_mut().for_each(|e| *e = 0);
        blocks.iter_mut().for_each(|b| b.flags = 0);
        Ok(Map { cfg, blocks, index, used: 0 })
    }

    /// A map view over slices that an earlier [`Map`] built (with `used` = that map's [`Map::blocks_used`]),
    /// **without clearing them**: the owner of long-lived storage (the flight executive's navigator) rebuilds a view
    /// per call instead of holding a borrow. Checked like [`Map::from_slices`], plus `used <= blocks.len()`; slices
    /// that no `Map` built give a map of garbage, never a panic.
    pub fn reattach(
        cfg: MapConfig,
        blocks: &'a mut [Block],
        index: &'a mut [u32],
        used: usize,
    ) -> Result<Map<'a>, MapError> {
        cfg.validate().map_err(MapError::Config)?;
        if blocks.is_empty()
            || blocks.len() > MAX_POOL_BLOCKS
            || !index.len().is_power_of_two()
            || index.len() < blocks.len()
            || used > blocks.len()
        {
            return Err(MapError::BadStorage);
        }
        Ok(Map { cfg, blocks, index, used })
    }

    /// The configuration.
    pub fn config(&self) -> &MapConfig {
        &self.cfg
    }

    /// Blocks in use.
    pub fn blocks_used(&self) -> usize {
        self.used
    }

    /// Pool capacity in blocks.
    pub fn blocks_capacity(&self) -> usize {
        self.blocks.len()
    }

    /// Forgets every block whose centre lies farther than `radius_m` from `centre` in the horizontal plane: its
    /// voxels become unknown and its slot is free again (the last block in use moves into it). The map of a long
    /// traverse keeps what lies round the rover when its pool fills (the navigator calls this, `nav`), instead of
    /// dropping every new voxel. The ESDF is repaired by the next [`Map::update_esdf`]: the blocks next to a
    /// forgotten one are marked as if their sites had moved, so every voxel whose site was forgotten (it lies within
    /// `esdf_max_distance` of it) is reset and pulled again. Returns the blocks forgotten. Bounded: three passes over
    /// the blocks in use, 27 index lookups per forgotten block, and one backward-shift delete in the index each.
    pub fn forget_beyond(&mut self, centre: &Vec3, radius_m: Real) -> usize {
        if !(crate::geom::is_finite3(centre) && radius_m.is_finite() && radius_m >= 0.0) {
            return 0;
        }
        let edge = BLOCK_EDGE as Real * self.cfg.voxel_size;
        let r2 = radius_m * radius_m;
        let mut marked = 0;
        for b in self.blocks.iter_mut().take(self.used) {
            let cx = (b.coord[0] as Real + 0.5) * edge - centre.x;
            let cy = (b.coord[1] as Real + 0.5) * edge - centre.y;
            if cx * cx + cy * cy > r2 {
                b.flags |= FLAG_FORGET;
                marked += 1;
            }
        }
        if marked == 0 {
            return 0;
        }
        // the kept neighbours of forgotten blocks: their regions cover every voxel that may hold a forgotten site
        for s in 0..self.used {
            let Some(b) = self.blocks.get(s) else { break };
            if b.flags & FLAG_FORGET == 0 {
                continue;
            }
            let c = b.coord;
            for j in 0..27 {
                let n = [c[0] + (j % 3) - 1, c[1] + ((j / 3) % 3) - 1, c[2] + (j / 9) - 1];
                if let Some(nb) = self.find_block(n).and_then(|k| self.blocks.get_mut(k)) {
                    if nb.flags & FLAG_FORGET == 0 {
                        nb.flags |= FLAG_SITES_CHANGED;
                    }
                }
            }
        }
        // remove from the last slot down: the block moved into a freed slot has been looked at already
        let mut forgotten = 0;
        for s in (0..self.used).rev() {
            if self.blocks.get(s).is_some_and(|b| b.flags & FLAG_FORGET != 0) {
                if self.remove_block(s) {
                    forgotten += 1;
                } else if let Some(b) = self.blocks.get_mut(s) {
                    // not in the index (storage no `Map` built): kept, and the mark must not outlive this call
                    b.flags &= !FLAG_FORGET;
                }
            }
        }
        forgotten
    }

    /// Removes the block in `slot` (its index entry by backward shift, which keeps every other entry within its probe
    /// sequence) and moves the last block in use into the slot. `false` if the block is not in the index (storage no
    /// `Map` built): nothing changes.
    fn remove_block(&mut self, slot: usize) -> bool {
        let Some(c) = self.blocks.get(slot).map(|b| b.coord) else { return false };
        let Some(pos) = self.index_position(c) else { return false };
        let mask = self.index.len() - 1;
        let mut hole = pos;
        let mut j = pos;
        for _ in 0..self.index.len() {
            j = (j + 1) & mask;
            let e = self.index.get(j).copied().unwrap_or(0);
            if e == 0 {
                break;
            }
            let Some(home) = self.blocks.get((e - 1) as usize).map(|b| hash(b.coord) & mask) else { break };
            // the entry at j may fill the hole unless its home lies cyclically in (hole, j]
            if (j.wrapping_sub(home) & mask) >= (j.wrapping_sub(hole) & mask) {
                if let Some(h) = self.index.get_mut(hole) {
                    *h = e;
                }
                hole = j;
            }
        }
        if let Some(h) = self.index.get_mut(hole) {
            *h = 0;
        }
        let Some(last) = self.used.checked_sub(1) else { return false };
        if slot != last {
            let Some(moved) = self.blocks.get(last).copied() else { return false };
            if let Some(p) = self.index_position(moved.coord) {
                if let Some(e) = self.index.get_mut(p) {
                    *e = slot as u32 + 1;
                }
            }
            if let Some(b) = self.blocks.get_mut(slot) {
                *b = moved;
            }
        }
        if let Some(b) = self.blocks.get_mut(last) {
            b.flags = 0;
        }
        self.used = last;
        true
    }

    /// Position in the index of the entry of block `c`.
    fn index_position(&self, c: [i32; 3]) -> Option<usize> {
        let mask = self.index.len() - 1;
        let mut h = hash(c) & mask;
        for _ in 0..MAX_PROBE.min(self.index.len()) {
            match self.index.get(h).copied() {
                Some(0) | None => return None,
                Some(e) => {
                    if self.blocks.get((e - 1) as usize).is_some_and(|b| b.coord == c) {
                        return Some(h);
                    }
                }
            }
            h = (h + 1) & mask;
        }
        None
    }

    /// Forget everything (the storage stays lent).
    pub fn clear(&mut self) {
        self.index.iter_mut().for_each(|e| *e = 0);
        self.blocks.iter_mut().take(self.used).for_each(|b| b.flags = 0);
        self.used = 0;
    }

    /// The voxel containing `p`.
    pub fn voxel_index(&self, p: &Vec3) -> VoxelIndex {
        let s = 1.0 / self.cfg.voxel_size;
        [crate::geom::floor_i32(p.x * s), crate::geom::floor_i32(p.y * s), crate::geom::floor_i32(p.z * s)]
    }

    /// Centre of voxel `g`, metres.
    pub fn voxel_center(&self, g: VoxelIndex) -> Vec3 {
        let v = self.cfg.voxel_size;
        Vec3::new((g[0] as Real + 0.5) * v, (g[1] as Real + 0.5) * v, (g[2] as Real + 0.5) * v)
    }

    /// Block coordinates of the blocks in use, in allocation order (`slot < blocks_used()`).
    pub fn block_coord(&self, slot: usize) -> Option<[i32; 3]> {
        if slot < self.used {
            self.blocks.get(slot).map(|b| b.coord)
        } else {
            None
        }
    }

    pub(crate) fn find_block(&self, c: [i32; 3]) -> Option<usize> {
        let h = self.index_position(c)?;
        self.index.get(h).map(|e| (e - 1) as usize)
    }

    pub(crate) fn find_or_alloc_block(&mut self, c: [i32; 3]) -> Result<usize, MapError> {
        let mask = self.index.len() - 1;
        let mut h = hash(c) & mask;
        for _ in 0..MAX_PROBE.min(self.index.len()) {
            match self.index.get(h).copied() {
                Some(0) => {
                    let slot = self.used;
                    let b = self.blocks.get_mut(slot).ok_or(MapError::PoolFull)?;
                    *b = Block::EMPTY;
                    b.coord = c;
                    b.flags = FLAG_IN_USE | FLAG_TSDF_DIRTY | FLAG_ESDF_NEW;
                    if let Some(e) = self.index.get_mut(h) {
                        *e = slot as u32 + 1;
                    }
                    self.used += 1;
                    return Ok(slot);
                }
                Some(e) => {
                    let slot = (e - 1) as usize;
                    if self.blocks.get(slot).is_some_and(|b| b.coord == c) {
                        return Ok(slot);
                    }
                }
                None => return Err(MapError::IndexProbeExhausted),
            }
            h = (h + 1) & mask;
        }
        Err(MapError::IndexProbeExhausted)
    }

    /// Block slot and local voxel index of global voxel `g`, if its block exists.
    pub(crate) fn locate(&self, g: VoxelIndex) -> Option<(usize, usize)> {
        let (bx, lx) = split(g[0]);
        let (by, ly) = split(g[1]);
        let (bz, lz) = split(g[2]);
        self.find_block([bx, by, bz]).map(|s| (s, local_index([lx, ly, lz])))
    }

    /// Sets one voxel's TSDF observation directly (signed distance in metres, clamped to the truncation, and
    /// weight), allocating its block. For fixtures, tests and reference grids; flight code integrates frames.
    pub fn set_voxel(&mut self, g: VoxelIndex, sdf: Real, weight: Real) -> Result<(), MapError> {
        let (bx, lx) = split(g[0]);
        let (by, ly) = split(g[1]);
        let (bz, lz) = split(g[2]);
        let slot = self.find_or_alloc_block([bx, by, bz])?;
        let q = self.quantize_tsdf(sdf);
        let w = quantize_weight(weight, self.cfg.max_weight);
        if let Some(b) = self.blocks.get_mut(slot) {
            let li = local_index([lx, ly, lz]);
            if let (Some(t), Some(wt)) = (b.tsdf.get_mut(li), b.weight.get_mut(li)) {
                if (*t < 0) != (q < 0) {
                    b.pending |= cell_bit(li);
                }
                *t = q;
                *wt = w;
            }
            b.flags |= FLAG_TSDF_DIRTY;
        }
        Ok(())
    }

    pub(crate) fn quantize_tsdf(&self, sdf: Real) -> i16 {
        let t = self.cfg.truncation;
        let r = (crate::geom::clamp(sdf, -t, t) / t) * 32767.0;
        crate::geom::round_i32(r) as i16
    }

    pub(crate) fn dequantize_tsdf(&self, q: i16) -> Real {
        q as Real * (self.cfg.truncation / 32767.0)
    }

    /// Site hysteresis in hundredths of a voxel.
    pub(crate) fn site_tolerance(&self) -> i32 {
        crate::geom::round_i32(self.cfg.esdf_site_tolerance * 100.0)
    }

    /// Bytes of storage per block (what the pool costs per allocated block, index share excluded).
    pub const fn block_bytes() -> usize {
        core::mem::size_of::<Block>()
    }
}

/// Weights are stored in 1/64 units.
pub(crate) const WEIGHT_SCALE: Real = 64.0;

pub(crate) fn quantize_weight(w: Real, max_weight: Real) -> u16 {
    let w = if w.is_finite() { crate::geom::clamp(w, 0.0, max_weight) } else { 0.0 };
    crate::geom::round_i32(w * WEIGHT_SCALE).clamp(0, u16::MAX as i32) as u16
}

/// For the other modules' tests: the onboard map of an exact `field`, its voxels in the box `lo..hi` (voxel indices)
/// set from the field's distance where `observed(voxel centre)`, the rest unobserved, and its ESDF updated.
#[cfg(test)]
pub(crate) fn map_of_field<'a>(
    field: &impl DistanceField,
    cfg: MapConfig,
    (blocks, index): (&'a mut [Block], &'a mut [u32]),
    (lo, hi): (VoxelIndex, VoxelIndex),
    observed: impl Fn(&Vec3) -> bool,
) -> Map<'a> {
    let mut map = Map::from_slices(cfg, blocks, index).unwrap_or_else(|e| panic!("{e:?}"));
    for x in lo[0]..hi[0] {
        for y in lo[1]..hi[1] {
            for z in lo[2]..hi[2] {
                let c = map.voxel_center([x, y, z]);
                if let (true, DistanceQuery::Known { distance, .. }) = (observed(&c), field.query(&c)) {
                    map.set_voxel([x, y, z], distance, 1.0).unwrap_or_else(|e| panic!("{e:?}"));
                }
            }
        }
    }
    assert!(map.update_esdf().converged);
    map
}

#[cfg(test)]
mod tests;
