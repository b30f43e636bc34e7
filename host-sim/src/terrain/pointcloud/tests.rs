//! Reader tests: round trips through files written here, and bad-input fixtures built in code.

use super::pcd::parse_pcd;
use super::ply::parse_ply;
use super::*;

/// A few points with awkward values: negative, fractional, large, exactly representable in f32.
fn sample() -> Vec<[f64; 3]> {
    vec![[0.0, 0.0, 0.0], [1.5, -2.25, 3.0], [-1000.125, 0.5, 1e6], [7.0, 8.0, -9.5]]
}

#[derive(Clone, Copy)]
enum PlyKind {
    Ascii,
    Le,
    Be,
}

/// A PLY file: a `camera` element before the vertices (skipped), vertices with `x y z` as `double`, `float`,
/// `double` between other properties (a `uchar`, a list), and a face element after them.
fn ply(points: &[[f64; 3]], kind: PlyKind, declared: usize) -> Vec<u8> {
    let name = match kind {
        PlyKind::Ascii => "ascii",
        PlyKind::Le => "binary_little_endian",
        PlyKind::Be => "binary_big_endian",
    };
    let mut out = format!(
        "ply\nformat {name} 1.0\ncomment made by a test\nelement camera 1\nproperty short id\n\
         element vertex {declared}\nproperty double x\nproperty uchar red\nproperty float y\n\
         property list uchar int tags\nproperty double z\nelement face 1\nproperty list uchar int vertex_indices\n\
         end_header\n"
    )
    .into_bytes();
    let be = matches!(kind, PlyKind::Be);
    let put = |out: &mut Vec<u8>, le: &[u8]| {
        let mut b = le.to_vec();
        if be {
            b.reverse();
        }
        out.extend_from_slice(&b);
    };
    match kind {
        PlyKind::Ascii => {
            out.extend_from_slice(b"7\n");
            for (i, p) in points.iter().enumerate() {
                out.extend_from_slice(format!("{} 200 {} 2 {i} 9 {}\n\n", p[0], p[1] as f32, p[2]).as_bytes());
            }
            out.extend_from_slice(b"3 0 1 2\n");
        }
        PlyKind::Le | PlyKind::Be => {
            put(&mut out, &7i16.to_le_bytes());
            for (i, p) in points.iter().enumerate() {
                put(&mut out, &p[0].to_le_bytes());
                out.push(200);
                put(&mut out, &(p[1] as f32).to_le_bytes());
                out.push(2);
                put(&mut out, &(i as i32).to_le_bytes());
                put(&mut out, &9i32.to_le_bytes());
                put(&mut out, &p[2].to_le_bytes());
            }
            out.push(3);
            for v in [0i32, 1, 2] {
                put(&mut out, &v.to_le_bytes());
            }
        }
    }
    out
}

/// A PCD file with `x y z` (x as F8, y and z as F4), an `rgb` U4 field between them and a two-element `normal`.
fn pcd(points: &[[f64; 3]], binary: bool, declared: usize) -> Vec<u8> {
    let mut out = format!(
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x rgb y z normal\nSIZE 8 4 4 4 4\n\
         TYPE F U F F F\nCOUNT 1 1 1 1 2\nWIDTH {declared}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {declared}\n\
         DATA {}\n",
        if binary { "binary" } else { "ascii" }
    )
    .into_bytes();
    for p in points {
        if binary {
            out.extend_from_slice(&p[0].to_le_bytes());
            out.extend_from_slice(&0x00ff_8000u32.to_le_bytes());
            out.extend_from_slice(&(p[1] as f32).to_le_bytes());
            out.extend_from_slice(&(p[2] as f32).to_le_bytes());
            out.extend_from_slice(&[0u8; 8]);
        } else {
            out.extend_from_slice(format!("{} 16744448 {} {} 0 1\n", p[0], p[1] as f32, p[2] as f32).as_bytes());
        }
    }
    out
}

fn opts() -> PointCloudOptions {
    PointCloudOptions::default()
}

#[test]
fn ply_round_trips_ascii_and_both_binary_byte_orders() {
    let pts = sample();
    for kind in [PlyKind::Ascii, PlyKind::Le, PlyKind::Be] {
        let c = parse_ply(&ply(&pts, kind, pts.len()), &opts()).unwrap();
        assert_eq!(c.points, pts);
        assert_eq!(c.non_finite_skipped, 0);
    }
}

#[test]
fn pcd_round_trips_ascii_and_binary() {
    let pts = sample();
    for binary in [false, true] {
        let c = parse_pcd(&pcd(&pts, binary, pts.len()), &opts()).unwrap();
        assert_eq!(c.points, pts, "binary {binary}");
        assert_eq!(c.bounds(), Some(([-1000.125, -2.25, -9.5], [7.0, 8.0, 1e6])));
    }
}

#[test]
fn non_finite_points_are_skipped_and_counted() {
    let mut pts = sample();
    pts.insert(1, [f64::NAN, 0.0, 0.0]);
    pts.push([0.0, f64::INFINITY, 0.0]);
    for bytes in [ply(&pts, PlyKind::Le, pts.len()), ply(&pts, PlyKind::Ascii, pts.len())] {
        let c = parse_ply(&bytes, &opts()).unwrap();
        assert_eq!((c.points, c.non_finite_skipped), (sample(), 2));
    }
    let c = parse_pcd(&pcd(&pts, true, pts.len()), &opts()).unwrap();
    assert_eq!((c.points, c.non_finite_skipped), (sample(), 2));
    let nan = [[f64::NAN; 3]];
    let e = parse_pcd(&pcd(&nan, false, 1), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Empty { format: Format::Pcd, non_finite: 1 }), "{e}");
}

#[test]
fn wrong_magic_is_reported() {
    let pts = sample();
    let mut b = ply(&pts, PlyKind::Le, pts.len());
    b[0] = b'P';
    assert!(matches!(parse_ply(&b, &opts()), Err(PointCloudError::BadMagic { format: Format::Ply })));
    assert!(matches!(parse_pcd(b"\x89PNG\r\n", &opts()), Err(PointCloudError::BadMagic { format: Format::Pcd })));
    assert!(matches!(parse_pcd(b"", &opts()), Err(PointCloudError::BadMagic { .. })));
    let e = las::parse_las(b"LASG and more", &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::BadMagic { format: Format::Las }), "{e}");
}

#[test]
fn a_count_larger_than_the_data_is_an_error_before_allocation() {
    let pts = sample();
    let huge = 1usize << 40;
    for kind in [PlyKind::Ascii, PlyKind::Le] {
        let e = parse_ply(&ply(&pts, kind, huge), &PointCloudOptions { max_points: u64::MAX }).unwrap_err();
        assert!(matches!(e, PointCloudError::CountTooLarge { declared, .. } if declared == huge as u64), "{e}");
    }
    let e = parse_pcd(&pcd(&pts, true, huge), &PointCloudOptions { max_points: u64::MAX }).unwrap_err();
    assert!(matches!(e, PointCloudError::CountTooLarge { .. }), "{e}");
    assert!(e.to_string().contains("holds at most"), "{e}");
    // the limit comes first
    let e = parse_pcd(&pcd(&pts, true, huge), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::OverLimit { max: PointCloudOptions::DEFAULT_MAX_POINTS, .. }), "{e}");
}

#[test]
fn truncated_files_name_the_point_and_the_place() {
    let pts = sample();
    // binary: the last vertex loses its last 10 bytes (its list and z; the face goes too); the count check
    // passes (the vertices' least size, lists empty, fits) and the list skip finds the end
    let b = ply(&pts, PlyKind::Be, pts.len());
    let e = parse_ply(&b[..b.len() - 13 - 10], &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Truncated { point: 3, at: Position::Byte(_), .. }), "{e}");
    // ASCII: the vertex lines stop after three (each followed by a blank line); with two, the count check (two
    // bytes per value at least) would already see that four cannot fit
    let text = String::from_utf8(ply(&pts, PlyKind::Ascii, pts.len())).unwrap();
    let keep: Vec<&str> = text.lines().take(15 + 3 * 2).collect();
    let e = parse_ply(keep.join("\n").as_bytes(), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Truncated { point: 3, at: Position::Line(20), .. }), "{e}");
    assert!(e.to_string().contains("point 3 (after line 20)"), "{e}");
    let text = String::from_utf8(pcd(&pts, false, pts.len())).unwrap();
    let keep: Vec<&str> = text.lines().take(14).collect();
    let e = parse_pcd(keep.join("\n").as_bytes(), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Truncated { point: 3, at: Position::Line(14), .. }), "{e}");
    assert!(e.to_string().contains("line 14"), "{e}");
    let b = pcd(&pts, true, pts.len());
    assert!(matches!(parse_pcd(&b[..b.len() - 1], &opts()), Err(PointCloudError::CountTooLarge { fits: 3, .. })));
}

#[test]
fn malformed_headers_and_values_name_their_line() {
    let pts = sample();
    let text = String::from_utf8(ply(&pts, PlyKind::Ascii, pts.len())).unwrap();
    let bad = text.replace("property float y", "property float4 y");
    let e = parse_ply(bad.as_bytes(), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::BadHeader { line: 9, .. }), "{e}");
    let bad = text.replace("property double z", "property double w");
    assert!(matches!(parse_ply(bad.as_bytes(), &opts()), Err(PointCloudError::MissingAxis { axis: 'z', .. })));
    let bad = text.replace("1.5 200", "1.5x 200");
    let e = parse_ply(bad.as_bytes(), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::BadValue { line: 18, .. }), "{e}");
    assert!(e.to_string().contains("\"1.5x\""), "{e}");
    let bad = text.replace("end_header\n", "");
    assert!(matches!(parse_ply(bad.as_bytes(), &opts()), Err(PointCloudError::BadHeader { .. })));
    let text = String::from_utf8(pcd(&pts, false, pts.len())).unwrap();
    let bad = text.replace("DATA ascii", "DATA binary_compressed");
    let e = parse_pcd(bad.as_bytes(), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Unsupported { .. }) && e.to_string().contains("binary_compressed"), "{e}");
    let bad = text.replace("SIZE 8 4 4 4 4", "SIZE 8 4 4 4");
    assert!(matches!(parse_pcd(bad.as_bytes(), &opts()), Err(PointCloudError::BadHeader { line: 11, .. })));
    let bad = text.replace("POINTS 4", "POINTS 5");
    assert!(matches!(parse_pcd(bad.as_bytes(), &opts()), Err(PointCloudError::BadHeader { .. })));
    let bad = text.replace("FIELDS x rgb y z", "FIELDS x rgb y q");
    assert!(matches!(parse_pcd(bad.as_bytes(), &opts()), Err(PointCloudError::MissingAxis { axis: 'z', .. })));
    let bad = text.replace("16744448 -2.25", "16744448 -2.25 5");
    assert!(matches!(parse_pcd(bad.as_bytes(), &opts()), Err(PointCloudError::BadValue { .. })));
}

/// A LAS file written by the `las` crate, with a scale and an offset, read back through [`las::parse_las`].
fn las_bytes(points: &[[f64; 3]], compress: bool) -> Vec<u8> {
    let mut builder = ::las::Builder::from((1, 2));
    builder.transforms = ::las::Vector {
        x: ::las::Transform { scale: 0.001, offset: 1000.0 },
        y: ::las::Transform { scale: 0.001, offset: -50.0 },
        z: ::las::Transform { scale: 0.01, offset: 0.0 },
    };
    builder.point_format.is_compressed = compress;
    let header = builder.into_header().unwrap();
    let mut w = ::las::Writer::new(std::io::Cursor::new(Vec::new()), header).unwrap();
    for p in points {
        w.write_point(::las::Point { x: p[0], y: p[1], z: p[2], ..Default::default() }).unwrap();
    }
    w.into_inner().unwrap().into_inner()
}

#[test]
fn las_round_trips_with_scale_and_offset() {
    let pts = [[1000.5, -49.25, 3.5], [999.001, 0.0, -12.25], [1234.567, 10.125, 0.01]];
    let c = las::parse_las(&las_bytes(&pts, false), &opts()).unwrap();
    assert_eq!(c.points.len(), 3);
    for (a, b) in c.points.iter().zip(&pts) {
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-9, "{a:?} vs {b:?}");
        }
    }
    let b = las_bytes(&pts, false);
    // the point count at byte 107 (LAS 1.2 legacy count) raised: more than the file holds
    let mut lie = b.clone();
    lie[107..111].copy_from_slice(&1_000_000u32.to_le_bytes());
    let e = las::parse_las(&lie, &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::CountTooLarge { declared: 1_000_000, .. }), "{e}");
    let e = las::parse_las(&b[..b.len() - 5], &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::CountTooLarge { .. } | PointCloudError::Las(_)), "{e}");
    let e = las::parse_las(&b[..100], &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::Las(_)), "{e}");
}

#[test]
fn laz_round_trips() {
    let pts = [[1000.5, -49.25, 3.5], [999.001, 0.0, -12.25]];
    let c = las::parse_las(&las_bytes(&pts, true), &opts()).unwrap();
    assert_eq!(c.points.len(), 2);
    assert!((c.points[1][2] + 12.25).abs() < 1e-9);
}

#[test]
fn load_picks_the_reader_by_extension() {
    let dir = std::env::temp_dir().join(format!("tetherbot-pointcloud-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let pts = sample();
    for (name, bytes) in [("a.PLY", ply(&pts, PlyKind::Le, 4)), ("b.pcd", pcd(&pts, true, 4))] {
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        assert_eq!(load_point_cloud(&path, &opts()).unwrap().points, pts);
    }
    let e = load_point_cloud(&dir.join("c.xyz"), &opts()).unwrap_err();
    assert!(matches!(e, PointCloudError::UnknownExtension(ref x) if x == "xyz"), "{e}");
    assert!(matches!(load_point_cloud(&dir.join("missing.las"), &opts()), Err(PointCloudError::Io(_))));
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every prefix and many byte flips of good files: `Ok` or a typed error, never a panic (the fuzz targets go on).
#[test]
fn damaged_files_never_panic() {
    let pts = sample();
    let files: Vec<(Parser, Vec<u8>)> = vec![
        (parse_ply, ply(&pts, PlyKind::Ascii, 4)),
        (parse_ply, ply(&pts, PlyKind::Le, 4)),
        (parse_pcd, pcd(&pts, false, 4)),
        (parse_pcd, pcd(&pts, true, 4)),
        (las::parse_las, las_bytes(&pts, false)),
        (las::parse_las, las_bytes(&pts, true)),
    ];
    for (parse, good) in files {
        for n in 0..good.len() {
            let _ = parse(&good[..n], &opts());
        }
        for i in 0..good.len() {
            for bit in [0x01u8, 0x10, 0x80] {
                let mut b = good.clone();
                b[i] ^= bit;
                let _ = parse(&b, &opts());
            }
        }
    }
}
