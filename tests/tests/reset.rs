//! A reset of the flight computer mid-descent (issue 24 item 2): the flight software comes back `Safe` with reason
//! `Reset`, recovers the anchor history from its retained memory (`firmware::nav::retained`), and continues when the
//! ground configures it again; the reset is in the field log and the replay resets at the same point.
//!
//! The scenario is `mission_snag.toml` (a hidden rock beside the descent line snags the tether): after 25 motions
//! the true tether touches the terrain and the flight software tracks two anchors, so a flight software that came
//! back with a straight tether would be wrong in a way the checks below see. The precondition is asserted, not
//! assumed.

use firmware::protocol::StopReason;
use host_sim::fieldlog;
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::recording::{RecordingLink, RESET_RECORD};
use host_sim::mission::run::{run_mission, MissionOptions, Verdict};
use host_sim::replay::{replay, ReplayOutcome};

const RESET_AFTER: u32 = 25;

#[test]
fn a_reset_mid_descent_recovers_the_wrapped_tether_continues_and_replays() {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/mission_snag.toml");
    let sc = host_sim::scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let opts = MissionOptions {
        seed: 1,
        tracking: firmware::protocol::Tracking::ClosedLoop,
        noiseless: false,
        live: false,
        reset_after_motions: Some(RESET_AFTER),
    };
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: 1,
        config: format!("{{\"scenario\":\"{}\",\"link\":\"inproc\",\"step_us\":{DEFAULT_STEP_US}}}", sc.name),
    };
    let writer = fieldlog::Writer::new(Vec::new(), &header).unwrap();
    let mut link = RecordingLink::new(host_sim::mission::link::mission_link(&sc).unwrap(), writer);
    let rep = run_mission(&mut link, &sc, &opts).unwrap();
    let (flight, bytes) = link.finish().unwrap();
    assert_eq!(flight.resets(), 1);

    let [r] = rep.resets.as_slice() else { panic!("one reset expected: {:?}", rep.resets) };
    assert_eq!(r.after_motions, RESET_AFTER);
    // the precondition: the tether was wrapped, by the simulator's own tether and by the flight software's
    assert!(r.true_contacts >= 1 && r.anchors_before >= 2, "not a wrapped tether at the reset: {r:?}");
    assert_eq!(r.reason, "Reset");
    assert_eq!(r.anchors_recovered, r.anchors_before, "the anchor history did not come back: {r:?}");
    // it continued: more motions after the reset, and an end that is an arrival or a safe stop with a reason
    assert!(rep.motions > RESET_AFTER, "nothing driven after the reset: {} motions", rep.motions);
    match rep.verdict {
        Verdict::Arrived => {}
        Verdict::SafeStop(reason) => assert!(
            !matches!(reason, StopReason::Reset | StopReason::TetherStateLost | StopReason::None),
            "{reason:?}"
        ),
        v => panic!("after the reset the mission ended {v:?}"),
    }

    // the log holds the reset, and a fresh flight software fed the same bytes resets there and answers the same
    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.faults.iter().filter(|f| f.bytes == RESET_RECORD).count(), 1);
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out:?}");
    // without the reset the replay cannot match: the check above can fail
    let mut no_reset = log.clone();
    no_reset.faults.clear();
    let out = replay(&no_reset, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Differs { .. }), "{out:?}");
}
