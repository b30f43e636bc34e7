//! Scenario definitions for the homotopy planner (shared/SCENARIOS.md B and C).
//!
//! Scenario B (Abad-Manterola et al. VI, Figs. 11-13): a 20 m x 20 m tether-demand plane at alpha = 45 deg between
//! two tether-free planes (rim above y = 20, floor below y = 0), anchor a0 near the top edge, two convex obstacles,
//! goal g below; compact soil (mu_c = 0.65, theta_c = 40.5 deg) above the line y = 6, loose sand (mu_s = 0.25,
//! theta_s = 14.5 deg) below it. The geometry is ours (the paper gives no coordinates), laid out like Fig. 11: the
//! naive straight tether a0 -> g touches no obstacle but meets g at 24 deg from upslope, more than theta_s.
//!
//! Scenario C (Tanner et al. IV, Fig. 11): a plane with two triangular obstacles, a0 at the top, g at the bottom; the
//! online variants add, remove and move obstacles during the descent.

use firmware::plan::homotopy::geo::{pt, Pt};
use firmware::plan::homotopy::planes::{HoldModel, SoilMap};

/// A homotopy-planning scenario on one tether-demand plane.
#[derive(Clone, Debug)]
pub struct Scenario {
    /// Name.
    pub name: &'static str,
    /// Plane outline (plane frame, m; y upslope).
    pub plane: Vec<Pt>,
    /// Obstacles the rover's map holds before the descent.
    pub known: Vec<Vec<Pt>>,
    /// Obstacles that really exist (for the closed loop; equal to `known` when the map is right).
    pub truth: Vec<Vec<Pt>>,
    /// Root anchor a0.
    pub a0: Pt,
    /// Goal g.
    pub g: Pt,
    /// Holding model (slope, soils).
    pub model: HoldModel,
}

fn deg(d: f64) -> f64 {
    d.to_radians()
}

fn square(w: f64, h: f64) -> Vec<Pt> {
    vec![pt(0.0, 0.0), pt(w, 0.0), pt(w, h), pt(0.0, h)]
}

/// Scenario B: compact soil above y = 6, loose sand below.
pub fn scenario_b() -> Scenario {
    let o1 = vec![pt(10.0, 12.0), pt(8.6, 11.3), pt(9.6, 9.6)];
    let o2 = vec![pt(12.8, 7.0), pt(10.8, 5.2), pt(12.0, 4.4)];
    Scenario {
        name: "B",
        plane: square(20.0, 20.0),
        known: vec![o1.clone(), o2.clone()],
        truth: vec![o1, o2],
        a0: pt(4.0, 19.5),
        g: pt(12.0, 1.5),
        model: HoldModel::point_mass(
            deg(45.0),
            SoilMap { line_point: pt(0.0, 6.0), line_dir: pt(1.0, 0.0), mu_left: 0.65, mu_right: 0.25 },
        ),
    }
}

/// Scenario C: two triangular obstacles; firm soil (theta_max = 50 deg at alpha = 50 deg, mu = 0.91).
pub fn scenario_c() -> Scenario {
    let o1 = vec![pt(6.0, 14.0), pt(9.0, 11.0), pt(10.0, 15.0)];
    let o2 = vec![pt(11.0, 8.0), pt(14.0, 6.0), pt(14.5, 9.5)];
    Scenario {
        name: "C",
        plane: square(20.0, 20.0),
        known: vec![o1.clone(), o2.clone()],
        truth: vec![o1, o2],
        a0: pt(8.0, 19.5),
        g: pt(12.0, 1.5),
        model: HoldModel::point_mass(deg(50.0), SoilMap::uniform(0.91)),
    }
}

/// Scenario C online: the map misses a rock in the first sleeve (it appears), holds a phantom rock (it vanishes),
/// and has one rock 1.5 m off (it moved).
pub fn scenario_c_online() -> Scenario {
    let mut s = scenario_c();
    s.name = "C-online";
    let phantom = vec![pt(12.0, 16.0), pt(14.0, 16.0), pt(13.0, 17.8)];
    let moved_map = vec![pt(6.0, 3.5), pt(8.0, 3.5), pt(7.0, 5.5)];
    let moved_true = vec![pt(7.2, 2.2), pt(9.2, 2.2), pt(8.2, 4.2)];
    let hidden = vec![pt(9.0, 6.0), pt(11.5, 4.2), pt(11.8, 5.8)];
    s.known = vec![s.known[0].clone(), s.known[1].clone(), phantom, moved_map];
    s.truth = vec![s.truth[0].clone(), s.truth[1].clone(), moved_true, hidden];
    s
}

/// Uniform number in [0, 1) from a seeded generator.
pub fn unit<R: rand_core::Rng>(rng: &mut R) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// A random convex obstacle: 3-6 corners on a jittered circle of radius `r` around `c`.
pub fn random_convex<R: rand_core::Rng>(rng: &mut R, c: Pt, r: f64) -> Vec<Pt> {
    let n = 3 + (rng.next_u64() % 4) as usize;
    let phase = unit(rng) * core::f64::consts::TAU;
    (0..n)
        .map(|i| {
            let a = phase + core::f64::consts::TAU * (i as f64 + 0.35 * (unit(rng) - 0.5)) / n as f64;
            let rr = r * (0.7 + 0.3 * unit(rng));
            pt(c.x + rr * a.cos(), c.y + rr * a.sin())
        })
        .collect()
}

/// A random obstacle field on a `size` x `size` plane: `n` convex obstacles with disjoint bounding circles
/// (0.3 m apart), a0 near the top edge, g near the bottom edge, both outside every obstacle. Uniform soil
/// (`theta_max` = 50 deg at alpha = 50 deg).
pub fn random_field<R: rand_core::Rng>(rng: &mut R, n: usize, size: f64) -> Scenario {
    let mut circles: Vec<(Pt, f64)> = Vec::new();
    let a0 = pt(size * (0.2 + 0.6 * unit(rng)), size - 0.5);
    let g = pt(size * (0.2 + 0.6 * unit(rng)), 0.5);
    let mut obstacles = Vec::new();
    let mut tries = 0;
    while obstacles.len() < n && tries < 1000 {
        tries += 1;
        let r = size * (0.04 + 0.08 * unit(rng));
        let c = pt(r + 0.3 + (size - 2.0 * r - 0.6) * unit(rng), r + 1.2 + (size - 2.0 * r - 2.4) * unit(rng));
        let clear = circles.iter().all(|(o, ro)| o.dist(c) > r + ro + 0.3) && a0.dist(c) > r + 0.3 && g.dist(c) > r + 0.3;
        if clear {
            circles.push((c, r));
            obstacles.push(random_convex(rng, c, r));
        }
    }
    Scenario {
        name: "random",
        plane: square(size, size),
        known: obstacles.clone(),
        truth: obstacles,
        a0,
        g,
        model: HoldModel::point_mass(deg(50.0), SoilMap::uniform(0.91)),
    }
}
