//! An indexed binary min-heap: the open list of every search.
//!
//! The heap holds `u32` ids (an edge slot, a cell, a node: whatever the search queues). The items themselves —
//! their keys and their heap positions — stay with the caller, who lends them to every operation as a
//! [`HeapItems`]: `before` orders two ids, `set_position` records where an id now sits, `position` reads it back.
//! Knowing the positions is what makes the heap *indexed*: an item whose key changed is moved in O(log n)
//! ([`Heap::update`], decrease-key and increase-key alike) and an item can leave from anywhere
//! ([`Heap::remove`]), as with OMPL's `BinaryHeap` element handles.
//! Items that each record their own position (ABIT*'s queued edges, the homotopy A*'s nodes) implement
//! [`HeapSlot`] instead: a slice of them, addressed by index, is then the [`HeapItems`].
//!
//! One algorithm, two kinds of id storage ([`HeapIds`]):
//! - [`IndexedHeap<N>`]: a fixed capacity `N`, a const generic (a `heapless::Vec` of ids); the heap can be a
//!   `static` ([`IndexedHeap::new`] is `const`). ABIT*'s edge queue and the homotopy and bounded-leg A* use it.
//! - [`LentHeap`]: ids in a slice lent by the caller (a [`LentIds`]: the slice plus a length), sized at run time —
//!   D* Lite's open list over a grid whose size is known only when the planner is built (512 x 512 on the host).
//!
//! - **No allocation.**
//! - **No panics.** A push onto a full heap returns [`Full`] and changes nothing; every lookup is checked.
//! - **Bounded loops.** A sift moves one level per round (at most log2 of the capacity rounds); `heapify` sifts
//!   `len / 2` positions.
//! - **Order.** The heap uses `before` alone, a strict order (`a` comes out before `b`). Two ids neither of which
//!   is before the other leave in an order fixed by the sequence of operations (deterministic, but not by id): a
//!   search that needs a specified tie-break puts it into `before` (ABIT* orders its edges by key, then by
//!   `(parent, child)`).
//! - **Clearing** is O(1) and leaves the caller's recorded positions stale; the heap never trusts a recorded
//!   position without checking that the id sits there, so a stale one is harmless.

use heapless::Vec;

/// The position a caller records for an id that is not in the heap.
pub const NOT_IN_HEAP: u32 = u32::MAX;

/// The heap was full: the push changed nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Full;

/// The caller's items, addressed by id: their order and their heap positions.
pub trait HeapItems {
    /// Does `a` come out of the heap before `b`? A strict order; `false` for an unknown id.
    fn before(&self, a: u32, b: u32) -> bool;
    /// Record that `id` now sits at heap position `pos` ([`NOT_IN_HEAP`] when it left the heap).
    fn set_position(&mut self, id: u32, pos: u32);
    /// The position last recorded for `id` (`None` or [`NOT_IN_HEAP`] if none).
    fn position(&self, id: u32) -> Option<u32>;
}

/// An item that records its own heap position, ordered against its peers: a slice of them, addressed by index,
/// is the [`HeapItems`] (ABIT*'s edge slab, the homotopy A*'s node arena).
pub trait HeapSlot {
    /// Does this item, id `id`, come out before `other`, id `other_id`? A strict order.
    fn before(&self, id: u32, other: &Self, other_id: u32) -> bool;
    /// The position last recorded for it.
    fn heap_position(&self) -> u32;
    /// Record that it now sits at heap position `pos` ([`NOT_IN_HEAP`] when it left the heap).
    fn set_heap_position(&mut self, pos: u32);
}

/// A slice of [`HeapSlot`]s: the id is the index.
impl<T: HeapSlot> HeapItems for [T] {
    fn before(&self, a: u32, b: u32) -> bool {
        match (self.get(a as usize), self.get(b as usize)) {
            (Some(x), Some(y)) => x.before(a, y, b),
            _ => false,
        }
    }
    fn set_position(&mut self, id: u32, pos: u32) {
        if let Some(x) = self.get_mut(id as usize) {
            x.set_heap_position(pos);
        }
    }
    fn position(&self, id: u32) -> Option<u32> {
        self.get(id as usize).map(T::heap_position)
    }
}

/// Where a heap keeps its ids: position 0 is the front. The heap algorithm ([`Heap`]) is written once over this.
pub trait HeapIds {
    /// The queued ids, in heap order.
    fn ids(&self) -> &[u32];
    /// The queued ids, mutable (the heap only swaps them).
    fn ids_mut(&mut self) -> &mut [u32];
    /// Append `id` at the end; [`Full`] (and no change) when there is no room.
    fn push_back(&mut self, id: u32) -> Result<(), Full>;
    /// Take the last id.
    fn pop_back(&mut self) -> Option<u32>;
    /// Forget every id (O(1)).
    fn clear(&mut self);
    /// How many ids fit.
    fn capacity(&self) -> usize;
}

impl<const N: usize> HeapIds for Vec<u32, N> {
    #[inline]
    fn ids(&self) -> &[u32] {
        self.as_slice()
    }
    #[inline]
    fn ids_mut(&mut self) -> &mut [u32] {
        self.as_mut_slice()
    }
    #[inline]
    fn push_back(&mut self, id: u32) -> Result<(), Full> {
        self.push(id).map_err(|_| Full)
    }
    #[inline]
    fn pop_back(&mut self) -> Option<u32> {
        self.pop()
    }
    #[inline]
    fn clear(&mut self) {
        Vec::clear(self)
    }
    #[inline]
    fn capacity(&self) -> usize {
        N
    }
}

/// Ids in a slice lent by the caller, of which the first `len` are queued. The capacity is the slice's length.
#[derive(Debug)]
pub struct LentIds<'a> {
    slots: &'a mut [u32],
    len: usize,
}

impl<'a> LentIds<'a> {
    /// Empty, over `slots` (their contents are ignored).
    pub fn new(slots: &'a mut [u32]) -> Self {
        Self { slots, len: 0 }
    }
}

impl HeapIds for LentIds<'_> {
    #[inline]
    fn ids(&self) -> &[u32] {
        self.slots.get(..self.len).unwrap_or(&[])
    }
    #[inline]
    fn ids_mut(&mut self) -> &mut [u32] {
        self.slots.get_mut(..self.len).unwrap_or(&mut [])
    }
    #[inline]
    fn push_back(&mut self, id: u32) -> Result<(), Full> {
        let slot = self.slots.get_mut(self.len).ok_or(Full)?;
        *slot = id;
        self.len += 1;
        Ok(())
    }
    #[inline]
    fn pop_back(&mut self) -> Option<u32> {
        let last = self.len.checked_sub(1)?;
        let id = self.slots.get(last).copied()?;
        self.len = last;
        Some(id)
    }
    #[inline]
    fn clear(&mut self) {
        self.len = 0;
    }
    #[inline]
    fn capacity(&self) -> usize {
        self.slots.len()
    }
}

/// An indexed binary min-heap over the id storage `S`. See the module docs.
#[derive(Debug, Clone)]
pub struct Heap<S> {
    ids: S,
}

/// A heap of at most `N` ids in a fixed `heapless::Vec` (can be a `static`).
pub type IndexedHeap<const N: usize> = Heap<Vec<u32, N>>;

/// A heap over ids in a slice lent by the caller (capacity: the slice's length).
pub type LentHeap<'a> = Heap<LentIds<'a>>;

impl<const N: usize> Default for Heap<Vec<u32, N>> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Heap<Vec<u32, N>> {
    /// An empty heap (const, so it can be a `static`).
    pub const fn new() -> Self {
        Self { ids: Vec::new() }
    }

    /// The capacity `N`.
    pub const fn capacity(&self) -> usize {
        N
    }
}

impl<'a> Heap<LentIds<'a>> {
    /// An empty heap over the lent `slots` (its capacity is `slots.len()`; their contents are ignored).
    pub fn lent(slots: &'a mut [u32]) -> Self {
        Self { ids: LentIds::new(slots) }
    }

    /// The capacity: the length of the lent slice.
    pub fn capacity(&self) -> usize {
        self.ids.capacity()
    }

    /// The lent slots, handed back (the heap's contents are dropped).
    pub fn into_slots(self) -> &'a mut [u32] {
        self.ids.slots
    }
}

impl<S: HeapIds> Heap<S> {
    /// Ids in the heap.
    pub fn len(&self) -> usize {
        self.ids.ids().len()
    }

    /// Is the heap empty?
    pub fn is_empty(&self) -> bool {
        self.ids.ids().is_empty()
    }

    /// Is the heap full (a push would return [`Full`])?
    pub fn is_full(&self) -> bool {
        self.len() >= self.ids.capacity()
    }

    /// The id that [`Self::pop`] would return.
    pub fn peek(&self) -> Option<u32> {
        self.ids.ids().first().copied()
    }

    /// The id at heap position `pos` (position 0 is the front).
    pub fn get(&self, pos: usize) -> Option<u32> {
        self.ids.ids().get(pos).copied()
    }

    /// Is `id` queued (its recorded position checked against the heap)?
    pub fn contains<I: HeapItems + ?Sized>(&self, id: u32, items: &I) -> bool {
        self.position_of(id, items).is_some()
    }

    /// Empty the heap. O(1): the positions the items recorded become stale (see the module docs).
    pub fn clear(&mut self) {
        self.ids.clear();
    }

    /// Queue `id` (the caller makes sure it is not queued yet).
    pub fn push<I: HeapItems + ?Sized>(&mut self, id: u32, items: &mut I) -> Result<(), Full> {
        let pos = self.len();
        self.ids.push_back(id)?;
        items.set_position(id, pos as u32);
        self.sift_up(pos, items);
        Ok(())
    }

    /// Take the front id out of the heap.
    pub fn pop<I: HeapItems + ?Sized>(&mut self, items: &mut I) -> Option<u32> {
        let last = self.len().checked_sub(1)?;
        self.swap(0, last, items);
        let id = self.ids.pop_back()?;
        self.sift_down(0, items);
        items.set_position(id, NOT_IN_HEAP);
        Some(id)
    }

    /// Restore the order after the key of `id` changed, in either direction. Nothing happens if `id` is not
    /// queued.
    pub fn update<I: HeapItems + ?Sized>(&mut self, id: u32, items: &mut I) {
        if let Some(pos) = self.position_of(id, items) {
            self.fix(pos, items);
        }
    }

    /// Take `id` out of the heap wherever it sits. `false` if it was not queued.
    pub fn remove<I: HeapItems + ?Sized>(&mut self, id: u32, items: &mut I) -> bool {
        let Some(pos) = self.position_of(id, items) else { return false };
        let Some(last) = self.len().checked_sub(1) else { return false };
        self.swap(pos, last, items);
        if self.ids.pop_back().is_none() {
            return false;
        }
        items.set_position(id, NOT_IN_HEAP);
        if pos < self.len() {
            self.fix(pos, items);
        }
        true
    }

    /// Restore the order after the keys of many queued ids changed (Floyd's bottom-up construction).
    pub fn heapify<I: HeapItems + ?Sized>(&mut self, items: &mut I) {
        for i in (0..self.len() / 2).rev() {
            self.sift_down(i, items);
        }
    }

    /// The position of `id`, if it is queued (the recorded position is checked against the heap).
    fn position_of<I: HeapItems + ?Sized>(&self, id: u32, items: &I) -> Option<usize> {
        let pos = items.position(id).filter(|&p| p != NOT_IN_HEAP)? as usize;
        (self.ids.ids().get(pos) == Some(&id)).then_some(pos)
    }

    #[inline]
    fn before_at<I: HeapItems + ?Sized>(&self, a: usize, b: usize, items: &I) -> bool {
        let ids = self.ids.ids();
        let (Some(&x), Some(&y)) = (ids.get(a), ids.get(b)) else {
            return false;
        };
        items.before(x, y)
    }

    #[inline]
    fn swap<I: HeapItems + ?Sized>(&mut self, a: usize, b: usize, items: &mut I) {
        let ids = self.ids.ids_mut();
        let len = ids.len();
        if a >= len || b >= len {
            return;
        }
        ids.swap(a, b);
        for i in [a, b] {
            if let Some(&id) = ids.get(i) {
                items.set_position(id, i as u32);
            }
        }
    }

    /// Move the id at `i` up to its place; returns where it ended.
    fn sift_up<I: HeapItems + ?Sized>(&mut self, mut i: usize, items: &mut I) -> usize {
        // Bounded: i halves every round.
        while i > 0 {
            let p = (i - 1) / 2;
            if self.before_at(i, p, items) {
                self.swap(i, p, items);
                i = p;
            } else {
                break;
            }
        }
        i
    }

    fn sift_down<I: HeapItems + ?Sized>(&mut self, mut i: usize, items: &mut I) {
        let len = self.len();
        // Bounded: i at least doubles every round.
        loop {
            let l = 2 * i + 1;
            if l >= len {
                break;
            }
            let r = l + 1;
            let c = if r < len && self.before_at(r, l, items) { r } else { l };
            if self.before_at(c, i, items) {
                self.swap(c, i, items);
                i = c;
            } else {
                break;
            }
        }
    }

    /// Up if it belongs higher, else down.
    fn fix<I: HeapItems + ?Sized>(&mut self, pos: usize, items: &mut I) {
        let up = self.sift_up(pos, items);
        if up == pos {
            self.sift_down(pos, items);
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec as StdVec;

    use super::*;

    /// Items with a key and a tie-break by id; positions kept per id.
    struct Keys {
        key: [i32; 16],
        pos: [u32; 16],
    }

    impl Keys {
        fn new(key: [i32; 16]) -> Self {
            Self { key, pos: [NOT_IN_HEAP; 16] }
        }
    }

    impl HeapItems for Keys {
        fn before(&self, a: u32, b: u32) -> bool {
            match (self.key.get(a as usize), self.key.get(b as usize)) {
                (Some(x), Some(y)) => (x, a) < (y, b),
                _ => false,
            }
        }
        fn set_position(&mut self, id: u32, pos: u32) {
            if let Some(p) = self.pos.get_mut(id as usize) {
                *p = pos;
            }
        }
        fn position(&self, id: u32) -> Option<u32> {
            self.pos.get(id as usize).copied()
        }
    }

    fn drain<S: HeapIds>(heap: &mut Heap<S>, items: &mut Keys) -> StdVec<u32> {
        let mut out = StdVec::new();
        while let Some(id) = heap.pop(items) {
            assert_eq!(items.pos[id as usize], NOT_IN_HEAP);
            out.push(id);
        }
        out
    }

    /// Every queued id's recorded position is where it sits, and no child comes before its parent.
    fn assert_consistent<S: HeapIds>(heap: &Heap<S>, items: &Keys) {
        for p in 0..heap.len() {
            let id = heap.get(p).unwrap();
            assert_eq!(items.pos[id as usize] as usize, p);
            if p > 0 {
                assert!(!items.before(id, heap.get((p - 1) / 2).unwrap()), "heap order broken at {p}");
            }
        }
    }

    // Every check runs on both kinds of id storage: the fixed one (`IndexedHeap`, one test each) and the lent one
    // (`LentHeap`, D* Lite's open list: `a_lent_heap_passes_every_check`), of capacity 16 unless said.

    /// Items with `keys`, ids `0..n` pushed in order.
    fn queued<S: HeapIds>(heap: &mut Heap<S>, keys: [i32; 16], n: u32) -> Keys {
        let mut items = Keys::new(keys);
        for id in 0..n {
            heap.push(id, &mut items).unwrap();
        }
        items
    }

    /// 16 ids pushed in a scrambled order pop by key, ties by id.
    fn check_pops_in_key_order<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = Keys::new([5, 3, 9, 3, 0, 7, 1, 8, 3, 2, 6, 4, 9, 0, 5, 1]);
        assert_eq!(heap.ids.capacity(), 16);
        assert!(heap.is_empty());
        for id in [7, 2, 11, 0, 15, 4, 9, 13, 1, 6, 12, 3, 10, 5, 8, 14] {
            heap.push(id, &mut items).unwrap();
            assert_consistent(&heap, &items);
        }
        assert!(heap.is_full());
        assert_eq!(heap.peek(), Some(4));
        let order = drain(&mut heap, &mut items);
        let mut expect: StdVec<u32> = (0..16).collect();
        expect.sort_by_key(|&i| (items.key[i as usize], i));
        assert_eq!(order, expect);
        assert!(heap.is_empty());
        assert_eq!(heap.pop(&mut items), None);
    }

    #[test]
    fn pops_in_key_order_with_ties_by_the_items_order() {
        check_pops_in_key_order(IndexedHeap::<16>::new());
    }

    fn check_update<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = queued(&mut heap, [10, 20, 30, 40, 50, 60, 70, 80, 0, 0, 0, 0, 0, 0, 0, 0], 8);
        items.key[6] = 5; // decrease: to the front
        heap.update(6, &mut items);
        assert_consistent(&heap, &items);
        assert_eq!(heap.peek(), Some(6));
        items.key[0] = 65; // increase: behind 5 (60), before 7 (80)
        heap.update(0, &mut items);
        assert_consistent(&heap, &items);
        assert_eq!(drain(&mut heap, &mut items), [6, 1, 2, 3, 4, 5, 0, 7]);
        // Updating an id that is not queued (its recorded position is stale) changes nothing.
        heap.push(3, &mut items).unwrap();
        items.pos[1] = 0;
        heap.update(1, &mut items);
        assert_eq!(heap.len(), 1);
        assert_eq!(heap.peek(), Some(3));
    }

    #[test]
    fn decrease_and_increase_key_move_the_item() {
        check_update(IndexedHeap::<16>::new());
    }

    fn check_heapify<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = queued(&mut heap, [0; 16], 16);
        for (id, k) in items.key.iter_mut().enumerate() {
            *k = (id as i32 * 7) % 16;
        }
        heap.heapify(&mut items);
        assert_consistent(&heap, &items);
        let order = drain(&mut heap, &mut items);
        let keys: StdVec<i32> = order.iter().map(|&i| items.key[i as usize]).collect();
        assert_eq!(keys, (0..16).collect::<StdVec<_>>());
    }

    #[test]
    fn rekeying_everything_then_heapify_restores_the_order() {
        check_heapify(IndexedHeap::<16>::new());
    }

    fn check_contains<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = queued(&mut heap, [4, 8, 1, 6, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0], 4);
        assert!((0..4).all(|id| heap.contains(id, &items)));
        assert!(!heap.contains(4, &items), "never queued");
        assert_eq!(heap.pop(&mut items), Some(2));
        assert!(!heap.contains(2, &items), "popped");
        // A stale position pointing at a slot another id holds is not membership.
        items.pos[5] = 0;
        assert!(!heap.contains(5, &items));
        heap.clear();
        assert!(!heap.contains(0, &items), "cleared: recorded positions are stale");
    }

    #[test]
    fn contains_checks_the_recorded_position() {
        check_contains(IndexedHeap::<16>::new());
    }

    fn check_remove<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = queued(&mut heap, [4, 8, 1, 6, 3, 9, 2, 7, 5, 0, 0, 0, 0, 0, 0, 0], 9);
        assert!(heap.remove(2, &mut items)); // the front
        assert!(heap.remove(5, &mut items)); // a leaf or inner node
        assert!(heap.remove(7, &mut items));
        assert_consistent(&heap, &items);
        assert!(!heap.remove(5, &mut items), "removed twice");
        assert_eq!(items.pos[5], NOT_IN_HEAP);
        assert_eq!(drain(&mut heap, &mut items), [6, 4, 0, 8, 3, 1]);
        assert!(!heap.remove(0, &mut items), "empty heap");
    }

    #[test]
    fn remove_takes_an_item_from_anywhere() {
        check_remove(IndexedHeap::<16>::new());
    }

    /// A heap of capacity 3.
    fn check_full<S: HeapIds>(mut heap: Heap<S>) {
        let mut items = Keys::new([3, 1, 2, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0]);
        assert_eq!(heap.ids.capacity(), 3);
        for id in 0..3 {
            heap.push(id, &mut items).unwrap();
        }
        assert!(heap.is_full());
        assert_eq!(heap.push(3, &mut items), Err(Full));
        assert_eq!(items.pos[3], NOT_IN_HEAP);
        assert_eq!(heap.len(), 3);
        assert_eq!(drain(&mut heap, &mut items), [1, 2, 0]);
        // Room again after pops; clear empties at once.
        heap.push(3, &mut items).unwrap();
        heap.clear();
        assert!(heap.is_empty());
        assert_eq!(heap.pop(&mut items), None);
    }

    #[test]
    fn a_full_heap_is_a_typed_outcome_that_changes_nothing() {
        let fixed = IndexedHeap::<3>::new();
        assert_eq!(fixed.capacity(), 3);
        check_full(fixed);
    }

    #[test]
    fn a_lent_heap_passes_every_check() {
        let mut slots = [7u32; 16]; // contents ignored
        check_pops_in_key_order(LentHeap::lent(&mut slots));
        check_update(LentHeap::lent(&mut slots));
        check_heapify(LentHeap::lent(&mut slots));
        check_contains(LentHeap::lent(&mut slots));
        check_remove(LentHeap::lent(&mut slots[..9]));
        let lent = LentHeap::lent(&mut slots[..3]);
        assert_eq!(lent.capacity(), 3);
        check_full(lent);
        // An empty lent slice: a heap of capacity 0, every push full.
        let mut items = Keys::new([0; 16]);
        let mut empty = LentHeap::lent(&mut slots[..0]);
        assert_eq!(empty.push(0, &mut items), Err(Full));
        assert_eq!(empty.pop(&mut items), None);
    }

    /// Items whose keys have many ties and no tie-break: the order among equal keys is the heap's own.
    struct TieKeys {
        key: [u8; 32],
        pos: [u32; 32],
    }

    impl HeapItems for TieKeys {
        fn before(&self, a: u32, b: u32) -> bool {
            matches!((self.key.get(a as usize), self.key.get(b as usize)), (Some(x), Some(y)) if x < y)
        }
        fn set_position(&mut self, id: u32, pos: u32) {
            if let Some(p) = self.pos.get_mut(id as usize) {
                *p = pos;
            }
        }
        fn position(&self, id: u32) -> Option<u32> {
            self.pos.get(id as usize).copied()
        }
    }

    /// A reference heap in the other common formulation: entries carry their keys, sift-down picks the least of
    /// parent, left, right (left first, strict), an update sifts up if the key decreased else down, a removal
    /// sifts up if the moved entry is below its parent else down. The heap above must pop in exactly its order,
    /// ties included, after any sequence of pushes, key changes and removals.
    struct Reference {
        heap: StdVec<(u8, u32)>,
        pos: [usize; 32],
    }

    impl Reference {
        fn swap(&mut self, i: usize, j: usize) {
            self.heap.swap(i, j);
            self.pos[self.heap[i].1 as usize] = i;
            self.pos[self.heap[j].1 as usize] = j;
        }
        fn up(&mut self, mut i: usize) {
            while i > 0 && self.heap[i].0 < self.heap[(i - 1) / 2].0 {
                self.swap(i, (i - 1) / 2);
                i = (i - 1) / 2;
            }
        }
        fn down(&mut self, mut i: usize) {
            loop {
                let (l, r, mut m) = (2 * i + 1, 2 * i + 2, i);
                if l < self.heap.len() && self.heap[l].0 < self.heap[m].0 {
                    m = l;
                }
                if r < self.heap.len() && self.heap[r].0 < self.heap[m].0 {
                    m = r;
                }
                if m == i {
                    break;
                }
                self.swap(i, m);
                i = m;
            }
        }
        fn set(&mut self, id: u32, k: u8) {
            match self.heap.iter().position(|e| e.1 == id) {
                Some(p) => {
                    let old = self.heap[p].0;
                    self.heap[p].0 = k;
                    if k < old {
                        self.up(p)
                    } else {
                        self.down(p)
                    }
                }
                None => {
                    self.heap.push((k, id));
                    self.pos[id as usize] = self.heap.len() - 1;
                    self.up(self.heap.len() - 1);
                }
            }
        }
        fn remove(&mut self, id: u32) {
            if let Some(p) = self.heap.iter().position(|e| e.1 == id) {
                let last = self.heap.len() - 1;
                self.swap(p, last);
                self.heap.pop();
                if p < self.heap.len() {
                    if p > 0 && self.heap[p].0 < self.heap[(p - 1) / 2].0 {
                        self.up(p)
                    } else {
                        self.down(p)
                    }
                }
            }
        }
    }

    #[test]
    fn lent_heap_matches_a_reference_heap_ties_included() {
        let mut rng = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = move |n: u64| {
            rng ^= rng << 13;
            rng ^= rng >> 7;
            rng ^= rng << 17;
            rng % n
        };
        for _round in 0..200 {
            let mut items = TieKeys { key: [0; 32], pos: [NOT_IN_HEAP; 32] };
            let mut slots = [0u32; 32];
            let mut heap = LentHeap::lent(&mut slots);
            let mut fixed: IndexedHeap<32> = IndexedHeap::new();
            let mut fixed_pos = [NOT_IN_HEAP; 32];
            let mut reference = Reference { heap: StdVec::new(), pos: [0; 32] };
            for _op in 0..120 {
                let id = next(32) as u32;
                let k = next(4) as u8; // few keys: many ties
                match next(5) {
                    0..=2 => {
                        // insert or re-key (D* Lite's insert-or-update)
                        items.key[id as usize] = k;
                        if heap.contains(id, &items) {
                            heap.update(id, &mut items);
                        } else {
                            heap.push(id, &mut items).unwrap();
                        }
                        core::mem::swap(&mut items.pos, &mut fixed_pos);
                        if fixed.contains(id, &items) {
                            fixed.update(id, &mut items);
                        } else {
                            fixed.push(id, &mut items).unwrap();
                        }
                        core::mem::swap(&mut items.pos, &mut fixed_pos);
                        reference.set(id, k);
                    }
                    3 => {
                        heap.remove(id, &mut items);
                        core::mem::swap(&mut items.pos, &mut fixed_pos);
                        fixed.remove(id, &mut items);
                        core::mem::swap(&mut items.pos, &mut fixed_pos);
                        reference.remove(id);
                    }
                    _ => {
                        // pop = remove the front (D* Lite's expansion)
                        if let Some(front) = reference.heap.first().map(|e| e.1) {
                            assert_eq!(heap.peek(), Some(front));
                            assert_eq!(fixed.peek(), Some(front));
                            assert!(heap.remove(front, &mut items));
                            core::mem::swap(&mut items.pos, &mut fixed_pos);
                            assert_eq!(fixed.pop(&mut items), Some(front));
                            core::mem::swap(&mut items.pos, &mut fixed_pos);
                            reference.remove(front);
                        }
                    }
                }
                let ids: StdVec<u32> = (0..heap.len()).map(|p| heap.get(p).unwrap()).collect();
                let ref_ids: StdVec<u32> = reference.heap.iter().map(|e| e.1).collect();
                let fixed_ids: StdVec<u32> = (0..fixed.len()).map(|p| fixed.get(p).unwrap()).collect();
                assert_eq!(ids, ref_ids, "same layout as the reference");
                assert_eq!(fixed_ids, ref_ids, "the fixed heap too");
                assert_consistent_ties(&heap, &items);
            }
        }
    }

    /// An item that keeps its own position, largest key first: a slice of them is the heap's items.
    struct Slot {
        key: i32,
        pos: u32,
    }

    impl HeapSlot for Slot {
        fn before(&self, id: u32, other: &Self, other_id: u32) -> bool {
            self.key > other.key || (self.key == other.key && id < other_id)
        }
        fn heap_position(&self) -> u32 {
            self.pos
        }
        fn set_heap_position(&mut self, pos: u32) {
            self.pos = pos;
        }
    }

    #[test]
    fn a_slice_of_heap_slots_is_ordered_by_the_slots_and_records_their_positions() {
        let keys = [4, 1, 3, 1, 0, 2];
        let mut slots: StdVec<Slot> = keys.iter().map(|&key| Slot { key, pos: NOT_IN_HEAP }).collect();
        let mut heap: IndexedHeap<8> = IndexedHeap::new();
        for id in 0..6 {
            heap.push(id, &mut slots[..]).unwrap();
        }
        for p in 0..heap.len() {
            let id = heap.get(p).unwrap();
            assert_eq!(slots[id as usize].pos as usize, p, "position recorded in the slot");
        }
        slots[0].key = 0;
        heap.update(0, &mut slots[..]);
        let mut order = StdVec::new();
        while let Some(id) = heap.pop(&mut slots[..]) {
            assert_eq!(slots[id as usize].pos, NOT_IN_HEAP);
            order.push(id);
        }
        assert_eq!(order, [2, 5, 1, 3, 0, 4], "largest key first, ties by id");
        assert!(!slots[..].before(0, 99), "an unknown id is never before");
    }

    fn assert_consistent_ties<S: HeapIds>(heap: &Heap<S>, items: &TieKeys) {
        for p in 0..heap.len() {
            let id = heap.get(p).unwrap();
            assert_eq!(items.pos[id as usize] as usize, p);
        }
    }
}
