//! `tetherbot judge-agreement SCENARIO --poses N`: the flight software's stability verdict against the physics
//! judge (issue 19's agreement study; figures in `host-sim/doc/physics_judge.md`).
//!
//! Poses: `N` points drawn uniformly (seeded PCG) over the scenario's planning bounds in x, y, each with a yaw
//! uniform in [-pi, pi) (the settler's yaw about the surface normal). For each pose:
//! - the **planner**, on the onboard map (voxel `--voxel`, 0.1 m, as `campaign` builds it) and on the exact field:
//!   `TetherSpace::settle_state` then `stable_with` (the LP with the planner's minimum margin) with the anchor
//!   history root + the true tether's contacts; verdicts *stable*, *unstable*, *no settle*;
//! - the **physics judge** at the planner's settled pose (axle x, y and the axle's direction, converted by
//!   `PhysicsJudge::heading_for_axle`; the yaw itself where the planner does not settle), with the true tether
//!   ([`crate::truth::taut`]) to the boom tip: *holds*, *falls*, *blocked* (cannot be placed), or *no tether*.
//!
//! Output: a confusion matrix per field, the count of planner-stable poses that fall (must be 0 for poses whose
//! margin is at least the planner's minimum margin: `stable` means exactly that), how conservative the planner is
//! (physics holds, planner refuses), the judge's throughput, and `--out` JSON with every pose.

use std::path::PathBuf;
use std::time::Instant;

use firmware::config::rover::RoverParams;
use firmware::geom::p3::to_vec3;
use firmware::geom::Real;
use firmware::map::DistanceField;
use firmware::plan::tethered::{PlanBounds, RoverState, TetherSpace, TetherSpaceParams};
use firmware::tether::{Anchor, AnchorHistory};
use rand_core::{Rng, SeedableRng};
use serde::Serialize;

use crate::campaign::{PlanningMap, Truth};
use crate::mission::params::ObstacleSpec;
use crate::mission::world::MissionWorld;
use crate::world::World;
use crate::physics::{BoomSetting, GroundPose, HoldOutcome, PhysicsJudge, TetherSpec};
use crate::truth::taut::{TautTether, WrapEdges, SHORTEST_SAMPLE_M};

/// With `--region`, how far the maps reach beyond it (m): the rover's footprint and settling neighbourhood.
const REGION_MARGIN_M: f64 = 3.0;

/// Arguments of `judge-agreement`.
#[derive(Debug, Clone, clap::Args)]
pub struct JudgeAgreementArgs {
    /// A scenario name from `host-sim/scenarios/` or a path to a `.toml` scenario.
    pub scenario: String,
    /// Poses to judge.
    #[arg(long, default_value_t = 200)]
    pub poses: usize,
    /// Seed of the pose sampler.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Voxel edge of the planning map, metres.
    #[arg(long, default_value_t = 0.1)]
    pub voxel: f64,
    /// Write every pose's verdicts here (JSON).
    #[arg(long, short)]
    pub out: Option<PathBuf>,
    /// Print how both judges saw these poses (indices in the sampled order, e.g. `--explain 12,40`): the planner's
    /// settled wheel contacts, its stability answer and boom, and each physics boom setting's placement and motion.
    #[arg(long, value_delimiter = ',')]
    pub explain: Vec<usize>,
    /// Draw the poses' x, y in this rectangle instead of the planning bounds (`x0,y0,x1,y1`, metres; e.g. around a
    /// mission's goal to see why the planner refuses it).
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    pub region: Option<Vec<f64>>,
    /// Every pose with this yaw (degrees) instead of a uniform one.
    #[arg(long, allow_hyphen_values = true)]
    pub yaw: Option<f64>,
}

/// The planner's verdict on a pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum PlannerVerdict {
    /// Settles and is stable with at least the minimum margin.
    Stable,
    /// Settles, not stable.
    Unstable,
    /// Does not settle (no surface, collision, steep contact, unknown space, ...).
    NoSettle,
}

/// The physics judge's verdict on a pose.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub enum PhysicsVerdict {
    /// Holds.
    Holds,
    /// Slides or tips.
    Falls,
    /// Cannot be placed.
    Blocked,
    /// No true tether to the pose.
    NoTether,
}

/// One pose of the study.
#[derive(Debug, Clone, Serialize)]
pub struct PoseRecord {
    /// Sampled ground x, y and settler yaw.
    pub sample: [f64; 3],
    /// Planner on the onboard map.
    pub map: PlannerVerdict,
    /// Planner on the exact field.
    pub exact: PlannerVerdict,
    /// The planner's margin on the exact field (when it settles and the LP answers).
    pub exact_margin: Option<f64>,
    /// Physics judge.
    pub physics: PhysicsVerdict,
    /// Physics: largest slide, metres.
    pub slide_m: f64,
    /// Physics: the axle centre where the judge set the rover down (`None`: it could not be placed).
    pub physics_axle: Option<[f64; 3]>,
}

/// A 3 x 4 confusion matrix: planner (stable, unstable, no settle) x physics (holds, falls, blocked, no tether).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Confusion(pub [[usize; 4]; 3]);

impl Confusion {
    fn add(&mut self, p: PlannerVerdict, q: PhysicsVerdict) {
        let i = match p {
            PlannerVerdict::Stable => 0,
            PlannerVerdict::Unstable => 1,
            PlannerVerdict::NoSettle => 2,
        };
        let j = match q {
            PhysicsVerdict::Holds => 0,
            PhysicsVerdict::Falls => 1,
            PhysicsVerdict::Blocked => 2,
            PhysicsVerdict::NoTether => 3,
        };
        self.0[i][j] += 1;
    }

    /// As a markdown table.
    pub fn table(&self, title: &str) -> String {
        let mut s = format!("{title}\n| planner \\ physics | holds | falls | blocked | no tether |\n|---|---|---|---|---|\n");
        for (name, row) in ["stable", "unstable", "no settle"].iter().zip(self.0.iter()) {
            s += &format!("| {name} | {} | {} | {} | {} |\n", row[0], row[1], row[2], row[3]);
        }
        s
    }
}

/// The study's result.
#[derive(Debug, Clone, Serialize)]
pub struct Agreement {
    /// Scenario name.
    pub name: String,
    /// Poses.
    pub poses: Vec<PoseRecord>,
    /// Planner on the map against physics.
    pub map: Confusion,
    /// Planner on the exact field against physics.
    pub exact: Confusion,
    /// Seconds spent in the physics judge (tether included).
    pub physics_s: f64,
}

fn planner_verdict<D: DistanceField>(space: &TetherSpace<'_, D>, x: f64, y: f64, yaw: f64, hist: &AnchorHistory) -> (PlannerVerdict, Option<RoverState>, Option<f64>) {
    match space.settle_state(x as Real, y as Real, yaw as Real) {
        Err(e) => {
            if std::env::var_os("TETHERBOT_SETTLE_WHY").is_some() {
                eprintln!("no settle at ({x:.3}, {y:.3}, yaw {yaw:.3}): {e:?}");
            }
            (PlannerVerdict::NoSettle, None, None)
        }
        Ok(s) => match space.stable_with(&s.settled, hist) {
            Ok(m) => (PlannerVerdict::Stable, Some(s), Some(m)),
            Err(_) => (PlannerVerdict::Unstable, Some(s), None),
        },
    }
}

/// `--explain`: both judges' view of one pose, printed.
#[allow(clippy::too_many_arguments)] // a print helper: both judges and the pose, as the study holds them
fn explain<D: DistanceField>(
    index: usize,
    space: &TetherSpace<'_, D>,
    map: &D,
    rover: &RoverParams,
    judge: &PhysicsJudge,
    sample: (f64, f64, f64),
    pose: GroundPose,
    hist: &AnchorHistory,
    anchor: Option<[f64; 3]>,
) {
    let f = |v: firmware::geom::Vec3| format!("({:.3}, {:.3}, {:.3})", v.x, v.y, v.z);
    println!("pose {index}: sample ({:.3}, {:.3}, yaw {:.3}); physics pose ({:.3}, {:.3}, heading {:.3})", sample.0, sample.1, sample.2, pose.x, pose.y, pose.yaw);
    println!("  anchor history: {}", hist.as_slice().iter().map(|a| f(a.point)).collect::<Vec<_>>().join(" -> "));
    match space.settle_state(sample.0 as Real, sample.1 as Real, sample.2 as Real) {
        Err(e) => println!("  planner: no settle ({e:?})"),
        Ok(s) => {
            let st = &s.settled;
            println!("  planner axle {} heading {:.3} roll {:.3}", f(st.pose.translation.vector), s.heading(), st.roll_rad);
            for (w, name) in st.wheels.iter().zip(["left", "right"]) {
                let slope = libm::acosf(w.normal.z.clamp(-1.0, 1.0)).to_degrees();
                println!("  planner {name} wheel contact {} normal {} ({slope:.1} deg) gap {:.4}", f(w.point), f(w.normal), w.gap_m);
            }
            let pull = firmware::plan::tethered::tether_pull_anchor(st, hist, rover);
            let r = firmware::rover::check_pose_stability(map, st, pull.as_ref(), rover);
            println!("  planner pull anchor {:?}: {r:?}", pull.map(f));
        }
    }
    let Some(anchor) = anchor else {
        println!("  physics: no true tether");
        return;
    };
    for boom in crate::physics::BOOM_SETTINGS {
        let v = judge.hold_with(pose, &TetherSpec { anchor, free_length_m: None }, boom);
        print!("  physics {boom:?}: {:?} slide {:.3} m tilt {:.2} deg end speed {:.4} m/s", v.outcome, v.slide_m, v.tilt_deg, v.end_speed_mps);
        if let Some(p) = v.placement {
            print!("; axle ({:.3}, {:.3}, {:.3}) axle dir ({:.3}, {:.3}, {:.3}) boom {:.1} deg tip ({:.3}, {:.3}, {:.3})", p.axle[0], p.axle[1], p.axle[2], p.axle_dir[0], p.axle_dir[1], p.axle_dir[2], p.boom_angle.to_degrees(), p.tip[0], p.tip[1], p.tip[2]);
        }
        println!();
    }
}

/// Run the study.
pub fn run(a: &JudgeAgreementArgs) -> Result<Agreement, String> {
    let file = crate::cli::campaign::scenario_file(&a.scenario);
    let sc = crate::scenario::load(&file).map_err(|e| e.to_string())?;
    // the mission's rocks stand where they would once they appear: the poses near them are the ones to judge
    let rocks = sc.mission.obstacles.iter().map(|o| ObstacleSpec { appears_after_m: 0.0, ..o.clone() }).collect();
    let mission_world = MissionWorld::new(sc.build_world().map_err(|e| e.to_string())?, None, rocks);
    let world = mission_world.truth();
    let world: &dyn World = &world;
    let wb = world.bounds();
    let mut lo = sc.plan.bounds_min.unwrap_or([f64::from(wb.min.x), f64::from(wb.min.y), f64::from(wb.min.z) - 1.0]);
    let mut hi = sc.plan.bounds_max.unwrap_or([f64::from(wb.max.x), f64::from(wb.max.y), f64::from(wb.max.z) + 1.0]);
    let (draw_lo, draw_hi) = match a.region.as_deref() {
        None => ([lo[0], lo[1]], [hi[0], hi[1]]),
        Some(&[x0, y0, x1, y1]) if [x0, y0, x1, y1].iter().all(|v| v.is_finite()) && x0 < x1 && y0 < y1 => ([x0, y0], [x1, y1]),
        Some(r) => return Err(format!("--region {r:?}: give four finite numbers x0,y0,x1,y1 with x0 < x1 and y0 < y1")),
    };
    if a.region.is_some() {
        // The maps cover the region with room for the rover's footprint, not the whole world.
        for k in 0..2 {
            lo[k] = lo[k].max(draw_lo[k] - REGION_MARGIN_M);
            hi[k] = hi[k].min(draw_hi[k] + REGION_MARGIN_M);
        }
    }
    let root = sc.tether.root_anchor;
    let bounds = PlanBounds { min: lo.map(|v| v as Real), max: hi.map(|v| v as Real) };
    let rover = RoverParams::AXEL;
    let params = TetherSpaceParams::DEFAULT;
    let box_lo = core::array::from_fn(|k| lo[k].min(root[k] - 1.0));
    let box_hi = core::array::from_fn(|k| hi[k].max(root[k] + 1.0));
    let mut map = PlanningMap::from_world(world, box_lo, box_hi, a.voxel)?;
    let view = map.view()?;
    let mut map_rover = rover;
    map_rover.body_clearance_m += a.voxel as Real;
    let mut map_params = params;
    map_params.surface_uncertainty_m = map_params.surface_uncertainty_m.max(0.5 * a.voxel as Real);
    let on_map = TetherSpace::new(&view, bounds, map_rover, map_params).map_err(|(f, r)| format!("{f}: {r}"))?;
    let truth = Truth(world);
    let on_truth = TetherSpace::new(&truth, bounds, rover, params).map_err(|(f, r)| format!("{f}: {r}"))?;
    let judge = PhysicsJudge::new(world, rover).map_err(|e| e.to_string())?;
    let edges = WrapEdges::new(&world.exact_geometry(), (box_lo.map(|v: f64| v - 1.0), box_hi.map(|v: f64| v + 1.0)))?;
    let mut rng = rand_pcg::Pcg64::seed_from_u64(a.seed);
    let mut unit = || (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
    let mut out = Agreement { name: sc.name.clone(), poses: Vec::with_capacity(a.poses), map: Confusion::default(), exact: Confusion::default(), physics_s: 0.0 };
    for _ in 0..a.poses {
        let (x, y) = (draw_lo[0] + (draw_hi[0] - draw_lo[0]) * unit(), draw_lo[1] + (draw_hi[1] - draw_lo[1]) * unit());
        let drawn = core::f64::consts::TAU * unit() - core::f64::consts::PI;
        let yaw = a.yaw.map_or(drawn, f64::to_radians);
        // Physics first: the true tether (to the boom tip) gives the planner its anchor history too.
        let t0 = Instant::now();
        let s = on_truth.settle_state(x as Real, y as Real, yaw as Real).ok();
        let pose = match s {
            Some(s) => {
                let a = s.axle();
                let (x, y) = (f64::from(a.x), f64::from(a.y));
                // handed over by its axle: a heading alone names another pose where the ground bends under it
                let axle = s.settled.pose.rotation * firmware::geom::Vec3::y();
                let yaw = judge.heading_for_axle(x, y, [axle.x, axle.y, axle.z].map(f64::from));
                GroundPose { x, y, yaw: yaw.unwrap_or(f64::from(s.heading())) }
            }
            None => GroundPose { x, y, yaw },
        };
        let mut anchor = root;
        let mut tether: Option<TautTether> = None;
        for _ in 0..2 {
            let Some(pl) = judge.place(pose, anchor, BoomSetting::Inline) else { break };
            tether = TautTether::shortest(&edges, root, pl.tip, SHORTEST_SAMPLE_M).ok();
            let Some(t) = &tether else { break };
            anchor = t.last_anchor(&edges);
        }
        let physics_axle = judge.axle_at(pose);
        let (physics, slide) = match &tether {
            _ if physics_axle.is_none() => (PhysicsVerdict::Blocked, 0.0),
            None => (PhysicsVerdict::NoTether, 0.0),
            Some(t) => {
                let v = judge.hold(pose, &TetherSpec { anchor: t.last_anchor(&edges), free_length_m: None });
                let p = match v.outcome {
                    HoldOutcome::Holds => PhysicsVerdict::Holds,
                    HoldOutcome::Falls => PhysicsVerdict::Falls,
                    HoldOutcome::Blocked => PhysicsVerdict::Blocked,
                };
                (p, v.slide_m)
            }
        };
        out.physics_s += t0.elapsed().as_secs_f64();
        let mut hist = AnchorHistory::new(Anchor::root(to_vec3(root)));
        if let Some(t) = &tether {
            for c in &t.contacts {
                if let Some(e) = edges.edges.get(c.edge) {
                    let _ = hist.push(Anchor { point: to_vec3(e.point(c.t)), gradient: to_vec3(e.out) });
                }
            }
        }
        let (m, _, _) = planner_verdict(&on_map, x, y, yaw, &hist);
        let (e, _, margin) = planner_verdict(&on_truth, x, y, yaw, &hist);
        if a.explain.contains(&out.poses.len()) {
            explain(out.poses.len(), &on_truth, &truth, &rover, &judge, (x, y, yaw), pose, &hist, tether.as_ref().map(|t| t.last_anchor(&edges)));
        }
        out.map.add(m, physics);
        out.exact.add(e, physics);
        out.poses.push(PoseRecord { sample: [x, y, yaw], map: m, exact: e, exact_margin: margin, physics, slide_m: slide, physics_axle });
    }
    if let Some(p) = &a.out {
        let json = serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?;
        std::fs::write(p, json).map_err(|e| format!("{}: {e}", p.display()))?;
    }
    Ok(out)
}

impl Agreement {
    /// The report.
    pub fn report(&self) -> String {
        let n = self.poses.len();
        let mut s = format!("judge agreement on {}: {n} poses\n\n", self.name);
        s += &self.map.table("planner on the onboard map vs physics");
        s += "\n";
        s += &self.exact.table("planner on the exact field vs physics");
        for (name, c) in [("map", &self.map), ("exact", &self.exact)] {
            let holds_refused = c.0[1][0] + c.0[2][0];
            let holds = c.0[0][0] + holds_refused;
            s += &format!(
                "\n{name}: planner-stable but physics falls: {}; physics holds but the planner refuses: {holds_refused} of {holds} holding poses\n",
                c.0[0][1]
            );
        }
        s += &format!("\nphysics judge: {:.1} poses per second ({:.2} s for {n} poses, tether included, one thread)\n", n as f64 / self.physics_s.max(1e-9), self.physics_s);
        s
    }
}

/// Run the command.
pub fn main(a: &JudgeAgreementArgs) -> std::process::ExitCode {
    super::printed(run(a).map(|r| r.report()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mission's rock (`mission_corridor_rock`: a 0.35 m sphere on the wall at (1.4, 0)) is in both judges'
    /// world, although it only appears mid-mission: poses drawn on top of it do not settle for the planner on the
    /// exact field, and the physics judge does not hold them. Without the rock they stand on the bare 35-degree
    /// wall, where every one of them settles.
    #[test]
    fn a_missions_rock_is_judged_where_it_will_stand() {
        let args = JudgeAgreementArgs {
            scenario: "mission_corridor_rock".into(),
            poses: 6,
            seed: 1,
            voxel: 0.1,
            out: None,
            explain: Vec::new(),
            region: Some(vec![1.35, -0.05, 1.45, 0.05]),
            yaw: None,
        };
        let a = run(&args).unwrap();
        assert_eq!(a.poses.len(), 6);
        // the same poses on the bare wall, as the judge would see them without the rock
        let sc = crate::scenario::load(&crate::cli::campaign::scenario_file("mission_corridor_rock")).unwrap();
        let bare = PhysicsJudge::new(&*sc.build_world().unwrap(), RoverParams::AXEL).unwrap();
        for p in &a.poses {
            assert_eq!(p.exact, PlannerVerdict::NoSettle, "{p:?}");
            // the rock blocks the rover or lifts it (a wheel perched on it), never the bare wall's pose
            let [x, y, yaw] = p.sample;
            let on_wall = bare.axle_at(GroundPose { x, y, yaw }).expect("the bare wall places every pose");
            match p.physics_axle {
                None => assert_eq!(p.physics, PhysicsVerdict::Blocked, "{p:?}"),
                Some(axle) => assert!(axle[2] > on_wall[2] + 0.05, "{p:?} against the bare wall's {on_wall:?}"),
            }
        }
    }
}
