//! A [`FlightLink`] wrapper that records every byte, both ways, into a field log, and the faults a
//! [`super::faults::FaultLink`] outside it injected (fault records, field-log format 4).

use std::io::Write;

use super::{FlightLink, LinkError};
use crate::fieldlog::{Direction, Writer};

/// The payload of the fault record a reset of the flight computer leaves ([`FlightLink::reset_flight`]); a replay
/// resets its flight software where the record lies between the data records (`crate::replay`).
pub const RESET_RECORD: &[u8] = b"flight computer reset";
/// The payload of the fault record a watchdog bite leaves ([`super::ResetCause::Watchdog`]).
pub const WATCHDOG_RESET_RECORD: &[u8] = b"flight computer reset: watchdog";

/// Records everything passing through `inner` into `log`, stamped with the link's time.
pub struct RecordingLink<L: FlightLink, W: Write> {
    inner: L,
    log: Writer<W>,
}

impl<L: FlightLink, W: Write> RecordingLink<L, W> {
    /// Wraps `inner`; `log` already holds its header.
    pub fn new(inner: L, log: Writer<W>) -> Self {
        Self { inner, log }
    }

    /// The wrapped link.
    pub fn inner(&self) -> &L {
        &self.inner
    }

    /// The wrapped link, mutably (bytes sent through it directly are not recorded).
    pub fn inner_mut(&mut self) -> &mut L {
        &mut self.inner
    }

    /// Closes the log with its end record ([`Writer::finish`]), flushes it and gives both parts back.
    pub fn finish(self) -> Result<(L, W), LinkError> {
        let out = self.log.finish().map_err(LinkError::Record)?;
        Ok((self.inner, out))
    }

    fn record_rx(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let t = self.inner.now_us();
        self.log
            .append(Direction::FlightToHost, t, bytes)
            .map_err(LinkError::Record)
    }
}

impl<L: FlightLink, W: Write> FlightLink for RecordingLink<L, W> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn now_us(&self) -> u64 {
        self.inner.now_us()
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        let t = self.inner.now_us();
        self.log
            .append(Direction::HostToFlight, t, bytes)
            .map_err(LinkError::Record)?;
        self.inner.send(bytes)
    }
    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        let got = self.inner.recv_until_quiet(max_wait_us)?;
        self.record_rx(&got)?;
        Ok(got)
    }
    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        let got = self.inner.advance_to(t_us)?;
        self.record_rx(&got)?;
        Ok(got)
    }
    fn note_fault(&mut self, event: &super::faults::FaultEvent) -> Result<(), LinkError> {
        self.log
            .append_fault(event.t_us, &event.to_bytes())
            .map_err(LinkError::Record)
    }
    fn end_faults(&mut self) -> Result<(), LinkError> {
        self.inner.end_faults()
    }
    fn reset_flight(&mut self, cause: super::ResetCause) -> Result<(), LinkError> {
        let t = self.inner.now_us();
        self.inner.reset_flight(cause)?;
        self.log.append_fault(t, cause.record()).map_err(LinkError::Record)
    }
}
