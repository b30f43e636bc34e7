//! Tether-demand planes from a DEM tile (issue 20 items 1 and 3; Abad-Manterola et al. III, Fig. 4: the descent is
//! a tether-free rim, a tether-demand wall and a tether-free floor; Tanner et al. II, Fig. 5).
//!
//! Input: a bounded [`HeightTile`] (origin, post spacing, rows x cols `f32` heights, at most [`MAX_TILE_CELLS`]
//! posts) and the root anchor a0 and goal g in world x/y. [`DemDescent::segment`]:
//!
//! 1. **Corridor.** The descent direction `d = (g - a0) / |g - a0|`; the corridor runs along it from
//!    `2 x footprint` before a0 to `2 x footprint` past g and `corridor_half_width_m` either side. It must lie inside
//!    the tile.
//! 2. **Profile.** Posts are binned by their distance `s` along `d` (bins of one post spacing, at most
//!    [`MAX_PROFILE_BINS`]); each bin's slope is that of its mean height gradient (central differences), classified
//!    with [`classify_slope`] (`mu cot alpha < 1`: tether-demand). Runs of equal class shorter than `min_band_m` are
//!    merged into their longer neighbour; more than three runs keep the first and last tether-free runs (rim, floor)
//!    and make everything between one wall. No tether-demand run: [`DemError::NoTetherDemand`].
//! 3. **Fits.** Each run's posts in the corridor get a least-squares plane `z = a + b x + c y`, fitted twice: the
//!    second fit leaves out posts more than `step_m` off the first (rocks must not tilt the plane); posts within a
//!    post spacing of a run's ends are left out when the run is longer than 4 spacings. When fewer than 3 posts are
//!    that close (a coarse tile), the first fit stands. Neighbouring
//!    planes less than [`MIN_FOLD_DEG`] apart are fitted as one.
//! 4. **Fold lines.** Consecutive planes meet along [`plane_intersection`]; from here on a post belongs to the plane
//!    between the fold lines around it (not to its profile run), so the planes join exactly. Each fold line must
//!    cross both corridor sides inside the corridor, in order ([`DemError::FoldOutsideCorridor`]).
//! 5. **Unfolding.** The reference plane is the steepest plane (the wall); every other plane is rotated about its
//!    fold line(s) into the reference plane (Rodrigues rotation taking its normal to its neighbour's, composed
//!    towards the reference). Unfolding is an isometry of each plane, so a taut tether over the rim is a straight
//!    segment in the unfolded frame and its 3D length is the unfolded length. The 2D frame is the reference plane's
//!    [`TerrainPlane::to_plane_frame`] (`y` up its steepest ascent), the frame the BTM and the holding model use. The
//!    outline is the unfolded corridor: 4 + 2 x (planes - 1) corners.
//! 6. **Obstacles.** A post (within the corridor grown by the footprint) is an obstacle when it protrudes from or
//!    is hollow against its plane by more than `step_m` at the footprint's scale (its residual minus the mean
//!    residual within 2 footprints, at most [`DEM_WINDOW_MAX`] posts: the smooth curvature a plane does not follow
//!    is no obstacle; a rough patch shows up the same way; on a tile whose posts are more than 2 footprints apart
//!    the residual is scaled by `2 footprint / spacing`, the share of it the wheels meet), or when its local
//!    normal is tilted more than `max_tilt_rad` from every plane's (too steep; a post on a fold line carries both
//!    planes' slopes). 4-connected components become octagons (8-DOPs, directions k x 45 deg) around their
//!    unfolded cell corners grown by `footprint_m` (the support of the cells' hull plus the footprint in each
//!    direction, so every obstacle cell and everything within the footprint of it is inside). Overlapping octagons
//!    are merged (support-wise maximum); beyond [`MAX_DEM_OBSTACLES`] the closest pair is merged (bigger obstacles
//!    are conservative). Octagons strictly inside the outline go to the BTM; the others are *edge obstacles* a route
//!    must not touch (checked in [`DemDescent::route_to_world`]).
//!
//! [`DemDescent::check_ends`] refuses a0 or g inside an inflated obstacle. [`DemDescent::hold_model`] gives the holding model on the unfolded descent (the wall's slope, the rim and floor as
//! tether-free half-planes; a second tether-demand plane is held to the steepest one's limit, conservative);
//! [`DemDescent::route_to_world`] maps a plan's shortest homotopic path, descent and intermediate anchors back onto
//! the planes and the DEM (breaking segments at the fold lines) and refuses a tether longer than `max_payout_m`.
//!
//! Parameters ([`DemParams`], defaults from the rover in [`DemParams::for_rover`]): `mu` (the soil's friction, the
//! caller's), `corridor_half_width_m` (the caller's), `step_m` = wheel radius (0.35 m for Axel: a wheel climbs about
//! its radius), `max_tilt_rad` = [`DEFAULT_MAX_TILT_DEG`] (30 deg), `footprint_m` = the radius of the circle around
//! both wheels seen from above, `sqrt((track/2)^2 + r^2)` (0.61 m for Axel), `min_band_m` =
//! [`DEFAULT_MIN_BAND_TRACKS`] x track (2 m). Capacities in `config::homotopy`; scratch ([`DemScratch`], ~112 KiB) and
//! the tile (~64 KiB) are caller-owned.

use super::geo::{grid_neighbours, orient, point_in_polygon, polygon_edges, segments_intersect, Pt, EPS};
use super::planes::{classify_slope, plane_intersection, HoldLimit, HoldModel, PlaneClass, SoilMap, TerrainPlane};
use super::plan::Plan;
use crate::config::homotopy::{
    DEFAULT_MAX_TILT_DEG, DEFAULT_MIN_BAND_TRACKS, DEM_MERGE_BUDGET, DEM_WINDOW_MAX, MAX_DEM_COMPONENTS, MAX_DEM_OBSTACLES,
    MAX_DEM_PLANES, MAX_OBSTACLE_VERTICES, MAX_PATH, MAX_PLANE_VERTICES, MAX_PROFILE_BINS, MAX_TILE_CELLS,
    MAX_TILE_RESOLUTION_M, MAX_TILE_SIDE, MIN_FOLD_DEG, MIN_TILE_RESOLUTION_M,
};
use crate::config::rover::RoverParams;
use heapless::Vec as HVec;

type V3 = [f64; 3];

/// Why a tile was refused; the tile keeps its previous contents.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TileError {
    /// Zero rows or columns.
    Empty,
    /// More than [`MAX_TILE_SIDE`] posts on a side.
    TooLarge {
        /// Rows given.
        rows: usize,
        /// Columns given.
        cols: usize,
    },
    /// Post spacing not finite or outside [`MIN_TILE_RESOLUTION_M`, `MAX_TILE_RESOLUTION_M`].
    Resolution(f64),
    /// The origin is not finite.
    Origin,
    /// `heights.len() != rows x cols`.
    Length {
        /// rows x cols.
        expected: usize,
        /// Heights given.
        got: usize,
    },
    /// A height is NaN or infinite (row-major index).
    NotFinite(usize),
}

/// A bounded height tile: posts at `origin + (col, row) x resolution` (world x/y, m), row-major, row 0 at the
/// smallest y.
#[derive(Clone)]
pub struct HeightTile {
    origin: [f64; 2],
    resolution_m: f64,
    rows: usize,
    cols: usize,
    heights: [f32; MAX_TILE_CELLS],
}

impl Default for HeightTile {
    fn default() -> Self {
        Self::new()
    }
}

impl HeightTile {
    /// An empty tile (0 x 0; spacing 0: no post to look up). All zero bytes, so a `static` holding one stays in
    /// `.bss`.
    pub const fn new() -> Self {
        HeightTile { origin: [0.0; 2], resolution_m: 0.0, rows: 0, cols: 0, heights: [0.0; MAX_TILE_CELLS] }
    }
    /// Replaces the tile after checking every input; on error the previous tile is intact.
    pub fn load(&mut self, origin: [f64; 2], resolution_m: f64, rows: usize, cols: usize, heights: &[f32]) -> Result<(), TileError> {
        if rows == 0 || cols == 0 {
            return Err(TileError::Empty);
        }
        if rows > MAX_TILE_SIDE || cols > MAX_TILE_SIDE {
            return Err(TileError::TooLarge { rows, cols });
        }
        if !(resolution_m.is_finite() && (MIN_TILE_RESOLUTION_M..=MAX_TILE_RESOLUTION_M).contains(&resolution_m)) {
            return Err(TileError::Resolution(resolution_m));
        }
        if !(origin[0].is_finite() && origin[1].is_finite()) {
            return Err(TileError::Origin);
        }
        if heights.len() != rows * cols {
            return Err(TileError::Length { expected: rows * cols, got: heights.len() });
        }
        if let Some(i) = heights.iter().position(|h| !h.is_finite()) {
            return Err(TileError::NotFinite(i));
        }
        for (d, s) in self.heights.iter_mut().zip(heights.iter()) {
            *d = *s;
        }
        (self.origin, self.resolution_m, self.rows, self.cols) = (origin, resolution_m, rows, cols);
        Ok(())
    }
    /// Rows, columns.
    pub fn shape(&self) -> (usize, usize) {
        (self.rows, self.cols)
    }
    /// Post spacing (m).
    pub fn resolution_m(&self) -> f64 {
        self.resolution_m
    }
    /// World x/y of post (row, col).
    pub fn post_xy(&self, row: usize, col: usize) -> [f64; 2] {
        [self.origin[0] + col as f64 * self.resolution_m, self.origin[1] + row as f64 * self.resolution_m]
    }
    /// Height of post (row, col).
    pub fn height(&self, row: usize, col: usize) -> Option<f64> {
        if row >= self.rows || col >= self.cols {
            return None;
        }
        self.heights.get(row * self.cols + col).map(|h| f64::from(*h))
    }
    /// Bilinear height at world (x, y), `None` outside the posts.
    pub fn height_at(&self, x: f64, y: f64) -> Option<f64> {
        let fx = (x - self.origin[0]) / self.resolution_m;
        let fy = (y - self.origin[1]) / self.resolution_m;
        if !(fx >= 0.0 && fy >= 0.0 && fx <= (self.cols - 1) as f64 && fy <= (self.rows - 1) as f64) {
            return None;
        }
        let (c0, r0) = ((fx as usize).min(self.cols.saturating_sub(2)), (fy as usize).min(self.rows.saturating_sub(2)));
        let (tx, ty) = (fx - c0 as f64, fy - r0 as f64);
        let h = |r: usize, c: usize| self.height(r.min(self.rows - 1), c.min(self.cols - 1));
        let (a, b, c, d) = (h(r0, c0)?, h(r0, c0 + 1)?, h(r0 + 1, c0)?, h(r0 + 1, c0 + 1)?);
        Some((a * (1.0 - tx) + b * tx) * (1.0 - ty) + (c * (1.0 - tx) + d * tx) * ty)
    }
    /// Height gradient (dz/dx, dz/dy) at a post by central differences (one-sided at the edges).
    pub fn gradient(&self, row: usize, col: usize) -> Option<(f64, f64)> {
        let d = |lo: Option<f64>, hi: Option<f64>, mid: f64, steps: f64| match (lo, hi) {
            (Some(l), Some(h)) => Some((h - l) / steps),
            (None, Some(h)) => Some(h - mid),
            (Some(l), None) => Some(mid - l),
            (None, None) => None,
        };
        let z = self.height(row, col)?;
        let xl = col.checked_sub(1).and_then(|c| self.height(row, c));
        let yl = row.checked_sub(1).and_then(|r| self.height(r, col));
        let (xh, yh) = (self.height(row, col + 1), self.height(row + 1, col));
        let sx = if xl.is_some() && xh.is_some() { 2.0 } else { 1.0 };
        let sy = if yl.is_some() && yh.is_some() { 2.0 } else { 1.0 };
        Some((d(xl, xh, z, sx)? / self.resolution_m, d(yl, yh, z, sy)? / self.resolution_m))
    }
}

/// Segmentation parameters (defaults in the module docs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DemParams {
    /// Soil friction coefficient (classification and holding).
    pub mu: f64,
    /// Half width of the descent corridor (m).
    pub corridor_half_width_m: f64,
    /// Largest protrusion / hollow against the plane, and largest residual range over 3 x 3 posts (m).
    pub step_m: f64,
    /// Largest tilt of the local normal from the plane's (rad).
    pub max_tilt_rad: f64,
    /// Obstacle inflation: the rover's footprint radius (m).
    pub footprint_m: f64,
    /// Shortest plane band along the descent (m).
    pub min_band_m: f64,
}

impl DemParams {
    /// Defaults for `rover` on soil `mu` with a corridor `half_width_m` either side of the descent line.
    pub fn for_rover(rover: &RoverParams, mu: f64, half_width_m: f64) -> Self {
        let (r, t) = (f64::from(rover.wheel_radius_m), f64::from(rover.track_m));
        DemParams {
            mu,
            corridor_half_width_m: half_width_m,
            step_m: r,
            max_tilt_rad: DEFAULT_MAX_TILT_DEG.to_radians(),
            footprint_m: libm::sqrt(0.25 * t * t + r * r),
            min_band_m: DEFAULT_MIN_BAND_TRACKS * t,
        }
    }
}

/// Why a descent could not be segmented.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum DemError {
    /// The tile is empty.
    EmptyTile,
    /// A parameter or a0 / g is not finite, or a0 = g.
    BadInput,
    /// The corridor leaves the tile.
    CorridorOutsideTile,
    /// No tether-demand stretch along the descent: the homotopy planner is not needed.
    NoTetherDemand,
    /// A plane fit had fewer than 3 posts or was singular.
    FitFailed,
    /// A fold line misses the corridor or crosses another inside it.
    FoldOutsideCorridor,
    /// The unfolded outline is not a simple polygon.
    BadOutline,
    /// a0 lies in an (inflated) obstacle.
    StartBlocked,
    /// g lies in an (inflated) obstacle.
    GoalBlocked,
}

/// Caller-owned scratch for [`DemDescent::segment`] (~112 KiB).
pub struct DemScratch {
    mask: [u8; MAX_TILE_CELLS],
    queue: [u16; MAX_TILE_CELLS],
    resid: [f32; MAX_TILE_CELLS],
}

impl Default for DemScratch {
    fn default() -> Self {
        Self::new()
    }
}

impl DemScratch {
    /// Empty scratch.
    pub const fn new() -> Self {
        DemScratch { mask: [0; MAX_TILE_CELLS], queue: [0; MAX_TILE_CELLS], resid: [0.0; MAX_TILE_CELLS] }
    }
}

/// A rigid motion `x -> R x + t`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rigid {
    r: [[f64; 3]; 3],
    t: V3,
}

fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: V3, b: V3) -> V3 {
    [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]
}
fn sub(a: V3, b: V3) -> V3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
/// Euclidean distance of two 3D points.
pub fn dist3(a: V3, b: V3) -> f64 {
    let d = sub(a, b);
    libm::sqrt(dot(d, d))
}

impl Rigid {
    const ID: Rigid = Rigid { r: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], t: [0.0; 3] };
    fn apply(&self, p: V3) -> V3 {
        let [a, b, c] = self.r;
        [dot(a, p) + self.t[0], dot(b, p) + self.t[1], dot(c, p) + self.t[2]]
    }
    fn rotate(&self, v: V3) -> V3 {
        let [a, b, c] = self.r;
        [dot(a, v), dot(b, v), dot(c, v)]
    }
    fn inverse_apply(&self, p: V3) -> V3 {
        let q = sub(p, self.t);
        let [a, b, c] = self.r;
        [a[0] * q[0] + b[0] * q[1] + c[0] * q[2], a[1] * q[0] + b[1] * q[1] + c[1] * q[2], a[2] * q[0] + b[2] * q[1] + c[2] * q[2]]
    }
    /// `self` after `first`: x -> self(first(x)).
    fn after(&self, first: &Rigid) -> Rigid {
        let mut r = [[0.0; 3]; 3];
        for (i, row) in r.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                let a = self.r.get(i).copied().unwrap_or_default();
                let col = [
                    first.r.first().and_then(|x| x.get(j)).copied().unwrap_or(0.0),
                    first.r.get(1).and_then(|x| x.get(j)).copied().unwrap_or(0.0),
                    first.r.get(2).and_then(|x| x.get(j)).copied().unwrap_or(0.0),
                ];
                *v = dot(a, col);
            }
        }
        Rigid { r, t: self.apply(first.t) }
    }
    /// Rotation by `angle` about the line through `p` along unit `axis` (Rodrigues).
    fn about_line(p: V3, axis: V3, angle: f64) -> Rigid {
        let (s, c) = (libm::sin(angle), libm::cos(angle));
        let [x, y, z] = axis;
        let k = 1.0 - c;
        let r = [
            [c + x * x * k, x * y * k - z * s, x * z * k + y * s],
            [y * x * k + z * s, c + y * y * k, y * z * k - x * s],
            [z * x * k - y * s, z * y * k + x * s, c + z * z * k],
        ];
        let rot = Rigid { r, t: [0.0; 3] };
        let rp = rot.rotate(p);
        Rigid { r, t: sub(p, rp) }
    }
}

/// One fitted plane of the descent.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BandPlane {
    /// The fitted plane (upward unit normal; `traction_mu` = the soil's).
    pub plane: TerrainPlane,
    /// Its class by the fitted slope.
    pub class: PlaneClass,
    /// Along-descent range of its profile run (m from a0).
    pub s_range: (f64, f64),
    /// Posts used by the second fit.
    pub posts: usize,
    /// RMS residual of the second fit (m).
    pub rms_m: f64,
    unfold: Rigid,
}

impl BandPlane {
    /// Height of the plane at world (x, y).
    pub fn height_at(&self, x: f64, y: f64) -> f64 {
        let [nx, ny, nz] = self.plane.normal;
        let o = self.plane.origin;
        o[2] - (nx * (x - o[0]) + ny * (y - o[1])) / nz
    }
}

/// Where two consecutive planes meet, clipped to the corridor.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Fold {
    /// The fold line's point on the corridor's right side (world, m).
    pub right: V3,
    /// Its point on the left side.
    pub left: V3,
    /// Unfolded images of `right` and `left`.
    pub right_2d: Pt,
    /// See `right_2d`.
    pub left_2d: Pt,
    /// Angle between the two planes' normals (rad).
    pub angle_rad: f64,
}

/// An obstacle octagon in the unfolded frame.
pub type Octagon = HVec<Pt, MAX_OBSTACLE_VERTICES>;

/// A descent segmented into unfolded planes with inflated obstacles.
#[derive(Clone, Debug)]
pub struct DemDescent {
    /// Planes in descent order (rim, wall, floor as found).
    pub planes: HVec<BandPlane, MAX_DEM_PLANES>,
    /// Index of the reference (steepest tether-demand) plane.
    pub reference: usize,
    /// Fold lines between consecutive planes.
    pub folds: HVec<Fold, MAX_DEM_PLANES>,
    /// Unfolded outline (the corridor).
    pub outline: HVec<Pt, MAX_PLANE_VERTICES>,
    /// Inflated obstacles strictly inside the outline (go to the BTM).
    pub obstacles: HVec<Octagon, MAX_DEM_OBSTACLES>,
    /// Inflated obstacles crossing the outline (a route must not touch them).
    pub edge_obstacles: HVec<Octagon, MAX_DEM_OBSTACLES>,
    /// a0 unfolded.
    pub a0: Pt,
    /// g unfolded.
    pub g: Pt,
    /// a0 in the world (on its plane).
    pub a0_world: V3,
    /// g in the world (on its plane).
    pub g_world: V3,
    /// Obstacle posts found.
    pub blocked_posts: usize,
    /// Obstacle components found (before merging).
    pub components: usize,
    /// Merges done (overlaps, full lists, reduction to the BTM's capacity).
    pub merges: usize,
    /// Soil friction.
    pub mu: f64,
    dir: [f64; 2],
    left: [f64; 2],
    a0_xy: [f64; 2],
}

/// 8-DOP directions (k x 45 deg).
fn dop_dir(k: usize) -> Pt {
    let a = k as f64 * core::f64::consts::FRAC_PI_4;
    Pt { x: libm::cos(a), y: libm::sin(a) }
}

fn dop_overlap(a: &[f64; 8], b: &[f64; 8], gap: f64) -> bool {
    (0..4).all(|k| {
        let (ak, ak4, bk, bk4) = (a.get(k), a.get(k + 4), b.get(k), b.get(k + 4));
        match (ak, ak4, bk, bk4) {
            (Some(ak), Some(ak4), Some(bk), Some(bk4)) => ak + bk4 > -gap && bk + ak4 > -gap,
            _ => true,
        }
    })
}

/// The 8-DOP support of `pts` (their extent along each of the eight directions).
pub(crate) fn dop_support(pts: &[Pt]) -> [f64; 8] {
    let mut h = [f64::MIN; 8];
    for p in pts {
        for (j, hj) in h.iter_mut().enumerate() {
            *hj = hj.max(p.dot(dop_dir(j)));
        }
    }
    h
}

pub(crate) fn dop_merge(a: &mut [f64; 8], b: &[f64; 8]) {
    for (x, y) in a.iter_mut().zip(b.iter()) {
        *x = x.max(*y);
    }
}

/// Separation of two 8-DOPs along their best axis (negative when they overlap).
fn dop_gap(a: &[f64; 8], b: &[f64; 8]) -> f64 {
    (0..4)
        .map(|k| {
            let g = |i: usize, s: &[f64; 8]| s.get(i).copied().unwrap_or(0.0);
            (-(g(k, a) + g(k + 4, b))).max(-(g(k, b) + g(k + 4, a)))
        })
        .fold(f64::MIN, f64::max)
}

/// The octagon of an 8-DOP support (coincident corners dropped).
pub(crate) fn dop_polygon(h: &[f64; 8]) -> Octagon {
    let mut out = Octagon::new();
    for k in 0..8 {
        let (u, v) = (dop_dir(k), dop_dir((k + 1) % 8));
        let (hu, hv) = (h.get(k).copied().unwrap_or(0.0), h.get((k + 1) % 8).copied().unwrap_or(0.0));
        let det = u.x * v.y - u.y * v.x;
        let p = Pt { x: (hu * v.y - hv * u.y) / det, y: (u.x * hv - v.x * hu) / det };
        if out.last().is_none_or(|q: &Pt| q.dist(p) > 1e-6) && out.first().is_none_or(|q: &Pt| q.dist(p) > 1e-6) {
            let _ = out.push(p);
        }
    }
    out
}

/// Least-squares plane `z = a + b x + c y` (x, y relative to `o`) over posts accepted by `keep`.
fn fit_plane(
    tile: &HeightTile,
    o: [f64; 2],
    mut keep: impl FnMut(usize, usize, [f64; 2], f64) -> bool,
) -> Option<([f64; 3], usize, f64)> {
    let (rows, cols) = tile.shape();
    let mut m = [[0.0f64; 4]; 3];
    let mut n = 0usize;
    for r in 0..rows {
        for c in 0..cols {
            let Some(z) = tile.height(r, c) else { continue };
            let xy = tile.post_xy(r, c);
            if !keep(r, c, xy, z) {
                continue;
            }
            let v = [1.0, xy[0] - o[0], xy[1] - o[1]];
            for (i, row) in m.iter_mut().enumerate() {
                let vi = v.get(i).copied().unwrap_or(0.0);
                for (j, e) in row.iter_mut().take(3).enumerate() {
                    *e += vi * v.get(j).copied().unwrap_or(0.0);
                }
                if let Some(e) = row.get_mut(3) {
                    *e += vi * z;
                }
            }
            n += 1;
        }
    }
    if n < 3 {
        return None;
    }
    // Gaussian elimination with partial pivoting on the 3 x 4 system.
    for col in 0..3 {
        let piv = (col..3).max_by(|&a, &b| {
            let f = |i: usize| m.get(i).and_then(|r| r.get(col)).map_or(0.0, |v: &f64| v.abs());
            f(a).total_cmp(&f(b))
        })?;
        // `swap` without its bounds panic (the flight build links `panic-never`): both rows exist
        let (Some(&rc), Some(&rp)) = (m.get(col), m.get(piv)) else { return None };
        if let Some(r) = m.get_mut(col) {
            *r = rp;
        }
        if let Some(r) = m.get_mut(piv) {
            *r = rc;
        }
        let p = *m.get(col)?;
        let d = p.get(col).copied()?;
        if d.abs() < 1e-12 * (1.0 + n as f64) {
            return None;
        }
        for (i, row) in m.iter_mut().enumerate() {
            if i == col {
                continue;
            }
            let f = row.get(col).copied().unwrap_or(0.0) / d;
            for (e, pe) in row.iter_mut().zip(p.iter()) {
                *e -= f * pe;
            }
        }
    }
    let sol = |i: usize| m.get(i).and_then(|r| Some(r.get(3)? / r.get(i)?));
    let coef = [sol(0)?, sol(1)?, sol(2)?];
    let mut ss = 0.0;
    for r in 0..rows {
        for c in 0..cols {
            let Some(z) = tile.height(r, c) else { continue };
            let xy = tile.post_xy(r, c);
            if keep(r, c, xy, z) {
                let e = z - (coef[0] + coef[1] * (xy[0] - o[0]) + coef[2] * (xy[1] - o[1]));
                ss += e * e;
            }
        }
    }
    Some((coef, n, libm::sqrt(ss / n as f64)))
}

/// The plane `z = c0 + c1 (x - o.x) + c2 (y - o.y)` with an upward unit normal.
fn plane_of(c: &[f64; 3], o: [f64; 2], mu: f64) -> TerrainPlane {
    let nn = libm::sqrt(c[1] * c[1] + c[2] * c[2] + 1.0);
    TerrainPlane { origin: [o[0], o[1], c[0]], normal: [-c[1] / nn, -c[2] / nn, 1.0 / nn], traction_mu: mu }
}

/// One run of the along-descent profile.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Run {
    class: PlaneClass,
    from: f64,
    to: f64,
}

fn merge_short_runs(runs: &mut HVec<Run, MAX_PROFILE_BINS>, min_len: f64) {
    for _ in 0..MAX_PROFILE_BINS {
        // Coalesce equal neighbours.
        let mut i = 1;
        while i < runs.len() {
            match (runs.get(i - 1).copied(), runs.get(i).copied()) {
                (Some(a), Some(b)) if a.class == b.class => {
                    if let Some(x) = runs.get_mut(i - 1) {
                        x.to = b.to;
                    }
                    let _ = super::geo::remove_at(runs, i);
                }
                _ => i += 1,
            }
        }
        if runs.len() < 2 {
            return;
        }
        let Some((i, _)) = runs
            .iter()
            .enumerate()
            .filter(|(_, r)| r.to - r.from < min_len)
            .min_by(|a, b| (a.1.to - a.1.from).total_cmp(&(b.1.to - b.1.from)))
        else {
            return;
        };
        // Into the longer neighbour.
        let len = |j: Option<&Run>| j.map_or(-1.0, |r| r.to - r.from);
        let prev = i.checked_sub(1).and_then(|j| runs.get(j));
        let into_prev = len(prev) >= len(runs.get(i + 1));
        let Some(cur) = runs.get(i).copied() else { return };
        if into_prev {
            if let Some(p) = i.checked_sub(1).and_then(|j| runs.get_mut(j)) {
                p.to = cur.to;
            }
        } else if let Some(n) = runs.get_mut(i + 1) {
            n.from = cur.from;
        }
        let _ = super::geo::remove_at(runs, i);
    }
}

impl DemDescent {
    /// Fold lines between consecutive planes, clipped to the corridor sides (step 4 of the module docs).
    fn compute_folds(&mut self, s_lo: f64, s_hi: f64, hw: f64) -> Result<(), DemError> {
        self.folds.clear();
    let mut prev_s = [s_lo, s_lo];
    for k in 0..self.planes.len().saturating_sub(1) {
        let (Some(a), Some(b)) = (self.planes.get(k), self.planes.get(k + 1)) else { break };
        let (p, l) = plane_intersection(&a.plane, &b.plane).ok_or(DemError::FoldOutsideCorridor)?;
        let angle = libm::acos(dot(a.plane.normal, b.plane.normal).clamp(-1.0, 1.0));
        // Where the line's ground track meets t = -hw and t = +hw.
        let lt = l[0] * self.left[0] + l[1] * self.left[1];
        if lt.abs() < 1e-6 {
            return Err(DemError::FoldOutsideCorridor);
        }
        let mut ends = [[0.0; 3]; 2];
        for (e, t) in ends.iter_mut().zip([-hw, hw]) {
            let lam = (t - self.t_of([p[0], p[1]])) / lt;
            *e = [p[0] + lam * l[0], p[1] + lam * l[1], p[2] + lam * l[2]];
        }
        let [er, el] = ends;
        let ss = [self.s_of([er[0], er[1]]), self.s_of([el[0], el[1]])];
        if ss.iter().zip(prev_s.iter()).any(|(s, ps)| !(*s > *ps && *s < s_hi)) {
            return Err(DemError::FoldOutsideCorridor);
        }
        prev_s = ss;
        let _ = self.folds.push(Fold { right: er, left: el, right_2d: Pt::default(), left_2d: Pt::default(), angle_rad: angle });
    }
        Ok(())
    }

    fn s_of(&self, xy: [f64; 2]) -> f64 {
        (xy[0] - self.a0_xy[0]) * self.dir[0] + (xy[1] - self.a0_xy[1]) * self.dir[1]
    }
    fn t_of(&self, xy: [f64; 2]) -> f64 {
        (xy[0] - self.a0_xy[0]) * self.left[0] + (xy[1] - self.a0_xy[1]) * self.left[1]
    }
    fn xy_of(&self, s: f64, t: f64) -> [f64; 2] {
        [self.a0_xy[0] + s * self.dir[0] + t * self.left[0], self.a0_xy[1] + s * self.dir[1] + t * self.left[1]]
    }
    /// Plane index of world (x, y): the number of fold lines it lies beyond.
    pub fn region_of(&self, xy: [f64; 2]) -> usize {
        let q = Pt { x: xy[0], y: xy[1] };
        self.folds
            .iter()
            .filter(|f| {
                let (a, b) = (Pt { x: f.right[0], y: f.right[1] }, Pt { x: f.left[0], y: f.left[1] });
                // The far side (growing s) is to the left of right -> left when d x left > 0: it is, by construction.
                orient(a, b, q) * self.fold_sign(a, b) > 0.0
            })
            .count()
    }
    fn fold_sign(&self, a: Pt, b: Pt) -> f64 {
        let far = self.xy_of(1e6, 0.0);
        if orient(a, b, Pt { x: far[0], y: far[1] }) > 0.0 {
            1.0
        } else {
            -1.0
        }
    }
    /// World point on plane `k` at (x, y).
    fn lift(&self, k: usize, xy: [f64; 2]) -> Option<V3> {
        let p = self.planes.get(k)?;
        Some([xy[0], xy[1], p.height_at(xy[0], xy[1])])
    }
    fn ref_plane(&self) -> Option<&TerrainPlane> {
        self.planes.get(self.reference).map(|p| &p.plane)
    }
    /// Unfolded 2D point of a world point on plane `k`.
    fn unfold_on(&self, k: usize, p: V3) -> Option<Pt> {
        let q = self.planes.get(k)?.unfold.apply(p);
        Some(self.ref_plane()?.to_plane_frame(q))
    }
    /// Unfolded 2D point of world (x, y) (lifted onto its plane).
    pub fn unfold_xy(&self, xy: [f64; 2]) -> Option<Pt> {
        let k = self.region_of(xy);
        self.unfold_on(k, self.lift(k, xy)?)
    }
    /// The 3D point on the reference plane with 2D coordinates `p`.
    fn ref_point(&self, p: Pt) -> Option<V3> {
        let rp = self.ref_plane()?;
        let [nx, ny, nz] = rp.normal;
        let h = libm::sqrt(nx * nx + ny * ny);
        let o = rp.origin;
        if h < EPS {
            return Some([o[0] + p.x, o[1] + p.y, o[2]]);
        }
        let n = libm::sqrt(nx * nx + ny * ny + nz * nz);
        let up = [-nx * nz / (h * n), -ny * nz / (h * n), h / n];
        let r = [-ny / h, nx / h, 0.0];
        Some([o[0] + p.x * r[0] + p.y * up[0], o[1] + p.x * r[1] + p.y * up[1], o[2] + p.x * r[2] + p.y * up[2]])
    }
    /// Plane index of an unfolded point: the number of fold images it lies beyond.
    pub fn region_2d(&self, p: Pt) -> usize {
        let Some(end) = self.outline.get(self.outline.len() / 2) else { return 0 };
        self.folds
            .iter()
            .filter(|f| {
                let side = orient(f.right_2d, f.left_2d, *end);
                orient(f.right_2d, f.left_2d, p) * side > 0.0
            })
            .count()
    }
    /// The world point (on its plane) of unfolded point `p`.
    pub fn fold_back(&self, p: Pt) -> Option<V3> {
        let k = self.region_2d(p);
        Some(self.planes.get(k)?.unfold.inverse_apply(self.ref_point(p)?))
    }

    /// Segments the descent from a0 to g (world x/y) on `tile` (see the module docs).
    pub fn segment(tile: &HeightTile, a0: [f64; 2], g: [f64; 2], params: &DemParams, scratch: &mut DemScratch) -> Result<Self, DemError> {
        let (rows, cols) = tile.shape();
        if rows < 3 || cols < 3 {
            return Err(DemError::EmptyTile);
        }
        let finite = [params.mu, params.corridor_half_width_m, params.step_m, params.max_tilt_rad, params.footprint_m, params.min_band_m]
            .iter()
            .chain(a0.iter())
            .chain(g.iter())
            .all(|v| v.is_finite());
        let len = libm::hypot(g[0] - a0[0], g[1] - a0[1]);
        if !finite || len < EPS || params.corridor_half_width_m <= 0.0 || params.footprint_m < 0.0 || params.step_m <= 0.0 {
            return Err(DemError::BadInput);
        }
        let dir = [(g[0] - a0[0]) / len, (g[1] - a0[1]) / len];
        let mut d = DemDescent {
            planes: HVec::new(),
            reference: 0,
            folds: HVec::new(),
            outline: HVec::new(),
            obstacles: HVec::new(),
            edge_obstacles: HVec::new(),
            a0: Pt::default(),
            g: Pt::default(),
            a0_world: [0.0; 3],
            g_world: [0.0; 3],
            blocked_posts: 0,
            components: 0,
            merges: 0,
            mu: params.mu,
            dir,
            left: [-dir[1], dir[0]],
            a0_xy: a0,
        };
        let res = tile.resolution_m();
        let margin = 2.0 * params.footprint_m.max(res);
        let (s_lo, s_hi, hw) = (-margin, len + margin, params.corridor_half_width_m);
        let lo = tile.post_xy(0, 0);
        let hi = tile.post_xy(rows - 1, cols - 1);
        for (s, t) in [(s_lo, -hw), (s_lo, hw), (s_hi, -hw), (s_hi, hw)] {
            let p = d.xy_of(s, t);
            if !(p[0] >= lo[0] && p[0] <= hi[0] && p[1] >= lo[1] && p[1] <= hi[1]) {
                return Err(DemError::CorridorOutsideTile);
            }
        }
        let in_corridor = |d: &DemDescent, xy: [f64; 2]| {
            let (s, t) = (d.s_of(xy), d.t_of(xy));
            s >= s_lo && s <= s_hi && t.abs() <= hw
        };

        // 2. Profile.
        let bin = res.max((s_hi - s_lo) / MAX_PROFILE_BINS as f64);
        let nb = (((s_hi - s_lo) / bin) as usize + 1).min(MAX_PROFILE_BINS);
        let mut acc: [(f64, f64, u32); MAX_PROFILE_BINS] = [(0.0, 0.0, 0); MAX_PROFILE_BINS];
        for r in 0..rows {
            for c in 0..cols {
                let xy = tile.post_xy(r, c);
                if !in_corridor(&d, xy) {
                    continue;
                }
                let Some((gx, gy)) = tile.gradient(r, c) else { continue };
                let b = (((d.s_of(xy) - s_lo) / bin) as usize).min(nb - 1);
                if let Some(a) = acc.get_mut(b) {
                    *a = (a.0 + gx, a.1 + gy, a.2 + 1);
                }
            }
        }
        let mut runs: HVec<Run, MAX_PROFILE_BINS> = HVec::new();
        let mut last = PlaneClass::TetherFree;
        for (b, a) in acc.iter().take(nb).enumerate() {
            let class = if a.2 == 0 {
                last
            } else {
                let n = f64::from(a.2);
                classify_slope(libm::atan(libm::hypot(a.0 / n, a.1 / n)), params.mu)
            };
            last = class;
            let (from, to) = (s_lo + b as f64 * bin, (s_lo + (b + 1) as f64 * bin).min(s_hi));
            match runs.last_mut() {
                Some(r) if r.class == class => r.to = to,
                _ => {
                    let _ = runs.push(Run { class, from, to });
                }
            }
        }
        merge_short_runs(&mut runs, params.min_band_m);
        if !runs.iter().any(|r| r.class == PlaneClass::TetherDemand) {
            return Err(DemError::NoTetherDemand);
        }
        let mut bands: HVec<Run, MAX_DEM_PLANES> = HVec::new();
        {
            let first = runs.first().copied().ok_or(DemError::NoTetherDemand)?;
            let lastr = runs.last().copied().ok_or(DemError::NoTetherDemand)?;
            let rim = (first.class == PlaneClass::TetherFree).then_some(first);
            let floor = (lastr.class == PlaneClass::TetherFree && runs.len() > 1).then_some(lastr);
            let wall_from = rim.map_or(s_lo, |r| r.to);
            let wall_to = floor.map_or(s_hi, |r| r.from);
            for r in [rim, Some(Run { class: PlaneClass::TetherDemand, from: wall_from, to: wall_to }), floor].into_iter().flatten() {
                let _ = bands.push(r);
            }
        }

        // 3. Fits (two passes), merging near-parallel neighbours.
        let fit_band = |d: &DemDescent, from: f64, to: f64| -> Result<(BandPlane, [f64; 3]), DemError> {
            // Posts within a post spacing of a run's end carry the neighbour's slope in their gradient: left out
            // when the run is long enough.
            let trim = if to - from > 4.0 * res { res } else { 0.0 };
            let sel = |xy: [f64; 2]| {
                let s = d.s_of(xy);
                in_corridor(d, xy) && s >= from + trim && s <= to - trim
            };
            let first = fit_plane(tile, a0, |_, _, xy, _| sel(xy)).ok_or(DemError::FitFailed)?;
            let c1 = first.0;
            let off = |xy: [f64; 2], z: f64, c: &[f64; 3]| z - (c[0] + c[1] * (xy[0] - a0[0]) + c[2] * (xy[1] - a0[1]));
            // Too few posts within `step_m` of the first fit (a coarse tile): the first fit stands.
            let (c2, n, rms) = fit_plane(tile, a0, |_, _, xy, z| sel(xy) && off(xy, z, &c1).abs() <= params.step_m).unwrap_or(first);
            let plane = plane_of(&c2, a0, params.mu);
            Ok((
                BandPlane { plane, class: plane.classify(), s_range: (from, to), posts: n, rms_m: rms, unfold: Rigid::ID },
                c2,
            ))
        };
        for _ in 0..MAX_DEM_PLANES {
            d.planes.clear();
            for b in bands.iter() {
                let (p, _) = fit_band(&d, b.from, b.to)?;
                let _ = d.planes.push(p);
            }
            let close = d.planes.windows(2).position(|w| match w {
                [a, b] => libm::acos(dot(a.plane.normal, b.plane.normal).clamp(-1.0, 1.0)) < MIN_FOLD_DEG.to_radians(),
                _ => false,
            });
            let Some(i) = close else { break };
            let Some(nxt) = bands.get(i + 1).copied() else { break };
            if let Some(b) = bands.get_mut(i) {
                b.to = nxt.to;
                if nxt.class == PlaneClass::TetherDemand {
                    b.class = PlaneClass::TetherDemand;
                }
            }
            let _ = super::geo::remove_at(&mut bands, i + 1);
        }

        // 4. Fold lines clipped to the corridor sides; then each plane is refitted on the posts between its fold
        // lines (more than two post spacings from them), and the folds found again (twice): a profile run's ends
        // are straight across the descent, a crease need not be.
        d.compute_folds(s_lo, s_hi, hw)?;
        for _ in 0..2 {
            for k in 0..d.planes.len() {
                let Some(cur) = d.planes.get(k).copied() else { break };
                let sel = |xy: [f64; 2], z: f64| {
                    let q = Pt { x: xy[0], y: xy[1] };
                    in_corridor(&d, xy)
                        && d.region_of(xy) == k
                        && (z - cur.height_at(xy[0], xy[1])).abs() <= params.step_m
                        && d.folds.iter().all(|f| {
                            let (a, b) = (Pt { x: f.right[0], y: f.right[1] }, Pt { x: f.left[0], y: f.left[1] });
                            orient(a, b, q).abs() > 2.0 * res * a.dist(b)
                        })
                };
                let Some((c, n, rms)) = fit_plane(tile, a0, |_, _, xy, z| sel(xy, z)) else { continue };
                let plane = plane_of(&c, a0, params.mu);
                if let Some(p) = d.planes.get_mut(k) {
                    *p = BandPlane { plane, class: plane.classify(), posts: n, rms_m: rms, ..cur };
                }
            }
            d.compute_folds(s_lo, s_hi, hw)?;
        }

        // The steepest plane: the profile found a tether-demand stretch, but a fit over a coarse band can come out
        // gentler than `atan(mu)` (its class then says so and the holding model holds everywhere).
        d.reference = d
            .planes
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.plane.slope_rad().total_cmp(&b.1.plane.slope_rad()))
            .map(|(i, _)| i)
            .ok_or(DemError::NoTetherDemand)?;

        // 5. Unfolding towards the reference plane.
        let np = d.planes.len();
        let fold_rot = |d: &DemDescent, k: usize, from: usize, to: usize| -> Option<Rigid> {
            let f = d.folds.get(k)?;
            let (nf, nt) = (d.planes.get(from)?.plane.normal, d.planes.get(to)?.plane.normal);
            let ax = sub(f.left, f.right);
            let al = libm::sqrt(dot(ax, ax));
            if al < EPS {
                return None;
            }
            let ax = [ax[0] / al, ax[1] / al, ax[2] / al];
            let angle = libm::atan2(dot(cross(nf, nt), ax), dot(nf, nt));
            Some(Rigid::about_line(f.right, ax, angle))
        };
        for k in (0..d.reference).rev() {
            let next = d.planes.get(k + 1).map(|p| p.unfold).ok_or(DemError::FoldOutsideCorridor)?;
            let r = fold_rot(&d, k, k, k + 1).ok_or(DemError::FoldOutsideCorridor)?;
            if let Some(p) = d.planes.get_mut(k) {
                p.unfold = next.after(&r);
            }
        }
        for k in d.reference + 1..np {
            let prev = d.planes.get(k - 1).map(|p| p.unfold).ok_or(DemError::FoldOutsideCorridor)?;
            let r = fold_rot(&d, k - 1, k, k - 1).ok_or(DemError::FoldOutsideCorridor)?;
            if let Some(p) = d.planes.get_mut(k) {
                p.unfold = prev.after(&r);
            }
        }
        for k in 0..d.folds.len() {
            let Some(f) = d.folds.get(k).copied() else { break };
            let (r2, l2) = (d.unfold_on(k, f.right), d.unfold_on(k, f.left));
            if let (Some(f), Some(r2), Some(l2)) = (d.folds.get_mut(k), r2, l2) {
                (f.right_2d, f.left_2d) = (r2, l2);
            }
        }
        // Outline: right side forward, left side back.
        let last = np - 1;
        let start_r = d.lift(0, d.xy_of(s_lo, -hw)).and_then(|p| d.unfold_on(0, p));
        let end_r = d.lift(last, d.xy_of(s_hi, -hw)).and_then(|p| d.unfold_on(last, p));
        let end_l = d.lift(last, d.xy_of(s_hi, hw)).and_then(|p| d.unfold_on(last, p));
        let start_l = d.lift(0, d.xy_of(s_lo, hw)).and_then(|p| d.unfold_on(0, p));
        let mut outline: HVec<Pt, MAX_PLANE_VERTICES> = HVec::new();
        let rights = d.folds.iter().map(|f| Some(f.right_2d));
        let lefts = d.folds.iter().rev().map(|f| Some(f.left_2d));
        for p in core::iter::once(start_r).chain(rights).chain([end_r, end_l]).chain(lefts).chain(core::iter::once(start_l)) {
            outline.push(p.ok_or(DemError::BadOutline)?).map_err(|_| DemError::BadOutline)?;
        }
        if !super::geo::polygon_is_simple(&outline) {
            return Err(DemError::BadOutline);
        }
        d.outline = outline;
        d.a0_world = d.lift(d.region_of(a0), a0).ok_or(DemError::BadInput)?;
        d.g_world = d.lift(d.region_of(g), g).ok_or(DemError::BadInput)?;
        d.a0 = d.unfold_xy(a0).ok_or(DemError::BadInput)?;
        d.g = d.unfold_xy(g).ok_or(DemError::BadInput)?;

        // 6. Obstacle posts (corridor grown by the footprint).
        let grow = params.footprint_m + res;
        let near = |d: &DemDescent, xy: [f64; 2]| {
            let (s, t) = (d.s_of(xy), d.t_of(xy));
            s >= s_lo - grow && s <= s_hi + grow && t.abs() <= hw + grow
        };
        let residual = |d: &DemDescent, r: usize, c: usize| -> Option<f64> {
            let xy = tile.post_xy(r, c);
            let k = d.region_of(xy);
            Some(tile.height(r, c)? - d.planes.get(k)?.height_at(xy[0], xy[1]))
        };
        let cos_tilt = libm::cos(params.max_tilt_rad);
        const OBST: u8 = 1;
        const SEEN: u8 = 2;
        for (i, e) in scratch.resid.iter_mut().enumerate().take(rows * cols) {
            let (r, c) = (i / cols, i % cols);
            *e = if near(&d, tile.post_xy(r, c)) { residual(&d, r, c).map_or(f32::NAN, |x| x as f32) } else { f32::NAN };
        }
        // Protrusion against the plane at the footprint's scale: the residual minus its mean over a window of
        // radius 2 x footprint (at least one post, at most DEM_WINDOW_MAX posts), so the smooth curvature a plane
        // does not follow is not an obstacle, a rock or a pit is; its edges are also rough and steep.
        let w = (libm::ceil(2.0 * params.footprint_m / res) as usize).clamp(1, DEM_WINDOW_MAX);
        // The relief the wheels meet across the rover's own width: on a tile whose posts are more than two
        // footprints apart, a residual `e` at one post rises over a whole post spacing (the surface is
        // interpolated between posts), so two footprints of it see `e x 2 footprint / res`.
        let relief_scale = (2.0 * params.footprint_m / res).min(1.0);
        for (i, m) in scratch.mask.iter_mut().enumerate().take(rows * cols) {
            *m = 0;
            let (r, c) = (i / cols, i % cols);
            let Some(e) = scratch.resid.get(i).map(|x| f64::from(*x)).filter(|x| x.is_finite()) else { continue };
            let (mut sum, mut n) = (0.0f64, 0u32);
            for rr in r.saturating_sub(w)..(r + w + 1).min(rows) {
                for cc in c.saturating_sub(w)..(c + w + 1).min(cols) {
                    if let Some(x) = scratch.resid.get(rr * cols + cc).map(|x| f64::from(*x)).filter(|x| x.is_finite()) {
                        sum += x;
                        n += 1;
                    }
                }
            }
            let e = e - sum / f64::from(n.max(1));
            // Too steep: tilted from every plane of the descent (posts on a fold carry both planes' slopes).
            let steep = tile.gradient(r, c).is_some_and(|(gx, gy)| {
                let nl = libm::sqrt(gx * gx + gy * gy + 1.0);
                d.planes.iter().all(|p| dot([-gx / nl, -gy / nl, 1.0 / nl], p.plane.normal) < cos_tilt)
            });
            if e.abs() * relief_scale > params.step_m || steep {
                *m = OBST;
                d.blocked_posts += 1;
            }
        }
        // Components -> 8-DOP supports of their unfolded cell corners.
        let mut comps: HVec<[f64; 8], MAX_DEM_COMPONENTS> = HVec::new();
        let half = 0.5 * res;
        for seed in 0..rows * cols {
            if scratch.mask.get(seed).copied() != Some(OBST) {
                continue;
            }
            let mut h = [f64::MIN; 8];
            if let Some(m) = scratch.mask.get_mut(seed) {
                *m |= SEEN;
            }
            if let Some(q) = scratch.queue.get_mut(0) {
                *q = seed as u16;
            }
            let (mut head, mut tail) = (0usize, 1usize);
            while head < tail && head < MAX_TILE_CELLS {
                let Some(&i) = scratch.queue.get(head) else { break };
                head += 1;
                let i = usize::from(i);
                let (r, c) = (i / cols, i % cols);
                let xy = tile.post_xy(r, c);
                let k = d.region_of(xy);
                for (dx, dy) in [(-half, -half), (half, -half), (half, half), (-half, half)] {
                    let cxy = [xy[0] + dx, xy[1] + dy];
                    let Some(p) = d.lift(k, cxy).and_then(|p| d.unfold_on(k, p)) else { continue };
                    for (j, hj) in h.iter_mut().enumerate() {
                        *hj = hj.max(p.dot(dop_dir(j)));
                    }
                }
                for nb in grid_neighbours(i, cols, rows).into_iter().flatten() {
                    if scratch.mask.get(nb).copied() == Some(OBST) {
                        if let Some(m) = scratch.mask.get_mut(nb) {
                            *m |= SEEN;
                        }
                        if let Some(q) = scratch.queue.get_mut(tail) {
                            *q = nb as u16;
                            tail += 1;
                        }
                    }
                }
            }
            d.components += 1;
            for hj in h.iter_mut() {
                *hj += params.footprint_m;
            }
            if let Err(h) = comps.push(h) {
                // Full: merge into the nearest (bigger obstacles are conservative).
                d.merges += 1;
                if let Some(nearest) = comps.iter_mut().min_by(|a, b| dop_gap(a, &h).total_cmp(&dop_gap(b, &h))) {
                    dop_merge(nearest, &h);
                }
            }
        }
        // Merge overlaps, then reduce to the BTM's capacity.
        for _ in 0..DEM_MERGE_BUDGET {
            let mut pair = None;
            'find: for i in 0..comps.len() {
                for j in i + 1..comps.len() {
                    if let (Some(a), Some(b)) = (comps.get(i), comps.get(j)) {
                        if dop_overlap(a, b, 1e-3) {
                            pair = Some((i, j));
                            break 'find;
                        }
                    }
                }
            }
            if pair.is_none() && comps.len() > MAX_DEM_OBSTACLES {
                let mut best = (f64::MAX, 0, 0);
                for i in 0..comps.len() {
                    for j in i + 1..comps.len() {
                        if let (Some(a), Some(b)) = (comps.get(i), comps.get(j)) {
                            let gap = dop_gap(a, b);
                            if gap < best.0 {
                                best = (gap, i, j);
                            }
                        }
                    }
                }
                pair = Some((best.1, best.2));
            }
            let Some((i, j)) = pair else { break };
            // swap_remove without its panic path: the last takes j's place
            let Some(&b) = comps.get(j) else { break };
            if let Some(&last) = comps.last() {
                if let Some(s) = comps.get_mut(j) {
                    *s = last;
                }
            }
            comps.pop();
            if let Some(a) = comps.get_mut(i) {
                dop_merge(a, &b);
            }
            d.merges += 1;
        }
        for h in comps.iter() {
            let oct = dop_polygon(h);
            let inside = oct.iter().all(|p| point_in_polygon(*p, &d.outline, true))
                && polygon_edges(&oct).all(|(p, q)| polygon_edges(&d.outline).all(|(a, b)| !segments_intersect(p, q, a, b)));
            let list = if inside { &mut d.obstacles } else { &mut d.edge_obstacles };
            let _ = list.push(oct);
        }
        Ok(d)
    }

    /// a0 and g must lie outside every inflated obstacle.
    pub fn check_ends(&self) -> Result<(), DemError> {
        let blocked = |p: Pt| self.obstacles.iter().chain(self.edge_obstacles.iter()).any(|o| point_in_polygon(p, o, false));
        if blocked(self.a0) {
            return Err(DemError::StartBlocked);
        }
        if blocked(self.g) {
            return Err(DemError::GoalBlocked);
        }
        Ok(())
    }

    /// The holding model on the unfolded descent: the reference (wall) slope, uniform soil, tether-free half-planes
    /// for a tether-free plane before and after the reference (the rim and floor).
    pub fn hold_model(&self) -> HoldModel {
        let slope = self.ref_plane().map_or(0.0, |p| p.slope_rad());
        let mut m = HoldModel::point_mass(slope, SoilMap::uniform(self.mu));
        let mut free = HVec::<(Pt, Pt), 2>::new();
        let r = self.reference;
        for (k, plane_side) in [(r.wrapping_sub(1), r.wrapping_sub(1)), (r, r + 1)] {
            let (Some(f), Some(p)) = (self.folds.get(k), self.planes.get(plane_side)) else { continue };
            if p.class != PlaneClass::TetherFree {
                continue;
            }
            // Orient the fold image so the tether-free plane is on its left.
            let probe = if plane_side < r { self.outline.first() } else { self.outline.get(self.outline.len() / 2) };
            let Some(probe) = probe else { continue };
            let line = if orient(f.right_2d, f.left_2d, *probe) > 0.0 { (f.right_2d, f.left_2d) } else { (f.left_2d, f.right_2d) };
            let _ = free.push(line);
        }
        m.tether_free = [free.first().copied(), free.get(1).copied()];
        m.limit = HoldLimit::PointMass;
        m
    }

    /// Builds the BTM of the unfolded descent (outline minus the inner obstacles).
    pub fn build_btm(&self, btm: &mut super::btm::Btm) -> Result<super::btm::UpdateReport, super::btm::BtmError> {
        let mut obs: HVec<&[Pt], MAX_DEM_OBSTACLES> = HVec::new();
        for o in self.obstacles.iter() {
            let _ = obs.push(o.as_slice());
        }
        btm.build(&self.outline, &obs)
    }

    /// Maps an unfolded polyline onto the planes, breaking it where it crosses a fold image.
    fn polyline_to_world<const N: usize>(&self, pts: &[Pt], out: &mut HVec<V3, N>) -> Result<(), RouteError> {
        for (i, p) in pts.iter().enumerate() {
            if i > 0 {
                let Some(q) = pts.get(i - 1).copied() else { continue };
                // Crossings with each fold image, in order along q -> p.
                let mut ts: HVec<f64, MAX_DEM_PLANES> = HVec::new();
                for f in self.folds.iter() {
                    let (a, b) = (f.right_2d, f.left_2d);
                    let (oq, op) = (orient(a, b, q), orient(a, b, *p));
                    if oq * op < 0.0 {
                        let _ = ts.push(oq / (oq - op));
                    }
                }
                super::geo::sort_by(&mut ts, |a, b| a.total_cmp(b).is_lt());
                for t in ts {
                    let x = q + (*p - q) * t;
                    let w = self.fold_back(x).ok_or(RouteError::Geometry)?;
                    out.push(w).map_err(|_| RouteError::Capacity)?;
                }
            }
            let w = self.fold_back(*p).ok_or(RouteError::Geometry)?;
            out.push(w).map_err(|_| RouteError::Capacity)?;
        }
        Ok(())
    }

    /// Maps a plan back to the world (see [`WorldRoute`]), refusing a route that touches an edge obstacle or needs
    /// more tether than `max_payout_m`.
    pub fn route_to_world(&self, tile: &HeightTile, plan: &Plan, max_payout_m: f64) -> Result<WorldRoute, RouteError> {
        for (k, o) in self.edge_obstacles.iter().enumerate() {
            for path in [plan.shp.pts.as_slice(), plan.descent.as_slice()] {
                let hit = path.windows(2).any(|w| match w {
                    [a, b] => {
                        point_in_polygon(*a, o, false) || polygon_edges(o).any(|(p, q)| segments_intersect(*a, *b, p, q))
                    }
                    _ => false,
                });
                if hit {
                    return Err(RouteError::HitsEdgeObstacle(k));
                }
            }
        }
        let mut r = WorldRoute::default();
        self.polyline_to_world(&plan.shp.pts, &mut r.tether)?;
        self.polyline_to_world(&plan.descent, &mut r.waypoints)?;
        for w in r.waypoints.iter_mut() {
            if let Some(z) = tile.height_at(w[0], w[1]) {
                w[2] = z;
            }
        }
        for a in plan.anchors.iter() {
            let mut w = self.fold_back(a.p).ok_or(RouteError::Geometry)?;
            if let Some(z) = tile.height_at(w[0], w[1]) {
                w[2] = z;
            }
            r.anchors.push(w).map_err(|_| RouteError::Capacity)?;
        }
        r.tether_length_m = r.tether.windows(2).map(|w| if let [a, b] = w { dist3(*a, *b) } else { 0.0 }).sum();
        // A NaN length or limit is refused too.
        if r.tether_length_m.partial_cmp(&max_payout_m).is_none_or(|o| o == core::cmp::Ordering::Greater) {
            return Err(RouteError::TetherTooLong { needed_m: r.tether_length_m, max_payout_m });
        }
        Ok(r)
    }
}

/// Most points of a world polyline: each unfolded segment gains at most one point per fold line.
pub const MAX_WORLD_PATH: usize = MAX_PATH * MAX_DEM_PLANES;

/// A plan in the world frame.
#[derive(Clone, Debug, Default)]
pub struct WorldRoute {
    /// The taut tether at the goal (the SHP) on the planes, broken at the fold lines (world, m).
    pub tether: HVec<V3, MAX_WORLD_PATH>,
    /// The descent's waypoints (broken at the fold lines) with DEM heights where the tile has them.
    pub waypoints: HVec<V3, MAX_WORLD_PATH>,
    /// Expected intermediate anchors a1..ak (obstacle corners) with DEM heights.
    pub anchors: HVec<V3, MAX_PATH>,
    /// 3D length of `tether` (m).
    pub tether_length_m: f64,
}

/// Why a plan could not become a world route.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RouteError {
    /// The tether to the goal is longer than the payout limit.
    TetherTooLong {
        /// 3D length needed (m).
        needed_m: f64,
        /// The limit (m).
        max_payout_m: f64,
    },
    /// The SHP or the descent touches an obstacle crossing the outline (index into `edge_obstacles`).
    HitsEdgeObstacle(usize),
    /// A world polyline is longer than [`MAX_WORLD_PATH`].
    Capacity,
    /// A point could not be folded back (degenerate planes).
    Geometry,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::homotopy::btm::Btm;
    use crate::plan::homotopy::plan::{preplan, HomotopyParams, PlanReport, Workspace};
    use std::boxed::Box;
    use std::vec::Vec;

    const RES: f64 = 0.2;
    const ROWS: usize = 100;
    const COLS: usize = 60;
    const RIM_Y: f64 = 14.0;
    const FLOOR_Y: f64 = 6.0;
    const RIM_Z: f64 = 20.0;

    /// Rim (flat, y > 14), a wall at `alpha` (6 < y < 14, rising with y), a flat floor (y < 6); `rock` adds a
    /// 1 m high block over the given world box.
    fn crater(alpha_deg: f64, rocks: &[[f64; 4]]) -> Box<HeightTile> {
        let t = libm::tan(alpha_deg.to_radians());
        let z = |x: f64, y: f64| {
            let base = RIM_Z - t * (RIM_Y - y.clamp(FLOOR_Y, RIM_Y));
            let bump = rocks.iter().any(|r| x >= r[0] && x <= r[1] && y >= r[2] && y <= r[3]);
            base + if bump { 1.0 } else { 0.0 }
        };
        let mut h = Vec::new();
        for r in 0..ROWS {
            for c in 0..COLS {
                h.push(z(c as f64 * RES, r as f64 * RES) as f32);
            }
        }
        let mut tile = Box::new(HeightTile::new());
        tile.load([0.0, 0.0], RES, ROWS, COLS, &h).unwrap();
        tile
    }

    fn descent(tile: &HeightTile, a0: [f64; 2], g: [f64; 2]) -> Result<DemDescent, DemError> {
        descent_hw(tile, a0, g, 4.0)
    }
    fn descent_hw(tile: &HeightTile, a0: [f64; 2], g: [f64; 2], hw: f64) -> Result<DemDescent, DemError> {
        let p = DemParams::for_rover(&RoverParams::AXEL, 0.6, hw);
        let d = DemDescent::segment(tile, a0, g, &p, &mut Box::new(DemScratch::new()))?;
        d.check_ends()?;
        Ok(d)
    }

    /// The three planes of a synthetic crater come back with their closed-form slopes and normals (tolerance
    /// 0.05 deg and 1e-3 on each normal component), the fold lines at the creases (within one post spacing).
    #[test]
    fn synthetic_crater_segments_into_rim_wall_floor() {
        for alpha in [45.0f64, 60.0] {
            let d = descent(&crater(alpha, &[]), [6.0, 18.0], [6.0, 2.0]).unwrap();
            assert_eq!(d.planes.len(), 3, "alpha {alpha}");
            assert_eq!(d.reference, 1);
            let want = [0.0, alpha, 0.0];
            for (p, w) in d.planes.iter().zip(want) {
                assert!((p.plane.slope_rad().to_degrees() - w).abs() < 0.05, "alpha {alpha}: {:?}", p.plane);
                let a = w.to_radians();
                let n = [0.0, -libm::sin(a), libm::cos(a)];
                for (x, y) in p.plane.normal.iter().zip(n) {
                    assert!((x - y).abs() < 1e-3, "{:?} vs {n:?}", p.plane.normal);
                }
            }
            assert_eq!(d.planes.iter().map(|p| p.class).collect::<Vec<_>>(), [PlaneClass::TetherFree, PlaneClass::TetherDemand, PlaneClass::TetherFree]);
            for (f, y) in d.folds.iter().zip([RIM_Y, FLOOR_Y]) {
                assert!((f.right[1] - y).abs() < RES && (f.left[1] - y).abs() < RES, "{f:?}");
            }
            assert!(d.obstacles.is_empty() && d.edge_obstacles.is_empty(), "a smooth crater has no obstacles: {d:?}");
        }
    }

    /// A straight taut tether over the rim and down the wall to the floor is one straight segment unfolded; its 3D
    /// length on the planes is the closed-form unfolded length sqrt(dx^2 + (rim + wall / cos alpha + floor)^2), and
    /// every point of the world polyline lies on the terrain.
    #[test]
    fn unfolding_makes_a_taut_tether_over_the_rim_straight() {
        let alpha = 55.0f64;
        let tile = crater(alpha, &[]);
        let (a0, g) = ([4.0, 17.0], [8.0, 3.0]);
        let d = descent_hw(&tile, a0, g, 2.0).unwrap();
        let along = (a0[1] - RIM_Y) + (RIM_Y - FLOOR_Y) / libm::cos(alpha.to_radians()) + (FLOOR_Y - g[1]);
        let closed = libm::hypot(g[0] - a0[0], along);
        assert!((d.a0.dist(d.g) - closed).abs() < 1e-3, "{} vs {closed}", d.a0.dist(d.g));
        let mut w: HVec<V3, MAX_WORLD_PATH> = HVec::new();
        d.polyline_to_world(&[d.a0, d.g], &mut w).unwrap();
        assert_eq!(w.len(), 4, "breaks at both fold lines: {w:?}");
        let len: f64 = w.windows(2).map(|p| dist3(p[0], p[1])).sum();
        assert!((len - closed).abs() < 1e-3, "{len} vs {closed}");
        for p in w.iter() {
            let z = tile.height_at(p[0], p[1]).unwrap();
            assert!((p[2] - z).abs() < 0.02, "{p:?} off the terrain ({z})");
        }
        // The ends come back where they started.
        assert!(dist3(w[0], [a0[0], a0[1], RIM_Z]) < 1e-6 && dist3(w[3], [g[0], g[1], RIM_Z - libm::tan(alpha.to_radians()) * 8.0]) < 1e-6);
        // Folding back is the inverse of unfolding.
        for xy in [[1.0, 19.0], [7.0, 10.0], [10.0, 1.0]] {
            let p = d.unfold_xy(xy).unwrap();
            let q = d.fold_back(p).unwrap();
            assert!((q[0] - xy[0]).abs() < 1e-9 && (q[1] - xy[1]).abs() < 1e-9, "{xy:?} -> {q:?}");
        }
    }

    /// Every obstacle post's cell lies inside an inflated octagon, at least the footprint away from its boundary.
    #[test]
    fn obstacles_are_inflated_by_the_footprint() {
        let rocks = [[4.0, 5.0, 10.0, 11.0], [7.6, 8.0, 8.0, 8.8]];
        let tile = crater(50.0, &rocks);
        let d = descent(&tile, [6.0, 18.0], [6.0, 2.0]).unwrap();
        let fp = DemParams::for_rover(&RoverParams::AXEL, 0.6, 4.0).footprint_m;
        assert!((fp - libm::sqrt(0.5 * 0.5 + 0.35 * 0.35)).abs() < 1e-6);
        assert!(d.blocked_posts > 0 && !d.obstacles.is_empty());
        let all: Vec<&Octagon> = d.obstacles.iter().chain(d.edge_obstacles.iter()).collect();
        let mut checked = 0;
        for r in 0..ROWS {
            for c in 0..COLS {
                let [x, y] = tile.post_xy(r, c);
                if !rocks.iter().any(|b| x >= b[0] && x <= b[1] && y >= b[2] && y <= b[3]) {
                    continue;
                }
                for (dx, dy) in [(-0.1, -0.1), (0.1, -0.1), (0.1, 0.1), (-0.1, 0.1)] {
                    let p = d.unfold_xy([x + dx, y + dy]).unwrap();
                    let ok = all.iter().any(|o| {
                        point_in_polygon(p, o, true)
                            && polygon_edges(o).all(|(a, b)| {
                                let t = ((p - a).dot(b - a) / (b - a).dot(b - a)).clamp(0.0, 1.0);
                                p.dist(a + (b - a) * t) >= fp - 1e-9
                            })
                    });
                    assert!(ok, "rock cell corner ({}, {}) not inside an inflated obstacle", x + dx, y + dy);
                    checked += 1;
                }
            }
        }
        assert!(checked > 40, "{checked}");
        for o in all {
            assert!(o.len() <= MAX_OBSTACLE_VERTICES && o.len() >= 3);
        }
    }

    /// On a tile coarser than the rover's footprint (4 m posts, the LOLA polar DEM at 1:400) a gentle undulation
    /// across the wall (0.6 m over 16 m, 8.5 deg at its steepest) is no obstacle, though each crest's residual
    /// against its 3 x 3 posts (0.4 m) is more than a wheel radius: between posts the surface is a facet, so the
    /// wheels meet 1.22 / 4 of it across the footprint. A 3 m block on one post still is one.
    #[test]
    fn relief_is_judged_at_the_footprint_on_coarse_tiles() {
        const R: f64 = 4.0;
        let (rows, cols) = (40usize, 30usize);
        let t = libm::tan(30f64.to_radians());
        let tile = |block: Option<(usize, usize)>| {
            let mut h = Vec::new();
            for r in 0..rows {
                for c in 0..cols {
                    let (x, y) = (c as f64 * R, r as f64 * R);
                    let wave = 0.6 * libm::sin(core::f64::consts::TAU * x / 16.0);
                    let on_wall = (40.0..=100.0).contains(&y);
                    let z = 40.0 - t * (100.0 - y.clamp(40.0, 100.0)) + if on_wall { wave } else { 0.0 };
                    h.push((z + if block == Some((r, c)) { 3.0 } else { 0.0 }) as f32);
                }
            }
            let mut tile = Box::new(HeightTile::new());
            tile.load([0.0, 0.0], R, rows, cols, &h).unwrap();
            tile
        };
        let p = DemParams::for_rover(&RoverParams::AXEL, 0.4, 12.0);
        let segment = |tile: &HeightTile| {
            DemDescent::segment(tile, [60.0, 130.0], [60.0, 20.0], &p, &mut Box::new(DemScratch::new())).unwrap()
        };
        let smooth = segment(&tile(None));
        assert_eq!(smooth.planes.len(), 3);
        assert_eq!(smooth.blocked_posts, 0, "the undulation is no obstacle: {:?}", smooth.edge_obstacles);
        assert!(smooth.obstacles.is_empty() && smooth.edge_obstacles.is_empty());
        let rock = segment(&tile(Some((17, 16))));
        assert!(rock.blocked_posts >= 1, "the block is an obstacle");
        let at = rock.unfold_xy([64.0, 68.0]).unwrap();
        assert!(rock.obstacles.iter().chain(rock.edge_obstacles.iter()).any(|o| point_in_polygon(at, o, false)));
    }

    /// Bad tiles are refused with their reason, and the previous tile is kept.
    #[test]
    fn bad_tiles_are_rejected_and_the_previous_tile_kept() {
        let mut t = crater(50.0, &[]);
        let before = t.height(50, 30);
        let ok = [1.0f32; 12];
        let mut nan = ok;
        nan[5] = f32::NAN;
        assert_eq!(t.load([0.0, 0.0], 0.5, 3, 4, &nan), Err(TileError::NotFinite(5)));
        assert_eq!(t.load([0.0, 0.0], 0.0, 3, 4, &ok), Err(TileError::Resolution(0.0)));
        assert_eq!(t.load([0.0, 0.0], 50.0, 3, 4, &ok), Err(TileError::Resolution(50.0)));
        assert!(matches!(t.load([0.0, 0.0], f64::NAN, 3, 4, &ok), Err(TileError::Resolution(_))));
        assert_eq!(t.load([0.0, 0.0], 0.5, 3, 5, &ok), Err(TileError::Length { expected: 15, got: 12 }));
        assert_eq!(t.load([0.0, 0.0], 0.5, MAX_TILE_SIDE + 1, 4, &ok), Err(TileError::TooLarge { rows: MAX_TILE_SIDE + 1, cols: 4 }));
        assert_eq!(t.load([f64::INFINITY, 0.0], 0.5, 3, 4, &ok), Err(TileError::Origin));
        assert_eq!(t.load([0.0, 0.0], 0.5, 0, 4, &[]), Err(TileError::Empty));
        assert_eq!(t.shape(), (ROWS, COLS));
        assert_eq!(t.height(50, 30), before);
        // Descents the tile cannot carry.
        assert_eq!(descent(&t, [6.0, 18.0], [6.0, 18.0]).unwrap_err(), DemError::BadInput);
        assert_eq!(descent(&t, [6.0, 18.0], [6.0, -5.0]).unwrap_err(), DemError::CorridorOutsideTile);
        assert_eq!(descent(&crater(10.0, &[]), [6.0, 18.0], [6.0, 2.0]).unwrap_err(), DemError::NoTetherDemand);
        assert_eq!(descent(&crater(50.0, &[[5.0, 7.0, 17.0, 19.0]]), [6.0, 18.0], [6.0, 2.0]).unwrap_err(), DemError::StartBlocked);
    }

    /// The rim and floor hold at any tether angle, the wall only within theta_max of upslope.
    #[test]
    fn hold_model_frees_the_rim_and_floor() {
        let d = descent(&crater(55.0, &[]), [6.0, 18.0], [6.0, 2.0]).unwrap();
        let m = d.hold_model();
        let tmax = crate::plan::homotopy::planes::theta_max(55f64.to_radians(), 0.6);
        let (rim, wall, floor) = (d.unfold_xy([6.0, 17.0]).unwrap(), d.unfold_xy([6.0, 10.0]).unwrap(), d.unfold_xy([6.0, 3.0]).unwrap());
        assert_eq!(m.theta_max_at(rim), core::f64::consts::PI);
        assert_eq!(m.theta_max_at(floor), core::f64::consts::PI);
        assert!((m.theta_max_at(wall) - tmax).abs() < 1e-3, "{} vs {tmax}", m.theta_max_at(wall));
    }

    /// A plan on a rocky wall maps back to the world: the tether's 3D length (summed here) equals the SHP's
    /// unfolded length, and the payout limit refuses it when it is shorter than that.
    #[test]
    fn world_route_length_and_payout_refusal() {
        let tile = crater(50.0, &[[4.5, 5.5, 10.0, 11.0], [6.5, 7.5, 7.5, 8.5]]);
        let d = descent(&tile, [6.0, 18.0], [6.0, 2.0]).unwrap();
        let mut btm = Box::new(Btm::new());
        d.build_btm(&mut btm).unwrap();
        let mut ws = Box::new(Workspace::default());
        let (mut lc, mut rep) = (HVec::new(), PlanReport::default());
        let plan = preplan(&btm, &d.hold_model(), &HomotopyParams::default(), &mut ws, d.a0, d.g, &mut lc, &mut rep)
            .unwrap()
            .expect("a plan on the rocky wall");
        let r = d.route_to_world(&tile, &plan, 100.0).unwrap();
        let summed: f64 = r.tether.windows(2).map(|w| dist3(w[0], w[1])).sum();
        assert!((summed - plan.shp.length()).abs() < 1e-6, "{summed} vs {}", plan.shp.length());
        assert_eq!(r.anchors.len(), plan.anchors.len());
        assert!(r.waypoints.len() >= plan.descent.len());
        let too_short = 0.9 * summed;
        assert_eq!(
            d.route_to_world(&tile, &plan, too_short).unwrap_err(),
            RouteError::TetherTooLong { needed_m: r.tether_length_m, max_payout_m: too_short }
        );
    }
}
