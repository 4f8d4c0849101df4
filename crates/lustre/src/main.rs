//! The lustre command line.

mod plot_cmd;

use clap::{Parser, Subcommand};

/// lustre: BSDF models, measured materials and their plots.
#[derive(Parser)]
#[command(name = "lustre", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Plot material lobes and transfer-probability arrays.
    Plot(plot_cmd::PlotArgs),
}

fn main() -> anyhow::Result<()> {
    match Cli::parse().command {
        Command::Plot(args) => plot_cmd::run(&args),
    }
}
