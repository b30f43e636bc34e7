//! Subcommand implementations of the `tetherbot` CLI, one module per area (main.rs only parses and dispatches).

pub mod team;
