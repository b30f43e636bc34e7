//! Generates the fuzz seed corpus (`firmware/fuzz/gen_corpus.sh` runs this with `--ignored`): one wire frame of
//! every message kind, and damaged variants. Also checks, in the normal run, that every seed deframes and decodes.

use firmware::config::protocol::MAX_ENCODED_FRAME_LEN;
use firmware::protocol::*;
use host_sim::scripted::{default_configure, synthetic_scan};

fn seeds() -> Vec<(String, Vec<u8>)> {
    let mut rng = rand_pcg::Pcg64Mcg::new(1);
    let scan = synthetic_scan(1, 200, &mut rng);
    let msgs = vec![
        Message::TimeTick(TimeTick { host_time_us: 1000 }),
        Message::SensorChunk(scan[0].clone()),
        Message::TetherReading(TetherReading {
            time_us: 5,
            payout_m: 1.0,
            tension_n: 2.0,
            boom_angle_rad: 0.1,
        }),
        Message::GoalRequest(GoalRequest {
            goal_id: 1,
            position: Point3::new(1.0, 2.0, 3.0),
            tolerance_m: 0.5,
            planner: PlannerChoice::Abit,
            max_iterations: 10,
            time_budget_ms: 0,
            allow_approximate: false,
        }),
        Message::Configure(default_configure(1)),
        Message::Shutdown(Shutdown),
        Message::TelemetryRequest(TelemetryRequest),
        Message::Ack(Ack { seq: 1 }),
        Message::Nack(Nack {
            seq: 2,
            reason: NackReason::BadCrc,
        }),
        Message::PlanStatus(PlanStatus {
            goal_id: 1,
            state: PlanState::Searching,
            iterations: 3,
            best_cost: Some(1.5),
        }),
        Message::Plan(Plan {
            goal_id: 1,
            part: 0,
            parts: 1,
            waypoints: heapless::Vec::new(),
        }),
        Message::DriveCommand(DriveCommand {
            command_id: 1,
            motion: Motion::Straight { distance_m: 0.5 },
        }),
        Message::Log(Log {
            level: LogLevel::Info,
            text: heapless::String::try_from("hello").unwrap(),
        }),
    ];
    let mut out = Vec::new();
    for (i, m) in msgs.iter().enumerate() {
        let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
        let n = encode(i as u32, m, &mut buf).unwrap();
        buf.truncate(n);
        // the first byte of a fuzz input picks the split size
        let mut input = vec![7u8];
        input.extend_from_slice(&buf);
        out.push((format!("{:?}", m.kind()), input.clone()));
        let mut damaged = input.clone();
        let mid = damaged.len() / 2;
        damaged[mid] ^= 0x10;
        out.push((format!("{:?}-flipped", m.kind()), damaged));
    }
    out
}

#[test]
fn every_valid_seed_decodes() {
    for (name, input) in seeds().iter().filter(|(n, _)| !n.ends_with("flipped")) {
        let mut d = Deframer::new();
        let (_, ev) = d.push(&input[1..]);
        let frame = ev.unwrap().unwrap();
        assert!(decode_frame(frame).is_ok(), "{name}");
    }
}

#[test]
#[ignore = "writes files; run by firmware/fuzz/gen_corpus.sh"]
fn write_fuzz_corpus() {
    let dir = std::env::var("FUZZ_CORPUS_DIR").expect("FUZZ_CORPUS_DIR");
    std::fs::create_dir_all(&dir).unwrap();
    for (name, bytes) in seeds() {
        std::fs::write(format!("{dir}/{name}"), bytes).unwrap();
    }
    println!("wrote {} seeds to {dir}", seeds().len());
}
