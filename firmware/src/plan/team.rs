//! `plan::team`: not yet implemented (see the issue tracker).
