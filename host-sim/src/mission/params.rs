//! The `[mission]` section of a scenario file: how the simulator executes, senses and disturbs a closed-loop
//! mission (`host-sim/doc/scenario.md` documents the schema; `host-sim/doc/mission.md` the models).
//!
//! Every field is optional; the defaults are the values below. Lengths in metres, angles in degrees, times in
//! seconds of link time.

use serde::{Deserialize, Serialize};

/// A rock that is part of the true world but not of the base terrain: hidden until scanned (every obstacle is), or
/// invisible to the range sensor altogether (`visible = false`: the tether snags on it, the map never shows it), or
/// appearing only once the rover has driven `appears_after_m` (a rock rolling into the planned corridor).
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleSpec {
    /// Centre of the spherical rock, world frame, metres.
    pub centre: [f64; 3],
    /// Radius, metres (> 0).
    pub radius_m: f64,
    /// Distance the rover must have driven before the rock exists, metres. Default 0 (there from the start).
    #[serde(default)]
    pub appears_after_m: f64,
    /// Whether the range sensor sees it. Default true.
    #[serde(default = "yes")]
    pub visible: bool,
}

fn yes() -> bool {
    true
}

/// `[mission]`: the closed-loop mission's execution, sensing and disturbance models.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields, default)]
pub struct MissionSection {
    /// Drive speed, m/s (link time a straight drive takes). Default 0.1.
    pub speed_mps: f64,
    /// Turn rate in place, deg/s. Default 10.
    pub turn_rate_dps: f64,
    /// Increment of a straight drive on the true world, metres. Default 0.05.
    pub drive_step_m: f64,
    /// Increment of a turn in place, degrees. Default 5.
    pub turn_step_deg: f64,
    /// A range scan at most every this many metres while driving (and after every motion). Default 0.5.
    pub scan_every_m: f64,
    /// Tether readings (payout, tension, boom angle) per second. Default 5.
    pub tether_rate_hz: f64,
    /// Noise (1 sigma) of the payout reading, metres. Default 0.01.
    pub payout_noise_m: f64,
    /// Noise (1 sigma) of the tension reading, newtons. Default 2.
    pub tension_noise_n: f64,
    /// Noise (1 sigma) of the boom-angle reading, degrees. Default 0.5.
    pub boom_noise_deg: f64,
    /// Localisation: constant position bias, drawn per seed with this sigma per axis (x, y), metres. Default 0.02.
    pub loc_bias_m: f64,
    /// Localisation: random-walk drift of the position estimate per metre driven (sigma per axis, x and y, per
    /// square-root metre). Default 0.01.
    pub loc_drift_per_m: f64,
    /// Localisation: white noise of each reported position (sigma per axis), metres. Default 0.01.
    pub loc_noise_m: f64,
    /// Localisation: white noise of each reported heading, degrees. Default 0.3.
    pub loc_yaw_noise_deg: f64,
    /// Actuation: drive-distance scale error, drawn per motion with this sigma (0.02 = 2 %). Default 0.01.
    pub drive_scale_sigma: f64,
    /// Actuation: heading error per turn, drawn per motion with this sigma, degrees. Default 0.5.
    pub turn_error_deg: f64,
    /// Tether drift: lateral slip per metre driven at a lateral-force-to-traction ratio of 1 (the model of
    /// `host-sim/doc/mission.md`). Default 0.15.
    pub drift_per_m: f64,
    /// A motion whose end is more than this far off the commanded motion (laterally) is reported `Slipped`,
    /// metres. Default 0.05.
    pub slip_threshold_m: f64,
    /// Smallest tension the winch holds (keeps the tether taut), newtons. Default 20.
    pub pretension_n: f64,
    /// The tension at which the true winch (or tether) gives way: beyond it the rover falls, newtons.
    /// Default 2000.
    pub winch_limit_n: f64,
    /// Link-time limit of the mission, seconds. Default 3600.
    pub time_limit_s: f64,
    /// Take an overview scan from a sensor on the root anchor's mast before the goal (Paton et al. VI: the lander
    /// or mother rover that holds the tether surveys the descent). Default true.
    pub overview_scan: bool,
    /// Where the overview sensor sits, world frame (a survey mast on the lander that holds the tether). Default:
    /// 0.3 m above the root anchor.
    pub overview_eye: Option<[f64; 3]>,
    /// Overview sensor's angular resolution, degrees (`mission::sensing::overview_sensor`). Default 0.5 (5 cm
    /// between rays at 6 m: the onboard map's voxel).
    pub overview_resolution_deg: f64,
    /// Allow the flight software to drive an approximate solution up to its last safe state. Default false.
    pub allow_approximate: bool,
    /// After every motion, the physics judge (`crate::physics`, rapier3d, independent of the flight software's
    /// model) holds the rover at its true pose with the true tether; a pose it cannot hold is a **fall**. An
    /// increment the simple statics cannot hold is a fall only if the judge cannot hold it (or cannot place the
    /// rover) either; the ones it holds are counted (`MissionReport::statics_overruled`) and the motion goes on
    /// (`tetherbot mission --physics-falls`). Default false: with it the
    /// development missions fall where the planner's wheel-patch model is optimistic (`host-sim/doc/mission.md`,
    /// 2026-12-05), an open defect of the planner, not of the judge.
    pub physics_falls: bool,
    /// Cross-track distance that triggers a replan on board (`MissionConfig.replan_cross_track_m`), metres.
    /// Default: the flight software's `MissionConfig::DEFAULT`.
    pub replan_cross_track_m: Option<f64>,
    /// Predicted-vs-measured payout tolerance on board (`MissionConfig.payout_tolerance_m`), metres. Default: the
    /// flight software's.
    pub payout_tolerance_m: Option<f64>,
    /// Minimum stability margin on board (`MissionConfig.min_margin_n`), newtons. Default: the flight software's.
    pub min_margin_n: Option<f64>,
    /// Hidden obstacles (`[[mission.obstacles]]`). Default none.
    pub obstacles: Vec<ObstacleSpec>,
    /// True goal arrival tolerance for the verdict, added to the goal's tolerance (localisation error), metres.
    /// Default 0.25.
    pub arrival_slack_m: f64,
    /// The rover's friction coefficient sent in `Configure` (and used by the truth), when not the scripted default
    /// 0.7. A homotopy goal classifies the tile's slopes with it (tether-demand above `atan(mu)`).
    pub friction: Option<f64>,
    /// Upload a tile of the terrain and ask for `PlannerChoice::Homotopy` (`[mission.homotopy]`, issue 20 item 4).
    /// Default none: the goal is an ABIT* goal.
    pub homotopy: Option<crate::homotopy::tile::TileSpec>,
    /// Operator waypoints, world frame, metres: the ground sends each as a goal (with `[goal] tolerance_m`), the
    /// next once the flight software reports `Arrived` at the one before, and `[goal]` after the last. The route
    /// is then the operator's choice and each leg the planner's (e.g. round the ledge's pole, whose far side the
    /// lander's mast cannot see). Default none; at most [`MAX_WAYPOINTS`]; not with `homotopy` (its route has
    /// its own legs).
    pub waypoints: Vec<[f64; 3]>,
    /// The operator ends the mission when the flight software has arrived at this many of `waypoints` (the rover
    /// stands at the last one; the verdict is [`crate::mission::run::Verdict::Ended`]): a run of a long mission's
    /// first part, such as the board's test of a watchdog bite behind the ledge's pole, which needs the bite and
    /// the waypoints after it, not the descent after them. Default none: the mission goes on to `[goal]`.
    pub end_at_waypoint: Option<u32>,
}

/// Most operator waypoints of a mission (`MissionSection::waypoints`).
pub const MAX_WAYPOINTS: usize = 16;

impl Default for MissionSection {
    fn default() -> Self {
        MissionSection {
            speed_mps: 0.1,
            turn_rate_dps: 10.0,
            drive_step_m: 0.05,
            turn_step_deg: 5.0,
            scan_every_m: 0.5,
            tether_rate_hz: 5.0,
            payout_noise_m: 0.01,
            tension_noise_n: 2.0,
            boom_noise_deg: 0.5,
            loc_bias_m: 0.02,
            loc_drift_per_m: 0.01,
            loc_noise_m: 0.01,
            loc_yaw_noise_deg: 0.3,
            drive_scale_sigma: 0.01,
            turn_error_deg: 0.5,
            drift_per_m: 0.15,
            slip_threshold_m: 0.05,
            pretension_n: 20.0,
            winch_limit_n: 2000.0,
            time_limit_s: 3600.0,
            overview_scan: true,
            overview_eye: None,
            overview_resolution_deg: 0.5,
            allow_approximate: false,
            physics_falls: false,
            replan_cross_track_m: None,
            payout_tolerance_m: None,
            min_margin_n: None,
            obstacles: Vec::new(),
            arrival_slack_m: 0.25,
            friction: None,
            homotopy: None,
            waypoints: Vec::new(),
            end_at_waypoint: None,
        }
    }
}

impl MissionSection {
    /// A copy with every noise and error source zero (deterministic unit tests; the drift model stays).
    pub fn noiseless(&self) -> Self {
        MissionSection {
            payout_noise_m: 0.0,
            tension_noise_n: 0.0,
            boom_noise_deg: 0.0,
            loc_bias_m: 0.0,
            loc_drift_per_m: 0.0,
            loc_noise_m: 0.0,
            loc_yaw_noise_deg: 0.0,
            drive_scale_sigma: 0.0,
            turn_error_deg: 0.0,
            ..self.clone()
        }
    }

    /// Checks the section; the error names the field (below `mission.`) and the reason.
    pub fn validate(&self) -> Result<(), (String, String)> {
        let positive = [
            ("speed_mps", self.speed_mps),
            ("turn_rate_dps", self.turn_rate_dps),
            ("drive_step_m", self.drive_step_m),
            ("turn_step_deg", self.turn_step_deg),
            ("scan_every_m", self.scan_every_m),
            ("tether_rate_hz", self.tether_rate_hz),
            ("slip_threshold_m", self.slip_threshold_m),
            ("winch_limit_n", self.winch_limit_n),
            ("time_limit_s", self.time_limit_s),
            ("overview_resolution_deg", self.overview_resolution_deg),
        ];
        for (f, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err((f.into(), format!("must be finite and > 0, got {v}")));
            }
        }
        let non_negative = [
            ("payout_noise_m", self.payout_noise_m),
            ("tension_noise_n", self.tension_noise_n),
            ("boom_noise_deg", self.boom_noise_deg),
            ("loc_bias_m", self.loc_bias_m),
            ("loc_drift_per_m", self.loc_drift_per_m),
            ("loc_noise_m", self.loc_noise_m),
            ("loc_yaw_noise_deg", self.loc_yaw_noise_deg),
            ("drive_scale_sigma", self.drive_scale_sigma),
            ("turn_error_deg", self.turn_error_deg),
            ("drift_per_m", self.drift_per_m),
            ("pretension_n", self.pretension_n),
            ("arrival_slack_m", self.arrival_slack_m),
        ];
        for (f, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err((f.into(), format!("must be finite and >= 0, got {v}")));
            }
        }
        if self.drive_step_m > 0.5 {
            return Err(("drive_step_m".into(), format!("must be at most 0.5 m (a few cm per increment), got {}", self.drive_step_m)));
        }
        if self.turn_step_deg > 30.0 {
            return Err(("turn_step_deg".into(), format!("must be at most 30 degrees, got {}", self.turn_step_deg)));
        }
        if self.overview_resolution_deg < 0.05 {
            return Err(("overview_resolution_deg".into(), format!("must be >= 0.05, got {}", self.overview_resolution_deg)));
        }
        if self.pretension_n >= self.winch_limit_n {
            return Err(("pretension_n".into(), format!("must be below winch_limit_n ({})", self.winch_limit_n)));
        }
        for (f, v) in [
            ("replan_cross_track_m", self.replan_cross_track_m),
            ("payout_tolerance_m", self.payout_tolerance_m),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v > 0.0) {
                    return Err((f.into(), format!("must be finite and > 0, got {v}")));
                }
            }
        }
        if let Some(v) = self.min_margin_n {
            if !(v.is_finite() && v >= 0.0) {
                return Err(("min_margin_n".into(), format!("must be finite and >= 0, got {v}")));
            }
        }
        if let Some(e) = self.overview_eye {
            if !e.iter().all(|v| v.is_finite()) {
                return Err(("overview_eye".into(), format!("must be three finite numbers, got {e:?}")));
            }
        }
        if self.waypoints.len() > MAX_WAYPOINTS {
            return Err(("waypoints".into(), format!("at most {MAX_WAYPOINTS}, got {}", self.waypoints.len())));
        }
        if let Some(i) = self.waypoints.iter().position(|w| !w.iter().all(|v| v.is_finite())) {
            return Err((format!("waypoints[{i}]"), format!("must be three finite numbers, got {:?}", self.waypoints[i])));
        }
        if let Some(n) = self.end_at_waypoint {
            if n == 0 || n as usize > self.waypoints.len() {
                return Err((
                    "end_at_waypoint".into(),
                    format!("must be between 1 and the number of waypoints ({}), got {n}", self.waypoints.len()),
                ));
            }
        }
        if !self.waypoints.is_empty() && self.homotopy.is_some() {
            return Err(("waypoints".into(), "a homotopy goal has its own legs; give waypoints or homotopy, not both".into()));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            if !o.centre.iter().all(|v| v.is_finite()) {
                return Err((format!("obstacles[{i}].centre"), format!("must be three finite numbers, got {:?}", o.centre)));
            }
            if !(o.radius_m.is_finite() && o.radius_m > 0.0 && o.radius_m <= 5.0) {
                return Err((format!("obstacles[{i}].radius_m"), format!("must be in (0, 5] m, got {}", o.radius_m)));
            }
            if !(o.appears_after_m.is_finite() && o.appears_after_m >= 0.0) {
                return Err((format!("obstacles[{i}].appears_after_m"), format!("must be >= 0, got {}", o.appears_after_m)));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_validate_and_bad_fields_are_named() {
        assert!(MissionSection::default().validate().is_ok());
        let cases: Vec<(MissionSection, &str)> = vec![
            (MissionSection { speed_mps: 0.0, ..Default::default() }, "speed_mps"),
            (MissionSection { loc_noise_m: f64::NAN, ..Default::default() }, "loc_noise_m"),
            (MissionSection { drive_step_m: 2.0, ..Default::default() }, "drive_step_m"),
            (MissionSection { overview_resolution_deg: 0.01, ..Default::default() }, "overview_resolution_deg"),
            (MissionSection { min_margin_n: Some(-1.0), ..Default::default() }, "min_margin_n"),
            (MissionSection { waypoints: vec![[0.0; 3], [f64::NAN, 0.0, 0.0]], ..Default::default() }, "waypoints[1]"),
            (MissionSection { waypoints: vec![[0.0; 3]; MAX_WAYPOINTS + 1], ..Default::default() }, "waypoints"),
            (MissionSection { end_at_waypoint: Some(1), ..Default::default() }, "end_at_waypoint"),
            (MissionSection { waypoints: vec![[0.0; 3]; 2], end_at_waypoint: Some(0), ..Default::default() }, "end_at_waypoint"),
            (MissionSection { waypoints: vec![[0.0; 3]; 2], end_at_waypoint: Some(3), ..Default::default() }, "end_at_waypoint"),
            (
                MissionSection {
                    waypoints: vec![[1.0, 2.0, 3.0]],
                    homotopy: Some(crate::homotopy::tile::TileSpec { origin: [0.0; 2], resolution_m: 0.5, posts: [8, 8] }),
                    ..Default::default()
                },
                "waypoints",
            ),
            (
                MissionSection {
                    obstacles: vec![ObstacleSpec { centre: [0.0, 0.0, 0.0], radius_m: -1.0, appears_after_m: 0.0, visible: true }],
                    ..Default::default()
                },
                "obstacles[0].radius_m",
            ),
        ];
        for (m, field) in cases {
            let (f, reason) = m.validate().unwrap_err();
            assert_eq!(f, field, "{reason}");
            assert!(!reason.is_empty());
        }
    }
}
