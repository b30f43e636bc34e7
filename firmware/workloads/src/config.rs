//! Capacities of the on-target planning workloads (this crate): fixtures for instruction counts on the emulated
//! flight computer (`tetherbot board bench`), not flight settings (those are `firmware::config`).
//!
//! # `tethered_test3` ([`crate::ledge_pole`]: ABIT* over the tether-aware space, Paton et al. VI-A test 3, 750
//! iterations)
//! Sized from measured high-water marks with about 2x headroom: the workload's own problem (exact ledge + pole
//! world) over seeds 1-30 (`cargo test -p tests --test board_ledge_pole -- --ignored arena_high_water_over_seeds`:
//! at most 263 nodes, 804 queued edges, 438 memo entries, 12 path states; seed 1, the workload's: 152 / 542 / 394 /
//! 12), and the host campaign of `ledge_test3` on the onboard map (~270 nodes, ~900 queued edges; its host arena is
//! 4096 / 32768 / 16384). A full node arena or queue ends `solve` with `Termination::ArenaFull` and keeps the best
//! path; a full memo only costs repeated edge checks; a path longer than the buffer is reported, not truncated.
//!
//! Bytes on the board (`thumbv7em`, `size_of`): 1 441 816 B arena + 56 580 B path = 1 498 400 B, of which the memo
//! is the largest part (each entry keeps the motion's resulting anchor history, 776 B), then the nodes (a settled
//! state and an anchor history each, ~1 KB).

/// Node slots of the ledge-with-pole (test-3) arena. Default 512 (high water 263 over seeds 1-30; ~270 in the map campaign).
pub const LEDGE_POLE_NODE_CAPACITY: usize = 512;

/// Edge-queue capacity of the ledge-with-pole arena. Default 2048 (high water 804 over seeds 1-30; ~900 in the map
/// campaign). An entry is ~60 B.
pub const LEDGE_POLE_EDGE_QUEUE_CAPACITY: usize = 2048;

/// Edge-memo capacity of the ledge-with-pole arena (open addressing, a power of two). Default 1024 (at most 438 entries
/// over seeds 1-30, so the table stays under half full and seed 1 probes exactly as in the campaign's 16384-entry
/// memo: `board_ledge_pole.rs` checks the trial is identical).
pub const LEDGE_POLE_EDGE_MEMO_CAPACITY: usize = 1024;

/// Longest path the ledge-with-pole workload writes out (states). Default 64 (at most 12 over seeds 1-30).
pub const LEDGE_POLE_PATH_CAPACITY: usize = 64;
