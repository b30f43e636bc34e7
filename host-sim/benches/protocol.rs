//! Frame encode and decode throughput: a small message (`Ack`) and a full sensor chunk (128 points).
//! One iteration = one frame, so frames/s = 1 / time; MB/s is criterion's byte throughput over wire bytes.
//!
//!     cargo bench -p host-sim --bench protocol

use core::hint::black_box;
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use firmware::config::protocol::{MAX_ENCODED_FRAME_LEN, MAX_POINTS_PER_CHUNK};
use firmware::protocol::*;

fn full_chunk() -> Message {
    let mut points = heapless::Vec::new();
    for i in 0..MAX_POINTS_PER_CHUNK {
        let _ = points.push(Point3::new(1.0 + i as f32 * 0.01, -0.5 * i as f32, 0.25));
    }
    Message::SensorChunk(SensorChunk {
        scan_id: 1,
        chunk_index: 0,
        chunk_count: 8,
        sensor_pose: Pose::IDENTITY,
        points,
    })
}

fn bench(c: &mut Criterion) {
    let cases = [
        ("ack", Message::Ack(Ack { seq: 123_456 })),
        ("sensor_chunk_128", full_chunk()),
    ];
    let mut g = c.benchmark_group("protocol");
    for (name, msg) in &cases {
        let mut buf = vec![0u8; MAX_ENCODED_FRAME_LEN];
        let n = encode(7, msg, &mut buf).unwrap();
        let wire = buf[..n].to_vec();
        g.throughput(Throughput::Bytes(n as u64));
        g.bench_function(format!("encode/{name}"), |b| {
            let mut out = vec![0u8; MAX_ENCODED_FRAME_LEN];
            b.iter(|| encode(black_box(7), black_box(msg), &mut out).unwrap())
        });
        g.bench_function(format!("deframe_decode/{name}"), |b| {
            let mut d = Deframer::new();
            b.iter(|| {
                let (_, ev) = d.push(black_box(&wire));
                let frame = ev.unwrap().unwrap();
                decode_frame(frame).unwrap()
            })
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
