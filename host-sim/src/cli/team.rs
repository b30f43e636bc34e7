//! `tetherbot movingai` and `tetherbot team`: the climbing-team subcommands (Morad et al.). See
//! `host-sim/doc/team.md`.

use crate::movingai::{load_map, load_scen, run_astar_reference, run_scenarios, tolerance, RunSummary};
use crate::team::worlds::{team_rng, team_scenario};
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
    let name = args.map.file_name().map(|f| f.to_string_lossy().into_owned()).unwrap_or_default();
    println!(
        "movingai {name}: scenarios run {}, mismatches {}, max |error| {:.3e}, expansions {}, time {:.3} s ({:.0} scenarios/s)",
        r.run,
        r.mismatches.len(),
        r.max_abs_error,
        r.expansions,
        secs,
        r.run as f64 / secs.max(1e-9)
    );
    // the reference, on the same scenarios in the same run
    let t = Instant::now();
    let a = run_astar_reference(&map, &scens, |i, _| i % stride == 0);
    let a_secs = t.elapsed().as_secs_f64();
    for m in &a.mismatches {
        let s = &m.scenario;
        println!("REFERENCE MISMATCH line {}: planned {:?} published {}", s.line, m.planned, s.optimal);
    }
    println!("| planner on {name} | scenarios | mismatches | max abs error | expansions | time [s] | expansions/s | scenarios/s |");
    println!("|---|---|---|---|---|---|---|---|");
    let row = |who: &str, r: &RunSummary, secs: f64| {
        println!(
            "| {who} | {} | {} | {:.2e} | {} | {:.3} | {:.3e} | {:.0} |",
            r.run,
            r.mismatches.len(),
            r.max_abs_error,
            r.expansions,
            secs,
            r.expansions as f64 / secs.max(1e-9),
            r.run as f64 / secs.max(1e-9)
        )
    };
    row("D* Lite (flight code, from scratch per scenario)", &r, secs);
    row("A* (`pathfinding` crate, reference)", &a, a_secs);
    Ok(r.mismatches.is_empty() && a.mismatches.is_empty())
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
    /// Where the hub's flight code runs: `inproc` (the flight executive, over protocol v8's team messages),
    /// `direct` (the flight crate's mission called as a library, the simulation before v8; the same run) or `qemu`
    /// (the flight executive on the emulated board, booted per seed with instruction counting; the same run, plus
    /// the board's instruction counts and resource report; builds the board binary if it is missing).
    #[arg(long, value_enum, default_value_t = crate::team::TeamLink::Inproc)]
    pub link: crate::team::TeamLink,
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
        let rep = if args.link == crate::team::TeamLink::Qemu {
            let elf = super::board::board_elf(None, false).map_err(|e| e.to_string())?;
            let (rep, board) = crate::team::simulate_on_board(surf.as_ref(), &start, &cfg, &mut rng, &elf, true).map_err(|e| e.to_string())?;
            let per_tick = board.figure("instructions_per_tick_under_icount").unwrap_or(0);
            let fig = |k: &str| board.figure(k).unwrap_or(0);
            println!(
                "board seed {seed}: {} lockstep executive steps, the costliest {} instructions, all {} instructions (-icount shift=0); boot to ready {:.1} ms",
                fig("lockstep_steps"),
                fig("lockstep_step_ticks_max") * per_tick,
                fig("lockstep_step_ticks_total") * per_tick,
                board.boot.as_secs_f64() * 1e3
            );
            for l in &board.report {
                println!("{l}");
            }
            rep
        } else {
            crate::team::simulate_over(surf.as_ref(), &start, &cfg, &mut rng, args.link).map_err(|e| e.to_string())?
        };
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
            rep.walls.len().max(rep.stats.walls as usize),
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
        walls += rep.walls.len().max(rep.stats.walls as usize);
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
