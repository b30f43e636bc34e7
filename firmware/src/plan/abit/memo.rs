//! The edge memo (OMPL's per-vertex black / white lists): motion-check results in a fixed open-addressing hash
//! table keyed by the two nodes and their generations.

use rand_core::Rng;

use crate::config::abit::MEMO_PROBES;
use crate::plan::space::{
    GoalRegion, MotionCheck, MotionValidator, OptimizationObjective, StateSpace, StateValidityChecker,
};
use super::{AbitStar, NONE};

/// One memoised motion check.
#[derive(Debug, Clone)]
pub(super) struct MemoEntry<A> {
    parent: u32,
    parent_generation: u32,
    child: u32,
    child_generation: u32,
    result: Option<A>,
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    V: StateValidityChecker<S>,
    M: MotionValidator<S>,
    O: OptimizationObjective<S>,
    G: GoalRegion<S>,
    R: Rng,
{
    pub(super) fn memo_slot(parent: u32, child: u32) -> usize {
        let h = (parent as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (child as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        if NM == 0 {
            0
        } else {
            ((h ^ (h >> 29)) % NM as u64) as usize
        }
    }

    pub(super) fn generations(&self, parent: u32, child: u32) -> (u32, u32) {
        (
            self.node(parent).map_or(NONE, |n| n.generation),
            self.node(child).map_or(NONE, |n| n.generation),
        )
    }

    pub(super) fn memo_get(&self, parent: u32, child: u32) -> Option<Option<S::Attachment>> {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        for p in 0..MEMO_PROBES.min(NM) {
            let slot = self.arena.memo.get((home + p) % NM.max(1))?;
            match slot {
                Some(e) if e.parent == parent && e.child == child => {
                    return (e.parent_generation == pg && e.child_generation == cg).then(|| e.result.clone());
                }
                None => return None,
                _ => {}
            }
        }
        None
    }

    pub(super) fn memo_put(&mut self, parent: u32, child: u32, result: Option<S::Attachment>) {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        let mut target = None;
        for p in 0..MEMO_PROBES.min(NM) {
            let idx = (home + p) % NM.max(1);
            let Some(slot) = self.arena.memo.get(idx) else { break };
            let reusable = match slot {
                None => true,
                Some(e) if e.parent == parent && e.child == child => true,
                Some(e) => {
                    // A stale entry (either node freed or disconnected since) may be overwritten.
                    let (epg, ecg) = self.generations(e.parent, e.child);
                    epg != e.parent_generation || ecg != e.child_generation
                }
            };
            if reusable {
                target = Some(idx);
                break;
            }
        }
        // Full neighbourhood: replace the home slot (the memo is a cache).
        let idx = target.unwrap_or(home);
        let was_empty = matches!(self.arena.memo.get(idx), Some(None));
        if let Some(slot) = self.arena.memo.get_mut(idx) {
            *slot = Some(MemoEntry { parent, parent_generation: pg, child, child_generation: cg, result });
            if was_empty {
                self.st.high_water.memo += 1;
            }
        }
    }

    /// Is the edge known to be unusable (invalid, or incompatible with the child's attachment)?
    pub(super) fn blacklisted(&self, parent: u32, child: u32) -> bool {
        match self.memo_get(parent, child) {
            Some(None) => true,
            Some(Some(att)) => match self.node(child).and_then(|c| c.attachment.as_ref()) {
                Some(existing) => !self.space.attachments_compatible(&att, existing),
                None => false,
            },
            None => false,
        }
    }

    /// Check the motion parent -> child (memoised). Returns the child's attachment after the motion.
    pub(super) fn check_edge(&mut self, parent: u32, child: u32) -> Option<S::Attachment> {
        if let Some(result) = self.memo_get(parent, child) {
            self.st.counters.memo_hits += 1;
            return result;
        }
        self.st.counters.edges_evaluated += 1;
        let result = match (self.arena.nodes.get(parent as usize), self.arena.nodes.get(child as usize)) {
            (Some(p), Some(c)) => match p.attachment.as_ref() {
                Some(att) => match self.motion.check_motion(self.space, &p.state, att, &c.state) {
                    MotionCheck::Valid { attachment } => Some(attachment),
                    MotionCheck::Invalid => None,
                },
                None => None,
            },
            _ => None,
        };
        self.memo_put(parent, child, result.clone());
        result
    }
}
