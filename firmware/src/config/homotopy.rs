//! Capacities and budgets for [`crate::plan::homotopy`] (Abad-Manterola et al.; Tanner et al.).
//!
//! Every array in the homotopy planner is sized by one of these consts; every loop is bounded by one of the
//! budgets. The defaults fit a tether-demand plane with a few dozen obstacles (the scale of Figs. 11-13 of both
//! papers) in well under 1 MiB, so the whole workspace can sit in the board's static SRAM/PSRAM.

/// Most vertices of one BTM (plane corners + obstacle corners). Default 160: 24 obstacles x 6 corners + plane.
pub const MAX_VERTICES: usize = 160;
/// Most triangles alive in one BTM. Default 2 x [`MAX_VERTICES`] (Euler: a triangulation of V vertices with holes
/// has fewer than 2V triangles).
pub const MAX_TRIANGLES: usize = 2 * MAX_VERTICES;
/// Most BTM edges incident to one vertex. Default 40 (greedy triangulations of random fields stay below 20).
pub const MAX_DEGREE: usize = 40;
/// Most corners of the tether-demand plane's outline. Default 8 (the papers use rectangles).
pub const MAX_PLANE_VERTICES: usize = 8;
/// Most obstacles on one plane at once. Default 24.
pub const MAX_OBSTACLES: usize = 24;
/// Most corners of one obstacle polygon. Default 8 (rocks are coarse polygons).
pub const MAX_OBSTACLE_VERTICES: usize = 8;
/// Candidate-edge arena for (re)triangulation: all vertex pairs of one region. Default V(V-1)/2.
pub const MAX_CANDIDATE_EDGES: usize = MAX_VERTICES * (MAX_VERTICES - 1) / 2;
/// Most triangles in one sleeve (and in one crossing sequence). Default 128.
pub const MAX_SLEEVE: usize = 128;
/// Most points on one path (SHP, descent, ascent, travelled tether). Default 64.
pub const MAX_PATH: usize = 64;
/// Most homotopy classes one A* enumeration returns. Default 16.
pub const MAX_CLASSES: usize = 16;
/// Most L-value constraints (rejected classes, `Lc` of Alg. 1-3). Default 32.
pub const MAX_L_CONSTRAINTS: usize = 32;
/// A* node arena (triangle x L-value states). Default 4096.
pub const MAX_SEARCH_NODES: usize = 4096;
/// A* expansions per enumeration call. Default 20 000.
pub const ASTAR_EXPANSION_BUDGET: usize = 20_000;
/// Funnel (simple stupid funnel) iterations per SHP, restarts included. Default 16 x [`MAX_SLEEVE`].
pub const FUNNEL_BUDGET: usize = 16 * MAX_SLEEVE;
/// Triangle steps when walking a polyline through the BTM. Default 8 x [`MAX_SLEEVE`].
pub const WALK_BUDGET: usize = 8 * MAX_SLEEVE;
/// Cells per side of the controllable-set grid (Abad-Manterola V-B computes controllable sets on a grid).
/// Default 72 (0.28 m cells on a 20 m plane).
pub const CONTROL_GRID: usize = 72;
/// Most map changes handled in one online update batch (Tanner III-C). Default 8.
pub const MAX_UPDATES_PER_BATCH: usize = 8;
/// Most replanning rounds (backtrack targets tried) per online update. Default 24.
pub const REPLAN_BUDGET: usize = 24;

/// Default of `HomotopyParams::max_classes`: classes per A* round. Default [`MAX_CLASSES`] (16), every class the
/// class list can hold.
pub const DEFAULT_CLASSES_PER_ROUND: usize = MAX_CLASSES;
/// Default of `HomotopyParams::descent_clearance_m`: how far the descent path is pushed off the SHP's bend corners,
/// metres (then halved, then zero if blocked). Default 0.15.
pub const DEFAULT_DESCENT_CLEARANCE_M: f64 = 0.15;
/// Default of `HomotopyParams::descent_sample_m`: spacing of the holding checks along the descent, metres.
/// Default 0.2 (finer than the controllable-set grid's 0.28 m cells on a 20 m plane).
pub const DEFAULT_DESCENT_SAMPLE_M: f64 = 0.2;

/// Axel holding limit ([`crate::plan::homotopy::axel`]): distance of the test anchor on the plane, m. Default 20
/// (the tether is then within 3 degrees of the plane from the 1 m boom).
pub const AXEL_ANCHOR_DISTANCE_M: f64 = 20.0;
/// Axel holding limit: scan step of the tether angle, degrees. Default 2.5.
pub const AXEL_THETA_STEP_DEG: f64 = 2.5;
/// Axel holding limit: scan steps (72 x 2.5 deg = 180 deg). Default 72.
pub const AXEL_THETA_STEPS: usize = 72;
/// Axel holding limit: bisections of the last scan interval (2.5 deg / 64 = 0.04 deg). Default 6.
pub const AXEL_BISECTIONS: usize = 6;

/// Largest height tile side, posts ([`crate::plan::homotopy::dem`]). Default 128 (a 128 x 128 f32 tile is 64 KiB).
pub const MAX_TILE_SIDE: usize = 128;
/// Largest height tile, posts. Default [`MAX_TILE_SIDE`]^2 = 16 384.
pub const MAX_TILE_CELLS: usize = MAX_TILE_SIDE * MAX_TILE_SIDE;
/// Smallest accepted post spacing, m. Default 0.02 (finer than any rover-scale DEM we use: Mars Yard 0.094 m).
pub const MIN_TILE_RESOLUTION_M: f64 = 0.02;
/// Largest accepted post spacing, m. Default 5.0 (coarser posts cannot resolve a rover-sized obstacle).
pub const MAX_TILE_RESOLUTION_M: f64 = 5.0;
/// Most planes along one descent (tether-free rim, tether-demand wall, tether-free floor). Default 3: the unfolded
/// outline then has 4 + 2 x 2 = 8 corners, [`MAX_PLANE_VERTICES`].
pub const MAX_DEM_PLANES: usize = 3;
/// Most along-descent bins of the profile used for segmentation. Default 256 (the diagonal of a full tile is 182).
pub const MAX_PROFILE_BINS: usize = 256;
/// Most obstacle components kept before merging (a full list merges a new component into its nearest). Default 64.
pub const MAX_DEM_COMPONENTS: usize = 64;
/// Most obstacles handed to the BTM from a DEM: what its vertex arena holds next to the outline. Default
/// (160 - 8) / 8 = 19.
pub const MAX_DEM_OBSTACLES: usize = (MAX_VERTICES - MAX_PLANE_VERTICES) / MAX_OBSTACLE_VERTICES;
/// Obstacle merge rounds (pairwise overlap merges and reductions to [`MAX_DEM_OBSTACLES`]). Default 256.
pub const DEM_MERGE_BUDGET: usize = 256;
/// Default of `DemParams::max_tilt_rad`: a post whose local normal is tilted more than this from its plane's normal
/// is an obstacle, degrees. Default 30 (a 30 deg lip on a plane the rover is held on tips the two-wheeled body).
pub const DEFAULT_MAX_TILT_DEG: f64 = 30.0;
/// Default of `DemParams::min_band_m` as a multiple of the rover's track: a plane band shorter than this along the
/// descent is merged into its neighbour. Default 2 (a 2 m band for Axel's 1 m track).
pub const DEFAULT_MIN_BAND_TRACKS: f64 = 2.0;
/// Smallest angle between consecutive fitted planes that is unfolded; closer planes are fitted as one, degrees.
/// Default 3.
pub const MIN_FOLD_DEG: f64 = 3.0;
/// Largest half width (posts) of the window over which a DEM post's protrusion is measured against its plane
/// (`dem` step 6). Default 8 (17 x 17 posts).
pub const DEM_WINDOW_MAX: usize = 8;
