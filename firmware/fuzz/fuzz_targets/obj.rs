//! Fuzz target: the Wavefront OBJ reader (`host_sim::terrain::obj::parse_obj`) with a fuzzed scale. An accepted
//! mesh has triangles, finite vertices, and every triangle's indices inside the vertex list.
#![no_main]

use host_sim::terrain::obj::{parse_obj, ObjOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(([s], text)) = firmware_fuzz::split::<1>(data) else {
        return;
    };
    let Ok(text) = core::str::from_utf8(text) else {
        return;
    };
    if let Ok(m) = parse_obj(
        text,
        &ObjOptions {
            scale: firmware_fuzz::scale(s),
        },
    ) {
        assert!(!m.triangles.is_empty(), "a mesh without triangles accepted");
        assert!(
            m.vertices.iter().flatten().all(|c| c.is_finite()),
            "non-finite vertex accepted"
        );
        for t in 0..m.triangles.len() {
            assert!(
                m.triangle(t).is_some(),
                "triangle {t} indexes outside the vertex list"
            );
        }
    }
});
