//! Ascent feasibility (Tanner Alg. 2), safe descent inside a feasible ascent sleeve, and pre-planning (Tanner
//! Alg. 1 = Abad-Manterola Fig. 6): ascent first, then a descent homotopic to it, so the robot can always retreat.
//!
//! Parameters ([`HomotopyParams`]): `max_classes` (16) classes per A* round; `descent_clearance_m` (0.15 m) by which
//! the descent path keeps off the obstacle corners where the SHP bends (the descent is the SHP with its bends pushed
//! outward, then halved, then zero if blocked); `descent_sample_m` (0.2 m) spacing of the holding checks along the
//! descent. Rounds are bounded by `REPLAN_BUDGET` (24).

use super::classes::{enumerate_classes, HomotopyClass, SearchArena, SearchError, SearchOutcome, SearchStart};
use super::btm::Btm;
use super::control::ControlGrid;
use super::geo::{Pt, EPS};
use super::lvalue::{polyline_lvalue, LValue};
use super::sleeve::{anchors, crossing_sequence, shortest_homotopic_path, walk_segment, Anchor, Path, Sleeve, SleeveError};
use super::planes::HoldModel;
use crate::config::homotopy::{
    DEFAULT_CLASSES_PER_ROUND, DEFAULT_DESCENT_CLEARANCE_M, DEFAULT_DESCENT_SAMPLE_M, MAX_CLASSES, MAX_L_CONSTRAINTS,
    MAX_PATH, REPLAN_BUDGET,
};
use crate::plan::status::{Enumeration, Status};
use heapless::Vec as HVec;

/// Planner parameters (see module docs for defaults).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HomotopyParams {
    /// Classes per A* round (<= `MAX_CLASSES`). Default 16.
    pub max_classes: usize,
    /// Clearance of the descent path from SHP bend corners (m). Default 0.15.
    pub descent_clearance_m: f64,
    /// Spacing of holding checks along the descent (m). Default 0.2.
    pub descent_sample_m: f64,
}

impl Default for HomotopyParams {
    fn default() -> Self {
        HomotopyParams {
            max_classes: DEFAULT_CLASSES_PER_ROUND,
            descent_clearance_m: DEFAULT_DESCENT_CLEARANCE_M,
            descent_sample_m: DEFAULT_DESCENT_SAMPLE_M,
        }
    }
}

/// Caller-owned scratch for planning (search arena, controllable-set grid, class list).
pub struct Workspace {
    /// A* arena.
    pub search: SearchArena,
    /// Controllable-set grid.
    pub grid: ControlGrid,
    /// Classes of the current round.
    pub classes: HVec<HomotopyClass, MAX_CLASSES>,
}

impl Workspace {
    /// Empty (const: a flight computer keeps it in a `static`).
    pub const fn new() -> Self {
        Workspace { search: SearchArena::new(), grid: ControlGrid::new(), classes: HVec::new() }
    }
}

impl Default for Workspace {
    fn default() -> Self {
        Self::new()
    }
}

/// Why an SHP's ascent is infeasible (Alg. 2).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Blocked {
    /// The robot cannot hold at the hand-off point on its proximal anchor (for a0 this is the naive case).
    NotHeld,
    /// The controllable set never reaches the anchor's SHP edge.
    NotPassable,
}

/// Outcome of the ascent feasibility check (Tanner Alg. 2).
#[derive(Clone, Debug, PartialEq)]
#[allow(clippy::large_enum_variant)]
pub enum Feasibility {
    /// Every intermediate anchor passable; hand-off points from g up to a0's segment.
    Feasible {
        /// Points where each anchor is passed (crossing its SHP edge), from the goal upward.
        handoffs: HVec<Pt, MAX_PATH>,
    },
    /// Blocked at anchor `anchor_index` (0 = a0, k = the last intermediate anchor).
    Infeasible {
        /// Anchor index (0 = a0).
        anchor_index: usize,
        /// Why.
        reason: Blocked,
    },
}

/// Alg. 2 `feasibilityCheck()`: from `q = g`, for `j = k..1` build `C_j(q)`, require `a_j` passable, hand off at its
/// SHP edge; finally the robot must hold on a0 (then it reels straight up the tether).
pub fn feasibility_check(btm: &Btm, model: &HoldModel, shp: &Path, anchors_: &[Anchor], grid: &mut ControlGrid) -> Feasibility {
    let mut handoffs = HVec::new();
    let (Some(&a0), Some(&g)) = (shp.pts.first(), shp.pts.last()) else {
        return Feasibility::Infeasible { anchor_index: 0, reason: Blocked::NotHeld };
    };
    let mut q = g;
    let mut j = anchors_.len();
    let anchor_pt = |j: usize| if j == 0 { Some(a0) } else { anchors_.get(j - 1).map(|a| a.p) };
    for _ in 0..=anchors_.len() {
        let Some(aj) = anchor_pt(j) else { break };
        if !model.holds(q, aj) {
            return Feasibility::Infeasible { anchor_index: j, reason: Blocked::NotHeld };
        }
        if j == 0 {
            return Feasibility::Feasible { handoffs };
        }
        let Some(prev) = anchor_pt(j - 1) else { break };
        let cs = grid.controllable_set(btm, model, q, prev, aj);
        match cs.crossing {
            Some(x) => {
                let _ = handoffs.push(x);
                q = x;
                j -= 1;
            }
            None => return Feasibility::Infeasible { anchor_index: j, reason: Blocked::NotPassable },
        }
    }
    Feasibility::Infeasible { anchor_index: j, reason: Blocked::NotPassable }
}

/// The descent: `path` with each bend on an obstacle corner pushed `clearance` outward along the bend's bisector.
/// `None` when a pushed segment leaves free space.
pub fn offset_path(btm: &Btm, path: &Path, clearance: f64) -> Option<HVec<Pt, MAX_PATH>> {
    let mut out = HVec::new();
    let n = path.pts.len();
    for (i, p) in path.pts.iter().enumerate() {
        let mut q = *p;
        if i > 0 && i + 1 < n && clearance > 0.0 {
            let (a, c) = (path.pts.get(i - 1).copied()?, path.pts.get(i + 1).copied()?);
            let (d1, d2) = (*p - a, c - *p);
            let (n1, n2) = (d1.norm(), d2.norm());
            if n1 > EPS && n2 > EPS {
                let out_dir = d1 * (1.0 / n1) - d2 * (1.0 / n2);
                let m = out_dir.norm();
                if m > EPS {
                    q = *p + out_dir * (clearance / m);
                }
            }
        }
        out.push(q).ok()?;
    }
    let ok = out.windows(2).all(|w| matches!(w, [a, b] if btm.segment_free(*a, *b)))
        && out.iter().all(|p| btm.is_free(*p) || path.pts.iter().any(|q| q == p));
    ok.then_some(out)
}

/// Checks a descent: from the end of `tether` (a0 ... start) along `descent` (starting at the tether's end), every
/// `sample_m` the robot holds on its proximal anchor (the last bend of the SHP of the tether so far), and the whole
/// tether + descent is in the class `class_l` (the descent stays in the feasible ascent sleeve).
pub fn descent_safe(
    btm: &Btm,
    model: &HoldModel,
    tether: &[Pt],
    descent: &[Pt],
    sample_m: f64,
    class_l: LValue,
) -> Result<bool, SleeveError> {
    let Some(&a0) = tether.first() else { return Ok(false) };
    let mut seq: Sleeve = HVec::new();
    crossing_sequence(btm, tether, &mut seq)?;
    let Some(&t_end) = seq.last() else { return Err(SleeveError::PointNotInFreeSpace) };
    let mut t = t_end;
    let step = sample_m.max(1e-3);
    let mut budget = 4096usize;
    for w in descent.windows(2) {
        let [a, b] = w else { continue };
        let len = a.dist(*b);
        let k = ((len / step) as usize).max(1);
        let mut prev = *a;
        for s in 1..=k {
            budget = budget.saturating_sub(1);
            if budget == 0 {
                return Err(SleeveError::Budget);
            }
            let p = *a + (*b - *a) * (s as f64 / k as f64);
            t = walk_segment(btm, t, prev, p, &mut seq)?;
            prev = p;
            let mut sl = seq.clone();
            if sl.last() != Some(&t) {
                super::sleeve::push_reduced(&mut sl, t)?;
            }
            let taut = shortest_homotopic_path(btm, &sl, a0, p)?;
            let n = taut.pts.len();
            let proximal = taut.pts.get(n.saturating_sub(2)).copied().unwrap_or(a0);
            if !model.holds(p, proximal) {
                return Ok(false);
            }
        }
    }
    let mut full: HVec<Pt, { 2 * MAX_PATH }> = HVec::new();
    for p in tether.iter().chain(descent.iter().skip(1)) {
        full.push(*p).map_err(|_| SleeveError::Budget)?;
    }
    Ok(polyline_lvalue(btm, &full).same_class(class_l))
}

/// A chosen ascent/descent pair in one feasible homotopy class.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The class (sleeve from a0 to g, L-value).
    pub class: HomotopyClass,
    /// SHP of the class from a0 to g (the taut tether at the goal).
    pub shp: Path,
    /// Intermediate anchors a1..ak of the SHP.
    pub anchors: HVec<Anchor, MAX_PATH>,
    /// Hand-off points of the ascent (Alg. 2), from g upward.
    pub handoffs: HVec<Pt, MAX_PATH>,
    /// Descent from the start point (a0, or the robot when replanning) to g.
    pub descent: HVec<Pt, MAX_PATH>,
}

impl Plan {
    /// The ascent path from g: the descent reversed (same sleeve, so the tether retracts along its own route).
    pub fn ascent(&self) -> impl Iterator<Item = Pt> + '_ {
        self.descent.iter().rev().copied()
    }
}

/// What happened to one examined class.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Verdict {
    /// Feasible ascent and safe descent: chosen.
    Chosen,
    /// Ascent infeasible (Alg. 2).
    Infeasible(usize, Blocked),
    /// Ascent feasible but no safe descent in the sleeve.
    DescentUnsafe,
    /// SHP or sleeve computation failed.
    Geometry(SleeveError),
}

/// One examined class, for reports and pictures.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ClassVerdict {
    /// L-value.
    pub l: LValue,
    /// SHP length (m).
    pub shp_length: f64,
    /// Number of intermediate anchors.
    pub anchors: usize,
    /// Verdict.
    pub verdict: Verdict,
}

/// Report of a planning call.
#[derive(Clone, Debug, Default)]
pub struct PlanReport {
    /// Classes examined, in order.
    pub examined: HVec<ClassVerdict, 64>,
    /// Last A* outcome.
    pub search: Option<SearchOutcome>,
    /// A* rounds.
    pub rounds: usize,
}

/// Planning errors (bad input).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlanError {
    /// Search input invalid.
    Search(SearchError),
    /// The tether so far cannot be walked through the BTM.
    Tether(SleeveError),
}

/// Plans from the end of `tether` (a0 first) to `g`: Alg. 1's loop. Rejected classes' L-values are added to
/// `constraints` (`Lc`). Returns the plan, or `None` when every class is infeasible or the budget ran out (see
/// `report.search`).
#[allow(clippy::too_many_arguments)]
pub fn plan_from(
    btm: &Btm,
    model: &HoldModel,
    params: &HomotopyParams,
    ws: &mut Workspace,
    tether: &[Pt],
    g: Pt,
    constraints: &mut HVec<LValue, MAX_L_CONSTRAINTS>,
    report: &mut PlanReport,
) -> Result<Option<Plan>, PlanError> {
    let Some(&start) = tether.last() else { return Err(PlanError::Search(SearchError::StartNotInFreeSpace)) };
    let Some(&a0) = tether.first() else { return Err(PlanError::Search(SearchError::StartNotInFreeSpace)) };
    let mut prefix: Sleeve = HVec::new();
    if tether.len() > 1 {
        crossing_sequence(btm, tether, &mut prefix).map_err(PlanError::Tether)?;
    }
    let l0 = polyline_lvalue(btm, tether);
    for _ in 0..REPLAN_BUDGET {
        report.rounds += 1;
        ws.classes.clear();
        let st = SearchStart { point: start, l0, prefix: &prefix };
        let outcome = enumerate_classes(btm, &mut ws.search, &st, g, constraints, params.max_classes, &mut ws.classes);
        if let Status::InvalidInput(e) = outcome {
            return Err(PlanError::Search(e));
        }
        report.search = Some(outcome);
        if ws.classes.is_empty() {
            return Ok(None);
        }
        // Examine in order of SHP length.
        let mut order: HVec<(f64, usize, Option<Path>), MAX_CLASSES> = HVec::new();
        for (i, c) in ws.classes.iter().enumerate() {
            let shp = shortest_homotopic_path(btm, &c.sleeve, a0, g);
            let len = shp.as_ref().map(|p| p.length()).unwrap_or(f64::MAX);
            let _ = order.push((len, i, shp.ok()));
        }
        // sorted by (length, class index) through a key list (the panic-free sort moves `Copy` values)
        let mut keys: HVec<(f64, usize, usize), MAX_CLASSES> = HVec::new();
        for (k, o) in order.iter().enumerate() {
            let _ = keys.push((o.0, o.1, k));
        }
        super::geo::sort_by(&mut keys, |a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).is_lt());
        for (len, i, shp) in keys.iter().filter_map(|k| order.get(k.2)) {
            let Some(class) = ws.classes.get(*i).cloned() else { continue };
            let Some(shp) = shp.clone() else {
                let _ = report.examined.push(ClassVerdict {
                    l: class.l,
                    shp_length: f64::NAN,
                    anchors: 0,
                    verdict: Verdict::Geometry(SleeveError::Budget),
                });
                let _ = constraints.push(class.l);
                continue;
            };
            let anch = anchors(btm, &shp);
            let mut verdict = ClassVerdict { l: class.l, shp_length: *len, anchors: anch.len(), verdict: Verdict::DescentUnsafe };
            match feasibility_check(btm, model, &shp, &anch, &mut ws.grid) {
                Feasibility::Infeasible { anchor_index, reason } => verdict.verdict = Verdict::Infeasible(anchor_index, reason),
                Feasibility::Feasible { handoffs } => {
                    // Descent from `start` along the remainder's SHP inside the searched part of the sleeve.
                    match shortest_homotopic_path(btm, &class.search_part, start, g) {
                        Err(e) => verdict.verdict = Verdict::Geometry(e),
                        Ok(rest) => {
                            for c in [params.descent_clearance_m, 0.5 * params.descent_clearance_m, 0.0] {
                                let Some(descent) = offset_path(btm, &rest, c) else { continue };
                                if descent_safe(btm, model, tether, &descent, params.descent_sample_m, class.l) == Ok(true) {
                                    let _ = report.examined.push(ClassVerdict { verdict: Verdict::Chosen, ..verdict });
                                    return Ok(Some(Plan { class, shp, anchors: anch, handoffs, descent }));
                                }
                            }
                        }
                    }
                }
            }
            let _ = report.examined.push(verdict);
            let _ = constraints.push(class.l);
        }
        if outcome != Status::Exact(Enumeration::Enough) {
            return Ok(None);
        }
    }
    Ok(None)
}

/// Alg. 1: offline pre-planning from a0 (BTM already built).
#[allow(clippy::too_many_arguments)]
pub fn preplan(
    btm: &Btm,
    model: &HoldModel,
    params: &HomotopyParams,
    ws: &mut Workspace,
    a0: Pt,
    g: Pt,
    constraints: &mut HVec<LValue, MAX_L_CONSTRAINTS>,
    report: &mut PlanReport,
) -> Result<Option<Plan>, PlanError> {
    plan_from(btm, model, params, ws, &[a0], g, constraints, report)
}
