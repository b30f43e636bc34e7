//! Capacities, budgets and default parameters of [`crate::plan::abit`] (ABIT*, Strub & Gammell ICRA 2020, as
//! used by Paton et al. section V).
//!
//! Arena capacities are const-generic arguments of [`crate::plan::abit::AbitArena`]; the caller owns the arena
//! (a `static` on the board, a `Box` on the host) and lends it to the planner. Parameter defaults are OMPL 1.5.2's
//! ABIT* defaults unless stated otherwise; they are collected in [`crate::plan::abit::AbitParams::ompl_defaults`].

/// Default capacity of the node arena (start, goals, samples and tree vertices share one arena, like OMPL's
/// `samples_` structure). 4096 nodes hold ~40 batches of 100 samples before pruning; beyond that, before a
/// solution, unconnected samples make room for new batches ([`ROOM_FOR_BATCHES`]), and a full arena ends `solve`
/// with `Termination::ArenaFull(Arena::Nodes)` and keeps the best solution.
pub const NODE_CAPACITY: usize = 4096;

/// Default capacity of the edge queue. The queue holds at most `k` outgoing edges per expanded vertex
/// (k ~ 20-40 for the RGG sizes above), so 16384 covers ~500 expanded vertices per search.
pub const EDGE_QUEUE_CAPACITY: usize = 16384;

/// Default capacity of the edge-evaluation memo (OMPL's per-vertex black/white lists), a power of two.
/// A full memo only costs repeated edge evaluations; it is never an error.
pub const EDGE_MEMO_CAPACITY: usize = 16384;

/// Slots probed per memo lookup or insertion (open addressing, linear probing): 8. It bounds the work of one
/// lookup; when all 8 slots of a run hold live entries an insertion replaces the home slot (the memo is a cache,
/// so a lost entry only costs a repeated edge check).
pub const MEMO_PROBES: usize = 8;

/// Upper bound on the neighbours of one vertex (k-nearest `k`, or the r-disc neighbour list). OMPL's k for
/// 10^4 states in R^2 is ~41; 64 leaves headroom. Larger `k` is clamped and counted in
/// `Counters::neighbour_lists_truncated`.
pub const NEIGHBOUR_CAPACITY: usize = 64;

/// Upper bound on goal vertices (the sampled goal plus the fresh goals with undetermined attachment created after
/// each improvement in non-Markovian spaces, Paton et al. V-A). 8 keeps the goal scan cheap.
pub const GOAL_CAPACITY: usize = 8;

/// Batches of samples the node arena keeps room for before each batch of a search without a solution: 2, one to
/// draw and one for the goals and history twins its search creates. Where the arena has less room, unconnected
/// samples are freed, the oldest batch's first (`plan::abit`, "Memory"). OMPL's arena is unbounded and needs no
/// such rule.
pub const ROOM_FOR_BATCHES: usize = 2;

/// Samples per batch (OMPL `samples_per_batch`, default 100).
pub const SAMPLES_PER_BATCH: u32 = 100;

/// Sampling attempts allowed per requested sample before the batch is closed with fewer samples (OMPL's
/// `averageNumOfAllowedFailedAttemptsWhenSampling_`, default 2).
pub const SAMPLE_ATTEMPTS_PER_SAMPLE: u32 = 2;

/// Rejection-sampling attempts for one informed sample in spaces without a direct informed sampler. 100 keeps a
/// batch bounded even when the informed set is a small fraction of the space.
pub const INFORMED_REJECTION_ATTEMPTS: u32 = 100;

/// RGG rewire factor (OMPL `rewire_factor`, default 1.1).
pub const REWIRE_FACTOR: f64 = 1.1;

/// ABIT* initial inflation factor of every batch's first search (OMPL `initial_inflation_factor`, 1e6).
pub const INITIAL_INFLATION_FACTOR: f64 = 1_000_000.0;

/// ABIT* inflation scaling parameter: the final search of a batch uses 1 + 10/q (OMPL, 10).
pub const INFLATION_SCALING_PARAMETER: f64 = 10.0;

/// ABIT* truncation scaling parameter: a search stops at factor 1 + 5/q (OMPL, 5).
pub const TRUNCATION_SCALING_PARAMETER: f64 = 5.0;

/// Prune only when at least this fraction of the states could be pruned (OMPL
/// `prune_threshold_as_fractional_cost_change`, 0.05).
pub const PRUNE_FRACTION: f64 = 0.05;

/// Fraction of new samples that copy an attachment (anchor history) from a neighbour — one of the distinct
/// attachments among their k nearest tree vertices — instead of receiving it when first connected (Paton et al.
/// V-A, "a user-defined percentage"; the paper does not state its value). 0.25 keeps most samples undetermined
/// so the tree can still grow into every region.
pub const ATTACHMENT_COPY_FRACTION: f64 = 0.25;

/// Default iteration budget of one `solve` call: 750, the budget of Paton et al. Table I.
pub const DEFAULT_ITERATION_BUDGET: u32 = 750;

/// Most copies of one state with different attachments ("twins", the state itself included): an edge from a
/// vertex into a tree vertex of an incompatible history goes to a twin of that state with undetermined history
/// (non-Markovian spaces). The ledge needs two or three histories (root only, anchored on the lip, anchored on
/// the pole); 4 bounds the arena growth.
pub const MAX_HISTORY_TWINS: usize = 4;

/// Fraction of new samples drawn near where the tether would catch on terrain
/// ([`crate::plan::space::StateSpace::sample_catch_boundary`]) instead of uniformly (non-Markovian spaces; this
/// project's addition, see the `plan::abit` module docs). The rest stay uniform (or informed), so the RGG still
/// covers the whole space.
pub const CATCH_SAMPLE_FRACTION: f64 = 0.1;

/// Most distinct attachments (compatibility classes of the tree's vertices) whose catch boundaries a batch samples
/// from; the first ones found in arena order are kept.
pub const CATCH_ATTACHMENT_CAPACITY: usize = 8;
