//! PCD (Point Cloud Library point cloud data, v0.6/v0.7) reader: the `x`, `y`, `z` fields.
//!
//! Header lines (`#` comments skipped): `VERSION` (optional), `FIELDS`, `SIZE`, `TYPE` (`F` with size 4 or 8;
//! `I`/`U` with size 1, 2, 4 or 8), `COUNT` (optional, default 1 each), `WIDTH`, `HEIGHT`, `VIEWPOINT` (ignored),
//! `POINTS` (default `WIDTH * HEIGHT`; both given and different is an error), and `DATA ascii | binary` last.
//! The first non-comment line must be `VERSION` or `FIELDS` (the "magic"). `DATA binary_compressed` is
//! [`PointCloudError::Unsupported`]. Binary data is little-endian and point-interleaved, as PCL writes it; ASCII
//! data is one point per line (blank lines skipped) with exactly the declared values. The coordinate is the first
//! element of the `x`, `y` and `z` fields; every other field is skipped by `SIZE * COUNT`. NaN coordinates (PCL's
//! "no return" in organized clouds) are skipped and counted. Errors: see the module [`super`].

use super::{axis_slots, check_count, store, Format, PointCloud, PointCloudError, PointCloudOptions, Position, Scalar};

const F: Format = Format::Pcd;

/// Parse PCD bytes.
pub fn parse_pcd(bytes: &[u8], opts: &PointCloudOptions) -> Result<PointCloud, PointCloudError> {
    let h = parse_header(bytes)?;
    let record: usize = h.fields.iter().map(|f| f.ty.size() * f.count).sum();
    let slots = axis_slots(F, h.fields.iter().map(|f| (f.name.as_str(), f.count >= 1)))?;
    let body = bytes.get(h.data_start..).unwrap_or_default();
    let min = if h.binary { record } else { 2 * h.fields.iter().map(|f| f.count).sum::<usize>() };
    check_count(F, h.points, min, body.len(), opts)?;
    let mut cloud = PointCloud::default();
    cloud.points.reserve(h.points as usize);
    if h.binary {
        for (point, rec) in (0..h.points).zip(body.chunks(record.max(1))) {
            let mut xyz = [0.0f64; 3];
            let mut at = 0usize;
            for (i, f) in h.fields.iter().enumerate() {
                let v = f.ty.decode(rec.get(at..).unwrap_or_default(), false).ok_or(PointCloudError::Truncated {
                    format: F,
                    point,
                    at: Position::Byte(h.data_start + point as usize * record + at),
                })?;
                store(&mut xyz, slots.get(i), v);
                at += f.ty.size() * f.count;
            }
            cloud.push(xyz);
        }
    } else {
        read_ascii(&h, body, &slots, &mut cloud)?;
    }
    cloud.finish(F)
}

#[derive(Debug)]
struct Field {
    name: String,
    ty: Scalar,
    count: usize,
}

struct Header {
    fields: Vec<Field>,
    points: u64,
    binary: bool,
    data_start: usize,
    /// 1-based line of the first data line.
    data_line: usize,
}

fn bad_header(line: usize, reason: impl Into<String>) -> PointCloudError {
    PointCloudError::BadHeader { format: F, line, reason: reason.into() }
}

fn numbers<T: core::str::FromStr>(values: &[&str], line: usize, key: &str) -> Result<Vec<T>, PointCloudError> {
    values.iter().map(|v| v.parse().map_err(|_| bad_header(line, format!("{key} value {v:?}")))).collect()
}

fn one_number(values: &[&str], line: usize, key: &str) -> Result<u64, PointCloudError> {
    match numbers::<u64>(values, line, key)?.as_slice() {
        [n] => Ok(*n),
        _ => Err(bad_header(line, format!("{key} needs one number"))),
    }
}

fn parse_header(bytes: &[u8]) -> Result<Header, PointCloudError> {
    let (mut names, mut sizes, mut types, mut counts): (Vec<String>, Vec<usize>, Vec<char>, Option<Vec<usize>>) =
        (Vec::new(), Vec::new(), Vec::new(), None);
    let (mut width, mut height, mut points) = (None, None, None);
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut seen_key = false;
    let binary = loop {
        let rest = bytes.get(pos..).unwrap_or_default();
        let len = rest.iter().position(|&b| b == b'\n').unwrap_or(rest.len());
        if rest.is_empty() {
            return Err(if seen_key {
                bad_header(line + 1, "the header ends without a DATA line")
            } else {
                PointCloudError::BadMagic { format: F }
            });
        }
        line += 1;
        pos += len + 1;
        let text = core::str::from_utf8(rest.get(..len).unwrap_or_default());
        let Ok(text) = text else {
            return Err(if seen_key {
                bad_header(line, "not ASCII text")
            } else {
                PointCloudError::BadMagic { format: F }
            });
        };
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let mut words = text.split_whitespace();
        let key = words.next().unwrap_or_default();
        let values: Vec<&str> = words.collect();
        if !seen_key && key != "VERSION" && key != "FIELDS" {
            return Err(PointCloudError::BadMagic { format: F });
        }
        seen_key = true;
        match key {
            "VERSION" | "VIEWPOINT" => {}
            "FIELDS" => names = values.iter().map(|s| (*s).to_string()).collect(),
            "SIZE" => sizes = numbers(&values, line, key)?,
            "TYPE" => {
                types = values
                    .iter()
                    .map(|t| match t.as_bytes() {
                        [c @ (b'F' | b'I' | b'U')] => Ok(char::from(*c)),
                        _ => Err(bad_header(line, format!("TYPE {t:?} (F, I, U are known)"))),
                    })
                    .collect::<Result<_, _>>()?
            }
            "COUNT" => counts = Some(numbers(&values, line, key)?),
            "WIDTH" => width = Some(one_number(&values, line, key)?),
            "HEIGHT" => height = Some(one_number(&values, line, key)?),
            "POINTS" => points = Some(one_number(&values, line, key)?),
            "DATA" => match values.as_slice() {
                ["ascii"] => break false,
                ["binary"] => break true,
                ["binary_compressed"] => {
                    return Err(PointCloudError::Unsupported { format: F, what: "DATA binary_compressed".into() })
                }
                _ => return Err(bad_header(line, format!("DATA {values:?} (ascii, binary are read)"))),
            },
            other => return Err(bad_header(line, format!("unknown header key {other:?}"))),
        }
    };
    let n = names.len();
    let counts = counts.unwrap_or_else(|| vec![1; n]);
    if n == 0 || sizes.len() != n || types.len() != n || counts.len() != n {
        return Err(bad_header(
            line,
            format!(
                "FIELDS ({n}), SIZE ({}), TYPE ({}) and COUNT ({}) must name the same non-zero number of fields",
                sizes.len(),
                types.len(),
                counts.len()
            ),
        ));
    }
    let mut fields = Vec::with_capacity(n);
    for (((name, size), ty), count) in names.into_iter().zip(sizes).zip(types).zip(counts) {
        let ty = match (ty, size) {
            ('F', 4) => Scalar::F32,
            ('F', 8) => Scalar::F64,
            ('I', 1) => Scalar::I8,
            ('I', 2) => Scalar::I16,
            ('I', 4) => Scalar::I32,
            ('I', 8) => Scalar::I64,
            ('U', 1) => Scalar::U8,
            ('U', 2) => Scalar::U16,
            ('U', 4) => Scalar::U32,
            ('U', 8) => Scalar::U64,
            _ => return Err(bad_header(line, format!("field {name:?}: TYPE {ty} with SIZE {size}"))),
        };
        if count > 1 << 16 {
            return Err(bad_header(line, format!("field {name:?}: COUNT {count} (at most 65536)")));
        }
        fields.push(Field { name, ty, count });
    }
    let grid = match (width, height) {
        (Some(w), Some(h)) => w.checked_mul(h),
        (Some(w), None) => Some(w),
        _ => None,
    };
    let points = match (points, grid) {
        (Some(p), Some(g)) if p != g => {
            return Err(bad_header(line, format!("POINTS {p} differs from WIDTH x HEIGHT = {g}")));
        }
        (Some(p), _) | (None, Some(p)) => p,
        (None, None) => return Err(bad_header(line, "neither POINTS nor WIDTH/HEIGHT given")),
    };
    Ok(Header { fields, points, binary, data_start: pos.min(bytes.len()), data_line: line + 1 })
}

fn read_ascii(h: &Header, body: &[u8], slots: &[Option<usize>], cloud: &mut PointCloud) -> Result<(), PointCloudError> {
    let mut lines = body
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (h.data_line + i, l))
        .filter(|(_, l)| l.iter().any(|b| !b.is_ascii_whitespace()));
    let mut last_line = h.data_line;
    for point in 0..h.points {
        let (line, raw) =
            lines.next().ok_or(PointCloudError::Truncated { format: F, point, at: Position::Line(last_line) })?;
        last_line = line;
        let bad = |reason: String| PointCloudError::BadValue { format: F, line, reason };
        let text = core::str::from_utf8(raw).map_err(|_| bad("not ASCII text".into()))?;
        let mut tokens = text.split_whitespace();
        let mut xyz = [0.0f64; 3];
        for (i, f) in h.fields.iter().enumerate() {
            for k in 0..f.count {
                let t = tokens.next().ok_or_else(|| bad(format!("the line ends before field {}", f.name)))?;
                let v: f64 = t.parse().map_err(|_| bad(format!("field {} = {t:?} is not a number", f.name)))?;
                if k == 0 {
                    store(&mut xyz, slots.get(i), v);
                }
            }
        }
        if tokens.next().is_some() {
            return Err(bad("more values than the header's fields".into()));
        }
        cloud.push(xyz);
    }
    Ok(())
}
