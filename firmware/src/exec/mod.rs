//! # The flight executive
//!
//! Owns the link to the host, the mode machine and the per-cycle budgets, and dispatches every protocol message
//! (`firmware/PROTOCOL.md`). Generic over the `hal` traits ([`hal::ByteLink`], [`hal::MonotonicClock`],
//! [`hal::Watchdog`]), over the planning hooks ([`Autonomy`]), and over where its large storage lives
//! ([`ExecStorage`], lent as `&'static mut` by a board or as a `Box` by the host).
//!
//! ## Modes
//! `Idle` (booted) -> `Mapping` (first scan chunk) -> `Planning` (goal accepted) -> `Driving` (plan sent) ->
//! `Mapping`; any mode -> `Safe` on `Shutdown`. A `GoalRequest` is also accepted in `Planning` and `Driving` (v2:
//! it replaces the current goal; a motion in flight is stopped with `DriveCommand{Stop}` and its report still
//! awaited), a `GoalCancel` for the current goal stops the rover and returns to `Mapping`. The allowed transitions are [`Mode::can_become`]; anything else is
//! refused and counted (`illegal_transitions`).
//!
//! ## One step
//! [`Executive::step`] is one bounded cycle: input, planning, output, telemetry, each under its own budget from
//! `config::exec` (`cycle.rs` documents the order, the budgets and the log forwarding). Every host frame gets
//! exactly one `Ack` or `Nack`; a rejected frame changes nothing but its rejection counter (and byte counters /
//! high-water marks).
//!
//! ## One drive command at a time (protocol v2)
//! In `Driving` the executive asks [`Autonomy::drive_step`] for the next motion only when no `MotionReport` is
//! awaited; it sends a `Turn` / `Straight` and awaits its report (a `Stop` is not reported). A report for any other
//! command id is `Nack(UnknownCommand)`. With no report within `MOTION_REPORT_TIMEOUT_US` of flight time it sends
//! `Stop`, forgets the command, counts `motion_report_timeouts` and calls [`Autonomy::motion_timeout`].
//! [`Autonomy::mission_status`] is polled each step; a `MissionStatus` frame goes out when its goal, state or
//! reason changed, after every accepted motion report, and after every `Telemetry` frame; a change to `Safe` or
//! `Arrived` while a report is awaited also sends `Stop`.
//!
//! ## Sequence numbers and duplicates (v4)
//! Every host frame that arrives intact (CRC good) is checked against the last `SEQ_HISTORY_LEN` intact frames: the
//! same sequence number and CRC again is a duplicate on the link, refused `Nack(DuplicateFrame)` so nothing acts on it
//! twice. Otherwise its sequence number is compared with the expected one (0 at boot, then the highest so far plus
//! one): ahead by `d <= SEQ_WINDOW` counts `d` frames lost or damaged on the way up (`Telemetry.seq_gaps`); behind by at most
//! `SEQ_WINDOW` counts a late frame (`seq_late`: reordered or delayed; still dispatched, so a retransmission or a
//! late report is handled by the message's own checks); further ahead (less than half the number range) after an
//! intact frame was seen is a loss burst (`seq_gaps` again); any other jump (further behind: a host restarted from
//! 0; or a first frame after boot not within the window ahead of 0, such as the soak's host starting near 2^32) is a
//! new host session (`seq_resyncs`). These
//! counters are the flight side's detection of link faults (`host-sim/doc/faults.md`).
//!
//! ## Lost answers (v5, issue 24)
//! The downlink can lose an `Ack`, and the host then resends a request the executive already acted on. A
//! `Configure` or `GoalRequest` whose body equals the last accepted one of its kind is answered `Ack` and not
//! dispatched again (`requests.rs`; `Telemetry.requests_repeated`). A drive command whose report has not come within
//! `DRIVE_COMMAND_RESEND_US` is sent again unchanged, every period until the report or `MOTION_REPORT_TIMEOUT_US`
//! (`Telemetry.drive_resends`); the host executes a command id once. v6: a `Stop` names the motion it stops
//! (`Motion::Stop { motion_id }`); once one is out for the awaited motion, that `Stop` is what goes again, on the same
//! schedule and counter, so a lost `Stop` is not the end of it and a late copy cannot stop the next motion.
//!
//! ## Cycle accounting (v4)
//! Each step reads the clock again at its end; the step's duration, the longest since boot and since the last
//! `Telemetry` frame, and the slips (steps longer than `STEP_BUDGET_US`) are reported in `Telemetry.cycle`, as F Prime's
//! rate groups account their cycles. A slip is also logged (`Warn`), throttled to the first slip after each
//! `Telemetry` frame (the frame carries the count). In-process the clock is the simulated one (a step takes no
//! simulated time unless the link charges host time, `host-sim` `SimClock`); free-running on the board it is SysTick.
//!
//! ## Determinism
//! Output bytes depend only on the input bytes and the clock readings: no randomness, no hash iteration; the time
//! is read once at the start of a step and passed on (the read at its end only measures the step).
//!
//! ## Layout
//! - `mod.rs`: the executive's state, the mode machine, the dispatch of each host message, planning and the
//!   transmission of a plan;
//! - `cycle.rs`: [`Executive::step`] and its budgets, the receive and transmit paths, the counters and
//!   high-water marks of `Telemetry`, log forwarding, [`StepReport`];
//! - `hooks.rs`: the [`Autonomy`] hook points where the map and the planners plug in;
//! - `requests.rs`: the last accepted requests, so a resend is answered but not acted on twice (v5);
//! - `team.rs`: the climbing team's mission (v8): `TeamConfigure`, team goals, scans, reports and orders, on the
//!   team storage lent with [`Executive::lend_team`].

mod cycle;
mod hooks;
mod requests;
mod team;

use core::borrow::BorrowMut;

use hal::{ByteLink, Instant, MonotonicClock, Watchdog};
use heapless::{Deque, Vec};

pub use cycle::StepReport;
pub use team::TeamLend;
pub use hooks::{Autonomy, DriveStep, NoAutonomy, PlanBuffer, PlanProgress, Refused, Scan};

use cycle::Counters;
use requests::LastRequests;
use team::TeamSlot;

use crate::config::exec::*;
use crate::config::protocol::SCAN_POINTS_CAPACITY;
use crate::config::protocol::{HEADER_LEN, MAX_WAYPOINTS_PER_PLAN_FRAME};
use crate::protocol::{
    self, Ack, Configure, Deframer, Direction, DriveCommand, Frame, GoalCancel, GoalRequest, Log,
    LogLevel, Message, MissionState, Mode, Motion, MotionReport, Nack, NackReason, Plan, PlanState,
    PlanStatus, PlannerChoice, Point3, ScanAssembler, SensorChunk, StopReason, TeamConfigure, TileAssembler, TileChunk,
};

impl Mode {
    /// The transition table of the mode machine.
    pub fn can_become(self, to: Mode) -> bool {
        use Mode::*;
        matches!(
            (self, to),
            (Idle, Mapping)
                | (Idle, Planning)
                | (Mapping, Planning)
                | (Planning, Mapping)
                | (Planning, Driving)
                | (Driving, Mapping)
                | (Driving, Planning)
                | (Idle | Mapping | Planning | Driving, Safe)
        )
    }
}

/// Large buffers of the executive, owned by the caller (about 130 KiB).
pub struct ExecStorage {
    /// Scan reassembly buffer.
    pub scan_points: [Point3; SCAN_POINTS_CAPACITY],
    /// The plan being built / transmitted.
    pub plan: PlanBuffer,
}

impl ExecStorage {
    /// Empty storage.
    pub const fn new() -> Self {
        Self {
            scan_points: [Point3::new(0.0, 0.0, 0.0); SCAN_POINTS_CAPACITY],
            plan: Vec::new(),
        }
    }
}

impl Default for ExecStorage {
    fn default() -> Self {
        Self::new()
    }
}

#[derive(Debug, Clone, Copy)]
struct ActiveGoal {
    goal_id: u32,
    state: PlanState,
    iterations: u32,
    best_cost: Option<f32>,
}

#[derive(Debug, Clone, Copy)]
struct PlanTx {
    goal_id: u32,
    next_part: u16,
    parts: u16,
}

/// The drive command whose `MotionReport` is awaited.
#[derive(Debug, Clone, Copy)]
struct Awaiting {
    command_id: u32,
    motion: Motion,
    sent_at: Instant,
    /// When it was last sent (again: `DRIVE_COMMAND_RESEND_US`).
    last_sent: Instant,
    /// The `command_id` of the `Stop` sent for it (v6: resent like a drive command until the report comes).
    stop_id: Option<u32>,
}

/// What a dispatched frame asks to send after its `Ack`.
enum Reply {
    None,
    Telemetry,
    PlanStatus,
    /// `PlanStatus`, then `Stop` (a goal replaced while a motion was in flight).
    PlanStatusAndStop,
    Stop,
    MissionStatus,
    /// The pending team order (v8).
    TeamCommand,
    /// `PlanStatus`, then the team mission's first order (v8).
    PlanStatusAndTeam,
}

/// The flight executive. See the module docs.
pub struct Executive<L, C, W, A, S> {
    link: L,
    clock: C,
    watchdog: W,
    autonomy: A,
    storage: S,
    mode: Mode,
    config: Option<Configure>,
    deframer: Deframer,
    assembler: ScanAssembler,
    tiles: TileAssembler,
    rx: [u8; RX_STAGING_LEN],
    rx_start: usize,
    rx_end: usize,
    tx: Deque<u8, TX_QUEUE_LEN>,
    seq_out: u32,
    counters: Counters,
    goal: Option<ActiveGoal>,
    plan_tx: Option<PlanTx>,
    drive_command_id: u32,
    /// The `command_id` of the last `Turn` / `Straight` sent (none since boot).
    last_motion_id: Option<u32>,
    awaiting: Option<Awaiting>,
    last_mission: Option<(u32, MissionState, StopReason)>,
    last_host_time_us: u64,
    telemetry_period_us: u64,
    last_telemetry: Option<Instant>,
    forward_level: LogLevel,
    log_queue: Deque<Log, LOG_QUEUE_LEN>,
    log_tokens: u32,
    log_refill_at: Instant,
    now: Instant,
    seq_next: u32,
    /// An intact host frame has arrived since boot (before that, a jump ahead is a session, not a loss burst).
    seq_seen: bool,
    seq_history: Deque<(u32, u32), SEQ_HISTORY_LEN>,
    /// The last accepted `Configure` and `GoalRequest` (v5: a resend is answered, not acted on again).
    requests: LastRequests,
    /// The team mission's set-up (v8), kept for the next team goal.
    team_cfg: Option<TeamConfigure>,
    /// The team mission and its storage (v8, `team.rs`).
    team: TeamSlot,
}

impl<L, C, W, A, S> Executive<L, C, W, A, S>
where
    L: ByteLink,
    C: MonotonicClock,
    W: Watchdog,
    A: Autonomy,
    S: BorrowMut<ExecStorage>,
{
    /// A freshly booted executive in `Idle` mode.
    pub fn new(link: L, clock: C, watchdog: W, autonomy: A, storage: S) -> Self {
        Self {
            link,
            clock,
            watchdog,
            autonomy,
            storage,
            mode: Mode::Idle,
            config: None,
            deframer: Deframer::new(),
            assembler: ScanAssembler::new(),
            tiles: TileAssembler::new(),
            rx: [0; RX_STAGING_LEN],
            rx_start: 0,
            rx_end: 0,
            tx: Deque::new(),
            seq_out: 0,
            counters: Counters::default(),
            goal: None,
            plan_tx: None,
            drive_command_id: 0,
            last_motion_id: None,
            awaiting: None,
            last_mission: None,
            last_host_time_us: 0,
            telemetry_period_us: DEFAULT_TELEMETRY_PERIOD_US,
            last_telemetry: None,
            forward_level: LogLevel::Off,
            log_queue: Deque::new(),
            log_tokens: LOG_BURST,
            log_refill_at: Instant::from_micros(0),
            now: Instant::from_micros(0),
            seq_next: 0,
            seq_seen: false,
            seq_history: Deque::new(),
            requests: LastRequests::default(),
            team_cfg: None,
            team: TeamSlot::Unlent,
        }
    }

    /// Current mode.
    pub fn mode(&self) -> Mode {
        self.mode
    }

    /// The accepted configuration, if any.
    pub fn config(&self) -> Option<&Configure> {
        self.config.as_ref()
    }

    /// The planning hooks.
    pub fn autonomy(&self) -> &A {
        &self.autonomy
    }

    /// The planning hooks, mutably (for glue code between steps).
    pub fn autonomy_mut(&mut self) -> &mut A {
        &mut self.autonomy
    }

    /// The link (host glue pushes simulated bytes through it).
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// The link.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The clock.
    pub fn clock(&self) -> &C {
        &self.clock
    }

    /// The clock (a simulated clock is advanced through it).
    pub fn clock_mut(&mut self) -> &mut C {
        &mut self.clock
    }

    fn handle_frame(&mut self, bytes: &[u8]) {
        let f = Frame::new_unchecked(bytes);
        let seq = if bytes.len() >= HEADER_LEN {
            f.seq()
        } else {
            0
        };
        if let Err(e) = f.check() {
            return self.reject(seq, e.into());
        }
        if let Err(reason) = self.track_seq(seq, f.crc()) {
            return self.reject(seq, reason);
        }
        let msg = match protocol::decode(&f) {
            Ok((_, m)) => m,
            Err(e) => return self.reject(seq, e.into()),
        };
        if msg.kind().direction() != Direction::HostToFlight {
            return self.reject(seq, NackReason::WrongDirection);
        }
        if self.requests.is_repeat(&msg, f.body()) {
            // a resend of a request already acted on (its Ack was lost): the same answer, no second action (v5)
            self.counters.requests_repeated = self.counters.requests_repeated.saturating_add(1);
            log::debug!("frame {seq}: a {:?} already acted on; answered, not applied again", msg.kind());
            self.counters.frames_accepted += 1;
            self.send(&Message::Ack(Ack { seq }));
            return;
        }
        match self.dispatch(&msg) {
            Ok(reply) => {
                self.requests.accepted(&msg, f.body());
                self.counters.frames_accepted += 1;
                self.send(&Message::Ack(Ack { seq }));
                match reply {
                    Reply::None => {}
                    Reply::Telemetry => self.send_telemetry(self.now),
                    Reply::PlanStatus => self.send_plan_status(),
                    Reply::PlanStatusAndStop => {
                        self.send_plan_status();
                        self.send_stop();
                    }
                    Reply::Stop => self.send_stop(),
                    Reply::MissionStatus => self.send_mission_status(),
                    Reply::TeamCommand => self.send_team_command(),
                    Reply::PlanStatusAndTeam => {
                        self.send_plan_status();
                        self.send_team_command();
                    }
                }
            }
            Err(reason) => self.reject(seq, reason),
        }
    }

    /// Refuses a duplicate and counts lost, late and resynchronised host sequence numbers (module docs).
    fn track_seq(&mut self, seq: u32, crc: u32) -> Result<(), NackReason> {
        if self.seq_history.iter().any(|&h| h == (seq, crc)) {
            return Err(NackReason::DuplicateFrame);
        }
        if self.seq_history.is_full() {
            self.seq_history.pop_front();
        }
        // Room was made above.
        let _ = self.seq_history.push_back((seq, crc));
        let c = &mut self.counters;
        // The host counts its frames from 0 (PROTOCOL.md section 1), so a lost first frame is a gap too.
        let (ahead, behind) = (seq.wrapping_sub(self.seq_next), self.seq_next.wrapping_sub(seq));
        if ahead <= SEQ_WINDOW {
            c.seq_gaps = c.seq_gaps.saturating_add(ahead);
            self.seq_next = seq.wrapping_add(1);
        } else if self.seq_seen && behind <= SEQ_WINDOW {
            c.seq_late = c.seq_late.saturating_add(1);
        } else if self.seq_seen && ahead < 1 << 31 {
            // A loss burst longer than the window: a restarted host counts from 0, so it shows behind, not ahead.
            c.seq_gaps = c.seq_gaps.saturating_add(ahead);
            self.seq_next = seq.wrapping_add(1);
        } else {
            c.seq_resyncs = c.seq_resyncs.saturating_add(1);
            self.seq_next = seq.wrapping_add(1);
        }
        self.seq_seen = true;
        Ok(())
    }

    fn reject(&mut self, seq: u32, reason: NackReason) {
        if let Some(c) = self.counters.frames_rejected.get_mut(reason.index()) {
            *c += 1;
        }
        log::warn!("rejected frame seq {seq}: {reason:?}");
        self.send(&Message::Nack(Nack { seq, reason }));
    }

    /// Checks everything first, then changes state; an `Err` leaves the executive as it was.
    fn dispatch(&mut self, msg: &Message) -> Result<Reply, NackReason> {
        let now = self.now;
        match msg {
            Message::TimeTick(t) => {
                self.last_host_time_us = t.host_time_us;
                Ok(Reply::None)
            }
            Message::TelemetryRequest(_) => Ok(Reply::Telemetry),
            Message::Configure(cfg) => {
                if !matches!(self.mode, Mode::Idle | Mode::Mapping) {
                    return Err(NackReason::NotAllowedInMode);
                }
                self.autonomy
                    .configure(cfg)
                    .map_err(|Refused| NackReason::Refused)?;
                self.config = Some(*cfg);
                self.telemetry_period_us = u64::from(cfg.telemetry.period_ms) * 1000;
                self.forward_level = cfg.telemetry.forward_log_level;
                self.note(
                    LogLevel::Info,
                    format_args!("configured (seed {})", cfg.planner.rng_seed),
                );
                Ok(Reply::None)
            }
            Message::SensorChunk(chunk) => self.on_chunk(chunk),
            Message::TileChunk(chunk) => self.on_tile_chunk(chunk),
            Message::TetherReading(r) => {
                if self.mode == Mode::Safe {
                    return Err(NackReason::NotAllowedInMode);
                }
                self.autonomy.tether_reading(r, now);
                self.counters.tether_readings += 1;
                Ok(Reply::None)
            }
            Message::GoalRequest(g) => self.on_goal(g),
            Message::MotionReport(r) => self.on_motion_report(r),
            Message::GoalCancel(c) => self.on_cancel(c),
            Message::TeamConfigure(c) => self.on_team_configure(c),
            Message::TeamScanChunk(c) => self.on_team_scan(c),
            Message::TeamReport(r) => self.on_team_report(r),
            Message::Shutdown(_) => {
                self.autonomy.abort();
                self.team_abort();
                if let Some(g) = self.goal.as_mut() {
                    if matches!(g.state, PlanState::Accepted | PlanState::Searching) {
                        g.state = PlanState::Aborted;
                    }
                }
                self.plan_tx = None;
                self.awaiting = None;
                if self.mode != Mode::Safe {
                    self.set_mode(Mode::Safe);
                }
                self.note(LogLevel::Warn, format_args!("shutdown: safe mode"));
                Ok(Reply::Stop)
            }
            // Flight -> host kinds are refused before dispatch.
            Message::Ack(_)
            | Message::Nack(_)
            | Message::PlanStatus(_)
            | Message::Plan(_)
            | Message::DriveCommand(_)
            | Message::Telemetry(_)
            | Message::Log(_)
            | Message::MissionStatus(_)
            | Message::TeamCommand(_) => Err(NackReason::WrongDirection),
        }
    }

    fn on_chunk(&mut self, chunk: &SensorChunk) -> Result<Reply, NackReason> {
        if self.mode == Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        if self.config.is_none() {
            return Err(NackReason::NotConfigured);
        }
        let storage = self.storage.borrow_mut();
        let accepted = self.assembler.accept(chunk, &mut storage.scan_points)?;
        let part = Scan {
            scan_id: chunk.scan_id,
            sensor_pose: chunk.sensor_pose,
            points: &chunk.points,
        };
        self.autonomy.scan_part(&part, self.now);
        if let Some(old) = accepted.abandoned {
            self.counters.scans_abandoned += 1;
            self.note(
                LogLevel::Warn,
                format_args!("scan {old} abandoned incomplete"),
            );
        }
        if let Some(done) = accepted.complete {
            let storage = self.storage.borrow_mut();
            let scan = Scan {
                scan_id: done.scan_id,
                sensor_pose: done.sensor_pose,
                points: storage.scan_points.get(..done.points).unwrap_or(&[]),
            };
            self.autonomy.scan_complete(&scan, self.now);
            self.counters.scans_completed += 1;
            log::debug!("scan {} complete: {} points", done.scan_id, done.points);
        }
        if self.mode == Mode::Idle {
            self.set_mode(Mode::Mapping);
        }
        Ok(Reply::None)
    }

    /// A terrain-tile chunk (v7): order and shape checked by the [`TileAssembler`] (a rejection changes nothing),
    /// then staged by the autonomy; the last chunk swaps the tile in. Any mode but `Safe`, configured or not (the
    /// tile is the ground's, not the rover's).
    fn on_tile_chunk(&mut self, chunk: &TileChunk) -> Result<Reply, NackReason> {
        if self.mode == Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        let accepted = self.tiles.accept(chunk)?;
        if let Some(old) = accepted.abandoned {
            self.note(LogLevel::Warn, format_args!("tile {old} abandoned incomplete"));
        }
        self.autonomy.tile_part(&accepted.header, accepted.offset, &chunk.heights, self.now);
        if accepted.complete {
            let id = accepted.header.tile_id;
            if self.autonomy.tile_complete(&accepted.header, self.now).is_err() {
                self.note(LogLevel::Warn, format_args!("tile {id} refused; the tile in use is kept"));
                return Err(NackReason::Refused);
            }
            self.note(LogLevel::Info, format_args!("tile {id} complete"));
        }
        Ok(Reply::None)
    }

    fn on_motion_report(&mut self, r: &MotionReport) -> Result<Reply, NackReason> {
        if self.mode == Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        let Some(a) = self.awaiting.filter(|a| a.command_id == r.command_id) else {
            return Err(NackReason::UnknownCommand);
        };
        self.awaiting = None;
        self.counters.motion_reports += 1;
        self.autonomy.motion_report(r, a.motion, self.now);
        Ok(Reply::MissionStatus)
    }

    fn on_cancel(&mut self, c: &GoalCancel) -> Result<Reply, NackReason> {
        if self.mode == Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        let current = self.goal.is_some_and(|g| g.goal_id == c.goal_id);
        if !current || !matches!(self.mode, Mode::Planning | Mode::Driving) {
            return Err(NackReason::UnknownGoal);
        }
        self.autonomy
            .cancel(c.goal_id, self.now)
            .map_err(|Refused| NackReason::Refused)?;
        if let Some(g) = self.goal.as_mut() {
            if matches!(g.state, PlanState::Accepted | PlanState::Searching) {
                g.state = PlanState::Aborted;
            }
        }
        self.plan_tx = None;
        self.counters.goal_cancels += 1;
        self.set_mode(Mode::Mapping);
        self.note(LogLevel::Info, format_args!("goal {} cancelled", c.goal_id));
        Ok(Reply::Stop)
    }

    fn on_goal(&mut self, g: &GoalRequest) -> Result<Reply, NackReason> {
        if self.mode == Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        if g.planner == PlannerChoice::Team {
            return self.on_goal_team(g);
        }
        if self.config.is_none() {
            return Err(NackReason::NotConfigured);
        }
        self.counters.goals_received += 1;
        // A goal while planning or driving replaces the current one: nothing more of the old plan goes out, and a
        // motion in flight is stopped (its report is still awaited, so the next command starts from where the
        // rover stopped).
        let replacing = matches!(self.mode, Mode::Planning | Mode::Driving);
        self.plan_tx = None;
        let stop = replacing && self.awaiting.is_some();
        let state = self.autonomy.goal(g, self.now);
        let state = match state {
            PlanState::Accepted | PlanState::Searching => {
                self.storage.borrow_mut().plan.clear();
                if self.mode != Mode::Planning {
                    self.set_mode(Mode::Planning);
                }
                PlanState::Accepted
            }
            PlanState::ExactSolution | PlanState::ApproximateSolution | PlanState::NoGoal => {
                // A hook may not skip planning; treat as a bug in the hook, reported honestly.
                self.note(
                    LogLevel::Error,
                    format_args!("goal hook returned {state:?}; treated as invalid"),
                );
                PlanState::InvalidInput
            }
            other => other,
        };
        match self.autonomy.refusal().filter(|_| state == PlanState::InvalidInput) {
            Some(why) => self.note(
                LogLevel::Warn,
                format_args!("goal {} refused: {why}", g.goal_id),
            ),
            None => self.note(
                LogLevel::Info,
                format_args!("goal {}: {state:?}", g.goal_id),
            ),
        }
        if replacing && state != PlanState::Accepted {
            self.set_mode(Mode::Mapping);
        }
        self.set_goal(g.goal_id, state);
        Ok(if stop {
            Reply::PlanStatusAndStop
        } else {
            Reply::PlanStatus
        })
    }

    /// A team goal (v8): needs a `TeamConfigure`, not a `Configure`; refused (`NoTeam`) while a team mission runs
    /// or before its configuration; started on the lent team storage (`team.rs`). The mission runs in `Mapping`.
    fn on_goal_team(&mut self, g: &GoalRequest) -> Result<Reply, NackReason> {
        if !matches!(self.mode, Mode::Idle | Mode::Mapping) {
            return Err(NackReason::NotAllowedInMode);
        }
        let state = self.on_team_goal(g)?;
        self.counters.goals_received += 1;
        self.plan_tx = None;
        // The mission steps inside the dispatch of each report, so the executive is not `Planning` between them.
        if state == PlanState::Accepted && self.mode == Mode::Idle {
            self.set_mode(Mode::Mapping);
        }
        self.set_goal(g.goal_id, state);
        Ok(if state == PlanState::Accepted {
            Reply::PlanStatusAndTeam
        } else {
            Reply::PlanStatus
        })
    }

    /// The goal now planned (or refused) is `goal_id`, in `state`.
    fn set_goal(&mut self, goal_id: u32, state: PlanState) {
        self.goal = Some(ActiveGoal {
            goal_id,
            state,
            iterations: 0,
            best_cost: None,
        });
    }

    fn set_mode(&mut self, to: Mode) {
        if self.mode.can_become(to) {
            log::info!("mode {:?} -> {:?}", self.mode, to);
            self.mode = to;
        } else {
            self.counters.illegal_transitions += 1;
            log::error!(
                "illegal mode transition {:?} -> {:?} refused",
                self.mode,
                to
            );
        }
    }

    fn run_planning(&mut self, now: Instant) {
        if self.mode != Mode::Planning {
            return;
        }
        let Some(mut g) = self.goal else {
            self.set_mode(Mode::Mapping);
            return;
        };
        let progress = self.autonomy.plan_step(
            now,
            PLANNER_ITERATIONS_PER_STEP,
            &mut self.storage.borrow_mut().plan,
        );
        match progress {
            PlanProgress::Searching {
                iterations,
                best_cost,
            } => {
                let first = g.state != PlanState::Searching;
                g.state = PlanState::Searching;
                g.iterations = iterations;
                g.best_cost = best_cost;
                self.goal = Some(g);
                if first {
                    self.send_plan_status();
                }
            }
            PlanProgress::Finished {
                state,
                iterations,
                best_cost,
            } => {
                g.iterations = iterations;
                g.best_cost = best_cost;
                let waypoints = self.storage.borrow_mut().plan.len();
                let solved = matches!(
                    state,
                    PlanState::ExactSolution | PlanState::ApproximateSolution
                );
                g.state = if solved && waypoints == 0 {
                    self.note(
                        LogLevel::Error,
                        format_args!("planner reported {state:?} with an empty plan"),
                    );
                    PlanState::InvalidInput
                } else {
                    state
                };
                self.goal = Some(g);
                self.send_plan_status();
                if let Some(why) = self.autonomy.refusal().filter(|_| g.state == PlanState::InvalidInput) {
                    self.note(
                        LogLevel::Warn,
                        format_args!("goal {}: planning stopped: {why}", g.goal_id),
                    );
                }
                if solved && waypoints > 0 {
                    let parts = waypoints.div_ceil(MAX_WAYPOINTS_PER_PLAN_FRAME) as u16;
                    self.plan_tx = Some(PlanTx {
                        goal_id: g.goal_id,
                        next_part: 0,
                        parts,
                    });
                    self.set_mode(Mode::Driving);
                } else {
                    self.set_mode(Mode::Mapping);
                }
            }
        }
    }

    /// Gives up the awaited report after `MOTION_REPORT_TIMEOUT_US` (any mode but `Safe`, which clears it).
    fn check_report_timeout(&mut self, now: Instant) {
        let Some(mut a) = self.awaiting else { return };
        if now.micros_since(a.sent_at) < MOTION_REPORT_TIMEOUT_US {
            // v5: the downlink may have lost the command; it goes again, unchanged, until the report comes (the
            // host executes a command id once). Once a `Stop` is out for it, the `Stop` goes again instead (v6: it
            // names this motion, so a late copy cannot stop another).
            if now.micros_since(a.last_sent) >= DRIVE_COMMAND_RESEND_US {
                a.last_sent = now;
                self.awaiting = Some(a);
                self.counters.drive_resends = self.counters.drive_resends.saturating_add(1);
                let (command_id, motion) = match a.stop_id {
                    Some(id) => (id, Motion::Stop { motion_id: a.command_id }),
                    None => (a.command_id, a.motion),
                };
                self.send(&Message::DriveCommand(DriveCommand { command_id, motion }));
            }
            return;
        }
        self.awaiting = None;
        self.counters.motion_report_timeouts += 1;
        self.note(
            LogLevel::Warn,
            format_args!("no report for drive command {}: stop", a.command_id),
        );
        self.send_stop_of(Some(a.command_id));
        self.autonomy.motion_timeout(a.command_id, now);
    }

    fn emit_plan_or_motion(&mut self, now: Instant) {
        self.check_report_timeout(now);
        self.resend_team_command(now);
        for _ in 0..PLAN_FRAMES_PER_STEP {
            if let Some(mut tx) = self.plan_tx {
                let start = usize::from(tx.next_part) * MAX_WAYPOINTS_PER_PLAN_FRAME;
                let plan = &self.storage.borrow_mut().plan;
                let end = (start + MAX_WAYPOINTS_PER_PLAN_FRAME).min(plan.len());
                let mut waypoints = Vec::new();
                for w in plan.get(start..end).unwrap_or(&[]) {
                    // Capacity equals the slice bound above; a failure here cannot happen and would only shorten.
                    let _ = waypoints.push(w.clone());
                }
                let msg = Message::Plan(Plan {
                    goal_id: tx.goal_id,
                    part: tx.next_part,
                    parts: tx.parts,
                    waypoints,
                });
                self.send(&msg);
                tx.next_part += 1;
                self.plan_tx = if tx.next_part >= tx.parts {
                    None
                } else {
                    Some(tx)
                };
            } else if self.awaiting.is_some_and(|a| self.mode == Mode::Driving && a.stop_id.is_none()) {
                if self.autonomy.stop_in_flight(now) {
                    self.send_stop();
                }
                return;
            } else if self.mode == Mode::Driving && self.awaiting.is_none() {
                match self.autonomy.drive_step(now) {
                    DriveStep::Motion(m) => {
                        self.send_motion(m);
                        return;
                    }
                    DriveStep::Wait => return,
                    DriveStep::Replan => {
                        if let Some(g) = self.goal.as_mut() {
                            g.state = PlanState::Accepted;
                            g.iterations = 0;
                            g.best_cost = None;
                        }
                        self.storage.borrow_mut().plan.clear();
                        self.set_mode(Mode::Planning);
                        return;
                    }
                    DriveStep::Finished => {
                        self.set_mode(Mode::Mapping);
                        return;
                    }
                }
            }
        }
    }

    /// Sends a `MissionStatus` when the autonomy's mission goal, state or reason changed since the last one sent.
    fn emit_mission_change(&mut self) {
        let Some(m) = self.autonomy.mission_status() else {
            return;
        };
        if self.last_mission != Some((m.goal_id, m.state, m.reason)) {
            self.send_mission_status();
            // A safe stop (or arrival) decided between reports, e.g. on a tether reading: stop the motion in
            // flight now (its report is still awaited).
            if matches!(m.state, MissionState::Safe | MissionState::Arrived) && self.awaiting.is_some() {
                self.send_stop();
            }
        }
    }

    /// Sends the autonomy's `MissionStatus` (none without a mission).
    pub(super) fn send_mission_status(&mut self) {
        if let Some(m) = self.autonomy.mission_status() {
            self.last_mission = Some((m.goal_id, m.state, m.reason));
            self.send(&Message::MissionStatus(m));
        }
    }

    fn send_plan_status(&mut self) {
        if let Some(g) = self.goal {
            self.send(&Message::PlanStatus(PlanStatus {
                goal_id: g.goal_id,
                state: g.state,
                iterations: g.iterations,
                best_cost: g.best_cost,
            }));
        }
    }

    /// Sends a `Turn` or `Straight` and awaits its report.
    fn send_motion(&mut self, motion: Motion) {
        let command_id = self.next_command_id();
        self.last_motion_id = Some(command_id);
        self.awaiting = Some(Awaiting {
            command_id,
            motion,
            sent_at: self.now,
            last_sent: self.now,
            stop_id: None,
        });
        self.send(&Message::DriveCommand(DriveCommand { command_id, motion }));
    }

    /// Stops the motion awaiting its report (its report is still awaited, and the `Stop` is resent until it comes),
    /// or, with none, sends a `Stop` of the last motion (already reported: the host does nothing with it); before any
    /// motion, a `Stop` naming its own command id, which names no motion (PROTOCOL.md section 5).
    fn send_stop(&mut self) {
        match self.awaiting {
            Some(mut a) => {
                // a second stop of the same motion (a goal change after a stop in flight) is the same command
                let stop_id = match a.stop_id {
                    Some(id) => id,
                    None => self.next_command_id(),
                };
                a.stop_id = Some(stop_id);
                a.last_sent = self.now;
                self.awaiting = Some(a);
                self.send(&Message::DriveCommand(DriveCommand {
                    command_id: stop_id,
                    motion: Motion::Stop { motion_id: a.command_id },
                }));
            }
            None => self.send_stop_of(self.last_motion_id),
        }
    }

    /// Sends a `Stop` of motion `motion_id` with nothing awaited for it (`None`: no motion, the stop's own id).
    fn send_stop_of(&mut self, motion_id: Option<u32>) {
        let command_id = self.next_command_id();
        let motion = Motion::Stop { motion_id: motion_id.unwrap_or(command_id) };
        self.send(&Message::DriveCommand(DriveCommand { command_id, motion }));
    }

    fn next_command_id(&mut self) -> u32 {
        let id = self.drive_command_id;
        self.drive_command_id = self.drive_command_id.wrapping_add(1);
        id
    }
}

#[cfg(test)]
mod tests;
