//! The host side of a conversation with the flight software: numbers and encodes outgoing messages, deframes and
//! decodes replies. Works over any [`FlightLink`].

use firmware::protocol::{
    self, Deframer, Header, Message, NackReason, Telemetry, TelemetryRequest,
};

use crate::link::{FlightLink, LinkError};

/// Link time a session waits for replies, microseconds.
pub const DEFAULT_REPLY_WAIT_US: u64 = 200_000;

/// A frame received from the flight software.
#[derive(Debug, Clone, PartialEq)]
pub struct Received {
    /// Link time when it was collected, microseconds.
    pub t_us: u64,
    /// Its header.
    pub header: Header,
    /// The message.
    pub message: Message,
}

/// Why a session operation failed.
#[derive(Debug)]
pub enum SessionError {
    /// The link failed.
    Link(LinkError),
    /// The flight software sent bytes that do not decode (should never happen on a clean link).
    BadReply(NackReason),
    /// A message could not be encoded (over its limits).
    Encode(protocol::EncodeError),
    /// An expected reply did not come.
    NoReply(&'static str),
}

impl core::fmt::Display for SessionError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            SessionError::Link(e) => write!(f, "{e}"),
            SessionError::BadReply(r) => {
                write!(f, "flight software sent an undecodable frame ({r:?})")
            }
            SessionError::Encode(e) => write!(f, "cannot encode message: {e:?}"),
            SessionError::NoReply(what) => write!(f, "no {what} from the flight software"),
        }
    }
}

impl core::error::Error for SessionError {}

impl From<LinkError> for SessionError {
    fn from(e: LinkError) -> Self {
        SessionError::Link(e)
    }
}

/// Host side of the protocol over a link.
pub struct HostSession<L: FlightLink> {
    link: L,
    seq: u32,
    deframer: Deframer,
    /// Every frame received so far, in order.
    pub log: Vec<Received>,
    /// Wait for replies, microseconds of link time.
    pub reply_wait_us: u64,
}

impl<L: FlightLink> HostSession<L> {
    /// A session starting at sequence number 0.
    pub fn new(link: L) -> Self {
        Self::starting_at(link, 0)
    }

    /// A session whose first frame carries `first_seq` (the soak starts near 2^32 so the count wraps).
    pub fn starting_at(link: L, first_seq: u32) -> Self {
        Self {
            link,
            seq: first_seq,
            deframer: Deframer::new(),
            log: Vec::new(),
            reply_wait_us: DEFAULT_REPLY_WAIT_US,
        }
    }

    /// The link.
    pub fn link(&self) -> &L {
        &self.link
    }

    /// The link, mutably.
    pub fn link_mut(&mut self) -> &mut L {
        &mut self.link
    }

    /// Gives the link back.
    pub fn into_link(self) -> L {
        self.link
    }

    /// The sequence number the next frame will carry.
    pub fn next_seq(&self) -> u32 {
        self.seq
    }

    /// Takes a sequence number for a hand-built frame.
    pub fn take_seq(&mut self) -> u32 {
        let s = self.seq;
        self.seq = self.seq.wrapping_add(1);
        s
    }

    /// Encodes and sends `msg`; returns its sequence number.
    pub fn send(&mut self, msg: &Message) -> Result<u32, SessionError> {
        let seq = self.take_seq();
        let mut buf = vec![0u8; firmware::config::protocol::MAX_ENCODED_FRAME_LEN];
        let n = protocol::encode(seq, msg, &mut buf).map_err(SessionError::Encode)?;
        self.link.send(&buf[..n])?;
        Ok(seq)
    }

    /// Sends raw wire bytes (for bad-input tests).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<(), SessionError> {
        Ok(self.link.send(bytes)?)
    }

    fn absorb(&mut self, bytes: &[u8]) -> Result<Vec<Message>, SessionError> {
        let t_us = self.link.now_us();
        let mut out = Vec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let (n, ev) = self.deframer.push(rest);
            rest = rest.get(n..).unwrap_or(&[]);
            let Some(ev) = ev else { continue };
            let frame = ev.map_err(|e| SessionError::BadReply(e.into()))?;
            let (header, message) =
                protocol::decode_frame(frame).map_err(SessionError::BadReply)?;
            self.log.push(Received {
                t_us,
                header,
                message: message.clone(),
            });
            out.push(message);
        }
        Ok(out)
    }

    /// Collects replies until the flight software is quiet.
    pub fn recv(&mut self) -> Result<Vec<Message>, SessionError> {
        let bytes = self.link.recv_until_quiet(self.reply_wait_us)?;
        self.absorb(&bytes)
    }

    /// Lets link time run to `t_us`, collecting what arrives.
    pub fn advance_to(&mut self, t_us: u64) -> Result<Vec<Message>, SessionError> {
        let bytes = self.link.advance_to(t_us)?;
        self.absorb(&bytes)
    }

    /// Sends `msg` and collects the replies.
    pub fn exchange(&mut self, msg: &Message) -> Result<Vec<Message>, SessionError> {
        self.send(msg)?;
        self.recv()
    }

    /// Requests telemetry and returns the `Telemetry` that answers the request (the first one after its `Ack`).
    pub fn telemetry(&mut self) -> Result<Telemetry, SessionError> {
        let seq = self.next_seq();
        let replies = self.exchange(&Message::TelemetryRequest(TelemetryRequest))?;
        let acked = replies
            .iter()
            .position(|m| *m == Message::Ack(firmware::protocol::Ack { seq }))
            .ok_or(SessionError::NoReply("ack of the telemetry request"))?;
        replies[acked..]
            .iter()
            .find_map(|m| {
                if let Message::Telemetry(t) = m {
                    Some(*t)
                } else {
                    None
                }
            })
            .ok_or(SessionError::NoReply("telemetry"))
    }
}
