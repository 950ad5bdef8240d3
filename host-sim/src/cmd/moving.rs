//! `host-sim moving`: people walking across and along the agent's first leg (issue 27): the same
//! walkers reported as still circles, with their velocity, and by an oracle; a door that closes and
//! opens (as circles or as live cells) or stays closed (live cells or a rebaked table); collisions
//! by kind, waiting time, travelled / optimal (runs.csv, summary.md, moving.png, pictures).

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

/// The options of `host-sim moving` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    /// Scenes: crossing, head-on, door, closed-door (comma-separated).
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "crossing,head-on"
    )]
    kinds: Vec<host_sim::study::moving::Kind>,
    /// Seeds per scene and treatment.
    #[arg(long, default_value_t = 10)]
    seeds: u64,
    /// Planning budget per call in ms on the virtual clock.
    #[arg(long, default_value_t = 5)]
    t_exp_ms: u64,
    /// Output directory.
    #[arg(long, default_value = "out/moving")]
    out: PathBuf,
    /// Also write an animated GIF of seed 0 (predicted) per scene, a frame every N calls.
    #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "20",
              value_parser = clap::value_parser!(u32).range(1..))]
    animate: Option<u32>,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        kinds,
        seeds,
        t_exp_ms,
        out,
        animate,
    } = cmd;
    let prep = host_sim::sim::Prepared::new(scenarios.one(Some("office_200"))?);
    host_sim::study::moving::moving(
        &prep,
        &host_sim::study::moving::MovingArgs {
            kinds,
            seeds,
            t_exp: std::time::Duration::from_millis(t_exp_ms),
            out,
            animate,
            route_calls: host_sim::study::moving::ROUTE_CALLS,
        },
    )?;
    Ok(())
}
