//! The edge memo (OMPL's per-vertex black / white lists): motion-check results in a fixed open-addressing hash
//! table keyed by the two nodes and their generations.

use crate::config::abit::MEMO_PROBES;
use crate::plan::space::{MotionCheck, MotionValidator, StateSpace};
use super::{AbitArena, AbitStar, NONE};

/// One memoised motion check.
#[derive(Debug, Clone)]
pub(super) struct MemoEntry<A> {
    parent: u32,
    parent_generation: u32,
    child: u32,
    child_generation: u32,
    result: Option<A>,
}

/// The memo is the arena's: a lookup needs only the nodes' generations, never the planner's problem.
impl<St, A: Clone, const NV: usize, const NQ: usize, const NM: usize> AbitArena<St, A, NV, NQ, NM> {
    fn memo_slot(parent: u32, child: u32) -> usize {
        let h = (parent as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (child as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        if NM == 0 {
            0
        } else {
            ((h ^ (h >> 29)) % NM as u64) as usize
        }
    }

    fn generations(&self, parent: u32, child: u32) -> (u32, u32) {
        (
            self.nodes.get(parent as usize).map_or(NONE, |n| n.generation),
            self.nodes.get(child as usize).map_or(NONE, |n| n.generation),
        )
    }

    /// The memoised result of the motion `parent -> child`, if its entry is there and both nodes are the ones it was
    /// computed for (same generations).
    pub(super) fn memo_get(&self, parent: u32, child: u32) -> Option<Option<A>> {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        for p in 0..MEMO_PROBES.min(NM) {
            let slot = self.memo.get((home + p) % NM.max(1))?;
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

    /// Memoise a motion check; true when the entry took an empty slot (the memo's high water grows).
    fn memo_put(&mut self, parent: u32, child: u32, result: Option<A>) -> bool {
        let (pg, cg) = self.generations(parent, child);
        let home = Self::memo_slot(parent, child);
        let mut target = None;
        for p in 0..MEMO_PROBES.min(NM) {
            let idx = (home + p) % NM.max(1);
            let Some(slot) = self.memo.get(idx) else { break };
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
        let was_empty = matches!(self.memo.get(idx), Some(None));
        match self.memo.get_mut(idx) {
            Some(slot) => {
                *slot = Some(MemoEntry { parent, parent_generation: pg, child, child_generation: cg, result });
                was_empty
            }
            None => false,
        }
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
    M: MotionValidator<S>,
{

    /// Is the edge known to be unusable (invalid, or incompatible with the child's attachment)?
    pub(super) fn blacklisted(&self, parent: u32, child: u32) -> bool {
        match self.arena.memo_get(parent, child) {
            Some(None) => true,
            Some(Some(att)) => match self.arena.nodes.get(child as usize).and_then(|c| c.attachment.as_ref()) {
                Some(existing) => !self.space.attachments_compatible(&att, existing),
                None => false,
            },
            None => false,
        }
    }

    /// Check the motion parent -> child (memoised). Returns the child's attachment after the motion.
    pub(super) fn check_edge(&mut self, parent: u32, child: u32) -> Option<S::Attachment> {
        if let Some(result) = self.arena.memo_get(parent, child) {
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
        if self.arena.memo_put(parent, child, result.clone()) {
            self.st.high_water.memo += 1;
        }
        result
    }
}
