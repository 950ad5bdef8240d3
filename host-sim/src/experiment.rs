//! The experiment runner: planners x scenarios x repeats under the agent protocol, in parallel
//! on all cores, written to `runs.csv` (one row per run and goal) and `summary.csv` (medians
//! per planner, scenario and goal).
//!
//! Per run (seed = first seed + repeat index, the same seeds for every planner):
//! - the goal sequence (goal 1, or all goals) is driven under `bi_am_rrt::agent`'s protocol;
//! - with `--anytime-ms`, a second planner with the same seed plans towards goal 1 without
//!   moving for that long, and the cost of its path to the goal is recorded (the paper does
//!   not report this; the issue asks for it).

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, bail};
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::clock::Clock;
use bi_am_rrt::{Config, RewireMode};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;
use serde::Serialize;

use crate::clock::{ClockKind, VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock};
use crate::maps::Scenario;
use crate::sim::{Prepared, drive, with_planner};
use crate::stats::{mean, median};

/// Which goals a run drives through.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum)]
pub enum Goals {
    /// Start to goal 1 (the Bi-AM-RRT* paper's static experiment).
    First,
    /// The whole sequence (the AM-RRT* paper's benchmark).
    All,
}

/// Everything the runner needs.
pub struct ExperimentArgs {
    /// Scenarios to run.
    pub scenarios: Vec<Scenario>,
    /// Planner configurations (Table 1 names).
    pub planners: Vec<Config>,
    /// Runs per planner and scenario.
    pub repeats: u32,
    /// Clock.
    pub clock: ClockKind,
    /// Goals.
    pub goals: Goals,
    /// First seed.
    pub seed: u64,
    /// Parallel jobs.
    pub jobs: Option<usize>,
    /// Reference-style rewiring budgets.
    pub faithful: bool,
    /// Keep the reverse tree's branches at the meet (`Config::keep_reverse_branches`).
    pub keep_reverse_branches: bool,
    /// Stop runs once the goal is in the tree.
    pub search_only: bool,
    /// Anytime measurement budget in ms (0: none).
    pub anytime_ms: u64,
    /// Diffusion table layout.
    pub table: crate::diffusion::TableOptions,
    /// Overrides every planner's `t_exp` (the paper: 150 ms).
    pub t_exp: Option<Duration>,
    /// Output directory.
    pub out: PathBuf,
}

/// `all` or a comma-separated list of Table 1 names.
pub fn parse_planners(spec: &str) -> Result<Vec<Config>> {
    if spec == "all" {
        return Ok(Config::table1().to_vec());
    }
    spec.split(',')
        .map(|name| {
            let name = name.trim();
            // Any case: `bi-am-rrt*(d)` is `Bi-AM-RRT*(D)`.
            let found = Config::table1()
                .into_iter()
                .chain(Config::table1().map(Config::tuned))
                .find(|c| c.name().to_string().eq_ignore_ascii_case(name));
            found.with_context(|| {
                let all: Vec<String> = Config::table1()
                    .iter()
                    .map(|c| c.name().to_string())
                    .collect();
                format!(
                    "unknown planner {name:?}; Table 1 names are {} (each also with the \
                     suffix \" tuned\")",
                    all.join(", ")
                )
            })
        })
        .collect()
}

/// One row of `runs.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub planner: String,
    pub scenario: String,
    pub goal_index: usize,
    pub seed: u64,
    pub reached: bool,
    pub search_time_s: Option<f64>,
    pub path_length_m: f32,
    /// The leg's exact optimum (from where the agent stood when the goal was set).
    pub optimal_m: Option<f32>,
    /// `path_length_m / optimal_m` for a reached goal.
    pub travelled_ratio: Option<f32>,
    pub collisions: u32,
    pub nodes_at_goal: Option<usize>,
    pub calls: u32,
    pub cost_at_start_m: Option<f32>,
    pub anytime_cost_m: Option<f32>,
    pub final_nodes: usize,
    pub clock: ClockKind,
    pub run_wall_s: f64,
}

/// One row of `summary.csv`.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    pub planner: String,
    pub scenario: String,
    pub goal_index: usize,
    pub runs: usize,
    pub reached: usize,
    pub collisions: u32,
    #[serde(serialize_with = "short")]
    pub search_time_median_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub search_time_mean_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_median_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_mean_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_median: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_max: Option<f64>,
    #[serde(serialize_with = "short")]
    pub nodes_at_goal_median: Option<f64>,
    #[serde(serialize_with = "short")]
    pub anytime_cost_median_m: Option<f64>,
}

/// A statistic in the files at the precision of its `f32` inputs (shortest `f32` form:
/// `68.88539`, not the `68.88539123535156` of its `f64` sum).
fn short<S: serde::Serializer>(v: &Option<f64>, s: S) -> Result<S::Ok, S::Error> {
    match v {
        Some(x) => s.serialize_some(&(*x as f32)),
        None => s.serialize_none(),
    }
}

/// Runs one planner on one scenario with one seed and returns its rows.
pub fn one_run(prep: &Prepared, cfg: Config, seed: u64, args: &ExperimentArgs) -> Result<Vec<Row>> {
    let wall = Instant::now();
    let goals: Vec<usize> = match args.goals {
        Goals::First => vec![0],
        Goals::All => (0..prep.scenario.goals.len()).collect(),
    };
    let protocol = Protocol {
        stop_when_found: args.search_only,
        ..Protocol::default()
    };
    let (runs, final_nodes) = with_planner(prep, cfg, seed, |p| {
        let runs = match args.clock {
            ClockKind::Wall => drive(
                p,
                prep,
                &WallClock::new(),
                &goals,
                &protocol,
                |_, _, _, _| {},
            )?,
            ClockKind::Virtual => drive(
                p,
                prep,
                &virtual_clock(VIRTUAL_NS_PER_UNIT),
                &goals,
                &protocol,
                |_, _, _, _| {},
            )?,
        };
        Ok((runs, p.tree().len()))
    })?;
    let anytime = if args.anytime_ms > 0 {
        let mut c = cfg;
        c.t_exp = Duration::from_millis(args.anytime_ms);
        with_planner(prep, c, seed, |p| {
            p.set_goal(prep.scenario.goals[0])
                .map_err(|e| anyhow::anyhow!("{e}"))?;
            let progress = match args.clock {
                ClockKind::Wall => p.grow(&WallClock::new()),
                ClockKind::Virtual => p.grow(&virtual_clock(VIRTUAL_NS_PER_UNIT)),
            };
            Ok(progress.goal_cost.filter(|c| !c.blocked).map(|c| c.length))
        })?
    } else {
        None
    };
    let run_wall_s = wall.elapsed().as_secs_f64();
    Ok(runs
        .iter()
        .map(|g| {
            let any = if g.goal_index == 0 { anytime } else { None };
            row(prep, cfg, seed, g, args.clock, final_nodes, any, run_wall_s)
        })
        .collect())
}

/// The row of one goal of a run.
#[allow(clippy::too_many_arguments)]
pub fn row(
    prep: &Prepared,
    cfg: Config,
    seed: u64,
    g: &crate::sim::GoalRun,
    clock: ClockKind,
    final_nodes: usize,
    anytime_cost_m: Option<f32>,
    run_wall_s: f64,
) -> Row {
    let optimal = prep.optima().get(g.goal_index).copied().flatten();
    Row {
        planner: cfg.name().to_string(),
        scenario: prep.scenario.name.clone(),
        goal_index: g.goal_index + 1,
        seed,
        reached: g.result.reached,
        search_time_s: g.search_s,
        path_length_m: g.result.travelled,
        optimal_m: optimal.map(|o| o as f32),
        travelled_ratio: optimal
            .filter(|_| g.result.reached)
            .map(|o| (g.result.travelled as f64 / o) as f32),
        collisions: g.result.collisions,
        nodes_at_goal: g.result.nodes_at_goal,
        calls: g.result.calls,
        cost_at_start_m: g.result.cost_at_start,
        anytime_cost_m,
        final_nodes,
        clock,
        run_wall_s,
    }
}

/// Groups rows by planner, scenario and goal, in first-seen order.
pub fn summarise(rows: &[Row]) -> Vec<Summary> {
    let mut keys: Vec<(String, String, usize)> = Vec::new();
    for r in rows {
        let k = (r.planner.clone(), r.scenario.clone(), r.goal_index);
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(planner, scenario, goal_index)| {
            let group: Vec<&Row> = rows
                .iter()
                .filter(|r| {
                    r.planner == planner && r.scenario == scenario && r.goal_index == goal_index
                })
                .collect();
            let reached: Vec<&&Row> = group.iter().filter(|r| r.reached).collect();
            let mut search: Vec<f64> = group.iter().filter_map(|r| r.search_time_s).collect();
            let mut len: Vec<f64> = reached.iter().map(|r| r.path_length_m as f64).collect();
            let mut nodes: Vec<f64> = group
                .iter()
                .filter_map(|r| r.nodes_at_goal.map(|n| n as f64))
                .collect();
            let mut any: Vec<f64> = group
                .iter()
                .filter_map(|r| r.anytime_cost_m.map(|c| c as f64))
                .collect();
            let mut ratio: Vec<f64> = reached
                .iter()
                .filter_map(|r| r.travelled_ratio.map(f64::from))
                .collect();
            let ratio_max = ratio.iter().copied().reduce(f64::max);
            Summary {
                travelled_ratio_median: median(&mut ratio),
                travelled_ratio_max: ratio_max,
                runs: group.len(),
                reached: reached.len(),
                collisions: group.iter().map(|r| r.collisions).sum(),
                search_time_mean_s: mean(&search),
                search_time_median_s: median(&mut search),
                path_length_mean_m: mean(&len),
                path_length_median_m: median(&mut len),
                nodes_at_goal_median: median(&mut nodes),
                anytime_cost_median_m: median(&mut any),
                planner,
                scenario,
                goal_index,
            }
        })
        .collect()
}

fn fmt_opt(v: Option<f64>, scale: f64, prec: usize) -> String {
    v.map_or_else(|| "-".into(), |x| format!("{:.*}", prec, x * scale))
}

/// Runs the experiment and writes its files.
pub fn run(args: &ExperimentArgs) -> Result<()> {
    if args.scenarios.is_empty() || args.planners.is_empty() {
        bail!("nothing to run");
    }
    let mut planners = args.planners.clone();
    if args.faithful {
        planners
            .iter_mut()
            .for_each(|c| c.rewire_mode = RewireMode::Faithful);
    }
    if let Some(t) = args.t_exp {
        planners.iter_mut().for_each(|c| c.t_exp = t);
    }
    if args.keep_reverse_branches {
        planners
            .iter_mut()
            .for_each(|c| c.keep_reverse_branches = true);
    }
    std::fs::create_dir_all(&args.out)?;
    let jobs = args
        .jobs
        .unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(jobs)
        .stack_size(32 << 20)
        .build()?;
    let preps: Vec<Prepared> = args
        .scenarios
        .iter()
        .cloned()
        .map(|s| Prepared::with_table(s, args.table))
        .collect();
    // Bake what the planners need before timing anything.
    let needs_d = planners
        .iter()
        .any(|c| c.metric == bi_am_rrt::MetricKind::Diffusion);
    pool.install(|| {
        preps.par_iter().try_for_each(|p| -> Result<()> {
            if needs_d {
                p.diffusion()?;
            }
            p.graph();
            p.optima();
            Ok(())
        })
    })?;
    for p in &preps {
        if let (Some(s), Ok(b)) = (p.bake_seconds.get(), p.diffusion()) {
            eprintln!(
                "{}: diffusion table ({} bytes) baked in {s:.3} s",
                p.scenario.name,
                b.table.len()
            );
        }
    }
    let mut jobs_list = Vec::new();
    for (si, _) in preps.iter().enumerate() {
        for cfg in &planners {
            for r in 0..args.repeats {
                jobs_list.push((si, *cfg, args.seed + r as u64));
            }
        }
    }
    let bar = ProgressBar::new(jobs_list.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} runs, eta {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let rows = Mutex::new(Vec::new());
    let result: Result<()> = pool.install(|| {
        jobs_list.par_iter().try_for_each(|&(si, cfg, seed)| {
            let r = one_run(&preps[si], cfg, seed, args).with_context(|| {
                format!("{} on {} seed {seed}", cfg.name(), preps[si].scenario.name)
            })?;
            rows.lock()
                .map_err(|_| anyhow::anyhow!("poisoned"))?
                .extend(r);
            bar.inc(1);
            Ok(())
        })
    });
    bar.finish();
    result?;
    let mut rows = rows.into_inner().map_err(|_| anyhow::anyhow!("poisoned"))?;
    // Deterministic file order whatever the scheduling.
    let order = |r: &Row| {
        (
            preps.iter().position(|p| p.scenario.name == r.scenario),
            planners
                .iter()
                .position(|c| c.name().to_string() == r.planner),
            r.seed,
            r.goal_index,
        )
    };
    rows.sort_by_key(order);
    let mut w = csv::Writer::from_path(args.out.join("runs.csv"))?;
    for r in &rows {
        w.serialize(r)?;
    }
    w.flush()?;
    let summary = summarise(&rows);
    let mut w = csv::Writer::from_path(args.out.join("summary.csv"))?;
    for s in &summary {
        w.serialize(s)?;
    }
    w.flush()?;
    println!(
        "{:<22} {:<10} {:>4} {:>8} {:>5} {:>12} {:>12} {:>10} {:>10} {:>8} {:>8} {:>9}",
        "planner",
        "scenario",
        "goal",
        "reached",
        "coll",
        "search med",
        "search mean",
        "len med",
        "len mean",
        "/opt med",
        "/opt max",
        "nodes@g"
    );
    for s in &summary {
        println!(
            "{:<22} {:<10} {:>4} {:>5}/{:<2} {:>5} {:>10} ms {:>9} ms {:>8} m {:>8} m {:>8} {:>8} {:>9}",
            s.planner,
            s.scenario,
            s.goal_index,
            s.reached,
            s.runs,
            s.collisions,
            fmt_opt(s.search_time_median_s, 1e3, 2),
            fmt_opt(s.search_time_mean_s, 1e3, 2),
            fmt_opt(s.path_length_median_m, 1.0, 2),
            fmt_opt(s.path_length_mean_m, 1.0, 2),
            fmt_opt(s.travelled_ratio_median, 1.0, 4),
            fmt_opt(s.travelled_ratio_max, 1.0, 4),
            fmt_opt(s.nodes_at_goal_median, 1.0, 0),
        );
    }
    println!(
        "wrote {} and {}",
        args.out.join("runs.csv").display(),
        args.out.join("summary.csv").display()
    );
    Ok(())
}

/// Measures wall nanoseconds per unit of planner work over a few built-in runs.
pub fn calibrate(repeats: u32) -> Result<()> {
    let preps: Vec<Prepared> = crate::maps::builtin_scenarios()
        .into_iter()
        .map(Prepared::new)
        .collect();
    let mut ratios = Vec::new();
    for prep in &preps {
        for name in ["Bi-AM-RRT*(D)", "AM-RRT*(E)", "RT-RRT*"] {
            let cfg = Config::from_name(name).context("planner")?;
            for seed in 1..=repeats as u64 {
                let clock = WallClock::new();
                let t0 = clock.now();
                // Twenty calls: the search and the start of the drive (3 s of planning).
                let protocol = Protocol {
                    max_calls: 20,
                    ..Protocol::default()
                };
                with_planner(prep, cfg, seed, |p| {
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
    planners: &[Config],
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
                ("per-expansion", base.rewire_mode),
                ("faithful", RewireMode::Faithful),
            ] {
                let mut cfg = *base;
                cfg.rewire_mode = rewire;
                cfg.t_exp = Duration::from_millis(call_ms);
                with_planner(&prep, cfg, seed, |p| {
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
