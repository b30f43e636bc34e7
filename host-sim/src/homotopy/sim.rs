//! Closed loop (Tanner et al. III-IV, scenario C): the rover descends a plane whose true obstacles differ from its
//! map; a simple range sensor on the plane (2D ray casts within a sensing radius, seeded range noise) reveals
//! them; the flight software's [`OnlinePlanner`] (Alg. 3) replans; the loop ends at the goal or with "no safe path".
//!
//! Perception is deliberately simple (documented simplification): a ray that hits a true obstacle not in the map
//! reveals that obstacle's polygon (a segmentation stand-in); if a map obstacle without a true counterpart lies
//! within 2.5 m of it, the change is reported as "moved". A map obstacle is a phantom once 3 rays pass through its
//! interior (within range) without a true hit before it.

use super::scenarios::{unit, Scenario};
use firmware::plan::homotopy::btm::Btm;
use firmware::plan::homotopy::geo::{point_in_polygon, Pt};
use firmware::plan::homotopy::lvalue::polyline_lvalue;
use firmware::plan::homotopy::online::{MapChange, OnlineAction, OnlinePlanner};
use firmware::plan::homotopy::plan::{PlanReport, HomotopyParams, Workspace};
use rand_core::SeedableRng;
use rand_pcg::Pcg64;

/// Closed-loop parameters.
#[derive(Clone, Copy, Debug)]
pub struct SimConfig {
    /// Drive step (m). Default 0.25.
    pub step_m: f64,
    /// Sensing radius (m). Default 3.0.
    pub sensor_range_m: f64,
    /// Rays per scan (evenly spread over 360 deg). Default 90.
    pub rays: usize,
    /// Range noise, uniform +- (m). Default 0.02.
    pub noise_m: f64,
    /// Seed of the noise.
    pub seed: u64,
    /// Step limit. Default 5000.
    pub max_steps: usize,
}

impl Default for SimConfig {
    fn default() -> Self {
        SimConfig { step_m: 0.25, sensor_range_m: 3.0, rays: 90, noise_m: 0.02, seed: 1, max_steps: 5000 }
    }
}

/// How the loop ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SimOutcome {
    /// At the goal, tether in a feasible class.
    ReachedGoal,
    /// The planner reported that no safe path exists (the rover retreated to a0).
    NoSafePath,
    /// The pre-plan on the initial map found nothing.
    NoInitialPlan,
    /// Step limit.
    StepLimit,
}

/// One replanning event.
#[derive(Clone)]
pub struct SimEvent {
    /// Step index.
    pub step: usize,
    /// Robot position.
    pub robot: Pt,
    /// Changes, human-readable.
    pub changes: Vec<String>,
    /// Triangles touched per change.
    pub touched: Vec<usize>,
    /// Planner decision.
    pub action: OnlineAction,
    /// BTM before and after (for pictures).
    pub before: Box<Btm>,
    /// BTM after.
    pub after: Box<Btm>,
    /// Plan before (SHP points).
    pub shp_before: Vec<Pt>,
    /// Plan after (SHP points).
    pub shp_after: Vec<Pt>,
}

/// Result of a closed-loop run.
pub struct SimResult {
    /// Outcome.
    pub outcome: SimOutcome,
    /// Robot positions, step by step.
    pub path: Vec<Pt>,
    /// Replanning events.
    pub events: Vec<SimEvent>,
    /// Drive segments that crossed a true obstacle (must be 0).
    pub collisions: usize,
    /// Whether the final tether (travelled waypoints + robot) is in the final plan's class.
    pub tether_in_plan_class: bool,
    /// Final map.
    pub btm: Box<Btm>,
    /// Final planner.
    pub planner: OnlinePlanner,
}

fn ray_hit(p: Pt, dir: Pt, range: f64, poly: &[Pt]) -> Option<f64> {
    let mut best: Option<f64> = None;
    for i in 0..poly.len() {
        let (a, b) = (poly[i], poly[(i + 1) % poly.len()]);
        let e = b - a;
        let den = dir.cross(e);
        if den.abs() < 1e-12 {
            continue;
        }
        let t = (a - p).cross(e) / den;
        let u = (a - p).cross(dir) / den;
        if t >= 0.0 && t <= range && (0.0..=1.0).contains(&u) && best.is_none_or(|b| t < b) {
            best = Some(t);
        }
    }
    best
}

fn segment_hits_truth(a: Pt, b: Pt, truth: &[Vec<Pt>]) -> bool {
    (1..20).any(|k| {
        let p = a + (b - a) * (k as f64 / 20.0);
        truth.iter().any(|o| point_in_polygon(p, o, true))
    })
}

/// Runs the closed loop on scenario `s` (map = `s.known`, world = `s.truth`).
pub fn run(s: &Scenario, cfg: &SimConfig) -> SimResult {
    let mut rng = Pcg64::seed_from_u64(cfg.seed);
    let mut btm = Box::new(Btm::new());
    let obs: Vec<&[Pt]> = s.known.iter().map(|o| o.as_slice()).collect();
    let _ = btm.build(&s.plane, &obs);
    let mut ws = Box::new(Workspace::default());
    let mut planner = OnlinePlanner::new(s.a0, s.g, s.model, HomotopyParams::default());
    // Map slot per known obstacle, and which truth obstacle each known one is.
    let mut slot_truth: Vec<(u8, Option<usize>)> = Vec::new();
    for (k, o) in btm.obstacles() {
        let t = s.truth.iter().position(|t| {
            t.len() == o.corners.len() && t.iter().all(|p| o.corners.iter().any(|q| q.dist(*p) < 1e-9))
        });
        slot_truth.push((k, t));
    }
    let mut truth_known: Vec<bool> = (0..s.truth.len()).map(|j| slot_truth.iter().any(|(_, t)| *t == Some(j))).collect();
    let mut phantom_evidence: Vec<(u8, usize)> = Vec::new();
    let mut robot = s.a0;
    let mut path = vec![robot];
    let mut events = Vec::new();
    let mut collisions = 0;
    let ok = planner.preplan(&btm, &mut ws, &mut PlanReport::default()).unwrap_or(false);
    let mut outcome = if ok { SimOutcome::StepLimit } else { SimOutcome::NoInitialPlan };
    let mut gave_up = false;
    for step in 0..cfg.max_steps {
        if !ok {
            break;
        }
        // Sense.
        let mut changes: Vec<MapChange> = Vec::new();
        let mut descr = Vec::new();
        for r in 0..cfg.rays {
            let ang = core::f64::consts::TAU * r as f64 / cfg.rays as f64;
            let dir = Pt { x: ang.cos(), y: ang.sin() };
            let mut hit: Option<(f64, usize)> = None;
            for (j, o) in s.truth.iter().enumerate() {
                if let Some(t) = ray_hit(robot, dir, cfg.sensor_range_m, o) {
                    if hit.is_none_or(|h| t < h.0) {
                        hit = Some((t, j));
                    }
                }
            }
            let noisy = hit.map(|(t, j)| (t + cfg.noise_m * (2.0 * unit(&mut rng) - 1.0), j));
            let free_range = noisy.map(|h| h.0).unwrap_or(cfg.sensor_range_m);
            if let Some((_, j)) = noisy {
                if !truth_known[j] {
                    truth_known[j] = true;
                    let poly: heapless::Vec<Pt, 8> = s.truth[j].iter().copied().collect();
                    let c = s.truth[j].iter().fold(Pt::default(), |a, p| a + *p) * (1.0 / s.truth[j].len() as f64);
                    let near = slot_truth.iter().position(|(k, t)| {
                        t.is_none()
                            && btm.obstacle(*k).is_some_and(|o| {
                                let oc = o.corners.iter().fold(Pt::default(), |a, p| a + *p) * (1.0 / o.corners.len() as f64);
                                oc.dist(c) < 2.5
                            })
                    });
                    match near {
                        Some(i) => {
                            let k = slot_truth[i].0;
                            slot_truth.remove(i);
                            descr.push(format!("O{k} moved"));
                            changes.push(MapChange::Moved(k, poly));
                            slot_truth.push((u8::MAX, Some(j)));
                        }
                        None => {
                            descr.push("new obstacle".to_string());
                            changes.push(MapChange::Appeared(poly));
                            slot_truth.push((u8::MAX, Some(j)));
                        }
                    }
                }
            }
            // Phantom evidence: a map obstacle with no true counterpart that this ray passes through.
            for (k, t) in slot_truth.iter() {
                if t.is_some() || *k == u8::MAX {
                    continue;
                }
                let Some(o) = btm.obstacle(*k) else { continue };
                if let Some(entry) = ray_hit(robot, dir, cfg.sensor_range_m, &o.corners) {
                    if entry + 0.3 < free_range {
                        match phantom_evidence.iter_mut().find(|e| e.0 == *k) {
                            Some(e) => e.1 += 1,
                            None => phantom_evidence.push((*k, 1)),
                        }
                    }
                }
            }
        }
        for (k, n) in phantom_evidence.iter() {
            if *n >= 3 {
                if let Some(i) = slot_truth.iter().position(|(kk, t)| kk == k && t.is_none()) {
                    slot_truth.remove(i);
                    descr.push(format!("O{k} is a phantom"));
                    changes.push(MapChange::Vanished(*k));
                }
            }
        }
        phantom_evidence.retain(|(k, _)| slot_truth.iter().any(|(kk, _)| kk == k));
        if !changes.is_empty() {
            let before = btm.clone();
            let shp_before = planner.plan.as_ref().map(|p| p.shp.pts.to_vec()).unwrap_or_default();
            let out = planner.apply_changes(&mut btm, &mut ws, &changes, robot);
            // Record the slots the map gave the new obstacles.
            let mut new_slots = out.changes.iter().filter_map(|c| c.obstacle);
            for st in slot_truth.iter_mut().filter(|(k, _)| *k == u8::MAX) {
                if let Some(k) = new_slots.next() {
                    st.0 = k;
                }
            }
            for c in out.changes.iter().filter(|c| c.error.is_some()) {
                descr.push(format!("refused: {:?}", c.error));
            }
            events.push(SimEvent {
                step,
                robot,
                changes: descr,
                touched: out.changes.iter().map(|c| c.update.touched()).collect(),
                action: out.action,
                before,
                after: btm.clone(),
                shp_before,
                shp_after: planner.plan.as_ref().map(|p| p.shp.pts.to_vec()).unwrap_or_default(),
            });
            if out.action == OnlineAction::NoSafePath {
                gave_up = true;
            }
        }
        // Drive.
        let Some(w) = planner.next_waypoint() else {
            outcome = if gave_up {
                SimOutcome::NoSafePath
            } else if robot.dist(s.g) < 1e-9 {
                SimOutcome::ReachedGoal
            } else {
                SimOutcome::NoSafePath
            };
            break;
        };
        let d = w - robot;
        let next = if d.norm() <= cfg.step_m {
            planner.reached_waypoint();
            w
        } else {
            robot + d * (cfg.step_m / d.norm())
        };
        if segment_hits_truth(robot, next, &s.truth) {
            collisions += 1;
        }
        robot = next;
        path.push(robot);
    }
    let mut tether = planner.traveled.to_vec();
    if tether.last() != Some(&robot) {
        tether.push(robot);
    }
    let tether_in_plan_class =
        planner.plan.as_ref().is_some_and(|p| polyline_lvalue(&btm, &tether).same_class(p.class.l));
    SimResult { outcome, path, events, collisions, tether_in_plan_class, btm, planner }
}
