//! Bounded reassembly of chunked sensor scans.
//!
//! Chunks of one scan must arrive in order `0..chunk_count` (the link is ordered; a gap means a lost frame). Points
//! are appended to a buffer lent by the caller (capacity `SCAN_POINTS_CAPACITY` points in the executive). Every
//! check happens before any state changes, so a rejected chunk leaves the reassembly exactly as it was and the
//! sender may resend the right chunk. A chunk 0 of a new scan while another is incomplete abandons the old scan
//! (counted as [`ChunkAccepted::abandoned`]).

use super::message::{Point3, Pose, SensorChunk};
use crate::config::protocol::MAX_CHUNKS_PER_SCAN;

/// Why a chunk was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ChunkError {
    /// `chunk_index >= chunk_count`.
    IndexOutOfRange,
    /// `chunk_count` is 0 or above `MAX_CHUNKS_PER_SCAN`.
    TooManyChunks,
    /// Already received (this scan, or the last completed scan).
    Duplicate,
    /// Ahead of the next expected chunk, or not chunk 0 with no scan in progress.
    OutOfOrder,
    /// Another scan id or chunk count while a scan is in progress.
    MixedScan,
    /// The points do not fit the buffer.
    Overflow,
    /// The sensor pose differs from chunk 0's.
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
    /// The scan id of an incomplete scan dropped because this chunk started a new one.
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
    next_index: u16,
    pose: Pose,
    points: usize,
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

    /// `(scan_id, next_chunk, chunk_count)` of the scan in progress.
    pub fn progress(&self) -> Option<(u32, u16, u16)> {
        self.current
            .map(|c| (c.scan_id, c.next_index, c.chunk_count))
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
        let n = chunk.points.len();
        let (start, abandoned) = match self.current {
            Some(c) if c.scan_id == chunk.scan_id => {
                if c.chunk_count != chunk.chunk_count {
                    return Err(ChunkError::MixedScan);
                }
                if chunk.chunk_index < c.next_index {
                    return Err(ChunkError::Duplicate);
                }
                if chunk.chunk_index > c.next_index {
                    return Err(ChunkError::OutOfOrder);
                }
                if chunk.sensor_pose != c.pose {
                    return Err(ChunkError::PoseMismatch);
                }
                (c.points, None)
            }
            Some(c) => {
                if chunk.chunk_index != 0 {
                    return Err(ChunkError::MixedScan);
                }
                if self.last_completed == Some(chunk.scan_id) {
                    return Err(ChunkError::Duplicate);
                }
                (0, Some(c.scan_id))
            }
            None => {
                if self.last_completed == Some(chunk.scan_id) {
                    return Err(ChunkError::Duplicate);
                }
                if chunk.chunk_index != 0 {
                    return Err(ChunkError::OutOfOrder);
                }
                (0, None)
            }
        };
        let dst = buffer
            .get_mut(start..start + n)
            .ok_or(ChunkError::Overflow)?;
        dst.copy_from_slice(&chunk.points);
        let points = start + n;
        self.high_water = self.high_water.max(points);
        let next_index = chunk.chunk_index + 1;
        if next_index == chunk.chunk_count {
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
                next_index,
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
            (chunk(1, 2, 3, 2), ChunkError::OutOfOrder),
            (chunk(2, 1, 3, 2), ChunkError::MixedScan),
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
        // a new scan at chunk 0 abandons the old one
        let r = a.accept(&chunk(2, 0, 2, 1), &mut buf).unwrap();
        assert_eq!(r.abandoned, Some(1));
    }
}
