//! [`HeightmapWorld`]: any [`Heightmap`] (GeoTIFF, ASCII grid, NumPy DEM) as a ground-truth world.
//!
//! The surface is the triangulated height field: each grid cell is split into two triangles along its
//! (0,0)-(1,1) diagonal; cells with a missing post have no surface (holes). The grid is centred on the world
//! origin (post (0,0) at `(-(w-1)/2, -(h-1)/2) * spacing`), scaled by `horizontal_scale` and `vertical_scale`.
//!
//! ## Signed distance and its error bound
//! The unsigned distance is the exact point-to-triangle distance (f64, Ericson's closest point) minimised over
//! the triangles of the cells in rings around the point's cell; ring `k` is searched only while `(k - 1) *
//! spacing` is below the best distance found (no triangle of a farther ring can be closer), so the result is
//! **exact to f64 rounding whenever the true distance is at most `exact_radius_m`** (default 4 m). Farther away the
//! search stops at `exact_radius_m`: the value returned is then an upper bound in `[true distance, distance to
//! the nearest triangle within the radius]`, and the true distance is known to exceed `exact_radius_m`. The ESDF
//! checks saturate far below that radius. Sign: above/below the triangulated height at the point's (x, y)
//! (clamped into the grid); over a hole, the side of the nearest triangle's plane. Gradient: `(p - q) / d` signed,
//! q the closest point (exact where the closest point is unique).
//!
//! Ray casts march along the ray in steps of a quarter of the post spacing on the sign of `z - h(x, y)` and
//! refine a sign change by 50 bisections: a feature thinner than a quarter post spacing along the ray can be
//! missed (a height field has none thinner than one post except at grazing incidence). The march covers only the
//! part of the ray over the grid and not above its highest post (elsewhere there is no surface to hit), on the
//! same grid of steps as a march from the origin, so the result is the same. A march stops after
//! [`RAYCAST_MAX_STEPS`] steps: [`HeightmapWorld::new`] rejects a grid whose box diagonal is longer, so a ray over
//! posts hits or leaves the box within the budget (below the lowest post every sample over a post is a hit); only a
//! ray that stays over a hole (no data) for the whole budget ends as a miss.
//!
//! Limits checked at load (absurd scales are errors, not hangs or NaN): post spacing at least
//! [`MIN_POST_SPACING_M`] (1 mm), every height finite, extent and height span at most [`MAX_EXTENT_M`] (10 000 km),
//! and the ray-cast budget above.

use super::geometry::{closest_point_on_triangle, P3};
use firmware::geom::p3::{cross, dot, norm, sub};
use super::{Aabb, World};
use crate::terrain::Heightmap;
use crate::truth::solid::{ExactGeometry, Solid};
use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};

/// Smallest post spacing after `horizontal_scale`, metres. Default 1 mm: finer than any DEM (the HiRISE DTMs are
/// 1 m, the Mars Yard 5 cm); a smaller one is a scale mistake.
pub const MIN_POST_SPACING_M: f64 = 1e-3;
/// Largest horizontal extent and height span of a grid, metres. Default 10 000 km (more than Mars' diameter; the
/// LOLA south-polar DEM spans 1218 km); keeps every distance and its square finite.
pub const MAX_EXTENT_M: f64 = 1e7;
/// Budget of one ray cast, in march steps (a quarter post spacing each). Default 2^20: a grid whose box diagonal
/// is longer than this many steps is rejected at load (about 185 000 posts on a side, or a height span of
/// 260 000 post spacings).
pub const RAYCAST_MAX_STEPS: usize = 1 << 20;

/// A height field world.
#[derive(Debug, Clone)]
pub struct HeightmapWorld {
    name: String,
    nx: usize,
    ny: usize,
    spacing: f64,
    x0: f64,
    y0: f64,
    heights: Vec<f64>, // NaN = missing
    z_min: f64,
    z_max: f64,
    /// Distances up to this are exact (see the module docs). Default 4.0 m.
    pub exact_radius_m: f64,
    /// Height range `(lowest, highest)` of the posts of each block of [`BLOCK`] x [`BLOCK`] cells, row by row
    /// (`(inf, -inf)`: no post): the distance search skips a block whose box is farther than the best triangle.
    block_z: Vec<(f64, f64)>,
    /// Blocks along x.
    blocks_x: usize,
}

/// Cells per side of a block of the distance search (see `block_z`). Default 8.
const BLOCK: usize = 8;

/// Why a heightmap cannot become a world.
#[derive(Debug, Clone, PartialEq)]
pub struct HeightmapWorldError(pub String);

impl core::fmt::Display for HeightmapWorldError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.write_str(&self.0)
    }
}

impl core::error::Error for HeightmapWorldError {}

/// Most posts of a rendering ([`HeightmapWorld::render`]). Default 16 M (24 m x 20 m at 0.01 m; 128 MiB of
/// heights on the host).
pub const MAX_RENDER_POSTS: usize = 16 << 20;

impl HeightmapWorld {
    /// `world` sampled as a DEM with posts `spacing_m` apart (a scenario's `[world] dem_spacing_m`): a square grid
    /// centred on the origin, posts on both axes (so the ledge's lip at x = 0 is a row of posts), covering the
    /// world's bounds; each post the world's `height_at`. A DEM's lowest post is z = 0, so the rendering keeps the
    /// world's coordinates when its lowest ground is z = 0 (the ledge and the crater wall); otherwise refused.
    pub fn render(name: &str, world: &dyn World, spacing_m: f64) -> Result<HeightmapWorld, HeightmapWorldError> {
        let bad = |s: String| Err(HeightmapWorldError(s));
        if !(spacing_m.is_finite() && spacing_m >= MIN_POST_SPACING_M) {
            return bad(format!("dem_spacing_m must be finite and at least {MIN_POST_SPACING_M} m, got {spacing_m}"));
        }
        let b = world.bounds();
        let half = |lo: Real, hi: Real| f64::from(lo.abs().max(hi.abs()));
        let (nx, ny) = ((half(b.min.x, b.max.x) / spacing_m).ceil(), (half(b.min.y, b.max.y) / spacing_m).ceil());
        let posts = (2.0 * nx + 1.0) * (2.0 * ny + 1.0);
        if posts.is_nan() || posts > MAX_RENDER_POSTS as f64 {
            return bad(format!(
                "a rendering at {spacing_m} m needs {posts:.3e} posts, above {MAX_RENDER_POSTS}: use a coarser dem_spacing_m"
            ));
        }
        let (nx, ny) = (nx as usize, ny as usize);
        let (w, h) = (2 * nx + 1, 2 * ny + 1);
        let mut heights = Vec::with_capacity(w * h);
        for j in 0..h {
            for i in 0..w {
                let (x, y) = ((i as f64 - nx as f64) * spacing_m, (j as f64 - ny as f64) * spacing_m);
                heights.push(world.height_at(x as Real, y as Real).map(f64::from));
            }
        }
        let lowest = heights.iter().flatten().copied().fold(f64::INFINITY, f64::min);
        if lowest != 0.0 {
            return bad(format!(
                "the world's lowest ground in its bounds is z = {lowest}, not 0: a DEM starts at z = 0, so the rendering \
                 would move the terrain"
            ));
        }
        HeightmapWorld::new(name, &Heightmap { width: w, height: h, spacing_m, heights_m: heights }, 1.0, 1.0)
    }

    /// Builds the world from `hm`, multiplying post spacing by `horizontal_scale` and heights by
    /// `vertical_scale`, and subtracting the minimum height so the lowest post is at z = 0.
    pub fn new(
        name: &str,
        hm: &Heightmap,
        horizontal_scale: f64,
        vertical_scale: f64,
    ) -> Result<HeightmapWorld, HeightmapWorldError> {
        let bad = |s: String| Err(HeightmapWorldError(s));
        if hm.width < 2 || hm.height < 2 || hm.heights_m.len() != hm.width * hm.height {
            return bad(format!("grid {} x {} with {} samples is not a usable DEM", hm.width, hm.height, hm.heights_m.len()));
        }
        for (what, v) in [("horizontal_scale", horizontal_scale), ("vertical_scale", vertical_scale)] {
            if !(v.is_finite() && v > 0.0) {
                return bad(format!("{what} must be finite and > 0, got {v}"));
            }
        }
        let spacing = hm.spacing_m * horizontal_scale;
        if !(spacing.is_finite() && spacing >= MIN_POST_SPACING_M) {
            return bad(format!(
                "post spacing {spacing} m ({} m x horizontal_scale {horizontal_scale}) is below {MIN_POST_SPACING_M} m: \
                 check horizontal_scale / spacing_m",
                hm.spacing_m
            ));
        }
        let extent = spacing * (hm.width.max(hm.height) - 1) as f64;
        if extent > MAX_EXTENT_M {
            return bad(format!("the grid spans {extent:.3e} m, above {MAX_EXTENT_M:.0e} m: check horizontal_scale / spacing_m"));
        }
        let raw: Vec<f64> = hm.heights_m.iter().map(|h| h.map_or(f64::NAN, |h| h * vertical_scale)).collect();
        if let Some(k) = hm.heights_m.iter().zip(&raw).position(|(h, r)| h.is_some() && !r.is_finite()) {
            return bad(format!(
                "post (column {}, row {}) has height {:?} x vertical_scale {vertical_scale:e} = {}: every height must be \
                 finite (mark missing posts as no data)",
                k % hm.width,
                k / hm.width,
                hm.heights_m.get(k).copied().flatten(),
                raw.get(k).copied().unwrap_or(f64::NAN)
            ));
        }
        let lo = raw.iter().copied().filter(|h| h.is_finite()).fold(f64::INFINITY, f64::min);
        let hi = raw.iter().copied().filter(|h| h.is_finite()).fold(f64::NEG_INFINITY, f64::max);
        if !lo.is_finite() {
            return bad("every post is 'no data'".into());
        }
        if hi - lo > MAX_EXTENT_M {
            return bad(format!(
                "heights span {:.3e} m, above {MAX_EXTENT_M:.0e} m: check height_scale / vertical_scale",
                hi - lo
            ));
        }
        let diagonal = (extent * extent * 2.0 + (hi - lo) * (hi - lo)).sqrt();
        let steps = diagonal / (spacing / 4.0);
        if steps > (RAYCAST_MAX_STEPS - 4) as f64 {
            return bad(format!(
                "a ray across this grid ({diagonal:.3e} m diagonal at {spacing:.3e} m post spacing) would take {steps:.3e} \
                 march steps, above the ray-cast budget of {RAYCAST_MAX_STEPS}: check horizontal_scale / vertical_scale"
            ));
        }
        let heights: Vec<f64> = raw.iter().map(|h| h - lo).collect();
        let (blocks_x, blocks_y) = ((hm.width - 1).div_ceil(BLOCK), (hm.height - 1).div_ceil(BLOCK));
        let mut block_z = vec![(f64::INFINITY, f64::NEG_INFINITY); blocks_x * blocks_y];
        // a block's posts: its cells' corners, so the shared row and column on its far sides count in both
        for j in 0..hm.height {
            for i in 0..hm.width {
                let h = heights[j * hm.width + i];
                if !h.is_finite() {
                    continue;
                }
                for bj in [j / BLOCK, j.saturating_sub(1) / BLOCK] {
                    for bi in [i / BLOCK, i.saturating_sub(1) / BLOCK] {
                        if let Some(z) = block_z.get_mut(bj.min(blocks_y - 1) * blocks_x + bi.min(blocks_x - 1)) {
                            *z = (z.0.min(h), z.1.max(h));
                        }
                    }
                }
            }
        }
        Ok(HeightmapWorld {
            name: name.to_string(),
            nx: hm.width,
            ny: hm.height,
            spacing,
            x0: -((hm.width - 1) as f64) * spacing / 2.0,
            y0: -((hm.height - 1) as f64) * spacing / 2.0,
            heights,
            z_min: 0.0,
            z_max: hi - lo,
            exact_radius_m: 4.0,
            block_z,
            blocks_x,
        })
    }

    /// Post spacing in metres (after scaling).
    pub fn spacing(&self) -> f64 {
        self.spacing
    }

    fn post(&self, i: usize, j: usize) -> Option<P3> {
        let h = *self.heights.get(j * self.nx + i)?;
        if i < self.nx && h.is_finite() {
            Some([self.x0 + i as f64 * self.spacing, self.y0 + j as f64 * self.spacing, h])
        } else {
            None
        }
    }

    /// The two triangles of cell (i, j), if all four posts exist.
    fn cell_triangles(&self, i: usize, j: usize) -> Option<[[P3; 3]; 2]> {
        let p00 = self.post(i, j)?;
        let p10 = self.post(i + 1, j)?;
        let p01 = self.post(i, j + 1)?;
        let p11 = self.post(i + 1, j + 1)?;
        Some([[p00, p10, p11], [p00, p11, p01]])
    }

    /// Triangulated height at (x, y), `None` outside the grid or over a hole.
    pub fn height(&self, x: f64, y: f64) -> Option<f64> {
        let u = (x - self.x0) / self.spacing;
        let v = (y - self.y0) / self.spacing;
        if !(u >= 0.0 && v >= 0.0 && u <= (self.nx - 1) as f64 && v <= (self.ny - 1) as f64) {
            return None;
        }
        let i = (u.floor() as usize).min(self.nx - 2);
        let j = (v.floor() as usize).min(self.ny - 2);
        let (fx, fy) = (u - i as f64, v - j as f64);
        let h = |a, b| self.post(a, b).map(|p| p[2]);
        let (h00, h10, h01, h11) = (h(i, j)?, h(i + 1, j)?, h(i, j + 1)?, h(i + 1, j + 1)?);
        Some(if fx >= fy { h00 + fx * (h10 - h00) + fy * (h11 - h10) } else { h00 + fy * (h01 - h00) + fx * (h11 - h01) })
    }

    /// Signed distance and closest surface point (f64). `None` only if the grid has no triangle at all nearby
    /// within `exact_radius_m` rings.
    pub fn sdf_closest(&self, p: P3) -> Option<(f64, P3)> {
        self.sdf_closest_within(p, self.exact_radius_m)
    }

    /// [`Self::sdf_closest`] with the search stopped at `radius` instead of `exact_radius_m`: exact when the true
    /// distance is at most `radius`; otherwise an upper bound of it that exceeds `radius`, or `None` when no
    /// triangle lies within the rings searched.
    pub fn sdf_closest_within(&self, p: P3, radius: f64) -> Option<(f64, P3)> {
        self.closest_within(p, radius).map(|(d, q, _)| (d, q))
    }

    /// Where the distance search starts: `p`'s cell (clamped into the grid), `p`'s horizontal distance from it
    /// (`p` may be outside the grid) and the last ring of cells within `radius`.
    fn search_start(&self, p: P3, radius: f64) -> (i64, i64, f64, i64) {
        let ci = (((p[0] - self.x0) / self.spacing).floor() as i64).clamp(0, self.nx as i64 - 2);
        let cj = (((p[1] - self.y0) / self.spacing).floor() as i64).clamp(0, self.ny as i64 - 2);
        let gx = (self.x0 + ci as f64 * self.spacing - p[0]).max(p[0] - (self.x0 + (ci + 1) as f64 * self.spacing)).max(0.0);
        let gy = (self.y0 + cj as f64 * self.spacing - p[1]).max(p[1] - (self.y0 + (cj + 1) as f64 * self.spacing)).max(0.0);
        let outside = (gx * gx + gy * gy).sqrt();
        (ci, cj, outside, ((radius + outside) / self.spacing).ceil() as i64 + 1)
    }

    /// [`Self::sdf_closest_within`] with the closest triangle's unit normal (pointing up, out of the terrain).
    ///
    /// The triangles of the cells in square rings round `p`'s cell, out to the ring the radius reaches, and the
    /// nearest of them; among equally near ones the first in ring order (ring, then row, then column, then the
    /// cell's first triangle). Blocks of cells, and cells, whose bounding box lies farther than the nearest
    /// triangle so far are skipped, and so are rings of blocks beyond it: the answer is the full scan's.
    fn closest_within(&self, p: P3, radius: f64) -> Option<(f64, P3, P3)> {
        let (ci, cj, outside, max_ring) = self.search_start(p, radius);
        let kmax = max_ring.min(self.nx.max(self.ny) as i64);
        let (ilo, ihi) = ((ci - kmax).max(0), (ci + kmax).min(self.nx as i64 - 2));
        let (jlo, jhi) = ((cj - kmax).max(0), (cj + kmax).min(self.ny as i64 - 2));
        let b = BLOCK as i64;
        let (bci, bcj) = (ci / b, cj / b);
        let block_rings = (bci - ilo / b).max(ihi / b - bci).max(bcj - jlo / b).max(jhi / b - bcj);
        // distance from p to a box, a lower bound of every triangle's in it; skip only when clearly farther, so
        // an equally near triangle is never skipped
        let box_dist = |x: [f64; 2], y: [f64; 2], z: (f64, f64)| {
            let ax = (x[0] - p[0]).max(p[0] - x[1]).max(0.0);
            let ay = (y[0] - p[1]).max(p[1] - y[1]).max(0.0);
            let az = (z.0 - p[2]).max(p[2] - z.1).max(0.0);
            (ax * ax + ay * ay + az * az).sqrt()
        };
        let farther = |lb: f64, d: f64| lb > d * (1.0 + 1e-9) + 1e-12;
        // (distance, ring-order key, closest point, triangle)
        let mut best: Option<(f64, [i64; 4], P3, [P3; 3])> = None;
        for r in 0..=block_rings {
            if let Some((d, ..)) = best {
                // every cell of block ring r is at least (r - 1) B cells from p's cell
                if farther(((r - 1) * b) as f64 * self.spacing - outside, d) {
                    break;
                }
            }
            for bj in (bcj - r).max(jlo / b)..=(bcj + r).min(jhi / b) {
                for bi in (bci - r).max(ilo / b)..=(bci + r).min(ihi / b) {
                    if (bi - bci).abs() != r && (bj - bcj).abs() != r {
                        continue;
                    }
                    let Some(&z) = self.block_z.get(bj as usize * self.blocks_x + bi as usize) else { continue };
                    let (x0, y0) = (self.x0 + (bi * b) as f64 * self.spacing, self.y0 + (bj * b) as f64 * self.spacing);
                    let (x1, y1) = (x0 + b as f64 * self.spacing, y0 + b as f64 * self.spacing);
                    if z.0 > z.1 || best.is_some_and(|(d, ..)| farther(box_dist([x0, x1], [y0, y1], z), d)) {
                        continue;
                    }
                    for j in (bj * b).max(jlo)..=((bj + 1) * b - 1).min(jhi) {
                        for i in (bi * b).max(ilo)..=((bi + 1) * b - 1).min(ihi) {
                            let Some(tris) = self.cell_triangles(i as usize, j as usize) else { continue };
                            if let Some((d, ..)) = best {
                                let [a, c, e] = tris[0];
                                let f = tris[1][2];
                                let zr = (a[2].min(c[2]).min(e[2]).min(f[2]), a[2].max(c[2]).max(e[2]).max(f[2]));
                                if farther(box_dist([a[0], c[0]], [a[1], f[1]], zr), d) {
                                    continue;
                                }
                            }
                            let (di, dj) = (i - ci, j - cj);
                            let k = di.abs().max(dj.abs());
                            for (ti, t) in tris.into_iter().enumerate() {
                                let q = closest_point_on_triangle(p, t[0], t[1], t[2]);
                                let d = norm(sub(p, q));
                                let key = [k, dj, di, ti as i64];
                                if best.is_none_or(|(bd, bk, ..)| d < bd || (d == bd && key < bk)) {
                                    best = Some((d, key, q, t));
                                }
                            }
                        }
                    }
                }
            }
        }
        let (d, _, q, t) = best?;
        let above = match self.height(p[0].clamp(self.x0, -self.x0), p[1].clamp(self.y0, -self.y0)) {
            Some(h) => p[2] >= h,
            None => {
                let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
                dot(sub(p, q), n) >= 0.0
            }
        };
        let n = cross(sub(t[1], t[0]), sub(t[2], t[0]));
        let l = norm(n);
        let up = if l > 0.0 { [n[0] / l, n[1] / l, n[2] / l] } else { [0.0, 0.0, 1.0] };
        let up = if up[2] < 0.0 { [-up[0], -up[1], -up[2]] } else { up };
        Some((if above { d } else { -d }, q, up))
    }
}

impl HeightmapWorld {
    /// The query's answer from the closest point. On the surface itself (`q` = the closest point) the gradient is
    /// the closest triangle's normal, as on the analytic worlds: a zero gradient there made every consumer that
    /// needs a surface normal (the settler's footprint normal) treat the point as unknown space (issue 19).
    fn distance_query(q: P3, closest: Option<(f64, P3, P3)>) -> DistanceQuery {
        let Some((d, c, up)) = closest else { return DistanceQuery::Unknown };
        let v = sub(q, c);
        let n = norm(v);
        let s = if d >= 0.0 { 1.0 } else { -1.0 };
        let gradient = if n > 1e-12 {
            Vec3::new((s * v[0] / n) as Real, (s * v[1] / n) as Real, (s * v[2] / n) as Real)
        } else {
            Vec3::new(up[0] as Real, up[1] as Real, up[2] as Real)
        };
        DistanceQuery::Known { distance: d as Real, gradient }
    }
}

impl DistanceField for HeightmapWorld {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        let q = [p.x as f64, p.y as f64, p.z as f64];
        Self::distance_query(q, self.closest_within(q, self.exact_radius_m))
    }
}

impl World for HeightmapWorld {
    fn name(&self) -> &str {
        &self.name
    }

    fn bounds(&self) -> Aabb {
        Aabb {
            min: Vec3::new(self.x0 as Real, self.y0 as Real, self.z_min as Real),
            max: Vec3::new(-self.x0 as Real, -self.y0 as Real, self.z_max as Real),
        }
    }

    fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
        let o = [origin.x as f64, origin.y as f64, origin.z as f64];
        let d = [dir.x as f64, dir.y as f64, dir.z as f64];
        let f = |t: f64| {
            let p = [o[0] + d[0] * t, o[1] + d[1] * t, o[2] + d[2] * t];
            self.height(p[0], p[1]).map(|h| p[2] - h)
        };
        let step = self.spacing / 4.0;
        let max_t = max_range as f64;
        let n = (max_t / step).ceil() + 1.0;
        // Only the part of the ray over the grid and not above its highest post can hit (see the module docs).
        let (x1, y1) = (-self.x0, -self.y0);
        let mut t_lo: f64 = 0.0;
        let mut t_hi: f64 = max_t;
        for (oa, da, lo, hi) in [(o[0], d[0], self.x0, x1), (o[1], d[1], self.y0, y1), (o[2], d[2], f64::NEG_INFINITY, self.z_max)] {
            if da == 0.0 {
                if !(oa >= lo && oa <= hi) {
                    return None;
                }
            } else {
                let (ta, tb) = ((lo - oa) / da, (hi - oa) / da);
                t_lo = t_lo.max(ta.min(tb));
                t_hi = t_hi.min(ta.max(tb));
            }
        }
        if t_lo.is_nan() || t_hi.is_nan() || t_lo > t_hi {
            return None;
        }
        // The same steps k * step as a march from the origin, from one before the entry to one after the exit.
        let k0 = ((t_lo / step).floor() - 1.0).max(0.0);
        let k1 = ((t_hi / step).ceil() + 1.0).min(n);
        // The budget: within the box a ray hits or leaves it in fewer steps (checked in `new`); below the lowest
        // post every sample over a post is a hit, so only a ray still over a hole can reach it (a miss).
        let k1 = k1.min(k0 + RAYCAST_MAX_STEPS as f64);
        let (k0, k1) = (k0 as usize, k1 as usize);
        let mut prev: Option<(f64, f64)> = None;
        for k in k0..k1 {
            let t = (k as f64 * step).min(max_t);
            match f(t) {
                Some(v) if v < 0.0 => {
                    let Some((mut a, _)) = prev else { return Some(0.0) };
                    let mut b = t;
                    for _ in 0..50 {
                        let m = 0.5 * (a + b);
                        match f(m) {
                            Some(v) if v >= 0.0 => a = m,
                            _ => b = m,
                        }
                    }
                    return Some(b as Real);
                }
                Some(v) => prev = Some((t, v)),
                None => prev = None,
            }
        }
        None
    }

    fn height_at(&self, x: Real, y: Real) -> Option<Real> {
        self.height(x as f64, y as f64).map(|h| h as Real)
    }

    fn exact_geometry(&self) -> ExactGeometry {
        ExactGeometry {
            solids: vec![Solid::HeightGrid {
                nx: self.nx,
                ny: self.ny,
                x0: self.x0,
                y0: self.y0,
                spacing: self.spacing,
                heights: self.heights.clone(),
            }],
        }
    }

    /// The ring search stopped at `limit`: a voxel far from the surface costs a few rings instead of
    /// `(distance / spacing)^2` cells. No triangle within `limit` (a hole): the full search.
    fn query_up_to(&self, p: &Vec3, limit: Real) -> DistanceQuery {
        let q = [p.x as f64, p.y as f64, p.z as f64];
        match self.closest_within(q, f64::from(limit).min(self.exact_radius_m)) {
            Some(found) => Self::distance_query(q, Some(found)),
            None => self.query(p),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The distance search without blocks or pruning: every cell of every ring out to the radius, in ring order
    /// (the search before the blocks, kept here as the oracle).
    fn full_scan(w: &HeightmapWorld, p: P3, radius: f64) -> Option<(f64, P3, [P3; 3])> {
        let (ci, cj, _, max_ring) = w.search_start(p, radius);
        let mut best: Option<(f64, P3, [P3; 3])> = None;
        for k in 0..=max_ring.min(w.nx.max(w.ny) as i64) {
            for dj in -k..=k {
                for di in -k..=k {
                    let (i, j) = (ci + di, cj + dj);
                    if (di.abs() != k && dj.abs() != k) || i < 0 || j < 0 || i > w.nx as i64 - 2 || j > w.ny as i64 - 2 {
                        continue;
                    }
                    for t in w.cell_triangles(i as usize, j as usize).into_iter().flatten() {
                        let q = closest_point_on_triangle(p, t[0], t[1], t[2]);
                        let d = norm(sub(p, q));
                        if best.is_none_or(|(b, _, _)| d < b) {
                            best = Some((d, q, t));
                        }
                    }
                }
            }
        }
        best
    }

    /// The block-pruned search gives the full scan's answer to the bit (distance, closest point and triangle, so
    /// the same normal), on a rough DEM with flat patches (ties), a hole and a cliff, near and far from it, inside
    /// and outside the grid, with the default radius and a short one.
    #[test]
    fn the_pruned_search_is_the_full_scan() {
        let (nx, ny) = (53, 41);
        let mut state: u64 = 0x853c_49e6_748f_ea9b;
        let mut unit = move || {
            state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut heights = Vec::with_capacity(nx * ny);
        for j in 0..ny {
            for i in 0..nx {
                let h = match (i, j) {
                    (10..=14, 8..=12) => None,                       // a hole
                    (20..=30, _) => Some(1.0),                       // a flat band: many equal distances
                    (31.., _) => Some(3.0 + 0.2 * unit()),           // above a cliff
                    _ => Some(0.5 * unit() + 0.02 * (i + j) as f64), // rough
                };
                heights.push(h);
            }
        }
        let w = HeightmapWorld::new("rough", &Heightmap { width: nx, height: ny, spacing_m: 0.1, heights_m: heights }, 1.0, 1.0)
            .expect("dem");
        let mut n = 0;
        for k in 0..3000 {
            let p = [6.0 * (unit() - 0.5), 5.0 * (unit() - 0.5), 5.0 * unit() - 0.5];
            // some exactly above posts and cell edges of the flat band (ties between triangles and cells)
            let p = if k % 5 == 0 { [w.x0 + 0.1 * (20 + k % 11) as f64, w.y0 + 0.1 * (k % 40) as f64, 1.0 + 0.3 * unit()] } else { p };
            for radius in [w.exact_radius_m, 0.35] {
                let got = w.closest_within(p, radius);
                let want = full_scan(&w, p, radius);
                match (got, want) {
                    (Some((d, q, up)), Some((wd, wq, t))) => {
                        let nrm = cross(sub(t[1], t[0]), sub(t[2], t[0]));
                        let l = norm(nrm);
                        let wup = if l > 0.0 { [nrm[0] / l, nrm[1] / l, nrm[2] / l] } else { [0.0, 0.0, 1.0] };
                        let wup = if wup[2] < 0.0 { [-wup[0], -wup[1], -wup[2]] } else { wup };
                        let bits = |d: f64, q: P3, u: P3| (d.to_bits(), q.map(f64::to_bits), u.map(f64::to_bits));
                        assert_eq!(bits(d.abs(), q, up), bits(wd, wq, wup), "{p:?} r {radius}");
                        n += 1;
                    }
                    (None, None) => {}
                    other => panic!("{p:?} r {radius}: {other:?}"),
                }
            }
        }
        assert!(n > 5000, "{n}");
    }

    /// A tilted plane z = 0.3 x + 0.1 y as a DEM: distance is analytic.
    fn plane() -> HeightmapWorld {
        let (w, h, s) = (41, 31, 0.1);
        let mut heights_m = Vec::new();
        for j in 0..h {
            for i in 0..w {
                heights_m.push(Some(0.3 * i as f64 * s + 0.1 * j as f64 * s));
            }
        }
        HeightmapWorld::new("plane", &Heightmap { width: w, height: h, spacing_m: s, heights_m }, 1.0, 1.0).unwrap()
    }

    #[test]
    fn tilted_plane_distance_is_exact() {
        let w = plane();
        let n = [-0.3, -0.1, 1.0];
        let nn = norm(n);
        // z(x, y) in world coordinates: the grid is centred and shifted so its lowest post is at 0.
        let z = |x: f64, y: f64| 0.3 * (x - w.x0) + 0.1 * (y - w.y0);
        for &(x, y, dz) in &[(0.0, 0.0, 0.5), (0.7, -0.4, -0.2), (-1.1, 0.9, 1.3), (0.33, 0.21, 0.01)] {
            let p = [x, y, z(x, y) + dz];
            let (d, _) = w.sdf_closest(p).unwrap();
            assert!((d - dz / nn).abs() < 1e-9, "({x}, {y}, {dz}): {d} vs {}", dz / nn);
        }
    }

    #[test]
    fn raycast_hits_the_surface_and_bad_input_is_rejected() {
        let w = plane();
        let o = Vec3::new(0.2, -0.3, 5.0);
        let dir = Vec3::new(0.3, 0.2, -1.0).normalize();
        let t = w.raycast(&o, &dir, 20.0).unwrap();
        let p = o + dir * t;
        let h = w.height_at(p.x, p.y).unwrap();
        assert!((p.z - h).abs() < 1e-4);
        let hm = Heightmap { width: 2, height: 2, spacing_m: 1.0, heights_m: vec![None; 4] };
        assert!(HeightmapWorld::new("x", &hm, 1.0, 1.0).is_err());
        let hm = Heightmap { width: 2, height: 2, spacing_m: 1.0, heights_m: vec![Some(0.0); 4] };
        assert!(HeightmapWorld::new("x", &hm, f64::NAN, 1.0).is_err());
    }

    /// The march over the grid's box only gives exactly the hits of a march from the origin over the whole range
    /// (the reference below is the old, unclipped march), for rays from outside, above, over holes and missing.
    #[test]
    fn clipped_raycast_equals_the_full_march() {
        let mut w = plane();
        let full = |w: &HeightmapWorld, o: Vec3, d: Vec3, r: f64| {
            let step = w.spacing / 4.0;
            let n = (r / step).ceil() as usize + 1;
            let f = |t: f64| w.height(o.x as f64 + d.x as f64 * t, o.y as f64 + d.y as f64 * t).map(|h| o.z as f64 + d.z as f64 * t - h);
            let mut prev: Option<f64> = None;
            for k in 0..n {
                let t = (k as f64 * step).min(r);
                match f(t) {
                    Some(v) if v < 0.0 => {
                        let Some(mut a) = prev else { return Some(0.0) };
                        let mut b = t;
                        for _ in 0..50 {
                            let m = 0.5 * (a + b);
                            match f(m) {
                                Some(v) if v >= 0.0 => a = m,
                                _ => b = m,
                            }
                        }
                        return Some(b as Real);
                    }
                    Some(_) => prev = Some(t),
                    None => prev = None,
                }
            }
            None
        };
        w.heights[200] = f64::NAN; // a hole
        let mut rng = rand_pcg::Pcg64::new(7, 11);
        let mut u = || (rand_core::Rng::next_u64(&mut rng) >> 11) as f64 / (1u64 << 53) as f64;
        let mut hits = 0;
        for _ in 0..400 {
            let o = Vec3::new((8.0 * u() - 4.0) as Real, (8.0 * u() - 4.0) as Real, (6.0 * u() - 1.0) as Real);
            let d = Vec3::new((2.0 * u() - 1.0) as Real, (2.0 * u() - 1.0) as Real, (2.0 * u() - 1.5) as Real).normalize();
            let r = 12.0 * u();
            let got = w.raycast(&o, &d, r as Real);
            assert_eq!(got, full(&w, o, d, r), "o {o:?} d {d:?} r {r}");
            hits += usize::from(got.is_some());
        }
        assert!(hits > 50, "{hits} hits");
        // A long vertical ray (range 1e6 m: 4e7 steps if it did not hit) hits like the full march.
        let (o, down) = (Vec3::new(0.13, -0.21, (w.z_max + 5.0) as Real), Vec3::new(0.0, 0.0, -1.0));
        let got = w.raycast(&o, &down, 1e6);
        assert!(got.is_some());
        assert_eq!(got, full(&w, o, down, 1e6));
    }

    /// Regression (issue 24): a horizontal scale of 1e-9 made every ray cast take 3e10 steps (map-check never
    /// ended); infinite heights and a height scale that overflows were accepted and gave NaN errors later.
    #[test]
    fn absurd_scales_and_infinite_heights_are_rejected_at_load() {
        let hm = |heights_m: Vec<Option<f64>>| Heightmap { width: 3, height: 2, spacing_m: 1.0, heights_m };
        let ok = hm(vec![Some(0.0), Some(1.0), Some(2.0), Some(0.5), Some(1.5), Some(2.5)]);
        assert!(HeightmapWorld::new("x", &ok, 1.0, 1.0).is_ok());
        let e = HeightmapWorld::new("x", &ok, 1e-9, 1.0).unwrap_err();
        assert!(e.0.contains("below 0.001 m"), "{e}");
        let e = HeightmapWorld::new("x", &ok, 1.0, 1e308).unwrap_err();
        assert!(e.0.contains("must be finite") && e.0.contains("column 2, row 0"), "{e}");
        let e = HeightmapWorld::new("x", &ok, 1.0, 1e12).unwrap_err();
        assert!(e.0.contains("heights span"), "{e}");
        let e = HeightmapWorld::new("x", &ok, 1.0, 3e5).unwrap_err();
        assert!(e.0.contains("ray-cast budget"), "{e}");
        let e = HeightmapWorld::new("x", &ok, 1e7, 1.0).unwrap_err();
        assert!(e.0.contains("spans"), "{e}");
        let inf = hm(vec![Some(0.0), Some(f64::INFINITY), Some(2.0), Some(0.5), Some(1.5), Some(2.5)]);
        assert!(HeightmapWorld::new("x", &inf, 1.0, 1.0).unwrap_err().0.contains("finite"));
    }
}
