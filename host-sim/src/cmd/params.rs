//! `host-sim params`: the configuration reference, every value a `NAME@field=value` override
//! can set (the core's parameter table), as Markdown (`docs/reference/configuration.md` is its output).

use anyhow::Result;
use clap::Args;

/// The options of `host-sim params` (none).
#[derive(Args)]
pub struct Cmd {}

/// Runs the command.
pub fn main(_cmd: Cmd) -> Result<()> {
    print!("{}", host_sim::sim::planners::reference());
    Ok(())
}
