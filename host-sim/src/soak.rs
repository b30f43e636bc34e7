//! The soak (issue 24, item 7): a long mission on the flight software with the host's sequence numbers started
//! near 2^32 so they cross the wrap, judged from its field log alone.
//!
//! [`analyse`] reads every frame of a mission's log in both directions and reports: frames the host sent and
//! whether their numbers crossed the wrap, the acknowledgements (every host frame acked exactly once, none
//! refused), the flight software's frames (numbered without a gap: none lost, none undecodable), and its periodic
//! `Telemetry` (every `DEFAULT_TELEMETRY_PERIOD_US`, 1 s) at the start, the middle and the end: the high-water
//! marks, which must not grow in the second half (flat), and the counters, which must never decrease from one
//! frame to the next (a wrapped counter would). `tetherbot soak` runs it (`host-sim/doc/soak.md`).

use std::collections::BTreeMap;

use firmware::protocol::{decode_frame, Deframer, HighWater, Message, Telemetry};

use crate::fieldlog::{Direction, FieldLog};

/// Host sequence number the soak starts at by default: 2^32 - 1000, so a mission of a few thousand host frames
/// crosses the wrap early and runs most of its length past it.
pub const DEFAULT_FIRST_SEQ: u32 = u32::MAX - 999;

/// One `Telemetry` frame as the soak samples it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// The flight software's sequence number of the frame.
    pub seq: u32,
    /// The telemetry.
    pub telemetry: Telemetry,
}

/// What a soak's field log shows.
#[derive(Debug, Clone, PartialEq)]
pub struct SoakReport {
    /// Host frames sent.
    pub host_frames: u64,
    /// First and last host sequence numbers.
    pub host_seq: Option<(u32, u32)>,
    /// The host's sequence numbers passed 2^32 - 1 and went on from 0.
    pub host_seq_wrapped: bool,
    /// Host frames whose numbers do not follow the previous one's (wrapping).
    pub host_seq_gaps: u64,
    /// Host frames acknowledged (an `Ack` with the frame's number).
    pub acked: u64,
    /// Host frames never acknowledged.
    pub unacked: u64,
    /// Host frames acknowledged more than once.
    pub acked_twice: u64,
    /// `Nack`s received.
    pub nacks: u64,
    /// Flight frames received (decoded).
    pub flight_frames: u64,
    /// Flight frames missing from the numbering (lost between the two sides).
    pub flight_lost: u64,
    /// Flight bytes that did not decode into a frame.
    pub flight_undecodable: u64,
    /// Every periodic `Telemetry` frame, in order.
    pub samples: Vec<Sample>,
}

/// The high-water marks of a telemetry frame, by name.
pub fn high_water(h: &HighWater) -> [(&'static str, u32); 7] {
    [
        ("tx_queue", h.tx_queue),
        ("rx_staging", h.rx_staging),
        ("frame_len", h.frame_len),
        ("scan_points", h.scan_points),
        ("log_queue", h.log_queue),
        ("frames_per_step", h.frames_per_step),
        ("rx_bytes_per_step", h.rx_bytes_per_step),
    ]
}

/// The counters of a telemetry frame that only ever count up, by name.
pub fn counters(t: &Telemetry) -> Vec<(&'static str, u64)> {
    vec![
        ("time_us", t.time_us),
        ("steps", u64::from(t.steps)),
        ("frames_accepted", u64::from(t.frames_accepted)),
        (
            "frames_rejected",
            t.frames_rejected.iter().map(|&n| u64::from(n)).sum(),
        ),
        ("frames_sent", u64::from(t.frames_sent)),
        ("bytes_received", u64::from(t.bytes_received)),
        ("bytes_sent", u64::from(t.bytes_sent)),
        (
            "steps_rx_budget_exhausted",
            u64::from(t.steps_rx_budget_exhausted),
        ),
        (
            "steps_frame_budget_exhausted",
            u64::from(t.steps_frame_budget_exhausted),
        ),
        ("scans_completed", u64::from(t.scans_completed)),
        ("scans_abandoned", u64::from(t.scans_abandoned)),
        ("tether_readings", u64::from(t.tether_readings)),
        ("goals_received", u64::from(t.goals_received)),
        ("motion_reports", u64::from(t.motion_reports)),
        (
            "motion_report_timeouts",
            u64::from(t.motion_report_timeouts),
        ),
        ("log_dropped", u64::from(t.log_dropped)),
        ("tx_dropped", u64::from(t.tx_dropped)),
        ("device_errors", u64::from(t.device_errors)),
        ("illegal_transitions", u64::from(t.illegal_transitions)),
        ("map.scans_integrated", u64::from(t.map.scans_integrated)),
        ("map.points_integrated", u64::from(t.map.points_integrated)),
        ("map.points_rejected", u64::from(t.map.points_rejected)),
        ("map.voxels_dropped", u64::from(t.map.voxels_dropped)),
        ("map.pool_errors", u64::from(t.map.pool_errors)),
    ]
}

/// The frames of one direction of a log, decoded in order: `(seq, message)`, and the count of frames that did
/// not deframe or decode.
fn frames(log: &FieldLog, dir: Direction) -> (Vec<(u32, Message)>, u64) {
    let mut d = Deframer::new();
    let (mut out, mut bad) = (Vec::new(), 0);
    for r in log.records.iter().filter(|r| r.direction == dir) {
        let mut rest = &r.bytes[..];
        while !rest.is_empty() {
            let (n, ev) = d.push(rest);
            rest = rest.get(n.max(1)..).unwrap_or(&[]);
            match ev.map(|f| {
                f.map_err(|_| ())
                    .and_then(|f| decode_frame(f).map_err(|_| ()))
            }) {
                Some(Ok((h, m))) => out.push((h.seq, m)),
                Some(Err(())) => bad += 1,
                None => {}
            }
        }
    }
    (out, bad)
}

/// Reads a soak's (or any mission's) field log.
pub fn analyse(log: &FieldLog) -> SoakReport {
    let (host, _) = frames(log, Direction::HostToFlight);
    let (flight, flight_undecodable) = frames(log, Direction::FlightToHost);
    let mut acks: BTreeMap<u32, u64> = BTreeMap::new();
    let mut nacks = 0;
    let mut samples = Vec::new();
    for (seq, m) in &flight {
        match m {
            Message::Ack(a) => *acks.entry(a.seq).or_default() += 1,
            Message::Nack(_) => nacks += 1,
            Message::Telemetry(t) => samples.push(Sample {
                seq: *seq,
                telemetry: *t,
            }),
            _ => {}
        }
    }
    let host_seq_gaps = host
        .windows(2)
        .filter(|w| w[1].0 != w[0].0.wrapping_add(1))
        .count() as u64;
    let host_seq_wrapped = host.windows(2).any(|w| w[1].0 < w[0].0);
    let acked = host.iter().filter(|(s, _)| acks.contains_key(s)).count() as u64;
    let acked_twice = host
        .iter()
        .filter(|(s, _)| acks.get(s).is_some_and(|&n| n > 1))
        .count() as u64;
    let flight_lost = flight
        .windows(2)
        .map(|w| u64::from(w[1].0.wrapping_sub(w[0].0).wrapping_sub(1)))
        .sum();
    SoakReport {
        host_frames: host.len() as u64,
        host_seq: host.first().zip(host.last()).map(|(a, b)| (a.0, b.0)),
        host_seq_wrapped,
        host_seq_gaps,
        acked,
        unacked: host.len() as u64 - acked,
        acked_twice,
        nacks,
        flight_frames: flight.len() as u64,
        flight_lost,
        flight_undecodable,
        samples,
    }
}

impl SoakReport {
    /// The telemetry at the start, the middle and the end of the run.
    pub fn start_middle_end(&self) -> Option<[&Sample; 3]> {
        let n = self.samples.len();
        Some([
            self.samples.first()?,
            self.samples.get(n / 2)?,
            self.samples.last()?,
        ])
    }

    /// Counters that went down from one telemetry frame to the next (as a wrapped or reset one would):
    /// (name, before, after).
    pub fn decreased(&self) -> Vec<(&'static str, u64, u64)> {
        let mut out = Vec::new();
        for w in self.samples.windows(2) {
            for ((name, a), (_, b)) in counters(&w[0].telemetry)
                .into_iter()
                .zip(counters(&w[1].telemetry))
            {
                if b < a {
                    out.push((name, a, b));
                }
            }
        }
        out
    }

    /// High-water marks that grew from the middle of the run to its end: (name, middle, end).
    pub fn grew_in_second_half(&self) -> Vec<(&'static str, u32, u32)> {
        let Some([_, mid, end]) = self.start_middle_end() else {
            return vec![];
        };
        high_water(&mid.telemetry.high_water)
            .into_iter()
            .zip(high_water(&end.telemetry.high_water))
            .filter(|((_, m), (_, e))| e > m)
            .map(|((name, m), (_, e))| (name, m, e))
            .collect()
    }

    /// Everything the soak must not show, one line each; empty when it passed. `want_wrap`: the host's numbers
    /// were started to cross 2^32.
    pub fn problems(&self, want_wrap: bool) -> Vec<String> {
        let mut p = Vec::new();
        let mut check = |bad: bool, what: String| {
            if bad {
                p.push(what);
            }
        };
        check(
            want_wrap && !self.host_seq_wrapped,
            "the host's sequence numbers did not cross 2^32".into(),
        );
        check(
            self.host_seq_gaps > 0,
            format!("{} gaps in the host's numbering", self.host_seq_gaps),
        );
        check(
            self.unacked > 0,
            format!(
                "{} host frames never acknowledged (lost or refused)",
                self.unacked
            ),
        );
        check(
            self.acked_twice > 0,
            format!("{} host frames acknowledged twice", self.acked_twice),
        );
        check(self.nacks > 0, format!("{} Nacks", self.nacks));
        check(
            self.flight_lost > 0,
            format!(
                "{} flight frames lost (gaps in their numbering)",
                self.flight_lost
            ),
        );
        check(
            self.flight_undecodable > 0,
            format!("{} flight frames undecodable", self.flight_undecodable),
        );
        check(
            self.samples.len() < 3,
            format!("{} telemetry frames, at least 3 needed", self.samples.len()),
        );
        for (name, a, b) in self.decreased() {
            check(
                true,
                format!("counter {name} went down from {a} to {b} (wrapped or reset)"),
            );
        }
        for s in &self.samples {
            // `frames_sent` excludes the telemetry frame itself, so it equals that frame's number (from 0)
            check(
                s.telemetry.frames_sent != s.seq,
                format!(
                    "telemetry frame {} counts {} frames sent before it",
                    s.seq, s.telemetry.frames_sent
                ),
            );
        }
        if let Some(end) = self.samples.last() {
            let t = &end.telemetry;
            check(
                t.tx_dropped > 0,
                format!(
                    "{} flight frames dropped on a full transmit queue",
                    t.tx_dropped
                ),
            );
            check(
                t.log_dropped > 0,
                format!("{} flight log lines dropped", t.log_dropped),
            );
        }
        for (name, m, e) in self.grew_in_second_half() {
            check(
                true,
                format!("high-water mark {name} grew in the second half: {m} -> {e}"),
            );
        }
        p
    }
}

impl core::fmt::Display for SoakReport {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        let (a, b) = self.host_seq.unwrap_or_default();
        writeln!(
            f,
            "host frames: {} sent (seq {a} .. {b}, wrapped: {}), {} acked, {} unacked, {} acked twice, {} nacks",
            self.host_frames, self.host_seq_wrapped, self.acked, self.unacked, self.acked_twice, self.nacks
        )?;
        writeln!(
            f,
            "flight frames: {} received, {} lost, {} undecodable; {} telemetry frames",
            self.flight_frames,
            self.flight_lost,
            self.flight_undecodable,
            self.samples.len()
        )?;
        if let Some(sme) = self.start_middle_end() {
            writeln!(
                f,
                "{:<30} {:>14} {:>14} {:>14}",
                "telemetry", "start", "middle", "end"
            )?;
            let names = high_water(&sme[0].telemetry.high_water).map(|(n, _)| n);
            for (k, name) in names.iter().enumerate() {
                let v = sme.map(|s| high_water(&s.telemetry.high_water)[k].1);
                writeln!(
                    f,
                    "{:<30} {:>14} {:>14} {:>14}",
                    format!("high water {name}"),
                    v[0],
                    v[1],
                    v[2]
                )?;
            }
            let [a, b, c] = sme.map(|s| counters(&s.telemetry));
            for (((name, x), (_, y)), (_, z)) in a.into_iter().zip(b).zip(c) {
                writeln!(f, "{:<30} {:>14} {:>14} {:>14}", name, x, y, z)?;
            }
        }
        Ok(())
    }
}
