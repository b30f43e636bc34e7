//! One status vocabulary for every planner, after OMPL's `PlannerStatus`: an **exact** solution, an
//! **approximate** one, **no solution**, or **invalid input**. Why a search stopped short of an exact answer (it
//! searched everything, its budget ran out, an arena filled up) is an [`Ended`]; what else a planner reports (a
//! cost, expansions, how the enumeration ended) is its own detail: the four type parameters of [`Status`], one per
//! case, which each planner fixes once in a type alias (`Never` for a case it does not have).
//!
//! | planner | `Exact` | `Approximate` | `NoSolution` | `InvalidInput` |
//! |---|---|---|---|---|
//! | ABIT* ([`crate::plan::space::PlannerStatus`]) | cost of the best path | heuristic cost-to-go of the best path's end | always [`Ended::BudgetExhausted`] (an anytime planner never proves there is none) | [`crate::plan::space::InvalidInput`] |
//! | bounded-leg A* ([`crate::plan::team::leg_astar::AStarStatus`]) | the path reaches the goal region | path to the expanded vertex closest to the goal: [`Ended::SearchComplete`] (goal unreachable) or [`Ended::BudgetExhausted`] (best so far, possibly just the start) | no hop brings the robot closer ([`Ended::SearchComplete`]) | the start vertex does not exist |
//! | D* Lite ([`crate::plan::team::dstar_lite::DStarOutcome`]) | cost and expansions | — (never) | [`Ended::SearchComplete`]: the goal is unreachable; [`Ended::BudgetExhausted`]: the search state is kept, call `replan` to continue; with the expansions | — (bad calls are a `DStarError`) |
//! | homotopy class enumeration ([`crate::plan::homotopy::classes::SearchOutcome`]) | [`Enumeration::Enough`] (`max_classes` found) or [`Enumeration::AllClasses`] (every reachable state expanded: the list is every class A* can produce, possibly empty) | [`Ended::BudgetExhausted`] or [`Ended::ArenaFull`]: the classes found so far are kept | — (never) | start or goal outside the free space |
//!
//! A planner's old case names (`Found`, `NoPath`, `Enough`, `BudgetExhausted`, ...) are kept as the words its
//! `label` prints, so reports read as before.

use core::convert::Infallible;

/// What a planner found (OMPL `PlannerStatus`), with the planner's detail of each case: `E` with an exact
/// solution, `A` with an approximate one, `N` with none, `I` why the input was rejected. See the module docs for
/// each planner's detail.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Status<E, A, N, I> {
    /// A solution that answers the query: a path into the goal region, or every requested class.
    Exact(E),
    /// The best answer short of an exact one (a path ending closest to the goal, the classes found so far).
    Approximate(A),
    /// No solution: proved ([`Ended::SearchComplete`]) or not found within the budget.
    NoSolution(N),
    /// The input was rejected before searching.
    InvalidInput(I),
}

impl<E, A, N, I> Status<E, A, N, I> {
    /// Is this an exact solution?
    pub fn is_exact(&self) -> bool {
        matches!(self, Self::Exact(_))
    }
}

/// Why a search ended without an exact answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Ended {
    /// Everything reachable was searched: the answer is final.
    SearchComplete,
    /// The expansion / iteration budget ran out (OMPL `TIMEOUT`).
    BudgetExhausted,
    /// An arena (nodes, open list) filled up.
    ArenaFull,
}

/// How a class enumeration that answered its query ended (the homotopy A*'s exact case).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Enumeration {
    /// `max_classes` classes found.
    Enough,
    /// Every reachable state expanded: the list holds every class the search can produce.
    AllClasses,
}

/// A case that never occurs for a planner.
pub type Never = Infallible;

#[cfg(test)]
mod tests {
    use super::*;

    type Demo = Status<u32, Ended, Ended, Never>;

    #[test]
    fn cases_carry_their_detail() {
        let s: Demo = Status::Exact(3);
        assert!(s.is_exact());
        assert_eq!(s, Status::Exact(3));
        let a: Demo = Status::Approximate(Ended::BudgetExhausted);
        assert!(!a.is_exact());
        assert_ne!(a, Status::NoSolution(Ended::BudgetExhausted));
    }
}
