//! Host-side links to the flight software, in one place.
//!
//! [`FlightLink`] is what the simulator, the scenarios, the field-log recorder and the test kit talk to; anything
//! written against it runs over every link:
//!
//! - [`inproc::InProcLink`]: the firmware executive linked in as a library, stepped on a simulated clock;
//! - [`qemu::QemuLink`]: the cross-compiled board binary in QEMU (emulated UART over TCP), stepped in lockstep on
//!   the same simulated clock, so it gives the same bytes as the in-process link (the board itself, its build and
//!   its reports live in [`crate::qemu`]);
//! - [`recording::RecordingLink`]: a wrapper around either that records every byte, both ways, into a field log;
//! - [`faults::FaultLink`]: a wrapper around any of them that injects seeded link faults (issue 24).
//!
//! [`LinkKind`] (in [`kind`]) is the CLI's choice between the in-process and the QEMU link.

pub mod faults;
pub mod inproc;
pub mod kind;
pub mod qemu;
pub mod recording;

pub use kind::LinkKind;

/// Why a link operation failed.
#[derive(Debug)]
pub enum LinkError {
    /// The flight side went away (emulator exited, socket closed).
    Disconnected(String),
    /// An I/O error on a real link.
    Io(std::io::Error),
    /// A field-log write failed while recording.
    Record(std::io::Error),
    /// The link cannot do what was asked (e.g. reset a flight software it did not build).
    Unsupported(&'static str),
}

impl core::fmt::Display for LinkError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            LinkError::Disconnected(why) => write!(f, "flight link disconnected: {why}"),
            LinkError::Io(e) => write!(f, "flight link I/O error: {e}"),
            LinkError::Record(e) => write!(f, "field log write failed: {e}"),
            LinkError::Unsupported(what) => write!(f, "this flight link cannot {what}"),
        }
    }
}

impl core::error::Error for LinkError {}

/// How the flight computer is reset ([`FlightLink::reset_flight`]; issue 24 item 2). Either way it loses RAM and
/// keeps its retained block; the field log records which (`recording::RESET_RECORD`, `WATCHDOG_RESET_RECORD`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ResetCause {
    /// A reset command (on the board: the control port's reboot, SYSRESETREQ), between executive steps.
    Command,
    /// The watchdog bites: the flight loop stops kicking it. On the board the CMSDK watchdog's interrupt, then its
    /// reset output, reboot the Cortex-M7; in-process there is no watchdog and the effect is a reset.
    Watchdog,
}

impl ResetCause {
    /// The payload of its fault record in a field log.
    pub fn record(self) -> &'static [u8] {
        match self {
            ResetCause::Command => recording::RESET_RECORD,
            ResetCause::Watchdog => recording::WATCHDOG_RESET_RECORD,
        }
    }

    /// The cause a fault record's payload names, if it is a reset record.
    pub fn from_record(bytes: &[u8]) -> Option<Self> {
        [ResetCause::Command, ResetCause::Watchdog].into_iter().find(|c| c.record() == bytes)
    }
}

/// A byte link to a running flight software, with the link's own notion of time.
///
/// Time: every link has a clock in microseconds (`now_us`). In-process it is simulated and advances only inside
/// `recv_until_quiet` / `advance_to`, so runs are deterministic; on a real link it is wall time since start.
pub trait FlightLink {
    /// A short name for reports ("inproc", "qemu").
    fn name(&self) -> &str;
    /// The link's current time, microseconds.
    fn now_us(&self) -> u64;
    /// Hands `bytes` to the flight software at the current time.
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError>;
    /// Lets the flight software run until it is quiet (no pending work, no more output) or `max_wait_us` of link
    /// time have passed; returns the bytes it sent meanwhile.
    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError>;
    /// Lets link time run up to `t_us` (no-op if already there); returns the bytes sent meanwhile.
    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError>;
    /// Notes a fault injected on the way to this link (a recorder writes it into the field log; others ignore it).
    fn note_fault(&mut self, _event: &faults::FaultEvent) -> Result<(), LinkError> {
        Ok(())
    }
    /// Stops injecting faults and delivers every frame a fault injector holds (a no-op without one); a mission
    /// calls it before its closing telemetry so the flight software's counts are complete.
    fn end_faults(&mut self) -> Result<(), LinkError> {
        Ok(())
    }
    /// Resets the flight computer now, as its watchdog or a reset command would (issue 24 item 2): everything in
    /// flight on the link is lost, the flight software boots again and recovers what its retained memory kept
    /// (`firmware::nav::retained`); link time goes on. A recorder writes the reset and its cause into the field
    /// log, so the replay resets at the same point. Default: unsupported.
    fn reset_flight(&mut self, _cause: ResetCause) -> Result<(), LinkError> {
        Err(LinkError::Unsupported("reset the flight computer"))
    }
}

impl<T: FlightLink + ?Sized> FlightLink for &mut T {
    fn name(&self) -> &str {
        (**self).name()
    }
    fn now_us(&self) -> u64 {
        (**self).now_us()
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        (**self).send(bytes)
    }
    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        (**self).recv_until_quiet(max_wait_us)
    }
    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        (**self).advance_to(t_us)
    }
    fn note_fault(&mut self, event: &faults::FaultEvent) -> Result<(), LinkError> {
        (**self).note_fault(event)
    }
    fn end_faults(&mut self) -> Result<(), LinkError> {
        (**self).end_faults()
    }
    fn reset_flight(&mut self, cause: ResetCause) -> Result<(), LinkError> {
        (**self).reset_flight(cause)
    }
}
