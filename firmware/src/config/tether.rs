//! Capacities and budgets for [`crate::tether`] (Paton et al. section IV-B, Alg. 1).

/// Anchors in one anchor history (root anchor included). Default 16: a descent wraps a handful of terrain
/// features; a longer history is reported as `TetherError::HistoryFull`.
pub const ANCHOR_HISTORY_CAPACITY: usize = 32;
/// Samples along the tether (from the anchor to the rover) per sweep line. Default 48.
pub const SWEEP_SAMPLES_ALONG: u32 = 48;
/// Sweep lines across the motion (the sweep triangle's other direction). Default 24.
pub const SWEEP_SAMPLES_ACROSS: u32 = 24;
/// Bisection steps that refine the first blocked sweep line. Default 14 (1/16384 of the motion).
pub const SWEEP_REFINE_STEPS: u32 = 14;
/// Attachments found in one call of `attach_anchors` (the repeat loop of IV-B a). Default 8.
pub const MAX_ATTACH_PER_SWEEP: usize = 8;
/// Iterations of the detach loop of Alg. 1. Default 16.
pub const MAX_DETACH_ITERATIONS: u32 = 32;
/// A sample closer than this to the terrain is an obstacle for the tether, metres. Default 0.005 m.
pub const TETHER_CONTACT_DISTANCE_M: f32 = 0.005;
/// Samples within this distance of the pivot anchor are ignored (the anchor itself lies on the surface),
/// metres. Default 0.1 m (also the spacing of successive anchors on a curved surface such as a pole).
pub const PIVOT_EXCLUSION_M: f32 = 0.1;
/// Extra samples near the pivot of each sweep line. Default 16.
pub const NEAR_PIVOT_SAMPLES: u32 = 16;
/// Range from the pivot covered by the near-pivot samples, metres. Default 1.0 m.
pub const NEAR_PIVOT_RANGE_M: f32 = 1.0;
