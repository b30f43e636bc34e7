//! Bounded reassembly of chunked sensor scans.
//!
//! Chunks of one scan may arrive in any order, each at most once (selective repeat: a lost chunk is sent again on
//! its own, and the chunks after it are not wasted). Which chunks arrived is one bit each (`MAX_CHUNKS_PER_SCAN`
//! is at most 64); points are appended in arrival order to a buffer lent by the caller (capacity
//! `SCAN_POINTS_CAPACITY` points in the executive), since a scan's points are a set. Every check happens before
//! any state changes, so a rejected chunk leaves the reassembly exactly as it was. Scan ids increase: a chunk of a
//! newer scan while another is incomplete abandons the old scan (counted as [`ChunkAccepted::abandoned`]); a chunk
//! of an older scan (a late retransmission) is refused, so it can never abandon the scan in progress.

use super::message::{Point3, Pose, SensorChunk};
use crate::config::protocol::MAX_CHUNKS_PER_SCAN;

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
}
