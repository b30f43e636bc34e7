//! Capacities and budgets for `homotopy` (filled in by the module that uses them).
