//! The lustre command line.

mod merl_cmd;

use clap::{Parser, Subcommand};

/// lustre: inspect, plot and synthesize measured materials.
#[derive(Parser, Debug)]
#[command(name = "lustre", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// MERL tables: synthesize from neural BRDFs, inspect.
    Merl(merl_cmd::MerlArgs),
}

fn main() -> anyhow::Result<()> {
    let cli = Cli::parse();
    match &cli.command {
        Command::Merl(args) => merl_cmd::run(args),
    }
}
