//! `host-sim`: run the planner on a scenario, run the paper's experiment matrix, bake metric
//! tables. `host-sim --help` lists the commands.

mod args;
mod cmd;

use anyhow::Result;
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    version,
    about = "Simulator and experiment runner for the Bi-AM-RRT* planner"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Drive an agent from start to goal on one scenario and draw the result.
    Run(cmd::run::Cmd),
    /// People walking across and along the agent's first leg (issue 27): the same walkers
    /// reported as still circles, with their velocity, and by an oracle; a door that closes
    /// and opens (as circles or as live cells) or stays closed (live cells or a rebaked
    /// table); collisions by kind, waiting time, travelled / optimal (runs.csv, summary.md,
    /// moving.png, pictures).
    Moving(cmd::moving::Cmd),
    /// Run planners x scenarios x repeats and write runs.csv and summary.csv.
    Experiment(cmd::experiment::Cmd),
    /// Turn an experiment's results folder into charts (SVG and PNG) and a Markdown report in
    /// the shape of the paper's Section 5: Fig. 6 (original vs modified for each scheme), box
    /// plots per planner, nodes at goal, Table 3 (map processing), the paper's claims.
    Report(cmd::report::Cmd),
    /// Join results folders of one experiment (its shards, or runs done on several machines)
    /// into one: rows in canonical order, JSON and summaries. Their settings must be equal; a
    /// run present twice is an error; missing runs are reported.
    Merge(cmd::merge::Cmd),
    /// Compare results folders that differ by one switch each against a base folder (the
    /// same matrix): per planner and map, the change of each mean with its Mann-Whitney p,
    /// as a Markdown page.
    Compare(cmd::compare::Cmd),
    /// Benchmark the planners on every leg of each scenario, like OMPL's benchmark: a fresh
    /// planner per leg and seed, thread CPU time, time to the first solution and path cost
    /// after fixed CPU budgets, against each leg's exact optimum. Writes bench.csv,
    /// summary.csv and summary.md.
    Bench(cmd::bench::Cmd),
    /// Soak test: one planner and one agent for a long time with a new random goal every few
    /// seconds (CPU time of the planner thread). Prints a line per minute and writes soak.csv.
    Soak(cmd::soak::Cmd),
    /// Safety stress test: seeded runs on the built-in maps with obstacles dropped on the path,
    /// between the agent and its waypoint, on the goal and around the agent, vanishing again,
    /// and goals changed mid-run; every move is checked. Fails if any move is unsafe or any
    /// run panics.
    Stress(cmd::stress::Cmd),
    /// Work per `plan` call with a clock that never advances (only the work cap ends a call):
    /// 2,048 and 8,192 nodes, both rewiring modes, on the first leg of each scenario.
    Frozen(cmd::frozen::Cmd),
    /// Bake a metric table from a map.
    Bake(cmd::bake::Cmd),
    /// Export a scenario for a firmware: its bit-packed grid, its diffusion table and Rust
    /// source that `include!`s them as flash `static`s (with the start and goals).
    Export(cmd::export::Cmd),
    /// Measure how the expansion rate changes as the tree grows (no motion, wall clock).
    Growth(cmd::growth::Cmd),
    /// The exact optimum of every leg of a scenario (the yardstick of travelled / optimum),
    /// with the map's obstacle corners and the CPU time each leg took (nothing cached), and
    /// the grid planners beside it: A* on the 8-connected grid and Theta*, length / optimum
    /// and CPU time.
    Optimum(cmd::optimum::Cmd),
    /// Measure wall nanoseconds per unit of planner work (to calibrate the virtual clock).
    Calibrate(cmd::calibrate::Cmd),
    /// The configuration reference: every value a `NAME@field=value` override sets, with its
    /// unit, rule, the paper's and the tuned value (Markdown; docs/reference/configuration.md).
    Params(cmd::params::Cmd),
    /// The command-line reference: every command's help, as Markdown
    /// (docs/reference/cli.md).
    CliReference,
}

fn main() -> Result<()> {
    args::warn_renamed(&std::env::args().collect::<Vec<_>>());
    match Cli::parse().command {
        Command::Run(c) => cmd::run::main(c),
        Command::Moving(c) => cmd::moving::main(c),
        Command::Experiment(c) => cmd::experiment::main(c),
        Command::Report(c) => cmd::report::main(c),
        Command::Merge(c) => cmd::merge::main(c),
        Command::Compare(c) => cmd::compare::main(c),
        Command::Bench(c) => cmd::bench::main(c),
        Command::Soak(c) => cmd::soak::main(c),
        Command::Stress(c) => cmd::stress::main(c),
        Command::Frozen(c) => cmd::frozen::main(c),
        Command::Bake(c) => cmd::bake::main(c),
        Command::Export(c) => cmd::export::main(c),
        Command::Growth(c) => cmd::growth::main(c),
        Command::Optimum(c) => cmd::optimum::main(c),
        Command::Calibrate(c) => cmd::calibrate::main(c),
        Command::Params(c) => cmd::params::main(c),
        Command::CliReference => {
            print!("{}", cli_reference());
            Ok(())
        }
    }
}

/// Every command's long help, as `--help` prints it at a fixed width, in one Markdown page
/// (`docs/reference/cli.md`; a test compares the page with this).
fn cli_reference() -> String {
    use clap::CommandFactory;
    let mut root = Cli::command().term_width(100).max_term_width(100);
    root.build();
    let mut md = String::from(
        "# Command-line reference\n\nGenerated by `host-sim cli-reference` from the commands' \
         definitions (do not edit by hand; a test compares this page with the command's \
         output). `host-sim <command> --help` prints the same.\n\n```text\n",
    );
    md += &root.render_long_help().to_string();
    md += "```\n";
    for sub in root.get_subcommands_mut() {
        if sub.get_name() == "help" {
            continue;
        }
        let name = sub.get_name().to_string();
        md += &format!(
            "\n## host-sim {name}\n\n```text\n{}```\n",
            sub.render_long_help()
        );
    }
    md
}
