//! Point clouds from scanners and photogrammetry: PLY, PCD and LAS/LAZ readers, and voxel-grid thinning to the
//! flight scan capacity.
//!
//! Formats ([`load_point_cloud`] picks the reader by the file's extension, case-insensitive):
//!
//! | format | extension | variants read | coordinates |
//! |---|---|---|---|
//! | PLY ([`ply`]) | `.ply` | `ascii 1.0`, `binary_little_endian 1.0`, `binary_big_endian 1.0` | the `vertex` element's scalar `x`, `y`, `z` properties, any numeric type |
//! | PCD ([`pcd`]) | `.pcd` | `DATA ascii`, `DATA binary` (`binary_compressed` is a [`PointCloudError::Unsupported`] error) | the first element of the `x`, `y`, `z` fields, any `TYPE`/`SIZE` |
//! | LAS/LAZ ([`las`]) | `.las`, `.laz` | every LAS 1.0-1.4 point format through the `las` crate, LAZ through its `laz` feature | the crate's scaled values: `raw * scale + offset` from the header |
//!
//! Every other property, field or element (colours, normals, intensities, PLY faces) is skipped by its declared
//! size. Coordinates keep the file's units (metres for LAS in a metric CRS; PLY and PCD have none).
//!
//! Bounds and errors, the same for the three readers (one [`PointCloudError`], which names the format): a
//! declared point count larger than the data that follows the header can hold is [`PointCloudError::CountTooLarge`]
//! before anything is allocated for it; a count above [`PointCloudOptions::max_points`] (default
//! [`PointCloudOptions::DEFAULT_MAX_POINTS`], 2^24 points, 384 MiB of coordinates) is
//! [`PointCloudError::OverLimit`]; a file that ends early is [`PointCloudError::Truncated`] with the point and the
//! byte offset (binary) or the line (ASCII); a malformed header or value names its 1-based line. Non-finite
//! coordinates (NaN, the PCD convention for "no return", and infinities) are **skipped and counted** in
//! [`PointCloud::non_finite_skipped`], not an error; a cloud left without a finite point is
//! [`PointCloudError::Empty`]. No reader panics on any input (fuzz targets `ply`, `pcd`, `las` in
//! `firmware/fuzz`); the LAS reader gets there by catching what the `las`/`laz` crates raise on corrupt data
//! ([`PointCloudError::DecoderPanic`]), so it relies on unwinding, as host builds do.
//!
//! Thinning ([`thin`]): one point per occupied voxel, the input point nearest the voxel's centre by default, the
//! voxel edge grown until the count fits a capacity, by default the flight scan capacity
//! [`FLIGHT_SCAN_CAPACITY`].

pub mod las;
pub mod pcd;
pub mod ply;
pub mod thin;

use core::fmt;
use std::path::Path;

/// Points per scan the flight software holds: `firmware::config::team::SCENE_MAX_POINTS` (4096).
pub const FLIGHT_SCAN_CAPACITY: usize = firmware::config::team::SCENE_MAX_POINTS;

/// A point cloud read from a file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PointCloud {
    /// Finite points in file order, in the file's units.
    pub points: Vec<[f64; 3]>,
    /// Points the file holds with a NaN or infinite coordinate, left out of `points`.
    pub non_finite_skipped: u64,
}

impl PointCloud {
    /// Axis-aligned bounds `(min, max)`; `None` for an empty cloud.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        bounds(&self.points)
    }

    /// Keeps `p` if all three coordinates are finite, else counts it as skipped.
    fn push(&mut self, p: [f64; 3]) {
        if p.iter().all(|c| c.is_finite()) {
            self.points.push(p);
        } else {
            self.non_finite_skipped += 1;
        }
    }

    /// The finished cloud, or [`PointCloudError::Empty`] when no finite point was read.
    fn finish(self, format: Format) -> Result<PointCloud, PointCloudError> {
        if self.points.is_empty() {
            return Err(PointCloudError::Empty { format, non_finite: self.non_finite_skipped });
        }
        Ok(self)
    }
}

/// Axis-aligned bounds `(min, max)` of `points`; `None` when there are none.
pub fn bounds(points: &[[f64; 3]]) -> Option<([f64; 3], [f64; 3])> {
    let first = *points.first()?;
    Some(points.iter().fold((first, first), |(mut lo, mut hi), p| {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
        (lo, hi)
    }))
}

/// Reader options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PointCloudOptions {
    /// Largest point count a file may declare. Default [`Self::DEFAULT_MAX_POINTS`].
    pub max_points: u64,
}

impl PointCloudOptions {
    /// 2^24 points: 384 MiB of `[f64; 3]`, above the largest scans of the papers (tens of thousands of points).
    pub const DEFAULT_MAX_POINTS: u64 = 1 << 24;
}

impl Default for PointCloudOptions {
    fn default() -> Self {
        Self { max_points: Self::DEFAULT_MAX_POINTS }
    }
}

/// The point-cloud file formats read here.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Stanford polygon file.
    Ply,
    /// Point Cloud Library's point cloud data file.
    Pcd,
    /// ASPRS LAS, or LAZ (compressed LAS).
    Las,
}

impl fmt::Display for Format {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Format::Ply => "PLY",
            Format::Pcd => "PCD",
            Format::Las => "LAS",
        })
    }
}

/// Why a point-cloud file could not be read.
#[derive(Debug)]
pub enum PointCloudError {
    /// The file could not be read from disk.
    Io(std::io::Error),
    /// The extension is not `.ply`, `.pcd`, `.las` or `.laz`.
    UnknownExtension(String),
    /// The file does not start as the format must (PLY: `ply`; PCD: a `VERSION` or `FIELDS` line; LAS: `LASF`).
    BadMagic {
        /// The format expected.
        format: Format,
    },
    /// A header line that is not understood.
    BadHeader {
        /// The format.
        format: Format,
        /// 1-based line number (0: the header as a whole, e.g. a missing line).
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// A variant or type the reader does not handle (e.g. PCD `binary_compressed`).
    Unsupported {
        /// The format.
        format: Format,
        /// What is not supported.
        what: String,
    },
    /// The point record has no `x`, `y` or `z`.
    MissingAxis {
        /// The format.
        format: Format,
        /// The axis missing.
        axis: char,
    },
    /// The header declares more points than the data after it can hold.
    CountTooLarge {
        /// The format.
        format: Format,
        /// Points declared.
        declared: u64,
        /// Points the bytes after the header can hold at most.
        fits: u64,
    },
    /// The header declares more points than [`PointCloudOptions::max_points`].
    OverLimit {
        /// The format.
        format: Format,
        /// Points declared.
        declared: u64,
        /// The limit.
        max: u64,
    },
    /// The data ends inside point `point` (0-based).
    Truncated {
        /// The format.
        format: Format,
        /// The point being read.
        point: u64,
        /// Where it ended: a byte offset in the file (binary) or a 1-based line (ASCII), see `at`.
        at: Position,
    },
    /// An ASCII value that is not a number, or a line with the wrong number of values.
    BadValue {
        /// The format.
        format: Format,
        /// 1-based line.
        line: usize,
        /// What is wrong.
        reason: String,
    },
    /// The `las` crate rejected the file.
    Las(::las::Error),
    /// The `las` or `laz` crate panicked on the file (seen on malformed LAZ item lists); the panic is caught at the
    /// reader's boundary and its message kept, so the reader itself returns an error (host builds unwind).
    DecoderPanic(String),
    /// The file holds no point with three finite coordinates.
    Empty {
        /// The format.
        format: Format,
        /// Points skipped for a non-finite coordinate.
        non_finite: u64,
    },
}

/// A place in a file, for error messages.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Position {
    /// A byte offset from the start of the file.
    Byte(usize),
    /// A 1-based line: the last line read.
    Line(usize),
}

impl fmt::Display for Position {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Position::Byte(b) => write!(f, "at byte {b}"),
            Position::Line(l) => write!(f, "after line {l}"),
        }
    }
}

impl fmt::Display for PointCloudError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            PointCloudError::Io(e) => write!(f, "cannot read point-cloud file: {e}"),
            PointCloudError::UnknownExtension(e) => {
                write!(f, "point-cloud extension {e:?} not known (.ply, .pcd, .las, .laz are)")
            }
            PointCloudError::BadMagic { format } => write!(f, "not a {format} file (wrong magic / first line)"),
            PointCloudError::BadHeader { format, line, reason } => write!(f, "{format} header line {line}: {reason}"),
            PointCloudError::Unsupported { format, what } => write!(f, "{format}: {what} is not supported"),
            PointCloudError::MissingAxis { format, axis } => {
                write!(f, "{format}: the points have no {axis:?} coordinate")
            }
            PointCloudError::CountTooLarge { format, declared, fits } => {
                write!(f, "{format}: header declares {declared} points but the data after it holds at most {fits}")
            }
            PointCloudError::OverLimit { format, declared, max } => {
                write!(f, "{format}: header declares {declared} points, more than the limit of {max}")
            }
            PointCloudError::Truncated { format, point, at } => {
                write!(f, "{format}: data ends inside point {point} ({at})")
            }
            PointCloudError::BadValue { format, line, reason } => write!(f, "{format} line {line}: {reason}"),
            PointCloudError::Las(e) => write!(f, "LAS: {e}"),
            PointCloudError::DecoderPanic(m) => write!(f, "LAS: the las/laz decoder failed on this file: {m}"),
            PointCloudError::Empty { format, non_finite } => {
                write!(f, "{format}: no point with finite coordinates ({non_finite} non-finite skipped)")
            }
        }
    }
}

impl core::error::Error for PointCloudError {}

impl From<std::io::Error> for PointCloudError {
    fn from(e: std::io::Error) -> Self {
        PointCloudError::Io(e)
    }
}

/// A reader: file bytes to a point cloud ([`ply::parse_ply`], [`pcd::parse_pcd`], [`las::parse_las`]).
pub type Parser = fn(&[u8], &PointCloudOptions) -> Result<PointCloud, PointCloudError>;

/// The reader for a file extension (`ply`, `pcd`, `las`, `laz`; case-insensitive).
pub fn parser_for(extension: &str) -> Option<Parser> {
    match extension.to_ascii_lowercase().as_str() {
        "ply" => Some(ply::parse_ply),
        "pcd" => Some(pcd::parse_pcd),
        "las" | "laz" => Some(las::parse_las),
        _ => None,
    }
}

/// Load a point cloud, the reader chosen by the extension (`.ply`, `.pcd`, `.las`, `.laz`).
pub fn load_point_cloud(path: &Path, opts: &PointCloudOptions) -> Result<PointCloud, PointCloudError> {
    let ext = path.extension().and_then(|e| e.to_str()).unwrap_or("");
    let parse = parser_for(ext).ok_or_else(|| PointCloudError::UnknownExtension(ext.to_ascii_lowercase()))?;
    let bytes = std::fs::read(path)?;
    parse(&bytes, opts)
}

/// Checks a declared count against the limit and against the bytes left (`record_min` bytes per point at least;
/// 0: no bound from the size, as for compressed data).
fn check_count(
    format: Format,
    declared: u64,
    record_min: usize,
    bytes_left: usize,
    opts: &PointCloudOptions,
) -> Result<(), PointCloudError> {
    if declared > opts.max_points {
        return Err(PointCloudError::OverLimit { format, declared, max: opts.max_points });
    }
    let fits = bytes_left.checked_div(record_min).map_or(u64::MAX, |n| n as u64);
    if declared > fits {
        return Err(PointCloudError::CountTooLarge { format, declared, fits });
    }
    Ok(())
}

/// For each field (name, whether it can hold a coordinate), the coordinate it holds: 0, 1, 2 for the first
/// eligible field named `x`, `y`, `z`; [`PointCloudError::MissingAxis`] when one of them is absent.
fn axis_slots<'a>(
    format: Format,
    fields: impl Iterator<Item = (&'a str, bool)> + Clone,
) -> Result<Vec<Option<usize>>, PointCloudError> {
    let mut slots = vec![None; fields.clone().count()];
    for (k, axis) in ["x", "y", "z"].into_iter().enumerate() {
        let i = fields
            .clone()
            .position(|(name, eligible)| eligible && name == axis)
            .ok_or(PointCloudError::MissingAxis { format, axis: char::from(b'x' + k as u8) })?;
        if let Some(s) = slots.get_mut(i) {
            *s = Some(k);
        }
    }
    Ok(slots)
}

/// Stores `v` as the coordinate `slot` names (see [`axis_slots`]), if any.
fn store(xyz: &mut [f64; 3], slot: Option<&Option<usize>>, v: f64) {
    if let Some(c) = slot.copied().flatten().and_then(|k| xyz.get_mut(k)) {
        *c = v;
    }
}

/// A binary scalar type shared by PLY properties and PCD fields.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    I64,
    U64,
    F32,
    F64,
}

impl Scalar {
    /// Bytes per value.
    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::I64 | Scalar::U64 | Scalar::F64 => 8,
        }
    }

    /// The value at the start of `raw` (which holds at least [`Self::size`] bytes), or `None` when it is shorter.
    fn decode(self, raw: &[u8], big_endian: bool) -> Option<f64> {
        let n = self.size();
        let mut b = [0u8; 8];
        b.get_mut(..n)?.copy_from_slice(raw.get(..n)?);
        if big_endian {
            b.get_mut(..n)?.reverse();
        }
        let [b0, b1, b2, b3, ..] = b;
        Some(match self {
            Scalar::I8 => f64::from(b0 as i8),
            Scalar::U8 => f64::from(b0),
            Scalar::I16 => f64::from(i16::from_le_bytes([b0, b1])),
            Scalar::U16 => f64::from(u16::from_le_bytes([b0, b1])),
            Scalar::I32 => f64::from(i32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::U32 => f64::from(u32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::F32 => f64::from(f32::from_le_bytes([b0, b1, b2, b3])),
            Scalar::I64 => i64::from_le_bytes(b) as f64,
            Scalar::U64 => u64::from_le_bytes(b) as f64,
            Scalar::F64 => f64::from_le_bytes(b),
        })
    }
}

#[cfg(test)]
mod tests;
