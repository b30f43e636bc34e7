//! PLY (Stanford polygon file) reader: the `vertex` element's `x`, `y`, `z`.
//!
//! Header: `ply`, then `format ascii 1.0 | binary_little_endian 1.0 | binary_big_endian 1.0`, `comment` and
//! `obj_info` lines (ignored), `element NAME COUNT` and `property TYPE NAME` / `property list COUNT_TYPE ITEM_TYPE
//! NAME` lines, and `end_header`. Types: `char uchar short ushort int uint float double` and their sized names
//! (`int8` ... `float64`). `x`, `y`, `z` must be scalar properties of `vertex`, of any type; every other property
//! is skipped by its declared type (lists by their count). Elements before `vertex` are skipped instance by
//! instance; elements after it (faces, edges) are not read. ASCII data: one line per element instance (blank lines
//! skipped), exactly the declared values on it. Errors: see the module [`super`].

use super::{axis_slots, check_count, store, Format, PointCloud, PointCloudError, PointCloudOptions, Position, Scalar};

const F: Format = Format::Ply;

/// Parse PLY bytes.
pub fn parse_ply(bytes: &[u8], opts: &PointCloudOptions) -> Result<PointCloud, PointCloudError> {
    let header = parse_header(bytes)?;
    let mut cloud = PointCloud::default();
    match header.encoding {
        Encoding::Ascii => read_ascii(&header, bytes, opts, &mut cloud)?,
        Encoding::Binary { big_endian } => read_binary(&header, bytes, big_endian, opts, &mut cloud)?,
    }
    cloud.finish(F)
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Encoding {
    Ascii,
    Binary { big_endian: bool },
}

#[derive(Debug)]
enum Property {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

#[derive(Debug)]
struct Element {
    name: String,
    count: u64,
    props: Vec<(String, Property)>,
}

impl Element {
    /// Least bytes one instance takes: binary (lists empty), or ASCII (one digit and one separator per value).
    fn min_bytes(&self, encoding: Encoding) -> usize {
        self.props
            .iter()
            .map(|(_, p)| match (encoding, p) {
                (Encoding::Ascii, _) => 2,
                (Encoding::Binary { .. }, Property::Scalar(t) | Property::List { count: t, .. }) => t.size(),
            })
            .sum()
    }

    /// For each property, the coordinate it holds when this is the vertex element.
    fn axis_slots(&self, is_vertex: bool) -> Result<Vec<Option<usize>>, PointCloudError> {
        if !is_vertex {
            return Ok(vec![None; self.props.len()]);
        }
        axis_slots(F, self.props.iter().map(|(n, p)| (n.as_str(), matches!(p, Property::Scalar(_)))))
    }
}

struct Header {
    encoding: Encoding,
    elements: Vec<Element>,
    /// Byte offset of the first data byte.
    data_start: usize,
    /// 1-based line of the first data line.
    data_line: usize,
}

fn bad_header(line: usize, reason: impl Into<String>) -> PointCloudError {
    PointCloudError::BadHeader { format: F, line, reason: reason.into() }
}

fn scalar_type(name: &str, line: usize) -> Result<Scalar, PointCloudError> {
    Ok(match name {
        "char" | "int8" => Scalar::I8,
        "uchar" | "uint8" => Scalar::U8,
        "short" | "int16" => Scalar::I16,
        "ushort" | "uint16" => Scalar::U16,
        "int" | "int32" => Scalar::I32,
        "uint" | "uint32" => Scalar::U32,
        "float" | "float32" => Scalar::F32,
        "double" | "float64" => Scalar::F64,
        _ => return Err(bad_header(line, format!("unknown property type {name:?}"))),
    })
}

fn parse_header(bytes: &[u8]) -> Result<Header, PointCloudError> {
    if !(bytes.starts_with(b"ply\n") || bytes.starts_with(b"ply\r\n")) {
        return Err(PointCloudError::BadMagic { format: F });
    }
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut pos = 0usize;
    let mut line = 0usize;
    loop {
        let rest = bytes.get(pos..).unwrap_or_default();
        let Some(len) = rest.iter().position(|&b| b == b'\n') else {
            return Err(bad_header(line + 1, "the header ends without an end_header line"));
        };
        line += 1;
        let raw = rest.get(..len).unwrap_or_default();
        pos += len + 1;
        let text = core::str::from_utf8(raw).map_err(|_| bad_header(line, "not ASCII text"))?;
        let words: Vec<&str> = text.split_whitespace().collect();
        match words.as_slice() {
            ["ply"] if line == 1 => {}
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["format", kind, "1.0"] if encoding.is_none() => {
                encoding = Some(match *kind {
                    "ascii" => Encoding::Ascii,
                    "binary_little_endian" => Encoding::Binary { big_endian: false },
                    "binary_big_endian" => Encoding::Binary { big_endian: true },
                    other => return Err(bad_header(line, format!("unknown format {other:?}"))),
                });
            }
            ["element", name, count] => {
                let count = count.parse().map_err(|_| bad_header(line, format!("element count {count:?}")))?;
                elements.push(Element { name: (*name).to_string(), count, props: Vec::new() });
            }
            ["property", "list", count, item, name] => {
                let prop = Property::List { count: scalar_type(count, line)?, item: scalar_type(item, line)? };
                let el = elements.last_mut().ok_or_else(|| bad_header(line, "property before any element"))?;
                el.props.push(((*name).to_string(), prop));
            }
            ["property", ty, name] => {
                let prop = Property::Scalar(scalar_type(ty, line)?);
                let el = elements.last_mut().ok_or_else(|| bad_header(line, "property before any element"))?;
                el.props.push(((*name).to_string(), prop));
            }
            ["end_header"] => break,
            _ => return Err(bad_header(line, format!("not understood: {text:?}"))),
        }
    }
    let encoding = encoding.ok_or_else(|| bad_header(0, "no format line"))?;
    if !elements.iter().any(|e| e.name == "vertex") {
        return Err(bad_header(0, "no vertex element"));
    }
    Ok(Header { encoding, elements, data_start: pos, data_line: line + 1 })
}

/// The elements up to and including `vertex`, each with whether it is the vertex element.
fn elements_to_read(header: &Header) -> impl Iterator<Item = (&Element, bool)> {
    let last = header.elements.iter().position(|e| e.name == "vertex").unwrap_or(0);
    header.elements.iter().take(last + 1).map(|e| (e, e.name == "vertex"))
}

fn read_binary(
    header: &Header,
    bytes: &[u8],
    big_endian: bool,
    opts: &PointCloudOptions,
    cloud: &mut PointCloud,
) -> Result<(), PointCloudError> {
    let mut pos = header.data_start;
    for (el, is_vertex) in elements_to_read(header) {
        let min = el.min_bytes(header.encoding);
        if min == 0 {
            continue; // no properties: instances take no bytes
        }
        check_count(F, el.count, min, bytes.len().saturating_sub(pos), opts)?;
        let slots = el.axis_slots(is_vertex)?;
        if is_vertex {
            cloud.points.reserve(el.count as usize);
        }
        for point in 0..el.count {
            let truncated = |at: usize| PointCloudError::Truncated { format: F, point, at: Position::Byte(at) };
            let mut xyz = [0.0f64; 3];
            for (i, (_, prop)) in el.props.iter().enumerate() {
                match prop {
                    Property::Scalar(t) => {
                        let v = t.decode(bytes.get(pos..).unwrap_or_default(), big_endian).ok_or(truncated(pos))?;
                        store(&mut xyz, slots.get(i), v);
                        pos += t.size();
                    }
                    Property::List { count, item } => {
                        let n = count.decode(bytes.get(pos..).unwrap_or_default(), big_endian).ok_or(truncated(pos))?;
                        pos += count.size();
                        let skip = list_len(n).and_then(|n| n.checked_mul(item.size())).ok_or(truncated(pos))?;
                        pos = pos.checked_add(skip).filter(|&end| end <= bytes.len()).ok_or(truncated(pos))?;
                    }
                }
            }
            if is_vertex {
                cloud.push(xyz);
            }
        }
    }
    Ok(())
}

/// A list length as stored (a non-negative integer), `None` otherwise.
fn list_len(n: f64) -> Option<usize> {
    (n >= 0.0 && n.fract() == 0.0 && n <= u32::MAX as f64).then_some(n as usize)
}

fn read_ascii(
    header: &Header,
    bytes: &[u8],
    opts: &PointCloudOptions,
    cloud: &mut PointCloud,
) -> Result<(), PointCloudError> {
    let body = bytes.get(header.data_start..).unwrap_or_default();
    let mut lines = body
        .split(|&b| b == b'\n')
        .enumerate()
        .map(|(i, l)| (header.data_line + i, l))
        .filter(|(_, l)| l.iter().any(|b| !b.is_ascii_whitespace()));
    let mut bytes_left = body.len();
    let mut last_line = header.data_line;
    for (el, is_vertex) in elements_to_read(header) {
        if el.props.is_empty() {
            continue;
        }
        check_count(F, el.count, el.min_bytes(header.encoding), bytes_left, opts)?;
        let slots = el.axis_slots(is_vertex)?;
        if is_vertex {
            cloud.points.reserve(el.count as usize);
        }
        for point in 0..el.count {
            let (line, raw) =
                lines.next().ok_or(PointCloudError::Truncated { format: F, point, at: Position::Line(last_line) })?;
            last_line = line;
            bytes_left = bytes_left.saturating_sub(raw.len() + 1);
            let bad = |reason: String| PointCloudError::BadValue { format: F, line, reason };
            let text = core::str::from_utf8(raw).map_err(|_| bad("not ASCII text".into()))?;
            let mut tokens = text.split_whitespace();
            let mut next = |what: &str| -> Result<f64, PointCloudError> {
                let t = tokens.next().ok_or_else(|| bad(format!("{} ends before {what}", el.name)))?;
                t.parse::<f64>().map_err(|_| bad(format!("{what} = {t:?} is not a number")))
            };
            let mut xyz = [0.0f64; 3];
            for (i, (name, prop)) in el.props.iter().enumerate() {
                match prop {
                    Property::Scalar(_) => {
                        store(&mut xyz, slots.get(i), next(name)?);
                    }
                    Property::List { .. } => {
                        let n = next(name)?;
                        let n = list_len(n).ok_or_else(|| bad(format!("list length {n} of {name}")))?;
                        for _ in 0..n {
                            next(name)?;
                        }
                    }
                }
            }
            if tokens.next().is_some() {
                return Err(bad(format!("more values than the {} properties of {}", el.props.len(), el.name)));
            }
            if is_vertex {
                cloud.push(xyz);
            }
        }
    }
    Ok(())
}
