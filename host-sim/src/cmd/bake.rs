//! `host-sim bake`: bake a metric table from a map.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::metric::bake;

use crate::args::*;

/// The options of `host-sim bake` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    /// PNG map (mean-threshold rule), ROS map_server YAML (with its PGM or PNG image), or
    /// `builtin:NAME`.
    #[arg(long)]
    map: String,
    /// Cell side of a PNG map in metres (default 1).
    #[arg(long)]
    resolution: Option<f32>,
    /// Metric to bake: `diffusion` (a table) or `geodesic` (the grid graph).
    #[arg(long, value_enum, default_value = "diffusion")]
    metric: MetricArg,
    /// Output file.
    #[arg(long)]
    out: PathBuf,
    #[command(flatten)]
    table: TableArgs,
    /// Also write Rust source with a `static` table to this file.
    #[arg(long)]
    rust: Option<PathBuf>,
    /// Geodesic: also time the computation of every distance field (all pairs).
    #[arg(long)]
    all_pairs: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        map,
        resolution,
        metric,
        out,
        table,
        rust,
        all_pairs,
    } = cmd;
    let grid = load_map(&map, resolution)?;
    match metric {
        MetricArg::Diffusion => {
            bake::diffusion_command(&grid, &map, &out, &table.options(), rust.as_deref())
        }
        MetricArg::Geodesic => bake::geodesic_command(&grid, &map, &out, all_pairs),
    }
}
