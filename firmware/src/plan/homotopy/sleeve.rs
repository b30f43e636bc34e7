//! Sleeves, crossing sequences and the shortest homotopic path (SHP) by the funnel algorithm
//! (Abad-Manterola et al. V-A, Fig. 8; Tanner et al. II-A, Fig. 7; Hershberger-Snoeyink; Lee-Preparata).
//!
//! A *sleeve* is a sequence of BTM triangles, each adjacent to the next, with no triangle twice (its dual is a
//! simple path). Walking a path through the BTM gives its *crossing sequence*; cancelling immediate back-and-forth
//! steps (`t, s, t -> t`) *reduces* it. Because every BTM vertex is a boundary vertex, the reduced sequence names
//! the homotopy class, and the SHP of the class is the shortest path inside that sleeve: the "simple stupid
//! funnel" (a Lee-Preparata funnel that restarts from the apex) finds it in time linear in the sleeve for the
//! sleeves a taut tether produces (restarts are bounded by `FUNNEL_BUDGET`, default 16 x `MAX_SLEEVE`).
//! The bends of the SHP are BTM vertices: those on obstacles are the *intermediate anchor points* a1..ak.

use super::btm::{corner, Btm, Id, Owner, NONE};
use super::geo::{orient, Pt};
use crate::config::homotopy::{FUNNEL_BUDGET, MAX_PATH, MAX_SLEEVE, WALK_BUDGET};
use heapless::Vec as HVec;

/// A sleeve: adjacent BTM triangles, no repeats.
pub type Sleeve = HVec<Id, MAX_SLEEVE>;

/// Errors of sleeve and path computations.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SleeveError {
    /// A point is outside the free space.
    PointNotInFreeSpace,
    /// A path segment leaves the free space (crosses an obstacle or the plane edge).
    SegmentBlocked,
    /// The reduced crossing sequence visits a triangle twice (the path winds around an obstacle).
    NotSimple,
    /// Two consecutive sleeve triangles are not adjacent.
    NotAdjacent,
    /// Walking or funnel budget exhausted, or an arena (`MAX_SLEEVE`, `MAX_PATH`) full.
    Budget,
}

/// Pushes triangle `t` onto a crossing sequence, cancelling an immediate return (`s, t, s -> s`).
pub fn push_reduced(seq: &mut Sleeve, t: Id) -> Result<(), SleeveError> {
    if seq.last() == Some(&t) {
        return Ok(());
    }
    if seq.len() >= 2 && seq.get(seq.len() - 2) == Some(&t) {
        seq.pop();
        return Ok(());
    }
    seq.push(t).map_err(|_| SleeveError::Budget)
}

/// True when no triangle repeats.
pub fn is_simple(seq: &[Id]) -> bool {
    seq.iter().enumerate().all(|(i, t)| !seq.iter().skip(i + 1).any(|s| s == t))
}

fn inside_closed(btm: &Btm, t: Id, p: Pt) -> bool {
    let Some([a, b, c]) = btm.tri_points(t) else { return false };
    let tol = -1e-12 * (1.0 + (b - a).norm() * (c - a).norm());
    orient(a, b, p) >= tol && orient(b, c, p) >= tol && orient(c, a, p) >= tol
}

/// Walks the segment `p -> q` from triangle `t` (containing `p`), appending crossed triangles to `seq` reduced.
/// Returns the triangle containing `q`.
pub fn walk_segment(btm: &Btm, mut t: Id, p: Pt, q: Pt, seq: &mut Sleeve) -> Result<Id, SleeveError> {
    let mut came_from = NONE;
    for _ in 0..WALK_BUDGET {
        if inside_closed(btm, t, q) {
            return Ok(t);
        }
        let Some(tr) = btm.tri(t).copied() else { return Err(SleeveError::PointNotInFreeSpace) };
        let Some(ps) = btm.tri_points(t) else { return Err(SleeveError::PointNotInFreeSpace) };
        let mut next = None;
        for i in 0..3 {
            let (a, b) = (corner(&ps, i), corner(&ps, i + 1));
            let n = tr.edge(i).2;
            if n == came_from && n != NONE {
                continue;
            }
            if orient(a, b, q) < 0.0 && orient(p, q, a) <= 0.0 && orient(p, q, b) >= 0.0 {
                next = Some(n);
                break;
            }
        }
        match next {
            Some(n) if n != NONE => {
                came_from = t;
                t = n;
                push_reduced(seq, t)?;
            }
            _ => return Err(SleeveError::SegmentBlocked),
        }
    }
    Err(SleeveError::Budget)
}

/// Reduced crossing sequence of a polyline through the BTM.
pub fn crossing_sequence(btm: &Btm, pts: &[Pt], seq: &mut Sleeve) -> Result<(), SleeveError> {
    seq.clear();
    let Some(&p0) = pts.first() else { return Ok(()) };
    let Some(mut t) = btm.locate(p0) else { return Err(SleeveError::PointNotInFreeSpace) };
    push_reduced(seq, t)?;
    for w in pts.windows(2) {
        if let [a, b] = w {
            t = walk_segment(btm, t, *a, *b, seq)?;
        }
    }
    // The walk may have cancelled the final triangle's entry; make the sequence end where the path ends.
    if seq.last() != Some(&t) {
        push_reduced(seq, t)?;
    }
    Ok(())
}

/// A path with, per point, the BTM vertex it sits on ([`NONE`] for free points such as a0, g, the robot).
#[derive(Clone, Debug, Default)]
pub struct Path {
    /// Points.
    pub pts: HVec<Pt, MAX_PATH>,
    /// BTM vertex under each point, or [`NONE`].
    pub vids: HVec<Id, MAX_PATH>,
}

impl Path {
    /// Euclidean length.
    pub fn length(&self) -> f64 {
        self.pts.windows(2).map(|w| if let [a, b] = w { a.dist(*b) } else { 0.0 }).sum()
    }
    fn push(&mut self, p: Pt, v: Id) -> Result<(), SleeveError> {
        if self.pts.last() == Some(&p) {
            return Ok(());
        }
        self.pts.push(p).map_err(|_| SleeveError::Budget)?;
        self.vids.push(v).map_err(|_| SleeveError::Budget)
    }
}

/// The portal (shared edge) from `t` to `s` as (left, right) vertex ids seen when travelling from `t` into `s`.
pub fn portal(btm: &Btm, t: Id, s: Id) -> Option<(Id, Id)> {
    let tr = btm.tri(t)?;
    (0..3).map(|i| tr.edge(i)).find(|e| e.2 == s).map(|(a, b, _)| (b, a))
}

/// Shortest path from `start` to `goal` inside `sleeve` (start in the first triangle, goal in the last): the SHP of
/// the sleeve's homotopy class, by the simple stupid funnel algorithm.
pub fn shortest_homotopic_path(btm: &Btm, sleeve: &[Id], start: Pt, goal: Pt) -> Result<Path, SleeveError> {
    let vp = |v: Id| btm.vertex(v).map(|x| x.p).unwrap_or_default();
    // Portal i: (left point, right point, left vid, right vid); last portal is the goal itself.
    let n = sleeve.len();
    let portal_at = |i: usize| -> Result<(Pt, Pt, Id, Id), SleeveError> {
        if i + 1 >= n {
            return Ok((goal, goal, NONE, NONE));
        }
        let (Some(&t), Some(&s)) = (sleeve.get(i), sleeve.get(i + 1)) else { return Err(SleeveError::NotAdjacent) };
        let (l, r) = portal(btm, t, s).ok_or(SleeveError::NotAdjacent)?;
        Ok((vp(l), vp(r), l, r))
    };
    let mut path = Path::default();
    path.push(start, NONE)?;
    let (mut apex, mut left, mut right) = (start, start, start);
    let (mut left_v, mut right_v) = (NONE, NONE);
    let (mut left_i, mut right_i) = (0usize, 0usize);
    let mut i = 0usize;
    let mut steps = 0usize;
    while i < n {
        steps += 1;
        if steps > FUNNEL_BUDGET {
            return Err(SleeveError::Budget);
        }
        let (pl, pr, lv, rv) = portal_at(i)?;
        // Tighten the right side.
        if orient(apex, right, pr) >= 0.0 {
            if apex == right || orient(apex, left, pr) < 0.0 {
                right = pr;
                right_v = rv;
                right_i = i;
            } else {
                // Right crosses over left: left becomes the new apex.
                apex = left;
                path.push(apex, left_v)?;
                right = apex;
                right_v = left_v;
                i = left_i + 1;
                right_i = left_i;
                continue;
            }
        }
        // Tighten the left side.
        if orient(apex, left, pl) <= 0.0 {
            if apex == left || orient(apex, right, pl) > 0.0 {
                left = pl;
                left_v = lv;
                left_i = i;
            } else {
                apex = right;
                path.push(apex, right_v)?;
                left = apex;
                left_v = right_v;
                i = right_i + 1;
                left_i = right_i;
                continue;
            }
        }
        i += 1;
    }
    if path.pts.last() != Some(&goal) {
        path.push(goal, NONE)?;
    }
    Ok(path)
}

/// An intermediate anchor point: a bend of the SHP on an obstacle corner (Abad-Manterola IV-C).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Anchor {
    /// Position.
    pub p: Pt,
    /// BTM vertex.
    pub vertex: Id,
    /// Obstacle slot it belongs to (`None` for a concave corner of the plane outline).
    pub obstacle: Option<u8>,
    /// +1 when the tether turns left at this anchor (obstacle on its left), -1 when it turns right.
    pub turn: i8,
}

/// Intermediate anchors a1..ak of an SHP, in order from a0; collinear pass-throughs are dropped.
pub fn anchors(btm: &Btm, shp: &Path) -> HVec<Anchor, MAX_PATH> {
    let mut out = HVec::new();
    let n = shp.pts.len();
    for i in 1..n.saturating_sub(1) {
        let (Some(&a), Some(&b), Some(&c), Some(&v)) = (shp.pts.get(i - 1), shp.pts.get(i), shp.pts.get(i + 1), shp.vids.get(i)) else {
            continue;
        };
        let o = orient(a, b, c);
        if o.abs() <= 1e-12 * (1.0 + (b - a).norm() * (c - b).norm()) {
            continue;
        }
        let obstacle = match btm.vertex(v).map(|x| x.owner) {
            Some(Owner::Obstacle { obstacle, .. }) => Some(obstacle),
            _ => None,
        };
        let _ = out.push(Anchor { p: b, vertex: v, obstacle, turn: if o > 0.0 { 1 } else { -1 } });
    }
    out
}
