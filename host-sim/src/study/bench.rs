//! The planner benchmark: every leg of a scenario, a fresh planner at the leg's start, the
//! thread's CPU time as the measure (read cheaply by the planner: [`CpuMonoClock`]), N seeds
//! per planner. Measured per run: CPU time
//! from `set_goal` to the goal joining the tree and the length of that first path, the tree's
//! path cost after fixed CPU budgets (default 0.01, 0.1 and 1 s), nodes, expansions per second
//! and clock readings per expansion. Lengths are divided by the leg's exact optimum
//! ([`crate::metric::optimum`]).
//!
//! The planner only grows (`Planner::grow`, the agent stands at the leg's start): this is the
//! static query OMPL's planners answer, measured the way `../shared/anchors/reference-figures.md`
//! measures them, so the figures compare. Variants in one run are interleaved leg by leg (all
//! seeds of one variant, then the next), so a noisy machine affects them alike; not seed by
//! seed, since a run that follows a run on the same seed replays its first steps on warm
//! caches and branch predictors and measured up to 20 % faster.
//!
//! Summary: per map and planner, the median over legs of the per-leg medians over seeds (the
//! reference figures' rule), written as `summary.csv` and printed as a Markdown table.

use std::io::Write as _;
use std::path::PathBuf;
use std::time::Duration;

use anyhow::{Context, Result, anyhow};
use bi_am_rrt::Named;
use serde::{Deserialize, Serialize};

use crate::metric::optimum::leg_starts;
use crate::results::stats::median;
use crate::results::table::{Cell, Column, Table};
use crate::scenario::Scenario;
use crate::sim::clock::{CpuClock, CpuMonoClock, VIRTUAL_NS_PER_UNIT, virtual_clock};
use crate::sim::planners::Variant;
use crate::sim::{BUCKETS, Prepared, SizedPlanner, with_planner_in};
use bi_am_rrt::Storage;

/// What to run.
pub struct BenchArgs {
    /// Scenarios (every leg of each).
    pub scenarios: Vec<Scenario>,
    /// Legs to run (1-based), all when empty.
    pub legs: Vec<usize>,
    /// Planner variants.
    pub variants: Vec<Variant>,
    /// Seeds per leg and variant (seeds 1..=seeds).
    pub seeds: u64,
    /// CPU budgets at which the tree's path cost is read, in seconds, ascending.
    pub budgets: Vec<f64>,
    /// Nodes per tree: 2048, 4096, 8192, 16384 or 65000 (`None`: [`Prepared::arena_for`] each
    /// planner on each map, as `run` does).
    pub nodes: Option<usize>,
    /// Output directory.
    pub out: PathBuf,
    /// Diffusion table layout.
    pub table: crate::metric::diffusion::TableOptions,
    /// OMPL's RRT-Connect harness (`benches/ompl`), run on every leg beside our planners.
    pub ompl: Option<PathBuf>,
    /// The planners' clock: thread CPU time (read cheaply, or a system call at every
    /// reading), the monotonic clock, or the virtual clock (work units at
    /// [`VIRTUAL_NS_PER_UNIT`] ns each: repeatable figures for comparing algorithmic changes,
    /// blind to how fast a unit of work runs).
    pub clock: BenchClock,
    /// Cold queries: caches flushed before every measured query ([`flush_caches`]; the
    /// OMPL harness does the same with `--cold`).
    pub cold: bool,
    /// Each of our runs ends at its first solution, in calls of at most 50 us (or at the last
    /// budget without one), as each of RRT-Connect's runs ends at its: the
    /// next query's caches are then those a first-solution search left, on both sides. No
    /// costs are read.
    pub until_first: bool,
    /// Also run the grid planners (A* on the 8-connected grid and Theta*) on every leg.
    pub grid: bool,
}

/// Bytes written and read back by [`flush_caches`]: several times any last-level cache of
/// the machines this runs on.
const FLUSH_BYTES: usize = 64 << 20;

/// Evicts the caches (and the TLB entries) a query could reuse: 64 MiB written and read
/// back, the sum kept from the optimiser.
pub fn flush_caches() {
    use std::sync::OnceLock;
    static BUF: OnceLock<std::sync::Mutex<Vec<u64>>> = OnceLock::new();
    let buf = BUF.get_or_init(|| std::sync::Mutex::new(vec![0; FLUSH_BYTES / 8]));
    let mut v = buf.lock().unwrap_or_else(|e| e.into_inner());
    let mut sum = 0u64;
    for (i, w) in v.iter_mut().enumerate() {
        *w = w.wrapping_add(i as u64);
        sum = sum.wrapping_add(*w);
    }
    std::hint::black_box(sum);
}

/// A bench run's clock: [`crate::sim::clock::ClockKind`] (`cpu-mono`, the default: thread CPU
/// time as the measurement, the planner's readings as cheap as the monotonic clock's,
/// [`CpuMonoClock`]; `cpu`, a thread CPU time system call of about 0.4-0.8 us at every reading;
/// `wall`, the monotonic clock, a vDSO read of about 30 ns and the clock OMPL's timed
/// termination condition reads in its loop; `virtual`).
pub type BenchClock = crate::sim::clock::ClockKind;

/// A bench run's clock, counting its readings.
enum RunClock {
    Cpu(CpuClock),
    CpuMono(CpuMonoClock),
    Steady(std::time::Instant, std::cell::Cell<u64>),
    Virtual(bi_am_rrt::clock::FakeClock, std::cell::Cell<u64>),
}

impl RunClock {
    fn new(kind: BenchClock) -> Self {
        match kind {
            BenchClock::Cpu => Self::Cpu(CpuClock::new()),
            BenchClock::CpuMono => Self::CpuMono(CpuMonoClock::new()),
            BenchClock::Wall => Self::Steady(std::time::Instant::now(), std::cell::Cell::new(0)),
            BenchClock::Virtual => {
                Self::Virtual(virtual_clock(VIRTUAL_NS_PER_UNIT), std::cell::Cell::new(0))
            }
        }
    }

    fn reads(&self) -> u64 {
        match self {
            Self::Cpu(c) => c.reads(),
            Self::CpuMono(c) => c.reads(),
            Self::Steady(_, r) | Self::Virtual(_, r) => r.get(),
        }
    }
}

impl bi_am_rrt::clock::Clock for RunClock {
    fn now(&self) -> u64 {
        match self {
            Self::Cpu(c) => c.now(),
            Self::CpuMono(c) => c.now(),
            Self::Steady(t, r) => {
                r.set(r.get() + 1);
                t.elapsed().as_nanos() as u64
            }
            Self::Virtual(c, r) => {
                r.set(r.get() + 1);
                c.now()
            }
        }
    }
    fn ticks_per_second(&self) -> u64 {
        1_000_000_000
    }
    fn charge(&self, units: u32) {
        if let Self::Virtual(c, _) = self {
            c.charge(units);
        }
    }
}

/// One run: one leg, variant and seed.
#[derive(Clone, Debug, Serialize)]
pub struct BenchRow {
    pub map: String,
    pub leg: usize,
    pub planner: String,
    pub seed: u64,
    pub optimal_m: f64,
    /// CPU time from `set_goal` to the goal joining, in microseconds.
    pub first_us: Option<f64>,
    /// Length of the first path to the goal / optimum.
    pub first_ratio: Option<f64>,
    /// Forward tree nodes when the goal joined.
    pub first_nodes: Option<usize>,
    /// Path cost / optimum after each budget (one column per budget).
    pub cost_ratio: Vec<Option<f64>>,
    /// Forward tree nodes at the end.
    pub nodes: usize,
    /// Path cost / optimum at equal time: read at the end of the first `grow` call that ends
    /// at or after OMPL's RRT-Connect + simplify's median time on the leg in the same run
    /// (with `--ompl`; `None` without, or when we had no path then).
    pub equal_ratio: Option<f64>,
    /// When that reading was taken, in CPU microseconds from `set_goal`.
    pub equal_us: Option<f64>,
    /// Forward and reverse expansions per CPU second.
    pub expansions_per_s: f64,
    /// Clock readings per expansion.
    pub reads_per_expansion: f64,
    /// Whether an arena filled up.
    pub full: bool,
}

/// Runs the bench and writes `bench.csv`, `summary.csv` and `summary.md` into `args.out`.
pub fn run(args: &BenchArgs) -> Result<Vec<BenchRow>> {
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("creating {}", args.out.display()))?;
    let mut rows = Vec::new();
    let mut arenas = Arenas::default();
    let settings = BenchSettings {
        command: std::iter::once("host-sim".to_string())
            .chain(std::env::args().skip(1))
            .collect::<Vec<_>>()
            .join(" "),
        seeds: args.seeds,
        budgets: args.budgets.clone(),
        clock: clap::ValueEnum::to_possible_value(&args.clock)
            .map_or_else(|| format!("{:?}", args.clock), |v| v.get_name().to_string()),
        cold: args.cold,
        until_first: args.until_first,
        grid: args.grid,
        ompl: args.ompl.is_some(),
    };
    std::fs::write(
        args.out.join(SETTINGS_FILE),
        serde_json::to_string_pretty(&settings)?,
    )?;
    let mut csv = std::fs::File::create(args.out.join("bench.csv"))?;
    writeln!(csv, "{}", header(&args.budgets))?;
    for s in &args.scenarios {
        let prep = Prepared::with_table(s.clone(), args.table);
        if args
            .variants
            .iter()
            .any(|v| v.named.metric == bi_am_rrt::MetricKind::Diffusion)
        {
            prep.diffusion()?;
        }
        let fitted = args
            .variants
            .iter()
            .map(|v| v.config_for(&prep))
            .collect::<Result<Vec<Named>>>()?;
        for cfg in &fitted {
            let last = args.budgets.last().copied().unwrap_or(0.0);
            let nodes = args.nodes.unwrap_or_else(|| prep.arena_for(*cfg));
            prep.warn_narrow_legs(*cfg, nodes, &|k| {
                (args.legs.is_empty() || args.legs.contains(&(k + 1)))
                    .then(|| format!("within {last} s"))
            });
        }
        let optima = prep.optima();
        let starts = leg_starts(s);
        for (k, (&start, &goal)) in starts.iter().zip(&s.goals).enumerate() {
            let leg = k + 1;
            if !args.legs.is_empty() && !args.legs.contains(&leg) {
                continue;
            }
            let opt = optima[k].ok_or_else(|| anyhow!("{} leg {leg}: goal unreachable", s.name))?;
            let mut equal_at = None;
            if let Some(bin) = &args.ompl {
                let theirs = ompl_leg(bin, &args.out, s, leg, start, goal, opt, args)?;
                // Equal time: RRT-Connect + simplify's median over seeds on this leg.
                let mut t: Vec<f64> = theirs
                    .iter()
                    .filter(|r| r.planner == OMPL_RRT_CONNECT_SIMPLIFIED)
                    .map(|r| r.first_us.unwrap_or(f64::INFINITY))
                    .collect();
                equal_at = median(&mut t).filter(|t| t.is_finite()).map(|t| t * 1e-6);
                for row in theirs {
                    writeln!(csv, "{}", csv_line(&row))?;
                    rows.push(row);
                }
            }
            if args.grid {
                for row in grid_leg(s, leg, start, goal, opt, args) {
                    writeln!(csv, "{}", csv_line(&row))?;
                    rows.push(row);
                }
            }
            // Variant by variant, each block after an unrecorded warm-up run (seed 0, first
            // budget): see the module docs.
            for (v, &cfg) in args.variants.iter().zip(&fitted) {
                for seed in 0..=args.seeds {
                    let run = Run {
                        clock: args.clock,
                        prep: &prep,
                        cfg,
                        seed,
                        start,
                        goal,
                        budgets: if seed == 0 {
                            &args.budgets[..1]
                        } else {
                            &args.budgets[..]
                        },
                        cold: args.cold,
                        equal_at,
                        until_first: args.until_first,
                    };
                    let r = match args.nodes.unwrap_or_else(|| prep.arena_for(cfg)) {
                        2048 => run.on(&mut arenas.n2048),
                        4096 => run.on(&mut arenas.n4096),
                        8192 => run.on(&mut arenas.n8192),
                        16384 => run.on(&mut arenas.n16384),
                        65000 => run.on(&mut arenas.n65000),
                        n => {
                            return Err(anyhow!(
                                "--nodes {n}: use one of {:?}",
                                crate::sim::ARENAS
                            ));
                        }
                    }?;
                    if seed == 0 {
                        continue;
                    }
                    let row = BenchRow {
                        map: s.name.clone(),
                        leg,
                        planner: v.name.clone(),
                        seed,
                        optimal_m: opt,
                        first_us: r.first_s.map(|t| t * 1e6),
                        first_ratio: r.first_len.map(|l| l / opt),
                        first_nodes: r.first_nodes,
                        cost_ratio: r.costs.iter().map(|c| c.map(|c| c / opt)).collect(),
                        nodes: r.nodes,
                        equal_ratio: r.equal.and_then(|e| e.1).map(|c| c / opt),
                        equal_us: r.equal.map(|e| e.0 * 1e6),
                        expansions_per_s: r.expansions as f64 / r.cpu_s.max(1e-9),
                        reads_per_expansion: r.reads as f64 / (r.expansions.max(1)) as f64,
                        full: r.full,
                    };
                    writeln!(csv, "{}", csv_line(&row))?;
                    csv.flush()?;
                    rows.push(row);
                }
            }
            eprintln!("{} leg {leg}: done", s.name);
        }
    }
    let summary = summarise(&rows, &args.budgets);
    std::fs::write(
        args.out.join("summary.csv"),
        summary_csv(&summary, &args.budgets),
    )?;
    let md = summary_markdown(&summary, &args.budgets);
    std::fs::write(args.out.join("summary.md"), &md)?;
    print!("{md}");
    if args.grid {
        let budgets: &[f64] = if args.until_first { &[] } else { &args.budgets };
        let grid = grid_markdown(&rows, budgets);
        std::fs::write(args.out.join("grid.md"), &grid)?;
        print!("\n{grid}");
    }
    if args.ompl.is_some() {
        // Until the first solution: no costs to compare.
        let budgets: &[f64] = if args.until_first { &[] } else { &args.budgets };
        let ratios = ratios_markdown(&rows, budgets, args.cold, args.until_first);
        std::fs::write(args.out.join("ratios.md"), &ratios)?;
        print!("\n{ratios}");
    }
    Ok(rows)
}

/// The settings file a bench writes beside `bench.csv`: with both, `host-sim report` makes
/// the bench's page ([`report`]).
pub const SETTINGS_FILE: &str = "bench.json";

/// How a report names a bench's clock (`bench.json`'s `clock`).
fn clock_words(clock: &str) -> String {
    match clock {
        "cpu" => "thread CPU time, a system call at each of the planner's clock readings \
                  (`--clock cpu`, the bench's default until 2026-11-29)"
            .to_string(),
        "cpu-mono" => "thread CPU time, the planner's readings advanced by the monotonic clock \
                       between system calls at most 1 ms apart (`--clock cpu-mono`)"
            .to_string(),
        "wall" => "the monotonic clock (`--clock wall`)".to_string(),
        "virtual" => "the virtual clock (work units; `--clock virtual`)".to_string(),
        other => format!("{other} clock"),
    }
}

/// What a bench ran with (`bench.json`).
#[derive(Serialize, Deserialize)]
pub struct BenchSettings {
    /// The command line.
    pub command: String,
    /// Seeds per leg and planner.
    pub seeds: u64,
    /// The CPU budgets at which costs were read, in seconds.
    pub budgets: Vec<f64>,
    /// The planners' clock (`cpu-mono`, `cpu`, `wall` or `virtual`).
    pub clock: String,
    /// Caches flushed before every measured query (the default) or not (`--warm`).
    pub cold: bool,
    /// Each of our runs ended at its first solution (`--until-first`).
    pub until_first: bool,
    /// The grid planners ran.
    pub grid: bool,
    /// OMPL's planners ran.
    pub ompl: bool,
}

/// Reads a bench's rows back from its `bench.csv` (the columns [`run`] writes, one cost
/// column per budget).
pub fn read_rows(path: &std::path::Path, budgets: &[f64]) -> Result<Vec<BenchRow>> {
    let mut r =
        csv::Reader::from_path(path).with_context(|| format!("reading {}", path.display()))?;
    let head = r.headers()?.clone();
    if head.iter().collect::<Vec<_>>().join(",") != header(budgets) {
        return Err(anyhow!(
            "{}: its columns are not those of a bench with budgets {budgets:?}",
            path.display()
        ));
    }
    let col = |name: &str| head.iter().position(|h| h == name).unwrap_or(usize::MAX);
    let mut rows = Vec::new();
    for rec in r.records() {
        let rec = rec?;
        let get = |name: &str| rec.get(col(name)).unwrap_or("");
        let num = |name: &str| -> Result<Option<f64>> {
            let v = get(name);
            if v.is_empty() {
                Ok(None)
            } else {
                v.parse()
                    .map(Some)
                    .with_context(|| format!("{}: column {name}: {v:?}", path.display()))
            }
        };
        let need =
            |name: &str| num(name)?.ok_or_else(|| anyhow!("{}: {name} empty", path.display()));
        rows.push(BenchRow {
            map: get("map").to_string(),
            leg: need("leg")? as usize,
            planner: get("planner").to_string(),
            seed: need("seed")? as u64,
            optimal_m: need("optimal_m")?,
            first_us: num("first_us")?,
            first_ratio: num("first_ratio")?,
            first_nodes: num("first_nodes")?.map(|v| v as usize),
            cost_ratio: budgets
                .iter()
                .map(|b| num(&format!("cost_ratio_{b}s")))
                .collect::<Result<_>>()?,
            nodes: need("nodes")? as usize,
            equal_ratio: num("equal_time_ratio")?,
            equal_us: num("equal_time_us")?,
            expansions_per_s: need("expansions_per_s")?,
            reads_per_expansion: need("reads_per_expansion")?,
            full: get("full") == "true",
        });
    }
    Ok(rows)
}

/// A bench's page from its folder (`bench.json` and `bench.csv`): the settings, the summary,
/// and the per-leg ratios against the grid planners and OMPL's that the bench printed.
/// `command` is the line that made the page; `notes`, Markdown to add after the settings.
pub fn report(dir: &std::path::Path, command: &str, notes: Option<&str>) -> Result<String> {
    let path = dir.join(SETTINGS_FILE);
    let settings: BenchSettings = serde_json::from_str(
        &std::fs::read_to_string(&path).with_context(|| format!("reading {}", path.display()))?,
    )
    .with_context(|| format!("reading {}", path.display()))?;
    let rows = read_rows(&dir.join("bench.csv"), &settings.budgets)?;
    let mut maps: Vec<&str> = Vec::new();
    for r in &rows {
        if !maps.contains(&r.map.as_str()) {
            maps.push(&r.map);
        }
    }
    let mut md = format!(
        "# Against the baselines: {}\n\n<!-- Made by `{command}` from bench.csv and bench.json: \
         regenerate it, do not edit. -->\n\nThe bench (`{}`): {} seeds a leg, {}, {}{} \
         {} s.\n\n",
        maps.join(", "),
        settings.command,
        settings.seeds,
        clock_words(&settings.clock),
        if settings.cold {
            "cold queries (caches flushed before each)"
        } else {
            "warm queries"
        },
        if settings.until_first {
            ", each of ours ended at its first solution, within"
        } else {
            "; costs read at"
        },
        settings
            .budgets
            .iter()
            .map(|b| b.to_string())
            .collect::<Vec<_>>()
            .join(", ")
    );
    if let Some(n) = notes {
        md.push_str(n.trim_end());
        md.push_str("\n\n");
    }
    md.push_str("## Summary\n\n");
    md.push_str(&summary_markdown(
        &summarise(&rows, &settings.budgets),
        &settings.budgets,
    ));
    let budgets: &[f64] = if settings.until_first {
        &[]
    } else {
        &settings.budgets
    };
    if settings.grid {
        md.push_str("\n## Against the grid planners\n\n");
        md.push_str(&grid_markdown(&rows, budgets));
    }
    if settings.ompl {
        md.push_str("\n## Against OMPL\n\n");
        md.push_str(&ratios_markdown(
            &rows,
            budgets,
            settings.cold,
            settings.until_first,
        ));
    }
    Ok(md)
}

/// The planner name of the OMPL rows.
pub const OMPL_RRT_CONNECT: &str = "OMPL RRT-Connect";
/// The name of OMPL's RRT-Connect followed by its path simplifier (`simplifyMax`) in the output:
/// first-solution time includes the simplifier's, the ratio is the simplified path's.
pub const OMPL_RRT_CONNECT_SIMPLIFIED: &str = "OMPL RRT-Connect + simplify";
/// The name of OMPL's Informed RRT* in the output (first solution, cost at every budget).
pub const OMPL_INFORMED_RRT_STAR: &str = "OMPL Informed RRT*";

/// Runs OMPL's RRT-Connect (the `benches/ompl` harness at `bin`) on one leg for `args.seeds`
/// seeds: it reads the grid and the leg from files written to `out`, and answers one CSV row
/// per seed (first-solution thread CPU time of `solve`, raw path length / optimum).
#[allow(clippy::too_many_arguments)]
fn ompl_leg(
    bin: &std::path::Path,
    out: &std::path::Path,
    s: &Scenario,
    leg: usize,
    start: bi_am_rrt::Point,
    goal: bi_am_rrt::Point,
    opt: f64,
    args: &BenchArgs,
) -> Result<Vec<BenchRow>> {
    // The same map as ours: with a robot body, the grid inflated for its disc.
    let g = s.reach_map();
    // The harness works in cells: the leg is handed over in cell units (the ratio to the
    // optimum, and OMPL's range of 0.2 x the extent, do not depend on the unit).
    let cell = f32::from_bits(g.cell_bits);
    let (start, goal) = (
        bi_am_rrt::Point::new(start.x / cell, start.y / cell),
        bi_am_rrt::Point::new(goal.x / cell, goal.y / cell),
    );
    let opt_cells = opt / f64::from(cell);
    let dir = out.join("ompl");
    std::fs::create_dir_all(&dir)?;
    std::fs::write(dir.join(format!("{}.grid", s.name)), &g.bits)?;
    let legs = dir.join("leg.csv");
    std::fs::write(
        &legs,
        format!(
            "map,leg,sx,sy,gx,gy,optimal_m\n{},{leg},{:?},{:?},{:?},{:?},{opt_cells:?}\n",
            s.name, start.x, start.y, goal.x, goal.y
        ),
    )?;
    let budgets: Vec<String> = args.budgets.iter().map(|b| b.to_string()).collect();
    let mut rows = Vec::new();
    for planner in ["connect", "informed"] {
        let output = std::process::Command::new(bin)
            .arg(&legs)
            .arg(&dir)
            .arg(args.seeds.to_string())
            .args(["--planner", planner, "--budgets", &budgets.join(",")])
            .arg(format!("{}={}x{}", s.name, g.width, g.height))
            .args(args.cold.then_some("--cold"))
            .output()
            .with_context(|| format!("running {}", bin.display()))?;
        if !output.status.success() {
            return Err(anyhow!(
                "{} failed: {}",
                bin.display(),
                String::from_utf8_lossy(&output.stderr)
            ));
        }
        let text = String::from_utf8(output.stdout)?;
        let before = rows.len();
        for line in text.lines().skip(1) {
            let f: Vec<&str> = line.split(',').collect();
            let (Some(&seed), Some(&us), Some(&ratio), Some(&simp_us), Some(&simp), Some(costs)) =
                (f.get(2), f.get(3), f.get(4), f.get(5), f.get(6), f.get(7..))
            else {
                return Err(anyhow!("{}: bad line {line:?}", bin.display()));
            };
            let num = |v: &str| -> Result<Option<f64>> {
                Ok(if v.is_empty() { None } else { Some(v.parse()?) })
            };
            let row = |name: &str, first_us: Option<f64>, first_ratio: Option<f64>, cost_ratio| {
                Ok::<_, anyhow::Error>(BenchRow {
                    map: s.name.clone(),
                    leg,
                    planner: name.to_string(),
                    seed: seed.parse()?,
                    optimal_m: opt,
                    first_us,
                    first_ratio,
                    first_nodes: None,
                    cost_ratio,
                    nodes: 0,
                    equal_ratio: None,
                    equal_us: None,
                    expansions_per_s: 0.0,
                    reads_per_expansion: 0.0,
                    full: false,
                })
            };
            if planner == "connect" {
                let none = vec![None; args.budgets.len()];
                rows.push(row(OMPL_RRT_CONNECT, num(us)?, num(ratio)?, none.clone())?);
                // RRT-Connect plus simplification: its time includes the simplifier's.
                let total = match (num(us)?, num(simp_us)?) {
                    (Some(a), Some(b)) => Some(a + b),
                    _ => None,
                };
                rows.push(row(OMPL_RRT_CONNECT_SIMPLIFIED, total, num(simp)?, none)?);
            } else {
                let costs = costs.iter().map(|c| num(c)).collect::<Result<Vec<_>>>()?;
                if costs.len() != args.budgets.len() {
                    return Err(anyhow!("{}: bad line {line:?}", bin.display()));
                }
                rows.push(row(OMPL_INFORMED_RRT_STAR, num(us)?, num(ratio)?, costs)?);
            }
        }
        let per_seed = if planner == "connect" { 2 } else { 1 };
        if (rows.len() - before) as u64 != args.seeds * per_seed {
            return Err(anyhow!(
                "{} --planner {planner}: {} rows for {} seeds",
                bin.display(),
                (rows.len() - before) / per_seed as usize,
                args.seeds
            ));
        }
    }
    Ok(rows)
}

/// The grid planners' names in the output ([`crate::metric::grid_planners`]).
pub const GRID_ASTAR: &str = "A* (8-connected)";
/// Theta*'s name in the output.
pub const GRID_THETA_STAR: &str = "Theta*";

/// Whether a row is a baseline's (OMPL's or a grid planner's), not one of our planners'.
pub fn is_baseline(planner: &str) -> bool {
    planner.starts_with("OMPL ") || planner == GRID_ASTAR || planner == GRID_THETA_STAR
}

/// Queries of each grid planner per leg: they are deterministic, so repeats only give the
/// time a median.
const GRID_REPEATS: u64 = 5;

/// A* on the 8-connected grid and Theta* on one leg ([`crate::metric::grid_planners`]: the cells
/// with room for the robot's body, as OMPL's and ours), `min(seeds, 5)` queries each, cold
/// as ours unless `--warm`: one row per query, its thread CPU time as the first-solution time
/// and its path / optimum as the first path (no costs at budgets: a grid planner's answer
/// is final).
fn grid_leg(
    s: &Scenario,
    leg: usize,
    start: bi_am_rrt::Point,
    goal: bi_am_rrt::Point,
    opt: f64,
    args: &BenchArgs,
) -> Vec<BenchRow> {
    type Plan = fn(
        &bi_am_rrt::map::OccupancyGrid<'_>,
        bi_am_rrt::Point,
        bi_am_rrt::Point,
    ) -> Option<GridPath>;
    use crate::metric::grid_planners::GridPath;
    let grid = s.reach_grid();
    let planners: [(&str, Plan); 2] = [
        (GRID_ASTAR, crate::metric::grid_planners::astar8),
        (GRID_THETA_STAR, crate::metric::grid_planners::theta_star),
    ];
    let mut rows = Vec::new();
    for (name, plan) in planners {
        for seed in 1..=args.seeds.min(GRID_REPEATS) {
            if args.cold {
                flush_caches();
            }
            let t0 = cpu_time::ThreadTime::now();
            let path = plan(&grid, start, goal);
            let us = t0.elapsed().as_secs_f64() * 1e6;
            let found = path.is_some();
            rows.push(BenchRow {
                map: s.name.clone(),
                leg,
                planner: name.to_string(),
                seed,
                optimal_m: opt,
                first_us: found.then_some(us),
                first_ratio: path.map(|p| p.length_m / opt),
                first_nodes: None,
                cost_ratio: vec![None; args.budgets.len()],
                nodes: 0,
                equal_ratio: None,
                equal_us: None,
                expansions_per_s: 0.0,
                reads_per_expansion: 0.0,
                full: false,
            });
        }
    }
    rows
}

/// What one run measured.
struct Measured {
    first_s: Option<f64>,
    first_len: Option<f64>,
    first_nodes: Option<usize>,
    costs: Vec<Option<f64>>,
    /// The equal-time reading: when, and the path cost then.
    equal: Option<(f64, Option<f64>)>,
    nodes: usize,
    expansions: u64,
    reads: u64,
    cpu_s: f64,
    full: bool,
}

/// The longest single `grow` call of the bench: budgets are hit within about this much.
const SLICE: Duration = Duration::from_micros(500);

/// The longest `grow` call with [`BenchArgs::until_first`]: a run ends at most this long after
/// its first solution (a call reads the clock once more than the calls of [`SLICE`], about
/// 0.4 us every 50 us of growth: under 1 %).
const SLICE_UNTIL_FIRST: Duration = Duration::from_micros(50);

/// The bench's planner storage, one per tree size, allocated once and reused by every run (as
/// a firmware's `static`, which the planner resets): no allocation or first touch of fresh
/// memory inside the measurements. The results are the same as on fresh storage.
#[derive(Default)]
struct Arenas {
    n2048: Option<Box<Storage<2048, BUCKETS>>>,
    n4096: Option<Box<Storage<4096, BUCKETS>>>,
    n8192: Option<Box<Storage<8192, BUCKETS>>>,
    n16384: Option<Box<Storage<16384, BUCKETS>>>,
    n65000: Option<Box<Storage<65000, BUCKETS>>>,
}

/// One run of the bench: a variant on a leg with a seed.
struct Run<'a> {
    clock: BenchClock,
    prep: &'a Prepared,
    /// The variant's configuration on this scenario ([`Variant::config_for`]).
    cfg: Named,
    seed: u64,
    start: bi_am_rrt::Point,
    goal: bi_am_rrt::Point,
    budgets: &'a [f64],
    cold: bool,
    /// The equal-time reading's time, in CPU seconds.
    equal_at: Option<f64>,
    until_first: bool,
}

impl Run<'_> {
    /// The run on `storage` (allocated at its first use).
    // Not inlined: the caller's `match` over the arenas would carry every arena's storage in
    // one stack frame (65,000 nodes a tree: 2.7 MB, over a test thread's 2 MiB).
    #[inline(never)]
    fn on<const N: usize>(
        &self,
        storage: &mut Option<Box<Storage<N, BUCKETS>>>,
    ) -> Result<Measured> {
        let storage = storage.get_or_insert_with(Box::default);
        with_planner_in::<N, _>(storage, self.prep, self.cfg, self.seed, self.start, |p| {
            if self.cold {
                flush_caches();
            }
            measure(
                p,
                self.goal,
                self.budgets,
                self.equal_at,
                self.clock,
                self.until_first,
            )
        })
    }
}

/// Grows `planner` towards `goal` until each CPU budget has passed (module docs), and reads
/// the path's cost once more at `equal_at` (the calls then end there as at a budget; past the
/// last budget, the run grows until then). With `until_first` ([`BenchArgs::until_first`]):
/// calls of at most [`SLICE_UNTIL_FIRST`] until the goal joins or the last budget has passed,
/// and no cost read.
fn measure<const N: usize>(
    planner: &mut SizedPlanner<'_, '_, N>,
    goal: bi_am_rrt::Point,
    budgets: &[f64],
    equal_at: Option<f64>,
    kind: BenchClock,
    until_first: bool,
) -> Result<Measured> {
    let clock = RunClock::new(kind);
    let mut costs = Vec::with_capacity(budgets.len());
    let mut equal = None;
    let mut full = false;
    let mut first: Option<(f64, f64, usize)> = None;
    // The budgets and the equal-time reading, in time order (`true`: the equal-time one).
    let mut stops: Vec<(f64, bool)> = if until_first {
        budgets.last().map(|&b| (b, false)).into_iter().collect()
    } else {
        budgets.iter().map(|&b| (b, false)).collect()
    };
    let slice = if until_first {
        SLICE_UNTIL_FIRST
    } else {
        SLICE
    };
    if let Some(t) = equal_at.filter(|_| !until_first) {
        // Read even past the last budget (the run then grows that long).
        stops.push((t, true));
    }
    stops.sort_by(|a, b| a.0.total_cmp(&b.0));
    // Zero: just before the goal is set, the harness's own lists made (a cold query would
    // otherwise count the allocator's misses as the planner's).
    let t0 = bi_am_rrt::clock::Clock::now(&clock);
    let secs = |t: u64| t.saturating_sub(t0) as f64 * 1e-9;
    planner.set_goal(goal).map_err(|e| anyhow!("goal: {e}"))?;
    // The first call starts without a reading of the harness's own: a thread CPU time
    // reading costs about 0.4 us here (a system call), and before the first call it would
    // fall inside the first solution's time, which OMPL's harness times with no reading of
    // its own between its two (`benches/ompl/rrt_connect.cpp`). Zero is `t0`, read just
    // before `set_goal`.
    let mut first_call = true;
    'stops: for (b, is_equal) in stops {
        loop {
            let now = if first_call {
                first_call = false;
                0.0
            } else {
                secs(bi_am_rrt::clock::Clock::now(&clock))
            };
            if now >= b {
                break;
            }
            let left = Duration::from_secs_f64(b - now).min(slice);
            planner
                .set_t_exp(left.max(Duration::from_micros(1)))
                .map_err(|e| anyhow!("{e}"))?;
            let p = planner.grow(&clock);
            full |= p.tree_full;
            if first.is_none()
                && let (Some(at), Some(c)) = (planner.stats().goal_found_at, p.goal_cost)
            {
                // The cost read now may already be lower than when the goal joined, if
                // rewiring ran in the same call: read the length the goal joined with.
                let len = planner.stats().first_cost.unwrap_or(c.length) as f64;
                first = Some((secs(at), len, planner.stats().nodes_at_goal.unwrap_or(0)));
            }
            if until_first && first.is_some() {
                break 'stops;
            }
        }
        let c = planner
            .goal_node()
            .and_then(|g| planner.tree().cost(g))
            .filter(|c| !c.blocked)
            .map(|c| c.length as f64);
        if is_equal {
            equal = Some((secs(bi_am_rrt::clock::Clock::now(&clock)), c));
        } else {
            costs.push(c);
        }
    }
    let cpu_s = secs(bi_am_rrt::clock::Clock::now(&clock));
    let st = planner.stats();
    Ok(Measured {
        first_s: first.map(|f| f.0),
        first_len: first.map(|f| f.1),
        first_nodes: first.map(|f| f.2),
        // Until the first solution: no cost is read.
        costs: if until_first {
            vec![None; budgets.len()]
        } else {
            costs
        },
        equal,
        nodes: planner.tree().len(),
        expansions: st.expansions + st.reverse_expansions,
        reads: clock.reads(),
        cpu_s,
        full,
    })
}

fn header(budgets: &[f64]) -> String {
    let mut h = String::from(
        "map,leg,planner,seed,optimal_m,first_us,first_ratio,first_nodes,nodes,expansions_per_s,reads_per_expansion,full",
    );
    for b in budgets {
        h.push_str(&format!(",cost_ratio_{b}s"));
    }
    h.push_str(",equal_time_ratio,equal_time_us");
    h
}

fn opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_default()
}

fn csv_line(r: &BenchRow) -> String {
    let mut s = format!(
        "{},{},\"{}\",{},{:.3},{},{},{},{},{:.0},{:.1},{}",
        r.map,
        r.leg,
        r.planner,
        r.seed,
        r.optimal_m,
        opt(r.first_us.map(|v| format!("{v:.1}"))),
        opt(r.first_ratio.map(|v| format!("{v:.6}"))),
        opt(r.first_nodes),
        r.nodes,
        r.expansions_per_s,
        r.reads_per_expansion,
        r.full
    );
    for c in &r.cost_ratio {
        s.push(',');
        s.push_str(&opt(c.map(|v| format!("{v:.6}"))));
    }
    s.push_str(&format!(
        ",{},{}",
        opt(r.equal_ratio.map(|v| format!("{v:.6}"))),
        opt(r.equal_us.map(|v| format!("{v:.1}")))
    ));
    s
}

/// One line of the summary: a map and a planner.
#[derive(Clone, Debug)]
pub struct SummaryRow {
    pub map: String,
    pub planner: String,
    /// Legs whose every seed found the goal / legs.
    pub solved: (usize, usize),
    pub first_us: Option<f64>,
    pub first_ratio: Option<f64>,
    pub cost_ratio: Vec<Option<f64>>,
    pub nodes: Option<f64>,
    pub expansions_per_s: Option<f64>,
    pub reads_per_expansion: Option<f64>,
}

/// Median over legs of the per-leg medians over seeds. A run that never found the goal counts
/// as infinitely slow (so the median is honest when some runs fail).
pub fn summarise(rows: &[BenchRow], budgets: &[f64]) -> Vec<SummaryRow> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.map.clone(), r.planner.clone());
        if !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys.into_iter()
        .map(|(map, planner)| {
            let mine: Vec<&BenchRow> = rows
                .iter()
                .filter(|r| r.map == map && r.planner == planner)
                .collect();
            let mut legs: Vec<usize> = mine.iter().map(|r| r.leg).collect();
            legs.sort_unstable();
            legs.dedup();
            let per_leg = |f: &dyn Fn(&BenchRow) -> Option<f64>| -> Option<f64> {
                let mut meds: Vec<f64> = legs
                    .iter()
                    .filter_map(|&l| {
                        let mut v: Vec<f64> = mine
                            .iter()
                            .filter(|r| r.leg == l)
                            .map(|r| f(r).unwrap_or(f64::INFINITY))
                            .collect();
                        median(&mut v)
                    })
                    .collect();
                median(&mut meds).filter(|m| m.is_finite())
            };
            let solved = legs
                .iter()
                .filter(|&&l| {
                    mine.iter()
                        .filter(|r| r.leg == l)
                        .all(|r| r.first_us.is_some())
                })
                .count();
            SummaryRow {
                map: map.clone(),
                planner: planner.clone(),
                solved: (solved, legs.len()),
                first_us: per_leg(&|r| r.first_us),
                first_ratio: per_leg(&|r| r.first_ratio),
                cost_ratio: (0..budgets.len())
                    .map(|i| per_leg(&|r| r.cost_ratio.get(i).copied().flatten()))
                    .collect(),
                nodes: per_leg(&|r| Some(r.nodes as f64)),
                expansions_per_s: per_leg(&|r| Some(r.expansions_per_s)),
                reads_per_expansion: per_leg(&|r| Some(r.reads_per_expansion)),
            }
        })
        .collect()
}

/// The summary as one table ([`crate::results::table`]): `summary.csv` and `summary.md`.
fn summary_table(rows: &[SummaryRow], budgets: &[f64]) -> Table {
    let mut columns = vec![
        Column::text("map", "map"),
        Column::text("planner", "planner"),
        Column::text("legs_solved,legs", "legs solved"),
        Column::number("first_us", "first solution (us)"),
        Column::number("first_ratio", "first path / opt"),
    ];
    for b in budgets {
        columns.push(Column::number(
            format!("cost_ratio_{b}s"),
            format!("cost at {b} s / opt"),
        ));
    }
    columns.extend([
        Column::number("nodes", "nodes"),
        Column::number("expansions_per_s", "expansions/s"),
        Column::number("reads_per_expansion", "clock reads/expansion"),
    ]);
    let rows = rows
        .iter()
        .map(|r| {
            let mut cells = vec![
                Cell::Text(r.map.clone()),
                Cell::Quoted(r.planner.clone()),
                Cell::Fraction(r.solved.0, r.solved.1),
                Cell::Number(r.first_us, 1, 0),
                Cell::Number(r.first_ratio, 4, 3),
            ];
            cells.extend(r.cost_ratio.iter().map(|c| Cell::Number(*c, 4, 3)));
            cells.extend([
                Cell::Number(r.nodes, 0, 0),
                Cell::Number(r.expansions_per_s, 0, 0),
                Cell::Number(r.reads_per_expansion, 1, 1),
            ]);
            cells
        })
        .collect();
    Table { columns, rows }
}

fn summary_csv(rows: &[SummaryRow], budgets: &[f64]) -> String {
    summary_table(rows, budgets).csv()
}

/// The summary as Markdown (`summary.md`, printed at the end).
pub fn summary_markdown(rows: &[SummaryRow], budgets: &[f64]) -> String {
    summary_table(rows, budgets).markdown()
}

/// Per leg, the median over seeds of `f` (a run without a value counts as infinite), for one
/// map and planner.
fn leg_medians(
    rows: &[BenchRow],
    map: &str,
    planner: &str,
    f: &dyn Fn(&BenchRow) -> Option<f64>,
) -> Vec<(usize, f64)> {
    let mut legs: Vec<usize> = rows
        .iter()
        .filter(|r| r.map == map && r.planner == planner)
        .map(|r| r.leg)
        .collect();
    legs.sort_unstable();
    legs.dedup();
    legs.into_iter()
        .filter_map(|l| {
            let mut v: Vec<f64> = rows
                .iter()
                .filter(|r| r.map == map && r.planner == planner && r.leg == l)
                .map(|r| f(r).unwrap_or(f64::INFINITY))
                .collect();
            median(&mut v).map(|m| (l, m))
        })
        .collect()
}

/// Ours / theirs leg by leg (per-leg medians over seeds): the median of the per-leg ratios and
/// the worst leg (the highest ratio, with its number). `None` when no leg has both.
pub fn leg_ratios(ours: &[(usize, f64)], theirs: &[(usize, f64)]) -> Option<(f64, usize, f64)> {
    let mut ratios: Vec<(usize, f64)> = ours
        .iter()
        .filter_map(|&(l, a)| {
            let &(_, b) = theirs.iter().find(|(lb, _)| *lb == l)?;
            Some((l, a / b))
        })
        .filter(|(_, r)| !r.is_nan())
        .collect();
    let worst = ratios.iter().copied().max_by(|a, b| a.1.total_cmp(&b.1))?;
    let mut v: Vec<f64> = ratios.drain(..).map(|(_, r)| r).collect();
    let med = median(&mut v)?;
    Some((med, worst.0, worst.1))
}

/// Issue 26's table: each of our planners against OMPL's in the same run, leg by leg (per-leg
/// medians over seeds, then the median of the per-leg ratios and the worst leg): first-solution
/// time against RRT-Connect, first path against RRT-Connect + simplify, and the cost at each
/// budget against Informed RRT*. Below 1 is ours ahead.
pub fn ratios_markdown(
    rows: &[BenchRow],
    budgets: &[f64],
    cold: bool,
    until_first: bool,
) -> String {
    let mode = match (cold, until_first) {
        (true, _) => {
            "cold: caches flushed (64 MiB written and read) before every query, ours and OMPL's"
        }
        (false, false) => "warm: each query on the caches the previous one left",
        (false, true) => {
            "warm, until the first solution: each query on the caches the previous one left, \
             and each of our queries, as each of RRT-Connect's, ended at its first solution"
        }
    };
    let mut s = format!(
        "Per-leg ratios, ours / OMPL's in the same run ({mode}); median over legs, and the \
         worst leg (leg: ratio); 0 where OMPL had no path by then, inf where we had none. \
         At equal time: our path when RRT-Connect + simplify had its path (its median time on \
         the leg; read at the end of our first call ending then or later: the median reading \
         is given in microseconds after that time) / that simplified path.\n\n| map | \
         planner | first solution / RRT-Connect | first path / (RRT-Connect + simplify) | \
         path at equal time / (RRT-Connect + simplify) | read after (us) |"
    );
    budget_columns(
        &mut s,
        budgets,
        "Informed RRT*",
        "|---|---|---:|---:|---:|---:|",
    );
    let keys = our_planners(rows);
    for (map, planner) in keys {
        let ours = |f: &dyn Fn(&BenchRow) -> Option<f64>| leg_medians(rows, &map, &planner, f);
        let theirs =
            |name: &str, f: &dyn Fn(&BenchRow) -> Option<f64>| leg_medians(rows, &map, name, f);
        let first = leg_ratios(
            &ours(&|r| r.first_us),
            &theirs(OMPL_RRT_CONNECT, &|r| r.first_us),
        );
        let path = leg_ratios(
            &ours(&|r| r.first_ratio),
            &theirs(OMPL_RRT_CONNECT_SIMPLIFIED, &|r| r.first_ratio),
        );
        // No equal-time reading in runs that end at their first solution.
        let read = rows
            .iter()
            .any(|r| r.map == map && r.planner == planner && r.equal_us.is_some());
        let equal = read
            .then(|| {
                leg_ratios(
                    &ours(&|r| r.equal_ratio),
                    &theirs(OMPL_RRT_CONNECT_SIMPLIFIED, &|r| r.first_ratio),
                )
            })
            .flatten();
        // How late our equal-time readings came: per run, after the leg's equal time.
        let t_eq = leg_medians(rows, &map, OMPL_RRT_CONNECT_SIMPLIFIED, &|r| r.first_us);
        let mut late: Vec<f64> = rows
            .iter()
            .filter(|r| r.map == map && r.planner == planner)
            .filter_map(|r| {
                let &(_, t) = t_eq.iter().find(|(l, _)| *l == r.leg)?;
                Some(r.equal_us? - t)
            })
            .collect();
        let late = median(&mut late).map_or("-".into(), |v| format!("{v:.0}"));
        s.push_str(&format!(
            "| {map} | {planner} | {} | {} | {} | {late} |",
            ratio_cell(first, 2),
            ratio_cell(path, 3),
            ratio_cell(equal, 3)
        ));
        for i in 0..budgets.len() {
            let get = move |r: &BenchRow| r.cost_ratio.get(i).copied().flatten();
            let c = leg_ratios(&ours(&get), &theirs(OMPL_INFORMED_RRT_STAR, &get));
            s.push_str(&format!(" {} |", ratio_cell(c, 4)));
        }
        s.push('\n');
    }
    s
}

/// The (map, planner) pairs of our planners' rows, in the order they first appear.
fn our_planners(rows: &[BenchRow]) -> Vec<(String, String)> {
    let mut keys: Vec<(String, String)> = Vec::new();
    for r in rows {
        let k = (r.map.clone(), r.planner.clone());
        if !is_baseline(&r.planner) && !keys.contains(&k) {
            keys.push(k);
        }
    }
    keys
}

/// Ends a table's header: a "cost at B s / `against`" column per budget, then the rule line
/// (`rule` for the columns before them).
fn budget_columns(s: &mut String, budgets: &[f64], against: &str, rule: &str) {
    for b in budgets {
        s.push_str(&format!(" cost at {b} s / {against} |"));
    }
    s.push('\n');
    s.push_str(rule);
    for _ in budgets {
        s.push_str("---:|");
    }
    s.push('\n');
}

/// A table cell of [`leg_ratios`]: the median and the worst leg, or `-`.
fn ratio_cell(r: Option<(f64, usize, f64)>, digits: usize) -> String {
    match r {
        Some((m, l, w)) => format!("{m:.digits$} (leg {l}: {w:.digits$})"),
        None => "-".into(),
    }
}

/// Each of our planners against the grid planners in the same run, leg by leg (per-leg
/// medians, then the median of the per-leg ratios and the worst leg): first-solution time
/// against the grid planner's query time, first path against its path, and the cost at each
/// budget against its path. Below 1 is ours ahead. Empty without grid rows.
pub fn grid_markdown(rows: &[BenchRow], budgets: &[f64]) -> String {
    let mut s = String::from(
        "Against the grid planners on the same cells, ours / theirs per leg (per-leg medians \
         over seeds; their time is one query's thread CPU time, the median of up to 5); \
         median over legs, and the worst leg (leg: ratio); inf where we had no path by then.\n\n\
         | map | planner | grid planner | first solution / its time | first path / its path |",
    );
    budget_columns(&mut s, budgets, "its path", "|---|---|---|---:|---:|");
    let keys = our_planners(rows);
    for (map, planner) in keys {
        for grid in [GRID_ASTAR, GRID_THETA_STAR] {
            let theirs = |f: &dyn Fn(&BenchRow) -> Option<f64>| leg_medians(rows, &map, grid, f);
            let ours = |f: &dyn Fn(&BenchRow) -> Option<f64>| leg_medians(rows, &map, &planner, f);
            if theirs(&|r| r.first_us).is_empty() {
                continue;
            }
            let first = leg_ratios(&ours(&|r| r.first_us), &theirs(&|r| r.first_us));
            let path = leg_ratios(&ours(&|r| r.first_ratio), &theirs(&|r| r.first_ratio));
            s.push_str(&format!(
                "| {map} | {planner} | {grid} | {} | {} |",
                ratio_cell(first, 2),
                ratio_cell(path, 3)
            ));
            for i in 0..budgets.len() {
                let get = move |r: &BenchRow| r.cost_ratio.get(i).copied().flatten();
                let c = leg_ratios(&ours(&get), &theirs(&|r| r.first_ratio));
                s.push_str(&format!(" {} |", ratio_cell(c, 3)));
            }
            s.push('\n');
        }
    }
    s
}
