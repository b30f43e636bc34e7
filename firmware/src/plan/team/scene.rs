//! Scene pipeline, stages 1-3 of Morad et al. section V-A (Fig. 7): range points -> normals from k nearest
//! neighbours -> a continuous surface.
//!
//! **Scene frame.** Origin at the centroid of the scan; normal = the mean of the point normals (below), oriented
//! along the robot's `up` (its outward direction from its attitude while gripping: gravity on a cliff, away from
//! the body's centre on an asteroid). Everything is expressed in this frame: plane coordinates (a, b) and height
//! z along the normal. On a cliff the plane is the wall, on an asteroid the local tangent plane; "height" is
//! protrusion from the mean surface, not altitude. (A plane fitted to the points themselves was tried first and
//! rejected: a deep crevasse or a far wall in the scan tilts it by tens of degrees.)
//!
//! **Normals (V-A.2).** For every point, a plane is fitted to the point and its [`KNN_K`] nearest neighbours; its
//! normal (oriented to `up`) is the point's normal. The neighbours come from a fixed 2-D bucket
//! index over the plane perpendicular to `up` ([`KNN_BUCKETS_PER_AXIS`]^2 buckets); the search visits rings of buckets outwards
//! and stops when the k-th best distance is below the ring's inner radius (exact kNN, bounded by the ring count).
//!
//! **Surface (V-A.3): what we chose and why.** The paper reconstructs a closed surface by screened Poisson
//! surface reconstruction (Kazhdan & Hoppe 2013), which needs an octree and a sparse linear solve of unbounded size.
//! In fixed memory we reconstruct a *height/normal grid over the scene plane*
//! ([`SURFACE_CELLS_PER_AXIS`]^2 cells): observed cells take the mean height of their points and the mean of their
//! point normals; unobserved cells within `fill_max_cells` of an observed one are filled by `fill_sweeps`
//! Gauss-Seidel sweeps of the membrane (Laplace) equation with the observed cells held fixed. That is the discrete
//! Poisson problem with a zero source and an infinite screening weight on the data — it does what the paper uses
//! SPSR for (fill occlusion shadows behind rocks, smooth discontinuities) with a fixed grid, a fixed number of
//! sweeps and no solver that can fail to converge. The price: one height per plane cell, so overhangs are
//! flattened into the wall (acceptable for hop targets, which must be reachable from the front anyway).
//! Filled cells are marked so the scoring can penalise unobserved anchors.
//!
//! Parameters (from [`TeamParams`]): `fill_max_cells` (default 4), `fill_sweeps` (default 30).
//!
//! [`KNN_K`]: crate::config::team::KNN_K
//! [`KNN_BUCKETS_PER_AXIS`]: crate::config::team::KNN_BUCKETS_PER_AXIS
//! [`SURFACE_CELLS_PER_AXIS`]: crate::config::team::SURFACE_CELLS_PER_AXIS
//! [`TeamParams`]: crate::config::team::TeamParams

use crate::config::team::{
    TeamParams, EIGEN_MAX_SWEEPS, KNN_BUCKETS_PER_AXIS, KNN_K, SURFACE_CELLS_PER_AXIS, SURFACE_MAX_VERTICES,
};
use crate::geom::{is_finite3, norm3, normalize3, Real, Vec3};
use nalgebra::Matrix3;

const NONE: u32 = u32::MAX;
const BUCKETS: usize = KNN_BUCKETS_PER_AXIS * KNN_BUCKETS_PER_AXIS;
const N: usize = SURFACE_CELLS_PER_AXIS;

/// State of a surface cell.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum CellState {
    /// No data and too far from data to fill.
    #[default]
    Empty,
    /// Contains range points.
    Observed,
    /// Filled in by the membrane reconstruction.
    Filled,
}

/// The scene frame: origin, in-plane axes u, v and normal n (right-handed, n along the robot's `up`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneFrame {
    /// Centroid of the scan.
    pub origin: Vec3,
    /// First in-plane axis.
    pub u: Vec3,
    /// Second in-plane axis.
    pub v: Vec3,
    /// Plane normal, on the side of `up`.
    pub n: Vec3,
}

impl SceneFrame {
    /// (a, b, z) coordinates of a world point.
    pub fn to_local(&self, p: &Vec3) -> Vec3 {
        let d = p - self.origin;
        Vec3::new(d.dot(&self.u), d.dot(&self.v), d.dot(&self.n))
    }

    /// World point of local (a, b, z).
    pub fn to_world(&self, l: &Vec3) -> Vec3 {
        self.origin + self.u * l.x + self.v * l.y + self.n * l.z
    }
}

/// Why a scene could not be built.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SceneError {
    /// Fewer than 3 finite points.
    TooFewPoints,
    /// More points than [`crate::config::team::SCENE_MAX_POINTS`]; the caller should thin the scan.
    TooManyPoints,
    /// The points are degenerate (collinear or coincident): no plane.
    Degenerate,
}

/// Surface grid and the per-point normals of one scene; a fixed arena (~120 KiB with the defaults).
pub struct Scene<const P: usize> {
    /// The scene frame.
    pub frame: SceneFrame,
    /// Minimum plane coordinates of the grid.
    pub min_ab: (Real, Real),
    /// Cell size, metres.
    pub cell: Real,
    /// Number of points used.
    pub n_points: usize,
    /// Local coordinates of the points.
    pub local: [Vec3; P],
    /// Point normals (world frame).
    pub normals: [Vec3; P],
    next: [u32; P],
    head: [u32; BUCKETS],
    bucket_min: (Real, Real),
    bucket_size: Real,
    /// Cell heights (local z), row-major (row = b index).
    pub height: [Real; SURFACE_MAX_VERTICES],
    /// Cell normals (world frame).
    pub cell_normal: [Vec3; SURFACE_MAX_VERTICES],
    /// Cell states.
    pub state: [CellState; SURFACE_MAX_VERTICES],
    /// Mean plane coordinates of an observed cell's points (the vertex sits where the data is, not at the cell
    /// centre, so a vertex on a rim is on the rim).
    pub cell_ab: [(Real, Real); SURFACE_MAX_VERTICES],
    count: [u16; SURFACE_MAX_VERTICES],
}

/// 3 x 3 symmetric eigen-decomposition by cyclic Jacobi rotations, bounded by [`EIGEN_MAX_SWEEPS`]; returns the
/// eigenvector of the smallest eigenvalue and the eigenvalues (ascending), or `None` on non-convergence.
pub fn smallest_eigenvector(m: [[Real; 3]; 3]) -> Option<(Vec3, [Real; 3])> {
    let mut a = Matrix3::from_fn(|i, j| m.get(i).and_then(|r| r.get(j)).copied().unwrap_or(0.0));
    let mut v = Matrix3::<Real>::identity();
    let scale = a.iter().fold(0.0 as Real, |s, x| s + x * x);
    if !scale.is_finite() {
        return None;
    }
    let mut converged = false;
    for _ in 0..EIGEN_MAX_SWEEPS {
        let off = a.m12 * a.m12 + a.m13 * a.m13 + a.m23 * a.m23;
        if off <= 1e-12 * scale || off == 0.0 {
            converged = true;
            break;
        }
        for (p, q) in [(0usize, 1usize), (0, 2), (1, 2)] {
            let at = |m: &Matrix3<Real>, i: usize, k: usize| m.get((i, k)).copied().unwrap_or(0.0);
            let apq = at(&a, p, q);
            if apq == 0.0 {
                continue;
            }
            let theta = (at(&a, q, q) - at(&a, p, p)) / (2.0 * apq);
            let t = if theta >= 0.0 {
                1.0 / (theta + libm::sqrtf(1.0 + theta * theta))
            } else {
                -1.0 / (-theta + libm::sqrtf(1.0 + theta * theta))
            };
            let c = 1.0 / libm::sqrtf(1.0 + t * t);
            let s = t * c;
            // Givens rotation J in the (p, q) plane; A' = J^T A J, V' = V J
            let mut j = Matrix3::<Real>::identity();
            for (i, k, x) in [(p, p, c), (q, q, c), (p, q, s), (q, p, -s)] {
                if let Some(e) = j.get_mut((i, k)) {
                    *e = x;
                }
            }
            a = j.transpose() * a * j;
            v *= j;
        }
    }
    if !converged {
        return None;
    }
    let ev = [a.m11, a.m22, a.m33];
    let (k, _) = ev.iter().enumerate().fold((0usize, Real::INFINITY), |(bk, bv), (i, &x)| if x < bv { (i, x) } else { (bk, bv) });
    let at = |i: usize| v.get((i, k)).copied().unwrap_or(0.0);
    let vec = Vec3::new(at(0), at(1), at(2));
    // three values in ascending order by a sorting network (no library sort: no panic path in the flight build)
    let [mut e0, mut e1, mut e2] = ev;
    if e0.total_cmp(&e1).is_gt() {
        core::mem::swap(&mut e0, &mut e1);
    }
    if e1.total_cmp(&e2).is_gt() {
        core::mem::swap(&mut e1, &mut e2);
    }
    if e0.total_cmp(&e1).is_gt() {
        core::mem::swap(&mut e0, &mut e1);
    }
    Some((vec, [e0, e1, e2]))
}

/// Covariance of points (about their mean) -> smallest eigenvector.
fn fit_normal<'a>(pts: impl Iterator<Item = &'a Vec3> + Clone) -> Option<(Vec3, [Real; 3])> {
    let mut n = 0.0 as Real;
    let mut c = Vec3::zeros();
    for p in pts.clone() {
        c += p;
        n += 1.0;
    }
    if n < 3.0 {
        return None;
    }
    c /= n;
    let mut m = Matrix3::<Real>::zeros();
    for p in pts {
        let d = p - c;
        m += d * d.transpose() / n;
    }
    smallest_eigenvector([[m.m11, m.m12, m.m13], [m.m21, m.m22, m.m23], [m.m31, m.m32, m.m33]])
}

fn any_perpendicular(n: &Vec3) -> Vec3 {
    let ax = if libm::fabsf(n.x) <= libm::fabsf(n.y) && libm::fabsf(n.x) <= libm::fabsf(n.z) {
        Vec3::x()
    } else if libm::fabsf(n.y) <= libm::fabsf(n.z) {
        Vec3::y()
    } else {
        Vec3::z()
    };
    let u = n.cross(&ax);
    normalize3(&u, 1e-9).unwrap_or_else(Vec3::x)
}

impl<const P: usize> Scene<P> {
    /// An empty scene arena.
    pub const fn new() -> Self {
        let z = Vec3::new(0.0, 0.0, 0.0);
        Self {
            frame: SceneFrame { origin: z, u: z, v: z, n: z },
            min_ab: (0.0, 0.0),
            cell: 1.0,
            n_points: 0,
            local: [z; P],
            normals: [z; P],
            next: [NONE; P],
            head: [NONE; BUCKETS],
            bucket_min: (0.0, 0.0),
            bucket_size: 1.0,
            height: [0.0; SURFACE_MAX_VERTICES],
            cell_normal: [z; SURFACE_MAX_VERTICES],
            state: [CellState::Empty; SURFACE_MAX_VERTICES],
            cell_ab: [(0.0, 0.0); SURFACE_MAX_VERTICES],
            count: [0; SURFACE_MAX_VERTICES],
        }
    }

    /// Build the scene from world points; `up` is the robot's outward direction (orients the normals).
    /// Non-finite points are skipped.
    pub fn build(&mut self, points: &[Vec3], up: &Vec3, params: &TeamParams) -> Result<(), SceneError> {
        let finite = || points.iter().filter(|p| is_finite3(p));
        let count = finite().count();
        if count < 3 {
            return Err(SceneError::TooFewPoints);
        }
        if count > P {
            return Err(SceneError::TooManyPoints);
        }
        // degenerate scans (collinear or coincident points) have no surface
        let (_, ev) = fit_normal(finite()).ok_or(SceneError::Degenerate)?;
        if ev[1] <= 1e-9 {
            return Err(SceneError::Degenerate);
        }
        let mut c = Vec3::zeros();
        for p in finite() {
            c += p;
        }
        c /= count as Real;
        self.n_points = count;
        // provisional frame on the robot's `up`, for the kNN bucket index
        let n0 = normalize3(up, 1e-9).unwrap_or(Vec3::z());
        let u0 = any_perpendicular(&n0);
        self.frame = SceneFrame { origin: c, u: u0, v: n0.cross(&u0), n: n0 };
        let extent = self.project(points);
        self.bucket_min = self.min_ab;
        self.bucket_size = extent / KNN_BUCKETS_PER_AXIS as Real * 1.0001;
        for h in self.head.iter_mut() {
            *h = NONE;
        }
        for i in (0..count).rev() {
            let b = self.bucket_of(i);
            if let (Some(nx), Some(h)) = (self.next.get_mut(i), self.head.get_mut(b)) {
                *nx = *h;
                *h = i as u32;
            }
        }
        // normals from the k nearest neighbours, oriented to `up`
        let mut mean_n = Vec3::zeros();
        for i in 0..count {
            let mut nb = [(Real::MAX, NONE); KNN_K];
            self.knn(i, &mut nb);
            let local = &self.local;
            let pts = core::iter::once(i as u32)
                .chain(nb.iter().filter(|x| x.1 != NONE).map(|x| x.1))
                .filter_map(|j| local.get(j as usize));
            let nl = match fit_normal(pts) {
                Some((nl, _)) => normalize3(&nl, 1e-9).unwrap_or(Vec3::z()),
                None => Vec3::z(),
            };
            let nl = if nl.z < 0.0 { -nl } else { nl };
            let f = self.frame;
            let nw = f.u * nl.x + f.v * nl.y + f.n * nl.z;
            mean_n += nw;
            if let Some(slot) = self.normals.get_mut(i) {
                *slot = nw;
            }
        }
        // the scene plane: the mean surface orientation (robust to a deep crevasse or a far wall in the scan,
        // which would tilt a plane fitted to the points themselves)
        let n = normalize3(&mean_n, 1e-6).unwrap_or(n0);
        let u = any_perpendicular(&n);
        let v = n.cross(&u);
        self.frame = SceneFrame { origin: c, u, v, n };
        let extent = self.project(points);
        let (amin, bmin) = self.min_ab;
        // surface grid
        self.cell = (extent / N as Real) * 1.0001;
        self.min_ab = (amin, bmin);
        for k in 0..SURFACE_MAX_VERTICES {
            if let Some(ab) = self.cell_ab.get_mut(k) {
                *ab = (0.0, 0.0);
            }
            if let (Some(h), Some(cn), Some(st), Some(ct)) =
                (self.height.get_mut(k), self.cell_normal.get_mut(k), self.state.get_mut(k), self.count.get_mut(k))
            {
                *h = 0.0;
                *cn = Vec3::zeros();
                *st = CellState::Empty;
                *ct = 0;
            }
        }
        for i in 0..count {
            let (l, nw) = match (self.local.get(i), self.normals.get(i)) {
                (Some(l), Some(nw)) => (*l, *nw),
                _ => continue,
            };
            if let Some(k) = self.cell_of(l.x, l.y) {
                if let Some(ab) = self.cell_ab.get_mut(k) {
                    ab.0 += l.x;
                    ab.1 += l.y;
                }
                if let (Some(h), Some(cn), Some(ct)) =
                    (self.height.get_mut(k), self.cell_normal.get_mut(k), self.count.get_mut(k))
                {
                    *h += l.z;
                    *cn += nw;
                    *ct = ct.saturating_add(1);
                }
            }
        }
        for k in 0..SURFACE_MAX_VERTICES {
            if let (Some(h), Some(cn), Some(st), Some(ct)) =
                (self.height.get_mut(k), self.cell_normal.get_mut(k), self.state.get_mut(k), self.count.get(k))
            {
                if *ct > 0 {
                    *h /= *ct as Real;
                    if let Some(ab) = self.cell_ab.get_mut(k) {
                        ab.0 /= *ct as Real;
                        ab.1 /= *ct as Real;
                    }
                    *cn = normalize3(cn, 1e-9).unwrap_or(n);
                    *st = CellState::Observed;
                }
            }
        }
        self.fill(params);
        Ok(())
    }

    /// Local coordinates of the finite points in the current frame; sets `min_ab` and returns the extent.
    fn project(&mut self, points: &[Vec3]) -> Real {
        let (mut amin, mut amax, mut bmin, mut bmax) = (Real::MAX, Real::MIN, Real::MAX, Real::MIN);
        let frame = self.frame;
        for (slot, p) in self.local.iter_mut().zip(points.iter().filter(|p| is_finite3(p))) {
            let l = frame.to_local(p);
            *slot = l;
            amin = amin.min(l.x);
            amax = amax.max(l.x);
            bmin = bmin.min(l.y);
            bmax = bmax.max(l.y);
        }
        self.min_ab = (amin, bmin);
        (amax - amin).max(bmax - bmin).max(1e-3)
    }

    fn bucket_of(&self, i: usize) -> usize {
        let l = self.local.get(i).copied().unwrap_or_else(Vec3::zeros);
        let bx = ((l.x - self.bucket_min.0) / self.bucket_size) as usize;
        let by = ((l.y - self.bucket_min.1) / self.bucket_size) as usize;
        by.min(KNN_BUCKETS_PER_AXIS - 1) * KNN_BUCKETS_PER_AXIS + bx.min(KNN_BUCKETS_PER_AXIS - 1)
    }

    /// The `KNN_K` nearest neighbours of point `i` (squared distance, index), ascending; unused slots `NONE`.
    fn knn(&self, i: usize, best: &mut [(Real, u32); KNN_K]) {
        let p = match self.local.get(i) {
            Some(p) => *p,
            None => return,
        };
        let b = self.bucket_of(i);
        let (bx, by) = ((b % KNN_BUCKETS_PER_AXIS) as i64, (b / KNN_BUCKETS_PER_AXIS) as i64);
        for ring in 0..KNN_BUCKETS_PER_AXIS as i64 {
            let inner = (ring - 1).max(0) as Real * self.bucket_size;
            if best.last().is_some_and(|w| w.1 != NONE && w.0 <= inner * inner) {
                break;
            }
            for dy in -ring..=ring {
                for dx in -ring..=ring {
                    if dx.abs() != ring && dy.abs() != ring {
                        continue;
                    }
                    let (x, y) = (bx + dx, by + dy);
                    if x < 0 || y < 0 || x >= KNN_BUCKETS_PER_AXIS as i64 || y >= KNN_BUCKETS_PER_AXIS as i64 {
                        continue;
                    }
                    let mut j = self.head.get(y as usize * KNN_BUCKETS_PER_AXIS + x as usize).copied().unwrap_or(NONE);
                    // each point is in exactly one bucket list: bounded by the point count
                    for _ in 0..P {
                        if j == NONE {
                            break;
                        }
                        if j as usize != i {
                            if let Some(q) = self.local.get(j as usize) {
                                let d2 = (q - p).norm_squared();
                                if best.last().is_some_and(|w| d2 < w.0) {
                                    if let Some(w) = best.last_mut() {
                                        *w = (d2, j);
                                    }
                                    // insertion: bubble the new entry towards the front (at most K steps)
                                    for k in (1..KNN_K).rev() {
                                        match (best.get(k), best.get(k - 1)) {
                                            (Some(x), Some(y)) if x.0 < y.0 => best.swap(k, k - 1),
                                            _ => break,
                                        }
                                    }
                                }
                            }
                        }
                        j = self.next.get(j as usize).copied().unwrap_or(NONE);
                    }
                }
            }
        }
    }

    /// Surface cell index of plane coordinates.
    pub fn cell_of(&self, a: Real, b: Real) -> Option<usize> {
        let i = (a - self.min_ab.0) / self.cell;
        let j = (b - self.min_ab.1) / self.cell;
        if i >= 0.0 && j >= 0.0 && (i as usize) < N && (j as usize) < N {
            Some(j as usize * N + i as usize)
        } else {
            None
        }
    }

    /// World position of a surface cell's vertex (observed: at the mean of its points; filled: at the centre).
    pub fn vertex(&self, k: usize) -> Vec3 {
        let (i, j) = (k % N, k / N);
        let (a, b) = match (self.state.get(k), self.cell_ab.get(k)) {
            (Some(CellState::Observed), Some(&ab)) => ab,
            _ => (self.min_ab.0 + (i as Real + 0.5) * self.cell, self.min_ab.1 + (j as Real + 0.5) * self.cell),
        };
        let z = self.height.get(k).copied().unwrap_or(0.0);
        self.frame.to_world(&Vec3::new(a, b, z))
    }

    fn fill(&mut self, params: &TeamParams) {
        // dilation: unknown cells next to known ones get the mean of their known neighbours
        for _ in 0..params.fill_max_cells {
            let mut changed = false;
            for k in 0..SURFACE_MAX_VERTICES {
                if self.state.get(k) != Some(&CellState::Empty) {
                    continue;
                }
                let (i, j) = ((k % N) as i64, (k / N) as i64);
                let (mut s, mut c) = (0.0 as Real, 0u32);
                for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1), (1, 1), (-1, 1), (1, -1), (-1, -1)] {
                    let (x, y) = (i + dx, j + dy);
                    if x < 0 || y < 0 || x >= N as i64 || y >= N as i64 {
                        continue;
                    }
                    let q = y as usize * N + x as usize;
                    // only cells known before this pass (count marks observed; Filled cells have count = u16::MAX - 1 sentinel)
                    if matches!(self.state.get(q), Some(CellState::Observed))
                        || (matches!(self.state.get(q), Some(CellState::Filled)) && self.count.get(q) == Some(&1))
                    {
                        s += self.height.get(q).copied().unwrap_or(0.0);
                        c += 1;
                    }
                }
                if c > 0 {
                    if let (Some(h), Some(st), Some(ct)) = (self.height.get_mut(k), self.state.get_mut(k), self.count.get_mut(k)) {
                        *h = s / c as Real;
                        *st = CellState::Filled;
                        *ct = 0; // becomes usable as a source in the next pass
                    }
                    changed = true;
                }
            }
            for k in 0..SURFACE_MAX_VERTICES {
                if self.state.get(k) == Some(&CellState::Filled) {
                    if let Some(ct) = self.count.get_mut(k) {
                        *ct = 1;
                    }
                }
            }
            if !changed {
                break;
            }
        }
        // membrane relaxation over the filled cells, observed cells fixed
        for _ in 0..params.fill_sweeps {
            for k in 0..SURFACE_MAX_VERTICES {
                if self.state.get(k) != Some(&CellState::Filled) {
                    continue;
                }
                let (i, j) = ((k % N) as i64, (k / N) as i64);
                let (mut s, mut c) = (0.0 as Real, 0u32);
                for (dx, dy) in [(1, 0), (-1, 0), (0, 1), (0, -1)] {
                    let (x, y) = (i + dx, j + dy);
                    if x < 0 || y < 0 || x >= N as i64 || y >= N as i64 {
                        continue;
                    }
                    let q = y as usize * N + x as usize;
                    if self.state.get(q) != Some(&CellState::Empty) {
                        s += self.height.get(q).copied().unwrap_or(0.0);
                        c += 1;
                    }
                }
                if c > 0 {
                    if let Some(h) = self.height.get_mut(k) {
                        *h = s / c as Real;
                    }
                }
            }
        }
        // normals of filled cells from the height gradient
        let n = self.frame.n;
        let (u, v) = (self.frame.u, self.frame.v);
        for k in 0..SURFACE_MAX_VERTICES {
            if self.state.get(k) != Some(&CellState::Filled) {
                continue;
            }
            let (i, j) = ((k % N) as i64, (k / N) as i64);
            let hz = |x: i64, y: i64| -> Option<Real> {
                if x < 0 || y < 0 || x >= N as i64 || y >= N as i64 {
                    return None;
                }
                let q = y as usize * N + x as usize;
                if self.state.get(q) == Some(&CellState::Empty) {
                    None
                } else {
                    self.height.get(q).copied()
                }
            };
            let h0 = hz(i, j).unwrap_or(0.0);
            let da = match (hz(i + 1, j), hz(i - 1, j)) {
                (Some(p), Some(m)) => (p - m) / (2.0 * self.cell),
                (Some(p), None) => (p - h0) / self.cell,
                (None, Some(m)) => (h0 - m) / self.cell,
                _ => 0.0,
            };
            let db = match (hz(i, j + 1), hz(i, j - 1)) {
                (Some(p), Some(m)) => (p - m) / (2.0 * self.cell),
                (Some(p), None) => (p - h0) / self.cell,
                (None, Some(m)) => (h0 - m) / self.cell,
                _ => 0.0,
            };
            let nw = n - u * da - v * db;
            if let Some(cn) = self.cell_normal.get_mut(k) {
                *cn = normalize3(&nw, 1e-9).unwrap_or(n);
            }
        }
        let _ = norm3(&n);
    }
}

impl<const P: usize> Default for Scene<P> {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use crate::config::team::SCENE_MAX_POINTS;
    use std::boxed::Box;

    #[test]
    fn jacobi_finds_smallest_eigenvector() {
        let (v, ev) = smallest_eigenvector([[4.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 9.0]]).unwrap();
        assert!((libm::fabsf(v.y) - 1.0).abs() < 1e-5);
        assert!((ev[0] - 1.0).abs() < 1e-5 && (ev[2] - 9.0).abs() < 1e-5);
    }

    #[test]
    fn tilted_plane_normals_and_flat_surface() {
        // points on the plane z = 0.5 x (a 26.6 degree slope), sensor above
        let mut pts = [Vec3::zeros(); 400];
        for (k, p) in pts.iter_mut().enumerate() {
            let (x, y) = ((k % 20) as Real * 0.5, (k / 20) as Real * 0.5);
            *p = Vec3::new(x, y, 0.5 * x);
        }
        let mut s: Box<Scene<SCENE_MAX_POINTS>> = Box::default();
        s.build(&pts, &Vec3::z(), &TeamParams::DEFAULT).unwrap();
        let expect = normalize3(&Vec3::new(-0.5, 0.0, 1.0), 1e-9).unwrap();
        assert!(s.frame.n.dot(&expect) > 0.9999, "{:?}", s.frame.n);
        for i in 0..400 {
            assert!(s.normals[i].dot(&expect) > 0.999, "point {i}: {:?}", s.normals[i]);
        }
        for k in 0..SURFACE_MAX_VERTICES {
            if s.state[k] != CellState::Empty {
                assert!(libm::fabsf(s.height[k]) < 1e-3);
            }
        }
        assert_eq!(s.build(&pts[..2], &Vec3::zeros(), &TeamParams::DEFAULT), Err(SceneError::TooFewPoints));
    }
}
