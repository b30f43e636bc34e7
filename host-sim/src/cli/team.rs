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
