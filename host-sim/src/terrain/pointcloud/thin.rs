//! Voxel-grid thinning of a point cloud to a capacity (by default the flight scan capacity, 4096 points).
//!
//! The grid is anchored at the cloud's minimum corner; a point's voxel is `floor((p - min) / edge)` per axis. Each
//! occupied voxel gives one point: by default ([`Representative::NearestToCentre`]) the input point nearest the
//! voxel's centre (ties: the earlier point in the input), so every output point is a measured one; or
//! ([`Representative::Centroid`]) the mean of the voxel's points, which lies within half a voxel diagonal of one
//! of them (its squared distance to the nearest is at most the voxel's variance, at most 3 edge^2 / 4).
//!
//! Edge choice: a cloud that already fits is returned unchanged ([`Thinned::voxel_edge`] is `None`). Otherwise
//! the edge starts at the bounding-box diagonal / capacity, doubles until the occupied voxels fit, then 20
//! bisection steps (geometric mean) between the last edge that did not fit and the first that did bring it to the
//! smallest edge found that fits, keeping as many points as the capacity allows. Occupancy counts sort the voxel
//! keys (no hashing), and the output is in ascending voxel order (x, then y, then z): the same input gives the same
//! output, bit for bit.

use super::FLIGHT_SCAN_CAPACITY;
use core::fmt;

/// Which point stands for an occupied voxel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Representative {
    /// The input point nearest the voxel centre (default): output points are input points.
    #[default]
    NearestToCentre,
    /// The mean of the voxel's points.
    Centroid,
}

/// Thinning options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThinOptions {
    /// Most points in the output; > 0. Default [`FLIGHT_SCAN_CAPACITY`].
    pub capacity: usize,
    /// The point kept per voxel. Default [`Representative::NearestToCentre`].
    pub representative: Representative,
}

impl Default for ThinOptions {
    fn default() -> Self {
        Self { capacity: FLIGHT_SCAN_CAPACITY, representative: Representative::NearestToCentre }
    }
}

/// A thinned cloud.
#[derive(Debug, Clone, PartialEq)]
pub struct Thinned {
    /// At most `capacity` points, one per occupied voxel, in ascending voxel order.
    pub points: Vec<[f64; 3]>,
    /// The voxel edge used, in the cloud's units; `None` when the input already fit and was kept as it is.
    pub voxel_edge: Option<f64>,
}

/// Why a cloud could not be thinned.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ThinError {
    /// The capacity is zero.
    ZeroCapacity,
    /// Input point `index` has a NaN or infinite coordinate.
    NonFinite {
        /// Index into the input.
        index: usize,
    },
}

impl fmt::Display for ThinError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ThinError::ZeroCapacity => write!(f, "thinning capacity must be > 0"),
            ThinError::NonFinite { index } => write!(f, "point {index} has a non-finite coordinate"),
        }
    }
}

impl core::error::Error for ThinError {}

/// Bisection steps between the last edge too small and the first that fits.
const BISECTION_STEPS: usize = 20;

/// Thin `points` to at most `opts.capacity` points on a voxel grid (see the module docs).
pub fn thin_to_capacity(points: &[[f64; 3]], opts: &ThinOptions) -> Result<Thinned, ThinError> {
    if opts.capacity == 0 {
        return Err(ThinError::ZeroCapacity);
    }
    if let Some(index) = points.iter().position(|p| !p.iter().all(|c| c.is_finite())) {
        return Err(ThinError::NonFinite { index });
    }
    let Some((lo, hi)) = super::bounds(points) else {
        return Ok(Thinned { points: Vec::new(), voxel_edge: None });
    };
    if points.len() <= opts.capacity {
        return Ok(Thinned { points: points.to_vec(), voxel_edge: None });
    }
    let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
    let fits = |edge: f64| occupied(points, lo, edge) <= opts.capacity;
    // a cloud of one repeated point fits one voxel of any edge
    let mut edge = if diagonal > 0.0 { diagonal / opts.capacity as f64 } else { 1.0 };
    let mut too_small = None;
    while !fits(edge) {
        too_small = Some(edge);
        edge *= 2.0;
    }
    if let Some(mut small) = too_small {
        for _ in 0..BISECTION_STEPS {
            let mid = (small * edge).sqrt();
            if fits(mid) {
                edge = mid;
            } else {
                small = mid;
            }
        }
    }
    Ok(Thinned { points: representatives(points, lo, edge, opts.representative), voxel_edge: Some(edge) })
}

type Key = [i64; 3];

/// The voxel of `p` on the grid anchored at `origin` (saturating casts: no overflow for any finite input).
fn voxel(p: &[f64; 3], origin: [f64; 3], edge: f64) -> Key {
    [0, 1, 2].map(|k| ((p[k] - origin[k]) / edge).floor() as i64)
}

/// Occupied voxels at this edge.
fn occupied(points: &[[f64; 3]], origin: [f64; 3], edge: f64) -> usize {
    let mut keys: Vec<Key> = points.iter().map(|p| voxel(p, origin, edge)).collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// One point per occupied voxel, in ascending voxel order.
fn representatives(points: &[[f64; 3]], origin: [f64; 3], edge: f64, rep: Representative) -> Vec<[f64; 3]> {
    let mut keyed: Vec<(Key, usize)> = points.iter().enumerate().map(|(i, p)| (voxel(p, origin, edge), i)).collect();
    keyed.sort_unstable();
    keyed
        .chunk_by(|a, b| a.0 == b.0)
        .filter_map(|group| {
            let key = group.first()?.0;
            let members = group.iter().filter_map(|&(_, i)| points.get(i));
            Some(match rep {
                Representative::NearestToCentre => {
                    let centre = [0, 1, 2].map(|k| origin[k] + (key[k] as f64 + 0.5) * edge);
                    let d2 = |p: &[f64; 3]| (0..3).map(|k| (p[k] - centre[k]).powi(2)).sum::<f64>();
                    // `min_by` keeps the first of equal elements: ties go to the earlier input point
                    *members.min_by(|a, b| d2(a).total_cmp(&d2(b)))?
                }
                Representative::Centroid => {
                    let n = group.len() as f64;
                    let sum = members.fold([0.0; 3], |s, p| [s[0] + p[0], s[1] + p[1], s[2] + p[2]]);
                    sum.map(|c| c / n)
                }
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic pseudo-random cloud: a wavy 40 m x 30 m slope with 0.2 m noise (a terrain scan's shape).
    fn cloud(n: usize) -> Vec<[f64; 3]> {
        let mut s = 0x9e37_79b9_7f4a_7c15u64;
        let mut r = move || {
            s ^= s << 13;
            s ^= s >> 7;
            s ^= s << 17;
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| {
                let (x, y) = (40.0 * r(), 30.0 * r());
                [x, y, 0.3 * x + (x / 3.0).sin() * 2.0 + 0.2 * r()]
            })
            .collect()
    }

    fn nearest(p: &[f64; 3], points: &[[f64; 3]]) -> f64 {
        points.iter().map(|q| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<f64>().sqrt()).fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn thins_to_the_flight_capacity_near_the_input() {
        let pts = cloud(30_000);
        for rep in [Representative::NearestToCentre, Representative::Centroid] {
            let opts = ThinOptions { representative: rep, ..ThinOptions::default() };
            let t = thin_to_capacity(&pts, &opts).unwrap();
            let edge = t.voxel_edge.unwrap();
            println!("30 000 points -> {} ({rep:?}), voxel edge {edge:.4} m", t.points.len());
            assert!(t.points.len() <= FLIGHT_SCAN_CAPACITY, "{}", t.points.len());
            // the bisection keeps most of the capacity (a coarser grid than needed would keep far fewer)
            assert!(t.points.len() > FLIGHT_SCAN_CAPACITY * 3 / 4, "{rep:?}: {} points, edge {edge}", t.points.len());
            let half_diagonal = edge * 3f64.sqrt() / 2.0;
            for p in &t.points {
                let d = nearest(p, &pts);
                match rep {
                    Representative::NearestToCentre => assert_eq!(d, 0.0),
                    Representative::Centroid => assert!(d <= half_diagonal, "{p:?}: {d} > {half_diagonal}"),
                }
            }
            // one point per voxel, in ascending voxel order
            let lo = crate::terrain::pointcloud::bounds(&pts).unwrap().0;
            let keys: Vec<Key> = t.points.iter().map(|p| voxel(p, lo, edge)).collect();
            assert!(keys.windows(2).all(|w| w[0] < w[1]), "{rep:?}: voxels not strictly ascending");
            assert_eq!(thin_to_capacity(&pts, &opts).unwrap(), t, "deterministic");
        }
    }

    #[test]
    fn input_order_does_not_change_the_nearest_to_centre_output() {
        let pts = cloud(10_000);
        let mut reversed = pts.clone();
        reversed.reverse();
        let opts = ThinOptions { capacity: 500, ..ThinOptions::default() };
        let a = thin_to_capacity(&pts, &opts).unwrap();
        let b = thin_to_capacity(&reversed, &opts).unwrap();
        assert_eq!(a, b);
        assert!(a.points.len() <= 500);
    }

    #[test]
    fn edge_cases() {
        let same = vec![[1.0, 2.0, 3.0]; 10];
        let t = thin_to_capacity(&same, &ThinOptions { capacity: 3, ..ThinOptions::default() }).unwrap();
        assert_eq!(t.points, vec![[1.0, 2.0, 3.0]]);
        let small = cloud(5);
        assert_eq!(thin_to_capacity(&small, &ThinOptions::default()).unwrap().points, small);
        assert!(thin_to_capacity(&[], &ThinOptions::default()).unwrap().points.is_empty());
        let zero = ThinOptions { capacity: 0, ..ThinOptions::default() };
        assert_eq!(thin_to_capacity(&small, &zero), Err(ThinError::ZeroCapacity));
        let mut bad = small.clone();
        bad[3][1] = f64::NAN;
        assert_eq!(thin_to_capacity(&bad, &ThinOptions::default()), Err(ThinError::NonFinite { index: 3 }));
        // far-apart points (an edge near the f64 range) stay finite and within capacity
        let far = vec![[-1e300, 0.0, 0.0], [1e300, 0.0, 0.0], [0.0, 1e300, -1e300], [5.0, 5.0, 5.0]];
        let t = thin_to_capacity(&far, &ThinOptions { capacity: 2, ..ThinOptions::default() }).unwrap();
        assert!(!t.points.is_empty() && t.points.len() <= 2, "{t:?}");
    }
}
