//! `plan::abit`: not yet implemented (see the issue tracker).
