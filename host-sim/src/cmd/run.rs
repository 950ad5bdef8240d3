//! `host-sim run`: drive an agent from start to goal on one scenario and draw the result.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::sim::clock::ClockKind;
use host_sim::study::run::{self, RunArgs};

/// The options of `host-sim run` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    #[command(flatten)]
    planner: crate::args::PlannerArgs,
    /// Run through every goal of the scenario instead of the first only.
    #[arg(long)]
    all_goals: bool,
    /// Random seed.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Clock, as every command names it: `wall` (real time, as the paper), `cpu` (the
    /// thread's CPU time) or `virtual` (work-driven, repeatable).
    #[arg(long, value_enum, default_value = "wall")]
    clock: ClockKind,
    /// Drop a disc of this radius on the planned path once the agent moves (paper Fig. 7).
    #[arg(long)]
    obstacle: Option<f32>,
    /// Output directory (pictures and result.json).
    #[arg(long, default_value = "out/run")]
    out: PathBuf,
    /// Planning time per call in ms (default: the paper's 150).
    #[arg(long)]
    t_exp_ms: Option<u64>,
    #[command(flatten)]
    fidelity: crate::args::FidelityArgs,
    /// Also write an animated GIF of the run (run.gif), one frame every N plan calls.
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "2",
              value_parser = clap::value_parser!(u32).range(1..))]
    animate: Option<u32>,
    /// Skip each leg's exact optimum (travelled / optimum stays empty). It is computed
    /// after the drive, when every goal's result is already in result.json; on maps with
    /// tens of thousands of obstacle corners it can take long.
    #[arg(long)]
    no_optimum: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        planner,
        all_goals,
        seed,
        clock,
        obstacle,
        out,
        animate,
        t_exp_ms,
        fidelity,
        no_optimum,
    } = cmd;
    let mut sc = scenarios.one(Some("bug_trap"))?;
    sc.paper_lengths = fidelity.paper_lengths();
    let mut planner = vec![planner.one()?];
    fidelity.apply(&mut planner, true)?;
    run::run(&RunArgs {
        scenario: sc,
        planner: planner.remove(0),
        all_goals,
        seed,
        clock,
        obstacle,
        out,
        animate,
        t_exp: t_exp_ms.map(std::time::Duration::from_millis),
        pace: fidelity.pace(),
        no_optimum,
    })
}
