//! Link performance of the emulated flight computer, measured on the host's wall clock with the board
//! **free-running** (its own SysTick clock, stepping continuously, sleeping when idle), as it would fly:
//!
//! - boot to ready: spawning QEMU to the hello byte on the control port, and to the boot `Telemetry` frame (the
//!   protocol's ready frame) on UART0;
//! - round-trip latency: one `TimeTick` frame out, its `Ack` back, repeated;
//! - sustained throughput: a burst of `TimeTick` frames written at once, until every `Ack` is back.
//!
//! Figures depend on the host's load (QEMU is a process on a shared machine); they are reported, never asserted.

use core::time::Duration;
use std::time::Instant;

use firmware::protocol::{self, Ack, Deframer, Message, TimeTick};

use super::{QemuBoard, QemuConfig, QemuError, QemuExit};

/// What [`measure`] found.
#[derive(Debug, Clone)]
pub struct LinkPerf {
    /// Spawn to hello byte.
    pub boot_to_hello: Duration,
    /// Spawn to the complete boot Telemetry frame.
    pub boot_to_telemetry: Duration,
    /// Round trips, sorted ascending.
    pub round_trips: Vec<Duration>,
    /// Frames in the throughput burst.
    pub burst_frames: usize,
    /// Wire bytes of the burst, host -> flight.
    pub burst_bytes_out: usize,
    /// Wire bytes received during the burst, flight -> host.
    pub burst_bytes_in: usize,
    /// Burst start to last Ack.
    pub burst_time: Duration,
    /// The board's exit (resource report in its output).
    pub exit: QemuExit,
}

impl LinkPerf {
    /// Round-trip percentile (0..=100).
    pub fn rtt_percentile(&self, p: usize) -> Duration {
        if self.round_trips.is_empty() {
            return Duration::ZERO;
        }
        let i = (self.round_trips.len() - 1) * p.min(100) / 100;
        self.round_trips[i]
    }
}

impl core::fmt::Display for LinkPerf {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let secs = self.burst_time.as_secs_f64().max(1e-9);
        writeln!(
            f,
            "boot to hello (control port):      {:>9.1} ms",
            self.boot_to_hello.as_secs_f64() * 1e3
        )?;
        writeln!(
            f,
            "boot to ready (boot Telemetry):    {:>9.1} ms",
            self.boot_to_telemetry.as_secs_f64() * 1e3
        )?;
        writeln!(
            f,
            "round trip TimeTick -> Ack (n={}): min {:.3} ms, median {:.3} ms, p90 {:.3} ms, max {:.3} ms",
            self.round_trips.len(),
            self.rtt_percentile(0).as_secs_f64() * 1e3,
            self.rtt_percentile(50).as_secs_f64() * 1e3,
            self.rtt_percentile(90).as_secs_f64() * 1e3,
            self.rtt_percentile(100).as_secs_f64() * 1e3
        )?;
        writeln!(
            f,
            "sustained: {} frames ({} B out, {} B in) in {:.1} ms = {:.0} frames/s, {:.0} B/s in + out",
            self.burst_frames,
            self.burst_bytes_out,
            self.burst_bytes_in,
            secs * 1e3,
            self.burst_frames as f64 / secs,
            (self.burst_bytes_out + self.burst_bytes_in) as f64 / secs
        )
    }
}

fn io_err(msg: impl Into<String>) -> QemuError {
    QemuError::Io(std::io::Error::new(
        std::io::ErrorKind::TimedOut,
        msg.into(),
    ))
}

/// Receives and decodes flight -> host frames until `done` says stop or `timeout` passes.
fn recv_until(
    board: &mut QemuBoard,
    deframer: &mut Deframer,
    timeout: Duration,
    bytes_in: &mut usize,
    mut done: impl FnMut(&Message) -> bool,
) -> Result<(), QemuError> {
    let deadline = Instant::now() + timeout;
    let mut buf = [0u8; 4096];
    loop {
        let left = deadline.saturating_duration_since(Instant::now());
        if left.is_zero() {
            return Err(io_err(format!("no expected reply within {timeout:?}")));
        }
        let n = board.recv(&mut buf, left.min(Duration::from_millis(100)))?;
        *bytes_in += n;
        let mut rest = &buf[..n];
        while !rest.is_empty() {
            let (used, event) = deframer.push(rest);
            rest = &rest[used.max(1).min(rest.len())..];
            if let Some(Ok(frame)) = event {
                if let Ok((_, msg)) = protocol::decode_frame(frame) {
                    if done(&msg) {
                        return Ok(());
                    }
                }
            }
        }
    }
}

fn tick(seq: u32, t: u64) -> Vec<u8> {
    let mut out = vec![0u8; firmware::config::protocol::MAX_ENCODED_FRAME_LEN];
    let n = protocol::encode(
        seq,
        &Message::TimeTick(TimeTick { host_time_us: t }),
        &mut out,
    )
    .unwrap_or(0);
    out.truncate(n);
    out
}

/// Boots the board free-running and measures the link; `rtt_samples` round trips, a burst of `burst` frames.
pub fn measure(
    elf: &std::path::Path,
    rtt_samples: usize,
    burst: usize,
) -> Result<LinkPerf, QemuError> {
    let cfg = QemuConfig::new(elf.to_path_buf());
    let t0 = Instant::now();
    let mut board = QemuBoard::start(&cfg)?;
    let boot_to_hello = board.boot_to_ready();
    let mut deframer = Deframer::new();
    let mut bytes_in = 0;
    recv_until(
        &mut board,
        &mut deframer,
        Duration::from_secs(10),
        &mut bytes_in,
        |m| matches!(m, Message::Telemetry(_)),
    )?;
    let boot_to_telemetry = t0.elapsed();

    let mut seq = 1u32;
    let mut round_trips = Vec::with_capacity(rtt_samples);
    for _ in 0..rtt_samples {
        let frame = tick(seq, u64::from(seq));
        let start = Instant::now();
        board.send(&frame)?;
        let want = Message::Ack(Ack { seq });
        recv_until(
            &mut board,
            &mut deframer,
            Duration::from_secs(5),
            &mut bytes_in,
            |m| *m == want,
        )?;
        round_trips.push(start.elapsed());
        seq += 1;
    }
    round_trips.sort();

    let first = seq;
    let mut wire = Vec::new();
    for k in 0..burst as u32 {
        wire.extend(tick(first + k, u64::from(first + k)));
    }
    let last = first + burst as u32 - 1;
    let mut burst_in = 0;
    let start = Instant::now();
    board.send(&wire)?;
    let mut acked = 0usize;
    recv_until(
        &mut board,
        &mut deframer,
        Duration::from_secs(60),
        &mut burst_in,
        |m| {
            if let Message::Ack(Ack { seq }) = m {
                if (first..=last).contains(seq) {
                    acked += 1;
                }
            }
            acked == burst
        },
    )?;
    let burst_time = start.elapsed();
    let exit = board.quit(Duration::from_secs(10))?;
    Ok(LinkPerf {
        boot_to_hello,
        boot_to_telemetry,
        round_trips,
        burst_frames: burst,
        burst_bytes_out: wire.len(),
        burst_bytes_in: burst_in,
        burst_time,
        exit,
    })
}
