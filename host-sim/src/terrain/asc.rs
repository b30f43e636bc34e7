//! Esri ASCII grid DEMs (`.asc`).
//!
//! Header keys (case-insensitive, one per line, any order): `ncols`, `nrows`, `cellsize`, optional
//! `xllcorner`/`xllcenter`, `yllcorner`/`yllcenter` (read, not used: the world is placed by the scenario),
//! optional `NODATA_value`. Then `nrows` rows of `ncols` numbers, north row first (rows may wrap over lines).
//! Samples equal to `NODATA_value` become `None`; heights are multiplied by `height_scale`.

use super::Heightmap;
use std::path::Path;

/// Why an ASCII grid could not be loaded: the line (1-based, 0 for the whole file) and the reason.
#[derive(Debug)]
pub enum AscError {
    /// The file could not be read.
    Io(std::io::Error),
    /// The content is malformed.
    Parse {
        /// 1-based line number (0 = whole file).
        line: usize,
        /// What is wrong.
        reason: String,
    },
}

impl core::fmt::Display for AscError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            AscError::Io(e) => write!(f, "cannot read file: {e}"),
            AscError::Parse { line, reason } => write!(f, "line {line}: {reason}"),
        }
    }
}

impl core::error::Error for AscError {}

/// Loads an Esri ASCII grid from a file.
pub fn load_asc(path: &Path, height_scale: f64) -> Result<Heightmap, AscError> {
    let text = std::fs::read_to_string(path).map_err(AscError::Io)?;
    parse_asc(&text, height_scale)
}

/// Parses an Esri ASCII grid.
pub fn parse_asc(text: &str, height_scale: f64) -> Result<Heightmap, AscError> {
    let err = |line: usize, reason: String| AscError::Parse { line, reason };
    if !(height_scale.is_finite() && height_scale != 0.0) {
        return Err(err(0, "height scale must be finite and non-zero".into()));
    }
    let mut ncols = None;
    let mut nrows = None;
    let mut cellsize = None;
    let mut nodata = None;
    let mut lines = text.lines().enumerate().peekable();
    while let Some((i, l)) = lines.peek().copied() {
        let mut it = l.split_whitespace();
        let Some(key) = it.next() else {
            lines.next();
            continue;
        };
        if key.parse::<f64>().is_ok() {
            break; // first data row
        }
        let val = it.next().ok_or_else(|| err(i + 1, format!("header key {key:?} has no value")))?;
        let num = || val.parse::<f64>().map_err(|_| err(i + 1, format!("{key} value {val:?} is not a number")));
        let count = || {
            val.parse::<usize>()
                .ok()
                .filter(|n| *n > 0)
                .ok_or_else(|| err(i + 1, format!("{key} must be a positive integer, got {val:?}")))
        };
        match key.to_ascii_lowercase().as_str() {
            "ncols" => ncols = Some(count()?),
            "nrows" => nrows = Some(count()?),
            "cellsize" => {
                let c = num()?;
                if !(c.is_finite() && c > 0.0) {
                    return Err(err(i + 1, format!("cellsize must be > 0, got {c}")));
                }
                cellsize = Some(c)
            }
            "nodata_value" => nodata = Some(num()?),
            "xllcorner" | "yllcorner" | "xllcenter" | "yllcenter" => {
                num()?;
            }
            _ => return Err(err(i + 1, format!("unknown header key {key:?}"))),
        }
        lines.next();
    }
    let ncols = ncols.ok_or_else(|| err(0, "missing header key ncols".into()))?;
    let nrows = nrows.ok_or_else(|| err(0, "missing header key nrows".into()))?;
    let cellsize = cellsize.ok_or_else(|| err(0, "missing header key cellsize".into()))?;
    let total = ncols.checked_mul(nrows).filter(|n| *n <= 100_000_000).ok_or_else(|| err(0, "grid too large".into()))?;
    let mut samples = Vec::with_capacity(total);
    for (i, l) in lines {
        for tok in l.split_whitespace() {
            let v: f64 = tok.parse().map_err(|_| err(i + 1, format!("sample {tok:?} is not a number")))?;
            if samples.len() == total {
                return Err(err(i + 1, format!("more than ncols x nrows = {total} samples")));
            }
            samples.push(v);
        }
    }
    if samples.len() != total {
        return Err(err(0, format!("{} samples, expected ncols x nrows = {total}", samples.len())));
    }
    let mut heights_m = Vec::with_capacity(total);
    for row in (0..nrows).rev() {
        for (col, s) in samples.iter().skip(row * ncols).take(ncols).enumerate() {
            let missing = s.is_nan() || nodata.is_some_and(|n| *s == n);
            if !missing && !(s * height_scale).is_finite() {
                // An infinite height is not "no data" (that is NODATA_value): the file is damaged.
                return Err(err(
                    0,
                    format!("sample (file row {row}, column {col}) is {s} (x height scale {height_scale}): heights must be finite; mark missing posts with NODATA_value"),
                ));
            }
            heights_m.push(if missing { None } else { Some(s * height_scale) });
        }
    }
    Ok(Heightmap { width: ncols, height: nrows, spacing_m: cellsize, heights_m })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FIXTURE: &str = "ncols 3\nNROWS 2\nxllcorner 100.0\nyllcorner 200.0\ncellsize 0.5\nNODATA_value -9999\n\
                           1 2 3\n4 -9999\n6\n";

    #[test]
    fn parses_header_rows_and_nodata() {
        let hm = parse_asc(FIXTURE, 2.0).unwrap();
        assert_eq!((hm.width, hm.height, hm.spacing_m), (3, 2, 0.5));
        assert_eq!(hm.get(0, 0), Some(8.0)); // south row = last file row
        assert_eq!(hm.get(1, 0), None);
        assert_eq!(hm.get(2, 1), Some(6.0));
    }

    #[test]
    fn a_height_scale_that_overflows_is_rejected() {
        let e = parse_asc("ncols 2\nnrows 1\ncellsize 1\n1e300 1\n", 1e10).unwrap_err().to_string();
        assert!(e.contains("must be finite"), "{e}");
    }

    #[test]
    fn file_round_trip() {
        let dir = std::env::temp_dir().join(format!("asc-test-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("t.asc");
        std::fs::write(&p, FIXTURE).unwrap();
        assert_eq!(load_asc(&p, 2.0).unwrap(), parse_asc(FIXTURE, 2.0).unwrap());
        assert!(matches!(load_asc(&dir.join("missing.asc"), 1.0), Err(AscError::Io(_))));
        std::fs::remove_dir_all(&dir).ok();
    }

    #[test]
    fn malformed_grids_name_the_line_and_reason() {
        let cases = [
            ("ncols 3\nnrows 1\ncellsize 1\n1 2\n", "expected"),
            ("ncols 3\nnrows 1\ncellsize 1\n1 2 x\n", "line 4"),
            ("ncols -3\nnrows 1\ncellsize 1\n1 2 3\n", "line 1"),
            ("ncols 3\nnrows 1\n1 2 3\n", "cellsize"),
            ("ncols 3\nnrows 1\ncellsize 0\n1 2 3\n", "cellsize must be > 0"),
            ("ncols 1\nnrows 1\ncellsize 1\nfoo 3\n1\n", "unknown header key"),
            ("ncols 1\nnrows 1\ncellsize 1\n1 2\n", "more than"),
            // regression (issue 24): +inf heights were accepted
            ("ncols 2\nnrows 1\ncellsize 1\n1 inf\n", "(file row 0, column 1) is inf"),
            ("ncols 2\nnrows 1\ncellsize 1\n-infinity 1\n", "heights must be finite"),
        ];
        for (text, want) in cases {
            let e = parse_asc(text, 1.0).unwrap_err().to_string();
            assert!(e.contains(want), "{text:?}: {e}");
        }
    }
}
