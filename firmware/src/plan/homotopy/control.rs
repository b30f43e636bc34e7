//! Controllable sets and passability of intermediate anchors (Abad-Manterola et al. IV-C, V-B, VI; Tanner II-A,
//! Fig. 8), for the point-mass robot with Coulomb friction.
//!
//! With the robot at `q` held by its tether to the proximal anchor `a_j` (the previous one being `a_{j-1}`), the
//! controllable set `C_j(q)` is the set of points reachable from `q` through positions that (1) are in free space,
//! (2) see `a_j` (the tether is straight from `a_j`), (3) keep `a_j` as the proximal anchor (same side of the line
//! `a_{j-1} a_j` as `q`), and (4) hold: the tether angle from upslope is at most `theta_max = asin(mu cot alpha)` for
//! the soil there. Its *SHP edge* is the ray from `a_j` continuing `a_{j-1} -> a_j`; crossing it removes `a_j` from
//! the SHP. `a_j` is *passable* when `C_j(q)` reaches a point beyond the SHP edge that holds on `a_{j-1}`.
//!
//! As in the paper (V-B: "computed on a grid"), sets are flood fills on a `CONTROL_GRID` x `CONTROL_GRID` grid
//! (default 72 x 72) over the plane's bounding box; 4-connected; cell centres are tested.

use super::btm::Btm;
use super::geo::{grid_neighbours, orient_sign, Pt};
use super::planes::HoldModel;
use crate::config::homotopy::CONTROL_GRID;

const CELLS: usize = CONTROL_GRID * CONTROL_GRID;

/// Flood-fill storage for controllable sets (caller-owned, ~11 KiB).
pub struct ControlGrid {
    set: [u64; CELLS.div_ceil(64)],
    queue: [u16; CELLS],
    origin: Pt,
    cell: f64,
}

impl Default for ControlGrid {
    fn default() -> Self {
        Self::new()
    }
}

/// Result of one controllable-set construction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ControllableSet {
    /// Cells in the set.
    pub cells: usize,
    /// A point just across the SHP edge from which `a_{j-1}` holds the robot, when `a_j` is passable.
    pub crossing: Option<Pt>,
}

impl ControlGrid {
    /// Empty grid.
    pub const fn new() -> Self {
        ControlGrid { set: [0; CELLS.div_ceil(64)], queue: [0; CELLS], origin: Pt { x: 0.0, y: 0.0 }, cell: 1.0 }
    }
    /// Cell size (m) of the last construction.
    pub fn cell_size(&self) -> f64 {
        self.cell
    }
    /// Centres of the cells in the last constructed set.
    pub fn cells(&self) -> impl Iterator<Item = Pt> + '_ {
        (0..CELLS).filter(|&i| self.contains(i)).map(|i| self.center(i))
    }
    fn contains(&self, i: usize) -> bool {
        self.set.get(i / 64).is_some_and(|w| w & (1u64 << (i % 64)) != 0)
    }
    fn insert(&mut self, i: usize) {
        if let Some(w) = self.set.get_mut(i / 64) {
            *w |= 1u64 << (i % 64);
        }
    }
    fn center(&self, i: usize) -> Pt {
        let (cx, cy) = (i % CONTROL_GRID, i / CONTROL_GRID);
        Pt { x: self.origin.x + (cx as f64 + 0.5) * self.cell, y: self.origin.y + (cy as f64 + 0.5) * self.cell }
    }
    fn cell_of(&self, p: Pt) -> Option<usize> {
        let fx = (p.x - self.origin.x) / self.cell;
        let fy = (p.y - self.origin.y) / self.cell;
        if !(fx >= 0.0 && fy >= 0.0 && fx < CONTROL_GRID as f64 && fy < CONTROL_GRID as f64) {
            return None;
        }
        Some(fy as usize * CONTROL_GRID + fx as usize)
    }

    /// Builds `C_j(q)` for anchor `anchor` (= a_j) with previous anchor `prev` (= a_{j-1}) and reports passability.
    pub fn controllable_set(&mut self, btm: &Btm, model: &HoldModel, q: Pt, prev: Pt, anchor: Pt) -> ControllableSet {
        let (mut lo, mut hi) = (Pt { x: f64::MAX, y: f64::MAX }, Pt { x: f64::MIN, y: f64::MIN });
        for p in btm.plane() {
            lo = Pt { x: lo.x.min(p.x), y: lo.y.min(p.y) };
            hi = Pt { x: hi.x.max(p.x), y: hi.y.max(p.y) };
        }
        self.origin = lo;
        self.cell = ((hi.x - lo.x).max(hi.y - lo.y) / CONTROL_GRID as f64).max(1e-9);
        self.set = [0; CELLS.div_ceil(64)];
        let side = orient_sign(prev, anchor, q);
        let out = ControllableSet { cells: 0, crossing: None };
        let Some(start) = self.cell_of(q) else { return out };
        if side == 0 || !model.holds(q, anchor) {
            return out;
        }
        let dir = anchor - prev;
        let member = |p: Pt| {
            orient_sign(prev, anchor, p) == side && btm.is_free(p) && model.holds(p, anchor) && btm.segment_free(p, anchor)
        };
        let crossing = |p: Pt| {
            orient_sign(prev, anchor, p) != side
                && (p - anchor).dot(dir) > 0.0
                && btm.is_free(p)
                && model.holds(p, prev)
                && btm.segment_free(p, prev)
        };
        self.insert(start);
        if let Some(s) = self.queue.get_mut(0) {
            *s = start as u16;
        }
        let (mut head, mut tail) = (0usize, 1usize);
        let mut found = None;
        while head < tail && head < CELLS {
            let Some(&c) = self.queue.get(head) else { break };
            head += 1;
            let c = usize::from(c);
            for nb in grid_neighbours(c, CONTROL_GRID, CONTROL_GRID).into_iter().flatten() {
                if self.contains(nb) {
                    continue;
                }
                let p = self.center(nb);
                if member(p) {
                    self.insert(nb);
                    if let Some(s) = self.queue.get_mut(tail) {
                        *s = nb as u16;
                        tail += 1;
                    }
                } else if found.is_none() && crossing(p) {
                    found = Some(p);
                }
            }
        }
        ControllableSet { cells: tail, crossing: found }
    }
}
