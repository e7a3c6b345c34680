//! The `ringmesh` command line: parses arguments, calls [`ringmesh::run`], prints.
//! Exit codes: 0 success, 1 failure, 2 bad input (nothing is written then).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Pretension design of the cable mesh of ring-truss deployable reflectors.
#[derive(Parser)]
#[command(name = "ringmesh", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Build the front net, rear net and ties of a scene.
    ///
    /// Prints a summary (free/fixed nodes, cables per group, shortest and longest
    /// cable) and writes network.json (interchange format, design positions,
    /// uniform initial q per group) and mesh.vtu (for ParaView).
    ///
    /// Example: ringmesh mesh problems/paper-26m.toml -o results/paper-26m
    Mesh {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Output folder [default: results/<scene name>].
        #[arg(short, long)]
        output: Option<PathBuf>,
    },
    /// Forward force density solve of an interchange-format network.
    ///
    /// Writes nodes (equilibrium xyz), lengths, forces, reactions (per fixed node,
    /// in the order of `fixed`) and max_residual.
    ///
    /// Example: ringmesh fdm results/paper-26m/network.json -o equilibrium.json
    Fdm {
        /// The network file (JSON: nodes, edges, fixed, q, loads?, groups?).
        network: PathBuf,
        /// Output JSON file.
        #[arg(short, long)]
        output: PathBuf,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Mesh { scene, output } => ringmesh::run::mesh(scene, output.as_deref()).map(|m| {
            println!("scene: {}", m.scene);
            print!("{}", m.summary);
            for path in m.written {
                println!("wrote {}", path.display());
            }
        }),
        Command::Fdm { network, output } => ringmesh::run::fdm(network, output).map(|o| {
            println!("max residual: {:.3e} N", o.max_residual);
            println!("wrote {}", output.display());
        }),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(error) => {
            eprintln!("error: {error}");
            ExitCode::from(if error.is_bad_input() { 2 } else { 1 })
        }
    }
}
