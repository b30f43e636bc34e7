//! Subcommand implementations of the `tetherbot` CLI, one module per area.

pub mod map;
