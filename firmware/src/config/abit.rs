//! Capacities and budgets for `abit` (filled in by the module that uses them).
