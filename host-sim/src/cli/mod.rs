//! CLI subcommand implementations (one module per subcommand; `main.rs` only parses and dispatches).

pub mod abit_bench;
