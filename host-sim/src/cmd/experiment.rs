//! `host-sim experiment`: run planners x scenarios x repeats and write runs.csv and summary.csv.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use host_sim::sim::clock::ClockKind;
use host_sim::study::experiment::{self, ExperimentArgs, Goals};

use crate::args::*;

/// The options of `host-sim experiment` (its description is the command's, in `main.rs`).
#[derive(Args)]
pub struct Cmd {
    #[command(flatten)]
    scenarios: crate::args::ScenarioArgs,
    #[command(flatten)]
    planners: crate::args::PlannerArgs,
    /// Runs per planner and scenario (seeds seed .. seed + repeats - 1).
    #[arg(long, default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..))]
    repeats: u32,
    /// Clock, as every command names it: `wall` (real time, as the paper), `cpu` (the
    /// thread's CPU time) or `virtual` (work-driven, repeatable).
    #[arg(long, value_enum, default_value = "wall")]
    clock: ClockKind,
    /// Goal 1 only, or the whole goal sequence.
    #[arg(long, value_enum, default_value = "first")]
    goals: Goals,
    /// First seed (run r uses seed + r).
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Parallel jobs (default: all cores).
    #[arg(long)]
    jobs: Option<usize>,
    #[command(flatten)]
    fidelity: crate::args::FidelityArgs,
    #[command(flatten)]
    table: TableArgs,
    /// Planning time per call in ms (default: the paper's 150).
    #[arg(long)]
    t_exp_ms: Option<u64>,
    /// Stop each run once the goal is in the tree (search time and nodes only).
    #[arg(long)]
    search_only: bool,
    /// Planning time for the "cost after 100 ms without moving" column (ms; 0: skip).
    #[arg(long, default_value_t = 100)]
    anytime_ms: u64,
    /// Run only slice K of N of the matrix (1-based, e.g. 3/8; runs i with i mod N = K - 1
    /// in the order scenario, planner, seed). Join the slices' folders with `merge`.
    #[arg(long)]
    shard: Option<host_sim::results::Shard>,
    /// Continue the experiment in --out: run only what it does not hold yet (its
    /// experiment.json must have the same settings).
    #[arg(long, conflicts_with = "overwrite")]
    resume: bool,
    /// Delete the results already in --out and start again.
    #[arg(long)]
    overwrite: bool,
    /// Output folder (experiment.json, runs.csv appended as runs end; runs.json,
    /// summary.csv and summary.json when complete).
    #[arg(long, default_value = "out/experiment")]
    out: PathBuf,
    /// Count the agent's 0.25 s wait from when the goal is set, as the AM-RRT* reference's
    /// benchmark does (default: from when the goal joins the tree).
    #[arg(long)]
    wait_from_set: bool,
    /// The AM-RRT* reference's agent rule (Figs. 7 and 10 as the papers ran them): the agent
    /// moves along the tree's path to the goal whatever its blocked flags, and every
    /// segment that is not clear counts as a collision (default: the agent moves to the
    /// planner's waypoint, and holds when none is clear, promise 1).
    #[arg(long)]
    move_when_blocked: bool,
    /// Skip each leg's exact optimum (`optimal_m` and `travelled_ratio` stay empty): on maps
    /// with tens of thousands of obstacle corners it can take long.
    #[arg(long)]
    no_optimum: bool,
    /// The paper's Meet: every pair within sigma is tested for a free segment, not only
    /// the 16 cheapest.
    #[arg(long)]
    meet_all_pairs: bool,
    /// The paper's Fig. 7: drop a disc of this radius (metres) on goal 1's planned path
    /// once the agent has moved 2 m, 10 m ahead along the path (as `run --obstacle`);
    /// rows record the replanning time, the replanned path's cost and the detour
    /// against the exact optimum around the disc.
    #[arg(long)]
    obstacle: Option<f32>,
}

/// Runs the command.
pub fn main(cmd: Cmd) -> Result<()> {
    let Cmd {
        scenarios,
        planners,
        repeats,
        clock,
        goals,
        seed,
        jobs,
        fidelity,
        table,
        t_exp_ms,
        search_only,
        anytime_ms,
        shard,
        resume,
        overwrite,
        out,
        wait_from_set,
        move_when_blocked,
        no_optimum,
        meet_all_pairs,
        obstacle,
    } = cmd;
    let mut scs = scenarios.all()?;
    for s in &mut scs {
        s.paper_lengths = fidelity.paper_lengths();
    }
    experiment::run(&ExperimentArgs {
        wait_from_set,
        move_when_blocked,
        pace: fidelity.pace(),
        no_optimum,
        as_printed: fidelity.as_printed()?,
        meet_all_pairs,
        obstacle,
        shard,
        existing: if resume {
            experiment::Existing::Resume
        } else if overwrite {
            experiment::Existing::Overwrite
        } else {
            experiment::Existing::Refuse
        },
        scenarios: scs,
        planners: planners.variants()?,
        repeats,
        clock,
        goals,
        seed,
        jobs,
        faithful: fidelity.faithful(),
        search_only,
        anytime_ms,
        table: table.options(),
        t_exp: t_exp_ms.map(std::time::Duration::from_millis),
        out,
    })
    .map(|_| ())
}
