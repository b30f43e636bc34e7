//! Export a field log to MCAP (<https://mcap.dev>) for standard robotics log viewers (Foxglove and others).
//!
//! Channels: `/link/host_to_flight` and `/link/flight_to_host` carry the raw recorded bytes (message encoding
//! `tetherbot-wire-v1`, COBS frames as sent); `/frames/host_to_flight` and `/frames/flight_to_host` carry one JSON
//! message per decoded frame (`{"seq", "kind", "body"}` or `{"error"}` for a frame that does not decode). Log
//! time is the recorded link time in nanoseconds. The field-log header goes into an MCAP metadata record.

use std::collections::BTreeMap;
use std::io::{Seek, Write};

use firmware::protocol::{self, Deframer, Message};
use mcap::records::{MessageHeader, Metadata};

use crate::fieldlog::{Direction, FieldLog};

/// The decoded body of a message as JSON.
pub fn message_json(m: &Message) -> serde_json::Value {
    let body = match m {
        Message::TimeTick(b) => serde_json::to_value(b),
        Message::SensorChunk(b) => serde_json::to_value(b),
        Message::TetherReading(b) => serde_json::to_value(b),
        Message::GoalRequest(b) => serde_json::to_value(b),
        Message::Configure(b) => serde_json::to_value(b),
        Message::Shutdown(b) => serde_json::to_value(b),
        Message::TelemetryRequest(b) => serde_json::to_value(b),
        Message::Ack(b) => serde_json::to_value(b),
        Message::Nack(b) => serde_json::to_value(b),
        Message::PlanStatus(b) => serde_json::to_value(b),
        Message::Plan(b) => serde_json::to_value(b),
        Message::DriveCommand(b) => serde_json::to_value(b),
        Message::Telemetry(b) => serde_json::to_value(b),
        Message::Log(b) => serde_json::to_value(b),
        Message::MotionReport(b) => serde_json::to_value(b),
        Message::GoalCancel(b) => serde_json::to_value(b),
        Message::MissionStatus(b) => serde_json::to_value(b),
    };
    body.unwrap_or(serde_json::Value::Null)
}

/// Counts of what was exported.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExportStats {
    /// Raw byte records written.
    pub raw_records: usize,
    /// Decoded frames written.
    pub frames: usize,
    /// Frames that did not decode (written as errors).
    pub bad_frames: usize,
}

/// Writes `log` as MCAP into `out`.
pub fn export<W: Write + Seek>(log: &FieldLog, out: W) -> Result<ExportStats, mcap::McapError> {
    let mut w = mcap::Writer::new(out)?;
    let none = BTreeMap::new();
    let raw_h2f = w.add_channel(0, "/link/host_to_flight", "tetherbot-wire-v1", &none)?;
    let raw_f2h = w.add_channel(0, "/link/flight_to_host", "tetherbot-wire-v1", &none)?;
    let json_h2f = w.add_channel(0, "/frames/host_to_flight", "json", &none)?;
    let json_f2h = w.add_channel(0, "/frames/flight_to_host", "json", &none)?;
    let mut meta = BTreeMap::new();
    meta.insert(
        "protocol_version".to_string(),
        log.header.protocol_version.to_string(),
    );
    meta.insert("seed".to_string(), log.header.seed.to_string());
    meta.insert(
        "created_at_unix_ms".to_string(),
        log.header.created_at_unix_ms.to_string(),
    );
    meta.insert("config".to_string(), log.header.config.clone());
    w.write_metadata(&Metadata {
        name: "tetherbot-field-log".to_string(),
        metadata: meta,
    })?;

    let mut stats = ExportStats::default();
    let mut deframers = [Deframer::new(), Deframer::new()];
    let mut seqs = [0u32; 4];
    for r in &log.records {
        let (raw, json, side) = match r.direction {
            Direction::HostToFlight => (raw_h2f, json_h2f, 0),
            Direction::FlightToHost => (raw_f2h, json_f2h, 1),
        };
        let t_ns = r.t_us.saturating_mul(1000);
        let header = |channel_id: u16, sequence: u32| MessageHeader {
            channel_id,
            sequence,
            log_time: t_ns,
            publish_time: t_ns,
        };
        w.write_to_known_channel(&header(raw, seqs[side]), &r.bytes)?;
        seqs[side] += 1;
        stats.raw_records += 1;
        let mut rest = &r.bytes[..];
        while !rest.is_empty() {
            let (n, ev) = deframers[side].push(rest);
            rest = &rest[n..];
            let Some(ev) = ev else { continue };
            let value = match ev
                .map_err(protocol::NackReason::from)
                .and_then(protocol::decode_frame)
            {
                Ok((h, m)) => {
                    serde_json::json!({"seq": h.seq, "kind": format!("{:?}", m.kind()), "body": message_json(&m)})
                }
                Err(reason) => {
                    stats.bad_frames += 1;
                    serde_json::json!({"error": format!("{reason:?}")})
                }
            };
            let bytes = serde_json::to_vec(&value).unwrap_or_default();
            w.write_to_known_channel(&header(json, seqs[side + 2]), &bytes)?;
            seqs[side + 2] += 1;
            stats.frames += 1;
        }
    }
    w.finish()?;
    Ok(stats)
}
