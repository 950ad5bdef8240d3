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
    /// Output folder (created): NAME.grid, NAME.table, NAME.rs, and scenario.rs (the same
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
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        out,
        table,
        flash_data,
    } = cmd;
    let sc = scenarios.one(None)?;
    no_clearance(
        std::slice::from_ref(&sc),
        "export does not write a clearance field yet (build one at start-up with bi_am_rrt::clearance::clearance_field)",
    )?;
    bake::export_command(&sc, &table.options(), &out, flash_data)
}
