//! D* Lite over the global grid of scenes (Morad et al. section V-A.7 and Fig. 12; the algorithm is Koenig and
//! Likhachev, "D* Lite", AAAI 2002, the optimised version of their Fig. 4).
//!
//! Each grid cell is a scene. Moves are octile (straight cost 1, diagonal cost sqrt 2) with **no corner cutting**:
//! a diagonal move needs both straight detours open, i.e. both side cells free and none of the four straight
//! edges involved walled. A *wall* is a blocked edge between two neighbouring cells: the team's local planner
//! (bounded-leg A*) failing to cross from one scene to the next is fed back as a wall, exactly the crevasse of
//! Fig. 12 — and because a diagonal that would pass the corner of a wall is also closed, the paper's reroute
//! (1,1),(1,2),(2,2),(2,3),(1,3) comes out as the optimal octile path.
//!
//! D* Lite searches backwards from the goal, so when the robot moves (`move_start`) and the map changes
//! (`block_cell`, `add_wall`), only the affected vertices are updated (`km` keeps old queue keys valid) and
//! `compute_shortest_path` repairs the search incrementally.
//!
//! Storage is lent by the caller ([`DStarStorage`]): per cell `g`, `rhs`, an epoch stamp, a queue key, a heap
//! slot, the occupancy, wall and allowed-move bits, plus the open list's id slots (one per cell), which a
//! [`LentHeap`] (the one heap of [`crate::plan::heap`]) orders by the cells' keys. Planning from scratch starts a new
//! epoch instead of clearing the arrays, so a host can run thousands of Moving AI scenarios on a 512 x 512 map without
//! touching every cell each time. A board uses [`DStarArena`] (capacity [`GLOBAL_GRID_MAX_CELLS`] by default).
//!
//! Parameters: the expansion budget per call (a caller's choice; [`DStarLite::plan`] and [`DStarLite::replan`]
//! take it). Running out of budget is `NoSolution(NoPath { ended: Ended::BudgetExhausted, .. })`; calling `replan`
//! again continues.
//!
//! [`GLOBAL_GRID_MAX_CELLS`]: crate::config::team::GLOBAL_GRID_MAX_CELLS

use core::cmp::Ordering;
use core::f64::consts::SQRT_2;

use crate::plan::heap::{HeapItems, LentHeap, NOT_IN_HEAP};
use crate::plan::status::{Ended, Never, Status};

/// Octile direction offsets (dx, dy); index = direction id. Straight first, then diagonals.
pub const DIRS: [(i32, i32); 8] = [(1, 0), (0, 1), (-1, 0), (0, -1), (1, 1), (-1, 1), (-1, -1), (1, -1)];

const INF: Cost = Cost::INF;

/// An octile path cost a + b * sqrt(2) (a straight moves' worth, b diagonals' worth), held exactly in integers.
///
/// Every cost D* Lite handles on an octile grid — g, rhs, the heuristic, km, the keys — is such a sum, so
/// comparing them exactly (integer arithmetic, [`Cost::cmp`]) removes the floating-point ties that can end a
/// D* Lite search too early (an incremental replan once missed a new wall that way: regression test
/// `km_tie_rounding_hid_a_wall` in `workloads::team`). It is also cheaper than soft-float f64 on the Cortex-M7.
/// Infinity is `a == i32::MAX`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Cost {
    /// Straight part.
    pub a: i32,
    /// Diagonal part (times sqrt 2).
    pub b: i32,
}

impl Cost {
    /// Unreachable.
    pub const INF: Cost = Cost { a: i32::MAX, b: 0 };
    /// Zero.
    pub const ZERO: Cost = Cost { a: 0, b: 0 };
    /// One straight move.
    pub const STRAIGHT: Cost = Cost { a: 1, b: 0 };
    /// One diagonal move.
    pub const DIAGONAL: Cost = Cost { a: 0, b: 1 };

    /// Is this infinity.
    pub fn is_inf(self) -> bool {
        self.a == i32::MAX
    }

    /// Sum (infinity absorbs; saturates to infinity on overflow).
    pub fn plus(self, o: Cost) -> Cost {
        if self.is_inf() || o.is_inf() {
            return Cost::INF;
        }
        match (self.a.checked_add(o.a), self.b.checked_add(o.b)) {
            (Some(a), Some(b)) if a != i32::MAX => Cost { a, b },
            _ => Cost::INF,
        }
    }

    /// The value as f64.
    pub fn to_f64(self) -> f64 {
        if self.is_inf() {
            f64::INFINITY
        } else {
            self.a as f64 + self.b as f64 * SQRT_2
        }
    }
}

impl PartialOrd for Cost {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl Ord for Cost {
    /// Exact order of a + b sqrt 2: sign of da + db sqrt 2 from da^2 vs 2 db^2 (no overflow).
    fn cmp(&self, o: &Self) -> Ordering {
        match (self.is_inf(), o.is_inf()) {
            (true, true) => return Ordering::Equal,
            (true, false) => return Ordering::Greater,
            (false, true) => return Ordering::Less,
            _ => {}
        }
        let da = self.a as i64 - o.a as i64;
        let db = self.b as i64 - o.b as i64;
        if da >= 0 && db >= 0 {
            if da == 0 && db == 0 {
                Ordering::Equal
            } else {
                Ordering::Greater
            }
        } else if da <= 0 && db <= 0 {
            Ordering::Less
        } else {
            // opposite signs: compare da^2 with 2 db^2 (i64 while |da|, |db| < 2^30, else i128)
            let small = da.unsigned_abs() < (1 << 30) && db.unsigned_abs() < (1 << 30);
            let ord = if small {
                (da * da).cmp(&(2 * db * db))
            } else {
                let (da, db) = (da as i128, db as i128);
                (da * da).cmp(&(2 * db * db))
            };
            if da > 0 {
                ord
            } else {
                ord.reverse()
            }
        }
    }
}

/// A cell's queue key (k1, k2), compared lexicographically.
pub type Key = (Cost, Cost);

/// Storage lent to the planner; every slice must hold at least `width * height` entries.
pub struct DStarStorage<'a> {
    /// Cost-to-goal estimates g.
    pub g: &'a mut [Cost],
    /// One-step lookahead values rhs.
    pub rhs: &'a mut [Cost],
    /// Epoch stamp per cell (lazy reset).
    pub stamp: &'a mut [u32],
    /// Queue key per cell (meaningful while the cell is queued).
    pub key: &'a mut [Key],
    /// Heap slot per cell.
    pub heap_pos: &'a mut [u32],
    /// The open list's id slots (the queued cells, in heap order).
    pub heap: &'a mut [u32],
    /// Occupancy: `true` = blocked cell.
    pub blocked: &'a mut [bool],
    /// Wall bits per cell: bit d set = the edge in direction `DIRS[d]` is walled.
    pub walls: &'a mut [u8],
    /// Allowed-move bits per cell (derived from `blocked` and `walls`, kept up to date by the planner).
    pub moves: &'a mut [u8],
}

impl DStarStorage<'_> {
    /// The cells this storage holds (its shortest slice).
    pub fn cells(&self) -> usize {
        [
            self.g.len(),
            self.rhs.len(),
            self.stamp.len(),
            self.key.len(),
            self.heap_pos.len(),
            self.heap.len(),
            self.blocked.len(),
            self.walls.len(),
            self.moves.len(),
        ]
        .into_iter()
        .min()
        .unwrap_or(0)
    }
}

/// Fixed arena for a board: `N` cells.
pub struct DStarArena<const N: usize> {
    g: [Cost; N],
    rhs: [Cost; N],
    stamp: [u32; N],
    key: [Key; N],
    heap_pos: [u32; N],
    heap: [u32; N],
    blocked: [bool; N],
    walls: [u8; N],
    moves: [u8; N],
}

impl<const N: usize> DStarArena<N> {
    /// An empty arena (place it in a `static` or a `Box` — it is large).
    pub const fn new() -> Self {
        Self {
            g: [INF; N],
            rhs: [INF; N],
            stamp: [0; N],
            key: [(Cost::ZERO, Cost::ZERO); N],
            heap_pos: [NOT_IN_HEAP; N],
            heap: [0; N],
            blocked: [false; N],
            walls: [0; N],
            moves: [0; N],
        }
    }

    /// Lend the arena to a planner.
    pub fn storage(&mut self) -> DStarStorage<'_> {
        DStarStorage {
            g: &mut self.g,
            rhs: &mut self.rhs,
            stamp: &mut self.stamp,
            key: &mut self.key,
            heap_pos: &mut self.heap_pos,
            heap: &mut self.heap,
            blocked: &mut self.blocked,
            walls: &mut self.walls,
            moves: &mut self.moves,
        }
    }
}

impl<const N: usize> Default for DStarArena<N> {
    fn default() -> Self {
        Self::new()
    }
}

/// Why the planner could not be set up or asked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DStarError {
    /// A storage slice is shorter than `width * height`.
    StorageTooSmall {
        /// Cells needed.
        needed: usize,
        /// Length of the shortest slice.
        have: usize,
    },
    /// Width or height is zero, or the cell count does not fit in `u32`.
    BadSize,
    /// A cell outside the grid.
    OutOfGrid {
        /// Column.
        x: i64,
        /// Row.
        y: i64,
    },
    /// The two cells of a wall are not 8-neighbours.
    NotNeighbours,
    /// `replan`, `move_start` or path extraction before `plan`.
    NotPlanned,
}

/// Result of a (re)planning call, the shared [`Status`] with D* Lite's detail: `Exact(Found)` — the shortest
/// path's cost; `NoSolution(NoPath)` — with [`Ended::SearchComplete`] the goal is not reachable from the start
/// (search completed, or the start or goal cell is blocked), with [`Ended::BudgetExhausted`] the expansion budget
/// ran out: the search state is kept, call `replan` to continue. D* Lite never returns an approximate path, and a
/// bad call is a [`DStarError`].
pub type DStarOutcome = Status<Found, Never, NoPath, Never>;

/// A shortest path was found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Found {
    /// Octile cost from the start to the goal.
    pub cost: f64,
    /// Vertices expanded in this call.
    pub expansions: u32,
}

/// No path: proved ([`Ended::SearchComplete`]) or not yet ([`Ended::BudgetExhausted`], call `replan`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct NoPath {
    /// Why the search ended.
    pub ended: Ended,
    /// Vertices expanded in this call.
    pub expansions: u32,
}

/// The word a report prints for `outcome`: `Found`, `NoPath` (search complete) or `BudgetExhausted`.
pub fn outcome_label(outcome: &DStarOutcome) -> &'static str {
    match outcome {
        Status::Exact(_) => "Found",
        Status::NoSolution(NoPath { ended: Ended::BudgetExhausted, .. }) => "BudgetExhausted",
        Status::NoSolution(_) => "NoPath",
        Status::Approximate(n) | Status::InvalidInput(n) => match *n {},
    }
}

/// Result of a path extraction into a caller buffer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PathOutcome {
    /// The whole path (start and goal included) was written; its length in cells.
    Complete(usize),
    /// The buffer filled before the goal; the prefix written is valid.
    BufferFull(usize),
    /// No finite path from the start.
    NoPath,
}

/// D* Lite on an octile grid with walls, over lent storage.
pub struct DStarLite<'a> {
    width: u32,
    height: u32,
    s: Cells<'a>,
    open: LentHeap<'a>,
    km: Cost,
    start: u32,
    last: u32,
    goal: u32,
    planned: bool,
}

#[inline]
fn key_less(a: Key, b: Key) -> bool {
    a < b
}

/// The per-cell arrays of [`DStarStorage`] (all but the heap's id slots) and the current epoch: the items the open
/// list orders ([`HeapItems`]: by [`key_less`] on the cells' keys).
struct Cells<'a> {
    g: &'a mut [Cost],
    rhs: &'a mut [Cost],
    stamp: &'a mut [u32],
    key: &'a mut [Key],
    heap_pos: &'a mut [u32],
    blocked: &'a mut [bool],
    walls: &'a mut [u8],
    moves: &'a mut [u8],
    epoch: u32,
}

impl Cells<'_> {
    #[inline]
    fn fresh(&self, c: u32) -> bool {
        self.stamp.get(c as usize).copied() == Some(self.epoch)
    }
}

impl HeapItems for Cells<'_> {
    #[inline]
    fn before(&self, a: u32, b: u32) -> bool {
        match (self.key.get(a as usize), self.key.get(b as usize)) {
            (Some(&ka), Some(&kb)) => key_less(ka, kb),
            _ => false,
        }
    }
    #[inline]
    fn set_position(&mut self, id: u32, pos: u32) {
        if let Some(p) = self.heap_pos.get_mut(id as usize) {
            *p = pos;
        }
    }
    /// A cell not touched in this epoch is not queued.
    #[inline]
    fn position(&self, id: u32) -> Option<u32> {
        if self.fresh(id) {
            self.heap_pos.get(id as usize).copied()
        } else {
            None
        }
    }
}

impl<'a> DStarLite<'a> {
    /// A planner over a `width` x `height` grid, all cells free, no walls.
    pub fn new(width: u32, height: u32, storage: DStarStorage<'a>) -> Result<Self, DStarError> {
        if width == 0 || height == 0 {
            return Err(DStarError::BadSize);
        }
        let cells = (width as u64) * (height as u64);
        if cells >= u32::MAX as u64 {
            return Err(DStarError::BadSize);
        }
        let cells = cells as usize;
        let have = storage.cells();
        if have < cells {
            return Err(DStarError::StorageTooSmall { needed: cells, have });
        }
        let DStarStorage { g, rhs, stamp, key, heap_pos, heap, blocked, walls, moves } = storage;
        let s = Cells { g, rhs, stamp, key, heap_pos, blocked, walls, moves, epoch: 0 };
        let open = LentHeap::lent(heap);
        let mut me = Self { width, height, s, open, km: Cost::ZERO, start: 0, last: 0, goal: 0, planned: false };
        // Stamps left by an earlier planner on the same storage would make its stale g / rhs look current (its
        // epochs start at 1 like ours): clear them (bounded by the cell count).
        for st in me.s.stamp.iter_mut().take(cells) {
            *st = 0;
        }
        me.clear_map();
        me.new_epoch();
        Ok(me)
    }

    /// The lent storage, handed back for the next planner (its contents are stale: [`Self::new`] clears what it
    /// must).
    pub fn into_storage(self) -> DStarStorage<'a> {
        let Cells { g, rhs, stamp, key, heap_pos, blocked, walls, moves, epoch: _ } = self.s;
        DStarStorage { g, rhs, stamp, key, heap_pos, heap: self.open.into_slots(), blocked, walls, moves }
    }

    /// Grid width (columns).
    pub fn width(&self) -> u32 {
        self.width
    }

    /// Grid height (rows).
    pub fn height(&self) -> u32 {
        self.height
    }

    fn cells(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Free every cell and remove every wall (does not update a running search: call `plan` afterwards).
    pub fn clear_map(&mut self) {
        let n = self.cells();
        for b in self.s.blocked.iter_mut().take(n) {
            *b = false;
        }
        for w in self.s.walls.iter_mut().take(n) {
            *w = 0;
        }
        for y in 0..self.height as i64 {
            for x in 0..self.width as i64 {
                self.update_mask(x, y);
            }
        }
        self.planned = false;
    }

    fn new_epoch(&mut self) {
        if self.s.epoch == u32::MAX {
            let n = self.cells();
            for st in self.s.stamp.iter_mut().take(n) {
                *st = 0;
            }
            self.s.epoch = 0;
        }
        self.s.epoch += 1;
        self.open.clear();
    }

    /// Cell index of (x, y), if inside the grid.
    pub fn index(&self, x: i64, y: i64) -> Option<u32> {
        if x >= 0 && y >= 0 && x < self.width as i64 && y < self.height as i64 {
            Some((y as u32) * self.width + x as u32)
        } else {
            None
        }
    }

    /// (x, y) of a cell index.
    pub fn coords(&self, c: u32) -> (i64, i64) {
        // `width >= 1` (checked by `new`); the checked forms leave no division-by-zero panic path in the flight build
        (c.checked_rem(self.width).unwrap_or(0) as i64, c.checked_div(self.width).unwrap_or(0) as i64)
    }

    fn idx_or_err(&self, x: i64, y: i64) -> Result<u32, DStarError> {
        self.index(x, y).ok_or(DStarError::OutOfGrid { x, y })
    }

    /// Is the cell blocked (outside = blocked).
    pub fn is_blocked(&self, x: i64, y: i64) -> bool {
        match self.index(x, y) {
            Some(c) => self.s.blocked.get(c as usize).copied().unwrap_or(true),
            None => true,
        }
    }

    fn wall_bit(&self, c: u32, d: usize) -> bool {
        self.s.walls.get(c as usize).map(|w| w & (1u8 << d) != 0).unwrap_or(true)
    }

    /// Cost of the move from cell (x, y) in direction `d`, `INF` when not allowed (from the cached move bits).
    #[inline]
    fn move_cost(&self, x: i64, y: i64, d: usize) -> Cost {
        let bits = match self.index(x, y) {
            Some(c) => self.s.moves.get(c as usize).copied().unwrap_or(0),
            None => 0,
        };
        if bits & (1u8 << (d & 7)) == 0 {
            INF
        } else if d < 4 {
            Cost::STRAIGHT
        } else {
            Cost::DIAGONAL
        }
    }

    fn update_mask(&mut self, x: i64, y: i64) {
        if let Some(c) = self.index(x, y) {
            let mut bits = 0u8;
            for d in 0..8 {
                if self.rule_cost(x, y, d) < INF {
                    bits |= 1u8 << d;
                }
            }
            if let Some(m) = self.s.moves.get_mut(c as usize) {
                *m = bits;
            }
        }
    }

    fn update_masks_around(&mut self, x: i64, y: i64) {
        for dy in -1..=1 {
            for dx in -1..=1 {
                self.update_mask(x + dx, y + dy);
            }
        }
    }

    /// The movement rules: cost of the move from (x, y) in direction `d`, `INF` when not allowed.
    fn rule_cost(&self, x: i64, y: i64, d: usize) -> Cost {
        let (dx, dy) = match DIRS.get(d) {
            Some(&(dx, dy)) => (dx as i64, dy as i64),
            None => return INF,
        };
        let a = match self.index(x, y) {
            Some(a) => a,
            None => return INF,
        };
        if self.is_blocked(x, y) || self.is_blocked(x + dx, y + dy) || self.wall_bit(a, d) {
            return INF;
        }
        if dx == 0 || dy == 0 {
            return Cost::STRAIGHT;
        }
        // diagonal: both side cells free and the four straight edges of the two detours unwalled
        if self.is_blocked(x + dx, y) || self.is_blocked(x, y + dy) {
            return INF;
        }
        let (sx, sy) = (self.index(x + dx, y), self.index(x, y + dy));
        let (sx, sy) = match (sx, sy) {
            (Some(p), Some(q)) => (p, q),
            _ => return INF,
        };
        let dir_x = if dx > 0 { 0 } else { 2 };
        let dir_y = if dy > 0 { 1 } else { 3 };
        if self.wall_bit(a, dir_x) || self.wall_bit(sx, dir_y) || self.wall_bit(a, dir_y) || self.wall_bit(sy, dir_x) {
            return INF;
        }
        Cost::DIAGONAL
    }

    /// Octile distance: (max - min) straight + min diagonal.
    fn h(&self, a: u32, b: u32) -> Cost {
        let (ax, ay) = self.coords(a);
        let (bx, by) = self.coords(b);
        let dx = (ax - bx).unsigned_abs() as i32;
        let dy = (ay - by).unsigned_abs() as i32;
        let (mx, mn) = if dx > dy { (dx, dy) } else { (dy, dx) };
        Cost { a: mx - mn, b: mn }
    }

    fn fresh(&self, c: u32) -> bool {
        self.s.fresh(c)
    }

    /// g of a cell in the current search (cost to the goal), as f64.
    pub fn g(&self, c: u32) -> f64 {
        self.gc(c).to_f64()
    }

    fn gc(&self, c: u32) -> Cost {
        if self.fresh(c) {
            self.s.g.get(c as usize).copied().unwrap_or(INF)
        } else {
            INF
        }
    }

    fn rhs(&self, c: u32) -> Cost {
        if self.fresh(c) {
            self.s.rhs.get(c as usize).copied().unwrap_or(INF)
        } else {
            INF
        }
    }

    fn touch(&mut self, c: u32) {
        let i = c as usize;
        if !self.fresh(c) {
            if let Some(v) = self.s.g.get_mut(i) {
                *v = INF;
            }
            if let Some(v) = self.s.rhs.get_mut(i) {
                *v = INF;
            }
            if let Some(v) = self.s.heap_pos.get_mut(i) {
                *v = NOT_IN_HEAP;
            }
            if let Some(v) = self.s.stamp.get_mut(i) {
                *v = self.s.epoch;
            }
        }
    }

    fn set_g(&mut self, c: u32, v: Cost) {
        self.touch(c);
        if let Some(x) = self.s.g.get_mut(c as usize) {
            *x = v;
        }
    }

    fn set_rhs(&mut self, c: u32, v: Cost) {
        self.touch(c);
        if let Some(x) = self.s.rhs.get_mut(c as usize) {
            *x = v;
        }
    }

    fn calc_key(&self, c: u32) -> Key {
        let m = self.gc(c).min(self.rhs(c));
        (m.plus(self.h(self.start, c)).plus(self.km), m)
    }

    // ---- the open list: a LentHeap of cells, ordered by their keys ----
    /// Queue `c` with key `k`, or move it to its new place if it is queued already.
    fn heap_insert_or_update(&mut self, c: u32, k: Key) {
        self.touch(c);
        if let Some(e) = self.s.key.get_mut(c as usize) {
            *e = k;
        }
        if self.open.contains(c, &self.s) {
            self.open.update(c, &mut self.s);
        } else {
            // capacity = cells, and each cell is in the heap at most once, so this always fits; were it full, the
            // cell would stay unqueued (no panic)
            let _ = self.open.push(c, &mut self.s);
        }
    }

    fn heap_remove(&mut self, c: u32) {
        self.open.remove(c, &mut self.s);
    }

    fn top(&self) -> Option<(u32, Key)> {
        let c = self.open.peek()?;
        self.s.key.get(c as usize).map(|&k| (c, k))
    }

    // ---- D* Lite proper ----
    fn update_vertex(&mut self, u: u32) {
        let (g, r) = (self.gc(u), self.rhs(u));
        let in_heap = self.open.contains(u, &self.s);
        if g != r {
            let k = self.calc_key(u);
            self.heap_insert_or_update(u, k);
        } else if in_heap {
            self.heap_remove(u);
        }
    }

    /// min over successors s' of c(u, s') + g(s').
    fn best_succ(&self, u: u32) -> Cost {
        let (x, y) = self.coords(u);
        let mut best = INF;
        for (d, &(dx, dy)) in DIRS.iter().enumerate() {
            let c = self.move_cost(x, y, d);
            if c < INF {
                if let Some(v) = self.index(x + dx as i64, y + dy as i64) {
                    let t = c.plus(self.gc(v));
                    if t < best {
                        best = t;
                    }
                }
            }
        }
        best
    }

    fn recompute_rhs(&mut self, u: u32) {
        if u != self.goal {
            let b = self.best_succ(u);
            self.set_rhs(u, b);
        }
        self.update_vertex(u);
    }

    fn compute_shortest_path(&mut self, budget: u32) -> DStarOutcome {
        let mut expansions = 0u32;
        loop {
            let start_key = self.calc_key(self.start);
            let (u, k_old) = match self.top() {
                Some(t) => t,
                None => break,
            };
            if !(key_less(k_old, start_key) || self.rhs(self.start) > self.gc(self.start)) {
                break;
            }
            if expansions >= budget {
                return Status::NoSolution(NoPath { ended: Ended::BudgetExhausted, expansions });
            }
            expansions += 1;
            let k_new = self.calc_key(u);
            let (gu, ru) = (self.gc(u), self.rhs(u));
            if key_less(k_old, k_new) {
                self.heap_insert_or_update(u, k_new);
            } else if gu > ru {
                self.set_g(u, ru);
                self.heap_remove(u);
                let (x, y) = self.coords(u);
                for (d, &(dx, dy)) in DIRS.iter().enumerate() {
                    // moves are symmetric: pred s of u with c(s,u) = c(u,s)
                    let c = self.move_cost(x, y, d);
                    if c < INF {
                        if let Some(s) = self.index(x + dx as i64, y + dy as i64) {
                            if s != self.goal {
                                let cand = c.plus(ru);
                                if cand < self.rhs(s) {
                                    self.set_rhs(s, cand);
                                }
                            }
                            self.update_vertex(s);
                        }
                    }
                }
            } else {
                let g_old = gu;
                self.set_g(u, INF);
                let (x, y) = self.coords(u);
                for (d, &(dx, dy)) in DIRS.iter().enumerate() {
                    let c = self.move_cost(x, y, d);
                    if c < INF {
                        if let Some(s) = self.index(x + dx as i64, y + dy as i64) {
                            if self.rhs(s) == c.plus(g_old) && s != self.goal {
                                let b = self.best_succ(s);
                                self.set_rhs(s, b);
                            }
                            self.update_vertex(s);
                        }
                    }
                }
                if self.rhs(u) == g_old && u != self.goal {
                    let b = self.best_succ(u);
                    self.set_rhs(u, b);
                }
                self.update_vertex(u);
            }
        }
        let cost = self.rhs(self.start);
        if cost < INF {
            Status::Exact(Found { cost: cost.to_f64(), expansions })
        } else {
            Status::NoSolution(NoPath { ended: Ended::SearchComplete, expansions })
        }
    }

    /// Plan from scratch from `start` to `goal` (cells as (x, y)), expanding at most `budget` vertices.
    pub fn plan(&mut self, start: (i64, i64), goal: (i64, i64), budget: u32) -> Result<DStarOutcome, DStarError> {
        let s = self.idx_or_err(start.0, start.1)?;
        let g = self.idx_or_err(goal.0, goal.1)?;
        self.new_epoch();
        self.start = s;
        self.last = s;
        self.goal = g;
        self.km = Cost::ZERO;
        self.planned = true;
        if self.is_blocked(goal.0, goal.1) || self.is_blocked(start.0, start.1) {
            return Ok(Status::NoSolution(NoPath { ended: Ended::SearchComplete, expansions: 0 }));
        }
        self.set_rhs(g, Cost::ZERO);
        let k = (self.h(s, g), Cost::ZERO);
        self.heap_insert_or_update(g, k);
        Ok(self.compute_shortest_path(budget))
    }

    /// Continue / repair the search after `move_start`, `block_cell` or `add_wall`.
    pub fn replan(&mut self, budget: u32) -> Result<DStarOutcome, DStarError> {
        if !self.planned {
            return Err(DStarError::NotPlanned);
        }
        let (sx, sy) = self.coords(self.start);
        if self.is_blocked(sx, sy) {
            return Ok(Status::NoSolution(NoPath { ended: Ended::SearchComplete, expansions: 0 }));
        }
        Ok(self.compute_shortest_path(budget))
    }

    /// The robot moved to `start` (any cell; normally the next cell of the path).
    pub fn move_start(&mut self, start: (i64, i64)) -> Result<(), DStarError> {
        if !self.planned {
            return Err(DStarError::NotPlanned);
        }
        let s = self.idx_or_err(start.0, start.1)?;
        self.km = self.km.plus(self.h(self.last, s));
        self.last = s;
        self.start = s;
        Ok(())
    }

    fn refresh_around(&mut self, x: i64, y: i64) {
        if !self.planned {
            return;
        }
        for dy in -1..=1 {
            for dx in -1..=1 {
                if let Some(c) = self.index(x + dx, y + dy) {
                    self.recompute_rhs(c);
                }
            }
        }
    }

    /// Mark a cell blocked or free; a running search is updated incrementally (call `replan`).
    pub fn set_blocked(&mut self, x: i64, y: i64, blocked: bool) -> Result<(), DStarError> {
        let c = self.idx_or_err(x, y)?;
        if let Some(b) = self.s.blocked.get_mut(c as usize) {
            if *b == blocked {
                return Ok(());
            }
            *b = blocked;
        }
        self.update_masks_around(x, y);
        self.refresh_around(x, y);
        Ok(())
    }

    /// Wall the edge between two 8-neighbouring cells (a local crossing failed); incremental like `set_blocked`.
    pub fn add_wall(&mut self, a: (i64, i64), b: (i64, i64)) -> Result<(), DStarError> {
        let ca = self.idx_or_err(a.0, a.1)?;
        let cb = self.idx_or_err(b.0, b.1)?;
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let d_ab = DIRS.iter().position(|&(x, y)| x as i64 == dx && y as i64 == dy).ok_or(DStarError::NotNeighbours)?;
        let d_ba = DIRS.iter().position(|&(x, y)| x as i64 == -dx && y as i64 == -dy).ok_or(DStarError::NotNeighbours)?;
        if let Some(w) = self.s.walls.get_mut(ca as usize) {
            *w |= 1u8 << d_ab;
        }
        if let Some(w) = self.s.walls.get_mut(cb as usize) {
            *w |= 1u8 << d_ba;
        }
        self.update_masks_around(a.0, a.1);
        self.update_masks_around(b.0, b.1);
        self.refresh_around(a.0, a.1);
        self.refresh_around(b.0, b.1);
        Ok(())
    }

    /// Cost of the current shortest path from the start (`INF` when none).
    pub fn cost(&self) -> f64 {
        self.rhs(self.start).to_f64()
    }

    /// Current start cell.
    pub fn start(&self) -> (i64, i64) {
        self.coords(self.start)
    }

    /// Best next cell from `from` (greedy on c + g), `None` at the goal or with no finite path.
    pub fn next_cell(&self, from: (i64, i64)) -> Option<(i64, i64)> {
        let u = self.index(from.0, from.1)?;
        if u == self.goal {
            return None;
        }
        let mut best = INF;
        let mut arg = None;
        for (d, &(dx, dy)) in DIRS.iter().enumerate() {
            let c = self.move_cost(from.0, from.1, d);
            if c < INF {
                let (nx, ny) = (from.0 + dx as i64, from.1 + dy as i64);
                if let Some(v) = self.index(nx, ny) {
                    let t = c.plus(self.gc(v));
                    if t < best {
                        best = t;
                        arg = Some((nx, ny));
                    }
                }
            }
        }
        arg
    }

    /// Write the path from the start to the goal into `out` (cells as (x, y)).
    pub fn path(&self, out: &mut [(i64, i64)]) -> Result<PathOutcome, DStarError> {
        if !self.planned {
            return Err(DStarError::NotPlanned);
        }
        if self.rhs(self.start).is_inf() {
            return Ok(PathOutcome::NoPath);
        }
        let mut cur = self.coords(self.start);
        let mut n = 0usize;
        // a shortest path visits each cell at most once: bounded by the cell count
        for _ in 0..=self.cells() {
            match out.get_mut(n) {
                Some(slot) => *slot = cur,
                None => return Ok(PathOutcome::BufferFull(n)),
            }
            n += 1;
            match self.next_cell(cur) {
                Some(nx) => cur = nx,
                None => break,
            }
        }
        if self.index(cur.0, cur.1) == Some(self.goal) {
            Ok(PathOutcome::Complete(n))
        } else {
            Ok(PathOutcome::NoPath)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Owned {
        g: [Cost; 64],
        rhs: [Cost; 64],
        stamp: [u32; 64],
        key: [Key; 64],
        pos: [u32; 64],
        heap: [u32; 64],
        blocked: [bool; 64],
        walls: [u8; 64],
        moves: [u8; 64],
    }

    #[test]
    fn exact_cost_order_matches_real_numbers() {
        // 99 - 70 sqrt 2 = 0.00505..., 70 sqrt 2 - 99 < 0; and the Pell pair 577 vs 408 sqrt 2
        let c = |a, b| Cost { a, b };
        assert!(c(99, 0) > c(0, 70));
        assert!(c(0, 408) < c(577, 0));
        assert!(c(3, 1) > c(1, 2)); // 4.414 > 3.828
        assert!(c(1, 2) < c(3, 1));
        assert_eq!(c(2, 2).cmp(&c(2, 2)), Ordering::Equal);
        assert!(Cost::INF > c(1_000_000, 1_000_000));
        // beyond 2^30 (the i128 branch): 1 414 213 562 sqrt 2 = 1 999 999 999.4
        assert!(c(2_000_000_000, 0) > c(0, 1_414_213_562));
        assert!(c(0, 1_414_213_563) > c(2_000_000_000, 0));
        assert_eq!(c(i32::MAX - 1, 0).plus(c(5, 0)), Cost::INF);
        for a in -30..30 {
            for b in -30..30 {
                let x = c(a, b);
                let y = c(7, -3);
                let (fx, fy) = (a as f64 + b as f64 * SQRT_2, 7.0 - 3.0 * SQRT_2);
                assert_eq!(x.cmp(&y), fx.partial_cmp(&fy).unwrap(), "{a} {b}");
            }
        }
    }

    #[test]
    fn storage_too_small_is_typed() {
        let mut o = Owned {
            g: [Cost::ZERO; 64],
            rhs: [Cost::ZERO; 64],
            stamp: [0; 64],
            key: [(Cost::ZERO, Cost::ZERO); 64],
            pos: [0; 64],
            heap: [0; 64],
            blocked: [false; 64],
            walls: [0; 64],
            moves: [0; 64],
        };
        let st = DStarStorage {
            g: &mut o.g,
            rhs: &mut o.rhs,
            stamp: &mut o.stamp,
            key: &mut o.key,
            heap_pos: &mut o.pos,
            heap: &mut o.heap[..10],
            blocked: &mut o.blocked,
            walls: &mut o.walls,
            moves: &mut o.moves,
        };
        assert_eq!(DStarLite::new(8, 8, st).err(), Some(DStarError::StorageTooSmall { needed: 64, have: 10 }));
    }

    #[test]
    fn open_grid_cost_is_octile_distance() {
        let mut arena: DStarArena<64> = DStarArena::new();
        let mut d = DStarLite::new(8, 8, arena.storage()).unwrap();
        let out = d.plan((0, 0), (7, 3), 10_000).unwrap();
        match out {
            Status::Exact(Found { cost, .. }) => assert!((cost - (4.0 + 3.0 * SQRT_2)).abs() < 1e-12),
            other => panic!("{other:?}"),
        }
        assert_eq!(d.plan((0, 0), (9, 0), 10).err(), Some(DStarError::OutOfGrid { x: 9, y: 0 }));
    }

    #[test]
    fn budget_exhausted_then_continues() {
        let mut arena: DStarArena<64> = DStarArena::new();
        let mut d = DStarLite::new(8, 8, arena.storage()).unwrap();
        let out = d.plan((0, 0), (7, 7), 2).unwrap();
        assert!(matches!(out, Status::NoSolution(NoPath { ended: Ended::BudgetExhausted, expansions: 2 })));
        let out = d.replan(10_000).unwrap();
        assert!(matches!(out, Status::Exact(Found { cost, .. }) if (cost - 7.0 * SQRT_2).abs() < 1e-12));
    }

    #[test]
    fn crevasse_reroute_of_fig_12() {
        // cells (x, y) = (column, row), 1-based as in the paper; (1,1) -> (1,3) is "south".
        let mut arena: DStarArena<64> = DStarArena::new();
        let mut d = DStarLite::new(5, 5, arena.storage()).unwrap();
        // the column x = 0 is off the map in the paper's figure: block it so the reroute must go east
        for y in 0..5 {
            d.set_blocked(0, y, true).unwrap();
        }
        let out = d.plan((1, 1), (1, 3), 1000).unwrap();
        assert!(matches!(out, Status::Exact(Found { cost, .. }) if cost == 2.0));
        let mut p = [(0i64, 0i64); 16];
        assert_eq!(d.path(&mut p).unwrap(), PathOutcome::Complete(3));
        assert_eq!(&p[..3], &[(1, 1), (1, 2), (1, 3)]);
        d.move_start((1, 2)).unwrap();
        d.add_wall((1, 2), (1, 3)).unwrap();
        let out = d.replan(1000).unwrap();
        assert!(matches!(out, Status::Exact(Found { cost, .. }) if cost == 3.0), "{out:?}");
        assert_eq!(d.path(&mut p).unwrap(), PathOutcome::Complete(4));
        assert_eq!(&p[..4], &[(1, 2), (2, 2), (2, 3), (1, 3)]);
    }
}
