//! `host-sim frozen`: work per `plan` call with a clock that never advances (only the work cap ends
//! a call): 2,048 and 8,192 nodes, both rewiring modes, on the first leg of each scenario.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::scenario;

use crate::args::*;

/// The options of `host-sim frozen` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Scenario file (e.g. ../shared/maps/scenarios.toml); the built-in maps without it.
    #[arg(long)]
    scenarios: Option<PathBuf>,
    #[command(flatten)]
    body: BodyArgs,
    /// Scenario names in --scenarios (comma-separated; all by default).
    #[arg(long, value_delimiter = ',')]
    maps: Option<Vec<String>>,
    #[command(flatten)]
    planner: crate::args::PlannerArgs,
    /// Calls per configuration.
    #[arg(long, default_value_t = 10)]
    calls: u32,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        body,
        maps: names,
        planner,
        calls,
    } = cmd;
    let scs = match scenarios {
        Some(file) => scenario::load_scenarios(&file, names.as_deref())?,
        None => scenario::builtin_scenarios(),
    };
    let scs = body.apply_all(scs)?;
    let base = match planner.named()?.as_slice() {
        [one] => *one,
        many => anyhow::bail!("frozen runs one planner; {} named", many.len()),
    };
    host_sim::study::bounds::print_frozen(scs, base, calls)
}
