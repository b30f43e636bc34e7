//! The `homotopy_tile_*` workloads (`workloads::homotopy_tile`: the navigator's three homotopy planning phases on
//! the HiRISE scarp tile of `mission_homotopy_hirise.toml`), on the host: the tile the board embeds is the
//! scenario's, bit for bit, and the host run finds a route from the root anchor over the fold that fits the tether.
//!
//! Rewrite the board's embedded tile after the scenario or the terrain changed:
//! `HOMOTOPY_TILE_WRITE=1 cargo test --release -p tests --test board_homotopy_tile`.

use std::path::PathBuf;

use firmware::plan::homotopy::{Btm, Workspace};
use host_sim::homotopy::tile::hirise_tile;
use workloads::homotopy_tile::{self, TileStorage};
use workloads::Harness;

fn embedded_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../firmware/boards/mps2-an500/data/hirise_tile_80x80.f32le")
}

/// The board's `include_bytes!` tile is the scenario's tile (little-endian f32, row-major from the smallest y), and
/// the workload's constants are the scenario's.
#[test]
fn the_embedded_tile_is_the_scenarios_tile() {
    let (spec, heights) = hirise_tile().unwrap();
    assert_eq!(spec.origin, homotopy_tile::ORIGIN);
    assert_eq!(spec.resolution_m, homotopy_tile::RESOLUTION_M);
    assert_eq!(spec.posts, [homotopy_tile::POSTS as u16; 2]);
    assert_eq!(heights.len(), homotopy_tile::CELLS);
    assert!(heights.iter().all(|h| h.is_finite()), "the scenario's tile has posts off the terrain");
    let bytes: Vec<u8> = heights.iter().flat_map(|h| h.to_le_bytes()).collect();
    if std::env::var_os("HOMOTOPY_TILE_WRITE").is_some() {
        std::fs::write(embedded_path(), &bytes).unwrap();
    }
    let embedded = std::fs::read(embedded_path()).unwrap();
    assert!(embedded == bytes, "the board's tile differs from the scenario's: rewrite it (module docs)");
    let sc = host_sim::scenario::load(std::path::Path::new(host_sim::homotopy::tile::HIRISE_SCENARIO)).unwrap();
    let r = sc.tether.root_anchor;
    assert_eq!([r[0], r[1]], homotopy_tile::ROOT_ANCHOR);
    let g = sc.goal.position;
    assert_eq!([g[0], g[1]], homotopy_tile::GOAL);
}

struct Collect(Vec<(&'static str, String)>);

impl Harness for Collect {
    fn measure(&mut self, _: &'static str, work: &mut dyn FnMut()) {
        work()
    }
    fn result(&mut self, name: &'static str, summary: &str) {
        self.0.push((name, summary.to_owned()));
    }
}

/// The three phases on the host: the descent has several planes and a BTM, Axel holds within a real angle, and
/// Alg. 1's route from the root anchor crosses the fold onto the wall, within the 40 m tether, ending at the goal; two runs give the same summaries (the board is compared with them).
#[test]
fn the_host_run_finds_a_route_over_the_fold() {
    let (_, heights) = hirise_tile().unwrap();
    let run = || {
        let (mut store, mut btm, mut ws): (Box<TileStorage>, Box<Btm>, Box<Workspace>) =
            (Box::default(), Box::default(), Box::default());
        let mut h = Collect(Vec::new());
        let out = homotopy_tile::run(&mut store, &mut btm, &mut ws, &heights, &mut h);
        (out, h.0)
    };
    let (out, lines) = run();
    for (n, s) in &lines {
        println!("{n}: {s}");
    }
    assert_eq!(lines.iter().map(|(n, _)| *n).collect::<Vec<_>>(), [homotopy_tile::SEGMENT, homotopy_tile::HOLD, homotopy_tile::ROUTE]);
    assert!(out.planes >= 2, "{} planes", out.planes);
    assert!(out.triangles > 0);
    let theta = out.theta_max_rad.unwrap();
    assert!(theta > 0.0 && theta < core::f64::consts::PI, "{theta}");
    assert!(out.classes >= 1);
    let route = out.route.as_ref().expect("a route");
    // The mission's tile has no obstacle inside the corridor (two on its edge), so the route is the straight class
    // from the root anchor: no intermediate anchor, the tether broken once at the rim-wall fold.
    assert!(route.tether.len() >= 3, "the tether does not cross the fold: {:?}", route.tether);
    assert!(route.anchors.len() <= 1, "{:?}", route.anchors);
    assert!(route.tether_length_m > 5.0 && route.tether_length_m <= homotopy_tile::MAX_PAYOUT_M, "{}", route.tether_length_m);
    let last = route.waypoints.last().unwrap();
    let g = homotopy_tile::GOAL;
    assert!((last[0] - g[0]).hypot(last[1] - g[1]) < 0.05, "{last:?}");
    assert_eq!(run().1, lines);
}
