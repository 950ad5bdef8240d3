//! The safety stress test (issue 7): many seeded runs on the built-in maps in which dynamic
//! obstacles keep appearing where they hurt most (on the path ahead, between the agent and its
//! waypoint, on the goal, around the agent) and vanishing again, and the goal changes mid-run.
//! Every agent move is checked against the map and every obstacle present at that moment; a
//! panic is caught and counted. The planner's promise is zero unsafe moves and zero panics; a
//! run that does not arrive reports why (the planner's last `Status`).

use std::collections::VecDeque;
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::time::Duration;

use anyhow::{Result, bail};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::geometry::unit_f32;
use bi_am_rrt::map::ObstacleId;
use bi_am_rrt::{Circle, Named, Point};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;
use rayon::prelude::*;
use serde::Serialize;

use crate::scenario::builtin_scenarios;
use crate::sim::clock::VIRTUAL_NS_PER_UNIT;
use crate::sim::{Prepared, with_planner};

/// What to stress.
#[derive(Clone, Debug)]
pub struct StressArgs {
    /// Number of runs (spread over maps, planners and seeds).
    pub runs: u32,
    /// Planner names (Table 1).
    pub planners: Vec<Named>,
    /// First seed.
    pub seed: u64,
    /// `t_exp` per call (virtual clock).
    pub t_exp: Duration,
    /// Calls before a run is abandoned.
    pub max_calls: u32,
}

/// One run's outcome.
#[derive(Clone, Debug, Serialize)]
pub struct StressRun {
    /// Map name.
    pub map: String,
    /// Planner name.
    pub planner: String,
    /// Seed.
    pub seed: u64,
    /// Calls made.
    pub calls: u32,
    /// Agent moves (calls in which it moved).
    pub moves: u32,
    /// Moves whose segment met the map or an obstacle present.
    pub unsafe_moves: u32,
    /// Obstacles dropped.
    pub obstacles: u32,
    /// Goal changes.
    pub goal_changes: u32,
    /// The agent stood on the final goal.
    pub arrived: bool,
    /// The run panicked (message).
    pub panic: Option<String>,
    /// Why the run did not arrive (the planner's last status), empty when it did.
    pub reason: String,
}

/// Totals over all runs.
#[derive(Clone, Debug, Default, Serialize)]
pub struct StressSummary {
    /// Runs.
    pub runs: u32,
    /// Agent moves.
    pub moves: u64,
    /// Unsafe moves (the promise: 0).
    pub unsafe_moves: u64,
    /// Panics (the promise: 0).
    pub panics: u32,
    /// Runs that arrived.
    pub arrived: u32,
    /// Obstacles dropped.
    pub obstacles: u64,
    /// Goal changes.
    pub goal_changes: u64,
}

/// Runs the stress test; rows in run order.
pub fn run(args: &StressArgs) -> Result<(StressSummary, Vec<StressRun>)> {
    if args.runs == 0 || args.planners.is_empty() {
        bail!("stress needs at least one run and one planner");
    }
    let preps: Vec<Prepared> = builtin_scenarios().into_iter().map(Prepared::new).collect();
    let cases: Vec<(usize, Named, u64)> = (0..args.runs as u64)
        .map(|i| {
            let map = i as usize % preps.len();
            let planner = args.planners[(i as usize / preps.len()) % args.planners.len()];
            (map, planner, args.seed + i)
        })
        .collect();
    let rows: Vec<StressRun> = cases
        .par_iter()
        .map(|&(m, cfg, seed)| {
            let prep = &preps[m];
            let outcome = catch_unwind(AssertUnwindSafe(|| one(prep, cfg, seed, args)));
            match outcome {
                Ok(Ok(row)) => row,
                Ok(Err(e)) => row_for(prep, cfg, seed, format!("error: {e:#}")),
                Err(p) => {
                    let msg = p
                        .downcast_ref::<String>()
                        .cloned()
                        .or_else(|| p.downcast_ref::<&str>().map(|s| s.to_string()))
                        .unwrap_or_else(|| "panic".into());
                    let mut row = row_for(prep, cfg, seed, "panic".into());
                    row.panic = Some(msg);
                    row
                }
            }
        })
        .collect();
    let mut sum = StressSummary::default();
    for r in &rows {
        sum.runs += 1;
        sum.moves += r.moves as u64;
        sum.unsafe_moves += r.unsafe_moves as u64;
        sum.panics += r.panic.is_some() as u32;
        sum.arrived += r.arrived as u32;
        sum.obstacles += r.obstacles as u64;
        sum.goal_changes += r.goal_changes as u64;
    }
    Ok((sum, rows))
}

/// An empty row for a run (the failure reason, if any, given).
fn row_for(prep: &Prepared, cfg: Named, seed: u64, reason: String) -> StressRun {
    StressRun {
        map: prep.scenario.name.clone(),
        planner: cfg.name().to_string(),
        seed,
        calls: 0,
        moves: 0,
        unsafe_moves: 0,
        obstacles: 0,
        goal_changes: 0,
        arrived: false,
        panic: None,
        reason,
    }
}

/// A free point of the map drawn uniformly (`None` after 200 tries).
fn free_point(p: &crate::sim::SimPlanner<'_, '_>, rng: &mut XorShiftRng) -> Option<Point> {
    let g = p.map().grid();
    (0..200).find_map(|_| {
        let q = Point::new(unit_f32(rng) * g.width_m(), unit_f32(rng) * g.height_m());
        p.map().free_point(q).then_some(q)
    })
}

fn one(prep: &Prepared, base: Named, seed: u64, args: &StressArgs) -> Result<StressRun> {
    let mut cfg = prep.fit(base);
    cfg.cfg.budget.t_exp = args.t_exp;
    let mut row = row_for(prep, base, seed, String::new());
    with_planner(prep, cfg, seed, |p| {
        let clock = FakeClock::nanos().with_work_cost(VIRTUAL_NS_PER_UNIT);
        let mut rng = XorShiftRng::seed_from_u64(seed ^ 0x5eed);
        let goals = &prep.scenario.goals;
        let mut goal = goals[0];
        p.set_goal(goal).map_err(|e| anyhow::anyhow!("goal: {e}"))?;
        let mut agent = p.root_position();
        // Live circles with the call at which each vanishes.
        let mut live: VecDeque<(u32, ObstacleId)> = VecDeque::new();
        let changes = 1 + (seed % 2) as u32;
        let mut last = None;
        for call in 0..args.max_calls {
            // Circles whose time is up vanish; a random one sometimes vanishes early.
            live.retain(|&(until, id)| {
                let keep = call < until;
                if !keep {
                    let _ = p.remove_obstacle(id);
                }
                keep
            });
            if !live.is_empty() && rng_chance(&mut rng, 0.03) {
                let i = (rng_u32(&mut rng) as usize) % live.len();
                if let Some((_, id)) = live.remove(i) {
                    let _ = p.remove_obstacle(id);
                }
            }
            // The goal changes mid-run (a few times per run, early on).
            if row.goal_changes < changes && call > 0 && call % 40 == 0 {
                let next = if rng_chance(&mut rng, 0.5) {
                    goals[(rng_u32(&mut rng) as usize) % goals.len()]
                } else {
                    free_point(p, &mut rng).unwrap_or(goal)
                };
                if p.set_goal(next).is_ok() {
                    goal = next;
                    row.goal_changes += 1;
                }
            }
            let pr = p
                .plan(&clock, agent)
                .map_err(|e| anyhow::anyhow!("plan at {agent:?}: {e}"))?;
            row.calls = call + 1;
            last = Some(pr.status);
            let step = agent.step_towards(pr.waypoint, 1.0);
            if step != agent {
                row.moves += 1;
                if !p.map().free_path(agent, step) {
                    row.unsafe_moves += 1;
                }
            }
            agent = step;
            if pr.goal_in_tree && agent == goal {
                row.arrived = true;
                break;
            }
            // A new circle, where it hurts (one call in five, at most 6 at once, each for 3 to
            // 22 calls).
            if live.len() < 6 && rng_chance(&mut rng, 0.2) {
                let mut path = vec![Point::ZERO; p.tree().len().max(1)];
                let n = p.path(&mut path).map(|i| i.len).unwrap_or(0);
                let kind = rng_u32(&mut rng) % 4;
                let circle = match kind {
                    // On the path ahead.
                    0 if n >= 2 => {
                        let k = 1 + (rng_u32(&mut rng) as usize) % (n - 1);
                        Circle::new(path[k], 0.5 + 1.5 * unit_f32(&mut rng))
                    }
                    // Between the agent and its waypoint.
                    1 if agent != pr.waypoint => Circle::new(
                        agent.lerp(pr.waypoint, unit_f32(&mut rng)),
                        0.3 + unit_f32(&mut rng),
                    ),
                    // On the goal.
                    2 => Circle::new(goal, 0.5 + 2.0 * unit_f32(&mut rng)),
                    // Around the agent.
                    _ => Circle::new(agent, 0.5 + unit_f32(&mut rng)),
                };
                let life = 3 + rng_u32(&mut rng) % 20;
                if let Ok(id) = p.add_obstacle(circle) {
                    live.push_back((call + life, id));
                    row.obstacles += 1;
                }
            }
        }
        if !row.arrived {
            row.reason = match last {
                Some(s) => format!("{s:?} after {} calls", row.calls),
                None => "no call".into(),
            };
        }
        Ok(())
    })?;
    Ok(row)
}

fn rng_u32(rng: &mut XorShiftRng) -> u32 {
    rand_core::Rng::next_u32(rng)
}

fn rng_chance(rng: &mut XorShiftRng, p: f32) -> bool {
    unit_f32(rng) < p
}

/// `host-sim stress`: [`run`], then stress.csv and summary.json in `out`, a line per run that
/// did not arrive and the totals; an error if any move was unsafe or any run panicked.
pub fn run_and_report(args: &StressArgs, out: &std::path::Path) -> Result<()> {
    let t0 = std::time::Instant::now();
    let (sum, rows) = run(args)?;
    std::fs::create_dir_all(out)?;
    let mut w = csv::Writer::from_path(out.join("stress.csv"))?;
    for r in &rows {
        w.serialize(r)?;
    }
    w.flush()?;
    std::fs::write(
        out.join("summary.json"),
        serde_json::to_string_pretty(&sum)?,
    )?;
    for r in rows.iter().filter(|r| !r.arrived) {
        println!(
            "not arrived: {} {} seed {}: {}{}",
            r.map,
            r.planner,
            r.seed,
            r.reason,
            r.panic
                .as_deref()
                .map(|m| format!(" ({m})"))
                .unwrap_or_default()
        );
    }
    println!(
        "stress: {} runs, {} moves, {} unsafe moves, {} panics, {} arrived, {} obstacles, \
         {} goal changes ({:.1} s; rows in {})",
        sum.runs,
        sum.moves,
        sum.unsafe_moves,
        sum.panics,
        sum.arrived,
        sum.obstacles,
        sum.goal_changes,
        t0.elapsed().as_secs_f64(),
        out.join("stress.csv").display()
    );
    if sum.unsafe_moves > 0 || sum.panics > 0 {
        bail!("the safety promise was broken");
    }
    Ok(())
}
