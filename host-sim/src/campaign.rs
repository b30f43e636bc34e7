//! Planning campaigns: Paton et al. section VI-A, Table I — N trials of one tether-aware planning problem with
//! different seeds, every returned path re-validated on the ground-truth world.
//!
//! Per trial: ABIT* ([`firmware::plan::abit`]) over the tether-aware space ([`firmware::plan::tethered`]) on the
//! **planning map**, `planner_iterations` iterations (an iteration is OMPL's: one call of the planner's step). The
//! planning map is the onboard [`Map`] (TSDF + ESDF) filled from the world's true signed distance over a box that
//! holds the planning bounds and the root anchor, as Voxblox's simulation fills its maps from ground-truth geometry
//! (Paton et al. VI-A); `--map truth` plans on the exact world instead. The returned path is then **re-validated
//! on the ground-truth world**: every state re-settled from its ground point and yaw, and every motion re-checked
//! (settling, body collision, anchor prediction from the root, static stability with a margin of at least 0).
//! That re-check uses the planner's own model (settling, Alg. 1, the stability LP) on the exact geometry: it
//! checks the map, not the model. So a returned path is also judged by the **physics judge**
//! ([`crate::physics::path`]): every pose along it, 5 cm / 0.1 rad apart, placed as rigid bodies on the exact
//! terrain with the true tether ([`crate::truth::taut`]) and simulated; it must hold
//! (`CampaignSpec::physics_judge`, default on in the CLI). A path is **found stable** when both the model-on-truth
//! re-check and the physics judge accept it; the table also reports each judge's own count.
//!
//! Outputs: Table I's columns (found stable / found unstable, time and iterations to the first solution, mean and
//! sd) plus batches, edges evaluated and states checked; `results.json` and `results.csv` (one row per trial);
//! `paths.svg` (all paths with their anchors over a height-shaded top view and a side view, like Fig. 9);
//! `timing.json` ([`CampaignTiming`]). Everything measured in wall-clock time (time to the first solution, trial
//! time, map build time, the campaign's wall time, and the thread count it ran on) is in `timing.json` only: the
//! other three files are a pure function of the scenario and the options, the same bytes on any machine, any
//! thread count and any split into shards ([`crate::shard`]; [`merge`] joins the shards' results).

use core::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::Instant;

use firmware::config::map::MapConfig;
use firmware::config::rover::RoverParams;
use firmware::geom::{Real, Vec3};
use firmware::geom::p3::{from_vec3, to_vec3};
use firmware::map::{Block, DistanceField, DistanceQuery, Map};
use firmware::plan::abit::{AbitArena, AbitParams, AbitStar};
use firmware::plan::space::{Budget, GoalState, Planner, ProblemDefinition, Termination};
use firmware::plan::tethered::{
    MotionStats, PlanBounds, RoverState, SettleFailure, TetherMotionValidator, TetherObjective, TetherSpace,
    TetherSpaceParams, TetherValidity,
};
use firmware::tether::{Anchor, AnchorHistory};
use heapless::Vec as HVec;
use rand_core::SeedableRng;
use serde::{Deserialize, Serialize};

use crate::physics::path::{judge_path, PathJudgement, PathPose};
use crate::physics::PhysicsJudge;
use crate::shard::{RunTiming, Shard};
use crate::truth::taut::WrapEdges;
use crate::world::World;

/// Node capacity of a campaign trial's arena (host).
pub const TRIAL_NODES: usize = 4096;
/// Edge-queue capacity of a campaign trial's arena (host).
pub const TRIAL_QUEUE: usize = 32768;
/// Edge-memo capacity of a campaign trial's arena (host).
pub const TRIAL_MEMO: usize = 16384;
/// Longest path written out.
pub const MAX_PATH: usize = 256;
/// Stack of a worker thread (the arena is built on it before it is boxed).
const WORKER_STACK: usize = 256 << 20;

/// The host arena of one trial.
pub type TrialArena = AbitArena<RoverState, AnchorHistory, TRIAL_NODES, TRIAL_QUEUE, TRIAL_MEMO>;

/// Which distance field the planner sees.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum PlanningField {
    /// The onboard map filled from the world's signed distance (default).
    Map,
    /// The exact world.
    Truth,
}

/// One planning problem, repeated over seeds.
pub struct CampaignSpec {
    /// Name (the scenario's).
    pub name: String,
    /// Ground truth.
    pub world: Box<dyn World>,
    /// Root anchor, world frame.
    pub root: [f64; 3],
    /// Start position (axle centre; the state is settled on the surface below it).
    pub start: [f64; 3],
    /// Start yaw, degrees.
    pub start_yaw_deg: f64,
    /// Goal position (axle centre).
    pub goal: [f64; 3],
    /// Goal radius, metres.
    pub goal_tolerance_m: f64,
    /// Where the planner samples.
    pub bounds: PlanBounds,
    /// Voxel edge of the planning map, metres.
    pub voxel_m: f64,
    /// Block capacity of the planning map (the scenario's `map.pool_blocks` when it gives one); `None`: as many
    /// blocks as the planning box needs.
    pub pool_blocks: Option<usize>,
    /// Tether available, metres (the scenario's `tether.length_m`): a found path whose tether, along the anchor
    /// history of any of its states, is longer does not count as found stable.
    pub tether_length_m: f64,
    /// Planner iterations per trial.
    pub iterations: u32,
    /// Trials.
    pub trials: u32,
    /// Seed of the first trial (trial `i` uses `first_seed + i`).
    pub first_seed: u64,
    /// The trials this run does ([`Shard::WHOLE`]: all of them).
    pub shard: Shard,
    /// Worker threads.
    pub threads: usize,
    /// Planning map or exact world.
    pub field: PlanningField,
    /// Space parameters.
    pub params: TetherSpaceParams,
    /// The rover, for planning (plus the map's clearance, [`planning_rover`]) and re-validation.
    pub rover: RoverParams,
    /// Planner parameters.
    pub abit: AbitParams,
    /// Judge every found path with the physics judge too (see the module docs).
    pub physics_judge: bool,
}

/// The ground-truth world as a sized distance field.
pub struct Truth<'a>(pub &'a dyn World);

impl DistanceField for Truth<'_> {
    fn query(&self, p: &Vec3) -> DistanceQuery {
        self.0.query(p)
    }

    fn lipschitz_bound(&self) -> Option<Real> {
        self.0.lipschitz_bound()
    }
}

/// The planning map's storage and how it was built.
pub struct PlanningMap {
    cfg: MapConfig,
    blocks: Vec<Block>,
    index: Vec<u32>,
    used: usize,
    /// Voxels written.
    pub voxels: usize,
    /// Seconds to fill the TSDF and converge the ESDF.
    pub build_s: f64,
    /// ESDF update calls until convergence.
    pub esdf_calls: usize,
}

impl PlanningMap {
    /// Fill a map of voxel `voxel_m` from `world`'s signed distance over the box `[lo, hi]` (exact up to the TSDF
    /// truncation, [`World::query_up_to`]), then converge the ESDF.
    pub fn from_world(world: &dyn World, lo: [f64; 3], hi: [f64; 3], voxel_m: f64) -> Result<PlanningMap, String> {
        Self::from_world_in_pool(world, lo, hi, voxel_m, None)
    }

    /// [`Self::from_world`] in a pool of at most `pool_blocks` blocks: a box that needs more is an error naming
    /// the pool, not a map with holes.
    pub fn from_world_in_pool(
        world: &dyn World,
        lo: [f64; 3],
        hi: [f64; 3],
        voxel_m: f64,
        pool_blocks: Option<usize>,
    ) -> Result<PlanningMap, String> {
        let t0 = Instant::now();
        let cfg = MapConfig::with_voxel_size(voxel_m as Real);
        cfg.validate().map_err(|e| format!("planning map: {}: {}", e.field, e.reason))?;
        let n = |a: usize| ((hi[a] - lo[a]) / voxel_m).ceil() as i64 + 1;
        let (nx, ny, nz) = (n(0), n(1), n(2));
        let e = firmware::config::map::BLOCK_EDGE as i64;
        let blocks_needed = ((nx / e + 2) * (ny / e + 2) * (nz / e + 2)) as usize;
        if blocks_needed > 1 << 20 {
            return Err(format!("planning map: {blocks_needed} blocks needed; use a larger --voxel"));
        }
        let blocks_needed = pool_blocks.map_or(blocks_needed, |p| p.min(blocks_needed));
        let mut blocks = vec![Block::EMPTY; blocks_needed];
        let mut index = vec![0u32; (2 * blocks_needed).next_power_of_two()];
        let (used, voxels, esdf_calls) = {
            let mut map = Map::from_slices(cfg, &mut blocks, &mut index).map_err(|e| format!("planning map: {e:?}"))?;
            let g0 = map.voxel_index(&Vec3::new(lo[0] as Real, lo[1] as Real, lo[2] as Real));
            let mut voxels = 0usize;
            for i in 0..nx as i32 {
                for j in 0..ny as i32 {
                    for k in 0..nz as i32 {
                        let g = [g0[0] + i, g0[1] + j, g0[2] + k];
                        let c = map.voxel_center(g);
                        // The TSDF keeps distances up to the truncation only: nothing farther needs to be exact.
                        let DistanceQuery::Known { distance, .. } = world.query_up_to(&c, cfg.truncation) else {
                            continue;
                        };
                        map.set_voxel(g, distance, 1.0).map_err(|e| match pool_blocks {
                            Some(p) => format!(
                                "planning map: {e:?}: the pool of {p} blocks (map.pool_blocks) cannot hold the \
                                 planning box at {voxel_m} m voxels; raise map.pool_blocks, use a larger voxel or \
                                 a smaller [plan] box"
                            ),
                            None => format!("planning map: {e:?}"),
                        })?;
                        voxels += 1;
                    }
                }
            }
            let mut calls = 0usize;
            loop {
                calls += 1;
                if map.update_esdf().converged {
                    break;
                }
                if calls > 100_000 {
                    return Err("planning map: the ESDF did not converge".into());
                }
            }
            (map.blocks_used(), voxels, calls)
        };
        Ok(PlanningMap { cfg, blocks, index, used, voxels, build_s: t0.elapsed().as_secs_f64(), esdf_calls })
    }

    /// A view of the map.
    pub fn view(&mut self) -> Result<Map<'_>, String> {
        Map::reattach(self.cfg, &mut self.blocks, &mut self.index, self.used).map_err(|e| format!("{e:?}"))
    }

    /// Blocks in use.
    pub fn blocks_used(&self) -> usize {
        self.used
    }

    /// Bytes of block storage in use.
    pub fn bytes_used(&self) -> usize {
        self.used * core::mem::size_of::<Block>()
    }
}

/// A state of a returned path, for the outputs.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct PathState {
    /// Axle centre.
    pub axle: [f64; 3],
    /// Ground point it was settled from.
    pub ground: [f64; 3],
    /// Settler yaw, radians.
    pub theta: f64,
    /// Anchor history after reaching the state (root first).
    pub anchors: Vec<[f64; 3]>,
    /// World heading of the settled rover's x axis, radians.
    pub heading: f64,
}

/// Ground-truth re-validation of a path.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Revalidation {
    /// Every state settles and every motion is valid and stable on the true terrain.
    pub stable: bool,
    /// The first failure: which motion (0 = the start state itself) and why.
    pub failure: Option<String>,
    /// Anchors of the true-terrain history at the path's end (root first).
    pub final_anchors: Vec<[f64; 3]>,
}

/// One trial. The wall-clock fields are not serialised into `results.json` (see [`CampaignTiming`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct TrialResult {
    /// Trial index.
    pub trial: u32,
    /// Planner seed.
    pub seed: u64,
    /// An exact solution was found.
    pub found: bool,
    /// Iteration of the first solution.
    pub first_iteration: Option<u32>,
    /// Seconds to the first solution (wall clock; in `timing.json`, not `results.json`).
    #[serde(skip)]
    pub first_time_s: Option<f64>,
    /// Cost of the best path after the budget.
    pub final_cost: Option<f64>,
    /// Iterations run.
    pub iterations: u32,
    /// Batches.
    pub batches: u32,
    /// Edges (motions) evaluated.
    pub edges_evaluated: u32,
    /// States checked.
    pub states_checked: u32,
    /// Seconds of the whole trial (wall clock; in `timing.json`, not `results.json`).
    #[serde(skip)]
    pub total_time_s: f64,
    /// Why the planner stopped.
    pub termination: String,
    /// Work of the traversability checks.
    pub settles: u32,
    /// Stability LPs solved.
    pub stability_checks: u32,
    /// Anchor predictions.
    pub anchor_predictions: u32,
    /// Motions invalid because unstable.
    pub motions_unstable: u32,
    /// Samples drawn near a catch boundary (the edge of a tether shadow) and added to the graph's draws.
    pub catch_samples: u32,
    /// Surface points probed for the tether shadow by the catch-boundary sampler.
    pub catch_probes: u32,
    /// Largest node-arena use.
    pub arena_nodes: usize,
    /// Largest edge-queue use.
    pub arena_queue: usize,
    /// The best path (start first).
    pub path: Vec<PathState>,
    /// Re-validation on the ground truth with the planner's own model (when found).
    pub revalidation: Option<Revalidation>,
    /// The physics judge's verdict (when found and judged).
    pub physics: Option<PathJudgement>,
}

impl TrialResult {
    /// Found and stable on the true terrain: the model-on-truth re-check and (when it ran) the physics judge
    /// both accept it.
    pub fn found_stable(&self) -> bool {
        self.model_stable() && self.physics.as_ref().is_none_or(|p| p.stable)
    }
    /// Found and accepted by the model-on-truth re-check (the planner's own model on the exact world).
    pub fn model_stable(&self) -> bool {
        self.found && self.revalidation.as_ref().is_some_and(|r| r.stable)
    }
    /// Found and judged unstable by the physics judge.
    pub fn physics_unstable(&self) -> bool {
        self.found && self.physics.as_ref().is_some_and(|p| !p.stable)
    }
    /// Found but not stable on the true terrain.
    pub fn found_unstable(&self) -> bool {
        self.found && !self.found_stable()
    }
}

fn anchors_of(h: &AnchorHistory) -> Vec<[f64; 3]> {
    h.as_slice().iter().map(|a| from_vec3(&a.point)).collect()
}

/// The rover model the planner uses: Axel, with the body clearance grown by one voxel when planning on the map
/// (the map's surfaces are off by up to about half a voxel, more at edges such as the pole; re-validation on the
/// ground truth uses Axel's own clearance).
pub fn planning_rover(spec: &CampaignSpec) -> RoverParams {
    let mut r = spec.rover;
    if spec.field == PlanningField::Map {
        r.body_clearance_m += spec.voxel_m as Real;
    }
    r
}

/// The tethered space's parameters the planner uses: the spec's, with a surface uncertainty of half a voxel when
/// planning on the map (re-validation on the ground truth uses the spec's own, exact-field parameters).
pub fn planning_params(spec: &CampaignSpec) -> TetherSpaceParams {
    let mut p = spec.params;
    if spec.field == PlanningField::Map {
        p.surface_uncertainty_m = p.surface_uncertainty_m.max(0.5 * spec.voxel_m as Real);
    }
    p
}

/// Start and goal states of a spec on a field.
pub fn endpoints<D: DistanceField>(space: &TetherSpace<'_, D>, spec: &CampaignSpec) -> Result<(RoverState, RoverState), String> {
    let yaw = spec.start_yaw_deg.to_radians() as Real;
    let start = space.settle_state(spec.start[0] as Real, spec.start[1] as Real, yaw).map_err(|e| {
        let hint = if spec.field == PlanningField::Map && e == SettleFailure::Collision {
            format!(
                " (on the onboard map Axel's body clearance grows by one voxel, {} m: try a finer --voxel, e.g. \
                 0.05, or --field truth)",
                spec.voxel_m
            )
        } else {
            String::new()
        };
        format!("the start {:?} does not settle: {e:?}{hint}", spec.start)
    })?;
    let goal = space.goal_state(to_vec3(spec.goal), 0.0).map_err(|e| format!("the goal {:?} does not settle: {e:?}", spec.goal))?;
    Ok((start, goal))
}

/// Re-validate a path (states as planned) on the ground truth.
pub fn revalidate(world: &dyn World, spec: &CampaignSpec, path: &[RoverState]) -> Revalidation {
    let truth = Truth(world);
    let mut params = spec.params;
    params.min_stability_margin = params.min_stability_margin.min(0.0);
    let fail = |failure: String, h: &AnchorHistory| Revalidation { stable: false, failure: Some(failure), final_anchors: anchors_of(h) };
    let root = AnchorHistory::new(Anchor::root(to_vec3(spec.root)));
    let space = match TetherSpace::new(&truth, spec.bounds, spec.rover, params) {
        Ok(s) => s,
        Err((f, r)) => return fail(format!("{f}: {r}"), &root),
    };
    let mut states = Vec::with_capacity(path.len());
    for (i, s) in path.iter().enumerate() {
        if s.off_map {
            states.push(*s);
            continue;
        }
        match space.settle_state(s.ground.x, s.ground.y, s.theta) {
            Ok(t) => states.push(t),
            Err(e) => return fail(format!("state {i} does not settle on the true terrain: {e:?}"), &root),
        }
    }
    let Some(first) = states.first() else { return fail("empty path".into(), &root) };
    if let Err(e) = space.stable_with(&first.settled, &root) {
        return fail(format!("start: {e:?}"), &root);
    }
    let mut hist = root;
    for (i, w) in states.windows(2).enumerate() {
        let [a, b] = [w[0], w[1]];
        match space.check(&a, &hist, &b) {
            Ok(h) => hist = h,
            Err(e) => return fail(format!("motion {} ({:.2}, {:.2}) -> ({:.2}, {:.2}): {e:?}", i + 1, a.ground.x, a.ground.y, b.ground.x, b.ground.y), &hist),
        }
    }
    Revalidation { stable: true, failure: None, final_anchors: anchors_of(&hist) }
}

/// Run one trial on `field` with `arena`.
pub fn run_trial<D: DistanceField>(
    field: &D,
    spec: &CampaignSpec,
    trial: u32,
    arena: &mut TrialArena,
) -> Result<TrialResult, String> {
    let seed = spec.first_seed + u64::from(trial);
    let mut space = TetherSpace::new(field, spec.bounds, planning_rover(spec), planning_params(spec)).map_err(|(f, r)| format!("{f}: {r}"))?;
    let (start, goal) = endpoints(&space, spec)?;
    let pdef = ProblemDefinition {
        start,
        start_attachment: AnchorHistory::new(Anchor::root(to_vec3(spec.root))),
        goal: GoalState { state: goal, tolerance: spec.goal_tolerance_m },
        objective: TetherObjective,
    };
    let mut validity = TetherValidity;
    let mut motion = TetherMotionValidator;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(seed);
    let t0 = Instant::now();
    let mut planner = AbitStar::new(arena, &mut space, &mut validity, &mut motion, &pdef, &mut rng, spec.abit);
    let mut first_time = None;
    let report = planner.solve_until(&Budget::iterations(spec.iterations), |c| {
        if first_time.is_none() && c.first_solution_iteration != 0 {
            first_time = Some(t0.elapsed());
        }
        false
    });
    let total = t0.elapsed();
    let c = report.counters;
    if first_time.is_none() && c.first_solution_iteration != 0 {
        first_time = Some(total);
    }
    let mut out: HVec<(RoverState, AnchorHistory), MAX_PATH> = HVec::new();
    let found = report.status.is_exact() && planner.write_path(&mut out).is_ok();
    let final_cost = found.then(|| planner.best_cost());
    let arena_use = planner.arena_use();
    let stats: MotionStats = space.stats();
    let states: Vec<RoverState> = out.iter().map(|(s, _)| *s).collect();
    let path: Vec<PathState> = out
        .iter()
        .map(|(s, h)| PathState {
            axle: from_vec3(&s.axle()),
            ground: from_vec3(&s.ground),
            theta: f64::from(s.theta),
            anchors: anchors_of(h),
            heading: f64::from(s.heading()),
        })
        .collect();
    let revalidation = found.then(|| {
        let mut r = revalidate(spec.world.as_ref(), spec, &states);
        if let Some(why) = tether_too_short(spec, &path) {
            if r.stable {
                r.stable = false;
                r.failure = Some(why);
            }
        }
        r
    });
    Ok(TrialResult {
        trial,
        seed,
        found,
        first_iteration: (c.first_solution_iteration != 0).then_some(c.first_solution_iteration),
        first_time_s: first_time.map(|d| d.as_secs_f64()),
        final_cost,
        iterations: c.iterations,
        batches: c.batches,
        edges_evaluated: c.edges_evaluated,
        states_checked: c.states_checked,
        total_time_s: total.as_secs_f64(),
        termination: match report.termination {
            Termination::BudgetExhausted(k) => format!("budget {k:?}"),
            t => format!("{t:?}"),
        },
        settles: stats.settles,
        stability_checks: stats.stability_checks,
        anchor_predictions: stats.anchor_predictions,
        motions_unstable: stats.fail_unstable,
        catch_samples: c.catch_samples,
        catch_probes: stats.catch_probes,
        arena_nodes: arena_use.nodes,
        arena_queue: arena_use.queue,
        path,
        revalidation,
        physics: None,
    })
}

/// The longest tether a path needs (root, then the anchors of each state's history, then its axle centre),
/// against `spec.tether_length_m`: the reason, when some state needs more tether than there is.
fn tether_too_short(spec: &CampaignSpec, path: &[PathState]) -> Option<String> {
    let dist = |a: &[f64; 3], b: &[f64; 3]| ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt();
    let (k, need) = path
        .iter()
        .map(|p| {
            let mut pts: Vec<&[f64; 3]> = p.anchors.iter().collect();
            pts.push(&p.axle);
            pts.windows(2).map(|w| dist(w[0], w[1])).sum::<f64>()
        })
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    (need > spec.tether_length_m).then(|| {
        format!("state {k} needs {need:.2} m of tether along its anchors; the tether is {:.2} m (tether.length_m)", spec.tether_length_m)
    })
}

/// The physics judge of a campaign: the judge and the world's wrap edges (built once, shared by the workers).
pub struct CampaignJudge {
    /// The rigid-body judge.
    pub judge: PhysicsJudge,
    /// The true tether's wrap edges.
    pub edges: WrapEdges,
}

impl CampaignJudge {
    /// The judge of `spec`'s world; the wrap edges of height grids and meshes within the planning bounds and the
    /// root (2 m margin).
    pub fn new(spec: &CampaignSpec) -> Result<CampaignJudge, String> {
        let judge = PhysicsJudge::new(spec.world.as_ref(), spec.rover).map_err(|e| format!("physics judge: {e}"))?;
        let b = spec.bounds;
        let lo = core::array::from_fn(|k| f64::from(b.min[k]).min(spec.root[k]) - 2.0);
        let hi = core::array::from_fn(|k| f64::from(b.max[k]).max(spec.root[k]) + 2.0);
        let edges = WrapEdges::new(&spec.world.exact_geometry(), (lo, hi)).map_err(|e| format!("true tether: {e}"))?;
        Ok(CampaignJudge { judge, edges })
    }

    /// Judge a trial's path (when found).
    pub fn judge_trial(&self, spec: &CampaignSpec, t: &mut TrialResult) {
        if !t.found {
            return;
        }
        let path: Vec<PathPose> = t.path.iter().map(|p| PathPose { axle: p.axle, heading: p.heading }).collect();
        t.physics = Some(judge_path(&self.judge, &self.edges, spec.root, &path));
    }
}

/// The outcome of a campaign (or of one shard of it). The wall-clock fields and the thread count are not
/// serialised into `results.json` (see [`CampaignTiming`]).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct CampaignResult {
    /// Scenario name.
    pub name: String,
    /// The part of the campaign these trials are (absent for the whole campaign, and so in a merge's result).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shard: Option<Shard>,
    /// Field planned on.
    pub field: PlanningField,
    /// Planning-map voxel, metres.
    pub voxel_m: f64,
    /// Planning-map blocks.
    pub map_blocks: usize,
    /// Seconds to build the planning map (wall clock; in `timing.json`).
    #[serde(skip)]
    pub map_build_s: f64,
    /// Iterations per trial.
    pub iterations: u32,
    /// Trials, in trial order.
    pub trials: Vec<TrialResult>,
    /// Wall-clock seconds of the whole campaign (in `timing.json`).
    #[serde(skip)]
    pub wall_s: f64,
    /// Worker threads (in `timing.json`).
    #[serde(skip)]
    pub threads: usize,
    /// The rover's wheel-terrain friction coefficient.
    pub wheel_mu: f32,
    /// Whether dead edges left the queue without an iteration (`AbitParams::drop_dead_edges`).
    pub drop_dead_edges: bool,
}

/// Mean and sample standard deviation.
pub fn mean_sd(xs: &[f64]) -> Option<(f64, f64)> {
    if xs.is_empty() {
        return None;
    }
    let n = xs.len() as f64;
    let m = xs.iter().sum::<f64>() / n;
    let var = if xs.len() > 1 { xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0) } else { 0.0 };
    Some((m, var.sqrt()))
}

impl CampaignResult {
    /// Trials found and stable on the true terrain.
    pub fn found_stable(&self) -> usize {
        self.trials.iter().filter(|t| t.found_stable()).count()
    }
    /// Trials found but unstable on the true terrain.
    pub fn found_unstable(&self) -> usize {
        self.trials.iter().filter(|t| t.found_unstable()).count()
    }
    /// Found trials the model-on-truth re-check rejects.
    pub fn model_unstable(&self) -> usize {
        self.trials.iter().filter(|t| t.found && !t.model_stable()).count()
    }
    /// Found trials the physics judge rejects.
    pub fn physics_unstable(&self) -> usize {
        self.trials.iter().filter(|t| t.physics_unstable()).count()
    }
    /// Found trials the physics judge ran on.
    pub fn physics_judged(&self) -> usize {
        self.trials.iter().filter(|t| t.physics.is_some()).count()
    }
    /// Table I and the work columns, as text.
    pub fn table(&self) -> String {
        let f = |xs: Vec<f64>, prec: usize| match mean_sd(&xs) {
            Some((m, s)) => format!("{m:.prec$} ({s:.prec$})"),
            None => "-".into(),
        };
        let found: Vec<&TrialResult> = self.trials.iter().filter(|t| t.found).collect();
        let all = &self.trials;
        let mut s = String::new();
        s += &format!(
            "campaign {}: {} trials x {} iterations, planning on {}, wheel mu {:.2}, {} threads, {:.1} s wall\n",
            self.name,
            all.len(),
            self.iterations,
            match self.field {
                PlanningField::Map => format!("the onboard map ({:.2} m voxels, {} blocks, built in {:.1} s)", self.voxel_m, self.map_blocks, self.map_build_s),
                PlanningField::Truth => "the exact world".to_string(),
            },
            self.wheel_mu,
            self.threads,
            self.wall_s
        );
        if self.drop_dead_edges {
            s += "iterations with BIT*'s edge-queue pruning (--drop-dead-edges): not OMPL's (or the paper's) count\n";
        }
        s += "| found stable | found unstable | not found | time to first solution [s] mean (sd) | iterations to first solution mean (sd) |\n|---|---|---|---|---|\n";
        s += &format!(
            "| {} | {} | {} | {} | {} |\n",
            self.found_stable(),
            self.found_unstable(),
            all.len() - found.len(),
            f(found.iter().filter_map(|t| t.first_time_s).collect(), 3),
            f(found.iter().filter_map(|t| t.first_iteration.map(f64::from)).collect(), 1),
        );
        s += "\n| per trial, mean (sd) | iterations | batches | edges evaluated | states checked | settles | stability LPs | anchor predictions | trial time [s] | final cost (found) |\n|---|---|---|---|---|---|---|---|---|---|\n";
        s += &format!(
            "| all trials | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            f(all.iter().map(|t| f64::from(t.iterations)).collect(), 1),
            f(all.iter().map(|t| f64::from(t.batches)).collect(), 1),
            f(all.iter().map(|t| f64::from(t.edges_evaluated)).collect(), 1),
            f(all.iter().map(|t| f64::from(t.states_checked)).collect(), 1),
            f(all.iter().map(|t| f64::from(t.settles)).collect(), 0),
            f(all.iter().map(|t| f64::from(t.stability_checks)).collect(), 0),
            f(all.iter().map(|t| f64::from(t.anchor_predictions)).collect(), 0),
            f(all.iter().map(|t| t.total_time_s).collect(), 3),
            f(found.iter().filter_map(|t| t.final_cost).collect(), 3),
        );
        s += &format!(
            "\nunstable by judge: model-on-truth (the planner's own model on the exact world) {}; physics judge (rigid bodies, true tether) {} of {} judged\n",
            self.model_unstable(),
            self.physics_unstable(),
            self.physics_judged()
        );
        for t in all.iter().filter(|t| t.physics_unstable()) {
            if let Some(p) = &t.physics {
                s += &format!("physics judge: trial {} seed {}: {}\n", t.trial, t.seed, p.failure.clone().unwrap_or_default());
            }
        }
        let nodes = all.iter().map(|t| t.arena_nodes).max().unwrap_or(0);
        let queue = all.iter().map(|t| t.arena_queue).max().unwrap_or(0);
        s += &format!("\narena high-water over all trials: {nodes} nodes of {TRIAL_NODES}, {queue} queued edges of {TRIAL_QUEUE}\n");
        let with_anchor = found.iter().filter(|t| t.path.last().is_some_and(|p| p.anchors.len() > 1)).count();
        s += &format!("found paths whose final anchor history holds an intermediate anchor: {with_anchor} of {}\n", found.len());
        for t in all.iter().filter(|t| t.found && !t.model_stable()) {
            if let Some(r) = &t.revalidation {
                s += &format!("unstable on the true terrain: trial {} seed {}: {}\n", t.trial, t.seed, r.failure.clone().unwrap_or_default());
            }
        }
        s
    }

    /// One CSV row per trial (no wall-clock columns: those are in [`CampaignTiming`]).
    pub fn csv(&self) -> String {
        let mut s = String::from("trial,seed,found,stable_on_truth,first_iteration,final_cost,iterations,batches,edges_evaluated,states_checked,settles,stability_checks,anchor_predictions,path_states,final_anchors,termination,model_stable,physics_stable\n");
        let o = |v: Option<String>| v.unwrap_or_default();
        for t in &self.trials {
            s += &format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                t.trial,
                t.seed,
                t.found,
                t.found_stable(),
                o(t.first_iteration.map(|v| v.to_string())),
                o(t.final_cost.map(|v| format!("{v:.6}"))),
                t.iterations,
                t.batches,
                t.edges_evaluated,
                t.states_checked,
                t.settles,
                t.stability_checks,
                t.anchor_predictions,
                t.path.len(),
                t.path.last().map_or(0, |p| p.anchors.len()),
                t.termination,
                t.model_stable(),
                o(t.physics.as_ref().map(|p| p.stable.to_string())),
            );
        }
        s
    }
}

/// The wall-clock side of a campaign (`timing.json`): what is measured, not computed, so it differs between any
/// two runs and is kept out of `results.json` and `results.csv`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignTiming {
    /// One entry per run: the unsharded run, or each shard of a merge (in shard order).
    pub runs: Vec<RunTiming>,
    /// Per trial, in trial order.
    pub trials: Vec<TrialTiming>,
}

/// The wall-clock figures of one trial.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrialTiming {
    /// Trial index.
    pub trial: u32,
    /// Seconds to the first solution.
    pub first_time_s: Option<f64>,
    /// Seconds of the whole trial.
    pub total_time_s: f64,
}

impl CampaignResult {
    /// This run's timing.
    pub fn timing(&self) -> CampaignTiming {
        CampaignTiming {
            runs: vec![RunTiming { shard: self.shard, threads: self.threads, wall_s: self.wall_s, map_build_s: Some(self.map_build_s) }],
            trials: self
                .trials
                .iter()
                .map(|t| TrialTiming { trial: t.trial, first_time_s: t.first_time_s, total_time_s: t.total_time_s })
                .collect(),
        }
    }

    /// Puts `timing`'s figures back into the result (after reading `results.json`, which has none); the run's
    /// figures are the largest over `timing.runs` (the shards ran side by side).
    pub fn apply_timing(&mut self, timing: &CampaignTiming) {
        for t in &mut self.trials {
            if let Some(m) = timing.trials.iter().find(|m| m.trial == t.trial) {
                t.first_time_s = m.first_time_s;
                t.total_time_s = m.total_time_s;
            }
        }
        let max = |f: &dyn Fn(&RunTiming) -> f64| timing.runs.iter().map(f).fold(0.0, f64::max);
        self.wall_s = max(&|r| r.wall_s);
        self.map_build_s = max(&|r| r.map_build_s.unwrap_or(0.0));
        self.threads = timing.runs.iter().map(|r| r.threads).max().unwrap_or(0);
    }
}

/// Joins the results of the N shards of one campaign, given in shard order and already checked to be one
/// complete set ([`crate::shard::check_set`]): the trials in trial order, the shard mark removed. The result
/// serialises to the bytes of the unsharded run's `results.json`. Refuses shards whose header fields differ (the
/// same options on different code) or whose trials are not exactly the shard's (a file edited by hand).
pub fn merge(shards: Vec<(String, CampaignResult)>, trials: u32, first_seed: u64) -> Result<CampaignResult, String> {
    let header = |r: &CampaignResult| {
        serde_json::to_value(CampaignResult { trials: Vec::new(), shard: None, ..r.clone() }).unwrap_or_default()
    };
    let mut it = shards.into_iter();
    let Some((p0, mut merged)) = it.next() else { return Err("no shard files given".into()) };
    let h0 = header(&merged);
    let mut all = core::mem::take(&mut merged.trials);
    let mut parts = vec![(p0.clone(), merged.shard, all.len())];
    for (p, r) in it {
        if header(&r) != h0 {
            return Err(format!(
                "{p0} and {p} record the same options but different campaign headers ({} vs {}): were they run by different builds of tetherbot?",
                h0, header(&r)
            ));
        }
        parts.push((p, r.shard, r.trials.len()));
        all.extend(r.trials);
    }
    let mut at = 0;
    for (p, shard, n) in &parts {
        let shard = shard.unwrap_or(Shard::WHOLE);
        let want = shard.indices(trials);
        let mine = &all[at..at + n];
        let got: Vec<u32> = mine.iter().map(|t| t.trial).collect();
        if let Some(t) = mine.iter().find(|t| Some(t.seed) != first_seed.checked_add(u64::from(t.trial))) {
            return Err(format!("{p}: trial {} has seed {}, not the campaign's {first_seed} + {} (an edited file)", t.trial, t.seed, t.trial));
        }
        if got != want {
            return Err(format!(
                "{p}: shard {shard} of {trials} trials should hold trials {want:?}, it holds {got:?} (an incomplete or edited file)"
            ));
        }
        at += n;
    }
    all.sort_by_key(|t| t.trial);
    merged.trials = all;
    merged.shard = None;
    Ok(merged)
}

/// Run the campaign (the trials of `spec.shard`): build the planning field once, then the trials on
/// `spec.threads` workers. `progress` is called after every finished trial with (done, total of this shard).
pub fn run(spec: &CampaignSpec, progress: &(dyn Fn(usize, usize) + Sync)) -> Result<CampaignResult, String> {
    let t0 = Instant::now();
    if spec.first_seed.checked_add(u64::from(spec.trials.saturating_sub(1))).is_none() {
        return Err(format!("seed {} with {} trials: the trial seeds would pass u64::MAX", spec.first_seed, spec.trials));
    }
    spec.shard.check_fits(spec.trials, "trials")?;
    let b = spec.bounds;
    let lo = [
        f64::from(b.min[0]).min(spec.root[0] - 1.0),
        f64::from(b.min[1]).min(spec.root[1] - 1.0),
        f64::from(b.min[2]).min(spec.root[2] - 1.0),
    ];
    let hi = [
        f64::from(b.max[0]).max(spec.root[0] + 1.0),
        f64::from(b.max[1]).max(spec.root[1] + 1.0),
        f64::from(b.max[2]).max(spec.root[2] + 1.0),
    ];
    let mut storage = match spec.field {
        PlanningField::Map => Some(PlanningMap::from_world_in_pool(spec.world.as_ref(), lo, hi, spec.voxel_m, spec.pool_blocks)?),
        PlanningField::Truth => None,
    };
    let (map_blocks, map_build_s) = storage.as_ref().map_or((0, 0.0), |m| (m.blocks_used(), m.build_s));
    let trials = match storage.as_mut() {
        Some(m) => {
            let view = m.view()?;
            run_trials(&view, spec, progress)?
        }
        None => run_trials(&Truth(spec.world.as_ref()), spec, progress)?,
    };
    Ok(CampaignResult {
        name: spec.name.clone(),
        shard: (!spec.shard.is_whole()).then_some(spec.shard),
        field: spec.field,
        voxel_m: spec.voxel_m,
        map_blocks,
        map_build_s,
        iterations: spec.iterations,
        trials,
        wall_s: t0.elapsed().as_secs_f64(),
        threads: spec.threads,
        wheel_mu: spec.rover.wheel_mu,
        drop_dead_edges: spec.abit.drop_dead_edges,
    })
}

fn run_trials<D: DistanceField + Sync>(
    field: &D,
    spec: &CampaignSpec,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<Vec<TrialResult>, String> {
    let judge = if spec.physics_judge { Some(CampaignJudge::new(spec)?) } else { None };
    let judge = judge.as_ref();
    let indices = spec.shard.indices(spec.trials);
    let total = indices.len();
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let results: Mutex<Vec<Result<TrialResult, String>>> = Mutex::new(Vec::new());
    std::thread::scope(|s| {
        for _ in 0..spec.threads.max(1) {
            let worker = std::thread::Builder::new().stack_size(WORKER_STACK).spawn_scoped(s, || {
                let mut arena: Box<TrialArena> = Box::default();
                while let Some(&i) = indices.get(next.fetch_add(1, Ordering::SeqCst)) {
                    let mut r = run_trial(field, spec, i, &mut arena);
                    if let (Ok(t), Some(j)) = (r.as_mut(), judge) {
                        j.judge_trial(spec, t);
                    }
                    if let Ok(mut v) = results.lock() {
                        v.push(r);
                    }
                    progress(done.fetch_add(1, Ordering::SeqCst) + 1, total);
                }
            });
            if let Err(e) = worker {
                if let Ok(mut v) = results.lock() {
                    v.push(Err(format!("cannot start a worker thread: {e}")));
                }
            }
        }
    });
    let mut out = Vec::with_capacity(total);
    for r in results.into_inner().map_err(|_| "a worker panicked".to_string())? {
        out.push(r?);
    }
    if out.len() != total {
        return Err(format!("{} of {total} trials finished (a worker died)", out.len()));
    }
    out.sort_by_key(|t| t.trial);
    Ok(out)
}

/// A picture of all paths (like Paton et al. Fig. 9): a height-shaded top view and a side view (x-z), paths
/// stable on the true terrain in green, unstable in red, intermediate anchors as dots, the root anchor as a star.
pub fn paths_svg(world: &dyn World, spec: &CampaignSpec, result: &CampaignResult) -> String {
    let b = spec.bounds;
    let (x0, x1) = (f64::from(b.min[0]).min(spec.root[0]) - 0.5, f64::from(b.max[0]).max(spec.root[0]) + 0.5);
    let (y0, y1) = (f64::from(b.min[1]).min(spec.root[1]) - 0.5, f64::from(b.max[1]).max(spec.root[1]) + 0.5);
    let (z0, z1) = (f64::from(b.min[2]), f64::from(b.max[2]).max(spec.root[2] + 0.5));
    let scale = 700.0 / (x1 - x0);
    let top_h = (y1 - y0) * scale;
    let side_h = (z1 - z0) * scale;
    let w = 720.0;
    let h = top_h + side_h + 80.0;
    let tx = |x: f64| 10.0 + (x - x0) * scale;
    let ty = |y: f64| 30.0 + (y1 - y) * scale;
    let sz = |z: f64| 60.0 + top_h + (z1 - z) * scale;
    let mut s = format!("<svg xmlns='http://www.w3.org/2000/svg' width='{w:.0}' height='{h:.0}' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n");
    s += &format!(
        "<text x='10' y='18'>{}: {} trials, {} found stable (green), {} found unstable (red); top view and side view (x-z)</text>\n",
        result.name,
        result.trials.len(),
        result.found_stable(),
        result.found_unstable()
    );
    // height shading of the top view
    let cells = 70usize;
    let (dx, dy) = ((x1 - x0) / cells as f64, (y1 - y0) / cells as f64);
    let mut heights = Vec::new();
    for i in 0..cells {
        for j in 0..cells {
            let (x, y) = (x0 + (i as f64 + 0.5) * dx, y0 + (j as f64 + 0.5) * dy);
            if let Some(hz) = world.height_at(x as Real, y as Real) {
                heights.push((x, y, f64::from(hz)));
            }
        }
    }
    let (hmin, hmax) = heights.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), h| (a.min(h.2), b.max(h.2)));
    for (x, y, hz) in &heights {
        let g = if hmax > hmin { 235.0 - 120.0 * (hz - hmin) / (hmax - hmin) } else { 220.0 };
        s += &format!(
            "<rect x='{:.1}' y='{:.1}' width='{:.1}' height='{:.1}' fill='rgb({g:.0},{g:.0},{g:.0})'/>\n",
            tx(x - dx / 2.0),
            ty(y + dy / 2.0),
            dx * scale + 0.5,
            dy * scale + 0.5
        );
    }
    // side-view terrain profile along y = start y
    let mut prof = String::new();
    for i in 0..=200 {
        let x = x0 + (x1 - x0) * i as f64 / 200.0;
        if let Some(hz) = world.height_at(x as Real, spec.start[1] as Real) {
            prof += &format!("{:.1},{:.1} ", tx(x), sz(f64::from(hz)));
        }
    }
    s += &format!("<polyline points='{prof}' fill='none' stroke='#888' stroke-width='2'/>\n");
    let star = |x: f64, y: f64| format!("<circle cx='{x:.1}' cy='{y:.1}' r='6' fill='gold' stroke='black'/>\n");
    s += &star(tx(spec.root[0]), ty(spec.root[1]));
    s += &star(tx(spec.root[0]), sz(spec.root[2]));
    for t in result.trials.iter().filter(|t| t.found) {
        let colour = if t.found_stable() { "rgba(0,150,0,0.45)" } else { "rgba(220,0,0,0.7)" };
        let top: String = t.path.iter().map(|p| format!("{:.1},{:.1} ", tx(p.axle[0]), ty(p.axle[1]))).collect();
        let side: String = t.path.iter().map(|p| format!("{:.1},{:.1} ", tx(p.axle[0]), sz(p.axle[2]))).collect();
        s += &format!("<polyline points='{top}' fill='none' stroke='{colour}' stroke-width='1.5'/>\n");
        s += &format!("<polyline points='{side}' fill='none' stroke='{colour}' stroke-width='1.5'/>\n");
        if let Some(last) = t.path.last() {
            for a in last.anchors.iter().skip(1) {
                s += &format!("<circle cx='{:.1}' cy='{:.1}' r='2.5' fill='blue'/>\n", tx(a[0]), ty(a[1]));
                s += &format!("<circle cx='{:.1}' cy='{:.1}' r='2.5' fill='blue'/>\n", tx(a[0]), sz(a[2]));
            }
        }
    }
    s += &format!("<circle cx='{:.1}' cy='{:.1}' r='5' fill='black'/>\n", tx(spec.start[0]), ty(spec.start[1]));
    s += &format!("<circle cx='{:.1}' cy='{:.1}' r='5' fill='none' stroke='black' stroke-width='2'/>\n", tx(spec.goal[0]), ty(spec.goal[1]));
    s += "</svg>\n";
    s
}
