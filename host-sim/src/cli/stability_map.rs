//! `tetherbot stability-map`: the stability region of the 55-degree ledge for a given root anchor, as a top-down
//! SVG map (green stable, red unstable, grey: the rover cannot settle there), like the shaded areas of Paton et al.
//! Fig. 8. See `host-sim/doc/stability_map.md`.
//!
//! For every grid cell the rover is settled (`firmware::rover::settle`) at the ground point with the given yaw, the
//! simulator's true tether (`truth::tether`, straight or over the lip / back edge) gives the last anchor, and
//! `firmware::rover::check_pose_stability` decides.

use core::fmt::Write as _;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Instant;

use firmware::config::rover::RoverParams;
use firmware::geom::{Real, Vec3};
use firmware::rover::{check_pose_stability, settle, SettleOutcome};

use crate::truth::tether::true_tether;
use crate::world::ledge::{self, LedgeWorld};

/// Arguments of `stability-map`.
#[derive(Debug, Clone, clap::Args)]
pub struct StabilityMapArgs {
    /// Root anchor: `test1` (4.9 m behind, 2 m above the start), `test2` (8.2 m in front, 2 m above), or `x,y,z`.
    #[arg(long, default_value = "test1")]
    pub root: String,
    /// Output SVG file.
    #[arg(long, short, default_value = "stability_map.svg")]
    pub out: PathBuf,
    /// Grid spacing, metres.
    #[arg(long, default_value_t = 0.2)]
    pub resolution: f64,
    /// Rover yaw about the surface normal, degrees (0: facing +x, down the slope).
    #[arg(long, default_value_t = 0.0)]
    pub yaw_deg: f64,
}

/// What one cell of the map says.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cell {
    /// Settled and statically stable.
    Stable,
    /// Settled but not stable (or the solver could not decide).
    Unstable,
    /// The rover does not settle there (collision, no ground, budget).
    NoSettle,
}

/// Parse the `--root` argument.
pub fn parse_root(s: &str) -> Result<[f64; 3], String> {
    match s {
        "test1" => Ok(ledge::ROOT_ANCHOR_TEST1),
        "test2" => Ok(ledge::ROOT_ANCHOR_TEST2),
        _ => {
            let v: Vec<f64> = s
                .split(',')
                .map(|t| t.trim().parse::<f64>())
                .collect::<Result<_, _>>()
                .map_err(|e| format!("--root {s:?}: expected test1, test2 or x,y,z ({e})"))?;
            match v.as_slice() {
                [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok([*x, *y, *z]),
                _ => Err(format!("--root {s:?}: expected three finite numbers x,y,z")),
            }
        }
    }
}

/// Evaluate one cell at ground point (x, y).
pub fn evaluate(world: &LedgeWorld, root: [f64; 3], x: f64, y: f64, yaw: Real) -> Cell {
    let params = RoverParams::AXEL;
    let g = Vec3::new(x as Real, y as Real, world.height_f64(x, y) as Real);
    let SettleOutcome::Settled(s) = settle(world, &g, yaw, &params) else {
        return Cell::NoSettle;
    };
    let axle = s.pose.translation.vector;
    let axle = [f64::from(axle.x), f64::from(axle.y), f64::from(axle.z)];
    let Some(t) = true_tether(world, root, axle, None) else {
        return Cell::Unstable;
    };
    let a = t.last_anchor(root);
    let a = Vec3::new(a[0] as Real, a[1] as Real, a[2] as Real);
    match check_pose_stability(world, &s, Some(&a), &params) {
        Ok((o, _)) if o.is_stable() => Cell::Stable,
        _ => Cell::Unstable,
    }
}

/// `stability-map` entry point.
pub fn main(args: &StabilityMapArgs) -> ExitCode {
    let root = match parse_root(&args.root) {
        Ok(r) => r,
        Err(e) => return super::fail(e),
    };
    if !(args.resolution.is_finite() && args.resolution >= 0.02) {
        return super::fail("--resolution must be a number >= 0.02 (metres)");
    }
    let world = LedgeWorld::new();
    let (x0, x1, y0, y1) = (-5.5, 6.5, -5.5, 5.5);
    let h = args.resolution;
    let (nx, ny) = (((x1 - x0) / h).ceil() as usize, ((y1 - y0) / h).ceil() as usize);
    let yaw = args.yaw_deg.to_radians() as Real;
    let t0 = Instant::now();
    let mut cells = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            let (x, y) = (x0 + (i as f64 + 0.5) * h, y0 + (j as f64 + 0.5) * h);
            cells.push(((x, y), evaluate(&world, root, x, y, yaw)));
        }
    }
    let elapsed = t0.elapsed();
    let count = |c: Cell| cells.iter().filter(|(_, k)| *k == c).count();
    // the slope face proper: cells where the whole rover (wheels 0.5 m either side, 0.35 m radius) rests on the
    // 55-degree face, not on the lip edge, the toe or the side edges
    let slope: Vec<_> =
        cells.iter().filter(|((x, y), _)| *x > 0.4 && *x < ledge::toe_x() - 0.4 && y.abs() < 4.4).collect();
    let slope_stable = slope.iter().filter(|(_, k)| *k == Cell::Stable).count();
    // SVG, 40 px per metre, y up
    let s = 40.0;
    let (w, hgt) = ((x1 - x0) * s, (y1 - y0) * s);
    let mut svg = String::new();
    let _ = writeln!(
        svg,
        r#"<svg xmlns="http://www.w3.org/2000/svg" width="{w}" height="{}" viewBox="0 0 {w} {}">"#,
        hgt + 40.0,
        hgt + 40.0
    );
    let px = |x: f64| (x - x0) * s;
    let py = |y: f64| (y1 - y) * s;
    for ((x, y), c) in &cells {
        let fill = match c {
            Cell::Stable => "#2ca02c",
            Cell::Unstable => "#d62728",
            Cell::NoSettle => "#999999",
        };
        let _ = writeln!(
            svg,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="{fill}"/>"#,
            px(x - h / 2.0),
            py(y + h / 2.0),
            h * s,
            h * s
        );
    }
    // ledge outline: back wall, lip, toe
    for (xa, xb, col) in [(-5.0, 0.0, "#000"), (0.0, ledge::toe_x(), "#555")] {
        let _ = writeln!(
            svg,
            r#"<rect x="{:.1}" y="{:.1}" width="{:.1}" height="{:.1}" fill="none" stroke="{col}" stroke-width="2"/>"#,
            px(xa),
            py(5.0),
            (xb - xa) * s,
            10.0 * s
        );
    }
    for (p, label) in [(ledge::START_GROUND, "start"), (ledge::GOAL_GROUND, "goal"), (root, "root anchor")] {
        let (cx, cy) = (px(p[0]).clamp(0.0, w), py(p[1]));
        let _ = writeln!(svg, r##"<circle cx="{cx:.1}" cy="{cy:.1}" r="6" fill="#1f77b4" stroke="#fff"/>"##);
        let _ = writeln!(svg, r#"<text x="{:.1}" y="{:.1}" font-size="14" font-family="sans-serif">{label}</text>"#, cx + 8.0, cy - 8.0);
    }
    let _ = writeln!(
        svg,
        r#"<text x="8" y="{:.1}" font-size="10" font-family="sans-serif">ledge55, root anchor ({:.2}, {:.2}, {:.2}), yaw {} deg: green stable, red unstable, grey no settle; slope face {}/{} cells stable</text>"#,
        hgt + 28.0,
        root[0],
        root[1],
        root[2],
        args.yaw_deg,
        slope_stable,
        slope.len()
    );
    svg.push_str("</svg>\n");
    if let Err(e) = std::fs::write(&args.out, svg) {
        return super::fail(format!("writing {}: {e}", args.out.display()));
    }
    println!(
        "stability map of ledge55 for root anchor ({:.2}, {:.2}, {:.2}): {} cells ({} stable, {} unstable, {} no settle); \
         slope face {}/{} stable; {:.2} s ({:.0} us/cell); wrote {}",
        root[0],
        root[1],
        root[2],
        cells.len(),
        count(Cell::Stable),
        count(Cell::Unstable),
        count(Cell::NoSettle),
        slope_stable,
        slope.len(),
        elapsed.as_secs_f64(),
        elapsed.as_secs_f64() * 1e6 / cells.len() as f64,
        args.out.display()
    );
    ExitCode::SUCCESS
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn root_argument_is_parsed_or_rejected_with_a_reason() {
        assert_eq!(parse_root("test1"), Ok(ledge::ROOT_ANCHOR_TEST1));
        assert_eq!(parse_root("1,2,3.5"), Ok([1.0, 2.0, 3.5]));
        assert!(parse_root("1,2").is_err_and(|e| e.contains("three")));
        assert!(parse_root("a,b,c").is_err_and(|e| e.contains("expected")));
    }

    #[test]
    fn direct_descent_is_stable_for_test1_and_not_for_test2() {
        let w = LedgeWorld::new();
        assert_eq!(evaluate(&w, ledge::ROOT_ANCHOR_TEST1, 1.5, 0.0, 0.0), Cell::Stable);
        assert_eq!(evaluate(&w, ledge::ROOT_ANCHOR_TEST2, 1.5, 0.0, 0.0), Cell::Unstable);
    }
}
