//! Team messages (protocol v8): the climbing team's mission over the link (Morad et al. sections IV-V; issue 21).
//!
//! The hub's flight computer runs the team mission (`crate::plan::team::mission`); the host (simulator or ground)
//! executes its orders on the robots and reports back:
//!
//! - host -> flight [`TeamConfigure`] (0x0B): the grid of scenes, the four robots' start grip points, the local
//!   planner's [`TeamParams`] and the mission's [`MissionParams`], scenes blocked beforehand. Then a
//!   `GoalRequest { planner: Team }` names the goal and starts the mission.
//! - flight -> host [`TeamCommand`] (0x89): the next order ([`TeamOrder`]: scan, hop, move the hub, done with its
//!   outcome), numbered by `command_id` (a resend carries the same id; the host executes an id once).
//! - host -> flight [`TeamScanChunk`] (0x0C): a robot's scan in chunks of at most `MAX_POINTS_PER_CHUNK` points,
//!   with its grip point, outward direction and the hub position measured by the tether encoders; the last chunk
//!   steps the mission.
//! - host -> flight [`TeamReport`] (0x0D): where a robot gripped after its hop, where the hub stopped, or a robot
//!   lost; each with the team's state (grip state and tether leg length of every robot).
//!
//! Limits (`config::protocol`): robots `TEAM_SIZE` (4), `MAX_TEAM_BLOCKED_CELLS` (32) blocked scenes per
//! configuration, `MAX_CHUNKS_PER_TEAM_SCAN` (32) chunks of a scan (`TEAM_SCAN_POINTS_CAPACITY` = 4096 points, the
//! local planner's `SCENE_MAX_POINTS`), grids of at most `GLOBAL_GRID_MAX_CELLS` (4096) scenes.

use heapless::Vec;
use serde::{Deserialize, Serialize};

use super::values::{non_negative, positive, Invalid, Point3, Validate};
use crate::config::protocol::{MAX_CHUNKS_PER_TEAM_SCAN, MAX_POINTS_PER_CHUNK, MAX_TEAM_BLOCKED_CELLS};
use crate::config::team::{MissionParams, TeamParams, GLOBAL_GRID_MAX_CELLS, TEAM_SIZE};

/// Unit vectors of the grid of scenes must have norm within this of 1 and be perpendicular within it.
pub const TEAM_AXIS_TOLERANCE: f32 = 1e-3;

/// The grid of scenes (`crate::plan::team::mission::SceneGrid` on the wire).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TeamGrid {
    /// Corner of scene (0, 0), metres.
    pub origin: Point3,
    /// Unit vector along the columns.
    pub u: Point3,
    /// Unit vector along the rows, perpendicular to `u`.
    pub v: Point3,
    /// Scene size, metres (> 0).
    pub cell_m: f32,
    /// Columns (>= 1); `width * height <= GLOBAL_GRID_MAX_CELLS`.
    pub width: u16,
    /// Rows (>= 1).
    pub height: u16,
}

/// The local planner's parameters: `config::team::TeamParams` field for field (defaults and meaning there).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct TeamPlannerSettings {
    pub h_max_m: f32,
    pub r_max_m: f32,
    pub landing_margin_m: f32,
    pub keep_permille: u16,
    pub w_relative_height: f32,
    pub w_flatness: f32,
    pub relief_scale_m: f32,
    pub flatness_scale_m: f32,
    pub score_radius_m: f32,
    pub unobserved_penalty: f32,
    pub risk_m: f32,
    pub fill_max_cells: u16,
    pub fill_sweeps: u16,
    pub astar_budget: u32,
}

/// `From` both ways between a parameter struct and its wire mirror, field for field (`wire: config`).
macro_rules! mirror {
    ($wire:ty, $cfg:ty, $($w:ident: $c:ident),+ $(,)?) => {
        impl From<$cfg> for $wire {
            fn from(p: $cfg) -> Self {
                Self { $($w: p.$c),+ }
            }
        }
        impl From<$wire> for $cfg {
            fn from(p: $wire) -> Self {
                Self { $($c: p.$w),+ }
            }
        }
    };
}

mirror!(
    TeamPlannerSettings,
    TeamParams,
    h_max_m: h_max,
    r_max_m: r_max,
    landing_margin_m: landing_margin,
    keep_permille: keep_permille,
    w_relative_height: w_relative_height,
    w_flatness: w_flatness,
    relief_scale_m: relief_scale,
    flatness_scale_m: flatness_scale,
    score_radius_m: score_radius,
    unobserved_penalty: unobserved_penalty,
    risk_m: risk_m,
    fill_max_cells: fill_max_cells,
    fill_sweeps: fill_sweeps,
    astar_budget: astar_budget,
);

/// The mission's budgets and thresholds: `config::team::MissionParams` field for field (defaults there).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[allow(missing_docs)]
pub struct TeamMissionSettings {
    pub max_rounds: u32,
    pub max_hops: u32,
    pub dstar_budget: u32,
    pub stall_rounds: u16,
    pub goal_stall_rounds: u16,
    pub progress_fraction: f32,
    pub waypoint_radius_fraction: f32,
}

mirror!(
    TeamMissionSettings,
    MissionParams,
    max_rounds: max_rounds,
    max_hops: max_hops,
    dstar_budget: dstar_budget,
    stall_rounds: stall_rounds,
    goal_stall_rounds: goal_stall_rounds,
    progress_fraction: progress_fraction,
    waypoint_radius_fraction: waypoint_radius_fraction,
);

/// Host -> flight (v8): the team mission's set-up. Accepted when no team mission runs; replaces an earlier one.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TeamConfigure {
    /// The grid of scenes.
    pub grid: TeamGrid,
    /// Each robot's start grip point, metres (the hub starts at their centroid).
    pub start: [Point3; TEAM_SIZE],
    /// The local planner's parameters.
    pub planner: TeamPlannerSettings,
    /// The mission's budgets.
    pub mission: TeamMissionSettings,
    /// Scenes known beforehand to be impassable (column, row), each inside the grid.
    pub blocked: Vec<(u16, u16), MAX_TEAM_BLOCKED_CELLS>,
}

impl TeamConfigure {
    /// A valid configuration for tests: a 4 x 3 grid of 20 m scenes around the origin, the team in an "x" of
    /// 4 m around it, default parameters.
    #[cfg(test)]
    pub(crate) fn example() -> Self {
        TeamConfigure {
            grid: TeamGrid {
                origin: Point3::new(-30.0, -30.0, 0.0),
                u: Point3::new(1.0, 0.0, 0.0),
                v: Point3::new(0.0, 1.0, 0.0),
                cell_m: 20.0,
                width: 4,
                height: 3,
            },
            start: [Point3::new(4.0, 4.0, 0.0), Point3::new(4.0, -4.0, 0.0), Point3::new(-4.0, 4.0, 0.0), Point3::new(-4.0, -4.0, 0.0)],
            planner: TeamParams::DEFAULT.into(),
            mission: MissionParams::DEFAULT.into(),
            blocked: Vec::new(),
        }
    }
}

/// A robot's grip (v8 team state).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum GripState {
    /// Gripping the surface (microspines engaged).
    Gripping,
    /// In the air or released.
    Released,
    /// Left the team (tether cut).
    Lost,
}

/// The team's state sent with every [`TeamReport`]: per robot its grip and its tether leg length measured by the
/// hub's encoders.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TeamState {
    /// Grip state per robot.
    pub grip: [GripState; TEAM_SIZE],
    /// Tether leg length per robot (hub to robot), metres (>= 0).
    pub legs_m: [f32; TEAM_SIZE],
}

/// Why a robot left the team (`crate::plan::team::mission::LossCause` on the wire).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TeamLoss {
    /// The tether was cut (node failure).
    TetherCut,
    /// The grip slipped.
    GripFailure,
}

/// What a [`TeamReport`] reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum TeamEvent {
    /// Robot `robot` gripped at `pos` after the hop `command_id` ordered.
    Landed {
        /// Robot index, `0..TEAM_SIZE`.
        robot: u8,
        /// Grip point, metres.
        pos: Point3,
    },
    /// The hub stopped at `pos` after the `MoveHub` `command_id` ordered.
    HubAt {
        /// Hub position, metres.
        pos: Point3,
    },
    /// Robot `robot` left the team (any time; `command_id` is the order it was executing or the last one).
    Lost {
        /// Robot index, `0..TEAM_SIZE`.
        robot: u8,
        /// Why.
        cause: TeamLoss,
    },
}

/// Host -> flight (v8): what an order achieved (or a robot lost), with the team's state.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TeamReport {
    /// The `TeamCommand.command_id` this answers.
    pub command_id: u32,
    /// What happened.
    pub event: TeamEvent,
    /// The team's state after it.
    pub state: TeamState,
}

/// Host -> flight (v8): one chunk of robot `robot`'s scan answering `TeamOrder::Scan`. Chunks of a scan share
/// `command_id`, `robot`, `chunk_count`, `grip`, `up` and `hub` and arrive in order `0..chunk_count`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TeamScanChunk {
    /// The `TeamCommand.command_id` of the scan order.
    pub command_id: u32,
    /// Robot index, `0..TEAM_SIZE`.
    pub robot: u8,
    /// Index of this chunk, `0..chunk_count`.
    pub chunk_index: u16,
    /// Number of chunks, `1..=MAX_CHUNKS_PER_TEAM_SCAN`.
    pub chunk_count: u16,
    /// The robot's grip point, metres.
    pub grip: Point3,
    /// Its outward direction (attitude), unit.
    pub up: Point3,
    /// The hub position measured by the tether encoders when the scan was taken, metres.
    pub hub: Point3,
    /// Range points in the mission frame, metres.
    pub points: Vec<Point3, MAX_POINTS_PER_CHUNK>,
}

/// How a team mission ended (`crate::plan::team::mission::MissionOutcome` on the wire).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum TeamOutcome {
    /// The hub is within the goal tolerance.
    GoalReached,
    /// D* Lite found no route of scenes.
    NoRoute,
    /// In the goal's scene, the goal cannot be reached.
    GoalUnreachable,
    /// Every tether is cut.
    TeamLost,
    /// `max_rounds` ran out.
    RoundsExhausted,
    /// `max_hops` ran out.
    HopsExhausted,
    /// D* Lite's budget ran out.
    GlobalPlannerExhausted,
    /// The hub left the grid of scenes.
    LeftGrid,
    /// The mission was stopped (`GoalCancel`, a new team goal or configuration, `Shutdown`).
    Aborted,
}

/// The next order of the team mission.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum TeamOrder {
    /// Robot `robot` scans and sends [`TeamScanChunk`]s.
    Scan {
        /// Robot index.
        robot: u8,
    },
    /// Robot `robot` hops to `target` and reports `Landed` (or `Lost`).
    Hop {
        /// Robot index.
        robot: u8,
        /// The planned anchor, metres.
        target: Point3,
        /// The normal of the robot's planning scene (unit): the direction along which the anchor was
        /// reconstructed.
        scene_normal: Point3,
    },
    /// The hub winches to `to` and reports `HubAt`.
    MoveHub {
        /// The hub's target, metres.
        to: Point3,
    },
    /// The mission is over.
    Done {
        /// How it ended.
        outcome: TeamOutcome,
        /// Rounds completed.
        rounds: u32,
        /// Hops commanded.
        hops: u32,
        /// Walls added to D* Lite.
        walls: u32,
    },
}

/// Flight -> host (v8): the team mission's next order.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TeamCommand {
    /// Increases with every new order; a resend carries the same id.
    pub command_id: u32,
    /// The team goal (`GoalRequest.goal_id`).
    pub goal_id: u32,
    /// The order.
    pub order: TeamOrder,
}

fn robot_index(r: u8) -> Result<(), Invalid> {
    if usize::from(r) < TEAM_SIZE {
        Ok(())
    } else {
        Err(Invalid::UnknownRobot)
    }
}

fn dot(a: &Point3, b: &Point3) -> f32 {
    a.x * b.x + a.y * b.y + a.z * b.z
}

fn unit(a: &Point3) -> Result<(), Invalid> {
    a.validate()?;
    if libm::fabsf(libm::sqrtf(dot(a, a)) - 1.0) <= TEAM_AXIS_TOLERANCE {
        Ok(())
    } else {
        Err(Invalid::OutOfRange)
    }
}

impl Validate for TeamConfigure {
    fn validate(&self) -> Result<(), Invalid> {
        let g = &self.grid;
        g.origin.validate()?;
        unit(&g.u)?;
        unit(&g.v)?;
        if libm::fabsf(dot(&g.u, &g.v)) > TEAM_AXIS_TOLERANCE {
            return Err(Invalid::OutOfRange);
        }
        positive(g.cell_m)?;
        let cells = usize::from(g.width) * usize::from(g.height);
        if cells == 0 || cells > GLOBAL_GRID_MAX_CELLS {
            return Err(Invalid::OutOfRange);
        }
        self.start.iter().try_for_each(Validate::validate)?;
        let p = &self.planner;
        [p.h_max_m, p.r_max_m, p.relief_scale_m, p.flatness_scale_m, p.score_radius_m].into_iter().try_for_each(positive)?;
        [p.landing_margin_m, p.w_relative_height, p.w_flatness, p.unobserved_penalty, p.risk_m]
            .into_iter()
            .try_for_each(non_negative)?;
        if p.keep_permille == 0 || p.keep_permille > 1000 || p.astar_budget == 0 {
            return Err(Invalid::OutOfRange);
        }
        let m = &self.mission;
        positive(m.progress_fraction)?;
        positive(m.waypoint_radius_fraction)?;
        if m.max_rounds == 0 || m.max_hops == 0 || m.dstar_budget == 0 || m.stall_rounds == 0 || m.goal_stall_rounds == 0 {
            return Err(Invalid::OutOfRange);
        }
        if self.blocked.iter().any(|&(c, r)| c >= g.width || r >= g.height) {
            return Err(Invalid::OutOfRange);
        }
        Ok(())
    }
}

impl Validate for TeamReport {
    fn validate(&self) -> Result<(), Invalid> {
        self.state.legs_m.iter().copied().try_for_each(non_negative)?;
        match &self.event {
            TeamEvent::Landed { robot, pos } => {
                robot_index(*robot)?;
                pos.validate()
            }
            TeamEvent::HubAt { pos } => pos.validate(),
            TeamEvent::Lost { robot, .. } => robot_index(*robot),
        }
    }
}

impl Validate for TeamScanChunk {
    fn validate(&self) -> Result<(), Invalid> {
        robot_index(self.robot)?;
        self.grip.validate()?;
        unit(&self.up)?;
        self.hub.validate()?;
        if self.chunk_count == 0 || self.chunk_count > MAX_CHUNKS_PER_TEAM_SCAN {
            return Err(Invalid::TooManyChunks);
        }
        if self.chunk_index >= self.chunk_count {
            return Err(Invalid::ChunkIndexOutOfRange);
        }
        self.points.iter().try_for_each(Validate::validate)
    }
}

impl Validate for TeamCommand {
    fn validate(&self) -> Result<(), Invalid> {
        match &self.order {
            TeamOrder::Scan { robot } => robot_index(*robot),
            TeamOrder::Hop { robot, target, scene_normal } => {
                robot_index(*robot)?;
                target.validate()?;
                scene_normal.validate()
            }
            TeamOrder::MoveHub { to } => to.validate(),
            TeamOrder::Done { .. } => Ok(()),
        }
    }
}
