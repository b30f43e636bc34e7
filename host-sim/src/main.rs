//! `tetherbot`: the operator's CLI (run a scenario, campaign, record, replay, export, render).

use clap::{Parser, Subcommand};
use host_sim::cli;
use std::process::ExitCode;

#[derive(Parser)]
#[command(name = "tetherbot", about = "Simulator and operator's tool for tethered extreme-terrain rovers")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run every Moving AI scenario of a .map/.scen pair through the team's global planner (D* Lite).
    Movingai(cli::team::MovingaiArgs),
    /// Simulate the four-robot climbing team on real terrain (HiRISE cliff, Itokawa) and draw it.
    Team(cli::team::TeamArgs),
}

fn main() -> ExitCode {
    let result = match Cli::parse().command {
        Command::Movingai(a) => cli::team::movingai(&a),
        Command::Team(a) => cli::team::team(&a),
    };
    match result {
        Ok(true) => ExitCode::SUCCESS,
        Ok(false) => ExitCode::FAILURE,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::from(2)
        }
    }
}
