//! One closed-loop mission (issue 18, items 1, 2 and 5): the simulator configures the flight software, scans,
//! sends the goal, then executes every drive command on the true world and reports it, streaming scans and tether
//! readings, until the flight software reports `Arrived` or `Safe` (with its reason), the rover falls, or the
//! mission's link-time limit passes.
//!
//! The conversation (protocol v2, `firmware/PROTOCOL.md`):
//! 1. boot telemetry; `Configure` (the scenario's root anchor, tether length as `max_payout_m`, the planner seed,
//!    `MissionConfig` with the tracking mode and the `[mission]` overrides);
//! 2. a tether reading, the overview scan from the root anchor's mast (`[mission] overview_scan`), a scan from the
//!    rover at its start pose (with the localisation error);
//! 3. the `GoalRequest` (with `allow_approximate`), to the first of the `[mission] waypoints` if there are any; at
//!    each waypoint's `Arrived` the next goal, the scenario's goal last;
//! 4. link time runs; tether readings every `1 / tether_rate_hz` seconds; each `DriveCommand` is executed on the
//!    true world ([`super::executor`]) increment by increment, each increment taking its link time (speed, turn
//!    rate), with a scan at most every `scan_every_m` metres; at its end a `MotionReport` (outcome, achieved
//!    turn and distance, the pose estimate) and a scan. A `Stop` while a motion runs ends it `Stalled`.
//! 5. the verdict is the simulator's own ([`Verdict`]): the flight software's word plus the truth's (the rover
//!    really within the goal tolerance plus `arrival_slack_m`, no fall).
//!
//! After a reset of the flight computer (`ResetAt`) the ground's recovery: `Configure` again, the mast's survey, the
//! rover's own recent scans taken within `RESEND_RADIUS_M` of it (the ground keeps the last `KEPT_SCANS`), a new
//! scan, and the goal again under a new id.
//!
//! Everything is seeded by the mission seed (planner, sensor noise, localisation, actuation, tether noise), so a
//! mission is a pure function of (scenario, seed, tracking) and the link's bytes replay bit for bit.

use std::time::Instant;

use firmware::config::rover::RoverParams;
use firmware::geom::p3::{dist, from_vec3, P3};
use firmware::geom::Real;
use firmware::protocol::{
    Configure, GoalRequest, LogLevel, MapSettings, Message, MessageKind, MissionConfig, MissionState, MissionStatus,
    Motion, MotionOutcome, MotionReport, PlanState, PlannerChoice, Point3, StopReason, Tracking,
};
use rand_core::Rng;
use serde::Serialize;

use super::executor::{Blocked, Execution, MissionTruth, Progress, TrueOutcome, TrueRover};
use super::params::MissionSection;
use super::sensing::{
    gaussian, overview_scan, overview_sensor, rover_scan, tether_reading, Localiser,
};
use super::truth::{true_tether, Body, TETHER_REGION_MARGIN_M};
use super::world::MissionWorld;
use crate::physics::{GroundPose, HoldOutcome, HoldVerdict, PhysicsJudge, TetherSpec};
use crate::link::{FlightLink, ResetCause};
use crate::scenario::{Scenario, WorldSpec};
use crate::sensor::{to_wire_pose, RangeSensorParams, Scan};
use crate::session::{HostSession, RetransmitPolicy, SessionError};

/// Points per scan chunk sent.
const CHUNK_POINTS: usize = 256;
/// Link time between two looks at the link while the rover stands still, microseconds.
const IDLE_STEP_US: u64 = 100_000;
/// Link time without a drive command or a mission-state change after which the mission ends `FlightQuiet`, s.
pub const QUIET_LIMIT_S: f64 = 300.0;
/// Trace points kept at most (the picture and the JSON), one per increment.
const MAX_TRACE: usize = 20_000;
/// The rover's scans the ground keeps for a recovery after a reset (the newest). Default 64.
const KEPT_SCANS: usize = 64;
/// After a reset the ground sends again the kept scans taken within this distance of the rover (horizontal), metres.
/// Default 3 m: the ground a first plan from there checks.
const RESEND_RADIUS_M: f64 = 3.0;
/// ... at most this many of them, the newest. Default 16.
const RESEND_SCANS: usize = 16;

/// How a mission ended, by the simulator's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum Verdict {
    /// The flight software reported `Arrived` and the true rover is within the goal tolerance (plus slack).
    Arrived,
    /// The flight software reported `Arrived` but the true rover is not within tolerance (localisation error).
    FalseArrival,
    /// The flight software stopped safe, with this reason.
    SafeStop(StopReason),
    /// The truth could not hold the rover: a fall.
    Fell,
    /// The mission's link-time limit passed.
    TimeLimit,
    /// The flight software sent nothing that moves the mission on (no drive command, no mission-state change)
    /// for [`QUIET_LIMIT_S`] of link time while not `Arrived` or `Safe`.
    FlightQuiet,
    /// The operator ended the mission at a waypoint (`[mission] end_at_waypoint`), the flight software having
    /// arrived there and the true rover within its tolerance plus `arrival_slack_m`.
    Ended,
    /// The ground gave up a message the mission needs (`Configure` or the goal request: no answer after the
    /// retransmission policy's sends, `session::RetransmitPolicy`), so the flight software never got the goal; the
    /// rover was never commanded and stands where it started. The link is down, not the rover.
    Undelivered,
}

impl Verdict {
    /// A short name for tables.
    pub fn name(&self) -> String {
        match self {
            Verdict::SafeStop(r) => format!("safe:{r:?}"),
            v => format!("{v:?}"),
        }
    }
}

/// One increment of the executed path.
#[derive(Debug, Clone, Copy, Serialize)]
pub struct TracePoint {
    /// Link time, seconds.
    pub t_s: f64,
    /// True axle centre.
    pub axle: P3,
    /// Estimated axle centre (last estimate sent).
    pub estimate: P3,
    /// True static margin, N.
    pub margin_n: f64,
    /// True tension, N.
    pub tension_n: f64,
    /// True payout, m.
    pub payout_m: f64,
    /// Distance driven, m.
    pub driven_m: f64,
    /// True body orientation (quaternion x, y, z, w): for the Foxglove export's `rover_true` frame, not in the
    /// JSON summary.
    #[serde(skip)]
    pub orientation: [f64; 4],
}

/// A plan the flight software sent.
#[derive(Debug, Clone, Serialize)]
pub struct PlanSeen {
    /// Link time, seconds.
    pub t_s: f64,
    /// Final planner state.
    pub state: String,
    /// Iterations.
    pub iterations: u32,
    /// Host wall time from the goal (or the previous plan's end) to this plan's end, seconds.
    pub host_s: f64,
    /// Waypoint axle positions.
    pub waypoints: Vec<P3>,
    /// Waypoint stability margins on the onboard map.
    pub margins: Vec<f32>,
}

/// A reset of the flight computer during the mission and what the flight software recovered (issue 24 item 2).
#[derive(Debug, Clone, Serialize)]
pub struct ResetSeen {
    /// Link time of the reset, seconds.
    pub t_s: f64,
    /// Motions executed before it.
    pub after_motions: u32,
    /// Anchors of the flight software's tracked tether in its last status before the reset (root included).
    pub anchors_before: u8,
    /// Anchors in the status it booted with: its recovered history (0: it reported no recovery).
    pub anchors_recovered: u8,
    /// The reason the rebooted flight software gave (`Reset`: recovered; `TetherStateLost`: not).
    pub reason: String,
    /// Contacts of the true tether (the simulator's own, `truth::taut`) at the reset: a wrapped tether has some.
    pub true_contacts: usize,
    /// Where they are (world, metres), from the root.
    pub true_contact_points: Vec<P3>,
    /// Operator waypoints reached before the reset (`MissionReport::waypoints_reached` then).
    pub waypoints_before: u32,
    /// How: `command` (between motions) or `watchdog` (a bite during a motion).
    pub cause: &'static str,
}

/// What a mission did.
#[derive(Debug, Clone, Serialize)]
pub struct MissionReport {
    /// Scenario name.
    pub scenario: String,
    /// Mission seed.
    pub seed: u64,
    /// Tracking mode sent.
    pub tracking: String,
    /// The verdict.
    pub verdict: Verdict,
    /// The flight software's last mission status.
    pub last_status: Option<MissionStatus>,
    /// True distance driven, m.
    pub distance_m: f64,
    /// Straight-line distance from the final true pose to the goal, m.
    pub goal_error_m: f64,
    /// Distance from the start to the goal, m.
    pub start_goal_m: f64,
    /// Replans the flight software reported.
    pub replans: u32,
    /// Motions executed.
    pub motions: u32,
    /// Motions that stalled / slipped.
    pub stalls: u32,
    /// Motions that slipped.
    pub slips: u32,
    /// Smallest true static margin along the executed path, N.
    pub min_true_margin_n: f64,
    /// Largest true tension, N.
    pub max_tension_n: f64,
    /// Largest true payout, m.
    pub max_payout_m: f64,
    /// Largest distance of the true axle from the plan being driven (horizontal), m.
    pub max_cross_track_m: f64,
    /// Mean of that distance over the increments, m.
    pub mean_cross_track_m: f64,
    /// Plans received.
    pub plans: Vec<PlanSeen>,
    /// Largest count of map blocks in use in any telemetry frame (the high water; the map forgets blocks far from
    /// the rover when its pool fills).
    pub map_blocks: u32,
    /// Map block capacity.
    pub map_blocks_capacity: u32,
    /// Nacks received.
    pub nacks: u32,
    /// Link time at the end, s.
    pub link_s: f64,
    /// Longest executive step the flight software measured (`Telemetry.cycle.max_step_us`), microseconds: zero
    /// on the simulated clock, host time with `InProcLink::charge_host_time`, emulated time free-running.
    pub max_step_us: u32,
    /// Executive steps over the step budget (`Telemetry.cycle.slips`).
    pub step_slips: u32,
    /// Frames the host sent again for want of an answer (`session::RetransmitPolicy`; 0 on a clean link).
    pub retransmits: u64,
    /// Messages the host gave up after the policy's sends.
    pub given_up: u64,
    /// Scan chunks the host sent again for want of an answer (`HostSession::send_scan`).
    pub chunks_resent: u64,
    /// Drive commands received again (a flight resend or a copy; protocol v5) and not executed again.
    pub commands_repeated: u64,
    /// `Stop`s taken (v6), by what each stopped: the motion executing, a motion that never arrived (reported
    /// `Stopped` with nothing done), or nothing (stale: its motion was already reported).
    pub stops: StopCounts,
    /// The host's detection on the downlink (`HostSession::downlink`).
    pub downlink: crate::session::DownlinkCounts,
    /// The flight sequence number of every frame whose drive command the host took (executed or a stop).
    #[serde(skip)]
    pub command_seqs: Vec<u32>,
    /// Resets of the flight computer during the mission, and what it recovered each time.
    pub resets: Vec<ResetSeen>,
    /// Host wall time, s.
    pub host_s: f64,
    /// The executed path.
    pub trace: Vec<TracePoint>,
    /// The true tether at the start, at each motion's end (every few) and at the end: (time s, points root..rover).
    pub tethers: Vec<(f64, Vec<P3>)>,
    /// Rocks: centre, radius, visible.
    pub rocks: Vec<(P3, f64, bool)>,
    /// Root anchor, start and goal.
    pub root: P3,
    /// Start axle.
    pub start: P3,
    /// Goal.
    pub goal: P3,
    /// Goal tolerance (flight) and the truth's slack.
    pub tolerance_m: f64,
    /// Poses the physics judge held the rover at (after each motion, `[mission] physics_falls`).
    pub physics_checks: u32,
    /// Poses the physics judge could not place the rover at (wheels or body in the terrain): not judged.
    pub physics_blocked: u32,
    /// The physics judge's verdict that ended the mission as a fall, in words.
    pub physics_fall: Option<String>,
    /// Increments the simple statics could not hold and the physics judge held (`physics_falls`): not falls.
    pub statics_overruled: u32,
    /// Increments whose true tether fell back from the general taut tether to the closed forms or the vertical
    /// profile (`mission::truth`: the rover outside the tether region, or the taut tether stuck).
    pub truth_tether_fallbacks: u32,
    /// The last warning or error the flight software forwarded (`Log` at `Warn` or `Error`): a refused goal's
    /// reason, a planning stop's, a safe stop's.
    pub flight_warning: Option<String>,
    /// Operator waypoints (`[mission] waypoints`) the flight software arrived at (the goal not counted).
    pub waypoints_reached: u32,
    /// The rover's earlier scans the ground sent again after resets (`Sim::recover`).
    pub scans_resent: u32,
}

impl MissionReport {
    /// Distance the flight software drove autonomously and the distance an operator would still have to drive
    /// (the straight line from the stop to the goal when the mission did not arrive).
    pub fn autonomy_m(&self) -> (f64, f64) {
        match self.verdict {
            Verdict::Arrived => (self.distance_m, 0.0),
            _ => (self.distance_m, self.goal_error_m),
        }
    }
}

/// What to run.
#[derive(Debug, Clone)]
pub struct MissionOptions {
    /// Seed of everything (planner, noise).
    pub seed: u64,
    /// Tracking mode sent in `MissionConfig`.
    pub tracking: Tracking,
    /// All noise and error sources zero (the deterministic unit tests).
    pub noiseless: bool,
    /// Print a live progress line on stderr.
    pub live: bool,
    /// Reset the flight computer once during the mission (issue 24 item 2). `None`: no reset.
    pub reset: Option<ResetAt>,
}

/// When a mission resets the flight computer (`tetherbot mission --reset-after-motions N | --reset-when-wrapped |
/// --watchdog-bite-in-motion N`). The commanded resets come right after a motion report has been answered; the
/// bite comes while the rover drives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResetAt {
    /// After this many executed motions.
    Motions(u32),
    /// After the first motion that leaves the tether wrapped: the simulator's true tether touches the terrain and
    /// the flight software's last status tracks an anchor besides the root. A mission whose tether never wraps is
    /// not reset.
    Wrapped,
    /// The watchdog bites during the motion after this many executed motions, after its first increment (before
    /// the report of a motion that took one increment): the rover stops where it is (its drive commands die with the flight computer), the motion's report is never
    /// sent, and the checkpoint the rebooted software recovers is the one from before the motion.
    BiteInMotion(u32),
    /// The watchdog bites, as in `BiteInMotion`, during the first motion that starts with the tether wrapped (as
    /// `Wrapped` judges it after each motion): a bite mid-descent that does not depend on how many motions the
    /// flight software needed to get there.
    BiteWhenWrapped,
}

/// Why a mission could not run (as opposed to how it ended).
#[derive(Debug)]
pub enum MissionError {
    /// The scenario cannot be simulated (world, start).
    Setup(String),
    /// The link or the protocol failed.
    Session(SessionError),
}

impl core::fmt::Display for MissionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            MissionError::Setup(s) => write!(f, "mission setup: {s}"),
            MissionError::Session(e) => write!(f, "mission link: {e}"),
        }
    }
}

impl core::error::Error for MissionError {}

impl From<SessionError> for MissionError {
    fn from(e: SessionError) -> Self {
        MissionError::Session(e)
    }
}

/// The configuration the mission sends: the scripted defaults with the scenario's tether and budgets.
pub fn mission_configure(sc: &Scenario, opts: &MissionOptions) -> Configure {
    let mut c = crate::scripted::default_configure(opts.seed);
    let r = sc.tether.root_anchor;
    c.tether.root_anchor = Point3::new(r[0] as f32, r[1] as f32, r[2] as f32);
    c.tether.max_payout_m = sc.tether.length_m as f32;
    c.planner.max_iterations = sc.budgets.planner_iterations;
    let m = &sc.mission;
    let d = MissionConfig::DEFAULT;
    c.mission = MissionConfig {
        tracking: opts.tracking,
        replan_cross_track_m: m.replan_cross_track_m.map_or(d.replan_cross_track_m, |v| v as f32),
        payout_tolerance_m: m.payout_tolerance_m.map_or(d.payout_tolerance_m, |v| v as f32),
        min_margin_n: m.min_margin_n.map_or(d.min_margin_n, |v| v as f32),
    };
    if let Some(mu) = m.friction {
        c.rover.friction_coefficient = mu as f32;
    }
    // The scenario's map configuration (checked when the mission's link was made; `mission_link`).
    c.map = sc.map_config().ok().map(MapSettings::from);
    c
}

/// The true rover for the configured rover: the Axel model with the configured geometry, mass and friction.
pub fn truth_for(sc: &Scenario, cfg: &Configure, m: &MissionSection) -> Result<MissionTruth, MissionError> {
    let base = sc.build_world().map_err(|e| MissionError::Setup(e.to_string()))?;
    let ledge = match sc.world_spec().map_err(|e| MissionError::Setup(e.to_string()))? {
        WorldSpec::Ledge { shape, poles } => crate::world::ledge::LedgeWorld::custom(shape, &poles).ok(),
        _ => None,
    };
    // The tether region: the box of the root, the start, the waypoints and the goal, widened by
    // `TETHER_REGION_MARGIN_M` across (the rover's excursions, and wraps round what stands beside its way), every
    // height; the wrap edges of a DEM or a mesh are built only there.
    let pts = [sc.tether.root_anchor, sc.rover.start, sc.goal.position];
    let (inf, ninf) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut lo, mut hi) = ([inf, inf, ninf], [ninf, ninf, inf]);
    for p in pts.iter().chain(&m.waypoints) {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - TETHER_REGION_MARGIN_M);
            hi[k] = hi[k].max(p[k] + TETHER_REGION_MARGIN_M);
        }
    }
    let world = MissionWorld::new(base, ledge, m.obstacles.clone()).with_tether_region((lo, hi));
    let mut rover = RoverParams::AXEL;
    rover.wheel_radius_m = cfg.rover.wheel_radius_m;
    rover.track_m = cfg.rover.axle_length_m;
    rover.boom_length_m = cfg.rover.boom_length_m;
    rover.wheel_mu = cfg.rover.friction_coefficient;
    Ok(MissionTruth {
        world,
        root: sc.tether.root_anchor,
        tether_length_m: sc.tether.length_m,
        rover,
        body: Body {
            mass_kg: f64::from(cfg.rover.mass_kg),
            gravity: f64::from(rover.gravity_mps2),
            mu: f64::from(cfg.rover.friction_coefficient),
            pretension_n: m.pretension_n,
            winch_limit_n: m.winch_limit_n,
        },
        drift_coeff: m.drift_per_m,
    })
}

/// The physics judge's hold test of the true rover where it stands, with the true tether taut from its last anchor.
///
/// The tether leaves the rover at the boom tip, not at the axle the executor's tether ends at: the inline boom is
/// aimed at the tether's last anchor and the true tether re-computed to that tip ([`PhysicsJudge::aim_tether`]), as
/// [`crate::physics::path::judge_path`] does.
pub fn judge_hold(judge: &PhysicsJudge, truth: &MissionTruth, rover: &TrueRover) -> HoldVerdict {
    let a = rover.axle();
    let pose = GroundPose { x: a[0], y: a[1], yaw: f64::from(rover.state.heading()) };
    let root = truth.root;
    let first = rover.tether.last_anchor(root);
    let (world, prev) = (&truth.world, &rover.tether);
    let aimed = judge.aim_tether(pose, first, |tip| Ok::<_, ()>(true_tether(world, root, tip, Some(prev)).last_anchor(root)));
    // unplaceable: the hold says so (Blocked)
    let anchor = aimed.ok().flatten().unwrap_or(first);
    judge.hold(pose, &TetherSpec { anchor, free_length_m: None })
}

/// The state of one mission on the host side.
struct Sim<'a, L: FlightLink> {
    s: HostSession<L>,
    sc: &'a Scenario,
    m: MissionSection,
    truth: MissionTruth,
    rover: TrueRover,
    loc: Localiser,
    rng: rand_pcg::Pcg64,
    scan_id: u32,
    next_reading_us: u64,
    reading_period_us: u64,
    last_scan_driven: f64,
    estimate: firmware::geom::Pose3,
    status: Option<MissionStatus>,
    done: Option<Verdict>,
    pending: Vec<(u32, Motion)>,
    rep: MissionReport,
    plan_parts: Vec<firmware::protocol::Waypoint>,
    current_plan: Vec<P3>,
    cross_sum: f64,
    cross_n: u32,
    live: bool,
    last_live_us: u64,
    /// Link time of the last drive command or mission-state change, microseconds.
    last_news_us: u64,
    /// A plan is being searched (Accepted seen, no final state yet).
    planning: bool,
    /// Host time spent in link calls while a plan was searched, seconds.
    plan_host_s: f64,
    /// The configuration and goal sent, sent again after a reset.
    cfg: Configure,
    goal: Option<GoalRequest>,
    reset: Option<ResetAt>,
    /// The flight software booted `Safe` with reason `Reset`: the ground configures it and sends the goal again.
    recovery_due: bool,
    /// The ground's recovery procedure is running: a `Safe` (`Reset`) status repeated meanwhile (the periodic
    /// status while the survey is sent) is the same reset, not another.
    recovering: bool,
    /// The operator waypoints (`[mission] waypoints`) and then the goal: what each goal sent asks for, in order.
    legs: Vec<P3>,
    /// The index in `legs` of the goal sent last.
    leg: usize,
    /// The flight software arrived at a waypoint: the ground sends the next goal from the main loop.
    waypoint_due: bool,
    /// The rover's last scans as the ground sent them (at most [`KEPT_SCANS`]), for the recovery after a reset.
    kept_scans: std::collections::VecDeque<Scan>,
    /// The id of the last drive command taken (none since boot).
    last_command_id: Option<u32>,
    /// The id of the last `Turn` / `Straight` taken (none since boot): a `Stop` of a newer one names a motion that
    /// never arrived.
    last_motion_id: Option<u32>,
    /// The physics judge of the true world as it is now (rebuilt when a rock appears); `None` without
    /// `physics_falls`.
    judge: Option<PhysicsJudge>,
}

impl<L: FlightLink> Sim<'_, L> {
    /// The physics judge holds the rover where it stands after a motion ([`judge_hold`]). `Some(words)` when it does
    /// not hold: a fall.
    fn physics_fall(&mut self) -> Option<String> {
        match self.physics_hold()? {
            (HoldOutcome::Falls, words) => Some(words),
            _ => None,
        }
    }

    /// The physics judge's hold test at the rover's true pose now ([`judge_hold`]), with its words when it does not
    /// hold; `None` without the judge. Counts the pose judged (and an unplaceable one).
    fn physics_hold(&mut self) -> Option<(HoldOutcome, String)> {
        let judge = self.judge.as_ref()?;
        let v = judge_hold(judge, &self.truth, &self.rover);
        self.rep.physics_checks += 1;
        match v.outcome {
            HoldOutcome::Holds => Some((HoldOutcome::Holds, String::new())),
            HoldOutcome::Blocked => {
                self.rep.physics_blocked += 1;
                Some((HoldOutcome::Blocked, String::new()))
            }
            HoldOutcome::Falls => {
                let a = self.rover.axle();
                Some((HoldOutcome::Falls, format!(
                    "the physics judge does not hold the rover at ({:.2}, {:.2}, {:.2}) heading {:.1} deg after {} motions: slides {:.3} m, tilts {:.1} deg, {:.3} m/s at the end",
                    a[0],
                    a[1],
                    a[2],
                    f64::from(self.rover.state.heading()).to_degrees(),
                    self.rep.motions,
                    v.slide_m,
                    v.tilt_deg,
                    v.end_speed_mps
                )))
            }
        }
    }

    fn now_s(&self) -> f64 {
        self.s.link().now_us() as f64 / 1e6
    }

    /// Handles what the flight software sent during a link call of `host_s` seconds.
    fn absorb(&mut self, msgs: Vec<Message>, host_s: f64) {
        let now = self.s.link().now_us();
        if self.planning || msgs.iter().any(|m| matches!(m, Message::PlanStatus(_))) {
            self.plan_host_s += host_s;
        }
        // the replies are the last frames the session read: their headers give the flight sequence numbers
        let first = self.s.log.len().saturating_sub(msgs.len());
        let seqs: Vec<u32> = self.s.log.get(first..).unwrap_or(&[]).iter().map(|r| r.header.seq).collect();
        for (i, msg) in msgs.into_iter().enumerate() {
            match msg {
                Message::DriveCommand(d) => {
                    // a command id is executed once: the flight software resends a command whose report is late
                    // (protocol v5), and ids increase (wrapping)
                    if self.last_command_id.is_some_and(|l| (d.command_id.wrapping_sub(l) as i32) <= 0) {
                        self.rep.commands_repeated += 1;
                        continue;
                    }
                    self.last_command_id = Some(d.command_id);
                    if !matches!(d.motion, Motion::Stop { .. }) {
                        self.last_motion_id = Some(d.command_id);
                    }
                    self.last_news_us = now;
                    self.rep.command_seqs.extend(seqs.get(i).copied());
                    self.pending.push((d.command_id, d.motion));
                }
                Message::MissionStatus(st) => {
                    if self.status.is_none_or(|old| old.state != st.state) {
                        self.last_news_us = now;
                    }
                    if st.state == MissionState::Safe && st.reason == StopReason::Reset && self.recovering {
                        // the reset being recovered from, reported again
                    } else if st.state == MissionState::Safe && st.reason == StopReason::Reset {
                        // the flight computer rebooted and recovered its tether state: the ground's procedure
                        // (configure, scan, the goal again) runs from the main loop
                        self.recovery_due = true;
                        if let Some(r) = self.rep.resets.last_mut().filter(|r| r.anchors_recovered == 0) {
                            r.anchors_recovered = st.anchors;
                            r.reason = format!("{:?}", st.reason);
                        }
                    } else if st.state == MissionState::Arrived
                        && self.leg + 1 < self.legs.len()
                        && self.goal.is_some_and(|g| g.goal_id == st.goal_id)
                    {
                        // at an operator waypoint (its goal, not an earlier one's late status): the next goal
                        // goes out from the main loop, unless the rover is not where the flight software thinks
                        let at = self.legs.get(self.leg).copied().unwrap_or(self.sc.goal.position);
                        if dist(self.rover.axle(), at) <= self.sc.goal.tolerance_m + self.m.arrival_slack_m {
                            self.waypoint_due = true;
                        } else if self.done.is_none() {
                            self.done = Some(Verdict::FalseArrival);
                        }
                    } else if matches!(st.state, MissionState::Arrived | MissionState::Safe) && self.done.is_none() {
                        self.done = Some(match st.state {
                            MissionState::Arrived => {
                                let e = dist(self.rover.axle(), self.sc.goal.position);
                                if e <= self.sc.goal.tolerance_m + self.m.arrival_slack_m {
                                    Verdict::Arrived
                                } else {
                                    Verdict::FalseArrival
                                }
                            }
                            _ => Verdict::SafeStop(st.reason),
                        });
                    }
                    self.status = Some(st);
                }
                Message::Plan(p) => {
                    if p.part == 0 {
                        self.plan_parts.clear();
                    }
                    self.plan_parts.extend(p.waypoints.iter().cloned());
                    if p.part + 1 == p.parts {
                        let wps: Vec<P3> = self
                            .plan_parts
                            .iter()
                            .map(|w| [f64::from(w.pose.position.x), f64::from(w.pose.position.y), f64::from(w.pose.position.z)])
                            .collect();
                        let margins = self.plan_parts.iter().map(|w| w.stability_margin).collect();
                        if let Some(last) = self.rep.plans.last_mut() {
                            if last.waypoints.is_empty() {
                                last.waypoints = wps.clone();
                                last.margins = margins;
                            }
                        }
                        self.current_plan = wps;
                    }
                }
                Message::PlanStatus(p) => {
                    if matches!(p.state, PlanState::Accepted | PlanState::Searching) {
                        self.planning = true;
                    } else if p.state != PlanState::NoGoal {
                        let t = self.now_s();
                        self.rep.plans.push(PlanSeen {
                            t_s: t,
                            state: format!("{:?}", p.state),
                            iterations: p.iterations,
                            host_s: self.plan_host_s,
                            waypoints: vec![],
                            margins: vec![],
                        });
                        self.planning = false;
                        self.plan_host_s = 0.0;
                    }
                }
                Message::Telemetry(t) => {
                    self.rep.map_blocks = self.rep.map_blocks.max(t.map.blocks_used);
                    self.rep.map_blocks_capacity = t.map.blocks_capacity;
                    self.rep.max_step_us = self.rep.max_step_us.max(t.cycle.max_step_us);
                    self.rep.step_slips = self.rep.step_slips.max(t.cycle.slips);
                }
                Message::Nack(_) => self.rep.nacks += 1,
                Message::Log(l) if matches!(l.level, LogLevel::Warn | LogLevel::Error) => {
                    self.rep.flight_warning = Some(l.text.as_str().to_string());
                }
                _ => {}
            }
        }
    }

    /// Lets link time run to `t_us`, sending the tether readings that fall due.
    fn run_to(&mut self, t_us: u64) -> Result<(), MissionError> {
        while self.next_reading_us <= t_us {
            let at = self.next_reading_us;
            let t0 = Instant::now();
            let got = self.s.advance_to(at)?;
            self.absorb(got, t0.elapsed().as_secs_f64());
            let r = tether_reading(&self.rover, self.truth.root, at, &self.m, &mut self.rng);
            self.s.send(&Message::TetherReading(r))?;
            self.next_reading_us += self.reading_period_us;
        }
        let t0 = Instant::now();
        let got = self.s.advance_to(t_us)?;
        self.absorb(got, t0.elapsed().as_secs_f64());
        self.live_line();
        Ok(())
    }

    fn live_line(&mut self) {
        let now = self.s.link().now_us();
        if !self.live || now < self.last_live_us + 2_000_000 {
            return;
        }
        self.last_live_us = now;
        let (state, margin) = self.status.map_or(("-".to_string(), f32::NAN), |s| (format!("{:?}", s.state), s.margin_n));
        eprint!(
            "\r  t {:7.1} s  {:<10} driven {:6.2} m  payout {:6.2} m  tension {:6.1} N  margin(board) {:7.1} N  margin(true) {:7.1} N   ",
            now as f64 / 1e6,
            state,
            self.rover.driven_m,
            self.rover.tether.length_m,
            self.rover.statics.tension_n,
            margin,
            self.rover.statics.margin_n
        );
    }

    /// Collects replies until the flight software is quiet.
    fn recv(&mut self) -> Result<(), MissionError> {
        let t0 = Instant::now();
        let got = self.s.recv()?;
        self.absorb(got, t0.elapsed().as_secs_f64());
        Ok(())
    }

    fn send_scan(&mut self, scan: &Scan) -> Result<(), MissionError> {
        self.scan_id += 1;
        let chunks = scan.to_chunks(self.scan_id, CHUNK_POINTS).map_err(|e| MissionError::Setup(format!("{e:?}")))?;
        let t0 = Instant::now();
        let (got, _) = self.s.send_scan(&chunks)?;
        self.absorb(got, t0.elapsed().as_secs_f64());
        Ok(())
    }

    /// The overview scans from the lander's mast (`MissionSection::overview_scan`), of the region from `from`
    /// to the goal.
    fn overview(&mut self, from: P3) -> Result<(), MissionError> {
        if !self.m.overview_scan {
            return Ok(());
        }
        let tiles: Vec<(RangeSensorParams, _)> = overview_sensor(self.truth.root, self.sc.goal.position, from, &self.sc.sensor, &self.m);
        for (params, pose) in tiles {
            let view = self.truth.world.sensed();
            let scan = overview_scan(&view, &params, &pose, &mut self.rng);
            self.send_scan(&scan)?;
        }
        Ok(())
    }

    fn scan_here(&mut self) -> Result<(), MissionError> {
        let pose = self.rover.state.settled.pose;
        self.estimate = self.loc.estimate(&pose);
        let view = self.truth.world.sensed();
        let scan = rover_scan(&view, &self.sc.sensor, &pose, &self.estimate, &mut self.rng);
        self.last_scan_driven = self.rover.driven_m;
        self.send_rover_scan(scan)
    }

    /// Sends one of the rover's own scans and keeps it for a recovery ([`Self::recover`]).
    fn send_rover_scan(&mut self, scan: Scan) -> Result<(), MissionError> {
        self.send_scan(&scan)?;
        if self.kept_scans.len() == KEPT_SCANS {
            self.kept_scans.pop_front();
        }
        self.kept_scans.push_back(scan);
        Ok(())
    }

    fn trace(&mut self) {
        let p = self.rover.axle();
        if !self.current_plan.is_empty() {
            let c = polyline_distance_xy(&self.current_plan, p);
            self.rep.max_cross_track_m = self.rep.max_cross_track_m.max(c);
            self.cross_sum += c;
            self.cross_n += 1;
        }
        let st = &self.rover.statics;
        self.rep.min_true_margin_n = self.rep.min_true_margin_n.min(st.margin_n);
        self.rep.max_tension_n = self.rep.max_tension_n.max(st.tension_n);
        self.rep.max_payout_m = self.rep.max_payout_m.max(self.rover.tether.length_m);
        if self.rep.trace.len() < MAX_TRACE {
            let e = from_vec3(&self.estimate.translation.vector);
            let q = self.rover.state.settled.pose.rotation.quaternion().coords;
            let t_s = self.now_s();
            self.rep.trace.push(TracePoint {
                t_s,
                axle: p,
                estimate: e,
                margin_n: st.margin_n,
                tension_n: st.tension_n,
                payout_m: self.rover.tether.length_m,
                driven_m: self.rover.driven_m,
                orientation: [f64::from(q.x), f64::from(q.y), f64::from(q.z), f64::from(q.w)],
            });
        }
    }

    fn snapshot_tether(&mut self) {
        let mut pts = vec![self.truth.root];
        pts.extend(self.rover.tether.contacts.iter().copied());
        pts.push(self.rover.axle());
        let t = self.now_s();
        self.rep.tethers.push((t, pts));
    }

    /// Resets the flight computer now (the link's reset: watchdog bite or reset command) and notes what the flight
    /// software had tracked; its boot status (absorbed by the next receive) says what it recovered.
    fn reset_flight(&mut self, cause: ResetCause) -> Result<(), MissionError> {
        let t_s = self.now_s();
        self.rep.resets.push(ResetSeen {
            t_s,
            after_motions: self.rep.motions,
            anchors_before: self.status.map_or(0, |s| s.anchors),
            anchors_recovered: 0,
            reason: String::new(),
            true_contacts: self.rover.tether.contacts.len(),
            true_contact_points: self.rover.tether.contacts.clone(),
            waypoints_before: self.rep.waypoints_reached,
            cause: match cause {
                ResetCause::Command => "command",
                ResetCause::Watchdog => "watchdog",
            },
        });
        log::warn!("mission: resetting the flight computer ({cause:?}) at t {t_s:.1} s");
        self.s.link_mut().reset_flight(cause).map_err(SessionError::Link)?;
        // drive commands of the software that was reset are void; the rebooted one numbers from 0 again
        self.pending.clear();
        self.last_command_id = None;
        self.last_motion_id = None;
        self.s.flight_rebooted();
        self.recv()?;
        if let Some(r) = self.rep.resets.last_mut().filter(|r| r.reason.is_empty()) {
            r.reason = self.status.map_or_else(String::new, |s| format!("{:?}", s.reason));
        }
        Ok(())
    }

    /// The ground's procedure after the flight software booted `Safe` (`Reset`): the same `Configure` (so it
    /// continues from the recovered tether), the survey, the rover's recent scans near where it stands and a new one
    /// (the map went with the reset), and the goal again under a new id.
    fn recover(&mut self) -> Result<(), MissionError> {
        self.recovery_due = false;
        self.recovering = true;
        let r = self.recovery_procedure();
        self.recovering = false;
        r
    }

    fn recovery_procedure(&mut self) -> Result<(), MissionError> {
        self.pending.clear();
        self.s.send(&Message::Configure(self.cfg))?;
        self.recv()?;
        // the map went with the reset: the lander's survey again (as at the start), then the rover's own scan
        let here = self.rover.axle();
        self.overview(here)?;
        // the rover's own recent scans taken near where it stands, oldest first (what its map held round it and the
        // mast cannot see again, e.g. behind a pole), then a new one
        let near: Vec<Scan> = self
            .kept_scans
            .iter()
            .filter(|sc| {
                let t = sc.sensor_pose.translation.vector;
                (f64::from(t.x) - here[0]).hypot(f64::from(t.y) - here[1]) <= RESEND_RADIUS_M
            })
            .cloned()
            .collect();
        let skip = near.len().saturating_sub(RESEND_SCANS);
        for scan in near.into_iter().skip(skip) {
            self.rep.scans_resent += 1;
            self.send_scan(&scan)?;
        }
        self.scan_here()?;
        if let Some(mut goal) = self.goal {
            goal.goal_id += 1;
            self.goal = Some(goal);
            self.s.send(&Message::GoalRequest(goal))?;
            self.last_news_us = self.s.link().now_us();
            self.recv()?;
        }
        Ok(())
    }

    /// The flight software arrived at an operator waypoint: the next waypoint (or the goal) as a new goal, with
    /// the same budget, tolerance and planner.
    fn next_waypoint(&mut self) -> Result<(), MissionError> {
        self.waypoint_due = false;
        let (Some(mut goal), Some(&next)) = (self.goal, self.legs.get(self.leg + 1)) else { return Ok(()) };
        self.leg += 1;
        self.rep.waypoints_reached += 1;
        if self.m.end_at_waypoint.is_some_and(|n| self.rep.waypoints_reached >= n) {
            log::info!("mission: waypoint {} of {} reached; the operator ends the mission here", self.leg, self.legs.len() - 1);
            self.done = Some(Verdict::Ended);
            return Ok(());
        }
        log::info!("mission: waypoint {} of {} reached; on to ({:.2}, {:.2}, {:.2})", self.leg, self.legs.len() - 1, next[0], next[1], next[2]);
        goal.goal_id = goal.goal_id.wrapping_add(1);
        goal.position = Point3::new(next[0] as Real, next[1] as Real, next[2] as Real);
        self.goal = Some(goal);
        self.s.send(&Message::GoalRequest(goal))?;
        self.last_news_us = self.s.link().now_us();
        self.recv()?;
        Ok(())
    }

    /// Reports a motion the flight software stopped before it arrived: `Stopped`, nothing achieved, from where the
    /// rover stands.
    fn report_unstarted(&mut self, id: u32) -> Result<(), MissionError> {
        let pose = self.rover.state.settled.pose;
        self.estimate = self.loc.estimate(&pose);
        let report = MotionReport {
            command_id: id,
            outcome: MotionOutcome::Stopped,
            achieved_yaw_rad: 0.0,
            achieved_distance_m: 0.0,
            pose: to_wire_pose(&self.estimate),
        };
        self.s.send(&Message::MotionReport(report))?;
        self.recv()?;
        Ok(())
    }

    /// Executes one `Turn` or `Straight` on the truth; returns false when the mission ended (fall).
    fn execute(&mut self, id: u32, motion: Motion) -> Result<bool, MissionError> {
        let scale = gaussian(&mut self.rng) * self.m.drive_scale_sigma;
        let turn = gaussian(&mut self.rng) * self.m.turn_error_deg.to_radians();
        let mut ex = Execution::new(id, motion, &self.rover, &self.m, scale, turn);
        let dt_us = (ex.step_seconds(&self.m) * 1e6).round().max(1.0) as u64;
        let mut stepped = false;
        let (outcome, blocked) = loop {
            // a stop of this motion from the flight software ends it where it is (v6: a stop names its motion)
            let stop = |p: &(u32, Motion)| matches!(p.1, Motion::Stop { motion_id } if motion_id == id);
            if self.pending.iter().any(stop) {
                self.pending.retain(|p| !stop(p));
                if stepped {
                    self.rep.stops.executing += 1;
                } else {
                    self.rep.stops.unstarted += 1;
                }
                break (TrueOutcome::Stalled, Some(Blocked::StopCommanded));
            }
            let before = self.rover.driven_m;
            let progress = match ex.step(&self.truth, &mut self.rover, self.m.slip_threshold_m) {
                // With the physics judge, it decides what the simple statics cannot hold (issue 19: the physical
                // judge, where it has landed, says what is a fall): a pose it holds is not a fall, and the motion
                // goes on; one it cannot hold, or cannot place, is.
                Progress::Ended(TrueOutcome::Fell, b) => match self.physics_hold() {
                    Some((HoldOutcome::Holds, _)) => {
                        self.rep.statics_overruled += 1;
                        Progress::Moving
                    }
                    Some((HoldOutcome::Falls, why)) => {
                        log::warn!("fall: {why}");
                        self.rep.physics_fall = Some(why);
                        Progress::Ended(TrueOutcome::Fell, b)
                    }
                    _ => Progress::Ended(TrueOutcome::Fell, b),
                },
                p => p,
            };
            stepped = true;
            #[cfg(feature = "sim")]
            if self.truth.world.tether_edges().is_some() && self.rover.tether.taut.is_none() {
                self.rep.truth_tether_fallbacks += 1;
            }
            self.loc.moved(self.rover.driven_m - before);
            if self.truth.world.advance(self.rover.driven_m, &mut self.rover.tether) > 0 {
                log::info!("a rock appeared after {:.2} m", self.rover.driven_m);
                if self.judge.is_some() {
                    self.judge = Some(PhysicsJudge::new(&self.truth.world.truth(), self.truth.rover).map_err(|e| MissionError::Setup(format!("physics judge: {e}")))?);
                }
            }
            self.trace();
            let t = self.s.link().now_us() + dt_us;
            self.run_to(t)?;
            if self.reset == Some(ResetAt::BiteInMotion(self.rep.motions)) {
                // the flight computer dies mid-motion (or, for a one-increment motion, before its report): the
                // rover stops here and no report is ever sent
                self.reset = None;
                self.rep.motions += 1;
                self.reset_flight(ResetCause::Watchdog)?;
                return Ok(true);
            }
            if let Progress::Ended(o, b) = progress {
                break (o, b);
            }
            if self.rover.driven_m - self.last_scan_driven >= self.m.scan_every_m {
                self.scan_here()?;
            }
        };
        self.rep.motions += 1;
        if self.rep.motions % 8 == 1 {
            self.snapshot_tether();
        }
        if outcome != TrueOutcome::Fell {
            if let Some(why) = self.physics_fall() {
                log::warn!("fall: {why}");
                self.rep.physics_fall = Some(why);
                self.snapshot_tether();
                self.done = Some(Verdict::Fell);
                return Ok(false);
            }
        }
        let wire = match outcome {
            TrueOutcome::Fell => {
                self.snapshot_tether();
                self.done = Some(Verdict::Fell);
                return Ok(false);
            }
            TrueOutcome::Completed => MotionOutcome::Completed,
            TrueOutcome::Slipped => {
                self.rep.slips += 1;
                MotionOutcome::Slipped
            }
            // the flight software stopped it (PROTOCOL.md: reported `Stopped`, with what was achieved)
            TrueOutcome::Stalled if matches!(blocked, Some(Blocked::StopCommanded)) => MotionOutcome::Stopped,
            TrueOutcome::Stalled => {
                self.rep.stalls += 1;
                MotionOutcome::Stalled
            }
        };
        let pose = self.rover.state.settled.pose;
        self.estimate = self.loc.estimate(&pose);
        let report = MotionReport {
            command_id: id,
            outcome: wire,
            achieved_yaw_rad: ex.achieved_yaw_rad as f32,
            achieved_distance_m: ex.achieved_distance_m as f32,
            pose: to_wire_pose(&self.estimate),
        };
        self.s.send(&Message::MotionReport(report))?;
        self.recv()?;
        let wrapped = !self.rover.tether.contacts.is_empty() && self.status.is_some_and(|s| s.anchors >= 2);
        let reset_due = match self.reset {
            Some(ResetAt::Motions(n)) => n == self.rep.motions,
            Some(ResetAt::Wrapped) => wrapped,
            Some(ResetAt::BiteWhenWrapped) => {
                if wrapped {
                    self.reset = Some(ResetAt::BiteInMotion(self.rep.motions));
                }
                false
            }
            Some(ResetAt::BiteInMotion(_)) | None => false,
        };
        if reset_due {
            self.reset = None;
            self.reset_flight(ResetCause::Command)?;
            return Ok(true);
        }
        // a scan after every motion, from where the rover stands (with the same pose estimate)
        let view = self.truth.world.sensed();
        let scan = rover_scan(&view, &self.sc.sensor, &pose, &self.estimate, &mut self.rng);
        self.last_scan_driven = self.rover.driven_m;
        self.send_rover_scan(scan)?;
        Ok(true)
    }
}

/// What the `Stop`s a mission took stopped (`MissionReport::stops`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct StopCounts {
    /// Stops of the motion being executed.
    pub executing: u64,
    /// Stops of a motion not started (never arrived, or queued): reported `Stopped`, nothing achieved.
    pub unstarted: u64,
    /// Stops of a motion already reported: nothing done.
    pub stale: u64,
}

/// Does the `Stop` with command id `stop_id` name motion `motion_id` that never arrived: newer than the last motion
/// taken (`None`: none since boot) and older than the stop itself (a motion is sent before its stop; a stop naming
/// its own id names none)? Command ids increase, wrapping (protocol section 5).
fn names_an_unseen_motion(last_motion_id: Option<u32>, motion_id: u32, stop_id: u32) -> bool {
    let newer = |a: u32, b: u32| (a.wrapping_sub(b) as i32) > 0;
    last_motion_id.is_none_or(|l| newer(motion_id, l)) && newer(stop_id, motion_id)
}

/// Horizontal distance from `p` to the polyline `pts`.
pub fn polyline_distance_xy(pts: &[P3], p: P3) -> f64 {
    let mut best = f64::INFINITY;
    for w in pts.windows(2) {
        best = best.min(crate::world::geometry::segment_distance_2d([p[0], p[1]], [w[0][0], w[0][1]], [w[1][0], w[1][1]]));
    }
    if pts.len() == 1 {
        best = ((p[0] - pts[0][0]).powi(2) + (p[1] - pts[0][1]).powi(2)).sqrt();
    }
    best
}

/// Runs the mission of `sc` over `link`.
pub fn run_mission(link: impl FlightLink, sc: &Scenario, opts: &MissionOptions) -> Result<MissionReport, MissionError> {
    run_mission_from(link, sc, opts, 0)
}

/// [`run_mission`] with the host's frames numbered from `first_seq` (wrapping; the soak, `crate::soak`).
pub fn run_mission_from(
    link: impl FlightLink,
    sc: &Scenario,
    opts: &MissionOptions,
    first_seq: u32,
) -> Result<MissionReport, MissionError> {
    let host_t0 = Instant::now();
    let m = if opts.noiseless { sc.mission.noiseless() } else { sc.mission.clone() };
    let cfg = mission_configure(sc, opts);
    let truth = truth_for(sc, &cfg, &m)?;
    let start = sc.rover.start;
    let st = truth
        .settle(start[0], start[1], sc.rover.yaw_deg.to_radians())
        .ok_or_else(|| MissionError::Setup(format!("the rover does not settle on the true world at {start:?}")))?;
    let rover = truth
        .place(st, None, 0.0)
        .map_err(|b| MissionError::Setup(format!("the start cannot be held: {b:?}")))?;
    let mut rng = rand_pcg::Pcg64::new(u128::from(opts.seed) ^ 0x6d69_7373_696f_6e00, 0x0a02_bdbf_7bb3_c0a7);
    let loc = Localiser::new(&m, opts.seed ^ rng.next_u64());
    let rep = MissionReport {
        scenario: sc.name.clone(),
        seed: opts.seed,
        tracking: format!("{:?}", opts.tracking),
        verdict: Verdict::TimeLimit,
        last_status: None,
        distance_m: 0.0,
        goal_error_m: 0.0,
        start_goal_m: dist(rover.axle(), sc.goal.position),
        replans: 0,
        motions: 0,
        stalls: 0,
        slips: 0,
        min_true_margin_n: f64::INFINITY,
        max_tension_n: 0.0,
        max_payout_m: 0.0,
        max_cross_track_m: 0.0,
        mean_cross_track_m: 0.0,
        plans: vec![],
        map_blocks: 0,
        map_blocks_capacity: 0,
        nacks: 0,
        link_s: 0.0,
        max_step_us: 0,
        step_slips: 0,
        retransmits: 0,
        given_up: 0,
        chunks_resent: 0,
        commands_repeated: 0,
        stops: StopCounts::default(),
        downlink: Default::default(),
        command_seqs: vec![],
        resets: vec![],
        host_s: 0.0,
        trace: vec![],
        tethers: vec![],
        rocks: truth
            .world
            .rocks()
            .map(|(r, _)| (r.centre, r.radius_m, r.visible))
            .collect(),
        root: sc.tether.root_anchor,
        start: rover.axle(),
        goal: sc.goal.position,
        tolerance_m: sc.goal.tolerance_m,
        physics_checks: 0,
        physics_blocked: 0,
        physics_fall: None,
        flight_warning: None,
        statics_overruled: 0,
        truth_tether_fallbacks: 0,
        waypoints_reached: 0,
        scans_resent: 0,
    };
    let m_legs: Vec<P3> = m.waypoints.iter().copied().chain([sc.goal.position]).collect();
    let estimate = rover.state.settled.pose;
    let judge = if m.physics_falls {
        Some(PhysicsJudge::new(&truth.world.truth(), truth.rover).map_err(|e| MissionError::Setup(format!("physics judge: {e}")))?)
    } else {
        None
    };
    let mut sim = Sim {
        s: {
            // Every frame that changes the flight state is sent again when unanswered (lost on a faulty link).
            let mut s = HostSession::starting_at(link, first_seq);
            s.retransmit = Some(RetransmitPolicy::default());
            s
        },
        sc,
        reading_period_us: (1e6 / m.tether_rate_hz).round().max(1.0) as u64,
        m,
        truth,
        rover,
        loc,
        rng,
        scan_id: 0,
        next_reading_us: 0,
        last_scan_driven: 0.0,
        estimate,
        status: None,
        done: None,
        pending: vec![],
        rep,
        plan_parts: vec![],
        current_plan: vec![],
        cross_sum: 0.0,
        cross_n: 0,
        live: opts.live && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        last_live_us: 0,
        last_news_us: 0,
        planning: false,
        plan_host_s: 0.0,
        cfg,
        goal: None,
        reset: opts.reset,
        recovery_due: false,
        recovering: false,
        legs: m_legs,
        leg: 0,
        waypoint_due: false,
        kept_scans: std::collections::VecDeque::new(),
        last_command_id: None,
        last_motion_id: None,
        judge,
    };
    sim.recv()?;
    sim.s.send(&Message::Configure(cfg))?;
    sim.recv()?;
    sim.next_reading_us = sim.s.link().now_us();
    let t = sim.s.link().now_us();
    sim.run_to(t)?;
    sim.snapshot_tether();
    sim.trace();
    sim.overview(sim.sc.rover.start)?;
    sim.scan_here()?;
    // a homotopy goal: the tile of the terrain first (the orbital DEM: the base terrain, no hidden rocks)
    let planner = match sim.m.homotopy {
        Some(spec) => {
            let heights = crate::homotopy::tile::tile_heights(sim.truth.world.base(), &spec);
            for chunk in crate::homotopy::tile::tile_chunks(1, &spec, &heights) {
                sim.s.send(&Message::TileChunk(chunk))?;
                sim.recv()?;
            }
            PlannerChoice::Homotopy
        }
        None => PlannerChoice::Abit,
    };
    let g = sim.legs.first().copied().unwrap_or(sc.goal.position);
    let goal = GoalRequest {
        goal_id: 1,
        position: Point3::new(g[0] as Real, g[1] as Real, g[2] as Real),
        tolerance_m: sc.goal.tolerance_m as f32,
        planner,
        max_iterations: sc.budgets.planner_iterations,
        time_budget_ms: 0,
        allow_approximate: sim.m.allow_approximate,
    };
    sim.goal = Some(goal);
    sim.s.send(&Message::GoalRequest(goal))?;
    sim.last_news_us = sim.s.link().now_us();
    sim.recv()?;
    let limit_us = (sim.m.time_limit_s * 1e6) as u64;
    let quiet_us = (QUIET_LIMIT_S * 1e6) as u64;
    while sim.done.is_none() {
        let now = sim.s.link().now_us();
        if now >= limit_us {
            break;
        }
        if let Some(k) = sim.s.given_up_kinds.iter().find(|k| matches!(k, MessageKind::Configure | MessageKind::GoalRequest)) {
            log::warn!("mission: the ground gave up sending {k:?}; the flight software cannot have the goal");
            sim.done = Some(Verdict::Undelivered);
            break;
        }
        if sim.recovery_due {
            sim.recover()?;
            continue;
        }
        if sim.waypoint_due {
            sim.next_waypoint()?;
            continue;
        }
        if sim.pending.is_empty() && now > sim.last_news_us + quiet_us {
            sim.done = Some(Verdict::FlightQuiet);
            break;
        }
        if sim.pending.is_empty() {
            sim.run_to(now + IDLE_STEP_US)?;
            continue;
        }
        let (id, motion) = sim.pending.remove(0);
        if let Motion::Stop { motion_id } = motion {
            // a stop of a motion not executing: of one that never arrived (lost on the way; a late copy is now a
            // repeat of an older id and is not taken), report it stopped with nothing done; of one already
            // reported, nothing (a late or repeated stop must not stop the next motion)
            if names_an_unseen_motion(sim.last_motion_id, motion_id, id) {
                sim.last_motion_id = Some(motion_id);
                sim.rep.stops.unstarted += 1;
                sim.report_unstarted(motion_id)?;
            } else {
                sim.rep.stops.stale += 1;
            }
            continue;
        }
        if !sim.execute(id, motion)? {
            break;
        }
    }
    if sim.live {
        eprintln!();
    }
    // a last look, on a clean link: the flight software's final status and telemetry
    sim.s.link_mut().end_faults().map_err(SessionError::Link)?;
    sim.recv()?;
    if let Ok(t) = sim.s.telemetry() {
        sim.rep.map_blocks = sim.rep.map_blocks.max(t.map.blocks_used);
        sim.rep.map_blocks_capacity = t.map.blocks_capacity;
        sim.rep.max_step_us = sim.rep.max_step_us.max(t.cycle.max_step_us);
        sim.rep.step_slips = sim.rep.step_slips.max(t.cycle.slips);
    }
    sim.rep.retransmits = sim.s.retransmitted;
    sim.rep.given_up = sim.s.given_up;
    sim.rep.chunks_resent = sim.s.chunks_resent;
    sim.rep.downlink = sim.s.downlink;
    sim.snapshot_tether();
    let mut rep = sim.rep;
    rep.verdict = sim.done.unwrap_or(Verdict::TimeLimit);
    rep.last_status = sim.status;
    rep.replans = sim.status.map_or(0, |s| s.replans);
    rep.distance_m = sim.rover.driven_m;
    rep.goal_error_m = dist(sim.rover.axle(), sc.goal.position);
    rep.mean_cross_track_m = if sim.cross_n > 0 { sim.cross_sum / f64::from(sim.cross_n) } else { 0.0 };
    rep.link_s = sim.s.link().now_us() as f64 / 1e6;
    rep.host_s = host_t0.elapsed().as_secs_f64();
    Ok(rep)
}

#[cfg(test)]
mod tests {
    use super::names_an_unseen_motion;

    /// A `Stop` names a motion that never arrived when its id is newer than the last motion taken (ids wrap).
    #[test]
    fn a_stop_of_a_newer_motion_names_one_that_never_arrived() {
        assert!(names_an_unseen_motion(None, 0, 1));
        assert!(names_an_unseen_motion(Some(4), 5, 6));
        assert!(!names_an_unseen_motion(Some(5), 5, 6), "the last motion taken: stale once reported");
        assert!(!names_an_unseen_motion(Some(6), 5, 7), "an older motion: stale");
        assert!(names_an_unseen_motion(Some(u32::MAX), 0, 1), "across the wrap");
        assert!(!names_an_unseen_motion(Some(0), u32::MAX, 1), "across the wrap, older");
        // a stop sent before any motion names its own id: no motion
        assert!(!names_an_unseen_motion(None, 0, 0));
        assert!(!names_an_unseen_motion(None, 3, 3));
    }
}
