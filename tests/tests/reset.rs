//! A reset of the flight computer mid-descent (issue 24 item 2): the flight software comes back `Safe` with reason
//! `Reset`, recovers the anchor history from its retained memory (`firmware::nav::retained`), and continues when the
//! ground configures it again; the reset is in the field log and the replay resets at the same point.
//!
//! The scenario is `mission_snag.toml` (a hidden rock beside the descent line snags the tether); the reset comes
//! after the first motion that leaves the tether wrapped (the true tether touches the terrain and the flight
//! software tracks an anchor besides the root), so a flight software that came back with a straight tether would be
//! wrong in a way the checks below see. The precondition is asserted, not assumed.

use firmware::protocol::StopReason;
use host_sim::fieldlog;
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::recording::{RecordingLink, RESET_RECORD};
use host_sim::link::{FlightLink, ResetCause};
use host_sim::mission::run::{run_mission, MissionOptions, ResetAt, Verdict};
use host_sim::replay::{replay, ReplayOutcome};

/// The seed of the snag mission these tests reset: one whose mission wraps the tether before it ends (seeds 1 and 2
/// stop safe on `MarginBelowMinimum` before the tether touches the rock since the stability LP's friction octagon,
/// 2026-12-04; the precondition is asserted below either way).
const SEED: u64 = 3;

/// A shipped scenario file and the options of one mission of it with seed `seed` and reset `reset`.
fn mission_setup(file: &str, seed: u64, reset: ResetAt) -> (host_sim::scenario::Scenario, MissionOptions) {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios").join(file);
    let sc = host_sim::scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let opts = MissionOptions {
        seed,
        tracking: firmware::protocol::Tracking::ClosedLoop,
        noiseless: false,
        live: false,
        reset: Some(reset),
    };
    (sc, opts)
}

/// `mission_snag.toml`, seed [`SEED`], reset once the tether is wrapped.
fn snag_with_reset() -> (host_sim::scenario::Scenario, MissionOptions) {
    mission_setup("mission_snag.toml", SEED, ResetAt::Wrapped)
}

fn header(scenario: &str, link: &str) -> fieldlog::Header {
    fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: SEED,
        config: format!("{{\"scenario\":\"{scenario}\",\"link\":\"{link}\",\"step_us\":{DEFAULT_STEP_US}}}"),
    }
}

/// The mission went on after the reset `r`: more motions after it, and an end that is an arrival or a safe stop
/// with a reason (not the reset's own `Reset`, not a lost tether state).
fn assert_went_on(rep: &host_sim::mission::run::MissionReport, r: &host_sim::mission::run::ResetSeen) {
    assert!(rep.motions > r.after_motions, "nothing driven after the reset: {} motions", rep.motions);
    match rep.verdict {
        // `Ended`: the operator ended the mission at a waypoint (`[mission] end_at_waypoint`, the board's test)
        Verdict::Arrived | Verdict::Ended => {}
        Verdict::SafeStop(reason) => assert!(
            !matches!(reason, StopReason::Reset | StopReason::TetherStateLost | StopReason::None),
            "{reason:?}"
        ),
        v => panic!("after the reset the mission ended {v:?}"),
    }
}

/// Runs the snag mission with `opts` in-process, recorded; checks what every reset must give (one reset, reason
/// `Reset`, the anchor history recovered, more motions after it, an arrival or a safe stop with a reason, the
/// reset's record with its `cause` in the log and an identical replay). Returns the reset and the log.
fn reset_mission(opts: &MissionOptions, cause: ResetCause) -> (host_sim::mission::run::ResetSeen, fieldlog::FieldLog) {
    let (sc, _) = snag_with_reset();
    let writer = fieldlog::Writer::new(Vec::new(), &header(&sc.name, "inproc")).unwrap();
    let mut link = RecordingLink::new(host_sim::mission::link::mission_link(&sc).unwrap(), writer);
    let rep = run_mission(&mut link, &sc, opts).unwrap();
    let (flight, bytes) = link.finish().unwrap();
    assert_eq!(flight.resets(), 1);
    let [r] = rep.resets.as_slice() else { panic!("one reset expected: {:?}", rep.resets) };
    assert_eq!(r.reason, "Reset");
    assert_eq!(r.anchors_recovered, r.anchors_before, "the anchor history did not come back: {r:?}");
    assert_went_on(&rep, r);
    // the log holds the reset, and a fresh flight software fed the same bytes resets there and answers the same
    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.faults.iter().filter(|f| f.bytes == cause.record()).count(), 1);
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out:?}");
    (r.clone(), log)
}

#[test]
fn a_reset_mid_descent_recovers_the_wrapped_tether_continues_and_replays() {
    let (_, opts) = snag_with_reset();
    let (r, log) = reset_mission(&opts, ResetCause::Command);
    // the precondition: the tether was wrapped, by the simulator's own tether and by the flight software's
    assert!(r.true_contacts >= 1 && r.anchors_before >= 2, "not a wrapped tether at the reset: {r:?}");
    assert_eq!(log.faults.iter().filter(|f| f.bytes == RESET_RECORD).count(), 1);
    // without the reset the replay cannot match: the check in `reset_mission` can fail
    let mut no_reset = log.clone();
    no_reset.faults.clear();
    let out = replay(&no_reset, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Differs { .. }), "{out:?}");
}

/// The watchdog bites in the middle of the first motion that starts with the tether wrapped on the hidden rock
/// (`ResetAt::BiteWhenWrapped`): the rover stops where it is, the motion's report is lost, and the rebooted
/// software recovers the checkpoint from before the motion; the ground's scan gives it the pose the rover really
/// has, and the mission goes on to an arrival or a safe stop with a reason. The log names the watchdog, and its
/// replay bites at the same point.
#[test]
fn a_watchdog_bite_mid_motion_recovers_the_wrapped_tether_continues_and_replays() {
    let (_, mut opts) = snag_with_reset();
    opts.reset = Some(ResetAt::BiteWhenWrapped);
    let (r, _) = reset_mission(&opts, ResetCause::Watchdog);
    assert_eq!(r.cause, "watchdog", "{r:?}");
    assert!(r.true_contacts >= 1 && r.anchors_before >= 2, "not a wrapped tether at the bite: {r:?}");
}

/// A fixed motion number still bites there (`ResetAt::BiteInMotion`), wrapped or not.
#[test]
fn a_watchdog_bite_in_a_given_motion_ends_that_motion() {
    let (_, mut opts) = snag_with_reset();
    opts.reset = Some(ResetAt::BiteInMotion(3));
    let (r, _) = reset_mission(&opts, ResetCause::Watchdog);
    assert_eq!((r.after_motions, r.cause), (4, "watchdog"), "the bite ends the fourth motion: {r:?}");
}

/// The reboot path on a link: boot, `Configure`, a tether reading (the flight software checkpoints root and payout),
/// a reset by `cause`, the boot status, `Configure` again and a telemetry request. Returns the link, the flight ->
/// host bytes and the mission statuses seen after the reset.
fn reboot_session<L: FlightLink>(link: L, cause: ResetCause) -> (L, Vec<u8>, Vec<firmware::protocol::MissionStatus>, u32) {
    use firmware::protocol::{Message, TetherReading};
    use host_sim::session::HostSession;
    let header = header("reboot", link.name());
    let mut s = HostSession::new(RecordingLink::new(link, fieldlog::Writer::new(Vec::new(), &header).unwrap()));
    s.recv().unwrap();
    s.send(&Message::Configure(host_sim::scripted::default_configure(5))).unwrap();
    s.recv().unwrap();
    let reading = TetherReading { time_us: s.link().now_us(), payout_m: 3.5, tension_n: 20.0, boom_angle_rad: 0.0 };
    s.send(&Message::TetherReading(reading)).unwrap();
    s.recv().unwrap();
    s.link_mut().reset_flight(cause).unwrap();
    let mut after = Vec::new();
    let mut keep = |msgs: Vec<Message>| {
        after.extend(msgs.into_iter().filter_map(|m| if let Message::MissionStatus(st) = m { Some(st) } else { None }))
    };
    keep(s.recv().unwrap());
    s.send(&Message::Configure(host_sim::scripted::default_configure(5))).unwrap();
    keep(s.recv().unwrap());
    let t = s.telemetry().unwrap();
    let resyncs = t.seq_gaps + t.seq_resyncs;
    let (link, bytes) = s.into_link().finish().unwrap();
    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.faults.iter().filter(|f| f.bytes == cause.record()).count(), 1, "the reset's record");
    let out = log
        .records
        .iter()
        .filter(|r| r.direction == fieldlog::Direction::FlightToHost)
        .flat_map(|r| r.bytes.iter().copied())
        .collect();
    (link, out, after, resyncs)
}

/// On the emulated board, by both causes: the reboot command resets the Cortex-M7 (SYSRESETREQ); a watchdog bite
/// (the flight loop stops kicking) lets the CMSDK watchdog's interrupt and then its reset output reboot it. Either
/// way the checkpoint in `.uninit` survives, the rebooted firmware reports `Safe` (`Reset`) and its output equals
/// the in-process flight software's byte for byte. (The whole mission with a watchdog bite
/// mid-descent on the board is the last test.)
#[test]
fn the_board_reboots_by_command_and_by_watchdog_keeps_its_tether_checkpoint_and_answers_as_in_process() {
    let Some(elf) = host_sim::qemu::board_for_tests("reset on the board").unwrap_or_else(|e| panic!("{e}")) else {
        return;
    };
    for cause in [ResetCause::Command, ResetCause::Watchdog] {
        let (_, inproc, inproc_after, inproc_resyncs) = reboot_session(InProcLink::new(DEFAULT_STEP_US), cause);
        let board_link = host_sim::link::qemu::QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
        let (board_link, board, board_after, board_resyncs) = reboot_session(board_link, cause);
        let first = inproc_after.first().expect("a mission status after the reset");
        assert_eq!((first.state, first.reason, first.anchors), (firmware::protocol::MissionState::Safe, StopReason::Reset, 1));
        // the host's numbering went on across the reset: the rebooted software saw the frames before as a gap
        assert!(inproc_resyncs > 0, "the rebooted software did not see the host's numbering jump");
        assert_eq!((board_after, board_resyncs), (inproc_after, inproc_resyncs), "{cause:?}");
        assert!(board == inproc, "{cause:?}: the board's output differs from the in-process flight software's ({} vs {} bytes)", board.len(), inproc.len());
        let exit = board_link.quit(core::time::Duration::from_secs(20)).unwrap_or_else(|e| panic!("{e}"));
        let text = exit.output.both();
        let bit = text.contains("board: WATCHDOG expired: probe lets the reset output act")
            && text.contains("board: REBOOTED by the watchdog's reset output");
        assert_eq!(bit, cause == ResetCause::Watchdog, "{cause:?}, board output: {text}");
    }
}

/// The whole mission on the emulated board with a real watchdog bite mid-descent (`ResetAt::BiteWhenWrapped`: the
/// flight loop stops kicking during the first motion that starts with the tether wrapped on the hidden rock; the
/// CMSDK watchdog's interrupt and then its reset output reboot the Cortex-M7). The rebooted board recovers the
/// wrapped tether from the `.uninit` checkpoint, continues to an arrival or a safe stop with a reason, and its
/// field log, bite included, replays identically on the in-process flight software. About 3 minutes of host time
/// (2 min 55 s measured on the 2-core machine, 2026-12-05).
#[test]
fn a_watchdog_bite_mid_descent_on_the_board_recovers_the_wrapped_tether_and_replays_in_process() {
    let Some(elf) = host_sim::qemu::board_for_tests("bite mission on the board").unwrap_or_else(|e| panic!("{e}")) else {
        return;
    };
    let (sc, mut opts) = snag_with_reset();
    opts.reset = Some(ResetAt::BiteWhenWrapped);
    let link = host_sim::link::qemu::QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
    let mut rec = RecordingLink::new(link, fieldlog::Writer::new(Vec::new(), &header(&sc.name, "qemu")).unwrap());
    let rep = run_mission(&mut rec, &sc, &opts).unwrap();
    let (board, bytes) = rec.finish().unwrap();
    let [r] = rep.resets.as_slice() else { panic!("one reset expected: {:?}", rep.resets) };
    assert!(r.true_contacts >= 1 && r.anchors_before >= 2, "not a wrapped tether at the bite: {r:?}");
    assert_eq!((r.cause, r.reason.as_str(), r.anchors_recovered), ("watchdog", "Reset", r.anchors_before));
    assert_went_on(&rep, r);
    // the board itself says the watchdog reset it
    let text = board.quit(core::time::Duration::from_secs(20)).unwrap_or_else(|e| panic!("{e}")).output.both();
    assert!(text.contains("board: REBOOTED by the watchdog's reset output"), "board output: {text}");
    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.faults.iter().filter(|f| f.bytes == ResetCause::Watchdog.record()).count(), 1);
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out:?}");
}

/// Paton et al.'s ledge test 3 with the operator's loop round the pole (`mission_ledge_test3_wrap.toml`, issue 24
/// item 2: "in the middle of ledge test 3, tether wrapped on the pole"): the watchdog bites in the first motion that
/// starts with the tether wrapped, which is behind the pole, where neither the lander's mast (the pole's shadow) nor
/// the rover's forward-looking sensor sees the ground under the rover again. The rebooted flight software recovers
/// the wrapped anchor history and the ground round the rover from its checkpoint (`firmware::nav::retained`), the
/// ground sends the survey and the rover's recent scans again, and the mission goes on round the pole to the next
/// waypoints; the log replays identically. Seed 1: the test needs a mission that wraps the pole before the bite
/// (it asserts so); seed 2 did until a wheel tilted against its face became a point contact, then seed 10 until the
/// navigator searched on before driving an approximate plan over observed ground (2026-12-07; `host-sim/doc/
/// mission.md`, "The Mars Yard's goal").
const LEDGE3_SEED: u64 = 1;

fn ledge3_wrap() -> (host_sim::scenario::Scenario, MissionOptions) {
    mission_setup("mission_ledge_test3_wrap.toml", LEDGE3_SEED, ResetAt::BiteWhenWrapped)
}

/// What the ledge-3 bite must show, on any link: the bite came with the true tether on the pole and the tracked
/// history wrapped, the history came back whole, and after it the rover reached another waypoint and drove on.
fn assert_ledge3_bite(rep: &host_sim::mission::run::MissionReport) {
    let [r] = rep.resets.as_slice() else { panic!("one reset expected: {:?}", rep.resets) };
    let (pole, radius) = (host_sim::world::ledge::POLE_CENTRE_XY, host_sim::world::ledge::POLE_RADIUS_M);
    let on_pole = |p: &[f64; 3]| ((p[0] - pole[0]).hypot(p[1] - pole[1]) - radius).abs() <= 0.05;
    assert!(r.anchors_before >= 2 && !r.true_contact_points.is_empty(), "not a wrapped tether at the bite: {r:?}");
    assert!(r.true_contact_points.iter().all(on_pole), "the true tether is not on the pole: {r:?}");
    assert_eq!((r.cause, r.reason.as_str(), r.anchors_recovered), ("watchdog", "Reset", r.anchors_before));
    assert!(rep.waypoints_reached > r.waypoints_before, "no waypoint reached after the bite: {r:?}");
    assert_went_on(rep, r);
}

#[test]
fn a_watchdog_bite_behind_the_ledge_pole_recovers_the_wrap_and_the_ground_and_goes_on() {
    let (sc, opts) = ledge3_wrap();
    let writer = fieldlog::Writer::new(Vec::new(), &header(&sc.name, "inproc")).unwrap();
    let mut link = RecordingLink::new(host_sim::mission::link::mission_link(&sc).unwrap(), writer);
    let rep = run_mission(&mut link, &sc, &opts).unwrap();
    let (_, bytes) = link.finish().unwrap();
    assert_ledge3_bite(&rep);
    assert!(rep.scans_resent > 0, "the ground sent none of the rover's scans again");
    let log = fieldlog::parse(&bytes).unwrap();
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out:?}");
}

/// The waypoint at which the operator ends the board's ledge-3 mission (`[mission] end_at_waypoint`): the first
/// after the bite, which comes after waypoint 2 with [`LEDGE3_SEED`] (a bite after it leaves no reset before the end,
/// and the test fails saying so). The bite and the waypoint reached after it are what the board test is about; the
/// in-process test above drives the loop's last leg too. On the 2-core host with other jobs beside it (2026-12-07)
/// the board bit 783 s into the mission, reached waypoint 3 269 s later and waypoint 4 35 s after that.
const LEDGE3_BOARD_END_WAYPOINT: u32 = 3;

/// The same bite on the emulated board: the CMSDK watchdog reboots the Cortex-M7, the `.uninit` checkpoint brings
/// the wrap and the ground back, and the board's log replays identically in-process. The operator ends the mission
/// at [`LEDGE3_BOARD_END_WAYPOINT`].
#[test]
fn a_watchdog_bite_behind_the_ledge_pole_on_the_board_recovers_and_replays_in_process() {
    let Some(elf) = host_sim::qemu::board_for_tests("ledge-3 bite on the board").unwrap_or_else(|e| panic!("{e}")) else {
        return;
    };
    let (mut sc, opts) = ledge3_wrap();
    sc.mission.end_at_waypoint = Some(LEDGE3_BOARD_END_WAYPOINT);
    let link = host_sim::link::qemu::QemuLink::start(&elf, DEFAULT_STEP_US).unwrap_or_else(|e| panic!("{e}"));
    let mut rec = RecordingLink::new(link, fieldlog::Writer::new(Vec::new(), &header(&sc.name, "qemu")).unwrap());
    let rep = run_mission(&mut rec, &sc, &opts).unwrap();
    let (board, bytes) = rec.finish().unwrap();
    assert_ledge3_bite(&rep);
    assert_eq!((rep.verdict, rep.waypoints_reached), (Verdict::Ended, LEDGE3_BOARD_END_WAYPOINT));
    let text = board.quit(core::time::Duration::from_secs(20)).unwrap_or_else(|e| panic!("{e}")).output.both();
    assert!(text.contains("board: REBOOTED by the watchdog's reset output"), "board output: {text}");
    let log = fieldlog::parse(&bytes).unwrap();
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out:?}");
}
