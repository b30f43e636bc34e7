//! The emulated board as a flight link (the board binary in QEMU, started by [`crate::qemu::QemuBoard`]).
//!
//! [`QemuLink`] runs the board in **lockstep**: the board's executive is stepped by the host over the control port
//! on the host's simulated clock, one step every `step_us`, with bytes delivered at step boundaries, exactly the
//! schedule of the in-process link. The same calls therefore give the same flight -> host bytes in-process and on
//! the emulated Cortex-M7 (the equivalence test, `tests/tests/board_equivalence.rs`), while the code that produces
//! them is the cross-compiled firmware running on the emulated CPU behind the emulated UART.
//!
//! Per call: [`QemuLink::send`] writes the bytes to UART0 at once and counts them; [`QemuLink::recv_until_quiet`]
//! and [`QemuLink::advance_to`] send one `R` command (announcing the bytes written since the last one, the start
//! time, the period and the step count) and collect the board's output bytes and its `D` reply. Every wait is
//! bounded by [`QemuLink::reply_timeout`]. A step that may work (the first after bytes were sent, or any step
//! after a busy one: planning, scan integration, plan re-checks) is sent as a run command of its own, so the bound
//! applies to one step, whose length the flight software bounds (and the board's watchdog catches); idle steps go
//! in runs of up to [`IDLE_RUN_STEPS`]. The split does not change the bytes: the steps run at the same times.

use core::time::Duration;
use std::io;
use std::time::Instant;

use super::{FlightLink, LinkError};
use crate::qemu::{QemuBoard, QemuConfig, QemuError, QemuExit};

/// Default bound on one lockstep run command's reply: one busy step (a mission's planning step on the emulated
/// Cortex-M7 takes seconds of host time) or a run of idle ones, on a loaded 2-core machine. Default 60 s, twice the
/// board's lockstep watchdog, which ends a wedged step first.
pub const DEFAULT_REPLY_TIMEOUT: Duration = Duration::from_secs(60);

/// Steps per run command while the executive is idle (no bytes sent, the last step reported no work). Default
/// 1024: an idle step costs microseconds on the board, so a run stays far inside the reply timeout.
pub const IDLE_RUN_STEPS: u64 = 1024;

/// The board in lockstep behind the host's link interface.
pub struct QemuLink {
    board: Option<QemuBoard>,
    now_us: u64,
    step_us: u64,
    unannounced: u64,
    /// Bound on each run command's reply.
    pub reply_timeout: Duration,
    steps: u64,
    round_trips: u64,
    busy_wall: Duration,
    /// The board's last step reported work.
    last_busy: bool,
}

impl QemuLink {
    /// Boots `elf` in QEMU in lockstep mode with executive period `step_us` (as the in-process link's).
    pub fn start(elf: &std::path::Path, step_us: u64) -> Result<Self, QemuError> {
        let mut cfg = QemuConfig::new(elf.to_path_buf());
        cfg.boot_words = Some("tetherbot.clock=lockstep".into());
        Self::with_config(&cfg, step_us)
    }

    /// As [`QemuLink::start`] with a full configuration; `tetherbot.clock=lockstep` must be among its boot words.
    pub fn with_config(cfg: &QemuConfig, step_us: u64) -> Result<Self, QemuError> {
        let board = QemuBoard::start(cfg)?;
        Ok(Self {
            board: Some(board),
            now_us: 0,
            step_us: step_us.max(1),
            unannounced: 0,
            reply_timeout: DEFAULT_REPLY_TIMEOUT,
            steps: 0,
            round_trips: 0,
            busy_wall: Duration::ZERO,
            last_busy: false,
        })
    }

    fn board(&mut self) -> io::Result<&mut QemuBoard> {
        self.board
            .as_mut()
            .ok_or_else(|| io::Error::new(io::ErrorKind::NotConnected, "the board was shut down"))
    }

    /// Host wall time from spawning QEMU to the board's hello.
    pub fn boot_to_ready(&self) -> Option<Duration> {
        self.board.as_ref().map(QemuBoard::boot_to_ready)
    }

    /// Executive steps run on the board so far, run commands sent, and the host wall time spent in them.
    pub fn stats(&self) -> (u64, u64, Duration) {
        (self.steps, self.round_trips, self.busy_wall)
    }

    /// The link's simulated time, microseconds.
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// The executive period, microseconds.
    pub fn step_us(&self) -> u64 {
        self.step_us
    }

    /// Writes `bytes` to the board's UART0; they are delivered at the next step.
    pub fn send(&mut self, bytes: &[u8]) -> io::Result<()> {
        self.board()?.send(bytes)?;
        self.unannounced += bytes.len() as u64;
        Ok(())
    }

    /// Steps until the executive reports no work, at most `ceil(max_wait_us / step_us)` (>= 1) steps.
    pub fn recv_until_quiet(&mut self, max_wait_us: u64) -> io::Result<Vec<u8>> {
        let steps = max_wait_us.div_ceil(self.step_us).max(1);
        self.run(steps, true)
    }

    /// Steps until the link time reaches `t_us`.
    pub fn advance_to(&mut self, t_us: u64) -> io::Result<Vec<u8>> {
        if self.now_us >= t_us {
            return Ok(Vec::new());
        }
        let steps = (t_us - self.now_us).div_ceil(self.step_us);
        self.run(steps, false)
    }

    fn run(&mut self, mut steps: u64, until_quiet: bool) -> io::Result<Vec<u8>> {
        let mut out = Vec::new();
        while steps > 0 {
            // One step per command while the executive may work; idle runs in blocks (module docs).
            let chunk = if self.unannounced > 0 || self.last_busy { 1 } else { steps.min(IDLE_RUN_STEPS) };
            let (ran, busy) = self.run_once(chunk as u32, until_quiet, &mut out)?;
            self.last_busy = busy;
            steps -= chunk;
            if until_quiet && (!busy || u64::from(ran) < chunk) {
                break;
            }
        }
        Ok(out)
    }

    fn run_once(
        &mut self,
        max_steps: u32,
        until_quiet: bool,
        out: &mut Vec<u8>,
    ) -> io::Result<(u32, bool)> {
        let t0 = Instant::now();
        let base = out.len();
        let announced = u32::try_from(self.unannounced).map_err(|_| {
            io::Error::new(
                io::ErrorKind::InvalidInput,
                "more than 4 GiB sent between steps",
            )
        })?;
        let mut cmd = Vec::with_capacity(22);
        cmd.push(b'R');
        cmd.extend_from_slice(&announced.to_le_bytes());
        cmd.extend_from_slice(&self.now_us.to_le_bytes());
        cmd.extend_from_slice(
            &u32::try_from(self.step_us)
                .unwrap_or(u32::MAX)
                .to_le_bytes(),
        );
        cmd.extend_from_slice(&max_steps.to_le_bytes());
        cmd.push(u8::from(until_quiet));
        let timeout = self.reply_timeout;
        let board = self.board()?;
        board.control_send(&cmd)?;
        // Drain UART0 while waiting for the reply, so a long run never fills the socket.
        let deadline = Instant::now() + timeout;
        let mut done = [0u8; 10];
        let mut buf = vec![0u8; 64 * 1024];
        loop {
            let n = board.try_recv(&mut buf)?;
            out.extend_from_slice(&buf[..n]);
            match board.control_recv_exact(
                &mut done,
                Duration::from_micros(if n > 0 { 100 } else { 1000 }),
            ) {
                Ok(()) => break,
                Err(e) if e.kind() == io::ErrorKind::TimedOut && Instant::now() < deadline => {}
                Err(e) => return Err(e),
            }
        }
        if done[0] != b'D' {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                format!("bad reply tag 0x{:02x}", done[0]),
            ));
        }
        let ran = u32::from_le_bytes([done[1], done[2], done[3], done[4]]);
        let busy = done[5] != 0;
        let tx = u32::from_le_bytes([done[6], done[7], done[8], done[9]]) as usize;
        // Collect the rest of this run's output (written by the board before its reply).
        while out.len() - base < tx {
            let left = deadline.saturating_duration_since(Instant::now());
            if left.is_zero() {
                return Err(io::Error::new(
                    io::ErrorKind::TimedOut,
                    "board output did not arrive in time",
                ));
            }
            let want = tx - (out.len() - base);
            let n = self.board()?.recv(
                &mut buf[..want.min(64 * 1024)],
                left.min(Duration::from_millis(50)),
            )?;
            out.extend_from_slice(&buf[..n]);
        }
        self.now_us += u64::from(ran) * self.step_us;
        self.unannounced = 0;
        self.steps += u64::from(ran);
        self.round_trips += 1;
        self.busy_wall += t0.elapsed();
        Ok((ran, busy))
    }

    /// Resets the board between runs (its reboot command, or a watchdog bite: `QemuBoard::bite_watchdog`) and
    /// waits for its hello; link time goes on. Refused
    /// with bytes sent and not yet announced (they would sit in the emulated UART and reach the rebooted
    /// software, where in-process they are lost with the executive's queue).
    pub fn reset_board(&mut self, cause: super::ResetCause) -> io::Result<()> {
        if self.unannounced > 0 {
            return Err(io::Error::new(
                io::ErrorKind::InvalidInput,
                "reset with bytes sent but not yet delivered; step first",
            ));
        }
        let timeout = self.reply_timeout;
        match cause {
            super::ResetCause::Command => self.board()?.reboot(timeout)?,
            super::ResetCause::Watchdog => self.board()?.bite_watchdog(timeout)?,
        }
        self.last_busy = false;
        Ok(())
    }

    /// Shuts the board down with a quit command; returns its exit status and resource report.
    pub fn quit(mut self, timeout: Duration) -> Result<QemuExit, QemuError> {
        match self.board.take() {
            Some(b) => b.quit(timeout),
            None => Err(QemuError::Io(io::Error::new(
                io::ErrorKind::NotConnected,
                "already shut down",
            ))),
        }
    }
}

fn link_error(link: &QemuLink, e: io::Error) -> LinkError {
    match e.kind() {
        io::ErrorKind::UnexpectedEof
        | io::ErrorKind::NotConnected
        | io::ErrorKind::ConnectionReset
        | io::ErrorKind::BrokenPipe => {
            let output = link
                .board
                .as_ref()
                .map(|b| b.output().both())
                .unwrap_or_default();
            LinkError::Disconnected(format!("emulated board: {e}; its output:\n{output}"))
        }
        _ => LinkError::Io(e),
    }
}

impl FlightLink for QemuLink {
    fn name(&self) -> &str {
        "qemu"
    }
    fn now_us(&self) -> u64 {
        self.now_us
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        QemuLink::send(self, bytes).map_err(|e| link_error(self, e))
    }
    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        QemuLink::recv_until_quiet(self, max_wait_us).map_err(|e| link_error(self, e))
    }
    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        QemuLink::advance_to(self, t_us).map_err(|e| link_error(self, e))
    }
    fn reset_flight(&mut self, cause: super::ResetCause) -> Result<(), LinkError> {
        QemuLink::reset_board(self, cause).map_err(|e| link_error(self, e))
    }
}
