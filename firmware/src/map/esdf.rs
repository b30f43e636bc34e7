//! ESDF from the TSDF: fixed-band sites, incremental reset of stale sites, and a queue-based wavefront of
//! nearest-site offsets (vector propagation) that touches only the voxels whose site changed and their neighbours.
//!
//! The wavefront follows Voxblox (Oleynikova et al., "Voxblox: Incremental 3D Euclidean Signed Distance Fields for
//! On-Board MAV Planning", IROS 2017) and FIESTA (Han et al., "FIESTA: Fast Incremental Euclidean Distance Fields
//! for Online Motion Planning of Aerial Robots", IROS 2019): a raise step forgets the sites that vanished or
//! changed, then a lower queue (FIFO) carries every improved site to the 26 neighbours.
//!
//! 1. Sites: the blocks whose TSDF changed get their fixed-band sites rebuilt; a site that appears or changes value
//!    is pushed onto the lower queue.
//! 2. Raise (done directly, as each voxel stores the offset of its site): in every block within
//!    `esdf_max_distance` of a block whose sites moved or vanished, a voxel whose site is no longer a fixed-band
//!    voxel is reset, and so is a fixed-band site that left the band; a reset voxel's unused offset holds the
//!    marker `RESET` until it is pulled. A voxel whose site only changed value keeps it with the new value (its
//!    distance moves by the change, within `esdf_max_distance` or it is reset): farther now, its cell is marked for
//!    a pull (a neighbour's site may be better); nearer, it is queued to offer the site again. That keeps the
//!    fixed point below, and visits each such voxel once instead of resetting and re-deriving it. Voxels that
//!    changed sign (marked by the integration), and in a newly allocated block the voxels next to a block that
//!    existed before this update, are marked by pull cells in the block's `pending` mask (64 bits in the lent
//!    storage; a cell is one voxel at the default edge of 4, 2x2x2 voxels at 8). The other voxels of a new block
//!    hear of every site through the queue.
//! 3. Lower: every reset voxel and every voxel of a marked cell is **pulled** (takes the best site of its 26
//!    neighbours) and queued if it improved; then the queue runs: each pop offers the voxel's site to its 26
//!    neighbours and queues those it improves (strictly better by 1e-5 voxel, within `esdf_max_distance`).
//!    Fixed-band sites keep their own value.
//!
//! The fixed point is the one the raster sweeps this replaced reached: every voxel holds the best site among its
//! own and its 26 neighbours' sites. Which of several such fixed points is reached depends on the order, so
//! individual voxels can differ from the sweeps' (where vector propagation is not exact either way).
//!
//! Neighbours: a voxel inside its block reaches its 26 neighbours by fixed index deltas; a voxel on the block's
//! border through a const table (per local voxel and neighbour: which of the 27 blocks around, and the local
//! index there) and the slots of those 27 blocks, looked up once per block in a 16-way direct-mapped cache.
//!
//! Bounds: the lower queue is a fixed array of [`ESDF_QUEUE_CAPACITY`] entries (default 8192, 32 KiB) on the
//! stack of [`Map::update_esdf`]. A voxel that finds it full, or finds spilled voxels waiting, sets its bit in its
//! block's `queued` mask (one bit per voxel, in the lent storage) and is counted in
//! [`EsdfOutcome::queue_overflows`]; its block joins a first-in first-out list of blocks with spilled voxels,
//! linked through a 24-bit slot in each block (hence a pool of at most
//! [`MAX_POOL_BLOCKS`](crate::config::map::MAX_POOL_BLOCKS) blocks). When the queue runs dry it is refilled from
//! the head of that list, so the wavefront stays breadth-first at the granularity of a block. The raise region of a
//! block whose sites moved is the cube of blocks within `esdf_max_distance`; where its -x, -y or -z neighbour's
//! sites moved too, only the part of the cube that neighbour's cube does not hold is looked up. The budget is
//! `esdf_max_sweeps` (default 32) times [`ESDF_VISITS_PER_BLOCK`] (default 8 at the default edge) voxel visits
//! (pulls and pops) per block in use, at least `esdf_max_sweeps` times the queue capacity. A call that runs out
//! moves the voxels still queued into their bits and returns `converged: false`; the next call continues from the
//! marks and bits (their blocks join the list in slot order). No heap, every loop bounded, slot and raster order
//! only (deterministic).

use super::{
    cell_bit, local_coords, local_index, split, Map, Site, BLOCK_EDGE, BLOCK_VOXELS, FLAG_ESDF_NEW, FLAG_QUEUED,
    FLAG_REGION, FLAG_RESET, FLAG_SITES_CHANGED, FLAG_TSDF_DIRTY, NO_SITE,
};
use crate::config::map::{ESDF_QUEUE_CAPACITY, ESDF_VISITS_PER_BLOCK};
use crate::geom::Real;

/// What one call of [`Map::update_esdf`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EsdfOutcome {
    /// Blocks whose TSDF had changed (their sites were rebuilt).
    pub blocks_rebuilt: u32,
    /// Blocks checked for stale sites (within `esdf_max_distance` of a block whose sites moved or vanished).
    pub blocks_in_region: u32,
    /// Times the empty queue was refilled from the spilled voxels.
    pub refills: u32,
    /// Voxels pulled (compared with their 26 neighbours) from the pending cells.
    pub voxels_pulled: u32,
    /// Voxels popped from the lower queue (each offers its site to its 26 neighbours).
    pub voxels_popped: u32,
    /// Voxel site changes (pulls and pushes).
    pub voxels_changed: u32,
    /// Voxels that found the lower queue full (they wait in their block's spill bits instead).
    pub queue_overflows: u32,
    /// True when the wavefront reached its fixed point; false when the budget (`esdf_max_sweeps` times the blocks
    /// in use times their voxels, in pulls and pops) ran out first (the next call continues where this one stopped).
    pub converged: bool,
}

/// Site value of a voxel with TSDF `d` (metres): signed hundredths of a voxel if inside the fixed band, else
/// [`NO_SITE`].
pub(crate) fn band_site(d: Real, band: Real, vs: Real) -> i8 {
    if libm::fabsf(d) < band {
        crate::geom::round_i32(d / vs * 100.0).clamp(-127, 127) as i8
    } else {
        NO_SITE
    }
}

/// Distance in voxels from a voxel (inside the terrain if `inside`) to the surface through a site at offset
/// `off` with signed value `w`: `|off| + sign * w` (see the module docs), at least 0.
#[inline]
pub(crate) fn site_distance(w: i8, off: [i32; 3], inside: bool) -> Real {
    let n2 = off[0] * off[0] + off[1] * off[1] + off[2] * off[2];
    let t = w as Real * 0.01;
    (integer_sqrt(n2) + if inside { -t } else { t }).max(0.0)
}

/// `sqrt(n)` for a squared voxel offset `n >= 0`, correctly rounded (the bits of `libm::sqrtf(n as f32)`): from
/// [`SQRT_OF_INTEGERS`] below its end, else `libm::sqrtf`. Each query reads 8 site distances, and the flight
/// computer's `libm::sqrtf` is a software routine of about 60 instructions (no `vsqrt` without `unsafe`).
#[inline]
pub(crate) fn integer_sqrt(n: i32) -> Real {
    match SQRT_OF_INTEGERS.get(n as usize) {
        Some(r) => *r,
        None => libm::sqrtf(n as Real),
    }
}

/// `sqrt(n)` for `n` in `0..1024` (offsets up to 32 voxels, beyond the default ESDF reach of 30 voxels at 5 cm),
/// correctly rounded to `f32`, built at compile time (4 KiB of flash). The indexing runs in the compiler (`get_mut`
/// is not `const`): an index out of range fails the build, not the flight.
#[allow(clippy::indexing_slicing)]
static SQRT_OF_INTEGERS: [Real; 1024] = {
    let mut table = [0.0 as Real; 1024];
    let mut n = 1;
    while n < table.len() {
        table[n] = rounded_sqrt(n as u32);
        n += 1;
    }
    table
};

/// `sqrt(n)` rounded to the nearest `f32` for `n < 2^24` (0 for `n = 0`): the 24-bit significand
/// `m = round(sqrt(n 2^(2s)))` with `2^23 <= m < 2^24`, from the integer square root (no ties: `m^2 + m + 1/4` is
/// never an integer).
pub(crate) const fn rounded_sqrt(n: u32) -> Real {
    if n == 0 || n >= 1 << 24 {
        return if n == 0 { 0.0 } else { Real::NAN };
    }
    // s: the shift that puts sqrt(n 2^(2s)) in [2^23, 2^24), i.e. n 2^(2s) in [2^46, 2^48); at most 23 for n >= 1
    let mut s: u32 = 0;
    while s < 23 && ((n as u64) << (2 * s)) < (1u64 << 46) {
        s += 1;
    }
    let big = (n as u64) << (2 * s);
    let mut m = big.isqrt();
    if big - m * m > m {
        m += 1;
    }
    // m may round up to 2^24: the exponent then grows by one (m = 2^24 has a zero significand field)
    let exponent = if m >> 24 != 0 { 24 - s } else { 23 - s };
    let significand = if m >> 24 != 0 { (m >> 1) & 0x7f_ffff } else { m & 0x7f_ffff };
    Real::from_bits(((exponent + 127) << 23) | significand as u32)
}

/// Cells of the coarse bit map of [`Map::mark_raise_region`] (8 KiB on its stack).
const REGION_CELLS: usize = 1 << 16;

/// `f` of the three pairs of coordinates of `a` and `b`.
#[inline]
fn zip3<T>(a: [i32; 3], b: [i32; 3], f: impl Fn(i32, i32) -> T) -> [T; 3] {
    [f(a[0], b[0]), f(a[1], b[1]), f(a[2], b[2])]
}

/// Sets bits `from..=to` of `bits` (bits past its end are ignored).
fn set_bits(bits: &mut [u64], from: usize, to: usize) {
    let mut i = from;
    // One word per pass: bounded by the words between `from` and `to`.
    while i <= to {
        let Some(w) = bits.get_mut(i / 64) else { return };
        let end = to.min(i | 63);
        let n = end - i + 1;
        let mask = if n >= 64 { u64::MAX } else { ((1u64 << n) - 1) << (i % 64) };
        *w |= mask;
        i = end + 1;
    }
}

/// The 26 neighbour offsets.
const NEIGHBOURS: [[i32; 3]; 26] = {
    let mut out = [[0i32; 3]; 26];
    let mut n = 0;
    let mut i: i32 = 0;
    while i < 27 {
        let d = [(i % 3) - 1, ((i / 3) % 3) - 1, (i / 9) - 1];
        if !(d[0] == 0 && d[1] == 0 && d[2] == 0) {
            #[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index fails the build
            {
                out[n] = d;
            }
            n += 1;
        }
        i += 1;
    }
    out
};

/// The lower queue: a FIFO ring of voxels (`slot << 9 | local index`) over a fixed array.
struct Ring<'q> {
    buf: &'q mut [u32],
    head: usize,
    len: usize,
}

/// The site offset of a voxel that lost its site in the current update and is still to be pulled (with
/// a site value of `NO_SITE`, whose offset is otherwise unused).
const RESET: [i8; 3] = [i8::MIN; 3];

/// Bits of a queue entry for the local voxel index.
const LOCAL_BITS: u32 = BLOCK_VOXELS.trailing_zeros();

impl Ring<'_> {
    fn push(&mut self, s: usize, i: usize) -> bool {
        let cap = self.buf.len();
        if self.len >= cap || s >= (1usize << (32 - LOCAL_BITS)) {
            return false;
        }
        let Some(e) = self.buf.get_mut((self.head + self.len) % cap) else { return false };
        *e = ((s as u32) << LOCAL_BITS) | i as u32;
        self.len += 1;
        true
    }

    fn pop(&mut self) -> Option<(usize, usize)> {
        if self.len == 0 {
            return None;
        }
        let e = *self.buf.get(self.head)?;
        self.head = (self.head + 1) % self.buf.len().max(1);
        self.len -= 1;
        Some(((e >> LOCAL_BITS) as usize, (e & ((1 << LOCAL_BITS) - 1)) as usize))
    }
}

/// "No block" in the 24-bit links of the FIFO of blocks with spilled voxels (`Block::qnext`); every slot is below
/// it ([`crate::config::map::MAX_POOL_BLOCKS`]).
const NO_LINK: usize = (1 << 24) - 1;

#[inline]
fn to_link(s: usize) -> [u8; 3] {
    [s as u8, (s >> 8) as u8, (s >> 16) as u8]
}

#[inline]
fn from_link(l: [u8; 3]) -> usize {
    l[0] as usize | (l[1] as usize) << 8 | (l[2] as usize) << 16
}

/// Slots of the 27 blocks around recently visited blocks, looked up on demand: a direct-mapped cache of
/// [`AROUND_WAYS`] blocks (by slot), since the queue interleaves the voxels of neighbouring blocks.
struct Around {
    keys: [u32; AROUND_WAYS],
    slots: [[u32; 27]; AROUND_WAYS],
}

const AROUND_WAYS: usize = 16;
const AROUND_UNKNOWN: u32 = u32::MAX;
const AROUND_MISSING: u32 = u32::MAX - 1;

impl Around {
    fn new() -> Around {
        Around { keys: [u32::MAX; AROUND_WAYS], slots: [[AROUND_UNKNOWN; 27]; AROUND_WAYS] }
    }
}

/// Work counters and the queue of one [`Map::update_esdf`] call.
struct Wave<'q> {
    queue: Ring<'q>,
    around: Around,
    /// Some block has pending cells.
    pending: bool,
    /// First block of the FIFO of blocks with queued bits (voxels that found the queue full), [`NO_LINK`] if none.
    head: usize,
    /// Last block of that FIFO.
    tail: usize,
    /// Voxel visits (pulls and pops) left in this call.
    budget: u64,
    dmax: Real,
    out: EsdfOutcome,
}

impl Map<'_> {
    /// Brings the ESDF up to date with the TSDF (see the module docs). Bounded by the budget of `esdf_max_sweeps`
    /// times [`ESDF_VISITS_PER_BLOCK`] voxel visits per block in use; `converged: false` means the next call
    /// continues.
    pub fn update_esdf(&mut self) -> EsdfOutcome {
        let mut buf = [0u32; ESDF_QUEUE_CAPACITY];
        let mut wave = Wave {
            queue: Ring { buf: &mut buf, head: 0, len: 0 },
            around: Around::new(),
            pending: true,
            head: NO_LINK,
            tail: NO_LINK,
            budget: (self.cfg.esdf_max_sweeps as u64)
                .saturating_mul(((self.used * ESDF_VISITS_PER_BLOCK) as u64).max(ESDF_QUEUE_CAPACITY as u64)),
            dmax: self.cfg.esdf_max_distance / self.cfg.voxel_size,
            out: EsdfOutcome::default(),
        };
        let used = self.used;
        let dmax = wave.dmax;

        // Voxels left queued by a call that ran out of budget: their blocks join the FIFO in slot order.
        for s in 0..used {
            if self.blocks.get(s).is_some_and(|b| b.flags & FLAG_QUEUED != 0) {
                self.append_block(&mut wave, s);
            }
        }
        self.mark_new_block_borders();
        self.rebuild_sites(&mut wave);
        if self.mark_raise_region(dmax) {
            self.raise(&mut wave);
        }
        for b in self.blocks.iter_mut().take(used) {
            b.flags &= !(FLAG_REGION | FLAG_SITES_CHANGED);
        }

        // 4. Lower: pull the pending cells, then run the queue (refilled from the spilled bits when it runs dry)
        // until it is empty or the budget is spent.
        self.pull_pending(&mut wave);
        self.pull_resets(&mut wave);
        loop {
            if wave.queue.len == 0 {
                if wave.pending {
                    self.pull_pending(&mut wave);
                }
                if wave.head != NO_LINK {
                    self.refill(&mut wave);
                }
                if wave.queue.len == 0 {
                    break;
                }
            }
            if wave.budget == 0 {
                break;
            }
            let Some((s, i)) = wave.queue.pop() else { break };
            wave.budget -= 1;
            self.offer_site(&mut wave, s, i);
        }
        // Out of budget: the voxels still queued have not offered their sites yet; they wait in the spill bits.
        while let Some((s, i)) = wave.queue.pop() {
            self.spill(&mut wave, s, i);
        }
        wave.out.converged =
            !self.blocks.iter().take(used).any(|b| b.pending != 0 || b.flags & FLAG_QUEUED != 0);
        wave.out
    }

    /// A new block's voxels learn the sites of the blocks that were there before by a pull of the cells next to
    /// those blocks; the rest hear of every site through the queue (new sites and pulled voxels offer theirs).
    #[inline(never)]
    fn mark_new_block_borders(&mut self) {
        let used = self.used;
        for s in 0..used {
            let Some(b) = self.blocks.get(s) else { break };
            if b.flags & FLAG_ESDF_NEW == 0 {
                continue;
            }
            let c = b.coord;
            let mut pending = 0u64;
            for (j, mask) in BORDER_CELLS.iter().enumerate() {
                if j == 13 {
                    continue;
                }
                let nc = [c[0] + (j % 3) as i32 - 1, c[1] + ((j / 3) % 3) as i32 - 1, c[2] + (j / 9) as i32 - 1];
                let old = self.find_block(nc).and_then(|n| self.blocks.get(n));
                if old.is_some_and(|nb| nb.flags & FLAG_ESDF_NEW == 0) {
                    pending |= mask;
                }
            }
            if let Some(b) = self.blocks.get_mut(s) {
                b.pending |= pending;
            }
        }
    }

    /// Step 1: rebuilds the fixed-band sites of blocks whose TSDF changed (values within the hysteresis are kept).
    /// New sites are queued; voxels that lost their site are marked for a pull.
    #[inline(never)]
    fn rebuild_sites(&mut self, wave: &mut Wave<'_>) {
        let used = self.used;
        let vs = self.cfg.voxel_size;
        let band = self.cfg.esdf_band * vs;
        let tq = self.cfg.truncation / 32767.0;
        let tol = self.site_tolerance();
        for s in 0..used {
            let Some(b) = self.blocks.get_mut(s) else { break };
            if b.flags & FLAG_TSDF_DIRTY == 0 {
                continue;
            }
            wave.out.blocks_rebuilt += 1;
            let mut sites_changed = false;
            let pending = b.pending;
            for i in 0..BLOCK_VOXELS {
                let Some(b) = self.blocks.get_mut(s) else { break };
                let (Some(t), Some(w), Some(Site { off: so, w: sw })) =
                    (b.tsdf.get(i), b.weight.get(i), b.esdf.get_mut(i))
                else {
                    break;
                };
                let nb = if *w > 0 { band_site(*t as Real * tq, band, vs) } else { NO_SITE };
                let is_site = *sw != NO_SITE && *so == [0, 0, 0];
                if nb != NO_SITE {
                    if !(is_site && (nb as i32 - *sw as i32).abs() <= tol) {
                        sites_changed |= is_site;
                        *so = [0; 3];
                        *sw = nb;
                        wave.out.voxels_changed += 1;
                        self.queue_or_spill(wave, s, i);
                    }
                } else if is_site {
                    *sw = NO_SITE;
                    *so = RESET;
                    sites_changed = true;
                }
            }
            if let Some(b) = self.blocks.get_mut(s) {
                b.pending |= pending;
                b.flags &= !(FLAG_TSDF_DIRTY | FLAG_ESDF_NEW);
                if sites_changed {
                    b.flags |= FLAG_SITES_CHANGED | FLAG_RESET;
                }
            }
        }

    }

    /// Step 2: marks the raise region, every block within `esdf_max_distance` (`dmax` voxels, `k` blocks) of a block
    /// whose sites moved or vanished, and some blocks a little farther. False if there is none.
    ///
    /// A coarse bit map over the changed blocks' bounding box grown by `k` (cells of 2x2x2 blocks, coarser if the
    /// box does not fit [`REGION_CELLS`]) gets every cell within `k` blocks of a changed block; every block in use
    /// whose cell is set joins the region. The region so holds the exact one plus at most a cell's width round it,
    /// for the price of one pass over the blocks in use instead of a block lookup per block of every changed
    /// block's cube. (The raise only needs a region that holds every voxel whose site moved: a larger one costs
    /// time, not correctness.)
    #[inline(never)]
    fn mark_raise_region(&mut self, dmax: Real) -> bool {
        let used = self.used;
        let k = libm::ceilf(dmax / BLOCK_EDGE as Real) as i32;
        let (mut lo, mut hi) = ([i32::MAX; 3], [i32::MIN; 3]);
        for b in self.blocks.iter().take(used) {
            if b.flags & FLAG_SITES_CHANGED != 0 {
                lo = zip3(lo, b.coord, i32::min);
                hi = zip3(hi, b.coord, i32::max);
            }
        }
        if lo[0] > hi[0] {
            return false;
        }
        let lo = lo.map(|c| c.saturating_sub(k));
        let hi = hi.map(|c| c.saturating_add(k));
        // The finest cells (at least 2 blocks) whose grid over the box fits the bit map.
        let mut shift = 1;
        let dims = loop {
            let d = zip3(hi, lo, |h, l| ((h as i64 - l as i64) >> shift) + 1);
            if d[0] * d[1] * d[2] <= REGION_CELLS as i64 || shift >= 40 {
                break d;
            }
            shift += 1;
        };
        let mut bits = [0u64; REGION_CELLS / 64];
        for b in self.blocks.iter().take(used) {
            if b.flags & FLAG_SITES_CHANGED == 0 {
                continue;
            }
            let c = b.coord;
            let from = zip3(c, lo, |c, l| (c as i64 - k as i64 - l as i64).max(0) >> shift);
            let to = zip3(c, lo, |c, l| (c as i64 + k as i64 - l as i64) >> shift);
            let to = [to[0].min(dims[0] - 1), to[1].min(dims[1] - 1), to[2].min(dims[2] - 1)];
            for z in from[2]..=to[2] {
                for y in from[1]..=to[1] {
                    let row = (z * dims[1] + y) * dims[0];
                    set_bits(&mut bits, (row + from[0]) as usize, (row + to[0]) as usize);
                }
            }
        }
        for b in self.blocks.iter_mut().take(used) {
            let c = b.coord;
            if zip3(c, lo, |c, l| c < l).contains(&true) || zip3(c, hi, |c, h| c > h).contains(&true) {
                continue;
            }
            let cell = zip3(c, lo, |c, l| (c as i64 - l as i64) >> shift);
            let i = ((cell[2] * dims[1] + cell[1]) * dims[0] + cell[0]) as usize;
            if bits.get(i / 64).is_some_and(|w| w & (1 << (i % 64)) != 0) {
                b.flags |= FLAG_REGION;
            }
        }
        true
    }

    /// Step 3, the raise: forgets every site that is no longer a fixed-band voxel (its voxels are reset and
    /// pulled); a voxel whose site only changed value keeps it with the new value.
    #[inline(never)]
    fn raise(&mut self, wave: &mut Wave<'_>) {
        let used = self.used;
        let dmax = wave.dmax;
        let e = BLOCK_EDGE as i32;
        for s in 0..used {
            let Some(b) = self.blocks.get(s) else { break };
            if b.flags & FLAG_REGION == 0 {
                continue;
            }
            wave.out.blocks_in_region += 1;
            let bc = b.coord;
            let mut cache: Option<([i32; 3], Option<usize>)> = None;
            let mut reset = false;
            for i in 0..BLOCK_VOXELS {
                let Some(b) = self.blocks.get(s) else { break };
                let Some(&Site { off, w }) = b.esdf.get(i) else { break };
                if w == NO_SITE || off == [0, 0, 0] {
                    continue;
                }
                let l = local_coords(i);
                let sg = [
                    bc[0] * e + l[0] as i32 + off[0] as i32,
                    bc[1] * e + l[1] as i32 + off[1] as i32,
                    bc[2] * e + l[2] as i32 + off[2] as i32,
                ];
                let (sbx, slx) = split(sg[0]);
                let (sby, sly) = split(sg[1]);
                let (sbz, slz) = split(sg[2]);
                let sb = [sbx, sby, sbz];
                let slot = match cache {
                    Some((c, sl)) if c == sb => sl,
                    _ => {
                        let sl = self.find_block(sb);
                        cache = Some((sb, sl));
                        sl
                    }
                };
                let si = local_index([slx, sly, slz]);
                // The site's value now, if it is still a fixed-band site.
                let now = slot.and_then(|n| self.blocks.get(n)).and_then(|nb| match nb.esdf.get(si) {
                    Some(&Site { off: [0, 0, 0], w }) if w != NO_SITE => Some(w),
                    _ => None,
                });
                let Some(b) = self.blocks.get_mut(s) else { break };
                let (Some(Site { off: so, w: sw }), Some(&t)) = (b.esdf.get_mut(i), b.tsdf.get(i)) else { break };
                let inside = t < 0;
                let off32 = [off[0] as i32, off[1] as i32, off[2] as i32];
                let within = |now: i8| site_distance(now, off32, inside) <= dmax;
                match now {
                    Some(now) if now == w => {}
                    Some(now) if within(now) => {
                        // The site stays and only its value moved: the voxel keeps it. Farther now, it is pulled
                        // (a neighbour's site may be better); nearer, it offers the site again.
                        *sw = now;
                        wave.out.voxels_changed += 1;
                        let farther = if inside { now < w } else { now > w };
                        if farther {
                            b.pending |= cell_bit(i);
                            wave.pending = true;
                        } else {
                            self.queue_or_spill(wave, s, i);
                        }
                    }
                    _ => {
                        reset = true;
                        *sw = NO_SITE;
                        *so = RESET;
                    }
                }
            }
            if reset {
                if let Some(b) = self.blocks.get_mut(s) {
                    b.flags |= FLAG_RESET;
                }
            }
        }
    }

    /// Queues voxel `(s, i)` (its site improved), or sets its spill bit when the queue is full or spilled
    /// voxels are waiting (they are older: first in, first out, by block).
    #[inline]
    fn queue_or_spill(&mut self, wave: &mut Wave<'_>, s: usize, i: usize) {
        if wave.head != NO_LINK || !wave.queue.push(s, i) {
            wave.out.queue_overflows += 1;
            self.spill(wave, s, i);
        }
    }

    /// Sets the spill bit of voxel `(s, i)`; its block joins the FIFO of blocks with spilled voxels if it is not
    /// in it yet.
    fn spill(&mut self, wave: &mut Wave<'_>, s: usize, i: usize) {
        let Some(b) = self.blocks.get_mut(s) else { return };
        let Some(w) = b.queued.get_mut(i / 64) else { return };
        *w |= 1u64 << (i % 64);
        if b.flags & FLAG_QUEUED == 0 {
            b.flags |= FLAG_QUEUED;
            self.append_block(wave, s);
        }
    }

    /// Appends block `s` to the FIFO of blocks with spilled voxels.
    fn append_block(&mut self, wave: &mut Wave<'_>, s: usize) {
        if let Some(b) = self.blocks.get_mut(s) {
            b.qnext = to_link(NO_LINK);
        }
        if wave.tail == NO_LINK {
            wave.head = s;
        } else if let Some(t) = self.blocks.get_mut(wave.tail) {
            t.qnext = to_link(s);
        }
        wave.tail = s;
    }

    /// Moves spilled voxels into the empty queue until it is full, block by block from the head of the FIFO of
    /// blocks with spilled voxels (a block whose voxels do not all fit stays at its head).
    fn refill(&mut self, wave: &mut Wave<'_>) {
        wave.out.refills += 1;
        // Each block leaves the FIFO once per pass: bounded by the pool.
        for _ in 0..self.blocks.len() {
            let s = wave.head;
            let Some(b) = self.blocks.get_mut(s) else {
                wave.head = NO_LINK;
                wave.tail = NO_LINK;
                return;
            };
            for (k, w) in b.queued.iter_mut().enumerate() {
                while *w != 0 {
                    let i = k * 64 + w.trailing_zeros() as usize;
                    if !wave.queue.push(s, i) {
                        return;
                    }
                    *w &= *w - 1;
                }
            }
            b.flags &= !FLAG_QUEUED;
            let next = from_link(b.qnext);
            wave.head = next;
            if next == NO_LINK {
                wave.tail = NO_LINK;
                return;
            }
        }
    }

    /// The slots of the 27 blocks around block `s` (index `j` = `bx + 3 by + 9 bz`, offsets 0..3 for -1..=1; 13 is
    /// `s`), from the cache; entries are looked up on first use by [`Map::resolve`].
    #[inline]
    fn around_slots(around: &mut Around, s: usize) -> Option<&mut [u32; 27]> {
        let way = s % AROUND_WAYS;
        let (key, slots) = (around.keys.get_mut(way)?, around.slots.get_mut(way)?);
        if *key != s as u32 {
            *key = s as u32;
            *slots = [AROUND_UNKNOWN; 27];
            if let Some(c) = slots.get_mut(13) {
                *c = s as u32;
            }
        }
        Some(slots)
    }

    /// Slot of block `j` of the 27 around block `s` (see [`Map::around_slots`]), if it exists.
    #[inline]
    fn resolve(&self, slots: &mut [u32; 27], s: usize, j: usize) -> Option<usize> {
        let slot = slots.get_mut(j)?;
        if *slot == AROUND_UNKNOWN {
            let c = self.blocks.get(s)?.coord;
            let nc = [c[0] + (j % 3) as i32 - 1, c[1] + ((j / 3) % 3) as i32 - 1, c[2] + (j / 9) as i32 - 1];
            *slot = self.find_block(nc).map_or(AROUND_MISSING, |n| n as u32);
        }
        if *slot == AROUND_MISSING {
            None
        } else {
            Some(*slot as usize)
        }
    }

    /// Pulls every voxel of every pending cell (in slot order) and clears the marks; voxels that improved are
    /// queued.
    fn pull_pending(&mut self, wave: &mut Wave<'_>) {
        wave.pending = false;
        let sh = super::CELL_SHIFT;
        let ce = BLOCK_EDGE >> sh; // cells per edge (4)
        for s in 0..self.used {
            let Some(b) = self.blocks.get_mut(s) else { break };
            let mut p = b.pending;
            if p == 0 {
                continue;
            }
            if wave.budget == 0 {
                wave.pending = true;
                return;
            }
            b.pending = 0;
            while p != 0 {
                let c = p.trailing_zeros() as usize;
                p &= p - 1;
                let c0 = [(c % ce) << sh, ((c / ce) % ce) << sh, (c / (ce * ce)) << sh];
                for v in 0..(1usize << (3 * sh)) {
                    let l = [
                        c0[0] + (v & ((1 << sh) - 1)),
                        c0[1] + ((v >> sh) & ((1 << sh) - 1)),
                        c0[2] + (v >> (2 * sh)),
                    ];
                    let i = local_index(l);
                    wave.out.voxels_pulled += 1;
                    wave.budget = wave.budget.saturating_sub(1);
                    if self.pull(wave, s, i) {
                        wave.out.voxels_changed += 1;
                        self.queue_or_spill(wave, s, i);
                    }
                }
            }
        }
    }

    /// Pulls every voxel that lost its site in this update (offset [`RESET`]), in slot order, and clears the
    /// markers; voxels that found a site are queued. Out of budget, the rest are marked in `pending`.
    fn pull_resets(&mut self, wave: &mut Wave<'_>) {
        for s in 0..self.used {
            let Some(b) = self.blocks.get_mut(s) else { break };
            if b.flags & FLAG_RESET == 0 {
                continue;
            }
            b.flags &= !FLAG_RESET;
            for i in 0..BLOCK_VOXELS {
                let Some(b) = self.blocks.get_mut(s) else { break };
                let Some(Site { off: so, w }) = b.esdf.get_mut(i) else { break };
                let w = *w;
                if w != NO_SITE || *so != RESET {
                    continue;
                }
                *so = [0; 3];
                if wave.budget == 0 {
                    b.pending |= cell_bit(i);
                    wave.pending = true;
                    continue;
                }
                wave.budget -= 1;
                wave.out.voxels_pulled += 1;
                if self.pull(wave, s, i) {
                    wave.out.voxels_changed += 1;
                    self.queue_or_spill(wave, s, i);
                }
            }
        }
    }

    /// Compares voxel `(s, i)` with its 26 neighbours and takes the best site; true if its site changed.
    fn pull(&mut self, wave: &mut Wave<'_>, s: usize, i: usize) -> bool {
        let l = local_coords(i);
        let Some(b) = self.blocks.get(s) else { return false };
        let (Some(&Site { off: o0, w: w0 }), Some(&t0)) = (b.esdf.get(i), b.tsdf.get(i)) else {
            return false;
        };
        if w0 != NO_SITE && o0 == [0, 0, 0] {
            return false; // a fixed-band site keeps its own value
        }
        let mut cand = Candidate::new(w0, o0, t0 < 0);
        let interior = l.iter().all(|&c| c >= 1 && c + 1 < BLOCK_EDGE);
        if interior {
            for (d, delta) in NEIGHBOURS.iter().zip(NEIGHBOUR_DELTAS.iter()) {
                let ni = (i as isize + delta) as usize;
                if let Some(&Site { off: so, w }) = b.esdf.get(ni) {
                    cand.consider(w, so, d, wave.dmax);
                }
            }
        } else {
            let (Some(slots), Some(table)) = (Map::around_slots(&mut wave.around, s), NEIGHBOUR_TABLE.get(i)) else {
                return false;
            };
            for (d, &[j, ni]) in NEIGHBOURS.iter().zip(table.iter()) {
                let Some(ns) = self.resolve(slots, s, j as usize) else { continue };
                let Some(nb) = self.blocks.get(ns) else { continue };
                let ni = ni as usize;
                if let Some(&Site { off: so, w }) = nb.esdf.get(ni) {
                    cand.consider(w, so, d, wave.dmax);
                }
            }
        }
        let Some((off, w)) = cand.best else { return false };
        let Some(b) = self.blocks.get_mut(s) else { return false };
        if let Some(e) = b.esdf.get_mut(i) {
            *e = Site { off, w };
            return true;
        }
        false
    }

    /// Offers the site of voxel `(s, i)` to its 26 neighbours; queues those that improve.
    fn offer_site(&mut self, wave: &mut Wave<'_>, s: usize, i: usize) {
        wave.out.voxels_popped += 1;
        let l = local_coords(i);
        let Some(b) = self.blocks.get(s) else { return };
        let Some(&Site { off: ou, w: wu }) = b.esdf.get(i) else { return };
        if wu == NO_SITE {
            return;
        }
        let interior = l.iter().all(|&c| c >= 1 && c + 1 < BLOCK_EDGE);
        let (Some(slots), Some(table)) = (Map::around_slots(&mut wave.around, s), NEIGHBOUR_TABLE.get(i)) else {
            return;
        };
        // Improved neighbours, queued after the loop (in neighbour order).
        let mut improved = [(0usize, 0usize); 26];
        let mut n_improved = 0;
        for ((d, delta), &[j, ni]) in NEIGHBOURS.iter().zip(NEIGHBOUR_DELTAS.iter()).zip(table.iter()) {
            let (ns, ni) = if interior {
                (s, (i as isize + delta) as usize)
            } else {
                match self.resolve(slots, s, j as usize) {
                    Some(ns) => (ns, ni as usize),
                    None => continue,
                }
            };
            // The site seen from the neighbour: u + ou - v = ou - d.
            let off = [ou[0] as i32 - d[0], ou[1] as i32 - d[1], ou[2] as i32 - d[2]];
            if off.iter().any(|o| o.abs() > 127) {
                continue;
            }
            let off8 = [off[0] as i8, off[1] as i8, off[2] as i8];
            let Some(nb) = self.blocks.get_mut(ns) else { continue };
            let (Some(Site { off: so, w: sw }), Some(&t)) = (nb.esdf.get_mut(ni), nb.tsdf.get(ni)) else { continue };
            if *sw != NO_SITE && (*so == [0, 0, 0] || (*so == off8 && *sw == wu)) {
                continue; // a fixed-band site keeps its own value; or the neighbour has this site already
            }
            let inside = t < 0;
            let dist = site_distance(wu, off, inside);
            if dist > wave.dmax {
                continue;
            }
            let cur = if *sw == NO_SITE {
                Real::INFINITY
            } else {
                site_distance(*sw, [so[0] as i32, so[1] as i32, so[2] as i32], inside)
            };
            if dist < cur - 1e-5 {
                *sw = wu;
                *so = off8;
                if let Some(e) = improved.get_mut(n_improved) {
                    *e = (ns, ni);
                    n_improved += 1;
                }
            }
        }
        for &(ns, ni) in improved.iter().take(n_improved) {
            wave.out.voxels_changed += 1;
            self.queue_or_spill(wave, ns, ni);
        }
    }
}

/// Local-index deltas of [`NEIGHBOURS`] inside a block.
const NEIGHBOUR_DELTAS: [isize; 26] = {
    let mut out = [0isize; 26];
    let mut n = 0;
    while n < 26 {
        #[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index fails the build
        {
            let d = NEIGHBOURS[n];
            out[n] = d[0] as isize + BLOCK_EDGE as isize * (d[1] as isize + BLOCK_EDGE as isize * d[2] as isize);
        }
        n += 1;
    }
    out
};

/// For each local voxel and each of [`NEIGHBOURS`]: which of the 27 blocks around (`bx + 3 by + 9 bz`, 13 = its
/// own) holds the neighbour, and the neighbour's local index there.
const NEIGHBOUR_TABLE: [[[u16; 2]; 26]; BLOCK_VOXELS] = {
    let mut out = [[[0u16; 2]; 26]; BLOCK_VOXELS];
    let e = BLOCK_EDGE as i32;
    let mut i = 0;
    while i < BLOCK_VOXELS {
        let l = [i as i32 % e, (i as i32 / e) % e, i as i32 / (e * e)];
        let mut n = 0;
        while n < 26 {
            #[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index fails the build
            {
                let d = NEIGHBOURS[n];
                let nl = [l[0] + d[0], l[1] + d[1], l[2] + d[2]];
                let mut j = 0;
                let mut ni = 0;
                let mut k = 3;
                while k > 0 {
                    k -= 1;
                    let ob = if nl[k] < 0 { 0 } else if nl[k] >= e { 2 } else { 1 };
                    j = j * 3 + ob;
                    ni = ni * e + (nl[k] & (e - 1));
                }
                out[i][n] = [j as u16, ni as u16];
            }
            n += 1;
        }
        i += 1;
    }
    out
};

/// For each of the 27 blocks around a block (`bx + 3 by + 9 bz`, 13 = itself): the pull cells (bits of
/// `Block::pending`, see `cell_bit`) whose voxels have a neighbour in that block.
const BORDER_CELLS: [u64; 27] = {
    let mut out = [0u64; 27];
    let sh = super::CELL_SHIFT;
    let mut i = 0;
    while i < BLOCK_VOXELS {
        let mut n = 0;
        while n < 26 {
            #[allow(clippy::indexing_slicing)] // const evaluation: an out-of-bounds index fails the build
            {
                let j = NEIGHBOUR_TABLE[i][n][0] as usize;
                let l = [i % BLOCK_EDGE, (i / BLOCK_EDGE) % BLOCK_EDGE, i / (BLOCK_EDGE * BLOCK_EDGE)];
                let c = (l[0] >> sh) + 4 * ((l[1] >> sh) + 4 * (l[2] >> sh));
                out[j] |= 1u64 << (c & 63);
            }
            n += 1;
        }
        i += 1;
    }
    out
};

/// The best site seen so far for one voxel during a sweep.
struct Candidate {
    cur_off: [i8; 3],
    cur_w: i8,
    best_d: Real,
    /// Squared offset length beyond which no candidate can win (|w| <= 1.27 voxels).
    reject_n2: i32,
    inside: bool,
    best: Option<([i8; 3], i8)>,
}

impl Candidate {
    fn new(w0: i8, o0: [i8; 3], inside: bool) -> Candidate {
        let best_d = if w0 == NO_SITE {
            Real::INFINITY
        } else {
            site_distance(w0, [o0[0] as i32, o0[1] as i32, o0[2] as i32], inside)
        };
        let mut c = Candidate { cur_off: o0, cur_w: w0, best_d, reject_n2: i32::MAX, inside, best: None };
        c.update_reject();
        c
    }

    fn update_reject(&mut self) {
        if self.best_d.is_finite() {
            let r = self.best_d + 1.28;
            self.reject_n2 = (r * r) as i32 + 1;
        }
    }

    #[inline]
    fn consider(&mut self, w: i8, so: [i8; 3], d: &[i32; 3], dmax: Real) {
        if w == NO_SITE {
            return;
        }
        let off = [so[0] as i32 + d[0], so[1] as i32 + d[1], so[2] as i32 + d[2]];
        if off.iter().any(|o| o.abs() > 127) {
            return;
        }
        let off8 = [off[0] as i8, off[1] as i8, off[2] as i8];
        if off8 == self.cur_off && w == self.cur_w {
            return; // the same site
        }
        let n2 = off[0] * off[0] + off[1] * off[1] + off[2] * off[2];
        if n2 > self.reject_n2 {
            return;
        }
        let dist = site_distance(w, off, self.inside);
        if dist < self.best_d - 1e-5 && dist <= dmax {
            self.best_d = dist;
            self.cur_off = off8;
            self.cur_w = w;
            self.best = Some((off8, w));
            self.update_reject();
        }
    }
}
