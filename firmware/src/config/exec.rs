//! Capacities and budgets for `exec` (filled in by the module that uses them).
