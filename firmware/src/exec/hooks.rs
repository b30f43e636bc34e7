//! Hook points where the map and the planners plug into the executive.
//!
//! The executive owns the protocol, the modes and the budgets; everything that knows about terrain, tether and
//! planning sits behind [`Autonomy`]. The flight implementation is `crate::nav::Navigator` (the onboard map and
//! tethered ABIT* on it); [`NoAutonomy`] (every method's default: nothing done, goals answered
//! `PlannerUnavailable`) runs the executive with no map and no planner (the executive's own tests, the board's
//! dispatch benchmark).
//!
//! The calls, all with the time passed in and each bounded by its caller's budget: [`Autonomy::configure`] on
//! `Configure`; [`Autonomy::tether_reading`] and [`Autonomy::scan`] for each reading and each reassembled scan
//! (Paton et al. IV, TSDF -> ESDF); [`Autonomy::tile_part`] and [`Autonomy::tile_complete`] for each accepted chunk
//! of a terrain tile and its completion (v7, the homotopy planner's orbital DEM patch); [`Autonomy::goal`] validates and sets up a goal request;
//! [`Autonomy::plan_step`] runs at most `PLANNER_ITERATIONS_PER_STEP` iterations per step (OMPL's
//! `solve(termination)` split into steps) and fills the [`PlanBuffer`] when it finishes;
//! [`Autonomy::next_motion`] hands out the motion primitives to drive; [`Autonomy::abort`] on `Shutdown`;
//! [`Autonomy::map_status`] for each `Telemetry` frame.
//!
//! Protocol v2 (the closed-loop mission): the executive sends one drive command at a time and asks
//! [`Autonomy::drive_step`] for the next only after [`Autonomy::motion_report`] delivered the report of the last
//! (the executive itself rejects reports for commands it is not awaiting, `Nack(UnknownCommand)`);
//! [`Autonomy::motion_timeout`] when no report came within `MOTION_REPORT_TIMEOUT_US`; [`Autonomy::cancel`] on a
//! `GoalCancel` for the current goal; [`Autonomy::goal`] is also called while driving (the new goal replaces the
//! old: the executive stops the rover first); [`Autonomy::mission_status`] is polled every step and sent on
//! every change, after every accepted motion report and with every `Telemetry` frame.

use hal::Instant;

use crate::config::exec::PLAN_WAYPOINTS_CAPACITY;
use crate::config::tether::RETAINED_BYTES;
use crate::protocol::{
    Configure, GoalRequest, MapStatus, MissionStatus, Motion, MotionReport, PlanState, Point3, Pose,
    TetherReading, TileHeader, Waypoint,
};

/// A complete, reassembled range scan, lent to [`Autonomy::scan`] for the duration of the call.
#[derive(Debug, Clone, Copy)]
pub struct Scan<'a> {
    /// Scan id from the host.
    pub scan_id: u32,
    /// Sensor pose (sensor frame to world frame).
    pub sensor_pose: Pose,
    /// Returns in the sensor frame, metres.
    pub points: &'a [Point3],
}

/// The hooks refused a message; the executive answers `Nack(Refused)` and changes nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Refused;

/// The plan being built; a planner fills it before reporting a solution.
pub type PlanBuffer = heapless::Vec<Waypoint, PLAN_WAYPOINTS_CAPACITY>;

/// Result of one bounded planning step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum PlanProgress {
    /// Still searching; `iterations` spent in total so far.
    Searching {
        /// Iterations so far.
        iterations: u32,
        /// Best cost so far, if a path exists.
        best_cost: Option<f32>,
    },
    /// Finished. With `ExactSolution` / `ApproximateSolution` the plan buffer holds the path.
    Finished {
        /// Final state (never `Searching` / `Accepted`).
        state: PlanState,
        /// Iterations spent.
        iterations: u32,
        /// Cost of the path, if any.
        best_cost: Option<f32>,
    },
}

/// What the autonomy wants while driving, asked once per step when no motion report is awaited.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveStep {
    /// Send this motion as the next drive command (then wait for its report).
    Motion(Motion),
    /// Nothing to send this step (e.g. re-checking the remaining plan in bounded parts); stay in `Driving`.
    Wait,
    /// Plan again from the current state: the executive goes to `Planning` and calls `plan_step` (a new
    /// `PlanStatus` / `Plan` follows).
    Replan,
    /// Driving is over (arrived, or stopped safe): the executive goes back to `Mapping`.
    Finished,
}

/// Planning modules as the executive sees them. All methods get the time passed in and must bound their work.
pub trait Autonomy {
    /// A validated `Configure` (Idle / Mapping modes). `Err` -> `Nack(Refused)`, configuration unchanged.
    fn configure(&mut self, _cfg: &Configure) -> Result<(), Refused> {
        Ok(())
    }
    /// A validated tether-encoder reading.
    fn tether_reading(&mut self, _reading: &TetherReading, _now: Instant) {}
    /// One accepted chunk of a scan, as it arrives (`part.points` holds that chunk's points only; chunks come in
    /// order). Integrating a scan chunk by chunk bounds each executive step's work by `FRAMES_PER_STEP` chunks
    /// instead of a whole scan (on the emulated board an 8000-point scan outlasts the watchdog in one step).
    fn scan_part(&mut self, _part: &Scan<'_>, _now: Instant) {}
    /// A complete scan: every chunk of it has been passed to [`Self::scan_part`]; `scan.points` holds them all.
    /// A scan abandoned incomplete (a new scan started first) gets no call: its parts stay delivered.
    fn scan_complete(&mut self, _scan: &Scan<'_>, _now: Instant) {}
    /// One accepted chunk of a terrain tile (v7): `heights` are the tile's posts `offset..` (row-major); chunks come
    /// in order and chunk 0 starts a tile (abandoning one in progress). The tile must be staged, not used, until
    /// [`Self::tile_complete`]: an upload that never completes leaves the tile in use as it was.
    fn tile_part(&mut self, _header: &TileHeader, _offset: usize, _heights: &[f32], _now: Instant) {}
    /// The tile's last chunk arrived: swap the staged tile in if it is valid. `Err` -> `Nack(Refused)`, the tile in
    /// use and its plan unchanged. Default: the tile is dropped (no planner uses it).
    fn tile_complete(&mut self, _header: &TileHeader, _now: Instant) -> Result<(), Refused> {
        Ok(())
    }
    /// A goal request (Idle / Mapping, configured). Return `Accepted` to start planning (the executive then calls
    /// [`Self::plan_step`] every step), or a final state (`InvalidInput`, `PlannerUnavailable`) to refuse it.
    fn goal(&mut self, _goal: &GoalRequest, _now: Instant) -> PlanState {
        PlanState::PlannerUnavailable
    }
    /// Runs at most `iterations` planner iterations. Fill `plan` before returning a solution state.
    fn plan_step(
        &mut self,
        _now: Instant,
        _iterations: u32,
        _plan: &mut PlanBuffer,
    ) -> PlanProgress {
        PlanProgress::Finished {
            state: PlanState::PlannerUnavailable,
            iterations: 0,
            best_cost: None,
        }
    }
    /// The next motion primitive while driving; `None` ends driving (back to Mapping). Used by the default
    /// [`Self::drive_step`].
    fn next_motion(&mut self, _now: Instant) -> Option<Motion> {
        None
    }
    /// What to do next while driving (no report awaited). Default: [`Self::next_motion`], `None` = `Finished`.
    fn drive_step(&mut self, now: Instant) -> DriveStep {
        match self.next_motion(now) {
            Some(m) => DriveStep::Motion(m),
            None => DriveStep::Finished,
        }
    }
    /// The validated report of the awaited drive command `motion` (the executive checked the command id).
    fn motion_report(&mut self, _report: &MotionReport, _motion: Motion, _now: Instant) {}
    /// No report for drive command `command_id` within `MOTION_REPORT_TIMEOUT_US`; the executive has sent `Stop`.
    fn motion_timeout(&mut self, _command_id: u32, _now: Instant) {}
    /// While a drive command is in flight (called every step until its report, bounded work): `true` when the
    /// motion must stop now (the map changed and its segment no longer checks); the executive then sends `Stop`
    /// once and waits for the report as usual.
    fn stop_in_flight(&mut self, _now: Instant) -> bool {
        false
    }
    /// A `GoalCancel` for the current goal (the executive stops the rover and returns to `Mapping`). `Err` ->
    /// `Nack(Refused)`, nothing changed. Default: refused (no mission to cancel).
    fn cancel(&mut self, _goal_id: u32, _now: Instant) -> Result<(), Refused> {
        Err(Refused)
    }
    /// Why the current goal was refused or its planning stopped with `InvalidInput`: a sentence a person can act on,
    /// which the executive forwards to the ground in a `Log` record with the `PlanStatus`. Default `None`.
    fn refusal(&self) -> Option<&'static str> {
        None
    }
    /// The mission's state for `MissionStatus` frames; `None` (the default) sends none.
    fn mission_status(&self) -> Option<MissionStatus> {
        None
    }
    /// Shutdown: stop planning and driving.
    fn abort(&mut self) {}
    /// The onboard map's state, for telemetry (zeros when there is no map).
    fn map_status(&self) -> MapStatus {
        MapStatus::default()
    }
    /// At boot, before the first step: the block of memory that survived the reset (the navigator's layout:
    /// `nav::retained`). Default: nothing to recover.
    fn recover_retained(&mut self, _block: &[u8; RETAINED_BYTES]) {}
    /// After each step: write what a reset must not lose into the retained block, if it changed since the last
    /// write. Default: nothing kept.
    fn keep_retained(&mut self, _block: &mut [u8; RETAINED_BYTES]) {}
}

/// No map, no planner: scans are reassembled and dropped, goals get `PlannerUnavailable`.
#[derive(Debug, Clone, Copy, Default)]
pub struct NoAutonomy;

impl Autonomy for NoAutonomy {}
