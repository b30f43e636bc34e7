//! The physics judge and the general true tether across crates: DEM renderings of the ledge judged like the
//! analytic ledge, and the DEM "truth" regression (issue 19).

use firmware::config::rover::RoverParams;
use firmware::geom::Real;
use firmware::plan::tethered::{PlanBounds, TetherSpace, TetherSpaceParams};
use host_sim::campaign::Truth;
use host_sim::terrain::Heightmap;
use host_sim::world::heightmap::HeightmapWorld;
use host_sim::world::ledge::{LedgeWorld, START_AXLE};

/// The ledge with the test-3 pole rendered as a DEM at `spacing` over x in [-11, 11], y in [-10, 10] (the grid is
/// centred on the origin, so the rendering keeps the ledge's coordinates).
fn dem_ledge_pole(spacing: f64) -> HeightmapWorld {
    let ledge = LedgeWorld::with_pole();
    let (nx, ny) = ((22.0 / spacing).round() as usize + 1, (20.0 / spacing).round() as usize + 1);
    let mut heights = Vec::with_capacity(nx * ny);
    for j in 0..ny {
        for i in 0..nx {
            heights.push(Some(ledge.height_f64(-11.0 + i as f64 * spacing, -10.0 + j as f64 * spacing)));
        }
    }
    HeightmapWorld::new("ledge_pole_dem", &Heightmap { width: nx, height: ny, spacing_m: spacing, heights_m: heights }, 1.0, 1.0)
        .expect("dem")
}

#[test]
fn regression_dem_rendering_of_the_ledge_settles_the_start_on_the_true_terrain() {
    let world = dem_ledge_pole(0.05);
    let truth = Truth(&world);
    let bounds = PlanBounds { min: [-5.0, -5.0, -0.5], max: [7.5, 5.0, 7.5] };
    let space = TetherSpace::new(&truth, bounds, RoverParams::AXEL, TetherSpaceParams::DEFAULT).expect("space");
    let s = space.settle_state(START_AXLE[0] as Real, START_AXLE[1] as Real, 0.0);
    assert!(s.is_ok(), "{s:?}");
}


#[test]
fn the_physics_judge_gives_the_same_verdicts_on_a_dem_rendering_of_the_ledge() {
    use host_sim::physics::{GroundPose, PhysicsJudge, TetherSpec};
    // A 0.05 m DEM (posts on x = 0, the lip) against the analytic ledge: the same poses, the same tethers.
    let dem = dem_ledge_pole(0.05);
    let exact = LedgeWorld::with_pole();
    let (jd, je) = (PhysicsJudge::new(&dem, RoverParams::AXEL).expect("dem"), PhysicsJudge::new(&exact, RoverParams::AXEL).expect("exact"));
    let lip = TetherSpec { anchor: [0.0, 0.0, 4.0], free_length_m: None };
    let slack = TetherSpec { anchor: [-6.4, 0.0, 6.35], free_length_m: Some(40.0) };
    let mut agree = 0;
    for (pose, tether) in [
        (GroundPose { x: 1.4, y: 0.0, yaw: 0.0 }, &lip),
        (GroundPose { x: 1.4, y: 0.0, yaw: 0.0 }, &slack),
        (GroundPose { x: -1.5, y: 0.0, yaw: 0.0 }, &slack),
        (GroundPose { x: 5.0, y: 1.0, yaw: 1.0 }, &slack),
    ] {
        let (a, b) = (jd.hold(pose, tether), je.hold(pose, tether));
        assert_eq!(a.outcome, b.outcome, "{pose:?}: DEM {a:?} vs analytic {b:?}");
        agree += 1;
    }
    assert_eq!(agree, 4);
}

#[test]
fn the_same_campaign_twice_gives_identical_json_minus_timings() {
    use host_sim::cli::campaign::{spec_from, CampaignArgs};
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                for k in ["first_time_s", "total_time_s", "wall_s", "map_build_s"] {
                    m.remove(k);
                }
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    let run = || {
        let spec = spec_from(&CampaignArgs {
            trials: Some(2),
            iterations: Some(1),
            threads: Some(2),
            field: "truth".into(),
            ..CampaignArgs::new("ledge_test1")
        })
        .expect("spec");
        let r = host_sim::campaign::run(&spec, &|_, _| {}).expect("campaign");
        assert_eq!(r.physics_judged(), 2, "{}", r.table());
        let mut v = serde_json::to_value(&r).expect("json");
        strip(&mut v);
        v
    };
    let (a, b) = (run(), run());
    assert!(a["trials"][0]["physics"]["poses"].as_u64().is_some_and(|n| n > 20), "{}", a["trials"][0]["physics"]);
    assert_eq!(a, b);
}
