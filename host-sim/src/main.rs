//! `tetherbot`: the operator's CLI (run a scenario, campaign, record, replay, export, render).

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "tetherbot", version, about = "Simulator and operator's tool for tethered extreme-terrain rovers")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build the onboard map from a scan sequence and print its ESDF error against ground truth, timing, memory.
    MapCheck(host_sim::cli::map::MapCheckArgs),
    /// Render the onboard map built from a scan sequence as a PNG (top view or vertical slice).
    RenderMap(host_sim::cli::map::RenderMapArgs),
    /// Time a full distance transform: the onboard ESDF vs libdynamicedt3d on the same grid.
    EdtBench(host_sim::cli::map::EdtBenchArgs),
}

fn main() {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::MapCheck(a) => host_sim::cli::map::map_check(&a),
        Command::RenderMap(a) => host_sim::cli::map::render_map(&a),
        Command::EdtBench(a) => host_sim::cli::map::edt_bench(&a),
    };
    if let Err(e) = result {
        eprintln!("tetherbot: {e}");
        std::process::exit(1);
    }
}
