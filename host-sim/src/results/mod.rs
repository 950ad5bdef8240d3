//! A results folder: what `experiment` writes and `merge` and `report` read.
//!
//! - `experiment.json`, the manifest: the settings every run of the folder shares (scenarios
//!   with a digest of their map, start, goals and `sigma`; planners; seeds; clock; protocol
//!   switches), the shard the folder holds, and each map's processing times (the paper's
//!   Table 3: diffusion bake, grid graph, one geodesic distance field).
//! - `runs.csv`: one row per run and goal (a run is a planner, a scenario and a seed), appended
//!   and flushed as each run ends, so an interrupted experiment keeps every finished run and
//!   `--resume` runs only the rest. When the folder's matrix is complete it is rewritten in the
//!   canonical order (scenario, planner, seed, goal: the manifest's order), whatever the
//!   scheduling or the sharding was.
//! - `runs.json`, `summary.csv` and `summary.json`, written when the matrix is complete (or
//!   merged): the rows as JSON, and per planner, scenario and goal the median, quartiles and
//!   mean of search time, path length and travelled / optimal.
//!
//! `merge` joins folders whose settings are equal (shards of one matrix, or runs done on
//! several machines) into one; a run present twice is an error.

pub mod stats;
pub mod table;

use std::collections::BTreeSet;
use std::fs::{self, File, OpenOptions};
use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use serde::{Deserialize, Serialize};

use crate::results::stats::Spread;
use crate::scenario::Scenario;
use crate::sim::clock::ClockKind;

fn is_false(b: &bool) -> bool {
    !*b
}

/// The manifest's file name.
pub const MANIFEST: &str = "experiment.json";
/// The rows' file name.
pub const RUNS: &str = "runs.csv";

/// Which goals a run drives through.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Goals {
    /// Start to goal 1 (the Bi-AM-RRT* paper's static experiment).
    First,
    /// The whole sequence (the AM-RRT* paper's benchmark).
    All,
}

/// How much a `plan` call computes (`experiment --pace`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Pace {
    /// As much as `t_exp` allows on this implementation (over a thousand expansions).
    #[default]
    Full,
    /// The paper's pace: 20 tree expansions a call (each tree's count, so a two-tree planner
    /// grows each tree about half as often) and 8 rewiring visits per phase and expansion
    /// (`sim::PAPER_EXPANSIONS_PER_CALL`, `sim::PAPER_VISITS`), every call lasting its full
    /// `t_exp` on the virtual clock, as a call of the paper's Python did.
    Paper,
}

/// A scenario as the manifest names it: its name and a digest of what a run depends on.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ScenarioId {
    /// The scenario's name.
    pub name: String,
    /// FNV-1a of the map (size, cell, cells), the start, the goals and `sigma`, in hex.
    pub digest: String,
}

impl ScenarioId {
    /// The id of a scenario.
    pub fn of(s: &Scenario) -> Self {
        let mut bytes = Vec::with_capacity(s.map.bits.len() + 64);
        bytes.extend_from_slice(&s.map.width.to_le_bytes());
        bytes.extend_from_slice(&s.map.height.to_le_bytes());
        bytes.extend_from_slice(&s.map.cell_bits.to_le_bytes());
        bytes.extend_from_slice(&s.map.bits);
        for p in std::iter::once(&s.start).chain(&s.goals) {
            bytes.extend_from_slice(&p.x.to_le_bytes());
            bytes.extend_from_slice(&p.y.to_le_bytes());
        }
        bytes.extend_from_slice(&s.sigma().to_le_bytes());
        // Only when set, so the digests of earlier folders stay valid.
        if s.paper_lengths {
            bytes.extend_from_slice(b"paper lengths");
        }
        Self {
            name: s.name.clone(),
            digest: format!("{:08x}", bi_am_rrt::metric::fnv1a32(&bytes)),
        }
    }
}

/// What every run of a folder shares: two folders can be resumed into one another or merged
/// only when these are equal.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    /// Scenarios, in the matrix's order.
    pub scenarios: Vec<ScenarioId>,
    /// Planner names, in the matrix's order.
    pub planners: Vec<String>,
    /// Runs per planner and scenario.
    pub repeats: u32,
    /// First seed (run `r` uses `seed + r`).
    pub seed: u64,
    /// Clock.
    pub clock: ClockKind,
    /// Goals driven per run.
    pub goals: Goals,
    /// Reference-style rewiring budgets.
    pub faithful: bool,
    /// Runs stop when the goal joins.
    pub search_only: bool,
    /// Anytime measurement in ms (0: none).
    pub anytime_ms: u64,
    /// `t_exp` override in ms (`None`: each planner's own, the paper's 150 ms).
    pub t_exp_ms: Option<f64>,
    /// Diffusion table options, as text.
    pub table: String,
    /// The agent's 0.25 s wait counted from when the goal is set (the reference's benchmark)
    /// instead of from the join (absent in folders made before issue 24: false).
    #[serde(default)]
    pub wait_from_set: bool,
    /// The reference's agent rule (`--move-when-blocked`): the agent moves along the tree's
    /// path whatever its blocked flags (absent, and not written, when off).
    #[serde(default, skip_serializing_if = "is_false")]
    pub move_when_blocked: bool,
    /// Work per call (absent in folders made before issue 24: full).
    #[serde(default)]
    pub pace: Pace,
    /// The parts of Algorithms 4 and 6 run as printed (`bi_am_rrt::AsPrinted` switch names;
    /// absent before issue 24: none).
    #[serde(default)]
    pub as_printed: Vec<String>,
    /// The paper's Meet over every pair within sigma (`Config::meet_all_pairs`; absent
    /// before issue 24: the 16 cheapest pairs).
    #[serde(default)]
    pub meet_all_pairs: bool,
    /// Fig. 7: radius of the disc dropped on goal 1's path (absent before issue 24: none).
    #[serde(default)]
    pub obstacle_m: Option<f32>,
    /// Each planner's full configuration as the runs start from it (every value of the core's
    /// parameter table, `host-sim params`), in the order of `planners`, before its lengths
    /// are fitted to each map (absent before issue 43: not compared).
    #[serde(default)]
    pub configs: Vec<std::collections::BTreeMap<String, String>>,
}

/// A configuration as a results folder records it: every value of the parameter table, as
/// text.
pub fn config_record(cfg: &bi_am_rrt::Config) -> std::collections::BTreeMap<String, String> {
    bi_am_rrt::config::PARAMS
        .iter()
        .map(|p| (p.name.to_string(), p.get(cfg).to_string()))
        .collect()
}

impl Settings {
    /// Every run of the matrix, in canonical order: (scenario, planner, seed).
    pub fn runs(&self) -> Vec<RunKey> {
        let mut out = Vec::new();
        for s in &self.scenarios {
            for p in &self.planners {
                for r in 0..self.repeats {
                    out.push(RunKey {
                        scenario: s.name.clone(),
                        planner: p.clone(),
                        seed: self.seed + u64::from(r),
                    });
                }
            }
        }
        out
    }

    /// The first setting that differs from `other`, named, or `None`.
    pub fn difference(&self, other: &Settings) -> Option<String> {
        let a = serde_json::to_value(self).ok()?;
        let b = serde_json::to_value(other).ok()?;
        let (a, b) = (a.as_object()?, b.as_object()?);
        // A folder made before the configurations were recorded has none to compare.
        let unrecorded =
            |k: &str| k == "configs" && (self.configs.is_empty() || other.configs.is_empty());
        a.iter()
            .find(|(k, v)| !unrecorded(k) && b.get(*k) != Some(v))
            .map(|(k, v)| {
                format!(
                    "{k}: {v} here, {} there",
                    b.get(k).cloned().unwrap_or_default()
                )
            })
    }
}

/// A deterministic slice of a matrix: runs `i` with `i % count == index - 1`, in the canonical
/// order, so shards `1/N` .. `N/N` hold every run once.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Shard {
    /// 1-based.
    pub index: u32,
    /// Number of shards.
    pub count: u32,
}

impl std::str::FromStr for Shard {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("--shard {s:?}: expected K/N with 1 <= K <= N (e.g. 3/8)");
        let (k, n) = s.split_once('/').ok_or_else(bad)?;
        let (index, count) = (
            k.trim().parse::<u32>().map_err(|_| bad())?,
            n.trim().parse::<u32>().map_err(|_| bad())?,
        );
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

impl std::fmt::Display for Shard {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

impl Shard {
    /// Keeps the runs of this shard.
    pub fn select<T>(self, runs: Vec<T>) -> Vec<T> {
        runs.into_iter()
            .enumerate()
            .filter(|(i, _)| *i as u64 % u64::from(self.count) == u64::from(self.index - 1))
            .map(|(_, r)| r)
            .collect()
    }
}

/// A map's processing times (the paper's Table 3), measured when the folder was (last) run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MapTimes {
    /// Scenario name.
    pub scenario: String,
    /// Map size in cells and the cell side in metres.
    pub cols: u16,
    pub rows: u16,
    pub cell_m: f32,
    /// Seconds of the diffusion bake (graph, eigenpairs, time scale, table), if any planner
    /// needed it.
    pub diffusion_bake_s: Option<f64>,
    /// Bytes of the diffusion table.
    pub table_bytes: Option<usize>,
    /// Seconds to build the grid graph (the geodesic metric's preprocessing).
    pub graph_s: f64,
    /// Seconds of one geodesic distance field (a Dijkstra over the grid graph); the geodesic
    /// metric computes one per target and caches it.
    pub geodesic_field_s: f64,
    /// Seconds of the exact optima of every leg (visibility graph + Dijkstra).
    pub optima_s: f64,
}

/// The manifest of a results folder.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Manifest {
    /// `host-sim` version that wrote it.
    pub tool: String,
    /// What every run shares.
    pub settings: Settings,
    /// The slice of the matrix this folder holds (`None`: all of it).
    pub shard: Option<Shard>,
    /// Processing times per map.
    pub maps: Vec<MapTimes>,
}

impl Manifest {
    /// Reads `dir/experiment.json` (`None` when absent).
    pub fn read(dir: &Path) -> Result<Option<Self>> {
        let path = dir.join(MANIFEST);
        if !path.exists() {
            return Ok(None);
        }
        let text = fs::read_to_string(&path).with_context(|| format!("{}", path.display()))?;
        serde_json::from_str(&text)
            .map(Some)
            .with_context(|| format!("{} is not a manifest", path.display()))
    }

    /// Writes `dir/experiment.json`.
    pub fn write(&self, dir: &Path) -> Result<()> {
        write_atomic(
            &dir.join(MANIFEST),
            serde_json::to_string_pretty(self)?.as_bytes(),
        )
    }

    /// The runs this folder is meant to hold.
    pub fn runs(&self) -> Vec<RunKey> {
        let all = self.settings.runs();
        match self.shard {
            Some(s) => s.select(all),
            None => all,
        }
    }
}

/// Which run a row belongs to.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct RunKey {
    pub scenario: String,
    pub planner: String,
    pub seed: u64,
}

/// One row of `runs.csv`: one goal of one run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Row {
    pub planner: String,
    pub scenario: String,
    /// 1-based, as everywhere in the output.
    pub goal_index: usize,
    pub seed: u64,
    pub reached: bool,
    /// Goal set until the goal is in the forward tree, on the run's clock.
    pub search_time_s: Option<f64>,
    /// Path travelled by the agent for this goal; empty in a `--search-only` run, where the
    /// agent does not move.
    pub path_length_m: Option<f32>,
    /// The leg's exact optimum (from where the agent stood when the goal was set).
    pub optimal_m: Option<f32>,
    /// `path_length_m / optimal_m` for a reached goal.
    pub travelled_ratio: Option<f32>,
    pub collisions: u32,
    /// Nodes in the forward tree when the goal joined.
    pub nodes_at_goal: Option<usize>,
    /// Search time read at the end of the call in which the goal joined (the reference's
    /// definition; absent in data made before issue 24).
    #[serde(default)]
    pub search_time_call_end_s: Option<f64>,
    /// Forward tree size at the end of that call (the reference's nodes at goal).
    #[serde(default)]
    pub nodes_at_call_end: Option<usize>,
    pub calls: u32,
    /// The tree's path cost when the agent started moving.
    pub cost_at_start_m: Option<f32>,
    /// Cost after `anytime_ms` of planning towards goal 1 without moving.
    pub anytime_cost_m: Option<f32>,
    pub final_nodes: usize,
    /// Fig. 7 (`experiment --obstacle`; absent before issue 24; empty when no disc was
    /// dropped on this goal's path, [`crate::sim::drop_on_path`]): the disc's centre and
    /// radius.
    #[serde(default)]
    pub disc_x_m: Option<f32>,
    #[serde(default)]
    pub disc_y_m: Option<f32>,
    #[serde(default)]
    pub disc_r_m: Option<f32>,
    /// The path's cost to the goal just before the drop.
    #[serde(default)]
    pub cost_before_drop_m: Option<f32>,
    /// From the drop to the end of the first call whose path to the goal is free of it
    /// (`None`: no such call before the run ended).
    #[serde(default)]
    pub replan_s: Option<f64>,
    /// That first free path's cost.
    #[serde(default)]
    pub replanned_cost_m: Option<f32>,
    /// What the agent travelled from where it stood at the drop to the goal.
    #[serde(default)]
    pub travelled_after_drop_m: Option<f32>,
    /// The exact optimum from there with the disc in place (rasterised to cells of at most
    /// 0.25 m lying wholly inside it, so at most the true optimum).
    #[serde(default)]
    pub optimal_after_drop_m: Option<f32>,
    pub clock: ClockKind,
    /// Wall seconds of the whole run (all its goals; not repeatable).
    pub run_wall_s: f64,
}

impl Row {
    /// The run this row belongs to.
    pub fn key(&self) -> RunKey {
        RunKey {
            scenario: self.scenario.clone(),
            planner: self.planner.clone(),
            seed: self.seed,
        }
    }
}

/// One row of `summary.csv`: a planner on a scenario's goal, over its runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Summary {
    pub planner: String,
    pub scenario: String,
    pub goal_index: usize,
    pub runs: usize,
    pub reached: usize,
    /// Runs in which the goal joined the tree (what a `--search-only` run counts; not in the
    /// files, which hold the search times).
    #[serde(skip)]
    pub found: usize,
    pub collisions: u32,
    #[serde(serialize_with = "short")]
    pub search_time_median_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub search_time_q1_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub search_time_q3_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub search_time_mean_s: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_median_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_q1_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_q3_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub path_length_mean_m: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_median: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_q1: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_q3: Option<f64>,
    #[serde(serialize_with = "short")]
    pub travelled_ratio_max: Option<f64>,
    #[serde(serialize_with = "short")]
    pub nodes_at_goal_median: Option<f64>,
    #[serde(serialize_with = "short")]
    pub nodes_at_goal_mean: Option<f64>,
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
            let search = Spread::of(group.iter().filter_map(|r| r.search_time_s).collect());
            let len = Spread::of(
                reached
                    .iter()
                    .filter_map(|r| r.path_length_m.map(f64::from))
                    .collect(),
            );
            let ratios: Vec<f64> = reached
                .iter()
                .filter_map(|r| r.travelled_ratio.map(f64::from))
                .collect();
            let ratio_max = ratios.iter().copied().reduce(f64::max);
            let ratio = Spread::of(ratios);
            let nodes = Spread::of(
                group
                    .iter()
                    .filter_map(|r| r.nodes_at_goal.map(|n| n as f64))
                    .collect(),
            );
            let any = Spread::of(
                group
                    .iter()
                    .filter_map(|r| r.anytime_cost_m.map(f64::from))
                    .collect(),
            );
            Summary {
                runs: group.len(),
                reached: reached.len(),
                found: group.iter().filter(|r| r.search_time_s.is_some()).count(),
                collisions: group.iter().map(|r| r.collisions).sum(),
                search_time_median_s: search.median,
                search_time_q1_s: search.q1,
                search_time_q3_s: search.q3,
                search_time_mean_s: search.mean,
                path_length_median_m: len.median,
                path_length_q1_m: len.q1,
                path_length_q3_m: len.q3,
                path_length_mean_m: len.mean,
                travelled_ratio_median: ratio.median,
                travelled_ratio_q1: ratio.q1,
                travelled_ratio_q3: ratio.q3,
                travelled_ratio_max: ratio_max,
                nodes_at_goal_median: nodes.median,
                nodes_at_goal_mean: nodes.mean,
                anytime_cost_median_m: any.median,
                planner,
                scenario,
                goal_index,
            }
        })
        .collect()
}

/// Writes `bytes` to `path` through a temporary file and a rename (never half a file).
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = path.with_extension("tmp");
    fs::write(&tmp, bytes).with_context(|| format!("{}", tmp.display()))?;
    fs::rename(&tmp, path).with_context(|| format!("{}", path.display()))
}

/// Reads a folder's `runs.csv` (no file: no rows). A last line cut short by an interruption is
/// dropped (and cut from the file when `repair`); anything else malformed is an error.
pub fn read_rows(dir: &Path, repair: bool) -> Result<Vec<Row>> {
    let path = dir.join(RUNS);
    if !path.exists() {
        return Ok(Vec::new());
    }
    let mut text = fs::read_to_string(&path).with_context(|| format!("{}", path.display()))?;
    if !text.is_empty() && !text.ends_with('\n') {
        let keep = text.rfind('\n').map_or(0, |i| i + 1);
        eprintln!(
            "warning: {}: its last line is cut ({} bytes without an end: a run stopped while \
             writing it); {}",
            path.display(),
            text.len() - keep,
            if repair {
                "removed, the run is done again"
            } else {
                "left out (`experiment --resume` removes it and runs it again)"
            }
        );
        text.truncate(keep);
        if repair {
            write_atomic(&path, text.as_bytes())?;
        }
    }
    let mut rdr = csv::Reader::from_reader(text.as_bytes());
    rdr.deserialize()
        .enumerate()
        .map(|(i, r)| r.with_context(|| format!("{} row {}", path.display(), i + 1)))
        .collect()
}

/// Appends the rows of finished runs to `runs.csv`, one flush per run.
pub struct RowSink {
    file: File,
    header: bool,
}

impl RowSink {
    /// Opens `dir/runs.csv` for appending (writing the header first if the file is new).
    pub fn open(dir: &Path) -> Result<Self> {
        let path = dir.join(RUNS);
        let header = !path.exists() || fs::metadata(&path)?.len() == 0;
        let file = OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .with_context(|| format!("{}", path.display()))?;
        Ok(Self { file, header })
    }

    /// Appends one run's rows in a single write.
    pub fn append(&mut self, rows: &[Row]) -> Result<()> {
        self.file.write_all(&csv_bytes(rows, self.header)?)?;
        self.file.flush()?;
        self.header = false;
        Ok(())
    }
}

/// The canonical order of rows: the manifest's scenario and planner order, then seed and goal.
pub fn sort_rows(settings: &Settings, rows: &mut [Row]) {
    let pos = |r: &Row| {
        (
            settings.scenarios.iter().position(|s| s.name == r.scenario),
            settings.planners.iter().position(|p| *p == r.planner),
            r.seed,
            r.goal_index,
        )
    };
    rows.sort_by_key(pos);
}

/// `items` as CSV (with a header line when `header`).
fn csv_bytes<T: Serialize>(items: &[T], header: bool) -> Result<Vec<u8>> {
    let mut w = csv::WriterBuilder::new()
        .has_headers(header)
        .from_writer(Vec::new());
    for it in items {
        w.serialize(it)?;
    }
    w.into_inner().map_err(|e| anyhow::anyhow!("{e}"))
}

/// Replaces `dir/runs.csv` with `rows`, atomically.
pub fn write_rows(dir: &Path, rows: &[Row]) -> Result<()> {
    write_atomic(&dir.join(RUNS), &csv_bytes(rows, true)?)
}

/// Writes a complete folder: `runs.csv` in canonical order, `runs.json`, `summary.csv`,
/// `summary.json`. Returns the summary.
pub fn write_complete(dir: &Path, settings: &Settings, rows: &mut [Row]) -> Result<Vec<Summary>> {
    sort_rows(settings, rows);
    write_rows(dir, rows)?;
    write_atomic(
        &dir.join("runs.json"),
        serde_json::to_string_pretty(&rows)?.as_bytes(),
    )?;
    let summary = summarise(rows);
    write_atomic(&dir.join("summary.csv"), &csv_bytes(&summary, true)?)?;
    write_atomic(
        &dir.join("summary.json"),
        serde_json::to_string_pretty(&summary)?.as_bytes(),
    )?;
    Ok(summary)
}

/// The runs of `rows` (each once).
pub fn done_runs(rows: &[Row]) -> BTreeSet<RunKey> {
    rows.iter().map(Row::key).collect()
}

/// A results folder's lock, held while a command writes the folder (`experiment`, its
/// `--resume`, `merge`): a second writer is refused at once instead of interleaving rows or
/// sharing temporary files. An advisory lock on `.lock` in the folder, which the system
/// releases when the process ends, however it ends.
pub struct FolderLock {
    _file: fs::File,
}

impl FolderLock {
    /// Locks `dir` (which exists), or says who to wait for.
    pub fn take(dir: &Path) -> Result<Self> {
        let path = dir.join(".lock");
        let file = fs::OpenOptions::new()
            .create(true)
            .truncate(false)
            .write(true)
            .open(&path)
            .with_context(|| format!("{}", path.display()))?;
        match file.try_lock() {
            Ok(()) => Ok(Self { _file: file }),
            Err(fs::TryLockError::WouldBlock) => bail!(
                "{} is being written by another run (its lock {} is held): wait for it to end, \
                 or write to another folder",
                dir.display(),
                path.display()
            ),
            Err(fs::TryLockError::Error(e)) => {
                Err(e).with_context(|| format!("locking {}", path.display()))
            }
        }
    }
}

/// What `merge` did.
#[derive(Debug)]
pub struct Merged {
    /// Runs in the merged folder.
    pub runs: usize,
    /// Runs of the matrix missing from every input.
    pub missing: usize,
    /// The summary written.
    pub summary: Vec<Summary>,
    /// Whether the folders hold a `--search-only` experiment.
    pub search_only: bool,
}

/// Joins results folders with equal settings into `out` (rows in canonical order, JSON,
/// summaries, a manifest without a shard). The folders may also be *seed blocks*: the same
/// settings but for `seed` and `repeats`, whose seed ranges are disjoint and together
/// contiguous (`--seed 1 --repeats 5`, `--seed 6 --repeats 5`, ...): the merged folder holds
/// the whole range. A run found in two inputs is an error; runs of the matrix that no input
/// holds are counted in `missing` (and named on stderr).
pub fn merge(inputs: &[PathBuf], out: &Path, overwrite: bool) -> Result<Merged> {
    if inputs.is_empty() {
        bail!("merge: no input folders");
    }
    let same = |a: &Path, b: &Path| match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if let Some(d) = inputs.iter().find(|d| same(d, out)) {
        bail!("merge: --out {} is one of the inputs", d.display());
    }
    if !overwrite && (out.join(MANIFEST).exists() || out.join(RUNS).exists()) {
        bail!(
            "merge: {} already holds an experiment's results: --overwrite replaces them, or \
             choose another --out",
            out.display()
        );
    }
    fs::create_dir_all(out)?;
    let _lock = FolderLock::take(out)?;
    let mut manifest: Option<Manifest> = None;
    let mut rows: Vec<Row> = Vec::new();
    let mut seen: BTreeSet<RunKey> = BTreeSet::new();
    let mut blocks: Vec<(u64, u32)> = Vec::new();
    for dir in inputs {
        let m = Manifest::read(dir)?.with_context(|| {
            format!(
                "{} has no {MANIFEST} (not an experiment's folder)",
                dir.display()
            )
        })?;
        if let Some(first) = &manifest
            && let Some(d) = {
                let mut a = m.settings.clone();
                a.seed = first.settings.seed;
                a.repeats = first.settings.repeats;
                a.difference(&first.settings)
            }
        {
            bail!(
                "{} and {} were run with different settings ({d})",
                dir.display(),
                inputs[0].display()
            );
        }
        let r = read_rows(dir, false)?;
        let here = done_runs(&r);
        if let Some(k) = here.intersection(&seen).next() {
            bail!(
                "run {} / {} / seed {} is in {} and in an earlier input",
                k.scenario,
                k.planner,
                k.seed,
                dir.display()
            );
        }
        seen.extend(here);
        rows.extend(r);
        blocks.push((m.settings.seed, m.settings.repeats));
        manifest.get_or_insert(m);
    }
    let mut m = manifest.context("no manifest")?;
    m.shard = None;
    // Seed blocks: one range without gaps or overlaps (shards of one matrix repeat theirs).
    blocks.sort_unstable();
    blocks.dedup();
    let first = blocks[0].0;
    let mut next = first;
    for &(seed, repeats) in &blocks {
        if seed != next {
            bail!(
                "the inputs' seeds do not make one range: seeds {seed}.. follow {first}..{}",
                next.saturating_sub(1)
            );
        }
        next = seed + u64::from(repeats);
    }
    m.settings.seed = first;
    m.settings.repeats = u32::try_from(next - first).context("too many seeds")?;
    let wanted = m.settings.runs();
    let missing: Vec<&RunKey> = wanted.iter().filter(|k| !seen.contains(k)).collect();
    for k in missing.iter().take(10) {
        eprintln!(
            "merge: missing run {} / {} / seed {}",
            k.scenario, k.planner, k.seed
        );
    }
    m.write(out)?;
    let summary = write_complete(out, &m.settings, &mut rows)?;
    Ok(Merged {
        runs: seen.len(),
        missing: missing.len(),
        summary,
        search_only: m.settings.search_only,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_partition_the_matrix() {
        assert!("0/3".parse::<Shard>().is_err());
        assert!("4/3".parse::<Shard>().is_err());
        assert!("x".parse::<Shard>().is_err());
        let all: Vec<u32> = (0..10).collect();
        let mut joined: Vec<u32> = (1..=3)
            .flat_map(|k| Shard { index: k, count: 3 }.select(all.clone()))
            .collect();
        joined.sort();
        assert_eq!(joined, all);
        assert_eq!("2/3".parse::<Shard>().unwrap().select(all), vec![1, 4, 7]);
    }
}
