//! # One executive cycle: its budgets, its accounting, its output
//!
//! [`Executive::step`] reads the clock once, kicks the watchdog, flushes queued output, then reads at most
//! `RX_BYTES_PER_STEP` bytes and dispatches at most `FRAMES_PER_STEP` frames (only while `TX_RESERVE` bytes of
//! transmit room are free, so replies are never dropped), runs `PLANNER_ITERATIONS_PER_STEP` planner iterations,
//! emits at most `PLAN_FRAMES_PER_STEP` plan / drive frames (one drive command, and none while its report is
//! awaited), a `MissionStatus` when the mission changed, one rate-limited `Log` frame, sends telemetry (and the
//! mission status with it) when due, and flushes again (at most `TX_BYTES_PER_STEP` bytes per flush). [`StepReport`] says what the step did.
//!
//! Accounting: the counters and high-water marks of every `Telemetry` frame ([`Executive::telemetry`]) are kept
//! here; a full transmit queue drops the frame and counts it (`tx_dropped`), a link or watchdog error counts as
//! `device_errors`, a budget that stops a step with input still pending counts as `steps_rx_budget_exhausted` /
//! `steps_frame_budget_exhausted`.
//!
//! ## Diagnostics
//! Events go to the `log` facade (the host prints them). With `TelemetryConfig.forward_log_level` the executive
//! also queues its own records (bounded, `LOG_QUEUE_LEN`) and sends them as `Log` frames, rate limited to
//! `LOG_FRAMES_PER_SECOND` with a burst of `LOG_BURST`; board glue may push records from a global `log::Log`
//! implementation through [`Executive::forward_log`].
//!
//! Parameters (`config::exec`): `RX_BYTES_PER_STEP` 1024, `FRAMES_PER_STEP` 4, `RX_STAGING_LEN` 256,
//! `TX_QUEUE_LEN` 8192, `TX_RESERVE` 4116, `TX_BYTES_PER_STEP` 4096, `LOG_QUEUE_LEN` 8, `LOG_FRAMES_PER_SECOND`
//! 10, `LOG_BURST` 4, `DEFAULT_TELEMETRY_PERIOD_US` 1 s, `PLAN_WAYPOINTS_CAPACITY` 256,
//! `PLANNER_ITERATIONS_PER_STEP` 8, `PLAN_FRAMES_PER_STEP` 1, `MOTION_REPORT_TIMEOUT_US` 120 s, `STEP_BUDGET_US`
//! 100 ms (cycle accounting: the step's duration is the clock read at its end minus the one at its start; module
//! docs of `exec`).

use core::borrow::BorrowMut;
use core::fmt::Write as _;

use hal::{ByteLink, Instant, MonotonicClock, Watchdog};
use heapless::String;

use super::{Autonomy, ExecStorage, Executive};
use crate::config::exec::*;
use crate::config::protocol::{MAX_ENCODED_FRAME_LEN, MAX_LOG_TEXT};
use crate::protocol::{
    self, CycleStats, HighWater, Log, LogLevel, Message, Mode, PlanState, Telemetry, NACK_REASON_COUNT,
};

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

/// The executive's counters and high-water marks, as a `Telemetry` frame reports them.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Counters {
    pub(super) frames_accepted: u32,
    pub(super) frames_rejected: [u32; NACK_REASON_COUNT],
    pub(super) frames_sent: u32,
    pub(super) bytes_received: u32,
    pub(super) bytes_sent: u32,
    pub(super) steps: u32,
    pub(super) steps_rx_budget_exhausted: u32,
    pub(super) steps_frame_budget_exhausted: u32,
    pub(super) scans_completed: u32,
    pub(super) scans_abandoned: u32,
    pub(super) tether_readings: u32,
    pub(super) goals_received: u32,
    pub(super) motion_reports: u32,
    pub(super) motion_report_timeouts: u32,
    pub(super) goal_cancels: u32,
    pub(super) log_dropped: u32,
    pub(super) tx_dropped: u32,
    pub(super) device_errors: u32,
    pub(super) illegal_transitions: u32,
    pub(super) high_water: HighWater,
    pub(super) seq_gaps: u32,
    pub(super) seq_late: u32,
    pub(super) seq_resyncs: u32,
    pub(super) requests_repeated: u32,
    pub(super) drive_resends: u32,
    pub(super) cycle: CycleStats,
    /// A slip was logged since the last `Telemetry` frame (the throttle).
    pub(super) slip_noted: bool,
}

impl<L, C, W, A, S> Executive<L, C, W, A, S>
where
    L: ByteLink,
    C: MonotonicClock,
    W: Watchdog,
    A: Autonomy,
    S: BorrowMut<ExecStorage>,
{
    /// The current telemetry snapshot (what a `Telemetry` frame sent now would carry).
    pub fn telemetry(&self) -> Telemetry {
        let c = &self.counters;
        let (scan_in_progress, scan_chunks_received) = self
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
            scan_chunks_received,
            tether_readings: c.tether_readings,
            goals_received: c.goals_received,
            motion_reports: c.motion_reports,
            motion_report_timeouts: c.motion_report_timeouts,
            goal_cancels: c.goal_cancels,
            plan_state: self.goal.map_or(PlanState::NoGoal, |g| g.state),
            log_dropped: c.log_dropped,
            tx_dropped: c.tx_dropped,
            device_errors: c.device_errors,
            illegal_transitions: c.illegal_transitions,
            high_water: hw,
            map: self.autonomy.map_status(),
            seq_gaps: c.seq_gaps,
            seq_late: c.seq_late,
            seq_resyncs: c.seq_resyncs,
            requests_repeated: c.requests_repeated,
            drive_resends: c.drive_resends,
            cycle: CycleStats {
                budget_us: u32::try_from(STEP_BUDGET_US).unwrap_or(u32::MAX),
                ..c.cycle
            },
        }
    }

    /// Queues a log record for forwarding as a `Log` frame if `level` passes the configured threshold. Text beyond
    /// `MAX_LOG_TEXT` bytes is cut. Returns false when the record was filtered or dropped (queue full; counted).
    pub fn forward_log(&mut self, level: LogLevel, args: core::fmt::Arguments<'_>) -> bool {
        if level == LogLevel::Off || level > self.forward_level {
            return false;
        }
        let mut text: String<MAX_LOG_TEXT> = String::new();
        // A full string stops formatting; the text written so far is kept, up to the last whole character.
        let _ = CutAtCapacity(&mut text).write_fmt(args);
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
        self.emit_mission_change();
        self.emit_log(now);
        if self.telemetry_period_us > 0
            && self
                .last_telemetry
                .is_some_and(|t| now.micros_since(t) >= self.telemetry_period_us)
        {
            self.send_telemetry(now);
        }
        report.tx_bytes += self.flush();
        let end = self.clock.now();
        self.account_cycle(end.micros_since(now));
        report.busy = self.rx_start < self.rx_end
            || self.deframer.pending() > 0 && self.link.read_ready().unwrap_or(false)
            || self.link.read_ready().unwrap_or(false)
            || !self.tx.is_empty()
            || self.mode == Mode::Planning
            || self.plan_tx.is_some()
            || self.mode == Mode::Driving && self.awaiting.is_none()
            || !self.log_queue.is_empty();
        report
    }

    /// Cycle accounting of one step of `took_us` on the flight clock; logs the first slip after each telemetry frame.
    fn account_cycle(&mut self, took_us: u64) {
        let took = u32::try_from(took_us).unwrap_or(u32::MAX);
        let c = &mut self.counters.cycle;
        c.max_step_us = c.max_step_us.max(took);
        c.period_max_step_us = c.period_max_step_us.max(took);
        if took_us > STEP_BUDGET_US {
            c.slips = c.slips.saturating_add(1);
            if !self.counters.slip_noted {
                self.counters.slip_noted = true;
                self.note(
                    LogLevel::Warn,
                    format_args!("cycle slip: step took {took_us} us, budget {STEP_BUDGET_US} us"),
                );
            }
        }
    }

    /// Reads at most `RX_BYTES_PER_STEP` bytes and dispatches at most `FRAMES_PER_STEP` frames, only while
    /// `TX_RESERVE` bytes of transmit room are free.
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

    /// Sends at most one queued `Log` frame, rate limited by a token bucket (`LOG_FRAMES_PER_SECOND`, depth
    /// `LOG_BURST`).
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

    /// Logs a record through the `log` facade and queues it for forwarding ([`Executive::forward_log`]).
    pub(super) fn note(&mut self, level: LogLevel, args: core::fmt::Arguments<'_>) {
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

    /// Queues a `Telemetry` frame with the current snapshot and restarts the telemetry period.
    pub(super) fn send_telemetry(&mut self, now: Instant) {
        self.last_telemetry = Some(now);
        let t = self.telemetry();
        // The period's longest step and the slip-log throttle restart with each frame.
        self.counters.cycle.period_max_step_us = 0;
        self.counters.slip_noted = false;
        self.send(&Message::Telemetry(t));
        self.send_mission_status();
    }

    /// Encodes and queues one frame; a frame that does not fit the queue is dropped and counted.
    pub(super) fn send(&mut self, msg: &Message) {
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

/// Formats into a log text, keeping as many whole characters of each piece as fit: heapless's own `write_str` drops a
/// piece that does not fit whole, which lost a long refusal reason after its "goal 1 refused: " prefix.
struct CutAtCapacity<'a>(&'a mut String<MAX_LOG_TEXT>);

impl core::fmt::Write for CutAtCapacity<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        for c in s.chars() {
            self.0.push(c).map_err(|_| core::fmt::Error)?;
        }
        Ok(())
    }
}
