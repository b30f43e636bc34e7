//! Online replanning when the map is wrong (Tanner et al. III, Alg. 3, Lemma 1).
//!
//! The robot descends along a planned route; the flight software keeps its *travelled tether* (a0 and the route
//! waypoints passed, the slack tether's configuration) so the homotopy class of the tether is always known. Map
//! changes (an obstacle appears, vanishes, moves; several at once, III-C) are applied to the BTM by local
//! retriangulation, each reporting how many triangles it touched. If the current sleeve is untouched the plan
//! stands (Alg. 3 line 6). Otherwise the planner replans from the robot's position with its tether as prefix
//! (update sleeve, SHP, anchors, feasibility); if no feasible class continues from there it backtracks: it tries
//! the travelled waypoints from the newest back to a0 as junctions, and the robot retreats along its own tether to
//! the first junction with a feasible unexplored sleeve. If none exists, even from a0, there is no safe path.
//!
//! L-value constraints `Lc` are relative to the set of poles, so they are cleared whenever the obstacle set changes
//! (a rejected class is then simply rejected again if still infeasible: safe, costs time only).
//! Capacities: route and tether `MAX_PATH` (64) points, `MAX_UPDATES_PER_BATCH` (8) changes per batch, backtrack
//! junctions tried per update bounded by `REPLAN_BUDGET` (24).

use super::btm::{Btm, BtmError, Id, UpdateReport};
use super::geo::Pt;
use super::lvalue::{polyline_lvalue, LValue};
use super::plan::{plan_from, Plan, PlanError, PlanReport, HomotopyParams, Workspace};
use super::sleeve::Path;
use super::planes::HoldModel;
use crate::config::homotopy::{MAX_L_CONSTRAINTS, MAX_OBSTACLE_VERTICES, MAX_PATH, MAX_SLEEVE, MAX_UPDATES_PER_BATCH, REPLAN_BUDGET};
use heapless::Vec as HVec;

/// A map error found during descent (Tanner III-A).
#[derive(Clone, Debug, PartialEq)]
pub enum MapChange {
    /// A new obstacle.
    Appeared(HVec<Pt, MAX_OBSTACLE_VERTICES>),
    /// Obstacle slot found to be a phantom.
    Vanished(u8),
    /// Obstacle slot is really at these corners.
    Moved(u8, HVec<Pt, MAX_OBSTACLE_VERTICES>),
}

/// What one change did to the BTM.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangeReport {
    /// Triangles removed/created.
    pub update: UpdateReport,
    /// Slot of the new obstacle, if any.
    pub obstacle: Option<u8>,
    /// Error, if the change was refused (the BTM is then unchanged by it).
    pub error: Option<BtmError>,
}

/// What the robot must do after an update.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum OnlineAction {
    /// Sleeve untouched: keep going.
    Continue,
    /// New descent from the robot's position (SHP, anchors and feasibility recomputed).
    Replanned,
    /// Retreat along the tether to `junction`, then descend a new sleeve.
    Backtrack {
        /// The junction point (a travelled waypoint or a0).
        junction: Pt,
    },
    /// No feasible class from any junction: retreat to a0 and report.
    NoSafePath,
}

/// Report of one online update.
#[derive(Clone, Debug)]
pub struct UpdateOutcome {
    /// Per change.
    pub changes: HVec<ChangeReport, MAX_UPDATES_PER_BATCH>,
    /// Whether the current sleeve was touched.
    pub sleeve_affected: bool,
    /// Whether the SHP of the plan changed.
    pub shp_changed: bool,
    /// Decision.
    pub action: OnlineAction,
    /// Planning details of the last attempt.
    pub report: PlanReport,
}

/// A route leg's bookkeeping on arrival.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Leg {
    /// Descending: the waypoint joins the travelled tether.
    Advance,
    /// Retreating: the waypoint leaves the travelled tether (`pop`), or is the junction (`!pop`).
    Retreat {
        /// Pop the travelled tether's last point on arrival.
        pop: bool,
    },
}

/// Online planner state (Alg. 3).
#[derive(Clone, Debug)]
pub struct OnlinePlanner {
    /// Root anchor.
    pub a0: Pt,
    /// Goal.
    pub g: Pt,
    /// Holding model.
    pub model: HoldModel,
    /// Parameters.
    pub params: HomotopyParams,
    /// Current plan.
    pub plan: Option<Plan>,
    /// Travelled tether: a0 and the waypoints passed.
    pub traveled: HVec<Pt, MAX_PATH>,
    /// Remaining route.
    pub route: HVec<(Pt, Leg), { 2 * MAX_PATH }>,
    /// L-value constraints `Lc`.
    pub constraints: HVec<LValue, MAX_L_CONSTRAINTS>,
    sleeve_sig: HVec<(Id, [Id; 3]), MAX_SLEEVE>,
}

impl OnlinePlanner {
    /// New planner (no plan yet).
    pub fn new(a0: Pt, g: Pt, model: HoldModel, params: HomotopyParams) -> Self {
        let mut traveled = HVec::new();
        let _ = traveled.push(a0);
        OnlinePlanner {
            a0,
            g,
            model,
            params,
            plan: None,
            traveled,
            route: HVec::new(),
            constraints: HVec::new(),
            sleeve_sig: HVec::new(),
        }
    }

    /// Alg. 1 on the current map. Returns whether a plan was found.
    pub fn preplan(&mut self, btm: &Btm, ws: &mut Workspace, report: &mut PlanReport) -> Result<bool, PlanError> {
        let tether = [self.a0];
        let plan = plan_from(btm, &self.model, &self.params, ws, &tether, self.g, &mut self.constraints, report)?;
        Ok(self.adopt(btm, plan, &[]))
    }

    fn adopt(&mut self, btm: &Btm, plan: Option<Plan>, retreat: &[(Pt, Leg)]) -> bool {
        self.route.clear();
        for r in retreat {
            let _ = self.route.push(*r);
        }
        let found = plan.is_some();
        if let Some(p) = &plan {
            for w in p.descent.iter().skip(1) {
                let _ = self.route.push((*w, Leg::Advance));
            }
            self.sleeve_sig.clear();
            for t in p.class.sleeve.iter() {
                if let Some(tr) = btm.tri(*t) {
                    let _ = self.sleeve_sig.push((*t, tr.v));
                }
            }
        }
        self.plan = plan;
        found
    }

    /// Next waypoint to drive to.
    pub fn next_waypoint(&self) -> Option<Pt> {
        self.route.first().map(|w| w.0)
    }

    /// The robot arrived at the next waypoint.
    pub fn reached_waypoint(&mut self) {
        if self.route.is_empty() {
            return;
        }
        let Some((p, leg)) = super::geo::remove_at(&mut self.route, 0) else { return };
        match leg {
            Leg::Advance => {
                if self.traveled.last() != Some(&p) {
                    let _ = self.traveled.push(p);
                }
            }
            Leg::Retreat { pop: true } => {
                if self.traveled.len() > 1 {
                    self.traveled.pop();
                }
            }
            Leg::Retreat { pop: false } => {}
        }
    }

    /// True when the robot is at the goal (route done and a plan was being followed).
    pub fn at_goal(&self, robot: Pt) -> bool {
        self.route.is_empty() && robot.dist(self.g) < 1e-6
    }

    fn sleeve_intact(&self, btm: &Btm) -> bool {
        self.sleeve_sig.iter().all(|(t, v)| btm.tri(*t).is_some_and(|tr| tr.v == *v))
    }

    /// Alg. 3 for one batch of map changes with the robot at `robot` (on its route).
    pub fn apply_changes(&mut self, btm: &mut Btm, ws: &mut Workspace, changes: &[MapChange], robot: Pt) -> UpdateOutcome {
        let mut out = UpdateOutcome {
            changes: HVec::new(),
            sleeve_affected: false,
            shp_changed: false,
            action: OnlineAction::Continue,
            report: PlanReport::default(),
        };
        for c in changes.iter().take(MAX_UPDATES_PER_BATCH) {
            let r = match c {
                MapChange::Appeared(p) => btm.add_obstacle(p).map(|(k, u)| (Some(k), u)),
                MapChange::Vanished(k) => btm.remove_obstacle(*k).map(|u| (None, u)),
                MapChange::Moved(k, p) => btm.move_obstacle(*k, p).map(|(k, u)| (Some(k), u)),
            };
            let rep = match r {
                Ok((k, u)) => ChangeReport { update: u, obstacle: k, error: None },
                Err(e) => ChangeReport { update: UpdateReport::default(), obstacle: None, error: Some(e) },
            };
            let _ = out.changes.push(rep);
        }
        self.constraints.clear();
        // Is the current sleeve (or the remaining route) affected?
        let mut route_pts: HVec<Pt, { 2 * MAX_PATH + 1 }> = HVec::new();
        let _ = route_pts.push(robot);
        for (p, _) in self.route.iter() {
            let _ = route_pts.push(*p);
        }
        let route_blocked = route_pts.windows(2).any(|w| matches!(w, [a, b] if !btm.segment_free(*a, *b)));
        out.sleeve_affected = self.plan.is_none() || !self.sleeve_intact(btm) || route_blocked;
        if !out.sleeve_affected {
            // The plan stands, but L-values are relative to the poles: recompute the class's value.
            let mut full: HVec<Pt, { 3 * MAX_PATH + 1 }> = HVec::new();
            for p in self.traveled.iter().chain(route_pts.iter()) {
                if full.last() != Some(p) {
                    let _ = full.push(*p);
                }
            }
            if let Some(plan) = self.plan.as_mut() {
                plan.class.l = polyline_lvalue(btm, &full);
            }
            return out;
        }
        let old_shp: Option<Path> = self.plan.as_ref().map(|p| p.shp.clone());
        // Replan from the robot with its tether as prefix; then from junctions back to a0.
        let mut tether: HVec<Pt, MAX_PATH> = self.traveled.clone();
        if tether.last() != Some(&robot) {
            let _ = tether.push(robot);
        }
        let n = self.traveled.len();
        // Candidates: the robot itself, then travelled waypoints newest first.
        for attempt in 0..=n.min(REPLAN_BUDGET) {
            let (t_slice, junction): (&[Pt], Option<usize>) = if attempt == 0 {
                (&tether, None)
            } else {
                let k = n - attempt;
                (self.traveled.get(..=k).unwrap_or(&[]), Some(k))
            };
            let mut rep = PlanReport::default();
            let res = plan_from(btm, &self.model, &self.params, ws, t_slice, self.g, &mut self.constraints, &mut rep);
            out.report = rep;
            let Ok(Some(plan)) = res else { continue };
            out.shp_changed = old_shp.as_ref().is_none_or(|o| o.pts != plan.shp.pts);
            match junction {
                None => {
                    // The robot's position becomes a tether point: the new descent starts there.
                    if self.traveled.last() != Some(&robot) {
                        let _ = self.traveled.push(robot);
                    }
                    self.adopt(btm, Some(plan), &[]);
                    out.action = OnlineAction::Replanned;
                }
                Some(k) => {
                    let mut retreat: HVec<(Pt, Leg), MAX_PATH> = HVec::new();
                    for i in (k..n).rev() {
                        if let Some(p) = self.traveled.get(i) {
                            let _ = retreat.push((*p, Leg::Retreat { pop: i != k }));
                        }
                    }
                    let junction_pt = self.traveled.get(k).copied().unwrap_or(self.a0);
                    self.adopt(btm, Some(plan), &retreat);
                    out.action = OnlineAction::Backtrack { junction: junction_pt };
                }
            }
            return out;
        }
        // No safe path: retreat all the way to a0.
        let mut retreat: HVec<(Pt, Leg), MAX_PATH> = HVec::new();
        for i in (0..n).rev() {
            if let Some(p) = self.traveled.get(i) {
                let _ = retreat.push((*p, Leg::Retreat { pop: i != 0 }));
            }
        }
        self.adopt(btm, None, &retreat);
        out.action = OnlineAction::NoSafePath;
        out
    }
}
