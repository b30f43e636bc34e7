//! The `homotopy_tile_*` workloads (issue 20): the navigator's three bounded `plan_step` phases of a
//! `PlannerChoice::Homotopy` goal (`firmware::nav::homotopy`), run on the HiRISE scarp tile the mission scenario
//! `host-sim/scenarios/mission_homotopy_hirise.toml` uploads (`[mission.homotopy]`: 80 x 80 posts at 0.25 m from
//! (-3, -3), i.e. a 20 m x 20 m tile; root anchor (11.5, 11.5), goal (3.4, 3.4), soil friction 0.5, 40 m of tether).
//!
//! Phases, one [`Harness::measure`] each (the same calls as the navigator's `segment_phase`, `hold_phase` and
//! `route_phase`):
//! 1. `homotopy_tile_segment`: [`DemDescent::segment`] (corridor half width `HOMOTOPY_CORRIDOR_HALF_WIDTH_M`),
//!    [`DemDescent::check_ends`], [`DemDescent::build_btm`] and the point-mass hold model;
//! 2. `homotopy_tile_hold`: Axel's holding limit ([`axel_model`]);
//! 3. `homotopy_tile_route`: Alg. 1 ([`preplan`], `HomotopyParams::default()`) and [`DemDescent::route_to_world`]
//!    with the `max_payout` check (the navigator's cutting of the route into legs is not included: a few hundred
//!    instructions).
//!
//! The rover is [`RoverParams::AXEL`] with `wheel_mu` 0.5 (the navigator builds its rover from `Configure`; the
//! mission's configured Axel differs in its masses and boom, so the figures are those of this workload, not a
//! replay of the mission's plan).
//!
//! The tile is an input (the board has no file system): the board crate embeds the heights as little-endian `f32`
//! (`firmware/boards/mps2-an500/data/hirise_tile_80x80.f32le`, written by `tests/tests/board_homotopy_tile.rs` from
//! the scenario), the host computes them from the scenario (`host_sim::homotopy::tile::tile_heights`), and the board
//! and host summaries must be equal. The tile is loaded into [`HeightTile`] outside the measured phases (on board the
//! navigator loads it when the ground uploads it).
//!
//! The BTM and the A* workspace are the caller's (the board and host bench reuse those of the scenario-C
//! workloads); the tile and the segmentation scratch are in [`TileStorage`].

use core::fmt::Write;

use firmware::config::nav::HOMOTOPY_CORRIDOR_HALF_WIDTH_M;
use firmware::config::rover::RoverParams;
use firmware::plan::homotopy::axel::axel_model;
use firmware::plan::homotopy::dem::{DemDescent, DemParams, DemScratch, HeightTile, WorldRoute};
use firmware::plan::homotopy::plan::PlanReport;
use firmware::plan::homotopy::{preplan, Btm, HomotopyParams, Workspace};

use crate::{Harness, Summary};

/// Name of phase 1 (segment, check ends, BTM).
pub const SEGMENT: &str = "homotopy_tile_segment";
/// Name of phase 2 (Axel's holding limit).
pub const HOLD: &str = "homotopy_tile_hold";
/// Name of phase 3 (Alg. 1 and the world route).
pub const ROUTE: &str = "homotopy_tile_route";
/// World x, y of post (0, 0), m (`[mission.homotopy] origin`).
pub const ORIGIN: [f64; 2] = [-3.0, -3.0];
/// Post spacing, m.
pub const RESOLUTION_M: f64 = 0.25;
/// Posts per side (rows = columns).
pub const POSTS: usize = 80;
/// Posts of the tile.
pub const CELLS: usize = POSTS * POSTS;
/// The root anchor's x, y (`[tether] root_anchor`).
pub const ROOT_ANCHOR: [f64; 2] = [11.5, 11.5];
/// The goal's x, y (`[goal] position`).
pub const GOAL: [f64; 2] = [3.4, 3.4];
/// Soil friction (`[mission] friction`).
pub const FRICTION: f32 = 0.5;
/// Tether the route may pay out, m (`[tether] length_m`).
pub const MAX_PAYOUT_M: f64 = 40.0;

/// The workload's own storage (all zero bytes when empty: `.psram` / `.bss` on the board).
pub struct TileStorage {
    /// The tile (fixed capacity `MAX_TILE_CELLS`, 64 KiB of heights).
    pub tile: HeightTile,
    /// The segmentation scratch (~112 KiB).
    pub scratch: DemScratch,
}

impl TileStorage {
    /// Empty.
    pub const fn new() -> Self {
        Self { tile: HeightTile::new(), scratch: DemScratch::new() }
    }
}

impl Default for TileStorage {
    fn default() -> Self {
        Self::new()
    }
}

/// The rover of the workload: [`RoverParams::AXEL`] on soil of friction [`FRICTION`].
pub fn rover() -> RoverParams {
    let mut r = RoverParams::AXEL;
    r.wheel_mu = FRICTION;
    r
}

fn line(args: core::fmt::Arguments<'_>) -> Summary {
    let mut s = Summary::new();
    let _ = s.write_fmt(args);
    s
}

/// What the three phases produced (for tests; the summaries are the same facts in text).
#[derive(Debug, Clone, Default)]
pub struct TileOutcome {
    /// Unfolded planes of the descent (0 when segmentation failed).
    pub planes: usize,
    /// BTM triangles.
    pub triangles: usize,
    /// Axel's holding limit on the wall, rad.
    pub theta_max_rad: Option<f64>,
    /// Classes Alg. 1 examined.
    pub classes: usize,
    /// The world route, if one was found and fits the tether.
    pub route: Option<WorldRoute>,
}

/// Runs the three phases on `heights` (row-major, [`CELLS`] posts from the smallest y), timing each with `h` and
/// reporting one summary per phase.
pub fn run(store: &mut TileStorage, btm: &mut Btm, ws: &mut Workspace, heights: &[f32], h: &mut dyn Harness) -> TileOutcome {
    let mut out = TileOutcome::default();
    if let Err(e) = store.tile.load(ORIGIN, RESOLUTION_M, POSTS, POSTS, heights) {
        h.result(SEGMENT, &line(format_args!("tile refused: {e:?}")));
        return out;
    }
    let rover = rover();
    // Phase 1: segment, check the ends, build the BTM, the point-mass model.
    let params = DemParams::for_rover(&rover, f64::from(rover.wheel_mu), HOMOTOPY_CORRIDOR_HALF_WIDTH_M);
    let (tile, scratch) = (&store.tile, &mut store.scratch);
    let mut seg = None;
    {
        let btm = &mut *btm;
        h.measure(SEGMENT, &mut || {
            seg = Some(DemDescent::segment(tile, ROOT_ANCHOR, GOAL, &params, scratch).and_then(|d| {
                d.check_ends()?;
                Ok(d)
            }).map(|d| {
                let built = d.build_btm(btm);
                let model = d.hold_model();
                (d, built, model)
            }));
        });
    }
    let (descent, model) = match seg {
        Some(Ok((d, Ok(_), model))) => {
            out.planes = d.planes.len();
            out.triangles = btm.triangle_count();
            let s = line(format_args!(
                "planes={} reference={} obstacles={} edge_obstacles={} triangles={} a0=({},{}) g=({},{})",
                d.planes.len(),
                d.reference,
                d.obstacles.len(),
                d.edge_obstacles.len(),
                btm.triangle_count(),
                d.a0.x,
                d.a0.y,
                d.g.x,
                d.g.y
            ));
            h.result(SEGMENT, &s);
            (d, model)
        }
        Some(Ok((_, Err(e), _))) => {
            h.result(SEGMENT, &line(format_args!("BTM not built: {e:?}")));
            return out;
        }
        Some(Err(e)) => {
            h.result(SEGMENT, &line(format_args!("not segmented: {e:?}")));
            return out;
        }
        None => {
            h.result(SEGMENT, &line(format_args!("not run")));
            return out;
        }
    };
    // Phase 2: Axel's holding limit.
    let mut held = None;
    h.measure(HOLD, &mut || held = Some(axel_model(&model, &rover)));
    let Some((ax, limits)) = held else {
        h.result(HOLD, &line(format_args!("not run")));
        return out;
    };
    let [wall, other] = limits;
    out.theta_max_rad = Some(wall.theta_max_rad);
    h.result(
        HOLD,
        &line(format_args!(
            "theta_max_rad={} checks={} unsettled={} second_theta_max_rad={} second_checks={}",
            wall.theta_max_rad, wall.checks, wall.unsettled, other.theta_max_rad, other.checks
        )),
    );
    // Phase 3: Alg. 1 with Axel's model, the plan mapped to the world with the max_payout check.
    let (mut constraints, mut rep) = (heapless::Vec::new(), PlanReport::default());
    let mut routed = None;
    {
        let (btm, tile, descent) = (&*btm, &store.tile, &descent);
        h.measure(ROUTE, &mut || {
            let plan = preplan(btm, &ax, &HomotopyParams::default(), ws, descent.a0, descent.g, &mut constraints, &mut rep);
            routed = Some(plan.map(|p| p.map(|p| (p.class.cost, p.anchors.len(), descent.route_to_world(tile, &p, MAX_PAYOUT_M)))));
        });
    }
    out.classes = rep.examined.len();
    let s = match routed {
        Some(Ok(Some((class_cost, anchors, Ok(route))))) => {
            let s = line(format_args!(
                "route class_cost={} anchors={} tether_m={} tether_points={} waypoints={} classes_examined={} rounds={} first_anchor={:?} last_waypoint={:?}",
                class_cost,
                anchors,
                route.tether_length_m,
                route.tether.len(),
                route.waypoints.len(),
                rep.examined.len(),
                rep.rounds,
                route.anchors.first(),
                route.waypoints.last()
            ));
            out.route = Some(route);
            s
        }
        Some(Ok(Some((_, _, Err(e))))) => line(format_args!("route refused: {e:?} classes_examined={}", rep.examined.len())),
        Some(Ok(None)) => line(format_args!("no plan classes_examined={} rounds={}", rep.examined.len(), rep.rounds)),
        Some(Err(e)) => line(format_args!("{e:?}")),
        None => line(format_args!("not run")),
    };
    h.result(ROUTE, &s);
    out
}
