//! The simulator's own truth during a mission: the true tether from the root anchor to the rover, the tension
//! the winch holds, the rover's static margin and whether the truth can hold the pose at all (a **fall**
//! otherwise), and the tether's sideways pull that makes the rover drift. None of this uses the flight software's
//! tether prediction or stability LP (`firmware::tether`, `firmware::stability`): the judge is independent.
//!
//! ## True tether
//! The general true tether ([`crate::truth::taut::TautTether`], the physics judge's) on every world: the terrain's
//! convex edges (a ledge's lip and back edge, a pole's side, a DEM's or a mesh's creases, a crater wall's rim) and
//! the present rocks' meshes, within the mission's tether region ([`MissionWorld::with_tether_region`]). Each
//! increment continues the previous increment's tether to the rover's new position ([`TautTether::update`]:
//! contacts caught, tightened, released), so it follows its homotopy class through any wrap (the loop round the
//! pole of Paton's test 3, then over the lip; round the side of a rock). From scratch ([`TautTether::shortest`])
//! at the first increment or when the update cannot go on. When a rock appears the edges are rebuilt and the
//! contacts carried over ([`TrueTether::carry_over`]).
//!
//! Only if the wrap edges cannot be built or neither gives a tether (the rover outside the tether region):
//! - on a ledge, [`crate::truth::tether`]'s closed forms (straight, over the lip or the back edge, around the pole
//!   in either wrap direction, at most half a turn), of which the candidate whose length and first contact are
//!   nearest the previous increment's is kept;
//! - elsewhere, the taut tether in the vertical plane through the root and the rover: the upper convex hull of the
//!   terrain profile under the segment (sampled every `PROFILE_STEP_M`), which cannot wrap round the side of
//!   anything.
//!
//! The tether ends at the axle centre (the boom's orifice is not modelled separately), as the flight software's
//! predicted payout does.
//!
//! ## Statics (the fall judge, interim)
//! The rover is one rigid body of mass `m` on its settled pose (normal `n`: the settled pose's up axis), pulled
//! by gravity and by the tether with tension `T` along `u` (from the axle to the last contact). The ground supplies
//! the contact force `C = -(T u + m g)`; it holds the pose when `N = C.n >= 0` and `|C - N n| <= mu N` (one
//! Coulomb cone for both wheels). The winch holds the tension that uses the least of the friction cone
//! (`argmin_T |C_t| / (mu N)` over `[pretension, winch_limit]`, a quasi-convex function, found by golden-section
//! search); the **margin** is `mu N - |C_t|` in newtons at that tension. A negative margin at the best tension is
//! a pose the truth cannot hold: a **fall**. (The rapier3d physics judge of `host-sim/src/physics/` will take over
//! this verdict.)
//!
//! ## Tether drift
//! The lateral component (along the axle) of the non-contact forces, `F_lat = (T u + m g).y`, is held by the
//! wheels' lateral traction `mu N`. While driving, the rover slips sideways by `drift_per_m * F_lat / (mu N)`
//! metres per metre driven, towards the pull (`[mission] drift_per_m`, default 0.15): no slip when the tether is
//! in line with the drive direction on a slope without side tilt, more the more the tether pulls across.

use firmware::geom::p3::{add_scaled, dist, dot, norm, scale, sub, P3};
use firmware::geom::Real;

use super::world::MissionWorld;
#[cfg(feature = "sim")]
use crate::truth::taut::{TautTether, WrapEdges, SHORTEST_SAMPLE_M};
use crate::truth::tether::{true_tether as ledge_tether, Wrap};
use crate::world::World;

/// Sampling step of the terrain profile under the tether, metres.
pub const PROFILE_STEP_M: f64 = 0.05;
/// How far across the tether region reaches beyond the box of the root, the start, the waypoints and the goal,
/// metres (`mission::run::truth_for`).
pub const TETHER_REGION_MARGIN_M: f64 = 10.0;

/// The true tether now.
#[derive(Debug, Clone, PartialEq)]
pub struct TrueTether {
    /// Contacts from the root to the rover (the root itself not included).
    pub contacts: Vec<P3>,
    /// Length from the root to the rover, metres.
    pub length_m: f64,
    /// The general true tether's state, which the next increment continues.
    pub taut: Option<TautState>,
}

/// The general true tether's state ([`crate::truth::taut`], built with the `sim` feature; without it there is none).
#[cfg(feature = "sim")]
pub type TautState = TautTether;
/// The general true tether's state (without the `sim` feature there is none).
#[cfg(not(feature = "sim"))]
pub type TautState = core::convert::Infallible;

impl TrueTether {
    /// The point the last straight piece leaves from.
    pub fn last_anchor(&self, root: P3) -> P3 {
        self.contacts.last().copied().unwrap_or(root)
    }

    /// The wrap edges changed from `old` to `new` (a rock appeared): the general tether's contacts move to the same
    /// edges in `new` (found by their ends, which the rebuild reproduces exactly); when one is not there, the state
    /// is dropped and the next increment starts from scratch.
    #[cfg(feature = "sim")]
    pub fn carry_over(&mut self, old: Option<&WrapEdges>, new: Option<&WrapEdges>) {
        let carried = match (self.taut.take(), old, new) {
            (Some(mut t), Some(old), Some(new)) => t
                .contacts
                .iter_mut()
                .all(|c| match old.edges.get(c.edge).and_then(|e| new.find(e)) {
                    Some(k) => {
                        c.edge = k;
                        true
                    }
                    None => false,
                })
                .then_some(t),
            _ => None,
        };
        self.taut = carried;
    }
}

/// The taut tether in the vertical plane through `root` and `end` over `world`'s height profile (module docs).
pub fn profile_tether(world: &dyn World, root: P3, end: P3) -> TrueTether {
    let (dx, dy) = (end[0] - root[0], end[1] - root[1]);
    let l = (dx * dx + dy * dy).sqrt();
    if l < 1e-6 {
        return TrueTether { contacts: vec![], length_m: dist(root, end), taut: None };
    }
    let n = (l / PROFILE_STEP_M).ceil() as usize;
    // (s, z) points: root, terrain samples strictly between, end
    let mut pts: Vec<(f64, f64)> = Vec::with_capacity(n + 2);
    pts.push((0.0, root[2]));
    for k in 1..n {
        let s = l * k as f64 / n as f64;
        let (x, y) = (root[0] + dx * s / l, root[1] + dy * s / l);
        if let Some(h) = world.height_at(x as Real, y as Real) {
            pts.push((s, f64::from(h)));
        }
    }
    pts.push((l, end[2]));
    // upper hull (monotone chain), left to right
    let mut hull: Vec<(f64, f64)> = Vec::with_capacity(pts.len());
    for p in pts {
        while hull.len() >= 2 {
            let (a, b) = (hull[hull.len() - 2], hull[hull.len() - 1]);
            // keep b only if it lies strictly above the segment a -> p
            let cross = (b.0 - a.0) * (p.1 - a.1) - (b.1 - a.1) * (p.0 - a.0);
            if cross >= 0.0 {
                hull.pop();
            } else {
                break;
            }
        }
        hull.push(p);
    }
    let to3 = |(s, z): (f64, f64)| [root[0] + dx * s / l, root[1] + dy * s / l, z];
    let chain: Vec<P3> = hull.iter().map(|p| to3(*p)).collect();
    let length_m = chain.windows(2).map(|w| dist(w[0], w[1])).sum();
    let contacts = chain.get(1..chain.len().saturating_sub(1)).unwrap_or(&[]).to_vec();
    TrueTether { contacts, length_m, taut: None }
}

/// The true tether from `root` to `end` (module docs); `prev` is the previous increment's, for continuity.
pub fn true_tether(world: &MissionWorld, root: P3, end: P3, prev: Option<&TrueTether>) -> TrueTether {
    #[cfg(feature = "sim")]
    if let Some(edges) = world.tether_edges() {
        // the general true tether: the previous increment's continued to `end`, else the shortest from scratch
        let continued = prev.and_then(|p| p.taut.clone()).and_then(|mut t| t.update(edges, end).ok().map(|()| t));
        if let Some(t) = continued.or_else(|| TautTether::shortest(edges, root, end, SHORTEST_SAMPLE_M).ok()) {
            let points = t.points(edges);
            let length_m = points.windows(2).map(|p| dist(p[0], p[1])).sum();
            let contacts = points.get(1..points.len().saturating_sub(1)).unwrap_or(&[]).to_vec();
            return TrueTether { contacts, length_m, taut: Some(t) };
        }
    }
    if let (Some(ledge), false) = (world.ledge(), world.has_present_rocks()) {
        let mut cands: Vec<TrueTether> = Vec::new();
        for wrap in [None, Some(Wrap::Ccw), Some(Wrap::Cw)] {
            if let Some(t) = ledge_tether(ledge, root, end, wrap) {
                cands.push(TrueTether { contacts: t.contacts, length_m: t.length, taut: None });
            }
        }
        // Continuity: the candidate whose length is nearest the previous one's, and, while both touch the terrain,
        // whose first contact is nearest the previous first contact. Right behind a pole both wrap directions have
        // almost the same length, and the tether cannot pass through the pole to its other side.
        let key = |t: &TrueTether| match prev {
            Some(p) => {
                let moved = match (t.contacts.first(), p.contacts.first()) {
                    (Some(a), Some(b)) => dist(*a, *b),
                    _ => 0.0,
                };
                (t.length_m - p.length_m).abs() + moved
            }
            None => t.length_m,
        };
        if let Some(best) = cands.into_iter().min_by(|a, b| key(a).total_cmp(&key(b))) {
            return best;
        }
    }
    profile_tether(&world.truth(), root, end)
}

/// The mass, friction and winch of the true rover.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Body {
    /// Total mass, kg.
    pub mass_kg: f64,
    /// Gravity, m/s^2.
    pub gravity: f64,
    /// Wheel-ground friction coefficient.
    pub mu: f64,
    /// Smallest tension the winch holds, N.
    pub pretension_n: f64,
    /// Largest tension before the winch or tether gives way, N.
    pub winch_limit_n: f64,
}

/// The statics of one pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Statics {
    /// The tension the winch holds, N.
    pub tension_n: f64,
    /// Friction reserve `mu N - |C_t|`, N (negative: the pose cannot be held).
    pub margin_n: f64,
    /// Normal force, N.
    pub normal_n: f64,
    /// Lateral (along-axle) non-contact force, N (positive towards the rover's +y, its left).
    pub lateral_n: f64,
    /// Lateral slip per metre driven (signed like `lateral_n`), m/m.
    pub drift_per_m: f64,
}

impl Statics {
    /// True when the truth holds the pose.
    pub fn holds(&self) -> bool {
        self.margin_n >= 0.0 && self.normal_n > 0.0
    }
}

/// The statics of a rover with up axis `n` and axle axis `y` (unit), tether direction `u` (unit, from the rover to
/// the last contact; zero vector when slack), for `body`; `drift_coeff` is `[mission] drift_per_m`.
pub fn statics(body: &Body, n: P3, y: P3, u: P3, drift_coeff: f64) -> Statics {
    let w = [0.0, 0.0, -body.mass_kg * body.gravity];
    let eval = |t: f64| {
        let ext = add_scaled(w, u, t);
        let c = scale(ext, -1.0);
        let normal = dot(c, n);
        let ct = norm(sub(c, scale(n, normal)));
        (normal, ct, ext)
    };
    let usage = |t: f64| {
        let (normal, ct, _) = eval(t);
        if normal <= 0.0 {
            f64::INFINITY
        } else {
            ct / (body.mu * normal)
        }
    };
    // golden-section search of the quasi-convex usage over [pretension, limit]
    let (mut a, mut b) = (body.pretension_n, body.winch_limit_n);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (usage(c), usage(d));
    for _ in 0..80 {
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = usage(c);
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = usage(d);
        }
    }
    let mut t = 0.5 * (a + b);
    // the ends of the interval (the search assumes an interior minimum)
    for end in [body.pretension_n, body.winch_limit_n] {
        if usage(end) < usage(t) {
            t = end;
        }
    }
    let (normal, ct, ext) = eval(t);
    let lateral = dot(ext, y);
    let traction = body.mu * normal.max(0.0);
    let drift = if traction > 0.0 { drift_coeff * lateral / traction } else { 0.0 };
    Statics { tension_n: t, margin_n: body.mu * normal - ct, normal_n: normal, lateral_n: lateral, drift_per_m: drift }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::ledge::LedgeWorld;

    const BODY: Body = Body { mass_kg: 45.0, gravity: 3.71, mu: 0.7, pretension_n: 20.0, winch_limit_n: 2000.0 };

    #[test]
    fn profile_tether_runs_over_the_lip_like_the_closed_form() {
        let w = LedgeWorld::new();
        let (root, rover) = ([-6.4, 0.0, 6.35], [1.5, 0.0, 2.2]);
        let hull = profile_tether(&w, root, rover);
        let closed = ledge_tether(&w, root, rover, None).expect("a tether exists");
        assert_eq!(hull.contacts.len(), 1, "{hull:?}");
        // the lip at x = 0, z = 4 (sampled every 5 cm: within one step of it)
        let c = hull.contacts[0];
        assert!(c[0].abs() <= PROFILE_STEP_M + 1e-9 && (c[2] - 4.0).abs() < 0.08, "{c:?}");
        assert!((hull.length_m - closed.length).abs() < 0.01, "{} vs {}", hull.length_m, closed.length);
        // a rover in sight of the root: straight, no contact
        let straight = profile_tether(&w, root, [-1.5, 0.0, 4.35]);
        assert!(straight.contacts.is_empty());
        assert!((straight.length_m - dist(root, [-1.5, 0.0, 4.35])).abs() < 1e-9);
    }

    /// Ledge test 3's world with the general true tether built over all of it.
    fn ledge3_world() -> MissionWorld {
        let base: Box<dyn crate::world::World> = Box::new(LedgeWorld::with_pole());
        let b = base.bounds();
        let f = |v: firmware::geom::Vec3| [f64::from(v.x), f64::from(v.y), f64::from(v.z)];
        let region = (f(b.min), f(b.max));
        MissionWorld::new(base, Some(LedgeWorld::with_pole()), Vec::new()).with_tether_region(region)
    }

    /// A rover passing behind the test-3 pole from its -y side, a few centimetres past the root-pole line and back:
    /// there both wrap directions have (nearly) the same length, and length continuity alone let the tether jump to
    /// the pole's other side (through the pole). It stays on the side it came from, and comes off the pole again.
    #[test]
    fn the_tether_behind_the_pole_stays_on_the_side_it_came_from() {
        let world = ledge3_world();
        let root = crate::world::ledge::ROOT_ANCHOR_TEST2;
        let path = [[-3.6, -0.8], [-3.9, -0.3], [-4.0, -0.05], [-4.0, 0.0], [-4.0, 0.03], [-4.0, 0.06], [-3.95, -0.2], [-3.9, -0.45], [-3.8, -0.9]];
        let mut prev: Option<TrueTether> = None;
        let mut wrapped = false;
        for [x, y] in path {
            let t = true_tether(&world, root, [x, y, 4.35], prev.as_ref());
            assert!(t.contacts.iter().all(|c| c[1] < 0.0), "at ({x}, {y}) the tether is on the pole's far side: {t:?}");
            wrapped |= !t.contacts.is_empty();
            prev = Some(t);
        }
        assert!(wrapped, "the path never wrapped the pole");
        assert!(prev.unwrap().contacts.is_empty(), "back on the -y side the tether comes off the pole");
    }

    /// Ledge-3 wrap's loop round the pole (behind it from its +y side, to its -y side, forward and over the lip),
    /// in 5 cm increments, the tether end 0.35 m above the true ground: the true tether stays round the back of the
    /// pole from its +y side to its -y side, and its length moves by at most what the end moved (a taut tether's
    /// length is 1-Lipschitz in its end). The closed-form candidates cannot hold the wrap with the lip and jumped by
    /// metres there (payout 12 -> 7.5 m in one 0.2 s reading).
    #[test]
    fn the_tether_stays_wrapped_round_the_pole_through_the_whole_loop() {
        let world = ledge3_world();
        let root = crate::world::ledge::ROOT_ANCHOR_TEST2;
        let corners: [[f64; 2]; 8] = [[-1.5, 0.0], [-1.8, 1.1], [-3.7, 1.4], [-4.2, 0.0], [-3.7, -1.4], [-1.0, -1.2], [-0.3, -0.8], [0.6, -0.6]];
        let (pole, radius) = (crate::world::ledge::POLE_CENTRE_XY, crate::world::ledge::POLE_RADIUS_M);
        let mut prev: Option<TrueTether> = None;
        let view = world.truth();
        let above = |x: f64, y: f64| {
            let h = crate::world::World::height_at(&view, x as Real, y as Real).expect("on the world");
            [x, y, f64::from(h) + 0.35]
        };
        let mut last_end = above(corners[0][0], corners[0][1]);
        for w in corners.windows(2) {
            let (a, b) = (w[0], w[1]);
            let n = ((b[0] - a[0]).hypot(b[1] - a[1]) / 0.05).ceil() as usize;
            for k in 1..=n {
                let f = k as f64 / n as f64;
                let end = above(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1]));
                let t = true_tether(&world, root, end, prev.as_ref());
                if let Some(p) = &prev {
                    let moved = dist(end, last_end);
                    assert!((t.length_m - p.length_m).abs() <= moved + 1e-3, "length jumped at {end:?}: {p:?} -> {t:?}");
                }
                prev = Some(t);
                last_end = end;
            }
        }
        let t = prev.expect("a tether");
        let on_pole: Vec<&P3> = t.contacts.iter().filter(|c| ((c[0] - pole[0]).hypot(c[1] - pole[1]) - radius).abs() < 0.01).collect();
        // round the back of the pole (its -x side, away from the root) from its +y side to its -y side
        let side = |sign: f64| on_pole.iter().any(|c| sign * (c[1] - pole[1]) > 0.8 * radius);
        assert!(side(1.0) && side(-1.0) && on_pole.iter().any(|c| c[0] < pole[0] - 0.8 * radius), "not wrapped: {t:?}");
    }

    /// The rim of a crater wall (rim at z = 1.5 m for x < 0) with a tall spherical rock (radius 1 m, centre on the
    /// rim's surface at (-2, 0)) between a low root and the rover, and a small rock on the wall far from the tether
    /// that appears after 1 m; the rocks listed with the late one first, so its appearance moves every edge of the
    /// tall rock in the list.
    fn rim_with_a_tall_rock() -> MissionWorld {
        let params = crate::world::crater::CraterWallParams {
            rim_height_m: 1.5,
            wall_angle_deg: 35.0,
            rim_length_m: 5.0,
            floor_length_m: 7.0,
            width_m: 8.0,
            rocks: 0,
            ..Default::default()
        };
        let base: Box<dyn World> = Box::new(crate::world::crater::CraterWall::new(params).expect("crater"));
        use super::super::params::ObstacleSpec as Rock;
        let rocks = vec![
            Rock { centre: [2.0, 3.0, 0.3], radius_m: 0.2, appears_after_m: 1.0, visible: true },
            Rock { centre: [-2.0, 0.0, 1.5], radius_m: 1.0, appears_after_m: 0.0, visible: true },
        ];
        let region = ([-5.0, -4.0, f64::NEG_INFINITY], [6.0, 4.0, f64::INFINITY]);
        MissionWorld::new(base, None, rocks).with_tether_region(region)
    }

    /// The rover drives across behind a rock too tall for the tether to pass over (root 1.8 m, rock top 2.5 m):
    /// the true tether is caught on the rock's side and stays there (the vertical-profile tether, the truth on such
    /// worlds before, runs over the rock's top instead), the rock that appears meanwhile leaves it where it was,
    /// and driving back unwraps it; its length never moves by more than the rover did.
    #[test]
    fn the_tether_wraps_round_the_side_of_a_tall_rock_and_unwraps() {
        let mut world = rim_with_a_tall_rock();
        let root = [-4.0, 0.0, 1.8];
        let (centre, radius) = ([-2.0, 0.0, 1.5], 1.0);
        let on_rock = |c: &P3| (dist(*c, centre) - radius).abs() < 0.05;
        let mut prev: Option<TrueTether> = None;
        let mut driven = 0.0;
        let mut appeared = false;
        let mut step = |world: &mut MissionWorld, prev: &mut Option<TrueTether>, y: f64| {
            let end = [-0.5, y, 1.85];
            let t = true_tether(world, root, end, prev.as_ref());
            assert!(t.taut.is_some(), "the general tether fell back at y = {y}");
            if let Some(p) = prev.as_ref() {
                assert!((t.length_m - p.length_m).abs() <= 0.05 + 1e-3, "length jumped at y = {y}: {p:?} -> {t:?}");
                driven += 0.05;
            }
            *prev = Some(t);
            if let Some(t) = prev.as_mut() {
                let before = t.clone();
                if world.advance(driven, t) > 0 {
                    // carried over to the rebuilt edges: the same points, on edges that moved in the list
                    let (edges, taut) = (world.tether_edges().expect("edges"), t.taut.as_ref().expect("carried over"));
                    let p = taut.points(edges);
                    assert_eq!(p.get(1..p.len() - 1), Some(&before.contacts[..]), "{before:?} -> {t:?}");
                    assert_ne!(taut.contacts, before.taut.as_ref().expect("taut").contacts, "the edges did not move");
                    appeared = true;
                }
            }
        };
        for k in 0..=64 {
            step(&mut world, &mut prev, -2.0 + 0.05 * f64::from(k));
        }
        assert!(world.rocks().all(|(_, p)| p), "the late rock did not appear");
        let t = prev.clone().expect("a tether");
        assert!(!t.contacts.is_empty() && t.contacts.iter().all(on_rock), "not caught on the rock: {t:?}");
        // round the -y side (it rides up the sphere's flank, never over the 2.5 m top)
        assert!(t.contacts.iter().all(|c| c[1] < -0.2 && c[2] < 2.4), "not round the rock's -y side: {t:?}");
        let over = profile_tether(&world.truth(), root, [-0.5, 1.2, 1.85]);
        assert!(over.contacts.iter().any(|c| c[2] > 1.95), "the profile tether should pass over the top: {over:?}");
        assert!(t.length_m > dist(root, [-0.5, 1.2, 1.85]) + 0.3, "{t:?}");
        for k in (0..64).rev() {
            step(&mut world, &mut prev, -2.0 + 0.05 * f64::from(k));
        }
        assert!(appeared, "the late rock's appearance was not seen by the tether");
        let back = prev.expect("a tether");
        assert!(back.contacts.is_empty(), "back where it started the tether is straight again: {back:?}");
    }

    #[test]
    fn statics_hold_on_a_slope_with_the_tether_and_fail_without_it() {
        let s = 40f64.to_radians();
        // a 40-degree slope falling towards +x; rover facing downhill, its y axis horizontal
        let n = [s.sin(), 0.0, s.cos()];
        let y = [0.0, 1.0, 0.0];
        let uphill = [-s.cos(), 0.0, s.sin()];
        let held = statics(&BODY, n, y, uphill, 0.15);
        assert!(held.holds(), "{held:?}");
        // the tether carries the downslope weight: m g sin(40) ~ 107 N
        assert!((held.tension_n - 45.0 * 3.71 * s.sin()).abs() < 2.0, "{held:?}");
        assert!(held.drift_per_m.abs() < 1e-9);
        // without a tether (slack: zero direction) 40 degrees exceed atan(0.7) = 35 degrees
        let slack = statics(&BODY, n, y, [0.0, 0.0, 0.0], 0.15);
        assert!(!slack.holds(), "{slack:?}");
        // a tether pulling across the drive direction makes the rover drift towards it
        let across = [-s.cos() * 0.7, 0.7, s.sin() * 0.7];
        let l = norm(across);
        let side = statics(&BODY, n, y, scale(across, 1.0 / l), 0.15);
        assert!(side.drift_per_m > 0.0 && side.lateral_n > 0.0, "{side:?}");
    }
}
