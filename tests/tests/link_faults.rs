//! Seeded link faults (issue 24, item 1) over the in-process link: every fault kind is accounted for by the flight
//! software's telemetry (injected = detected + harmless), no damaged frame is acknowledged, the host's
//! retransmission gets state-changing frames through, and a faulty run's field log holds the faults and replays
//! byte for byte.

use firmware::protocol::{self, Configure, Deframer, GoalCancel, Message, TetherReading, TimeTick};
use host_sim::fieldlog::{self, Completeness, Direction};
use host_sim::link::faults::{FaultAccount, FaultEvent, FaultKind, FaultLink, FaultProfile, LinkDirection};
use host_sim::link::inproc::{InProcLink, DEFAULT_STEP_US};
use host_sim::link::recording::RecordingLink;
use host_sim::mission::run::{run_mission, MissionOptions, MissionReport, Verdict};
use host_sim::link::FlightLink;
use host_sim::replay::{replay, ReplayOutcome};
use host_sim::session::{DownlinkCounts, HostSession, RetransmitPolicy};

type Faulty = FaultLink<RecordingLink<InProcLink, Vec<u8>>>;

fn configure() -> Configure {
    host_sim::scripted::default_configure(5)
}

/// A short conversation over `link`: `Configure`, then rounds of a time tick, a tether reading and a goal cancel
/// (refused: no goal), with link time running between rounds; faults end, then the closing telemetry.
fn converse(link: &mut Faulty, rounds: u32) -> (bool, u64, DownlinkCounts) {
    let mut s = HostSession::new(link);
    s.retransmit = Some(RetransmitPolicy::default());
    s.recv().unwrap();
    s.send(&Message::Configure(configure())).unwrap();
    s.recv().unwrap();
    for i in 0..rounds {
        let t = s.link().now_us();
        s.send(&Message::TimeTick(TimeTick { host_time_us: t }))
            .unwrap();
        s.send(&Message::TetherReading(TetherReading {
            time_us: t,
            payout_m: 1.0,
            tension_n: 50.0,
            boom_angle_rad: 0.0,
        }))
        .unwrap();
        s.send(&Message::GoalCancel(GoalCancel { goal_id: i }))
            .unwrap();
        s.advance_to(t + 50_000).unwrap();
    }
    s.advance_to(s.link().now_us() + 2_000_000).unwrap();
    s.link_mut().end_faults().unwrap();
    s.recv().unwrap();
    let t = s.telemetry().unwrap();
    (t.configured, s.retransmitted, s.downlink)
}

fn faulty(profile: FaultProfile) -> Faulty {
    let header = fieldlog::Header {
        protocol_version: firmware::config::protocol::PROTOCOL_VERSION,
        created_at_unix_ms: 0,
        seed: profile.seed,
        config: format!(
            "{{\"scenario\":\"faults\",\"link\":\"inproc\",\"step_us\":{DEFAULT_STEP_US}}}"
        ),
    };
    let writer = fieldlog::Writer::new(Vec::new(), &header).unwrap();
    FaultLink::new(
        RecordingLink::new(InProcLink::new(DEFAULT_STEP_US), writer),
        profile,
    )
}

/// Runs the conversation under `profile`; the accounting and the log bytes.
fn run(profile: FaultProfile, rounds: u32) -> (FaultAccount, Vec<u8>, bool, u64) {
    let mut link = faulty(profile);
    let (configured, retransmitted, down) = converse(&mut link, rounds);
    let acc = link.account().with_host(down, &[]);
    let (_, bytes) = link.into_inner().finish().unwrap();
    (acc, bytes, configured, retransmitted)
}

#[test]
fn every_fault_kind_is_accounted_for_by_the_flight_telemetry() {
    for kind in FaultKind::ALL {
        let (acc, _, configured, retransmitted) = run(FaultProfile::single(kind, 3e-3, 11), 150);
        let injected = acc.injected(kind);
        assert!(injected >= 5, "{kind:?}: only {injected} faults injected");
        let t = acc.telemetry.expect("closing telemetry");
        let detected = kind.group().detected(&t);
        println!(
            "{kind:?}: injected {injected}, detected {detected}, harmless {}, retransmitted {retransmitted}",
            acc.harmless(kind)
        );
        assert_eq!(acc.check(), Ok(()), "{kind:?}");
        assert_eq!(injected, detected + acc.harmless(kind), "{kind:?}");
        match kind {
            // a lost or damaged frame is never harmless, and the configuration got through by retransmission
            FaultKind::BitFlip | FaultKind::Drop | FaultKind::Truncate => {
                assert_eq!(acc.harmless(kind), 0, "{kind:?}");
                assert!(retransmitted > 0, "{kind:?}: nothing retransmitted");
            }
            FaultKind::Duplicate => assert_eq!(detected, injected),
            // a stall keeps the order: nothing late
            FaultKind::Stall => assert_eq!(detected, 0),
            FaultKind::Reorder | FaultKind::Delay => {
                assert!(detected > 0, "{kind:?}: no late frame")
            }
        }
        assert!(configured, "{kind:?}: the configuration never got through");
        assert_eq!(acc.acked_damaged, 0);
    }
    // every kind at once: the groups still balance
    let acc = every_kind_at_once("all=5e-4,seed=3");
    assert!(FaultKind::ALL.iter().map(|&k| acc.injected(k)).sum::<u64>() > 10);
}

/// The conversation under `profile` (every kind at once): the accounting balances and the configuration gets
/// through.
fn every_kind_at_once(profile: &str) -> FaultAccount {
    let (acc, _, configured, _) = run(FaultProfile::parse(profile).unwrap(), 150);
    assert_eq!(acc.check(), Ok(()), "{profile}");
    assert!(configured, "{profile}");
    acc
}

#[test]
fn a_faulty_run_records_its_faults_and_replays_byte_for_byte() {
    let profile = FaultProfile::parse("bitflip=1e-3,drop=1e-3,duplicate=1e-3,reorder=1e-3,truncate=1e-3,delay=1e-3,stall=1e-3,seed=9").unwrap();
    let (acc, bytes, _, _) = run(profile.clone(), 120);
    let (_, again, _, _) = run(profile.clone(), 120);
    assert_eq!(bytes, again, "the same seed gives the same faulty log");
    let (_, other, _, _) = run(
        FaultProfile {
            seed: 10,
            ..profile
        },
        120,
    );
    assert_ne!(bytes, other, "the seed reaches the faults");

    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.completeness(), Completeness::Complete);
    // every injected fault is in the log, readable, in time order
    let events: Vec<FaultEvent> = log
        .faults
        .iter()
        .map(|f| FaultEvent::from_bytes(f.t_us, &f.bytes).expect("a fault record"))
        .collect();
    let injected: u64 = FaultKind::ALL.iter().map(|&k| acc.injected(k)).sum();
    assert_eq!(events.len() as u64, injected);
    assert!(events.windows(2).all(|w| w[0].t_us <= w[1].t_us));
    // the log holds the bytes the flight software received: damaged frames among them
    let mut d = Deframer::new();
    let mut undecodable = 0;
    for r in log
        .records
        .iter()
        .filter(|r| r.direction == Direction::HostToFlight)
    {
        let mut rest = &r.bytes[..];
        while !rest.is_empty() {
            let (n, ev) = d.push(rest);
            rest = &rest[n.max(1).min(rest.len())..];
            if let Some(ev) = ev {
                if ev
                    .map_err(protocol::NackReason::from)
                    .and_then(protocol::decode_frame)
                    .is_err()
                {
                    undecodable += 1;
                }
            }
        }
    }
    assert!(undecodable > 0, "no damaged frame in the log");
    // and a fresh flight software fed them answers byte for byte as the faulty run's did
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out}");
}

#[test]
fn fault_profiles_parse_and_bad_ones_say_why() {
    let p = FaultProfile::parse("bitflip=1e-4, stall=2e-5,stall_us=300000,seed=4").unwrap();
    assert_eq!(
        (
            p.rate(FaultKind::BitFlip),
            p.rate(FaultKind::Stall),
            p.stall_us,
            p.seed
        ),
        (1e-4, 2e-5, 300_000, 4)
    );
    assert_eq!(p.rate(FaultKind::Drop), 0.0);
    assert_eq!(
        FaultProfile::parse(&p.to_string()).unwrap(),
        p,
        "Display gives a profile that parses back"
    );
    assert!(!FaultProfile::parse("none").unwrap().any());
    for (bad, says) in [
        ("flip=1e-3", "unknown key `flip`"),
        ("drop=2", "must be in [0, 1]"),
        ("drop=-1e-3", "must be in [0, 1]"),
        ("drop=NaN", "must be in [0, 1]"),
        ("drop", "not KEY=VALUE"),
        ("delay_us=-5", "delay_us=-5"),
    ] {
        let e = FaultProfile::parse(bad).expect_err(bad);
        assert!(e.contains(says), "{bad}: {e}");
    }
}

/// A whole closed-loop mission (the fault campaign's short crater-wall descent) with every fault kind on the uplink
/// at 1e-4 per byte: about one scan-chunk frame in seven is lost, damaged, duplicated, reordered, delayed or stalled.
/// The host resends what got no answer (a scan's chunks one by one), so the mission arrives; every fault is
/// accounted for and no damaged frame was acknowledged. Before scan chunks could arrive in any order, the first lost
/// chunk lost its whole scan and such a mission stopped at once, its goal refused for want of a pose.
#[test]
fn a_mission_through_every_fault_kind_arrives_and_accounts_for_each_fault() {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/mission_faults.toml");
    let sc = host_sim::scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let opts = MissionOptions { seed: 11, tracking: firmware::protocol::Tracking::ClosedLoop, noiseless: false, live: false, reset: None };
    let profile = FaultProfile::parse("all=1e-4,seed=12").unwrap();
    let mut link = FaultLink::new(host_sim::mission::link::mission_link(&sc).unwrap(), profile);
    let rep = run_mission(&mut link, &sc, &opts).unwrap();
    let acc = link.account();
    assert_eq!(acc.check(), Ok(()));
    assert_eq!(acc.acked_damaged, 0);
    let lossy = [FaultKind::BitFlip, FaultKind::Drop, FaultKind::Truncate];
    assert!(lossy.iter().map(|&k| acc.injected(k)).sum::<u64>() > 20, "{acc:?}");
    assert!(rep.chunks_resent > 0, "no scan chunk was sent again");
    assert_eq!(rep.verdict, Verdict::Arrived, "{:?}", rep.verdict);
}

/// Downlink faults (flight -> host): every kind is accounted for by the host's own counters (its deframer and CRC
/// check and the flight software's sequence numbers: injected = detected + harmless), the conversation survives
/// (a lost `Ack` makes the host resend, and the flight software answers the resend without acting again), and the
/// flight software never saw a damaged frame (the uplink is clean).
#[test]
fn every_downlink_fault_kind_is_accounted_for_by_the_host() {
    for kind in FaultKind::ALL {
        let profile = FaultProfile::parse(&format!("down.{}=3e-3,seed=11", kind.name())).unwrap();
        let (acc, _, configured, retransmitted) = run(profile, 150);
        let injected = acc.down_injected(kind);
        assert!(injected >= 5, "{kind:?}: only {injected} downlink faults injected");
        assert_eq!(acc.injected(kind), 0, "{kind:?}: the uplink was faulted");
        let host = acc.host.expect("host counts");
        let detected = kind.group().detected_down(&host);
        println!(
            "{kind:?}: injected {injected}, detected {detected}, harmless {}, retransmitted {retransmitted}, host {host:?}",
            acc.down_harmless(kind)
        );
        assert_eq!(acc.check(), Ok(()), "{kind:?}");
        match kind {
            FaultKind::BitFlip | FaultKind::Truncate => {
                assert_eq!(acc.down_harmless(kind), 0);
                assert!(host.damaged > 0, "{kind:?}: no damaged frame seen");
            }
            FaultKind::Drop => assert_eq!(acc.down_harmless(kind), 0),
            FaultKind::Duplicate => assert_eq!(host.duplicates, injected),
            FaultKind::Stall => assert_eq!(detected, 0),
            FaultKind::Reorder | FaultKind::Delay => assert!(detected > 0, "{kind:?}: no late frame"),
        }
        assert!(configured, "{kind:?}: the configuration never got through");
        let t = acc.telemetry.expect("closing telemetry");
        // a clean uplink: the flight software saw no gap, no duplicate; a lost Ack's resend was answered, not
        // applied again
        assert_eq!((t.seq_gaps, t.seq_late), (0, 0), "{kind:?}");
        if matches!(kind, FaultKind::Drop | FaultKind::BitFlip | FaultKind::Truncate) && retransmitted > 0 {
            println!("  requests repeated {}", t.requests_repeated);
        }
    }
    // both directions at once, every kind: each side balances
    let acc = every_kind_at_once("all=5e-4,down.all=5e-4,seed=3");
    assert!(FaultKind::ALL.iter().map(|&k| acc.down_injected(k)).sum::<u64>() > 10);
}

/// Profiles name the downlink with `down.`; the old keys still mean the uplink, and adding downlink faults leaves
/// a seed's uplink faults as they were.
#[test]
fn downlink_profiles_parse_and_leave_the_uplink_faults_alone() {
    let p = FaultProfile::parse("drop=1e-4,down.drop=2e-4,down.all=1e-5,seed=4").unwrap();
    assert_eq!((p.rate(FaultKind::Drop), p.down_rate(FaultKind::Drop), p.down_rate(FaultKind::Stall)), (1e-4, 1e-5, 1e-5));
    let p = FaultProfile::parse("down.drop=2e-4,seed=4").unwrap();
    assert_eq!((p.rate(FaultKind::Drop), p.down_rate(FaultKind::Drop)), (0.0, 2e-4));
    assert_eq!(FaultProfile::parse(&p.to_string()).unwrap(), p);
    let e = FaultProfile::parse("down.flip=1e-3").unwrap_err();
    assert!(e.contains("unknown key `down.flip`"), "{e}");
    assert!(FaultProfile::parse("down.drop=2").unwrap_err().contains("must be in [0, 1]"));
    let up = |profile: &str| {
        let (acc, _, _, _) = run(FaultProfile::parse(profile).unwrap(), 60);
        acc.injected
    };
    assert_eq!(up("drop=3e-3,seed=5"), up("drop=3e-3,down.all=3e-3,seed=5"));
    // a format-3 fault record (no direction byte) reads as an uplink fault; a format-4 one keeps its direction
    let ev = FaultEvent { t_us: 5, direction: LinkDirection::Down, kind: FaultKind::Delay, frame: 3, seq: 9, frame_len: 20, detail: 7 };
    let b = ev.to_bytes();
    assert_eq!(FaultEvent::from_bytes(5, &b), Some(ev));
    assert_eq!(FaultEvent::from_bytes(5, &b[..b.len() - 1]), Some(FaultEvent { direction: LinkDirection::Up, ..ev }));
    let mut bad = b.clone();
    *bad.last_mut().unwrap() = 2;
    assert_eq!(FaultEvent::from_bytes(5, &bad), None);
}

/// A whole closed-loop mission with every fault kind on the DOWNLINK at 1e-4 per byte (and the uplink clean): lost
/// `Ack`s make the host resend goals, configurations and reports the flight software already took, lost or late
/// drive commands are sent again by the flight software. The mission arrives; no motion is executed twice (the
/// flight software accepted exactly one report per motion the rover made, and took exactly one goal); no drive
/// command came from a damaged frame; every downlink fault is accounted for by the host's counters; and the field
/// log (recorded inside the injector) replays byte for byte.
#[test]
fn a_mission_through_downlink_faults_arrives_executes_no_motion_twice_and_replays() {
    let (rep, acc, bytes) = faulty_mission(11, "down.all=1e-4,seed=21");
    println!("{:?}: {} motions, {} commands repeated, host {:?}, downlink injected {:?}", rep.verdict, rep.motions, rep.commands_repeated, rep.downlink, acc.down_injected);
    assert_eq!(acc.check(), Ok(()));
    assert_eq!(acc.executed_damaged, 0);
    let lossy = [FaultKind::BitFlip, FaultKind::Drop, FaultKind::Truncate];
    assert!(lossy.iter().map(|&k| acc.down_injected(k)).sum::<u64>() > 5, "{acc:?}");
    assert_eq!(rep.verdict, Verdict::Arrived, "{:?}", rep.verdict);
    let t = acc.telemetry.expect("closing telemetry");
    assert_eq!(t.motion_reports, rep.motions, "a motion executed twice (or a report lost)");
    assert_eq!(t.goals_received, 1, "the goal was applied again");
    let log = fieldlog::parse(&bytes).unwrap();
    assert_eq!(log.completeness(), Completeness::Complete);
    let down_records = log
        .faults
        .iter()
        .filter_map(|f| FaultEvent::from_bytes(f.t_us, &f.bytes))
        .filter(|e| e.direction == LinkDirection::Down)
        .count() as u64;
    assert_eq!(down_records, acc.down_injected.iter().sum::<u64>());
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out}");
}

/// A lossy downlink (bit flips, drops and truncations at 1e-2 per byte each: about one `DriveCommand` in three and
/// a sixth of the `Ack`s lost): the flight software sends drive commands again when their reports are late, the
/// host resends what got no answer and the flight software answers a request it already took without taking it
/// again. The mission arrives, one accepted report per motion the rover made (no motion twice), one goal taken, no
/// drive command from a damaged frame, the host's counts balance the injected faults, and the log replays.
#[test]
fn a_mission_through_a_lossy_downlink_recovers_lost_commands_and_answers() {
    let (rep, acc, bytes) = faulty_mission(5, "down.bitflip=1e-2,down.drop=1e-2,down.truncate=1e-2,seed=3");
    let t = acc.telemetry.expect("closing telemetry");
    println!(
        "{:?}: {} motions, retransmits {}, host {:?}, flight: requests repeated {}, drive resends {}",
        rep.verdict, rep.motions, rep.retransmits, rep.downlink, t.requests_repeated, t.drive_resends
    );
    assert_eq!(acc.check(), Ok(()));
    assert_eq!(rep.verdict, Verdict::Arrived, "{:?}", rep.verdict);
    assert!(t.drive_resends > 0, "no drive command was lost: the test exercises nothing");
    assert_eq!(t.motion_reports, rep.motions, "a motion executed twice (or a report lost)");
    assert_eq!(t.goals_received, 1, "the goal was applied again");
    assert_eq!(t.motion_report_timeouts, 0);
    let log = fieldlog::parse(&bytes).unwrap();
    let out = replay(&log, &mut InProcLink::new(DEFAULT_STEP_US)).unwrap();
    assert!(matches!(out, ReplayOutcome::Identical { .. }), "{out}");
}

/// The fault campaign's mission (the crater-wall descent) with mission seed `seed` over `profile`, recorded inside
/// the injector: its report, the accounting with the host's side added, and the field log.
fn faulty_mission(seed: u64, profile: &str) -> (MissionReport, FaultAccount, Vec<u8>) {
    let p = std::path::PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../host-sim/scenarios/mission_faults.toml");
    let sc = host_sim::scenario::load(&p).unwrap_or_else(|e| panic!("{e}"));
    let opts = MissionOptions { seed, tracking: firmware::protocol::Tracking::ClosedLoop, noiseless: false, live: false, reset: None };
    let mut link = faulty(FaultProfile::parse(profile).unwrap());
    let rep = run_mission(&mut link, &sc, &opts).unwrap();
    let acc = link.account().with_host(rep.downlink, &rep.command_seqs);
    let (_, bytes) = link.into_inner().finish().unwrap();
    (rep, acc, bytes)
}
