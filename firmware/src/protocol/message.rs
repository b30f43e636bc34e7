//! Message set v3: the bodies of frames, as serde types encoded with postcard.
//!
//! Version 2 added the closed-loop mission: `GoalRequest.allow_approximate`, `Configure.mission`
//! ([`MissionConfig`]), the host -> flight [`MotionReport`] and [`GoalCancel`], and the flight -> host
//! [`MissionStatus`]. Version 3 adds `Configure.map` ([`MapSettings`]): the ground sets the onboard map's
//! resolution per mission (see `firmware/PROTOCOL.md`).
//!
//! Every float is validated on decode ([`Validate`]): NaN and infinities are an error everywhere, pose quaternions
//! must be unit within [`QUATERNION_NORM_TOLERANCE`], lengths and counts must be inside their `config::protocol`
//! limits. Variable-length fields are `heapless` containers, so a length prefix that claims more than the capacity
//! is a decode error, never an allocation.

use heapless::{String, Vec};
use serde::{Deserialize, Serialize};

pub use super::values::{Invalid, Point3, Validate};
use super::values::{finite, non_negative, positive};

pub use super::team::{
    GripState, TeamCommand, TeamConfigure, TeamEvent, TeamGrid, TeamLoss, TeamMissionSettings, TeamOrder, TeamOutcome,
    TeamPlannerSettings, TeamReport, TeamScanChunk, TeamState,
};

use crate::config::map::MapConfig;
use crate::config::mission as mission_cfg;
use crate::config::protocol::{
    MAX_ANCHORS_PER_WAYPOINT, MAX_HEIGHTS_PER_TILE_CHUNK, MAX_LOG_TEXT, MAX_POINTS_PER_CHUNK,
    MAX_WAYPOINTS_PER_PLAN_FRAME, MIN_TELEMETRY_PERIOD_MS, QUATERNION_NORM_TOLERANCE,
};
use crate::config::homotopy::{MAX_TILE_RESOLUTION_M, MAX_TILE_SIDE, MIN_TILE_RESOLUTION_M};

/// Who sends a message kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Direction {
    /// Simulator / ground station to flight software.
    HostToFlight,
    /// Flight software to simulator / ground station.
    FlightToHost,
}

/// The message kind byte of the header. All other values are an error ([`MessageKind::from_u8`] returns `None`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
#[repr(u8)]
pub enum MessageKind {
    /// [`TimeTick`] (host -> flight).
    TimeTick = 0x01,
    /// [`SensorChunk`] (host -> flight).
    SensorChunk = 0x02,
    /// [`TetherReading`] (host -> flight).
    TetherReading = 0x03,
    /// [`GoalRequest`] (host -> flight).
    GoalRequest = 0x04,
    /// [`Configure`] (host -> flight).
    Configure = 0x05,
    /// [`Shutdown`] (host -> flight).
    Shutdown = 0x06,
    /// [`TelemetryRequest`] (host -> flight).
    TelemetryRequest = 0x07,
    /// [`MotionReport`] (host -> flight, v2).
    MotionReport = 0x08,
    /// [`GoalCancel`] (host -> flight, v2).
    GoalCancel = 0x09,
    /// [`TileChunk`] (host -> flight, v7).
    TileChunk = 0x0A,
    /// [`TeamConfigure`] (host -> flight, v8).
    TeamConfigure = 0x0B,
    /// [`TeamScanChunk`] (host -> flight, v8).
    TeamScanChunk = 0x0C,
    /// [`TeamReport`] (host -> flight, v8).
    TeamReport = 0x0D,
    /// [`Ack`] (flight -> host).
    Ack = 0x81,
    /// [`Nack`] (flight -> host).
    Nack = 0x82,
    /// [`PlanStatus`] (flight -> host).
    PlanStatus = 0x83,
    /// [`Plan`] (flight -> host).
    Plan = 0x84,
    /// [`DriveCommand`] (flight -> host).
    DriveCommand = 0x85,
    /// [`Telemetry`] (flight -> host).
    Telemetry = 0x86,
    /// [`Log`] (flight -> host).
    Log = 0x87,
    /// [`MissionStatus`] (flight -> host, v2).
    MissionStatus = 0x88,
    /// [`TeamCommand`] (flight -> host, v8).
    TeamCommand = 0x89,
}

impl MessageKind {
    /// Every kind, in code order.
    pub const ALL: [MessageKind; 22] = [
        Self::TimeTick,
        Self::SensorChunk,
        Self::TetherReading,
        Self::GoalRequest,
        Self::Configure,
        Self::Shutdown,
        Self::TelemetryRequest,
        Self::MotionReport,
        Self::GoalCancel,
        Self::TileChunk,
        Self::TeamConfigure,
        Self::TeamScanChunk,
        Self::TeamReport,
        Self::Ack,
        Self::Nack,
        Self::PlanStatus,
        Self::Plan,
        Self::DriveCommand,
        Self::Telemetry,
        Self::Log,
        Self::MissionStatus,
        Self::TeamCommand,
    ];

    /// The kind for a header byte; `None` for every value not listed in the spec.
    pub fn from_u8(b: u8) -> Option<Self> {
        Self::ALL.iter().copied().find(|k| *k as u8 == b)
    }

    /// Who sends this kind: codes below 0x80 go host -> flight, the others flight -> host.
    pub fn direction(self) -> Direction {
        if (self as u8) < 0x80 {
            Direction::HostToFlight
        } else {
            Direction::FlightToHost
        }
    }
}

/// A unit quaternion `(x, y, z, w)` (Hamilton convention, `w` the scalar part).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Quat {
    /// i component.
    pub x: f32,
    /// j component.
    pub y: f32,
    /// k component.
    pub z: f32,
    /// Scalar component.
    pub w: f32,
}

impl Quat {
    /// The identity rotation.
    pub const IDENTITY: Quat = Quat {
        x: 0.0,
        y: 0.0,
        z: 0.0,
        w: 1.0,
    };
}

/// A rigid transform, SE(3): position plus unit-quaternion orientation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Position, metres (world frame).
    pub position: Point3,
    /// Orientation (body/sensor frame to world frame).
    pub orientation: Quat,
}

impl Pose {
    /// The identity pose at the origin.
    pub const IDENTITY: Pose = Pose {
        position: Point3::new(0.0, 0.0, 0.0),
        orientation: Quat::IDENTITY,
    };

    /// As an `nalgebra` isometry (the quaternion is renormalised; it was checked to be unit within tolerance): the
    /// one conversion from the wire pose, for the navigator and the simulator alike.
    pub fn to_isometry(&self) -> crate::geom::Pose3 {
        let q = nalgebra::Quaternion::new(
            self.orientation.w,
            self.orientation.x,
            self.orientation.y,
            self.orientation.z,
        );
        crate::geom::Pose3::from_parts(
            nalgebra::Translation3::new(self.position.x, self.position.y, self.position.z),
            nalgebra::UnitQuaternion::new_normalize(q),
        )
    }
}

/// Host -> flight: the host's time, for time sync. The flight side never takes it as its own clock.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TimeTick {
    /// Host (simulation) time, microseconds.
    pub host_time_us: u64,
}

/// Host -> flight: one chunk of a range scan. Chunks of a scan share `scan_id`, `chunk_count` and `sensor_pose` and
/// must arrive in order `0..chunk_count`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorChunk {
    /// Identifies the scan.
    pub scan_id: u32,
    /// Index of this chunk, `0..chunk_count`.
    pub chunk_index: u16,
    /// Number of chunks in the scan, `1..=MAX_CHUNKS_PER_SCAN`.
    pub chunk_count: u16,
    /// Pose estimate of the sensor (sensor frame to world frame) when the scan was taken.
    pub sensor_pose: Pose,
    /// Returns in the sensor frame, metres.
    pub points: Vec<Point3, MAX_POINTS_PER_CHUNK>,
}

/// Host -> flight: one chunk of a terrain tile (v7): an orbital DEM patch for the homotopy planner
/// (`crate::plan::homotopy::dem::HeightTile`). Posts at `origin + (col, row) x resolution_m` (world x/y, metres), row 0
/// at the smallest y; heights in row-major order, chunk `i` carrying posts `i * MAX_HEIGHTS_PER_TILE_CHUNK ..`, every
/// chunk full but the last. Chunks of a tile share `tile_id`, `chunk_count`, the origin, the spacing and the shape,
/// and must arrive in order `0..chunk_count`; chunk 0 starts a tile (abandoning one in progress). The tile replaces
/// the navigator's only when complete and valid.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TileChunk {
    /// Identifies the tile.
    pub tile_id: u32,
    /// Index of this chunk, `0..chunk_count`.
    pub chunk_index: u16,
    /// Number of chunks: `ceil(rows * cols / MAX_HEIGHTS_PER_TILE_CHUNK)`.
    pub chunk_count: u16,
    /// World x of post (0, 0), metres.
    pub origin_x_m: f32,
    /// World y of post (0, 0), metres.
    pub origin_y_m: f32,
    /// Post spacing, metres, within `[MIN_TILE_RESOLUTION_M, MAX_TILE_RESOLUTION_M]` (0.02 .. 5 m).
    pub resolution_m: f32,
    /// Posts along y, `1..=MAX_TILE_SIDE` (128).
    pub rows: u16,
    /// Posts along x, `1..=MAX_TILE_SIDE` (128).
    pub cols: u16,
    /// Heights (world z, metres) of this chunk's posts, row-major.
    pub heights: Vec<f32, MAX_HEIGHTS_PER_TILE_CHUNK>,
}

/// Host -> flight: one tether-encoder reading.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TetherReading {
    /// Time of the sample (host clock), microseconds.
    pub time_us: u64,
    /// Tether paid out from the root anchor, metres (>= 0).
    pub payout_m: f32,
    /// Tether tension, newtons (>= 0).
    pub tension_n: f32,
    /// Boom angle relative to the body, radians.
    pub boom_angle_rad: f32,
}

/// Which planner a goal request asks for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PlannerChoice {
    /// ABIT* over settled SE(3) states with anchor histories (Paton et al. V).
    Abit,
    /// Homotopy planning on tether-demand planes (Abad-Manterola et al.; Tanner et al.).
    Homotopy,
    /// Tethered climbing team (Morad et al.).
    Team,
}

/// Host -> flight: plan to a goal region.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GoalRequest {
    /// Identifies the goal in later `PlanStatus` / `Plan` messages.
    pub goal_id: u32,
    /// Goal position, metres (world frame).
    pub position: Point3,
    /// Radius of the goal region, metres (> 0).
    pub tolerance_m: f32,
    /// The planner to run.
    pub planner: PlannerChoice,
    /// Planner iteration budget (> 0).
    pub max_iterations: u32,
    /// Wall-time budget, milliseconds of flight time (0 = none).
    pub time_budget_ms: u32,
    /// Drive an approximate solution (the planner's state closest to the goal) up to its last safe state. When
    /// false an approximate solution ends the mission safe with `StopReason::NoSolution`.
    pub allow_approximate: bool,
}

/// Rover parameters (the Axel model).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RoverConfig {
    /// Mass, kg (> 0).
    pub mass_kg: f32,
    /// Wheel radius, metres (> 0).
    pub wheel_radius_m: f32,
    /// Distance between the wheels along the axle, metres (> 0).
    pub axle_length_m: f32,
    /// Caster boom length, metres (> 0).
    pub boom_length_m: f32,
    /// Coulomb friction coefficient of the wheels on the terrain (> 0).
    pub friction_coefficient: f32,
}

/// Tether parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TetherConfig {
    /// Root anchor, metres (world frame).
    pub root_anchor: Point3,
    /// Tether length on the spool, metres (> 0).
    pub max_payout_m: f32,
    /// Largest allowed tension, newtons (> 0).
    pub max_tension_n: f32,
}

/// Planner parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlannerConfig {
    /// Seed of the planner's random generator (deterministic runs).
    pub rng_seed: u64,
    /// Default iteration budget (> 0).
    pub max_iterations: u32,
    /// Samples per batch (ABIT*) (> 0).
    pub batch_size: u32,
    /// Probability of sampling the goal, `0..=1`.
    pub goal_bias: f32,
}

/// Severity of a log record (also the forwarding threshold in [`TelemetryConfig`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum LogLevel {
    /// Nothing (as a threshold: forward no records).
    Off,
    /// Errors.
    Error,
    /// Warnings.
    Warn,
    /// Information.
    Info,
    /// Debugging detail.
    Debug,
    /// Tracing detail.
    Trace,
}

/// Telemetry and log-forwarding parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TelemetryConfig {
    /// Period of unsolicited telemetry, milliseconds: 0 (only on request) or at least `MIN_TELEMETRY_PERIOD_MS`.
    pub period_ms: u32,
    /// Records at this level or more severe are forwarded as `Log` frames (`Off` = none).
    pub forward_log_level: LogLevel,
}

/// Host -> flight: configuration. Accepted in `Idle` and `Mapping` modes only.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Configure {
    /// The rover.
    pub rover: RoverConfig,
    /// The tether.
    pub tether: TetherConfig,
    /// The planners.
    pub planner: PlannerConfig,
    /// Telemetry and log forwarding.
    pub telemetry: TelemetryConfig,
    /// The closed-loop mission (v2). Defaults: `MissionConfig::DEFAULT` (`firmware::config::mission`).
    pub mission: MissionConfig,
    /// The onboard map's configuration (v3). `None` keeps the map as it is (at boot `MapConfig::DEFAULT`); a
    /// configuration different from the map's clears the map and rebuilds it at the new resolution.
    pub map: Option<MapSettings>,
}

/// The onboard map's parameters in a `Configure` (v3): `firmware::config::map::MapConfig` field for field (the
/// defaults and meaning of each are listed there), counts as `u32`. Validated by `MapConfig::validate`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct MapSettings {
    pub voxel_size_m: f32,
    pub truncation_m: f32,
    pub max_weight: f32,
    pub max_carve_length_m: f32,
    pub max_ray_voxels: u32,
    pub max_range_m: f32,
    pub min_range_m: f32,
    pub esdf_band_voxels: f32,
    pub esdf_site_tolerance_voxels: f32,
    pub esdf_max_distance_m: f32,
    pub esdf_max_sweeps: u32,
}

impl From<MapConfig> for MapSettings {
    fn from(c: MapConfig) -> Self {
        let count = |n: usize| u32::try_from(n).unwrap_or(u32::MAX);
        MapSettings {
            voxel_size_m: c.voxel_size,
            truncation_m: c.truncation,
            max_weight: c.max_weight,
            max_carve_length_m: c.max_carve_length,
            max_ray_voxels: count(c.max_ray_voxels),
            max_range_m: c.max_range,
            min_range_m: c.min_range,
            esdf_band_voxels: c.esdf_band,
            esdf_site_tolerance_voxels: c.esdf_site_tolerance,
            esdf_max_distance_m: c.esdf_max_distance,
            esdf_max_sweeps: count(c.esdf_max_sweeps),
        }
    }
}

impl From<MapSettings> for MapConfig {
    fn from(m: MapSettings) -> Self {
        let count = |n: u32| usize::try_from(n).unwrap_or(usize::MAX);
        MapConfig {
            voxel_size: m.voxel_size_m,
            truncation: m.truncation_m,
            max_weight: m.max_weight,
            max_carve_length: m.max_carve_length_m,
            max_ray_voxels: count(m.max_ray_voxels),
            max_range: m.max_range_m,
            min_range: m.min_range_m,
            esdf_band: m.esdf_band_voxels,
            esdf_site_tolerance: m.esdf_site_tolerance_voxels,
            esdf_max_distance: m.esdf_max_distance_m,
            esdf_max_sweeps: count(m.esdf_max_sweeps),
        }
    }
}

/// How straight drives are executed (v2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Tracking {
    /// The plan's motions as they are (the v1 executor; the comparison baseline).
    OpenLoop,
    /// The tether-aware path-tracking controller: straight drives in closed-loop sub-segments that correct heading
    /// and cross-track error from the reported pose, with the tether's pull as feed-forward.
    ClosedLoop,
}

/// Mission parameters of a `Configure` (v2). Defaults: `MissionConfig::DEFAULT` in `firmware::config::mission`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MissionConfig {
    /// Open-loop or closed-loop execution of straight drives.
    pub tracking: Tracking,
    /// Replan from the current pose when it is farther than this from the plan being driven, metres (> 0).
    pub replan_cross_track_m: f32,
    /// Largest allowed difference between the tracked tether length and the encoder's payout, metres (> 0).
    pub payout_tolerance_m: f32,
    /// Smallest stability margin a waypoint or the current state may have, newtons (>= 0).
    pub min_margin_n: f32,
}

impl MissionConfig {
    /// The defaults of `firmware::config::mission`.
    pub const DEFAULT: MissionConfig = MissionConfig {
        tracking: if mission_cfg::DEFAULT_CLOSED_LOOP {
            Tracking::ClosedLoop
        } else {
            Tracking::OpenLoop
        },
        replan_cross_track_m: mission_cfg::DEFAULT_REPLAN_CROSS_TRACK_M,
        payout_tolerance_m: mission_cfg::DEFAULT_PAYOUT_TOLERANCE_M,
        min_margin_n: mission_cfg::DEFAULT_MIN_MARGIN_N,
    };
}

impl Default for MissionConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Host -> flight: stop everything and enter `Safe` mode (the rover holds position).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shutdown;

/// Host -> flight: send one `Telemetry` frame now.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct TelemetryRequest;

/// Flight -> host: the frame with sequence number `seq` was accepted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Ack {
    /// Sequence number of the accepted frame.
    pub seq: u32,
}

/// Why a frame was rejected. Wire value: postcard enum index (the order below, starting at 0).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
pub enum NackReason {
    /// The frame was cut short: COBS block runs past the delimiter, or fewer than header + CRC bytes.
    Truncated,
    /// More than `MAX_FRAME_LEN` bytes before the delimiter; bytes were discarded up to the next delimiter.
    Oversize,
    /// CRC mismatch (damaged frame).
    BadCrc,
    /// Protocol version byte is not this build's version.
    WrongVersion,
    /// Message kind byte is not in the spec.
    UnknownKind,
    /// A flight -> host kind was sent to the flight software (or the reverse).
    WrongDirection,
    /// The body ended before the message did (a length prefix claimed more than was sent).
    BodyTooShort,
    /// Bytes were left over after the message (a length prefix claimed less than was sent).
    BodyTooLong,
    /// A length prefix exceeds the field's capacity.
    LengthOverLimit,
    /// Malformed body: bad varint, enum tag, bool or UTF-8.
    MalformedBody,
    /// A float is NaN or infinite.
    NonFinite,
    /// A pose quaternion is not unit.
    NotUnitQuaternion,
    /// A value is outside its documented range (negative length, zero budget, ...).
    OutOfRange,
    /// `chunk_index >= chunk_count`.
    ChunkIndexOutOfRange,
    /// `chunk_count` is 0 or above `MAX_CHUNKS_PER_SCAN`.
    TooManyChunks,
    /// A chunk that was already received.
    DuplicateChunk,
    /// A chunk ahead of the next expected one (a chunk is missing), or a scan not starting at chunk 0.
    OutOfOrderChunk,
    /// A chunk of another scan (or another chunk count) while a scan is in progress, not at chunk 0.
    MixedScan,
    /// The scan does not fit the reassembly buffer.
    ScanOverflow,
    /// A chunk's sensor pose differs from the scan's first chunk.
    PoseMismatch,
    /// The message is not accepted in the current mode (e.g. `Configure` while planning, anything but ticks and
    /// telemetry requests in `Safe`).
    NotAllowedInMode,
    /// A sensor chunk or goal before the first `Configure`.
    NotConfigured,
    /// The planning hooks refused the message (see the flight log).
    Refused,
    /// A `MotionReport` for a command that is not awaiting a report: never sent, a `Stop`, already reported, or
    /// given up after the report timeout (v2).
    UnknownCommand,
    /// A `GoalCancel` for a goal that is not the one being planned or driven (v2).
    UnknownGoal,
    /// The same frame (sequence number and CRC) as one of the last `SEQ_HISTORY_LEN` accepted: a duplicate on the
    /// link, not acted on twice (v4).
    DuplicateFrame,
    /// A `TileChunk` with more than `MAX_TILE_SIDE` (128) posts on a side: cut or resample the DEM patch (v7).
    TileTooLarge,
    /// A `TileChunk` whose post spacing is outside `MIN_TILE_RESOLUTION_M..=MAX_TILE_RESOLUTION_M` (0.02 .. 5 m):
    /// resample the DEM patch (v7).
    TileResolution,
    /// A `TileChunk` (not chunk 0) of another tile than the one in progress, or with another origin, spacing,
    /// shape or chunk count than its chunk 0, or with no tile in progress: resend the tile from chunk 0 (v7).
    TileMismatch,
    /// A `TileChunk` whose height count is not what its index requires (`MAX_HEIGHTS_PER_TILE_CHUNK`, the last
    /// chunk the rest), or whose chunk count does not match its shape: fix the uploader (v7).
    TileChunkLength,
    /// A team message naming a robot outside `0..TEAM_SIZE` (v8).
    UnknownRobot,
    /// A team goal without a `TeamConfigure`, a team scan or report when no team mission awaits it, or a
    /// `TeamConfigure` while a team mission runs (v8).
    NoTeam,
}

/// Number of [`NackReason`] values (the length of the rejection counters).
pub const NACK_REASON_COUNT: usize = 32;

impl NackReason {
    /// Every reason, in wire order.
    pub const ALL: [NackReason; NACK_REASON_COUNT] = [
        Self::Truncated,
        Self::Oversize,
        Self::BadCrc,
        Self::WrongVersion,
        Self::UnknownKind,
        Self::WrongDirection,
        Self::BodyTooShort,
        Self::BodyTooLong,
        Self::LengthOverLimit,
        Self::MalformedBody,
        Self::NonFinite,
        Self::NotUnitQuaternion,
        Self::OutOfRange,
        Self::ChunkIndexOutOfRange,
        Self::TooManyChunks,
        Self::DuplicateChunk,
        Self::OutOfOrderChunk,
        Self::MixedScan,
        Self::ScanOverflow,
        Self::PoseMismatch,
        Self::NotAllowedInMode,
        Self::NotConfigured,
        Self::Refused,
        Self::UnknownCommand,
        Self::UnknownGoal,
        Self::DuplicateFrame,
        Self::TileTooLarge,
        Self::TileResolution,
        Self::TileMismatch,
        Self::TileChunkLength,
        Self::UnknownRobot,
        Self::NoTeam,
    ];

    /// Index into rejection counters (equals the wire value).
    pub fn index(self) -> usize {
        self as usize
    }
}

/// Flight -> host: the frame with sequence number `seq` was rejected. For frames whose header could not be trusted
/// (truncated, oversize, bad CRC) `seq` is the value read from the header bytes if there were at least six, else 0.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct Nack {
    /// Sequence number of the rejected frame (see above).
    pub seq: u32,
    /// Why.
    pub reason: NackReason,
}

/// State of planning toward a goal (OMPL's status split).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PlanState {
    /// No goal yet.
    NoGoal,
    /// The goal was accepted; planning starts.
    Accepted,
    /// Planning is running.
    Searching,
    /// A path reaching the goal region was found (a `Plan` follows).
    ExactSolution,
    /// A path ending closest to the goal was found within budget (a `Plan` follows).
    ApproximateSolution,
    /// The budget ran out without a solution.
    NoSolutionWithinBudget,
    /// The goal or the start is invalid (outside the map, in collision, unstable).
    InvalidInput,
    /// No planner of the requested kind is available on board.
    PlannerUnavailable,
    /// Planning was stopped (shutdown).
    Aborted,
}

/// Flight -> host: progress or outcome of planning for a goal.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlanStatus {
    /// The goal this refers to.
    pub goal_id: u32,
    /// Its state.
    pub state: PlanState,
    /// Planner iterations spent so far.
    pub iterations: u32,
    /// Cost of the best path so far, if any.
    pub best_cost: Option<f32>,
}

/// One plan waypoint: a settled SE(3) state with its anchor history and stability margin (Paton et al. IV).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Waypoint {
    /// Settled rover pose.
    pub pose: Pose,
    /// Anchor history, root anchor first.
    pub anchors: Vec<Point3, MAX_ANCHORS_PER_WAYPOINT>,
    /// Static stability margin at this state (>= 0 is stable), newtons.
    pub stability_margin: f32,
}

/// Flight -> host: a plan (or one part of a long plan).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The goal this plan reaches.
    pub goal_id: u32,
    /// Part index, `0..parts`.
    pub part: u16,
    /// Number of parts (>= 1).
    pub parts: u16,
    /// Waypoints of this part, in order.
    pub waypoints: Vec<Waypoint, MAX_WAYPOINTS_PER_PLAN_FRAME>,
}

/// A rover motion primitive (Axel: in-place turn, straight drive).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum Motion {
    /// Stop the wheels and hold the tether (v6: names the motion it stops).
    Stop {
        /// The `command_id` of the `Turn` / `Straight` this stops. A host stops that motion only: one it is
        /// executing, or one not started yet (never started, reported `Stopped` with nothing achieved); a stop
        /// for a motion already reported is stale and does nothing, so a late or repeated `Stop` cannot stop the
        /// next motion.
        motion_id: u32,
    },
    /// Turn in place, radians (positive counter-clockwise).
    Turn {
        /// Yaw change, radians.
        yaw_rad: f32,
    },
    /// Drive straight, metres (negative = reverse).
    Straight {
        /// Distance, metres.
        distance_m: f32,
    },
}

/// Flight -> host: a drive command for the rover (the simulator executes it). v2: the flight software sends one
/// `Turn` / `Straight` and the next only after the [`MotionReport`] for it (or after the report timeout,
/// `config::exec::MOTION_REPORT_TIMEOUT_US`); a `Stop` is never reported and may interrupt the motion in flight,
/// whose report then follows (outcome `Stopped`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DriveCommand {
    /// Increases with every command.
    pub command_id: u32,
    /// The motion.
    pub motion: Motion,
}

/// How a commanded motion ended (v2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MotionOutcome {
    /// The commanded amount was executed.
    Completed,
    /// The wheels stopped before the commanded amount (blocked, tether limit).
    Stalled,
    /// The rover moved off the commanded motion by more than the simulator's slip threshold.
    Slipped,
    /// A `DriveCommand{Stop}` interrupted the motion (flight addition: a goal change, a cancel or a safe stop).
    Stopped,
}

/// Host -> flight: what a commanded motion achieved (v2). Exactly one per `Turn` / `Straight` command.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MotionReport {
    /// The `DriveCommand.command_id` this reports.
    pub command_id: u32,
    /// How it ended.
    pub outcome: MotionOutcome,
    /// Yaw change achieved, radians (positive counter-clockwise).
    pub achieved_yaw_rad: f32,
    /// Distance achieved along the drive direction, metres (negative = reverse).
    pub achieved_distance_m: f32,
    /// Localisation estimate of the body frame (axle centre, x forward, z up) in the world frame after the motion.
    pub pose: Pose,
}

/// Host -> flight: stop driving and planning for a goal (v2). The rover is stopped; the mission ends `Safe` with
/// reason `Cancelled` and the executive returns to `Mapping` (a new goal may follow).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalCancel {
    /// The goal to cancel (must be the goal being planned or driven, else `Nack(UnknownGoal)`).
    pub goal_id: u32,
}

/// State of the closed-loop mission (v2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MissionState {
    /// No goal yet.
    Idle,
    /// Integrating scans, no goal being pursued.
    Mapping,
    /// Planning (or replanning) toward the goal.
    Planning,
    /// A motion is being driven (one drive command at a time).
    Driving,
    /// Re-checking the remaining plan on the updated map after a motion or a scan.
    Verifying,
    /// The current pose is within the goal tolerance.
    Arrived,
    /// Stopped and holding; `MissionStatus.reason` says why.
    Safe,
}

/// Why a mission is `Safe` (v2). Each reason's doc says what a person can do about it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum StopReason {
    /// Not stopped.
    None,
    /// A `Shutdown` was received; reboot or reconfigure to continue.
    Shutdown,
    /// The host cancelled the goal; send a new `GoalRequest` to continue.
    Cancelled,
    /// The goal was refused when set up (see the `PlanStatus` and the flight log: no map, start or goal does not
    /// settle); map more or move the goal.
    GoalRefused,
    /// The planner found no path within budget (or only an approximate one while `allow_approximate` is false);
    /// raise the budget, allow approximate solutions, or map the gap.
    NoSolution,
    /// The current state's stability margin on the map is below `min_margin_n`; recover by hand (winch in).
    MarginBelowMinimum,
    /// Tracked tether length and encoder payout disagree beyond `payout_tolerance_m` even after re-predicting the
    /// anchors on the current map (e.g. a snag on an unmapped rock); inspect the tether.
    TetherInconsistent,
    /// The encoder tension exceeded `Configure.tether.max_tension_n`; check for a snag or lower the slope.
    TensionLimit,
    /// The remaining plan needs more tether than `max_payout_m`; move the goal or use a longer tether.
    PayoutLimit,
    /// A reported pose jumped against odometry more than physically possible; check localisation.
    PoseJump,
    /// A motion stalled and no replan made progress; inspect the terrain ahead.
    MotionStalled,
    /// More replans than `config::mission::MAX_REPLANS` for one goal; the map or the goal needs a look.
    ReplanLimit,
    /// No `MotionReport` arrived within the report timeout (flight addition); check the link and the rover.
    MotionTimeout,
    /// Scans kept disagreeing with odometry (flight addition); check localisation.
    ScanInconsistent,
    /// The flight computer was reset (watchdog or command) and recovered the tether state it had checkpointed
    /// (`nav::retained`): send `Configure` (the same root anchor) and a goal to continue from it.
    Reset,
    /// The flight computer was reset and its tether checkpoint does not read back: the anchor history is unknown,
    /// goals are refused (the rover must not plan with a straight tether it may not have); inspect the tether.
    TetherStateLost,
}

/// Flight -> host: the mission's state (v2). Sent on every mission-state change, after every accepted motion
/// report, and with each `Telemetry` frame.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MissionStatus {
    /// The goal being pursued (0 before the first goal).
    pub goal_id: u32,
    /// Mission state.
    pub state: MissionState,
    /// Why the mission is `Safe` (`StopReason::None` otherwise).
    pub reason: StopReason,
    /// Distance driven on this goal (sum of the reported achieved distances), metres.
    pub distance_driven_m: f32,
    /// Length of the tracked anchor history's tether to the current pose, metres.
    pub predicted_payout_m: f32,
    /// Last accepted encoder payout, metres.
    pub measured_payout_m: f32,
    /// Last accepted encoder tension, newtons.
    pub tension_n: f32,
    /// Stability margin of the current state on the onboard map, newtons.
    pub margin_n: f32,
    /// Distance of the current pose from the plan being driven, metres.
    pub cross_track_m: f32,
    /// Replans for this goal.
    pub replans: u32,
    /// Length of the tracked anchor history.
    pub anchors: u8,
    /// Motion reports accepted for this goal.
    pub motions_done: u32,
    /// Tether readings rejected by the navigator (payout jump larger than physically possible) (flight addition).
    pub tether_rejected: u32,
    /// Motion reports whose pose jumped against odometry, rejected (flight addition).
    pub pose_jumps: u32,
    /// Scans whose pose disagreed with odometry, not integrated (flight addition).
    pub scans_rejected: u32,
    /// Re-estimates of the anchor history after an encoder disagreement (flight addition).
    pub tether_reestimates: u32,
}

/// Flight executive mode.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum Mode {
    /// Booted, waiting for configuration and data.
    Idle,
    /// Integrating sensor scans into the map.
    Mapping,
    /// Planning toward a goal.
    Planning,
    /// Issuing drive commands along a plan.
    Driving,
    /// Holding position after a shutdown or fault; only ticks and telemetry requests are accepted.
    Safe,
}

/// The onboard map as telemetry reports it (all zero while no map is wired in).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct MapStatus {
    /// Voxel blocks in use.
    pub blocks_used: u32,
    /// Voxel blocks in the pool.
    pub blocks_capacity: u32,
    /// Scans integrated into the map.
    pub scans_integrated: u32,
    /// Points whose ray was integrated.
    pub points_integrated: u32,
    /// Points ignored (not finite, too near, too far).
    pub points_rejected: u32,
    /// Voxel updates lost because a block could not be allocated (pool full or index probe exhausted).
    pub voxels_dropped: u32,
    /// Scans during which the pool was full or the index probe ran out.
    pub pool_errors: u32,
    /// ESDF updates that ran out of their sweep budget (the next update continues).
    pub esdf_budget_exhausted: u32,
    /// Terrain tiles uploaded complete and swapped in for the homotopy planner (v7).
    pub tiles_loaded: u32,
    /// The id of the tile in use (0 before the first).
    pub tile_id: u32,
    /// Tile uploads abandoned incomplete (a chunk 0 started another) (v7).
    pub tiles_abandoned: u32,
}

/// Largest use of each bounded resource since boot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct HighWater {
    /// Transmit queue, bytes.
    pub tx_queue: u32,
    /// Receive staging buffer, bytes.
    pub rx_staging: u32,
    /// Largest decoded frame, bytes.
    pub frame_len: u32,
    /// Reassembly buffer, points.
    pub scan_points: u32,
    /// Log queue, records.
    pub log_queue: u32,
    /// Frames dispatched in one step.
    pub frames_per_step: u32,
    /// Bytes read in one step.
    pub rx_bytes_per_step: u32,
}

/// Flight -> host: counters and state of the executive.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Telemetry {
    /// Flight time, microseconds.
    pub time_us: u64,
    /// Current mode.
    pub mode: Mode,
    /// A `Configure` has been accepted.
    pub configured: bool,
    /// Frames accepted (this request included).
    pub frames_accepted: u32,
    /// Frames rejected, indexed by [`NackReason`] wire value.
    pub frames_rejected: [u32; NACK_REASON_COUNT],
    /// Frames sent by the flight software (this one excluded).
    pub frames_sent: u32,
    /// Bytes received.
    pub bytes_received: u32,
    /// Bytes queued for sending.
    pub bytes_sent: u32,
    /// Executive steps run.
    pub steps: u32,
    /// Steps that stopped reading because the byte budget ran out.
    pub steps_rx_budget_exhausted: u32,
    /// Steps that stopped dispatching because the frame budget ran out.
    pub steps_frame_budget_exhausted: u32,
    /// Scans completely reassembled and handed to the map.
    pub scans_completed: u32,
    /// Scans abandoned incomplete (a new scan started before all chunks arrived).
    pub scans_abandoned: u32,
    /// Scan being reassembled (0 if none).
    pub scan_in_progress: u32,
    /// Chunks of that scan received so far (they may arrive in any order).
    pub scan_chunks_received: u16,
    /// Tether readings accepted.
    pub tether_readings: u32,
    /// Goal requests accepted.
    pub goals_received: u32,
    /// Motion reports accepted (v2).
    pub motion_reports: u32,
    /// Drive commands whose report did not arrive within the report timeout (v2).
    pub motion_report_timeouts: u32,
    /// Goal cancels accepted (v2).
    pub goal_cancels: u32,
    /// State of the latest goal.
    pub plan_state: PlanState,
    /// Log records dropped (queue full or rate limit).
    pub log_dropped: u32,
    /// Outgoing frames dropped because the transmit queue was full.
    pub tx_dropped: u32,
    /// Errors reported by the link or the watchdog.
    pub device_errors: u32,
    /// Mode changes refused because the transition table does not allow them (a bug if ever non-zero).
    pub illegal_transitions: u32,
    /// High-water marks.
    pub high_water: HighWater,
    /// The onboard map.
    pub map: MapStatus,
    /// Host sequence numbers skipped: frames lost or damaged on the way up (v4; `exec` module docs).
    pub seq_gaps: u32,
    /// Host frames that arrived behind a later one (reordered or delayed on the way up), still accepted (v4).
    pub seq_late: u32,
    /// Jumps of the host sequence number by more than `SEQ_WINDOW` either way (a restarted host session) (v4).
    pub seq_resyncs: u32,
    /// Cycle accounting of the executive's steps (v4).
    pub cycle: CycleStats,
    /// Resent state-changing requests answered `Ack` without acting again (v5; `exec` module docs).
    pub requests_repeated: u32,
    /// Drive commands sent again because their `MotionReport` was late (v5; `DRIVE_COMMAND_RESEND_US`).
    pub drive_resends: u32,
}

/// Cycle accounting of [`Telemetry`] (v4): each executive step's duration on the flight clock against the step
/// budget (`config::exec::STEP_BUDGET_US`), as F Prime's rate groups account their cycles.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CycleStats {
    /// The step budget, microseconds.
    pub budget_us: u32,
    /// Longest step since boot, microseconds (saturating).
    pub max_step_us: u32,
    /// Longest step since the previous `Telemetry` frame, microseconds (saturating).
    pub period_max_step_us: u32,
    /// Steps longer than the budget since boot (saturating).
    pub slips: u32,
}

/// Flight -> host: a forwarded log record (bounded text).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Log {
    /// Severity.
    pub level: LogLevel,
    /// Text, cut to `MAX_LOG_TEXT` bytes at a character boundary.
    pub text: String<MAX_LOG_TEXT>,
}

/// Any message of set v2.
#[derive(Debug, Clone, PartialEq)]
#[allow(missing_docs)]
pub enum Message {
    TimeTick(TimeTick),
    SensorChunk(SensorChunk),
    TetherReading(TetherReading),
    GoalRequest(GoalRequest),
    Configure(Configure),
    Shutdown(Shutdown),
    TelemetryRequest(TelemetryRequest),
    MotionReport(MotionReport),
    GoalCancel(GoalCancel),
    TileChunk(TileChunk),
    Ack(Ack),
    Nack(Nack),
    PlanStatus(PlanStatus),
    Plan(Plan),
    DriveCommand(DriveCommand),
    Telemetry(Telemetry),
    Log(Log),
    MissionStatus(MissionStatus),
    TeamConfigure(TeamConfigure),
    TeamScanChunk(TeamScanChunk),
    TeamReport(TeamReport),
    TeamCommand(TeamCommand),
}

impl From<Invalid> for NackReason {
    fn from(e: Invalid) -> Self {
        match e {
            Invalid::NonFinite => NackReason::NonFinite,
            Invalid::NotUnitQuaternion => NackReason::NotUnitQuaternion,
            Invalid::OutOfRange => NackReason::OutOfRange,
            Invalid::TileTooLarge => NackReason::TileTooLarge,
            Invalid::TileResolution => NackReason::TileResolution,
            Invalid::UnknownRobot => NackReason::UnknownRobot,
            Invalid::TooManyChunks => NackReason::TooManyChunks,
            Invalid::ChunkIndexOutOfRange => NackReason::ChunkIndexOutOfRange,
        }
    }
}


impl Validate for Pose {
    fn validate(&self) -> Result<(), Invalid> {
        self.position.validate()?;
        let q = &self.orientation;
        finite(q.x)?;
        finite(q.y)?;
        finite(q.z)?;
        finite(q.w)?;
        let n2 = q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w;
        if libm::fabsf(libm::sqrtf(n2) - 1.0) <= QUATERNION_NORM_TOLERANCE {
            Ok(())
        } else {
            Err(Invalid::NotUnitQuaternion)
        }
    }
}

impl Validate for SensorChunk {
    /// Checks the pose and points. Chunk indices and counts are checked by the reassembler (they have their own
    /// reasons), so a chunk with `chunk_index >= chunk_count` passes here.
    fn validate(&self) -> Result<(), Invalid> {
        self.sensor_pose.validate()?;
        self.points.iter().try_for_each(Validate::validate)
    }
}

impl Validate for TileChunk {
    /// Checks the georeference, the spacing, the shape and the heights. Chunk order, counts and lengths are checked
    /// by the tile reassembly (`reassembly::TileAssembler`, their own reasons).
    fn validate(&self) -> Result<(), Invalid> {
        finite(self.origin_x_m)?;
        finite(self.origin_y_m)?;
        finite(self.resolution_m)?;
        if !(MIN_TILE_RESOLUTION_M..=MAX_TILE_RESOLUTION_M).contains(&f64::from(self.resolution_m)) {
            return Err(Invalid::TileResolution);
        }
        if self.rows == 0 || self.cols == 0 {
            return Err(Invalid::OutOfRange);
        }
        if usize::from(self.rows) > MAX_TILE_SIDE || usize::from(self.cols) > MAX_TILE_SIDE {
            return Err(Invalid::TileTooLarge);
        }
        self.heights.iter().try_for_each(|h| finite(*h))
    }
}

impl Validate for TetherReading {
    fn validate(&self) -> Result<(), Invalid> {
        non_negative(self.payout_m)?;
        non_negative(self.tension_n)?;
        finite(self.boom_angle_rad)
    }
}

impl Validate for GoalRequest {
    fn validate(&self) -> Result<(), Invalid> {
        self.position.validate()?;
        positive(self.tolerance_m)?;
        if self.max_iterations == 0 {
            return Err(Invalid::OutOfRange);
        }
        Ok(())
    }
}

impl Validate for Configure {
    fn validate(&self) -> Result<(), Invalid> {
        let r = &self.rover;
        positive(r.mass_kg)?;
        positive(r.wheel_radius_m)?;
        positive(r.axle_length_m)?;
        positive(r.boom_length_m)?;
        positive(r.friction_coefficient)?;
        self.tether.root_anchor.validate()?;
        positive(self.tether.max_payout_m)?;
        positive(self.tether.max_tension_n)?;
        let p = &self.planner;
        if p.max_iterations == 0 || p.batch_size == 0 {
            return Err(Invalid::OutOfRange);
        }
        finite(p.goal_bias)?;
        if !(0.0..=1.0).contains(&p.goal_bias) {
            return Err(Invalid::OutOfRange);
        }
        let period = self.telemetry.period_ms;
        if period != 0 && period < MIN_TELEMETRY_PERIOD_MS {
            return Err(Invalid::OutOfRange);
        }
        self.mission.validate()?;
        self.map.map_or(Ok(()), |m| m.validate())
    }
}

impl Validate for MissionConfig {
    fn validate(&self) -> Result<(), Invalid> {
        positive(self.replan_cross_track_m)?;
        positive(self.payout_tolerance_m)?;
        non_negative(self.min_margin_n)
    }
}

impl Validate for MapSettings {
    fn validate(&self) -> Result<(), Invalid> {
        [
            self.voxel_size_m,
            self.truncation_m,
            self.max_weight,
            self.max_carve_length_m,
            self.max_range_m,
            self.min_range_m,
            self.esdf_band_voxels,
            self.esdf_site_tolerance_voxels,
            self.esdf_max_distance_m,
        ]
        .into_iter()
        .try_for_each(finite)?;
        MapConfig::from(*self).validate().map_err(|_| Invalid::OutOfRange)
    }
}

impl Validate for MotionReport {
    fn validate(&self) -> Result<(), Invalid> {
        finite(self.achieved_yaw_rad)?;
        finite(self.achieved_distance_m)?;
        self.pose.validate()
    }
}

impl Validate for MissionStatus {
    fn validate(&self) -> Result<(), Invalid> {
        [
            self.distance_driven_m,
            self.predicted_payout_m,
            self.measured_payout_m,
            self.tension_n,
            self.margin_n,
            self.cross_track_m,
        ]
        .into_iter()
        .try_for_each(finite)
    }
}

impl Validate for PlanStatus {
    fn validate(&self) -> Result<(), Invalid> {
        self.best_cost.map_or(Ok(()), finite)
    }
}

impl Validate for Plan {
    fn validate(&self) -> Result<(), Invalid> {
        if self.parts == 0 || self.part >= self.parts {
            return Err(Invalid::OutOfRange);
        }
        self.waypoints.iter().try_for_each(|w| {
            w.pose.validate()?;
            w.anchors.iter().try_for_each(Validate::validate)?;
            finite(w.stability_margin)
        })
    }
}

impl Validate for DriveCommand {
    fn validate(&self) -> Result<(), Invalid> {
        match self.motion {
            Motion::Stop { .. } => Ok(()),
            Motion::Turn { yaw_rad } => finite(yaw_rad),
            Motion::Straight { distance_m } => finite(distance_m),
        }
    }
}

impl Validate for Message {
    fn validate(&self) -> Result<(), Invalid> {
        match self {
            Message::SensorChunk(m) => m.validate(),
            Message::TileChunk(m) => m.validate(),
            Message::TetherReading(m) => m.validate(),
            Message::GoalRequest(m) => m.validate(),
            Message::Configure(m) => m.validate(),
            Message::PlanStatus(m) => m.validate(),
            Message::Plan(m) => m.validate(),
            Message::DriveCommand(m) => m.validate(),
            Message::MotionReport(m) => m.validate(),
            Message::MissionStatus(m) => m.validate(),
            Message::TeamConfigure(m) => m.validate(),
            Message::TeamScanChunk(m) => m.validate(),
            Message::TeamReport(m) => m.validate(),
            Message::TeamCommand(m) => m.validate(),
            Message::TimeTick(_)
            | Message::GoalCancel(_)
            | Message::Shutdown(_)
            | Message::TelemetryRequest(_)
            | Message::Ack(_)
            | Message::Nack(_)
            | Message::Telemetry(_)
            | Message::Log(_) => Ok(()),
        }
    }
}

impl Message {
    /// The kind byte of this message.
    pub fn kind(&self) -> MessageKind {
        match self {
            Message::TimeTick(_) => MessageKind::TimeTick,
            Message::SensorChunk(_) => MessageKind::SensorChunk,
            Message::TetherReading(_) => MessageKind::TetherReading,
            Message::GoalRequest(_) => MessageKind::GoalRequest,
            Message::Configure(_) => MessageKind::Configure,
            Message::Shutdown(_) => MessageKind::Shutdown,
            Message::TelemetryRequest(_) => MessageKind::TelemetryRequest,
            Message::MotionReport(_) => MessageKind::MotionReport,
            Message::GoalCancel(_) => MessageKind::GoalCancel,
            Message::TileChunk(_) => MessageKind::TileChunk,
            Message::Ack(_) => MessageKind::Ack,
            Message::Nack(_) => MessageKind::Nack,
            Message::PlanStatus(_) => MessageKind::PlanStatus,
            Message::Plan(_) => MessageKind::Plan,
            Message::DriveCommand(_) => MessageKind::DriveCommand,
            Message::Telemetry(_) => MessageKind::Telemetry,
            Message::Log(_) => MessageKind::Log,
            Message::MissionStatus(_) => MessageKind::MissionStatus,
            Message::TeamConfigure(_) => MessageKind::TeamConfigure,
            Message::TeamScanChunk(_) => MessageKind::TeamScanChunk,
            Message::TeamReport(_) => MessageKind::TeamReport,
            Message::TeamCommand(_) => MessageKind::TeamCommand,
        }
    }

    /// Serialises the body (without the enum tag: the kind is in the header) into `buf`; returns its length.
    pub fn encode_body(&self, buf: &mut [u8]) -> Result<usize, postcard::Error> {
        let out = match self {
            Message::TimeTick(m) => postcard::to_slice(m, buf),
            Message::SensorChunk(m) => postcard::to_slice(m, buf),
            Message::TetherReading(m) => postcard::to_slice(m, buf),
            Message::GoalRequest(m) => postcard::to_slice(m, buf),
            Message::Configure(m) => postcard::to_slice(m, buf),
            Message::Shutdown(m) => postcard::to_slice(m, buf),
            Message::TelemetryRequest(m) => postcard::to_slice(m, buf),
            Message::MotionReport(m) => postcard::to_slice(m, buf),
            Message::GoalCancel(m) => postcard::to_slice(m, buf),
            Message::TileChunk(m) => postcard::to_slice(m, buf),
            Message::Ack(m) => postcard::to_slice(m, buf),
            Message::Nack(m) => postcard::to_slice(m, buf),
            Message::PlanStatus(m) => postcard::to_slice(m, buf),
            Message::Plan(m) => postcard::to_slice(m, buf),
            Message::DriveCommand(m) => postcard::to_slice(m, buf),
            Message::Telemetry(m) => postcard::to_slice(m, buf),
            Message::Log(m) => postcard::to_slice(m, buf),
            Message::MissionStatus(m) => postcard::to_slice(m, buf),
            Message::TeamConfigure(m) => postcard::to_slice(m, buf),
            Message::TeamScanChunk(m) => postcard::to_slice(m, buf),
            Message::TeamReport(m) => postcard::to_slice(m, buf),
            Message::TeamCommand(m) => postcard::to_slice(m, buf),
        }?;
        Ok(out.len())
    }
}
