//! In-process link: the firmware executive runs inside the host, through host implementations of the `hal`
//! traits (byte queues, a simulated clock, a counting watchdog).
//!
//! Time is simulated: the executive is stepped once every `step_us` microseconds of link time, only inside
//! [`FlightLink::recv_until_quiet`] and [`FlightLink::advance_to`]. Bytes sent with [`FlightLink::send`] arrive at
//! the current time. The same sequence of calls therefore always gives the same output bytes, which is what
//! `replay` relies on.

use std::collections::VecDeque;

use firmware::config::map::{MapConfig, FLIGHT_BLOCKS, FLIGHT_INDEX};
use firmware::exec::{Autonomy, ExecStorage, Executive, StepReport};
use firmware::map::Block;
use firmware::nav::retained::{RetainedBlock, RETAINED_BYTES};
use firmware::nav::{HomotopyStorage, NavPlanStorage, Navigator};
use hal::{ByteLink, Instant, MonotonicClock, Watchdog};

use super::{FlightLink, LinkError};

/// Default executive period of the in-process link, microseconds (1 kHz).
pub const DEFAULT_STEP_US: u64 = 1000;

/// Host side of the in-process byte link: a queue each way. Reads and writes never block or fail.
#[derive(Debug, Default)]
pub struct QueueByteLink {
    /// Bytes waiting for the flight software.
    pub to_flight: VecDeque<u8>,
    /// Bytes the flight software wrote.
    pub to_host: Vec<u8>,
}

impl ByteLink for QueueByteLink {
    type Error = core::convert::Infallible;
    fn read(&mut self, buf: &mut [u8]) -> Result<usize, Self::Error> {
        let n = buf.len().min(self.to_flight.len());
        for (dst, src) in buf.iter_mut().zip(self.to_flight.drain(..n)) {
            *dst = src;
        }
        Ok(n)
    }
    fn write(&mut self, buf: &[u8]) -> Result<usize, Self::Error> {
        self.to_host.extend_from_slice(buf);
        Ok(buf.len())
    }
    fn read_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(!self.to_flight.is_empty())
    }
    fn write_ready(&mut self) -> Result<bool, Self::Error> {
        Ok(true)
    }
}

/// A clock that reads whatever the simulation set.
///
/// The executive reads it at the start and at the end of each step (cycle accounting, `firmware::exec`). By
/// default both reads give the step's simulated time, so every step takes no time and the run is deterministic.
/// With `step_start` set (host time charged, [`InProcLink::charge_host_time`]) every read after a step's first adds
/// the host time since the step began: the executive then measures its steps in host time; the schedule stays
/// simulated, but the telemetry's cycle figures are host measurements, so such a run does not replay byte for byte.
#[derive(Debug, Default, Clone, Copy)]
pub struct SimClock {
    /// Current simulated time, microseconds.
    pub now_us: u64,
    /// Host instant the current step began (host time charged), else `None`.
    pub step_start: Option<std::time::Instant>,
    /// Reads in the current step.
    pub reads: u32,
}

impl MonotonicClock for SimClock {
    fn now(&mut self) -> Instant {
        self.reads += 1;
        let charged = match self.step_start {
            Some(t0) if self.reads > 1 => {
                u64::try_from(t0.elapsed().as_micros()).unwrap_or(u64::MAX)
            }
            _ => 0,
        };
        Instant::from_micros(self.now_us.saturating_add(charged))
    }
}

/// A watchdog that counts kicks.
#[derive(Debug, Default, Clone, Copy)]
pub struct SimWatchdog {
    /// Kicks so far.
    pub kicks: u64,
}

impl Watchdog for SimWatchdog {
    type Error = core::convert::Infallible;
    fn kick(&mut self) -> Result<(), Self::Error> {
        self.kicks += 1;
        Ok(())
    }
}

/// The executive type the in-process link runs.
pub type InProcExecutive<A> = Executive<QueueByteLink, SimClock, SimWatchdog, A, Box<ExecStorage>>;

/// The flight software's autonomy as it flies: the [`Navigator`] over a map pool of the flight computer's size
/// ([`FLIGHT_BLOCKS`] blocks, ~14 MiB, the board's PSRAM) and the on-board planning storage ([`NavPlanStorage`],
/// ~1.5 MiB, the board's SRAM) and the global planner's ([`HomotopyStorage`], ~0.66 MiB: homotopy goals on an
/// uploaded tile), here on the heap.
pub type FlightAutonomy = Navigator<Vec<Block>, Vec<u32>, Box<NavPlanStorage>, Box<HomotopyStorage>>;

/// A fresh [`FlightAutonomy`] with the flight defaults ([`MapConfig::DEFAULT`]); the board builds the same.
pub fn flight_autonomy() -> FlightAutonomy {
    match Navigator::new(MapConfig::DEFAULT, vec![Block::EMPTY; FLIGHT_BLOCKS], vec![0u32; FLIGHT_INDEX], plan_storage()) {
        Ok(nav) => nav.with_homotopy(homotopy_storage()),
        // The defaults and the storage sizes are constants checked by the firmware's own tests.
        Err(e) => unreachable!("flight map defaults rejected: {e:?}"),
    }
}

// The two planning storages pass through the stack on their way to the heap (1.1 MiB and 0.66 MiB in a test build):
// one function each, never inlined, so they are never on the stack together (a test thread has 2 MiB).
#[inline(never)]
fn plan_storage() -> Box<NavPlanStorage> {
    Box::default()
}

#[inline(never)]
fn homotopy_storage() -> Box<HomotopyStorage> {
    Box::new(HomotopyStorage::new())
}

/// The firmware executive behind a [`FlightLink`].
pub struct InProcLink<A: Autonomy = FlightAutonomy> {
    exec: InProcExecutive<A>,
    /// The flight computer's memory that survives a reset (the board's `.uninit` SRAM): zero at power-on.
    retained: Box<RetainedBlock>,
    /// Builds the autonomy a reset boots with (`None`: this link cannot reset).
    rebuild: Option<fn() -> A>,
    /// Resets so far.
    resets: u32,
    step_us: u64,
    last_step: StepReport,
    longest: Option<LongestStep>,
    charge_host_time: bool,
}

/// The executive step that took the most host wall time (a measurement of this host, not part of the output).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LongestStep {
    /// Host wall time of the step.
    pub wall: core::time::Duration,
    /// Link time at which it ran, microseconds.
    pub t_us: u64,
    /// The executive's mode before the step.
    pub mode: firmware::protocol::Mode,
}

impl InProcLink<FlightAutonomy> {
    /// A freshly booted flight software (executive + [`FlightAutonomy`], as on the board), stepped every
    /// `step_us` microseconds.
    pub fn new(step_us: u64) -> Self {
        let mut link = Self::with_autonomy(flight_autonomy(), step_us);
        link.rebuild = Some(flight_autonomy);
        link
    }
}

impl<A: Autonomy> InProcLink<A> {
    /// A freshly booted executive with the given planning hooks.
    pub fn with_autonomy(autonomy: A, step_us: u64) -> Self {
        let retained = Box::new([0u8; RETAINED_BYTES]);
        Self {
            exec: boot(autonomy, 0, &retained),
            retained,
            rebuild: None,
            resets: 0,
            step_us: step_us.max(1),
            last_step: StepReport::default(),
            longest: None,
            charge_host_time: false,
        }
    }

    /// The executive (for tests and glue: telemetry snapshot, mode, hooks).
    pub fn executive(&self) -> &InProcExecutive<A> {
        &self.exec
    }

    /// The executive, mutably.
    pub fn executive_mut(&mut self) -> &mut InProcExecutive<A> {
        &mut self.exec
    }

    /// Resets so far ([`FlightLink::reset_flight`]).
    pub fn resets(&self) -> u32 {
        self.resets
    }

    /// The executive period, microseconds.
    pub fn step_us(&self) -> u64 {
        self.step_us
    }

    /// What the last step did.
    pub fn last_step(&self) -> StepReport {
        self.last_step
    }

    /// The step that took the most host wall time so far (`None` before the first step). The flight software
    /// bounds each step's work, not its time; this shows how long the longest bounded step is on this host.
    pub fn longest_step(&self) -> Option<LongestStep> {
        self.longest
    }

    /// Charges host time to the executive's steps ([`SimClock`]): its cycle accounting then reports host times.
    pub fn charge_host_time(&mut self, on: bool) {
        self.charge_host_time = on;
    }

    /// Runs one executive step at the current time, then advances the clock by one period.
    pub fn step_once(&mut self) -> Vec<u8> {
        let (t0, mode) = (std::time::Instant::now(), self.exec.mode());
        let clock = self.exec.clock_mut();
        clock.reads = 0;
        clock.step_start = self.charge_host_time.then_some(t0);
        self.last_step = self.exec.step();
        self.exec.autonomy_mut().keep_retained(&mut self.retained);
        let wall = t0.elapsed();
        if self.longest.is_none_or(|l| wall > l.wall) {
            self.longest = Some(LongestStep {
                wall,
                t_us: self.exec.clock_mut().now_us,
                mode,
            });
        }
        self.exec.clock_mut().now_us += self.step_us;
        core::mem::take(&mut self.exec.link_mut().to_host)
    }
}

impl<A: Autonomy> FlightLink for InProcLink<A> {
    fn name(&self) -> &str {
        "inproc"
    }

    fn now_us(&self) -> u64 {
        self.last_now()
    }

    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.exec.link_mut().to_flight.extend(bytes.iter().copied());
        Ok(())
    }

    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        let mut out = Vec::new();
        let steps = max_wait_us.div_ceil(self.step_us).max(1);
        for _ in 0..steps {
            out.extend(self.step_once());
            if !self.last_step.busy {
                break;
            }
        }
        Ok(out)
    }

    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        let mut out = Vec::new();
        while self.last_now() < t_us {
            out.extend(self.step_once());
        }
        Ok(out)
    }

    /// Both causes reboot the executive the same way: the in-process flight software has no watchdog to bite.
    fn reset_flight(&mut self, _cause: super::ResetCause) -> Result<(), LinkError> {
        let rebuild = self.rebuild.ok_or(LinkError::Unsupported("reset a flight software it was handed"))?;
        // bytes on the way either side are lost with the executive's queues; the simulated time goes on
        self.exec = boot(rebuild(), self.last_now(), &self.retained);
        self.last_step = StepReport::default();
        self.resets += 1;
        Ok(())
    }
}

/// A booted executive at simulated time `now_us`, its autonomy given the retained block first (as the board's
/// reset handler does before the flight loop).
fn boot<A: Autonomy>(autonomy: A, now_us: u64, retained: &RetainedBlock) -> InProcExecutive<A> {
    let mut exec = Executive::new(
        QueueByteLink::default(),
        SimClock { now_us, ..SimClock::default() },
        SimWatchdog::default(),
        autonomy,
        Box::new(ExecStorage::new()),
    );
    exec.autonomy_mut().recover_retained(retained);
    exec
}

impl<A: Autonomy> InProcLink<A> {
    fn last_now(&self) -> u64 {
        self.exec.clock().now_us
    }
}
