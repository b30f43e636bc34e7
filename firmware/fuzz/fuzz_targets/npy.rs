//! Fuzz target: the NumPy `.npy` DEM reader (`host_sim::terrain::npy::parse_npy`) with fuzzed options.
#![no_main]

use host_sim::terrain::npy::{parse_npy, FirstRow, NpyOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(([sp, s, nd], bytes)) = firmware_fuzz::split::<3>(data) else {
        return;
    };
    let opts = NpyOptions {
        spacing_m: firmware_fuzz::scale(sp),
        height_scale: firmware_fuzz::scale(s),
        nodata: (nd % 2 == 1).then(|| firmware_fuzz::scale(nd / 4)),
        first_row: if nd & 2 == 0 {
            FirstRow::North
        } else {
            FirstRow::South
        },
    };
    if let Ok(h) = parse_npy(bytes, &opts) {
        firmware_fuzz::check_heightmap(&h);
    }
});
