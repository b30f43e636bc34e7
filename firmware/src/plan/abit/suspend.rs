//! Suspending and resuming a search: [`AbitSuspended`] holds everything the planner keeps outside its arena.

use crate::plan::space::{Arena, Cost, Counters, InvalidInput, ProblemDefinition, StateSpace};
use super::attachments::CatchHistories;
use super::{AbitArena, AbitParams, AbitStar, ArenaUse, NONE};

/// The search state of a suspended [`AbitStar`]: everything the planner keeps outside its arena (inflation and
/// truncation, the best solution, the RGG terms, the counters), as plain data, so a caller that cannot keep the
/// planner's borrows alive between calls (the on-board navigator, between executive steps) can hold it and
/// continue the search later with [`AbitStar::resume`]. The graph (with its free list and goal vertices), the edge
/// queue and the memo stay in the arena.
#[derive(Debug, Clone)]
pub struct AbitSuspended<St> {
    pub(super) params: AbitParams,
    pub(super) goal_state: Option<St>,
    pub(super) best_goal: u32,
    pub(super) best_cost: Cost,
    pub(super) min_cost: Cost,
    pub(super) inflation: f64,
    pub(super) truncation: f64,
    pub(super) search_id: u32,
    pub(super) search_done: bool,
    pub(super) final_search: bool,
    pub(super) k: usize,
    pub(super) r: f64,
    pub(super) recycled: usize,
    pub(super) approx_vertex: u32,
    pub(super) approx_h: Cost,
    pub(super) pending_full: Option<Arena>,
    pub(super) counters: Counters,
    pub(super) invalid: Option<InvalidInput>,
    pub(super) high_water: ArenaUse,
    pub(super) sampling: Option<BatchSampling>,
}

/// A batch being drawn over several steps (`AbitParams::draws_per_step`).
#[derive(Debug, Clone)]
pub(super) struct BatchSampling {
    /// Draws left of the batch's `sample_attempts_per_sample * samples_per_batch`.
    pub(super) draws_left: usize,
    /// Samples added so far.
    pub(super) added: usize,
    /// The batch's catch-boundary histories.
    pub(super) catch: CatchHistories,
}

impl<St> AbitSuspended<St> {
    /// The state of a search not begun: no goal yet, no solution, the first batch's inflation.
    pub(super) fn fresh(params: AbitParams) -> Self {
        Self {
            params,
            goal_state: None,
            best_goal: NONE,
            best_cost: f64::INFINITY,
            min_cost: f64::INFINITY,
            inflation: params.initial_inflation_factor,
            truncation: 1.0,
            search_id: 1,
            search_done: false,
            final_search: false,
            k: 0,
            r: f64::INFINITY,
            recycled: 0,
            approx_vertex: NONE,
            approx_h: f64::INFINITY,
            pending_full: None,
            counters: Counters::default(),
            invalid: None,
            high_water: ArenaUse::default(),
            sampling: None,
        }
    }

    /// The work counters when the search was suspended.
    pub fn counters(&self) -> Counters {
        self.counters
    }
}

impl<'a, S, V, M, O, G, R, const NV: usize, const NQ: usize, const NM: usize> AbitStar<'a, S, V, M, O, G, R, NV, NQ, NM>
where
    S: StateSpace,
{
    /// Release the borrows and keep the search: the graph, queue and memo stay in the arena, the rest is
    /// returned. Resume it with [`Self::resume`]; a new problem starts with [`Self::new`] instead.
    pub fn suspend(self) -> AbitSuspended<S::State> {
        self.st
    }

    /// Continue a suspended search where [`Self::suspend`] left it. The caller's contract: the arena is the one
    /// the search was suspended from, untouched since; the problem, the space (its map) and the validators answer
    /// as they did; `rng` continues the generator's sequence. Then the search goes on exactly as if it had never
    /// been interrupted (`a_suspended_and_resumed_search_is_the_uninterrupted_search` in
    /// `firmware/workloads/tests/abit_geometric.rs`, and `nav`'s tests).
    pub fn resume(
        arena: &'a mut AbitArena<S::State, S::Attachment, NV, NQ, NM>,
        space: &'a mut S,
        validity: &'a mut V,
        motion: &'a mut M,
        pdef: &'a ProblemDefinition<S, G, O>,
        rng: &'a mut R,
        suspended: AbitSuspended<S::State>,
    ) -> Self {
        Self { arena, space, validity, motion, pdef, rng, st: suspended }
    }
}
