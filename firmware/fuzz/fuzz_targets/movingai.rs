//! Fuzz target: the Moving AI benchmark readers (`host_sim::movingai::parse_map`, `parse_scen`). The input is a
//! map and a scenario list separated by the first `0xFF` byte (never valid UTF-8); when both read and the map is
//! small, the scenarios are run through D* Lite as `tetherbot team movingai` does, which must not panic either.
#![no_main]

use host_sim::movingai::{parse_map, parse_scen, run_scenarios};
use libfuzzer_sys::fuzz_target;

/// Largest map (cells) and number of problems run through the planner per input, so an execution stays short.
const RUN_CELLS: usize = 4096;
const RUN_PROBLEMS: usize = 4;

fuzz_target!(|data: &[u8]| {
    let (map, scen) = match data.iter().position(|&b| b == 0xFF) {
        Some(i) => (&data[..i], &data[i + 1..]),
        None => (data, &[][..]),
    };
    let map = core::str::from_utf8(map)
        .ok()
        .and_then(|t| parse_map(t).ok());
    if let Some(m) = &map {
        assert_eq!(
            m.passable.len(),
            m.width * m.height,
            "cells do not fill the map"
        );
    }
    let Ok(scen) = core::str::from_utf8(scen) else {
        return;
    };
    let Ok(problems) = parse_scen(scen) else {
        return;
    };
    assert!(!problems.is_empty(), "an empty scenario list accepted");
    if let Some(m) = map.filter(|m| m.width * m.height <= RUN_CELLS) {
        let _ = run_scenarios(&m, &problems, |i, _| i < RUN_PROBLEMS);
    }
});
