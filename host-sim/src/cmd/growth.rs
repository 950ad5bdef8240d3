//! `host-sim growth`: measure how the expansion rate changes as the tree grows (no motion, wall
//! clock).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::scenario;

use crate::args::*;

/// The options of `host-sim growth` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Scenario file (TOML), or `builtin`.
    #[arg(long)]
    scenarios: PathBuf,
    #[command(flatten)]
    body: BodyArgs,
    /// Comma-separated scenario names (default: all in the file).
    #[arg(long, value_delimiter = ',')]
    maps: Option<Vec<String>>,
    #[command(flatten)]
    planners: crate::args::PlannerArgs,
    /// Seconds of planning per planner and mode.
    #[arg(long, default_value_t = 3.0)]
    seconds: f64,
    /// Length of one plan call (ms).
    #[arg(long, default_value_t = 50)]
    call_ms: u64,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output folder.
    #[arg(long, default_value = "out/growth")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        body,
        maps: names,
        planners,
        seconds,
        call_ms,
        seed,
        out,
    } = cmd;
    let scs = body.apply_all(scenario::load_scenarios(&scenarios, names.as_deref())?)?;
    host_sim::study::growth::growth(&scs, &planners.named()?, seconds, call_ms, seed, &out)
}
