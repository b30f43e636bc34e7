//! `tetherbot abit-bench`: this project's ABIT* side by side with OMPL 1.5.2's ABIT* on the shared geometric
//! problems (issue 6). See `host-sim/doc/abit_bench.md`.
//!
//! For every problem: our planner runs `--seeds` times (seeds `first_seed..`), then — when `pkg-config` finds
//! OMPL — the C++ driver `host-sim/bench-ref/ompl_abit.cpp` is built (once, into `--out-dir`) and runs the same
//! problem (written to a text file from the same `GeometricProblem`) with the same iteration and time budgets.
//! Runs are sequential so the two planners never compete for a core. Prints one table: success rate, median
//! time and iteration of the first solution, median final cost (unsolved runs count as infinite, so a median
//! is finite only if more than half the runs solved), median total time, and the ratios ours / OMPL; writes
//! every run to `results.csv`.

use core::fmt::Write as _;
use core::time::Duration;
use std::path::{Path, PathBuf};
use std::process::Command;

use crate::harness::{
    shared_problems, AbitGeometric, HarnessPlanner, RunResult, RunSpec, SharedProblem,
};
use firmware::plan::abit::AbitParams;

/// Arguments of `tetherbot abit-bench`.
#[derive(Debug, Clone, clap::Args)]
pub struct Args {
    /// Runs per problem and planner.
    #[arg(long, default_value_t = 50)]
    pub seeds: u32,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    pub first_seed: u64,
    /// Iteration budget per run (an iteration = one edge processed or one batch started, as OMPL counts).
    #[arg(long, default_value_t = 3000)]
    pub iterations: u32,
    /// Wall-clock cap per run of the equal-iteration table, seconds (whichever budget ends first).
    #[arg(long, default_value_t = 10.0)]
    pub seconds: f64,
    /// Wall-clock budget per run of the second, equal-time table (no iteration limit), seconds; 0 skips it.
    #[arg(long, default_value_t = 0.05)]
    pub equal_time: f64,
    /// Comma-separated problem names (default: all of wall2, wall4, wall8, box3d).
    #[arg(long)]
    pub problems: Option<String>,
    /// Skip the OMPL side.
    #[arg(long)]
    pub no_ompl: bool,
    /// Directory for problem files, the built driver and results.csv.
    #[arg(long, default_value = "target/abit-bench")]
    pub out_dir: PathBuf,
    /// The OMPL driver's source.
    #[arg(long, default_value = concat!(env!("CARGO_MANIFEST_DIR"), "/bench-ref/ompl_abit.cpp"))]
    pub ompl_source: PathBuf,
}

/// Per-planner summary of one problem.
#[derive(Debug, Clone, Copy)]
pub struct Summary {
    /// Runs.
    pub runs: usize,
    /// Runs with an exact solution.
    pub solved: usize,
    /// Median first-solution time, seconds (infinite when at most half solved).
    pub median_first_time: f64,
    /// Median first-solution iteration.
    pub median_first_iteration: f64,
    /// Median final cost.
    pub median_final_cost: f64,
    /// Median total time, seconds.
    pub median_total_time: f64,
    /// Median iterations run.
    pub median_iterations: f64,
    /// Runs whose path failed the independent re-validation.
    pub invalid_paths: usize,
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        let (a, b) = (v[n / 2 - 1], v[n / 2]);
        if a.is_infinite() || b.is_infinite() {
            f64::INFINITY
        } else {
            (a + b) / 2.0
        }
    }
}

/// Summarise runs (unsolved runs count as infinite time, iteration and cost).
pub fn summarise(runs: &[RunResult]) -> Summary {
    let inf = f64::INFINITY;
    Summary {
        runs: runs.len(),
        solved: runs.iter().filter(|r| r.solved).count(),
        median_first_time: median(
            runs.iter()
                .map(|r| r.first_solution_time.map_or(inf, |t| t.as_secs_f64()))
                .collect(),
        ),
        median_first_iteration: median(
            runs.iter()
                .map(|r| r.first_solution_iteration.map_or(inf, f64::from))
                .collect(),
        ),
        median_final_cost: median(runs.iter().map(|r| r.final_cost.unwrap_or(inf)).collect()),
        median_total_time: median(runs.iter().map(|r| r.total_time.as_secs_f64()).collect()),
        median_iterations: median(runs.iter().map(|r| f64::from(r.iterations)).collect()),
        invalid_paths: runs
            .iter()
            .filter(|r| r.path_verified == Some(false))
            .count(),
    }
}

/// Build the OMPL driver if OMPL is installed; `Ok(None)` when it is not.
pub fn build_ompl_driver(source: &Path, out_dir: &Path) -> Result<Option<PathBuf>, String> {
    let exists = Command::new("pkg-config")
        .args(["--exists", "ompl"])
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !exists {
        return Ok(None);
    }
    let bin = out_dir.join("ompl_abit");
    let fresh = match (
        std::fs::metadata(&bin).and_then(|m| m.modified()),
        std::fs::metadata(source).and_then(|m| m.modified()),
    ) {
        (Ok(b), Ok(s)) => b >= s,
        _ => false,
    };
    if fresh {
        return Ok(Some(bin));
    }
    let cflags = Command::new("pkg-config")
        .args(["--cflags", "ompl"])
        .output()
        .map_err(|e| format!("pkg-config failed: {e}"))?;
    let cflags = String::from_utf8_lossy(&cflags.stdout).to_string();
    // `pkg-config --libs ompl` is broken on Debian bookworm; link explicitly (shared/EMBEDDED.md).
    let mut cmd = Command::new("g++");
    cmd.args(["-O2", "-std=c++17"])
        .args(cflags.split_whitespace())
        .arg(source)
        .args(["-lompl", "-lpthread", "-o"])
        .arg(&bin);
    let out = cmd.output().map_err(|e| format!("cannot run g++: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "building the OMPL driver failed:\n{}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(Some(bin))
}

/// Run the OMPL driver on one problem; one [`RunResult`] per seed.
pub fn run_ompl(
    bin: &Path,
    problem: &SharedProblem,
    out_dir: &Path,
    first_seed: u64,
    seeds: u32,
    iterations: u32,
    seconds: f64,
) -> Result<Vec<RunResult>, String> {
    let file = out_dir.join(format!("{}.txt", problem.name()));
    std::fs::write(&file, problem.to_text())
        .map_err(|e| format!("cannot write {}: {e}", file.display()))?;
    let out = Command::new(bin)
        .arg(&file)
        .arg(first_seed.to_string())
        .arg(seeds.to_string())
        .arg(iterations.to_string())
        .arg(seconds.to_string())
        .output()
        .map_err(|e| format!("cannot run {}: {e}", bin.display()))?;
    if !out.status.success() {
        return Err(format!(
            "OMPL driver failed: {}",
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    let text = String::from_utf8_lossy(&out.stdout);
    let mut runs = Vec::new();
    for line in text.lines() {
        let f: Vec<&str> = line.split_whitespace().collect();
        if f.len() != 9 {
            return Err(format!("unexpected OMPL driver line: {line}"));
        }
        let num = |i: usize| {
            f[i].parse::<f64>()
                .map_err(|e| format!("bad field {i} in `{line}`: {e}"))
        };
        let solved = num(1)? > 0.5;
        let first_time = num(2)?;
        let first_iter = num(3)?;
        runs.push(RunResult {
            planner: "ABIT* (OMPL 1.5.2)",
            problem: problem.name(),
            seed: num(0)? as u64,
            solved,
            first_solution_time: (first_time >= 0.0).then(|| Duration::from_secs_f64(first_time)),
            first_solution_iteration: (first_iter >= 0.0).then_some(first_iter as u32),
            final_cost: solved.then_some(num(4)?),
            iterations: num(5)? as u32,
            batches: num(8)? as u32,
            edges_evaluated: num(7)? as u32,
            states_checked: 0,
            total_time: Duration::from_secs_f64(num(6)?),
            path_verified: None,
        });
    }
    Ok(runs)
}

fn fmt_ms(s: f64) -> String {
    if s.is_finite() {
        format!("{:.3}", s * 1e3)
    } else {
        "inf".into()
    }
}

fn fmt_num(x: f64, prec: usize) -> String {
    if x.is_finite() {
        format!("{x:.prec$}")
    } else {
        "inf".into()
    }
}

/// Percentile-bootstrap 95 % interval of `median(a) / median(b)` (2000 resamples of each side, fixed seed, so
/// the table is reproducible). `None` when either side is empty or the interval is not finite (too many
/// unsolved runs).
pub fn median_ratio_ci(a: &[f64], b: &[f64]) -> Option<(f64, f64)> {
    use rand_core::{Rng, SeedableRng};
    if a.is_empty() || b.is_empty() {
        return None;
    }
    let mut rng = rand_pcg::Pcg64::seed_from_u64(0);
    let mut resample = |v: &[f64]| -> f64 {
        let n = v.len() as u64;
        median(
            (0..v.len())
                .map(|_| v[(rng.next_u64() % n) as usize])
                .collect(),
        )
    };
    let mut ratios: Vec<f64> = (0..2000)
        .map(|_| {
            let (x, y) = (resample(a), resample(b));
            // An infinite median (most runs unsolved) has no ratio; NaN sorts last and voids the interval.
            if x.is_finite() && y.is_finite() && y > 0.0 {
                x / y
            } else {
                f64::NAN
            }
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    let (lo, hi) = (ratios[50], ratios[1949]);
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

fn ratio_ci(a: f64, b: f64, ci: Option<(f64, f64)>) -> String {
    match ci {
        Some((lo, hi)) => format!("{} [{lo:.3}, {hi:.3}]", ratio(a, b)),
        None => ratio(a, b),
    }
}

fn ratio(a: f64, b: f64) -> String {
    if a.is_finite() && b.is_finite() && b > 0.0 {
        format!("{:.3}", a / b)
    } else {
        "-".into()
    }
}

/// `tetherbot abit-bench`: run, print the table, exit 0 (or 2 if the benchmark could not run).
pub fn main(args: &Args) -> std::process::ExitCode {
    match run(args) {
        Ok(table) => {
            print!("{table}");
            std::process::ExitCode::SUCCESS
        }
        Err(e) => super::fail(e),
    }
}

/// Run the benchmark and print the table. Returns the table text.
pub fn run(args: &Args) -> Result<String, String> {
    std::fs::create_dir_all(&args.out_dir)
        .map_err(|e| format!("cannot create {}: {e}", args.out_dir.display()))?;
    let wanted: Option<Vec<String>> = args
        .problems
        .as_ref()
        .map(|s| s.split(',').map(|x| x.trim().to_string()).collect());
    let problems: Vec<SharedProblem> = shared_problems()
        .into_iter()
        .filter(|p| {
            wanted
                .as_ref()
                .is_none_or(|w| w.iter().any(|n| n == p.name()))
        })
        .collect();
    if problems.is_empty() {
        return Err("no problem matches --problems (known: wall2, wall4, wall8, box3d)".into());
    }
    let ompl = if args.no_ompl {
        None
    } else {
        build_ompl_driver(&args.ompl_source, &args.out_dir)?
    };
    if ompl.is_none() && !args.no_ompl {
        eprintln!("OMPL not found (pkg-config ompl); running our side only. Install with: apt-get install -y libompl-dev");
    }
    let mut table = String::new();
    let mut csv = String::from(
        "budget,planner,problem,seed,solved,first_time_s,first_iteration,final_cost,iterations,total_time_s,edges_evaluated,batches,path_verified\n",
    );
    let mut budgets = vec![("equal iterations", args.iterations, args.seconds)];
    if args.equal_time > 0.0 {
        budgets.push(("equal time", u32::MAX, args.equal_time));
    }
    for (label, iterations, seconds) in budgets {
        run_budget(
            args,
            &problems,
            ompl.as_deref(),
            (label, iterations, seconds),
            &mut table,
            &mut csv,
        )?;
    }
    let csv_path = args.out_dir.join("results.csv");
    std::fs::write(&csv_path, csv)
        .map_err(|e| format!("cannot write {}: {e}", csv_path.display()))?;
    let _ = writeln!(table, "per-run results: {}", csv_path.display());
    Ok(table)
}

/// One budget: run every problem with both planners, append the table rows and the CSV lines.
fn run_budget(
    args: &Args,
    problems: &[SharedProblem],
    ompl: Option<&Path>,
    (label, iterations, seconds): (&str, u32, f64),
    table: &mut String,
    csv: &mut String,
) -> Result<(), String> {
    let ours = AbitGeometric {
        params: AbitParams::ompl_defaults(),
    };
    let limit = Some(Duration::from_secs_f64(seconds));
    let iteration_text = if iterations == u32::MAX {
        "no iteration limit".to_string()
    } else {
        format!("{iterations} iterations")
    };
    let _ = writeln!(
        table,
        "\n## {label}: {iteration_text}, {seconds} s per run, {} seeds from {}; medians count unsolved runs as inf",
        args.seeds, args.first_seed
    );
    let _ = writeln!(
        table,
        "{:<7} {:<19} {:>7} {:>13} {:>10} {:>11} {:>11} {:>10} {:>8}",
        "problem",
        "planner",
        "solved",
        "t_first[ms]",
        "it_first",
        "final_cost",
        "t_total[ms]",
        "iters",
        "badpath"
    );
    for problem in problems {
        let bar = indicatif::ProgressBar::new(u64::from(args.seeds));
        bar.set_message(format!("{} (ours, {label})", problem.name()));
        let mut our_runs = Vec::new();
        for s in 0..u64::from(args.seeds) {
            our_runs.push(ours.run(
                problem,
                &RunSpec {
                    seed: args.first_seed + s,
                    iterations,
                    time_limit: limit,
                },
            ));
            bar.inc(1);
        }
        bar.finish_and_clear();
        let mut rows = vec![("ABIT* (ours)", summarise(&our_runs))];
        let mut all = our_runs;
        if let Some(bin) = ompl {
            let runs = run_ompl(
                bin,
                problem,
                &args.out_dir,
                args.first_seed,
                args.seeds,
                iterations,
                seconds,
            )?;
            rows.push(("ABIT* (OMPL 1.5.2)", summarise(&runs)));
            all.extend(runs);
        }
        for (name, s) in &rows {
            let _ = writeln!(
                table,
                "{:<7} {:<19} {:>3}/{:<3} {:>13} {:>10} {:>11} {:>11} {:>10} {:>8}",
                problem.name(),
                name,
                s.solved,
                s.runs,
                fmt_ms(s.median_first_time),
                fmt_num(s.median_first_iteration, 0),
                fmt_num(s.median_final_cost, 4),
                fmt_ms(s.median_total_time),
                fmt_num(s.median_iterations, 0),
                s.invalid_paths
            );
        }
        if let [(_, a), (_, b)] = rows.as_slice() {
            let inf = f64::INFINITY;
            let side = |ours: bool, f: &dyn Fn(&RunResult) -> f64| -> Vec<f64> {
                all.iter()
                    .filter(|r| (r.planner == "ABIT* (ours)") == ours)
                    .map(f)
                    .collect()
            };
            let t_first = |r: &RunResult| r.first_solution_time.map_or(inf, |t| t.as_secs_f64());
            let cost = |r: &RunResult| r.final_cost.unwrap_or(inf);
            let _ = writeln!(
                table,
                "{:<7} {:<19} ratios ours/OMPL [95% bootstrap CI]: t_first {}  it_first {}  final_cost {}  t_total {}",
                problem.name(),
                "",
                ratio_ci(a.median_first_time, b.median_first_time, median_ratio_ci(&side(true, &t_first), &side(false, &t_first))),
                ratio(a.median_first_iteration, b.median_first_iteration),
                ratio_ci(a.median_final_cost, b.median_final_cost, median_ratio_ci(&side(true, &cost), &side(false, &cost))),
                ratio(a.median_total_time, b.median_total_time)
            );
        }
        for r in &all {
            let _ = writeln!(
                csv,
                "{},{},{},{},{},{},{},{},{},{:.9},{},{},{}",
                label,
                r.planner,
                r.problem,
                r.seed,
                r.solved,
                r.first_solution_time
                    .map_or(String::new(), |t| format!("{:.9}", t.as_secs_f64())),
                r.first_solution_iteration
                    .map_or(String::new(), |i| i.to_string()),
                r.final_cost.map_or(String::new(), |c| format!("{c:.12}")),
                r.iterations,
                r.total_time.as_secs_f64(),
                r.edges_evaluated,
                r.batches,
                r.path_verified.map_or(String::new(), |v| v.to_string())
            );
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bootstrap_interval_of_constant_samples_is_the_exact_ratio() {
        // Every resample of a constant sample has the same median, so the interval collapses to 3 / 2.
        let (lo, hi) = median_ratio_ci(&[3.0; 40], &[2.0; 25]).unwrap();
        assert_eq!((lo, hi), (1.5, 1.5));
    }

    #[test]
    fn bootstrap_interval_brackets_the_median_ratio_and_shrinks_with_more_runs() {
        // a = 1..=n, b = the same values doubled: the medians' ratio is 0.5.
        let make = |n: usize| -> (Vec<f64>, Vec<f64>) {
            let a: Vec<f64> = (1..=n).map(|i| i as f64).collect();
            let b = a.iter().map(|x| 2.0 * x).collect();
            (a, b)
        };
        let (a, b) = make(51);
        let (lo, hi) = median_ratio_ci(&a, &b).unwrap();
        assert!(lo < 0.5 && 0.5 < hi, "[{lo}, {hi}]");
        let (a, b) = make(801);
        let (lo2, hi2) = median_ratio_ci(&a, &b).unwrap();
        assert!(lo2 < 0.5 && 0.5 < hi2, "[{lo2}, {hi2}]");
        assert!(hi2 - lo2 < hi - lo);
    }

    #[test]
    fn bootstrap_interval_is_none_when_most_runs_are_unsolved() {
        let mut b = vec![f64::INFINITY; 30];
        b.extend([1.0; 10]);
        assert_eq!(median_ratio_ci(&[1.0; 40], &b), None);
        assert_eq!(median_ratio_ci(&[], &[1.0]), None);
    }
}
