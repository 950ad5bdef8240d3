//! `host-sim`: run the planner on a scenario, run the paper's experiment matrix, bake metric
//! tables. `host-sim --help` lists the commands.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use bi_am_rrt::metric::ElementKind;
use clap::{Args, Parser, Subcommand, ValueEnum};
use host_sim::bake;
use host_sim::clock::ClockKind;
use host_sim::diffusion::{TableLayout, TableOptions};
use host_sim::experiment::{self, ExperimentArgs, Goals};
use host_sim::maps;
use host_sim::run::{self, RunArgs};
use host_sim::stress;

#[derive(Parser)]
#[command(
    version,
    about = "Simulator and experiment runner for the Bi-AM-RRT* planner"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum MetricArg {
    Diffusion,
    Geodesic,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum KindArg {
    I16,
    F32,
}

#[derive(Subcommand)]
enum Command {
    /// Drive an agent from start to goal on one scenario and draw the result.
    Run {
        /// A built-in scenario: open, bug_trap, maze (small fixtures) or trap_100, maze_100,
        /// office_200 (the paper's sizes) ...
        #[arg(long, default_value = "bug_trap")]
        builtin: String,
        /// ... or a scenario from a file (with --scenario NAME).
        #[arg(long)]
        scenarios: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArgs,
        /// Scenario name in --scenarios.
        #[arg(long)]
        scenario: Option<String>,
        /// Planner name as in the paper's Table 1 (any case; suffix " tuned" for the tuned
        /// configuration; `@field=value` overrides as in `bench --planners`). The default is
        /// the tuned planner (`Config::default()`); "Bi-AM-RRT*(D)" is the paper's.
        #[arg(long, default_value = "Bi-AM-RRT*(D) tuned")]
        planner: String,
        /// Run through every goal of the scenario instead of the first only.
        #[arg(long)]
        all_goals: bool,
        /// Random seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Clock: `wall` (real time, as the paper) or `virtual` (work-driven, repeatable).
        #[arg(long, value_enum, default_value = "wall")]
        clock: ClockKind,
        /// Drop a disc of this radius on the planned path once the agent moves (paper Fig. 7).
        #[arg(long)]
        obstacle: Option<f32>,
        /// Output directory (pictures and result.json).
        #[arg(long, default_value = "out/run")]
        out: PathBuf,
        /// Planning time per call in ms (default: the paper's 150).
        #[arg(long)]
        t_exp_ms: Option<u64>,
        /// Table 2's lengths in metres as printed (e_max 5 m, sigma 30 m, ...) instead of
        /// the lengths that follow the map (the default: Table 2's on maps 100-200 m across,
        /// proportional to the map's size off that range; README "Lengths that follow the map").
        #[arg(long)]
        paper_lengths: bool,
        /// Work per call, as `experiment --pace` (`paper` needs --clock virtual).
        #[arg(long, value_enum, default_value = "full")]
        pace: host_sim::results::Pace,
        /// Also write an animated GIF of the run (run.gif), one frame every N plan calls.
        #[arg(long, value_name = "N", num_args = 0..=1, default_missing_value = "2",
              value_parser = clap::value_parser!(u32).range(1..))]
        animate: Option<u32>,
        /// Skip each leg's exact optimum (travelled / optimum stays empty). It is computed
        /// after the drive, when every goal's result is already in result.json; on maps with
        /// tens of thousands of obstacle corners it can take long.
        #[arg(long)]
        no_optimum: bool,
    },
    /// People walking across and along the agent's first leg (issue 27): the same walkers
    /// reported as still circles, with their velocity, and by an oracle; a door that closes
    /// and opens (as circles or as live cells) or stays closed (live cells or a rebaked
    /// table); collisions by kind, waiting time, travelled / optimal (runs.csv, summary.md,
    /// moving.png, pictures).
    Moving {
        /// A built-in scenario (default office_200) ...
        #[arg(long, default_value = "office_200")]
        builtin: String,
        /// ... or a scenario from a file (with --scenario NAME).
        #[arg(long)]
        scenarios: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArgs,
        /// Scenario name in --scenarios.
        #[arg(long)]
        scenario: Option<String>,
        /// Scenes: crossing, head-on, door, closed-door (comma-separated).
        #[arg(
            long,
            value_enum,
            value_delimiter = ',',
            default_value = "crossing,head-on"
        )]
        kinds: Vec<host_sim::moving::Kind>,
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
    },
    /// Run planners x scenarios x repeats and write runs.csv and summary.csv.
    Experiment {
        /// Scenario file (TOML in the form of shared/maps/scenarios.toml), or `builtin` for the
        /// built-in scenarios (open, bug_trap, maze and the paper-sized trap_100, maze_100,
        /// office_200).
        #[arg(long)]
        scenarios: PathBuf,
        #[command(flatten)]
        body: BodyArgs,
        /// Comma-separated scenario names (default: all in the file).
        #[arg(long, value_delimiter = ',')]
        maps: Option<Vec<String>>,
        /// `all` or a comma-separated list of Table 1 names.
        #[arg(long, default_value = "all")]
        planners: String,
        /// Runs per planner and scenario (seeds seed .. seed + repeats - 1).
        #[arg(long, default_value_t = 25, value_parser = clap::value_parser!(u32).range(1..))]
        repeats: u32,
        /// Clock: `wall` (real time, as the paper) or `virtual` (work-driven, repeatable).
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
        /// Rewiring as the reference (every expansion spends its full t_root/t_goal).
        #[arg(long)]
        faithful: bool,
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
        /// Work per call: `full` (as much as t_exp allows here) or `paper` (the paper's pace:
        /// 20 expansions and 8 rewiring visits per phase and expansion, every call lasting
        /// its full t_exp on the virtual clock; needs --clock virtual).
        #[arg(long, value_enum, default_value = "full")]
        pace: host_sim::results::Pace,
        /// Skip each leg's exact optimum (`optimal_m` and `travelled_ratio` stay empty): on maps
        /// with tens of thousands of obstacle corners it can take long.
        #[arg(long)]
        no_optimum: bool,
        /// Table 2's lengths in metres as printed (e_max 5 m, sigma 30 m, ...) instead of
        /// the lengths that follow the map (the default: Table 2's on maps 100-200 m across,
        /// proportional to the map's size off that range; README "Lengths that follow the map").
        #[arg(long)]
        paper_lengths: bool,
        /// Parts of Algorithms 4 and 6 run exactly as printed instead of this crate's reading
        /// (src/rewire.rs): `all`, `none`, or a comma-separated list of alg4-take (Algorithm
        /// 4 dequeues x_r2), alg6-take (Algorithm 6 pops x_r2), alg6-cost (Algorithm 6's
        /// cost test through x_r1), alg6-clear (Algorithm 6's clearing test on Second(S)).
        #[arg(long, default_value = "none")]
        as_printed: String,
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
    },
    /// Turn an experiment's results folder into charts (SVG and PNG) and a Markdown report in
    /// the shape of the paper's Section 5: Fig. 6 (original vs modified for each scheme), box
    /// plots per planner, nodes at goal, Table 3 (map processing), the paper's claims.
    Report {
        /// The results folder (experiment.json and runs.csv, or a `moving` folder:
        /// moving.json and runs.csv).
        #[arg(long)]
        results: PathBuf,
        /// The Markdown file to write; the charts go to a folder beside it of the same name
        /// (default: RESULTS/report.md and RESULTS/report/).
        #[arg(long)]
        out: Option<PathBuf>,
        /// A Markdown file written by hand to include after the settings (kept when the
        /// report is regenerated).
        #[arg(long)]
        notes: Option<PathBuf>,
    },
    /// Join results folders of one experiment (its shards, or runs done on several machines)
    /// into one: rows in canonical order, JSON and summaries. Their settings must be equal; a
    /// run present twice is an error; missing runs are reported.
    Merge {
        /// Output folder.
        #[arg(long)]
        out: PathBuf,
        /// Folders to join.
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
    },
    /// Compare results folders that differ by one switch each against a base folder (the
    /// same matrix): per planner and map, the change of each mean with its Mann-Whitney p,
    /// as a Markdown page.
    Compare {
        /// The base folder.
        #[arg(long)]
        base: PathBuf,
        /// Variants as LABEL=FOLDER.
        #[arg(required = true)]
        variants: Vec<String>,
        /// Markdown file to write.
        #[arg(long)]
        out: PathBuf,
        /// Hand-written Markdown to include after the variants' table.
        #[arg(long)]
        notes: Option<PathBuf>,
    },
    /// Benchmark the planners on every leg of each scenario, like OMPL's benchmark: a fresh
    /// planner per leg and seed, thread CPU time, time to the first solution and path cost
    /// after fixed CPU budgets, against each leg's exact optimum. Writes bench.csv,
    /// summary.csv and summary.md.
    Bench {
        /// Scenario file (TOML in the form of shared/maps/scenarios.toml), or `builtin` for the
        /// built-in scenarios (open, bug_trap, maze and the paper-sized trap_100, maze_100,
        /// office_200).
        #[arg(long)]
        scenarios: PathBuf,
        #[command(flatten)]
        body: BodyArgs,
        /// Comma-separated scenario names (default: all in the file).
        #[arg(long, value_delimiter = ',')]
        maps: Option<Vec<String>>,
        /// Legs to run, 1-based and comma-separated (default: all).
        #[arg(long, value_delimiter = ',')]
        legs: Option<Vec<usize>>,
        /// Comma-separated planner names (Table 1 names, any case).
        #[arg(long, default_value = "Bi-AM-RRT*(D)")]
        planners: String,
        /// Seeds per leg and planner (seeds 1..=N).
        #[arg(long, default_value_t = 10, value_parser = clap::value_parser!(u64).range(1..))]
        seeds: u64,
        /// CPU budgets in seconds at which the path cost is read, comma-separated.
        #[arg(long, value_delimiter = ',', default_value = "0.01,0.1,1")]
        budgets: Vec<f64>,
        /// Nodes per tree: 2048, 4096 or 8192.
        #[arg(long, default_value_t = 8192)]
        nodes: usize,
        #[command(flatten)]
        table: TableArgs,
        /// Output folder.
        #[arg(long, default_value = "out/bench")]
        out: PathBuf,
        /// Also run OMPL's RRT-Connect on every leg, in the same run: the path of the
        /// `benches/ompl` harness binary (see its README; needs libompl-dev).
        #[arg(long)]
        ompl: Option<PathBuf>,
        /// The planners' clock: thread CPU time, the monotonic clock (cheaper to read; at least
        /// the CPU time), or the virtual clock (work units, repeatable: for comparing
        /// algorithmic changes; its "us" are virtual).
        #[arg(long, value_enum, default_value = "cpu")]
        clock: host_sim::bench::BenchClock,
        /// Table 2's lengths in metres as printed (e_max 5 m, sigma 30 m, ...) instead of
        /// the lengths that follow the map (the default: Table 2's on maps 100-200 m across,
        /// proportional to the map's size off that range; README "Lengths that follow the map").
        #[arg(long)]
        paper_lengths: bool,
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
    },
    /// Soak test: one planner and one agent for a long time with a new random goal every few
    /// seconds (CPU time of the planner thread). Prints a line per minute and writes soak.csv.
    Soak {
        /// Scenario file (TOML in the form of shared/maps/scenarios.toml), or `builtin` for the
        /// built-in scenarios (open, bug_trap, maze and the paper-sized trap_100, maze_100,
        /// office_200).
        #[arg(long)]
        scenarios: PathBuf,
        #[command(flatten)]
        body: BodyArgs,
        /// Scenario name in --scenarios.
        #[arg(long)]
        scenario: String,
        /// Planner name (Table 1, optionally with the suffix " tuned" and the bench's
        /// `@field=value` overrides).
        #[arg(long, default_value = "Bi-AM-RRT*(D) tuned")]
        planner: String,
        /// Length in minutes of planner CPU time.
        #[arg(long, default_value_t = 30.0)]
        minutes: f64,
        /// Seconds of planner CPU time between two goals.
        #[arg(long, default_value_t = 3.0)]
        goal_every: f64,
        /// Metres the agent moves per call.
        #[arg(long, default_value_t = 0.7)]
        speed: f32,
        /// Nodes per tree: 2048 or 8192.
        #[arg(long, default_value_t = 8192)]
        nodes: usize,
        /// Seed of the planner and the goals.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[command(flatten)]
        table: TableArgs,
        /// Output folder.
        #[arg(long, default_value = "out/soak")]
        out: PathBuf,
    },
    /// Safety stress test: seeded runs on the built-in maps with obstacles dropped on the path,
    /// between the agent and its waypoint, on the goal and around the agent, vanishing again,
    /// and goals changed mid-run; every move is checked. Fails if any move is unsafe or any
    /// run panics.
    Stress {
        /// Number of runs (cycling over maps, then planners; seeds consecutive).
        #[arg(long, default_value_t = 1000)]
        runs: u32,
        /// Planner names (Table 1), comma-separated, or `all`.
        #[arg(long, default_value = "Bi-AM-RRT*(E),Bi-AM-RRT*(D),AM-RRT*(E),RT-RRT*")]
        planners: String,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Planning time per call, in milliseconds of the virtual clock.
        #[arg(long, default_value_t = 5)]
        t_exp_ms: u64,
        /// Calls before a run is abandoned.
        #[arg(long, default_value_t = 1500)]
        max_calls: u32,
        /// Output folder (stress.csv, summary.json).
        #[arg(long, default_value = "out/stress")]
        out: PathBuf,
    },
    /// Work per `plan` call with a clock that never advances (only the work cap ends a call):
    /// 2,048 and 8,192 nodes, both rewiring modes, on the first leg of each scenario.
    Frozen {
        /// Scenario file (e.g. ../shared/maps/scenarios.toml); the built-in maps without it.
        #[arg(long)]
        scenarios: Option<PathBuf>,
        #[command(flatten)]
        body: BodyArgs,
        /// Scenario names in --scenarios (comma-separated; all by default).
        #[arg(long, value_delimiter = ',')]
        maps: Option<Vec<String>>,
        /// Planner name (Table 1).
        #[arg(long, default_value = "Bi-AM-RRT*(D)")]
        planner: String,
        /// Calls per configuration.
        #[arg(long, default_value_t = 10)]
        calls: u32,
    },
    /// Bake a metric table from a map.
    Bake {
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
    },
    /// Export a scenario for a firmware: its bit-packed grid, its diffusion table and Rust
    /// source that `include!`s them as flash `static`s (with the start and goals).
    Export {
        /// Scenario file (TOML), or `builtin`.
        #[arg(long)]
        scenarios: PathBuf,
        #[command(flatten)]
        body: BodyArgs,
        /// Scenario to export.
        #[arg(long)]
        scenario: String,
        /// Output folder (created): NAME.grid, NAME.table, NAME.rs, and scenario.rs (the same
        /// source, which the firmware example includes).
        #[arg(long)]
        out: PathBuf,
        #[command(flatten)]
        table: TableArgs,
        /// Flash the firmware leaves to grid and table, in bytes: with `--max-bytes 0` the table
        /// is kept within it (the firmware example: 144 KiB of its 256 KiB); a grid too large
        /// for it is refused with the way out.
        #[arg(long, default_value_t = bake::FIRMWARE_DATA_BYTES)]
        flash_data: usize,
    },
    /// Measure how the expansion rate changes as the tree grows (no motion, wall clock).
    Growth {
        /// Scenario file (TOML), or `builtin`.
        #[arg(long)]
        scenarios: PathBuf,
        #[command(flatten)]
        body: BodyArgs,
        /// Comma-separated scenario names (default: all in the file).
        #[arg(long, value_delimiter = ',')]
        maps: Option<Vec<String>>,
        /// Comma-separated Table 1 names.
        #[arg(long, default_value = "Bi-AM-RRT*(D),Bi-AM-RRT*(E)")]
        planners: String,
        /// Seconds of planning per planner and mode.
        #[arg(long, default_value_t = 3.0)]
        seconds: f64,
        /// Length of one plan call (ms).
        #[arg(long, default_value_t = 50)]
        call_ms: u64,
        /// First seed.
        #[arg(long, default_value_t = 1)]
        seed: u64,
        /// Output folder.
        #[arg(long, default_value = "out/growth")]
        out: PathBuf,
    },
    /// The exact optimum of every leg of a scenario (the yardstick of travelled / optimum),
    /// with the map's obstacle corners and the CPU time each leg took (nothing cached), and
    /// the grid planners beside it: A* on the 8-connected grid and Theta*, length / optimum
    /// and CPU time.
    Optimum {
        /// Scenario file.
        #[arg(long)]
        scenarios: PathBuf,
        /// Scenario name in --scenarios.
        #[arg(long)]
        scenario: String,
        #[command(flatten)]
        body: BodyArgs,
    },
    /// Measure wall nanoseconds per unit of planner work (to calibrate the virtual clock).
    Calibrate {
        /// Runs (the median is reported).
        #[arg(long, default_value_t = 5)]
        repeats: u32,
    },
}

fn kind_of(k: KindArg) -> ElementKind {
    match k {
        KindArg::I16 => ElementKind::I16,
        KindArg::F32 => ElementKind::F32,
    }
}

/// The robot's body, shared by every command that runs a planner.
#[derive(Args, Clone, Copy, Debug)]
struct BodyArgs {
    /// The robot's radius in metres: every path keeps the disc clear of the walls and
    /// obstacles (default: the scenario file's `robot_radius_m`, else 0, a point).
    #[arg(long, value_name = "METRES")]
    robot_radius: Option<f32>,
    /// Move a start or goal where the robot's disc has no room to the nearest position where
    /// it has, and say how far (without it such a scenario is refused, naming that position).
    #[arg(long)]
    snap_to_room: bool,
    /// Prefer paths that keep this many metres beyond the robot's body where the space
    /// allows (a cost that rises near walls, as nav2's inflation layer: see docs/body.md;
    /// default: none, every edge costs its length).
    #[arg(long, value_name = "METRES")]
    clearance_margin: Option<f32>,
    /// How much more a metre costs at the body's edge than in open space, with
    /// --clearance-margin.
    #[arg(
        long,
        value_name = "W",
        default_value_t = 1.0,
        requires = "clearance_margin"
    )]
    clearance_weight: f32,
}

impl BodyArgs {
    /// The scenario for the robot these flags name (unchanged without them).
    fn apply(&self, sc: maps::Scenario) -> Result<maps::Scenario> {
        let radius = self.robot_radius.unwrap_or(sc.robot_radius);
        let sc = if self.robot_radius.is_none() && !self.snap_to_room {
            sc
        } else {
            sc.with_body(radius, self.snap_to_room)?
        };
        match self.clearance_margin {
            Some(m) => sc.with_clearance(m, self.clearance_weight),
            None => Ok(sc),
        }
    }

    fn apply_all(&self, scs: Vec<maps::Scenario>) -> Result<Vec<maps::Scenario>> {
        scs.into_iter().map(|s| self.apply(s)).collect()
    }
}

/// Refuses a clearance preference (`--clearance-margin`, or a scenario file's
/// `clearance_margin_m`) on a command that cannot honour it, saying `why`.
fn no_clearance(scs: &[maps::Scenario], why: &str) -> Result<()> {
    match scs.iter().find(|s| s.clearance.is_some()) {
        Some(s) => bail!(
            "scenario {}: a clearance preference is not supported here: {why}",
            s.name
        ),
        None => Ok(()),
    }
}

/// The diffusion table options shared by `experiment`, `bake` and `export`.
#[derive(Args)]
struct TableArgs {
    /// Diffusion table element type.
    #[arg(long, value_enum, default_value = "i16")]
    table_kind: KindArg,
    /// Diffusion table: map cells per block along each axis (0: the block side that fits
    /// --max-bytes with the smallest error).
    #[arg(long, default_value_t = 0)]
    coarsen: u16,
    /// Diffusion table: size budget in bytes when --coarsen is 0 (0: 128 KiB, plus the piece
    /// map's half byte per cell beyond 32 KiB on maps over 65,536 cells).
    #[arg(long, default_value_t = 0)]
    max_bytes: usize,
    /// Diffusion bake: most memory it may use, in MiB (estimated before it starts; a larger
    /// bake is refused with its estimate).
    #[arg(long, default_value_t = host_sim::diffusion::DEFAULT_MAX_MEMORY >> 20)]
    max_memory: usize,
    /// Diffusion bake: compute the map on every free cell (`cells`), on the table's pieces
    /// (`pieces`), or `auto` (cells up to 65,536 free cells, pieces above).
    #[arg(long, value_enum, default_value = "auto")]
    basis: host_sim::diffusion::BasisChoice,
    /// Diffusion table layout: `pieces` (one entry per connected free piece of a block,
    /// never across a wall) or `uniform` (one entry per block, the format-1 table).
    #[arg(long, value_enum, default_value = "pieces")]
    layout: TableLayout,
}

impl TableArgs {
    fn options(self) -> TableOptions {
        TableOptions {
            kind: kind_of(self.table_kind),
            coarsen: self.coarsen,
            max_bytes: self.max_bytes,
            layout: self.layout,
            max_memory: self.max_memory << 20,
            basis: self.basis,
            map_hash: None,
            keep: None,
        }
    }
}

fn load_map(spec: &str, resolution: Option<f32>) -> Result<maps::OwnedGrid> {
    let mut grid = match spec.strip_prefix("builtin:") {
        Some(name) => maps::builtin_by_name(name)?.map,
        None if spec.ends_with(".yaml") || spec.ends_with(".yml") => {
            if resolution.is_some() {
                bail!("--resolution is for PNG maps: a ROS map's YAML gives its own");
            }
            maps::load_ros_yaml(&PathBuf::from(spec))?.grid
        }
        None => maps::load_png(&PathBuf::from(spec))?,
    };
    if let Some(r) = resolution {
        if !(r.is_finite() && r > 0.0) {
            bail!("--resolution {r}: must be a positive number of metres");
        }
        grid.cell_bits = r.to_bits();
    }
    Ok(grid)
}

fn main() -> Result<()> {
    let cli = Cli::parse();
    match cli.command {
        Command::Run {
            builtin,
            scenarios,
            body,
            scenario,
            planner,
            all_goals,
            seed,
            clock,
            obstacle,
            out,
            animate,
            t_exp_ms,
            paper_lengths,
            pace,
            no_optimum,
        } => {
            let sc = match (scenarios, scenario) {
                (Some(file), Some(name)) => maps::load_scenarios(&file, Some(&[name]))?.remove(0),
                (Some(_), None) => bail!("--scenarios needs --scenario NAME"),
                (None, Some(_)) => bail!("--scenario needs --scenarios FILE"),
                (None, None) => maps::builtin_by_name(&builtin)?,
            };
            let mut sc = body.apply(sc)?;
            sc.paper_lengths = paper_lengths;
            run::run(&RunArgs {
                scenario: sc,
                planner,
                all_goals,
                seed,
                clock,
                obstacle,
                out,
                animate,
                t_exp: t_exp_ms.map(std::time::Duration::from_millis),
                pace,
                no_optimum,
            })
        }
        Command::Moving {
            builtin,
            scenarios,
            body,
            scenario,
            kinds,
            seeds,
            t_exp_ms,
            out,
            animate,
        } => {
            let sc = match (scenarios, scenario) {
                (Some(file), Some(name)) => maps::load_scenarios(&file, Some(&[name]))?.remove(0),
                (Some(_), None) => bail!("--scenarios needs --scenario NAME"),
                (None, Some(_)) => bail!("--scenario needs --scenarios FILE"),
                (None, None) => maps::builtin_by_name(&builtin)?,
            };
            let prep = host_sim::sim::Prepared::new(body.apply(sc)?);
            host_sim::moving::moving(
                &prep,
                &host_sim::moving::MovingArgs {
                    kinds,
                    seeds,
                    t_exp: std::time::Duration::from_millis(t_exp_ms),
                    out,
                    animate,
                    route_calls: host_sim::moving::ROUTE_CALLS,
                },
            )?;
            Ok(())
        }
        Command::Experiment {
            scenarios,
            body,
            maps: names,
            planners,
            repeats,
            clock,
            goals,
            seed,
            jobs,
            faithful,
            table,
            t_exp_ms,
            search_only,
            anytime_ms,
            shard,
            resume,
            overwrite,
            out,
            wait_from_set,
            pace,
            no_optimum,
            paper_lengths,
            as_printed,
            meet_all_pairs,
            obstacle,
        } => {
            let mut scs = body.apply_all(maps::load_scenarios(&scenarios, names.as_deref())?)?;
            for s in &mut scs {
                s.paper_lengths = paper_lengths;
            }
            experiment::run(&ExperimentArgs {
                wait_from_set,
                pace,
                no_optimum,
                as_printed: experiment::parse_as_printed(&as_printed)?,
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
                planners: experiment::parse_planners(&planners)?,
                repeats,
                clock,
                goals,
                seed,
                jobs,
                faithful,
                search_only,
                anytime_ms,
                table: table.options(),
                t_exp: t_exp_ms.map(std::time::Duration::from_millis),
                out,
            })
            .map(|_| ())
        }
        Command::Report {
            results,
            out,
            notes,
        } => {
            let out = out.unwrap_or_else(|| results.join("report.md"));
            let mut command = format!(
                "host-sim report --results {} --out {}",
                results.display(),
                out.display()
            );
            let notes = match &notes {
                Some(n) => {
                    command.push_str(&format!(" --notes {}", n.display()));
                    Some(
                        std::fs::read_to_string(n)
                            .with_context(|| format!("reading {}", n.display()))?,
                    )
                }
                None => None,
            };
            if results.join(host_sim::moving::SETTINGS_FILE).exists() {
                let charts = host_sim::moving::report(&results, &out, &command)?;
                println!(
                    "wrote {} and {} chart (SVG and PNG) of a moving run",
                    out.display(),
                    charts.len()
                );
                return Ok(());
            }
            let r = host_sim::report::report(&results, &out, &command, notes.as_deref())?;
            println!(
                "wrote {} and {} charts (SVG and PNG) in {}",
                r.markdown.display(),
                r.charts.len(),
                out.with_extension("").display()
            );
            Ok(())
        }
        Command::Compare {
            base,
            variants,
            out,
            notes,
        } => {
            let vs = variants
                .iter()
                .map(|v| {
                    let (l, d) = v
                        .split_once('=')
                        .with_context(|| format!("variant {v:?}: expected LABEL=FOLDER"))?;
                    Ok((l.to_string(), PathBuf::from(d)))
                })
                .collect::<Result<Vec<_>>>()?;
            let notes_text = notes
                .as_ref()
                .map(std::fs::read_to_string)
                .transpose()
                .context("reading --notes")?;
            let command = std::iter::once("host-sim".to_string())
                .chain(std::env::args().skip(1))
                .collect::<Vec<_>>()
                .join(" ");
            host_sim::report::compare(&base, &vs, &out, &command, notes_text.as_deref())?;
            println!("wrote {}", out.display());
            Ok(())
        }
        Command::Merge { out, inputs } => {
            let m = host_sim::results::merge(&inputs, &out)?;
            experiment::print_summary(&m.summary);
            println!(
                "merged {} folders: {} runs{} -> {}",
                inputs.len(),
                m.runs,
                if m.missing > 0 {
                    format!(", {} runs of the matrix missing", m.missing)
                } else {
                    String::new()
                },
                out.display()
            );
            Ok(())
        }
        Command::Bench {
            scenarios,
            body,
            maps: names,
            legs,
            planners,
            seeds,
            mut budgets,
            nodes,
            table,
            out,
            ompl,
            clock,
            paper_lengths,
            warm,
            cold: _,
            until_first,
            no_grid,
        } => {
            if budgets.iter().any(|b| !(b.is_finite() && *b > 0.0)) {
                bail!("--budgets: every budget must be a positive number of seconds");
            }
            budgets.sort_by(f64::total_cmp);
            let mut scs = body.apply_all(maps::load_scenarios(&scenarios, names.as_deref())?)?;
            no_clearance(
                &scs,
                "bench compares path costs with OMPL's, which are lengths",
            )?;
            for s in &mut scs {
                s.paper_lengths = paper_lengths;
            }
            let variants = host_sim::bench::parse_variants(&planners)?;
            host_sim::bench::run(&host_sim::bench::BenchArgs {
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
        Command::Soak {
            scenarios,
            body,
            scenario,
            planner,
            minutes,
            goal_every,
            speed,
            nodes,
            seed,
            table,
            out,
        } => {
            if !(minutes > 0.0 && goal_every > 0.0 && speed > 0.0) {
                bail!("--minutes, --goal-every and --speed must be positive");
            }
            let mut scs = body.apply_all(maps::load_scenarios(&scenarios, Some(&[scenario]))?)?;
            let variant = host_sim::bench::parse_variants(&planner)?
                .into_iter()
                .next()
                .context("no planner")?;
            host_sim::soak::run(&host_sim::soak::SoakArgs {
                scenario: scs.remove(0),
                variant,
                seconds: minutes * 60.0,
                goal_every,
                speed,
                nodes,
                seed,
                out,
                table: table.options(),
            })
            .map(|_| ())
        }
        Command::Stress {
            runs,
            planners,
            seed,
            t_exp_ms,
            max_calls,
            out,
        } => stress::run_and_report(
            &stress::StressArgs {
                runs,
                planners: experiment::parse_planners(&planners)?,
                seed,
                t_exp: std::time::Duration::from_millis(t_exp_ms),
                max_calls,
            },
            &out,
        ),
        Command::Frozen {
            scenarios,
            body,
            maps: names,
            planner,
            calls,
        } => {
            let scs = match scenarios {
                Some(file) => maps::load_scenarios(&file, names.as_deref())?,
                None => maps::builtin_scenarios(),
            };
            let scs = body.apply_all(scs)?;
            let base = experiment::parse_planners(&planner)?
                .first()
                .copied()
                .context("no planner")?;
            host_sim::bounds::print_frozen(scs, base, calls)
        }
        Command::Export {
            scenarios,
            body,
            scenario,
            out,
            table,
            flash_data,
        } => {
            let sc = body.apply(maps::load_scenarios(&scenarios, Some(&[scenario]))?.remove(0))?;
            no_clearance(
                std::slice::from_ref(&sc),
                "export does not write a clearance field yet (build one at start-up with bi_am_rrt::clearance::clearance_field)",
            )?;
            bake::export_command(&sc, &table.options(), &out, flash_data)
        }
        Command::Bake {
            map,
            resolution,
            metric,
            out,
            table,
            rust,
            all_pairs,
        } => {
            let grid = load_map(&map, resolution)?;
            match metric {
                MetricArg::Diffusion => {
                    bake::diffusion_command(&grid, &map, &out, &table.options(), rust.as_deref())
                }
                MetricArg::Geodesic => bake::geodesic_command(&grid, &map, &out, all_pairs),
            }
        }
        Command::Growth {
            scenarios,
            body,
            maps: names,
            planners,
            seconds,
            call_ms,
            seed,
            out,
        } => {
            let scs = body.apply_all(maps::load_scenarios(&scenarios, names.as_deref())?)?;
            host_sim::growth::growth(
                &scs,
                &experiment::parse_planners(&planners)?,
                seconds,
                call_ms,
                seed,
                &out,
            )
        }
        Command::Optimum {
            scenarios,
            scenario,
            body,
        } => {
            let sc = body.apply(maps::load_scenarios(&scenarios, Some(&[scenario]))?.remove(0))?;
            host_sim::optimum::report(&sc);
            Ok(())
        }
        Command::Calibrate { repeats } => {
            host_sim::growth::calibrate(repeats).context("calibrating")
        }
    }
}
