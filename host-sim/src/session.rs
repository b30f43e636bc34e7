//! The host side of a conversation with the flight software: numbers and encodes outgoing messages, deframes and
//! decodes replies. Works over any [`FlightLink`].
//!
//! **Retransmission** ([`RetransmitPolicy`], on with [`HostSession::retransmit`]): every host frame gets exactly one
//! `Ack` or `Nack` (`firmware/PROTOCOL.md` section 5). A frame that changes the flight state and has no answer
//! after `after_us` of link time is sent again with a new sequence number (at most `max_tries` times), so a frame
//! lost or damaged on the way up is not lost to the mission. A `Nack` for damage (`Truncated`, `Oversize`,
//! `BadCrc`) answers nothing (its sequence number was read from a damaged header); any other `Nack` is an answer.
//! Periodic and idempotent messages (`TimeTick`, `TetherReading`, `TelemetryRequest`) are not retransmitted: the
//! next one replaces them. Scan chunks are retransmitted per scan, not per frame ([`HostSession::send_scan`]): one lost
//! chunk would lose its scan; the flight software takes a scan's chunks in any order, so the chunks without an
//! answer are sent again alone once the others are answered.
//!
//! **A resend is never executed twice** (protocol v5): when the downlink loses the `Ack`, a resend reaches a flight
//! software that already acted on the first copy; the flight software answers it `Ack` without acting again (its
//! last accepted request of each kind, `firmware/src/exec`). Any transmission's answer answers the message: the
//! session keeps every sequence number a message was sent under. A `GoalRequest` supersedes older unanswered goals
//! (they are not sent again: an old goal must never replace a newer one).
//!
//! **The downlink** ([`DownlinkCounts`], [`HostSession::downlink`]): a frame that fails its COBS structure, CRC or
//! decoding is counted (`damaged`) and skipped, never acted on; the flight software's sequence numbers give frames
//! lost (`gaps`), late (`late`) and duplicated (`duplicates`: the same sequence number and CRC as one of the last
//! `SEQ_HISTORY_LEN` intact frames; dropped, so a copy made by the link is never acted on twice), with the same
//! rules and windows as the flight side's counters on the uplink (`firmware/src/exec`). After a reset of the flight
//! computer the mission calls [`HostSession::flight_rebooted`] (its numbering starts again from 0).

use std::collections::VecDeque;

use firmware::config::exec::{SEQ_HISTORY_LEN, SEQ_WINDOW};
use firmware::protocol::{
    self, Deframer, Frame, Header, Message, NackReason, SensorChunk, Telemetry, TelemetryRequest,
};

use crate::link::{FlightLink, LinkError};

/// Link time a session waits for replies, microseconds.
pub const DEFAULT_REPLY_WAIT_US: u64 = 200_000;

/// When a session sends a frame again.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RetransmitPolicy {
    /// Link time without an answer after which a frame is sent again, microseconds (default 1 s: far above a
    /// clean link's answer time of a few executive steps, and above the fault injector's delays and stalls).
    pub after_us: u64,
    /// Sends of one message at most (default 8), after which it is given up (counted).
    pub max_tries: u32,
}

impl Default for RetransmitPolicy {
    fn default() -> Self {
        Self {
            after_us: 1_000_000,
            max_tries: 8,
        }
    }
}

/// What the host saw of the downlink (flight -> host) frames: its own detection of downlink faults.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize)]
pub struct DownlinkCounts {
    /// Intact frames read (duplicates included).
    pub frames: u64,
    /// Frames that failed their COBS structure, CRC or decoding (skipped).
    pub damaged: u64,
    /// Flight sequence numbers skipped (frames lost or damaged on the way, or late ones not yet arrived).
    pub gaps: u64,
    /// Frames behind the expected sequence number (reordered or delayed; still read).
    pub late: u64,
    /// Copies of one of the last intact frames (dropped).
    pub duplicates: u64,
    /// Jumps beyond the window: a new flight session.
    pub resyncs: u64,
}

/// A sent message waiting for its answer.
#[derive(Debug, Clone)]
struct Pending {
    /// Every sequence number it was sent under, the latest last.
    seqs: Vec<u32>,
    msg: Message,
    sent_us: u64,
    tries: u32,
}

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
    /// Retransmission of unanswered frames (`None`: off).
    pub retransmit: Option<RetransmitPolicy>,
    pending: Vec<Pending>,
    /// Frames sent again.
    pub retransmitted: u64,
    /// Messages given up after `max_tries` sends.
    pub given_up: u64,
    /// Scan chunks sent again ([`Self::send_scan`]).
    pub chunks_resent: u64,
    /// Kinds of the messages given up, in order.
    pub given_up_kinds: Vec<protocol::MessageKind>,
    /// The host's detection on the downlink.
    pub downlink: DownlinkCounts,
    /// Expected next flight sequence number.
    down_next: u32,
    /// An intact flight frame has been read since the flight software (re)booted.
    down_seen: bool,
    /// (sequence number, CRC) of the last intact flight frames.
    down_history: VecDeque<(u32, u32)>,
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
            retransmit: None,
            pending: Vec::new(),
            retransmitted: 0,
            given_up: 0,
            chunks_resent: 0,
            given_up_kinds: Vec::new(),
            downlink: DownlinkCounts::default(),
            down_next: 0,
            down_seen: false,
            down_history: VecDeque::new(),
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
        if matches!(msg, Message::GoalRequest(_)) {
            // a newer goal supersedes an unanswered older one: never send the old one again (module docs)
            self.pending.retain(|p| !matches!(p.msg, Message::GoalRequest(_)));
        }
        self.send_try(msg, 1, Vec::new())
    }

    /// The flight software rebooted: its frame numbering starts again (the downlink counters go on).
    pub fn flight_rebooted(&mut self) {
        self.down_next = 0;
        self.down_seen = false;
        self.down_history.clear();
    }

    fn send_try(&mut self, msg: &Message, tries: u32, mut seqs: Vec<u32>) -> Result<u32, SessionError> {
        let seq = self.take_seq();
        let mut buf = vec![0u8; firmware::config::protocol::MAX_ENCODED_FRAME_LEN];
        let n = protocol::encode(seq, msg, &mut buf).map_err(SessionError::Encode)?;
        // Scan chunks are resent per scan by `send_scan` (module docs).
        let periodic = matches!(
            msg,
            Message::TimeTick(_)
                | Message::TetherReading(_)
                | Message::TelemetryRequest(_)
                | Message::SensorChunk(_)
        );
        if self.retransmit.is_some() && !periodic {
            seqs.push(seq);
            self.pending.push(Pending {
                seqs,
                msg: msg.clone(),
                sent_us: self.link.now_us(),
                tries,
            });
        }
        self.link.send(&buf[..n])?;
        Ok(seq)
    }

    /// Sends again every frame unanswered for the policy's time (module docs).
    fn retransmit_due(&mut self) -> Result<(), SessionError> {
        let Some(policy) = self.retransmit else {
            return Ok(());
        };
        let now = self.link.now_us();
        let (due, rest): (Vec<Pending>, Vec<Pending>) = core::mem::take(&mut self.pending)
            .into_iter()
            .partition(|p| now.saturating_sub(p.sent_us) >= policy.after_us);
        self.pending = rest;
        for p in due {
            if p.tries >= policy.max_tries {
                self.given_up += 1;
                self.given_up_kinds.push(p.msg.kind());
                log::warn!(
                    "message given up after {} sends: {:?}",
                    p.tries,
                    p.msg.kind()
                );
                continue;
            }
            self.retransmitted += 1;
            self.send_try(&p.msg, p.tries + 1, p.seqs)?;
        }
        Ok(())
    }

    /// Frames sent and not answered yet (retransmission on).
    pub fn unanswered(&self) -> usize {
        self.pending.len()
    }

    /// Sends raw wire bytes (for bad-input tests).
    pub fn send_raw(&mut self, bytes: &[u8]) -> Result<(), SessionError> {
        Ok(self.link.send(bytes)?)
    }

    /// Checks an intact flight frame's sequence number (module docs); false for a duplicate (not to be read).
    fn track_down(&mut self, seq: u32, crc: u32) -> bool {
        if self.down_history.contains(&(seq, crc)) {
            self.downlink.duplicates += 1;
            log::debug!("downlink frame seq {seq} duplicated: dropped");
            return false;
        }
        if self.down_history.len() >= SEQ_HISTORY_LEN {
            self.down_history.pop_front();
        }
        self.down_history.push_back((seq, crc));
        self.downlink.frames += 1;
        let ahead = seq.wrapping_sub(self.down_next);
        let behind = self.down_next.wrapping_sub(seq);
        if ahead <= SEQ_WINDOW || (self.down_seen && ahead < u32::MAX / 2) {
            self.downlink.gaps += u64::from(ahead);
            self.down_next = seq.wrapping_add(1);
        } else if self.down_seen && behind <= SEQ_WINDOW {
            self.downlink.late += 1;
        } else {
            self.downlink.resyncs += 1;
            self.down_next = seq.wrapping_add(1);
        }
        self.down_seen = true;
        true
    }

    fn absorb(&mut self, bytes: &[u8]) -> Result<Vec<Message>, SessionError> {
        let t_us = self.link.now_us();
        let mut out = Vec::new();
        let mut rest = bytes;
        while !rest.is_empty() {
            let (n, ev) = self.deframer.push(rest);
            rest = rest.get(n..).unwrap_or(&[]);
            let Some(ev) = ev else { continue };
            // A damaged frame is counted and skipped: nothing in it can be trusted (module docs).
            let decoded = ev.map_err(NackReason::from).and_then(|frame| {
                let f = Frame::new_unchecked(frame);
                f.check().map_err(NackReason::from)?;
                let (header, message) = protocol::decode_frame(frame)?;
                Ok((header, message, f.crc()))
            });
            let (header, message, crc) = match decoded {
                Ok(d) => d,
                Err(reason) => {
                    self.downlink.damaged += 1;
                    log::debug!("damaged downlink frame skipped ({reason:?})");
                    continue;
                }
            };
            if !self.track_down(header.seq, crc) {
                continue;
            }
            match &message {
                Message::Ack(a) => self.pending.retain(|p| !p.seqs.contains(&a.seq)),
                Message::Nack(n)
                    if !matches!(
                        n.reason,
                        NackReason::Truncated | NackReason::Oversize | NackReason::BadCrc
                    ) =>
                {
                    self.pending.retain(|p| !p.seqs.contains(&n.seq))
                }
                _ => {}
            }
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
        let out = self.absorb(&bytes)?;
        self.retransmit_due()?;
        Ok(out)
    }

    /// Lets link time run to `t_us`, collecting what arrives.
    pub fn advance_to(&mut self, t_us: u64) -> Result<Vec<Message>, SessionError> {
        let bytes = self.link.advance_to(t_us)?;
        let out = self.absorb(&bytes)?;
        self.retransmit_due()?;
        Ok(out)
    }

    /// Sends one scan's chunks and collects the replies. With retransmission on, it waits until every chunk is
    /// answered or the policy's time has passed, then sends again, alone, each chunk that had no answer (the flight
    /// software takes a scan's chunks in any order), at most `max_tries` rounds; then the scan is given up (counted
    /// in `given_up`). A chunk refused for good (`Nack` other than `DuplicateChunk`, which means it arrived before)
    /// ends the scan at once. Returns the replies and whether every chunk arrived.
    pub fn send_scan(
        &mut self,
        chunks: &[SensorChunk],
    ) -> Result<(Vec<Message>, bool), SessionError> {
        let mut replies = Vec::new();
        let rounds = self.retransmit.map_or(1, |p| p.max_tries.max(1));
        let mut todo: Vec<&SensorChunk> = chunks.iter().collect();
        for round in 0..rounds {
            if round > 0 {
                self.chunks_resent += todo.len() as u64;
                log::info!(
                    "scan {}: {} chunk(s) sent again (no answer)",
                    todo[0].scan_id,
                    todo.len()
                );
            }
            let mut seqs = Vec::with_capacity(todo.len());
            for c in &todo {
                seqs.push(self.send(&Message::SensorChunk((*c).clone()))?);
            }
            let sent_us = self.link.now_us();
            // Per chunk: no answer yet, arrived, refused for good.
            let mut answer: Vec<Option<bool>> = vec![None; seqs.len()];
            loop {
                let got = self.recv()?;
                for m in &got {
                    let (seq, arrived) = match m {
                        Message::Ack(a) => (a.seq, true),
                        Message::Nack(n) if n.reason == NackReason::DuplicateChunk => (n.seq, true),
                        // A copy made by the link: the frame itself was answered on its own.
                        Message::Nack(n) if n.reason == NackReason::DuplicateFrame => continue,
                        Message::Nack(n)
                            if !matches!(
                                n.reason,
                                NackReason::Truncated | NackReason::Oversize | NackReason::BadCrc
                            ) =>
                        {
                            (n.seq, false)
                        }
                        _ => continue,
                    };
                    if let Some(a) = seqs.iter().position(|&s| s == seq).and_then(|i| answer.get_mut(i)) {
                        *a = Some(arrived || *a == Some(true));
                    }
                }
                replies.extend(got);
                let waited = self.link.now_us().saturating_sub(sent_us);
                match self.retransmit {
                    Some(p) if answer.contains(&None) && waited < p.after_us => continue,
                    _ => break,
                }
            }
            if answer.contains(&Some(false)) {
                return Ok((replies, false));
            }
            todo = todo
                .into_iter()
                .zip(&answer)
                .filter(|(_, a)| a.is_none())
                .map(|(c, _)| c)
                .collect();
            if todo.is_empty() {
                return Ok((replies, true));
            }
            if self.retransmit.is_none() {
                return Ok((replies, false));
            }
        }
        self.given_up += 1;
        log::warn!("scan {} given up after {rounds} rounds: {} chunk(s) unanswered", chunks[0].scan_id, todo.len());
        Ok((replies, false))
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
