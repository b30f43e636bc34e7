//! The in-process flight software a mission runs against: the navigator over the flight computer's pool sizes
//! (`FLIGHT_BLOCKS`, `FLIGHT_INDEX`), booted with `MapConfig::DEFAULT` like the board; the mission's `Configure`
//! carries the scenario's map configuration (`[map]`, `[budgets]`: `Scenario::map_config`; protocol v3
//! `Configure.map`), so a mission in-process and on the board (`--link qemu`) run the same navigator.

use crate::link::inproc::{FlightAutonomy, InProcLink, DEFAULT_STEP_US};
use crate::scenario::Scenario;

/// The in-process link for `sc` (executive period `DEFAULT_STEP_US`). Errors when `sc`'s map configuration is
/// invalid (the mission would send it in its `Configure`).
pub fn mission_link(sc: &Scenario) -> Result<InProcLink<FlightAutonomy>, String> {
    mission_link_with_step(sc, DEFAULT_STEP_US)
}

/// The in-process link for `sc` with executive period `step_us`.
pub fn mission_link_with_step(sc: &Scenario, step_us: u64) -> Result<InProcLink<FlightAutonomy>, String> {
    sc.map_config().map_err(|e| e.to_string())?;
    Ok(InProcLink::new(step_us))
}
