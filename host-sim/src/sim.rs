//! What every simulation shares: a scenario prepared for all metrics (grid graph, diffusion
//! table), the planner type of the simulator, and one planner run through a goal sequence
//! under the agent protocol of the core (`bi_am_rrt::agent`).

use std::sync::{Arc, OnceLock};
use std::time::Instant;

use anyhow::{Result, anyhow};
use bi_am_rrt::agent::{Protocol, RunResult, run_to_goal};
use bi_am_rrt::clock::Clock;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Map, MetricKind, Planner, Storage};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

use crate::bake::{Baked, bake_diffusion};
use crate::diffusion::{Options, TableOptions};
use crate::graph::GridGraph;
use crate::maps::Scenario;
use crate::metrics::{AnyMetric, Geodesic};

/// Nodes per tree in the simulator (office needs several thousand).
pub const NODES: usize = 8192;
/// Spatial-index buckets per tree (5 m buckets cover a 200 m map).
pub const BUCKETS: usize = 2048;
/// Dynamic obstacles at most.
pub const OBSTACLES: usize = 8;
/// Geodesic field cache per run, in bytes.
pub const GEODESIC_CACHE_BYTES: usize = 192 << 20;

/// The simulator's planner type with `N` nodes per tree.
pub type SizedPlanner<'s, 't, const N: usize> =
    Planner<'s, 't, AnyMetric<'t>, XorShiftRng, N, BUCKETS, OBSTACLES>;

/// The simulator's planner type.
pub type SimPlanner<'s, 't> = SizedPlanner<'s, 't, NODES>;

/// A scenario with its metric data, computed on first use and shared by all runs.
pub struct Prepared {
    /// The scenario.
    pub scenario: Scenario,
    graph: OnceLock<Arc<GridGraph>>,
    diffusion: OnceLock<Result<Baked, String>>,
    /// Seconds the diffusion bake took (once done).
    pub bake_seconds: OnceLock<f64>,
    /// Layout of the diffusion table.
    pub table: TableOptions,
    optima: OnceLock<Vec<Option<f64>>>,
}

impl Prepared {
    /// Wraps a scenario; nothing is computed yet.
    pub fn new(scenario: Scenario) -> Self {
        Self::with_table(scenario, TableOptions::default())
    }

    /// Wraps a scenario whose diffusion table will have this layout.
    pub fn with_table(scenario: Scenario, table: TableOptions) -> Self {
        Self {
            scenario,
            graph: OnceLock::new(),
            diffusion: OnceLock::new(),
            bake_seconds: OnceLock::new(),
            table,
            optima: OnceLock::new(),
        }
    }

    /// The grid graph (for the geodesic metric).
    pub fn graph(&self) -> Arc<GridGraph> {
        self.graph
            .get_or_init(|| Arc::new(GridGraph::build(&self.scenario.map.grid())))
            .clone()
    }

    /// The exact optimum of every leg (leg `k` from goal `k - 1`, or the start, to goal `k`),
    /// in metres; `None` for an unreachable goal.
    pub fn optima(&self) -> &[Option<f64>] {
        self.optima
            .get_or_init(|| crate::optimum::leg_optima(&self.scenario))
    }

    /// The baked diffusion table.
    pub fn diffusion(&self) -> Result<&Baked> {
        self.diffusion
            .get_or_init(|| {
                let t0 = Instant::now();
                // Verified once here (checksum included); `metric` borrows it again per run.
                let r = bake_diffusion(&self.scenario.map, &Options::default(), &self.table)
                    .and_then(|b| match DiffusionTable::new(&b.table) {
                        Ok(_) => Ok(b),
                        Err(e) => Err(anyhow!("baked table rejected: {e}")),
                    })
                    .map_err(|e| format!("{e:#}"));
                let _ = self.bake_seconds.set(t0.elapsed().as_secs_f64());
                r
            })
            .as_ref()
            .map_err(|e| anyhow!("diffusion bake of {}: {e}", self.scenario.name))
    }

    /// The metric a configuration asks for.
    pub fn metric(&self, kind: MetricKind) -> Result<AnyMetric<'_>> {
        Ok(match kind {
            MetricKind::Euclidean => AnyMetric::Euclidean,
            MetricKind::Diffusion => AnyMetric::Diffusion(
                DiffusionTable::new_unverified(&self.diffusion()?.table)
                    .map_err(|e| anyhow!("table: {e}"))?,
            ),
            MetricKind::Geodesic => AnyMetric::Geodesic(Geodesic::with_cache_bytes(
                self.graph(),
                GEODESIC_CACHE_BYTES,
            )),
        })
    }

    /// The configuration for this scenario: the named planner with its lengths fitted to the
    /// map ([`Config::for_map`]; Table 2's metres with `paper_lengths`) and the scenario's
    /// `sigma`. A length set by hand (`@e_max=8`, a value other than the named planner's) is
    /// taken as written, in metres.
    pub fn config(&self, base: Config) -> Config {
        let mut c = base;
        if !self.scenario.paper_lengths {
            let named = Config::from_name(&base.name().to_string()).unwrap_or(base);
            let fitted = named.for_grid(&self.scenario.map.grid());
            let fit =
                |mine: f32, named: f32, fitted: f32| if mine == named { fitted } else { mine };
            c.e_max = fit(c.e_max, named.e_max, fitted.e_max);
            c.e_search = fit(c.e_search, named.e_search, fitted.e_search);
            c.root_step = fit(c.root_step, named.root_step, fitted.root_step);
        }
        c.with_sigma(self.scenario.sigma)
    }

    /// The length scale the configurations get on this scenario (1: Table 2's metres).
    pub fn length_scale(&self) -> f32 {
        if self.scenario.paper_lengths {
            return 1.0;
        }
        let g = self.scenario.map.grid();
        bi_am_rrt::config::length_scale(g.width_m().max(g.height_m()))
    }
}

/// Builds a planner for `prep` and hands it to `f`.
pub fn with_planner<T>(
    prep: &Prepared,
    cfg: Config,
    seed: u64,
    f: impl FnOnce(&mut SimPlanner<'_, '_>) -> Result<T>,
) -> Result<T> {
    with_planner_at::<NODES, T>(prep, cfg, seed, prep.scenario.start, f)
}

/// Builds a planner of `N` nodes per tree for `prep`, starting at `start`, and hands it to `f`.
pub fn with_planner_at<const N: usize, T>(
    prep: &Prepared,
    cfg: Config,
    seed: u64,
    start: bi_am_rrt::Point,
    f: impl FnOnce(&mut SizedPlanner<'_, '_, N>) -> Result<T>,
) -> Result<T> {
    let mut storage: Box<Storage<N, BUCKETS>> = Box::default();
    with_planner_in(&mut storage, prep, cfg, seed, start, f)
}

/// [`with_planner_at`] in storage the caller keeps: a planner starts on the storage as a
/// firmware's does on its `static` (the planner resets it), so a benchmark that runs many
/// planners neither allocates nor touches fresh memory inside its measurements.
pub fn with_planner_in<const N: usize, T>(
    storage: &mut Storage<N, BUCKETS>,
    prep: &Prepared,
    cfg: Config,
    seed: u64,
    start: bi_am_rrt::Point,
    f: impl FnOnce(&mut SizedPlanner<'_, '_, N>) -> Result<T>,
) -> Result<T> {
    prep.scenario.validate()?;
    let metric = prep.metric(cfg.metric)?;
    let map = Map::new(prep.scenario.map.grid());
    let rng = XorShiftRng::seed_from_u64(seed);
    let mut planner = Planner::new(storage, map, metric, rng, prep.config(cfg), start)
        .map_err(|e| anyhow!("planner for {}: {e}", prep.scenario.name))?;
    f(&mut planner)
}

/// One goal of a run.
#[derive(Clone, Copy, Debug)]
pub struct GoalRun {
    /// Index in the scenario's goal list.
    pub goal_index: usize,
    /// The protocol's measurements.
    pub result: RunResult,
    /// Search time in seconds on the run's clock.
    pub search_s: Option<f64>,
    /// Search time read at the end of the call in which the goal joined.
    pub search_call_end_s: Option<f64>,
}

/// Drives `planner` through `goals` (indices into the scenario's goals) in order.
pub fn drive<'s, 't, C: Clock + ?Sized>(
    planner: &mut SimPlanner<'s, 't>,
    prep: &Prepared,
    clock: &C,
    goals: &[usize],
    protocol: &Protocol,
    mut on_call: impl FnMut(&mut SimPlanner<'s, 't>, usize, bi_am_rrt::Point, u32),
) -> Result<Vec<GoalRun>> {
    let mut out = Vec::new();
    for &gi in goals {
        let goal = prep.scenario.goals[gi];
        let result = run_to_goal(planner, clock, goal, protocol, |p, a, c| {
            on_call(p, gi, a, c)
        })
        .map_err(|e| anyhow!("goal {} of {}: {e}", gi + 1, prep.scenario.name))?;
        let search_s = result
            .search_ticks
            .map(|t| t as f64 / clock.ticks_per_second() as f64);
        let search_call_end_s = result
            .search_ticks_call_end
            .map(|t| t as f64 / clock.ticks_per_second() as f64);
        out.push(GoalRun {
            goal_index: gi,
            result,
            search_s,
            search_call_end_s,
        });
        if !result.reached {
            break;
        }
    }
    Ok(out)
}
