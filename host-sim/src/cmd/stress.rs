//! `host-sim stress`: safety stress test: seeded runs on the built-in maps with obstacles dropped
//! on the path, between the agent and its waypoint, on the goal and around the agent, vanishing
//! again, and goals changed mid-run; every move is checked.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::study::stress;

/// The options of `host-sim stress` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// Number of runs (cycling over maps, then planners; seeds consecutive).
    #[arg(long, default_value_t = 1000)]
    runs: u32,
    #[command(flatten)]
    planners: crate::args::PlannerArgs,
    /// First seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Planning time per call, in milliseconds of the virtual clock.
    #[arg(long, default_value_t = 5)]
    t_exp_ms: u64,
    /// Calls before a run is abandoned.
    #[arg(long, default_value_t = 1500)]
    max_calls: u32,
    /// Output folder (stress.csv, summary.json).
    #[arg(long, default_value = "out/stress")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        runs,
        planners,
        seed,
        t_exp_ms,
        max_calls,
        out,
    } = cmd;
    stress::run_and_report(
        &stress::StressArgs {
            runs,
            planners: planners.named()?,
            seed,
            t_exp: std::time::Duration::from_millis(t_exp_ms),
            max_calls,
        },
        &out,
    )
}
