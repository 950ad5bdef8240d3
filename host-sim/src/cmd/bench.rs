//! `host-sim bench`: benchmark the planners on every leg of each scenario, like OMPL's benchmark: a
//! fresh planner per leg and seed, thread CPU time, time to the first solution and path cost after
//! fixed CPU budgets, against each leg's exact optimum.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args;

use crate::args::*;

/// The options of `host-sim bench` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    /// Legs to run, 1-based and comma-separated (default: all).
    #[arg(long, value_delimiter = ',')]
    legs: Option<Vec<usize>>,
    #[command(flatten)]
    planners: crate::args::PlannerArgs,
    /// Seeds per leg and planner (seeds 1..=N).
    #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..))]
    seeds: u64,
    /// CPU budgets in seconds at which the path cost is read, comma-separated.
    #[arg(long, value_delimiter = ',', default_value = "0.01,0.1,1")]
    budgets: Vec<f64>,
    /// Nodes per tree: 2048, 4096, 8192, 16384 or 65000 (default: 8192, or the smallest that
    /// holds the map's roadmap, as `run`)
    #[arg(long)]
    nodes: Option<usize>,
    #[command(flatten)]
    table: TableArgs,
    /// Output folder.
    #[arg(long, default_value = "out/bench")]
    out: PathBuf,
    /// Also run OMPL's RRT-Connect on every leg, in the same run: the path of the
    /// `benches/ompl` harness binary (see its README; needs libompl-dev).
    #[arg(long)]
    ompl: Option<PathBuf>,
    /// The planners' clock, as every command names it: `cpu-mono` (the default: thread CPU
    /// time, read by a system call at most once a millisecond and between those readings
    /// advanced by the monotonic clock, so that each of the planner's readings costs what a
    /// robot's or OMPL's does, about 30 ns), `cpu` (thread CPU time, a system call of
    /// 0.4-0.8 us at every reading: the default before 2026-11-29), `wall` (the monotonic
    /// clock: at least the CPU time; `steady` is the old spelling) or `virtual` (work units,
    /// repeatable: for comparing algorithmic changes; its "us" are virtual).
    #[arg(long, value_enum, default_value = "cpu-mono")]
    clock: host_sim::study::bench::BenchClock,
    #[command(flatten)]
    fidelity: crate::args::FidelityArgs,
    /// Warm queries: each query runs on the caches the previous one left. By default
    /// (cold, what a user's one query meets) the caches are flushed before every
    /// measured query, ours, OMPL's and the grid planners' (64 MiB written and read
    /// back, outside the timed part). Warm flatters whoever runs a query right after
    /// another on the same map: OMPL's harness, and our seeds after the first.
    #[arg(long, conflicts_with = "cold")]
    warm: bool,
    /// Cold queries: the default since issue 42 (kept so that older commands run).
    #[arg(long, hide = true)]
    cold: bool,
    /// Leave out the grid planners (A* on the 8-connected grid and Theta*, run on every
    /// leg by default; `grid.md` compares each of our planners with them).
    #[arg(long)]
    no_grid: bool,
    /// Each of our runs ends at its first solution (or at the last budget without one),
    /// as each of RRT-Connect's runs ends at its: a warm query then starts on the caches a
    /// first-solution search left, as RRT-Connect's do, not on those of a query that grew
    /// for the whole budget. No costs are read (their columns stay empty): for
    /// first-solution figures only.
    #[arg(long)]
    until_first: bool,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        legs,
        planners,
        seeds,
        mut budgets,
        nodes,
        table,
        out,
        ompl,
        clock,
        fidelity,
        warm,
        cold: _,
        until_first,
        no_grid,
    } = cmd;
    if budgets.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
        bail!("--budgets: every budget must be a positive number of seconds");
    }
    budgets.sort_by(f64::total_cmp);
    let mut scs = scenarios.all()?;
    no_clearance(
        &scs,
        "bench compares path costs with OMPL's, which are lengths",
    )?;
    for s in &mut scs {
        s.paper_lengths = fidelity.paper_lengths();
    }
    let mut variants = planners.variants()?;
    fidelity.apply(&mut variants, false)?;
    host_sim::study::bench::run(&host_sim::study::bench::BenchArgs {
        scenarios: scs,
        legs: legs.unwrap_or_default(),
        variants,
        seeds,
        budgets,
        nodes,
        out,
        table: table.options(),
        ompl,
        clock,
        cold: !warm,
        until_first,
        grid: !no_grid,
    })
    .map(|_| ())
}
