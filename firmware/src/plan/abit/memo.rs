//! The edge memo (OMPL's per-vertex black / white lists): [`EdgeMemo`] keeps motion-check results in a fixed
//! open-addressing hash table keyed by the two nodes and their generations, so a lookup needs only the nodes'
//! generations, never the planner's problem. A full neighbourhood of `MEMO_PROBES` slots replaces the home slot:
//! the memo is a cache, a lost entry only costs a repeated motion check.

use heapless::Vec;

use crate::config::abit::MEMO_PROBES;
use crate::plan::space::{MotionCheck, MotionValidator, StateSpace};
use super::node::Node;
use super::NONE;

/// One memoised motion check.
#[derive(Debug, Clone)]
struct MemoEntry<A> {
    parent: u32,
    parent_generation: u32,
    child: u32,
    child_generation: u32,
    result: Option<A>,
}

/// What [`EdgeMemo::check`] did.
pub(super) enum MemoCheck<A> {
    /// The result was memoised: the child's attachment after the motion, `None` for an invalid motion.
    Known(Option<A>),
    /// The motion was checked (and memoised); `filled`: its entry took an empty slot.
    Checked {
        /// The child's attachment after the motion, `None` for an invalid motion.
        result: Option<A>,
        /// The entry took an empty slot (the memo's high water grows).
        filled: bool,
    },
}

/// The memo: `NM` slots (each empty or holding one entry).
pub(super) struct EdgeMemo<A, const NM: usize> {
    slots: Vec<Option<MemoEntry<A>>, NM>,
}

impl<A, const NM: usize> EdgeMemo<A, NM> {
    /// A memo without slots (const, so the arena can be a `static`); [`Self::reset`] makes the `NM` empty slots.
    pub(super) const fn new() -> Self {
        Self { slots: Vec::new() }
    }

    /// `NM` empty slots.
    pub(super) fn reset(&mut self) {
        self.slots.clear();
        // Bounded by NM.
        for _ in 0..NM {
            if self.slots.push(None).is_err() {
                break;
            }
        }
    }
}

impl<A: Clone, const NM: usize> EdgeMemo<A, NM> {
    fn home_slot(parent: u32, child: u32) -> usize {
        let h = (parent as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ (child as u64).wrapping_mul(0xC2B2_AE3D_27D4_EB4F);
        if NM == 0 {
            0
        } else {
            ((h ^ (h >> 29)) % NM as u64) as usize
        }
    }

    fn generations<St>(nodes: &[Node<St, A>], parent: u32, child: u32) -> (u32, u32) {
        (
            nodes.get(parent as usize).map_or(NONE, |n| n.generation),
            nodes.get(child as usize).map_or(NONE, |n| n.generation),
        )
    }

    /// The memoised result of the motion `parent -> child`, if its entry is there and both nodes are the ones it was
    /// computed for (same generations).
    pub(super) fn get<St>(&self, nodes: &[Node<St, A>], parent: u32, child: u32) -> Option<Option<A>> {
        let (pg, cg) = Self::generations(nodes, parent, child);
        let home = Self::home_slot(parent, child);
        for p in 0..MEMO_PROBES.min(NM) {
            let slot = self.slots.get((home + p) % NM.max(1))?;
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

    /// Memoise a motion check; true when the entry took an empty slot.
    fn put<St>(&mut self, nodes: &[Node<St, A>], parent: u32, child: u32, result: Option<A>) -> bool {
        let (pg, cg) = Self::generations(nodes, parent, child);
        let home = Self::home_slot(parent, child);
        let mut target = None;
        for p in 0..MEMO_PROBES.min(NM) {
            let idx = (home + p) % NM.max(1);
            let Some(slot) = self.slots.get(idx) else { break };
            let reusable = match slot {
                None => true,
                Some(e) if e.parent == parent && e.child == child => true,
                Some(e) => {
                    // A stale entry (either node freed or disconnected since) may be overwritten.
                    let (epg, ecg) = Self::generations(nodes, e.parent, e.child);
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
        let was_empty = matches!(self.slots.get(idx), Some(None));
        match self.slots.get_mut(idx) {
            Some(slot) => {
                *slot = Some(MemoEntry { parent, parent_generation: pg, child, child_generation: cg, result });
                was_empty
            }
            None => false,
        }
    }

    /// Is the edge known to be unusable: invalid, or giving the child an attachment incompatible with the one it
    /// holds?
    pub(super) fn blacklisted<S>(&self, nodes: &[Node<S::State, A>], space: &S, parent: u32, child: u32) -> bool
    where
        S: StateSpace<Attachment = A>,
    {
        match self.get(nodes, parent, child) {
            Some(None) => true,
            Some(Some(att)) => match nodes.get(child as usize).and_then(|c| c.attachment.as_ref()) {
                Some(existing) => !space.attachments_compatible(&att, existing),
                None => false,
            },
            None => false,
        }
    }

    /// The motion `parent -> child` from the memo, or checked by `motion` (from the parent's attachment) and
    /// memoised.
    pub(super) fn check<S, M>(
        &mut self,
        nodes: &[Node<S::State, A>],
        space: &S,
        motion: &mut M,
        parent: u32,
        child: u32,
    ) -> MemoCheck<A>
    where
        S: StateSpace<Attachment = A>,
        M: MotionValidator<S>,
    {
        if let Some(result) = self.get(nodes, parent, child) {
            return MemoCheck::Known(result);
        }
        let result = match (nodes.get(parent as usize), nodes.get(child as usize)) {
            (Some(p), Some(c)) => match p.attachment.as_ref() {
                Some(att) => match motion.check_motion(space, &p.state, att, &c.state) {
                    MotionCheck::Valid { attachment } => Some(attachment),
                    MotionCheck::Invalid => None,
                },
                None => None,
            },
            _ => None,
        };
        let filled = self.put(nodes, parent, child, result.clone());
        MemoCheck::Checked { result, filled }
    }
}
