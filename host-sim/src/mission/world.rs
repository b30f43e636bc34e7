//! The mission's true world: the scenario's terrain plus the `[mission]` section's rocks (spheres), each present
//! from the start or only after the rover has driven a given distance, and each seen by the range sensor or not.
//!
//! Two views of it implement [`World`]: [`TrueView`] (everything that exists now: what the rover settles on and the
//! tether wraps over) and [`SensorView`] (what the range sensor's rays hit: rocks with `visible = false` are left
//! out, so the onboard map never shows them). Signed distance of the union is the minimum of the parts (exact
//! outside the solids, a bound inside); ray casts take the nearest hit; `height_at` the highest top.

use firmware::geom::{Real, Vec3};
use firmware::map::{DistanceField, DistanceQuery};

use super::params::ObstacleSpec;
#[cfg(feature = "sim")]
use super::truth::TrueTether;
#[cfg(feature = "sim")]
use crate::truth::taut::WrapEdges;
use crate::world::ledge::LedgeWorld;
use crate::truth::solid::{ExactGeometry, Solid};
use crate::world::{Aabb, World};

/// The region the true tether's wrap edges are built in (min, max corners), metres.
pub type TetherRegion = ([f64; 3], [f64; 3]);

/// The scenario's terrain with the mission's rocks.
pub struct MissionWorld {
    base: Box<dyn World>,
    /// The same terrain as an analytic ledge, when it is one (the closed-form true tether needs it).
    ledge: Option<LedgeWorld>,
    /// Where the true tether's height-grid and mesh wrap edges are built: a DEM has millions of edges, and the
    /// tether touches only those near the root and the rover.
    #[cfg(feature = "sim")]
    tether_region: TetherRegion,
    /// The wrap edges of the terrain and the present rocks for the general true tether ([`crate::truth::taut`]),
    /// rebuilt when a rock appears (`None` when they cannot be built: the closed forms and the profile then stand
    /// alone).
    #[cfg(feature = "sim")]
    tether_edges: Option<WrapEdges>,
    rocks: Vec<ObstacleSpec>,
    present: Vec<bool>,
}

impl MissionWorld {
    /// Wraps `base`; `ledge` is the same world as a [`LedgeWorld`] when the scenario is a ledge. Rocks with
    /// `appears_after_m = 0` are present at once. No general true tether until [`MissionWorld::with_tether_region`].
    pub fn new(base: Box<dyn World>, ledge: Option<LedgeWorld>, rocks: Vec<ObstacleSpec>) -> Self {
        let present = rocks.iter().map(|r| r.appears_after_m <= 0.0).collect();
        MissionWorld {
            base,
            ledge,
            #[cfg(feature = "sim")]
            tether_region: ([0.0; 3], [0.0; 3]),
            #[cfg(feature = "sim")]
            tether_edges: None,
            rocks,
            present,
        }
    }

    /// The same world with the general true tether's wrap edges built in `region` (the height-grid and mesh edges
    /// that touch it; prism, cylinder and rock edges are all kept).
    #[cfg(feature = "sim")]
    #[must_use]
    pub fn with_tether_region(mut self, region: TetherRegion) -> Self {
        self.tether_region = region;
        self.build_tether_edges();
        self
    }

    #[cfg(feature = "sim")]
    fn build_tether_edges(&mut self) {
        self.tether_edges = WrapEdges::new(&self.exact_geometry_with(false), self.tether_region)
            .map_err(|e| log::warn!("mission truth: the wrap edges: {e}; the closed forms and the profile stand alone"))
            .ok();
    }

    /// The wrap edges of the terrain and the present rocks for the general true tether.
    #[cfg(feature = "sim")]
    pub fn tether_edges(&self) -> Option<&WrapEdges> {
        self.tether_edges.as_ref()
    }

    /// The analytic ledge, if the terrain is one.
    pub fn ledge(&self) -> Option<&LedgeWorld> {
        self.ledge.as_ref()
    }

    /// The base terrain.
    pub fn base(&self) -> &dyn World {
        self.base.as_ref()
    }

    /// The rocks and whether each is present now.
    pub fn rocks(&self) -> impl Iterator<Item = (&ObstacleSpec, bool)> {
        self.rocks.iter().zip(self.present.iter().copied())
    }

    /// True when some present rock exists (the closed-form ledge tether does not know rocks).
    pub fn has_present_rocks(&self) -> bool {
        self.present.iter().any(|p| *p)
    }

    /// Makes the rocks whose `appears_after_m` has been driven present; returns how many appeared now.
    fn appear(&mut self, driven_m: f64) -> usize {
        let mut n = 0;
        for (r, p) in self.rocks.iter().zip(self.present.iter_mut()) {
            if !*p && driven_m >= r.appears_after_m {
                *p = true;
                n += 1;
            }
        }
        n
    }

    /// Makes the rocks whose `appears_after_m` has been driven present; returns how many appeared now. The wrap
    /// edges are rebuilt with them, and `tether`'s contacts carried over to the new edges.
    #[cfg(feature = "sim")]
    pub fn advance(&mut self, driven_m: f64, tether: &mut TrueTether) -> usize {
        let n = self.appear(driven_m);
        if n > 0 && self.tether_edges.is_some() {
            let old = self.tether_edges.take();
            self.build_tether_edges();
            tether.carry_over(old.as_ref(), self.tether_edges.as_ref());
        }
        n
    }

    /// Makes the rocks whose `appears_after_m` has been driven present; returns how many appeared now.
    #[cfg(not(feature = "sim"))]
    pub fn advance(&mut self, driven_m: f64) -> usize {
        self.appear(driven_m)
    }

    /// What the rover and the tether meet.
    pub fn truth(&self) -> TrueView<'_> {
        TrueView(self)
    }

    /// What the range sensor sees.
    pub fn sensed(&self) -> SensorView<'_> {
        SensorView(self)
    }

    fn query_with(&self, p: &Vec3, sensor: bool) -> DistanceQuery {
        let mut best = self.base.query(p);
        for (r, present) in self.rocks() {
            if !present || (sensor && !r.visible) {
                continue;
            }
            let c = Vec3::new(r.centre[0] as Real, r.centre[1] as Real, r.centre[2] as Real);
            let d = p - c;
            let n = d.norm();
            let dist = n - r.radius_m as Real;
            let better = match best {
                DistanceQuery::Known { distance, .. } => dist < distance,
                DistanceQuery::Unknown => true,
            };
            if better {
                let gradient = if n > 1e-6 { d / n } else { Vec3::z() };
                best = DistanceQuery::Known { distance: dist, gradient };
            }
        }
        best
    }

    fn raycast_with(&self, o: &Vec3, dir: &Vec3, max_range: Real, sensor: bool) -> Option<Real> {
        let mut best = self.base.raycast(o, dir, max_range);
        for (r, present) in self.rocks() {
            if !present || (sensor && !r.visible) {
                continue;
            }
            let c = Vec3::new(r.centre[0] as Real, r.centre[1] as Real, r.centre[2] as Real);
            // |o + t d - c| = r, smallest t >= 0
            let oc = o - c;
            let b = oc.dot(dir);
            let q = oc.dot(&oc) - (r.radius_m * r.radius_m) as Real;
            let disc = b * b - q;
            if disc < 0.0 {
                continue;
            }
            let t = -b - disc.sqrt();
            if t >= 0.0 && t <= max_range && best.is_none_or(|bt| t < bt) {
                best = Some(t);
            }
        }
        best
    }

    fn height_with(&self, x: Real, y: Real, sensor: bool) -> Option<Real> {
        let mut h = self.base.height_at(x, y);
        for (r, present) in self.rocks() {
            if !present || (sensor && !r.visible) {
                continue;
            }
            let (dx, dy) = (x as f64 - r.centre[0], y as f64 - r.centre[1]);
            let d2 = dx * dx + dy * dy;
            if d2 < r.radius_m * r.radius_m {
                let top = (r.centre[2] + (r.radius_m * r.radius_m - d2).sqrt()) as Real;
                h = Some(h.map_or(top, |v| v.max(top)));
            }
        }
        h
    }
}

/// Sectors and rings of the closed mesh that stands for a spherical rock in [`MissionWorld::exact_geometry_with`].
const ROCK_MESH_SECTORS: u32 = 16;
const ROCK_MESH_RINGS: u32 = 8;

/// A closed UV-sphere mesh (counter-clockwise seen from outside) inscribed in the sphere: its vertices lie on the
/// sphere, so its faces are at most `r (1 - cos(pi / 16))`, 2 % of the radius, inside it.
fn sphere_mesh(c: [f64; 3], r: f64) -> Solid {
    let (ns, nr) = (ROCK_MESH_SECTORS, ROCK_MESH_RINGS);
    let mut vertices = vec![[c[0], c[1], c[2] + r]];
    for i in 1..nr {
        let th = core::f64::consts::PI * f64::from(i) / f64::from(nr);
        for j in 0..ns {
            let ph = 2.0 * core::f64::consts::PI * f64::from(j) / f64::from(ns);
            vertices.push([c[0] + r * th.sin() * ph.cos(), c[1] + r * th.sin() * ph.sin(), c[2] + r * th.cos()]);
        }
    }
    let bottom = u32::try_from(vertices.len()).unwrap_or(u32::MAX);
    vertices.push([c[0], c[1], c[2] - r]);
    let at = |ring: u32, j: u32| 1 + (ring - 1) * ns + j % ns;
    let mut triangles = Vec::new();
    for j in 0..ns {
        triangles.push([0, at(1, j), at(1, j + 1)]);
        triangles.push([bottom, at(nr - 1, j + 1), at(nr - 1, j)]);
        for ring in 1..nr - 1 {
            triangles.push([at(ring, j), at(ring + 1, j), at(ring + 1, j + 1)]);
            triangles.push([at(ring, j), at(ring + 1, j + 1), at(ring, j + 1)]);
        }
    }
    Solid::Mesh { vertices, triangles }
}

impl MissionWorld {
    /// The terrain's exact geometry plus every present rock as a closed mesh inscribed in its sphere ([`sphere_mesh`]);
    /// with `sensor`, only the rocks the sensor sees.
    fn exact_geometry_with(&self, sensor: bool) -> ExactGeometry {
        let mut g = self.base.exact_geometry();
        for (r, present) in self.rocks() {
            if present && (r.visible || !sensor) {
                g.solids.push(sphere_mesh(r.centre, r.radius_m));
            }
        }
        g
    }
}

/// Everything that exists now (see the module docs).
pub struct TrueView<'a>(&'a MissionWorld);
/// What the range sensor sees (see the module docs).
pub struct SensorView<'a>(&'a MissionWorld);

macro_rules! view {
    ($t:ident, $sensor:expr) => {
        impl DistanceField for $t<'_> {
            fn query(&self, p: &Vec3) -> DistanceQuery {
                self.0.query_with(p, $sensor)
            }
        }
        impl World for $t<'_> {
            fn name(&self) -> &str {
                self.0.base.name()
            }
            fn bounds(&self) -> Aabb {
                self.0.base.bounds()
            }
            fn raycast(&self, origin: &Vec3, dir: &Vec3, max_range: Real) -> Option<Real> {
                self.0.raycast_with(origin, dir, max_range, $sensor)
            }
            fn height_at(&self, x: Real, y: Real) -> Option<Real> {
                self.0.height_with(x, y, $sensor)
            }
            fn exact_geometry(&self) -> ExactGeometry {
                self.0.exact_geometry_with($sensor)
            }
        }
    };
}
view!(TrueView, false);
view!(SensorView, true);

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_rock_mesh_is_closed_and_on_its_sphere() {
        let Solid::Mesh { vertices, triangles } = sphere_mesh([1.0, 2.0, 3.0], 0.5) else { panic!("not a mesh") };
        for v in &vertices {
            let d = ((v[0] - 1.0).powi(2) + (v[1] - 2.0).powi(2) + (v[2] - 3.0).powi(2)).sqrt();
            assert!((d - 0.5).abs() < 1e-12, "vertex {v:?} off the sphere");
        }
        // closed and consistently oriented: every directed edge appears once, and its reverse once
        let mut edges = std::collections::BTreeMap::new();
        for t in &triangles {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1, "edge {a}-{b} used {n} times in one direction");
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no opposite");
        }
        // outward: the signed volume is positive and near the sphere's
        let vol: f64 = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| vertices[i as usize]);
                let a = [a[0] - 1.0, a[1] - 2.0, a[2] - 3.0];
                let b = [b[0] - 1.0, b[1] - 2.0, b[2] - 3.0];
                let c = [c[0] - 1.0, c[1] - 2.0, c[2] - 3.0];
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) + a[2] * (b[0] * c[1] - b[1] * c[0])) / 6.0
            })
            .sum();
        let sphere = 4.0 / 3.0 * core::f64::consts::PI * 0.125;
        assert!(vol > 0.9 * sphere && vol < sphere, "volume {vol} vs sphere {sphere}");
    }

    fn world() -> MissionWorld {
        let rocks = vec![
            ObstacleSpec { centre: [3.0, 0.0, 0.0], radius_m: 0.5, appears_after_m: 0.0, visible: false },
            ObstacleSpec { centre: [5.0, 0.0, 0.0], radius_m: 0.4, appears_after_m: 2.0, visible: true },
        ];
        MissionWorld::new(Box::new(LedgeWorld::new()), Some(LedgeWorld::new()), rocks)
    }

    #[test]
    fn hidden_rocks_are_felt_not_seen_and_late_rocks_appear() {
        let mut w = world();
        let down = Vec3::new(0.0, 0.0, -1.0);
        let above = |x: Real| Vec3::new(x, 0.0, 2.0);
        // the invisible rock: the truth has it, the sensor's ray passes to the ground
        assert!((w.truth().raycast(&above(3.0), &down, 5.0).unwrap() - 1.5).abs() < 1e-5);
        assert!((w.sensed().raycast(&above(3.0), &down, 5.0).unwrap() - 2.0).abs() < 1e-5);
        assert!((w.truth().height_at(3.0, 0.0).unwrap() - 0.5).abs() < 1e-5);
        assert!(w.sensed().height_at(3.0, 0.0).unwrap().abs() < 1e-5);
        // the late rock is absent until 2 m are driven
        assert!((w.truth().raycast(&above(5.0), &down, 5.0).unwrap() - 2.0).abs() < 1e-5);
        let mut t = TrueTether { contacts: vec![], length_m: 0.0, taut: None };
        assert_eq!(w.advance(1.0, &mut t), 0);
        assert_eq!(w.advance(2.5, &mut t), 1);
        assert!((w.sensed().raycast(&above(5.0), &down, 5.0).unwrap() - 1.6).abs() < 1e-5);
        match w.truth().query(&Vec3::new(5.0, 0.0, 1.0)) {
            DistanceQuery::Known { distance, gradient } => {
                assert!((distance - 0.6).abs() < 1e-5);
                assert!((gradient.z - 1.0).abs() < 1e-5);
            }
            DistanceQuery::Unknown => panic!("the ledge world is known everywhere"),
        }
    }
}
