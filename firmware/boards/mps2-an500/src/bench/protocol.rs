//! Benchmarks of the flight code's link path: protocol encode and deframe + decode of fixed frames (`TimeTick`,
//! `TetherReading`, a 128-point `SensorChunk`), [`BENCH_FRAMES`] frames each, and the whole receive path through
//! the executive (`exec_dispatch_time_tick`: deframe, decode, validate, dispatch, encode and send the Ack, for
//! [`BENCH_FRAMES`] `TimeTick` frames over an in-memory link). Each decode and the executive run are followed by a
//! `bench: check name=... ` line (frames decoded, wire bytes, frames accepted, bytes out).

use firmware::exec::{Executive, NoAutonomy};
use hal::{ByteLink, Instant};

use super::measure::measure;
use crate::clock::{BoardClock, SysTickClock};
use crate::storage::{Lent, EXEC_STORAGE};

/// One frame's wire bytes for the benchmarks.
struct WireFrame {
    bytes: [u8; firmware::config::protocol::MAX_ENCODED_FRAME_LEN],
    len: usize,
}

fn wire(msg: &firmware::protocol::Message) -> WireFrame {
    let mut f = WireFrame {
        bytes: [0; firmware::config::protocol::MAX_ENCODED_FRAME_LEN],
        len: 0,
    };
    f.len = firmware::protocol::encode(7, msg, &mut f.bytes).unwrap_or(0);
    f
}

/// Deframes and decodes `frame` `iterations` times; returns the number of frames decoded (for a sanity line).
fn deframe_decode(frame: &WireFrame, iterations: u32) -> u32 {
    let mut deframer = firmware::protocol::Deframer::new();
    let mut decoded = 0;
    let bytes = frame.bytes.get(..frame.len).unwrap_or(&[]);
    for _ in 0..iterations {
        let mut rest = bytes;
        // A frame completes within one pass; the bound is the frame length (each pass consumes >= 1 byte).
        for _ in 0..bytes.len() {
            let (used, event) = deframer.push(rest);
            rest = rest.get(used.max(1)..).unwrap_or(&[]);
            if let Some(Ok(raw)) = event {
                if firmware::protocol::decode_frame(raw).is_ok() {
                    decoded += 1;
                }
            }
            if rest.is_empty() {
                break;
            }
        }
    }
    core::hint::black_box(decoded)
}

/// Frames per workload.
const BENCH_FRAMES: u32 = 200;

/// Runs the workloads of the module docs.
pub fn run(clock: &mut SysTickClock) {
    use firmware::protocol::{Message, Point3, Pose, SensorChunk, TetherReading, TimeTick};
    let tick = Message::TimeTick(TimeTick {
        host_time_us: 123_456_789,
    });
    let tether = Message::TetherReading(TetherReading {
        time_us: 1_000_000,
        payout_m: 12.5,
        tension_n: 80.0,
        boom_angle_rad: 0.3,
    });
    let mut points = heapless::Vec::new();
    for i in 0..firmware::config::protocol::MAX_POINTS_PER_CHUNK {
        let f = i as f32;
        let _ = points.push(Point3::new(1.0 + 0.01 * f, -0.5 + 0.02 * f, 0.25));
    }
    let chunk = Message::SensorChunk(SensorChunk {
        scan_id: 1,
        chunk_index: 0,
        chunk_count: 1,
        sensor_pose: Pose::IDENTITY,
        points,
    });
    for (name, msg) in [
        ("time_tick", &tick),
        ("tether_reading", &tether),
        ("sensor_chunk_128_points", &chunk),
    ] {
        let frame = wire(msg);
        let mut enc_name: heapless::String<48> = heapless::String::new();
        let _ = core::fmt::Write::write_fmt(&mut enc_name, format_args!("encode_{name}"));
        measure(clock, &enc_name, BENCH_FRAMES, || {
            let mut out = [0u8; firmware::config::protocol::MAX_ENCODED_FRAME_LEN];
            for i in 0..BENCH_FRAMES {
                core::hint::black_box(
                    firmware::protocol::encode(i, core::hint::black_box(msg), &mut out).ok(),
                );
            }
        });
        let mut dec_name: heapless::String<48> = heapless::String::new();
        let _ = core::fmt::Write::write_fmt(&mut dec_name, format_args!("deframe_decode_{name}"));
        let mut decoded = 0;
        measure(clock, &dec_name, BENCH_FRAMES, || {
            decoded = deframe_decode(&frame, BENCH_FRAMES)
        });
        host_println!(
            "bench: check name={} wire_bytes={} decoded={}",
            dec_name,
            frame.len,
            decoded
        );
    }
    exec_dispatch_workload(clock, &tick);
}

/// In-memory link for the executive workload: reads from a fixed byte stream, counts and discards output.
struct MemLink {
    input: &'static [u8],
    written: usize,
}

impl ByteLink for MemLink {
    type Error = core::convert::Infallible;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let n = buf.len().min(self.input.len());
        if let (Some(dst), Some(src)) = (buf.get_mut(..n), self.input.get(..n)) {
            dst.copy_from_slice(src);
        }
        self.input = self.input.get(n..).unwrap_or(&[]);
        Ok(n)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.written += buf.len();
        Ok(buf.len())
    }
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.input.is_empty())
    }
    fn write_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(true)
    }
}

struct NoWatchdog;
impl hal::Watchdog for NoWatchdog {
    type Error = core::convert::Infallible;
    fn kick(&mut self) -> Result<(), Self::Error> {
        crate::watchdog::kick();
        Ok(())
    }
}

/// Wire bytes of the executive workload's input (BENCH_FRAMES time ticks of 16 bytes each, with margin).
static EXEC_INPUT: Lent<[u8; 8192]> = Lent::new([0; 8192]);

/// The whole receive path through the executive: deframe, decode, validate, dispatch, encode and send the Ack,
/// for BENCH_FRAMES `TimeTick` frames, stepping until the input is consumed and the executive is quiet.
fn exec_dispatch_workload(clock: &mut SysTickClock, tick: &firmware::protocol::Message) {
    let (Some(input), Some(storage)) = (EXEC_INPUT.take(), EXEC_STORAGE.take()) else {
        return;
    };
    let mut len = 0;
    for seq in 0..BENCH_FRAMES {
        let frame = firmware::protocol::encode(seq, tick, input.get_mut(len..).unwrap_or(&mut []))
            .unwrap_or(0);
        len += frame;
    }
    let input: &'static [u8] = input.get(..len).unwrap_or(&[]);
    let link = MemLink { input, written: 0 };
    let clock_for_exec = BoardClock {
        systick: SysTickClock::detached(),
        lockstep_now: Some(Instant::from_micros(0)),
    };
    let mut exec = Executive::new(link, clock_for_exec, NoWatchdog, NoAutonomy, storage);
    // The boot Telemetry is sent by the first step: run it outside the measurement.
    let _ = exec.step();
    let mut steps = 0u32;
    measure(clock, "exec_dispatch_time_tick", BENCH_FRAMES, || {
        // Bound: FRAMES_PER_STEP frames per step, so BENCH_FRAMES steps always suffice.
        for k in 1..=BENCH_FRAMES {
            exec.clock_mut().lockstep_now = Some(Instant::from_micros(u64::from(k)));
            steps += 1;
            if !exec.step().busy {
                break;
            }
        }
    });
    let t = exec.telemetry();
    host_println!(
        "bench: check name=exec_dispatch_time_tick steps={} frames_accepted={} bytes_out={}",
        steps,
        t.frames_accepted,
        exec.link_mut().written
    );
}
