//! The climbing team's mission in the executive (protocol v8; Morad et al. sections IV-V, Figs. 4, 7 and 12;
//! issue 21).
//!
//! The hub's flight computer runs [`DefaultTeamMission`] (global D* Lite over the grid of scenes, the bounded-leg
//! A* per robot and hop, the climbing order, the hub motion, walls and node loss) and talks to the team over the
//! link: a [`TeamConfigure`] sets the mission up, a `GoalRequest { planner: Team }` starts it, and from then on each
//! completed [`TeamScanChunk`] series or [`TeamReport`] steps it once; each resulting order goes down as a
//! [`TeamCommand`] with a new `command_id`. `Done` ends it: its outcome is in the `Done` order and in the goal's
//! `PlanStatus` state (`ExactSolution` for `GoalReached`, `NoSolutionWithinBudget` otherwise). The mission runs in
//! `Mapping` mode: each of its steps runs inside the dispatch of the frame that completes a report.
//!
//! ## Storage
//! The mission borrows its D* Lite arena (`GLOBAL_GRID_MAX_CELLS` = 4096 scenes, ~190 KiB), the local planner
//! (`DefaultLocalPlanner`, ~0.6 MiB) and the scan reassembly (`TEAM_SCAN_POINTS_CAPACITY` = 4096 points, 48 KiB) for
//! its whole run, and the mission itself (~7 KiB) lives beside them; so they are lent to the executive for good as a
//! [`TeamLend`] of `'static` parts ([`Executive::lend_team`]): the board's `.psram` statics, the host's boxes. An
//! ended mission stays readable (its scene and hop graph, for the host's pictures) until the next team goal, which
//! takes the storage back from it ([`TeamMission::into_storage`]) and starts on it; so a lending serves any number of
//! missions, one at a time. [`Executive::reclaim_team`] hands the storage back to the lender while no mission runs
//! (the host reuses it for its next in-process executive). Without a lending every team goal is
//! `PlannerUnavailable`; a grid larger than the lent D* Lite storage is `InvalidInput`, the storage kept.
//!
//! [`TeamMission::into_storage`]: crate::plan::team::mission::TeamMission::into_storage
//!
//! ## Order and duplicates
//! A scan chunk or report must answer the pending order's `command_id` (`Nack(UnknownCommand)` otherwise), name
//! its robot (`Nack(UnknownRobot)`) and match its kind (a `Landed` for a hop, `HubAt` for a hub move, chunks for a
//! scan: `Nack(UnknownCommand)`); chunks arrive in order (`OutOfOrderChunk`, `DuplicateChunk`, `MixedScan`,
//! `ScanOverflow` as for sensor scans). A `Lost` is taken at any time. A copy of the message that answered the
//! previous order (its `Ack` lost on the way down) is answered `Ack` and not applied again. With no answer within
//! `TEAM_COMMAND_RESEND_US` (default 10 s, `config::exec`) the pending order goes again with the same id (the host
//! executes an id once). Team messages before a `TeamConfigure` or outside a mission are `Nack(NoTeam)`.

use core::borrow::BorrowMut;

use hal::{ByteLink, Instant, MonotonicClock, Watchdog};

use super::{Autonomy, ExecStorage, Executive, Reply};
use crate::config::exec::TEAM_COMMAND_RESEND_US;
use crate::config::protocol::TEAM_SCAN_POINTS_CAPACITY;
use crate::config::team::{MissionParams, TeamParams, TEAM_SIZE};
use crate::geom::Vec3;
use crate::plan::team::dstar_lite::DStarStorage;
use crate::plan::team::mission::{
    Blocked, Budget, Command, DefaultTeamMission, LossCause, MissionOutcome, Report, SceneGrid,
};
use crate::plan::team::DefaultLocalPlanner;
use crate::protocol::{
    GoalRequest, LogLevel, Message, NackReason, PlanState, Point3, TeamCommand, TeamConfigure, TeamEvent, TeamLoss,
    TeamOrder, TeamOutcome, TeamReport, TeamScanChunk,
};

/// The team mission's storage, lent for good (module docs).
pub struct TeamLend {
    /// D* Lite's storage over the grid of scenes (a `DStarArena<GLOBAL_GRID_MAX_CELLS>`'s `storage()`: a smaller
    /// one refuses larger grids).
    pub dstar: DStarStorage<'static>,
    /// The bounded-leg A* local planner.
    pub planner: &'static mut DefaultLocalPlanner,
    /// Team scan reassembly.
    pub points: &'static mut [Vec3; TEAM_SCAN_POINTS_CAPACITY],
    /// Where the mission itself lives (~7 KiB: its walls and route records), so it is neither in the executive
    /// nor on the stack between steps. Empty (`None`) when lent.
    pub mission: &'static mut Option<DefaultTeamMission<'static>>,
}

/// A scan being reassembled.
#[derive(Debug, Clone, Copy)]
struct ScanIn {
    robot: u8,
    chunk_count: u16,
    next: u16,
    grip: Point3,
    up: Point3,
    hub: Point3,
    points: usize,
}

/// A running (or finished) mission.
pub(super) struct TeamRun {
    /// The lent mission slot, `Some` for the run's whole life (`None` only once [`TeamRun::into_lend`] took it).
    slot: &'static mut Option<DefaultTeamMission<'static>>,
    points: &'static mut [Vec3; TEAM_SCAN_POINTS_CAPACITY],
    goal_id: u32,
    /// The pending order, its id and when it was last sent.
    command: TeamCommand,
    last_sent: Instant,
    /// The id of the order the last applied report or scan answered (a copy of it is acknowledged, not applied).
    answered: Option<u32>,
    scan: Option<ScanIn>,
    /// Stopped before its end (shutdown).
    aborted: bool,
}

/// Where the team mission stands.
#[derive(Default)]
pub(super) enum TeamSlot {
    /// No storage lent: team goals are `PlannerUnavailable`.
    #[default]
    Unlent,
    /// Storage lent, no mission started yet.
    Free(TeamLend),
    /// A mission running or ended (its storage stays with it).
    Run(TeamRun),
}

fn v3(p: &Point3) -> Vec3 {
    Vec3::new(p.x, p.y, p.z)
}

fn p3(v: &Vec3) -> Point3 {
    Point3::new(v.x, v.y, v.z)
}

fn outcome(o: MissionOutcome) -> TeamOutcome {
    match o {
        MissionOutcome::GoalReached => TeamOutcome::GoalReached,
        MissionOutcome::Blocked(Blocked::NoRoute) => TeamOutcome::NoRoute,
        MissionOutcome::Blocked(Blocked::GoalUnreachable) => TeamOutcome::GoalUnreachable,
        MissionOutcome::TeamLost => TeamOutcome::TeamLost,
        MissionOutcome::BudgetExhausted(Budget::Rounds) => TeamOutcome::RoundsExhausted,
        MissionOutcome::BudgetExhausted(Budget::Hops) => TeamOutcome::HopsExhausted,
        MissionOutcome::BudgetExhausted(Budget::GlobalPlanner) => TeamOutcome::GlobalPlannerExhausted,
        MissionOutcome::LeftGrid => TeamOutcome::LeftGrid,
    }
}

/// A robot index from the wire (validated `< TEAM_SIZE` on decode).
fn robot(r: u8) -> usize {
    usize::from(r)
}

/// Steps the mission in `slot` (always there while its run lives; an empty slot ends the run).
fn step_mission(slot: &mut Option<DefaultTeamMission<'static>>, report: Report<'_>) -> Command {
    slot.as_mut().map_or(Command::Done(MissionOutcome::LeftGrid), |m| m.step(report))
}

impl TeamRun {
    /// The order for `cmd` (a robot index from the mission is below `TEAM_SIZE`, so it fits a `u8`).
    fn order(&self, cmd: Command) -> TeamOrder {
        let idx = |m: usize| u8::try_from(m).unwrap_or(u8::MAX);
        match cmd {
            Command::Scan { robot } => TeamOrder::Scan { robot: idx(robot) },
            Command::Hop { robot, target } => TeamOrder::Hop {
                robot: idx(robot),
                target: p3(&target),
                scene_normal: p3(&self.mission().map_or(Vec3::z(), |m| m.planner().scene.frame.n)),
            },
            Command::MoveHub { to } => TeamOrder::MoveHub { to: p3(&to) },
            Command::Done(o) => {
                let s = self.mission().map(|m| m.stats()).unwrap_or_default();
                TeamOrder::Done { outcome: outcome(o), rounds: s.rounds, hops: s.hops, walls: s.walls }
            }
        }
    }

    /// Ended: the mission's outcome is in, or it was stopped.
    fn ended(&self) -> bool {
        self.aborted || self.mission().is_none_or(|m| m.outcome().is_some())
    }

    /// The mission, for the host's pictures and reports (in-process only).
    pub(super) fn mission(&self) -> Option<&DefaultTeamMission<'static>> {
        self.slot.as_ref()
    }

    /// The run's storage, taken back from its mission (which ends here) for the next one.
    fn into_lend(self) -> Option<TeamLend> {
        let (dstar, planner) = self.slot.take()?.into_storage();
        Some(TeamLend { dstar, planner, points: self.points, mission: self.slot })
    }
}

impl<L: ByteLink, C: MonotonicClock, W: Watchdog, A: Autonomy, S: BorrowMut<ExecStorage>> Executive<L, C, W, A, S> {
    /// Lends the team mission's storage for good (module docs). Whatever is not kept comes back as `Some`: a
    /// second lending replaces an unused first one (which comes back), and is itself refused while a mission runs
    /// or its storage holds the last one's results.
    #[must_use = "a lending not kept comes back"]
    pub fn lend_team(&mut self, lend: TeamLend) -> Option<TeamLend> {
        if matches!(self.team, TeamSlot::Run(_)) {
            return Some(lend);
        }
        match core::mem::replace(&mut self.team, TeamSlot::Free(lend)) {
            TeamSlot::Free(old) => Some(old),
            _ => None,
        }
    }

    /// The team storage handed back (module docs), unless a mission is running; the last mission's results go
    /// with it. Team goals are `PlannerUnavailable` until the next lending.
    pub fn reclaim_team(&mut self) -> Option<TeamLend> {
        if self.team_running() {
            return None;
        }
        match core::mem::take(&mut self.team) {
            TeamSlot::Unlent => None,
            TeamSlot::Free(lend) => Some(lend),
            TeamSlot::Run(run) => run.into_lend(),
        }
    }

    /// The team mission (running or ended), if one was started.
    pub fn team_mission(&self) -> Option<&DefaultTeamMission<'static>> {
        match &self.team {
            TeamSlot::Run(r) => r.mission(),
            _ => None,
        }
    }

    fn team_running(&self) -> bool {
        matches!(&self.team, TeamSlot::Run(r) if !r.ended())
    }

    /// `TeamConfigure`: kept for the next team goal; refused while a team mission runs.
    pub(super) fn on_team_configure(&mut self, c: &TeamConfigure) -> Result<Reply, NackReason> {
        if self.mode == crate::protocol::Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        if self.team_running() {
            return Err(NackReason::NoTeam);
        }
        self.team_cfg = Some(c.clone());
        self.note(LogLevel::Info, format_args!("team configured: {} x {} scenes", c.grid.width, c.grid.height));
        Ok(Reply::None)
    }

    /// `GoalRequest { planner: Team }`: starts the mission on the lent storage; its first order follows the status.
    pub(super) fn on_team_goal(&mut self, g: &GoalRequest) -> Result<PlanState, NackReason> {
        let Some(cfg) = self.team_cfg.clone() else {
            return Err(NackReason::NoTeam);
        };
        if self.team_running() {
            return Err(NackReason::NoTeam);
        }
        let lend = match core::mem::take(&mut self.team) {
            TeamSlot::Free(lend) => Some(lend),
            // the last mission ended: its storage serves this one
            TeamSlot::Run(run) => run.into_lend(),
            TeamSlot::Unlent => None,
        };
        let Some(lend) = lend else {
            self.note(LogLevel::Warn, format_args!("team goal {}: no team storage lent", g.goal_id));
            return Ok(PlanState::PlannerUnavailable);
        };
        let grid = SceneGrid {
            origin: v3(&cfg.grid.origin),
            u: v3(&cfg.grid.u),
            v: v3(&cfg.grid.v),
            cell: cfg.grid.cell_m,
            width: u32::from(cfg.grid.width),
            height: u32::from(cfg.grid.height),
        };
        let goal = v3(&g.position);
        let start: [Vec3; TEAM_SIZE] = cfg.start.map(|p| v3(&p));
        let hub = start.iter().fold(Vec3::zeros(), |a, p| a + p) / TEAM_SIZE as f32;
        // checked before the storage is handed over, so it stays free
        if grid.cell_of(&goal).is_none() || grid.cell_of(&hub).is_none() {
            self.team = TeamSlot::Free(lend);
            self.note(LogLevel::Warn, format_args!("team goal {}: goal or start outside the scenes", g.goal_id));
            return Ok(PlanState::InvalidInput);
        }
        let cells = usize::from(cfg.grid.width).saturating_mul(usize::from(cfg.grid.height));
        if cells > lend.dstar.cells() {
            let have = lend.dstar.cells();
            self.team = TeamSlot::Free(lend);
            self.note(
                LogLevel::Warn,
                format_args!("team goal {}: {cells} scenes, the team storage holds {have}", g.goal_id),
            );
            return Ok(PlanState::InvalidInput);
        }
        let TeamLend { dstar, planner, points, mission: slot } = lend;
        let made = DefaultTeamMission::new(
            grid,
            goal,
            g.tolerance_m,
            start,
            TeamParams::from(cfg.planner),
            MissionParams::from(cfg.mission),
            dstar,
            planner,
        );
        let mission = match made {
            Ok(m) => slot.insert(m),
            Err(e) => {
                // not reached: every cause was checked above or on decode
                self.note(LogLevel::Error, format_args!("team goal {}: {e:?}; team storage spent", g.goal_id));
                return Ok(PlanState::InvalidInput);
            }
        };
        for &(c, r) in &cfg.blocked {
            // inside the grid: checked on decode
            let _ = mission.block_cell((i64::from(c), i64::from(r)));
        }
        let first = mission.begin();
        let mut run = TeamRun {
            slot,
            points,
            goal_id: g.goal_id,
            command: TeamCommand { command_id: 0, goal_id: g.goal_id, order: TeamOrder::Scan { robot: 0 } },
            last_sent: self.now,
            answered: None,
            scan: None,
            aborted: false,
        };
        let command_id = self.next_command_id();
        run.command = TeamCommand { command_id, goal_id: g.goal_id, order: run.order(first) };
        self.team = TeamSlot::Run(run);
        self.note(LogLevel::Info, format_args!("team goal {}: mission started", g.goal_id));
        Ok(PlanState::Accepted)
    }

    /// Sends the pending team order (after the status of the goal that started it, or after a step).
    pub(super) fn send_team_command(&mut self) {
        let now = self.now;
        let TeamSlot::Run(run) = &mut self.team else { return };
        run.last_sent = now;
        let cmd = run.command;
        self.send(&Message::TeamCommand(cmd));
        if let TeamOrder::Done { outcome, .. } = cmd.order {
            self.team_done(cmd.goal_id, outcome);
        }
    }

    fn team_done(&mut self, goal_id: u32, o: TeamOutcome) {
        if let Some(g) = self.goal.as_mut().filter(|g| g.goal_id == goal_id) {
            g.state = if o == TeamOutcome::GoalReached {
                PlanState::ExactSolution
            } else {
                PlanState::NoSolutionWithinBudget
            };
        }
        self.note(LogLevel::Info, format_args!("team goal {goal_id}: {o:?}"));
    }

    /// The pending order again, unchanged, when no answer came within `TEAM_COMMAND_RESEND_US`.
    pub(super) fn resend_team_command(&mut self, now: Instant) {
        let TeamSlot::Run(run) = &mut self.team else { return };
        if run.ended() || now.micros_since(run.last_sent) < TEAM_COMMAND_RESEND_US {
            return;
        }
        run.last_sent = now;
        let cmd = run.command;
        self.counters.drive_resends = self.counters.drive_resends.saturating_add(1);
        self.send(&Message::TeamCommand(cmd));
    }

    /// Checks that a team message answers the pending order; `Ok(false)` for a copy of the last answer.
    fn team_pending(&mut self, command_id: u32) -> Result<bool, NackReason> {
        let TeamSlot::Run(run) = &self.team else {
            return Err(NackReason::NoTeam);
        };
        if run.answered == Some(command_id) {
            return Ok(false);
        }
        if run.ended() {
            return Err(NackReason::NoTeam);
        }
        if run.command.command_id != command_id {
            return Err(NackReason::UnknownCommand);
        }
        Ok(true)
    }

    /// Steps the mission with `report` and makes the next order pending (a new id unless the order is the same
    /// and `same_if_unchanged`).
    fn team_step(&mut self, answered: bool, step: impl FnOnce(&mut TeamRun) -> Command) -> Reply {
        let next_id = self.drive_command_id;
        let TeamSlot::Run(run) = &mut self.team else { return Reply::None };
        let cmd = step(run);
        let order = run.order(cmd);
        if answered {
            run.answered = Some(run.command.command_id);
        } else if order == run.command.order {
            return Reply::None;
        }
        run.command = TeamCommand { command_id: next_id, goal_id: run.goal_id, order };
        self.drive_command_id = next_id.wrapping_add(1);
        Reply::TeamCommand
    }

    /// `TeamReport`: a landing, a hub stop, or a robot lost.
    pub(super) fn on_team_report(&mut self, r: &TeamReport) -> Result<Reply, NackReason> {
        if self.mode == crate::protocol::Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        if let TeamEvent::Lost { robot: m, cause } = r.event {
            if !matches!(&self.team, TeamSlot::Run(run) if !run.ended()) {
                return Err(NackReason::NoTeam);
            }
            let cause = match cause {
                TeamLoss::TetherCut => LossCause::TetherCut,
                TeamLoss::GripFailure => LossCause::GripFailure,
            };
            // a loss while the robot's own order is pending answers it (the mission moves on)
            let answers = matches!(&self.team, TeamSlot::Run(run) if run.command.command_id == r.command_id
                && matches!(run.command.order, TeamOrder::Scan { robot } | TeamOrder::Hop { robot, .. } if robot == m));
            return Ok(self.team_step(answers, |run| {
                run.scan = None;
                step_mission(run.slot, Report::Lost { robot: robot(m), cause })
            }));
        }
        if !self.team_pending(r.command_id)? {
            return Ok(Reply::None);
        }
        let TeamSlot::Run(run) = &self.team else { return Err(NackReason::NoTeam) };
        let report = match (run.command.order, r.event) {
            (TeamOrder::Hop { robot: want, .. }, TeamEvent::Landed { robot: m, pos }) => {
                if want != m {
                    return Err(NackReason::UnknownRobot);
                }
                Report::Landed { robot: robot(m), pos: v3(&pos) }
            }
            (TeamOrder::MoveHub { .. }, TeamEvent::HubAt { pos }) => Report::HubAt { pos: v3(&pos) },
            _ => return Err(NackReason::UnknownCommand),
        };
        Ok(self.team_step(true, |run| step_mission(run.slot, report)))
    }

    /// `TeamScanChunk`: reassembled in order; the last chunk steps the mission with the whole scan.
    pub(super) fn on_team_scan(&mut self, c: &TeamScanChunk) -> Result<Reply, NackReason> {
        if self.mode == crate::protocol::Mode::Safe {
            return Err(NackReason::NotAllowedInMode);
        }
        if !self.team_pending(c.command_id)? {
            return Ok(Reply::None);
        }
        let TeamSlot::Run(run) = &mut self.team else { return Err(NackReason::NoTeam) };
        match run.command.order {
            TeamOrder::Scan { robot } if robot == c.robot => {}
            TeamOrder::Scan { .. } => return Err(NackReason::UnknownRobot),
            _ => return Err(NackReason::UnknownCommand),
        }
        let mut s = match run.scan {
            _ if c.chunk_index == 0 => ScanIn {
                robot: c.robot,
                chunk_count: c.chunk_count,
                next: 0,
                grip: c.grip,
                up: c.up,
                hub: c.hub,
                points: 0,
            },
            None => return Err(NackReason::OutOfOrderChunk),
            Some(s) => s,
        };
        if s.chunk_count != c.chunk_count || s.grip != c.grip || s.up != c.up || s.hub != c.hub {
            return Err(NackReason::MixedScan);
        }
        if c.chunk_index < s.next {
            return Err(NackReason::DuplicateChunk);
        }
        if c.chunk_index > s.next {
            return Err(NackReason::OutOfOrderChunk);
        }
        let end = s.points + c.points.len();
        let Some(dst) = run.points.get_mut(s.points..end) else {
            return Err(NackReason::ScanOverflow);
        };
        for (d, p) in dst.iter_mut().zip(c.points.iter()) {
            *d = v3(p);
        }
        s.points = end;
        s.next += 1;
        if s.next < s.chunk_count {
            run.scan = Some(s);
            return Ok(Reply::None);
        }
        run.scan = None;
        Ok(self.team_step(true, |run| {
            let points = run.points.get(..s.points).unwrap_or(&[]);
            step_mission(run.slot, Report::Scan {
                robot: robot(s.robot),
                pos: v3(&s.grip),
                up: v3(&s.up),
                hub: v3(&s.hub),
                points,
            })
        }))
    }

    /// Ends a running team mission (shutdown, cancel): nothing more is ordered.
    pub(super) fn team_abort(&mut self) {
        if let TeamSlot::Run(run) = &mut self.team {
            run.aborted = true;
        }
    }
}
