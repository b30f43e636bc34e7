//! Defaults and budgets of the closed-loop mission in [`crate::nav`] (issue 18; protocol v2's `MissionConfig`).
//!
//! | const | default | reason |
//! |---|---|---|
//! | [`DEFAULT_CLOSED_LOOP`] | true (`Tracking::ClosedLoop`) | the tether-aware path-tracking controller; `OpenLoop` is the comparison baseline |
//! | [`DEFAULT_REPLAN_CROSS_TRACK_M`] | 0.3 | half the Axel axle track (0.6 m): farther off the path the plan's motion checks no longer describe where the wheels run |
//! | [`DEFAULT_PAYOUT_TOLERANCE_M`] | 0.5 | encoder noise and the taut-tether model's error (a sagging tether is a few percent longer) stay well below it; a snag on a rock that moves the tether's path by decimetres over metres shows above it |
//! | [`DEFAULT_MIN_MARGIN_N`] | 0.0 | the stability check's own boundary (`config::stability::MIN_MARGIN`): a waypoint that fails it is never sent |
//!
//! `protocol::MissionConfig::DEFAULT` bundles them; a `Configure` carries its own values.

/// Default execution of straight drives: true = `Tracking::ClosedLoop`, false = `Tracking::OpenLoop` (config names no
/// protocol type: the wire's enum is built from this in `protocol::MissionConfig::DEFAULT`).
pub const DEFAULT_CLOSED_LOOP: bool = true;
/// Default cross-track distance beyond which the navigator replans from the current pose, metres.
pub const DEFAULT_REPLAN_CROSS_TRACK_M: f32 = 0.3;
/// Default tolerance between tracked tether length and encoder payout, metres.
pub const DEFAULT_PAYOUT_TOLERANCE_M: f32 = 0.5;
/// Default smallest stability margin of a waypoint or the current state, newtons.
pub const DEFAULT_MIN_MARGIN_N: f32 = 0.0;

/// Standard gravity, m/s^2: the rover's weight `mass_kg * STANDARD_GRAVITY` converts the stability check's margin
/// (a fraction of the weight) to newtons.
pub const STANDARD_GRAVITY: f32 = 9.81;

/// Longest closed-loop sub-segment of a straight drive, metres. Default 0.5 m: the controller re-aims at a point
/// this far ahead on the planned segment after every sub-segment (pose feedback every half metre; Axel's axle
/// track is 0.6 m).
pub const TRACK_SEGMENT_M: f32 = 0.5;
/// Heading error below which the closed-loop controller drives instead of turning first, radians. Default 0.03
/// (1.7 degrees: 1.5 cm of lateral error per half-metre sub-segment).
pub const HEADING_TOLERANCE_RAD: f32 = 0.03;
/// A path segment counts as driven when less than this of it is left along the path, metres. Default 0.08 m.
pub const SEGMENT_DONE_M: f32 = 0.08;
/// Replans of one goal without progress before the mission stops safe with `ReplanLimit`: the count restarts
/// whenever the rover has come `REPLAN_PROGRESS_M` nearer the goal (horizontally) since it last restarted, so a
/// long descent may replan as often as its map grows, while a rover that replans in place stops. Bounded: at
/// most `MAX_REPLANS * (1 + d / REPLAN_PROGRESS_M)` replans for a start `d` metres from the goal. Default 8.
pub const MAX_REPLANS: u32 = 8;
/// Progress towards the goal that restarts the `MAX_REPLANS` count, metres. Default 0.5 m (one closed-loop
/// sub-segment, `TRACK_SEGMENT_M`).
pub const REPLAN_PROGRESS_M: f32 = 0.5;
/// An approximate plan (allowed by the goal request) is driven only when its last state is at least this much
/// nearer the goal than its start (axle to goal position), metres; else the mission stops safe with
/// `NoSolution`. At its end the navigator replans from where the rover stands, on the map its scans have grown
/// (a receding horizon, bounded by `MAX_REPLANS`). Default 0.25 m (half Axel's wheel base: less is not worth a
/// drive).
pub const MIN_APPROXIMATE_PROGRESS_M: f32 = 0.25;
/// Columns checked for observed ground on the line from an approximate plan's end to the goal (the navigator
/// searches on before driving an approximate plan over ground it has seen, `nav::mission`): one per voxel, at
/// most this many. Default 128 (12.8 m at the missions' 10 cm voxels; a longer line is sampled more sparsely).
pub const GROUND_TO_GOAL_SAMPLES: usize = 128;
/// Voxels looked at down each of those columns, from the top of the planning bounds, for the terrain behind an
/// observed surface. Default 512 (51 m at 10 cm, 25.6 m at 5 cm: deeper than any mission's bounds so far).
pub const GROUND_COLUMN_VOXELS: usize = 512;
/// Looks at an unobserved goal per goal: when planning ends with nothing the mission could drive and the goal's
/// voxel column is unobserved, the rover turns in place to face the goal, so its next scan sees it, and plans again
/// (`nav::mission`, `look_at_goal`). The range sensor looks ahead only, and a plan driven in reverse (Axel drives
/// either way) leaves the goal behind it. Default 2: one look, and one more from wherever the next plan ends.
pub const MAX_LOOKS: u32 = 2;
/// A look turns only when the goal's bearing is at least this far from the heading, radians. Default 0.35 (20
/// degrees: well inside any forward range sensor's horizontal field of view, so a rover facing the goal this
/// closely has already looked at it).
pub const LOOK_MIN_TURN_RAD: f32 = 0.35;
/// Consecutive stalled motions before the mission stops safe with `MotionStalled` (each stall replans first).
/// Default 2.
pub const MAX_STALLS: u32 = 2;
/// A reported pose farther than `POSE_JUMP_BASE_M + POSE_JUMP_PER_M * |achieved distance|` from odometry (the last
/// pose moved by the achieved motion) is a jump: rejected and counted. Defaults 0.5 m and 0.5 m/m: localisation
/// drift and tether-induced slip of a few tens of percent stay inside, a relocalisation of metres does not.
pub const POSE_JUMP_BASE_M: f32 = 0.5;
/// See [`POSE_JUMP_BASE_M`]. Default 0.5 (metres per metre driven).
pub const POSE_JUMP_PER_M: f32 = 0.5;
/// A reported yaw farther than this from odometry's is a jump, radians. Default 0.6 (34 degrees).
pub const POSE_JUMP_YAW_RAD: f32 = 0.6;
/// Consecutive rejected poses before the mission stops safe with `PoseJump`. Default 3.
pub const MAX_POSE_JUMPS: u32 = 3;
/// A scan whose sensor position is horizontally farther than this from the body pose estimate (while a straight
/// drive runs: from the drive's segment) is not integrated (counted), metres. Default 2.0 m: the sensor mount's
/// offset from the axle is not known on board.
pub const SCAN_POSE_TOLERANCE_M: f32 = 2.0;
/// Consecutive rejected scans before the mission stops safe with `ScanInconsistent`. Default 3.
pub const MAX_SCAN_REJECTS: u32 = 3;
/// Fastest physically possible payout change, m/s. Default 1.0 (Axel drives at ~0.1-0.3 m/s; the winch follows).
pub const MAX_PAYOUT_RATE_M_PER_S: f32 = 1.0;
/// Payout change allowed between two readings on top of the rate, metres (encoder noise). Default 0.3 m.
pub const PAYOUT_JUMP_SLACK_M: f32 = 0.3;
/// Segments of the remaining plan re-checked (motion checks on the current map) after each motion report.
/// Default 2: the segments about to be driven; after a scan the whole remaining plan is re-checked. One check per
/// executive step (`config::nav::MOTION_CHECKS_PER_STEP`).
pub const RECHECK_AFTER_MOTION: usize = 2;
/// Executed axle positions kept for re-estimating the anchor history from the root. Default 64; a full buffer
/// keeps every other position (the re-estimate then propagates over longer moves).
pub const EXECUTED_CAPACITY: usize = 64;
/// Bound of the learned drift gain (lateral metres per metre driven per unit of lateral tether direction).
/// Default 1.0.
pub const DRIFT_GAIN_LIMIT: f32 = 1.0;
/// Straight drives shorter than this do not update the drift estimate, metres. Default 0.05 m.
pub const MIN_DRIFT_SAMPLE_M: f32 = 0.05;
/// Alg. 1 predictions of a tether re-estimate per executive step (the re-estimate propagates from the root along
/// up to `EXECUTED_CAPACITY - 1` executed moves; the rover waits until it is done). Default 4.
pub const REESTIMATE_PER_STEP: usize = 4;

/// A recovered tether checkpoint (`nav::retained`) applies to a `Configure` whose root anchor is within this of the
/// checkpoint's, metres: the same deployment (the wire carries f32, so equal roots compare equal; the slack only
/// absorbs a ground that recomputes the root). Default 0.01.
pub const RECOVERY_ROOT_TOLERANCE_M: f32 = 0.01;
