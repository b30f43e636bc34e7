//! Our hand-written code against maintained crates (issue 23, item 4): the tests behind the keep-or-switch table
//! of `host-sim/doc/crates.md`. Each crate is an independent oracle for one of ours:
//!
//! | ours | oracle |
//! |---|---|
//! | `firmware::protocol::cobs` | `cobs` 0.3.0 (the version postcard pulls in) |
//! | `host_sim::terrain::obj::parse_obj` | `tobj` 4 (`use_f64`) |
//! | `host_sim::terrain::npy::parse_npy` | `npyz` 0.9 |
//! | `host_sim::world::mesh::MeshWorld` | `parry3d-f64` 0.31 (the version rapier pulls in) |
//! | `firmware::plan::heap::IndexedHeap` | `std::collections::BinaryHeap` (lazy deletion) |
//!
//! Where ours and the crate differ on purpose, the test pins the difference exactly (so it fails if either side
//! changes) and the doc says why.
//!
//!     cargo test -p host-sim --test crate_oracles -- --nocapture   # prints the measured maxima

use firmware::plan::heap::{IndexedHeap, NOT_IN_HEAP};
use firmware::protocol::cobs::{self as ours_cobs, max_encoded_len, CobsError};
use host_sim::terrain::npy::{parse_npy, FirstRow, NpyError, NpyOptions};
use host_sim::terrain::obj::{parse_obj, ObjError, ObjOptions};
use host_sim::world::mesh::MeshWorld;
use npyz::WriterBuilder;
use parry3d_f64::query::{PointQuery, Ray, RayCast};
use proptest::prelude::*;

mod oracles;
use oracles::{parry_mesh, pv, shared_bytes, tobj_parse, Entry, HIRISE};

/// SplitMix64: seeded numbers for query points, independent of the code under test.
struct SplitMix(u64);
impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * ((self.next_u64() >> 11) as f64 / (1u64 << 53) as f64)
    }
    fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n as u64) as usize
    }
}

// ---------------------------------------------------------------------------------------------------------- COBS

fn ours_encode(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; max_encoded_len(data.len())];
    let n = ours_cobs::encode(data, &mut out).expect("max_encoded_len is enough");
    out.truncate(n);
    out
}

fn crate_encode(data: &[u8]) -> Vec<u8> {
    let mut out = vec![0u8; cobs::max_encoding_length(data.len())];
    let n = cobs::try_encode(data, &mut out).expect("max_encoding_length is enough");
    out.truncate(n);
    out
}

fn ours_decode(enc: &[u8]) -> Result<Vec<u8>, CobsError> {
    let mut out = vec![0u8; enc.len()];
    ours_cobs::decode(enc, &mut out).map(|n| out[..n].to_vec())
}

fn crate_decode(enc: &[u8]) -> Result<Vec<u8>, cobs::DecodeError> {
    let mut out = vec![0u8; enc.len()];
    cobs::decode(enc, &mut out).map(|n| out[..n].to_vec())
}

/// Length of the run of non-zero bytes that ends the input.
fn trailing_run(data: &[u8]) -> usize {
    data.iter().rev().take_while(|&&b| b != 0).count()
}

/// The two encoders agree byte for byte except in two cases, pinned here exactly:
/// - empty input: ours writes the one-block frame `[0x01]` (Cheshire & Baker: every frame is at least one block),
///   the crate writes nothing (an empty frame, which its own decoder then rejects as `EmptyFrame`);
/// - input ending in a non-zero run whose length is a positive multiple of 254: ours closes the last full block
///   with an empty block `0x01`, the crate leaves it off. Both decoders accept both forms.
fn check_cobs_agreement(data: &[u8]) {
    let (o, c) = (ours_encode(data), crate_encode(data));
    let run = trailing_run(data);
    if data.is_empty() {
        assert_eq!((o.as_slice(), c.as_slice()), (&[0x01u8][..], &[][..]));
    } else if run > 0 && run.is_multiple_of(254) {
        assert_eq!(o.len(), c.len() + 1, "len {}", data.len());
        assert_eq!((&o[..c.len()], o[c.len()]), (c.as_slice(), 0x01));
    } else {
        assert_eq!(o, c, "len {}", data.len());
    }
    assert!(o.len() <= max_encoded_len(data.len()) && !o.contains(&0));
    // Each decodes the other's output (the crate's empty frame aside, see above).
    assert_eq!(ours_decode(&o).as_deref(), Ok(data));
    assert_eq!(crate_decode(&o).as_deref(), Ok(data));
    assert_eq!(ours_decode(&c).as_deref(), Ok(data));
    if data.is_empty() {
        assert_eq!(crate_decode(&c), Err(cobs::DecodeError::EmptyFrame));
    } else {
        assert_eq!(crate_decode(&c).as_deref(), Ok(data));
    }
}

/// Bytes with zeros at a chosen rate, so both short and long zero-free runs occur.
fn cobs_input() -> impl Strategy<Value = Vec<u8>> {
    (0u8..=4, 0usize..1500).prop_flat_map(|(zero_rate, len)| {
        proptest::collection::vec(
            (0u8..16, 1u8..=255).prop_map(move |(r, b)| if r < zero_rate { 0 } else { b }),
            len,
        )
    })
}

#[test]
fn cobs_edge_cases_agree() {
    check_cobs_agreement(&[]);
    for n in 1..600 {
        check_cobs_agreement(&vec![0u8; n]);
    }
    for n in [1, 253, 254, 255, 256, 507, 508, 509, 762, 1024, 65536] {
        let run: Vec<u8> = (0..n).map(|i| (i % 255) as u8 + 1).collect();
        check_cobs_agreement(&run);
        for (pre, post) in [(true, false), (false, true), (true, true)] {
            let mut v = Vec::new();
            if pre {
                v.push(0);
            }
            v.extend_from_slice(&run);
            if post {
                v.push(0);
            }
            check_cobs_agreement(&v);
        }
    }
}

/// What each decoder does with a damaged frame.
#[derive(Debug, Default)]
struct CorruptTally {
    both_reject: usize,
    both_accept_same: usize,
    /// The crate accepted, ours rejected: every case must have a `0x00` in the frame (the crate ends the frame at
    /// the first zero and returns the prefix; ours reports `ZeroByte`).
    crate_only_with_zero: usize,
    /// Cut to nothing (see `classify_corrupt`).
    empty: usize,
}

fn classify_corrupt(frame: &[u8], tally: &mut CorruptTally) {
    if frame.is_empty() {
        // No blocks at all: ours decodes the empty message, the crate says `EmptyFrame`. The deframer never hands
        // ours an empty frame (two delimiters in a row are skipped), so the difference cannot reach the protocol.
        assert_eq!(
            (ours_decode(frame), crate_decode(frame)),
            (Ok(vec![]), Err(cobs::DecodeError::EmptyFrame))
        );
        tally.empty += 1;
        return;
    }
    match (ours_decode(frame), crate_decode(frame)) {
        (Err(_), Err(_)) => tally.both_reject += 1,
        (Ok(a), Ok(b)) => {
            assert_eq!(a, b, "{frame:?}");
            tally.both_accept_same += 1;
        }
        (Err(e), Ok(_)) => {
            assert!(
                frame.contains(&0) && e == CobsError::ZeroByte,
                "{frame:?}: ours {e:?}, crate accepted"
            );
            tally.crate_only_with_zero += 1;
        }
        (Ok(a), Err(e)) => panic!("{frame:?}: ours accepted {a:?}, crate {e:?}"),
    }
}

#[test]
fn cobs_damaged_frames_are_rejected_by_both_or_decoded_alike() {
    let mut rng = SplitMix(23);
    let mut tally = CorruptTally::default();
    for _ in 0..3000 {
        let len = rng.below(700) + 1;
        let data: Vec<u8> = (0..len)
            .map(|_| {
                if rng.below(40) == 0 {
                    0
                } else {
                    rng.below(255) as u8 + 1
                }
            })
            .collect();
        let enc = ours_encode(&data);
        // cut short: a strict prefix
        classify_corrupt(&enc[..rng.below(enc.len())], &mut tally);
        // one byte changed (possibly to zero)
        let mut flipped = enc.clone();
        let at = rng.below(enc.len());
        flipped[at] = if rng.below(4) == 0 {
            0
        } else {
            flipped[at].wrapping_add(rng.below(255) as u8 + 1)
        };
        classify_corrupt(&flipped, &mut tally);
    }
    // A truncated last block: both must say so.
    assert_eq!(ours_decode(&[0x05, 1, 2]), Err(CobsError::Truncated));
    assert!(matches!(
        crate_decode(&[0x05, 1, 2]),
        Err(cobs::DecodeError::InvalidFrame { .. })
    ));
    // A zero right after a complete block: the crate returns the first block as the whole frame, ours refuses.
    assert_eq!(
        crate_decode(&[0x02, 7, 0x00, 0x02, 9]).as_deref(),
        Ok(&[7u8][..])
    );
    assert_eq!(
        ours_decode(&[0x02, 7, 0x00, 0x02, 9]),
        Err(CobsError::ZeroByte)
    );
    eprintln!("COBS damaged frames: {tally:?}");
    assert!(
        tally.both_reject > 0 && tally.both_accept_same > 0 && tally.crate_only_with_zero > 0,
        "{tally:?}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]
    #[test]
    fn cobs_random_inputs_agree(data in cobs_input()) {
        check_cobs_agreement(&data);
    }
}

// ----------------------------------------------------------------------------------------------------------- OBJ

/// Same vertices (bit for bit) and the same triangles: tobj renumbers the vertices in order of first use, so the
/// index triples must agree up to a one-to-one renumbering, and every triangle corner must be the same point.
fn check_obj_agreement(rel: &str) {
    let text = String::from_utf8(shared_bytes(rel)).expect("UTF-8");
    let ours = parse_obj(&text, &ObjOptions::METRES).expect("ours parses");
    let models = tobj_parse(&text).expect("tobj parses");
    assert_eq!(models.len(), 1, "{rel}: one model (no o/g statements)");
    let m = &models[0].mesh;
    assert_eq!(m.positions.len() % 3, 0);
    assert_eq!(
        m.positions.len() / 3,
        ours.vertices.len(),
        "{rel}: vertex count"
    );
    assert_eq!(
        m.indices.len(),
        3 * ours.triangles.len(),
        "{rel}: triangle count"
    );
    assert!(m.face_arities.is_empty(), "tobj triangulated");
    let mut renumber = vec![u32::MAX; ours.vertices.len()];
    let mut used = vec![false; ours.vertices.len()];
    let mut max_ulps = 0u64;
    for (t, tri) in ours.triangles.iter().enumerate() {
        for (k, &o) in tri.iter().enumerate() {
            let (o, c) = (o as usize, m.indices[3 * t + k]);
            if renumber[o] == u32::MAX {
                assert!(
                    !used[c as usize],
                    "{rel}: tobj vertex {c} stands for two of ours"
                );
                renumber[o] = c;
                used[c as usize] = true;
            }
            assert_eq!(renumber[o], c, "{rel}: triangle {t} corner {k}");
            for a in 0..3 {
                let (x, y) = (ours.vertices[o][a], m.positions[3 * c as usize + a]);
                max_ulps = max_ulps.max(x.to_bits().abs_diff(y.to_bits()));
            }
        }
    }
    eprintln!(
        "OBJ {rel}: {} vertices, {} triangles, max difference {max_ulps} ulp",
        ours.vertices.len(),
        ours.triangles.len()
    );
    assert_eq!(
        max_ulps, 0,
        "{rel}: both read the decimal text with Rust's correctly rounded parse"
    );
}

#[test]
fn obj_itokawa_agrees_with_tobj() {
    check_obj_agreement("asteroids/itokawa.obj");
}

#[test]
fn obj_bennu_agrees_with_tobj() {
    check_obj_agreement("asteroids/bennu.obj");
}

/// Malformed files: both refuse; ours names the line, tobj names only the kind of error.
#[test]
fn obj_malformed_files_are_refused_by_both() {
    let text = String::from_utf8(shared_bytes("asteroids/itokawa.obj")).expect("UTF-8");
    let lines: Vec<&str> = text.lines().collect();
    // A vertex line cut after its first coordinate (the file truncated mid-line, then faces follow).
    let mut cut = lines.clone();
    cut[100] = "v -0.151021";
    let cut = cut.join("\n");
    let e = parse_obj(&cut, &ObjOptions::METRES).unwrap_err();
    assert!(matches!(e, ObjError::BadVertex { line: 101 }), "{e}");
    let t = tobj_parse(&cut).unwrap_err();
    eprintln!("OBJ cut vertex line: ours \"{e}\"; tobj \"{t}\"");
    // A face with a letter for an index.
    let mut bad = lines.clone();
    let f = lines
        .iter()
        .position(|l| l.starts_with("f "))
        .expect("a face")
        + 5;
    bad[f] = "f 1 2 x";
    let bad = bad.join("\n");
    let e = parse_obj(&bad, &ObjOptions::METRES).unwrap_err();
    assert!(
        matches!(e, ObjError::BadFaceIndex { line } if line == f + 1),
        "{e}"
    );
    let t = tobj_parse(&bad).unwrap_err();
    eprintln!("OBJ bad face index: ours \"{e}\"; tobj \"{t}\"");
    // The file truncated in the middle of the face list, mid-line: a face referring to a vertex never defined.
    let mut oob = lines.clone();
    oob[f] = "f 1 2 99999";
    let oob = oob.join("\n");
    let e = parse_obj(&oob, &ObjOptions::METRES).unwrap_err();
    assert!(
        matches!(e, ObjError::IndexOutOfRange { index: 99999, .. }),
        "{e}"
    );
    let t = tobj_parse(&oob).unwrap_err();
    eprintln!("OBJ face index out of range: ours \"{e}\"; tobj \"{t}\"");
    // The file truncated in the middle of its last face line, leaving two corners.
    let last = lines.len() - 1;
    let mut cut_face = lines[..last].to_vec();
    let two: Vec<&str> = lines[last].split_whitespace().take(3).collect();
    let two = two.join(" ");
    cut_face.push(&two);
    let cut_face = cut_face.join("\n");
    let e = parse_obj(&cut_face, &ObjOptions::METRES).unwrap_err();
    assert!(
        matches!(e, ObjError::DegenerateFace { line } if line == lines.len()),
        "{e}"
    );
    // tobj accepts it: the two-corner face becomes a triangle with a repeated corner, and the count is unchanged.
    let t = tobj_parse(&cut_face).expect("tobj accepts a two-corner face");
    let idx = &t[0].mesh.indices;
    let tail = &idx[idx.len() - 3..];
    assert_eq!(
        idx.len() / 3,
        lines.iter().filter(|l| l.starts_with("f ")).count()
    );
    assert!(
        tail[0] == tail[1] || tail[1] == tail[2] || tail[0] == tail[2],
        "{tail:?}"
    );
    eprintln!("OBJ last face cut to two corners: ours \"{e}\"; tobj accepts it as the degenerate triangle {tail:?}");
}

// --------------------------------------------------------------------------------------------------------- NumPy

fn south_first(spacing: f64) -> NpyOptions {
    NpyOptions {
        first_row: FirstRow::South,
        ..NpyOptions::metres(spacing)
    }
}

#[test]
fn npy_hirise_agrees_with_npyz() {
    let bytes = shared_bytes(HIRISE);
    let ours = parse_npy(&bytes, &south_first(1.0)).expect("ours parses");
    let file = npyz::NpyFile::new(&bytes[..]).expect("npyz reads the header");
    assert_eq!(file.shape(), &[ours.height as u64, ours.width as u64]);
    assert_eq!(file.order(), npyz::Order::C);
    let values: Vec<f32> = file.into_vec().expect("npyz reads the data");
    assert_eq!(values.len(), ours.heights_m.len());
    let mut compared = 0;
    for (i, (v, h)) in values.iter().zip(&ours.heights_m).enumerate() {
        match h {
            Some(h) => assert_eq!(h.to_bits(), (*v as f64).to_bits(), "sample {i}"),
            None => assert!(!v.is_finite(), "sample {i}: ours no-data, npyz {v}"),
        }
        compared += 1;
    }
    eprintln!(
        "NumPy HiRISE: {compared} samples, shape {:?}, all bit-equal",
        [ours.height, ours.width]
    );
}

/// Arrays written by npyz in each byte order, element type and storage order, read by ours.
#[test]
fn npy_arrays_written_by_npyz_are_read_alike() {
    let mut rng = SplitMix(7);
    let mut cases = 0;
    for order in [npyz::Order::C, npyz::Order::Fortran] {
        for descr in [
            "<f4", ">f4", "<f8", ">f8", "<i2", ">i4", "<i8", "|u1", ">u2", "<u4", "|i1",
        ] {
            let (rows, cols) = (rng.below(20) + 1, rng.below(20) + 1);
            // logical values in row-major order, exactly representable in every type used
            let logical: Vec<f64> = (0..rows * cols)
                .map(|_| {
                    let v = rng.below(200) as f64;
                    if descr.contains('f') {
                        v * 0.25 - 20.0
                    } else if descr.contains('u') {
                        v
                    } else {
                        v - 100.0
                    }
                })
                .collect();
            let storage: Vec<f64> = match order {
                npyz::Order::C => logical.clone(),
                npyz::Order::Fortran => (0..rows * cols)
                    .map(|k| logical[(k % rows) * cols + k / rows])
                    .collect(),
            };
            let bytes = write_npyz(descr, order, &[rows as u64, cols as u64], &storage);
            let h = parse_npy(&bytes, &south_first(0.5))
                .unwrap_or_else(|e| panic!("{descr} {order:?}: {e}"));
            assert_eq!((h.height, h.width), (rows, cols), "{descr} {order:?}");
            let got: Vec<f64> = h.heights_m.iter().map(|v| v.expect("finite")).collect();
            assert_eq!(got, logical, "{descr} {order:?}");
            cases += 1;
        }
    }
    eprintln!("NumPy synthetic: {cases} arrays (11 dtypes x C/Fortran) read alike");
}

fn write_npyz(descr: &str, order: npyz::Order, shape: &[u64], storage: &[f64]) -> Vec<u8> {
    fn write<T: npyz::Serialize>(
        descr: &str,
        order: npyz::Order,
        shape: &[u64],
        vals: impl Iterator<Item = T>,
    ) -> Vec<u8> {
        let mut out = Vec::new();
        let dtype = npyz::DType::Plain(descr.parse().expect("type string"));
        let mut w = npyz::WriteOptions::new()
            .dtype(dtype)
            .order(order)
            .shape(shape)
            .writer(&mut out)
            .begin_nd()
            .expect("npyz writer");
        w.extend(vals).expect("npyz write");
        w.finish().expect("npyz finish");
        out
    }
    let it = storage.iter().copied();
    match &descr[1..] {
        "f4" => write(descr, order, shape, it.map(|v| v as f32)),
        "f8" => write(descr, order, shape, it),
        "i1" => write(descr, order, shape, it.map(|v| v as i8)),
        "i2" => write(descr, order, shape, it.map(|v| v as i16)),
        "i4" => write(descr, order, shape, it.map(|v| v as i32)),
        "i8" => write(descr, order, shape, it.map(|v| v as i64)),
        "u1" => write(descr, order, shape, it.map(|v| v as u8)),
        "u2" => write(descr, order, shape, it.map(|v| v as u16)),
        "u4" => write(descr, order, shape, it.map(|v| v as u32)),
        other => panic!("no writer for {other}"),
    }
}

/// Malformed files: both refuse; ours says how many bytes were needed, npyz gives an I/O error.
#[test]
fn npy_malformed_files_are_refused_by_both() {
    let bytes = shared_bytes(HIRISE);
    let cut = &bytes[..bytes.len() - 100];
    let e = parse_npy(cut, &south_first(1.0)).unwrap_err();
    assert!(
        matches!(e, NpyError::Truncated { needed, have } if needed == bytes.len() && have == cut.len()),
        "{e}"
    );
    let t = npyz::NpyFile::new(cut)
        .and_then(|f| f.into_vec::<f32>())
        .unwrap_err();
    eprintln!("NumPy truncated data: ours \"{e}\"; npyz \"{t}\"");
    let mut bad = bytes.clone();
    let at = bytes
        .windows(7)
        .position(|w| w == b"'shape'")
        .expect("shape key");
    bad[at + 10] = b'x';
    let e = parse_npy(&bad, &south_first(1.0)).unwrap_err();
    assert!(matches!(e, NpyError::BadHeader(_)), "{e}");
    let t = npyz::NpyFile::new(&bad[..])
        .and_then(|f| f.into_vec::<f32>())
        .unwrap_err();
    eprintln!("NumPy bad shape entry: ours \"{e}\"; npyz \"{t}\"");
}

// ---------------------------------------------------------------------------------------------------------- Mesh

fn dist3(a: [f64; 3], b: parry3d_f64::math::Vector) -> f64 {
    ((a[0] - b.x).powi(2) + (a[1] - b.y).powi(2) + (a[2] - b.z).powi(2)).sqrt()
}

/// Tolerance on distances, closest points and ray parameters, metres, for a 535 m body (coordinates of a few
/// hundred metres: one f64 ulp is ~6e-14 m; two exact closest-point algorithms differ by rounding only).
const MESH_TOL_M: f64 = 1e-9;

#[test]
fn mesh_signed_distance_and_rays_agree_with_parry_on_itokawa() {
    let text = String::from_utf8(shared_bytes("asteroids/itokawa.obj")).expect("UTF-8");
    let mesh = parse_obj(&text, &ObjOptions::KILOMETRES).expect("itokawa");
    let ours = MeshWorld::new("itokawa", &mesh, 1.0).expect("mesh world");
    let theirs = parry_mesh(&mesh);
    let (lo, hi) = mesh.bounds().expect("bounds");
    let pad: Vec<f64> = (0..3).map(|k| 0.15 * (hi[k] - lo[k])).collect();
    let mut rng = SplitMix(2026);
    let mut queries: Vec<[f64; 3]> = (0..2000)
        .map(|_| core::array::from_fn(|k| rng.uniform(lo[k] - pad[k], hi[k] + pad[k])))
        .collect();
    // Near the surface, where sign errors live: a random point of a random triangle, pushed up to 2 m off it.
    for _ in 0..2000 {
        let [a, b, c] = mesh
            .triangle(rng.below(mesh.triangles.len()))
            .expect("triangle");
        let (mut u, mut v) = (rng.uniform(0.0, 1.0), rng.uniform(0.0, 1.0));
        if u + v > 1.0 {
            (u, v) = (1.0 - u, 1.0 - v);
        }
        let off: [f64; 3] = core::array::from_fn(|_| rng.uniform(-2.0, 2.0));
        queries.push(core::array::from_fn(|k| {
            a[k] + u * (b[k] - a[k]) + v * (c[k] - a[k]) + off[k]
        }));
    }
    let (mut max_d, mut max_q, mut inside) = (0.0f64, 0.0f64, 0usize);
    for p in &queries {
        let (sd, q) = ours.sdf_closest(*p);
        let proj = theirs.project_local_point(pv(*p), false);
        let d = dist3(*p, proj.point);
        max_d = max_d.max((sd.abs() - d).abs());
        max_q = max_q.max(dist3(q, proj.point));
        assert_eq!(
            sd < 0.0,
            proj.is_inside,
            "{p:?}: ours {sd}, parry distance {d} inside {}",
            proj.is_inside
        );
        inside += usize::from(sd < 0.0);
    }
    eprintln!(
        "Mesh SDF: {} points ({inside} inside), max |distance difference| {max_d:.3e} m, max closest-point gap {max_q:.3e} m, sign agrees on all",
        queries.len()
    );
    assert!(
        max_d <= MESH_TOL_M && max_q <= MESH_TOL_M,
        "{max_d} {max_q}"
    );
    assert!(
        inside > 200 && inside < queries.len() - 200,
        "both signs are exercised: {inside}"
    );

    // Rays: random origins and directions in the padded box, and rays from outside aimed at a random surface point.
    let mut rays: Vec<([f64; 3], [f64; 3])> = Vec::new();
    for i in 0..2000 {
        let o: [f64; 3] = core::array::from_fn(|k| rng.uniform(lo[k] - pad[k], hi[k] + pad[k]));
        let d: [f64; 3] = if i % 2 == 0 {
            core::array::from_fn(|_| rng.uniform(-1.0, 1.0))
        } else {
            let [a, b, c] = mesh
                .triangle(rng.below(mesh.triangles.len()))
                .expect("triangle");
            core::array::from_fn(|k| (a[k] + b[k] + c[k]) / 3.0 - o[k])
        };
        let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
        rays.push((o, d.map(|x| x / n)));
    }
    let (mut hits, mut max_t) = (0usize, 0.0f64);
    for (o, d) in &rays {
        let a = ours.first_hit(*o, *d, 1000.0);
        let b = theirs.cast_local_ray(&Ray::new(pv(*o), pv(*d)), 1000.0, false);
        match (a, b) {
            (Some(a), Some(b)) => {
                max_t = max_t.max((a - b).abs());
                hits += 1;
            }
            (None, None) => {}
            _ => panic!("ray {o:?} {d:?}: ours {a:?}, parry {b:?}"),
        }
    }
    eprintln!(
        "Mesh rays: {} rays ({hits} hit), hit/miss agrees on all, max |t difference| {max_t:.3e} m",
        rays.len()
    );
    assert!(max_t <= MESH_TOL_M, "{max_t}");
    assert!(
        hits > 500 && hits < rays.len() - 200,
        "hits and misses are exercised: {hits}"
    );
}

// ------------------------------------------------------------------------------------------------ Priority queue

/// A Dijkstra-like run (push, decrease-key, pop) on the one indexed heap of the planners and on std's
/// `BinaryHeap` with lazy deletion: the same ids leave in the same order.
#[test]
fn indexed_heap_pops_like_std_binary_heap() {
    const N: usize = 1024;
    let mut rng = SplitMix(17);
    for _round in 0..20 {
        let mut items: Vec<Entry> = (0..N)
            .map(|_| Entry {
                key: 0,
                pos: NOT_IN_HEAP,
            })
            .collect();
        let mut ours: IndexedHeap<N> = IndexedHeap::new();
        let mut std_heap = std::collections::BinaryHeap::new();
        // The lazy-deletion side's own record: the current key of each queued id.
        let mut std_key: Vec<Option<u64>> = vec![None; N];
        let (mut out_ours, mut out_std) = (Vec::new(), Vec::new());
        for step in 0..4 * N {
            let id = rng.below(N) as u32;
            if step % 3 == 2 {
                if let Some(x) = ours.pop(&mut items[..]) {
                    out_ours.push(x);
                }
                while let Some(core::cmp::Reverse((k, x))) = std_heap.pop() {
                    if std_key[x as usize] == Some(k) {
                        std_key[x as usize] = None;
                        out_std.push(x);
                        break;
                    }
                }
            } else if !ours.contains(id, &items[..]) {
                let k = rng.next_u64() % 5000;
                items[id as usize].key = k;
                ours.push(id, &mut items[..]).expect("capacity N");
                std_heap.push(core::cmp::Reverse((k, id)));
                std_key[id as usize] = Some(k);
            } else {
                // decrease-key
                let k = items[id as usize].key.saturating_sub(rng.next_u64() % 100);
                items[id as usize].key = k;
                ours.update(id, &mut items[..]);
                std_heap.push(core::cmp::Reverse((k, id)));
                std_key[id as usize] = Some(k);
            }
        }
        assert!(out_ours.len() > N / 2);
        assert_eq!(out_ours, out_std);
    }
}
