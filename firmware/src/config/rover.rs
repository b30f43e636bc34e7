//! Capacities and budgets for `rover` (filled in by the module that uses them).
