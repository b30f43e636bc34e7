//! The named team worlds of Morad et al.'s experiments, built for the simulator: `cliff` (the steepest part of the
//! HiRISE crop scaled into a cliff, Fig. 15's 10 m hops), `itokawa` and `bennu` (the shape models, 30 m hops as in
//! Fig. 16) and `crevasse` (a synthetic gap). The CLI (`tetherbot team --world`), scenario files
//! ([`super::scenario`]), the tests and the benchmark all build them here.

/// The scenario set-up shared by the CLI, the tests and the benchmark: (surface, start, config, view, background).
pub type TeamScenario = (Box<dyn crate::team::surface::Surface>, [[f64; 3]; 4], crate::team::SimConfig, [f64; 3], Vec<[f64; 3]>);

pub(crate) fn centroid(p: &[[f64; 3]; 4]) -> [f64; 3] {
    let s = p.iter().fold([0.0; 3], |a, q| [a[0] + q[0], a[1] + q[1], a[2] + q[2]]);
    [s[0] / 4.0, s[1] / 4.0, s[2] / 4.0]
}

/// The DEM posts of a height surface (the picture's background).
fn dem_background(surf: &crate::team::surface::HeightSurface) -> Vec<[f64; 3]> {
    let hm = &surf.hm;
    (0..hm.height)
        .flat_map(|y| (0..hm.width).map(move |x| (x, y)))
        .filter_map(|(x, y)| hm.get(x, y).map(|z| [x as f64 * hm.spacing_m, y as f64 * hm.spacing_m, z]))
        .collect()
}

/// The rock-wall scale of Fig. 15 (10 m hops, 15 m tethers, 1 m landing margin, 0.3 m landing error, 8 m goal
/// tolerance) over `grid`, with a sensor of `range` metres and `max_rounds` rounds.
#[allow(clippy::too_many_arguments)]
fn hop10_config(
    grid: firmware::plan::team::mission::SceneGrid,
    blocked: Vec<(i64, i64)>,
    range: f64,
    max_rounds: u32,
    goal: [f64; 3],
    fail: Option<(usize, usize)>,
    seed: u64,
) -> crate::team::SimConfig {
    use crate::team::{grip::GripModel, RangeSensor, SimConfig};
    use firmware::config::team::{MissionParams, TeamParams};
    let params = TeamParams { landing_margin: 1.0, ..TeamParams::DEFAULT };
    SimConfig {
        params,
        mission: MissionParams { max_rounds, ..MissionParams::DEFAULT },
        grid,
        blocked,
        sensor: RangeSensor { rays: 3000, range, noise: 0.03, height: 0.3 },
        goal,
        goal_tol: 8.0,
        landing_error: 0.3,
        grip: GripModel::for_hop(params.h_max as f64),
        fail,
        seed,
    }
}

/// Build a named team scenario: `cliff`, `itokawa`, `bennu` or `crevasse`.
pub fn team_scenario(world: &str, data: &std::path::Path, fail: Option<(usize, usize)>, seed: u64) -> Result<TeamScenario, String> {
    use crate::team::grip::GripModel;
    use crate::team::surface::Surface;
    use crate::team::{asteroid, cliff_from_hirise, crevasse_world, scene_grid, x_start, RangeSensor, SimConfig};
    use firmware::config::team::{MissionParams, TeamParams};
    match world {
        "cliff" => {
            let (surf, _slope) = cliff_from_hirise(&data.join("terrain/hirise_DTEEC_010228_1490_016320_1490_crop_120x70.npy"), 40, 4.0, 8.0)?;
            // start low on the cliff, goal at the top: find the lowest and highest posts away from the border
            let (mut lo, mut hi) = ((f64::MAX, 0.0, 0.0), (f64::MIN, 0.0, 0.0));
            for y in 6..surf.hm.height - 6 {
                for x in 6..surf.hm.width - 6 {
                    if let Some(z) = surf.hm.get(x, y) {
                        let (px, py) = (x as f64 * surf.hm.spacing_m, y as f64 * surf.hm.spacing_m);
                        if z < lo.0 {
                            lo = (z, px, py);
                        }
                        if z > hi.0 {
                            hi = (z, px, py);
                        }
                    }
                }
            }
            let center = surf.point(lo.1, lo.2).ok_or("no start point")?;
            let goal = surf.point(hi.1, hi.2).ok_or("no goal point")?;
            let start = x_start(&surf, center, [center[0], center[1], center[2] - 1000.0], 6.0).ok_or("cannot place the team")?;
            let bg = dem_background(&surf);
            let grid = scene_grid(centroid(&start), goal, [0.0, 0.0, 1.0], 20.0, 2);
            let cfg = hop10_config(grid, Vec::new(), 25.0, 120, goal, fail, seed);
            Ok((Box::new(surf), start, cfg, [0.0, 0.0, 1.0], bg))
        }
        "itokawa" | "bennu" => {
            let surf = asteroid(&data.join(format!("asteroids/{world}.obj")), world)?;
            let (lo, hi) = surf.mesh.bounds().ok_or("empty mesh")?;
            let c = [(lo[0] + hi[0]) / 2.0, (lo[1] + hi[1]) / 2.0, (lo[2] + hi[2]) / 2.0];
            // start and goal on the +z face, 150 m apart along x
            let top = |x: f64| -> Option<[f64; 3]> {
                let o = [x, c[1], hi[2] + 100.0];
                surf.raycast(o, [0.0, 0.0, -1.0], 1000.0).map(|t| [o[0], o[1], o[2] - t])
            };
            let center = top(c[0] - 75.0).ok_or("no start point")?;
            let goal = top(c[0] + 75.0).ok_or("no goal point")?;
            let start = x_start(&surf, center, c, 12.0).ok_or("cannot place the team")?;
            let params = TeamParams { h_max: 30.0, r_max: 45.0, landing_margin: 2.0, score_radius: 8.0, flatness_scale: 1.5, ..TeamParams::DEFAULT };
            let hub = centroid(&start);
            let cfg = SimConfig {
                params,
                mission: MissionParams { max_rounds: 60, ..MissionParams::DEFAULT },
                grid: scene_grid(hub, goal, crate::team::surface::unit(firmware::geom::p3::sub(hub, c)), 50.0, 1),
                blocked: Vec::new(),
                sensor: RangeSensor { rays: 3000, range: 70.0, noise: 0.05, height: 0.3 },
                goal,
                goal_tol: 20.0,
                landing_error: 0.6,
                grip: GripModel::for_hop(params.h_max as f64),
                fail,
                seed,
            };
            let bg = surf.mesh.vertices.clone();
            Ok((Box::new(surf), start, cfg, [0.0, 0.0, 1.0], bg))
        }
        "crevasse" => {
            use firmware::geom::Vec3;
            use firmware::plan::team::mission::SceneGrid;
            let surf = crevasse_world();
            let center = surf.point(45.0, 45.0).ok_or("no start point")?;
            let goal = surf.point(45.0, 105.0).ok_or("no goal point")?;
            let start = x_start(&surf, center, [45.0, 45.0, -1000.0], 6.0).ok_or("cannot place the team")?;
            let bg = dem_background(&surf);
            // the paper's 1-based scene indices: column 0 is off its map (blocked)
            let grid = SceneGrid { origin: Vec3::zeros(), u: Vec3::x(), v: Vec3::y(), cell: 30.0, width: 5, height: 5 };
            let cfg = hop10_config(grid, (0..5).map(|y| (0, y)).collect(), 22.0, 100, goal, fail, seed);
            Ok((Box::new(surf), start, cfg, [0.0, 0.0, 1.0], bg))
        }
        other => Err(format!("unknown world {other:?} (cliff, itokawa, bennu, crevasse)")),
    }
}

/// The seeded generator of a team run.
pub fn team_rng(seed: u64) -> rand_pcg::Pcg64 {
    rand_pcg::Pcg64::new(seed as u128, 0x0a02_bdbf_7bb3_c0a7_ac28_fa16_a64a_bf96)
}

