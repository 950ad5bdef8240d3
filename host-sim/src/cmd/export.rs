//! `host-sim export`: export a scenario for a firmware: its bit-packed grid, its diffusion table
//! and Rust source that `include!`s them as flash `static`s (with the start and goals).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::metric::bake;

use crate::args::*;

/// The options of `host-sim export` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    /// Output folder (created): NAME.grid, NAME.table, NAME.roadmap, NAME.rs, and scenario.rs (the same
    /// source, which the firmware example includes).
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    table: TableArgs,
    /// Flash the firmware leaves to grid and table, in bytes: with `--max-bytes 0` the table
    /// is kept within it (the firmware example: 144 KiB of its 256 KiB); a grid too large
    /// for it is refused with the way out.
    #[arg(long, default_value_t = bake::FIRMWARE_DATA_BYTES)]
    flash_data: usize,
    /// The planner the firmware flies: `tuned` (the default) or `paper` (Bi-AM-RRT*(D), the
    /// tuned set or the paper's; the firmware examples fly no other).
    #[command(flatten)]
    planners: PlannerArgs,
    /// The firmware flies every goal of the scenario in turn (default: goal 1).
    #[arg(long)]
    all_goals: bool,
    /// The office firmware's walkers: people pacing across goal 1's way at 1 m/s (0-4).
    #[arg(long, default_value_t = 0, value_parser = clap::value_parser!(u8).range(0..=4))]
    walkers: u8,
    /// The office firmware's door: a live overlay closing and opening across goal 1's line.
    #[arg(long)]
    door: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        out,
        table,
        flash_data,
        planners,
        all_goals,
        walkers,
        door,
    } = cmd;
    let planner = planners.one()?;
    let tuned = match planner.name.as_str() {
        "Bi-AM-RRT*(D) tuned" => true,
        "Bi-AM-RRT*(D)" => false,
        other => anyhow::bail!(
            "the firmware examples fly Bi-AM-RRT*(D), the tuned set (`--planners tuned`) or \
             the paper's (`--planners paper`), not {other:?}"
        ),
    };
    let mission = bake::Mission {
        tuned,
        all_goals,
        walkers,
        door,
    };
    let sc = scenarios.one(None)?;
    no_clearance(
        std::slice::from_ref(&sc),
        "export does not write a clearance field yet (build one at start-up with bi_am_rrt::clearance::clearance_field)",
    )?;
    bake::export_command(&sc, &table.options(), &out, flash_data, &mission)
}
