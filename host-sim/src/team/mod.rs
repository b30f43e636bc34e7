//! Simulation of a tethered climbing team (Morad et al.; scenario D): four robots gripping a real steep surface,
//! tethered to a hub, each with a range sensor; each robot in turn scans, runs the flight planner
//! ([`firmware::plan::team::LocalPlanner`], bounded-leg A*) and hops to the first anchor of its plan.
//!
//! The simulator is the referee: it lands the robot on the *true* surface (ray cast along the scene normal
//! through the planned anchor) and checks, with its own code, every hop against h_max (hop length) and r_max (the
//! landing point's distance to the hub, which the gripped robots hold still during the hop), and every leg against
//! r_max after each hub motion. Violations are recorded, never corrected. A scripted gripper failure cuts a
//! robot's tether (node loss); the others continue.
//!
//! Worlds: [`cliff_from_hirise`] (the steepest part of the HiRISE crop, scaled into a cliff) and
//! [`itokawa`] (the Hayabusa shape model, metres; 30 m hops as in Fig. 16). Pictures: [`svg`].

pub mod svg;
pub mod surface;

use firmware::config::team::TeamParams;
use firmware::geom::{Real, Vec3};
use firmware::plan::status::Status;
use firmware::plan::team::leg_astar::AStarStatus;
use firmware::plan::team::formation::Team;
use firmware::plan::team::DefaultLocalPlanner;
use rand_core::Rng;
use firmware::geom::p3::{add, cross, dist, from_vec3, scale, sub, to_vec3};
use surface::{unit, Surface, P3};

/// Range sensor: `rays` directions spread over the sphere (Fibonacci lattice), range, Gaussian-ish noise.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RangeSensor {
    /// Rays per scan.
    pub rays: usize,
    /// Maximum range, metres.
    pub range: f64,
    /// Range noise (uniform, +- metres).
    pub noise: f64,
    /// Sensor height above the grip point along the surface normal, metres (SphereX: 0.30 m diameter).
    pub height: f64,
}

impl RangeSensor {
    /// Ray directions.
    pub fn directions(&self) -> Vec<P3> {
        let n = self.rays.max(1);
        let golden = core::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n)
            .map(|i| {
                let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
                let r = (1.0 - z * z).sqrt();
                let th = golden * i as f64;
                [r * th.cos(), r * th.sin(), z]
            })
            .collect()
    }
}

/// A simulated run's configuration.
#[derive(Debug, Clone)]
pub struct SimConfig {
    /// Planner parameters (h_max, r_max, ...).
    pub params: TeamParams,
    /// The sensor.
    pub sensor: RangeSensor,
    /// Team goal (hub goal), metres.
    pub goal: P3,
    /// The run succeeds when the hub is within this of the goal.
    pub goal_tol: f64,
    /// Rounds budget.
    pub max_rounds: usize,
    /// Scripted node failure: (robot, its turn number counted from 0) at which its gripper fails.
    pub fail: Option<(usize, usize)>,
    /// Noise seed.
    pub seed: u64,
}

/// One executed hop.
#[derive(Debug, Clone, PartialEq)]
pub struct HopRecord {
    /// Robot.
    pub robot: usize,
    /// Round.
    pub round: usize,
    /// Where it took off.
    pub from: P3,
    /// Where it gripped (true surface).
    pub to: P3,
    /// Hub during the hop.
    pub hub: P3,
    /// Planner status.
    pub status: AStarStatus,
    /// Planning time, seconds (host).
    pub plan_s: f64,
}

/// What happened.
#[derive(Debug, Clone, Default)]
pub struct SimReport {
    /// World name.
    pub world: String,
    /// Executed hops.
    pub hops: Vec<HopRecord>,
    /// Robot paths (anchor points, start first), per robot.
    pub paths: Vec<Vec<P3>>,
    /// Hub positions after each round.
    pub hub_path: Vec<P3>,
    /// Constraint violations the referee found (empty = every hop respected h_max and r_max).
    pub violations: Vec<String>,
    /// Robots whose tether was cut.
    pub lost: Vec<usize>,
    /// Rounds run.
    pub rounds: usize,
    /// Hub reached the goal.
    pub reached: bool,
    /// The first plan's graph (vertices, edges as index pairs) and the four first paths, for pictures.
    pub first_graph: (Vec<P3>, Vec<(usize, usize)>),
    /// The first plan of each robot (anchor points).
    pub first_plans: Vec<Vec<P3>>,
    /// Local plan times, seconds.
    pub plan_times: Vec<f64>,
}

/// Run the team from `start` (one grip point per robot) to `cfg.goal` on `surface`.
pub fn simulate<R: Rng>(surface: &dyn Surface, start: &[P3; 4], cfg: &SimConfig, rng: &mut R) -> SimReport {
    let params = cfg.params;
    let mut team: Team<4> = Team::new(start.map(to_vec3));
    let mut planner: Box<DefaultLocalPlanner> = Box::default();
    let dirs = cfg.sensor.directions();
    let mut rep = SimReport { world: surface.name().to_string(), ..Default::default() };
    rep.paths = start.iter().map(|p| vec![*p]).collect();
    rep.hub_path.push(from_vec3(&team.hub));
    let mut turns = [0usize; 4];
    let mut stalled = 0usize;
    let mut moved_this_round = false;
    let mut round = 0usize;
    let max_turns = cfg.max_rounds * 4 + 4;
    for _ in 0..max_turns {
        let Some((m, new_round)) = team.next_mover() else { break };
        if new_round && !(round == 0 && rep.hops.is_empty() && turns.iter().all(|&t| t == 0)) {
            // end of the previous round: hub motion, then the referee checks every leg
            team.hub_motion(params.r_max);
            rep.hub_path.push(from_vec3(&team.hub));
            for (k, r) in team.robots.iter().enumerate() {
                let l = dist(from_vec3(&r.pos), from_vec3(&team.hub));
                if r.attached && l > params.r_max as f64 + 1e-4 {
                    rep.violations.push(format!("round {round}: robot {k} leg {l:.3} m > r_max {}", params.r_max));
                }
            }
            if dist(from_vec3(&team.hub), cfg.goal) <= cfg.goal_tol {
                rep.reached = true;
                break;
            }
            stalled = if moved_this_round { 0 } else { stalled + 1 };
            if stalled >= 2 {
                break;
            }
            moved_this_round = false;
            round += 1;
            if round >= cfg.max_rounds {
                break;
            }
        }
        let turn = turns[m];
        turns[m] += 1;
        if cfg.fail == Some((m, turn)) {
            team.cut_tether(m);
            rep.lost.push(m);
            continue;
        }
        let pos = from_vec3(&team.robots[m].pos);
        let n_true = surface.normal_near(pos);
        let sensor = add(pos, scale(n_true, cfg.sensor.height));
        let hits = surface.scan(sensor, &dirs, cfg.sensor.range);
        let mut pts = Vec::with_capacity(hits.len());
        for (d, h) in dirs.iter().zip(hits) {
            if let Some(t) = h {
                let e = (rng.next_u32() as f64 / u32::MAX as f64 * 2.0 - 1.0) * cfg.sensor.noise;
                pts.push(to_vec3(add(sensor, scale(*d, t + e))));
            }
        }
        let leg = team.leg(m).unwrap_or_else(Vec3::zeros);
        let goal = team.slot_goal(m, &to_vec3(cfg.goal));
        let t0 = std::time::Instant::now();
        let plan = planner.plan(&pts, &to_vec3(n_true), &team.robots[m].pos, &leg, &goal, 0.5 * cfg.goal_tol as Real, &params);
        let dt = t0.elapsed().as_secs_f64();
        rep.plan_times.push(dt);
        let plan = match plan {
            Ok(p) => p,
            Err(_) => continue,
        };
        if rep.first_plans.len() < 4 && turn == 0 {
            rep.first_plans.push(plan.hops.iter().map(from_vec3).collect());
            if m == 0 {
                let g = &planner.graph;
                let verts: Vec<P3> = g.vertices[..g.n_vertices].iter().map(|v| from_vec3(&v.pos)).collect();
                let mut edges = Vec::new();
                for a in 0..g.n_vertices {
                    for e in g.out_edges(a) {
                        edges.push((a, e.to as usize));
                    }
                }
                rep.first_graph = (verts, edges);
            }
        }
        if !matches!(plan.status, Status::Exact(()) | Status::Approximate(_)) {
            continue;
        }
        let Some(target) = plan.hops.get(1) else { continue };
        // land on the true surface: cast along the scene normal through the planned anchor
        let n = from_vec3(&planner.scene.frame.n);
        let tp = from_vec3(target);
        let o = add(tp, scale(n, 3.0));
        let landing = surface
            .raycast(o, scale(n, -1.0), 6.0)
            .map(|t| add(o, scale(n, -t)))
            .or_else(|| surface.raycast(tp, n, 3.0).map(|t| add(tp, scale(n, t))));
        let Some(to) = landing else { continue };
        let hub = from_vec3(&team.hub);
        // the referee's checks (independent of the planner)
        let hop = dist(pos, to);
        if hop > params.h_max as f64 + 1e-4 {
            rep.violations.push(format!("robot {m} round {round}: hop {hop:.3} m > h_max {}", params.h_max));
        }
        let legl = dist(to, hub);
        if legl > params.r_max as f64 + 1e-4 {
            rep.violations.push(format!("robot {m} round {round}: landing {legl:.3} m from hub > r_max {}", params.r_max));
        }
        team.hop(m, to_vec3(to));
        rep.paths[m].push(to);
        rep.hops.push(HopRecord { robot: m, round, from: pos, to, hub, status: plan.status, plan_s: dt });
        if hop > 1e-3 {
            moved_this_round = true;
        }
    }
    rep.rounds = round + 1;
    if !rep.reached && dist(from_vec3(&team.hub), cfg.goal) <= cfg.goal_tol {
        rep.reached = true;
    }
    rep
}

/// The steepest `win` x `win` window of the HiRISE crop, horizontal spacing times `h_scale` and heights times
/// `z_scale` (z_scale / h_scale > 1 steepens it into a cliff). Returns the surface and its mean slope (degrees).
pub fn cliff_from_hirise(path: &std::path::Path, win: usize, h_scale: f64, z_scale: f64) -> Result<(surface::HeightSurface, f64), String> {
    use crate::terrain::npy::{load_npy, NpyOptions};
    let hm = load_npy(path, &NpyOptions::metres(1.01)).map_err(|e| e.to_string())?;
    let slope = |x: usize, y: usize| -> Option<f64> {
        let gx = (hm.get(x + 1, y)? - hm.get(x - 1, y)?) / (2.0 * hm.spacing_m);
        let gy = (hm.get(x, y + 1)? - hm.get(x, y - 1)?) / (2.0 * hm.spacing_m);
        Some((gx * gx + gy * gy).sqrt())
    };
    let win = win.min(hm.width - 2).min(hm.height - 2);
    let mut best = (f64::MIN, 0, 0);
    for y0 in (1..hm.height - win - 1).step_by(2) {
        for x0 in (1..hm.width - win - 1).step_by(2) {
            let mut s = 0.0;
            for y in y0..y0 + win {
                for x in x0..x0 + win {
                    s += slope(x, y).unwrap_or(0.0);
                }
            }
            if s > best.0 {
                best = (s, x0, y0);
            }
        }
    }
    let (_, x0, y0) = best;
    let mut heights = Vec::with_capacity(win * win);
    for y in y0..y0 + win {
        for x in x0..x0 + win {
            heights.push(hm.get(x, y).map(|h| h * z_scale));
        }
    }
    let min = heights.iter().flatten().fold(f64::MAX, |a, &b| a.min(b));
    let heights: Vec<Option<f64>> = heights.into_iter().map(|h| h.map(|v| v - min)).collect();
    let out = crate::terrain::Heightmap { width: win, height: win, spacing_m: hm.spacing_m * h_scale, heights_m: heights };
    let mut ss = 0.0f64;
    let mut n = 0.0f64;
    for y in 1..win - 1 {
        for x in 1..win - 1 {
            if let (Some(a), Some(b), Some(c), Some(d)) = (out.get(x + 1, y), out.get(x - 1, y), out.get(x, y + 1), out.get(x, y - 1)) {
                let g = (((a - b) / (2.0 * out.spacing_m)).powi(2) + ((c - d) / (2.0 * out.spacing_m)).powi(2)).sqrt();
                ss += g.atan().to_degrees();
                n += 1.0;
            }
        }
    }
    Ok((surface::HeightSurface::new("hirise-cliff", out), ss / n.max(1.0)))
}

/// Itokawa in metres.
pub fn itokawa(path: &std::path::Path) -> Result<surface::MeshSurface, String> {
    use crate::terrain::obj::{load_obj, ObjOptions};
    let m = load_obj(path, &ObjOptions::KILOMETRES).map_err(|e| e.to_string())?;
    Ok(surface::MeshSurface::new("itokawa", m))
}

/// Four grip points in an "x" of half-diagonal `r` around the surface point under `center` (height field: along
/// z; mesh: along the ray from the body's centre), on the true surface.
pub fn x_start(surface: &dyn Surface, center: P3, body_center: P3, r: f64) -> Option<[P3; 4]> {
    let up = unit(sub(center, body_center));
    let a = unit(if up[2].abs() < 0.9 { cross(up, [0.0, 0.0, 1.0]) } else { cross(up, [1.0, 0.0, 0.0]) });
    let b = cross(up, a);
    let mut out = [[0.0; 3]; 4];
    // the paper's order: (1,1), (1,0), (0,1), (0,0) around the hub at (0.5, 0.5)
    for (k, (sa, sb)) in [(1.0, 1.0), (1.0, -1.0), (-1.0, 1.0), (-1.0, -1.0)].iter().enumerate() {
        let guess = add(center, add(scale(a, sa * r / 2f64.sqrt()), scale(b, sb * r / 2f64.sqrt())));
        let o = add(guess, scale(up, 50.0));
        let t = surface.raycast(o, scale(up, -1.0), 200.0)?;
        out[k] = add(o, scale(up, -t));
    }
    Some(out)
}
