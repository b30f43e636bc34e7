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
//! - [`Watchdog`]: kicked once per executive cycle.
//!
//! The rover's own devices (tether encoder, range sensor, drive) have no trait here: their readings and commands
//! travel as protocol frames over the [`ByteLink`] (`firmware::protocol`: `TetherReading`, `SensorChunk`,
//! `DriveCommand`), produced and consumed by the simulator or the rover's device glue. A trait for one of them is
//! added together with its first implementation and its first caller.
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
