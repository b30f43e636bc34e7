//! Where the team's flight computer runs for [`super::simulate_with`]: [`DirectFlight`], the flight crate's
//! [`DefaultTeamMission`] called as a library (the original simulation), or [`LinkFlight`], the flight executive
//! over protocol v8 (`TeamConfigure`, `GoalRequest { Team }`, `TeamScanChunk`, `TeamReport` up, `TeamCommand`
//! down; `firmware/PROTOCOL.md`) on any [`FlightLink`] — in-process ([`LinkFlight::inproc`]) the executive runs
//! the same mission code, so the same seed gives the same run.

use firmware::config::protocol::MAX_POINTS_PER_CHUNK;
use firmware::config::team::{GLOBAL_GRID_MAX_CELLS, TEAM_SIZE};
use core::cell::{Cell, RefCell};

use firmware::exec::TeamLend;
use firmware::geom::Vec3;
use firmware::plan::team::dstar_lite::DStarArena;
use firmware::plan::team::mission::{Blocked, Budget, Command, DefaultTeamMission, LossCause, MissionOutcome, Report};
use firmware::plan::team::DefaultLocalPlanner;
use firmware::protocol::{
    GoalRequest, GripState, Message, PlannerChoice, Point3, TeamCommand, TeamConfigure, TeamEvent, TeamGrid, TeamLoss,
    TeamOrder, TeamOutcome, TeamReport, TeamScanChunk, TeamState,
};

use super::{SimConfig, SimError};
use crate::link::inproc::{InProcLink, DEFAULT_STEP_US};
use crate::link::FlightLink;
use crate::session::HostSession;

/// The team's flight computer as the simulator sees it.
pub trait TeamFlight {
    /// Starts the mission; the first order.
    fn begin(&mut self) -> Result<Command, SimError>;
    /// Answers the pending order (or reports a loss); the next order.
    fn step(&mut self, report: Report<'_>) -> Result<Command, SimError>;
    /// The flight code's mission, where the host can see it (direct and in-process; `None` over a real link).
    fn mission(&self) -> Option<&DefaultTeamMission<'_>>;
    /// The counters the `Done` order carried (rounds, hops, walls), over a link.
    fn done_counts(&self) -> Option<(u32, u32, u32)> {
        None
    }
}

/// The mission called as a library.
pub struct DirectFlight<'a> {
    /// The mission.
    pub mission: DefaultTeamMission<'a>,
}

impl TeamFlight for DirectFlight<'_> {
    fn begin(&mut self) -> Result<Command, SimError> {
        Ok(self.mission.begin())
    }
    fn step(&mut self, report: Report<'_>) -> Result<Command, SimError> {
        Ok(self.mission.step(report))
    }
    fn mission(&self) -> Option<&DefaultTeamMission<'_>> {
        Some(&self.mission)
    }
}

thread_local! {
    /// Team storage handed back by in-process executives on this thread, for the next one.
    static SPARE_LENDS: RefCell<Vec<TeamLend>> = const { RefCell::new(Vec::new()) };
    /// Team storages made on this thread.
    static LENDS_MADE: Cell<usize> = const { Cell::new(0) };
}

/// The team storage an in-process executive gets (about 0.85 MiB, `firmware/src/exec/team.rs`): one handed back
/// by an earlier executive on this thread ([`give_back_team_lend`]; [`LinkFlight`] does it when dropped), else a
/// new one, leaked as a board's statics live for the program. So a thread holds at most as many as it runs at
/// once, whatever the number of team missions it runs one after another.
pub fn team_lend() -> TeamLend {
    SPARE_LENDS.with_borrow_mut(Vec::pop).unwrap_or_else(|| {
        LENDS_MADE.set(LENDS_MADE.get() + 1);
        TeamLend {
            dstar: Box::leak(dstar_arena()).storage(),
            planner: Box::leak(local_planner()),
            mission: Box::leak(Box::new(None)),
            points: Box::leak(vec![Vec3::zeros(); firmware::config::protocol::TEAM_SCAN_POINTS_CAPACITY].into_boxed_slice().try_into().unwrap_or_else(|_| unreachable!("sized above"))),
        }
    })
}

/// Hands team storage back for the next in-process executive on this thread.
pub fn give_back_team_lend(lend: TeamLend) {
    SPARE_LENDS.with_borrow_mut(|v| v.push(lend));
}

/// Team storages [`team_lend`] has made on this thread.
pub fn team_lends_made() -> usize {
    LENDS_MADE.get()
}

// Large storages pass through the stack on their way to the heap: one function each, never inlined.
#[inline(never)]
fn dstar_arena() -> Box<DStarArena<GLOBAL_GRID_MAX_CELLS>> {
    Box::default()
}

#[inline(never)]
fn local_planner() -> Box<DefaultLocalPlanner> {
    Box::default()
}

/// The executive over protocol v8 on link `L`.
pub struct LinkFlight<L: FlightLink> {
    session: HostSession<L>,
    peek: fn(&L) -> Option<&DefaultTeamMission<'static>>,
    /// Takes the team storage back from the flight software when this is dropped (in-process only).
    reclaim: fn(&mut L) -> Option<TeamLend>,
    setup: TeamConfigure,
    goal: Point3,
    goal_tol: f32,
    /// The pending order.
    command: Option<TeamCommand>,
    /// The team's state as the host knows it (sent with every report).
    pos: [Vec3; TEAM_SIZE],
    hub: Vec3,
    grip: [GripState; TEAM_SIZE],
    /// The `Done` order's rounds, hops and walls.
    done: Option<(u32, u32, u32)>,
}

impl LinkFlight<InProcLink> {
    /// The in-process executive (booted as the board's, with team storage lent) for `cfg` from `start`.
    pub fn inproc(cfg: &SimConfig, start: [Vec3; TEAM_SIZE]) -> Result<Self, SimError> {
        let mut link = InProcLink::new(DEFAULT_STEP_US);
        if let Some(lend) = link.executive_mut().lend_team(team_lend()) {
            give_back_team_lend(lend);
        }
        let mut me = Self::new(link, |l| l.executive().team_mission(), cfg, start)?;
        me.reclaim = |l| l.executive_mut().reclaim_team();
        Ok(me)
    }
}

fn p3(v: &Vec3) -> Point3 {
    Point3::new(v.x, v.y, v.z)
}

fn v3(p: &Point3) -> Vec3 {
    Vec3::new(p.x, p.y, p.z)
}

fn link_err(e: impl core::fmt::Display) -> SimError {
    SimError::Link(e.to_string())
}

impl<L: FlightLink> LinkFlight<L> {
    /// A team mission on `link`; `peek` shows the flight code's mission where the host can see it.
    pub fn new(link: L, peek: fn(&L) -> Option<&DefaultTeamMission<'static>>, cfg: &SimConfig, start: [Vec3; TEAM_SIZE]) -> Result<Self, SimError> {
        let g = &cfg.grid;
        let narrow = |n: u32| u16::try_from(n).map_err(|_| link_err(format!("a grid of {n} scenes a side does not fit the protocol")));
        let blocked = cfg
            .blocked
            .iter()
            .map(|&(c, r)| Ok((u16::try_from(c).map_err(link_err)?, u16::try_from(r).map_err(link_err)?)))
            .collect::<Result<Vec<_>, SimError>>()?;
        let setup = TeamConfigure {
            grid: TeamGrid { origin: p3(&g.origin), u: p3(&g.u), v: p3(&g.v), cell_m: g.cell, width: narrow(g.width)?, height: narrow(g.height)? },
            start: start.map(|p| p3(&p)),
            planner: cfg.params.into(),
            mission: cfg.mission.into(),
            blocked: heapless::Vec::from_slice(&blocked).map_err(|_| link_err("more blocked scenes than a TeamConfigure holds"))?,
        };
        let hub = start.iter().fold(Vec3::zeros(), |a, p| a + p) / TEAM_SIZE as f32;
        Ok(Self {
            session: HostSession::new(link),
            peek,
            reclaim: |_| None,
            setup,
            goal: Point3::new(cfg.goal[0] as f32, cfg.goal[1] as f32, cfg.goal[2] as f32),
            goal_tol: cfg.goal_tol as f32,
            command: None,
            pos: start,
            hub,
            grip: [GripState::Gripping; TEAM_SIZE],
            done: None,
        })
    }

    /// The session (link counters, the link itself).
    pub fn session(&self) -> &HostSession<L> {
        &self.session
    }

    fn state(&self) -> TeamState {
        TeamState { grip: self.grip, legs_m: core::array::from_fn(|k| (self.pos[k] - self.hub).norm()) }
    }

    /// Sends `msg`; a `Nack` is an error; returns the new pending order if one came.
    fn exchange(&mut self, msg: Message) -> Result<Option<TeamCommand>, SimError> {
        let seq = self.session.next_seq();
        let replies = self.session.exchange(&msg).map_err(link_err)?;
        let mut order = None;
        for m in replies {
            match m {
                Message::Nack(n) if n.seq == seq => return Err(link_err(format!("{:?} refused: {:?}", msg.kind(), n.reason))),
                Message::TeamCommand(c) if self.command.is_none_or(|p| p.command_id != c.command_id) => order = Some(c),
                _ => {}
            }
        }
        Ok(order)
    }

    /// The order that came, as the mission's command (an order must come: every answer is answered).
    fn next(&mut self, order: Option<TeamCommand>) -> Result<Command, SimError> {
        let Some(c) = order.or(self.command) else {
            return Err(link_err("no team order came"));
        };
        self.command = Some(c);
        Ok(match c.order {
            TeamOrder::Scan { robot } => Command::Scan { robot: usize::from(robot) },
            TeamOrder::Hop { robot, target, .. } => Command::Hop { robot: usize::from(robot), target: v3(&target) },
            TeamOrder::MoveHub { to } => Command::MoveHub { to: v3(&to) },
            TeamOrder::Done { outcome, rounds, hops, walls } => Command::Done({
                self.done = Some((rounds, hops, walls));
                match outcome {
                TeamOutcome::GoalReached => MissionOutcome::GoalReached,
                TeamOutcome::NoRoute => MissionOutcome::Blocked(Blocked::NoRoute),
                TeamOutcome::GoalUnreachable => MissionOutcome::Blocked(Blocked::GoalUnreachable),
                TeamOutcome::TeamLost => MissionOutcome::TeamLost,
                TeamOutcome::RoundsExhausted => MissionOutcome::BudgetExhausted(Budget::Rounds),
                TeamOutcome::HopsExhausted => MissionOutcome::BudgetExhausted(Budget::Hops),
                TeamOutcome::GlobalPlannerExhausted => MissionOutcome::BudgetExhausted(Budget::GlobalPlanner),
                TeamOutcome::LeftGrid => MissionOutcome::LeftGrid,
                TeamOutcome::Aborted => return Err(link_err("the flight software stopped the team mission")),
                }
            }),
        })
    }

    fn report(&mut self, event: TeamEvent) -> Result<Command, SimError> {
        let command_id = self.command.map_or(0, |c| c.command_id);
        let order = self.exchange(Message::TeamReport(TeamReport { command_id, event, state: self.state() }))?;
        self.next(order)
    }
}

impl<L: FlightLink> Drop for LinkFlight<L> {
    fn drop(&mut self) {
        if let Some(lend) = (self.reclaim)(self.session.link_mut()) {
            give_back_team_lend(lend);
        }
    }
}

impl<L: FlightLink> TeamFlight for LinkFlight<L> {
    fn begin(&mut self) -> Result<Command, SimError> {
        self.exchange(Message::TeamConfigure(self.setup.clone()))?;
        let order = self.exchange(Message::GoalRequest(GoalRequest {
            goal_id: 1,
            position: self.goal,
            tolerance_m: self.goal_tol,
            planner: PlannerChoice::Team,
            max_iterations: 1,
            time_budget_ms: 0,
            allow_approximate: false,
        }))?;
        self.next(order)
    }

    fn step(&mut self, report: Report<'_>) -> Result<Command, SimError> {
        match report {
            Report::Scan { robot, pos, up, hub, points } => {
                self.hub = hub;
                let command_id = self.command.map_or(0, |c| c.command_id);
                let chunks: Vec<&[Vec3]> = if points.is_empty() { vec![&[][..]] } else { points.chunks(MAX_POINTS_PER_CHUNK).collect() };
                let count = u16::try_from(chunks.len()).map_err(link_err)?;
                let mut order = None;
                for (i, part) in chunks.iter().enumerate() {
                    let chunk = TeamScanChunk {
                        command_id,
                        robot: u8::try_from(robot).map_err(link_err)?,
                        chunk_index: i as u16,
                        chunk_count: count,
                        grip: p3(&pos),
                        up: p3(&up),
                        hub: p3(&hub),
                        points: part.iter().map(p3).collect(),
                    };
                    order = self.exchange(Message::TeamScanChunk(chunk))?;
                }
                self.next(order)
            }
            Report::Landed { robot, pos } => {
                if let Some(p) = self.pos.get_mut(robot) {
                    *p = pos;
                }
                self.report(TeamEvent::Landed { robot: u8::try_from(robot).map_err(link_err)?, pos: p3(&pos) })
            }
            Report::HubAt { pos } => {
                self.hub = pos;
                self.report(TeamEvent::HubAt { pos: p3(&pos) })
            }
            Report::Lost { robot, cause } => {
                if let Some(g) = self.grip.get_mut(robot) {
                    *g = GripState::Lost;
                }
                let cause = match cause {
                    LossCause::TetherCut => TeamLoss::TetherCut,
                    LossCause::GripFailure => TeamLoss::GripFailure,
                };
                self.report(TeamEvent::Lost { robot: u8::try_from(robot).map_err(link_err)?, cause })
            }
        }
    }

    fn mission(&self) -> Option<&DefaultTeamMission<'_>> {
        (self.peek)(self.session.link())
    }

    fn done_counts(&self) -> Option<(u32, u32, u32)> {
        self.done
    }
}
