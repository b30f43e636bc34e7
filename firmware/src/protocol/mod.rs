//! # Wire protocol between the simulator / ground station and the flight software (version 8)
//!
//! The byte-level specification, with limits and example bytes, is `firmware/PROTOCOL.md`; this module is its
//! implementation and the unit tests check the document's example bytes.
//!
//! - [`message`]: the message set v3 (serde types, postcard bodies; v2 added the closed-loop mission messages, v3 `Configure.map`) and
//!   their validation ([`Validate`]).
//! - [`frame`]: `header | body | CRC-32` frames, the [`Frame`] view with a checked constructor, [`encode`] and
//!   [`decode`] / [`decode_frame`].
//! - [`cobs`]: byte stuffing, so `0x00` delimits frames.
//! - [`deframer`]: the incremental [`Deframer`] (any byte split, resynchronises after garbage or oversize).
//! - [`team`]: the team mission's messages (v8: `TeamConfigure`, `TeamScanChunk`, `TeamReport`, `TeamCommand`).
//! - [`reassembly`]: the bounded [`ScanAssembler`] for chunked sensor scans and the [`TileAssembler`] for chunked
//!   terrain tiles (v7).
//!
//! Errors are narrow per layer ([`DeframeError`], [`FrameError`], [`DecodeError`], [`ChunkError`]) and each maps
//! to one [`NackReason`], the value the flight software reports back and counts.
//!
//! Limits (all in `config::protocol`): `MAX_FRAME_LEN` = 2048 decoded bytes, `MAX_POINTS_PER_CHUNK` = 128,
//! `MAX_CHUNKS_PER_SCAN` = 64, `SCAN_POINTS_CAPACITY` = 8192, `MAX_WAYPOINTS_PER_PLAN_FRAME` = 12,
//! `MAX_ANCHORS_PER_WAYPOINT` = 8, `MAX_LOG_TEXT` = 120.

pub mod cobs;
pub mod deframer;
pub mod frame;
pub mod message;
pub mod reassembly;
pub mod team;
pub mod values;

pub use deframer::{DeframeError, Deframer};
pub use frame::{
    build_raw, decode, decode_frame, encode, stuff, DecodeError, EncodeError, Frame, FrameError,
    Header, CRC,
};
pub use message::*;
pub use reassembly::{
    ChunkAccepted, ChunkError, CompleteScan, ScanAssembler, TileAccepted, TileAssembler, TileChunkError, TileHeader,
};

impl From<DeframeError> for NackReason {
    fn from(e: DeframeError) -> Self {
        match e {
            DeframeError::Oversize => NackReason::Oversize,
            DeframeError::Truncated => NackReason::Truncated,
        }
    }
}

#[cfg(test)]
mod tests;
