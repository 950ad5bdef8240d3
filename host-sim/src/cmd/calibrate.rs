//! `host-sim calibrate`: measure wall nanoseconds per unit of planner work (to calibrate the
//! virtual clock).

use anyhow::{Context, Result};
use clap::Args;

/// The options of `host-sim calibrate` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Runs (the median is reported).
    #[arg(long, default_value_t = 5)]
    repeats: u32,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd { repeats } = cmd;
    host_sim::study::growth::calibrate(repeats).context("calibrating")
}
