//! Fuzz target: the GeoTIFF DEM reader (`host_sim::terrain::geotiff::read_geotiff`, over the `tiff` crate) with
//! fuzzed options (height scale, spacing, no-data value).
#![no_main]

use host_sim::terrain::geotiff::{read_geotiff, GeoTiffOptions};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(([s, sp, nd], tiff)) = firmware_fuzz::split::<3>(data) else {
        return;
    };
    let opts = GeoTiffOptions {
        height_scale: firmware_fuzz::scale(s),
        // even selectors leave the spacing to ModelPixelScaleTag and the no-data value to GDAL_NODATA
        spacing_m: (sp % 2 == 1).then(|| firmware_fuzz::scale(sp / 2)),
        nodata: (nd % 2 == 1).then(|| firmware_fuzz::scale(nd / 2)),
    };
    if let Ok(h) = read_geotiff(std::io::Cursor::new(tiff), &opts) {
        firmware_fuzz::check_heightmap(&h);
    }
});
