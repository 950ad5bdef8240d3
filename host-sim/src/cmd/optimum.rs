//! `host-sim optimum`: the exact optimum of every leg of a scenario (the yardstick of travelled /
//! optimum), with the map's obstacle corners and the CPU time each leg took (nothing cached), and
//! the grid planners beside it: A* on the 8-connected grid and Theta*, length / optimum and CPU
//! time.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::scenario;

use crate::args::*;

/// The options of `host-sim optimum` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Scenario file.
    #[arg(long)]
    scenarios: PathBuf,
    /// Scenario name in --scenarios.
    #[arg(long)]
    scenario: String,
    #[command(flatten)]
    body: BodyArgs,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        scenario,
        body,
    } = cmd;
    let sc = body.apply(scenario::load_scenarios(&scenarios, Some(&[scenario]))?.remove(0))?;
    host_sim::metric::optimum::report(&sc);
    Ok(())
}
