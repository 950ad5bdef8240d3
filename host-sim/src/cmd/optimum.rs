//! `host-sim optimum`: the exact optimum of every leg of a scenario (the yardstick of travelled /
//! optimum), with the map's obstacle corners and the CPU time each leg took (nothing cached), and
//! the grid planners beside it: A* on the 8-connected grid and Theta*, length / optimum and CPU
//! time.

use anyhow::Result;
use clap::Args;

/// The options of `host-sim optimum` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    /// Leave the grid planners (A*, Theta*) out: the exact optimum alone.
    #[arg(long)]
    no_grid: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd { scenarios, no_grid } = cmd;
    let sc = scenarios.one(None)?;
    host_sim::metric::optimum::report(&sc, !no_grid);
    Ok(())
}
