//! The simulated range sensor (stereo- or lidar-like), ray-cast into a ground-truth [`World`].
//!
//! Rays cover a rectangular field of view in azimuth x elevation at a fixed angular resolution, in the sensor
//! frame (x forward, y left, z up). Each return gets seeded Gaussian range noise and may drop out; returns beyond
//! `max_range_m` (or before `min_range_m`) are absent, as from a real sensor. The sensor is mounted on the rover
//! at `mount` (rover frame). A scan becomes protocol [`SensorChunk`]s of at most
//! [`MAX_POINTS_PER_CHUNK`] points each ([`Scan::to_chunks`]).
//!
//! The host never sends a non-finite point (the flight side Nacks a whole chunk holding one, `NonFinite`):
//! [`scan`] drops a return whose range is not finite (a world's ray cast gone wrong), and [`Scan::to_chunks`]
//! drops any non-finite point a caller put in a [`Scan`], says so (`log::warn!`) and counts it
//! ([`Scan::non_finite_points`]); a non-finite sensor pose is an error, not a chunk.
//!
//! Parameters (defaults): `h_fov_deg` 90, `v_fov_deg` 60, `resolution_deg` 1.0 (91 x 61 = 5551 rays, within the
//! protocol's `SCAN_POINTS_CAPACITY` of 8192), `min_range_m` 0.3, `max_range_m` 8.0, `noise_sigma_m` 0.005,
//! `dropout_probability` 0.02, mount 0.5 m above the rover origin pitched 30 degrees down.

use crate::world::World;
use firmware::config::protocol::{MAX_CHUNKS_PER_SCAN, MAX_POINTS_PER_CHUNK};
use firmware::geom::{Pose3, Real, Rot3, Vec3};
use firmware::protocol::{Point3, Pose, Quat, SensorChunk};
use rand_core::Rng;

/// Range sensor parameters.
#[derive(Debug, Clone, PartialEq, serde::Deserialize, serde::Serialize)]
#[serde(default, deny_unknown_fields)]
pub struct RangeSensorParams {
    /// Horizontal field of view, degrees. Default 90.
    pub h_fov_deg: f64,
    /// Vertical field of view, degrees. Default 60.
    pub v_fov_deg: f64,
    /// Angular step between rays, degrees. Default 1.0.
    pub resolution_deg: f64,
    /// Nearest return, metres. Default 0.3.
    pub min_range_m: f64,
    /// Farthest return, metres. Default 8.0.
    pub max_range_m: f64,
    /// Standard deviation of the range noise, metres. Default 0.005.
    pub noise_sigma_m: f64,
    /// Probability that a return is dropped. Default 0.02.
    pub dropout_probability: f64,
    /// Mount position in the rover frame, metres. Default [0, 0, 0.5].
    pub mount_xyz_m: [f64; 3],
    /// Mount pitch (positive looks down), degrees. Default 30.
    pub mount_pitch_down_deg: f64,
}

impl Default for RangeSensorParams {
    fn default() -> Self {
        RangeSensorParams {
            h_fov_deg: 90.0,
            v_fov_deg: 60.0,
            resolution_deg: 1.0,
            min_range_m: 0.3,
            max_range_m: 8.0,
            noise_sigma_m: 0.005,
            dropout_probability: 0.02,
            mount_xyz_m: [0.0, 0.0, 0.5],
            mount_pitch_down_deg: 30.0,
        }
    }
}

impl RangeSensorParams {
    /// Checks the parameters; the error names the field and the reason.
    pub fn validate(&self) -> Result<(), (&'static str, String)> {
        let fov = |v: f64| v.is_finite() && v > 0.0 && v <= 360.0;
        if !fov(self.h_fov_deg) {
            return Err(("h_fov_deg", format!("must be in (0, 360], got {}", self.h_fov_deg)));
        }
        if !(self.v_fov_deg.is_finite() && self.v_fov_deg > 0.0 && self.v_fov_deg <= 180.0) {
            return Err(("v_fov_deg", format!("must be in (0, 180], got {}", self.v_fov_deg)));
        }
        if !(self.resolution_deg.is_finite() && self.resolution_deg >= 0.05) {
            return Err(("resolution_deg", format!("must be >= 0.05, got {}", self.resolution_deg)));
        }
        if !(self.min_range_m >= 0.0 && self.max_range_m.is_finite() && self.max_range_m > self.min_range_m) {
            return Err(("max_range_m", format!("need 0 <= min_range_m < max_range_m, got {} / {}", self.min_range_m, self.max_range_m)));
        }
        if !(self.noise_sigma_m >= 0.0 && self.noise_sigma_m.is_finite()) {
            return Err(("noise_sigma_m", format!("must be >= 0, got {}", self.noise_sigma_m)));
        }
        if !(0.0..=1.0).contains(&self.dropout_probability) {
            return Err(("dropout_probability", format!("must be in [0, 1], got {}", self.dropout_probability)));
        }
        if self.mount_xyz_m.iter().any(|v| !v.is_finite()) || !self.mount_pitch_down_deg.is_finite() {
            return Err(("mount_xyz_m", "mount must be finite".into()));
        }
        if self.ray_count() > firmware::config::protocol::SCAN_POINTS_CAPACITY {
            return Err((
                "resolution_deg",
                format!("{} rays exceed the protocol's scan capacity of {}", self.ray_count(), firmware::config::protocol::SCAN_POINTS_CAPACITY),
            ));
        }
        Ok(())
    }

    fn steps(&self) -> (usize, usize) {
        ((self.h_fov_deg / self.resolution_deg).floor() as usize + 1, (self.v_fov_deg / self.resolution_deg).floor() as usize + 1)
    }

    /// Rays per scan.
    pub fn ray_count(&self) -> usize {
        let (h, v) = self.steps();
        h * v
    }

    /// The mount transform (sensor frame to rover frame).
    pub fn mount(&self) -> Pose3 {
        let m = self.mount_xyz_m;
        Pose3::from_parts(
            Vec3::new(m[0] as Real, m[1] as Real, m[2] as Real).into(),
            Rot3::from_euler_angles(0.0, self.mount_pitch_down_deg.to_radians() as Real, 0.0),
        )
    }
}

/// One scan: the sensor's pose in the world and the returns in the sensor frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Scan {
    /// Sensor frame to world frame.
    pub sensor_pose: Pose3,
    /// Returns, sensor frame, metres.
    pub points: Vec<Vec3>,
}

/// A scan that cannot become protocol chunks.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ChunkError {
    /// More (finite) points than the protocol's chunking limits hold.
    TooManyPoints {
        /// Points in the scan.
        points: usize,
        /// Largest number that fits.
        capacity: usize,
    },
    /// The sensor pose is not finite: every point would be garbage on the flight side.
    NonFinitePose,
}

impl core::fmt::Display for ChunkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ChunkError::TooManyPoints { points, capacity } => {
                write!(f, "{points} points do not fit the protocol's {capacity} points per scan")
            }
            ChunkError::NonFinitePose => write!(f, "the sensor pose is not finite"),
        }
    }
}

/// Uniform in [0, 1).
fn unit(rng: &mut impl Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// Standard normal (Box-Muller).
fn gaussian(rng: &mut impl Rng) -> f64 {
    let u1 = unit(rng).max(1e-300);
    let u2 = unit(rng);
    (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
}

/// Takes one scan of `world` from a rover at `rover_pose`.
pub fn scan(world: &dyn World, params: &RangeSensorParams, rover_pose: &Pose3, rng: &mut impl Rng) -> Scan {
    let sensor_pose = rover_pose * params.mount();
    let origin = sensor_pose.translation.vector;
    let (nh, nv) = params.steps();
    let mut points = Vec::with_capacity(nh * nv);
    for iv in 0..nv {
        let el = (-params.v_fov_deg / 2.0 + iv as f64 * params.resolution_deg).to_radians();
        for ih in 0..nh {
            let az = (-params.h_fov_deg / 2.0 + ih as f64 * params.resolution_deg).to_radians();
            let d_s = Vec3::new((el.cos() * az.cos()) as Real, (el.cos() * az.sin()) as Real, el.sin() as Real);
            let d_w = sensor_pose.rotation * d_s;
            // Draw noise and dropout for every ray so the random sequence does not depend on the hits.
            let noise = gaussian(rng) * params.noise_sigma_m;
            let drop = unit(rng) < params.dropout_probability;
            let Some(t) = world.raycast(&origin, &d_w, params.max_range_m as Real) else { continue };
            let r = t as f64 + noise;
            // A NaN range fails the range test too: it is dropped, never sent.
            if drop || !(r >= params.min_range_m && r <= params.max_range_m) {
                continue;
            }
            points.push(d_s * r as Real);
        }
    }
    Scan { sensor_pose, points }
}

/// Converts an `nalgebra` pose to the protocol's pose.
pub fn to_wire_pose(p: &Pose3) -> Pose {
    let t = p.translation.vector;
    let q = p.rotation.quaternion();
    Pose { position: Point3::new(t.x, t.y, t.z), orientation: Quat { x: q.i, y: q.j, z: q.k, w: q.w } }
}

impl Scan {
    /// Points of the scan that are not finite (dropped by [`Scan::to_chunks`]).
    pub fn non_finite_points(&self) -> usize {
        self.points.iter().filter(|p| !p.iter().all(|c| c.is_finite())).count()
    }

    /// Splits the scan's finite points into protocol chunks of at most `max_points` points (clamped to
    /// `1..=MAX_POINTS_PER_CHUNK`); non-finite points are dropped with a warning (see the module docs). A scan
    /// with more than `MAX_CHUNKS_PER_SCAN` chunks, or with a non-finite sensor pose, is refused.
    pub fn to_chunks(&self, scan_id: u32, max_points: usize) -> Result<Vec<SensorChunk>, ChunkError> {
        let pose = to_wire_pose(&self.sensor_pose);
        let finite_pose = [pose.position.x, pose.position.y, pose.position.z]
            .iter()
            .chain([pose.orientation.x, pose.orientation.y, pose.orientation.z, pose.orientation.w].iter())
            .all(|c| c.is_finite());
        if !finite_pose {
            return Err(ChunkError::NonFinitePose);
        }
        let dropped = self.non_finite_points();
        if dropped > 0 {
            log::warn!("scan {scan_id}: dropped {dropped} non-finite point(s) of {} before sending", self.points.len());
        }
        let finite: Vec<&Vec3> = self.points.iter().filter(|p| p.iter().all(|c| c.is_finite())).collect();
        let n = max_points.clamp(1, MAX_POINTS_PER_CHUNK);
        let count = finite.len().div_ceil(n).max(1);
        if count > MAX_CHUNKS_PER_SCAN as usize {
            return Err(ChunkError::TooManyPoints { points: finite.len(), capacity: n * MAX_CHUNKS_PER_SCAN as usize });
        }
        let mut out = Vec::with_capacity(count);
        for k in 0..count {
            let mut points = heapless::Vec::new();
            for p in finite.iter().skip(k * n).take(n) {
                // Cannot fail: at most n <= MAX_POINTS_PER_CHUNK points per chunk.
                let _ = points.push(Point3::new(p.x, p.y, p.z));
            }
            out.push(SensorChunk {
                scan_id,
                chunk_index: k as u16,
                chunk_count: count as u16,
                sensor_pose: pose,
                points,
            });
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::crater::{CraterWall, CraterWallParams};
    use firmware::map::{DistanceField, DistanceQuery};

    fn rover_on_rim() -> Pose3 {
        Pose3::from_parts(Vec3::new(-2.0, 0.0, 6.0).into(), Rot3::identity())
    }

    #[test]
    fn noiseless_returns_lie_on_the_surface_and_scans_are_seeded() {
        let w = CraterWall::new(CraterWallParams::default()).unwrap();
        let mut p = RangeSensorParams { noise_sigma_m: 0.0, dropout_probability: 0.0, ..Default::default() };
        let mut rng = rand_pcg::Pcg32::new(1, 1);
        let s = scan(&w, &p, &rover_on_rim(), &mut rng);
        assert!(s.points.len() > 1000, "{}", s.points.len());
        for q in &s.points {
            let pw = s.sensor_pose.transform_point(&(*q).into()).coords;
            match w.query(&pw) {
                DistanceQuery::Known { distance, .. } => assert!(distance.abs() < 2e-3, "{distance}"),
                DistanceQuery::Unknown => unreachable!(),
            }
        }
        p.noise_sigma_m = 0.01;
        p.dropout_probability = 0.1;
        let a = scan(&w, &p, &rover_on_rim(), &mut rand_pcg::Pcg32::new(5, 1));
        let b = scan(&w, &p, &rover_on_rim(), &mut rand_pcg::Pcg32::new(5, 1));
        let c = scan(&w, &p, &rover_on_rim(), &mut rand_pcg::Pcg32::new(6, 1));
        assert_eq!(a, b);
        assert_ne!(a, c);
        // About 10 % dropped.
        let ratio = a.points.len() as f64 / s.points.len() as f64;
        assert!((0.85..0.95).contains(&ratio), "{ratio}");
    }

    #[test]
    fn chunks_respect_the_protocol_limits_and_keep_every_point() {
        let w = CraterWall::new(CraterWallParams::default()).unwrap();
        let s = scan(&w, &RangeSensorParams::default(), &rover_on_rim(), &mut rand_pcg::Pcg32::new(2, 2));
        let chunks = s.to_chunks(7, 100).unwrap();
        assert_eq!(chunks.len(), s.points.len().div_ceil(100));
        let mut all = Vec::new();
        for (k, c) in chunks.iter().enumerate() {
            assert_eq!((c.scan_id, c.chunk_index as usize, c.chunk_count as usize), (7, k, chunks.len()));
            assert!(c.points.len() <= 100);
            all.extend(c.points.iter().map(|p| Vec3::new(p.x, p.y, p.z)));
        }
        assert_eq!(all, s.points);
        let big = Scan { sensor_pose: Pose3::identity(), points: vec![Vec3::zeros(); 64 * 128 + 1] };
        assert!(matches!(big.to_chunks(1, 128), Err(ChunkError::TooManyPoints { .. })));
        let e = RangeSensorParams { resolution_deg: 0.2, ..Default::default() }.validate().unwrap_err();
        assert_eq!(e.0, "resolution_deg");
    }

    /// Regression (issue 24): one NaN point made the flight side Nack every chunk of its scan (`NonFinite`). The
    /// host drops the point, counts it and sends the rest; a non-finite pose is refused.
    #[test]
    fn non_finite_points_are_dropped_and_counted_never_sent() {
        let mut points: Vec<Vec3> = (0..300).map(|i| Vec3::new(1.0 + i as Real * 0.01, 0.0, 0.5)).collect();
        points[17].x = Real::NAN;
        points[250].z = Real::INFINITY;
        let s = Scan { sensor_pose: Pose3::identity(), points: points.clone() };
        assert_eq!(s.non_finite_points(), 2);
        let chunks = s.to_chunks(3, 100).unwrap();
        let sent: Vec<Vec3> = chunks.iter().flat_map(|c| c.points.iter().map(|p| Vec3::new(p.x, p.y, p.z))).collect();
        let finite: Vec<Vec3> = points.into_iter().filter(|p| p.iter().all(|c| c.is_finite())).collect();
        assert_eq!(sent, finite);
        assert_eq!(sent.len(), 298);
        let mut bad = s.clone();
        bad.sensor_pose.translation.vector.x = Real::NAN;
        assert_eq!(bad.to_chunks(3, 100).unwrap_err(), ChunkError::NonFinitePose);
    }
}
