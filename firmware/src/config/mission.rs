//! Defaults and budgets of the closed-loop mission in [`crate::nav`] (issue 18; protocol v2's `MissionConfig`).
//!
//! | const | default | reason |
//! |---|---|---|
//! | [`DEFAULT_CLOSED_LOOP`] | true (`Tracking::ClosedLoop`) | the tether-aware path-tracking controller; `OpenLoop` is the comparison baseline |
//! | [`DEFAULT_REPLAN_CROSS_TRACK_M`] | 0.3 | half the Axel axle track (0.6 m): farther off the path the plan's motion checks no longer describe where the wheels run |
//! | [`DEFAULT_PAYOUT_TOLERANCE_M`] | 0.5 | encoder noise and the taut-tether model's error (a sagging tether is a few percent longer) stay well below it; a snag on a rock that moves the tether's path by decimetres over metres shows above it |
//! | [`DEFAULT_MIN_MARGIN_N`] | 0.0 | the stability check's own boundary (`config::stability::MIN_MARGIN`): a waypoint that fails it is never sent |
//!
//! `protocol::MissionConfig::DEFAULT` bundles them; a `Configure` carries its own values.

/// Default execution of straight drives: true = `Tracking::ClosedLoop`, false = `Tracking::OpenLoop` (config names no
/// protocol type: the wire's enum is built from this in `protocol::MissionConfig::DEFAULT`).
pub const DEFAULT_CLOSED_LOOP: bool = true;
/// Default cross-track distance beyond which the navigator replans from the current pose, metres.
pub const DEFAULT_REPLAN_CROSS_TRACK_M: f32 = 0.3;
/// Default tolerance between tracked tether length and encoder payout, metres.
pub const DEFAULT_PAYOUT_TOLERANCE_M: f32 = 0.5;
/// Default smallest stability margin of a waypoint or the current state, newtons.
pub const DEFAULT_MIN_MARGIN_N: f32 = 0.0;
