//! L-value-constrained A* over BTM triangles (Tanner et al. II-B): enumerates distinct homotopy classes from a start
//! point (a0, or the robot with its tether so far) to the goal g in order of cost.
//!
//! Search states are (triangle, L-value of the path so far); the path runs from the start through the midpoints of
//! the crossed edges. Two states with the same triangle and L-value are the same homotopy class so far: the later
//! (costlier, the heuristic being consistent) one is dropped, so the search is Markovian in (triangle, L) and finds
//! every class in cost order whatever the triangulation. Chains are at most as deep as the BTM has triangles (a
//! simple sleeve visits each once). When a state in g's triangle is popped, its L-value (completed to g) is compared
//! with the classes already found and with the constraint list `Lc`; a new value is a new class unless it winds
//! (Abad-Manterola: "we only consider shortest paths which do not wind around an obstacle"): the loop formed with
//! the straight line back turns more than 1.5 times around some pole. The class's sleeve is its reduced crossing
//! sequence; a class that turns round the far side of an obstacle may cross a large triangle twice, so, as in
//! Hershberger-Snoeyink, the sleeve is taken in the universal cover (a triangle may repeat) and the funnel runs over
//! its portal sequence. Chains are at most 2 x the BTM's triangle count deep.
//!
//! Parameters: `max_classes` (<= `MAX_CLASSES`, default 16), node arena `MAX_SEARCH_NODES` (4096), expansion
//! budget `ASTAR_EXPANSION_BUDGET` (20 000). Cost: Euclidean length of the midpoint path; heuristic: straight-line
//! distance to g. Open list: a [`crate::plan::heap::IndexedHeap`] ordered by (f as its IEEE bits, node index).

use super::btm::{Btm, Id, NONE};
use super::geo::Pt;
use super::lvalue::{segment_log, segment_lvalue, LValue};
use super::sleeve::{push_reduced, Sleeve};
use crate::config::homotopy::{ASTAR_EXPANSION_BUDGET, MAX_CLASSES, MAX_OBSTACLES, MAX_SEARCH_NODES, MAX_SLEEVE, MAX_TRIANGLES};
use crate::plan::heap::{HeapSlot, IndexedHeap, NOT_IN_HEAP};
use crate::plan::status::{Ended, Enumeration, Never, Status};
use heapless::Vec as HVec;

/// One homotopy class from a0 to g.
#[derive(Clone, Debug)]
pub struct HomotopyClass {
    /// Its sleeve (reduced, simple) from a0's triangle to g's triangle.
    pub sleeve: Sleeve,
    /// The triangles of the searched part only (start point's triangle to g's), for paths from the robot.
    pub search_part: Sleeve,
    /// L-value of the class (a0 -> g).
    pub l: LValue,
    /// A* cost of the midpoint path found.
    pub cost: f64,
}

/// How the enumeration ended, the shared [`Status`] with the class enumeration's detail:
/// `Exact(Enumeration::Enough)` — `max_classes` found; `Exact(Enumeration::AllClasses)` — every reachable state
/// expanded, the list is all the classes A* can produce (possibly none); `Approximate(Ended::BudgetExhausted)` —
/// the expansion budget ran out, and `Approximate(Ended::ArenaFull)` — the node arena filled up (the classes found
/// so far are kept either way); `InvalidInput(SearchError)` — start or goal outside the BTM. There is no
/// `NoSolution` case: an exhausted search that found no class is `Exact(AllClasses)` with an empty list.
pub type SearchOutcome = Status<Enumeration, Ended, Never, SearchError>;

/// The word a report prints for `outcome`: `Enough`, `Exhausted`, `BudgetExhausted`, `ArenaFull`, or the
/// input error's name.
pub fn outcome_label(outcome: &SearchOutcome) -> &'static str {
    match outcome {
        Status::Exact(Enumeration::Enough) => "Enough",
        Status::Exact(Enumeration::AllClasses) => "Exhausted",
        Status::Approximate(Ended::ArenaFull) => "ArenaFull",
        Status::Approximate(_) => "BudgetExhausted",
        Status::NoSolution(n) => match *n {},
        Status::InvalidInput(SearchError::StartNotInFreeSpace) => "StartNotInFreeSpace",
        Status::InvalidInput(SearchError::GoalNotInFreeSpace) => "GoalNotInFreeSpace",
    }
}

/// Bad search input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SearchError {
    /// Start point not in any BTM triangle.
    StartNotInFreeSpace,
    /// Goal point not in any BTM triangle.
    GoalNotInFreeSpace,
}

#[derive(Clone, Copy)]
struct Node {
    tri: Id,
    point: Pt,
    g: f64,
    l: LValue,
    parent: u16,
    depth: u16,
    next_same_tri: u16,
    /// Open-list key: `key(f)` of f = g + h.
    key: u64,
    /// Position in the open list.
    heap_pos: u32,
}

const NO_NODE: u16 = u16::MAX;

// Node indices are `u16` (`alloc`'s `i as u16`, below `MAX_SEARCH_NODES`) with `NO_NODE` = `u16::MAX` never a real
// index; chain depths are `u16` below `MAX_SLEEVE`.
const _: () = assert!(MAX_SEARCH_NODES <= u16::MAX as usize);
const _: () = assert!(MAX_SLEEVE <= u16::MAX as usize);

/// Node arena and open list, owned by the caller (about 0.3 MiB).
pub struct SearchArena {
    nodes: [Node; MAX_SEARCH_NODES],
    len: usize,
    head: [u16; MAX_TRIANGLES],
    open: IndexedHeap<MAX_SEARCH_NODES>,
}

/// The open list's order: by `(key, node index)`, the order of the `(u64, u16)` pairs the search queued before
/// it used [`IndexedHeap`] (a strict total order: node indices are unique, so there are no ties).
impl HeapSlot for Node {
    fn before(&self, id: u32, other: &Self, other_id: u32) -> bool {
        (self.key, id) < (other.key, other_id)
    }
    fn heap_position(&self) -> u32 {
        self.heap_pos
    }
    fn set_heap_position(&mut self, pos: u32) {
        self.heap_pos = pos;
    }
}

impl Default for SearchArena {
    fn default() -> Self {
        Self::new()
    }
}

impl SearchArena {
    /// An empty arena (`const`, so a board can keep it in a `static`).
    pub const fn new() -> Self {
        const N: Node = Node {
            tri: NONE,
            point: Pt { x: 0.0, y: 0.0 },
            g: 0.0,
            l: LValue { re: 0.0, im: 0.0 },
            parent: NO_NODE,
            depth: 0,
            next_same_tri: NO_NODE,
            key: u64::MAX,
            heap_pos: NOT_IN_HEAP,
        };
        SearchArena { nodes: [N; MAX_SEARCH_NODES], len: 0, head: [NO_NODE; MAX_TRIANGLES], open: IndexedHeap::new() }
    }
    fn reset(&mut self) {
        self.len = 0;
        self.head = [NO_NODE; MAX_TRIANGLES];
        self.open.clear();
    }
    fn node(&self, i: u16) -> Option<&Node> {
        self.nodes.get(..self.len).and_then(|n| n.get(usize::from(i)))
    }
    fn alloc(&mut self, n: Node) -> Option<u16> {
        let i = self.len;
        let slot = self.nodes.get_mut(i)?;
        *slot = n;
        self.len += 1;
        let idx = i as u16;
        if let Some(h) = self.head.get_mut(usize::from(n.tri)) {
            let old = *h;
            *h = idx;
            if let Some(s) = self.nodes.get_mut(i) {
                s.next_same_tri = old;
            }
        }
        Some(idx)
    }
    /// Queue node `i` with open-list key `k`.
    fn push_open(&mut self, i: u16, k: u64) -> Result<(), crate::plan::heap::Full> {
        if let Some(n) = self.nodes.get_mut(usize::from(i)) {
            n.key = k;
        }
        self.open.push(u32::from(i), &mut self.nodes[..])
    }
    /// Take the open node with the least `(key, index)`.
    fn pop_open(&mut self) -> Option<u16> {
        self.open.pop(&mut self.nodes[..]).map(|i| i as u16)
    }
    fn has_state(&self, tri: Id, l: LValue) -> bool {
        let mut i = self.head.get(usize::from(tri)).copied().unwrap_or(NO_NODE);
        let mut guard = 0;
        while i != NO_NODE && guard < MAX_SEARCH_NODES {
            guard += 1;
            let Some(n) = self.node(i) else { return false };
            if n.l.same_class(l) {
                return true;
            }
            i = n.next_same_tri;
        }
        false
    }
}

fn key(f: f64) -> u64 {
    // Non-negative finite f64 order like their bit patterns.
    if f.is_finite() && f >= 0.0 { f.to_bits() } else { u64::MAX }
}

/// Where the search starts: a point, its L-value so far, and the reduced crossing sequence so far (ending at the
/// point's triangle). For pre-planning: `start = a0`, `l0 = 0`, `prefix = [tri(a0)]`.
#[derive(Clone, Copy, Debug)]
pub struct SearchStart<'a> {
    /// Start point.
    pub point: Pt,
    /// L-value of the tether from a0 to `point`.
    pub l0: LValue,
    /// Reduced crossing sequence of that tether; empty means "just the start point's triangle".
    pub prefix: &'a [Id],
}

/// Enumerates up to `max_classes` homotopy classes to `goal` whose L-values are not in `constraints` (the list
/// `Lc`), appending them to `out` in order of A* cost. Classes whose full sleeve (prefix + searched part) is not
/// simple are skipped. A start or goal outside the BTM is `InvalidInput`.
pub fn enumerate_classes(
    btm: &Btm,
    arena: &mut SearchArena,
    start: &SearchStart<'_>,
    goal: Pt,
    constraints: &[LValue],
    max_classes: usize,
    out: &mut HVec<HomotopyClass, MAX_CLASSES>,
) -> SearchOutcome {
    let t0 = match start.prefix.last() {
        Some(&t) if btm.tri(t).is_some() => t,
        _ => match btm.locate(start.point) {
            Some(t) => t,
            None => return Status::InvalidInput(SearchError::StartNotInFreeSpace),
        },
    };
    let Some(tg) = btm.locate(goal) else { return Status::InvalidInput(SearchError::GoalNotInFreeSpace) };
    arena.reset();
    let h0 = start.point.dist(goal);
    let Some(root) = arena.alloc(Node {
        tri: t0,
        point: start.point,
        g: 0.0,
        l: start.l0,
        parent: NO_NODE,
        depth: 0,
        next_same_tri: NO_NODE,
        key: u64::MAX,
        heap_pos: NOT_IN_HEAP,
    }) else {
        return Status::Approximate(Ended::ArenaFull);
    };
    let _ = arena.push_open(root, key(h0));
    let max_classes = max_classes.min(MAX_CLASSES);
    // A simple sleeve visits each triangle at most once.
    let depth_limit = (2 * btm.triangle_count()).min(MAX_SLEEVE);
    let mut full = false;
    for _ in 0..ASTAR_EXPANSION_BUDGET {
        let Some(ni) = arena.pop_open() else { return Status::Exact(Enumeration::AllClasses) };
        let Some(n) = arena.node(ni).copied() else { continue };
        if n.tri == tg {
            let l = n.l.plus(segment_lvalue(btm, n.point, goal));
            let known = constraints.iter().any(|c| c.same_class(l)) || out.iter().any(|c| c.l.same_class(l));
            if !known {
                if let Some(class) = build_class(btm, arena, ni, start, t0, goal, l, n.g + n.point.dist(goal)) {
                    let _ = out.push(class);
                    if out.len() >= max_classes {
                        return Status::Exact(Enumeration::Enough);
                    }
                }
            }
        }
        if usize::from(n.depth) + 1 >= depth_limit {
            continue;
        }
        let Some(tr) = btm.tri(n.tri).copied() else { continue };
        for i in 0..3 {
            let (va, vb, s) = tr.edge(i);
            if s == NONE {
                continue;
            }
            let (Some(a), Some(b)) = (btm.vertex(va), btm.vertex(vb)) else { continue };
            let m = (a.p + b.p) * 0.5;
            let l = n.l.plus(segment_lvalue(btm, n.point, m));
            if arena.has_state(s, l) {
                continue;
            }
            let g = n.g + n.point.dist(m);
            let node = Node {
                tri: s,
                point: m,
                g,
                l,
                parent: ni,
                depth: n.depth + 1,
                next_same_tri: NO_NODE,
                key: u64::MAX,
                heap_pos: NOT_IN_HEAP,
            };
            match arena.alloc(node) {
                Some(idx) => {
                    if arena.push_open(idx, key(g + m.dist(goal))).is_err() {
                        full = true;
                    }
                }
                None => full = true,
            }
        }
        if full {
            return Status::Approximate(Ended::ArenaFull);
        }
    }
    Status::Approximate(Ended::BudgetExhausted)
}

#[allow(clippy::too_many_arguments)]
fn build_class(
    btm: &Btm,
    arena: &SearchArena,
    mut ni: u16,
    start: &SearchStart<'_>,
    t0: Id,
    goal: Pt,
    l: LValue,
    cost: f64,
) -> Option<HomotopyClass> {
    let mut rev: Sleeve = HVec::new();
    let mut guard = 0;
    let mut prev_pt = goal;
    let mut turns = [0.0f64; MAX_OBSTACLES];
    while ni != NO_NODE && guard <= MAX_SLEEVE {
        guard += 1;
        let n = arena.node(ni)?;
        rev.push(n.tri).ok()?;
        for ((_, o), t) in btm.obstacles().zip(turns.iter_mut()) {
            *t += segment_log(n.point, prev_pt, o.rep).im;
        }
        prev_pt = n.point;
        ni = n.parent;
    }
    // Close the loop with the straight segment start -> goal reversed: the loop's winding number around each pole
    // tells a class that goes once round the far side of an obstacle (|w| <= 1) from one that winds (|w| >= 2).
    for ((_, o), t) in btm.obstacles().zip(turns.iter_mut()) {
        *t += segment_log(goal, start.point, o.rep).im;
        if libm::fabs(*t) > 3.0 * core::f64::consts::PI {
            return None;
        }
    }
    let mut search_part: Sleeve = HVec::new();
    for t in rev.iter().rev() {
        search_part.push(*t).ok()?;
    }
    let mut sleeve: Sleeve = HVec::new();
    if start.prefix.is_empty() {
        sleeve.push(t0).ok()?;
    } else {
        for t in start.prefix {
            push_reduced(&mut sleeve, *t).ok()?;
        }
    }
    for t in search_part.iter().skip(1) {
        push_reduced(&mut sleeve, *t).ok()?;
    }
    Some(HomotopyClass { sleeve, search_part, l, cost })
}
