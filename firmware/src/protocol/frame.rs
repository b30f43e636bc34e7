//! Frames: `header | postcard body | CRC-32`, COBS-encoded and terminated by `0x00`.
//!
//! [`Frame`] is a view over a decoded (un-stuffed) frame in the style of smoltcp's `wire` module: a checked
//! constructor validates length and CRC once; after that no accessor can panic. [`Header`] is the representation
//! of the header. [`decode`] turns a checked frame into a validated [`Message`]; [`encode`] is the inverse and
//! produces wire bytes (COBS + delimiter).

use super::cobs;
use super::message::*;
use crate::config::protocol::{
    CRC_LEN, HEADER_LEN, MAX_BODY_LEN, MAX_FRAME_LEN, MIN_FRAME_LEN, PROTOCOL_VERSION,
};

/// The frame CRC: CRC-32/ISO-HDLC (poly 0x04C11DB7 reflected, init and xorout 0xFFFFFFFF; zlib's `crc32`).
pub const CRC: crc::Crc<u32> = crc::Crc::<u32>::new(&crc::CRC_32_ISO_HDLC);

/// Why a decoded byte string is not a frame (length and CRC only; see [`DecodeError`] for the contents).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// Shorter than header + CRC.
    Truncated,
    /// Longer than `MAX_FRAME_LEN`.
    Oversize,
    /// The CRC does not match.
    BadCrc,
}

impl From<FrameError> for NackReason {
    fn from(e: FrameError) -> Self {
        match e {
            FrameError::Truncated => NackReason::Truncated,
            FrameError::Oversize => NackReason::Oversize,
            FrameError::BadCrc => NackReason::BadCrc,
        }
    }
}

/// A view over one decoded frame.
#[derive(Debug, Clone)]
pub struct Frame<T: AsRef<[u8]>> {
    buffer: T,
}

impl<T: AsRef<[u8]>> Frame<T> {
    /// Wraps `buffer` without checking it; accessors return zeros / empty slices on a short buffer.
    pub const fn new_unchecked(buffer: T) -> Self {
        Self { buffer }
    }

    /// Wraps `buffer` after checking its length and CRC.
    pub fn new_checked(buffer: T) -> Result<Self, FrameError> {
        let f = Self::new_unchecked(buffer);
        f.check()?;
        Ok(f)
    }

    /// Checks length bounds and the CRC.
    pub fn check(&self) -> Result<(), FrameError> {
        let b = self.buffer.as_ref();
        if b.len() < MIN_FRAME_LEN {
            return Err(FrameError::Truncated);
        }
        if b.len() > MAX_FRAME_LEN {
            return Err(FrameError::Oversize);
        }
        let (covered, _) = b.split_at(b.len() - CRC_LEN);
        if CRC.checksum(covered) == self.crc() {
            Ok(())
        } else {
            Err(FrameError::BadCrc)
        }
    }

    fn byte(&self, i: usize) -> u8 {
        self.buffer.as_ref().get(i).copied().unwrap_or(0)
    }

    /// Protocol version byte.
    pub fn version(&self) -> u8 {
        self.byte(0)
    }

    /// Message kind byte.
    pub fn kind(&self) -> u8 {
        self.byte(1)
    }

    /// Sequence number.
    pub fn seq(&self) -> u32 {
        u32::from_le_bytes([self.byte(2), self.byte(3), self.byte(4), self.byte(5)])
    }

    /// The postcard body.
    pub fn body(&self) -> &[u8] {
        let b = self.buffer.as_ref();
        b.get(HEADER_LEN..b.len().saturating_sub(CRC_LEN))
            .unwrap_or(&[])
    }

    /// The CRC trailer as stored.
    pub fn crc(&self) -> u32 {
        let b = self.buffer.as_ref();
        let n = b.len();
        match b.get(n.saturating_sub(CRC_LEN)..) {
            Some(&[a, b2, c, d]) => u32::from_le_bytes([a, b2, c, d]),
            _ => 0,
        }
    }

    /// The header.
    pub fn header(&self) -> Header {
        Header {
            version: self.version(),
            kind: self.kind(),
            seq: self.seq(),
        }
    }

    /// Gives the buffer back.
    pub fn into_inner(self) -> T {
        self.buffer
    }
}

/// The frame header (representation).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Header {
    /// Protocol version (this build: `PROTOCOL_VERSION`).
    pub version: u8,
    /// Message kind byte.
    pub kind: u8,
    /// Sequence number (each side counts its own frames from 0, wrapping).
    pub seq: u32,
}

impl Header {
    /// Writes the header into the first `HEADER_LEN` bytes of `buf`.
    pub fn emit(&self, buf: &mut [u8]) -> Option<()> {
        let s = self.seq.to_le_bytes();
        buf.get_mut(..HEADER_LEN)?.copy_from_slice(&[
            self.version,
            self.kind,
            s[0],
            s[1],
            s[2],
            s[3],
        ]);
        Some(())
    }
}

/// Why a frame's header or body is not a valid message.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// Version byte is not `PROTOCOL_VERSION`.
    WrongVersion,
    /// Kind byte is not in the spec.
    UnknownKind,
    /// The body ended early.
    BodyTooShort,
    /// Bytes left over after the body.
    BodyTooLong,
    /// A length prefix exceeds its capacity.
    LengthOverLimit,
    /// Bad varint / enum tag / bool / UTF-8.
    MalformedBody,
    /// Validation failed.
    Invalid(Invalid),
}

impl From<DecodeError> for NackReason {
    fn from(e: DecodeError) -> Self {
        match e {
            DecodeError::WrongVersion => NackReason::WrongVersion,
            DecodeError::UnknownKind => NackReason::UnknownKind,
            DecodeError::BodyTooShort => NackReason::BodyTooShort,
            DecodeError::BodyTooLong => NackReason::BodyTooLong,
            DecodeError::LengthOverLimit => NackReason::LengthOverLimit,
            DecodeError::MalformedBody => NackReason::MalformedBody,
            DecodeError::Invalid(i) => i.into(),
        }
    }
}

fn body<'a, M: serde::Deserialize<'a>>(
    kind: MessageKind,
    bytes: &'a [u8],
) -> Result<M, DecodeError> {
    match postcard::take_from_bytes::<M>(bytes) {
        Ok((m, [])) => Ok(m),
        Ok((_, _rest)) => Err(DecodeError::BodyTooLong),
        Err(postcard::Error::DeserializeUnexpectedEnd) => Err(DecodeError::BodyTooShort),
        // serde reports both "sequence longer than its capacity" and "enum index out of range" as a custom error;
        // the layout probe tells them apart.
        Err(postcard::Error::SerdeDeCustom) if sequence_over_capacity(kind, bytes) => {
            Err(DecodeError::LengthOverLimit)
        }
        Err(_) => Err(DecodeError::MalformedBody),
    }
}

fn varint(b: &[u8], at: &mut usize) -> Option<usize> {
    let mut v: u32 = 0;
    for shift in [0u32, 7, 14, 21, 28] {
        let byte = *b.get(*at)?;
        *at += 1;
        v |= u32::from(byte & 0x7F).checked_shl(shift)?;
        if byte & 0x80 == 0 {
            return Some(v as usize);
        }
    }
    None
}

/// True when a sequence length prefix in `body` exceeds its capacity (walks the documented layout; only the
/// kinds with variable-length fields can say yes).
fn sequence_over_capacity(kind: MessageKind, b: &[u8]) -> bool {
    use crate::config::protocol::{
        MAX_ANCHORS_PER_WAYPOINT, MAX_HEIGHTS_PER_TILE_CHUNK, MAX_LOG_TEXT, MAX_POINTS_PER_CHUNK,
        MAX_WAYPOINTS_PER_PLAN_FRAME,
    };
    const POSE_LEN: usize = 28;
    let mut at = 0;
    let probe = |at: &mut usize| -> Option<bool> {
        match kind {
            MessageKind::SensorChunk => {
                varint(b, at)?;
                varint(b, at)?;
                varint(b, at)?;
                *at += POSE_LEN;
                Some(varint(b, at)? > MAX_POINTS_PER_CHUNK)
            }
            MessageKind::TileChunk => {
                // tile id, chunk index, chunk count; origin x, y and spacing (3 x f32); rows, cols
                varint(b, at)?;
                varint(b, at)?;
                varint(b, at)?;
                *at += 12;
                varint(b, at)?;
                varint(b, at)?;
                Some(varint(b, at)? > MAX_HEIGHTS_PER_TILE_CHUNK)
            }
            MessageKind::Log => {
                varint(b, at)?;
                Some(varint(b, at)? > MAX_LOG_TEXT)
            }
            MessageKind::TeamScanChunk => {
                // command id, robot (u8), chunk index, chunk count; grip, up, hub (3 x 12 bytes)
                varint(b, at)?;
                *at += 1;
                varint(b, at)?;
                varint(b, at)?;
                *at += 36;
                Some(varint(b, at)? > MAX_POINTS_PER_CHUNK)
            }
            MessageKind::Plan => {
                varint(b, at)?;
                varint(b, at)?;
                varint(b, at)?;
                let n = varint(b, at)?;
                if n > MAX_WAYPOINTS_PER_PLAN_FRAME {
                    return Some(true);
                }
                for _ in 0..n {
                    *at += POSE_LEN;
                    let anchors = varint(b, at)?;
                    if anchors > MAX_ANCHORS_PER_WAYPOINT {
                        return Some(true);
                    }
                    *at += 12 * anchors + 4;
                }
                Some(false)
            }
            _ => Some(false),
        }
    };
    probe(&mut at).unwrap_or(false)
}

/// Decodes and validates the message in a checked frame.
pub fn decode<T: AsRef<[u8]>>(frame: &Frame<T>) -> Result<(Header, Message), DecodeError> {
    let h = frame.header();
    if h.version != PROTOCOL_VERSION {
        return Err(DecodeError::WrongVersion);
    }
    let kind = MessageKind::from_u8(h.kind).ok_or(DecodeError::UnknownKind)?;
    let b = frame.body();
    let m = match kind {
        MessageKind::TimeTick => Message::TimeTick(body(kind, b)?),
        MessageKind::SensorChunk => Message::SensorChunk(body(kind, b)?),
        MessageKind::TetherReading => Message::TetherReading(body(kind, b)?),
        MessageKind::GoalRequest => Message::GoalRequest(body(kind, b)?),
        MessageKind::Configure => Message::Configure(body(kind, b)?),
        MessageKind::Shutdown => Message::Shutdown(body(kind, b)?),
        MessageKind::TelemetryRequest => Message::TelemetryRequest(body(kind, b)?),
        MessageKind::MotionReport => Message::MotionReport(body(kind, b)?),
        MessageKind::GoalCancel => Message::GoalCancel(body(kind, b)?),
        MessageKind::TileChunk => Message::TileChunk(body(kind, b)?),
        MessageKind::Ack => Message::Ack(body(kind, b)?),
        MessageKind::Nack => Message::Nack(body(kind, b)?),
        MessageKind::PlanStatus => Message::PlanStatus(body(kind, b)?),
        MessageKind::Plan => Message::Plan(body(kind, b)?),
        MessageKind::DriveCommand => Message::DriveCommand(body(kind, b)?),
        MessageKind::Telemetry => Message::Telemetry(body(kind, b)?),
        MessageKind::Log => Message::Log(body(kind, b)?),
        MessageKind::MissionStatus => Message::MissionStatus(body(kind, b)?),
        MessageKind::TeamConfigure => Message::TeamConfigure(body(kind, b)?),
        MessageKind::TeamScanChunk => Message::TeamScanChunk(body(kind, b)?),
        MessageKind::TeamReport => Message::TeamReport(body(kind, b)?),
        MessageKind::TeamCommand => Message::TeamCommand(body(kind, b)?),
    };
    m.validate().map_err(DecodeError::Invalid)?;
    Ok((h, m))
}

/// Checks and decodes one decoded (un-stuffed) frame, mapping every failure to its [`NackReason`].
pub fn decode_frame(bytes: &[u8]) -> Result<(Header, Message), NackReason> {
    let f = Frame::new_checked(bytes)?;
    Ok(decode(&f)?)
}

/// Why a message could not be encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum EncodeError {
    /// The body does not fit `MAX_BODY_LEN` (cannot happen for messages within their `heapless` capacities).
    BodyTooLarge,
    /// The output buffer is smaller than the encoded frame.
    OutputTooSmall,
}

/// Builds the decoded frame `header | body | CRC` into `frame`; returns its length.
pub fn build_raw(header: Header, body: &[u8], frame: &mut [u8]) -> Result<usize, EncodeError> {
    let n = HEADER_LEN + body.len() + CRC_LEN;
    let f = frame.get_mut(..n).ok_or(EncodeError::OutputTooSmall)?;
    header.emit(f).ok_or(EncodeError::OutputTooSmall)?;
    f.get_mut(HEADER_LEN..HEADER_LEN + body.len())
        .ok_or(EncodeError::OutputTooSmall)?
        .copy_from_slice(body);
    let crc = CRC.checksum(f.get(..n - CRC_LEN).unwrap_or(&[]));
    f.get_mut(n - CRC_LEN..)
        .ok_or(EncodeError::OutputTooSmall)?
        .copy_from_slice(&crc.to_le_bytes());
    Ok(n)
}

/// COBS-encodes a decoded frame and appends the `0x00` delimiter; returns the wire length.
pub fn stuff(frame: &[u8], out: &mut [u8]) -> Result<usize, EncodeError> {
    let n = cobs::encode(frame, out).ok_or(EncodeError::OutputTooSmall)?;
    *out.get_mut(n).ok_or(EncodeError::OutputTooSmall)? = 0;
    Ok(n + 1)
}

/// Encodes `msg` with sequence number `seq` into wire bytes (COBS + delimiter) in `out`; returns the length.
/// Deterministic: the same message and sequence number always give the same bytes.
pub fn encode(seq: u32, msg: &Message, out: &mut [u8]) -> Result<usize, EncodeError> {
    let mut body_buf = [0u8; MAX_BODY_LEN];
    let len = msg
        .encode_body(&mut body_buf)
        .map_err(|_| EncodeError::BodyTooLarge)?;
    let b = body_buf.get(..len).ok_or(EncodeError::BodyTooLarge)?;
    let header = Header {
        version: PROTOCOL_VERSION,
        kind: msg.kind() as u8,
        seq,
    };
    let mut frame = [0u8; MAX_FRAME_LEN];
    let n = build_raw(header, b, &mut frame)?;
    stuff(frame.get(..n).unwrap_or(&[]), out)
}
