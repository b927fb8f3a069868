//! The generator's command line: generate a model's Rust module, or `inspect` what is derived.

use clap::{Parser, Subcommand};
use generator::command::{self, GenerateArgs};
use std::path::PathBuf;
use std::process::ExitCode;

/// The symbolic core allocates many small nodes and maps: mimalloc cut scene 2's load, derive
/// and emit by 15 % against the system allocator (`cargo bench --bench scaling`).
/// Built without transparent huge pages (the feature `no_thp`, in the workspace manifest): on
/// the planar chain of 20 rods in absolute angles the process then peaks at 96 MB instead of
/// 145 MB, and the kernel no longer stalls it now and then to compact memory for a huge page
/// (24 alternating runs: median CPU 0.62 s either way, worst 0.87 s against 1.01 s).
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// Derives a multibody model's equations of motion symbolically and writes them as a Rust module
/// (to stdout, or to the file given with -o); a summary of sizes, operation counts and timings
/// goes to stderr.
#[derive(Parser, Debug)]
#[command(name = "generator", version, args_conflicts_with_subcommands = true)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    generate: GenerateArgs,
    /// The most expression nodes a derivation may build (default 1000000, about 1 KB of memory
    /// each): a larger model stops with an error naming the budget, never by running out of
    /// memory.
    #[arg(long, global = true, value_name = "N", value_parser = clap::value_parser!(u64).range(1..))]
    max_nodes: Option<u64>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Shows what is derived from a model: T, M, N, Q, the constraints, Definition 1 per
    /// coordinate, and the reduced method's W_NI, X_NI, M_NI, L_NI.
    Inspect {
        /// The model file (RON).
        model: PathBuf,
        /// Print LaTeX instead of text.
        #[arg(long)]
        latex: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    generator::symbolic::budget_for_command_line(cli.max_nodes);
    let result = match cli.command {
        Some(Command::Inspect { model, latex }) => command::inspect(&model, latex),
        None => command::generate(cli.generate),
    };
    command::exit(result)
}
