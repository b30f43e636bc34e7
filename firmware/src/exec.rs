//! `exec`: not yet implemented (see the issue tracker).
