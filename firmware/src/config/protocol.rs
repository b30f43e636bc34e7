//! Capacities and budgets for `protocol` (filled in by the module that uses them).
