//! Where a tether-aware search spends its time, phase by phase (issue 22, goal 1: "per-phase counters on the
//! board"). The caller lends a [`PhaseClock`] ([`super::TetherSpace::with_phase_clock`]); the space then adds
//! the clock's ticks spent in each of its three expensive leaves to [`PhaseTicks`]:
//!
//! | phase | what is timed | paper |
//! |---|---|---|
//! | `settle` | [`super::TetherSpace::settle_state`]: the settler (wheel rims, footprint, body collision) | Paton et al. IV-B |
//! | `stability` | [`super::TetherSpace::stable_with`] / `stable_enough`: building and solving the margin LPs | Paton et al. IV-C |
//! | `anchors` | [`super::TetherSpace::predict`]: anchor prediction (Alg. 1) with its tether sweeps | Paton et al. IV-A |
//!
//! The distance-field queries inside them are timed by the caller's own field wrapper if it wants them (the
//! board's bench does); what is left of the search's total is ABIT*'s own work (sampling, queues, graph).
//! Without a clock (flight, every planner call in `nav`) nothing is read and the counts stay 0: the clock is
//! for benchmarks, which lend the board's SysTick under `-icount shift=0` (one tick, 40 instructions).

/// A monotonic tick counter lent by a benchmark.
pub trait PhaseClock {
    /// Ticks since an arbitrary origin; never decreases.
    fn ticks(&self) -> u64;
}

/// Clock ticks spent in each phase (see the module table), summed over the space's life.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PhaseTicks {
    /// Settling states.
    pub settle: u64,
    /// Stability checks (margin LPs).
    pub stability: u64,
    /// Anchor prediction.
    pub anchors: u64,
}

/// The phases [`PhaseTicks`] counts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Phase {
    Settle,
    Stability,
    Anchors,
}

impl PhaseTicks {
    pub(super) fn add(&mut self, phase: Phase, ticks: u64) {
        let slot = match phase {
            Phase::Settle => &mut self.settle,
            Phase::Stability => &mut self.stability,
            Phase::Anchors => &mut self.anchors,
        };
        *slot = slot.saturating_add(ticks);
    }
}
