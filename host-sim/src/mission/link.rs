//! The in-process flight software a mission runs against: the navigator over the flight computer's pool sizes
//! (`FLIGHT_BLOCKS`, `FLIGHT_INDEX`), with the scenario's map configuration (`[map]`, `[budgets]`:
//! `Scenario::map_config`). The board (`--link qemu`) always runs `MapConfig::DEFAULT`; a mission on it is the same
//! as in-process only for a scenario whose map configuration is the default ([`board_equivalent`]).

use firmware::config::map::{MapConfig, FLIGHT_BLOCKS, FLIGHT_INDEX};
use firmware::map::Block;
use firmware::nav::{NavPlanStorage, Navigator};

use crate::link::inproc::{FlightAutonomy, InProcLink, DEFAULT_STEP_US};
use crate::scenario::Scenario;

/// The in-process link for `sc` (executive period `DEFAULT_STEP_US`).
pub fn mission_link(sc: &Scenario) -> Result<InProcLink<FlightAutonomy>, String> {
    mission_link_with_step(sc, DEFAULT_STEP_US)
}

/// The in-process link for `sc` with executive period `step_us`.
pub fn mission_link_with_step(sc: &Scenario, step_us: u64) -> Result<InProcLink<FlightAutonomy>, String> {
    inproc_with_map(sc.map_config().map_err(|e| e.to_string())?, step_us)
}

/// True when `sc`'s map configuration is the board's (`MapConfig::DEFAULT`).
pub fn board_equivalent(sc: &Scenario) -> bool {
    sc.map_config().is_ok_and(|c| c == MapConfig::DEFAULT)
}

/// An in-process link whose navigator runs `cfg` (replay of a mission log).
pub fn inproc_with_map(cfg: MapConfig, step_us: u64) -> Result<InProcLink<FlightAutonomy>, String> {
    let planning: Box<NavPlanStorage> = Box::default();
    let nav = Navigator::new(cfg, vec![Block::EMPTY; FLIGHT_BLOCKS], vec![0u32; FLIGHT_INDEX], planning)
        .map_err(|e| format!("the navigator refused the map configuration: {e:?}"))?;
    Ok(InProcLink::with_autonomy(nav, step_us))
}
