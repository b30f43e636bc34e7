//! Incremental deframer: accepts wire bytes in any split, yields decoded (un-stuffed) frames.
//!
//! Bytes are collected up to the `0x00` delimiter and then COBS-decoded. A frame longer than
//! `MAX_ENCODED_FRAME_LEN` is reported once as [`DeframeError::Oversize`] and everything up to the next delimiter
//! is discarded (resynchronisation). Empty frames (two delimiters in a row) are skipped silently, so a sender may
//! emit a lone `0x00` to flush a half-sent frame on the other side. [`Deframer::needs`] gives a lower bound on the
//! bytes still needed to finish the current frame (in the spirit of postcard's accumulator and F Prime's
//! `DeframingProtocol`).

use super::cobs::{self, CobsError};
use crate::config::protocol::{MAX_ENCODED_FRAME_LEN, MAX_FRAME_LEN, MIN_FRAME_LEN};

/// Stuffed bytes of one frame, without the delimiter.
const RAW_LEN: usize = MAX_ENCODED_FRAME_LEN - 1;
/// Smallest wire frame: a minimal frame needs one code byte and the delimiter on top.
const MIN_WIRE_LEN: usize = MIN_FRAME_LEN + 2;

/// Why bytes between two delimiters are not a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeframeError {
    /// Longer than the largest frame; the rest up to the next delimiter is discarded.
    Oversize,
    /// A COBS block runs past the delimiter: the frame was cut short.
    Truncated,
}

/// Incremental deframer with its own fixed buffers (about 4 KiB).
#[derive(Debug, Clone)]
pub struct Deframer {
    raw: [u8; RAW_LEN],
    len: usize,
    discarding: bool,
    block_remaining: usize,
    decoded: [u8; RAW_LEN],
    high_water: usize,
}

impl Default for Deframer {
    fn default() -> Self {
        Self::new()
    }
}

impl Deframer {
    /// An empty deframer.
    pub const fn new() -> Self {
        Self {
            raw: [0; RAW_LEN],
            len: 0,
            discarding: false,
            block_remaining: 0,
            decoded: [0; RAW_LEN],
            high_water: 0,
        }
    }

    /// Consumes bytes from `input` until one frame (or one error) is complete. Returns the number of bytes
    /// consumed and, if something completed, the decoded frame or the error. Call again with the rest of `input`.
    pub fn push(&mut self, input: &[u8]) -> (usize, Option<Result<&[u8], DeframeError>>) {
        for (i, &b) in input.iter().enumerate() {
            if b == 0 {
                let was_discarding = self.discarding;
                let len = self.len;
                self.len = 0;
                self.discarding = false;
                self.block_remaining = 0;
                if was_discarding || len == 0 {
                    continue;
                }
                let raw = self.raw.get(..len).unwrap_or(&[]);
                return match cobs::decode(raw, &mut self.decoded) {
                    Ok(n) if n > MAX_FRAME_LEN => (i + 1, Some(Err(DeframeError::Oversize))),
                    Ok(n) => {
                        self.high_water = self.high_water.max(n);
                        (i + 1, Some(Ok(self.decoded.get(..n).unwrap_or(&[]))))
                    }
                    Err(CobsError::Truncated | CobsError::ZeroByte) => {
                        (i + 1, Some(Err(DeframeError::Truncated)))
                    }
                    Err(CobsError::OutputFull) => (i + 1, Some(Err(DeframeError::Oversize))),
                };
            }
            if self.discarding {
                continue;
            }
            match self.raw.get_mut(self.len) {
                Some(slot) => {
                    *slot = b;
                    self.len += 1;
                    self.block_remaining = if self.block_remaining == 0 {
                        usize::from(b) - 1
                    } else {
                        self.block_remaining - 1
                    };
                }
                None => {
                    self.discarding = true;
                    self.len = 0;
                    self.block_remaining = 0;
                    return (i + 1, Some(Err(DeframeError::Oversize)));
                }
            }
        }
        (input.len(), None)
    }

    /// A lower bound on the bytes needed to complete the current frame (delimiter included): 1 while discarding.
    pub fn needs(&self) -> usize {
        if self.discarding {
            1
        } else {
            (self.block_remaining + 1).max(MIN_WIRE_LEN.saturating_sub(self.len))
        }
    }

    /// Bytes of the current, incomplete frame held.
    pub fn pending(&self) -> usize {
        self.len
    }

    /// True while discarding an oversize frame up to the next delimiter.
    pub fn is_discarding(&self) -> bool {
        self.discarding
    }

    /// Largest decoded frame seen, bytes.
    pub fn high_water(&self) -> usize {
        self.high_water
    }

    /// Drops any partial frame.
    pub fn reset(&mut self) {
        self.len = 0;
        self.discarding = false;
        self.block_remaining = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::{encode, Ack, Message};

    fn frames(
        d: &mut Deframer,
        mut input: &[u8],
    ) -> std::vec::Vec<Result<std::vec::Vec<u8>, DeframeError>> {
        let mut out = std::vec::Vec::new();
        while !input.is_empty() {
            let (n, ev) = d.push(input);
            if let Some(ev) = ev {
                out.push(ev.map(|f| f.to_vec()));
            }
            input = &input[n..];
        }
        out
    }

    #[test]
    fn any_split_gives_the_same_frames() {
        let mut wire = std::vec::Vec::new();
        for seq in 0..3 {
            let mut buf = [0u8; 64];
            let n = encode(seq, &Message::Ack(Ack { seq: 1000 + seq }), &mut buf).unwrap();
            wire.extend_from_slice(&buf[..n]);
        }
        let whole = frames(&mut Deframer::new(), &wire);
        assert_eq!(whole.len(), 3);
        for split in 0..wire.len() {
            let mut d = Deframer::new();
            let mut got = frames(&mut d, &wire[..split]);
            got.extend(frames(&mut d, &wire[split..]));
            assert_eq!(got, whole, "split at {split}");
        }
        // byte by byte, checking the needs() lower bound never overshoots
        let mut d = Deframer::new();
        let mut got = std::vec::Vec::new();
        let mut since_frame = 0usize;
        let mut bound = d.needs();
        for &b in &wire {
            since_frame += 1;
            let (_, ev) = d.push(&[b]);
            if let Some(ev) = ev {
                assert!(
                    since_frame >= bound,
                    "needs() promised at least {bound}, frame came after {since_frame}"
                );
                got.push(ev.map(|f| f.to_vec()));
                since_frame = 0;
                bound = d.needs();
            }
        }
        assert_eq!(got, whole);
    }

    #[test]
    fn oversize_resyncs_on_next_delimiter() {
        let mut wire = std::vec![0x55u8; MAX_ENCODED_FRAME_LEN + 100];
        wire.push(0);
        let mut buf = [0u8; 64];
        let n = encode(7, &Message::Ack(Ack { seq: 9 }), &mut buf).unwrap();
        wire.extend_from_slice(&buf[..n]);
        let got = frames(&mut Deframer::new(), &wire);
        assert_eq!(got.len(), 2);
        assert_eq!(got[0], Err(DeframeError::Oversize));
        assert!(got[1].is_ok());
    }
}
