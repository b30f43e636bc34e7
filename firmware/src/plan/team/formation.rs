//! The team: robots tethered to a hub in an "x", the climbing order and the hub motion, node loss
//! (Morad et al. sections III-IV, V-A.6).
//!
//! - **Climbing order** (section IV, Fig. 4): one robot moves while the others stay gripped; robots take turns
//!   in index order, skipping robots whose tether is cut. [`Team::next_mover`] gives the next one.
//! - **Hub motion**: the hub is held by the gripped robots during a hop; after a round (every attached robot has
//!   had its turn) it is drawn towards the "instantaneous center" (the centroid of the attached robots, section IV
//!   Fig. 5) as far as every attached robot's leg stays within r_max (bisection on the step, [`HUB_BISECTION_STEPS`]
//!   steps; a zero step is always feasible, so the tether limit is never broken by the hub).
//! - **Node loss** (section V-A.6): a robot that fails cuts its tether ([`Team::cut_tether`]); the rest keep
//!   planning independently, indifferent to the loss.
//!
//! Each robot's goal is the team goal plus its slot vector (its leg at the start), so the "x" is kept.
//! Capacity: the team size is the const generic `N` (default [`TEAM_SIZE`] = 4).
//!
//! [`TEAM_SIZE`]: crate::config::team::TEAM_SIZE
//! [`HUB_BISECTION_STEPS`]: crate::config::team::HUB_BISECTION_STEPS

use crate::config::team::HUB_BISECTION_STEPS;
use crate::geom::{norm3, Real, Vec3};

/// One robot as the team sees it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robot {
    /// Anchor position (where it grips).
    pub pos: Vec3,
    /// Tether to the hub intact.
    pub attached: bool,
}

/// A team of `N` robots and a hub.
#[derive(Debug, Clone, PartialEq)]
pub struct Team<const N: usize> {
    /// The robots.
    pub robots: [Robot; N],
    /// Hub position.
    pub hub: Vec3,
    /// Slot vectors: each robot's leg at the start.
    pub slots: [Vec3; N],
    turn: usize,
    last: Option<usize>,
}

impl<const N: usize> Team<N> {
    /// A team gripping at `positions`, hub at their centroid (the instantaneous center).
    pub fn new(positions: [Vec3; N]) -> Self {
        let mut c = Vec3::zeros();
        for p in &positions {
            c += p;
        }
        c /= N.max(1) as Real;
        let mut slots = [Vec3::zeros(); N];
        for (s, p) in slots.iter_mut().zip(positions.iter()) {
            *s = p - c;
        }
        let mut robots = [Robot { pos: Vec3::zeros(), attached: true }; N];
        for (r, p) in robots.iter_mut().zip(positions.iter()) {
            r.pos = *p;
        }
        Self { robots, hub: c, slots, turn: 0, last: None }
    }

    /// Hub-to-robot vector c_m (what robot m measures with its draw-wire encoder).
    pub fn leg(&self, m: usize) -> Option<Vec3> {
        self.robots.get(m).map(|r| r.pos - self.hub)
    }

    /// Robots still attached.
    pub fn attached(&self) -> usize {
        self.robots.iter().filter(|r| r.attached).count()
    }

    /// The next robot to move in the climbing order, and whether it starts a new round (its index is not after
    /// the previous mover's). `None` when every tether is cut.
    pub fn next_mover(&mut self) -> Option<(usize, bool)> {
        for k in 0..N {
            let m = (self.turn + k) % N.max(1);
            if self.robots.get(m).map(|r| r.attached) == Some(true) {
                let new_round = match self.last {
                    None => true,
                    Some(prev) => m <= prev,
                };
                self.last = Some(m);
                self.turn = m + 1;
                return Some((m, new_round));
            }
        }
        None
    }

    /// Robot `m` grips at `to`.
    pub fn hop(&mut self, m: usize, to: Vec3) {
        if let Some(r) = self.robots.get_mut(m) {
            r.pos = to;
        }
    }

    /// Node loss: robot `m` cuts its tether.
    pub fn cut_tether(&mut self, m: usize) {
        if let Some(r) = self.robots.get_mut(m) {
            r.attached = false;
        }
    }

    /// Robot `m`'s goal: the team goal plus its slot.
    pub fn slot_goal(&self, m: usize, team_goal: &Vec3) -> Vec3 {
        team_goal + self.slots.get(m).copied().unwrap_or_else(Vec3::zeros)
    }

    /// Hub motion at the end of a round: towards the attached robots' centroid, as far as every attached leg stays
    /// within `r_max`. Returns the distance moved.
    pub fn hub_motion(&mut self, r_max: Real) -> Real {
        let n = self.attached();
        if n == 0 {
            return 0.0;
        }
        let mut c = Vec3::zeros();
        for r in self.robots.iter().filter(|r| r.attached) {
            c += r.pos;
        }
        c /= n as Real;
        let ok = |h: &Vec3| self.robots.iter().filter(|r| r.attached).all(|r| norm3(&(r.pos - h)) <= r_max);
        let step = c - self.hub;
        let target = if ok(&c) {
            1.0
        } else {
            let (mut lo, mut hi) = (0.0 as Real, 1.0 as Real);
            for _ in 0..HUB_BISECTION_STEPS {
                let mid = 0.5 * (lo + hi);
                if ok(&(self.hub + step * mid)) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            lo
        };
        let old = self.hub;
        if ok(&(self.hub + step * target)) {
            self.hub += step * target;
        }
        norm3(&(self.hub - old))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn paper_team() -> Team<4> {
        // section IV: robots 1..4 at (1,1,0), (1,0,0), (0,1,0), (0,0,0) m
        Team::new([Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0), Vec3::new(0.0, 0.0, 0.0)])
    }

    #[test]
    fn climbing_order_one_moves_three_hold_and_node_loss() {
        let mut t = paper_team();
        assert_eq!(t.hub, Vec3::new(0.5, 0.5, 0.0));
        let seq: [(usize, bool); 5] = core::array::from_fn(|_| t.next_mover().unwrap());
        assert_eq!(seq, [(0, true), (1, false), (2, false), (3, false), (0, true)]);
        t.cut_tether(1);
        assert_eq!(t.attached(), 3);
        let seq: [(usize, bool); 4] = core::array::from_fn(|_| t.next_mover().unwrap());
        assert_eq!(seq, [(2, false), (3, false), (0, true), (2, false)]);
        for m in 0..4 {
            t.cut_tether(m);
        }
        assert_eq!(t.next_mover(), None);
    }

    #[test]
    fn hub_motion_follows_the_team_and_never_overstretches_a_tether() {
        // the paper's climb: each robot hops 0.75 m along y; after the round the hub has moved 0.75 m
        let mut t = paper_team();
        for m in 0..4 {
            let p = t.robots[m].pos + Vec3::new(0.0, 0.75, 0.0);
            t.hop(m, p);
        }
        let moved = t.hub_motion(2.0);
        assert!((moved - 0.75).abs() < 1e-6);
        assert!((t.hub - Vec3::new(0.5, 1.25, 0.0)).norm() < 1e-6);
        // three robots ahead, one behind: the full step to the centroid would overstretch the laggard's tether,
        // so the hub stops where the laggard's leg is exactly r_max (analytic: hub x = 0.5)
        let mut t = Team::new([Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 0.1, 0.0), Vec3::new(1.0, -0.1, 0.0), Vec3::new(-0.5, 0.0, 0.0)]);
        t.hub = Vec3::zeros();
        let r_max = 1.01;
        t.hub_motion(r_max);
        assert!((t.hub.x - 0.51).abs() < 1e-4 && t.hub.y.abs() < 1e-6, "{:?}", t.hub);
        for m in 0..4 {
            assert!(norm3(&t.leg(m).unwrap()) <= r_max + 1e-5, "leg {m}");
        }
        // node loss: the cut robot no longer pulls the hub
        let mut t = paper_team();
        t.cut_tether(0);
        t.hub_motion(5.0);
        assert!((t.hub - Vec3::new(1.0 / 3.0, 1.0 / 3.0, 0.0)).norm() < 1e-6);
    }
}
