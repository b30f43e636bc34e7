//! `tetherbot`: the operator's CLI (run a scenario, campaign, record, replay, export, render).
//!
//! Subcommand logic lives in `host_sim::cli::<name>`; this file only parses and dispatches.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use host_sim::cli;

/// Onboard navigation for tethered extreme-terrain rovers: simulator and operator's tool.
#[derive(Parser)]
#[command(name = "tetherbot", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// A closed-loop mission with the flight software in the loop (the main job; default: a crater-wall descent).
    Mission(cli::mission::MissionCli),
    /// A long mission with the host's sequence numbers crossing 2^32, judged for lost frames, counters, high water.
    Soak(cli::soak::SoakArgs),
    /// Run a scenario against the flight software on the in-process link (the main job).
    Run(cli::run::RunArgs),
    /// Run a scenario and record every byte into a field log (same as `run --log LOG`).
    Record(cli::run::RunArgs),
    /// Replay a field log against a fresh flight software and compare every output byte.
    Replay(cli::replay::ReplayArgs),
    /// Export a field log to MCAP.
    Export(cli::export::ExportArgs),
    /// Show a field log's header, frames and damage.
    Inspect(cli::inspect::InspectArgs),
    /// Run every Moving AI scenario of a .map/.scen pair through the team's global planner (D* Lite).
    Movingai(cli::team::MovingaiArgs),
    /// Simulate the four-robot climbing team on real terrain (HiRISE cliff, Itokawa) and draw it.
    Team(cli::team::TeamArgs),
    /// Build the onboard map from a scan sequence and print its ESDF error against ground truth, timing, memory.
    MapCheck(cli::map::MapCheckArgs),
    /// Render the onboard map built from a scan sequence as a PNG (top view or vertical slice).
    RenderMap(cli::map::RenderMapArgs),
    /// Time a full distance transform: the onboard ESDF vs libdynamicedt3d on the same grid.
    EdtBench(cli::map::EdtBenchArgs),
    /// Paton et al.'s Table I for a scenario: N planning trials, each path re-validated on the true terrain.
    Campaign(cli::campaign::CampaignCli),
    /// ABIT* side by side with OMPL 1.5.2's ABIT* on the shared geometric problems.
    AbitBench(cli::abit_bench::Args),
    /// Homotopy planning on a tether-demand plane (scenarios B, C; closed loop with a range sensor).
    Homotopy(cli::homotopy::HomotopyArgs),
    /// The emulated flight computer (QEMU mps2-an500): resource report, on-target benchmarks, link performance.
    Board(cli::board::BoardArgs),
    /// Render the stability region of the 55-degree ledge for a root anchor (SVG).
    StabilityMap(cli::stability_map::StabilityMapArgs),
    /// The planner's stability verdict (map and exact field) against the physics judge: confusion matrices.
    JudgeAgreement(cli::judge_agreement::JudgeAgreementArgs),
}

fn main() -> ExitCode {
    env_logger_lite();
    match Cli::parse().command {
        Command::Mission(a) => cli::mission::cli_main(&a),
        Command::Soak(a) => cli::soak::main(&a),
        Command::Run(a) => cli::run::main(&a),
        Command::Record(a) => {
            if a.log.is_none() {
                return cli::fail("record needs --log LOG (or -o LOG)");
            }
            cli::run::main(&a)
        }
        Command::Replay(a) => cli::replay::main(&a),
        Command::Export(a) => cli::export::main(&a),
        Command::Inspect(a) => cli::inspect::main(&a),
        Command::Movingai(a) => cli::check_outcome(cli::team::movingai(&a)),
        Command::Team(a) => cli::check_outcome(cli::team::team(&a)),
        Command::MapCheck(a) => cli::done(cli::map::map_check(&a)),
        Command::RenderMap(a) => cli::done(cli::map::render_map(&a)),
        Command::EdtBench(a) => cli::done(cli::map::edt_bench(&a)),
        Command::Campaign(a) => cli::campaign::cli_main(&a),
        Command::AbitBench(a) => cli::printed(cli::abit_bench::run(&a)),
        Command::Homotopy(a) => cli::homotopy::main(&a),
        Command::Board(a) => cli::board::main(&a),
        Command::StabilityMap(a) => cli::stability_map::main(&a),
        Command::JudgeAgreement(a) => cli::judge_agreement::main(&a),
    }
}

/// Prints `log` records from the flight software to stderr when `TETHERBOT_LOG` is set (error/warn/info/debug).
fn env_logger_lite() {
    host_sim::cli::install_stderr_logger();
}
