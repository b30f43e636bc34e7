//! Capacities and limits of the wire protocol (`crate::protocol`). See `firmware/PROTOCOL.md` for the byte layout.
//!
//! | const | default | reason |
//! |---|---|---|
//! | [`PROTOCOL_VERSION`] | 7 | first byte of every frame; a receiver rejects any other value (v2: the closed-loop mission messages; v3: `Configure.map`; v4: sequence and cycle accounting in `Telemetry`, `Nack(DuplicateFrame)`; v5: resent requests answered without acting again, drive commands resent; v6: a `Stop` names the motion it stops and is resent; v7: `TileChunk`, the terrain-tile upload, its `Nack` reasons and `MapStatus` tile counters; v8: the team mission, `TeamConfigure`, `TeamScanChunk`, `TeamReport`, `TeamCommand`, `Nack` reasons `UnknownRobot` and `NoTeam`) |
//! | [`HEADER_LEN`] | 6 | version u8, kind u8, sequence u32 little-endian |
//! | [`CRC_LEN`] | 4 | CRC-32 (ISO-HDLC, the Ethernet/zlib CRC) over header and body, little-endian |
//! | [`MAX_FRAME_LEN`] | 2048 | largest decoded frame (header + body + CRC): a full sensor chunk plus margin; small enough for a UART DMA buffer |
//! | [`MAX_BODY_LEN`] | 2038 | `MAX_FRAME_LEN - HEADER_LEN - CRC_LEN` |
//! | [`MAX_ENCODED_FRAME_LEN`] | 2058 | COBS adds at most one byte per 254 plus one; plus the `0x00` delimiter |
//! | [`MAX_POINTS_PER_CHUNK`] | 128 | 128 x 12 bytes = 1536 bytes of points per frame, with room for the pose and header |
//! | [`MAX_CHUNKS_PER_SCAN`] | 64 | a scan of up to 8192 points; bounds the reassembly bookkeeping |
//! | [`SCAN_POINTS_CAPACITY`] | 8192 | reassembly buffer (points), lent by the caller: 96 KiB |
//! | [`MAX_HEIGHTS_PER_TILE_CHUNK`] | 256 | 256 x 4 bytes = 1024 bytes of heights per `TileChunk` frame, with room for the header fields |
//! | [`MAX_CHUNKS_PER_TILE`] | 64 | `MAX_TILE_CELLS` (128 x 128 posts, `config::homotopy`) / 256: a full tile; bounds the tile bookkeeping |
//! | [`MAX_CHUNKS_PER_TEAM_SCAN`] | 32 | chunks of one robot's scan (v8): 32 x 128 = 4096 points, the local planner's `SCENE_MAX_POINTS` |
//! | [`TEAM_SCAN_POINTS_CAPACITY`] | 4096 | team scan reassembly (points), in the team storage the board lends: 48 KiB |
//! | [`MAX_TEAM_BLOCKED_CELLS`] | 32 | scenes blocked beforehand in one `TeamConfigure` (v8); keeps the frame under 512 bytes |
//! | [`MAX_ANCHORS_PER_WAYPOINT`] | 8 | anchor history carried with each plan waypoint (Paton et al. IV-B: a bounded stack) |
//! | [`MAX_WAYPOINTS_PER_PLAN_FRAME`] | 12 | waypoints per `Plan` frame (12 x 129 bytes at most fits a frame); longer plans go in parts |
//! | [`MAX_LOG_TEXT`] | 120 | bytes of text in one forwarded `Log` record; longer text is cut |
//! | [`QUATERNION_NORM_TOLERANCE`] | 1e-3 | a pose's quaternion must have norm within this of 1 |
//! | [`MIN_TELEMETRY_PERIOD_MS`] | 100 | telemetry rate limit: a `Configure` asking for periodic telemetry faster than 10 Hz is rejected |

/// The protocol version this build speaks (first byte of every frame).
pub const PROTOCOL_VERSION: u8 = 8;
/// Header length in bytes: version (u8), kind (u8), sequence number (u32 LE).
pub const HEADER_LEN: usize = 6;
/// Trailer length in bytes: CRC-32 (ISO-HDLC) little-endian.
pub const CRC_LEN: usize = 4;
/// Largest decoded frame, header + body + CRC, in bytes.
pub const MAX_FRAME_LEN: usize = 2048;
/// Smallest decoded frame (empty body).
pub const MIN_FRAME_LEN: usize = HEADER_LEN + CRC_LEN;
/// Largest postcard body in bytes.
pub const MAX_BODY_LEN: usize = MAX_FRAME_LEN - HEADER_LEN - CRC_LEN;
/// Largest frame on the wire: COBS overhead (one byte per 254, plus one) and the `0x00` delimiter.
pub const MAX_ENCODED_FRAME_LEN: usize = MAX_FRAME_LEN + MAX_FRAME_LEN / 254 + 2;
/// Most points in one `SensorChunk`.
pub const MAX_POINTS_PER_CHUNK: usize = 128;
/// Most chunks in one scan (`chunk_count` above this is rejected).
pub const MAX_CHUNKS_PER_SCAN: u16 = 64;
/// Points the scan reassembly buffer holds (lent by the caller).
pub const SCAN_POINTS_CAPACITY: usize = MAX_POINTS_PER_CHUNK * MAX_CHUNKS_PER_SCAN as usize;
/// Most heights in one `TileChunk` (v7).
pub const MAX_HEIGHTS_PER_TILE_CHUNK: usize = 256;
/// Most chunks in one terrain tile (v7): a full tile of `MAX_TILE_CELLS` posts.
pub const MAX_CHUNKS_PER_TILE: u16 = (crate::config::homotopy::MAX_TILE_CELLS / MAX_HEIGHTS_PER_TILE_CHUNK) as u16;
/// Most chunks in one team scan (v8): `SCENE_MAX_POINTS` points.
pub const MAX_CHUNKS_PER_TEAM_SCAN: u16 = (crate::config::team::SCENE_MAX_POINTS / MAX_POINTS_PER_CHUNK) as u16;
/// Points the team scan reassembly holds (v8).
pub const TEAM_SCAN_POINTS_CAPACITY: usize = MAX_POINTS_PER_CHUNK * MAX_CHUNKS_PER_TEAM_SCAN as usize;
/// Scenes blocked beforehand in one `TeamConfigure` (v8).
pub const MAX_TEAM_BLOCKED_CELLS: usize = 32;
/// Anchor points carried with each plan waypoint.
pub const MAX_ANCHORS_PER_WAYPOINT: usize = 8;
/// Waypoints in one `Plan` frame.
pub const MAX_WAYPOINTS_PER_PLAN_FRAME: usize = 12;
/// Bytes of text in one `Log` record.
pub const MAX_LOG_TEXT: usize = 120;
/// Allowed deviation of a pose quaternion's norm from 1.
pub const QUATERNION_NORM_TOLERANCE: f32 = 1e-3;

/// Shortest period of unsolicited telemetry a `Configure` may ask for (0 = only on request is always allowed).
pub const MIN_TELEMETRY_PERIOD_MS: u32 = 100;

const _: () = assert!(MAX_FRAME_LEN > MIN_FRAME_LEN);
// A full sensor chunk (pose 28 bytes, ids <= 13 bytes, points 12 each, length prefix <= 2) must fit one body.
const _: () = assert!(MAX_POINTS_PER_CHUNK * 12 + 28 + 13 + 2 <= MAX_BODY_LEN);
// A full plan frame: per waypoint pose 28 + anchors (1 + 12 each) + margin 4.
const _: () = assert!(
    MAX_WAYPOINTS_PER_PLAN_FRAME * (28 + 1 + 12 * MAX_ANCHORS_PER_WAYPOINT + 4) + 16
        <= MAX_BODY_LEN
);
// A full tile chunk (ids and counts <= 17 bytes, origin and spacing 12, rows and cols <= 6, heights 4 each, length
// prefix <= 3) must fit one body; a full tile needs exactly `MAX_CHUNKS_PER_TILE` chunks.
const _: () = assert!(MAX_HEIGHTS_PER_TILE_CHUNK * 4 + 17 + 12 + 6 + 3 <= MAX_BODY_LEN);
const _: () = assert!(MAX_CHUNKS_PER_TILE as usize * MAX_HEIGHTS_PER_TILE_CHUNK == crate::config::homotopy::MAX_TILE_CELLS);
const _: () = assert!(MAX_CHUNKS_PER_TILE as u32 <= u64::BITS);
// A full team scan chunk (ids and counts <= 16 bytes, grip, up and hub 36, points 12 each, length prefix <= 2).
const _: () = assert!(MAX_POINTS_PER_CHUNK * 12 + 16 + 36 + 2 <= MAX_BODY_LEN);
const _: () = assert!(TEAM_SCAN_POINTS_CAPACITY == crate::config::team::SCENE_MAX_POINTS);
