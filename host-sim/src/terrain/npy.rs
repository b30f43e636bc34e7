//! NumPy `.npy` grid loader -> [`Heightmap`].
//!
//! Reads the NumPy array file format (versions 1.0, 2.0 and 3.0; see the NumPy "format" documentation):
//! magic `\x93NUMPY`, a version byte pair, a little-endian header length (u16 for 1.0, u32 for 2.0/3.0), an ASCII
//! Python-dict header with `descr`, `fortran_order` and `shape`, then the raw data.
//!
//! Supported: two-dimensional arrays `(rows, cols)` of `f4`, `f8`, `i1`, `i2`, `i4`, `i8`, `u1`, `u2`, `u4`
//! in either byte order (`<`, `>`, `|`, `=` taken as little-endian), C or Fortran order. NaN, infinities and an
//! optional sentinel value become "no data" (`None`). Everything else is a typed [`NpyError`].
//!
//! Orientation: a DEM stored as an image has its first row at the north edge; [`Heightmap`] has row 0 at the
//! south edge. [`NpyOptions::first_row`] says which edge the file's first row is (default: north, the image
//! convention, as for the HiRISE crop in `shared/data/terrain`).

use super::Heightmap;
use core::fmt;
use std::path::Path;

/// Which map edge the first row of the array describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FirstRow {
    /// Image convention: row 0 of the file is the north (maximum y) edge; rows are flipped on load.
    North,
    /// Row 0 of the file is the south (minimum y) edge; rows are kept in file order.
    South,
}

/// How to turn the array into metres.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NpyOptions {
    /// Horizontal grid spacing, metres (the .npy format has no georeferencing). Must be finite and > 0.
    pub spacing_m: f64,
    /// Multiply every stored value by this to get metres (1.0 for a DEM in metres).
    pub height_scale: f64,
    /// A stored value meaning "no data" (compared before scaling), if the file uses one.
    pub nodata: Option<f64>,
    /// Which edge the file's first row is.
    pub first_row: FirstRow,
}

impl NpyOptions {
    /// Options for a metre-valued DEM with the given spacing, first row north, no sentinel.
    pub fn metres(spacing_m: f64) -> Self {
        Self { spacing_m, height_scale: 1.0, nodata: None, first_row: FirstRow::North }
    }
}

/// Why a `.npy` file could not be read.
#[derive(Debug)]
pub enum NpyError {
    /// The file could not be read from disk.
    Io(std::io::Error),
    /// The first six bytes are not `\x93NUMPY`: not a NumPy array file.
    BadMagic,
    /// The file ends before the header or the data it announces.
    Truncated {
        /// Bytes needed.
        needed: usize,
        /// Bytes present.
        have: usize,
    },
    /// A format version this loader does not know (known: 1.0, 2.0, 3.0).
    UnsupportedVersion(u8, u8),
    /// The header dictionary is not parseable; the string says which part.
    BadHeader(String),
    /// The element type is not one of the supported numeric types.
    UnsupportedDtype(String),
    /// The array is not two-dimensional (or has a zero dimension).
    BadShape(Vec<usize>),
    /// `spacing_m` or `height_scale` is not a finite positive number.
    BadOptions(&'static str),
    /// A stored value that is finite but not once multiplied by `height_scale` (an overflow to infinity).
    HeightNotFinite {
        /// File row (as stored).
        row: usize,
        /// Column.
        col: usize,
        /// The stored value.
        value: f64,
    },
}

impl fmt::Display for NpyError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            NpyError::Io(e) => write!(f, "cannot read .npy file: {e}"),
            NpyError::BadMagic => write!(f, "not a NumPy .npy file (missing \\x93NUMPY magic)"),
            NpyError::Truncated { needed, have } => {
                write!(f, ".npy file truncated: needs {needed} bytes, has {have}")
            }
            NpyError::UnsupportedVersion(a, b) => {
                write!(f, ".npy format version {a}.{b} not supported (1.0, 2.0, 3.0 are)")
            }
            NpyError::BadHeader(s) => write!(f, ".npy header not understood: {s}"),
            NpyError::UnsupportedDtype(s) => {
                write!(f, ".npy dtype {s:?} not supported (use f4, f8, i1/i2/i4/i8 or u1/u2/u4)")
            }
            NpyError::BadShape(s) => write!(f, ".npy array shape {s:?} is not a non-empty 2-D grid"),
            NpyError::BadOptions(s) => write!(f, "bad .npy load options: {s}"),
            NpyError::HeightNotFinite { row, col, value } => write!(
                f,
                ".npy sample (file row {row}, column {col}) is {value}: times the height scale it is not a finite height; lower the height scale"
            ),
        }
    }
}

impl core::error::Error for NpyError {}

impl From<std::io::Error> for NpyError {
    fn from(e: std::io::Error) -> Self {
        NpyError::Io(e)
    }
}

/// Load a `.npy` file from disk.
pub fn load_npy(path: &Path, opts: &NpyOptions) -> Result<Heightmap, NpyError> {
    let bytes = std::fs::read(path)?;
    parse_npy(&bytes, opts)
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    F,
    I,
    U,
}

/// Parse `.npy` bytes.
pub fn parse_npy(bytes: &[u8], opts: &NpyOptions) -> Result<Heightmap, NpyError> {
    if !(opts.spacing_m.is_finite() && opts.spacing_m > 0.0) {
        return Err(NpyError::BadOptions("spacing_m must be finite and > 0"));
    }
    if !(opts.height_scale.is_finite() && opts.height_scale != 0.0) {
        return Err(NpyError::BadOptions("height_scale must be finite and non-zero"));
    }
    if bytes.len() < 8 {
        if bytes.len() >= 6 && &bytes[..6] != b"\x93NUMPY" {
            return Err(NpyError::BadMagic);
        }
        return Err(NpyError::Truncated { needed: 8, have: bytes.len() });
    }
    if &bytes[..6] != b"\x93NUMPY" {
        return Err(NpyError::BadMagic);
    }
    let (major, minor) = (bytes[6], bytes[7]);
    let (header_len, header_start) = match major {
        1 => {
            let b = bytes.get(8..10).ok_or(NpyError::Truncated { needed: 10, have: bytes.len() })?;
            (u16::from_le_bytes([b[0], b[1]]) as usize, 10usize)
        }
        2 | 3 => {
            let b = bytes.get(8..12).ok_or(NpyError::Truncated { needed: 12, have: bytes.len() })?;
            (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as usize, 12usize)
        }
        _ => return Err(NpyError::UnsupportedVersion(major, minor)),
    };
    let data_start = header_start
        .checked_add(header_len)
        .ok_or(NpyError::BadHeader("header length overflows".into()))?;
    let header_bytes = bytes
        .get(header_start..data_start)
        .ok_or(NpyError::Truncated { needed: data_start, have: bytes.len() })?;
    let header = core::str::from_utf8(header_bytes)
        .map_err(|_| NpyError::BadHeader("header is not UTF-8 / ASCII".into()))?;
    let descr = dict_value(header, "descr")?;
    let descr = descr.trim().trim_matches(|c| c == '\'' || c == '"');
    let fortran = dict_value(header, "fortran_order")?.trim().to_string();
    let fortran = match fortran.as_str() {
        "True" => true,
        "False" => false,
        other => return Err(NpyError::BadHeader(format!("fortran_order = {other:?}"))),
    };
    let shape = parse_shape(&dict_value(header, "shape")?)?;
    if shape.len() != 2 || shape.contains(&0) {
        return Err(NpyError::BadShape(shape));
    }
    let (rows, cols) = (shape[0], shape[1]);
    let (big_endian, kind, size) = parse_descr(descr)?;
    let count = rows.checked_mul(cols).ok_or_else(|| NpyError::BadShape(shape.clone()))?;
    let needed = count
        .checked_mul(size)
        .and_then(|n| n.checked_add(data_start))
        .ok_or_else(|| NpyError::BadShape(shape.clone()))?;
    if bytes.len() < needed {
        return Err(NpyError::Truncated { needed, have: bytes.len() });
    }
    let data = &bytes[data_start..needed];
    let mut heights = vec![None; count];
    for r in 0..rows {
        for c in 0..cols {
            let idx = if fortran { c * rows + r } else { r * cols + c };
            let raw = &data[idx * size..(idx + 1) * size];
            let v = decode(raw, big_endian, kind);
            let valid = v.is_finite() && opts.nodata.is_none_or(|nd| v != nd);
            let out_row = match opts.first_row {
                FirstRow::North => rows - 1 - r,
                FirstRow::South => r,
            };
            let h = v * opts.height_scale;
            if valid && !h.is_finite() {
                return Err(NpyError::HeightNotFinite { row: r, col: c, value: v });
            }
            heights[out_row * cols + c] = if valid { Some(h) } else { None };
        }
    }
    Ok(Heightmap { width: cols, height: rows, spacing_m: opts.spacing_m, heights_m: heights })
}

fn decode(raw: &[u8], big: bool, kind: Kind) -> f64 {
    let mut b = [0u8; 8];
    let n = raw.len();
    b[..n].copy_from_slice(raw);
    if big {
        b[..n].reverse();
    }
    match (kind, n) {
        (Kind::F, 4) => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (Kind::F, _) => f64::from_le_bytes(b),
        (Kind::I, 1) => b[0] as i8 as f64,
        (Kind::I, 2) => i16::from_le_bytes([b[0], b[1]]) as f64,
        (Kind::I, 4) => i32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
        (Kind::I, _) => i64::from_le_bytes(b) as f64,
        (Kind::U, 1) => b[0] as f64,
        (Kind::U, 2) => u16::from_le_bytes([b[0], b[1]]) as f64,
        (Kind::U, _) => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
    }
}

fn parse_descr(descr: &str) -> Result<(bool, Kind, usize), NpyError> {
    let bad = || NpyError::UnsupportedDtype(descr.to_string());
    let mut chars = descr.chars();
    let first = chars.next().ok_or_else(bad)?;
    let (big, rest) = match first {
        '<' | '=' | '|' => (false, chars.as_str()),
        '>' => (true, chars.as_str()),
        _ => (false, descr),
    };
    let (kind, size) = match rest {
        "f4" => (Kind::F, 4),
        "f8" => (Kind::F, 8),
        "i1" => (Kind::I, 1),
        "i2" => (Kind::I, 2),
        "i4" => (Kind::I, 4),
        "i8" => (Kind::I, 8),
        "u1" => (Kind::U, 1),
        "u2" => (Kind::U, 2),
        "u4" => (Kind::U, 4),
        _ => return Err(bad()),
    };
    Ok((big, kind, size))
}

/// The text of the value of `'key':` in a Python dict literal, up to the next top-level comma or closing brace.
fn dict_value(header: &str, key: &str) -> Result<String, NpyError> {
    let pat_single = format!("'{key}'");
    let pat_double = format!("\"{key}\"");
    let pos = header
        .find(&pat_single)
        .or_else(|| header.find(&pat_double))
        .ok_or_else(|| NpyError::BadHeader(format!("no {key:?} entry")))?;
    let after = &header[pos + pat_single.len()..];
    let colon = after.find(':').ok_or_else(|| NpyError::BadHeader(format!("no ':' after {key:?}")))?;
    let value = &after[colon + 1..];
    let mut depth = 0i32;
    let mut end = value.len();
    for (i, ch) in value.char_indices() {
        match ch {
            '(' | '[' => depth += 1,
            ')' | ']' => depth -= 1,
            ',' | '}' if depth == 0 => {
                end = i;
                break;
            }
            _ => {}
        }
        if depth < 0 {
            return Err(NpyError::BadHeader(format!("unbalanced brackets in {key:?}")));
        }
    }
    Ok(value[..end].to_string())
}

fn parse_shape(s: &str) -> Result<Vec<usize>, NpyError> {
    let t = s.trim();
    let inner = t
        .strip_prefix('(')
        .and_then(|x| x.strip_suffix(')'))
        .ok_or_else(|| NpyError::BadHeader(format!("shape {t:?} is not a tuple")))?;
    inner
        .split(',')
        .map(str::trim)
        .filter(|p| !p.is_empty())
        .map(|p| p.trim_end_matches('L').parse::<usize>().map_err(|_| NpyError::BadHeader(format!("shape entry {p:?}"))))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn build(descr: &str, shape: &str, fortran: bool, data: &[u8], version: u8) -> Vec<u8> {
        let mut header = format!(
            "{{'descr': '{descr}', 'fortran_order': {}, 'shape': {shape}, }}",
            if fortran { "True" } else { "False" }
        );
        let pre = if version == 1 { 10 } else { 12 };
        while (pre + header.len() + 1) % 64 != 0 {
            header.push(' ');
        }
        header.push('\n');
        let mut out = b"\x93NUMPY".to_vec();
        out.push(version);
        out.push(0);
        if version == 1 {
            out.extend_from_slice(&(header.len() as u16).to_le_bytes());
        } else {
            out.extend_from_slice(&(header.len() as u32).to_le_bytes());
        }
        out.extend_from_slice(header.as_bytes());
        out.extend_from_slice(data);
        out
    }

    fn f4(vals: &[f32], big: bool) -> Vec<u8> {
        vals.iter().flat_map(|v| if big { v.to_be_bytes() } else { v.to_le_bytes() }).collect()
    }

    #[test]
    fn c_order_first_row_north_is_flipped() {
        // rows: [1,2,3] (north), [4,5,6] (south)
        let b = build("<f4", "(2, 3)", false, &f4(&[1., 2., 3., 4., 5., 6.], false), 1);
        let h = parse_npy(&b, &NpyOptions::metres(2.0)).unwrap();
        assert_eq!((h.width, h.height, h.spacing_m), (3, 2, 2.0));
        assert_eq!(h.get(0, 0), Some(4.0)); // south-west
        assert_eq!(h.get(2, 1), Some(3.0)); // north-east
        let mut o = NpyOptions::metres(2.0);
        o.first_row = FirstRow::South;
        let h = parse_npy(&b, &o).unwrap();
        assert_eq!(h.get(0, 0), Some(1.0));
    }

    #[test]
    fn fortran_big_endian_f8_and_version_2() {
        // logical array [[1,2],[3,4]] stored column-major: 1,3,2,4
        let data: Vec<u8> = [1.0f64, 3.0, 2.0, 4.0].iter().flat_map(|v| v.to_be_bytes()).collect();
        let b = build(">f8", "(2, 2)", true, &data, 2);
        let mut o = NpyOptions::metres(1.0);
        o.first_row = FirstRow::South;
        let h = parse_npy(&b, &o).unwrap();
        assert_eq!(h.heights_m, vec![Some(1.0), Some(2.0), Some(3.0), Some(4.0)]);
    }

    /// Regression (fuzz target `npy`): a finite stored value times a huge height scale gave a height of +inf.
    #[test]
    fn a_height_infinite_after_scaling_is_rejected() {
        let data: Vec<u8> = [1i64, 2, 3, 4].iter().flat_map(|v| v.to_le_bytes()).collect();
        let b = build("<i8", "(2, 2)", false, &data, 1);
        assert!(parse_npy(&b, &NpyOptions::metres(1.0)).is_ok());
        let o = NpyOptions { height_scale: 1e308, ..NpyOptions::metres(1.0) };
        let e = parse_npy(&b, &o).unwrap_err();
        assert!(matches!(e, NpyError::HeightNotFinite { row: 0, col: 1, .. }), "{e}");
        assert!(e.to_string().contains("not a finite height"), "{e}");
    }

    #[test]
    fn int16_scale_nodata_and_nan() {
        let data: Vec<u8> = [10i16, -32768, 4, 6].iter().flat_map(|v| v.to_le_bytes()).collect();
        let b = build("<i2", "(1, 4)", false, &data, 1);
        let o = NpyOptions { spacing_m: 1.0, height_scale: 0.5, nodata: Some(-32768.0), first_row: FirstRow::South };
        let h = parse_npy(&b, &o).unwrap();
        assert_eq!(h.heights_m, vec![Some(5.0), None, Some(2.0), Some(3.0)]);
        let b = build("<f4", "(1, 2)", false, &f4(&[f32::NAN, 1.0], false), 1);
        let h = parse_npy(&b, &NpyOptions::metres(1.0)).unwrap();
        assert_eq!(h.heights_m, vec![None, Some(1.0)]);
    }

    #[test]
    fn bad_inputs_are_typed_errors() {
        let good = build("<f4", "(2, 2)", false, &f4(&[1., 2., 3., 4.], false), 1);
        let o = NpyOptions::metres(1.0);
        assert!(matches!(parse_npy(b"", &o), Err(NpyError::Truncated { .. })));
        assert!(matches!(parse_npy(b"PK\x03\x04zipfile", &o), Err(NpyError::BadMagic)));
        assert!(matches!(parse_npy(&good[..good.len() - 1], &o), Err(NpyError::Truncated { .. })));
        assert!(matches!(parse_npy(&good[..20], &o), Err(NpyError::Truncated { .. })));
        let mut v9 = good.clone();
        v9[6] = 9;
        assert!(matches!(parse_npy(&v9, &o), Err(NpyError::UnsupportedVersion(9, 0))));
        let b = build("<c16", "(2, 2)", false, &[0u8; 64], 1);
        assert!(matches!(parse_npy(&b, &o), Err(NpyError::UnsupportedDtype(_))));
        let b = build("<f4", "(4,)", false, &f4(&[1., 2., 3., 4.], false), 1);
        assert!(matches!(parse_npy(&b, &o), Err(NpyError::BadShape(_))));
        let b = build("<f4", "(0, 3)", false, &[], 1);
        assert!(matches!(parse_npy(&b, &o), Err(NpyError::BadShape(_))));
        let b = build("<f4", "(2, x)", false, &[], 1);
        assert!(matches!(parse_npy(&b, &o), Err(NpyError::BadHeader(_))));
        let b = build("<f4", "(99999999999, 99999999999)", false, &[], 1);
        assert!(matches!(parse_npy(&b, &o), Err(NpyError::BadShape(_) | NpyError::Truncated { .. })));
        assert!(matches!(parse_npy(&good, &NpyOptions::metres(0.0)), Err(NpyError::BadOptions(_))));
        let msg = format!("{}", NpyError::BadMagic);
        assert!(msg.contains("NUMPY"));
    }

    #[test]
    fn hirise_crop_loads() {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../shared/data/terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy");
        if !path.exists() {
            eprintln!("skipping: {} not present", path.display());
            return;
        }
        let h = load_npy(&path, &NpyOptions::metres(1.01)).unwrap();
        assert_eq!((h.width, h.height), (70, 120));
        assert!(h.heights_m.iter().all(|v| v.is_some()));
        // the first stored value (file row 0, column 0) lands on the north row after the flip
        let first = f32::from_le_bytes([0xe8, 0x13, 0x44, 0x44]) as f64;
        assert_eq!(h.get(0, 119), Some(first));
    }

    #[test]
    fn random_bytes_never_panic() {
        // a small deterministic fuzz: every prefix and byte-flip of a good file returns Ok or a typed error
        let good = build("<f4", "(3, 3)", false, &f4(&[1.; 9], false), 1);
        let o = NpyOptions::metres(1.0);
        for n in 0..good.len() {
            let _ = parse_npy(&good[..n], &o);
        }
        for i in 0..good.len() {
            for bit in [0x01u8, 0x20, 0x80] {
                let mut b = good.clone();
                b[i] ^= bit;
                let _ = parse_npy(&b, &o);
            }
        }
    }
}
