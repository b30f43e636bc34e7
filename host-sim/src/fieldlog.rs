//! Field logs: every byte in both directions, with timestamps, in an append-only file with a checksum per record.
//!
//! Format (all integers little-endian; `host-sim/doc/fieldlog.md` has the same table):
//!
//! Header: `magic "TBOTFLOG"` (8) | `format_version u16` (= 1) | `protocol_version u8` | `reserved u8` (0) |
//! `created_at_unix_ms u64` (passed in by the caller) | `seed u64` | `config_len u32` | `config` (UTF-8 JSON,
//! at most 1 MiB) | `header_crc u32` (CRC-32/ISO-HDLC of all header bytes before it).
//!
//! Record: `direction u8` (1 host -> flight, 2 flight -> host) | `t_us u64` (link time) | `len u32` (at most
//! 16 MiB) | `bytes` | `crc u32` (CRC-32 of direction, t_us, len and bytes).
//!
//! The reader returns every valid record up to the first damage and reports where (byte offset) and why the
//! damage starts, and how many bytes follow it; nothing before the damage is lost.

use std::io::Write;

/// Magic bytes at the start of a field log.
pub const MAGIC: &[u8; 8] = b"TBOTFLOG";
/// Format version this build writes and reads.
pub const FORMAT_VERSION: u16 = 1;
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

/// Why reading stopped before the end of the file.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DamageReason {
    /// The file ends inside a record.
    Truncated,
    /// A record's checksum does not match.
    BadChecksum,
    /// A record's direction byte is not 1 or 2.
    BadDirection,
    /// A record's length is above `MAX_RECORD_LEN`.
    LengthTooLarge,
}

/// Where and why a log is damaged.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Damage {
    /// Byte offset of the first damaged record.
    pub offset: u64,
    /// Why it is damaged.
    pub reason: DamageReason,
    /// Bytes from the damage to the end of the file (not read).
    pub unread_bytes: u64,
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
                "field log format version {v} is not supported (this build reads {FORMAT_VERSION})"
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

/// A parsed log: the header, every valid record, and the damage if reading stopped early.
#[derive(Debug, Clone)]
pub struct FieldLog {
    /// The header.
    pub header: Header,
    /// Records up to the damage (or the end).
    pub records: Vec<Record>,
    /// The first damage, if any.
    pub damage: Option<Damage>,
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
    let mut b = Vec::with_capacity(RECORD_OVERHEAD + bytes.len());
    b.push(direction.to_u8());
    b.extend_from_slice(&t_us.to_le_bytes());
    b.extend_from_slice(&(bytes.len() as u32).to_le_bytes());
    b.extend_from_slice(bytes);
    let crc = CRC.checksum(&b);
    b.extend_from_slice(&crc.to_le_bytes());
    b
}

/// Appends records to a field log.
pub struct Writer<W: Write> {
    out: W,
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
        Ok(Self { out })
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
        self.out.write_all(&record_bytes(direction, t_us, bytes))
    }

    /// Flushes the underlying writer.
    pub fn flush(&mut self) -> std::io::Result<()> {
        self.out.flush()
    }

    /// Gives the writer back.
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
    if version != FORMAT_VERSION {
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
    let mut at = end + 4;
    let mut records = Vec::new();
    let mut damage = None;
    while at < b.len() {
        let fail = |reason| Damage {
            offset: at as u64,
            reason,
            unread_bytes: (b.len() - at) as u64,
        };
        let Some(&dir) = b.get(at) else { break };
        let (Some(t_us), Some(len)) = (u64_at(b, at + 1), u32_at(b, at + 9)) else {
            damage = Some(fail(DamageReason::Truncated));
            break;
        };
        let len = len as usize;
        if len > MAX_RECORD_LEN {
            damage = Some(fail(DamageReason::LengthTooLarge));
            break;
        }
        let body_end = at + 13 + len;
        let Some(stored) = u32_at(b, body_end) else {
            damage = Some(fail(DamageReason::Truncated));
            break;
        };
        if CRC.checksum(&b[at..body_end]) != stored {
            damage = Some(fail(DamageReason::BadChecksum));
            break;
        }
        let Some(direction) = Direction::from_u8(dir) else {
            damage = Some(fail(DamageReason::BadDirection));
            break;
        };
        records.push(Record {
            direction,
            t_us,
            bytes: b[at + 13..body_end].to_vec(),
            offset: at as u64,
        });
        at = body_end + 4;
    }
    Ok(FieldLog {
        header,
        records,
        damage,
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
}
