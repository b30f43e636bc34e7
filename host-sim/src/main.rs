//! `tetherbot`: the operator's CLI (run a scenario, campaign, record, replay, export, render).

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "tetherbot", about = "Tethered extreme-terrain rover navigation: simulator and operator's tool")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// ABIT* side by side with OMPL 1.5.2's ABIT* on the shared geometric problems.
    AbitBench(host_sim::cli::abit_bench::Args),
}

fn main() {
    let code = match Cli::parse().command {
        Command::AbitBench(a) => report(host_sim::cli::abit_bench::run(&a)),
    };
    std::process::exit(code);
}

fn report(r: Result<String, String>) -> i32 {
    match r {
        Ok(text) => {
            print!("{text}");
            0
        }
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
