//! Sensing in the loop (issue 18, item 2): range scans from the true pose sent with a pose estimate that carries
//! the localisation error, tether readings with noise, and the overview scan from the root anchor's mast.
//!
//! ## Localisation error ([`Localiser`])
//! The estimate of the body pose is the true pose with, in x and y: a constant **bias** (drawn once per seed,
//! sigma `loc_bias_m`), a **drift** (a random walk growing with the distance driven, sigma `loc_drift_per_m` per
//! square-root metre) and white **noise** per estimate (sigma `loc_noise_m`); the heading gets white noise (sigma
//! `loc_yaw_noise_deg`). Height is not disturbed (the flight software settles the rover under the estimate
//! anyway). A scan is ray-cast from the **true** pose but sent with the **estimated** sensor pose, so the map is
//! built in the estimate's frame, as on a real rover.
//!
//! ## Tether readings ([`tether_reading`])
//! Payout = the true tether's length, tension = the statics' tension, boom angle = the tether's angle in the
//! rover's x-z plane (the boom points inline at the last contact); each with white noise (`payout_noise_m`,
//! `tension_noise_n`, `boom_noise_deg`), payout and tension clamped at 0 (a real encoder reads no negative
//! length).
//!
//! ## Overview scan ([`overview_scan`])
//! The onboard planner needs observed space above the terrain (its surface search starts at the top of the
//! planning bounds) and at the root anchor (the tether sweep of anchor prediction). A rover-mounted sensor alone
//! does not observe either. So, before the goal, a sensor 0.3 m above the root anchor (on the mast or lander that
//! holds the tether, or at `overview_eye`: a survey mast on the lander; its pose is surveyed, so it is sent without localisation error) scans 60 degrees wide
//! towards the goal, from [`OVERVIEW_ABOVE_GOAL_DEG`] above the goal's direction down past the nadir (100 degrees below the
//! horizon: the ground under the mast, where the rover starts), at `overview_resolution_deg` (0.5: one ray per
//! 5 cm voxel at 6 m), out to 3 times the goal's distance (at least 15 m), in tiles of at
//! most 8000 rays (one scan each). The rover's own sensor is the scenario's `[sensor]`; the
//! mission scenarios mount it on a mast (`mount_xyz_m`).

use firmware::geom::{Pose3, Real, Rot3, Vec3};
use firmware::geom::p3::{dot, sub, unit_or, P3};
use firmware::protocol::TetherReading;
use rand_core::Rng;

use super::executor::TrueRover;
use super::params::MissionSection;
use crate::sensor::{scan, RangeSensorParams, Scan};
use crate::world::World;

/// Uniform in [0, 1).
fn unit(rng: &mut impl Rng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// Standard normal (Box-Muller).
pub fn gaussian(rng: &mut impl Rng) -> f64 {
    let u1 = unit(rng).max(1e-300);
    let u2 = unit(rng);
    (-2.0 * u1.ln()).sqrt() * (core::f64::consts::TAU * u2).cos()
}

/// The localisation error model (module docs).
#[derive(Debug, Clone)]
pub struct Localiser {
    bias: [f64; 2],
    walk: [f64; 2],
    drift: f64,
    noise: f64,
    yaw_noise: f64,
    rng: rand_pcg::Pcg64,
}

impl Localiser {
    /// A localiser for `m`'s error model, seeded.
    pub fn new(m: &MissionSection, seed: u64) -> Self {
        let mut rng = rand_pcg::Pcg64::new(u128::from(seed) ^ 0x6c6f_6361_6c69_7365, 0x0a02_bdbf_7bb3_c0a7);
        let bias = [gaussian(&mut rng) * m.loc_bias_m, gaussian(&mut rng) * m.loc_bias_m];
        Localiser {
            bias,
            walk: [0.0; 2],
            drift: m.loc_drift_per_m,
            noise: m.loc_noise_m,
            yaw_noise: m.loc_yaw_noise_deg.to_radians(),
            rng,
        }
    }

    /// The rover drove `ds` metres: the drift walks.
    pub fn moved(&mut self, ds: f64) {
        let s = self.drift * ds.abs().sqrt();
        for w in &mut self.walk {
            *w += gaussian(&mut self.rng) * s;
        }
    }

    /// The current position error without noise (bias + drift), metres.
    pub fn offset(&self) -> [f64; 2] {
        [self.bias[0] + self.walk[0], self.bias[1] + self.walk[1]]
    }

    /// An estimate of the true body pose.
    pub fn estimate(&mut self, truth: &Pose3) -> Pose3 {
        let o = self.offset();
        let (nx, ny) = (gaussian(&mut self.rng) * self.noise, gaussian(&mut self.rng) * self.noise);
        let yaw = gaussian(&mut self.rng) * self.yaw_noise;
        let t = truth.translation.vector + Vec3::new((o[0] + nx) as Real, (o[1] + ny) as Real, 0.0);
        let r = Rot3::from_axis_angle(&Vec3::z_axis(), yaw as Real) * truth.rotation;
        Pose3::from_parts(t.into(), r)
    }
}

/// A tether reading of `rover`'s truth at `time_us`, with `m`'s noise.
pub fn tether_reading(rover: &TrueRover, root: P3, time_us: u64, m: &MissionSection, rng: &mut impl Rng) -> TetherReading {
    let u = unit_or(sub(rover.tether.last_anchor(root), rover.axle()), [0.0, 0.0, 1.0]);
    let beta = dot(u, rover.axis(2)).atan2(dot(u, rover.axis(0)));
    let payout = rover.tether.length_m + gaussian(rng) * m.payout_noise_m;
    let tension = rover.statics.tension_n + gaussian(rng) * m.tension_noise_n;
    let boom = beta + gaussian(rng) * m.boom_noise_deg.to_radians();
    TetherReading {
        time_us,
        payout_m: payout.max(0.0) as f32,
        tension_n: tension.max(0.0) as f32,
        boom_angle_rad: firmware::geom::wrap_angle(boom as Real),
    }
}

/// A scan of `world` from the true body pose `truth`, re-stamped with the estimated body pose `estimate`.
pub fn rover_scan(world: &dyn World, sensor: &RangeSensorParams, truth: &Pose3, estimate: &Pose3, rng: &mut impl Rng) -> Scan {
    let mut s = scan(world, sensor, truth, rng);
    s.sensor_pose = estimate * sensor.mount();
    s
}

/// Points per overview tile at most (within the protocol's 8192-point scan).
pub const OVERVIEW_TILE_POINTS: usize = 8000;
/// The overview looks this far above the goal's direction, degrees (rays past the goal observe the space above it).
pub const OVERVIEW_ABOVE_GOAL_DEG: f64 = 25.0;
/// The overview's range: this many times the goal's distance from the mast (rays beyond the goal carve the space above
/// it), at least [`OVERVIEW_MIN_RANGE_M`].
pub const OVERVIEW_RANGE_FACTOR: f64 = 3.0;
/// Smallest range of the overview, metres.
pub const OVERVIEW_MIN_RANGE_M: f64 = 15.0;
/// Horizontal field of view of the overview, degrees.
pub const OVERVIEW_H_FOV_DEG: f64 = 60.0;
/// The overview looks down to this depression below the horizon, degrees (past the nadir: the ground under and
/// just behind the mast, where the rover starts).
pub const OVERVIEW_MAX_DEPRESSION_DEG: f64 = 100.0;

/// The overview sensor's tiles (module docs): at `[mission] overview_eye` (default: on the mast 0.3 m above `root`),
/// facing the goal, from 25 degrees above the goal's direction down past the nadir ([`OVERVIEW_MAX_DEPRESSION_DEG`]),
/// [`OVERVIEW_H_FOV_DEG`] wide, at `overview_resolution_deg`, split into tiles of at most [`OVERVIEW_TILE_POINTS`]
/// rays (one scan each). When the rover's start lies outside that view (a mast ahead of the rover, facing a goal
/// beyond it), the same sweep facing the start follows: the flight software cannot plan from ground it has not
/// seen, and the rover's own sensor looks ahead of it, not under it.
pub fn overview_sensor(root: P3, goal: P3, start: P3, rover_sensor: &RangeSensorParams, m: &MissionSection) -> Vec<(RangeSensorParams, Pose3)> {
    let eye = m.overview_eye.unwrap_or([root[0], root[1], root[2] + 0.3]);
    let mut tiles = overview_sweep(eye, goal, rover_sensor, m);
    if !overview_sees(eye, goal, start) {
        tiles.extend(overview_sweep(eye, start, rover_sensor, m));
    }
    tiles
}

/// Is `p` inside the sweep facing `target` from `eye`: within the horizontal field of view less a 5-degree margin
/// and below the sweep's top, or within 10 degrees of the nadir (the sweep's rays past it)?
fn overview_sees(eye: P3, target: P3, p: P3) -> bool {
    let (d, t) = (sub(p, eye), sub(target, eye));
    let h = (d[0] * d[0] + d[1] * d[1]).sqrt();
    let depression = (-d[2]).atan2(h).to_degrees();
    if depression > 80.0 {
        return true;
    }
    let az = (d[1].atan2(d[0]) - t[1].atan2(t[0])).to_degrees();
    let az = (az + 180.0).rem_euclid(360.0) - 180.0;
    let top = ((-t[2]).atan2((t[0] * t[0] + t[1] * t[1]).sqrt()).to_degrees() - OVERVIEW_ABOVE_GOAL_DEG).max(-10.0);
    az.abs() <= OVERVIEW_H_FOV_DEG / 2.0 - 5.0 && depression >= top
}

/// The sweep of tiles facing `target` from `eye` (see [`overview_sensor`]).
fn overview_sweep(eye: P3, target: P3, rover_sensor: &RangeSensorParams, m: &MissionSection) -> Vec<(RangeSensorParams, Pose3)> {
    let d = sub(target, eye);
    let yaw = d[1].atan2(d[0]);
    let target_depression = (-d[2]).atan2((d[0] * d[0] + d[1] * d[1]).sqrt()).to_degrees();
    let top = (target_depression - OVERVIEW_ABOVE_GOAL_DEG).max(-10.0);
    let far = firmware::geom::p3::dist(eye, target);
    let r = m.overview_resolution_deg;
    let nh = (OVERVIEW_H_FOV_DEG / r).floor() as usize + 1;
    let rows_per_tile = (OVERVIEW_TILE_POINTS / nh).max(2);
    let tile_span = (rows_per_tile - 1) as f64 * r;
    let mut tiles = Vec::new();
    let mut lo = top;
    while lo < OVERVIEW_MAX_DEPRESSION_DEG {
        let span = tile_span.min(OVERVIEW_MAX_DEPRESSION_DEG - lo).max(r);
        let centre = lo + span / 2.0;
        let params = RangeSensorParams {
            h_fov_deg: OVERVIEW_H_FOV_DEG,
            v_fov_deg: span,
            resolution_deg: r,
            max_range_m: (OVERVIEW_RANGE_FACTOR * far).max(OVERVIEW_MIN_RANGE_M),
            mount_xyz_m: [0.0, 0.0, 0.0],
            mount_pitch_down_deg: 0.0,
            ..rover_sensor.clone()
        };
        let pose = Pose3::from_parts(
            Vec3::new(eye[0] as Real, eye[1] as Real, eye[2] as Real).into(),
            Rot3::from_euler_angles(0.0, centre.to_radians() as Real, yaw as Real),
        );
        tiles.push((params, pose));
        lo += span + r;
    }
    tiles
}

/// One overview tile's scan (module docs).
pub fn overview_scan(world: &dyn World, params: &RangeSensorParams, pose: &Pose3, rng: &mut impl Rng) -> Scan {
    scan(world, params, pose, rng)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::ledge::LedgeWorld;

    #[test]
    fn localisation_error_is_zero_when_noiseless_and_grows_with_distance_otherwise() {
        let p = Pose3::from_parts(Vec3::new(1.0, 2.0, 3.0).into(), Rot3::from_euler_angles(0.0, 0.0, 0.4));
        let mut quiet = Localiser::new(&MissionSection::default().noiseless(), 1);
        quiet.moved(10.0);
        assert_eq!(quiet.estimate(&p), p);
        let m = MissionSection { loc_bias_m: 0.0, loc_noise_m: 0.0, loc_yaw_noise_deg: 0.0, loc_drift_per_m: 0.05, ..Default::default() };
        // the spread of the drift after 100 m is ~10x that after 1 m (sqrt of the distance): 50 seeds
        let spread = |dist: f64| {
            let mut s = 0.0;
            for seed in 0..50 {
                let mut l = Localiser::new(&m, seed);
                for _ in 0..100 {
                    l.moved(dist / 100.0);
                }
                let o = l.offset();
                s += o[0] * o[0] + o[1] * o[1];
            }
            (s / 100.0).sqrt()
        };
        let (a, b) = (spread(1.0), spread(100.0));
        assert!(b / a > 6.0 && b / a < 16.0, "{a} {b}");
        assert!((b - 0.5).abs() < 0.2, "sigma after 100 m: {b}");
    }

    /// Ledge test 3's mast stands ahead of the rover (eye at x = 4 m, the rover at -1.5 m, the goal beyond at 6 m):
    /// the sweep facing the goal has no return near the start; the overview adds the sweep facing the start, which
    /// has. A mast behind the rover (ledge test 1) sees the start in the goal's sweep and adds nothing.
    #[test]
    fn the_overview_also_faces_a_start_outside_the_goal_sweep() {
        let w = LedgeWorld::new();
        let m = MissionSection { overview_eye: Some([4.0, 0.0, 10.0]), ..Default::default() };
        let (goal, start) = ([6.0, 0.0, 0.35], [-1.5, 0.0, 4.35]);
        let returns_near_start = |tiles: &[(RangeSensorParams, Pose3)]| {
            tiles.iter().any(|(params, pose)| {
                let s = overview_scan(&w, params, pose, &mut rand_pcg::Pcg32::new(1, 1));
                s.points.iter().any(|p| {
                    let q = pose.transform_point(&(*p).into()).coords;
                    (q.x + 1.5).abs() < 0.3 && q.y.abs() < 0.3 && (q.z - 4.0).abs() < 0.05
                })
            })
        };
        let goal_only = overview_sweep([4.0, 0.0, 10.0], goal, &RangeSensorParams::default(), &m);
        assert!(!returns_near_start(&goal_only), "the goal's sweep already sees the start: the test shows nothing");
        let tiles = overview_sensor([6.7, 0.0, 6.35], goal, start, &RangeSensorParams::default(), &m);
        assert!(tiles.len() > goal_only.len());
        assert!(returns_near_start(&tiles));
        let behind = MissionSection { overview_eye: Some([-3.0, 0.0, 10.0]), ..Default::default() };
        let ahead_of_mast = overview_sensor([-6.4, 0.0, 6.35], goal, start, &RangeSensorParams::default(), &behind);
        assert_eq!(ahead_of_mast.len(), overview_sweep([-3.0, 0.0, 10.0], goal, &RangeSensorParams::default(), &behind).len());
    }

    #[test]
    fn the_overview_scan_sees_the_descent_from_the_mast() {
        let w = LedgeWorld::new();
        let m = MissionSection::default();
        let tiles = overview_sensor([-6.4, 0.0, 6.35], [6.0, 0.0, 0.35], [-1.5, 0.0, 4.35], &RangeSensorParams::default(), &m);
        assert!(tiles.len() >= 2);
        let mut world_pts: Vec<Vec3> = Vec::new();
        for (params, pose) in &tiles {
            params.validate().expect("within the protocol's scan size");
            let s = overview_scan(&w, params, pose, &mut rand_pcg::Pcg32::new(1, 1));
            world_pts.extend(s.points.iter().map(|p| pose.transform_point(&(*p).into()).coords));
        }
        // straight below the mast: the ground behind the ledge's back wall (z = 0 at x = -6.4)
        assert!(world_pts.iter().any(|p| (p.x + 6.4).abs() < 0.2 && p.z.abs() < 0.05));
        // returns on the ledge top near the start and on the ground near the goal
        assert!(world_pts.iter().any(|p| (p.x + 1.5).abs() < 0.3 && (p.z - 4.0).abs() < 0.05));
        assert!(world_pts.iter().any(|p| p.x > -0.3 && p.x < 0.0 && (p.z - 4.0).abs() < 0.05));
        // the ledge hides the ground at its foot from the mast (the line over the lip meets the ground at
        // x = 4 * 6.4 / 2.65 = 9.7 m): no returns there
        assert!(!world_pts.iter().any(|p| p.x > 3.5 && p.x < 9.0 && p.z.abs() < 0.05), "{}", world_pts.len());
    }
}
