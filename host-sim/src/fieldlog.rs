//! Field logs: every byte in both directions, with timestamps, in an append-only file with a checksum per record.
//!
//! Format (all integers little-endian; `host-sim/doc/fieldlog.md` has the same table):
//!
//! Header: `magic "TBOTFLOG"` (8) | `format_version u16` (= 4; 1, 2 and 3 are still read) | `protocol_version u8` |
//! `reserved u8` (0) | `created_at_unix_ms u64` (passed in by the caller) | `seed u64` | `config_len u32` |
//! `config` (UTF-8 JSON, at most 1 MiB) | `header_crc u32` (CRC-32/ISO-HDLC of all header bytes before it).
//!
//! Record: `direction u8` (1 host -> flight, 2 flight -> host, 3 end, 4 fault) | `t_us u64` (link time) | `len u32` (at
//! most 16 MiB) | `bytes` | `crc u32` (CRC-32 of direction, t_us, len and bytes).
//!
//! End record (format 2): direction 3, the last record's time, 8 bytes: the number of data records before it
//! (`u64`). [`Writer::finish`] writes it; a log without one was cut short (possibly exactly at a record boundary,
//! where nothing else would show it) or is a format-1 log, and [`FieldLog::end`] is `None`.
//!
//! Fault record (format 3): direction 4, the link time of an injected link fault, its description
//! (`link::faults::FaultEvent::to_bytes`). Fault records are kept apart from the data records ([`FieldLog::faults`]),
//! so replay and export see only the bytes that crossed the link; the end record counts both. Format 4 (downlink
//! faults): a fault record's payload ends with the faulted direction (26 bytes; a format-3 payload has 25 and was
//! always an uplink fault).
//!
//! The reader keeps every valid record. At damage (a bad checksum, direction or length, or a truncated record)
//! it reports where (byte offset) and why, then resynchronises: it looks for the next byte offset where a whole
//! valid record starts (direction 1-3, a length that fits, a time not before the last good record's, a matching
//! checksum) and goes on from there, so one flipped bit costs one record, not the rest of the log. Each damaged
//! span is one [`Damage`] with the bytes skipped; the end record's count says how many records were lost.

use std::io::Write;

/// Magic bytes at the start of a field log.
pub const MAGIC: &[u8; 8] = b"TBOTFLOG";
/// Format version this build writes (it also reads [`FORMAT_VERSION_1`], [`FORMAT_VERSION_2`] and
/// [`FORMAT_VERSION_3`]).
pub const FORMAT_VERSION: u16 = 4;
/// The third format: fault records of uplink faults only (25-byte payloads, no direction byte).
pub const FORMAT_VERSION_3: u16 = 3;
/// The second format: an end record, no fault records.
pub const FORMAT_VERSION_2: u16 = 2;
/// The first format: the same records, no end record.
pub const FORMAT_VERSION_1: u16 = 1;
/// Direction byte of the end record (format 2).
const END_DIRECTION: u8 = 3;
/// Direction byte of a fault record (format 3).
const FAULT_DIRECTION: u8 = 4;
/// Largest configuration text.
pub const MAX_CONFIG_LEN: usize = 1 << 20;
/// Largest record payload.
pub const MAX_RECORD_LEN: usize = 1 << 24;
/// Bytes of a record around its payload.
pub const RECORD_OVERHEAD: usize = 1 + 8 + 4 + 4;

const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Direction of a record.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Direction {
    /// Host (simulator) to flight software.
    HostToFlight,
    /// Flight software to host.
    FlightToHost,
}

impl Direction {
    fn to_u8(self) -> u8 {
        match self {
            Direction::HostToFlight => 1,
            Direction::FlightToHost => 2,
        }
    }
    fn from_u8(b: u8) -> Option<Self> {
        match b {
            1 => Some(Direction::HostToFlight),
            2 => Some(Direction::FlightToHost),
            _ => None,
        }
    }
}

/// The log header.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Header {
    /// Protocol version of the recorded frames.
    pub protocol_version: u8,
    /// When the log was created, Unix milliseconds (passed in; never read from a clock by this module).
    pub created_at_unix_ms: u64,
    /// Seed of the run.
    pub seed: u64,
    /// Configuration of the run (JSON text).
    pub config: String,
}

/// One record.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Record {
    /// Which way the bytes went.
    pub direction: Direction,
    /// Link time, microseconds.
    pub t_us: u64,
    /// The bytes.
    pub bytes: Vec<u8>,
    /// Byte offset of the record in the file.
    pub offset: u64,
}

/// A fault record: an injected link fault (its payload is `link::faults::FaultEvent::to_bytes`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct FaultRecord {
    /// Link time, microseconds.
    pub t_us: u64,
    /// The fault's description.
    pub bytes: Vec<u8>,
    /// Byte offset of the record in the file.
    pub offset: u64,
}

/// Why bytes of the log could not be read as records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DamageReason {
    /// The file ends inside a record.
    Truncated,
    /// Bytes follow the end record.
    AfterEnd,
    /// An end record's payload is not one 8-byte count.
    BadEndRecord,
    /// A record's checksum does not match.
    BadChecksum,
    /// A record's direction byte is not one of its format's (1, 2; 3 from format 2; 4 from format 3).
    BadDirection,
    /// A record's length is above `MAX_RECORD_LEN`.
    LengthTooLarge,
}

/// Where and why a log is damaged: one damaged span, from `offset` to the next valid record (or the end).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Damage {
    /// Byte offset of the first damaged record.
    pub offset: u64,
    /// Why it is damaged.
    pub reason: DamageReason,
    /// Bytes skipped from the damage to the next valid record (or to the end of the file).
    pub unread_bytes: u64,
}

/// The end record of a complete log.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EndRecord {
    /// Byte offset of the end record.
    pub offset: u64,
    /// Data records the writer wrote before it.
    pub records: u64,
}

/// Why the header could not be read (then nothing in the log can be trusted).
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum HeaderError {
    /// Not a field log (magic bytes differ).
    BadMagic,
    /// A format version this build does not read.
    UnsupportedVersion(u16),
    /// The file ends inside the header.
    Truncated,
    /// The header checksum does not match.
    BadChecksum,
    /// The configuration is longer than `MAX_CONFIG_LEN` or not UTF-8.
    BadConfig,
}

impl core::fmt::Display for HeaderError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            HeaderError::BadMagic => write!(f, "not a tetherbot field log (bad magic)"),
            HeaderError::UnsupportedVersion(v) => write!(
                f,
                "field log format version {v} is not supported (this build reads 1 to {FORMAT_VERSION})"
            ),
            HeaderError::Truncated => write!(f, "field log header is truncated"),
            HeaderError::BadChecksum => write!(f, "field log header checksum mismatch"),
            HeaderError::BadConfig => {
                write!(f, "field log configuration text is too long or not UTF-8")
            }
        }
    }
}

impl core::error::Error for HeaderError {}

/// A parsed log: the header, every valid record, the damage and the end record.
#[derive(Debug, Clone)]
pub struct FieldLog {
    /// The header.
    pub header: Header,
    /// Format version of the file (1 or 2).
    pub format_version: u16,
    /// Every valid data record, in file order (damaged spans skipped).
    pub records: Vec<Record>,
    /// Every valid fault record (format 3), in file order.
    pub faults: Vec<FaultRecord>,
    /// The first damage, if any (the same as `damaged[0]`).
    pub damage: Option<Damage>,
    /// Every damaged span, in file order.
    pub damaged: Vec<Damage>,
    /// The end record (format 2), if the file has one.
    pub end: Option<EndRecord>,
}

/// What a reader can say about a log's completeness.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Completeness {
    /// An end record, no damage, and its count equals the records read.
    Complete,
    /// No end record and no damage: the log may have been cut at a record boundary (or is format 1).
    NoEndRecord,
    /// Damaged spans were skipped; `lost` records are missing by the end record's count (`None` without one).
    Damaged {
        /// Damaged spans.
        spans: usize,
        /// Records missing (the end record's count minus the records read), if there is an end record.
        lost: Option<u64>,
    },
    /// No damage, but the end record counts other than the records read (a writer bug or a forged log).
    CountMismatch {
        /// The end record's count.
        expected: u64,
        /// Records read.
        read: u64,
    },
}

impl FieldLog {
    /// Whether the log is complete, and if not, why.
    pub fn completeness(&self) -> Completeness {
        let read = (self.records.len() + self.faults.len()) as u64;
        match (self.damaged.len(), self.end) {
            (0, Some(e)) if e.records == read => Completeness::Complete,
            (0, Some(e)) => Completeness::CountMismatch {
                expected: e.records,
                read,
            },
            (0, None) => Completeness::NoEndRecord,
            (spans, end) => Completeness::Damaged {
                spans,
                lost: end.map(|e| e.records.saturating_sub(read)),
            },
        }
    }
}

impl core::fmt::Display for Completeness {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            Completeness::Complete => write!(f, "complete (end record present, every record read)"),
            Completeness::NoEndRecord => write!(f, "no end record: truncated? (or a format-1 log, which has none)"),
            Completeness::Damaged { spans, lost: Some(n) } => {
                write!(f, "{spans} damaged span(s) skipped; {n} record(s) lost by the end record's count")
            }
            Completeness::Damaged { spans, lost: None } => {
                write!(f, "{spans} damaged span(s) skipped; no end record, so the number of lost records is unknown")
            }
            Completeness::CountMismatch { expected, read } => {
                write!(f, "the end record counts {expected} records but {read} were read")
            }
        }
    }
}

fn header_bytes(h: &Header) -> Vec<u8> {
    let mut b = Vec::with_capacity(36 + h.config.len());
    b.extend_from_slice(MAGIC);
    b.extend_from_slice(&FORMAT_VERSION.to_le_bytes());
    b.push(h.protocol_version);
    b.push(0);
    b.extend_from_slice(&h.created_at_unix_ms.to_le_bytes());
    b.extend_from_slice(&h.seed.to_le_bytes());
    b.extend_from_slice(&(h.config.len() as u32).to_le_bytes());
    b.extend_from_slice(h.config.as_bytes());
    let crc = CRC.checksum(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Encodes one record.
pub fn record_bytes(direction: Direction, t_us: u64, bytes: &[u8]) -> Vec<u8> {
    raw_record(direction.to_u8(), t_us, bytes)
}

/// Encodes the end record: `records` data records were written before it, the last at `t_us`.
pub fn end_record_bytes(t_us: u64, records: u64) -> Vec<u8> {
    raw_record(END_DIRECTION, t_us, &records.to_le_bytes())
}

fn raw_record(direction: u8, t_us: u64, bytes: &[u8]) -> Vec<u8> {
    let mut b = Vec::with_capacity(RECORD_OVERHEAD + bytes.len());
    b.push(direction);
    b.extend_from_slice(&t_us.to_le_bytes());
    b.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    b.extend_from_slice(bytes);
    let crc = CRC.checksum(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Appends records to a field log; [`Writer::finish`] closes it with the end record.
pub struct Writer<W: Write> {
    out: W,
    records: u64,
    last_t_us: u64,
}

impl<W: Write> Writer<W> {
    /// Writes the header.
    pub fn new(mut out: W, header: &Header) -> std::io::Result<Self> {
        if header.config.len() > MAX_CONFIG_LEN {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "configuration text too long",
            ));
        }
        out.write_all(&header_bytes(header))?;
        Ok(Self { out, records: 0, last_t_us: 0 })
    }

    /// Appends one record (empty byte strings are skipped).
    pub fn append(&mut self, direction: Direction, t_us: u64, bytes: &[u8]) -> std::io::Result<()> {
        if bytes.is_empty() {
            return Ok(());
        }
        if bytes.len() > MAX_RECORD_LEN {
            return Err(std::io::Error::new(
                std::io::ErrorKind::InvalidInput,
                "record too long",
            ));
        }
        self.out.write_all(&record_bytes(direction, t_us, bytes))?;
        self.records += 1;
        self.last_t_us = self.last_t_us.max(t_us);
        Ok(())
    }

    /// Appends a fault record (format 3; [`FieldLog::faults`]).
    pub fn append_fault(&mut self, t_us: u64, bytes: &[u8]) -> std::io::Result<()> {
        self.out
            .write_all(&raw_record(FAULT_DIRECTION, t_us, bytes))?;
        self.records += 1;
        self.last_t_us = self.last_t_us.max(t_us);
        Ok(())
    }

    /// Writes the end record (the count of records appended), flushes and gives the writer back. A log closed
    /// without it reads as "no end record: truncated?".
    pub fn finish(mut self) -> std::io::Result<W> {
        self.out
            .write_all(&end_record_bytes(self.last_t_us, self.records))?;
        self.out.flush()?;
        Ok(self.out)
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }

    /// Gives the writer back without an end record (the log then reads as possibly truncated; see
    /// [`Writer::finish`]).
    pub fn into_inner(self) -> W {
        self.out
    }
}

fn u16_at(b: &[u8], at: usize) -> Option<u16> {
    Some(u16::from_le_bytes(b.get(at..at + 2)?.try_into().ok()?))
}
fn u32_at(b: &[u8], at: usize) -> Option<u32> {
    Some(u32::from_le_bytes(b.get(at..at + 4)?.try_into().ok()?))
}
fn u64_at(b: &[u8], at: usize) -> Option<u64> {
    Some(u64::from_le_bytes(b.get(at..at + 8)?.try_into().ok()?))
}

/// Parses a whole log from memory.
pub fn parse(b: &[u8]) -> Result<FieldLog, HeaderError> {
    if b.len() < 8 {
        return Err(if MAGIC.starts_with(b) {
            HeaderError::Truncated
        } else {
            HeaderError::BadMagic
        });
    }
    if b.get(..8) != Some(&MAGIC[..]) {
        return Err(HeaderError::BadMagic);
    }
    let version = u16_at(b, 8).ok_or(HeaderError::Truncated)?;
    if !(FORMAT_VERSION_1..=FORMAT_VERSION).contains(&version) {
        return Err(HeaderError::UnsupportedVersion(version));
    }
    let protocol_version = *b.get(10).ok_or(HeaderError::Truncated)?;
    let created_at_unix_ms = u64_at(b, 12).ok_or(HeaderError::Truncated)?;
    let seed = u64_at(b, 20).ok_or(HeaderError::Truncated)?;
    let config_len = u32_at(b, 28).ok_or(HeaderError::Truncated)? as usize;
    if config_len > MAX_CONFIG_LEN {
        return Err(HeaderError::BadConfig);
    }
    let end = 32 + config_len;
    let config_bytes = b.get(32..end).ok_or(HeaderError::Truncated)?;
    let crc = u32_at(b, end).ok_or(HeaderError::Truncated)?;
    if CRC.checksum(&b[..end]) != crc {
        return Err(HeaderError::BadChecksum);
    }
    let config = String::from_utf8(config_bytes.to_vec()).map_err(|_| HeaderError::BadConfig)?;
    let header = Header {
        protocol_version,
        created_at_unix_ms,
        seed,
        config,
    };
    let mut log = FieldLog {
        header,
        format_version: version,
        records: Vec::new(),
        faults: Vec::new(),
        damage: None,
        damaged: Vec::new(),
        end: None,
    };
    let mut at = end + 4;
    let mut last_t = 0u64;
    // Each pass reads one record or one damaged span; every pass advances `at`, so at most `b.len()` passes.
    while at < b.len() {
        match record_at(b, at, version) {
            Ok(r) => {
                let next = at + RECORD_OVERHEAD + r.bytes.len();
                if r.dir == END_DIRECTION {
                    match <[u8; 8]>::try_from(r.bytes) {
                        Ok(n) => {
                            log.end = Some(EndRecord {
                                offset: at as u64,
                                records: u64::from_le_bytes(n),
                            });
                            if next < b.len() {
                                push_damage(&mut log, next, DamageReason::AfterEnd, b.len() - next);
                            }
                            break;
                        }
                        Err(_) => {
                            push_damage(&mut log, at, DamageReason::BadEndRecord, next - at);
                            at = next;
                            continue;
                        }
                    }
                }
                if r.dir == FAULT_DIRECTION {
                    last_t = last_t.max(r.t_us);
                    log.faults.push(FaultRecord {
                        t_us: r.t_us,
                        bytes: r.bytes.to_vec(),
                        offset: at as u64,
                    });
                    at = next;
                    continue;
                }
                let Some(direction) = Direction::from_u8(r.dir) else {
                    break;
                };
                last_t = last_t.max(r.t_us);
                log.records.push(Record {
                    direction,
                    t_us: r.t_us,
                    bytes: r.bytes.to_vec(),
                    offset: at as u64,
                });
                at = next;
            }
            Err(reason) => {
                let resume = (at + 1..b.len())
                    .find(|&p| record_at(b, p, version).is_ok_and(|r| r.t_us >= last_t));
                let stop = resume.unwrap_or(b.len());
                push_damage(&mut log, at, reason, stop - at);
                at = stop;
            }
        }
    }
    Ok(log)
}

fn push_damage(log: &mut FieldLog, at: usize, reason: DamageReason, skipped: usize) {
    let d = Damage {
        offset: at as u64,
        reason,
        unread_bytes: skipped as u64,
    };
    log.damage.get_or_insert(d);
    log.damaged.push(d);
}

/// A whole record's fields, checked (the checksum matches; the direction is one of the format's).
struct RawRecord<'a> {
    dir: u8,
    t_us: u64,
    bytes: &'a [u8],
}

fn record_at(b: &[u8], at: usize, version: u16) -> Result<RawRecord<'_>, DamageReason> {
    let (Some(&dir), Some(t_us), Some(len)) = (b.get(at), u64_at(b, at + 1), u32_at(b, at + 9))
    else {
        return Err(DamageReason::Truncated);
    };
    let len = len as usize;
    if len > MAX_RECORD_LEN {
        return Err(DamageReason::LengthTooLarge);
    }
    let body_end = at + 13 + len;
    let (Some(body), Some(stored)) = (b.get(at..body_end), u32_at(b, body_end)) else {
        return Err(DamageReason::Truncated);
    };
    if CRC.checksum(body) != stored {
        return Err(DamageReason::BadChecksum);
    }
    let known = Direction::from_u8(dir).is_some()
        || (version >= FORMAT_VERSION_2 && dir == END_DIRECTION)
        || (version >= FORMAT_VERSION_3 && dir == FAULT_DIRECTION);
    if !known {
        return Err(DamageReason::BadDirection);
    }
    Ok(RawRecord {
        dir,
        t_us,
        bytes: body.get(13..).unwrap_or_default(),
    })
}

/// Reads and parses a log file.
pub fn read_file(path: &std::path::Path) -> Result<FieldLog, Box<dyn core::error::Error>> {
    let b = std::fs::read(path).map_err(|e| format!("cannot read {}: {e}", path.display()))?;
    Ok(parse(&b)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> Vec<u8> {
        let h = Header {
            protocol_version: 1,
            created_at_unix_ms: 5,
            seed: 42,
            config: "{\"a\":1}".into(),
        };
        let mut w = Writer::new(Vec::new(), &h).unwrap();
        w.append(Direction::HostToFlight, 10, &[1, 2, 3]).unwrap();
        w.append(Direction::FlightToHost, 20, &[4, 5]).unwrap();
        w.append(Direction::HostToFlight, 30, &[6]).unwrap();
        w.into_inner()
    }

    #[test]
    fn roundtrip_and_offsets() {
        let b = sample();
        let log = parse(&b).unwrap();
        assert_eq!(log.header.seed, 42);
        assert_eq!(log.header.config, "{\"a\":1}");
        assert_eq!(log.records.len(), 3);
        assert!(log.damage.is_none());
        // header: 32 fixed bytes + 7 config + 4 crc = 43
        assert_eq!(log.records[0].offset, 43);
        assert_eq!(log.records[1].offset, 43 + 17 + 3);
        assert_eq!(log.records[2].bytes, [6]);
    }

    #[test]
    fn every_truncation_keeps_the_whole_records_before_it() {
        let b = sample();
        let offsets: Vec<usize> = parse(&b)
            .unwrap()
            .records
            .iter()
            .map(|r| r.offset as usize)
            .collect();
        for cut in offsets[0]..b.len() {
            let log = parse(&b[..cut]).unwrap();
            let whole = offsets.iter().filter(|&&o| o < cut).count();
            let complete = log.records.len();
            // records fully inside the cut are kept; the one cut through is reported at its offset
            let expect_damage = !offsets.contains(&cut);
            assert_eq!(log.damage.is_some(), expect_damage, "cut {cut}");
            if let Some(d) = log.damage {
                assert_eq!(d.reason, DamageReason::Truncated);
                assert_eq!(d.offset as usize, offsets[complete]);
                assert_eq!(complete, whole - 1);
            } else {
                assert_eq!(complete, whole);
            }
        }
    }

    fn finished() -> (Vec<u8>, Vec<u64>) {
        let h = Header { protocol_version: 1, created_at_unix_ms: 5, seed: 42, config: "{}".into() };
        let mut w = Writer::new(Vec::new(), &h).unwrap();
        for k in 0..6u8 {
            let dir = if k % 2 == 0 { Direction::HostToFlight } else { Direction::FlightToHost };
            w.append(dir, 10 * u64::from(k), &[k; 5]).unwrap();
        }
        let b = w.finish().unwrap();
        let offsets = parse(&b).unwrap().records.iter().map(|r| r.offset).collect();
        (b, offsets)
    }

    /// Regression (issue 24): a log cut exactly at a record boundary read as complete ("no damage"). A finished
    /// log has an end record with the record count; every cut, at a boundary or not, is reported.
    #[test]
    fn a_finished_log_is_complete_and_every_cut_is_reported() {
        let (b, offsets) = finished();
        let log = parse(&b).unwrap();
        assert_eq!(log.format_version, FORMAT_VERSION);
        assert_eq!(log.completeness(), Completeness::Complete);
        assert_eq!(log.end.map(|e| e.records), Some(6));
        for cut in offsets[0] as usize..b.len() {
            let log = parse(&b[..cut]).unwrap();
            assert_ne!(log.completeness(), Completeness::Complete, "cut {cut}");
            if offsets.contains(&(cut as u64)) || cut == b.len() - RECORD_OVERHEAD - 8 {
                assert_eq!(log.completeness(), Completeness::NoEndRecord, "cut {cut}");
            }
        }
        // bytes after the end record are damage
        let mut longer = b.clone();
        longer.extend_from_slice(&[0u8; 3]);
        let log = parse(&longer).unwrap();
        assert_eq!(log.damage.map(|d| (d.reason, d.unread_bytes)), Some((DamageReason::AfterEnd, 3)));
        assert_eq!(log.records.len(), 6);
    }

    /// Regression (issue 24): one flipped bit in a payload lost every record after it. The reader skips the
    /// damaged record, resynchronises at the next one and counts the loss by the end record.
    #[test]
    fn one_bit_flip_costs_one_record() {
        let (b, offsets) = finished();
        let good = parse(&b).unwrap();
        for k in 0..offsets.len() {
            let mut flipped = b.clone();
            flipped[offsets[k] as usize + 13 + 2] ^= 0x08;
            let log = parse(&flipped).unwrap();
            let mut expect = good.records.clone();
            expect.remove(k);
            assert_eq!(log.records, expect, "flip in record {k}");
            let d = log.damage.unwrap();
            assert_eq!((d.offset, d.reason, d.unread_bytes), (offsets[k], DamageReason::BadChecksum, (RECORD_OVERHEAD + 5) as u64));
            assert_eq!(log.completeness(), Completeness::Damaged { spans: 1, lost: Some(1) });
        }
        // two damaged spans, garbage in between, a flipped time field: still every other record
        let mut two = b.clone();
        two[offsets[1] as usize + 3] ^= 0x01;
        two[offsets[4] as usize] = 9;
        let log = parse(&two).unwrap();
        assert_eq!(log.records.len(), 4);
        assert_eq!(log.damaged.len(), 2);
        assert_eq!(
            log.completeness(),
            Completeness::Damaged {
                spans: 2,
                lost: Some(2)
            }
        );
    }

    /// Format 3 (and 4): fault records are kept apart from the data records and counted by the end record; a
    /// format-2 log (every log before issue 24 item 1) still reads, and a fault record is not a format-2 record.
    #[test]
    fn fault_records_in_format_3_and_format_2_logs_still_read() {
        let h = Header {
            protocol_version: 4,
            created_at_unix_ms: 5,
            seed: 42,
            config: "{}".into(),
        };
        let mut w = Writer::new(Vec::new(), &h).unwrap();
        w.append(Direction::HostToFlight, 10, &[1, 2]).unwrap();
        w.append_fault(12, &[7; 25]).unwrap();
        w.append(Direction::FlightToHost, 20, &[3]).unwrap();
        let b = w.finish().unwrap();
        let log = parse(&b).unwrap();
        assert_eq!(log.format_version, FORMAT_VERSION);
        assert_eq!(log.records.len(), 2);
        assert_eq!(log.faults.len(), 1);
        assert_eq!(
            (log.faults[0].t_us, log.faults[0].bytes.as_slice()),
            (12, &[7u8; 25][..])
        );
        assert_eq!(log.end.map(|e| e.records), Some(3));
        assert_eq!(log.completeness(), Completeness::Complete);
        // a lost fault record is a lost record
        let mut cut = b.clone();
        cut[log.faults[0].offset as usize + 14] ^= 1;
        assert_eq!(
            parse(&cut).unwrap().completeness(),
            Completeness::Damaged {
                spans: 1,
                lost: Some(1)
            }
        );
        // the same bytes as format 2: the data records and the end record read; the fault record is damage
        let mut v2 = b.clone();
        v2[8..10].copy_from_slice(&FORMAT_VERSION_2.to_le_bytes());
        let hdr_end = 32 + 2;
        let crc = CRC.checksum(&v2[..hdr_end]);
        v2[hdr_end..hdr_end + 4].copy_from_slice(&crc.to_le_bytes());
        let old = parse(&v2).unwrap();
        assert_eq!(
            (old.format_version, old.records.len(), old.faults.len()),
            (2, 2, 0)
        );
        assert_eq!(
            old.damage.map(|d| d.reason),
            Some(DamageReason::BadDirection)
        );
        // a format-2 log as the previous build wrote it (no fault record) is complete
        let mut w2 = Writer::new(Vec::new(), &h).unwrap();
        w2.append(Direction::HostToFlight, 10, &[1, 2]).unwrap();
        let mut b2 = w2.finish().unwrap();
        b2[8..10].copy_from_slice(&FORMAT_VERSION_2.to_le_bytes());
        let crc = CRC.checksum(&b2[..hdr_end]);
        b2[hdr_end..hdr_end + 4].copy_from_slice(&crc.to_le_bytes());
        assert_eq!(parse(&b2).unwrap().completeness(), Completeness::Complete);
        assert_eq!(
            parse(
                &b2[..8]
                    .iter()
                    .chain(&(FORMAT_VERSION + 1).to_le_bytes())
                    .copied()
                    .collect::<Vec<u8>>()
            )
            .map(|_| ()),
            Err(HeaderError::UnsupportedVersion(FORMAT_VERSION + 1))
        );
    }

    /// A format-1 log (no end record) still reads, with the verdict "no end record".
    #[test]
    fn format_1_logs_still_read() {
        let mut v1 = sample();
        v1[8..10].copy_from_slice(&FORMAT_VERSION_1.to_le_bytes());
        let hdr_end = 32 + 7;
        let crc = CRC.checksum(&v1[..hdr_end]);
        v1[hdr_end..hdr_end + 4].copy_from_slice(&crc.to_le_bytes());
        let log = parse(&v1).unwrap();
        assert_eq!((log.format_version, log.records.len()), (1, 3));
        assert_eq!(log.completeness(), Completeness::NoEndRecord);
        assert!(log.completeness().to_string().contains("no end record: truncated?"));
        // an end record is not a format-1 record
        let mut with_end = v1.clone();
        with_end.extend_from_slice(&end_record_bytes(30, 3));
        assert_eq!(parse(&with_end).unwrap().damage.map(|d| d.reason), Some(DamageReason::BadDirection));
    }
}
