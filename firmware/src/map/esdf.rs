//! ESDF from the TSDF: fixed-band sites, incremental reset of stale sites, vector propagation by raster sweeps.

use super::{
    local_coords, local_index, split, Map, BLOCK_EDGE, BLOCK_VOXELS, FLAG_ESDF_DIRTY, FLAG_ESDF_NEXT, FLAG_REGION,
    FLAG_SITES_CHANGED, FLAG_TSDF_DIRTY, NO_SITE,
};
use crate::geom::Real;

/// What one call of [`Map::update_esdf`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct EsdfOutcome {
    /// Blocks whose TSDF had changed (their sites were rebuilt).
    pub blocks_rebuilt: u32,
    /// Blocks checked for stale sites (within `esdf_max_distance` of a block whose sites moved or vanished).
    pub blocks_in_region: u32,
    /// Sweeps run (each visits every dirty block once forward and once backward).
    pub sweeps: u32,
    /// Block visits over all sweeps.
    pub blocks_processed: u32,
    /// Voxel site changes over all sweeps.
    pub voxels_changed: u32,
    /// True when the propagation reached its fixed point; false when `esdf_max_sweeps` ran out first (the next
    /// call continues where this one stopped).
    pub converged: bool,
}

/// Site value of a voxel with TSDF `d` (metres): signed hundredths of a voxel if inside the fixed band, else
/// [`NO_SITE`].
pub(crate) fn band_site(d: Real, band: Real, vs: Real) -> i8 {
    if libm::fabsf(d) < band {
        (libm::roundf(d / vs * 100.0) as i32).clamp(-127, 127) as i8
    } else {
        NO_SITE
    }
}

/// Distance in voxels from a voxel (inside the terrain if `inside`) to the surface through a site at offset
/// `off` with signed value `w`: `|off| + sign * w` (see the module docs), at least 0.
#[inline]
pub(crate) fn site_distance(w: i8, off: [i32; 3], inside: bool) -> Real {
    let n2 = (off[0] * off[0] + off[1] * off[1] + off[2] * off[2]) as Real;
    let t = w as Real * 0.01;
    (libm::sqrtf(n2) + if inside { -t } else { t }).max(0.0)
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

impl Map<'_> {
    /// Brings the ESDF up to date with the TSDF. Bounded by `esdf_max_sweeps` sweeps over the blocks in use.
    pub fn update_esdf(&mut self) -> EsdfOutcome {
        let mut out = EsdfOutcome::default();
        let used = self.used;
        let vs = self.cfg.voxel_size;
        let band = self.cfg.esdf_band * vs;
        let tq = self.cfg.truncation / 32767.0;
        let dmax = self.cfg.esdf_max_distance / vs;

        // 1. Rebuild the fixed-band sites of blocks whose TSDF changed (values within the hysteresis are kept).
        let tol = self.site_tolerance();
        for b in self.blocks.iter_mut().take(used) {
            if b.flags & FLAG_TSDF_DIRTY == 0 {
                continue;
            }
            out.blocks_rebuilt += 1;
            let mut sites_changed = false;
            for ((t, w), (s, sw)) in
                b.tsdf.iter().zip(b.weight.iter()).zip(b.site.iter_mut().zip(b.site_tsdf.iter_mut()))
            {
                let nb = if *w > 0 { band_site(*t as Real * tq, band, vs) } else { NO_SITE };
                let is_site = *sw != NO_SITE && *s == [0, 0, 0];
                if nb != NO_SITE {
                    if !(is_site && (nb as i32 - *sw as i32).abs() <= tol) {
                        sites_changed |= is_site;
                        *s = [0; 3];
                        *sw = nb;
                    }
                } else if is_site {
                    *sw = NO_SITE;
                    sites_changed = true;
                }
            }
            b.flags |= FLAG_ESDF_DIRTY;
            if sites_changed {
                b.flags |= FLAG_SITES_CHANGED;
            }
            b.flags &= !FLAG_TSDF_DIRTY;
        }

        // 2. The raise region: every block within esdf_max_distance of a block whose sites moved or vanished.
        let k = libm::ceilf(dmax / BLOCK_EDGE as Real) as i32;
        let mut any_changed = false;
        for s in 0..used {
            let Some(b) = self.blocks.get(s) else { break };
            if b.flags & FLAG_SITES_CHANGED == 0 {
                continue;
            }
            any_changed = true;
            let c = b.coord;
            for dz in -k..=k {
                for dy in -k..=k {
                    for dx in -k..=k {
                        if let Some(n) = self.find_block([c[0] + dx, c[1] + dy, c[2] + dz]) {
                            if let Some(nb) = self.blocks.get_mut(n) {
                                nb.flags |= FLAG_REGION;
                            }
                        }
                    }
                }
            }
        }
        // 3. Raise: forget every site that is no longer a fixed-band voxel with the same value.
        if any_changed {
            let e = BLOCK_EDGE as i32;
            for s in 0..used {
                let Some(b) = self.blocks.get(s) else { break };
                if b.flags & FLAG_REGION == 0 {
                    continue;
                }
                out.blocks_in_region += 1;
                let bc = b.coord;
                let mut cache: Option<([i32; 3], Option<usize>)> = None;
                let mut reset = false;
                for i in 0..BLOCK_VOXELS {
                    let Some(b) = self.blocks.get(s) else { break };
                    let (Some(&w), Some(&off)) = (b.site_tsdf.get(i), b.site.get(i)) else { break };
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
                    let valid = slot.and_then(|n| self.blocks.get(n)).is_some_and(|nb| {
                        nb.site_tsdf.get(si) == Some(&w) && nb.site.get(si) == Some(&[0, 0, 0])
                    });
                    if !valid {
                        reset = true;
                        if let Some(sw) = self.blocks.get_mut(s).and_then(|b| b.site_tsdf.get_mut(i)) {
                            *sw = NO_SITE;
                        }
                    }
                }
                if reset {
                    if let Some(b) = self.blocks.get_mut(s) {
                        b.flags |= FLAG_ESDF_DIRTY;
                    }
                }
            }
        }
        for b in self.blocks.iter_mut().take(used) {
            b.flags &= !(FLAG_REGION | FLAG_SITES_CHANGED);
        }

        // 4. Lower: sweep the dirty blocks until nothing changes.
        for sweep in 0..self.cfg.esdf_max_sweeps {
            let mut any = false;
            // Alternate the block order so distances cross block borders in both directions.
            for j in 0..used {
                let s = if sweep % 2 == 0 { j } else { used - 1 - j };
                let Some(b) = self.blocks.get(s) else { break };
                if b.flags & FLAG_ESDF_DIRTY == 0 {
                    continue;
                }
                any = true;
                let c = b.coord;
                let mut nb = [None; 27];
                for (j, slot) in nb.iter_mut().enumerate() {
                    let d = [(j % 3) as i32 - 1, ((j / 3) % 3) as i32 - 1, (j / 9) as i32 - 1];
                    *slot = self.find_block([c[0] + d[0], c[1] + d[1], c[2] + d[2]]);
                }
                let changed = self.sweep_block(s, &nb, dmax);
                out.blocks_processed += 1;
                out.voxels_changed += changed;
                if let Some(b) = self.blocks.get_mut(s) {
                    b.flags &= !FLAG_ESDF_DIRTY;
                }
                if changed > 0 {
                    for n in nb.iter().flatten() {
                        if let Some(b) = self.blocks.get_mut(*n) {
                            b.flags |= FLAG_ESDF_NEXT;
                        }
                    }
                }
            }
            if !any {
                out.converged = true;
                return out;
            }
            out.sweeps += 1;
            for b in self.blocks.iter_mut().take(used) {
                if b.flags & FLAG_ESDF_NEXT != 0 {
                    b.flags = (b.flags & !FLAG_ESDF_NEXT) | FLAG_ESDF_DIRTY;
                }
            }
        }
        out.converged = !self.blocks.iter().take(used).any(|b| b.flags & FLAG_ESDF_DIRTY != 0);
        out
    }

    /// One forward and one backward raster pass over block `s`; returns the number of voxels whose site changed.
    fn sweep_block(&mut self, s: usize, nb: &[Option<usize>; 27], dmax: Real) -> u32 {
        let e = BLOCK_EDGE as i32;
        let mut changed = 0;
        for pass in 0..2 {
            for k in 0..BLOCK_VOXELS {
                let i = if pass == 0 { k } else { BLOCK_VOXELS - 1 - k };
                let l = local_coords(i);
                let Some(b) = self.blocks.get(s) else { return changed };
                let (Some(&w0), Some(&o0), Some(&t0)) = (b.site_tsdf.get(i), b.site.get(i), b.tsdf.get(i)) else {
                    return changed;
                };
                if w0 != NO_SITE && o0 == [0, 0, 0] {
                    continue; // a fixed-band site keeps its own value
                }
                let inside = t0 < 0;
                let mut cand = Candidate::new(w0, o0, inside);
                // Forward pass: the 13 neighbours before the voxel in raster order; backward: the 13 after. A sweep
                // without changes has therefore compared every voxel with all 26 neighbours (the fixed point).
                let (nbrs, deltas) = if pass == 0 {
                    (NEIGHBOURS.get(..13), NEIGHBOUR_DELTAS.get(..13))
                } else {
                    (NEIGHBOURS.get(13..), NEIGHBOUR_DELTAS.get(13..))
                };
                let (Some(nbrs), Some(deltas)) = (nbrs, deltas) else { return changed };
                let interior = l.iter().all(|&c| c >= 1 && c + 1 < BLOCK_EDGE);
                if interior {
                    // Fast path: all 26 neighbours are in this block.
                    for (d, delta) in nbrs.iter().zip(deltas.iter()) {
                        let ni = (i as isize + delta) as usize;
                        if let (Some(&w), Some(&so)) = (b.site_tsdf.get(ni), b.site.get(ni)) {
                            cand.consider(w, so, d, dmax);
                        }
                    }
                } else {
                    for d in nbrs.iter() {
                        let nl = [l[0] as i32 + d[0], l[1] as i32 + d[1], l[2] as i32 + d[2]];
                        let ob = [
                            if nl[0] < 0 { 0 } else if nl[0] >= e { 2 } else { 1 },
                            if nl[1] < 0 { 0 } else if nl[1] >= e { 2 } else { 1 },
                            if nl[2] < 0 { 0 } else if nl[2] >= e { 2 } else { 1 },
                        ];
                        let Some(Some(ns)) = nb.get(ob[0] + 3 * ob[1] + 9 * ob[2]) else { continue };
                        let Some(nblk) = self.blocks.get(*ns) else { continue };
                        let ni = local_index([
                            (nl[0] & (e - 1)) as usize,
                            (nl[1] & (e - 1)) as usize,
                            (nl[2] & (e - 1)) as usize,
                        ]);
                        if let (Some(&w), Some(&so)) = (nblk.site_tsdf.get(ni), nblk.site.get(ni)) {
                            cand.consider(w, so, d, dmax);
                        }
                    }
                }
                if let Some((off, w)) = cand.best {
                    if let Some(b) = self.blocks.get_mut(s) {
                        if let (Some(sw), Some(so)) = (b.site_tsdf.get_mut(i), b.site.get_mut(i)) {
                            *sw = w;
                            *so = off;
                            changed += 1;
                        }
                    }
                }
            }
        }
        changed
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
