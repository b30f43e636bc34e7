//! Capacities and budgets for `map` (filled in by the module that uses them).
