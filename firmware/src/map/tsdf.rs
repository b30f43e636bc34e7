//! TSDF integration by ray casting (Voxblox's "simple" integrator with a carving-length budget per ray).
//!
//! Bad input is counted, never integrated: a point that is not finite or outside `min_range..=max_range` of the
//! sensor is rejected; so is a point or sensor origin beyond the map bounds
//! ([`crate::config::map::MAX_VOXEL_COORD`] voxels from the map origin), which would overflow the `i32` voxel
//! index. The ray walk steps voxel indices with checked arithmetic and stops rather than wrap.

use super::esdf::band_site;
use super::{
    cell_bit, local_index, quantize_weight, split, Map, MapError, Site, FLAG_TSDF_DIRTY, NO_SITE, WEIGHT_SCALE,
};
use crate::config::map::{MAX_VOXEL_COORD, MIN_INCIDENCE_COSINE};
use crate::geom::{floor_i32, norm3, round_i32, Pose3, Real, Vec3};

/// What one call of [`Map::integrate_points`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct IntegrationOutcome {
    /// Points whose ray was integrated.
    pub points_integrated: u32,
    /// Points ignored: not finite, closer than `min_range`, beyond `max_range`, or out of the map bounds (every
    /// rejected point, whatever the reason).
    pub points_rejected: u32,
    /// Of `points_rejected`: the point or the sensor origin lies beyond the map bounds
    /// ([`crate::config::map::MAX_VOXEL_COORD`] voxels from the map origin on some axis).
    pub points_out_of_bounds: u32,
    /// Voxel updates applied.
    pub voxels_updated: u32,
    /// Voxel updates lost because their block could not be allocated.
    pub voxels_dropped: u32,
    /// Rays whose carving was shortened by `max_ray_voxels`.
    pub rays_truncated: u32,
    /// The first allocation failure, if any (the pool is full or the index probe ran out).
    pub pool_error: Option<MapError>,
}

impl Map<'_> {
    /// Integrates one sensor frame (or a chunk of one): `points` in the sensor frame, `sensor_pose` the sensor's
    /// pose in the map frame. Work is bounded by `points.len() * max_ray_voxels` voxel updates.
    pub fn integrate_points(&mut self, sensor_pose: &Pose3, points: &[Vec3]) -> IntegrationOutcome {
        let mut out = IntegrationOutcome::default();
        let origin = sensor_pose.translation.vector;
        let inv = 1.0 / self.cfg.voxel_size;
        // NaN is not "beyond" (it fails the comparison) and is rejected below as not finite; infinity is beyond.
        let beyond = |q: &Vec3| q.iter().any(|c| (c * inv).abs() > MAX_VOXEL_COORD);
        let origin_beyond = beyond(&origin);
        let k = VoxelUpdate::new(self);
        for p in points {
            let pw = sensor_pose.transform_point(&(*p).into()).coords;
            if origin_beyond || beyond(&pw) {
                out.points_rejected += 1;
                out.points_out_of_bounds += 1;
                continue;
            }
            let v = pw - origin;
            let depth = norm3(&v);
            if !depth.is_finite() || depth < self.cfg.min_range || depth > self.cfg.max_range {
                out.points_rejected += 1;
                continue;
            }
            let dir = v / depth;
            self.integrate_ray(&k, &origin, &dir, depth, &mut out);
            out.points_integrated += 1;
        }
        out
    }

    fn integrate_ray(&mut self, k: &VoxelUpdate, o: &Vec3, d: &Vec3, depth: Real, out: &mut IntegrationOutcome) {
        let vs = self.cfg.voxel_size;
        let trunc = self.cfg.truncation;
        let t_end = depth + trunc;
        let mut t_start = (depth - self.cfg.max_carve_length).max(0.0);
        // Keep the voxels nearest the surface: shorten the carved part if the budget is too small.
        // A ray crosses at most ~sqrt(3) voxels per voxel length.
        let budget = self.cfg.max_ray_voxels;
        let max_len = budget as Real * vs / 1.75;
        if t_end - t_start > max_len {
            t_start = t_end - max_len;
            out.rays_truncated += 1;
        }
        let p0 = o + d * t_start;
        let inv = 1.0 / vs;
        let mut g = [floor_i32(p0.x * inv), floor_i32(p0.y * inv), floor_i32(p0.z * inv)];
        let axis = |da: Real, pa: Real, ga: i32| -> (i32, Real, Real) {
            if da > 0.0 {
                (1, t_start + ((ga as Real + 1.0) * vs - pa) / da, vs / da)
            } else if da < 0.0 {
                (-1, t_start + ((ga as Real) * vs - pa) / da, -vs / da)
            } else {
                (0, Real::INFINITY, Real::INFINITY)
            }
        };
        let ax = axis(d.x, p0.x, g[0]);
        let ay = axis(d.y, p0.y, g[1]);
        let az = axis(d.z, p0.z, g[2]);
        let step = [ax.0, ay.0, az.0];
        let mut t_max = [ax.1, ay.1, az.1];
        let t_delta = [ax.2, ay.2, az.2];
        let mut cache: Option<([i32; 3], Result<usize, MapError>)> = None;
        let incidence = self.incidence_cosine(&(o + d * depth), d);
        for _ in 0..budget {
            let c = self.voxel_center(g);
            let projective = depth - (c - o).dot(d);
            let sdf = projective * incidence;
            if projective >= -trunc {
                let mut w = 1.0;
                if projective < -vs {
                    w = (trunc + projective) / (trunc - vs);
                }
                if w > 0.0 {
                    let (bx, lx) = split(g[0]);
                    let (by, ly) = split(g[1]);
                    let (bz, lz) = split(g[2]);
                    let bc = [bx, by, bz];
                    let slot = match cache {
                        Some((cc, r)) if cc == bc => r,
                        _ => {
                            let r = self.find_or_alloc_block(bc);
                            cache = Some((bc, r));
                            r
                        }
                    };
                    match slot {
                        Ok(s) => {
                            self.update_voxel(k, s, local_index([lx, ly, lz]), sdf, w);
                            out.voxels_updated += 1;
                        }
                        Err(e) => {
                            out.voxels_dropped += 1;
                            if out.pool_error.is_none() {
                                out.pool_error = Some(e);
                            }
                        }
                    }
                }
            }
            // Next voxel along the ray.
            let a = if t_max[0] < t_max[1] {
                if t_max[0] < t_max[2] { 0 } else { 2 }
            } else if t_max[1] < t_max[2] {
                1
            } else {
                2
            };
            let (Some(tm), Some(ga), Some(st), Some(td)) =
                (t_max.get_mut(a), g.get_mut(a), step.get(a), t_delta.get(a))
            else {
                break;
            };
            if *tm > t_end {
                break;
            }
            // Cannot overflow within the map bounds (MAX_VOXEL_COORD << i32::MAX); stop rather than wrap.
            let Some(next) = ga.checked_add(*st) else { break };
            *ga = next;
            *tm += *td;
        }
    }

    /// The cosine of the angle between the ray and the surface it hits (`|d . n|`, at least
    /// [`MIN_INCIDENCE_COSINE`]), `n` the TSDF's gradient (central differences) at the voxel of the hit `h`; 1 where
    /// the map does not know the surface there yet. The projective distance along a ray is the true distance divided
    /// by this cosine: a ray that grazes a face at 7 degrees tells a voxel 1 cm above the face that it is 8 cm away
    /// (and free space up to the truncation), and averaged with steeper rays that bends the surface: a 55-degree
    /// face seen from above its lip came out as an overhang. Scaling by the cosine gives the distance to the hit's
    /// tangent plane (KinectFusion-style maps do the same with the normal of the depth image).
    fn incidence_cosine(&self, h: &Vec3, d: &Vec3) -> Real {
        let vs = self.cfg.voxel_size;
        let g = [floor_i32(h.x / vs), floor_i32(h.y / vs), floor_i32(h.z / vs)];
        let mut grad = [0.0 as Real; 3];
        for (axis, slot) in grad.iter_mut().enumerate() {
            let mut lo = g;
            let mut hi = g;
            let (Some(l), Some(u)) = (lo.get_mut(axis), hi.get_mut(axis)) else { return 1.0 };
            let (Some(a), Some(b)) = (l.checked_sub(1), u.checked_add(1)) else { return 1.0 };
            *l = a;
            *u = b;
            let (Some((t_lo, _)), Some((t_hi, _))) = (self.tsdf_voxel(lo), self.tsdf_voxel(hi)) else { return 1.0 };
            *slot = t_hi - t_lo;
        }
        let n = Vec3::new(grad[0], grad[1], grad[2]);
        match crate::geom::normalize3(&n, 1e-6) {
            Some(u) => crate::geom::clamp(libm::fabsf(u.dot(d)), MIN_INCIDENCE_COSINE, 1.0),
            None => 1.0,
        }
    }

    fn update_voxel(&mut self, k: &VoxelUpdate, slot: usize, li: usize, sdf: Real, w: Real) {
        let Some(b) = self.blocks.get_mut(slot) else { return };
        let (Some(tq), Some(wq)) = (b.tsdf.get_mut(li), b.weight.get_mut(li)) else { return };
        let w_old = *wq as Real / WEIGHT_SCALE;
        let w_new = w_old + w;
        let wn = quantize_weight(w_new, k.max_weight).max(1);
        // Free space seen free again (most of a ray's carving): the TSDF stays +truncation, only the weight moves,
        // and such a voxel is no site, so its site is not read (a voxel that was a site and left the band marked
        // its block dirty on the way out, and `rebuild_sites` clears that flag only with the site).
        if sdf >= k.truncation && *tq == i16::MAX && *wq > 0 && !k.saturated_is_site {
            *wq = wn;
            return;
        }
        let Some(&Site { off: so, w: sw }) = b.esdf.get(li) else { return };
        let d_old = *tq as Real * k.tsdf_unit;
        let d_new = (d_old * w_old + sdf.min(k.truncation) * w) / w_new;
        let q = round_i32((crate::geom::clamp(d_new, -k.truncation, k.truncation) / k.truncation) * 32767.0) as i16;
        // The ESDF depends on: observed or not, the sign, and the fixed-band site value (with hysteresis).
        let was_observed = *wq > 0;
        let was_inside = *tq < 0;
        *tq = q;
        *wq = wn;
        let is_site = sw != NO_SITE && so == [0, 0, 0];
        let nb = band_site(q as Real * k.tsdf_unit, k.band, k.voxel_size);
        let site_moved = match (is_site, nb != NO_SITE) {
            (true, true) => (nb as i32 - sw as i32).abs() > k.site_tolerance,
            (false, false) => false,
            _ => true,
        };
        if was_inside != (q < 0) {
            // Its distance to every site changes with the sign: the ESDF compares it with its neighbours again.
            b.pending |= cell_bit(li);
        }
        if !was_observed || was_inside != (q < 0) || site_moved {
            b.flags |= FLAG_TSDF_DIRTY;
        }
    }
}

/// The map configuration as one voxel update needs it, worked out once per [`Map::integrate_points`] call.
struct VoxelUpdate {
    truncation: Real,
    /// Metres per TSDF quantum (`truncation / 32767`).
    tsdf_unit: Real,
    max_weight: Real,
    voxel_size: Real,
    /// The fixed band's half-width, metres.
    band: Real,
    /// Site hysteresis, hundredths of a voxel.
    site_tolerance: i32,
    /// Whether a voxel at +truncation lies in the fixed band (a truncation under 1.25 voxels can make it so).
    saturated_is_site: bool,
}

impl VoxelUpdate {
    fn new(map: &Map<'_>) -> VoxelUpdate {
        let c = &map.cfg;
        let tsdf_unit = c.truncation / 32767.0;
        let band = c.esdf_band * c.voxel_size;
        VoxelUpdate {
            truncation: c.truncation,
            tsdf_unit,
            max_weight: c.max_weight,
            voxel_size: c.voxel_size,
            band,
            site_tolerance: map.site_tolerance(),
            saturated_is_site: band_site(i16::MAX as Real * tsdf_unit, band, c.voxel_size) != NO_SITE,
        }
    }
}
