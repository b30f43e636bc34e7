//! Fuzz target: arbitrary bytes, in arbitrary splits, into the deframer and the decoder; and the scan reassembler
//! fed with whatever chunks decode. Must never panic; whatever decodes must re-encode and decode to itself.
#![no_main]

use firmware::config::protocol::MAX_ENCODED_FRAME_LEN;
use firmware::protocol::{decode_frame, encode, Deframer, Message, Point3, ScanAssembler};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    // first byte chooses the split size, so byte-wise and bulk feeding are both exercised
    let Some((&split, bytes)) = data.split_first() else {
        return;
    };
    let step = usize::from(split % 64) + 1;
    let mut d = Deframer::new();
    let mut asm = ScanAssembler::new();
    // a small reassembly buffer (not the flight capacity) keeps executions fast and reaches ScanOverflow
    let mut points = [Point3::default(); 512];
    for piece in bytes.chunks(step) {
        let mut rest = piece;
        while !rest.is_empty() {
            let (n, ev) = d.push(rest);
            assert!(n >= 1 && n <= rest.len());
            if let Some(Ok(frame)) = ev {
                if let Ok((h, m)) = decode_frame(frame) {
                    let mut buf = [0u8; MAX_ENCODED_FRAME_LEN];
                    let len = encode(h.seq, &m, &mut buf).expect("a decoded message re-encodes");
                    let mut d2 = Deframer::new();
                    let (_, ev2) = d2.push(&buf[..len]);
                    let (_, m2) =
                        decode_frame(ev2.expect("one frame").expect("valid")).expect("decodes");
                    assert_eq!(m2, m);
                    if let Message::SensorChunk(c) = &m {
                        let _ = asm.accept(c, &mut points);
                    }
                }
            }
            rest = &rest[n..];
        }
    }
});
