//! Tethered climbing teams (Morad, Kalita, Thangavelautham, "Planning and Navigation of Climbing Robots in
//! Low-Gravity Environments", IEEE Aerospace 2018, sections III-VI; scenario D of `SCENARIOS.md`).
//!
//! Four SphereX robots grip a steep surface, tethered to a hub in an "x"; one hops while three hold. Each robot,
//! independently and without communication, runs the local pipeline of Fig. 7 before each hop:
//!
//! 1. [`scene`]: range points -> scene frame, normals from k nearest neighbours (bounded bucket kNN), a surface
//!    (a bounded membrane reconstruction on a height/normal grid, standing in for screened Poisson; see there why).
//! 2. [`score`]: anchor-point score r per surface vertex (relative height, flatness; lower is safer).
//! 3. [`cull`]: keep the best fraction (15 %).
//! 4. [`graph`]: directed hop graph, edge weights d_ab and L'_ab = L_b + r_b.
//! 5. [`leg_astar`]: bounded-leg A* (hop <= h_max, |c_m + h| <= r_max).
//!
//! [`LocalPlanner`] chains 1-5 over one fixed arena. [`formation`] holds the team: climbing order, hub motion,
//! node loss. [`dstar_lite`] is the global planner over a grid of scenes (a local failure between two cells
//! becomes a wall; D* Lite replans incrementally — the crevasse of Fig. 12). [`mission`] is the hub's flight
//! computer running all of it as one step-wise state machine (scan / hop / hub commands in, reports out).
//!
//! Parameters: [`TeamParams`] (every field documented with its default); capacities in [`crate::config::team`].
//! Every loop is bounded by a capacity or a budget; a full arena or exhausted budget is a typed outcome.

pub mod leg_astar;
pub mod cull;
pub mod dstar_lite;
pub mod formation;
pub mod graph;
pub mod mission;
pub mod scene;
pub mod score;

use crate::config::team::{TeamParams, PATH_MAX_HOPS, SURFACE_MAX_VERTICES};
use crate::geom::{Real, Vec3};
use leg_astar::{bounded_leg_astar, AStarArena, AStarStatus};
use cull::{cull, CullOutcome};
use graph::{AnchorVertex, GraphOutcome, HopGraph};
use heapless::Vec as HVec;
use scene::{Scene, SceneError};

/// Result of one local plan.
#[derive(Debug, Clone, PartialEq)]
pub struct LocalPlan {
    /// A* status.
    pub status: AStarStatus,
    /// Anchor points of the path, the robot's current position first.
    pub hops: HVec<Vec3, PATH_MAX_HOPS>,
    /// Culling outcome.
    pub cull: CullOutcome,
    /// Graph outcome.
    pub graph: GraphOutcome,
    /// Path loss (sum of L').
    pub loss: Real,
    /// A* expansions.
    pub expansions: u32,
}

/// The whole local pipeline over one fixed arena (~0.6 MiB with the defaults; a board puts it in a `static`, the
/// host in a `Box`). `P` points, `V` graph vertices, `E` graph edges.
pub struct LocalPlanner<const P: usize, const V: usize, const E: usize> {
    /// The scene (points, normals, surface).
    pub scene: Scene<P>,
    /// Anchor scores per surface vertex.
    pub scores: [Real; SURFACE_MAX_VERTICES],
    order: [u16; SURFACE_MAX_VERTICES],
    /// The hop graph of the last plan (vertex 0 is the robot).
    pub graph: HopGraph<V, E>,
    astar: AStarArena<V>,
}

impl<const P: usize, const V: usize, const E: usize> LocalPlanner<P, V, E> {
    /// An empty planner.
    pub const fn new() -> Self {
        Self {
            scene: Scene::new(),
            scores: [0.0; SURFACE_MAX_VERTICES],
            order: [0; SURFACE_MAX_VERTICES],
            graph: HopGraph::new(),
            astar: AStarArena::new(),
        }
    }

    /// Plan robot m's hops: scan `points`, robot gripping at `robot` with outward direction `up` (from its
    /// attitude), leg `c_m` (hub to robot, from the draw-wire encoder), towards `goal` (region radius `goal_tol`).
    #[allow(clippy::too_many_arguments)]
    pub fn plan(
        &mut self,
        points: &[Vec3],
        up: &Vec3,
        robot: &Vec3,
        c_m: &Vec3,
        goal: &Vec3,
        goal_tol: Real,
        params: &TeamParams,
    ) -> Result<LocalPlan, SceneError> {
        self.scene.build(points, up, params)?;
        score::score_vertices(&self.scene, params, &mut self.scores);
        let c = cull(&self.scores, params, V.saturating_sub(1), &mut self.order);
        self.graph.clear();
        let _ = self.graph.push_vertex(AnchorVertex { pos: *robot, score: 0.0 });
        for &k in self.order.iter().take(c.kept) {
            let v = AnchorVertex { pos: self.scene.vertex(k as usize), score: self.scores.get(k as usize).copied().unwrap_or(0.0) };
            if self.graph.push_vertex(v).is_err() {
                break;
            }
        }
        let g = self.graph.build_edges(params);
        let p: leg_astar::LocalPath<PATH_MAX_HOPS> =
            bounded_leg_astar(&self.graph, &mut self.astar, 0, goal, goal_tol, c_m, params);
        let mut hops = HVec::new();
        for &v in &p.vertices {
            if let Some(x) = self.graph.vertices.get(v as usize) {
                let _ = hops.push(x.pos);
            }
        }
        Ok(LocalPlan { status: p.status, hops, cull: c, graph: g, loss: p.loss, expansions: p.expansions })
    }
}

impl<const P: usize, const V: usize, const E: usize> Default for LocalPlanner<P, V, E> {
    fn default() -> Self {
        Self::new()
    }
}

/// The planner with the default capacities of [`crate::config::team`].
pub type DefaultLocalPlanner = LocalPlanner<
    { crate::config::team::SCENE_MAX_POINTS },
    { crate::config::team::GRAPH_MAX_VERTICES },
    { crate::config::team::GRAPH_MAX_EDGES },
>;
