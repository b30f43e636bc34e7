//! Capacities and budgets for [`crate::tether`] (Paton et al. section IV-B, Alg. 1).

/// Anchors in one anchor history (root anchor included). Default 32: a tether wrapped half a turn around the 0.25 m
/// pole of Paton et al.'s test 3 already takes 8-14 anchors (one per ~0.4 rad, see `PIVOT_EXCLUSION_M`), plus the
/// lip; a longer history is reported as `TetherError::HistoryFull`.
pub const ANCHOR_HISTORY_CAPACITY: usize = 32;
/// Samples along the tether (from the anchor to the rover) per sweep line. Default 48.
pub const SWEEP_SAMPLES_ALONG: u32 = 48;
/// Sweep lines across the motion (the sweep triangle's other direction). Default 24.
pub const SWEEP_SAMPLES_ACROSS: u32 = 24;
/// Bisection steps that refine the first blocked sweep line. Default 14 (1/16384 of the motion).
pub const SWEEP_REFINE_STEPS: u32 = 14;
/// Attachments found in one call of `attach_anchors` (the repeat loop of IV-B a). Default 16 (a tether laid over
/// the rounded crest of a real DEM ridge touches it at up to a dozen points in one step).
pub const MAX_ATTACH_PER_SWEEP: usize = 16;
/// Iterations of the detach loop of Alg. 1. Default 32 (one per anchor of a full history).
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

/// Cells from the centre to the edge of the retained ground patch (`nav::retained::GroundPatch`), each way.
/// Default 10: a 21 x 21 grid.
pub const GROUND_PATCH_HALF_CELLS: usize = 10;
/// Cells along one side of the retained ground patch.
pub const GROUND_PATCH_SIDE: usize = 2 * GROUND_PATCH_HALF_CELLS + 1;
/// Cells of the retained ground patch (441).
pub const GROUND_PATCH_CELLS: usize = GROUND_PATCH_SIDE * GROUND_PATCH_SIDE;
/// Spacing of the retained ground patch's cells, metres. Default 0.1 m: the patch spans 2 m x 2 m round the axle,
/// Axel's wheels (1 m apart) at any heading and a first drive step each way.
pub const GROUND_PATCH_SPACING_M: f32 = 0.1;
/// Space above a patch cell's ground that the map must show free for the cell to be kept, and that the cell's
/// vertical ray marks free again when the patch is restored, metres. Default 0.5 m: the wheels' lower halves and the
/// body's underside, which the settler needs observed (`crate::rover`).
pub const GROUND_PATCH_CLEAR_M: f32 = 0.5;
/// A patch cell's ground is searched from this far above the axle, metres. Default 1.0 m.
pub const GROUND_PATCH_ABOVE_M: f32 = 1.0;
/// ... down to this far below it, metres. Default 2.0 m (the patch's edge on a 55-degree face is 1.4 m lower).
pub const GROUND_PATCH_BELOW_M: f32 = 2.0;

/// Bytes of one slot of the retained tether checkpoint (`nav::retained`): a 46-byte head (magic, generation, root,
/// body pose, payout, goal id, anchor count), the ground patch (flag, centre, height reference, a height per cell
/// in millimetres), the largest anchor history at 24 bytes an anchor, and a CRC-32.
pub const RETAINED_SLOT_BYTES: usize = 46 + 13 + GROUND_PATCH_CELLS * 2 + ANCHOR_HISTORY_CAPACITY * 24 + 4;
/// Bytes of the retained block a board lends for it (two slots, written alternately): 3426 with 32 anchors and
/// the 21 x 21 patch.
pub const RETAINED_BYTES: usize = 2 * RETAINED_SLOT_BYTES;
