//! Fuzz target: the scenario loader (`host_sim::scenario::parse`, TOML), then the world spec, the map
//! configuration, and for the analytic worlds (no file to read; ledge variants and coarse DEM renderings
//! included) the world itself and the geometric checks. Worlds
//! that name a file are not built here: the fuzzer must not read whatever path it writes.
#![no_main]

use host_sim::scenario::{parse, WorldSpec};
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = core::str::from_utf8(data) else {
        return;
    };
    let Ok(sc) = parse(text, Path::new("fuzz/inline.toml")) else {
        return;
    };
    let name = sc.file_safe_name();
    assert!(
        !name.is_empty() && !name.contains('/') && name != "." && name != "..",
        "unsafe output name {name:?}"
    );
    let _ = sc.map_config();
    let Ok(spec) = sc.world_spec() else { return };
    // A DEM rendering of an analytic world reads no file either; below 0.05 m posts it is refused or costs up to
    // 16 M height samples, too slow for one fuzz input.
    let analytic = |s: &WorldSpec| matches!(s, WorldSpec::CraterWall(_) | WorldSpec::Ledge { .. });
    let buildable = match &spec {
        WorldSpec::Rendered { of, spacing_m } => analytic(of) && *spacing_m >= 0.05,
        other => analytic(other),
    };
    if buildable {
        if let Ok(world) = sc.build_world() {
            let _ = sc.check(world.as_ref());
        }
    }
});
