//! Generates the fuzz seed corpora (`firmware/fuzz/gen_corpus.sh` runs this with `--ignored`), one directory per
//! target: for the protocol, one wire frame of every message kind (hand-built, and every kind a recorded protocol
//! run sends), and damaged variants; for the readers, small valid files of each format written here (a field
//! log, the shipped scenario files, a GeoTIFF, an Esri ASCII grid, a `.npy`, an OBJ, PLY and PCD point clouds, a
//! Moving AI map and scenario list; the real LAS/LAZ sample of `host-sim/tests/data/pointcloud`). Also checks, in the normal run, that every protocol seed deframes and decodes and that every
//! reader accepts its seeds (a seed the reader rejects would start the fuzzer off the valid path).

use firmware::config::protocol::MAX_ENCODED_FRAME_LEN;
use firmware::protocol::*;
use host_sim::fieldlog::{self, Direction};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::recording::RecordingLink;
use host_sim::scripted::{default_configure, run_protocol, synthetic_scan};
use std::collections::BTreeMap;
use std::path::Path;

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut rng = rand_pcg::Pcg64Mcg::new(1);
    let scan = synthetic_scan(1, 200, &mut rng);
    let msgs = vec![
        Message::TimeTick(TimeTick { host_time_us: 1000 }),
        Message::SensorChunk(scan[0].clone()),
        Message::TetherReading(TetherReading {
            time_us: 5,
            payout_m: 1.0,
            tension_n: 2.0,
            boom_angle_rad: 0.1,
        }),
        Message::GoalRequest(GoalRequest {
            goal_id: 1,
            position: Point3::new(1.0, 2.0, 3.0),
            tolerance_m: 0.5,
            planner: PlannerChoice::Abit,
            max_iterations: 10,
            time_budget_ms: 0,
            allow_approximate: false,
        }),
        Message::Configure(default_configure(1)),
        Message::Shutdown(Shutdown),
        Message::TelemetryRequest(TelemetryRequest),
        Message::Ack(Ack { seq: 1 }),
        Message::Nack(Nack {
            seq: 2,
            reason: NackReason::BadCrc,
        }),
        Message::PlanStatus(PlanStatus {
            goal_id: 1,
            state: PlanState::Searching,
            iterations: 3,
            best_cost: Some(1.5),
        }),
        Message::Plan(Plan {
            goal_id: 1,
            part: 0,
            parts: 1,
            waypoints: heapless::Vec::new(),
        }),
        Message::DriveCommand(DriveCommand {
            command_id: 1,
            motion: Motion::Straight { distance_m: 0.5 },
        }),
        Message::Log(Log {
            level: LogLevel::Info,
            text: heapless::String::try_from("hello").unwrap(),
        }),
        Message::MotionReport(MotionReport {
            command_id: 1,
            outcome: MotionOutcome::Completed,
            achieved_yaw_rad: 0.25,
            achieved_distance_m: 0.5,
            pose: Pose::IDENTITY,
        }),
        Message::GoalCancel(GoalCancel { goal_id: 1 }),
        // protocol v8: the team mission
        Message::TeamScanChunk(TeamScanChunk {
            command_id: 1,
            robot: 2,
            chunk_index: 0,
            chunk_count: 1,
            grip: Point3::new(1.0, 2.0, 3.0),
            up: Point3::new(0.0, 0.0, 1.0),
            hub: Point3::new(0.0, 0.0, 3.5),
            points: heapless::Vec::from_slice(&[Point3::new(1.0, 2.5, 3.0), Point3::new(0.5, 2.0, 3.1)]).unwrap(),
        }),
        Message::TeamReport(TeamReport {
            command_id: 2,
            event: TeamEvent::Landed { robot: 1, pos: Point3::new(4.0, 0.0, 0.0) },
            state: TeamState { grip: [GripState::Gripping; 4], legs_m: [4.0, 5.0, 6.0, 7.0] },
        }),
        Message::TeamCommand(TeamCommand { command_id: 3, goal_id: 1, order: TeamOrder::MoveHub { to: Point3::new(1.0, 0.0, 2.0) } }),
    ];
    let mut out = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
        let n = encode(i as u32, m, &mut buf).unwrap();
        buf.truncate(n);
        // the first byte of a fuzz input picks the split size
        let mut input = vec![7u8];
        input.extend_from_slice(&buf);
        out.push((format!("{:?}", m.kind()), input.clone()));
        let mut damaged = input.clone();
        let mid = damaged.len() / 2;
        damaged[mid] ^= 0x10;
        out.push((format!("{:?}-flipped", m.kind()), damaged));
    }
    out
}

#[test]
fn every_valid_seed_decodes() {
    for (name, input) in seeds().iter().filter(|(n, _)| !n.ends_with("flipped")) {
        let mut d = Deframer::new();
        let (_, ev) = d.push(&input[1..]);
        let frame = ev.unwrap().unwrap();
        assert!(decode_frame(frame).is_ok(), "{name}");
    }
}

/// A protocol run (the `record protocol` scenario) over the in-process link, recorded in memory.
fn recorded_protocol_run() -> Vec<u8> {
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: 1,
        config: "{\"scenario\":\"protocol\"}".into(),
    };
    let writer = fieldlog::Writer::new(Vec::new(), &header).unwrap();
    let mut rec = RecordingLink::new(InProcLink::new(DEFAULT_STEP_US), writer);
    let report = run_protocol(&mut rec, 1).unwrap();
    assert!(report.passed(), "{report}");
    rec.finish().unwrap().1
}

/// The first decoded frame of every (direction, kind) in a recorded log: the frames the two sides really send.
fn recorded_frames(log: &[u8]) -> BTreeMap<String, Vec<u8>> {
    let log = fieldlog::parse(log).unwrap();
    let mut out = BTreeMap::new();
    for dir in [Direction::HostToFlight, Direction::FlightToHost] {
        let mut d = Deframer::new();
        for r in log.records.iter().filter(|r| r.direction == dir) {
            let mut rest = &r.bytes[..];
            while !rest.is_empty() {
                let (n, ev) = d.push(rest);
                // the protocol run sends damaged frames on purpose (its bad-input cases); those are not seeds here
                if let Some(Ok((frame, Ok((_, m))))) = ev.map(|e| e.map(|f| (f, decode_frame(f)))) {
                    out.entry(format!("recorded-{dir:?}-{:?}", m.kind())).or_insert_with(|| frame.to_vec());
                }
                rest = &rest[n..];
            }
        }
    }
    out
}

/// `frame_decode`'s input for a decoded frame: the frame without its CRC (the target adds a correct one).
fn frame_decode_input(frame: &[u8]) -> Vec<u8> {
    frame[..frame.len() - 4].to_vec()
}

/// Small valid inputs for the reader targets, by target; the option-selector bytes each target reads first are 0
/// (scale 1, spacing from the file, no sentinel), and a few seeds set them otherwise.
fn reader_seeds(protocol_log: &[u8]) -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out = Vec::new();
    let with = |prefix: &[u8], body: &[u8]| [prefix, body].concat();
    // field log: the recorded protocol run cut to its first records (short inputs fuzz faster), read as it is
    // (first byte even) and a description of records that the target writes itself (first byte odd)
    let log = fieldlog::parse(protocol_log).unwrap();
    let mut w = fieldlog::Writer::new(Vec::new(), &log.header).unwrap();
    for r in log.records.iter().take(12) {
        w.append(r.direction, r.t_us, &r.bytes).unwrap();
    }
    let short = w.finish().unwrap();
    out.push(("fieldlog", "recorded-12".into(), with(&[0, 0, 0, 0, 0], &short)));
    out.push(("fieldlog", "described".into(), with(&[1, 0, 40, 4, 0], b"{}  \x00\x05\x04abcd\x01\x07\x02xy\x00\x00\x01z")));
    out.push(("fieldlog", "described-cut".into(), with(&[1, 1, 40, 4, 0], b"{}  \x00\x05\x04abcd\x01\x07\x02xy")));
    out.push(("fieldlog", "described-flip".into(), with(&[1, 2, 90, 4, 1], b"{}  \x00\x05\x04abcd\x01\x07\x02xy")));
    // scenarios: the shipped files
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios");
    let mut names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().path()).collect();
    names.sort();
    for p in names.iter().filter(|p| p.extension().is_some_and(|e| e == "toml")) {
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        out.push(("scenario", name, std::fs::read(p).unwrap()));
    }
    // GeoTIFF: 3 x 2 int16 and float32 DEMs with the pixel-scale and GDAL_NODATA tags
    out.push(("geotiff", "i16-tags".into(), with(&[0, 0, 0], &tiff_dem::<tiff::encoder::colortype::GrayI16>(&[1, 2, 3, 4, -9999, 6]))));
    out.push(("geotiff", "f32-tags".into(), with(&[0, 0, 0], &tiff_dem::<tiff::encoder::colortype::Gray32Float>(&[1.5, 2.0, 3.0, 4.0, -9999.0, 6.0]))));
    out.push(("geotiff", "f32-spacing-nodata".into(), with(&[1, 1, 1], &tiff_dem::<tiff::encoder::colortype::Gray32Float>(&[1.5, 2.0, 3.0, 4.0, -9999.0, 6.0]))));
    // Esri ASCII grid
    let asc = "ncols 3\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 2.5\nNODATA_value -9999\n1 2 3\n4 -9999 6\n";
    out.push(("asc", "3x2".into(), with(&[0], asc.as_bytes())));
    out.push(("asc", "3x2-half".into(), with(&[1], asc.replace("xllcorner 0\nyllcorner 0\n", "").as_bytes())));
    // NumPy: little-endian f4 (version 1) and big-endian i2 in Fortran order (version 2)
    let f4: Vec<u8> = [1.0f32, 2.0, 3.0, 4.0, 5.0, 6.0].iter().flat_map(|v| v.to_le_bytes()).collect();
    out.push(("npy", "f4".into(), with(&[0, 0, 0], &npy("<f4", "(2, 3)", false, &f4, 1))));
    let i2: Vec<u8> = [1i16, 3, 2, -9999].iter().flat_map(|v| v.to_be_bytes()).collect();
    out.push(("npy", "i2-fortran-nodata".into(), with(&[0, 0, 3], &npy(">i2", "(2, 2)", true, &i2, 2))));
    // OBJ: a tetrahedron, plain and with texture/normal indices and a negative (relative) index
    let obj = "# tetrahedron\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 3 1 4\n";
    out.push(("obj", "tetrahedron".into(), with(&[0], obj.as_bytes())));
    let obj2 = "o t\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvt 0 0\nf 1/1/1 2/1/1 -1/1/1\n";
    out.push(("obj", "slashes-relative".into(), with(&[1], obj2.as_bytes())));
    // point clouds (two selector bytes: point limit, thinning capacity): PLY ASCII and binary (big-endian, with a
    // list property and a face element), PCD ASCII and binary, and the real LAS/LAZ sample the readers' tests use
    let ply_ascii = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                     property uchar red\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n\
                     0 0 0 255\n1 0 0.5 0\n0 1 nan 7\n3 0 1 2\n";
    out.push(("ply", "ascii".into(), with(&[0, 3], ply_ascii.as_bytes())));
    let mut ply_be = b"ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\nproperty list uchar int n\n\
                       property float y\nproperty float z\nend_header\n"
        .to_vec();
    for (x, y, z) in [(1.0f64, 2.0f32, 3.0f32), (-4.0, 5.5, 0.25)] {
        ply_be.extend(x.to_be_bytes().into_iter().chain([1]).chain(9i32.to_be_bytes()));
        ply_be.extend(y.to_be_bytes().into_iter().chain(z.to_be_bytes()));
    }
    out.push(("ply", "binary-be-list".into(), with(&[0, 1], &ply_be)));
    let pcd_head = |data: &str| {
        format!("# .PCD v0.7\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\nTYPE F F F U\nCOUNT 1 1 1 1\nWIDTH 2\n\
                 HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 2\nDATA {data}\n")
    };
    out.push(("pcd", "ascii".into(), with(&[0, 1], format!("{}1 2 3 0\n-1 0.5 nan 255\n", pcd_head("ascii")).as_bytes())));
    let mut pcd_bin = pcd_head("binary").into_bytes();
    for v in [1.0f32, 2.0, 3.0, 0.0, -1.0, 0.5, 4.0, 0.0] {
        pcd_bin.extend(v.to_le_bytes());
    }
    out.push(("pcd", "binary".into(), with(&[0, 1], &pcd_bin)));
    let real = Path::new(env!("CARGO_MANIFEST_DIR")).join("../host-sim/tests/data/pointcloud");
    for name in ["simple.las", "simple.laz"] {
        out.push(("las", name.replace('.', "-"), with(&[0, 7], &std::fs::read(real.join(name)).unwrap())));
    }
    // Moving AI: a small map and two problems on it, separated by 0xFF
    let map = "type octile\nheight 4\nwidth 5\nmap\n.....\n.@@..\n..T..\n.....\n";
    let scen = "version 1\n0\tsmall.map\t5\t4\t0\t0\t4\t3\t6.41421356\n0\tsmall.map\t5\t4\t0\t3\t4\t0\t6.41421356\n";
    out.push(("movingai", "small".into(), [map.as_bytes(), &[0xFF], scen.as_bytes()].concat()));
    // retained tether checkpoint: a block with a wrapped tether written twice (both slots), and one slot only
    out.push(("retained", "two-slots".into(), retained_block(2).to_vec()));
    out.push(("retained", "one-slot".into(), retained_block(1).to_vec()));
    // terrain tile: the wire frames of a 20 x 20 tile (two chunks), then of a second tile after it
    out.push(("tile", "one-tile".into(), tile_frames(&[1])));
    out.push(("tile", "two-tiles".into(), tile_frames(&[1, 2])));
    out
}

/// What the `tile` target does with a seed (deframe, decode, reassemble in order, stage, load): at least one tile
/// loads, each the tile in use once complete.
fn tile_seed_loads(b: &[u8], what: &str) {
    use firmware::exec::Autonomy;
    let mut nav = firmware::nav::Navigator::new(
        firmware::config::map::MapConfig::with_voxel_size(0.1),
        vec![firmware::map::Block::EMPTY; 16],
        vec![0u32; 64],
        Box::default(),
    )
    .unwrap();
    let (mut d, mut a, now) = (Deframer::new(), TileAssembler::new(), hal::Instant::from_micros(0));
    let (mut rest, mut loaded) = (b, 0);
    while !rest.is_empty() {
        let (n, ev) = d.push(rest);
        rest = &rest[n..];
        let Some(Ok(frame)) = ev else { continue };
        let (_, Message::TileChunk(c)) = decode_frame(frame).expect(what) else { panic!("{what}") };
        c.validate().expect(what);
        let acc = a.accept(&c).expect(what);
        nav.tile_part(&acc.header, acc.offset, &c.heights, now);
        if acc.complete {
            nav.tile_complete(&acc.header, now).expect(what);
            loaded += 1;
            assert_eq!(nav.map_status().tile_id, acc.header.tile_id, "{what}");
        }
    }
    assert!(loaded >= 1, "{what}: no tile loaded");
}

/// The wire frames (COBS, as the link carries them) of the `TileChunk`s of 20 x 20-post tiles with ids `ids`, a
/// slope of 0.1 m per post along x.
fn tile_frames(ids: &[u32]) -> Vec<u8> {
    let spec = host_sim::homotopy::tile::TileSpec { origin: [-5.0, -5.0], resolution_m: 0.5, posts: [20, 20] };
    let heights: Vec<f32> = (0..400).map(|k| 0.1 * (k % 20) as f32).collect();
    let mut out = Vec::new();
    for &id in ids {
        for (i, c) in host_sim::homotopy::tile::tile_chunks(id, &spec, &heights).into_iter().enumerate() {
            let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
            let n = encode(i as u32, &Message::TileChunk(c), &mut buf).unwrap();
            out.extend_from_slice(&buf[..n]);
        }
    }
    out
}

/// A retained block after `writes` checkpoints of a tether wrapped once (root and one contact), with a ground patch
/// (flat, a hole of cells without ground).
fn retained_block(writes: u32) -> firmware::nav::retained::RetainedBlock {
    use firmware::geom::Vec3;
    use firmware::nav::retained::{write, GroundPatch, TetherCheckpoint, RETAINED_BYTES};
    use firmware::tether::{Anchor, AnchorHistory};
    let mut block = [0u8; RETAINED_BYTES];
    let root = Vec3::new(6.7, 0.0, 6.35);
    let mut anchors = AnchorHistory::new(Anchor::root(root));
    anchors.push(Anchor { point: Vec3::new(-2.5, 0.1, 4.6), gradient: Vec3::new(0.0, 1.0, 0.0) }).unwrap();
    let mut ground = GroundPatch::empty([-3.9, 0.1], 4.35);
    for k in (0..firmware::config::tether::GROUND_PATCH_CELLS).filter(|k| k % 5 != 0) {
        ground.set(k, 4.0);
    }
    for generation in 1..=writes {
        let cp = TetherCheckpoint {
            generation,
            root,
            anchors: anchors.clone(),
            body: None,
            payout_m: 9.5,
            goal_id: 1,
            ground: Some(ground.clone()),
        };
        write(&mut block, &cp);
    }
    block
}

/// A 3 x 2 GeoTIFF DEM written in memory with the pixel-scale (2.5 m) and GDAL_NODATA (-9999) tags.
fn tiff_dem<C: tiff::encoder::colortype::ColorType>(v: &[C::Inner]) -> Vec<u8>
where
    [C::Inner]: tiff::encoder::TiffValue,
{
    let mut buf = std::io::Cursor::new(Vec::new());
    let mut enc = tiff::encoder::TiffEncoder::new(&mut buf).unwrap();
    let mut img = enc.new_image::<C>(3, 2).unwrap();
    img.encoder().write_tag(tiff::tags::Tag::ModelPixelScaleTag, &[2.5f64, 2.5, 0.0][..]).unwrap();
    img.encoder().write_tag(tiff::tags::Tag::GdalNodata, "-9999").unwrap();
    img.write_data(v).unwrap();
    buf.into_inner()
}

/// A `.npy` file: magic, version, header dictionary padded to 64 bytes, data.
fn npy(descr: &str, shape: &str, fortran: bool, data: &[u8], version: u8) -> Vec<u8> {
    let order = if fortran { "True" } else { "False" };
    let mut header = format!("{{'descr': '{descr}', 'fortran_order': {order}, 'shape': {shape}, }}");
    let pre = if version == 1 { 10 } else { 12 };
    while (pre + header.len() + 1) % 64 != 0 {
        header.push(' ');
    }
    header.push('\n');
    let mut out = b"\x93NUMPY".to_vec();
    out.extend_from_slice(&[version, 0]);
    if version == 1 {
        out.extend_from_slice(&(header.len() as u16).to_le_bytes());
    } else {
        out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    }
    out.extend_from_slice(header.as_bytes());
    out.extend_from_slice(data);
    out
}

/// Every seed of every target: `(target, name, bytes)`.
fn all_seeds() -> Vec<(&'static str, String, Vec<u8>)> {
    let mut out: Vec<_> = seeds().into_iter().map(|(n, b)| ("deframe_decode", n, b)).collect();
    let log = recorded_protocol_run();
    for (name, frame) in recorded_frames(&log) {
        out.push(("frame_decode", name.clone(), frame_decode_input(&frame)));
        let mut wire = vec![0u8; MAX_ENCODED_FRAME_LEN];
        let n = stuff(&frame, &mut wire).unwrap();
        out.push(("deframe_decode", name, [&[7u8][..], &wire[..n]].concat()));
    }
    for (name, input) in seeds().into_iter().filter(|(n, _)| !n.ends_with("flipped")) {
        let mut d = Deframer::new();
        let (_, ev) = d.push(&input[1..]);
        out.push(("frame_decode", name, frame_decode_input(ev.unwrap().unwrap())));
    }
    out.extend(reader_seeds(&log));
    out
}

#[test]
fn the_recorded_run_gives_seeds_of_the_telemetry_kinds() {
    let frames = recorded_frames(&recorded_protocol_run());
    for kind in ["Telemetry", "MissionStatus", "Ack", "Configure", "SensorChunk"] {
        assert!(frames.keys().any(|k| k.ends_with(&format!("-{kind}"))), "no {kind} frame recorded: {:?}", frames.keys());
    }
}

#[test]
fn every_reader_accepts_its_seeds() {
    use host_sim::terrain::{asc, geotiff, npy, obj};
    let log = recorded_protocol_run();
    for (target, name, b) in reader_seeds(&log) {
        let what = format!("{target}/{name}");
        match target {
            "fieldlog" if b[0] == 0 => {
                let l = fieldlog::parse(&b[5..]).expect(&what);
                assert_eq!((l.records.len(), l.completeness()), (12, fieldlog::Completeness::Complete), "{what}");
            }
            "fieldlog" => {}
            "scenario" => {
                let sc = host_sim::scenario::parse(core::str::from_utf8(&b).unwrap(), Path::new("x.toml"));
                sc.expect(&what).world_spec().expect(&what);
            }
            "geotiff" => {
                let opts = geotiff::GeoTiffOptions::default();
                let h = geotiff::read_geotiff(std::io::Cursor::new(&b[3..]), &opts).expect(&what);
                assert_eq!((h.width, h.height, h.spacing_m, h.heights_m.iter().flatten().count()), (3, 2, 2.5, 5), "{what}");
            }
            "asc" => {
                let h = asc::parse_asc(core::str::from_utf8(&b[1..]).unwrap(), 1.0).expect(&what);
                assert_eq!((h.width, h.height, h.heights_m.iter().flatten().count()), (3, 2, 5), "{what}");
            }
            "npy" => {
                let mut o = npy::NpyOptions::metres(1.0);
                o.nodata = (b[2] == 3).then_some(-9999.0);
                let h = npy::parse_npy(&b[3..], &o).expect(&what);
                assert!(h.width * h.height >= 4, "{what}");
            }
            "obj" => {
                let m = obj::parse_obj(core::str::from_utf8(&b[1..]).unwrap(), &obj::ObjOptions::METRES).expect(&what);
                assert!(!m.triangles.is_empty(), "{what}");
            }
            "ply" | "pcd" | "las" => {
                use host_sim::terrain::pointcloud::{parser_for, PointCloudOptions};
                let c = parser_for(target).unwrap()(&b[2..], &PointCloudOptions::default()).expect(&what);
                assert!(c.points.len() as u64 + c.non_finite_skipped >= 2, "{what}");
            }
            "movingai" => {
                let i = b.iter().position(|&c| c == 0xFF).unwrap();
                let m = host_sim::movingai::parse_map(core::str::from_utf8(&b[..i]).unwrap()).expect(&what);
                let s = host_sim::movingai::parse_scen(core::str::from_utf8(&b[i + 1..]).unwrap()).expect(&what);
                let summary = host_sim::movingai::run_scenarios(&m, &s, |_, _| true).expect(&what);
                assert_eq!((summary.run, summary.mismatches.len()), (2, 0), "{what}: {summary:?}");
            }
            "retained" => {
                let block: firmware::nav::retained::RetainedBlock = b.as_slice().try_into().expect(&what);
                let got = firmware::nav::retained::read(&block);
                assert!(matches!(&got, firmware::nav::retained::Recovered::Valid(cp) if cp.anchors.len() == 2), "{what}: {got:?}");
            }
            "tile" => {
                // a thread with room for the navigator's planning storage, which `Box::default()` builds on the stack
                let (b, what) = (b.clone(), what.clone());
                std::thread::Builder::new()
                    .stack_size(64 << 20)
                    .spawn(move || tile_seed_loads(&b, &what))
                    .unwrap()
                    .join()
                    .unwrap();
            }
            other => panic!("seed for unknown target {other}"),
        }
    }
}

#[test]
#[ignore = "writes files; run by firmware/fuzz/gen_corpus.sh"]
fn write_fuzz_corpus() {
    let root = std::env::var("FUZZ_CORPUS_DIR").expect("FUZZ_CORPUS_DIR");
    let seeds = all_seeds();
    for (target, name, bytes) in &seeds {
        let dir = Path::new(&root).join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    println!("wrote {} seeds to {root}", seeds.len());
}
