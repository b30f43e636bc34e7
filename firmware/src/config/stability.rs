//! Capacities and budgets for `stability` (filled in by the module that uses them).
