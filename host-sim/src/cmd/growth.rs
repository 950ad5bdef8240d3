//! `host-sim growth`: measure how the expansion rate changes as the tree grows (no motion, wall
//! clock).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

/// The options of `host-sim growth` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
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
        planners,
        seconds,
        call_ms,
        seed,
        out,
    } = cmd;
    let scs = scenarios.all()?;
    host_sim::study::growth::growth(&scs, &planners.named()?, seconds, call_ms, seed, &out)
}
