//! Fuzz target: the Esri ASCII grid reader (`host_sim::terrain::asc::parse_asc`) with a fuzzed height scale.
#![no_main]

use host_sim::terrain::asc::parse_asc;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(([s], text)) = firmware_fuzz::split::<1>(data) else {
        return;
    };
    let Ok(text) = core::str::from_utf8(text) else {
        return;
    };
    if let Ok(h) = parse_asc(text, firmware_fuzz::scale(s)) {
        firmware_fuzz::check_heightmap(&h);
    }
});
