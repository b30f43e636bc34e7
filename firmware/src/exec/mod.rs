//! # The flight executive
//!
//! Owns the link to the host, the mode machine and the per-cycle budgets, and dispatches every protocol message
//! (`firmware/PROTOCOL.md`). Generic over the `hal` traits ([`hal::ByteLink`], [`hal::MonotonicClock`],
//! [`hal::Watchdog`]), over the planning hooks ([`Autonomy`]), and over where its large storage lives
//! ([`ExecStorage`], lent as `&'static mut` by a board or as a `Box` by the host).
//!
//! ## Modes
//! `Idle` (booted) -> `Mapping` (first scan chunk) -> `Planning` (goal accepted) -> `Driving` (plan sent) ->
//! `Mapping`; any mode -> `Safe` on `Shutdown`. The allowed transitions are [`Mode::can_become`]; anything else is
//! refused and counted (`illegal_transitions`).
//!
//! ## One step
//! [`Executive::step`] reads the clock once, kicks the watchdog, flushes queued output, then reads at most
//! `RX_BYTES_PER_STEP` bytes and dispatches at most `FRAMES_PER_STEP` frames (only while `TX_RESERVE` bytes of
//! transmit room are free, so replies are never dropped), runs `PLANNER_ITERATIONS_PER_STEP` planner iterations,
//! emits at most `PLAN_FRAMES_PER_STEP` plan / drive frames and one rate-limited `Log` frame, sends telemetry when
//! due, and flushes again. Every host frame gets exactly one `Ack` or `Nack`; a rejected frame changes nothing but
//! its rejection counter (and byte counters / high-water marks).
//!
//! ## Determinism
//! Output bytes depend only on the input bytes and the clock readings: no randomness, no hash iteration; the time
//! is read once per step and passed on.
//!
//! ## Diagnostics
//! Events go to the `log` facade (the host prints them). With `TelemetryParams.forward_log_level` the executive
//! also queues its own records (bounded, `LOG_QUEUE_LEN`) and sends them as `Log` frames, rate limited to
//! `LOG_FRAMES_PER_SECOND` with a burst of `LOG_BURST`; board glue may push records from a global `log::Log`
//! implementation through [`Executive::forward_log`].
//!
//! Parameters (`config::exec`): `RX_BYTES_PER_STEP` 1024, `FRAMES_PER_STEP` 4, `RX_STAGING_LEN` 256,
//! `TX_QUEUE_LEN` 8192, `TX_RESERVE` 4116, `TX_BYTES_PER_STEP` 4096, `LOG_QUEUE_LEN` 8, `LOG_FRAMES_PER_SECOND`
//! 10, `LOG_BURST` 4, `DEFAULT_TELEMETRY_PERIOD_US` 1 s, `PLAN_WAYPOINTS_CAPACITY` 256,
//! `PLANNER_ITERATIONS_PER_STEP` 8, `PLAN_FRAMES_PER_STEP` 1.

mod hooks;

use core::borrow::BorrowMut;
use core::fmt::Write as _;

use hal::{ByteLink, Instant, MonotonicClock, Watchdog};
use heapless::{Deque, String, Vec};

pub use hooks::{Autonomy, NoAutonomy, PlanBuffer, PlanProgress, Refused, Scan};

use crate::config::exec::*;
use crate::config::protocol::SCAN_POINTS_CAPACITY;
use crate::config::protocol::{
    HEADER_LEN, MAX_ENCODED_FRAME_LEN, MAX_LOG_TEXT, MAX_WAYPOINTS_PER_PLAN_FRAME,
};
use crate::protocol::{
    self, Ack, Configure, Deframer, Direction, DriveCommand, Frame, GoalRequest, HighWater, Log,
    LogLevel, Message, Mode, Motion, Nack, NackReason, Plan, PlanState, PlanStatus, Point3,
    ScanAssembler, SensorChunk, Telemetry, NACK_REASON_COUNT,
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

/// What one [`Executive::step`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct StepReport {
    /// Time read at the start of the step.
    pub now: Instant,
    /// Frames (or framing errors) dispatched.
    pub frames: usize,
    /// Bytes read from the link.
    pub rx_bytes: usize,
    /// Bytes written to the link.
    pub tx_bytes: usize,
    /// True when the executive has work left (input staged, output queued, planning, plan or log frames pending);
    /// false means it is quiet until new input arrives or a timer (telemetry) fires.
    pub busy: bool,
}

#[derive(Debug, Clone, Copy, Default)]
struct Counters {
    frames_accepted: u32,
    frames_rejected: [u32; NACK_REASON_COUNT],
    frames_sent: u32,
    bytes_received: u32,
    bytes_sent: u32,
    steps: u32,
    steps_rx_budget_exhausted: u32,
    steps_frame_budget_exhausted: u32,
    scans_completed: u32,
    scans_abandoned: u32,
    tether_readings: u32,
    goals_received: u32,
    log_dropped: u32,
    tx_dropped: u32,
    device_errors: u32,
    illegal_transitions: u32,
    high_water: HighWater,
}

#[derive(Debug, Clone, Copy)]
struct GoalState {
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

/// What a dispatched frame asks to send after its `Ack`.
enum Reply {
    None,
    Telemetry,
    PlanStatus,
    Stop,
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
    rx: [u8; RX_STAGING_LEN],
    rx_start: usize,
    rx_end: usize,
    tx: Deque<u8, TX_QUEUE_LEN>,
    seq_out: u32,
    counters: Counters,
    goal: Option<GoalState>,
    plan_tx: Option<PlanTx>,
    drive_command_id: u32,
    last_host_time_us: u64,
    telemetry_period_us: u64,
    last_telemetry: Option<Instant>,
    forward_level: LogLevel,
    log_queue: Deque<Log, LOG_QUEUE_LEN>,
    log_tokens: u32,
    log_refill_at: Instant,
    now: Instant,
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
            rx: [0; RX_STAGING_LEN],
            rx_start: 0,
            rx_end: 0,
            tx: Deque::new(),
            seq_out: 0,
            counters: Counters::default(),
            goal: None,
            plan_tx: None,
            drive_command_id: 0,
            last_host_time_us: 0,
            telemetry_period_us: DEFAULT_TELEMETRY_PERIOD_US,
            last_telemetry: None,
            forward_level: LogLevel::Off,
            log_queue: Deque::new(),
            log_tokens: LOG_BURST,
            log_refill_at: Instant::from_micros(0),
            now: Instant::from_micros(0),
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

    /// The current telemetry snapshot (what a `Telemetry` frame sent now would carry).
    pub fn telemetry(&self) -> Telemetry {
        let c = &self.counters;
        let (scan_in_progress, scan_next_chunk) = self
            .assembler
            .progress()
            .map_or((0, 0), |(id, next, _)| (id, next));
        let mut hw = c.high_water;
        hw.frame_len = hw.frame_len.max(self.deframer.high_water() as u32);
        hw.scan_points = hw.scan_points.max(self.assembler.high_water() as u32);
        Telemetry {
            time_us: self.now.micros,
            mode: self.mode,
            configured: self.config.is_some(),
            frames_accepted: c.frames_accepted,
            frames_rejected: c.frames_rejected,
            frames_sent: c.frames_sent,
            bytes_received: c.bytes_received,
            bytes_sent: c.bytes_sent,
            steps: c.steps,
            steps_rx_budget_exhausted: c.steps_rx_budget_exhausted,
            steps_frame_budget_exhausted: c.steps_frame_budget_exhausted,
            scans_completed: c.scans_completed,
            scans_abandoned: c.scans_abandoned,
            scan_in_progress,
            scan_next_chunk,
            tether_readings: c.tether_readings,
            goals_received: c.goals_received,
            plan_state: self.goal.map_or(PlanState::NoGoal, |g| g.state),
            log_dropped: c.log_dropped,
            tx_dropped: c.tx_dropped,
            device_errors: c.device_errors,
            illegal_transitions: c.illegal_transitions,
            high_water: hw,
            map: self.autonomy.map_status(),
        }
    }

    /// Queues a log record for forwarding as a `Log` frame if `level` passes the configured threshold. Text beyond
    /// `MAX_LOG_TEXT` bytes is cut. Returns false when the record was filtered or dropped (queue full; counted).
    pub fn forward_log(&mut self, level: LogLevel, args: core::fmt::Arguments<'_>) -> bool {
        if level == LogLevel::Off || level > self.forward_level {
            return false;
        }
        let mut text: String<MAX_LOG_TEXT> = String::new();
        // A full string stops formatting; the text written so far is kept.
        let _ = text.write_fmt(args);
        if self.log_queue.push_back(Log { level, text }).is_err() {
            self.counters.log_dropped += 1;
            return false;
        }
        self.counters.high_water.log_queue = self
            .counters
            .high_water
            .log_queue
            .max(self.log_queue.len() as u32);
        true
    }

    /// One bounded cycle of work. See the module docs.
    pub fn step(&mut self) -> StepReport {
        let now = self.clock.now();
        self.now = now;
        self.counters.steps = self.counters.steps.wrapping_add(1);
        if self.watchdog.kick().is_err() {
            self.counters.device_errors += 1;
        }
        if self.last_telemetry.is_none() {
            self.send_telemetry(now);
        }
        let mut report = StepReport {
            now,
            ..StepReport::default()
        };
        report.tx_bytes += self.flush();
        self.receive(&mut report);
        self.run_planning(now);
        self.emit_plan_or_motion(now);
        self.emit_log(now);
        if self.telemetry_period_us > 0
            && self
                .last_telemetry
                .is_some_and(|t| now.micros_since(t) >= self.telemetry_period_us)
        {
            self.send_telemetry(now);
        }
        report.tx_bytes += self.flush();
        report.busy = self.rx_start < self.rx_end
            || self.deframer.pending() > 0 && self.link.read_ready().unwrap_or(false)
            || self.link.read_ready().unwrap_or(false)
            || !self.tx.is_empty()
            || self.mode == Mode::Planning
            || self.plan_tx.is_some()
            || self.mode == Mode::Driving
            || !self.log_queue.is_empty();
        report
    }

    fn receive(&mut self, report: &mut StepReport) {
        // Each pass either reads into the empty staging buffer or consumes at least one staged byte.
        for _ in 0..2 * RX_BYTES_PER_STEP + 2 {
            if report.frames >= FRAMES_PER_STEP {
                if self.rx_start < self.rx_end || self.link.read_ready().unwrap_or(false) {
                    self.counters.steps_frame_budget_exhausted += 1;
                }
                return;
            }
            if TX_QUEUE_LEN - self.tx.len() < TX_RESERVE {
                return;
            }
            if self.rx_start >= self.rx_end {
                let budget = RX_BYTES_PER_STEP
                    .saturating_sub(report.rx_bytes)
                    .min(RX_STAGING_LEN);
                if budget == 0 {
                    if self.link.read_ready().unwrap_or(false) {
                        self.counters.steps_rx_budget_exhausted += 1;
                    }
                    return;
                }
                let n = match self.link.read(self.rx.get_mut(..budget).unwrap_or(&mut [])) {
                    Ok(n) => n.min(budget),
                    Err(_) => {
                        self.counters.device_errors += 1;
                        return;
                    }
                };
                if n == 0 {
                    return;
                }
                self.rx_start = 0;
                self.rx_end = n;
                report.rx_bytes += n;
                self.counters.bytes_received = self.counters.bytes_received.wrapping_add(n as u32);
                let hw = &mut self.counters.high_water;
                hw.rx_staging = hw.rx_staging.max(n as u32);
                hw.rx_bytes_per_step = hw.rx_bytes_per_step.max(report.rx_bytes as u32);
            }
            let staged = self.rx.get(self.rx_start..self.rx_end).unwrap_or(&[]);
            let (used, event) = self.deframer.push(staged);
            self.rx_start += used.max(1).min(self.rx_end - self.rx_start);
            let Some(event) = event else { continue };
            report.frames += 1;
            let hw = &mut self.counters.high_water;
            hw.frames_per_step = hw.frames_per_step.max(report.frames as u32);
            // Copy out of the deframer so dispatch can borrow `self` mutably (a frame is at most 2 KiB).
            let mut frame = [0u8; MAX_ENCODED_FRAME_LEN];
            let result = match event {
                Ok(bytes) => {
                    let n = bytes.len().min(frame.len());
                    if let (Some(dst), Some(src)) = (frame.get_mut(..n), bytes.get(..n)) {
                        dst.copy_from_slice(src);
                    }
                    Ok(n)
                }
                Err(e) => Err(e),
            };
            match result {
                Ok(n) => self.handle_frame(frame.get(..n).unwrap_or(&[])),
                Err(e) => self.reject(0, e.into()),
            }
        }
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
        let msg = match protocol::decode(&f) {
            Ok((_, m)) => m,
            Err(e) => return self.reject(seq, e.into()),
        };
        if msg.kind().direction() != Direction::HostToFlight {
            return self.reject(seq, NackReason::WrongDirection);
        }
        match self.dispatch(&msg) {
            Ok(reply) => {
                self.counters.frames_accepted += 1;
                self.send(&Message::Ack(Ack { seq }));
                match reply {
                    Reply::None => {}
                    Reply::Telemetry => self.send_telemetry(self.now),
                    Reply::PlanStatus => self.send_plan_status(),
                    Reply::Stop => self.send_motion(Motion::Stop),
                }
            }
            Err(reason) => self.reject(seq, reason),
        }
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
            Message::TetherReading(r) => {
                if self.mode == Mode::Safe {
                    return Err(NackReason::NotAllowedInMode);
                }
                self.autonomy.tether_reading(r, now);
                self.counters.tether_readings += 1;
                Ok(Reply::None)
            }
            Message::GoalRequest(g) => self.on_goal(g),
            Message::Shutdown(_) => {
                self.autonomy.abort();
                if let Some(g) = self.goal.as_mut() {
                    if matches!(g.state, PlanState::Accepted | PlanState::Searching) {
                        g.state = PlanState::Aborted;
                    }
                }
                self.plan_tx = None;
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
            | Message::Log(_) => Err(NackReason::WrongDirection),
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
            self.autonomy.scan(&scan, self.now);
            self.counters.scans_completed += 1;
            log::debug!("scan {} complete: {} points", done.scan_id, done.points);
        }
        if self.mode == Mode::Idle {
            self.set_mode(Mode::Mapping);
        }
        Ok(Reply::None)
    }

    fn on_goal(&mut self, g: &GoalRequest) -> Result<Reply, NackReason> {
        match self.mode {
            Mode::Safe | Mode::Planning | Mode::Driving => {
                return Err(NackReason::NotAllowedInMode)
            }
            Mode::Idle | Mode::Mapping => {}
        }
        if self.config.is_none() {
            return Err(NackReason::NotConfigured);
        }
        self.counters.goals_received += 1;
        let state = self.autonomy.goal(g, self.now);
        let state = match state {
            PlanState::Accepted | PlanState::Searching => {
                self.storage.borrow_mut().plan.clear();
                self.set_mode(Mode::Planning);
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
        self.note(
            LogLevel::Info,
            format_args!("goal {}: {state:?}", g.goal_id),
        );
        self.goal = Some(GoalState {
            goal_id: g.goal_id,
            state,
            iterations: 0,
            best_cost: None,
        });
        Ok(Reply::PlanStatus)
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

    fn emit_plan_or_motion(&mut self, now: Instant) {
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
            } else if self.mode == Mode::Driving {
                match self.autonomy.next_motion(now) {
                    Some(m) => self.send_motion(m),
                    None => {
                        self.set_mode(Mode::Mapping);
                        return;
                    }
                }
            }
        }
    }

    fn emit_log(&mut self, now: Instant) {
        let period = 1_000_000 / u64::from(LOG_FRAMES_PER_SECOND);
        let gained = now.micros_since(self.log_refill_at) / period;
        if gained > 0 {
            self.log_tokens = (self.log_tokens as u64 + gained).min(u64::from(LOG_BURST)) as u32;
            self.log_refill_at = Instant::from_micros(self.log_refill_at.micros + gained * period);
        }
        if self.log_tokens == 0 {
            return;
        }
        if let Some(rec) = self.log_queue.pop_front() {
            self.log_tokens -= 1;
            self.send(&Message::Log(rec));
        }
    }

    fn note(&mut self, level: LogLevel, args: core::fmt::Arguments<'_>) {
        match level {
            LogLevel::Error => log::error!("{args}"),
            LogLevel::Warn => log::warn!("{args}"),
            LogLevel::Info => log::info!("{args}"),
            LogLevel::Debug => log::debug!("{args}"),
            LogLevel::Trace => log::trace!("{args}"),
            LogLevel::Off => {}
        }
        self.forward_log(level, args);
    }

    fn send_telemetry(&mut self, now: Instant) {
        self.last_telemetry = Some(now);
        let t = self.telemetry();
        self.send(&Message::Telemetry(t));
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

    fn send_motion(&mut self, motion: Motion) {
        let command_id = self.drive_command_id;
        self.drive_command_id = self.drive_command_id.wrapping_add(1);
        self.send(&Message::DriveCommand(DriveCommand { command_id, motion }));
    }

    /// Encodes and queues one frame; a frame that does not fit the queue is dropped and counted.
    fn send(&mut self, msg: &Message) {
        let mut buf = [0u8; MAX_ENCODED_FRAME_LEN];
        let Ok(n) = protocol::encode(self.seq_out, msg, &mut buf) else {
            self.counters.tx_dropped += 1;
            return;
        };
        if TX_QUEUE_LEN - self.tx.len() < n {
            self.counters.tx_dropped += 1;
            return;
        }
        for &b in buf.get(..n).unwrap_or(&[]) {
            // Room was checked above.
            let _ = self.tx.push_back(b);
        }
        self.seq_out = self.seq_out.wrapping_add(1);
        self.counters.frames_sent += 1;
        self.counters.bytes_sent = self.counters.bytes_sent.wrapping_add(n as u32);
        let hw = &mut self.counters.high_water;
        hw.tx_queue = hw.tx_queue.max(self.tx.len() as u32);
    }

    /// Hands queued bytes to the link, at most `TX_BYTES_PER_STEP`.
    fn flush(&mut self) -> usize {
        let mut sent = 0;
        // At most two passes: the deque's two contiguous slices.
        for _ in 0..2 {
            let (front, _) = self.tx.as_slices();
            let want = front.len().min(TX_BYTES_PER_STEP - sent);
            if want == 0 {
                break;
            }
            let n = match self.link.write(front.get(..want).unwrap_or(&[])) {
                Ok(n) => n.min(want),
                Err(_) => {
                    self.counters.device_errors += 1;
                    break;
                }
            };
            for _ in 0..n {
                self.tx.pop_front();
            }
            sent += n;
            if n < want {
                break;
            }
        }
        sent
    }
}

#[cfg(test)]
mod tests;
