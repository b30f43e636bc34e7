//! The team mission on the hub's flight computer (Morad et al. sections IV-V, Figs. 7 and 12; scenario D of
//! `SCENARIOS.md`): global D* Lite over a grid of scenes, the bounded-leg A* per robot and hop, the climbing
//! order, the hub motion, walls and node loss, as one step-wise state machine.
//!
//! The machine is driven by reports (a robot's scan with its grip point, outward direction and the hub position
//! measured by the tether encoders; where a robot gripped after a hop; where the hub stopped; a robot lost) and
//! answers each with the next [`Command`]: scan robot m, hop robot m to an anchor, move the hub, or
//! [`Command::Done`] with a [`MissionOutcome`]. No heap: the D* Lite storage and the local planner's arena are lent
//! by the caller (a board's statics, the host's boxes); every loop is bounded by a capacity or by
//! [`MissionParams`]' budgets.
//!
//! One round (section IV, Fig. 4): every attached robot in the order of [`Team::next_mover`] scans, plans its hops
//! with [`LocalPlanner::plan`] towards its slot around the next scene's waypoint, and hops to the first anchor of the
//! plan (the paper replans before each hop); the three others hold. Before a hop is commanded the mission checks it
//! against the **reported** hub position and grip point: hop <= h_max - landing_margin and anchor-to-hub
//! <= r_max - landing_margin. At the end of the round the hub is moved towards the attached robots' centroid as far
//! as every tether allows ([`Team::hub_motion`]).
//!
//! Global (section V-A.7, Fig. 12): the grid of scenes ([`SceneGrid`], a plane frame cut into square cells) holds
//! the team's D* Lite. The team's cell is the hub's; the waypoint is the next cell's centre (the goal itself in the
//! goal's cell), at the height over the scene plane of the scan points around it (the linear blend of the hub's
//! and the goal's heights when the scan does not reach it). A crossing the local planners cannot make — the hub
//! does not get `progress_fraction * h_max` closer to the waypoint for `stall_rounds` rounds in a row — becomes a
//! wall between the two cells and D* Lite replans incrementally; no route left is
//! [`MissionOutcome::Blocked`] (`NoRoute`; in the goal's scene, `goal_stall_rounds` rounds without progress are
//! `GoalUnreachable`). A robot lost (tether cut, grip failure) leaves the team; the others continue.
//!
//! Parameters ([`MissionParams`], defaults): `max_rounds` 200, `max_hops` 2000, `dstar_budget` 20 000 expansions,
//! `stall_rounds` 2, `goal_stall_rounds` 6, `progress_fraction` 0.1, `waypoint_radius_fraction` 0.25; the local planner's
//! [`TeamParams`] (h_max 10 m, r_max 15 m, landing_margin 0.5 m, ...). Capacities: [`MISSION_MAX_WALLS`] (64)
//! walls and [`MISSION_MAX_ROUTE`] (256) route cells recorded.

use super::dstar_lite::{DStarError, DStarLite, DStarOutcome, DStarStorage, PathOutcome};
use super::formation::Team;
use super::LocalPlanner;
use crate::config::team::{MissionParams, TeamParams, MISSION_MAX_ROUTE, MISSION_MAX_WALLS};
use crate::geom::{floor_i32, is_finite3, norm3, Real, Vec3};
use crate::plan::status::{Ended, Status};
use heapless::Vec as HVec;

/// A scene cell (column, row).
pub type Cell = (i64, i64);

/// The global grid of scenes: square cells of `cell` metres over the plane through `origin` spanned by the unit
/// vectors `u` (columns) and `v` (rows); cell (0, 0) has its corner at `origin`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneGrid {
    /// Corner of cell (0, 0).
    pub origin: Vec3,
    /// Unit vector along the columns (x).
    pub u: Vec3,
    /// Unit vector along the rows (y), perpendicular to `u`.
    pub v: Vec3,
    /// Cell (scene) size, metres.
    pub cell: Real,
    /// Columns.
    pub width: u32,
    /// Rows.
    pub height: u32,
}

impl SceneGrid {
    /// Unit normal of the scene plane (`u` x `v`).
    pub fn normal(&self) -> Vec3 {
        self.u.cross(&self.v)
    }

    /// Plane coordinates of `p`.
    pub fn plane(&self, p: &Vec3) -> (Real, Real) {
        let d = p - self.origin;
        (d.dot(&self.u), d.dot(&self.v))
    }

    /// Height of `p` over the scene plane.
    pub fn height_of(&self, p: &Vec3) -> Real {
        (p - self.origin).dot(&self.normal())
    }

    /// The cell holding `p`'s projection, `None` outside the grid.
    pub fn cell_of(&self, p: &Vec3) -> Option<Cell> {
        let (a, b) = self.plane(p);
        if !(a.is_finite() && b.is_finite() && self.cell > 0.0) {
            return None;
        }
        let (x, y) = (floor_i32(a / self.cell) as i64, floor_i32(b / self.cell) as i64);
        (x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64).then_some((x, y))
    }

    /// Plane coordinates of a cell's centre.
    pub fn centre(&self, c: Cell) -> (Real, Real) {
        ((c.0 as Real + 0.5) * self.cell, (c.1 as Real + 0.5) * self.cell)
    }

    /// The point at plane coordinates (a, b) and height h.
    pub fn point(&self, a: Real, b: Real, h: Real) -> Vec3 {
        self.origin + self.u * a + self.v * b + self.normal() * h
    }
}

/// What the hub's flight computer asks for next.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Command {
    /// Robot `robot` scans from where it grips and reports ([`Report::Scan`]).
    Scan {
        /// Robot index.
        robot: usize,
    },
    /// Robot `robot` hops to `target` and reports where it gripped ([`Report::Landed`]).
    Hop {
        /// Robot index.
        robot: usize,
        /// The planned anchor.
        target: Vec3,
    },
    /// The hub winches to `to` (end of a round) and reports where it stopped ([`Report::HubAt`]).
    MoveHub {
        /// The hub's target.
        to: Vec3,
    },
    /// The mission is over.
    Done(MissionOutcome),
}

/// Why a robot left the team.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LossCause {
    /// The tether was cut (node failure, section V-A.6).
    TetherCut,
    /// The grip slipped on landing or while holding; the robot's tether is cut so it does not drag the team.
    GripFailure,
}

/// What the team reports.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Report<'p> {
    /// Robot `robot`'s scan (points in the mission frame), taken gripping at `pos` with outward direction `up`;
    /// `hub` is the hub position measured at the same time (tether encoders).
    Scan {
        /// Robot index.
        robot: usize,
        /// Grip point.
        pos: Vec3,
        /// Outward direction (attitude).
        up: Vec3,
        /// Hub position.
        hub: Vec3,
        /// Range points.
        points: &'p [Vec3],
    },
    /// Robot `robot` gripped at `pos` after its hop (where it really is, not where it was sent).
    Landed {
        /// Robot index.
        robot: usize,
        /// Grip point.
        pos: Vec3,
    },
    /// The hub stopped at `pos`.
    HubAt {
        /// Hub position.
        pos: Vec3,
    },
    /// Robot `robot` left the team (any time).
    Lost {
        /// Robot index.
        robot: usize,
        /// Why.
        cause: LossCause,
    },
}

/// Why there is no route.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Blocked {
    /// D* Lite proved that no route of scenes reaches the goal's scene (walls everywhere).
    NoRoute,
    /// The team is in the goal's scene but cannot get within the goal tolerance.
    GoalUnreachable,
}

/// Which budget ran out.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Budget {
    /// `max_rounds`.
    Rounds,
    /// `max_hops`.
    Hops,
    /// D* Lite's `dstar_budget` in one (re)plan.
    GlobalPlanner,
}

/// The end of a mission.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MissionOutcome {
    /// The hub is within the goal tolerance.
    GoalReached,
    /// No way to the goal.
    Blocked(Blocked),
    /// Every tether is cut.
    TeamLost,
    /// A budget ran out (the work done so far is kept).
    BudgetExhausted(Budget),
    /// The hub left the grid of scenes.
    LeftGrid,
}

impl MissionOutcome {
    /// The word a report prints.
    pub fn label(&self) -> &'static str {
        match self {
            Self::GoalReached => "GoalReached",
            Self::Blocked(Blocked::NoRoute) => "Blocked(NoRoute)",
            Self::Blocked(Blocked::GoalUnreachable) => "Blocked(GoalUnreachable)",
            Self::TeamLost => "TeamLost",
            Self::BudgetExhausted(Budget::Rounds) => "BudgetExhausted(rounds)",
            Self::BudgetExhausted(Budget::Hops) => "BudgetExhausted(hops)",
            Self::BudgetExhausted(Budget::GlobalPlanner) => "BudgetExhausted(D* Lite)",
            Self::LeftGrid => "LeftGrid",
        }
    }
}

/// Why a mission could not be set up.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MissionError {
    /// The D* Lite storage or grid was rejected.
    Grid(DStarError),
    /// The goal (or the start hub) is outside the grid of scenes.
    OutsideGrid,
    /// A cell size that is not positive and finite.
    BadCell,
}

impl From<DStarError> for MissionError {
    fn from(e: DStarError) -> Self {
        Self::Grid(e)
    }
}

/// Counters of a mission so far.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct MissionStats {
    /// Rounds completed (hub moves).
    pub rounds: u32,
    /// Hops commanded.
    pub hops: u32,
    /// Local plans run.
    pub local_plans: u32,
    /// Local plans without a usable first hop (no solution, a scene error, or at the robot already).
    pub no_hop: u32,
    /// First hops the mission's own check against the reported hub refused.
    pub refused_hops: u32,
    /// Walls added (also those past the record's capacity).
    pub walls: u32,
    /// Reports that did not answer the pending command (ignored).
    pub ignored_reports: u32,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Await {
    Start,
    Scan(usize),
    Landing(usize),
    Hub(usize),
    Done(MissionOutcome),
}

/// The team mission of `N` robots over a local planner of capacities `P`, `V`, `E` (see [`LocalPlanner`]).
pub struct TeamMission<'a, const N: usize, const P: usize, const V: usize, const E: usize> {
    params: TeamParams,
    mp: MissionParams,
    grid: SceneGrid,
    goal: Vec3,
    goal_tol: Real,
    team: Team<N>,
    dstar: DStarLite<'a>,
    planner: &'a mut LocalPlanner<P, V, E>,
    state: Await,
    command: Command,
    here: Cell,
    goal_cell: Cell,
    best: Real,
    stall: u16,
    turns_in_round: u32,
    walls: HVec<(Cell, Cell), MISSION_MAX_WALLS>,
    route: HVec<Cell, MISSION_MAX_ROUTE>,
    lost: [Option<LossCause>; N],
    stats: MissionStats,
}

impl<'a, const N: usize, const P: usize, const V: usize, const E: usize> TeamMission<'a, N, P, V, E> {
    /// A mission for the team gripping at `start` (hub at their centroid) to bring the hub within `goal_tol` of
    /// `goal`, over `grid`, with D* Lite `storage` (at least `width * height` cells) and the local `planner`.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        grid: SceneGrid,
        goal: Vec3,
        goal_tol: Real,
        start: [Vec3; N],
        params: TeamParams,
        mp: MissionParams,
        storage: DStarStorage<'a>,
        planner: &'a mut LocalPlanner<P, V, E>,
    ) -> Result<Self, MissionError> {
        if !(grid.cell.is_finite() && grid.cell > 0.0) {
            return Err(MissionError::BadCell);
        }
        let dstar = DStarLite::new(grid.width, grid.height, storage)?;
        let goal_cell = grid.cell_of(&goal).ok_or(MissionError::OutsideGrid)?;
        let team = Team::new(start);
        let here = grid.cell_of(&team.hub).ok_or(MissionError::OutsideGrid)?;
        Ok(Self {
            params,
            mp,
            grid,
            goal,
            goal_tol,
            team,
            dstar,
            planner,
            state: Await::Start,
            command: Command::Done(MissionOutcome::LeftGrid),
            here,
            goal_cell,
            best: Real::INFINITY,
            stall: 0,
            turns_in_round: 0,
            walls: HVec::new(),
            route: HVec::new(),
            lost: [None; N],
            stats: MissionStats::default(),
        })
    }

    /// A scene known beforehand to be impassable (e.g. off the orbital map); call before [`Self::begin`].
    pub fn block_cell(&mut self, c: Cell) -> Result<(), MissionError> {
        Ok(self.dstar.set_blocked(c.0, c.1, true)?)
    }

    /// Plan the route and give the first command.
    pub fn begin(&mut self) -> Command {
        if self.state != Await::Start {
            return self.command;
        }
        let _ = self.route.push(self.here);
        let out = self.dstar.plan(self.here, self.goal_cell, self.mp.dstar_budget);
        if let Some(end) = self.route_outcome(out) {
            return self.finish(end);
        }
        if self.at_goal() {
            return self.finish(MissionOutcome::GoalReached);
        }
        self.best = self.waypoint_distance();
        self.next_turn()
    }

    /// Take a report, give the next command. A report that does not answer the pending command is ignored (the
    /// pending command is given again), except [`Report::Lost`], which is taken at any time.
    pub fn step(&mut self, report: Report<'_>) -> Command {
        if let Await::Done(_) = self.state {
            return self.command;
        }
        match (report, self.state) {
            (Report::Lost { robot, cause }, state) => self.robot_lost(robot, cause, state),
            (Report::Scan { robot, pos, up, hub, points }, Await::Scan(m)) if robot == m => {
                self.local_plan(m, pos, up, hub, points)
            }
            (Report::Landed { robot, pos }, Await::Landing(m)) if robot == m => {
                self.team.hop(m, pos);
                self.next_turn()
            }
            (Report::HubAt { pos }, Await::Hub(m)) => {
                self.team.hub = pos;
                match self.end_of_round() {
                    Some(end) => self.finish(end),
                    None if self.team.robots.get(m).is_some_and(|r| r.attached) => self.scan(m),
                    None => self.next_turn(),
                }
            }
            _ => {
                self.stats.ignored_reports = self.stats.ignored_reports.saturating_add(1);
                self.command
            }
        }
    }

    fn robot_lost(&mut self, robot: usize, cause: LossCause, state: Await) -> Command {
        if self.team.robots.get(robot).is_some_and(|r| r.attached) {
            self.team.cut_tether(robot);
            if let Some(l) = self.lost.get_mut(robot) {
                *l = Some(cause);
            }
        }
        if self.team.attached() == 0 {
            return self.finish(MissionOutcome::TeamLost);
        }
        match state {
            Await::Scan(m) | Await::Landing(m) if m == robot => self.next_turn(),
            _ => self.command,
        }
    }

    fn finish(&mut self, end: MissionOutcome) -> Command {
        self.state = Await::Done(end);
        self.command = Command::Done(end);
        self.command
    }

    fn scan(&mut self, m: usize) -> Command {
        self.turns_in_round = self.turns_in_round.saturating_add(1);
        self.state = Await::Scan(m);
        self.command = Command::Scan { robot: m };
        self.command
    }

    /// The next robot in the climbing order; at the end of a round, the hub motion first.
    fn next_turn(&mut self) -> Command {
        let Some((m, new_round)) = self.team.next_mover() else {
            return self.finish(MissionOutcome::TeamLost);
        };
        if new_round && self.turns_in_round > 0 {
            self.turns_in_round = 0;
            let mut moved = self.team.clone();
            moved.hub_motion(self.params.r_max);
            self.state = Await::Hub(m);
            self.command = Command::MoveHub { to: moved.hub };
            return self.command;
        }
        self.scan(m)
    }

    fn at_goal(&self) -> bool {
        norm3(&(self.team.hub - self.goal)) <= self.goal_tol
    }

    /// D* Lite's answer as a mission end, `None` while a route exists.
    fn route_outcome(&self, out: Result<DStarOutcome, DStarError>) -> Option<MissionOutcome> {
        match out {
            Ok(Status::Exact(_)) => None,
            Ok(Status::NoSolution(n)) if n.ended == Ended::BudgetExhausted => {
                Some(MissionOutcome::BudgetExhausted(Budget::GlobalPlanner))
            }
            Ok(_) => Some(MissionOutcome::Blocked(Blocked::NoRoute)),
            Err(_) => Some(MissionOutcome::LeftGrid),
        }
    }

    /// The next scene of the route (`None` in the goal's scene).
    pub fn next_cell(&self) -> Option<Cell> {
        self.dstar.next_cell(self.here)
    }

    /// Plane coordinates of the waypoint: the next cell's centre, or the goal in (or next to) the goal's cell.
    fn waypoint_plane(&self) -> (Real, Real) {
        match self.next_cell() {
            Some(c) if c != self.goal_cell => self.grid.centre(c),
            _ => self.grid.plane(&self.goal),
        }
    }

    /// The hub's distance to the waypoint in the scene plane.
    fn waypoint_distance(&self) -> Real {
        let (a, b) = self.grid.plane(&self.team.hub);
        let (wa, wb) = self.waypoint_plane();
        libm::hypotf(wa - a, wb - b)
    }

    /// The waypoint in space: its plane coordinates at the height of the scan points around it, or the blend of
    /// the hub's and the goal's heights when the scan does not reach it (bounded by the scan's length).
    fn waypoint(&self, points: &[Vec3]) -> Vec3 {
        let (wa, wb) = self.waypoint_plane();
        let (ga, gb) = self.grid.plane(&self.goal);
        if libm::hypotf(wa - ga, wb - gb) < 1e-3 {
            return self.goal;
        }
        let r = self.mp.waypoint_radius_fraction * self.grid.cell;
        let (mut sum, mut n) = (0.0 as Real, 0u32);
        for p in points.iter().filter(|p| is_finite3(p)) {
            let (a, b) = self.grid.plane(p);
            if libm::hypotf(a - wa, b - wb) <= r {
                sum += self.grid.height_of(p);
                n += 1;
            }
        }
        let h = if n > 0 {
            sum / n as Real
        } else {
            let (ha, hb) = self.grid.plane(&self.team.hub);
            let total = libm::hypotf(ga - ha, gb - hb).max(1e-3);
            let t = (1.0 - libm::hypotf(ga - wa, gb - wb) / total).clamp(0.0, 1.0);
            let hh = self.grid.height_of(&self.team.hub);
            hh + (self.grid.height_of(&self.goal) - hh) * t
        };
        self.grid.point(wa, wb, h)
    }

    fn local_plan(&mut self, m: usize, pos: Vec3, up: Vec3, hub: Vec3, points: &[Vec3]) -> Command {
        self.team.hop(m, pos);
        self.team.hub = hub;
        let c_m = pos - hub;
        let goal_m = self.team.slot_goal(m, &self.waypoint(points));
        let tol = 0.5 * self.goal_tol;
        self.stats.local_plans = self.stats.local_plans.saturating_add(1);
        let plan = self.planner.plan(points, &up, &pos, &c_m, &goal_m, tol, &self.params);
        let target = match &plan {
            Ok(p) if matches!(p.status, Status::Exact(()) | Status::Approximate(_)) => p.hops.get(1).copied(),
            _ => None,
        };
        let Some(target) = target.filter(|t| norm3(&(t - pos)) > 1e-3) else {
            self.stats.no_hop = self.stats.no_hop.saturating_add(1);
            return self.next_turn();
        };
        // the mission's own check of the hop against the reported grip point and hub
        let eps = 1e-3;
        let h_ok = norm3(&(target - pos)) <= self.params.h_max - self.params.landing_margin + eps;
        let r_ok = norm3(&(target - hub)) <= self.params.r_max - self.params.landing_margin + eps;
        if !(h_ok && r_ok) {
            self.stats.refused_hops = self.stats.refused_hops.saturating_add(1);
            return self.next_turn();
        }
        if self.stats.hops >= self.mp.max_hops {
            return self.finish(MissionOutcome::BudgetExhausted(Budget::Hops));
        }
        self.stats.hops += 1;
        self.state = Await::Landing(m);
        self.command = Command::Hop { robot: m, target };
        self.command
    }

    /// After the hub moved: goal, budgets, the team's scene, progress and walls.
    fn end_of_round(&mut self) -> Option<MissionOutcome> {
        self.stats.rounds = self.stats.rounds.saturating_add(1);
        if self.at_goal() {
            return Some(MissionOutcome::GoalReached);
        }
        if self.stats.rounds >= self.mp.max_rounds {
            return Some(MissionOutcome::BudgetExhausted(Budget::Rounds));
        }
        let Some(cell) = self.grid.cell_of(&self.team.hub) else {
            return Some(MissionOutcome::LeftGrid);
        };
        if cell != self.here {
            self.here = cell;
            let _ = self.route.push(cell);
            let out = self.dstar.move_start(cell).and_then(|_| self.dstar.replan(self.mp.dstar_budget));
            if let Some(end) = self.route_outcome(out) {
                return Some(end);
            }
            self.stall = 0;
            self.best = self.waypoint_distance();
            return None;
        }
        let d = self.waypoint_distance();
        if d < self.best - self.mp.progress_fraction * self.params.h_max {
            self.best = d;
            self.stall = 0;
            return None;
        }
        self.stall = self.stall.saturating_add(1);
        let next = self.next_cell();
        let limit = if next.is_some() { self.mp.stall_rounds } else { self.mp.goal_stall_rounds };
        if self.stall < limit {
            return None;
        }
        self.stall = 0;
        let Some(next) = next else {
            return Some(MissionOutcome::Blocked(Blocked::GoalUnreachable));
        };
        // the local planners cannot cross from `here` to `next`: a wall for D* Lite
        let out = self.dstar.add_wall(self.here, next).and_then(|_| self.dstar.replan(self.mp.dstar_budget));
        let _ = self.walls.push((self.here, next));
        self.stats.walls = self.stats.walls.saturating_add(1);
        if let Some(end) = self.route_outcome(out) {
            return Some(end);
        }
        self.best = self.waypoint_distance();
        None
    }

    /// The pending command.
    pub fn command(&self) -> Command {
        self.command
    }

    /// The outcome once the mission is over.
    pub fn outcome(&self) -> Option<MissionOutcome> {
        match self.state {
            Await::Done(o) => Some(o),
            _ => None,
        }
    }

    /// Counters so far.
    pub fn stats(&self) -> MissionStats {
        self.stats
    }

    /// The team as the mission believes it (positions from the reports).
    pub fn team(&self) -> &Team<N> {
        &self.team
    }

    /// Why each robot left the team (`None`: still attached).
    pub fn lost(&self) -> &[Option<LossCause>; N] {
        &self.lost
    }

    /// Walls added so far (first [`MISSION_MAX_WALLS`]).
    pub fn walls(&self) -> &[(Cell, Cell)] {
        &self.walls
    }

    /// The cells the team's scene moved through, start first (first [`MISSION_MAX_ROUTE`]).
    pub fn visited(&self) -> &[Cell] {
        &self.route
    }

    /// The team's scene.
    pub fn here(&self) -> Cell {
        self.here
    }

    /// The grid of scenes.
    pub fn grid(&self) -> &SceneGrid {
        &self.grid
    }

    /// The current D* Lite route from the team's scene into `out`.
    pub fn route(&self, out: &mut [Cell]) -> Result<PathOutcome, DStarError> {
        self.dstar.path(out)
    }

    /// The local planner (its last scene and hop graph).
    pub fn planner(&self) -> &LocalPlanner<P, V, E> {
        self.planner
    }

    /// Ends the mission and hands its lent storage back, for the next mission.
    pub fn into_storage(self) -> (DStarStorage<'a>, &'a mut LocalPlanner<P, V, E>) {
        (self.dstar.into_storage(), self.planner)
    }
}

/// The mission with the default capacities of [`crate::config::team`].
pub type DefaultTeamMission<'a> = TeamMission<
    'a,
    { crate::config::team::TEAM_SIZE },
    { crate::config::team::SCENE_MAX_POINTS },
    { crate::config::team::GRAPH_MAX_VERTICES },
    { crate::config::team::GRAPH_MAX_EDGES },
>;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plan::team::dstar_lite::DStarArena;
    use std::boxed::Box;
    use std::vec::Vec;

    type Planner = LocalPlanner<4096, 512, 32768>;

    fn grid(w: u32, h: u32, cell: Real) -> SceneGrid {
        SceneGrid { origin: Vec3::zeros(), u: Vec3::x(), v: Vec3::y(), cell, width: w, height: h }
    }

    /// A flat plane z = 0 with a 1 m lattice of points within `range` of `at` (inside the grid's extent).
    fn flat_scan(at: &Vec3, range: Real, extent: (Real, Real)) -> Vec<Vec3> {
        let n = range as i32 + 1;
        let mut pts = Vec::new();
        for j in -n..=n {
            for i in -n..=n {
                let p = Vec3::new(libm::roundf(at.x) + i as Real, libm::roundf(at.y) + j as Real, 0.0);
                if norm3(&(p - at)) <= range && p.x >= 0.0 && p.y >= 0.0 && p.x <= extent.0 && p.y <= extent.1 {
                    pts.push(p);
                }
            }
        }
        pts
    }

    fn start() -> [Vec3; 4] {
        [Vec3::new(14.0, 14.0, 0.0), Vec3::new(14.0, 6.0, 0.0), Vec3::new(6.0, 14.0, 0.0), Vec3::new(6.0, 6.0, 0.0)]
    }

    #[test]
    fn flat_ground_goal_reached_with_every_hop_checked_against_the_real_hub() {
        let mut arena: Box<DStarArena<64>> = Box::default();
        let mut planner: Box<Planner> = Box::default();
        let params = TeamParams::DEFAULT;
        let g = grid(8, 2, 20.0);
        let goal = Vec3::new(130.0, 10.0, 0.0);
        let mut m = TeamMission::new(g, goal, 5.0, start(), params, MissionParams::DEFAULT, arena.storage(), &mut planner)
            .unwrap();
        let mut pos = start();
        let mut hub = m.team().hub;
        let mut cmd = m.begin();
        for _ in 0..10_000 {
            cmd = match cmd {
                Command::Scan { robot } => {
                    let pts = flat_scan(&pos[robot], 20.0, (160.0, 40.0));
                    m.step(Report::Scan { robot, pos: pos[robot], up: Vec3::z(), hub, points: &pts })
                }
                Command::Hop { robot, target } => {
                    // the flight code's hop limits, against where the robot and the hub really are
                    assert!(norm3(&(target - pos[robot])) <= params.h_max + 1e-3);
                    assert!(norm3(&(target - hub)) <= params.r_max + 1e-3);
                    pos[robot] = target;
                    m.step(Report::Landed { robot, pos: target })
                }
                Command::MoveHub { to } => {
                    for p in &pos {
                        assert!(norm3(&(p - to)) <= params.r_max + 1e-3);
                    }
                    hub = to;
                    m.step(Report::HubAt { pos: to })
                }
                Command::Done(_) => break,
            };
        }
        assert_eq!(cmd, Command::Done(MissionOutcome::GoalReached), "{:?}", m.stats());
        assert!(norm3(&(hub - goal)) <= 5.0);
        assert!(m.walls().is_empty());
        // the team's scene went east cell by cell
        assert_eq!(m.visited().first(), Some(&(0, 0)));
        assert_eq!(m.visited().last(), Some(&(6, 0)));
    }

    /// The team of [`start`] on an 8 x 2 grid of 20 m scenes, goal 120 m east.
    fn eastward<'a>(arena: &'a mut DStarArena<64>, planner: &'a mut Planner) -> TeamMission<'a, 4, 4096, 512, 32768> {
        let goal = Vec3::new(130.0, 10.0, 0.0);
        TeamMission::new(grid(8, 2, 20.0), goal, 5.0, start(), TeamParams::DEFAULT, MissionParams::DEFAULT, arena.storage(), planner)
            .unwrap()
    }

    #[test]
    fn blocked_goal_is_reported_and_not_reached() {
        let mut arena: Box<DStarArena<64>> = Box::default();
        let mut planner: Box<Planner> = Box::default();
        let mut m = eastward(&mut arena, &mut planner);
        // a column of impassable scenes between the team and the goal
        m.block_cell((3, 0)).unwrap();
        m.block_cell((3, 1)).unwrap();
        assert_eq!(m.begin(), Command::Done(MissionOutcome::Blocked(Blocked::NoRoute)));
        assert_eq!(m.outcome(), Some(MissionOutcome::Blocked(Blocked::NoRoute)));
    }

    #[test]
    fn node_loss_keeps_the_others_going_and_all_lost_ends_the_mission() {
        let mut arena: Box<DStarArena<64>> = Box::default();
        let mut planner: Box<Planner> = Box::default();
        let mut m = eastward(&mut arena, &mut planner);
        assert_eq!(m.begin(), Command::Scan { robot: 0 });
        // a landing nobody asked for is ignored
        assert_eq!(m.step(Report::Landed { robot: 2, pos: Vec3::zeros() }), Command::Scan { robot: 0 });
        assert_eq!(m.stats().ignored_reports, 1);
        // robot 0 loses its grip before scanning: robot 1 is next
        assert_eq!(m.step(Report::Lost { robot: 0, cause: LossCause::GripFailure }), Command::Scan { robot: 1 });
        // robot 3's tether is cut while robot 1 is pending: robot 1 is still asked
        assert_eq!(m.step(Report::Lost { robot: 3, cause: LossCause::TetherCut }), Command::Scan { robot: 1 });
        assert_eq!(m.team().attached(), 2);
        assert_eq!(m.lost()[0], Some(LossCause::GripFailure));
        assert_eq!(m.step(Report::Lost { robot: 1, cause: LossCause::TetherCut }), Command::Scan { robot: 2 });
        assert_eq!(m.step(Report::Lost { robot: 2, cause: LossCause::TetherCut }), Command::Done(MissionOutcome::TeamLost));
        assert_eq!(m.step(Report::HubAt { pos: Vec3::zeros() }), Command::Done(MissionOutcome::TeamLost));
    }
}
