//! `host-sim soak`: soak test: one planner and one agent for a long time with a new random goal
//! every few seconds (CPU time of the planner thread).

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;

use crate::args::*;

/// The options of `host-sim soak` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    #[command(flatten)]
    planner: crate::args::PlannerArgs,
    /// Length in minutes of planner CPU time.
    #[arg(long, default_value_t = 30.0)]
    minutes: f64,
    /// Seconds of planner CPU time between two goals.
    #[arg(long, default_value_t = 3.0)]
    goal_every: f64,
    /// Metres the agent moves per call.
    #[arg(long, default_value_t = 0.7)]
    speed: f32,
    /// Nodes per tree: 2048 or 8192.
    #[arg(long, default_value_t = 8192)]
    nodes: usize,
    /// Seed of the planner and the goals.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    table: TableArgs,
    /// Output folder.
    #[arg(long, default_value = "out/soak")]
    out: PathBuf,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        planner,
        minutes,
        goal_every,
        speed,
        nodes,
        seed,
        table,
        out,
    } = cmd;
    if !(minutes > 0.0 && goal_every > 0.0 && speed > 0.0) {
        bail!("--minutes, --goal-every and --speed must be positive");
    }
    let mut scs = vec![scenarios.one(None)?];
    let variant = planner.one()?;
    host_sim::study::soak::run(&host_sim::study::soak::SoakArgs {
        scenario: scs.remove(0),
        variant,
        seconds: minutes * 60.0,
        goal_every,
        speed,
        nodes,
        seed,
        out,
        table: table.options(),
    })
    .map(|_| ())
}
