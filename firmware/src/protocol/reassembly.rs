//! Bounded reassembly of chunked sensor scans.
//!
//! Chunks of one scan may arrive in any order, each at most once (selective repeat: a lost chunk is sent again on
//! its own, and the chunks after it are not wasted). Which chunks arrived is one bit each (`MAX_CHUNKS_PER_SCAN`
//! is at most 64); points are appended in arrival order to a buffer lent by the caller (capacity
//! `SCAN_POINTS_CAPACITY` points in the executive), since a scan's points are a set. Every check happens before
//! any state changes, so a rejected chunk leaves the reassembly exactly as it was. Scan ids increase: a chunk of a
//! newer scan while another is incomplete abandons the old scan (counted as [`ChunkAccepted::abandoned`]); a chunk
//! of an older scan (a late retransmission) is refused, so it can never abandon the scan in progress.

use super::message::{Point3, Pose, SensorChunk, TileChunk};
use crate::config::protocol::{MAX_CHUNKS_PER_SCAN, MAX_CHUNKS_PER_TILE, MAX_HEIGHTS_PER_TILE_CHUNK};

const _: () = assert!(MAX_CHUNKS_PER_SCAN as u32 <= u64::BITS);

/// Why a chunk was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkError {
    /// `chunk_index >= chunk_count`.
    IndexOutOfRange,
    /// `chunk_count` is 0 or above `MAX_CHUNKS_PER_SCAN`.
    TooManyChunks,
    /// Already received (this scan, or the last completed scan).
    Duplicate,
    /// A chunk of a scan older than the one in progress or the last completed one.
    OutOfOrder,
    /// Another chunk count for the scan in progress.
    MixedScan,
    /// The points do not fit the buffer.
    Overflow,
    /// The sensor pose differs from the first chunk's.
    PoseMismatch,
}

impl From<ChunkError> for super::NackReason {
    fn from(e: ChunkError) -> Self {
        use super::NackReason as R;
        match e {
            ChunkError::IndexOutOfRange => R::ChunkIndexOutOfRange,
            ChunkError::TooManyChunks => R::TooManyChunks,
            ChunkError::Duplicate => R::DuplicateChunk,
            ChunkError::OutOfOrder => R::OutOfOrderChunk,
            ChunkError::MixedScan => R::MixedScan,
            ChunkError::Overflow => R::ScanOverflow,
            ChunkError::PoseMismatch => R::PoseMismatch,
        }
    }
}

/// A chunk was taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChunkAccepted {
    /// The scan id of an incomplete scan dropped because this chunk started a newer one.
    pub abandoned: Option<u32>,
    /// `Some` when this chunk completed its scan: the points are `buffer[..points]`.
    pub complete: Option<CompleteScan>,
}

/// A fully reassembled scan.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CompleteScan {
    /// Scan id.
    pub scan_id: u32,
    /// Sensor pose.
    pub sensor_pose: Pose,
    /// Number of points in the buffer.
    pub points: usize,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct InProgress {
    scan_id: u32,
    chunk_count: u16,
    /// Bit `i` set: chunk `i` arrived.
    received: u64,
    pose: Pose,
    points: usize,
}

/// `id` is older than `than` (scan ids wrap: the half-range behind `than` is older).
fn older(id: u32, than: u32) -> bool {
    (id.wrapping_sub(than) as i32) < 0
}

/// Reassembly state (small; the point buffer is lent on each call).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ScanAssembler {
    current: Option<InProgress>,
    last_completed: Option<u32>,
    high_water: usize,
}

impl ScanAssembler {
    /// No scan in progress.
    pub const fn new() -> Self {
        Self {
            current: None,
            last_completed: None,
            high_water: 0,
        }
    }

    /// `(scan_id, chunks received, chunk_count)` of the scan in progress.
    pub fn progress(&self) -> Option<(u32, u16, u16)> {
        self.current
            .map(|c| (c.scan_id, c.received.count_ones() as u16, c.chunk_count))
    }

    /// Most points held at once.
    pub fn high_water(&self) -> usize {
        self.high_water
    }

    /// Takes one validated chunk, appending its points to `buffer`. Errors leave `self` and the used part of
    /// `buffer` unchanged.
    pub fn accept(
        &mut self,
        chunk: &SensorChunk,
        buffer: &mut [Point3],
    ) -> Result<ChunkAccepted, ChunkError> {
        if chunk.chunk_count == 0 || chunk.chunk_count > MAX_CHUNKS_PER_SCAN {
            return Err(ChunkError::TooManyChunks);
        }
        if chunk.chunk_index >= chunk.chunk_count {
            return Err(ChunkError::IndexOutOfRange);
        }
        let bit = 1u64.wrapping_shl(u32::from(chunk.chunk_index));
        if self.last_completed == Some(chunk.scan_id) {
            return Err(ChunkError::Duplicate);
        }
        if self.last_completed.is_some_and(|l| older(chunk.scan_id, l)) {
            return Err(ChunkError::OutOfOrder);
        }
        let (start, received, abandoned) = match self.current {
            Some(c) if c.scan_id == chunk.scan_id => {
                if c.chunk_count != chunk.chunk_count {
                    return Err(ChunkError::MixedScan);
                }
                if c.received & bit != 0 {
                    return Err(ChunkError::Duplicate);
                }
                if chunk.sensor_pose != c.pose {
                    return Err(ChunkError::PoseMismatch);
                }
                (c.points, c.received, None)
            }
            Some(c) if older(chunk.scan_id, c.scan_id) => return Err(ChunkError::OutOfOrder),
            Some(c) => (0, 0, Some(c.scan_id)),
            None => (0, 0, None),
        };
        let n = chunk.points.len();
        let dst = buffer
            .get_mut(start..start + n)
            .ok_or(ChunkError::Overflow)?;
        dst.copy_from_slice(&chunk.points);
        let points = start + n;
        self.high_water = self.high_water.max(points);
        let received = received | bit;
        let all = u64::MAX.wrapping_shr(u64::BITS - u32::from(chunk.chunk_count));
        if received == all {
            self.current = None;
            self.last_completed = Some(chunk.scan_id);
            Ok(ChunkAccepted {
                abandoned,
                complete: Some(CompleteScan {
                    scan_id: chunk.scan_id,
                    sensor_pose: chunk.sensor_pose,
                    points,
                }),
            })
        } else {
            self.current = Some(InProgress {
                scan_id: chunk.scan_id,
                chunk_count: chunk.chunk_count,
                received,
                pose: chunk.sensor_pose,
                points,
            });
            Ok(ChunkAccepted {
                abandoned,
                complete: None,
            })
        }
    }
}

/// Why a terrain-tile chunk was rejected (v7).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TileChunkError {
    /// `chunk_index >= chunk_count`.
    IndexOutOfRange,
    /// `chunk_count` is 0 or above `MAX_CHUNKS_PER_TILE`.
    TooManyChunks,
    /// The chunk count does not match the shape, or the heights do not match the chunk's index.
    ChunkLength,
    /// Already received (the tile in progress, or the last completed tile).
    Duplicate,
    /// A chunk ahead of the next expected one (a chunk is missing).
    OutOfOrder,
    /// A chunk of another tile than the one in progress, another header than its chunk 0, or no tile in progress.
    Mismatch,
}

impl From<TileChunkError> for super::NackReason {
    fn from(e: TileChunkError) -> Self {
        use super::NackReason as R;
        match e {
            TileChunkError::IndexOutOfRange => R::ChunkIndexOutOfRange,
            TileChunkError::TooManyChunks => R::TooManyChunks,
            TileChunkError::ChunkLength => R::TileChunkLength,
            TileChunkError::Duplicate => R::DuplicateChunk,
            TileChunkError::OutOfOrder => R::OutOfOrderChunk,
            TileChunkError::Mismatch => R::TileMismatch,
        }
    }
}

/// What every chunk of a tile shares.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileHeader {
    /// Tile id.
    pub tile_id: u32,
    /// World x, y of post (0, 0), metres.
    pub origin: [f32; 2],
    /// Post spacing, metres.
    pub resolution_m: f32,
    /// Posts along y.
    pub rows: u16,
    /// Posts along x.
    pub cols: u16,
    /// Chunks in the tile.
    pub chunk_count: u16,
}

impl TileHeader {
    /// The header of a chunk.
    pub fn of(c: &TileChunk) -> Self {
        TileHeader {
            tile_id: c.tile_id,
            origin: [c.origin_x_m, c.origin_y_m],
            resolution_m: c.resolution_m,
            rows: c.rows,
            cols: c.cols,
            chunk_count: c.chunk_count,
        }
    }
    /// Posts in the tile.
    pub fn cells(&self) -> usize {
        usize::from(self.rows) * usize::from(self.cols)
    }
}

/// A tile chunk was taken: its heights go to `offset..` of the staging tile (row-major post index).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileAccepted {
    /// The tile's header.
    pub header: TileHeader,
    /// Post index of the chunk's first height.
    pub offset: usize,
    /// A tile in progress that this chunk 0 abandoned.
    pub abandoned: Option<u32>,
    /// This chunk completed the tile.
    pub complete: bool,
}

/// Reassembly state of terrain tiles (v7). Unlike scans, tile chunks arrive strictly in order (a tile is staged
/// row-major and swapped in whole; an uplink that lost a chunk resends from it, and a chunk 0 starts over), so the
/// state is the next expected index. Every check happens before any state changes.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TileAssembler {
    current: Option<(TileHeader, u16)>,
    last_completed: Option<u32>,
}

impl TileAssembler {
    /// No tile in progress.
    pub const fn new() -> Self {
        Self { current: None, last_completed: None }
    }

    /// `(tile_id, chunks received, chunk_count)` of the tile in progress.
    pub fn progress(&self) -> Option<(u32, u16, u16)> {
        self.current.map(|(h, next)| (h.tile_id, next, h.chunk_count))
    }

    /// Takes one validated chunk (`TileChunk::validate` passed). Errors leave `self` unchanged.
    pub fn accept(&mut self, c: &TileChunk) -> Result<TileAccepted, TileChunkError> {
        if c.chunk_count == 0 || c.chunk_count > MAX_CHUNKS_PER_TILE {
            return Err(TileChunkError::TooManyChunks);
        }
        let header = TileHeader::of(c);
        let cells = header.cells();
        if usize::from(c.chunk_count) != cells.div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK) {
            return Err(TileChunkError::ChunkLength);
        }
        if c.chunk_index >= c.chunk_count {
            return Err(TileChunkError::IndexOutOfRange);
        }
        let offset = usize::from(c.chunk_index) * MAX_HEIGHTS_PER_TILE_CHUNK;
        let expected = cells.saturating_sub(offset).min(MAX_HEIGHTS_PER_TILE_CHUNK);
        if c.heights.len() != expected {
            return Err(TileChunkError::ChunkLength);
        }
        let abandoned = match self.current {
            Some((h, next)) if h.tile_id == c.tile_id => {
                if h != header {
                    return Err(TileChunkError::Mismatch);
                }
                if c.chunk_index < next {
                    return Err(TileChunkError::Duplicate);
                }
                if c.chunk_index > next {
                    return Err(TileChunkError::OutOfOrder);
                }
                None
            }
            _ if self.last_completed == Some(c.tile_id) => return Err(TileChunkError::Duplicate),
            Some((h, _)) if c.chunk_index == 0 => Some(h.tile_id),
            None if c.chunk_index == 0 => None,
            _ => return Err(TileChunkError::Mismatch),
        };
        let next = c.chunk_index.saturating_add(1);
        let complete = next == c.chunk_count;
        if complete {
            self.current = None;
            self.last_completed = Some(c.tile_id);
        } else {
            self.current = Some((header, next));
        }
        Ok(TileAccepted { header, offset, abandoned, complete })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use heapless::Vec;

    fn chunk(scan_id: u32, idx: u16, count: u16, npts: usize) -> SensorChunk {
        let mut points = Vec::new();
        for i in 0..npts {
            points.push(Point3::new(idx as f32, i as f32, 0.0)).unwrap();
        }
        SensorChunk {
            scan_id,
            chunk_index: idx,
            chunk_count: count,
            sensor_pose: Pose::IDENTITY,
            points,
        }
    }

    #[test]
    fn in_order_scan_completes_with_all_points() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); 32];
        assert_eq!(
            a.accept(&chunk(5, 0, 3, 4), &mut buf).unwrap().complete,
            None
        );
        assert_eq!(
            a.accept(&chunk(5, 1, 3, 4), &mut buf).unwrap().complete,
            None
        );
        let done = a
            .accept(&chunk(5, 2, 3, 2), &mut buf)
            .unwrap()
            .complete
            .unwrap();
        assert_eq!(done.points, 10);
        assert_eq!(buf[4], Point3::new(1.0, 0.0, 0.0));
        assert_eq!(buf[9], Point3::new(2.0, 1.0, 0.0));
    }

    #[test]
    fn every_bad_chunk_has_its_reason_and_changes_nothing() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); 8];
        a.accept(&chunk(1, 0, 3, 2), &mut buf).unwrap();
        let before = a;
        let cases = [
            (chunk(1, 0, 3, 2), ChunkError::Duplicate),
            (chunk(0, 1, 3, 2), ChunkError::OutOfOrder),
            (chunk(1, 1, 4, 2), ChunkError::MixedScan),
            (chunk(1, 3, 3, 2), ChunkError::IndexOutOfRange),
            (chunk(1, 1, 0, 2), ChunkError::TooManyChunks),
            (
                chunk(1, 1, MAX_CHUNKS_PER_SCAN + 1, 2),
                ChunkError::TooManyChunks,
            ),
            (chunk(1, 1, 3, 7), ChunkError::Overflow),
        ];
        for (c, e) in cases {
            assert_eq!(a.accept(&c, &mut buf), Err(e));
            assert_eq!(a, before);
        }
        let mut moved = chunk(1, 1, 3, 2);
        moved.sensor_pose.position.x = 1.0;
        assert_eq!(a.accept(&moved, &mut buf), Err(ChunkError::PoseMismatch));
        assert_eq!(a, before);
        // any chunk of a newer scan abandons the old one
        let r = a.accept(&chunk(2, 1, 2, 1), &mut buf).unwrap();
        assert_eq!(r.abandoned, Some(1));
    }

    #[test]
    fn chunks_in_any_order_complete_the_scan_once() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); 32];
        // chunk 1 was lost and comes again after 2 and 3
        for idx in [0, 2, 3] {
            assert_eq!(a.accept(&chunk(9, idx, 4, 3), &mut buf).unwrap().complete, None);
        }
        assert_eq!(a.progress(), Some((9, 3, 4)));
        assert_eq!(a.accept(&chunk(9, 2, 4, 3), &mut buf), Err(ChunkError::Duplicate));
        let done = a.accept(&chunk(9, 1, 4, 3), &mut buf).unwrap().complete.unwrap();
        assert_eq!((done.scan_id, done.points), (9, 12));
        // every chunk's points are there, each once
        let mut per_chunk = [0usize; 4];
        for p in &buf[..12] {
            per_chunk[p.x as usize] += 1;
        }
        assert_eq!(per_chunk, [3; 4]);
        assert_eq!(a.accept(&chunk(9, 1, 4, 3), &mut buf), Err(ChunkError::Duplicate));
    }

    #[test]
    fn a_late_chunk_of_an_older_scan_never_abandons_the_newer_one() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); 32];
        a.accept(&chunk(4, 0, 3, 2), &mut buf).unwrap();
        // scan 5 starts without its chunk 0: scan 4 is abandoned
        assert_eq!(a.accept(&chunk(5, 2, 3, 2), &mut buf).unwrap().abandoned, Some(4));
        let before = a;
        assert_eq!(a.accept(&chunk(4, 1, 3, 2), &mut buf), Err(ChunkError::OutOfOrder));
        assert_eq!(a, before);
        a.accept(&chunk(5, 0, 3, 2), &mut buf).unwrap();
        assert!(a.accept(&chunk(5, 1, 3, 2), &mut buf).unwrap().complete.is_some());
        // after completion, an older scan is still refused
        assert_eq!(a.accept(&chunk(3, 0, 3, 2), &mut buf), Err(ChunkError::OutOfOrder));
    }

    #[test]
    fn scan_ids_wrap() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); 8];
        assert!(a.accept(&chunk(u32::MAX, 0, 1, 2), &mut buf).unwrap().complete.is_some());
        assert!(a.accept(&chunk(0, 0, 1, 2), &mut buf).unwrap().complete.is_some());
        assert_eq!(a.accept(&chunk(u32::MAX, 0, 1, 2), &mut buf), Err(ChunkError::OutOfOrder));
    }

    #[test]
    fn a_full_scan_of_the_largest_chunk_count_completes() {
        let mut a = ScanAssembler::new();
        let mut buf = [Point3::default(); MAX_CHUNKS_PER_SCAN as usize];
        for idx in (0..MAX_CHUNKS_PER_SCAN).rev() {
            let r = a.accept(&chunk(1, idx, MAX_CHUNKS_PER_SCAN, 1), &mut buf).unwrap();
            assert_eq!(r.complete.is_some(), idx == 0);
        }
    }

    fn tile(id: u32, idx: u16, rows: u16, cols: u16) -> TileChunk {
        let cells = usize::from(rows) * usize::from(cols);
        let count = cells.div_ceil(MAX_HEIGHTS_PER_TILE_CHUNK) as u16;
        let start = usize::from(idx) * MAX_HEIGHTS_PER_TILE_CHUNK;
        let mut heights = Vec::new();
        for i in start..cells.min(start + MAX_HEIGHTS_PER_TILE_CHUNK) {
            heights.push(i as f32).unwrap();
        }
        TileChunk {
            tile_id: id,
            chunk_index: idx,
            chunk_count: count,
            origin_x_m: 1.0,
            origin_y_m: 2.0,
            resolution_m: 0.5,
            rows,
            cols,
            heights,
        }
    }

    #[test]
    fn a_tile_in_order_completes_with_its_offsets() {
        let mut a = TileAssembler::new();
        // 20 x 30 = 600 posts: chunks of 256, 256, 88
        for idx in 0..3u16 {
            let r = a.accept(&tile(7, idx, 20, 30)).unwrap();
            assert_eq!(r.offset, usize::from(idx) * MAX_HEIGHTS_PER_TILE_CHUNK);
            assert_eq!(r.complete, idx == 2);
            assert_eq!(r.abandoned, None);
        }
        assert_eq!(a.progress(), None);
    }

    #[test]
    fn every_bad_tile_chunk_has_its_reason_and_changes_nothing() {
        let mut a = TileAssembler::new();
        a.accept(&tile(3, 0, 20, 30)).unwrap();
        a.accept(&tile(3, 1, 20, 30)).unwrap();
        let before = a;
        let mut short = tile(3, 2, 20, 30);
        short.heights.pop();
        let mut count = tile(3, 2, 20, 30);
        count.chunk_count = 4;
        let mut zero = tile(3, 2, 20, 30);
        zero.chunk_count = 0;
        let mut moved = tile(3, 2, 20, 30);
        moved.origin_x_m = 5.0;
        let mut index = tile(3, 2, 20, 30);
        index.chunk_index = 3;
        let cases = [
            (tile(3, 1, 20, 30), TileChunkError::Duplicate),
            (tile(3, 0, 20, 30), TileChunkError::Duplicate),
            (tile(4, 2, 20, 30), TileChunkError::Mismatch),
            (moved, TileChunkError::Mismatch),
            (short, TileChunkError::ChunkLength),
            (count, TileChunkError::ChunkLength),
            (zero, TileChunkError::TooManyChunks),
            (index, TileChunkError::IndexOutOfRange),
        ];
        for (c, e) in cases {
            assert_eq!(a.accept(&c), Err(e), "{c:?}");
            assert_eq!(a, before);
        }
        // chunk 2 of 3 is next: a gap (chunk 1 of a 4-chunk tile of the same id would mismatch) is out of order
        let mut big = TileAssembler::new();
        big.accept(&tile(5, 0, 40, 30)).unwrap();
        let before = big;
        assert_eq!(big.accept(&tile(5, 2, 40, 30)), Err(TileChunkError::OutOfOrder));
        assert_eq!(big, before);
        // completed: its chunks again are duplicates, a chunk k > 0 of no tile in progress a mismatch
        a.accept(&tile(3, 2, 20, 30)).unwrap();
        assert_eq!(a.accept(&tile(3, 2, 20, 30)), Err(TileChunkError::Duplicate));
        assert_eq!(a.accept(&tile(3, 0, 20, 30)), Err(TileChunkError::Duplicate));
        assert_eq!(a.accept(&tile(9, 1, 20, 30)), Err(TileChunkError::Mismatch));
    }

    #[test]
    fn a_chunk_0_of_another_tile_abandons_the_one_in_progress() {
        let mut a = TileAssembler::new();
        a.accept(&tile(1, 0, 20, 30)).unwrap();
        let r = a.accept(&tile(2, 0, 20, 30)).unwrap();
        assert_eq!(r.abandoned, Some(1));
        assert_eq!(a.progress(), Some((2, 1, 3)));
    }

    #[test]
    fn the_largest_tile_takes_the_largest_chunk_count() {
        let side = crate::config::homotopy::MAX_TILE_SIDE as u16;
        let mut a = TileAssembler::new();
        for idx in 0..MAX_CHUNKS_PER_TILE {
            let r = a.accept(&tile(1, idx, side, side)).unwrap();
            assert_eq!(r.complete, idx + 1 == MAX_CHUNKS_PER_TILE);
        }
    }
}
