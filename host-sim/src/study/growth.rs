//! Measurements of the planner's speed outside the experiment matrix: the expansion rate as
//! the tree grows (`growth`), and wall nanoseconds per unit of planner work (`calibrate`, the
//! constant of the virtual clock).

use std::time::Duration;

use anyhow::{Context, Result};
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::clock::Clock;
use bi_am_rrt::{Named, RewireMode};
use serde::Serialize;

use crate::results::stats::median;
use crate::scenario::Scenario;
use crate::sim::clock::{VIRTUAL_NS_PER_UNIT, WallClock};
use crate::sim::{Prepared, drive, with_planner};

/// Measures wall nanoseconds per unit of planner work over a few built-in runs.
pub fn calibrate(repeats: u32) -> Result<()> {
    let preps: Vec<Prepared> = crate::scenario::builtin_scenarios()
        .into_iter()
        .map(Prepared::new)
        .collect();
    let mut ratios = Vec::new();
    for prep in &preps {
        for name in ["Bi-AM-RRT*(D)", "AM-RRT*(E)", "RT-RRT*"] {
            let cfg = Named::from_name(name).context("planner")?;
            for seed in 1..=repeats as u64 {
                let clock = WallClock::new();
                let t0 = clock.now();
                // Twenty calls: the search and the start of the drive (3 s of planning).
                let protocol = Protocol {
                    max_calls: 20,
                    ..Protocol::default()
                };
                with_planner(prep, prep.fit(cfg), seed, |p| {
                    drive(p, prep, &clock, &[0], &protocol, |_, _, _, _| {}).map(|_| ())
                })?;
                let ns = (clock.now() - t0) as f64;
                ratios.push(ns / clock.work().max(1) as f64);
            }
        }
    }
    let m = median(&mut ratios).unwrap_or(0.0);
    // `median` sorted the sample.
    println!(
        "wall ns per work unit: median {m:.2} over {} runs (min {:.2}, max {:.2}); the virtual clock uses {VIRTUAL_NS_PER_UNIT}",
        ratios.len(),
        ratios.first().copied().unwrap_or(0.0),
        ratios.last().copied().unwrap_or(0.0)
    );
    Ok(())
}

/// One sample of the expansion-rate measurement.
#[derive(Clone, Debug, Serialize)]
pub struct GrowthRow {
    pub planner: String,
    pub mode: String,
    pub scenario: String,
    pub t_s: f64,
    pub nodes: usize,
    pub expansions: u32,
    pub expansions_per_s: f64,
    pub goal_cost_m: Option<f32>,
}

/// Measures how the expansion rate changes as the tree grows: each planner plans towards goal
/// 1 without moving for `seconds` of wall time in calls of `call_ms`, in both rewiring modes
/// (per-expansion visit budget, and the reference's full time budgets).
pub fn growth(
    scenarios: &[Scenario],
    planners: &[Named],
    seconds: f64,
    call_ms: u64,
    seed: u64,
    out: &std::path::Path,
) -> Result<()> {
    std::fs::create_dir_all(out)?;
    let mut rows = Vec::new();
    for sc in scenarios {
        let prep = Prepared::new(sc.clone());
        for base in planners {
            for (mode, rewire) in [
                ("per-expansion", base.cfg.rewiring.mode),
                ("faithful", RewireMode::Faithful),
            ] {
                let mut cfg = *base;
                cfg.cfg.rewiring.mode = rewire;
                cfg.cfg.budget.t_exp = Duration::from_millis(call_ms);
                with_planner(&prep, prep.fit(cfg), seed, |p| {
                    p.set_goal(sc.goals[0])
                        .map_err(|e| anyhow::anyhow!("{e}"))?;
                    let clock = WallClock::new();
                    while (clock.now() as f64) < seconds * 1e9 {
                        let t0 = clock.now();
                        let pr = p.grow(&clock);
                        let dt = (clock.now() - t0) as f64 * 1e-9;
                        rows.push(GrowthRow {
                            planner: base.name().to_string(),
                            mode: mode.into(),
                            scenario: sc.name.clone(),
                            t_s: clock.now() as f64 * 1e-9,
                            nodes: pr.nodes,
                            expansions: pr.expansions,
                            expansions_per_s: pr.expansions as f64 / dt.max(1e-9),
                            goal_cost_m: pr.goal_cost.filter(|c| !c.blocked).map(|c| c.length),
                        });
                    }
                    Ok(())
                })?;
            }
        }
    }
    let mut w = csv::Writer::from_path(out.join("growth.csv"))?;
    for r in &rows {
        w.serialize(r)?;
    }
    w.flush()?;
    // Median rate per tree-size band.
    let bands = [0usize, 250, 500, 1000, 2000, 4000, 8000, usize::MAX];
    println!(
        "{:<16} {:<10} {:<14} {:>14} {:>16}",
        "planner", "scenario", "mode", "nodes", "expansions/s"
    );
    let mut keys: Vec<(String, String, String)> = Vec::new();
    for r in &rows {
        let k = (r.planner.clone(), r.scenario.clone(), r.mode.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    for (planner, scenario, mode) in keys {
        for w in bands.windows(2) {
            let mut rates: Vec<f64> = rows
                .iter()
                .filter(|r| r.planner == planner && r.scenario == scenario && r.mode == mode)
                .filter(|r| r.nodes >= w[0] && r.nodes < w[1])
                .map(|r| r.expansions_per_s)
                .collect();
            if let Some(m) = median(&mut rates) {
                let band = if w[1] == usize::MAX {
                    format!("{}+", w[0])
                } else {
                    format!("{}-{}", w[0], w[1])
                };
                println!("{planner:<16} {scenario:<10} {mode:<14} {band:>14} {m:>16.0}");
            }
        }
    }
    println!("wrote {}", out.join("growth.csv").display());
    Ok(())
}
