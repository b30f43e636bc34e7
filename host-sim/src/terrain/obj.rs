//! Wavefront OBJ triangle-mesh loader (shape models such as `shared/data/asteroids/*.obj`).
//!
//! Reads `v x y z [w]` vertex lines and `f` face lines. Face entries may be `i`, `i/t`, `i//n` or `i/t/n`, with
//! 1-based or negative (relative) indices; polygons with more than three corners are fan-triangulated. Comments
//! (`#`) and every other statement (`vn`, `vt`, `o`, `g`, `s`, `usemtl`, `mtllib`, ...) are ignored. A blank or
//! malformed number, an index out of range, a face with fewer than three corners, a degenerate face (repeated
//! corner) or an empty mesh is a typed [`ObjError`] carrying the 1-based line number.
//!
//! Units: OBJ has none. [`ObjOptions::scale`] multiplies every coordinate (`ObjOptions::KILOMETRES` = 1000 turns
//! the shape models' kilometres into metres).

use core::fmt;
use std::path::Path;

/// A triangle mesh in metres.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions, metres.
    pub vertices: Vec<[f64; 3]>,
    /// Triangles as indices into `vertices` (0-based), counter-clockwise as in the file.
    pub triangles: Vec<[u32; 3]>,
}

impl TriMesh {
    /// Axis-aligned bounds `(min, max)`; `None` for an empty mesh.
    pub fn bounds(&self) -> Option<([f64; 3], [f64; 3])> {
        let first = *self.vertices.first()?;
        let mut lo = first;
        let mut hi = first;
        for v in &self.vertices {
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        Some((lo, hi))
    }

    /// The three corner positions of triangle `t`.
    pub fn triangle(&self, t: usize) -> Option<[[f64; 3]; 3]> {
        let tri = self.triangles.get(t)?;
        Some([
            *self.vertices.get(tri[0] as usize)?,
            *self.vertices.get(tri[1] as usize)?,
            *self.vertices.get(tri[2] as usize)?,
        ])
    }
}

/// Loader options.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ObjOptions {
    /// Multiply every coordinate by this to get metres. Must be finite and > 0.
    pub scale: f64,
}

impl ObjOptions {
    /// Coordinates already in metres.
    pub const METRES: ObjOptions = ObjOptions { scale: 1.0 };
    /// Coordinates in kilometres (the asteroid shape models).
    pub const KILOMETRES: ObjOptions = ObjOptions { scale: 1000.0 };
}

/// Why an OBJ file could not be read.
#[derive(Debug)]
pub enum ObjError {
    /// The file could not be read from disk.
    Io(std::io::Error),
    /// The file is not UTF-8 text.
    NotText,
    /// A vertex line without three finite numbers.
    BadVertex {
        /// 1-based line number.
        line: usize,
    },
    /// A face entry that is not an integer index.
    BadFaceIndex {
        /// 1-based line number.
        line: usize,
    },
    /// A face index that is zero or refers to a vertex that does not exist (yet).
    IndexOutOfRange {
        /// 1-based line number.
        line: usize,
        /// The index as written.
        index: i64,
        /// Vertices defined so far.
        vertices: usize,
    },
    /// A face with fewer than three corners, or with a repeated corner.
    DegenerateFace {
        /// 1-based line number.
        line: usize,
    },
    /// No triangles in the file.
    Empty,
    /// The scale option is not a finite positive number.
    BadScale,
    /// Every triangle has zero area (all vertices coincide or lie on one line): the mesh has no surface a sensor
    /// could see.
    NoSurface,
}

impl fmt::Display for ObjError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ObjError::Io(e) => write!(f, "cannot read OBJ file: {e}"),
            ObjError::NotText => write!(f, "OBJ file is not UTF-8 text"),
            ObjError::BadVertex { line } => write!(f, "OBJ line {line}: vertex needs three numbers that stay finite times the scale"),
            ObjError::BadFaceIndex { line } => write!(f, "OBJ line {line}: face entry is not an integer index"),
            ObjError::IndexOutOfRange { line, index, vertices } => write!(
                f,
                "OBJ line {line}: face index {index} is out of range ({vertices} vertices defined so far)"
            ),
            ObjError::DegenerateFace { line } => {
                write!(f, "OBJ line {line}: face needs at least three distinct corners")
            }
            ObjError::Empty => write!(f, "OBJ file has no faces"),
            ObjError::BadScale => write!(f, "OBJ scale must be finite and > 0"),
            ObjError::NoSurface => write!(
                f,
                "OBJ mesh is degenerate: every triangle has zero area (coincident or collinear vertices, or a scale that rounds them together)"
            ),
        }
    }
}

impl core::error::Error for ObjError {}

impl From<std::io::Error> for ObjError {
    fn from(e: std::io::Error) -> Self {
        ObjError::Io(e)
    }
}

/// Load an OBJ file from disk.
pub fn load_obj(path: &Path, opts: &ObjOptions) -> Result<TriMesh, ObjError> {
    let bytes = std::fs::read(path)?;
    let text = core::str::from_utf8(&bytes).map_err(|_| ObjError::NotText)?;
    parse_obj(text, opts)
}

/// Parse OBJ text.
pub fn parse_obj(text: &str, opts: &ObjOptions) -> Result<TriMesh, ObjError> {
    if !(opts.scale.is_finite() && opts.scale > 0.0) {
        return Err(ObjError::BadScale);
    }
    let mut mesh = TriMesh::default();
    let mut corners: Vec<u32> = Vec::with_capacity(8);
    for (i, raw) in text.lines().enumerate() {
        let line = i + 1;
        let content = raw.split('#').next().unwrap_or("");
        let mut it = content.split_whitespace();
        match it.next() {
            Some("v") => {
                let mut p = [0.0f64; 3];
                for slot in &mut p {
                    let v: f64 = it
                        .next()
                        .and_then(|s| s.parse().ok())
                        .map(|v: f64| v * opts.scale)
                        // finite after scaling: a finite 1e300 times a scale of 1000 is +inf
                        .filter(|v| v.is_finite())
                        .ok_or(ObjError::BadVertex { line })?;
                    *slot = v;
                }
                mesh.vertices.push(p);
            }
            Some("f") => {
                corners.clear();
                for entry in it {
                    let idx_text = entry.split('/').next().unwrap_or("");
                    let idx: i64 = idx_text.parse().map_err(|_| ObjError::BadFaceIndex { line })?;
                    let n = mesh.vertices.len() as i64;
                    let zero_based = if idx > 0 { idx - 1 } else { n + idx };
                    if idx == 0 || zero_based < 0 || zero_based >= n || zero_based > u32::MAX as i64 {
                        return Err(ObjError::IndexOutOfRange { line, index: idx, vertices: n as usize });
                    }
                    corners.push(zero_based as u32);
                }
                if corners.len() < 3 {
                    return Err(ObjError::DegenerateFace { line });
                }
                let mut sorted = corners.clone();
                sorted.sort_unstable();
                if sorted.windows(2).any(|w| w[0] == w[1]) {
                    return Err(ObjError::DegenerateFace { line });
                }
                for k in 1..corners.len() - 1 {
                    mesh.triangles.push([corners[0], corners[k], corners[k + 1]]);
                }
            }
            _ => {}
        }
    }
    if mesh.triangles.is_empty() {
        return Err(ObjError::Empty);
    }
    let area = |t: &[u32; 3]| -> Option<f64> {
        let [a, b, c] = [mesh.vertices.get(t[0] as usize)?, mesh.vertices.get(t[1] as usize)?, mesh.vertices.get(t[2] as usize)?];
        let (u, v) = ([b[0] - a[0], b[1] - a[1], b[2] - a[2]], [c[0] - a[0], c[1] - a[1], c[2] - a[2]]);
        let n = [u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]];
        Some(0.5 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt())
    };
    if !mesh.triangles.iter().any(|t| area(t).is_some_and(|a| a > 0.0)) {
        return Err(ObjError::NoSurface);
    }
    Ok(mesh)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_vertices_faces_formats_and_scale() {
        let text = "# a quad and a triangle\nmtllib x.mtl\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0 1.0\nvn 0 0 1\n\
                    f 1/1/1 2/2/1 3/3/1 4/4/1\nf -4//1 -2//1 -1//1  # relative\n";
        let m = parse_obj(text, &ObjOptions::KILOMETRES).unwrap();
        assert_eq!(m.vertices.len(), 4);
        assert_eq!(m.vertices[2], [1000.0, 1000.0, 0.0]);
        assert_eq!(m.triangles, vec![[0, 1, 2], [0, 2, 3], [0, 2, 3]]);
        assert_eq!(m.bounds(), Some(([0.0, 0.0, 0.0], [1000.0, 1000.0, 0.0])));
        assert_eq!(m.triangle(1).map(|t| t[2]), Some([0.0, 1000.0, 0.0]));
        assert!(m.triangle(3).is_none());
    }

    #[test]
    fn bad_inputs_are_typed_errors_with_line_numbers() {
        let o = ObjOptions::METRES;
        assert!(matches!(parse_obj("v 0 0\nf 1 2 3\n", &o), Err(ObjError::BadVertex { line: 1 })));
        // regression (issue 24): a degenerate mesh loaded and map-check then saw 0 points with exit 0
        assert!(matches!(parse_obj("v 0 0 0\nv 1 1 1\nv 2 2 2\nf 1 2 3\n", &o), Err(ObjError::NoSurface)));
        assert!(matches!(parse_obj("v 0 0 0\nv 0 0 0\nv 0 0 0\nf 1 2 3\n", &o), Err(ObjError::NoSurface)));
        assert!(matches!(parse_obj("v 0 0 nan\n", &o), Err(ObjError::BadVertex { line: 1 })));
        let three = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        assert!(matches!(parse_obj(&format!("{three}f 1 2 x\n"), &o), Err(ObjError::BadFaceIndex { line: 4 })));
        assert!(matches!(
            parse_obj(&format!("{three}f 1 2 4\n"), &o),
            Err(ObjError::IndexOutOfRange { line: 4, index: 4, vertices: 3 })
        ));
        assert!(matches!(parse_obj(&format!("{three}f 0 1 2\n"), &o), Err(ObjError::IndexOutOfRange { .. })));
        assert!(matches!(parse_obj(&format!("{three}f -4 1 2\n"), &o), Err(ObjError::IndexOutOfRange { .. })));
        assert!(matches!(parse_obj(&format!("{three}f 1 2\n"), &o), Err(ObjError::DegenerateFace { line: 4 })));
        assert!(matches!(parse_obj(&format!("{three}f 1 2 2\n"), &o), Err(ObjError::DegenerateFace { .. })));
        assert!(matches!(parse_obj(three, &o), Err(ObjError::Empty)));
        assert!(matches!(parse_obj("", &o), Err(ObjError::Empty)));
        assert!(matches!(parse_obj(three, &ObjOptions { scale: -1.0 }), Err(ObjError::BadScale)));
        assert!(format!("{}", ObjError::Empty).contains("no faces"));
    }

    /// Regression (fuzz target `obj`): a finite coordinate that overflows to infinity when scaled was accepted.
    #[test]
    fn a_coordinate_infinite_after_scaling_is_rejected() {
        let text = "v 0 0 0\nv 1 0 0\nv 0 1 4e306\nf 1 2 3\n";
        assert!(parse_obj(text, &ObjOptions::METRES).is_ok());
        let e = parse_obj(text, &ObjOptions::KILOMETRES).unwrap_err();
        assert!(matches!(e, ObjError::BadVertex { line: 3 }), "{e}");
        assert!(e.to_string().contains("finite times the scale"), "{e}");
    }

    #[test]
    fn itokawa_shape_model_loads_in_metres() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/data/asteroids/itokawa.obj");
        if !path.exists() {
            eprintln!("skipping: {} not present", path.display());
            return;
        }
        let m = load_obj(&path, &ObjOptions::KILOMETRES).unwrap();
        assert_eq!(m.vertices.len(), 8112);
        assert_eq!(m.triangles.len(), 16220);
        let (lo, hi) = m.bounds().unwrap();
        // Itokawa is about 535 x 294 x 209 m (Fujiwara et al. 2006)
        let ext: Vec<f64> = (0..3).map(|k| hi[k] - lo[k]).collect();
        assert!((500.0..580.0).contains(&ext[0]), "{ext:?}");
        assert!((250.0..330.0).contains(&ext[1]), "{ext:?}");
        assert!((180.0..250.0).contains(&ext[2]), "{ext:?}");
    }
}
