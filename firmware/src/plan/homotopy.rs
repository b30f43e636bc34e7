//! `plan::homotopy`: not yet implemented (see the issue tracker).
