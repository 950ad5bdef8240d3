//! The experiment matrix: planners x scenarios x repeats under the agent protocol, in parallel
//! on all cores, into a results folder (`results`): each run's rows are appended to
//! `runs.csv` as the run ends, so an interrupted matrix keeps its finished runs and
//! `--resume` does only the rest; `--shard K/N` runs a deterministic slice (for a job array
//! across machines) and `merge` joins the slices.
//!
//! Per run (seed = first seed + repeat index, the same seeds for every planner):
//! - the goal sequence (goal 1, or all goals) is driven under `bi_am_rrt::agent`'s protocol;
//! - with `--anytime-ms`, a second planner with the same seed plans towards goal 1 without
//!   moving for that long, and the cost of its path to the goal is recorded (the paper does
//!   not report this).

use crate::sim::planners::{Variant, as_printed_names};
use crate::sim::{paper_pace, row};
use std::collections::{BTreeMap, BTreeSet};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use anyhow::{Context, Result, anyhow, bail};
use bi_am_rrt::RewireMode;
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::clock::Clock as _;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

pub use crate::results::Goals;
use crate::results::{
    Manifest, MapTimes, Row, RowSink, RunKey, ScenarioId, Settings, Shard, Summary,
};
use crate::scenario::Scenario;
use crate::sim::clock::{ClockKind, VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock};
use crate::sim::{DiscTrack, Prepared, drive, with_planner};

/// What to do with a results folder that already holds an experiment.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Existing {
    /// Stop with an error (the default: hours of results are not overwritten by mistake).
    Refuse,
    /// Run only the runs the folder does not hold yet (same settings required).
    Resume,
    /// Delete its results and start again.
    Overwrite,
}

/// Everything the runner needs.
pub struct ExperimentArgs {
    /// Scenarios to run.
    pub scenarios: Vec<Scenario>,
    /// Planner configurations (Table 1 names).
    pub planners: Vec<Variant>,
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
    /// The agent's wait counted from when the goal is set (`--wait-from-set`).
    pub wait_from_set: bool,
    /// The reference's agent rule (`--move-when-blocked`, `Protocol::move_when_blocked`).
    pub move_when_blocked: bool,
    /// Work per call (`--pace`).
    pub pace: crate::results::Pace,
    /// Skip each leg's exact optimum (`--no-optimum`: `optimal_m` and `travelled_ratio` empty).
    pub no_optimum: bool,
    /// Parts of Algorithms 4 and 6 as printed (`--as-printed`).
    pub as_printed: bi_am_rrt::AsPrinted,
    /// The paper's Meet over every pair (`--meet-all-pairs`).
    pub meet_all_pairs: bool,
    /// Fig. 7: radius of a disc dropped on goal 1's path (`--obstacle`).
    pub obstacle: Option<f32>,
    /// Stop runs once the goal is in the tree.
    pub search_only: bool,
    /// Anytime measurement budget in ms (0: none).
    pub anytime_ms: u64,
    /// Diffusion table layout.
    pub table: crate::metric::diffusion::TableOptions,
    /// Overrides every planner's `t_exp` (the paper: 150 ms).
    pub t_exp: Option<Duration>,
    /// Only this slice of the matrix.
    pub shard: Option<Shard>,
    /// An output folder that already holds results.
    pub existing: Existing,
    /// Output directory.
    pub out: PathBuf,
}

/// The planners as the runs use them (the switches applied).
fn planners_of(args: &ExperimentArgs) -> Result<Vec<Variant>> {
    args.planners
        .iter()
        .map(|v| {
            let mut v = v.clone();
            // On the named configuration, before its lengths are fitted and its overrides
            // applied (an override of the same value wins).
            v.edit_named(|c| {
                if args.faithful {
                    c.rewiring.mode = RewireMode::Faithful;
                }
                if let Some(t) = args.t_exp {
                    c.budget.t_exp = t;
                }
                c.as_printed = args.as_printed;
                c.as_printed.meet_all_pairs |= args.meet_all_pairs;
                if args.pace == crate::results::Pace::Paper {
                    paper_pace(c);
                }
            })?;
            Ok(v)
        })
        .collect()
}

/// The settings a results folder records for these arguments.
pub fn settings(args: &ExperimentArgs) -> Result<Settings> {
    let t = &args.table;
    Ok(Settings {
        scenarios: args.scenarios.iter().map(ScenarioId::of).collect(),
        planners: args.planners.iter().map(|v| v.name.clone()).collect(),
        repeats: args.repeats,
        seed: args.seed,
        clock: args.clock,
        goals: args.goals,
        faithful: args.faithful,
        wait_from_set: args.wait_from_set,
        move_when_blocked: args.move_when_blocked,
        pace: args.pace,
        as_printed: as_printed_names(args.as_printed),
        meet_all_pairs: args.meet_all_pairs,
        obstacle_m: args.obstacle,
        search_only: args.search_only,
        anytime_ms: args.anytime_ms,
        t_exp_ms: args.t_exp.map(|d| d.as_secs_f64() * 1e3),
        table: format!(
            "{:?} {:?} coarsen {} max_bytes {}",
            t.kind, t.layout, t.coarsen, t.max_bytes
        ),
        configs: planners_of(args)?
            .iter()
            .map(|v| crate::results::config_record(&v.cfg.cfg))
            .collect(),
    })
}

/// Runs one planner on one scenario with one seed and returns its rows.
pub fn one_run(
    prep: &Prepared,
    planner: &Variant,
    seed: u64,
    args: &ExperimentArgs,
) -> Result<Vec<Row>> {
    let wall = Instant::now();
    let goals: Vec<usize> = match args.goals {
        Goals::First => vec![0],
        Goals::All => (0..prep.scenario.goals.len()).collect(),
    };
    let protocol = Protocol {
        stop_when_found: args.search_only,
        wait_from_set: args.wait_from_set,
        move_when_blocked: args.move_when_blocked,
        ..Protocol::default()
    };
    // Fig. 7: a disc dropped on goal 1's path (the first goal driven).
    let mut disc = args.obstacle.map(DiscTrack::new);
    let first = goals[0];
    let leg_start = crate::metric::optimum::leg_starts(&prep.scenario)[first];
    let mut track = |p: &mut crate::sim::SimPlanner<'_, '_>, gi: usize, agent, now_s: f64| {
        if let Some(d) = disc.as_mut().filter(|_| gi == first) {
            d.on_call(p, agent, leg_start, now_s);
        }
    };
    // Named -> fitted to the map -> the overrides.
    let cfg = planner.config_for(prep)?;
    let (runs, final_nodes) = with_planner(prep, cfg, seed, |p| {
        let runs = match args.clock {
            ClockKind::Wall => {
                let clock = WallClock::new();
                let hz = clock.ticks_per_second() as f64;
                drive(p, prep, &clock, &goals, &protocol, |p, gi, a, _| {
                    track(p, gi, a, clock.now() as f64 / hz)
                })?
            }
            ClockKind::Cpu => {
                let clock = crate::sim::clock::CpuClock::new();
                let hz = clock.ticks_per_second() as f64;
                drive(p, prep, &clock, &goals, &protocol, |p, gi, a, _| {
                    track(p, gi, a, clock.now() as f64 / hz)
                })?
            }
            ClockKind::CpuMono => {
                let clock = crate::sim::clock::CpuMonoClock::new();
                let hz = clock.ticks_per_second() as f64;
                drive(p, prep, &clock, &goals, &protocol, |p, gi, a, _| {
                    track(p, gi, a, clock.now() as f64 / hz)
                })?
            }
            ClockKind::Virtual => {
                let clock = virtual_clock(VIRTUAL_NS_PER_UNIT);
                let hz = clock.ticks_per_second() as f64;
                // At the paper's pace every call lasts its full t_exp, as in the paper's
                // Python: the clock moves on to where the call's budget ends.
                let paper = args.pace == crate::results::Pace::Paper;
                let t_exp = clock.ticks(cfg.cfg.budget.t_exp);
                let call_end = std::cell::Cell::new(clock.peek());
                drive(p, prep, &clock, &goals, &protocol, |p, gi, a, _| {
                    if paper {
                        let end = call_end.get().saturating_add(t_exp).max(clock.peek());
                        clock.set(end);
                        call_end.set(end);
                    }
                    track(p, gi, a, clock.peek() as f64 / hz);
                })?
            }
        };
        Ok((runs, p.tree().len()))
    })?;
    let anytime = if args.anytime_ms > 0 {
        let mut c = cfg;
        c.cfg.budget.t_exp = Duration::from_millis(args.anytime_ms);
        with_planner(prep, c, seed, |p| {
            p.set_goal(prep.scenario.goals[0])
                .map_err(|e| anyhow!("{e}"))?;
            let progress = match args.clock {
                ClockKind::Wall => p.grow(&WallClock::new()),
                ClockKind::Cpu => p.grow(&crate::sim::clock::CpuClock::new()),
                ClockKind::CpuMono => p.grow(&crate::sim::clock::CpuMonoClock::new()),
                ClockKind::Virtual => p.grow(&virtual_clock(VIRTUAL_NS_PER_UNIT)),
            };
            Ok(progress.goal_cost.filter(|c| !c.blocked).map(|c| c.length))
        })?
    } else {
        None
    };
    let run_wall_s = wall.elapsed().as_secs_f64();
    let t_exp = cfg.cfg.budget.t_exp.as_secs_f64();
    Ok(runs
        .iter()
        .map(|g| {
            let any = if g.goal_index == 0 { anytime } else { None };
            let mut r = row(prep, cfg, seed, g, args.clock, final_nodes, any, run_wall_s);
            r.planner = planner.name.clone();
            // The agent does not move in a search: no path (an empty field, not 0 m).
            if args.search_only {
                r.path_length_m = None;
            }
            if let Some(d) = disc.as_ref().filter(|_| g.goal_index == first) {
                d.finish(&mut r, prep, prep.scenario.goals[first]);
            }
            // At the paper's pace the call in which the goal joined lasted its full t_exp
            // (the clock moves on after the reading): its end is a whole number of calls.
            if args.pace == crate::results::Pace::Paper {
                r.search_time_call_end_s = r
                    .search_time_call_end_s
                    .map(|s| (s / t_exp - 1e-9).ceil().max(1.0) * t_exp);
            }
            r
        })
        .collect())
}

/// The runs `rows` holds in full: every goal the run drives, or up to the first goal it did
/// not reach. Rows of a run cut short by an interruption do not count (the run is done again).
fn complete_runs(rows: &[Row], scenarios: &[Scenario], goals: Goals) -> BTreeSet<RunKey> {
    let mut by_run: BTreeMap<RunKey, Vec<&Row>> = BTreeMap::new();
    for r in rows {
        by_run.entry(r.key()).or_default().push(r);
    }
    by_run
        .into_iter()
        .filter(|(k, mine)| {
            let wanted = match goals {
                Goals::First => 1,
                Goals::All => scenarios
                    .iter()
                    .find(|s| s.name == k.scenario)
                    .map_or(usize::MAX, |s| s.goals.len()),
            };
            let last = mine.iter().map(|r| r.goal_index).max().unwrap_or(0);
            let contiguous =
                (1..=last).all(|g| mine.iter().filter(|r| r.goal_index == g).count() == 1);
            contiguous && (last >= wanted || mine.iter().any(|r| !r.reached))
        })
        .map(|(k, _)| k)
        .collect()
}

/// Bakes what the planners need and times each map's processing.
fn prepare(
    preps: &[Prepared],
    planners: &[Variant],
    pool: &rayon::ThreadPool,
) -> Result<Vec<MapTimes>> {
    let needs_d = planners
        .iter()
        .any(|v| v.named.metric == bi_am_rrt::MetricKind::Diffusion);
    pool.install(|| {
        preps
            .par_iter()
            .map(|p| -> Result<MapTimes> {
                let table_bytes = if needs_d {
                    Some(p.diffusion()?.table.len())
                } else {
                    None
                };
                let t0 = Instant::now();
                let graph = p.graph();
                let graph_s = t0.elapsed().as_secs_f64();
                let (geodesic_field_s, _) = crate::metric::bake::geodesic_costs(&graph, 5, false);
                let t0 = Instant::now();
                p.optima();
                let optima_s = t0.elapsed().as_secs_f64();
                let g = &p.scenario.map;
                Ok(MapTimes {
                    scenario: p.scenario.name.clone(),
                    cols: g.width,
                    rows: g.height,
                    cell_m: f32::from_bits(g.cell_bits),
                    diffusion_bake_s: p.bake_seconds.get().copied(),
                    table_bytes,
                    graph_s,
                    geodesic_field_s,
                    optima_s,
                })
            })
            .collect()
    })
}

/// What a call of `run` did.
#[derive(Debug)]
pub struct Outcome {
    /// Runs of the folder's matrix (its shard).
    pub runs: usize,
    /// Runs done by this call.
    pub ran: usize,
    /// The folder's summary.
    pub summary: Vec<Summary>,
}

/// Runs the experiment (or what the folder still lacks) and writes its files.
pub fn run(args: &ExperimentArgs) -> Result<Outcome> {
    if args.scenarios.is_empty() || args.planners.is_empty() || args.repeats == 0 {
        bail!("nothing to run (no scenario, no planner or no repeat)");
    }
    if args.pace == crate::results::Pace::Paper && args.clock != ClockKind::Virtual {
        bail!("--pace paper needs --clock virtual (each call is made to last its full t_exp)");
    }
    let planners = planners_of(args)?;
    let out = &args.out;
    std::fs::create_dir_all(out).with_context(|| format!("{}", out.display()))?;
    let _lock = crate::results::FolderLock::take(out)?;
    let settings = settings(args)?;
    let old = crate::results::Manifest::read(out)?;
    let has_rows = out.join(crate::results::RUNS).exists();
    match (args.existing, &old) {
        (Existing::Refuse, _) if old.is_some() || has_rows => bail!(
            "{} already holds an experiment's results: --resume continues it (same settings), \
             --overwrite deletes them and starts again, or choose another --out",
            out.display()
        ),
        (Existing::Resume, Some(m)) => {
            if let Some(d) = settings.difference(&m.settings) {
                bail!(
                    "--resume: {} was run with other settings ({d})",
                    out.display()
                );
            }
            if m.shard != args.shard {
                bail!(
                    "--resume: {} holds shard {}, not {}",
                    out.display(),
                    m.shard.map_or("all".into(), |s| s.to_string()),
                    args.shard.map_or("all".into(), |s| s.to_string())
                );
            }
        }
        (Existing::Resume, None) if has_rows => bail!(
            "--resume: {} has runs.csv but no experiment.json",
            out.display()
        ),
        (Existing::Overwrite, _) => {
            for f in [
                crate::results::MANIFEST,
                crate::results::RUNS,
                "runs.json",
                "summary.csv",
                "summary.json",
            ] {
                let p = out.join(f);
                if p.exists() {
                    std::fs::remove_file(&p).with_context(|| format!("{}", p.display()))?;
                }
            }
        }
        _ => {}
    }
    let mut rows = if args.existing == Existing::Resume {
        crate::results::read_rows(out, true)?
    } else {
        Vec::new()
    };
    let done = complete_runs(&rows, &args.scenarios, args.goals);
    rows.retain(|r| done.contains(&r.key()));

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
        .map(|s| {
            let p = Prepared::with_table(s, args.table);
            if args.no_optimum {
                p.without_optimum()
            } else {
                p
            }
        })
        .collect();
    // Legs through long narrow corridors, said before the runs (issue 42).
    for prep in &preps {
        for cfg in &planners {
            prep.warn_narrow_legs(cfg.config_for(prep)?, crate::sim::NODES, &|k| {
                Some(format!(
                    "within the leg's {} calls",
                    prep.leg_calls(k, &Default::default())
                ))
            });
        }
    }
    // Bake what the planners need before timing anything.
    let maps = prepare(&preps, &planners, &pool)?;
    for m in &maps {
        if let (Some(s), Some(b)) = (m.diffusion_bake_s, m.table_bytes) {
            eprintln!(
                "{}: diffusion table ({b} bytes) baked in {s:.3} s",
                m.scenario
            );
        }
    }
    let manifest = Manifest {
        tool: format!("host-sim {}", env!("CARGO_PKG_VERSION")),
        settings,
        shard: args.shard,
        maps,
    };
    manifest.write(out)?;
    // Rewrite the kept rows (an interrupted run's partial rows are gone), then append.
    if args.existing == Existing::Resume {
        crate::results::write_rows(out, &rows)?;
    }
    let wanted = manifest.runs();
    let todo: Vec<(usize, &Variant, u64)> = wanted
        .iter()
        .filter(|k| !done.contains(k))
        .map(|k| {
            let si = preps
                .iter()
                .position(|p| p.scenario.name == k.scenario)
                .context("scenario")?;
            let cfg = planners
                .iter()
                .find(|v| v.name == k.planner)
                .context("planner")?;
            Ok((si, cfg, k.seed))
        })
        .collect::<Result<_>>()?;
    eprintln!(
        "{}: {} runs{}, {} already done, {} to run on {jobs} threads",
        out.display(),
        wanted.len(),
        args.shard
            .map(|s| format!(" (shard {s})"))
            .unwrap_or_default(),
        wanted.len() - todo.len(),
        todo.len()
    );
    let bar = ProgressBar::new(todo.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{elapsed_precise} [{bar:40}] {pos}/{len} runs, eta {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let sink = Mutex::new(RowSink::open(out)?);
    let fresh = Mutex::new(Vec::new());
    let result: Result<()> = pool.install(|| {
        todo.par_iter().try_for_each(|&(si, cfg, seed)| {
            let r = one_run(&preps[si], cfg, seed, args).with_context(|| {
                format!("{} on {} seed {seed}", cfg.name, preps[si].scenario.name)
            })?;
            sink.lock().map_err(|_| anyhow!("poisoned"))?.append(&r)?;
            // Off a terminal the bar draws nothing: a plain line per run instead.
            if bar.is_hidden() {
                let (done, what) = if args.search_only {
                    let found = r.iter().filter(|row| row.search_time_s.is_some());
                    (found.count(), "found")
                } else {
                    (r.iter().filter(|row| row.reached).count(), "reached")
                };
                eprintln!(
                    "run {}/{}: {} on {} seed {seed}: {done}/{} goals {what} ({:.1} s)",
                    bar.position() + 1,
                    bar.length().unwrap_or(0),
                    cfg.name,
                    preps[si].scenario.name,
                    r.len(),
                    bar.elapsed().as_secs_f64()
                );
            }
            fresh.lock().map_err(|_| anyhow!("poisoned"))?.extend(r);
            bar.inc(1);
            Ok(())
        })
    });
    bar.finish();
    result?;
    rows.extend(fresh.into_inner().map_err(|_| anyhow!("poisoned"))?);
    let summary = crate::results::write_complete(out, &manifest.settings, &mut rows)?;
    print_summary(&summary, args.search_only);
    println!(
        "wrote {} ({} runs), runs.json, summary.csv and summary.json",
        out.join(crate::results::RUNS).display(),
        wanted.len()
    );
    Ok(Outcome {
        runs: wanted.len(),
        ran: todo.len(),
        summary,
    })
}

fn fmt_opt(v: Option<f64>, scale: f64, prec: usize) -> String {
    v.map_or_else(|| "-".into(), |x| format!("{:.*}", prec, x * scale))
}

/// Prints the summary as a table (medians and interquartile ranges); a `--search-only` run's
/// counts goals found (the agent does not move to reach them).
pub fn print_summary(summary: &[Summary], search_only: bool) {
    println!(
        "{:<22} {:<10} {:>4} {:>8} {:>5} {:>24} {:>24} {:>8} {:>8} {:>9}",
        "planner",
        "scenario",
        "goal",
        if search_only { "found" } else { "reached" },
        "coll",
        "search ms med [IQR]",
        "path m med [IQR]",
        "/opt med",
        "/opt max",
        "nodes@g"
    );
    for s in summary {
        println!(
            "{:<22} {:<10} {:>4} {:>5}/{:<2} {:>5} {:>24} {:>24} {:>8} {:>8} {:>9}",
            s.planner,
            s.scenario,
            s.goal_index,
            if search_only { s.found } else { s.reached },
            s.runs,
            s.collisions,
            format!(
                "{} [{}, {}]",
                fmt_opt(s.search_time_median_s, 1e3, 2),
                fmt_opt(s.search_time_q1_s, 1e3, 2),
                fmt_opt(s.search_time_q3_s, 1e3, 2)
            ),
            format!(
                "{} [{}, {}]",
                fmt_opt(s.path_length_median_m, 1.0, 2),
                fmt_opt(s.path_length_q1_m, 1.0, 2),
                fmt_opt(s.path_length_q3_m, 1.0, 2)
            ),
            fmt_opt(s.travelled_ratio_median, 1.0, 4),
            fmt_opt(s.travelled_ratio_max, 1.0, 4),
            fmt_opt(s.nodes_at_goal_median, 1.0, 0),
        );
    }
}
