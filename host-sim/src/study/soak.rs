//! The soak test: one planner driving one agent for a long time (default 30 minutes of the
//! planner thread's CPU time) with a new random goal every few seconds, under the agent
//! protocol's motion (`speed` metres per `plan` call). It shows whether a tree that lives
//! forever stays healthy: nodes, path quality and time per call must stay flat.
//!
//! Per goal (one row of `soak.csv`): when it was set, its exact optimum from the agent's
//! position then ([`crate::metric::optimum`]), the CPU time until it joined the tree, and when the
//! next goal replaces it: `(travelled since set + planned cost left) / optimum`, the forward
//! tree's size, the calls and their median and longest CPU time. Every move is checked against
//! the map; a collision fails the run. Per minute, a line summarises the goals set in it.

use std::io::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result, anyhow, bail};
use bi_am_rrt::Point;
use bi_am_rrt::clock::Clock;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;
use serde::Serialize;

use crate::metric::optimum::Corners;
use crate::results::stats::median;
use crate::scenario::Scenario;
use crate::sim::clock::CpuClock;
use crate::sim::planners::Variant;
use crate::sim::{Prepared, SizedPlanner, with_planner_at};

/// What to run.
pub struct SoakArgs {
    /// The scenario (its map; the start is the agent's first position).
    pub scenario: Scenario,
    /// The planner (fitted to the scenario, then its overrides: [`Variant::config_for`]).
    pub variant: Variant,
    /// CPU seconds of the whole soak.
    pub seconds: f64,
    /// CPU seconds between two goals.
    pub goal_every: f64,
    /// Metres per call.
    pub speed: f32,
    /// Nodes per tree: 2048 or 8192.
    pub nodes: usize,
    /// Seed of the planner and of the goals.
    pub seed: u64,
    /// Output directory.
    pub out: PathBuf,
    /// Diffusion table layout.
    pub table: crate::metric::diffusion::TableOptions,
}

/// One goal of the soak.
#[derive(Clone, Debug, Serialize)]
pub struct SoakRow {
    pub goal: usize,
    pub set_at_s: f32,
    pub x: f32,
    pub y: f32,
    pub optimal_m: f32,
    /// CPU ms from setting the goal to its joining the tree.
    pub search_ms: Option<f32>,
    /// (travelled + planned cost left) / optimum when the next goal came.
    pub planned_ratio: Option<f32>,
    pub reached: bool,
    pub nodes: usize,
    pub calls: u32,
    pub call_ms_median: f32,
    pub call_ms_max: f32,
}

/// Runs the soak; writes `soak.csv` and prints a line per minute.
pub fn run(args: &SoakArgs) -> Result<Vec<SoakRow>> {
    match args.nodes {
        2048 => run_n::<2048>(args),
        8192 => run_n::<8192>(args),
        n => bail!("--nodes {n}: use 2048 or 8192"),
    }
}

fn run_n<const N: usize>(args: &SoakArgs) -> Result<Vec<SoakRow>> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let prep = Prepared::with_table(args.scenario.clone(), args.table);
    let corners = Corners::of(&prep.scenario.reach_grid());
    let cfg = args.variant.config_for(&prep)?;
    with_planner_at::<N, _>(&prep, cfg, args.seed, prep.scenario.start, |planner| {
        drive(planner, args, &corners)
    })
}

/// The soak proper on a built planner (module docs).
fn drive<const N: usize>(
    planner: &mut SizedPlanner<'_, '_, N>,
    args: &SoakArgs,
    corners: &Corners,
) -> Result<Vec<SoakRow>> {
    let mut goals = XorShiftRng::seed_from_u64(args.seed ^ 0x5eed);
    let clock = CpuClock::new();
    let secs = |t: u64| t as f64 * 1e-9;
    let mut csv = csv::Writer::from_path(args.out.join("soak.csv"))?;
    let mut rows: Vec<SoakRow> = Vec::new();
    let mut agent = args.scenario.start;
    let mut minute = 0u64;
    let grid = args.scenario.map.grid();
    let mut planner_cpu = 0.0f64;
    while planner_cpu < args.seconds {
        // A new reachable goal.
        let (goal, opt) = loop {
            let p = Point::new(
                unit(&mut goals) * grid.width_m(),
                unit(&mut goals) * grid.height_m(),
            );
            if grid.point_free(p)
                && p.dist(agent) > 1.0
                && let Some(o) = corners.shortest(agent, p)
            {
                break (p, o);
            }
        };
        let t_set = clock.now();
        planner.set_goal(goal).map_err(|e| anyhow!("goal: {e}"))?;
        let set_at = planner_cpu;
        let mut times = Vec::new();
        let mut travelled = 0.0f64;
        let mut search_ms = None;
        let mut reached = false;
        let mut last = None;
        while planner_cpu - set_at < args.goal_every && planner_cpu < args.seconds {
            let t0 = clock.now();
            let p = planner
                .plan(&clock, agent)
                .map_err(|e| anyhow!("plan at {agent:?}: {e}"))?;
            let dt = secs(clock.now().saturating_sub(t0));
            planner_cpu += dt;
            times.push(dt * 1e3);
            if search_ms.is_none()
                && let Some(at) = planner.stats().goal_found_at
            {
                search_ms = Some(secs(at.saturating_sub(t_set)) * 1e3);
            }
            let step = agent.step_towards(p.waypoint, args.speed);
            if !planner.map().free_path(agent, step) {
                bail!("collision: move {agent:?} -> {step:?} crosses the map");
            }
            travelled += agent.dist(step) as f64;
            agent = step;
            last = Some(p);
            if p.goal_in_tree && agent == goal {
                reached = true;
                break;
            }
        }
        let planned = if reached {
            Some(travelled / opt)
        } else {
            // The agent is on its way to the root; the tree's cost counts from the root.
            let to_root = agent.dist(planner.root_position()) as f64;
            last.and_then(|p| p.goal_cost)
                .filter(|c| !c.blocked)
                .map(|c| (travelled + to_root + c.length as f64) / opt)
        };
        let calls = times.len() as u32;
        let max = times.iter().copied().fold(0.0, f64::max);
        // Written at f32 precision: no float noise in the CSV.
        let row = SoakRow {
            goal: rows.len() + 1,
            set_at_s: set_at as f32,
            x: goal.x,
            y: goal.y,
            optimal_m: opt as f32,
            search_ms: search_ms.map(|v| v as f32),
            planned_ratio: planned.map(|v| v as f32),
            reached,
            nodes: planner.tree().len(),
            calls,
            call_ms_median: median(&mut times).unwrap_or(0.0) as f32,
            call_ms_max: max as f32,
        };
        csv.serialize(&row)?;
        csv.flush()?;
        rows.push(row);
        if planner_cpu >= (minute + 1) as f64 * 60.0 || planner_cpu >= args.seconds {
            minute = (planner_cpu / 60.0) as u64;
            let recent: Vec<&SoakRow> = rows
                .iter()
                .filter(|r| f64::from(r.set_at_s) >= planner_cpu - 60.0)
                .collect();
            print_line(planner_cpu, &recent);
        }
    }
    let all: Vec<&SoakRow> = rows.iter().collect();
    println!("whole soak:");
    print_line(planner_cpu, &all);
    std::io::stdout().flush()?;
    Ok(rows)
}

fn unit(r: &mut XorShiftRng) -> f32 {
    (r.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

fn print_line(at: f64, rows: &[&SoakRow]) {
    let f = |v: Option<f32>| v.map_or(f64::INFINITY, f64::from);
    let mut search: Vec<f64> = rows.iter().map(|r| f(r.search_ms)).collect();
    let mut ratio: Vec<f64> = rows.iter().map(|r| f(r.planned_ratio)).collect();
    let mut nodes: Vec<f64> = rows.iter().map(|r| r.nodes as f64).collect();
    let mut med: Vec<f64> = rows.iter().map(|r| f64::from(r.call_ms_median)).collect();
    let max = rows
        .iter()
        .map(|r| f64::from(r.call_ms_max))
        .fold(0.0, f64::max);
    let found = rows.iter().filter(|r| r.search_ms.is_some()).count();
    println!(
        "{:7.1} s: {} goals, {} joined, search median {:.1} ms, planned/optimal median {:.3}, nodes median {:.0}, call median {:.2} ms, longest {:.2} ms",
        at,
        rows.len(),
        found,
        median(&mut search).unwrap_or(f64::NAN),
        median(&mut ratio).unwrap_or(f64::NAN),
        median(&mut nodes).unwrap_or(f64::NAN),
        median(&mut med).unwrap_or(f64::NAN),
        max
    );
}
