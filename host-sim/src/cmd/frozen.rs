//! `host-sim frozen`: work per `plan` call with a clock that never advances (only the work cap ends
//! a call): 2,048 and 8,192 nodes, both rewiring modes, on the first leg of each scenario.

use anyhow::Result;
use clap::Args;
use host_sim::scenario;

/// The options of `host-sim frozen` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
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
        planner,
        calls,
    } = cmd;
    // The small built-ins by default (the paper-sized ones take long with a frozen clock).
    let scs = scenarios.all_or(scenario::builtin_scenarios)?;
    let base = match planner.named()?.as_slice() {
        [one] => *one,
        many => anyhow::bail!("frozen runs one planner; {} named", many.len()),
    };
    host_sim::study::bounds::print_frozen(scs, base, calls)
}
