//! Replay: feed a field log's host -> flight bytes to a fresh flight software at the recorded times and compare
//! every flight -> host byte with the recording.
//!
//! The in-process link steps the executive on a fixed grid of link time (`step_us`, from the log's configuration),
//! so a recording made through [`crate::link::inproc::InProcLink`] is reproduced exactly by calling
//! `advance_to(t)` before each recorded send and at the end up to the last record's time. The comparison is over the
//! concatenated flight -> host byte stream; a difference is reported as the first differing record (index in the
//! log and byte offset inside it) and the offset in the stream.

use crate::fieldlog::{Direction, FieldLog};
use crate::link::{FlightLink, LinkError};

/// Run configuration stored in a field log's header (JSON).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RunConfig {
    /// Scenario name.
    pub scenario: String,
    /// Link kind that recorded it ("inproc").
    pub link: String,
    /// Executive period of the in-process link, microseconds.
    pub step_us: u64,
}

/// The outcome of a replay.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReplayOutcome {
    /// Every flight -> host byte matched.
    Identical {
        /// Host -> flight records fed.
        records_fed: usize,
        /// Flight -> host bytes compared.
        bytes_compared: usize,
    },
    /// The outputs differ.
    Differs {
        /// Index (in the log) of the first flight -> host record that differs (or the last one, if the replay
        /// produced more bytes than were recorded).
        record: usize,
        /// Byte offset inside that record.
        offset_in_record: usize,
        /// Byte offset in the whole flight -> host stream.
        stream_offset: usize,
        /// Recorded byte there (`None` past the end of the recording).
        expected: Option<u8>,
        /// Replayed byte there (`None` past the end of the replay).
        got: Option<u8>,
    },
}

impl core::fmt::Display for ReplayOutcome {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplayOutcome::Identical { records_fed, bytes_compared } => write!(
                f,
                "identical: fed {records_fed} host->flight records, {bytes_compared} flight->host bytes match"
            ),
            ReplayOutcome::Differs { record, offset_in_record, stream_offset, expected, got } => write!(
                f,
                "DIFFERS at flight->host record #{record}, byte {offset_in_record} (stream offset {stream_offset}): \
                 recorded {expected:02x?}, replayed {got:02x?}"
            ),
        }
    }
}

/// Why a log is not replayed at all.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ReplayRefusal {
    /// The log was recorded in another protocol version than this build speaks (every frame would be answered
    /// `WrongVersion`).
    WrongProtocol {
        /// The log header's protocol version.
        log: u8,
        /// This build's `PROTOCOL_VERSION`.
        build: u8,
    },
    /// The configuration's executive period is 0 (link time would never advance).
    ZeroStep,
    /// A record's time is before the previous record's (a recording's link time only grows).
    TimeGoesBack {
        /// Index of the record in the log.
        record: usize,
        /// Its time, microseconds.
        t_us: u64,
        /// The previous record's time, microseconds.
        previous_us: u64,
    },
    /// A record's time is past the replay's link-time budget.
    TooLong {
        /// Index of the record in the log.
        record: usize,
        /// Its time, microseconds.
        t_us: u64,
        /// The budget, microseconds.
        max_us: u64,
        /// Executive period, microseconds.
        step_us: u64,
    },
}

impl core::fmt::Display for ReplayRefusal {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            ReplayRefusal::WrongProtocol { log, build } => write!(
                f,
                "the log was recorded in protocol version {log}; this build speaks version {build}: replay it with a \
                 build of version {log}"
            ),
            ReplayRefusal::ZeroStep => write!(f, "the log's configuration has step_us = 0: link time cannot advance"),
            ReplayRefusal::TimeGoesBack { record, t_us, previous_us } => write!(
                f,
                "record #{record} is stamped {t_us} us, before the previous record's {previous_us} us: the time \
                 stamps are damaged (link time only grows)"
            ),
            ReplayRefusal::TooLong { record, t_us, max_us, step_us } => write!(
                f,
                "record #{record} is stamped {:.3} s of link time: replaying to it takes {} executive steps of {step_us} \
                 us, past the limit of {:.0} s; a damaged time stamp? (raise --max-link-time-s if the run really \
                 lasted that long)",
                *t_us as f64 / 1e6,
                t_us / (*step_us).max(1),
                *max_us as f64 / 1e6
            ),
        }
    }
}

impl core::error::Error for ReplayRefusal {}

/// Checks that replaying `log` ends: a non-zero executive period, record times that never go back and stay within
/// `max_link_time_us` (the replay steps the executive every `step_us` up to the last record's time, so one time
/// stamp of `u64::MAX` would otherwise run for ever).
pub fn check_replayable(log: &FieldLog, step_us: u64, max_link_time_us: u64) -> Result<(), ReplayRefusal> {
    let build = firmware::config::protocol::PROTOCOL_VERSION;
    if log.header.protocol_version != build {
        return Err(ReplayRefusal::WrongProtocol { log: log.header.protocol_version, build });
    }
    if step_us == 0 {
        return Err(ReplayRefusal::ZeroStep);
    }
    let mut previous_us = 0;
    for (record, r) in log.records.iter().enumerate() {
        if r.t_us < previous_us {
            return Err(ReplayRefusal::TimeGoesBack { record, t_us: r.t_us, previous_us });
        }
        if r.t_us > max_link_time_us {
            return Err(ReplayRefusal::TooLong { record, t_us: r.t_us, max_us: max_link_time_us, step_us });
        }
        previous_us = r.t_us;
    }
    Ok(())
}

/// Replays `log` through `link` (a fresh flight software) and compares the output. Run [`check_replayable`]
/// first on a log from outside: the replay steps the link up to every record's time.
pub fn replay(log: &FieldLog, link: &mut impl FlightLink) -> Result<ReplayOutcome, LinkError> {
    let mut got = Vec::new();
    let mut expected = Vec::new();
    // (stream offset where the record starts, record index)
    let mut starts = Vec::new();
    let mut fed = 0;
    let mut end_t = 0;
    // resets of the flight computer, in file order: each happens where its record lies between the data records
    let mut resets = log
        .faults
        .iter()
        .filter_map(|f| crate::link::ResetCause::from_record(&f.bytes).map(|c| (f, c)))
        .peekable();
    for (i, r) in log.records.iter().enumerate() {
        while let Some((reset, cause)) = resets.next_if(|(f, _)| f.offset < r.offset) {
            got.extend(link.advance_to(reset.t_us)?);
            link.reset_flight(cause)?;
        }
        end_t = end_t.max(r.t_us);
        match r.direction {
            Direction::HostToFlight => {
                got.extend(link.advance_to(r.t_us)?);
                link.send(&r.bytes)?;
                fed += 1;
            }
            Direction::FlightToHost => {
                starts.push((expected.len(), i));
                expected.extend_from_slice(&r.bytes);
            }
        }
    }
    for (reset, cause) in resets {
        got.extend(link.advance_to(reset.t_us)?);
        link.reset_flight(cause)?;
    }
    got.extend(link.advance_to(end_t)?);
    let first_diff = expected
        .iter()
        .zip(&got)
        .position(|(a, b)| a != b)
        .or_else(|| (expected.len() != got.len()).then_some(expected.len().min(got.len())));
    Ok(match first_diff {
        None => ReplayOutcome::Identical {
            records_fed: fed,
            bytes_compared: expected.len(),
        },
        Some(at) => {
            let (start, record) = starts
                .iter()
                .rev()
                .find(|(s, _)| *s <= at)
                .copied()
                .unwrap_or((0, 0));
            ReplayOutcome::Differs {
                record,
                offset_in_record: at - start,
                stream_offset: at,
                expected: expected.get(at).copied(),
                got: got.get(at).copied(),
            }
        }
    })
}
