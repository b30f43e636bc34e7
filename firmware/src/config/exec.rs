//! Capacities and per-cycle budgets of the flight executive (`crate::exec`).
//!
//! | const | default | reason |
//! |---|---|---|
//! | [`RX_BYTES_PER_STEP`] | 1024 | bytes read from the link per `step`: at 115200 baud a 10 ms cycle brings ~115 bytes, so this drains a burst in a few cycles while bounding the cycle's work |
//! | [`FRAMES_PER_STEP`] | 4 | frames dispatched per `step`; one full sensor chunk costs most |
//! | [`RX_STAGING_LEN`] | 256 | bytes read from the link at once into the staging buffer |
//! | [`TX_QUEUE_LEN`] | 8192 | outgoing bytes buffered when the link is slower than the replies |
//! | [`TX_RESERVE`] | 2 x `MAX_ENCODED_FRAME_LEN` | input is only read while this much transmit room is free, so replies are never dropped |
//! | [`TX_BYTES_PER_STEP`] | 4096 | bytes handed to the link per `step` |
//! | [`LOG_QUEUE_LEN`] | 8 | forwarded log records waiting for their turn; a full queue drops and counts |
//! | [`LOG_FRAMES_PER_SECOND`] | 10 | token-bucket rate of `Log` frames |
//! | [`LOG_BURST`] | 4 | token-bucket depth of `Log` frames |
//! | [`DEFAULT_TELEMETRY_PERIOD_US`] | 1_000_000 | periodic telemetry until `Configure` says otherwise (0 = only on request) |
//! | [`PLAN_WAYPOINTS_CAPACITY`] | 256 | waypoints of one plan kept for transmission (22 `Plan` frames of 12) |
//! | [`PLANNER_ITERATIONS_PER_STEP`] | 8 | planner iterations granted per `step` in planning mode |
//! | [`PLAN_FRAMES_PER_STEP`] | 1 | `Plan` / `DriveCommand` frames emitted per `step` |
//! | [`MOTION_REPORT_TIMEOUT_US`] | 120_000_000 | flight time to wait for a drive command's `MotionReport` before stopping and giving it up |
//! | [`STEP_BUDGET_US`] | 100_000 | a step longer than this is a cycle slip (counted in `Telemetry.cycle`): the fastest telemetry period a `Configure` may ask for (`MIN_TELEMETRY_PERIOD_MS`), a twentieth of the board's 2 s watchdog |
//! | [`SEQ_WINDOW`] | 1024 | host sequence numbers within this distance of the expected one count as lost (ahead) or late (behind); further behind is a new host session (`exec` module docs) |
//! | [`SEQ_HISTORY_LEN`] | 16 | accepted frames (sequence number, CRC) remembered to refuse a duplicate |
//! | [`DRIVE_COMMAND_RESEND_US`] | 10_000_000 | flight time after which an unreported drive command is sent again (same `command_id`; v5), until `MOTION_REPORT_TIMEOUT_US` |
//! | [`TEAM_COMMAND_RESEND_US`] | 10_000_000 | flight time after which an unanswered team order is sent again (same `command_id`; v8), until the mission ends |

use super::protocol::MAX_ENCODED_FRAME_LEN;

/// Bytes read from the link per executive step.
pub const RX_BYTES_PER_STEP: usize = 1024;
/// Frames dispatched per executive step.
pub const FRAMES_PER_STEP: usize = 4;
/// Size of the receive staging buffer.
pub const RX_STAGING_LEN: usize = 256;
/// Capacity of the transmit queue in bytes.
pub const TX_QUEUE_LEN: usize = 8192;
/// Free transmit room required before more input is read.
pub const TX_RESERVE: usize = 2 * MAX_ENCODED_FRAME_LEN;
/// Bytes handed to the link per step.
pub const TX_BYTES_PER_STEP: usize = 4096;
/// Forwarded log records waiting to be sent.
pub const LOG_QUEUE_LEN: usize = 8;
/// Sustained rate of `Log` frames.
pub const LOG_FRAMES_PER_SECOND: u32 = 10;
/// Burst of `Log` frames.
pub const LOG_BURST: u32 = 4;
/// Default telemetry period in microseconds (0 = only on request).
pub const DEFAULT_TELEMETRY_PERIOD_US: u64 = 1_000_000;
/// Waypoints of one plan kept for transmission.
pub const PLAN_WAYPOINTS_CAPACITY: usize = 256;
/// Planner iterations granted per step.
pub const PLANNER_ITERATIONS_PER_STEP: u32 = 8;
/// `Plan` / `DriveCommand` frames emitted per step.
pub const PLAN_FRAMES_PER_STEP: usize = 1;

const _: () = assert!(TX_QUEUE_LEN > TX_RESERVE);
const _: () = assert!(RX_STAGING_LEN <= RX_BYTES_PER_STEP);

/// Flight time the executive waits for the `MotionReport` of a drive command, microseconds. Default 120 s: a
/// straight drive of a few metres at Axel's ~0.1 m/s with margin. On timeout the executive sends `Stop`, forgets
/// the command (a late report is `Nack(UnknownCommand)`), counts it and tells the autonomy
/// (`Autonomy::motion_timeout`).
pub const MOTION_REPORT_TIMEOUT_US: u64 = 120_000_000;

/// Step budget, microseconds: a step that takes longer on the flight clock is a cycle slip (F Prime's rate groups
/// count the same). Default 100 ms: the shortest telemetry period (`MIN_TELEMETRY_PERIOD_MS`), so a step within
/// budget never makes periodic telemetry late, and a twentieth of the board's 2 s watchdog.
pub const STEP_BUDGET_US: u64 = 100_000;
/// Distance from the expected host sequence number within which a frame counts as after lost frames (ahead) or
/// late (behind); a larger jump either way is a new host session (counted, followed).
pub const SEQ_WINDOW: u32 = 1024;
/// Accepted host frames remembered (sequence number and CRC) to refuse a duplicate.
pub const SEQ_HISTORY_LEN: usize = 16;
/// Flight time after which a drive command still awaiting its `MotionReport` is sent again, unchanged (same
/// `command_id`; protocol v5), microseconds: the downlink may have lost it. Default 10 s: longer than most motions
/// (a 1 m straight drive at Axel's ~0.1 m/s), so a clean link sees few resends, and short against
/// `MOTION_REPORT_TIMEOUT_US`, which still ends the wait (at most 11 resends of one command). The host executes a
/// command id once.
pub const DRIVE_COMMAND_RESEND_US: u64 = 10_000_000;

const _: () = assert!(DRIVE_COMMAND_RESEND_US > 0 && DRIVE_COMMAND_RESEND_US < MOTION_REPORT_TIMEOUT_US);

/// Flight time after which a team order (protocol v8 `TeamCommand`) with no answer goes again, unchanged,
/// microseconds. Default 10 s, as `DRIVE_COMMAND_RESEND_US`: a hop or a hub move takes seconds; the host executes
/// an order's id once, so a resend is safe.
pub const TEAM_COMMAND_RESEND_US: u64 = 10_000_000;
