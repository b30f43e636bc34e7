//! LAS / LAZ reader through the `las` crate (with its `laz` feature for compressed files).
//!
//! Coordinates are the crate's scaled values, `raw * scale + offset` with the header's scale and offset per axis.
//! Every LAS 1.0-1.4 point format is read; only x, y, z are kept. Bounds: the declared point count is checked
//! against [`PointCloudOptions::max_points`] and, for uncompressed files, against the bytes in the file before any
//! point is read; points are then decoded in batches of [`BATCH_POINTS`], so a LAZ file that declares more points
//! than it holds fails when its data runs out ([`PointCloudError::Truncated`] or the crate's error) instead of
//! allocating the declared count. The LAZ fields the `laz` crate trusts are checked first (`check_laz`); a panic
//! still left inside the `las`/`laz` crates is caught here and returned as [`PointCloudError::DecoderPanic`].
//! Errors: see the module [`super`].

use super::{check_count, Format, PointCloud, PointCloudError, PointCloudOptions, Position};
use std::io::Cursor;

const F: Format = Format::Las;

/// Points decoded per call into the `las` crate.
pub const BATCH_POINTS: u64 = 4096;

/// Parse LAS or LAZ bytes.
pub fn parse_las(bytes: &[u8], opts: &PointCloudOptions) -> Result<PointCloud, PointCloudError> {
    if !bytes.starts_with(b"LASF") {
        return Err(PointCloudError::BadMagic { format: F });
    }
    // The `laz` crate panics on some malformed item lists (an `expect` in its decompressor set-up): the crates are
    // run behind `catch_unwind`, so a damaged file is an error here, not a crash of the caller.
    std::panic::catch_unwind(|| read(bytes, opts)).unwrap_or_else(|payload| {
        let msg = payload
            .downcast_ref::<&str>()
            .map(|s| (*s).to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "a panic without a message".into());
        Err(PointCloudError::DecoderPanic(msg))
    })
}

fn read(bytes: &[u8], opts: &PointCloudOptions) -> Result<PointCloud, PointCloudError> {
    // the header alone first: the checks below come before the crate builds a LAZ decompressor from it
    let header = ::las::Header::new(Cursor::new(bytes)).map_err(PointCloudError::Las)?;
    let declared = header.number_of_points();
    let format = header.point_format();
    // LAZ data is smaller than its records: only the limit applies, and the batches below bound the allocation
    let record_min = if format.is_compressed { 0 } else { usize::from(format.len()) };
    check_count(F, declared, record_min, bytes.len(), opts)?;
    if format.is_compressed {
        check_laz(bytes, &header)?;
    }
    let mut reader = ::las::Reader::new(Cursor::new(bytes.to_vec())).map_err(PointCloudError::Las)?;
    let mut cloud = PointCloud::default();
    cloud.points.reserve(declared.min(BATCH_POINTS) as usize);
    let mut batch = ::las::PointDataBuilder::new().for_header(reader.header()).build();
    let mut read = 0u64;
    while read < declared {
        let n = reader.fill_points(BATCH_POINTS.min(declared - read), &mut batch).map_err(PointCloudError::Las)?;
        if n == 0 {
            return Err(PointCloudError::Truncated { format: F, point: read, at: Position::Byte(bytes.len()) });
        }
        for ((x, y), z) in batch.x().zip(batch.y()).zip(batch.z()).take(n as usize) {
            cloud.push([x, y, z]);
        }
        read += n;
    }
    cloud.finish(F)
}

fn bad_laz(reason: impl Into<String>) -> PointCloudError {
    PointCloudError::BadHeader { format: F, line: 0, reason: reason.into() }
}

fn le<const N: usize>(bytes: &[u8], at: usize) -> Option<[u8; N]> {
    bytes.get(at..at.checked_add(N)?)?.try_into().ok()
}

/// Checks, before the `laz` crate sees them, the LAZ fields it trusts: the LASzip VLR's item list (at least one
/// item, item sizes adding up to the point record length; an empty list made the crate panic) and the chunk
/// count of the chunk table (the crate reserves 16 bytes per declared chunk: a damaged count asked for 61 GB);
/// every chunk holds at least one compressed byte, so more chunks than the file has bytes is an error.
fn check_laz(bytes: &[u8], header: &::las::Header) -> Result<(), PointCloudError> {
    let vlr = header
        .vlrs()
        .iter()
        .find(|v| v.user_id == "laszip encoded" && v.record_id == 22204)
        .ok_or_else(|| bad_laz("compressed point format without a LASzip VLR"))?;
    // LASzip VLR: compressor u16, coder u16, version 4 bytes, options u32, chunk size u32, two i64 (special EVLRs),
    // then the item count u16 at byte 32 and 6-byte items (type u16, size u16, version u16)
    let items = le::<2>(&vlr.data, 32).map(u16::from_le_bytes).ok_or_else(|| bad_laz("LASzip VLR too short"))?;
    let mut size = 0usize;
    for i in 0..usize::from(items) {
        let item = le::<2>(&vlr.data, 34 + 6 * i + 2).ok_or_else(|| bad_laz("LASzip VLR ends inside its item list"))?;
        size += usize::from(u16::from_le_bytes(item));
    }
    let record = usize::from(header.point_format().len());
    if items == 0 || size != record {
        return Err(bad_laz(format!("LASzip items ({items}) take {size} bytes, the point record {record}")));
    }
    // the chunk table: its offset is the first 8 bytes of the point data, or the file's last 8 when unset
    let Some(start) = le::<4>(bytes, 96).map(|b| u32::from_le_bytes(b) as usize) else {
        return Ok(());
    };
    let offset_at = |at: usize| le::<8>(bytes, at).map(i64::from_le_bytes).filter(|&o| o > start as i64);
    let table = offset_at(start).or_else(|| offset_at(bytes.len().saturating_sub(8)));
    if let Some(chunks) = table.and_then(|t| le::<4>(bytes, usize::try_from(t).ok()?.checked_add(4)?)) {
        let chunks = u32::from_le_bytes(chunks);
        if chunks as usize > bytes.len() {
            return Err(bad_laz(format!("chunk table declares {chunks} chunks in a file of {} bytes", bytes.len())));
        }
    }
    Ok(())
}
