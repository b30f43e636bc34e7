//! Capacities of the on-target planning workloads ([`crate::workload`]): fixtures for instruction counts on the
//! emulated flight computer (`tetherbot board bench`), not flight settings.
//!
//! # `tethered_test3` (ABIT* over the tether-aware space, Paton et al. VI-A test 3, 750 iterations)
//! Sized from the high-water marks of the workload itself (seed 1) and of the host campaign's 100 trials of
//! `ledge_test3` (seeds 1-100, `host-sim/src/campaign.rs`, whose host arena is 4096 / 32768 / 16384), with
//! headroom; see [`crate::workload::test3`] for the measured figures. A full arena is not an error: `solve` ends
//! with `Termination::ArenaFull` and keeps the best path (the memo only ever costs repeated evaluations).

/// Node slots of the test-3 arena. Default 512 (high water: 262 for seed 1, at most ~300 over the campaign's
/// seeds 1-100): every node holds a settled state and an anchor history (~1.1 KB), so this is the big one.
pub const TEST3_NODE_CAPACITY: usize = 512;

/// Edge-queue capacity of the test-3 arena. Default 2048 (high water: 884 for seed 1, at most ~1 000 over the
/// campaign's seeds).
pub const TEST3_EDGE_QUEUE_CAPACITY: usize = 2048;

/// Edge-memo capacity of the test-3 arena (a power of two). Default 2048 (filled slots: 740 for seed 1).
pub const TEST3_EDGE_MEMO_CAPACITY: usize = 2048;

/// Longest path the test-3 workload writes out (states). Default 64 (seed 1's path: 9 states).
pub const TEST3_PATH_CAPACITY: usize = 64;
