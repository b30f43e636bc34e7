//! Capacities and budgets for `team` (filled in by the module that uses them).
