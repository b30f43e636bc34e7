//! Queries: voxel state, interpolated signed distance and gradient, surface points and normals.

use super::esdf::site_distance;
use super::{
    local_coords, local_index, split, CellKey, DistanceField, DistanceQuery, Map, Site, VoxelIndex, BLOCK_EDGE,
    BLOCK_VOXELS, NO_SITE,
};
use crate::config::map::BELOW_SURFACE_FILL_VOXELS;
use crate::geom::{floor_i32, normalize3, Real, Vec3};

/// What the map knows about one voxel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum VoxelState {
    /// Never observed (no block, or weight 0).
    Unknown,
    /// Observed, TSDF >= 0.
    Free,
    /// Observed, TSDF < 0 (behind the surface).
    Occupied,
}

/// A surface point for the settler and the planners.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SurfacePoint {
    /// Position on the TSDF zero crossing, metres.
    pub position: Vec3,
    /// Unit normal pointing into free space (TSDF gradient).
    pub normal: Vec3,
}

/// Where [`Map::extract_surface`] resumes. Start with `SurfaceCursor::default()`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SurfaceCursor {
    slot: usize,
    voxel: usize,
    axis: usize,
    done: bool,
}

impl SurfaceCursor {
    /// True once every block has been scanned.
    pub fn is_done(&self) -> bool {
        self.done
    }
}

impl Map<'_> {
    /// Observation state of voxel `g`.
    pub fn voxel_state(&self, g: VoxelIndex) -> VoxelState {
        match self.tsdf_voxel(g) {
            None => VoxelState::Unknown,
            Some((d, _)) if d < 0.0 => VoxelState::Occupied,
            Some(_) => VoxelState::Free,
        }
    }

    /// TSDF (metres) and weight of voxel `g`, `None` if unknown.
    pub fn tsdf_voxel(&self, g: VoxelIndex) -> Option<(Real, Real)> {
        let (s, i) = self.locate(g)?;
        self.tsdf_at(s, i)
    }

    fn tsdf_at(&self, s: usize, i: usize) -> Option<(Real, Real)> {
        let b = self.blocks.get(s)?;
        let w = *b.weight.get(i)?;
        if w == 0 {
            return None;
        }
        Some((self.dequantize_tsdf(*b.tsdf.get(i)?), w as Real / super::WEIGHT_SCALE))
    }

    /// ESDF value of voxel `g` (metres, signed, saturated at `esdf_max_distance`), `None` if unknown.
    pub fn esdf_voxel(&self, g: VoxelIndex) -> Option<Real> {
        let (s, i) = self.locate(g)?;
        self.esdf_at(s, i)
    }

    /// Unsigned distance in voxels of voxel `g` to its ESDF site, `None` if the block is missing or no site is
    /// within range (used by the tests' brute-force oracle; independent of observation state).
    pub fn site_distance_voxels(&self, g: VoxelIndex) -> Option<Real> {
        let (s, i) = self.locate(g)?;
        let b = self.blocks.get(s)?;
        let Site { off: o, w } = *b.esdf.get(i)?;
        if w == NO_SITE {
            return None;
        }
        Some(site_distance(w, [o[0] as i32, o[1] as i32, o[2] as i32], *b.tsdf.get(i)? < 0))
    }

    fn esdf_at(&self, s: usize, i: usize) -> Option<Real> {
        let b = self.blocks.get(s)?;
        if *b.weight.get(i)? == 0 {
            return None;
        }
        let dmax = self.cfg.esdf_max_distance;
        let Site { off: o, w } = *b.esdf.get(i)?;
        let d = if w == NO_SITE {
            dmax
        } else {
            let inside = *b.tsdf.get(i)? < 0;
            (site_distance(w, [o[0] as i32, o[1] as i32, o[2] as i32], inside) * self.cfg.voxel_size).min(dmax)
        };
        Some(if *b.tsdf.get(i)? < 0 { -d } else { d })
    }

    /// The values `f(slot, local index)` of the 8 voxels of the interpolation cell whose lowest corner is `g0` (x
    /// fastest, then y, then z), `None` if one is unknown. Each block of the cell is looked up in the index once
    /// (a cell lies in one block (1 - 1/`BLOCK_EDGE`)^3 of the time, 42 % at the default edge): the map queries are
    /// most of the planners' time.
    fn cell_values(&self, g0: VoxelIndex, f: impl Fn(usize, usize) -> Option<Real>) -> Option<[Real; 8]> {
        let mut v = [0.0 as Real; 8];
        let ((bx, lx), (by, ly), (bz, lz)) = (split(g0[0]), split(g0[1]), split(g0[2]));
        let last = BLOCK_EDGE - 1;
        if lx < last && ly < last && lz < last {
            // the whole cell in one block (27 of 64 cells at the default edge): one index lookup, fixed offsets
            let slot = self.find_block([bx, by, bz])?;
            let base = local_index([lx, ly, lz]);
            for (k, vk) in v.iter_mut().enumerate() {
                *vk = f(slot, base + local_index([k & 1, (k >> 1) & 1, (k >> 2) & 1]))?;
            }
            return Some(v);
        }
        // the cell crosses into the next block along the axes where the lowest corner is on the block's last
        // layer: look up each of the (2, 4 or 8) blocks once, by which axes a corner crosses
        let cross = (lx == last) as usize | ((ly == last) as usize) << 1 | ((lz == last) as usize) << 2;
        let mut slots = [usize::MAX; 8];
        for (k, vk) in v.iter_mut().enumerate() {
            let j = k & cross;
            let slot = match slots.get(j).copied() {
                Some(slot) if slot != usize::MAX => slot,
                _ => {
                    let slot = self.find_block([bx + (j & 1) as i32, by + ((j >> 1) & 1) as i32, bz + (j >> 2) as i32])?;
                    if let Some(e) = slots.get_mut(j) {
                        *e = slot;
                    }
                    slot
                }
            };
            let l = [(lx + (k & 1)) & last, (ly + ((k >> 1) & 1)) & last, (lz + (k >> 2)) & last];
            *vk = f(slot, local_index(l))?;
        }
        Some(v)
    }

    /// Trilinear interpolation at `p` of the per-voxel field `f(slot, local index)`, with the gradient of the
    /// interpolant.
    fn trilinear(&self, p: &Vec3, f: impl Fn(usize, usize) -> Option<Real>) -> Option<(Real, Vec3)> {
        let (g0, t) = self.interpolation_cell(p);
        let v = self.cell_values(g0, f)?;
        Some(self.interpolate(&v, t))
    }

    /// The interpolation cell of `p`: its lowest voxel and `p`'s fractional position in it.
    fn interpolation_cell(&self, p: &Vec3) -> (VoxelIndex, [Real; 3]) {
        let u = p / self.cfg.voxel_size - Vec3::new(0.5, 0.5, 0.5);
        let i0 = [floor_i32(u.x), floor_i32(u.y), floor_i32(u.z)];
        (i0, [u.x - i0[0] as Real, u.y - i0[1] as Real, u.z - i0[2] as Real])
    }

    /// The trilinear interpolant of the cell values `v` (x fastest, then y, then z) at fractions `t`, with its
    /// gradient (metres).
    fn interpolate(&self, v: &[Real; 8], t: [Real; 3]) -> (Real, Vec3) {
        let [fx, fy, fz] = t;
        let [v000, v100, v010, v110, v001, v101, v011, v111] = *v;
        let lerp = |a: Real, b: Real, t: Real| a + (b - a) * t;
        let x00 = lerp(v000, v100, fx);
        let x10 = lerp(v010, v110, fx);
        let x01 = lerp(v001, v101, fx);
        let x11 = lerp(v011, v111, fx);
        let y0 = lerp(x00, x10, fy);
        let y1 = lerp(x01, x11, fy);
        let value = lerp(y0, y1, fz);
        let dx = lerp(lerp(v100 - v000, v110 - v010, fy), lerp(v101 - v001, v111 - v011, fy), fz);
        let dy = lerp(x10 - x00, x11 - x01, fz);
        let dz = y1 - y0;
        (value, Vec3::new(dx, dy, dz) / self.cfg.voxel_size)
    }

    /// The ESDF value of voxel `g`, or, when `g` is unknown, a value filled in from observed neighbours (`None`
    /// when neither rule applies):
    /// 1. **a gap between rays**: its two neighbours along x, or along y, are observed: their mean. Far from the
    ///    sensor and at grazing incidence, neighbouring rays land more than a voxel apart and leave one-voxel
    ///    stripes unobserved between observed ones (the crater floor and the HiRISE slope seen from a mast); the
    ///    field is continuous across one voxel. Wider gaps stay unknown.
    /// 2. **below an observed surface**: the first known voxel above `g` within [`BELOW_SURFACE_FILL_VOXELS`] is
    ///    occupied (TSDF < 0): `g` is inside the terrain, deeper by its height difference,
    ///    `esdf(above) - k * voxel_size`. A range sensor sees a slope at a grazing angle, so the TSDF's band behind
    ///    the surface (the truncation along each ray) is thin and holed, while the settler's wheel rims, footprint
    ///    ring and sphere-traced drops query a few centimetres to decimetres under the surface. Terrain under an
    ///    observed solid surface is solid (no caves within the fill depth): the fill is conservative for collision
    ///    (more inside, never free) and places no surface where none was observed (the zero crossing stays
    ///    between observed voxels, since the first known voxel above is already inside). Unknown space with free or
    ///    no observed space above it stays unknown.
    pub fn esdf_filled(&self, g: VoxelIndex) -> Option<Real> {
        if let Some(d) = self.esdf_voxel(g) {
            return Some(d);
        }
        for axis in 0..2 {
            let (mut lo, mut hi) = (g, g);
            if let (Some(a), Some(b)) = (lo.get_mut(axis), hi.get_mut(axis)) {
                *a = a.saturating_sub(1);
                *b = b.saturating_add(1);
            }
            if let (Some(a), Some(b)) = (self.esdf_voxel(lo), self.esdf_voxel(hi)) {
                return Some(0.5 * (a + b));
            }
        }
        let vs = self.cfg.voxel_size;
        for k in 1..=BELOW_SURFACE_FILL_VOXELS {
            let above = [g[0], g[1], g[2].saturating_add(k)];
            if let Some((tsdf, _)) = self.tsdf_voxel(above) {
                if tsdf >= 0.0 {
                    return None;
                }
                return Some(self.esdf_voxel(above)? - k as Real * vs);
            }
        }
        None
    }

    /// The 8 values of the interpolation cell whose lowest corner is `g0`, unknown voxels filled in where they can
    /// be ([`Self::esdf_filled`]).
    fn filled_cell_values(&self, g0: VoxelIndex) -> Option<[Real; 8]> {
        let mut v = [0.0 as Real; 8];
        for (k, vk) in v.iter_mut().enumerate() {
            let g = [g0[0] + (k & 1) as i32, g0[1] + ((k >> 1) & 1) as i32, g0[2] + ((k >> 2) & 1) as i32];
            *vk = self.esdf_filled(g)?;
        }
        Some(v)
    }

    /// Interpolated TSDF at `p` (metres) with its gradient, `None` if any of the 8 voxels is unknown.
    pub fn tsdf_interpolated(&self, p: &Vec3) -> Option<(Real, Vec3)> {
        self.trilinear(p, |s, i| self.tsdf_at(s, i).map(|(d, _)| d))
    }

    /// Fills `out` with surface points, resuming at `cursor`; returns how many were written. Call again with the
    /// same cursor until [`SurfaceCursor::is_done`]. A surface point is the zero crossing of the TSDF between
    /// a voxel and its +x, +y or +z neighbour, both observed; its normal is the interpolated TSDF gradient there
    /// (falling back to the axis direction, signed towards free space, where a neighbour is unknown).
    pub fn extract_surface(&self, cursor: &mut SurfaceCursor, out: &mut [SurfacePoint]) -> usize {
        let mut n = 0;
        let vs = self.cfg.voxel_size;
        let e = BLOCK_EDGE as i32;
        while cursor.slot < self.used {
            let Some(b) = self.blocks.get(cursor.slot) else { break };
            let bc = b.coord;
            while cursor.voxel < BLOCK_VOXELS {
                let l = local_coords(cursor.voxel);
                let g = [bc[0] * e + l[0] as i32, bc[1] * e + l[1] as i32, bc[2] * e + l[2] as i32];
                if let Some((d0, _)) = self.tsdf_voxel(g) {
                    while cursor.axis < 3 {
                        let a = cursor.axis;
                        let mut g1 = g;
                        if let Some(c) = g1.get_mut(a) {
                            *c += 1;
                        }
                        if let Some((d1, _)) = self.tsdf_voxel(g1) {
                            if (d0 < 0.0) != (d1 < 0.0) {
                                let Some(slot) = out.get_mut(n) else { return n };
                                let t = d0 / (d0 - d1);
                                let mut axis = Vec3::zeros();
                                if let Some(c) = axis.get_mut(a) {
                                    *c = 1.0;
                                }
                                let position = self.voxel_center(g) + axis * (t * vs);
                                let fallback = if d1 > d0 { axis } else { -axis };
                                let normal = self
                                    .tsdf_interpolated(&position)
                                    .and_then(|(_, gr)| normalize3(&gr, 1e-6))
                                    .unwrap_or(fallback);
                                *slot = SurfacePoint { position, normal };
                                n += 1;
                            }
                        }
                        cursor.axis += 1;
                    }
                }
                cursor.axis = 0;
                cursor.voxel += 1;
            }
            cursor.voxel = 0;
            cursor.slot += 1;
        }
        cursor.done = true;
        n
    }
}

impl Map<'_> {
    /// The interpolated ESDF at `p` (filled where it can be), its gradient, and the smallest of the cell's 8 values
    /// (a lower bound on the interpolant anywhere in the cell, before rounding).
    fn esdf_interpolated(&self, p: &Vec3) -> Option<(Real, Vec3, Real)> {
        let (g0, t) = self.interpolation_cell(p);
        let v = self.cell_values(g0, |s, i| self.esdf_at(s, i)).or_else(|| self.filled_cell_values(g0))?;
        let (distance, gradient) = self.interpolate(&v, t);
        Some((distance, gradient, v.iter().fold(Real::INFINITY, |m, x| m.min(*x))))
    }
}

/// What the trilinear interpolant may lose to `f32` rounding below the smallest of its 8 values: 0.1 mm, hundreds
/// of ulps of the ESDF's values (at most `esdf_max_distance`, metres).
const CELL_BOUND_MARGIN_M: Real = 1e-4;

impl DistanceField for Map<'_> {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        self.query_with_cell_bound(p).0
    }

    /// The interpolation cell of `p` while `p`'s fractions in it are within `[0, 1]` (the interpolant is then a
    /// convex combination of the cell's 8 values).
    fn cell_key(&self, p: &Vec3) -> Option<CellKey> {
        if !crate::geom::is_finite3(p) {
            return None;
        }
        let (g0, t) = self.interpolation_cell(p);
        t.iter().all(|f| (0.0..=1.0).contains(f)).then_some(g0)
    }

    fn query_with_cell_bound(&self, p: &Vec3) -> (DistanceQuery, Option<Real>) {
        if !crate::geom::is_finite3(p) {
            return (DistanceQuery::Unknown, None);
        }
        match self.esdf_interpolated(p) {
            Some((distance, gr, min)) => (
                DistanceQuery::Known { distance, gradient: normalize3(&gr, 1e-6).unwrap_or_else(Vec3::zeros) },
                Some(min - CELL_BOUND_MARGIN_M),
            ),
            None => (DistanceQuery::Unknown, None),
        }
    }
}
