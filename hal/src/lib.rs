//! # hal — the rover-computer hardware abstraction layer
//!
//! Traits only, no logic. The flight software (`firmware`) is generic over these traits; a board crate
//! (`firmware/boards/*`) implements them on real or emulated hardware, and the host simulator (`host-sim`)
//! implements them in-process.
//!
//! Style follows `embedded-hal` 1.0 / `embedded-io`: each trait has an associated error type whose values can be
//! classified by a common [`ErrorKind`]; there are no "not supported" errors — a device that cannot do something
//! simply does not implement the trait.
//!
//! Devices as the flight software sees them:
//! - [`ByteLink`]: the serial-like link to the host / ground (a UART on the board, a byte queue in-process);
//! - [`MonotonicClock`]: time since boot, passed into algorithms by the executive (algorithms never read clocks);
//! - [`Watchdog`]: kicked once per executive cycle;
//! - [`TetherEncoder`], [`RangeSensor`], [`DriveActuator`]: the rover's devices. In simulation they are backed by
//!   the link (the simulator's frames arrive as bytes and the glue turns them into readings); on a rover they would
//!   be backed by drivers.
#![no_std]
#![forbid(unsafe_code)]

/// A coarse, portable classification of a device error, for telemetry and for deciding whether to retry.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ErrorKind {
    /// The device reported a hardware fault (framing/parity/overrun on a UART, encoder fault line, ...).
    Fault,
    /// The device did not answer within its own deadline.
    Timeout,
    /// The peer went away (link closed, emulator exited).
    Disconnected,
    /// A reading was produced but is not physically plausible (NaN, out of range).
    InvalidReading,
    /// Anything else; see the implementation's own error type.
    Other,
}

/// Implemented by every device error type so callers can classify errors without knowing the device.
pub trait Error: core::fmt::Debug {
    /// The portable kind of this error.
    fn kind(&self) -> ErrorKind;
}

impl Error for core::convert::Infallible {
    fn kind(&self) -> ErrorKind {
        match *self {}
    }
}

/// A bidirectional, non-blocking byte link (UART, socket, in-process queue).
///
/// Both directions are non-blocking: `read` returns `Ok(0)` when nothing is pending and `write` may accept fewer
/// bytes than offered when the transmit side is full. Readiness can be asked for explicitly.
pub trait ByteLink {
    /// Device error type.
    type Error: Error;
    /// Reads up to `buf.len()` pending bytes; returns how many were read (0 if none are pending).
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error>;
    /// Writes up to `buf.len()` bytes; returns how many were accepted (0 if the transmitter is full).
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error>;
    /// True when at least one byte can be read without waiting.
    fn read_ready(&mut self) -> Result<bool, Self::Error>;
    /// True when at least one byte can be written without waiting.
    fn write_ready(&mut self) -> Result<bool, Self::Error>;
}

/// A point in time on the monotonic clock, in microseconds since boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct Instant {
    /// Microseconds since boot.
    pub micros: u64,
}

impl Instant {
    /// An instant `micros` microseconds after boot.
    pub const fn from_micros(micros: u64) -> Self {
        Self { micros }
    }
    /// Microseconds elapsed from `earlier` to `self`, saturating at zero.
    pub const fn micros_since(self, earlier: Instant) -> u64 {
        self.micros.saturating_sub(earlier.micros)
    }
}

/// A monotonic clock. Read only by the executive, which passes the time into algorithms.
pub trait MonotonicClock {
    /// The current time; never decreases.
    fn now(&mut self) -> Instant;
}

/// A hardware (or emulated) watchdog that resets the computer unless kicked in time.
pub trait Watchdog {
    /// Device error type.
    type Error: Error;
    /// Restarts the watchdog's countdown.
    fn kick(&mut self) -> Result<(), Self::Error>;
}

/// One tether-encoder sample: what the winch / boom sensors report.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TetherSample {
    /// Time of the sample.
    pub at: Instant,
    /// Tether paid out from the root anchor, metres.
    pub payout_m: f32,
    /// Tether tension, newtons.
    pub tension_n: f32,
    /// Boom angle relative to the body, radians.
    pub boom_angle_rad: f32,
}

/// The tether encoder (payout length, tension, boom angle).
pub trait TetherEncoder {
    /// Device error type.
    type Error: Error;
    /// The latest sample, or `Ok(None)` if no new sample arrived since the last call.
    fn sample(&mut self) -> Result<Option<TetherSample>, Self::Error>;
}

/// One range return in the sensor frame, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RangePoint {
    /// x (forward), metres.
    pub x: f32,
    /// y (left), metres.
    pub y: f32,
    /// z (up), metres.
    pub z: f32,
}

/// A range sensor (stereo or lidar) delivering scans as points in the sensor frame.
pub trait RangeSensor {
    /// Device error type.
    type Error: Error;
    /// Copies up to `out.len()` points of the next pending scan into `out`; returns how many were written and
    /// whether the scan is complete. `Ok((0, false))` means no scan is pending.
    fn read_points(&mut self, out: &mut [RangePoint]) -> Result<(usize, bool), Self::Error>;
}

/// A drive command: the Axel motion primitives (in-place turn, straight drive) and the tether winch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveCommand {
    /// Stop the wheels and hold the tether.
    Stop,
    /// Turn in place by the given yaw angle, radians (positive counter-clockwise about the surface normal).
    Turn {
        /// Yaw change, radians.
        yaw_rad: f32,
    },
    /// Drive straight by the given distance, metres (negative = reverse), paying out or reeling in tether.
    Straight {
        /// Distance, metres.
        distance_m: f32,
    },
}

/// The drive actuator (wheels + tether winch), as the flight software commands it.
pub trait DriveActuator {
    /// Device error type.
    type Error: Error;
    /// Issues a command; returns once the actuator has accepted it (not when the motion is done).
    fn command(&mut self, cmd: DriveCommand) -> Result<(), Self::Error>;
}
