//! `tetherbot movingai` and `tetherbot team`: the climbing-team subcommands (Morad et al.). See
//! `host-sim/doc/team.md`.

use crate::movingai::{load_map, load_scen, run_scenarios, tolerance};
use std::path::PathBuf;
use std::time::Instant;

/// `tetherbot movingai <map> <scen>`: run every scenario through the global planner (D* Lite).
#[derive(Debug, clap::Args)]
pub struct MovingaiArgs {
    /// The `.map` file.
    pub map: PathBuf,
    /// The `.scen` file.
    pub scen: PathBuf,
    /// Run only every N-th scenario (1 = all).
    #[arg(long, default_value_t = 1)]
    pub stride: usize,
}

/// Run the subcommand; `Ok(true)` when every scenario matched.
pub fn movingai(args: &MovingaiArgs) -> Result<bool, String> {
    let map = load_map(&args.map).map_err(|e| format!("{}: {e}", args.map.display()))?;
    let scens = load_scen(&args.scen).map_err(|e| format!("{}: {e}", args.scen.display()))?;
    let stride = args.stride.max(1);
    let t = Instant::now();
    let r = run_scenarios(&map, &scens, |i, _| i % stride == 0)?;
    let secs = t.elapsed().as_secs_f64();
    for m in &r.mismatches {
        let s = &m.scenario;
        println!(
            "MISMATCH line {} bucket {}: ({},{}) -> ({},{}) planned {} published {:.*} (tolerance {:.1e})",
            s.line,
            s.bucket,
            s.start_x,
            s.start_y,
            s.goal_x,
            s.goal_y,
            m.planned.map(|c| format!("{c:.8}")).unwrap_or_else(|| "no path".into()),
            s.decimals,
            s.optimal,
            tolerance(s.decimals)
        );
    }
    println!(
        "movingai {}: scenarios run {}, mismatches {}, max |error| {:.3e}, expansions {}, time {:.3} s ({:.0} scenarios/s)",
        args.map.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default(),
        r.run,
        r.mismatches.len(),
        r.max_abs_error,
        r.expansions,
        secs,
        r.run as f64 / secs.max(1e-9)
    );
    Ok(r.mismatches.is_empty())
}

/// `tetherbot team`: run the four-robot team mission in closed loop (the flight code's D* Lite over scenes and
/// bounded-leg A* per hop; the simulator's true surface, landing errors, grip slips and referee) and draw it.
#[derive(Debug, clap::Args)]
pub struct TeamArgs {
    /// A team scenario file (TOML; schema in `host-sim/doc/team.md`, "Scenario files"). Without it, `--world`.
    pub scenario: Option<PathBuf>,
    /// World: `cliff` (HiRISE crop scaled into a cliff, 10 m hops), `itokawa` or `bennu` (shape models, 30 m
    /// hops), `crevasse` (the paper's Fig. 12 crevasse in a true world).
    #[arg(long, default_value = "cliff")]
    pub world: String,
    /// Directory of the shared data (`terrain/`, `asteroids/`).
    #[arg(long, default_value = "../shared/data")]
    pub data: PathBuf,
    /// Write the picture here (SVG; with `--seeds`, of the first seed).
    #[arg(long)]
    pub svg: Option<PathBuf>,
    /// Scripted node loss `ROBOT:TURN` (0-based), e.g. `2:3`.
    #[arg(long)]
    pub fail: Option<String>,
    /// Seed (sensor noise, landing errors, grip slips). Default 1, or the scenario file's `seeds.first`.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Run this many seeds from `--seed` on and print a campaign summary. Default 1, or the scenario file's
    /// `seeds.count`.
    #[arg(long)]
    pub seeds: Option<u64>,
    /// Grips never slip (the grip model's slip probability set to 0; isolates the route from node losses).
    #[arg(long)]
    pub no_slip: bool,
}

/// The scenario set-up shared by the CLI, the tests and the benchmark: (surface, start, config, view, background).
pub type TeamScenario = (Box<dyn crate::team::surface::Surface>, [[f64; 3]; 4], crate::team::SimConfig, [f64; 3], Vec<[f64; 3]>);

fn centroid(p: &[[f64; 3]; 4]) -> [f64; 3] {
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

fn fmt_cells(c: &[(i64, i64)]) -> String {
    c.iter().map(|(x, y)| format!("({x},{y})")).collect::<Vec<_>>().join(",")
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Run the subcommand; `Ok(true)` when every run reached the goal (flight code and referee agree) with no
/// violation.
pub fn team(args: &TeamArgs) -> Result<bool, String> {
    let fail = match &args.fail {
        None => None,
        Some(s) => {
            let (a, b) = s.split_once(':').ok_or("--fail wants ROBOT:TURN")?;
            Some((a.parse().map_err(|_| "bad robot")?, b.parse().map_err(|_| "bad turn")?))
        }
    };
    let file = args.scenario.as_deref().map(crate::team::scenario::load).transpose()?;
    let (first, count) = file.as_ref().map(|f| f.seeds()).unwrap_or((1, 1));
    let (seed0, nseeds) = (args.seed.unwrap_or(first), args.seeds.unwrap_or(count).max(1));
    let label = file.as_ref().map(|f| f.file.name.clone()).unwrap_or_else(|| args.world.clone());
    let mut all_ok = true;
    let (mut reached, mut hops, mut walls, mut lost, mut violations, mut runs) = (0usize, Vec::new(), 0usize, 0usize, 0usize, 0usize);
    let (mut plan_times, mut round_times) = (Vec::new(), Vec::new());
    for seed in seed0..seed0 + nseeds {
        let (surf, start, mut cfg, view, bg) = match &file {
            Some(f) => {
                let mut s = f.build(&args.data, seed)?;
                s.2.fail = fail;
                s
            }
            None => team_scenario(&args.world, &args.data, fail, seed)?,
        };
        if args.no_slip {
            cfg.grip = crate::team::grip::GripModel::never_slips(cfg.params.h_max as f64);
        }
        let mut rng = team_rng(seed);
        let t = Instant::now();
        let rep = crate::team::simulate(surf.as_ref(), &start, &cfg, &mut rng).map_err(|e| e.to_string())?;
        let secs = t.elapsed().as_secs_f64();
        let mut times = rep.plan_times.clone();
        let med = median(&mut times);
        let max = times.last().copied().unwrap_or(0.0);
        let mut q: Vec<f64> = rep.hops.iter().map(|h| h.grip_q).collect();
        q.sort_by(|a, b| a.total_cmp(b));
        let q90 = q.get(q.len() * 9 / 10).copied().unwrap_or(0.0);
        let qmed = median(&mut q);
        for v in &rep.violations {
            println!("VIOLATION seed {seed}: {v}");
        }
        println!(
            "team {} seed {seed}: outcome {}, reached {}, hops {}, rounds {}, walls {} [{}], scenes {}, lost {:?}, violations {}, grip q median {qmed:.3} p90 {q90:.3}, local plans {} (median {:.1} ms, max {:.1} ms), wall {:.2} s",
            rep.world,
            rep.outcome.map(|o| o.label()).unwrap_or("none"),
            rep.reached,
            rep.hops.len(),
            rep.rounds,
            rep.walls.len(),
            rep.walls.iter().map(|(a, b)| format!("{}-{}", fmt_cells(&[*a]), fmt_cells(&[*b]))).collect::<Vec<_>>().join(" "),
            fmt_cells(&rep.visited),
            rep.lost,
            rep.violations.len(),
            times.len(),
            med * 1e3,
            max * 1e3,
            secs
        );
        if seed == seed0 {
            if let Some(p) = &args.svg {
                std::fs::write(p, crate::team::svg::render(&rep, view, &bg)).map_err(|e| format!("{}: {e}", p.display()))?;
                println!("picture: {}", p.display());
            }
        }
        all_ok &= rep.success();
        runs += 1;
        reached += usize::from(rep.success());
        hops.push(rep.hops.len() as f64);
        walls += rep.walls.len();
        lost += rep.lost.len();
        violations += rep.violations.len();
        plan_times.extend(rep.plan_times);
        round_times.extend(rep.round_times);
    }
    if runs > 1 {
        let mean_hops = hops.iter().sum::<f64>() / runs as f64;
        let med_hops = median(&mut hops);
        let pmed = median(&mut plan_times);
        let pmax = plan_times.last().copied().unwrap_or(0.0);
        let rmed = median(&mut round_times);
        let rmax = round_times.last().copied().unwrap_or(0.0);
        println!(
            "campaign {} seeds {}..={}: reached {reached}/{runs}, hops mean {mean_hops:.1} median {med_hops:.0}, walls {walls}, robots lost {lost}, violations {violations}, local plan median {:.1} ms max {:.1} ms ({} plans), end of round median {:.3} ms max {:.3} ms",
            label,
            seed0,
            seed0 + runs as u64 - 1,
            pmed * 1e3,
            pmax * 1e3,
            plan_times.len(),
            rmed * 1e3,
            rmax * 1e3
        );
    }
    Ok(all_ok)
}

/// `movingai` as a process exit code: 0 all matched, 1 a mismatch, 2 the files could not be read.
pub fn movingai_main(args: &MovingaiArgs) -> std::process::ExitCode {
    match movingai(args) {
        Ok(true) => std::process::ExitCode::SUCCESS,
        Ok(false) => std::process::ExitCode::from(super::EXIT_FAILED),
        Err(e) => super::fail(e),
    }
}

/// `team` as a process exit code: 0 every run reached the goal with no violation, 1 a run did not reach the goal or
/// had a violation, 2 the world could not be built.
pub fn team_main(args: &TeamArgs) -> std::process::ExitCode {
    match team(args) {
        Ok(true) => std::process::ExitCode::SUCCESS,
        Ok(false) => std::process::ExitCode::from(super::EXIT_FAILED),
        Err(e) => super::fail(e),
    }
}
