//! The rover's scene for Foxglove (issue 23): field logs and mission runs exported to MCAP
//! (<https://mcap.dev>) with Foxglove's well-known protobuf schemas, written and served by the Foxglove SDK
//! (the `foxglove` crate), so a viewer shows the rover, its scans, plans and tether in 3D, plots and logs.
//!
//! One [`Scene`] turns the link's bytes into channels; the export feeds it a field log's records, `mission
//! --live` feeds it the running link ([`SceneLink`]) with a WebSocket server as the sink. What the wire says
//! (pose estimates, scans, plans, tether readings, status, telemetry, logs) is the same in both; a mission run
//! adds what only the simulator knows (the true pose, tether, path and terrain) with [`Scene::truth`].
//!
//! Channels (`host-sim/doc/foxglove.md` has the panels that show them):
//! - `/link/host_to_flight`, `/link/flight_to_host`: the raw recorded bytes (encoding `tetherbot-wire-v1`, COBS
//!   frames as sent), one message per field-log record;
//! - `/frames/host_to_flight`, `/frames/flight_to_host`: each decoded frame as schemaless JSON
//!   (`{"seq", "kind", "body"}`, or `{"error"}` for a frame that does not decode);
//! - `/tf` (`foxglove.FrameTransforms`): `world` to `rover` (the pose estimate of each `MotionReport`), `world`
//!   to `sensor` (each scan's sensor pose) and, in a mission run, `world` to `rover_true` (the true pose of each
//!   executed increment);
//! - `/scans` (`foxglove.PointCloud`): each complete range scan (its chunks joined), in the `world` frame with the
//!   sensor pose as the cloud's pose;
//! - `/scene/wire` (`foxglove.SceneUpdate`): the root anchor, the goal, every plan (`plan/0` planned, `plan/1..`
//!   replanned) with its tether (a line from the root through the plan's anchors, anchors as spheres), the path
//!   of the pose estimates;
//! - `/scene/truth` (mission runs): the true terrain (a triangle mesh from the world's height field), the rocks,
//!   the executed path, the true tether through its contacts at each snapshot of the run;
//! - plottable series (JSON with a JSON schema): `/tether/reading` (payout, tension, boom angle),
//!   `/mission/status` (board margin, tension, payouts, cross-track, replans), `/telemetry` (map blocks, frames,
//!   scans), `/truth/series` (true margin, tension, payout, distance driven);
//! - `/log` (`foxglove.Log`): the flight software's `Log` frames.
//!
//! Log time is the recorded link time in nanoseconds (the mission starts at 0). The field-log header goes into
//! an MCAP metadata record `tetherbot-field-log`.

use std::collections::BTreeMap;
use std::io::{Seek, Write};
use std::sync::Arc;

use firmware::protocol::{self, Deframer, LogLevel, Message, Waypoint};
use foxglove::messages::{
    log::Level, packed_element_field::NumericType, Color, CubePrimitive, FrameTransform,
    FrameTransforms, LinePrimitive, Log, PackedElementField, Point3, PointCloud, Pose, Quaternion,
    SceneEntity, SceneUpdate, SpherePrimitive, Timestamp, TriangleListPrimitive, Vector3,
};
use foxglove::{Channel, Context, FoxgloveError, PartialMetadata, RawChannel, Schema};

use crate::fieldlog::{Direction, FieldLog};
use crate::link::{FlightLink, LinkError};
use crate::mission::run::MissionReport;
use crate::world::World;

/// Channel topics.
pub mod topic {
    /// Raw bytes, host to flight.
    pub const RAW_H2F: &str = "/link/host_to_flight";
    /// Raw bytes, flight to host.
    pub const RAW_F2H: &str = "/link/flight_to_host";
    /// Decoded frames (JSON), host to flight.
    pub const FRAMES_H2F: &str = "/frames/host_to_flight";
    /// Decoded frames (JSON), flight to host.
    pub const FRAMES_F2H: &str = "/frames/flight_to_host";
    /// Frame transforms.
    pub const TF: &str = "/tf";
    /// Range scans.
    pub const SCANS: &str = "/scans";
    /// What the wire says, as scene primitives.
    pub const SCENE_WIRE: &str = "/scene/wire";
    /// What only the simulator knows, as scene primitives.
    pub const SCENE_TRUTH: &str = "/scene/truth";
    /// Tether readings (series).
    pub const TETHER: &str = "/tether/reading";
    /// Mission status (series).
    pub const STATUS: &str = "/mission/status";
    /// Telemetry (series).
    pub const TELEMETRY: &str = "/telemetry";
    /// The truth along the executed path (series).
    pub const TRUTH_SERIES: &str = "/truth/series";
    /// Flight log frames.
    pub const LOG: &str = "/log";
}

/// Frame ids.
pub mod frame {
    /// The world (scenario) frame.
    pub const WORLD: &str = "world";
    /// The rover's body by its pose estimate.
    pub const ROVER: &str = "rover";
    /// The range sensor of the last scan.
    pub const SENSOR: &str = "sensor";
    /// The rover's true body (mission runs).
    pub const ROVER_TRUE: &str = "rover_true";
}

/// Counts of what was written.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ExportStats {
    /// Raw byte records written.
    pub raw_records: usize,
    /// Decoded frames written.
    pub frames: usize,
    /// Frames that did not decode (written as errors).
    pub bad_frames: usize,
    /// Complete scans written as point clouds.
    pub scans: usize,
    /// Scans whose chunks did not all arrive in order (not drawn; their chunks are in `/frames`).
    pub broken_scans: usize,
    /// Rover pose estimates written (`MotionReport`s).
    pub poses: usize,
    /// Complete plans drawn.
    pub plans: usize,
    /// Flight log frames written.
    pub logs: usize,
    /// True poses written (mission runs).
    pub true_poses: usize,
}

/// The decoded body of a message as JSON.
pub fn message_json(m: &Message) -> serde_json::Value {
    let body = match m {
        Message::TimeTick(b) => serde_json::to_value(b),
        Message::SensorChunk(b) => serde_json::to_value(b),
        Message::TetherReading(b) => serde_json::to_value(b),
        Message::GoalRequest(b) => serde_json::to_value(b),
        Message::Configure(b) => serde_json::to_value(b),
        Message::Shutdown(b) => serde_json::to_value(b),
        Message::TelemetryRequest(b) => serde_json::to_value(b),
        Message::Ack(b) => serde_json::to_value(b),
        Message::Nack(b) => serde_json::to_value(b),
        Message::PlanStatus(b) => serde_json::to_value(b),
        Message::Plan(b) => serde_json::to_value(b),
        Message::DriveCommand(b) => serde_json::to_value(b),
        Message::Telemetry(b) => serde_json::to_value(b),
        Message::Log(b) => serde_json::to_value(b),
        Message::MotionReport(b) => serde_json::to_value(b),
        Message::GoalCancel(b) => serde_json::to_value(b),
        Message::TileChunk(b) => serde_json::to_value(b),
        Message::MissionStatus(b) => serde_json::to_value(b),
        Message::TeamConfigure(b) => serde_json::to_value(b),
        Message::TeamScanChunk(b) => serde_json::to_value(b),
        Message::TeamReport(b) => serde_json::to_value(b),
        Message::TeamCommand(b) => serde_json::to_value(b),
    };
    body.unwrap_or(serde_json::Value::Null)
}

/// A JSON channel whose messages are flat objects of the named fields (a JSON schema, so the Plot panel offers
/// them and a reader can validate them).
fn series_channel(
    ctx: &Arc<Context>,
    topic: &str,
    name: &str,
    fields: &[(&str, &str)],
) -> Result<Arc<RawChannel>, FoxgloveError> {
    let props: serde_json::Map<String, serde_json::Value> = fields
        .iter()
        .map(|(f, t)| (f.to_string(), serde_json::json!({ "type": t })))
        .collect();
    let required: Vec<&str> = fields.iter().map(|(f, _)| *f).collect();
    let schema = serde_json::json!({
        "title": name,
        "type": "object",
        "properties": props,
        "required": required,
        "additionalProperties": false,
    });
    ctx.channel_builder(topic)
        .message_encoding("json")
        .schema(Schema::new(
            name,
            "jsonschema",
            serde_json::to_vec(&schema).unwrap_or_default(),
        ))
        .build_raw()
}

fn log_raw(ch: &RawChannel, bytes: &[u8], t_ns: u64) {
    ch.log_with_meta(bytes, PartialMetadata::with_log_time(t_ns));
}

fn stamp(t_ns: u64) -> Timestamp {
    Timestamp::new((t_ns / 1_000_000_000) as u32, (t_ns % 1_000_000_000) as u32)
}

fn v3(x: f64, y: f64, z: f64) -> Vector3 {
    Vector3 { x, y, z }
}

fn p3(p: [f64; 3]) -> Point3 {
    Point3 {
        x: p[0],
        y: p[1],
        z: p[2],
    }
}

fn wire_p3(p: &protocol::Point3) -> Point3 {
    Point3 {
        x: f64::from(p.x),
        y: f64::from(p.y),
        z: f64::from(p.z),
    }
}

fn rgba(r: f64, g: f64, b: f64, a: f64) -> Color {
    Color { r, g, b, a }
}

fn wire_pose(p: &protocol::Pose) -> Pose {
    let (t, q) = (&p.position, &p.orientation);
    Pose {
        position: Some(v3(f64::from(t.x), f64::from(t.y), f64::from(t.z))),
        orientation: Some(Quaternion {
            x: f64::from(q.x),
            y: f64::from(q.y),
            z: f64::from(q.z),
            w: f64::from(q.w),
        }),
    }
}

fn at(p: [f64; 3]) -> Pose {
    Pose {
        position: Some(v3(p[0], p[1], p[2])),
        orientation: Some(Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0,
        }),
    }
}

fn sphere(p: [f64; 3], diameter: f64, color: Color) -> SpherePrimitive {
    SpherePrimitive {
        pose: Some(at(p)),
        size: Some(v3(diameter, diameter, diameter)),
        color: Some(color),
    }
}

fn line(points: Vec<Point3>, thickness: f64, color: Color) -> LinePrimitive {
    LinePrimitive {
        r#type: foxglove::messages::line_primitive::Type::LineStrip as i32,
        pose: Some(at([0.0; 3])),
        thickness,
        scale_invariant: false,
        points,
        color: Some(color),
        colors: vec![],
        indices: vec![],
    }
}

fn entity(t_ns: u64, id: String) -> SceneEntity {
    SceneEntity {
        timestamp: Some(stamp(t_ns)),
        frame_id: frame::WORLD.into(),
        id,
        ..Default::default()
    }
}

/// Colours of successive plans (the first planned, the rest replanned).
const PLAN_COLOURS: [(f64, f64, f64); 4] = [
    (0.1, 0.8, 0.2),
    (0.1, 0.6, 0.9),
    (0.9, 0.5, 0.1),
    (0.8, 0.2, 0.8),
];
/// Diameter of anchor spheres, metres.
const ANCHOR_D: f64 = 0.15;
/// Height-field samples of the terrain mesh per side at most (the mesh's vertices are this squared).
const TERRAIN_SAMPLES: usize = 121;
/// Margin around the mission's points covered by the terrain mesh, metres.
const TERRAIN_MARGIN_M: f64 = 2.0;

/// A scan being joined from its chunks.
struct ScanInProgress {
    scan_id: u32,
    next: u16,
    count: u16,
    pose: protocol::Pose,
    t_ns: u64,
    data: Vec<u8>,
}

/// The channels of the rover's scene and what joining the wire's messages needs.
pub struct Scene {
    raw: [Arc<RawChannel>; 2],
    frames: [Arc<RawChannel>; 2],
    tf: Channel<FrameTransforms>,
    scans: Channel<PointCloud>,
    wire: Channel<SceneUpdate>,
    truth: Channel<SceneUpdate>,
    tether: Arc<RawChannel>,
    status: Arc<RawChannel>,
    telemetry: Arc<RawChannel>,
    truth_series: Arc<RawChannel>,
    log: Channel<Log>,
    deframers: [Deframer; 2],
    scan: Option<ScanInProgress>,
    plan_parts: Vec<Waypoint>,
    root: Option<[f64; 3]>,
    estimates: Vec<Point3>,
    stats: ExportStats,
}

impl Scene {
    /// Makes the scene's channels in `ctx` (its sinks, an MCAP writer or a WebSocket server, receive them).
    pub fn new(ctx: &Arc<Context>) -> Result<Self, FoxgloveError> {
        let raw = |t: &str| {
            ctx.channel_builder(t)
                .message_encoding("tetherbot-wire-v1")
                .build_raw()
        };
        let json = |t: &str| ctx.channel_builder(t).message_encoding("json").build_raw();
        Ok(Self {
            raw: [raw(topic::RAW_H2F)?, raw(topic::RAW_F2H)?],
            frames: [json(topic::FRAMES_H2F)?, json(topic::FRAMES_F2H)?],
            tf: ctx.channel_builder(topic::TF).build(),
            scans: ctx.channel_builder(topic::SCANS).build(),
            wire: ctx.channel_builder(topic::SCENE_WIRE).build(),
            truth: ctx.channel_builder(topic::SCENE_TRUTH).build(),
            tether: series_channel(
                ctx,
                topic::TETHER,
                "tetherbot.TetherReading",
                &[
                    ("payout_m", "number"),
                    ("tension_n", "number"),
                    ("boom_angle_rad", "number"),
                ],
            )?,
            status: series_channel(
                ctx,
                topic::STATUS,
                "tetherbot.MissionStatus",
                &[
                    ("state", "string"),
                    ("reason", "string"),
                    ("margin_n", "number"),
                    ("tension_n", "number"),
                    ("measured_payout_m", "number"),
                    ("predicted_payout_m", "number"),
                    ("cross_track_m", "number"),
                    ("distance_driven_m", "number"),
                    ("replans", "integer"),
                    ("motions_done", "integer"),
                ],
            )?,
            telemetry: series_channel(
                ctx,
                topic::TELEMETRY,
                "tetherbot.Telemetry",
                &[
                    ("mode", "string"),
                    ("map_blocks_used", "integer"),
                    ("map_blocks_capacity", "integer"),
                    ("frames_accepted", "integer"),
                    ("frames_sent", "integer"),
                    ("scans_completed", "integer"),
                    ("log_dropped", "integer"),
                ],
            )?,
            truth_series: series_channel(
                ctx,
                topic::TRUTH_SERIES,
                "tetherbot.Truth",
                &[
                    ("margin_n", "number"),
                    ("tension_n", "number"),
                    ("payout_m", "number"),
                    ("driven_m", "number"),
                ],
            )?,
            log: ctx.channel_builder(topic::LOG).build(),
            deframers: [Deframer::new(), Deframer::new()],
            scan: None,
            plan_parts: vec![],
            root: None,
            estimates: vec![],
            stats: ExportStats::default(),
        })
    }

    /// Whether a sink (a live viewer) subscribed to the rover's transforms.
    pub fn subscribed(&self) -> bool {
        self.tf.has_sinks()
    }

    /// What was written so far.
    pub fn stats(&self) -> ExportStats {
        self.stats
    }

    /// Bytes that went over the link in direction `dir` at link time `t_us`.
    /// Empty reads are not records (as in the field log) and write nothing.
    pub fn bytes(&mut self, dir: Direction, t_us: u64, bytes: &[u8]) {
        if bytes.is_empty() {
            return;
        }
        let side = match dir {
            Direction::HostToFlight => 0,
            Direction::FlightToHost => 1,
        };
        let t_ns = t_us.saturating_mul(1000);
        log_raw(&self.raw[side], bytes, t_ns);
        self.stats.raw_records += 1;
        let mut rest = bytes;
        while !rest.is_empty() {
            let (n, ev) = self.deframers[side].push(rest);
            rest = rest.get(n..).unwrap_or_default();
            let Some(ev) = ev else { continue };
            let decoded = ev
                .map_err(protocol::NackReason::from)
                .and_then(protocol::decode_frame);
            let value = match &decoded {
                Ok((h, m)) => {
                    serde_json::json!({"seq": h.seq, "kind": format!("{:?}", m.kind()), "body": message_json(m)})
                }
                Err(reason) => {
                    self.stats.bad_frames += 1;
                    serde_json::json!({"error": format!("{reason:?}")})
                }
            };
            log_raw(
                &self.frames[side],
                &serde_json::to_vec(&value).unwrap_or_default(),
                t_ns,
            );
            self.stats.frames += 1;
            if let Ok((_, m)) = decoded {
                self.message(t_ns, &m);
            }
        }
    }

    fn json(ch: &RawChannel, v: serde_json::Value, t_ns: u64) {
        log_raw(ch, &serde_json::to_vec(&v).unwrap_or_default(), t_ns);
    }

    fn transform(&self, t_ns: u64, child: &str, pose: &Pose) {
        let tf = FrameTransform {
            timestamp: Some(stamp(t_ns)),
            parent_frame_id: frame::WORLD.into(),
            child_frame_id: child.into(),
            translation: pose.position,
            rotation: pose.orientation,
        };
        self.tf.log_with_time(
            &FrameTransforms {
                transforms: vec![tf],
            },
            t_ns,
        );
    }

    /// One decoded message.
    fn message(&mut self, t_ns: u64, m: &Message) {
        match m {
            Message::Configure(c) => {
                let r = &c.tether.root_anchor;
                let root = [f64::from(r.x), f64::from(r.y), f64::from(r.z)];
                self.root = Some(root);
                let mut e = entity(t_ns, "root_anchor".into());
                e.spheres.push(sphere(root, 0.3, rgba(0.9, 0.1, 0.1, 1.0)));
                self.wire.log_with_time(
                    &SceneUpdate {
                        deletions: vec![],
                        entities: vec![e],
                    },
                    t_ns,
                );
            }
            Message::GoalRequest(g) => {
                let p = &g.position;
                let mut e = entity(t_ns, "goal".into());
                let d = 2.0 * f64::from(g.tolerance_m);
                e.spheres.push(sphere(
                    [f64::from(p.x), f64::from(p.y), f64::from(p.z)],
                    d,
                    rgba(1.0, 0.85, 0.0, 0.5),
                ));
                self.wire.log_with_time(
                    &SceneUpdate {
                        deletions: vec![],
                        entities: vec![e],
                    },
                    t_ns,
                );
            }
            Message::SensorChunk(c) => self.chunk(t_ns, c),
            Message::MotionReport(r) => {
                let pose = wire_pose(&r.pose);
                self.transform(t_ns, frame::ROVER, &pose);
                self.stats.poses += 1;
                self.estimates.push(wire_p3(&r.pose.position));
                let mut e = entity(t_ns, "estimated_path".into());
                e.lines
                    .push(line(self.estimates.clone(), 0.04, rgba(0.2, 0.4, 1.0, 1.0)));
                let mut body = entity(t_ns, "rover_body".into());
                body.frame_id = frame::ROVER.into();
                body.frame_locked = true;
                body.cubes.push(CubePrimitive {
                    pose: Some(at([0.0; 3])),
                    size: Some(v3(0.3, 0.6, 0.3)),
                    color: Some(rgba(0.2, 0.4, 1.0, 0.8)),
                });
                self.wire.log_with_time(
                    &SceneUpdate {
                        deletions: vec![],
                        entities: vec![e, body],
                    },
                    t_ns,
                );
            }
            Message::Plan(p) => {
                if p.part == 0 {
                    self.plan_parts.clear();
                }
                self.plan_parts.extend(p.waypoints.iter().cloned());
                if p.part + 1 == p.parts {
                    self.plan(t_ns);
                }
            }
            Message::TetherReading(r) => Self::json(
                &self.tether,
                serde_json::json!({"payout_m": r.payout_m, "tension_n": r.tension_n, "boom_angle_rad": r.boom_angle_rad}),
                t_ns,
            ),
            Message::MissionStatus(s) => Self::json(
                &self.status,
                serde_json::json!({
                    "state": format!("{:?}", s.state),
                    "reason": format!("{:?}", s.reason),
                    "margin_n": s.margin_n,
                    "tension_n": s.tension_n,
                    "measured_payout_m": s.measured_payout_m,
                    "predicted_payout_m": s.predicted_payout_m,
                    "cross_track_m": s.cross_track_m,
                    "distance_driven_m": s.distance_driven_m,
                    "replans": s.replans,
                    "motions_done": s.motions_done,
                }),
                t_ns,
            ),
            Message::Telemetry(t) => Self::json(
                &self.telemetry,
                serde_json::json!({
                    "mode": format!("{:?}", t.mode),
                    "map_blocks_used": t.map.blocks_used,
                    "map_blocks_capacity": t.map.blocks_capacity,
                    "frames_accepted": t.frames_accepted,
                    "frames_sent": t.frames_sent,
                    "scans_completed": t.scans_completed,
                    "log_dropped": t.log_dropped,
                }),
                t_ns,
            ),
            Message::Log(l) => {
                let level = match l.level {
                    LogLevel::Error => Level::Error,
                    LogLevel::Warn => Level::Warning,
                    LogLevel::Info => Level::Info,
                    LogLevel::Debug | LogLevel::Trace => Level::Debug,
                    LogLevel::Off => Level::Unknown,
                };
                let log = Log {
                    timestamp: Some(stamp(t_ns)),
                    level: level as i32,
                    message: l.text.to_string(),
                    name: "flight".into(),
                    file: String::new(),
                    line: 0,
                };
                self.log.log_with_time(&log, t_ns);
                self.stats.logs += 1;
            }
            _ => {}
        }
    }

    /// A scan chunk: joined with the scan's earlier chunks; the scan is drawn when its last chunk arrives.
    fn chunk(&mut self, t_ns: u64, c: &protocol::SensorChunk) {
        if c.chunk_index == 0 {
            if self.scan.is_some() {
                self.stats.broken_scans += 1;
            }
            self.scan = Some(ScanInProgress {
                scan_id: c.scan_id,
                next: 0,
                count: c.chunk_count,
                pose: c.sensor_pose,
                t_ns,
                data: vec![],
            });
        }
        let Some(s) = self.scan.as_mut() else {
            self.stats.broken_scans += 1;
            return;
        };
        if s.scan_id != c.scan_id || s.next != c.chunk_index || s.count != c.chunk_count {
            self.stats.broken_scans += 1;
            self.scan = None;
            return;
        }
        for p in &c.points {
            for v in [p.x, p.y, p.z] {
                s.data.extend_from_slice(&v.to_le_bytes());
            }
        }
        s.next += 1;
        if s.next < s.count {
            return;
        }
        let Some(s) = self.scan.take() else { return };
        let pose = wire_pose(&s.pose);
        self.transform(s.t_ns, frame::SENSOR, &pose);
        let field = |name: &str, offset: u32| PackedElementField {
            name: name.into(),
            offset,
            r#type: NumericType::Float32 as i32,
        };
        let cloud = PointCloud {
            timestamp: Some(stamp(s.t_ns)),
            frame_id: frame::WORLD.into(),
            pose: Some(pose),
            point_stride: 12,
            fields: vec![field("x", 0), field("y", 4), field("z", 8)],
            data: s.data.into(),
        };
        self.scans.log_with_time(&cloud, t_ns);
        self.stats.scans += 1;
    }

    /// A complete plan: its path and the tether it plans (root, the anchors of its last waypoint, the rover).
    fn plan(&mut self, t_ns: u64) {
        let k = self.stats.plans;
        self.stats.plans += 1;
        let (r, g, b) = PLAN_COLOURS[k % PLAN_COLOURS.len()];
        let mut e = entity(t_ns, format!("plan/{k}"));
        e.lines.push(line(
            self.plan_parts
                .iter()
                .map(|w| wire_p3(&w.pose.position))
                .collect(),
            0.05,
            rgba(r, g, b, 1.0),
        ));
        if let Some(last) = self.plan_parts.last() {
            let mut tether: Vec<Point3> = self.root.map(p3).into_iter().collect();
            tether.extend(last.anchors.iter().map(wire_p3));
            tether.push(wire_p3(&last.pose.position));
            e.lines.push(line(tether, 0.02, rgba(r, g, b, 0.6)));
            for a in &last.anchors {
                e.spheres.push(sphere(
                    [f64::from(a.x), f64::from(a.y), f64::from(a.z)],
                    ANCHOR_D,
                    rgba(r, g, b, 1.0),
                ));
            }
        }
        self.wire.log_with_time(
            &SceneUpdate {
                deletions: vec![],
                entities: vec![e],
            },
            t_ns,
        );
    }

    /// The true terrain as a triangle mesh over the mission's region, at `t_ns` (the world's height field
    /// sampled on a grid; a world without one, such as the ledge, has no mesh).
    pub fn terrain(&self, world: &dyn World, points: &[[f64; 3]], t_ns: u64) -> bool {
        let Some(mesh) = terrain_mesh(world, points) else {
            return false;
        };
        let mut e = entity(t_ns, "terrain".into());
        e.triangles.push(mesh);
        self.truth.log_with_time(
            &SceneUpdate {
                deletions: vec![],
                entities: vec![e],
            },
            t_ns,
        );
        true
    }

    /// What only the simulator knows, from a mission's report: the true pose of every executed increment, the
    /// true tether at each snapshot, the executed path so far at each snapshot, the rocks, the terrain and the
    /// true margin, tension and payout as series.
    pub fn truth(&mut self, rep: &MissionReport, world: &dyn World) {
        let mut pts = vec![rep.root, rep.start, rep.goal];
        pts.extend(rep.trace.iter().map(|t| t.axle));
        self.terrain(world, &pts, 0);
        let mut rocks = entity(0, "rocks".into());
        for (c, radius, visible) in &rep.rocks {
            let a = if *visible { 1.0 } else { 0.4 };
            rocks
                .spheres
                .push(sphere(*c, 2.0 * radius, rgba(0.55, 0.35, 0.2, a)));
        }
        self.truth.log_with_time(
            &SceneUpdate {
                deletions: vec![],
                entities: vec![rocks],
            },
            0,
        );
        for tp in &rep.trace {
            let t_ns = (tp.t_s * 1e9).round() as u64;
            let [x, y, z, w] = tp.orientation;
            let pose = Pose {
                position: Some(v3(tp.axle[0], tp.axle[1], tp.axle[2])),
                orientation: Some(Quaternion { x, y, z, w }),
            };
            self.transform(t_ns, frame::ROVER_TRUE, &pose);
            self.stats.true_poses += 1;
            Self::json(
                &self.truth_series,
                serde_json::json!({"margin_n": tp.margin_n, "tension_n": tp.tension_n, "payout_m": tp.payout_m, "driven_m": tp.driven_m}),
                t_ns,
            );
        }
        let mut body = entity(0, "rover_true_body".into());
        body.frame_id = frame::ROVER_TRUE.into();
        body.frame_locked = true;
        body.cubes.push(CubePrimitive {
            pose: Some(at([0.0; 3])),
            size: Some(v3(0.3, 0.6, 0.3)),
            color: Some(rgba(0.9, 0.3, 0.1, 0.8)),
        });
        self.truth.log_with_time(
            &SceneUpdate {
                deletions: vec![],
                entities: vec![body],
            },
            0,
        );
        for (t_s, tether) in &rep.tethers {
            let t_ns = (t_s * 1e9).round() as u64;
            let mut e = entity(t_ns, "true_tether".into());
            e.lines.push(line(
                tether.iter().copied().map(p3).collect(),
                0.03,
                rgba(0.9, 0.1, 0.1, 1.0),
            ));
            for c in tether.iter().skip(1).take(tether.len().saturating_sub(2)) {
                e.spheres
                    .push(sphere(*c, ANCHOR_D, rgba(0.9, 0.1, 0.1, 1.0)));
            }
            let mut path = entity(t_ns, "true_path".into());
            let done: Vec<Point3> = rep
                .trace
                .iter()
                .take_while(|p| p.t_s <= *t_s)
                .map(|p| p3(p.axle))
                .collect();
            path.lines.push(line(done, 0.04, rgba(0.9, 0.3, 0.1, 1.0)));
            self.truth.log_with_time(
                &SceneUpdate {
                    deletions: vec![],
                    entities: vec![e, path],
                },
                t_ns,
            );
        }
    }
}

/// The world's height field over the box around `points` (plus [`TERRAIN_MARGIN_M`]) as an indexed triangle
/// list, coloured by height; `None` when the world has no height field there.
pub fn terrain_mesh(world: &dyn World, points: &[[f64; 3]]) -> Option<TriangleListPrimitive> {
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for p in points {
        for k in 0..2 {
            lo[k] = lo[k].min(p[k] - TERRAIN_MARGIN_M);
            hi[k] = hi[k].max(p[k] + TERRAIN_MARGIN_M);
        }
    }
    if !(lo[0] < hi[0] && lo[1] < hi[1]) {
        return None;
    }
    let n = TERRAIN_SAMPLES;
    let step = [
        (hi[0] - lo[0]) / (n - 1) as f64,
        (hi[1] - lo[1]) / (n - 1) as f64,
    ];
    let mut heights = Vec::with_capacity(n * n);
    for j in 0..n {
        for i in 0..n {
            let (x, y) = (lo[0] + i as f64 * step[0], lo[1] + j as f64 * step[1]);
            heights.push(
                world
                    .height_at(x as f32, y as f32)
                    .map(f64::from)
                    .filter(|h| h.is_finite()),
            );
        }
    }
    let (zmin, zmax) = heights
        .iter()
        .flatten()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &h| {
            (a.min(h), b.max(h))
        });
    if !zmin.is_finite() {
        return None;
    }
    let mut mesh = TriangleListPrimitive {
        pose: Some(at([0.0; 3])),
        color: Some(rgba(0.6, 0.6, 0.6, 1.0)),
        ..Default::default()
    };
    let mut index = vec![None; n * n];
    for j in 0..n {
        for i in 0..n {
            if let Some(h) = heights[j * n + i] {
                index[j * n + i] = Some(mesh.points.len() as u32);
                mesh.points.push(Point3 {
                    x: lo[0] + i as f64 * step[0],
                    y: lo[1] + j as f64 * step[1],
                    z: h,
                });
                let s = if zmax > zmin {
                    (h - zmin) / (zmax - zmin)
                } else {
                    0.5
                };
                mesh.colors
                    .push(rgba(0.35 + 0.5 * s, 0.3 + 0.45 * s, 0.25 + 0.4 * s, 1.0));
            }
        }
    }
    for j in 0..n - 1 {
        for i in 0..n - 1 {
            let (a, b, c, d) = (
                index[j * n + i],
                index[j * n + i + 1],
                index[(j + 1) * n + i],
                index[(j + 1) * n + i + 1],
            );
            if let (Some(a), Some(b), Some(c), Some(d)) = (a, b, c, d) {
                mesh.indices.extend_from_slice(&[a, b, d, a, d, c]);
            }
        }
    }
    (!mesh.indices.is_empty()).then_some(mesh)
}

fn metadata(log: &FieldLog) -> BTreeMap<String, String> {
    let mut meta = BTreeMap::new();
    meta.insert(
        "protocol_version".to_string(),
        log.header.protocol_version.to_string(),
    );
    meta.insert("seed".to_string(), log.header.seed.to_string());
    meta.insert(
        "created_at_unix_ms".to_string(),
        log.header.created_at_unix_ms.to_string(),
    );
    meta.insert("config".to_string(), log.header.config.clone());
    meta
}

/// Writes `log` as MCAP into `out`, with the truth of the mission run that wrote it when given.
pub fn export_with<W: Write + Seek + Send + 'static>(
    log: &FieldLog,
    truth: Option<(&MissionReport, &dyn World)>,
    out: W,
) -> Result<ExportStats, FoxgloveError> {
    let ctx = Context::new();
    let writer = ctx.mcap_writer().create(out)?;
    writer.write_metadata("tetherbot-field-log", metadata(log))?;
    let mut scene = Scene::new(&ctx)?;
    for r in &log.records {
        scene.bytes(r.direction, r.t_us, &r.bytes);
    }
    if let Some((rep, world)) = truth {
        scene.truth(rep, world);
    }
    writer.close()?;
    Ok(scene.stats())
}

/// Writes `log` as MCAP into `out` (what the wire says).
pub fn export<W: Write + Seek + Send + 'static>(
    log: &FieldLog,
    out: W,
) -> Result<ExportStats, FoxgloveError> {
    export_with(log, None, out)
}

/// A [`FlightLink`] wrapper that shows every byte passing through it in a [`Scene`] as it goes (the live view).
pub struct SceneLink<'s, L: FlightLink> {
    inner: L,
    scene: &'s mut Scene,
}

impl<'s, L: FlightLink> SceneLink<'s, L> {
    /// Wraps `inner`.
    pub fn new(inner: L, scene: &'s mut Scene) -> Self {
        Self { inner, scene }
    }
}

impl<L: FlightLink> FlightLink for SceneLink<'_, L> {
    fn name(&self) -> &str {
        self.inner.name()
    }
    fn now_us(&self) -> u64 {
        self.inner.now_us()
    }
    fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.scene
            .bytes(Direction::HostToFlight, self.inner.now_us(), bytes);
        self.inner.send(bytes)
    }
    fn recv_until_quiet(&mut self, max_wait_us: u64) -> Result<Vec<u8>, LinkError> {
        let got = self.inner.recv_until_quiet(max_wait_us)?;
        self.scene
            .bytes(Direction::FlightToHost, self.inner.now_us(), &got);
        Ok(got)
    }
    fn advance_to(&mut self, t_us: u64) -> Result<Vec<u8>, LinkError> {
        let got = self.inner.advance_to(t_us)?;
        self.scene
            .bytes(Direction::FlightToHost, self.inner.now_us(), &got);
        Ok(got)
    }
    fn note_fault(&mut self, event: &crate::link::faults::FaultEvent) -> Result<(), LinkError> {
        self.inner.note_fault(event)
    }
    fn end_faults(&mut self) -> Result<(), LinkError> {
        self.inner.end_faults()
    }
    fn reset_flight(&mut self, cause: crate::link::ResetCause) -> Result<(), LinkError> {
        self.inner.reset_flight(cause)
    }
}
