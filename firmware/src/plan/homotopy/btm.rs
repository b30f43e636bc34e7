//! Boundary Triangulated 2-Manifold (BTM) of a tether-demand plane minus its obstacles (Tanner et al.
//! Definition 1; Abad-Manterola et al. V-A, Fig. 7), with local retriangulation after map changes (Tanner Lemma 1,
//! Figs. 9-10) and an invariant checker.
//!
//! Every vertex of the BTM is a corner of the plane outline or of an obstacle (no Steiner points), so every vertex
//! is a boundary vertex and the reduced crossing sequence of a path is a canonical name of its homotopy class.
//!
//! Construction: greedy triangulation restricted to a region. All vertex pairs of the region whose open segment
//! lies in free space are sorted by length (ties by vertex ids, so the result is deterministic) and inserted when
//! they cross no edge already present; a maximal set of non-crossing free edges over the region's corners
//! triangulates it. A full build uses the whole plane as the region; an added obstacle uses the union of the
//! triangles it touches (the *affected region*); a removed obstacle uses the triangles incident to its corners
//! plus its hole (Lemma 1). Only edges with both ends in the region can cross a segment inside it, so a local
//! update costs O(r^2 (r + V)) for r region corners, against O(V^3) for a rebuild.
//!
//! Capacities ([`crate::config::homotopy`]): `MAX_VERTICES` (160), `MAX_TRIANGLES` (320), `MAX_DEGREE` (40),
//! `MAX_PLANE_VERTICES` (8), `MAX_OBSTACLES` (24), `MAX_OBSTACLE_VERTICES` (8), `MAX_CANDIDATE_EDGES` (V(V-1)/2).
//! The whole structure is ~0.3 MiB: the caller owns it (a `static` on the board, a `Box` on the host).

use super::geo::{
    ear_clip, orient, point_in_polygon, point_strictly_on_segment, polygon_area, polygon_edges, polygon_is_simple,
    polygons_overlap, segments_cross_properly, Pt, EPS,
};
use crate::config::homotopy::{
    MAX_CANDIDATE_EDGES, MAX_DEGREE, MAX_OBSTACLES, MAX_OBSTACLE_VERTICES, MAX_PLANE_VERTICES, MAX_TRIANGLES,
    MAX_VERTICES,
};
use heapless::Vec as HVec;

/// Index of a vertex or triangle; [`NONE`] marks "no such".
pub type Id = u16;
/// "No triangle / no vertex".
pub const NONE: Id = Id::MAX;

/// Which boundary a vertex belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Owner {
    /// Corner `corner` of the plane outline.
    Plane {
        /// Index in the outline.
        corner: u8,
    },
    /// Corner `corner` of obstacle `obstacle`.
    Obstacle {
        /// Obstacle slot.
        obstacle: u8,
        /// Index in the obstacle's corners.
        corner: u8,
    },
}

/// A BTM vertex.
#[derive(Clone, Copy, Debug)]
pub struct Vertex {
    /// Position (plane frame, m).
    pub p: Pt,
    /// Boundary it belongs to.
    pub owner: Owner,
    /// False for a free slot.
    pub alive: bool,
}

/// A BTM triangle, counter-clockwise; `nbr[i]` is the triangle across edge `(v[i], v[i+1])`, or [`NONE`] when that
/// edge is a boundary edge.
#[derive(Clone, Copy, Debug)]
pub struct Tri {
    /// Corners, counter-clockwise.
    pub v: [Id; 3],
    /// Neighbours across the edges.
    pub nbr: [Id; 3],
    /// False for a free slot.
    pub alive: bool,
}

impl Tri {
    /// Edge `i` (0..3) as (from, to, neighbour across it).
    pub fn edge(&self, i: usize) -> (Id, Id, Id) {
        let [a, b, c] = self.v;
        let [n0, n1, n2] = self.nbr;
        match i % 3 {
            0 => (a, b, n0),
            1 => (b, c, n1),
            _ => (c, a, n2),
        }
    }
    /// Sets the neighbour across edge `i`.
    pub fn set_nbr(&mut self, i: usize, t: Id) {
        match i % 3 {
            0 => self.nbr[0] = t,
            1 => self.nbr[1] = t,
            _ => self.nbr[2] = t,
        }
    }
    /// Index of the edge `from -> to`, if this triangle has it in that direction.
    pub fn edge_index(&self, from: Id, to: Id) -> Option<usize> {
        (0..3).find(|&k| {
            let (a, b, _) = self.edge(k);
            a == from && b == to
        })
    }
}

/// Corner `i` (mod 3) of a point triple.
pub fn corner(ps: &[Pt; 3], i: usize) -> Pt {
    let [a, b, c] = *ps;
    match i % 3 {
        0 => a,
        1 => b,
        _ => c,
    }
}

/// A polygonal obstacle (hole) on the plane.
#[derive(Clone, Debug)]
pub struct Obstacle {
    /// Corners, counter-clockwise.
    pub corners: HVec<Pt, MAX_OBSTACLE_VERTICES>,
    /// BTM vertex of each corner.
    pub vids: HVec<Id, MAX_OBSTACLE_VERTICES>,
    /// Representative point strictly inside (the pole zeta_i of the L-value, Tanner II-B): centroid of the first
    /// ear of the ear-clipping decomposition, so it is inside even for non-convex obstacles.
    pub rep: Pt,
}

/// Arena that ran out.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arena {
    /// `MAX_VERTICES`.
    Vertices,
    /// `MAX_TRIANGLES`.
    Triangles,
    /// `MAX_DEGREE`.
    Degree,
    /// `MAX_CANDIDATE_EDGES`.
    Candidates,
    /// `MAX_OBSTACLES`.
    Obstacles,
}

/// Why an obstacle was refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ObstacleReject {
    /// Fewer than 3 corners.
    TooFewCorners,
    /// More than `MAX_OBSTACLE_VERTICES` corners.
    TooManyCorners,
    /// A coordinate is NaN or infinite.
    NotFinite,
    /// Edges cross, touch, or have zero length.
    NotSimple,
    /// Not strictly inside the plane outline.
    OutsidePlane,
    /// Touches or overlaps obstacle `0` (merge them into one polygon first).
    OverlapsObstacle(u8),
}

/// Errors of BTM construction and updates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BtmError {
    /// An arena is full; the BTM is left as before the call only for obstacle validation errors, otherwise it must
    /// be rebuilt with larger capacities.
    Full(Arena),
    /// Plane outline unusable (reason).
    InvalidPlane(&'static str),
    /// Obstacle refused (nothing changed).
    InvalidObstacle(ObstacleReject),
    /// No obstacle in that slot.
    UnknownObstacle(u8),
    /// The region could not be triangulated (numerically degenerate input: near-collinear or coincident corners).
    Degenerate,
}

/// What one update touched (Tanner III-A: "report how many triangles each update touched").
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct UpdateReport {
    /// Triangles removed from the affected region.
    pub removed: usize,
    /// Triangles created by retriangulating it.
    pub created: usize,
    /// Corners of the affected region.
    pub region_vertices: usize,
}

impl UpdateReport {
    /// Triangles touched (removed + created).
    pub fn touched(&self) -> usize {
        self.removed + self.created
    }
}

/// A violated BTM invariant (see [`Btm::check_invariants`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum InvariantViolation {
    /// Triangle not counter-clockwise or of (near) zero area.
    Degenerate(Id),
    /// Neighbour links not symmetric, or pointing at a triangle without the shared edge.
    Adjacency(Id),
    /// An edge with one triangle that is not a plane/obstacle edge, or a plane/obstacle edge with two triangles.
    Boundary(Id),
    /// Triangle edge missing from the edge set, or an edge used by no triangle (not conforming).
    Conforming(Id),
    /// A vertex strictly inside a triangle (overlap).
    Overlap(Id),
    /// A vertex that is not on exactly two boundary edges (Definition 1).
    NotBoundaryVertex(Id),
    /// Sum of triangle areas differs from plane area minus obstacle areas: (sum, expected).
    Area(f64, f64),
    /// Triangle inside an obstacle or outside the plane.
    OutsideFreeSpace(Id),
}

/// The BTM of one tether-demand plane, with its obstacles.
#[derive(Clone)]
pub struct Btm {
    plane: HVec<Pt, MAX_PLANE_VERTICES>,
    verts: [Vertex; MAX_VERTICES],
    adj: [[Id; MAX_DEGREE]; MAX_VERTICES],
    deg: [u8; MAX_VERTICES],
    tris: [Tri; MAX_TRIANGLES],
    obstacles: [Option<Obstacle>; MAX_OBSTACLES],
    cand: [(Id, Id, f64); MAX_CANDIDATE_EDGES],
    in_region: [bool; MAX_VERTICES],
    tri_mark: [bool; MAX_TRIANGLES],
    /// Affected region of the current local update: removed triangles and (for a removal) the removed hole;
    /// `None` for a full rebuild (the region is the whole plane).
    region_tris: HVec<[Pt; 3], MAX_TRIANGLES>,
    region_hole: HVec<Pt, MAX_OBSTACLE_VERTICES>,
    region_full: bool,
}

impl Default for Btm {
    fn default() -> Self {
        Self::new()
    }
}

const DEAD_VERTEX: Vertex = Vertex { p: Pt { x: 0.0, y: 0.0 }, owner: Owner::Plane { corner: 0 }, alive: false };
const DEAD_TRI: Tri = Tri { v: [NONE; 3], nbr: [NONE; 3], alive: false };

fn id(i: usize) -> Id {
    Id::try_from(i).unwrap_or(NONE)
}

impl Btm {
    /// An empty BTM (no plane). `const`, so a board can keep it in a `static`.
    pub const fn new() -> Self {
        const NO_OBSTACLE: Option<Obstacle> = None;
        Btm {
            plane: HVec::new(),
            verts: [DEAD_VERTEX; MAX_VERTICES],
            adj: [[NONE; MAX_DEGREE]; MAX_VERTICES],
            deg: [0; MAX_VERTICES],
            tris: [DEAD_TRI; MAX_TRIANGLES],
            obstacles: [NO_OBSTACLE; MAX_OBSTACLES],
            cand: [(NONE, NONE, 0.0); MAX_CANDIDATE_EDGES],
            in_region: [false; MAX_VERTICES],
            tri_mark: [false; MAX_TRIANGLES],
            region_tris: HVec::new(),
            region_hole: HVec::new(),
            region_full: true,
        }
    }

    /// Builds the BTM of `plane` (a simple polygon, either orientation) minus `obstacles` from scratch.
    /// Obstacles keep the slots `0..obstacles.len()`.
    pub fn build(&mut self, plane: &[Pt], obstacles: &[&[Pt]]) -> Result<UpdateReport, BtmError> {
        self.reset();
        if plane.len() < 3 || plane.len() > MAX_PLANE_VERTICES {
            return Err(BtmError::InvalidPlane("outline needs 3..=MAX_PLANE_VERTICES corners"));
        }
        if plane.iter().any(|p| !p.is_finite()) {
            return Err(BtmError::InvalidPlane("outline has a non-finite coordinate"));
        }
        if !polygon_is_simple(plane) || polygon_area(plane).abs() < EPS {
            return Err(BtmError::InvalidPlane("outline is not a simple polygon"));
        }
        self.plane.clear();
        let ccw = polygon_area(plane) > 0.0;
        for k in 0..plane.len() {
            let p = if ccw { plane.get(k) } else { plane.get(plane.len() - 1 - k) };
            let Some(&p) = p else { continue };
            let _ = self.plane.push(p);
            self.add_vertex(p, Owner::Plane { corner: k as u8 })?;
        }
        let np = self.plane.len();
        for k in 0..np {
            self.add_edge(id(k), id((k + 1) % np))?;
        }
        for o in obstacles {
            self.insert_obstacle_only(o)?;
        }
        self.rebuild()
    }

    /// Back to the state of [`Btm::new`], in place: `*self = Self::new()` would build a ~0.25 MiB temporary on
    /// the stack (it overflowed the board's 256 KiB stack, found by the on-target `homotopy_btm_build_c` workload).
    fn reset(&mut self) {
        self.plane.clear();
        self.verts.fill(DEAD_VERTEX);
        for a in self.adj.iter_mut() {
            a.fill(NONE);
        }
        self.deg.fill(0);
        self.tris.fill(DEAD_TRI);
        for o in self.obstacles.iter_mut() {
            *o = None;
        }
        self.cand.fill((NONE, NONE, 0.0));
        self.in_region.fill(false);
        self.tri_mark.fill(false);
        self.region_tris.clear();
        self.region_hole.clear();
        self.region_full = true;
    }

    /// Retriangulates the whole plane with the current obstacles (the "full rebuild" baseline).
    pub fn rebuild(&mut self) -> Result<UpdateReport, BtmError> {
        let mut removed = 0;
        for t in self.tris.iter_mut() {
            if t.alive {
                removed += 1;
            }
            *t = DEAD_TRI;
        }
        for v in 0..MAX_VERTICES {
            let alive = self.verts.get(v).is_some_and(|x| x.alive);
            if let Some(r) = self.in_region.get_mut(v) {
                *r = alive;
            }
        }
        // Drop every non-constraint edge.
        for a in 0..MAX_VERTICES {
            let nbrs = self.neighbours_copy(id(a));
            for b in nbrs.iter().copied() {
                if !self.is_constraint(id(a), b) {
                    self.remove_edge(id(a), b);
                }
            }
        }
        let region = self.in_region.iter().filter(|x| **x).count();
        self.region_full = true;
        let created = self.triangulate_region()?;
        Ok(UpdateReport { removed, created, region_vertices: region })
    }

    /// Plane outline (counter-clockwise).
    pub fn plane(&self) -> &[Pt] {
        &self.plane
    }
    /// Vertex `v`, if alive.
    pub fn vertex(&self, v: Id) -> Option<&Vertex> {
        self.verts.get(usize::from(v)).filter(|x| x.alive)
    }
    /// Triangle `t`, if alive.
    pub fn tri(&self, t: Id) -> Option<&Tri> {
        self.tris.get(usize::from(t)).filter(|x| x.alive)
    }
    /// Alive triangles with their ids.
    pub fn triangles(&self) -> impl Iterator<Item = (Id, &Tri)> + '_ {
        self.tris.iter().enumerate().filter(|(_, t)| t.alive).map(|(i, t)| (id(i), t))
    }
    /// Number of alive triangles.
    pub fn triangle_count(&self) -> usize {
        self.tris.iter().filter(|t| t.alive).count()
    }
    /// Obstacles with their slots.
    pub fn obstacles(&self) -> impl Iterator<Item = (u8, &Obstacle)> + '_ {
        self.obstacles.iter().enumerate().filter_map(|(i, o)| o.as_ref().map(|o| (i as u8, o)))
    }
    /// Obstacle in slot `k`.
    pub fn obstacle(&self, k: u8) -> Option<&Obstacle> {
        self.obstacles.get(usize::from(k)).and_then(|o| o.as_ref())
    }
    /// Corner positions of triangle `t`.
    pub fn tri_points(&self, t: Id) -> Option<[Pt; 3]> {
        let tr = self.tri(t)?;
        Some([self.vertex(tr.v[0])?.p, self.vertex(tr.v[1])?.p, self.vertex(tr.v[2])?.p])
    }

    /// True when `p` is strictly inside the plane and not inside (or on) any obstacle.
    pub fn is_free(&self, p: Pt) -> bool {
        point_in_polygon(p, &self.plane, true) && self.obstacles().all(|(_, o)| !point_in_polygon(p, &o.corners, false))
    }

    /// True when the closed segment `p q` avoids every obstacle interior and stays in the plane. Touching an
    /// obstacle corner or sliding along an obstacle edge is allowed (a taut tether does that).
    pub fn segment_free(&self, p: Pt, q: Pt) -> bool {
        for (a, b) in polygon_edges(&self.plane) {
            if segments_cross_properly(p, q, a, b) {
                return false;
            }
        }
        if !point_in_polygon(p, &self.plane, false) || !point_in_polygon(q, &self.plane, false) {
            return false;
        }
        for (_, o) in self.obstacles() {
            for (a, b) in polygon_edges(&o.corners) {
                if segments_cross_properly(p, q, a, b) {
                    return false;
                }
            }
            // Split at obstacle corners on the segment; each piece is then wholly inside or outside.
            let mut ts: HVec<f64, { MAX_OBSTACLE_VERTICES + 2 }> = HVec::new();
            let _ = ts.push(0.0);
            let _ = ts.push(1.0);
            let d = q - p;
            let l2 = d.dot(d);
            for c in o.corners.iter() {
                if l2 > 0.0 && (point_strictly_on_segment(*c, p, q)) {
                    let _ = ts.push((*c - p).dot(d) / l2);
                }
            }
            super::geo::sort_by(&mut ts, |a, b| a.total_cmp(b).is_lt());
            for w in ts.windows(2) {
                if let [t0, t1] = w {
                    let m = p + d * (0.5 * (t0 + t1));
                    if t1 - t0 > 1e-12 && point_in_polygon(m, &o.corners, true) {
                        return false;
                    }
                }
            }
        }
        true
    }

    /// Triangle containing `p` (boundary inclusive), lowest id first.
    pub fn locate(&self, p: Pt) -> Option<Id> {
        self.triangles().find_map(|(i, _)| {
            let [a, b, c] = self.tri_points(i)?;
            let tol = -1e-12 * (1.0 + (b - a).norm() * (c - a).norm());
            (orient(a, b, p) >= tol && orient(b, c, p) >= tol && orient(c, a, p) >= tol).then_some(i)
        })
    }

    /// Adds obstacle `corners` (simple polygon, either orientation) and retriangulates only the affected region:
    /// the triangles the obstacle touches (Tanner Lemma 1). Returns its slot and what was touched.
    pub fn add_obstacle(&mut self, corners: &[Pt]) -> Result<(u8, UpdateReport), BtmError> {
        let poly = self.validate_obstacle(corners)?;
        // Affected region: triangles the new obstacle touches.
        for (i, m) in self.tri_mark.iter_mut().enumerate() {
            *m = false;
            let Some(t) = self.tris.get(i).filter(|t| t.alive) else { continue };
            let ps = [t.v[0], t.v[1], t.v[2]].map(|v| self.verts.get(usize::from(v)).map(|x| x.p).unwrap_or_default());
            *m = polygons_overlap(&ps, &poly);
        }
        let k = self.insert_obstacle_only(&poly)?;
        let (removed, region_vertices) = self.clear_marked_region(None);
        let Some(o) = self.obstacle(k) else { return Err(BtmError::UnknownObstacle(k)) };
        let vids = o.vids.clone();
        let mut region_vertices = region_vertices;
        for v in vids {
            if let Some(r) = self.in_region.get_mut(usize::from(v)) {
                if !*r {
                    region_vertices += 1;
                }
                *r = true;
            }
        }
        let created = self.triangulate_region()?;
        Ok((k, UpdateReport { removed, created, region_vertices }))
    }

    /// Removes obstacle `k` (a phantom, Tanner III-A) and retriangulates the triangles incident to its corners plus
    /// its hole.
    pub fn remove_obstacle(&mut self, k: u8) -> Result<UpdateReport, BtmError> {
        let Some(o) = self.obstacle(k) else { return Err(BtmError::UnknownObstacle(k)) };
        let vids = o.vids.clone();
        let hole = o.corners.clone();
        for (i, m) in self.tri_mark.iter_mut().enumerate() {
            *m = self.tris.get(i).is_some_and(|t| t.alive && t.v.iter().any(|v| vids.contains(v)));
        }
        let (removed, _) = self.clear_marked_region(Some(&vids));
        self.region_hole = hole;
        for v in vids.iter().copied() {
            let nb = self.neighbours_copy(v);
            for b in nb {
                self.remove_edge(v, b);
            }
            if let Some(x) = self.verts.get_mut(usize::from(v)) {
                *x = DEAD_VERTEX;
            }
            if let Some(r) = self.in_region.get_mut(usize::from(v)) {
                *r = false;
            }
        }
        if let Some(slot) = self.obstacles.get_mut(usize::from(k)) {
            *slot = None;
        }
        let region_vertices = self.in_region.iter().filter(|x| **x).count();
        let created = self.triangulate_region()?;
        Ok(UpdateReport { removed, created, region_vertices })
    }

    /// Moves obstacle `k` to `corners` (removal then addition, Tanner III-A: "an obstacle that has changed shape or
    /// position can simply be removed and replaced"). The new obstacle may get another slot.
    pub fn move_obstacle(&mut self, k: u8, corners: &[Pt]) -> Result<(u8, UpdateReport), BtmError> {
        // Validate against the others before touching anything.
        let poly = self.validate_obstacle_except(corners, &[k])?;
        let r1 = self.remove_obstacle(k)?;
        let (k2, r2) = self.add_obstacle(&poly)?;
        Ok((
            k2,
            UpdateReport {
                removed: r1.removed + r2.removed,
                created: r1.created + r2.created,
                region_vertices: r1.region_vertices + r2.region_vertices,
            },
        ))
    }

    /// Replaces obstacles `merged` by one obstacle `corners` that holds them (Tanner III-A: obstacles that came to
    /// overlap are merged into one polygon), checked against the others before anything changes. Returns its slot.
    /// An error after the check (an arena full, a degenerate region), like [`Self::move_obstacle`]'s, leaves a BTM
    /// to be rebuilt.
    pub fn merge_obstacles(&mut self, merged: &[u8], corners: &[Pt]) -> Result<(u8, UpdateReport), BtmError> {
        let poly = self.validate_obstacle_except(corners, merged)?;
        let mut total = UpdateReport { removed: 0, created: 0, region_vertices: 0 };
        for &k in merged {
            let r = self.remove_obstacle(k)?;
            total.removed += r.removed;
            total.created += r.created;
            total.region_vertices += r.region_vertices;
        }
        let (k, r) = self.add_obstacle(&poly)?;
        total.removed += r.removed;
        total.created += r.created;
        total.region_vertices += r.region_vertices;
        Ok((k, total))
    }

    /// Checks an obstacle polygon without adding it; returns it counter-clockwise.
    pub fn validate_obstacle(&self, corners: &[Pt]) -> Result<HVec<Pt, MAX_OBSTACLE_VERTICES>, BtmError> {
        self.validate_obstacle_except(corners, &[])
    }

    fn validate_obstacle_except(
        &self,
        corners: &[Pt],
        except: &[u8],
    ) -> Result<HVec<Pt, MAX_OBSTACLE_VERTICES>, BtmError> {
        use ObstacleReject as R;
        let rej = |r| Err(BtmError::InvalidObstacle(r));
        if corners.len() < 3 {
            return rej(R::TooFewCorners);
        }
        if corners.len() > MAX_OBSTACLE_VERTICES {
            return rej(R::TooManyCorners);
        }
        if corners.iter().any(|p| !p.is_finite()) {
            return rej(R::NotFinite);
        }
        if !polygon_is_simple(corners) || polygon_area(corners).abs() < 1e-9 {
            return rej(R::NotSimple);
        }
        let mut poly: HVec<Pt, MAX_OBSTACLE_VERTICES> = HVec::new();
        let ccw = polygon_area(corners) > 0.0;
        for k in 0..corners.len() {
            let p = if ccw { corners.get(k) } else { corners.get(corners.len() - 1 - k) };
            if let Some(&p) = p {
                let _ = poly.push(p);
            }
        }
        let inside = poly.iter().all(|p| point_in_polygon(*p, &self.plane, true))
            && !polygon_edges(&poly).any(|(a, b)| polygon_edges(&self.plane).any(|(c, d)| segments_cross_properly(a, b, c, d)));
        if !inside {
            return rej(R::OutsidePlane);
        }
        for (k, o) in self.obstacles() {
            if !except.contains(&k) && polygons_overlap(&poly, &o.corners) {
                return rej(R::OverlapsObstacle(k));
            }
        }
        Ok(poly)
    }

    /// Adds the obstacle's vertices and boundary edges, no triangles.
    fn insert_obstacle_only(&mut self, corners: &[Pt]) -> Result<u8, BtmError> {
        let poly = self.validate_obstacle(corners)?;
        let Some(k) = self.obstacles.iter().position(|o| o.is_none()) else {
            return Err(BtmError::Full(Arena::Obstacles));
        };
        let free_vertices = self.verts.iter().filter(|v| !v.alive).count();
        if free_vertices < poly.len() {
            return Err(BtmError::Full(Arena::Vertices));
        }
        let k8 = k as u8;
        let mut vids: HVec<Id, MAX_OBSTACLE_VERTICES> = HVec::new();
        for (c, p) in poly.iter().enumerate() {
            let v = self.add_vertex(*p, Owner::Obstacle { obstacle: k8, corner: c as u8 })?;
            let _ = vids.push(v);
        }
        let mut ears = [[0u8; 3]; MAX_OBSTACLE_VERTICES];
        let n = ear_clip(&poly, &mut ears);
        let rep = match (n, ears.first()) {
            (1.., Some(&[a, b, c])) => {
                let g = |i: u8| poly.get(usize::from(i)).copied().unwrap_or_default();
                (g(a) + g(b) + g(c)) * (1.0 / 3.0)
            }
            _ => return Err(BtmError::InvalidObstacle(ObstacleReject::NotSimple)),
        };
        if let Some(slot) = self.obstacles.get_mut(k) {
            *slot = Some(Obstacle { corners: poly, vids: vids.clone(), rep });
        }
        for (i, a) in vids.iter().enumerate() {
            let b = vids.get((i + 1) % vids.len()).copied().unwrap_or(NONE);
            self.add_edge(*a, b)?;
        }
        Ok(k8)
    }

    /// Kills the marked triangles, removes the edges interior to their union, and marks the region's corners
    /// (except `skip`). Returns (triangles removed, region corners).
    fn clear_marked_region(&mut self, skip: Option<&[Id]>) -> (usize, usize) {
        for r in self.in_region.iter_mut() {
            *r = false;
        }
        self.region_full = false;
        self.region_tris.clear();
        self.region_hole.clear();
        let mut removed = 0;
        for t in 0..MAX_TRIANGLES {
            if !self.tri_mark.get(t).copied().unwrap_or(false) {
                continue;
            }
            let Some(tr) = self.tris.get(t).copied() else { continue };
            removed += 1;
            let ps = tr.v.map(|v| self.verts.get(usize::from(v)).map(|x| x.p).unwrap_or_default());
            let _ = self.region_tris.push(ps);
            for i in 0..3 {
                let (a, b, n) = tr.edge(i);
                let interior = n != NONE && self.tri_mark.get(usize::from(n)).copied().unwrap_or(false);
                if interior && !self.is_constraint(a, b) {
                    self.remove_edge(a, b);
                }
                if n != NONE && !interior {
                    // Unlink the surviving neighbour.
                    if let Some(nt) = self.tris.get_mut(usize::from(n)) {
                        for s in nt.nbr.iter_mut() {
                            if *s == id(t) {
                                *s = NONE;
                            }
                        }
                    }
                }
                if !skip.is_some_and(|s| s.contains(&a)) {
                    if let Some(r) = self.in_region.get_mut(usize::from(a)) {
                        *r = true;
                    }
                }
            }
            if let Some(x) = self.tris.get_mut(t) {
                *x = DEAD_TRI;
            }
        }
        // Edges between two region corners that crossed the (new) obstacle were interior; ones left dangling
        // (no surviving triangle) are removed by the triangulation's edge filter below.
        (removed, self.in_region.iter().filter(|x| **x).count())
    }

    /// Greedy triangulation of the marked region. Returns the number of triangles created.
    fn triangulate_region(&mut self) -> Result<usize, BtmError> {
        let mut region: HVec<Id, MAX_VERTICES> = HVec::new();
        for (i, r) in self.in_region.iter().enumerate() {
            if *r && self.verts.get(i).is_some_and(|v| v.alive) {
                let _ = region.push(id(i));
            }
        }
        // Drop region-internal edges used by no alive triangle and not constraints (dangling after clearing).
        for &a in region.iter() {
            for b in self.neighbours_copy(a) {
                if a < b && self.in_region.get(usize::from(b)).copied().unwrap_or(false) && !self.is_constraint(a, b) && !self.edge_has_alive_triangle(a, b) {
                    self.remove_edge(a, b);
                }
            }
        }
        // Candidate edges: free segments between region corners.
        let mut n = 0usize;
        for (i, &a) in region.iter().enumerate() {
            for &b in region.iter().skip(i + 1) {
                if self.has_edge(a, b) {
                    continue;
                }
                let (Some(pa), Some(pb)) = (self.vertex(a).map(|v| v.p), self.vertex(b).map(|v| v.p)) else { continue };
                if !self.candidate_free(a, b, pa, pb) || !self.in_affected_region((pa + pb) * 0.5) {
                    continue;
                }
                let Some(slot) = self.cand.get_mut(n) else { return Err(BtmError::Full(Arena::Candidates)) };
                *slot = (a, b, pa.dist(pb));
                n += 1;
            }
        }
        let Some(cands) = self.cand.get_mut(..n) else { return Err(BtmError::Full(Arena::Candidates)) };
        super::geo::sort_by(cands, |x, y| x.2.total_cmp(&y.2).then(x.0.cmp(&y.0)).then(x.1.cmp(&y.1)).is_lt());
        for c in 0..n {
            let Some(&(a, b, _)) = self.cand.get(c) else { continue };
            let (Some(pa), Some(pb)) = (self.vertex(a).map(|v| v.p), self.vertex(b).map(|v| v.p)) else { continue };
            let mut crosses = false;
            'outer: for &u in region.iter() {
                let Some(pu) = self.vertex(u).map(|v| v.p) else { continue };
                for &w in self.neighbours(u) {
                    if w <= u || !self.in_region.get(usize::from(w)).copied().unwrap_or(false) {
                        continue;
                    }
                    let Some(pw) = self.vertex(w).map(|v| v.p) else { continue };
                    if segments_cross_properly(pa, pb, pu, pw) {
                        crosses = true;
                        break 'outer;
                    }
                }
            }
            if !crosses {
                self.add_edge(a, b)?;
            }
        }
        // Faces: counter-clockwise 3-cycles with smallest corner first, empty, in free space, not already present.
        let mut created = 0;
        for &u in region.iter() {
            let nb = self.neighbours_copy(u);
            for &v in nb.iter() {
                if v <= u || !self.in_region.get(usize::from(v)).copied().unwrap_or(false) {
                    continue;
                }
                for &w in nb.iter() {
                    if w <= u || w == v || !self.has_edge(v, w) || !self.in_region.get(usize::from(w)).copied().unwrap_or(false) {
                        continue;
                    }
                    let (Some(pu), Some(pv), Some(pw)) =
                        (self.vertex(u).map(|x| x.p), self.vertex(v).map(|x| x.p), self.vertex(w).map(|x| x.p))
                    else {
                        continue;
                    };
                    if orient(pu, pv, pw) <= 0.0 {
                        continue;
                    }
                    let centroid = (pu + pv + pw) * (1.0 / 3.0);
                    if !self.is_free(centroid) || !self.in_affected_region(centroid) {
                        continue;
                    }
                    let tri = [pu, pv, pw];
                    let nonempty = self.verts.iter().enumerate().any(|(i, x)| {
                        x.alive && id(i) != u && id(i) != v && id(i) != w && point_in_polygon(x.p, &tri, true)
                    });
                    if nonempty || self.find_triangle([u, v, w]).is_some() {
                        continue;
                    }
                    self.add_triangle([u, v, w])?;
                    created += 1;
                }
            }
        }
        if created == 0 && !region.is_empty() && self.triangle_count() == 0 {
            return Err(BtmError::Degenerate);
        }
        Ok(created)
    }

    /// True when `p` is in the affected region of the current update (always, for a full rebuild).
    fn in_affected_region(&self, p: Pt) -> bool {
        self.region_full
            || self.region_tris.iter().any(|t| point_in_polygon(p, t, false))
            || (self.region_hole.len() >= 3 && point_in_polygon(p, &self.region_hole, false))
    }

    fn candidate_free(&self, a: Id, b: Id, pa: Pt, pb: Pt) -> bool {
        // No corner strictly on the open segment.
        for (i, v) in self.verts.iter().enumerate() {
            if v.alive && id(i) != a && id(i) != b && point_strictly_on_segment(v.p, pa, pb) {
                return false;
            }
        }
        let m = (pa + pb) * 0.5;
        if !point_in_polygon(m, &self.plane, true) {
            return false;
        }
        for (a0, b0) in polygon_edges(&self.plane) {
            if segments_cross_properly(pa, pb, a0, b0) {
                return false;
            }
        }
        for (_, o) in self.obstacles() {
            if point_in_polygon(m, &o.corners, false) {
                return false;
            }
            for (c, d) in polygon_edges(&o.corners) {
                if segments_cross_properly(pa, pb, c, d) {
                    return false;
                }
            }
        }
        true
    }

    fn find_triangle(&self, v: [Id; 3]) -> Option<Id> {
        self.triangles().find(|(_, t)| v.iter().all(|x| t.v.contains(x))).map(|(i, _)| i)
    }

    fn edge_has_alive_triangle(&self, a: Id, b: Id) -> bool {
        self.triangles().any(|(_, t)| t.v.contains(&a) && t.v.contains(&b))
    }

    fn add_triangle(&mut self, v: [Id; 3]) -> Result<Id, BtmError> {
        let Some(slot) = self.tris.iter().position(|t| !t.alive) else { return Err(BtmError::Full(Arena::Triangles)) };
        let t = id(slot);
        let mut nbr = [NONE; 3];
        for (i, n) in nbr.iter_mut().enumerate() {
            let (a, b, _) = Tri { v, nbr: [NONE; 3], alive: true }.edge(i);
            // The neighbour has the edge reversed: (b, a).
            let found = self.triangles().find_map(|(j, o)| o.edge_index(b, a).map(|k| (j, k)));
            if let Some((j, k)) = found {
                *n = j;
                if let Some(o) = self.tris.get_mut(usize::from(j)) {
                    o.set_nbr(k, t);
                }
            }
        }
        if let Some(x) = self.tris.get_mut(slot) {
            *x = Tri { v, nbr, alive: true };
        }
        Ok(t)
    }

    fn add_vertex(&mut self, p: Pt, owner: Owner) -> Result<Id, BtmError> {
        let Some(slot) = self.verts.iter().position(|v| !v.alive) else { return Err(BtmError::Full(Arena::Vertices)) };
        if let Some(v) = self.verts.get_mut(slot) {
            *v = Vertex { p, owner, alive: true };
        }
        if let Some(d) = self.deg.get_mut(slot) {
            *d = 0;
        }
        Ok(id(slot))
    }

    /// Neighbours of vertex `v` in the edge set.
    pub fn neighbours(&self, v: Id) -> &[Id] {
        let d = usize::from(self.deg.get(usize::from(v)).copied().unwrap_or(0));
        self.adj.get(usize::from(v)).and_then(|a| a.get(..d)).unwrap_or(&[])
    }

    fn neighbours_copy(&self, v: Id) -> HVec<Id, MAX_DEGREE> {
        let mut out = HVec::new();
        for &w in self.neighbours(v) {
            let _ = out.push(w);
        }
        out
    }

    /// True when `a b` is an edge of the BTM's edge set.
    pub fn has_edge(&self, a: Id, b: Id) -> bool {
        self.neighbours(a).contains(&b)
    }

    fn add_edge(&mut self, a: Id, b: Id) -> Result<(), BtmError> {
        if self.has_edge(a, b) {
            return Ok(());
        }
        for (x, y) in [(a, b), (b, a)] {
            let d = usize::from(self.deg.get(usize::from(x)).copied().unwrap_or(0));
            if d >= MAX_DEGREE {
                return Err(BtmError::Full(Arena::Degree));
            }
            if let Some(s) = self.adj.get_mut(usize::from(x)).and_then(|r| r.get_mut(d)) {
                *s = y;
            }
            if let Some(dd) = self.deg.get_mut(usize::from(x)) {
                *dd += 1;
            }
        }
        Ok(())
    }

    fn remove_edge(&mut self, a: Id, b: Id) {
        for (x, y) in [(a, b), (b, a)] {
            let d = usize::from(self.deg.get(usize::from(x)).copied().unwrap_or(0));
            let Some(row) = self.adj.get_mut(usize::from(x)) else { continue };
            let Some(live) = row.get_mut(..d) else { continue };
            if let Some(pos) = live.iter().position(|&w| w == y) {
                live.copy_within(pos + 1.., pos);
                if let Some(dd) = self.deg.get_mut(usize::from(x)) {
                    *dd -= 1;
                }
            }
        }
    }

    /// True when `a b` is an edge of the plane outline or of an obstacle (a *boundary edge* of Definition 1).
    pub fn is_constraint(&self, a: Id, b: Id) -> bool {
        let (Some(va), Some(vb)) = (self.vertex(a), self.vertex(b)) else { return false };
        match (va.owner, vb.owner) {
            (Owner::Plane { corner: i }, Owner::Plane { corner: j }) => {
                let n = self.plane.len() as u8;
                n > 0 && ((i + 1) % n == j || (j + 1) % n == i)
            }
            (Owner::Obstacle { obstacle: k, corner: i }, Owner::Obstacle { obstacle: l, corner: j }) if k == l => {
                let n = self.obstacle(k).map(|o| o.corners.len() as u8).unwrap_or(0);
                n > 0 && ((i + 1) % n == j || (j + 1) % n == i)
            }
            _ => false,
        }
    }

    /// Checks every BTM invariant: counter-clockwise non-degenerate triangles in free space, symmetric adjacency,
    /// conforming (every triangle edge is an edge, every edge has a triangle, no corner inside a triangle),
    /// boundary edges exactly the plane/obstacle edges, every vertex on exactly two boundary edges (Definition 1),
    /// and area sum = plane area - obstacle areas.
    pub fn check_invariants(&self) -> Result<(), InvariantViolation> {
        use InvariantViolation as V;
        let mut area = 0.0;
        for (t, tr) in self.triangles() {
            let Some([a, b, c]) = self.tri_points(t) else { return Err(V::Degenerate(t)) };
            let o = orient(a, b, c);
            if o <= 1e-12 || tr.v[0] == tr.v[1] || tr.v[1] == tr.v[2] || tr.v[0] == tr.v[2] {
                return Err(V::Degenerate(t));
            }
            area += 0.5 * o;
            if !self.is_free((a + b + c) * (1.0 / 3.0)) {
                return Err(V::OutsideFreeSpace(t));
            }
            for i in 0..3 {
                let (x, y, n) = tr.edge(i);
                if !self.has_edge(x, y) {
                    return Err(V::Conforming(t));
                }
                if n == NONE {
                    if !self.is_constraint(x, y) {
                        return Err(V::Boundary(t));
                    }
                } else {
                    let Some(nt) = self.tri(n) else { return Err(V::Adjacency(t)) };
                    let back = nt.edge_index(y, x).is_some_and(|k| nt.edge(k).2 == t);
                    if !back {
                        return Err(V::Adjacency(t));
                    }
                    if self.is_constraint(x, y) {
                        return Err(V::Boundary(t));
                    }
                }
            }
            for (i, v) in self.verts.iter().enumerate() {
                if v.alive && !tr.v.contains(&id(i)) && point_in_polygon(v.p, &[a, b, c], true) {
                    return Err(V::Overlap(t));
                }
            }
        }
        for (i, v) in self.verts.iter().enumerate() {
            if !v.alive {
                continue;
            }
            let vi = id(i);
            let mut boundary = 0;
            for &w in self.neighbours(vi) {
                let users = self.triangles().filter(|(_, t)| t.v.contains(&vi) && t.v.contains(&w)).count();
                if users == 0 || users > 2 {
                    return Err(V::Conforming(vi));
                }
                if users == 1 {
                    boundary += 1;
                }
            }
            if boundary != 2 {
                return Err(V::NotBoundaryVertex(vi));
            }
        }
        let expected = polygon_area(&self.plane) - self.obstacles().map(|(_, o)| polygon_area(&o.corners)).sum::<f64>();
        if (area - expected).abs() > 1e-7 * (1.0 + expected.abs()) {
            return Err(V::Area(area, expected));
        }
        Ok(())
    }

    /// Canonical description of the triangulation for comparisons: sorted corner-position triples.
    pub fn edge_count(&self) -> usize {
        (0..MAX_VERTICES).map(|v| self.neighbours(id(v)).len()).sum::<usize>() / 2
    }
}
