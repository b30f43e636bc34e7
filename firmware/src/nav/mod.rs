//! The navigator: the flight executive's [`Autonomy`] implementation.
//!
//! Paton et al. (section IV) plan on a map the rover builds itself from its own range sensor. The navigator is
//! where that happens on board: each scan chunk the executive accepts from the link is integrated into the onboard
//! TSDF as it arrives ([`Autonomy::scan_part`], [`Map::integrate_points`]); when the scan is complete the ESDF is
//! brought up to date ([`Map::update_esdf`]) within the map's own budgets ([`Autonomy::scan_complete`]); the map's
//! state goes out in every `Telemetry` frame ([`MapStatus`]). The map's configuration comes with `Configure.map`
//! (protocol v3; the navigator boots with [`MapConfig::DEFAULT`]); another resolution rebuilds the map empty.
//! When the block pool is 7/8 full, a scan first forgets the blocks far from the rover ([`Map::forget_beyond`]; the
//! radii and fills are `config::nav`'s `MAP_FORGET_*`), so a traverse longer than the pool holds keeps the map round
//! the rover instead of dropping every new voxel.
//!
//! ## Goals: tethered ABIT* on the onboard map (Paton et al. V)
//! A `GoalRequest` for [`PlannerChoice::Abit`] sets up the problem of [`crate::plan::tethered`] on the onboard map
//! ([`Autonomy::goal`]):
//! - **start**: the rover settled ([`crate::rover::settle`]) on the map under the tracked body pose (the last
//!   accepted `MotionReport` pose, see the mission below); before the first report under the last scan's sensor
//!   position, with the sensor's heading as yaw (the sensor mount's horizontal offset from the axle is not known on
//!   board and is ignored); a start that collides only within the extra voxel of body clearance (below) is settled
//!   with the rover's own clearance, so a rover next to a rock that appeared can be planned away from it;
//! - **anchor history**: the mission's tracked anchor history once the rover has moved (replans and goal changes
//!   start from the tether as it lies); before that the root anchor of the last `Configure`
//!   (`tether.root_anchor`) alone, i.e. a straight tether from the root;
//! - **rover**: the Axel model ([`crate::config::rover::RoverParams::AXEL`]) with `Configure.rover`'s wheel radius,
//!   track (`axle_length_m`), boom length, mass (split body / boom by `BOOM_MASS_FRACTION`), friction and the
//!   tether's tension limit; one voxel of extra body clearance, as the campaign plans on a map; up to
//!   `FOOTPRINT_UNOBSERVED_MAX` footprint ring points in unobserved space;
//! - **bounds** ([`PlanBounds`]): the extent of the map's blocks (grown to contain the start, plus
//!   `BOUNDS_Z_MARGIN_M` in z), cut to the **planning window** (the horizontal box spanned by the start and the
//!   goal, grown by `PLAN_WINDOW_MARGIN_M`: a mast's scan observes far beyond the descent, and samples there are
//!   wasted). A goal outside it is an **off-map goal** (section VI-B): it connects from any state
//!   within `off_map_edge_m` of the bounds, and the plan ends at that state;
//! - **goal region**: within `tolerance_m` (axle distance) of the rover settled under the goal position (at the
//!   first of `GOAL_SETTLE_YAWS` yaws that settles); where it does not settle there on observed ground (a rock's
//!   voxels under the body, a steep contact), a position of the region where it does: of `GOAL_REGION_RINGS`
//!   rings of 8 positions `tolerance_m / 4` apart, the innermost with one whose axle stands within
//!   `3 tolerance_m / 4` of the goal, the one nearest the start, and the region shrinks by that distance (so a plan
//!   that reaches it ends within `tolerance_m`); searched again when a scan changes the map under it;
//! - **budget**: `min(goal.max_iterations, MAX_PLAN_ITERATIONS)` iterations, and `time_budget_ms` of flight time
//!   when non-zero; in a mission, a search that spends its iterations with nothing the mission can drive (no
//!   path; an approximate one not allowed or short of `MIN_APPROXIMATE_PROGRESS_M`), or with only an approximate
//!   path over ground the map shows all the way to the goal, goes on where it stopped for further rounds of the
//!   same budget, up to `MAX_PLAN_ITERATIONS` in all, before the mission stops `NoSolution` or drives it
//!   (`NavPlanStats::search_extensions` counts them); the sampler is SplitMix64 ([`crate::plan::SplitMix64`]) seeded from `Configure.planner.rng_seed` and the goal id;
//!   `batch_size` is the samples per batch (at most `SAMPLES_PER_BATCH`); `goal_bias` has no meaning for ABIT*
//!   (it samples no goal states) and is ignored.
//!
//! Refusals are `InvalidInput` with a [`GoalRefusal`] reason, logged and counted ([`NavPlanStats::refusals`]): no
//! `Configure`, no scan yet, an empty map, a map without an observed surface block, a start or an on-map goal that
//! does not settle. `PlannerChoice::Team` never reaches the navigator: the executive runs the team mission itself
//! (protocol v8, `exec/team.rs`); a navigator asked anyway answers `PlannerUnavailable`, as it answers `Homotopy`
//! without the global planner's storage ([`Navigator::new`]; [`Navigator::with_homotopy`] lends it).
//!
//! ## Terrain tiles and homotopy goals (protocol v7; issue 20 item 4; `nav/tile.rs`, `nav/homotopy.rs`)
//! Abad-Manterola et al. (III-VI) and Tanner et al. (II) choose the homotopy class and the intermediate anchors of a
//! long descent on an orbital DEM; the settled path is Paton et al.'s local problem. On board:
//! - **Tile upload**: `TileChunk`s (in order, checked by the executive's `TileAssembler`) are staged
//!   ([`Autonomy::tile_part`]); the last one swaps the staged tile in if `HeightTile::load` accepts it whole
//!   ([`Autonomy::tile_complete`]). A rejected, abandoned or refused upload leaves the tile in use and any route
//!   planned on it intact. `MapStatus.tiles_loaded`, `tile_id`, `tiles_abandoned`. Limits: 128 x 128 posts
//!   (`MAX_TILE_SIDE`; 64 KiB of `f32`), spacing 0.02 .. 5 m; staging and tile 128 KiB of [`NavPlanStorage`].
//! - **Global route** (a `GoalRequest` for `PlannerChoice::Homotopy`, checked at once: a `Configure`, a pose and a
//!   tile, else `InvalidInput` with `NotConfigured` / `NoPose` / `NoTile`), in three `plan_step` calls, one phase
//!   each: (1) `DemDescent::segment` of the tile from `Configure.tether.root_anchor` to the goal (corridor half
//!   width `HOMOTOPY_CORRIDOR_HALF_WIDTH_M` 6 m, soil friction `Configure.rover.friction_coefficient`, the rest
//!   `DemParams::for_rover` of the configured rover), `check_ends`, `build_btm`; (2) Axel's holding limit on the
//!   wall (`axel_model`); (3) Alg. 1 (`preplan`) with Axel's model and `route_to_world` with
//!   `Configure.tether.max_payout_m`. Refusals are `InvalidInput`, counted and logged like the others:
//!   `DescentNotSegmented` (the log names the `DemError`), `NoRoute`, `PayoutExceeded`, `RouteRefused`. The route is
//!   reported as the goal's first `PlanStatus` (`ExactSolution`, `iterations` = classes examined, `best_cost` = the
//!   tether's 3D length) and `Plan`: the **leg goals** (each facing the next; anchors: the root and the anchors the
//!   route expects; margin 0, not evaluated on the tile).
//! - **Legs**: the route's waypoints after the route segment nearest to the rover (never back up the route),
//!   skipping those within `HOMOTOPY_LEG_MIN_M` (1 m) of the previous leg goal and splitting stretches longer than
//!   `HOMOTOPY_LEG_MAX_M` (5 m); the last leg's goal is the request's position and tolerance, the others'
//!   tolerance `HOMOTOPY_LEG_TOLERANCE_M` (0.5 m); at most `HOMOTOPY_MAX_LEGS` (32). Each leg is a tethered ABIT*
//!   goal set up by the same `set_up` as a replan, from the tracked pose and anchor history (the mission's), when the
//!   first drive step after the route (or after the previous leg's arrival) finds no leg active: the executive goes
//!   to `Planning` and a new `PlanStatus` / `Plan` follows. Arriving within a leg's tolerance starts the next leg
//!   (the mission stays `Driving`); only the last leg's arrival is `Arrived`. Replans, stalls and the replan limit
//!   work per leg (a leg is not counted as a replan). At each leg's start the tracked anchors (after the root) are
//!   compared with the route's expected anchors: one farther than `HOMOTOPY_ANCHOR_AGREEMENT_M` (1 m) from every
//!   expected anchor is logged and counted ([`HomotopyStats::anchor_disagreements`]).
//! - **Global replanning** (Tanner et al. Alg. 3, reduced): a leg other than the last whose ABIT* ends without a plan
//!   the mission would drive (`NoSolutionWithinBudget`, or an approximate plan not allowed or short of
//!   `MIN_APPROXIMATE_PROGRESS_M`) means the onboard map contradicts the tile there: a regular octagon of radius
//!   `HOMOTOPY_BLOCK_RADIUS_M` (1 m) round the leg's goal joins the BTM (a local update; where it overlaps
//!   obstacles already there, a region blocked before or a tile obstacle, they merge into one 8-DOP round all of
//!   them, `Btm::merge_obstacles`) and the route is planned
//!   again from the root anchor (Alg. 1), reported as a new route (`ExactSolution` and its `Plan`), its legs from
//!   the rover on; at most `HOMOTOPY_MAX_GLOBAL_REPLANS` (3) per goal, counted with their one reason
//!   ([`HomotopyStats::global_replans`], `global_replan_failures`) and logged. Not done: Alg. 3's plan from the
//!   tether already paid out (the new route starts at the root, the legs at the rover; the tracked anchors are only
//!   compared), and the last leg's failure (its goal is the request's) ends the mission like any goal's.
//! - Storage: [`HomotopyStorage`] (~0.66 MiB: BTM 240 KiB, A* workspace 292 KiB, segmentation scratch 112 KiB, the
//!   descent, the route and the legs), lent once like the rest (host: a `Box`; board: a static in SRAM `.data`).
//!
//! [`Autonomy::plan_step`] runs at most `iterations` new ABIT* iterations, and stops earlier (after at least one)
//! once `MOTION_CHECKS_PER_STEP` new motion checks were computed, or after a step that drew `DRAWS_PER_STEP` more
//! samples of a batch (ABIT* draws a batch over several steps, `AbitParams::draws_per_step`), so one executive step
//! does a bounded amount of geometry (on the emulated board a motion check costs ~0.2-0.5 s against the 2 s
//! watchdog). When the budget is spent (or the
//! planner converges, fills its arena, or the time budget passes) it reports the final state: `ExactSolution`,
//! `ApproximateSolution` (the tree vertex closest to the goal, `TRACK_APPROXIMATE`), `NoSolutionWithinBudget`, and
//! fills the plan buffer with the path's settled states (their anchor histories, root and most recent anchors up
//! to `MAX_ANCHORS_PER_WAYPOINT`, and their stability margins on the map); [`Autonomy::next_motion`] then hands out
//! its motion primitives in order: per path segment an in-place turn to the drive heading, a straight drive (negative
//! when Axel drives the segment backwards) and a turn to the next state's yaw ([`segment_motions`], exactly the
//! motions [`crate::plan::tethered::MotionPlan`] interpolated and the validator checked).
//!
//! **No waypoint below the minimum margin or beyond the spool.** When a plan is filled, the path is cut before its
//! first state whose stability margin on the map (`TetherSpace::stable_with`, a fraction of the rover's weight,
//! times `mass_kg * STANDARD_GRAVITY`) is below `Configure.mission.min_margin_n` or fails the check, or whose
//! tether (anchor history length to the axle) exceeds `Configure.tether.max_payout_m`; a cut plan is reported
//! `ApproximateSolution` (it no longer reaches the goal), a plan cut to the start alone `NoSolutionWithinBudget`.
//! The planner itself is unchanged (its own stability check already rejects unstable states).
//!
//! ## The mission (protocol v2; issue 18; `nav/mission.rs`)
//! The navigator runs the closed loop Paton et al. (section VII) drove with a person in it:
//! - **State machine** ([`MissionState`](crate::protocol::MissionState), in every `MissionStatus`): `Idle` ->
//!   `Planning` (goal accepted) -> `Driving` (one drive command at a time) -> `Verifying` (after each report and
//!   each scan: re-checks of the remaining plan) -> `Driving` ... -> `Arrived` (the tracked pose horizontally
//!   within `tolerance_m` of the goal position), or `Safe` with a [`StopReason`](crate::protocol::StopReason): a
//!   refused goal (`GoalRefused`), no path or an approximate one without `allow_approximate` (`NoSolution`; an
//!   approximate plan that is allowed is driven to its last (safe) state, then `NoSolution`), a cancel, a
//!   shutdown, the current state unstable on the map or its margin below `min_margin_n` (`MarginBelowMinimum`;
//!   a margin below the planner's `min_stability_margin` but not below `min_margin_n` replans instead, see
//!   "Re-checks and replans"), tension over
//!   `max_tension_n` (`TensionLimit`), tracked tether and encoder inconsistent after a re-estimate
//!   (`TetherInconsistent`), `MAX_POSE_JUMPS` rejected poses in a row (`PoseJump`), `MAX_STALLS` stalls in a row
//!   (`MotionStalled`), more than `MAX_REPLANS` replans without `REPLAN_PROGRESS_M` of progress towards the goal
//!   (`ReplanLimit`), no report in time (`MotionTimeout`),
//!   `MAX_SCAN_REJECTS` rejected scans in a row (`ScanInconsistent`). A goal request while driving replaces the
//!   goal (the executive stops the motion in flight); a cancel stops safe (`Cancelled`).
//! - **Tracked tether**: the anchor history starts at the root on `Configure` and is propagated with Alg. 1
//!   ([`crate::tether::predict_anchors`]) along each executed motion (previous -> reported axle position) on the
//!   onboard map. The predicted payout is its length to the axle centre (the tether end the planner uses). A
//!   reading whose payout changed by more than `MAX_PAYOUT_RATE_M_PER_S * dt + PAYOUT_JUMP_SLACK_M` since the last
//!   accepted one is rejected (`tether_rejected`). With no motion in flight, a payout more than
//!   `payout_tolerance_m` from the prediction re-estimates the history (Alg. 1 from the root along the last
//!   `EXECUTED_CAPACITY` executed positions on the current map, which may now show the snag; `REESTIMATE_PER_STEP`
//!   predictions per executive step, the rover waiting); then it stops safe (`TetherInconsistent`) if the last
//!   payout still disagrees, else replans from the re-estimated history.
//! - **Approximate plans (a receding horizon)**: an approximate plan is driven only when the goal request allows
//!   it and its last state is at least `MIN_APPROXIMATE_PROGRESS_M` nearer the goal than its start (else
//!   `NoSolution`); at its last (safe) state the navigator replans from there, on the map its scans have grown
//!   on the way (terrain beyond a rise or a lip is observed only from near it). When the map already shows the
//!   ground from its end to the goal (an occupied voxel in every column on the line between them,
//!   `GROUND_TO_GOAL_SAMPLES` columns at most), looking again cannot help, and the search goes on to
//!   `MAX_PLAN_ITERATIONS` first (budget, above): on a steep slope an approximate end beside the goal can be a
//!   dead end that Axel, which holds there only along the fall line, leaves only by going back up.
//! - **Looking at an unobserved goal**: when planning ends with nothing the mission could drive (`NoSolution`, or
//!   an approximate plan it may not drive) while the goal's voxel column is unobserved and the goal's bearing is
//!   more than `LOOK_MIN_TURN_RAD` from the heading, the rover turns in place to face the goal (the turn passes a
//!   motion check on the current map with the tracked tether first), its next scan looks there, and it plans again,
//!   at most `MAX_LOOKS` times per goal. The range sensor looks ahead only, and a plan driven in reverse (Axel drives
//!   either way) leaves the goal behind it; without the look the mission stopped `NoSolution` in front of ground it
//!   had never turned towards.
//! - **Re-checks and replans**: after each report the next `RECHECK_AFTER_MOTION` segments are re-checked
//!   (the current state's margin and the motion from it to the segment's end, then the planned motions, each a
//!   full motion check on the current map: collision, settling, anchors, stability), after each scan the whole
//!   remaining plan; one check per executive step (`Wait`). A failed check of a later segment ends the plan
//!   before that segment (the segments before it passed on the same map: they are driven, and the navigator
//!   plans again at their end, where it sees more). A failed check of the current segment, a stall, a cross-track
//!   distance over `replan_cross_track_m`, or the end of a plan short of the goal replans from the tracked pose
//!   and history (a new seed per replan). The current state is settled with its own axle and heading
//!   (`TetherSpace::settle_under_axle`), not as a surface point. When it is stable on the map with less than the
//!   planner's minimum margin (0.02 rover weights) but at least `min_margin_n`, the rover stands where no plan
//!   could start: the replan gives states within `START_ESCAPE_VOXELS` of it the start's own margin as their
//!   minimum (`planning::thin_start_escape`, `MarginEscape`), so the plan leaves through nothing worse, and every
//!   state beyond keeps the full minimum (counted in `MissionCounters::thin_margin_replans`).
//! - **Tracking** (`Configure.mission.tracking`): `OpenLoop` hands out the plan's motions as planned (the
//!   baseline). `ClosedLoop` is the tether-aware path-tracking controller: along the current segment it aims at
//!   the point `TRACK_SEGMENT_M` ahead of the rover's projection, turns when the heading error exceeds
//!   `HEADING_TOLERANCE_RAD`, else drives at most `TRACK_SEGMENT_M`; the feed-forward turns the aim by
//!   `-atan(k * s)`, where `s` is the sine from the drive direction to the tracked tether's last anchor (the
//!   tether's lateral pull) and `k` the drift gain learned online by least squares from the lateral displacement
//!   of each reported straight drive (`k = sum(lat * s) / sum(s^2 * |d|)`, bounded by `DRIFT_GAIN_LIMIT`). The
//!   simulator's drift model is not used.
//! - **Bad input in the loop**: a report for an unknown command is the executive's `Nack(UnknownCommand)`; a
//!   pose farther than `POSE_JUMP_BASE_M + POSE_JUMP_PER_M * |d|` (or `POSE_JUMP_YAW_RAD`) from odometry is
//!   replaced by odometry and counted (`pose_jumps`); a scan whose sensor is more than `SCAN_POSE_TOLERANCE_M`
//!   from the tracked pose is not integrated (`scans_rejected`); counters in `MissionStatus` and
//!   [`MissionCounters`].
//! - Parameters (`config::mission`): `TRACK_SEGMENT_M` 0.5, `HEADING_TOLERANCE_RAD` 0.03, `SEGMENT_DONE_M` 0.08,
//!   `MAX_REPLANS` 8, `REPLAN_PROGRESS_M` 0.5, `MIN_APPROXIMATE_PROGRESS_M` 0.25, `MAX_LOOKS` 2,
//!   `LOOK_MIN_TURN_RAD` 0.35, `MAX_STALLS` 2,
//!   `POSE_JUMP_BASE_M` 0.5, `POSE_JUMP_PER_M` 0.5, `POSE_JUMP_YAW_RAD` 0.6,
//!   `MAX_POSE_JUMPS` 3, `SCAN_POSE_TOLERANCE_M` 2.0, `MAX_SCAN_REJECTS` 3, `MAX_PAYOUT_RATE_M_PER_S` 1.0,
//!   `PAYOUT_JUMP_SLACK_M` 0.3, `RECHECK_AFTER_MOTION` 2, `EXECUTED_CAPACITY` 64, `REESTIMATE_PER_STEP` 4,
//!   `DRIFT_GAIN_LIMIT` 1.0,
//!   `MIN_DRIFT_SAMPLE_M` 0.05, `STANDARD_GRAVITY` 9.81, `RECOVERY_ROOT_TOLERANCE_M` 0.01;
//!   `MissionConfig::DEFAULT`: ClosedLoop, 0.3 m, 0.5 m, 0 N.
//! - Resets (issue 24 item 2, [`retained`]): after each step the navigator checkpoints the tether state (root,
//!   tracked anchors, body pose, payout) and the ground round the rover (a 2 m x 2 m height patch taken from the
//!   map after each complete scan) into retained memory when it changed; at boot it reads it back. A
//!   checkpoint makes the mission `Safe` (`Reset`) and the next `Configure` with the same root continues from the
//!   recovered anchors (a re-estimate then starts from them, not from the root); an unreadable one makes it `Safe`
//!   (`TetherStateLost`) and refuses goals. The recovered pose is the plan's start; scans are not checked against
//!   it until the first motion report (the ground surveys again, from the lander's mast too). The recovered ground
//!   patch is written into the new map at that `Configure` (where no survey sees under the rover, its start
//!   still settles).
//! - Bounds: each report does one Alg. 1 prediction; each `Verifying` step one settle, one stability check and one
//!   motion check; each re-estimate step `REESTIMATE_PER_STEP` predictions; each closed-loop step one pass over
//!   the path's segments (`PATH_CAPACITY`).
//!
//! ## Suspended between steps, restarted after a map change (no heap, no `unsafe`)
//! [`AbitStar`](crate::plan::abit::AbitStar) borrows its arena, the space (which borrows the map), the validators,
//! the problem and the generator for its whole life. The navigator cannot keep it between executive steps: that
//! would be a self-referential struct (the map view borrows the navigator's own storage, which scans must also
//! mutate). So every `plan_step` rebuilds the map view, the space and the problem, and
//! - **resumes** the search the previous step suspended ([`AbitStar::suspend`](crate::plan::abit::AbitStar::suspend)
//!   keeps the graph, queue and memo in the lent arena and returns the rest as plain data, held in
//!   [`NavPlanStorage`] with the SplitMix64 generator's state; `resume` continues exactly where it stopped), or
//! - after a scan (the map changed: the suspended search's motion checks and its solution no longer hold)
//!   **restarts** it from the goal's seed on the new map, for what is left of the goal's iteration budget
//!   (`NavPlanStats::restarts`; the start state settled at goal time is kept).
//!
//! A resumed search equals one uninterrupted `solve` (`firmware/workloads/tests/abit_geometric.rs`'s
//! `a_suspended_and_resumed_search_is_the_uninterrupted_search`; here `same_inputs_same_plan_whatever_the_step_size`:
//! with 3 iterations per step, the same plan, iterations, motion checks and stability problems as in one step, and
//! one extra settle per step, the goal state's). No step runs an iteration twice, so every step's geometry stays
//! within `MOTION_CHECKS_PER_STEP`.
//!
//! ## Storage
//! The block pool and the block index are owned by the caller and lent to the navigator for good (`Vec`s on the
//! host, `&'static mut` slices in the board's PSRAM). So is the planning storage ([`NavPlanStorage`], ~1 MiB: the
//! ABIT* arena, the suspended search, the best path and its motions; a `Box` on the host, a `static` in the
//! board's SRAM).
//! The navigator builds a short-lived [`Map`] view per call ([`Map::reattach`]), so it holds no borrow between
//! calls.
//!
//! ## Parameters
//! - the map: [`MapConfig`] (default [`MapConfig::DEFAULT`]: 5 cm voxels, 15 cm truncation, 32 ESDF sweeps);
//! - [`NAV_POINT_BATCH`](crate::config::map::NAV_POINT_BATCH): points converted and integrated per batch
//!   (default 256), the only stack buffer;
//! - planning (`config::nav`): `NODE_CAPACITY` 512, `EDGE_QUEUE_CAPACITY` 4096, `EDGE_MEMO_CAPACITY` 256,
//!   `MOTION_CHECKS_PER_STEP` 1, `SAMPLES_PER_BATCH` 100, `DRAWS_PER_STEP` 20, `MAX_PLAN_ITERATIONS` 750, `PATH_CAPACITY` 64,
//!   `MOTION_CAPACITY` 189, `MIN_TURN_RAD` 1e-3, `MIN_DRIVE_M` 1e-3, `BOUNDS_Z_MARGIN_M` 0.5,
//!   `PLAN_WINDOW_MARGIN_M` 3.0, `FOOTPRINT_UNOBSERVED_MAX` 4, `GOAL_REGION_RINGS` 2,
//!   `TRACK_APPROXIMATE` true, `BOOM_MASS_FRACTION` 0.2; the space's parameters are
//!   [`TetherSpaceParams::ONBOARD`](crate::plan::tethered::TetherSpaceParams::ONBOARD) and ABIT*'s
//!   [`AbitParams::ompl_defaults`](crate::plan::abit::AbitParams::ompl_defaults).
//!
//! ## What the onboard map must hold
//! - The tether sweep of anchor prediction ([`crate::tether::predict_anchors`]) runs through unobserved space as
//!   free on board ([`TetherSpaceParams::ONBOARD`](crate::plan::tethered::TetherSpaceParams::ONBOARD), and the
//!   mission's tracked tether): the root may lie off the map (behind the rover, above an unmapped rim), and what the
//!   tether meets unseen shows as a payout the prediction does not explain (re-estimate, then `TetherInconsistent`).
//! - The surface search of a sample starts at the top of the planning bounds and steps through unknown space to
//!   the **highest observed surface** of the column ([`crate::plan::tethered::surface_point`]); the settler then
//!   needs observed space round the rover: the footprint, the lower halves of the wheels and the body (unobserved
//!   space above the axle is taken as free: no overhangs; [`crate::rover`]). Unknown space **under** an observed
//!   surface is inside the terrain ([`Map::esdf_filled`]): a slope seen at a grazing angle has only a
//!   thin observed band behind its surface, and the settler's queries reach below it.
//! - Rays leave unobserved stripes between them where they land more than a voxel apart (far from the sensor, at
//!   grazing incidence): a goal column inside such a stripe does not settle (`GoalNotSettled`).
//! - A scan is integrated chunk by chunk (at most `FRAMES_PER_STEP` chunks of 128 points per executive step):
//!   integrated whole, an 8000-point scan at 5 cm voxels outlasted the emulated board's watchdog in one step. The
//!   mission's pose check runs at a scan's first chunk; a rejected scan's chunks are all skipped. Chunks of a scan
//!   abandoned incomplete stay in the TSDF (each ray is a measurement of its own); the ESDF and the plan re-check
//!   follow the next complete scan.
//!
//! ## Budgets
//! Work per chunk is bounded by `points * max_ray_voxels` voxel updates, per complete scan by `esdf_max_sweeps` ESDF
//! sweeps of `ESDF_VISITS_PER_BLOCK` voxel visits per block in use (`Configure.map` keeps both within
//! `MAX_RAY_VOXELS_LIMIT` and `ESDF_SWEEPS_LIMIT`); an ESDF that runs out of budget is counted and continues with
//! the next scan. Work per `plan_step` is bounded by
//! its new iterations, `MOTION_CHECKS_PER_STEP` and `DRAWS_PER_STEP`, each iteration bounded by the planner's own
//! budgets.
//!
//! ## Tests
//! Mission tests (`nav::mission_tests`, a kinematic world in the test): a mission that arrives, a cancel, a goal
//! change while driving, a disagreeing tether reading (re-estimate, then `TetherInconsistent`), a payout jump and
//! a tension limit, a pose jump, and closed-loop tracking against open loop under a lateral tether drift.
//! Unit tests (`nav::tests`): plans on mapped flat and 12-degree worlds whose motions, dead-reckoned, end in the goal
//! region; a goal behind an unobserved gap ends approximate or unsolved; every refusal; per-step and goal budgets;
//! the time budget; the same plan for the same inputs whatever the step size (resumed), with no motion check or
//! sample computed twice; a scan between steps restarts the search. `tests/tests/nav_planning.rs`: the same
//! end to end over the link, and on the emulated board (QEMU mps2-an500) with identical output.
//! `host-sim/doc/nav.md` has the on-target storage and stack figures and how the navigator came to its design.
//!

mod homotopy;
mod mission;
pub mod retained;
mod planning;
mod tile;
#[cfg(test)]
mod tests;
#[cfg(test)]
mod homotopy_tests;
#[cfg(test)]
mod mission_tests;

pub use homotopy::{GlobalPlanStorage, HomotopyStats, HomotopyStorage, NoGlobalPlanner};
pub use mission::{BodyPose, Mission, MissionCounters};
pub use planning::{segment_motions, GoalRefusal, NavArena, NavPlanStats, NavPlanStorage};

use core::borrow::BorrowMut;

use hal::Instant;

use crate::config::map::{MapConfig, NAV_POINT_BATCH};
use crate::config::nav::{MAP_FORGET_AT_EIGHTHS, MAP_FORGET_RADII_M, MAP_FORGET_TO_EIGHTHS, MAX_PLAN_ITERATIONS};
use crate::exec::{Autonomy, DriveStep, PlanBuffer, PlanProgress, Refused, Scan};
use crate::geom::Vec3;
use crate::map::{Block, Map, MapError};
use crate::plan::tethered::{PlanBounds, RoverState};
use crate::protocol::{
    Configure, GoalRequest, MapStatus, MissionStatus, Motion, MotionReport, PlanState, PlannerChoice, Point3, Pose,
    TetherReading, TileHeader,
};
use crate::tether::AnchorHistory;

use planning::{PlanSetup, Problem};

/// The executive's autonomy: builds the onboard map from scans and plans goals on it (see the module docs).
pub struct Navigator<B, I, P, H = NoGlobalPlanner> {
    cfg: MapConfig,
    blocks: B,
    index: I,
    used: usize,
    status: MapStatus,
    storage: P,
    setup: Option<PlanSetup>,
    pose: Option<Pose>,
    problem: Option<Problem>,
    next_motion: usize,
    stats: NavPlanStats,
    mission: Mission,
    replan_pending: bool,
    /// The scan whose chunks are arriving, and whether its pose passed the mission's check.
    scan_in: Option<(u32, bool)>,
    /// The last checkpoint written to the retained block (`retained`), to write only what changed.
    retained_last: Option<retained::TetherCheckpoint>,
    /// The homotopy goal being planned or driven (`nav::homotopy`).
    homotopy: Option<homotopy::HomotopyGoal>,
    hstats: HomotopyStats,
    /// The global planner's storage (`nav::homotopy`), if lent.
    global: H,
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>, P: BorrowMut<NavPlanStorage>> Navigator<B, I, P> {
    /// A navigator over lent map and planning storage, which are cleared, without the global planner (homotopy
    /// goals are `PlannerUnavailable`; lend its storage with [`Self::with_homotopy`]). Errors as [`Map::from_slices`].
    pub fn new(cfg: MapConfig, mut blocks: B, mut index: I, mut storage: P) -> Result<Self, MapError> {
        let capacity = Map::from_slices(cfg, blocks.borrow_mut(), index.borrow_mut())?.blocks_capacity();
        let status = MapStatus {
            blocks_capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
            ..MapStatus::default()
        };
        planning::clear_plan(&mut storage);
        Ok(Self {
            cfg,
            blocks,
            index,
            used: 0,
            status,
            storage,
            setup: None,
            pose: None,
            problem: None,
            next_motion: 0,
            stats: NavPlanStats::default(),
            mission: Mission::new(),
            replan_pending: false,
            scan_in: None,
            retained_last: None,
            homotopy: None,
            hstats: HomotopyStats::default(),
            global: NoGlobalPlanner,
        })
    }

    /// The same navigator with the global planner's storage lent (`PlannerChoice::Homotopy` goals are planned).
    pub fn with_homotopy<H: GlobalPlanStorage>(self, global: H) -> Navigator<B, I, P, H> {
        Navigator {
            cfg: self.cfg,
            blocks: self.blocks,
            index: self.index,
            used: self.used,
            status: self.status,
            storage: self.storage,
            setup: self.setup,
            pose: self.pose,
            problem: self.problem,
            next_motion: self.next_motion,
            stats: self.stats,
            mission: self.mission,
            replan_pending: self.replan_pending,
            scan_in: self.scan_in,
            retained_last: self.retained_last,
            homotopy: self.homotopy,
            hstats: self.hstats,
            global,
        }
    }
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>, P: BorrowMut<NavPlanStorage>, H: GlobalPlanStorage> Navigator<B, I, P, H> {

    /// The onboard map (a view over the navigator's storage), for planners, tests and pictures.
    pub fn map(&mut self) -> Option<Map<'_>> {
        Map::reattach(self.cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), self.used).ok()
    }

    /// A whole scan at once: [`Autonomy::scan_part`] then [`Autonomy::scan_complete`] (what the executive does
    /// chunk by chunk).
    pub fn integrate_scan(&mut self, scan: &Scan<'_>, now: Instant) {
        self.scan_part(scan, now);
        self.scan_complete(scan, now);
    }

    /// The terrain tile in use for the homotopy planner (protocol v7), if one was uploaded.
    pub fn terrain_tile(&self) -> Option<&crate::plan::homotopy::dem::HeightTile> {
        self.storage.borrow().tile.current()
    }

    /// Counters of homotopy goals.
    pub fn homotopy_stats(&self) -> HomotopyStats {
        self.hstats
    }

    /// The leg goals of the homotopy route being driven (world frame; empty before the first route).
    pub fn homotopy_legs(&self) -> &[[f32; 3]] {
        self.global.global_ref().map_or(&[], |g| g.legs.as_slice())
    }

    /// The homotopy route being driven (world frame), if one was planned.
    pub fn homotopy_route(&self) -> Option<&crate::plan::homotopy::dem::WorldRoute> {
        self.global.global_ref().and_then(|g| g.route.as_ref())
    }

    /// Which leg of the homotopy route is driven (0-based), while a homotopy goal is.
    pub fn homotopy_leg(&self) -> Option<usize> {
        self.homotopy.filter(|h| h.phase == homotopy::Phase::Legs).map(|h| h.leg)
    }

    /// Counters of on-board planning.
    pub fn plan_stats(&self) -> NavPlanStats {
        self.stats
    }

    /// The planning bounds of the goal being (or last) planned.
    pub fn plan_bounds(&self) -> Option<PlanBounds> {
        self.problem.map(|p| p.bounds)
    }

    /// The start state of the goal being (or last) planned.
    pub fn plan_start(&self) -> Option<RoverState> {
        self.problem.map(|p| p.start)
    }

    /// The last plan's states with their anchor histories (start first; empty without a plan).
    pub fn plan_path(&mut self) -> &[(RoverState, AnchorHistory)] {
        planning::path(&mut self.storage)
    }

    fn refuse(&mut self, why: GoalRefusal) -> PlanState {
        self.stats.refused(why);
        log::warn!("nav: goal refused: {}", why.reason());
        PlanState::InvalidInput
    }

    /// A `GoalRequest` for `PlannerChoice::Homotopy`: checked here, planned by `plan_step` in phases.
    fn goal_homotopy(&mut self, goal: &GoalRequest) -> PlanState {
        self.replan_pending = false;
        if self.global.global_ref().is_none() {
            return PlanState::PlannerUnavailable;
        }
        let why = if self.setup.is_none() {
            Some(GoalRefusal::NotConfigured)
        } else if self.start_pose().is_none() {
            Some(GoalRefusal::NoPose)
        } else if self.storage.borrow().tile.current().is_none() {
            Some(GoalRefusal::NoTile)
        } else {
            None
        };
        if let Some(why) = why {
            self.mission_goal(goal, false);
            return self.refuse(why);
        }
        self.homotopy = Some(homotopy::HomotopyGoal { goal: *goal, phase: homotopy::Phase::Segment, leg: 0, leg_active: false });
        self.stats.goals_accepted = self.stats.goals_accepted.saturating_add(1);
        self.mission_goal(goal, true);
        PlanState::Accepted
    }

    /// A homotopy leg's ABIT* ended without a path the mission would drive (none, or an approximate one it may not
    /// drive): the global replan (`homotopy::replan_around`), reported like the first route. `None`: not a homotopy
    /// leg, the last leg, the replan budget spent, or no new route (the mission stops as for any goal).
    fn homotopy_leg_failed(&mut self, state: PlanState, plan: &mut PlanBuffer) -> Option<PlanProgress> {
        let mut h = self.homotopy.filter(|h| h.phase == homotopy::Phase::Legs && h.leg_active)?;
        let failed = match state {
            PlanState::NoSolutionWithinBudget => true,
            // the mission drives an approximate plan only when allowed and it makes progress (`mission_planned`)
            PlanState::ApproximateSolution => !self.approximate_drivable(h.goal.allow_approximate),
            _ => false,
        };
        let legs = self.global.global_ref().map_or(0, |g| g.legs.len());
        if !failed || h.leg + 1 >= legs || self.hstats.global_replans >= crate::config::nav::HOMOTOPY_MAX_GLOBAL_REPLANS {
            return None;
        }
        let setup = self.setup?;
        let start = self.start_pose();
        let blocked = self.global.global_ref().and_then(|g| g.legs.get(h.leg)).map(|p| [p[0], p[1]])?;
        self.hstats.global_replans = self.hstats.global_replans.saturating_add(1);
        log::warn!(
            "homotopy: leg {} to ({}, {}) found no path ({state:?}): the onboard map contradicts the tile; global replan {}",
            h.leg + 1,
            blocked[0],
            blocked[1],
            self.hstats.global_replans
        );
        let outcome = {
            let global = self.global.global()?;
            let tile = self.storage.borrow().tile.current()?;
            homotopy::replan_around(&mut h, tile, global, &setup, start.as_ref(), blocked)
        };
        match outcome {
            homotopy::PhaseOutcome::Planned { cost, classes } => {
                self.homotopy = Some(h);
                let root = Point3::new(setup.root.x, setup.root.y, setup.root.z);
                if let Some(g) = self.global.global_ref() {
                    homotopy::route_waypoints(g, root, plan);
                }
                self.hstats.routes = self.hstats.routes.saturating_add(1);
                self.mission_planned(PlanState::ExactSolution);
                Some(PlanProgress::Finished { state: PlanState::ExactSolution, iterations: classes, best_cost: Some(cost) })
            }
            _ => {
                self.hstats.global_replan_failures = self.hstats.global_replan_failures.saturating_add(1);
                log::warn!("homotopy: the global replan found no route");
                None
            }
        }
    }

    /// One phase of a homotopy goal's global plan (`nav::homotopy`).
    fn homotopy_plan_step(&mut self, mut h: homotopy::HomotopyGoal, plan: &mut PlanBuffer) -> PlanProgress {
        let refused = |nav: &mut Self, why| {
            nav.homotopy = None;
            nav.refuse(why);
            nav.mission_planned(PlanState::InvalidInput);
            PlanProgress::Finished { state: PlanState::InvalidInput, iterations: 0, best_cost: None }
        };
        let Some(setup) = self.setup else { return refused(self, GoalRefusal::NotConfigured) };
        let start = self.start_pose();
        let outcome = {
            let Some(global) = self.global.global() else { return refused(self, GoalRefusal::NoTile) };
            let Some(tile) = self.storage.borrow().tile.current() else { return refused(self, GoalRefusal::NoTile) };
            homotopy::phase_step(&mut h, tile, global, &setup, start.as_ref())
        };
        self.homotopy = Some(h);
        match outcome {
            homotopy::PhaseOutcome::Continue => PlanProgress::Searching { iterations: 0, best_cost: None },
            homotopy::PhaseOutcome::Planned { cost, classes } => {
                let root = Point3::new(setup.root.x, setup.root.y, setup.root.z);
                if let Some(g) = self.global.global_ref() {
                    homotopy::route_waypoints(g, root, plan);
                }
                self.hstats.routes = self.hstats.routes.saturating_add(1);
                self.mission_planned(PlanState::ExactSolution);
                PlanProgress::Finished { state: PlanState::ExactSolution, iterations: classes, best_cost: Some(cost) }
            }
            homotopy::PhaseOutcome::Refused(why) => refused(self, why),
        }
    }
}

/// Before each batch of a scan's points, when the map's pool is [`MAP_FORGET_AT_EIGHTHS`] full: forgets the blocks
/// farther from the rover than the first of [`MAP_FORGET_RADII_M`] that brings it down to [`MAP_FORGET_TO_EIGHTHS`]
/// (the module docs).
fn make_room(map: &mut Map<'_>, rover: &Vec3) {
    let capacity = map.blocks_capacity();
    if map.blocks_used() * 8 < capacity * MAP_FORGET_AT_EIGHTHS {
        return;
    }
    let before = map.blocks_used();
    for r in MAP_FORGET_RADII_M {
        map.forget_beyond(rover, r);
        if map.blocks_used() * 8 <= capacity * MAP_FORGET_TO_EIGHTHS {
            break;
        }
    }
    log::info!(
        "map: the pool was {} of {} blocks full: forgot {} blocks far from the rover",
        before,
        capacity,
        before.saturating_sub(map.blocks_used())
    );
}

/// Adds `n` to a telemetry counter, saturating at `u32::MAX` (a counter never wraps back to small values).
fn count_up(counter: &mut u32, n: u32) {
    *counter = counter.saturating_add(n);
}

impl<B: BorrowMut<[Block]>, I: BorrowMut<[u32]>, P: BorrowMut<NavPlanStorage>, H: GlobalPlanStorage> Autonomy
    for Navigator<B, I, P, H>
{
    fn configure(&mut self, cfg: &Configure) -> Result<(), Refused> {
        if let Some(settings) = cfg.map {
            let map_cfg = MapConfig::from(settings);
            if map_cfg != self.cfg {
                // A new resolution: the map is rebuilt empty (its voxels mean nothing at another size).
                // `from_slices` checks the configuration before it clears anything, so a refusal changes nothing.
                let capacity = Map::from_slices(map_cfg, self.blocks.borrow_mut(), self.index.borrow_mut())
                    .map_err(|_| Refused)?
                    .blocks_capacity();
                log::info!("map: reconfigured to {} m voxels; the map is cleared", map_cfg.voxel_size);
                self.cfg = map_cfg;
                self.used = 0;
                self.status = MapStatus {
                    blocks_capacity: u32::try_from(capacity).unwrap_or(u32::MAX),
                    ..MapStatus::default()
                };
                self.scan_in = None;
                self.pose = None;
                self.problem = None;
                planning::forget_search(&mut self.storage);
            }
        }
        self.setup = Some(PlanSetup::from_configure(cfg));
        self.mission.configure(cfg);
        self.restore_ground_patch();
        Ok(())
    }

    fn tether_reading(&mut self, reading: &TetherReading, _now: Instant) {
        self.mission_tether(reading);
    }

    fn scan_part(&mut self, part: &Scan<'_>, _now: Instant) {
        // The pose check runs once per scan, at its first chunk; a rejected scan's later chunks are skipped.
        let accepted = match self.scan_in {
            Some((id, accepted)) if id == part.scan_id => accepted,
            _ => {
                let accepted = self.mission_scan_accepted(&part.sensor_pose);
                self.scan_in = Some((part.scan_id, accepted));
                accepted
            }
        };
        if !accepted {
            return;
        }
        let sensor_pose = part.sensor_pose.to_isometry();
        let mut status = self.status;
        let Some(mut map) = self.map() else {
            // Unreachable with storage that `new` accepted; counted rather than ignored.
            count_up(&mut status.pool_errors, 1);
            self.status = status;
            return;
        };
        let p = part.sensor_pose.position;
        let rover = Vec3::new(p.x, p.y, p.z);
        let mut batch = [Vec3::zeros(); NAV_POINT_BATCH];
        let mut pool_error = false;
        for chunk in part.points.chunks(NAV_POINT_BATCH) {
            make_room(&mut map, &rover);
            for (dst, p) in batch.iter_mut().zip(chunk) {
                *dst = Vec3::new(p.x, p.y, p.z);
            }
            let out = map.integrate_points(&sensor_pose, batch.get(..chunk.len()).unwrap_or(&[]));
            count_up(&mut status.points_integrated, out.points_integrated);
            count_up(&mut status.points_rejected, out.points_rejected);
            count_up(&mut status.voxels_dropped, out.voxels_dropped);
            pool_error |= out.pool_error.is_some();
        }
        if pool_error {
            count_up(&mut status.pool_errors, 1);
            log::warn!("map: pool full or index probe exhausted during scan {}", part.scan_id);
        }
        self.used = map.blocks_used();
        status.blocks_used = u32::try_from(self.used).unwrap_or(u32::MAX);
        self.status = status;
    }

    fn scan_complete(&mut self, scan: &Scan<'_>, _now: Instant) {
        if self.scan_in.take() != Some((scan.scan_id, true)) {
            return;
        }
        self.pose = Some(scan.sensor_pose);
        // The map changes: the suspended search's motion checks no longer hold; the next step starts anew.
        planning::forget_search(&mut self.storage);
        self.mission_map_changed();
        let mut status = self.status;
        let Some(mut map) = self.map() else {
            count_up(&mut status.pool_errors, 1);
            self.status = status;
            return;
        };
        if !map.update_esdf().converged {
            count_up(&mut status.esdf_budget_exhausted, 1);
        }
        count_up(&mut status.scans_integrated, 1);
        self.status = status;
        self.take_ground_patch(&scan.sensor_pose);
    }

    fn tile_part(&mut self, header: &TileHeader, offset: usize, heights: &[f32], _now: Instant) {
        if let Some(old) = self.storage.borrow_mut().tile.part(header, offset, heights) {
            count_up(&mut self.status.tiles_abandoned, 1);
            log::warn!("tile {old} abandoned incomplete; the tile in use is kept");
        }
    }

    fn tile_complete(&mut self, header: &TileHeader, _now: Instant) -> Result<(), Refused> {
        match self.storage.borrow_mut().tile.complete(header) {
            Ok(()) => {
                count_up(&mut self.status.tiles_loaded, 1);
                self.status.tile_id = header.tile_id;
                log::info!(
                    "tile {}: {} x {} posts at {} m loaded for the homotopy planner",
                    header.tile_id,
                    header.rows,
                    header.cols,
                    header.resolution_m
                );
                Ok(())
            }
            Err(e) => {
                log::warn!("tile {} refused ({e:?}); the tile in use is kept", header.tile_id);
                Err(Refused)
            }
        }
    }

    fn goal(&mut self, goal: &GoalRequest, now: Instant) -> PlanState {
        self.stats.last_refusal = None;
        if self.mission.tether_state_lost() {
            // the mission stays Safe (TetherStateLost): planning needs the anchor history the reset lost
            return self.refuse(GoalRefusal::TetherStateLost);
        }
        self.problem = None;
        self.next_motion = 0;
        planning::clear_plan(&mut self.storage);
        self.homotopy = None;
        match goal.planner {
            PlannerChoice::Abit => {}
            PlannerChoice::Homotopy => return self.goal_homotopy(goal),
            // the executive runs team goals (`exec/team.rs`); this is reached only by a caller of the hook itself
            PlannerChoice::Team => return PlanState::PlannerUnavailable,
        }
        self.replan_pending = false;
        let Some(setup) = self.setup else {
            self.mission_goal(goal, false);
            return self.refuse(GoalRefusal::NotConfigured);
        };
        let Some(pose) = self.start_pose() else {
            self.mission_goal(goal, false);
            return self.refuse(GoalRefusal::NoPose);
        };
        let budget = goal.max_iterations.min(MAX_PLAN_ITERATIONS);
        let (cfg, used) = (self.cfg, self.used);
        let set_up = match Map::reattach(cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), used) {
            Ok(map) => planning::set_up(&map, &setup, &pose, goal, budget, now),
            Err(_) => Err(GoalRefusal::MapEmpty),
        };
        match set_up {
            Ok(problem) => {
                self.problem = Some(problem);
                self.stats.goals_accepted = self.stats.goals_accepted.saturating_add(1);
                self.mission_goal(goal, true);
                PlanState::Accepted
            }
            Err(why) => {
                self.mission_goal(goal, false);
                self.refuse(why)
            }
        }
    }

    fn plan_step(&mut self, now: Instant, iterations: u32, plan: &mut PlanBuffer) -> PlanProgress {
        if let Some(h) = self.homotopy.filter(|h| h.phase != homotopy::Phase::Legs) {
            return self.homotopy_plan_step(h, plan);
        }
        let Some(mut problem) = self.problem else {
            return PlanProgress::Finished { state: PlanState::NoGoal, iterations: 0, best_cost: None };
        };
        if let Some(state) = problem.finished {
            return PlanProgress::Finished { state, iterations: problem.done, best_cost: problem.best_cost };
        }
        let (cfg, used) = (self.cfg, self.used);
        let progress = match Map::reattach(cfg, self.blocks.borrow_mut(), self.index.borrow_mut(), used) {
            Ok(map) => planning::step(&map, &mut problem, &mut self.storage, &mut self.stats, now, iterations, plan),
            Err(_) => {
                problem.finished = Some(PlanState::InvalidInput);
                PlanProgress::Finished { state: PlanState::InvalidInput, iterations: problem.done, best_cost: None }
            }
        };
        self.problem = Some(problem);
        if let PlanProgress::Finished { state, iterations, best_cost } = progress {
            if self.mission_search_more(state) {
                plan.clear();
                return PlanProgress::Searching { iterations, best_cost };
            }
            if let Some(p) = self.homotopy_leg_failed(state, plan) {
                return p;
            }
            self.mission_planned(state);
        }
        progress
    }

    fn next_motion(&mut self, _now: Instant) -> Option<Motion> {
        let m = planning::motion_at(&mut self.storage, self.next_motion)?;
        self.next_motion = self.next_motion.saturating_add(1);
        Some(m)
    }

    fn drive_step(&mut self, now: Instant) -> DriveStep {
        if let Some(step) = self.mission_start_leg(now) {
            return step;
        }
        self.mission_drive(now)
    }

    fn motion_report(&mut self, report: &MotionReport, motion: Motion, _now: Instant) {
        self.mission_report(report, motion);
    }

    fn motion_timeout(&mut self, _command_id: u32, _now: Instant) {
        self.mission_timeout();
    }

    fn stop_in_flight(&mut self, _now: Instant) -> bool {
        self.mission_stop_in_flight()
    }

    fn cancel(&mut self, _goal_id: u32, _now: Instant) -> Result<(), Refused> {
        self.mission_cancel();
        Ok(())
    }

    fn refusal(&self) -> Option<&'static str> {
        self.stats.last_refusal.map(GoalRefusal::reason)
    }

    fn mission_status(&self) -> Option<MissionStatus> {
        Some(self.mission.status())
    }

    fn abort(&mut self) {
        if let Some(p) = self.problem.as_mut() {
            if p.finished.is_none() {
                p.finished = Some(PlanState::Aborted);
            }
        }
        self.next_motion = usize::MAX;
        self.mission_abort();
    }

    fn map_status(&self) -> MapStatus {
        self.status
    }

    fn recover_retained(&mut self, block: &retained::RetainedBlock) {
        self.mission.recover(retained::read(block));
    }

    fn keep_retained(&mut self, block: &mut retained::RetainedBlock) {
        let Some(mut cp) = self.mission.checkpoint() else { return };
        if let Some(last) = &self.retained_last {
            cp.generation = last.generation;
            if *last == cp {
                return;
            }
        }
        cp.generation = self.mission.generation.wrapping_add(1);
        self.mission.generation = cp.generation;
        retained::write(block, &cp);
        self.retained_last = Some(cp);
    }
}
