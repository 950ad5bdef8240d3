//! What every simulation shares: a scenario prepared for all metrics (grid graph, diffusion
//! table), the planner type of the simulator, and one planner run through a goal sequence
//! under the agent protocol of the core (`bi_am_rrt::agent`).

use crate::results::Row;
use crate::sim::clock::ClockKind;
use bi_am_rrt::RewireMode;
use std::sync::{Arc, OnceLock};
use std::time::Instant;

use anyhow::{Result, anyhow};
use bi_am_rrt::agent::{Protocol, RunResult, run_to_goal};
use bi_am_rrt::clock::Clock;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Circle, Config, Map, MetricKind, Named, Planner, Point, Storage};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

use crate::metric::bake::{Baked, bake_diffusion};
use crate::metric::diffusion::{Options, TableOptions};
use crate::metric::graph::GridGraph;
use crate::metric::{AnyMetric, Geodesic};
use crate::scenario::Scenario;

/// Nodes per tree in the simulator (office needs several thousand).
pub const NODES: usize = 8192;
/// The arenas the simulator is compiled for, nodes per tree (`host-sim bench --nodes`; `run`
/// takes the smallest that holds the scenario's roadmap when it needs more than [`NODES`]:
/// 11,473 nodes on a 204.8 m building at 0.05 m, 37,219 there for a robot of 0.1 m).
pub const ARENAS: [usize; 5] = [2048, 4096, 8192, 16384, 65000];
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
    /// Skip the exact optimum (`--no-optimum`): every leg's optimum reads `None`.
    pub no_optimum: bool,
    /// Each leg's 8-connected grid path over the cells with room, once computed
    /// ([`Prepared::grid_paths`]).
    grid_paths: OnceLock<Vec<Option<crate::metric::grid_planners::GridPath>>>,
    /// The straight pieces of each leg's exact shortest path, once computed
    /// ([`Prepared::warn_narrow_legs`]).
    pieces: OnceLock<Vec<Option<usize>>>,
    /// A diffusion table the caller gave ([`Prepared::with_diffusion_table`]): the planners'
    /// diffusion metric instead of a bake.
    given_table: Option<Vec<u8>>,
    /// The roadmap, once baked ([`Prepared::roadmap`]), or why there is none.
    roadmap: OnceLock<Result<crate::metric::roadmap::Baked, String>>,
    /// A note about the roadmap was printed (a planner too small for it).
    roadmap_noted: std::sync::atomic::AtomicBool,
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
            pieces: OnceLock::new(),
            no_optimum: false,
            grid_paths: OnceLock::new(),
            given_table: None,
            roadmap: OnceLock::new(),
            roadmap_noted: std::sync::atomic::AtomicBool::new(false),
        }
    }

    /// The scenario's roadmap (the `roadmap` tactic; module [`crate::metric::roadmap`]),
    /// baked the first time it is asked for from the grid the planner tests paths on (inflated
    /// for the robot's body, if any), or why there is none (a map whose outline keeps more
    /// than [`crate::metric::roadmap::MAX_NODES`] corners).
    pub fn roadmap(&self) -> Result<&crate::metric::roadmap::Baked> {
        self.roadmap
            .get_or_init(|| {
                crate::metric::roadmap::of_scenario(&self.scenario).map_err(|e| format!("{e:#}"))
            })
            .as_ref()
            .map_err(|e| anyhow!("{e}"))
    }

    /// The nodes a tree of a run with `cfg` holds: [`NODES`], or, when `cfg` has the `roadmap`
    /// tactic and the scenario's roadmap needs more (its search's scratch is the reverse
    /// arena's spare slots: a node each, and one more), the smallest of [`ARENAS`] that holds
    /// it. A building of 200 m at 0.05 m has a roadmap of 11,473 nodes; without it the trees'
    /// first paths there go through the wrong doors (`docs/notebook/long-runs.md`).
    pub fn arena_for(&self, cfg: Named) -> usize {
        let need = cfg
            .cfg
            .tactics
            .roadmap
            .then(|| self.roadmap().ok().map(|r| r.nodes + 1))
            .flatten()
            .unwrap_or(0);
        ARENAS
            .into_iter()
            .find(|&n| n >= NODES && n >= need)
            .unwrap_or(NODES)
    }

    /// Attaches the scenario's roadmap to `planner` when its configuration has the `roadmap`
    /// tactic on; when there is none or it does not fit the planner's arena, says so once
    /// and the planner runs without it.
    pub fn attach_roadmap<
        'm,
        M: bi_am_rrt::Metric,
        R: rand_core::Rng,
        const N: usize,
        const B: usize,
        const K: usize,
    >(
        &'m self,
        planner: &mut bi_am_rrt::Planner<'_, 'm, M, R, N, B, K>,
    ) {
        if !planner.config().tactics.roadmap {
            return;
        }
        let attached = self.roadmap().and_then(|b| {
            let rm = bi_am_rrt::roadmap::Roadmap::from_bytes(&b.bytes)
                .map_err(|e| anyhow!("roadmap: {e}"))?;
            planner.set_roadmap(Some(rm)).map_err(|e| {
                anyhow!(
                    "roadmap of {} nodes: {e}; the arena holds {N} a tree, it needs {} or more",
                    b.nodes,
                    b.nodes + 1
                )
            })
        });
        if let Err(e) = attached
            && !self
                .roadmap_noted
                .swap(true, std::sync::atomic::Ordering::Relaxed)
        {
            eprintln!(
                "note: {}: planning without a roadmap ({e:#})",
                self.scenario.name
            );
        }
    }

    /// This scenario with a diffusion table the caller baked or loaded (a file `host-sim bake`
    /// writes): the planners with the diffusion metric read it instead of a bake. The table's
    /// checksum is verified here; a table of another map is refused when a planner starts on
    /// it (its map hash).
    pub fn with_diffusion_table(mut self, bytes: Vec<u8>) -> Result<Self> {
        DiffusionTable::new(&bytes).map_err(|e| anyhow!("diffusion table: {e}"))?;
        self.given_table = Some(bytes);
        Ok(self)
    }

    /// This scenario without the exact optimum (`--no-optimum`: rows leave `optimal_m` and
    /// `travelled_ratio` empty).
    pub fn without_optimum(mut self) -> Self {
        self.no_optimum = true;
        self
    }

    /// The optima if they were computed (or skipped), without computing them.
    pub fn optima_if_known(&self) -> Option<&[Option<f64>]> {
        self.optima.get().map(Vec::as_slice)
    }

    /// The calls the agent protocol gives leg `gi` before it gives up: the protocol's
    /// `max_calls` (3,000), or four times the calls the leg's geodesic length over the grid of
    /// cells with room takes at the protocol's speed when that is more (a 6 km leg through a
    /// maze of 1 m corridors), so that the cap follows the leg, not a fixed distance. The
    /// leg's length is its 8-connected path over the cells with room
    /// ([`Prepared::grid_paths`]).
    pub fn leg_calls(&self, gi: usize, protocol: &Protocol) -> u32 {
        let m = self
            .grid_paths()
            .get(gi)
            .and_then(Option::as_ref)
            .map_or(0.0, |p| p.length_m);
        // In whole decimetres, as before the paths were kept.
        let dm = (m * 10.0).ceil();
        let speed = f64::from(protocol.speed.max(1e-3));
        let need = (4.0 * dm / 10.0 / speed).ceil() as u32;
        protocol.max_calls.max(need)
    }

    /// Each leg's shortest 8-connected path over the cells with room
    /// ([`crate::metric::grid_planners::astar8`]; `None` for a leg without one), computed once.
    pub fn grid_paths(&self) -> &[Option<crate::metric::grid_planners::GridPath>] {
        self.grid_paths.get_or_init(|| {
            let grid = self.scenario.reach_grid();
            let starts = crate::metric::optimum::leg_starts(&self.scenario);
            starts
                .iter()
                .zip(&self.scenario.goals)
                .map(|(&a, &b)| crate::metric::grid_planners::astar8(&grid, a, b))
                .collect()
        })
    }

    /// The legs whose shortest grid path runs mostly (half or more) through passages
    /// narrower than `e_max / 4`, for at least 20 `e_max` (issue 42), with what their paths
    /// run through ([`crate::metric::grid_planners::passages`]): sampling trees, ours and OMPL's,
    /// cross long corridors of a few cells slowly. Measured: on a 129 x 129 maze of 1 m
    /// corridors (`scripts/gen-maps.py`), leg 1 (2.4 km through corridors one cell wide),
    /// neither the tuned set with `e_max` 1.2-5 m nor OMPL's RRT-Connect had a path after 10 s
    /// of CPU, where A* took 0.6 ms. Commands print [`narrow_warning`] for each before they
    /// run, so a user knows early; the run goes on.
    pub fn narrow_legs(&self, e_max: f32) -> Vec<(usize, crate::metric::grid_planners::Passages)> {
        let grid = self.scenario.reach_grid();
        let width = f64::from(e_max) / 4.0;
        self.grid_paths()
            .iter()
            .enumerate()
            .filter_map(|(k, p)| {
                let p = crate::metric::grid_planners::passages(&grid, p.as_ref()?, width);
                (p.narrow_m >= 0.5 * p.length_m && p.narrow_m >= 20.0 * f64::from(e_max))
                    .then_some((k, p))
            })
            .collect()
    }

    /// Prints [`Prepared::narrow_notes`] to stderr.
    pub fn warn_narrow_legs(
        &self,
        cfg: Named,
        nodes: usize,
        budget: &dyn Fn(usize) -> Option<String>,
    ) {
        for line in self.narrow_notes(cfg, nodes, budget) {
            eprintln!("{line}");
        }
    }

    /// What a run says before it starts of [`Prepared::narrow_legs`] with `cfg`'s lengths
    /// (the configuration a run gets here, fitted: [`Prepared::config`]) and an arena of
    /// `nodes` a tree: a [`narrow_warning`] for each leg; `budget(k)` says what the planner
    /// has for leg `k` (`None`: the leg is not run). With the scenario's roadmap, a note
    /// instead (the first path comes from it), unless the arena cannot hold the roadmap: then
    /// a warning that names the arena it needs, and the legs' warnings.
    pub fn narrow_notes(
        &self,
        cfg: Named,
        nodes: usize,
        budget: &dyn Fn(usize) -> Option<String>,
    ) -> Vec<String> {
        let e_max = cfg.cfg.search.e_max;
        let legs = self.narrow_legs(e_max);
        let mut out = Vec::new();
        if legs.is_empty() {
            return out;
        }
        // With the scenario's roadmap the first path does not come from the trees, when the
        // arena can hold it (its search's scratch is the reverse arena's spare slots).
        let roadmap = cfg
            .cfg
            .tactics
            .roadmap
            .then(|| self.roadmap().ok())
            .flatten();
        match roadmap {
            Some(rm) if rm.nodes >= nodes => out.push(format!(
                "warning: {} on {}: the scenario's roadmap has {} nodes and the arena holds \
                 {nodes} a tree, so the planner runs without it and its first paths come from \
                 the trees alone (an arena of {} nodes or more keeps the roadmap{})",
                cfg.name(),
                self.scenario.name,
                rm.nodes,
                rm.nodes + 1,
                ARENAS
                    .into_iter()
                    .find(|&n| n > rm.nodes)
                    .map_or(String::new(), |n| format!(": `bench --nodes {n}`"))
            )),
            Some(rm) => {
                for (k, p) in legs {
                    if budget(k).is_none() {
                        continue;
                    }
                    out.push(format!(
                        "note: {} on {}, leg {}: {:.0} m of its {:.0} m shortest grid path run \
                         through passages narrower than e_max / 4; its first path comes from \
                         the scenario's roadmap ({} nodes), which sampling trees alone \
                         (`@roadmap=false`, and OMPL's) would be slow to find there",
                        cfg.name(),
                        self.scenario.name,
                        k + 1,
                        p.narrow_m,
                        p.length_m,
                        rm.nodes
                    ));
                }
                return out;
            }
            None => {}
        }
        // The exact shortest path of each leg (once per scenario, whichever planners ask):
        // how many straight pieces a tree path needs about.
        let pieces = self.pieces.get_or_init(|| {
            use rayon::prelude::*;
            let grid = self.scenario.reach_grid();
            let corners = crate::metric::optimum::Corners::of(&grid);
            let starts = crate::metric::optimum::leg_starts(&self.scenario);
            starts
                .par_iter()
                .zip(&self.scenario.goals)
                .map(|(&a, &b)| corners.shortest_path(a, b).map(|(_, pts)| pts.len() - 1))
                .collect()
        });
        for (k, p) in legs {
            let Some(budget) = budget(k) else { continue };
            let w = narrow_warning(k, &p, e_max, &budget, pieces[k], nodes);
            out.push(format!(
                "warning: {} on {}, {w}",
                cfg.name(),
                self.scenario.name
            ));
        }
        out
    }

    /// The grid graph (for the geodesic metric).
    pub fn graph(&self) -> Arc<GridGraph> {
        self.graph
            .get_or_init(|| Arc::new(GridGraph::build(&self.scenario.reach_grid())))
            .clone()
    }

    /// The exact optimum of every leg (leg `k` from goal `k - 1`, or the start, to goal `k`),
    /// in metres; `None` for an unreachable goal.
    pub fn optima(&self) -> &[Option<f64>] {
        self.optima.get_or_init(|| {
            if self.no_optimum {
                vec![None; self.scenario.goals.len()]
            } else {
                crate::metric::optimum::leg_optima(&self.scenario)
            }
        })
    }

    /// The baked diffusion table.
    pub fn diffusion(&self) -> Result<&Baked> {
        self.diffusion
            .get_or_init(|| {
                let t0 = Instant::now();
                // Verified once here (checksum included); `metric` borrows it again per run.
                // For a robot body: on where its disc can go, recording the map and radius.
                let table = TableOptions {
                    map_hash: self.scenario.table_hash(),
                    keep: self.scenario.start_cell(),
                    ..self.table
                };
                let r = bake_diffusion(self.scenario.reach_map(), &Options::default(), &table)
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
            MetricKind::Diffusion => {
                let bytes = match &self.given_table {
                    Some(b) => b,
                    None => &self.diffusion()?.table,
                };
                AnyMetric::Diffusion(
                    DiffusionTable::new_unverified(bytes).map_err(|e| anyhow!("table: {e}"))?,
                )
            }
            MetricKind::Geodesic => AnyMetric::Geodesic(Geodesic::with_cache_bytes(
                self.graph(),
                GEODESIC_CACHE_BYTES,
            )),
            MetricKind::Other => anyhow::bail!("the simulator has no metric of kind (?)"),
        })
    }

    /// A named configuration fitted to this scenario, the second of the three steps a run's
    /// configuration takes (named -> fitted -> the user's overrides,
    /// [`crate::sim::planners::Variant::config_for`]): `e_max`, `e_search` and `root_step` follow the
    /// map ([`Config::for_grid`]), or stay Table 2's metres with `paper_lengths`, and `sigma`
    /// is the scenario's ([`crate::scenario::Scenario::sigma`]). Every length is replaced: pass the
    /// named configuration, and set lengths by hand after this step.
    pub fn config(&self, named: Config) -> Config {
        let mut c = named;
        if !self.scenario.paper_lengths {
            let fitted = named.for_grid(&self.scenario.map.grid());
            c.search.e_max = fitted.search.e_max;
            c.search.e_search = fitted.search.e_search;
            c.rewiring.root_step = fitted.rewiring.root_step;
        }
        c.with_sigma(self.scenario.sigma())
    }

    /// [`Prepared::config`] of a named planner (its metric kept).
    pub fn fit(&self, named: Named) -> Named {
        Named {
            cfg: self.config(named.cfg),
            ..named
        }
    }
}

/// Builds a planner for `prep` and hands it to `f`. `cfg` is what the planner gets, as it is
/// (the robot's radius and clearance weight come from the scenario): fit a named
/// configuration to the map first ([`Prepared::config`], or [`crate::sim::planners::Variant::config_for`]
/// with overrides).
pub fn with_planner<T>(
    prep: &Prepared,
    cfg: Named,
    seed: u64,
    f: impl FnOnce(&mut SimPlanner<'_, '_>) -> Result<T>,
) -> Result<T> {
    with_planner_at::<NODES, T>(prep, cfg, seed, prep.scenario.start, f)
}

/// Builds a planner of `N` nodes per tree for `prep`, starting at `start`, and hands it to `f`.
pub fn with_planner_at<const N: usize, T>(
    prep: &Prepared,
    cfg: Named,
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
    cfg: Named,
    seed: u64,
    start: bi_am_rrt::Point,
    f: impl FnOnce(&mut SizedPlanner<'_, '_, N>) -> Result<T>,
) -> Result<T> {
    let map = prep.scenario.planner_map()?;
    f(&mut planner_on(storage, prep, map, cfg, seed, start)?)
}

/// The planner of `prep` on `map` (the scenario's grid, with or without an overlay), in
/// `storage`: what [`with_planner_in`] hands on, for a caller that keeps the planner itself.
pub fn planner_on<'s, 'm, const N: usize>(
    storage: &'s mut Storage<N, BUCKETS>,
    prep: &'m Prepared,
    map: Map<'m, OBSTACLES>,
    cfg: Named,
    seed: u64,
    start: bi_am_rrt::Point,
) -> Result<SizedPlanner<'s, 'm, N>> {
    prep.scenario.validate()?;
    let metric = prep.metric(cfg.metric)?;
    let rng = XorShiftRng::seed_from_u64(seed);
    let mut cfg = cfg.cfg;
    cfg.robot_radius = prep.scenario.robot_radius;
    cfg.clearance_weight = prep.scenario.clearance_weight();
    let mut planner = Planner::new(storage, map, metric, rng, cfg, start)
        .map_err(|e| anyhow!("planner for {}: {e}", prep.scenario.name))?;
    prep.attach_roadmap(&mut planner);
    Ok(planner)
}

/// [`with_planner`] on a map with a live overlay ([`bi_am_rrt::map::Overlay`]): cells the run
/// marks and clears with `set_cells` (issue 27's door).
pub fn with_live_planner<T>(
    prep: &Prepared,
    cfg: Named,
    seed: u64,
    f: impl FnOnce(&mut SimPlanner<'_, '_>) -> Result<T>,
) -> Result<T> {
    let n = live_bytes(prep);
    let (mut overlay, mut space) = (vec![0u8; n], vec![0u8; n]);
    let mut storage: Box<Storage<NODES, BUCKETS>> = Box::default();
    let map = live_map(prep, &mut overlay, &mut space)?;
    let start = prep.scenario.start;
    f(&mut planner_on(&mut storage, prep, map, cfg, seed, start)?)
}

/// The bytes of each buffer [`live_map`] takes.
pub fn live_bytes(prep: &Prepared) -> usize {
    let grid = prep.scenario.map.grid();
    bi_am_rrt::OccupancyGrid::bytes_needed(grid.cols(), grid.rows())
}

/// The scenario's map with a live overlay in `overlay` (and, with a body, its inflation in
/// `space`: the live cells re-inflate there as they are edited), each [`live_bytes`] long.
pub fn live_map<'m>(
    prep: &'m Prepared,
    overlay: &'m mut [u8],
    space: &'m mut [u8],
) -> Result<Map<'m, OBSTACLES>> {
    let map = Map::new(prep.scenario.map.grid())
        .with_overlay(overlay)
        .and_then(|m| m.with_body(prep.scenario.robot_radius, space))
        .map_err(|e| anyhow!("overlay: {e}"))?;
    prep.scenario.with_clearance_field(map)
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
pub fn drive<'s, 't, C: Clock + ?Sized, const N: usize>(
    planner: &mut SizedPlanner<'s, 't, N>,
    prep: &Prepared,
    clock: &C,
    goals: &[usize],
    protocol: &Protocol,
    on_call: impl FnMut(&mut SizedPlanner<'s, 't, N>, usize, bi_am_rrt::Point, u32),
) -> Result<Vec<GoalRun>> {
    drive_each(planner, prep, clock, goals, protocol, on_call, |_| {})
}

/// [`drive`], calling `on_goal` as each goal's run ends (`run` writes its results goal by
/// goal). Each leg gets [`Prepared::leg_calls`] calls.
pub fn drive_each<'s, 't, C: Clock + ?Sized, const N: usize>(
    planner: &mut SizedPlanner<'s, 't, N>,
    prep: &Prepared,
    clock: &C,
    goals: &[usize],
    protocol: &Protocol,
    mut on_call: impl FnMut(&mut SizedPlanner<'s, 't, N>, usize, bi_am_rrt::Point, u32),
    mut on_goal: impl FnMut(&GoalRun),
) -> Result<Vec<GoalRun>> {
    let mut out = Vec::new();
    for &gi in goals {
        let goal = prep.scenario.goals[gi];
        let leg = Protocol {
            max_calls: prep.leg_calls(gi, protocol),
            ..*protocol
        };
        let result = run_to_goal(planner, clock, goal, &leg, |p, a, c| on_call(p, gi, a, c))
            .map_err(|e| anyhow!("goal {} of {}: {e}", gi + 1, prep.scenario.name))?;
        let search_s = result
            .search_ticks
            .map(|t| t as f64 / clock.ticks_per_second() as f64);
        let search_call_end_s = result
            .search_ticks_call_end
            .map(|t| t as f64 / clock.ticks_per_second() as f64);
        let run = GoalRun {
            goal_index: gi,
            result,
            search_s,
            search_call_end_s,
        };
        on_goal(&run);
        out.push(run);
        if !result.reached {
            break;
        }
    }
    Ok(out)
}

/// The paper's Fig. 7 rule for dropping a dynamic obstacle (`run --obstacle`, `experiment
/// --obstacle`): once the agent stands more than 2 m from where the goal was set, a disc of
/// radius `r` is dropped on the planned path at the first path point more than 10 m ahead
/// (along the path) that is farther than `r + 3` m from the goal and whose disc would not
/// cover the agent. Returns the disc if one was dropped.
pub fn drop_on_path<const N: usize>(
    p: &mut SizedPlanner<'_, '_, N>,
    agent: Point,
    leg_start: Point,
    r: f32,
) -> Option<Circle> {
    if agent.dist(leg_start) <= 2.0 {
        return None;
    }
    let goal = p.goal()?;
    let mut path = vec![Point::ZERO; p.tree().len().max(1)];
    let n = p.path(&mut path).ok()?.len;
    let mut ahead = 0.0;
    for w in path[..n].windows(2) {
        ahead += w[0].dist(w[1]);
        if ahead > 10.0 && w[1].dist(goal) > r + 3.0 && w[1].dist(agent) > r + 0.5 {
            let c = Circle::new(w[1], r);
            return p.add_obstacle(c).is_ok().then_some(c);
        }
    }
    None
}

/// Fig. 7's measurements of one goal (`DiscTrack::on_call` after every plan call, then
/// [`DiscTrack::finish`]), filled into a row's `disc_*`, `replan_s`, ... fields.
#[derive(Clone, Debug, Default)]
pub struct DiscTrack {
    /// Radius of the disc to drop.
    pub radius: f32,
    /// The disc dropped, when.
    pub disc: Option<Circle>,
    dropped_at_s: f64,
    agent_at_drop: Point,
    travelled_at_drop: f64,
    /// The path's cost just before the drop.
    pub cost_before: Option<f32>,
    /// Seconds from the drop to the first free path to the goal.
    pub replan_s: Option<f64>,
    /// That path's cost.
    pub replanned_cost: Option<f32>,
    travelled: f64,
    last: Option<Point>,
}

impl DiscTrack {
    /// A track that drops a disc of radius `radius`.
    pub fn new(radius: f32) -> Self {
        Self {
            radius,
            ..Self::default()
        }
    }

    /// After a plan call at `now_s` on the run's clock, the agent at `agent`, on the leg that
    /// began at `leg_start`. Returns the disc when this call dropped it.
    pub fn on_call<const N: usize>(
        &mut self,
        p: &mut SizedPlanner<'_, '_, N>,
        agent: Point,
        leg_start: Point,
        now_s: f64,
    ) -> Option<Circle> {
        if let Some(last) = self.last {
            self.travelled += f64::from(last.dist(agent));
        }
        self.last = Some(agent);
        let goal_cost = |p: &SizedPlanner<'_, '_, N>| {
            p.goal_node()
                .and_then(|g| p.tree().cost(g))
                .filter(|c| !c.blocked)
                .map(|c| c.length)
        };
        if self.disc.is_none() {
            let before = goal_cost(p);
            let c = drop_on_path(p, agent, leg_start, self.radius)?;
            self.disc = Some(c);
            self.cost_before = before;
            self.dropped_at_s = now_s;
            self.agent_at_drop = agent;
            self.travelled_at_drop = self.travelled;
            return Some(c);
        }
        if self.replan_s.is_none()
            && let Some(cost) = goal_cost(p)
        {
            self.replan_s = Some(now_s - self.dropped_at_s);
            self.replanned_cost = Some(cost);
        }
        None
    }

    /// Fills the row's Fig. 7 fields (nothing when no disc was dropped); `optimum` gives the
    /// exact optimum from the agent's position at the drop to the goal with the disc.
    pub fn finish(&self, row: &mut crate::results::Row, prep: &Prepared, goal: Point) {
        let Some(c) = self.disc else {
            return;
        };
        row.disc_x_m = Some(c.center.x);
        row.disc_y_m = Some(c.center.y);
        row.disc_r_m = Some(c.radius);
        row.cost_before_drop_m = self.cost_before;
        row.replan_s = self.replan_s;
        row.replanned_cost_m = self.replanned_cost;
        if row.reached {
            row.travelled_after_drop_m = Some((self.travelled - self.travelled_at_drop) as f32);
        }
        row.optimal_after_drop_m =
            optimum_with_disc(&prep.scenario, c, self.agent_at_drop, goal).map(|o| o as f32);
    }
}

/// The exact optimum from `a` to `b` on the scenario's map with the disc `c` added, the disc
/// rasterised to cells of at most 0.25 m (the map's cells split evenly) lying wholly inside
/// it: at most the true optimum around the disc.
pub fn optimum_with_disc(s: &Scenario, c: Circle, a: Point, b: Point) -> Option<f64> {
    // For a robot disc: the inflated map, and the disc grown by the robot's radius.
    let grid = s.reach_grid();
    let c = Circle::new(c.center, c.radius + s.robot_radius);
    let cell = grid.cell_size();
    let split = (cell / 0.25).ceil().max(1.0) as u32;
    let fine = cell / split as f32;
    let cols = u32::from(grid.cols()) * split;
    let rows = u32::from(grid.rows()) * split;
    let (cols16, rows16) = (u16::try_from(cols).ok()?, u16::try_from(rows).ok()?);
    let r2 = c.radius * c.radius;
    let inside = |x: f32, y: f32| {
        let (dx, dy) = (x - c.center.x, y - c.center.y);
        dx * dx + dy * dy <= r2
    };
    let refined = crate::scenario::OwnedGrid::from_fn(cols16, rows16, fine, |col, row| {
        let (col, row) = (u32::from(col), u32::from(row));
        let coarse = grid.is_occupied((col / split) as u16, (row / split) as u16);
        let (x0, y0) = (col as f32 * fine, row as f32 * fine);
        let (x1, y1) = (x0 + fine, y0 + fine);
        coarse || (inside(x0, y0) && inside(x1, y0) && inside(x0, y1) && inside(x1, y1))
    })
    .ok()?;
    crate::metric::optimum::Corners::of(&refined.grid()).shortest(a, b)
}

/// The warning for leg `k` (0-based) of [`Prepared::narrow_legs`] for `e_max`; `budget` says
/// what the planner has for it ("within the leg's 3000 calls"), `arena` how many nodes a tree
/// holds.
pub fn narrow_warning(
    k: usize,
    p: &crate::metric::grid_planners::Passages,
    e_max: f32,
    budget: &str,
    pieces: Option<usize>,
    arena: usize,
) -> String {
    // A tree path joining the goal has about a node a straight piece of the shortest path.
    let nodes = pieces.map_or(String::new(), |n| {
        format!(
            "; its exact shortest path has {n} straight pieces, so a tree path to the goal \
             needs about {n} nodes and the two trees hold {arena} each{}",
            if n > 2 * arena {
                ": more than they can hold"
            } else {
                ""
            }
        )
    });
    format!(
        "leg {}: {:.0} m of its {:.0} m shortest grid path run through passages narrower than \
         e_max / 4 ({:.2} m; median width {:.2} m){nodes}: sampling trees, this planner's and \
         OMPL's, cross long narrow corridors slowly and may not reach this goal {budget}; a \
         grid planner finds it in milliseconds (`host-sim optimum` runs A* and Theta*; \
         docs/notebook/grid-planners.md)",
        k + 1,
        p.narrow_m,
        p.length_m,
        e_max / 4.0,
        p.median_width_m,
    )
}

/// The paper's pace (`--pace paper`): [`PAPER_EXPANSIONS_PER_CALL`] tree expansions per call and
/// [`PAPER_VISITS`] rewiring visits per phase and expansion (the caller makes every call last
/// its full `t_exp` on a virtual clock).
pub fn paper_pace(c: &mut Config) {
    c.budget.max_expansions = PAPER_EXPANSIONS_PER_CALL;
    c.rewiring.mode = RewireMode::PerExpansion {
        visits: PAPER_VISITS,
    };
}

/// Tree expansions per `plan` call at the paper's pace. Each tree's expansion counts
/// (`Budget::max_expansions`): Algorithm 1's loop calls `Expend_f` and, until the trees meet,
/// `Expend_r`, and every `Expend` spends its own `t_root` of root rewiring (Algorithm 3's
/// timed loop), so a 150 ms call of the paper's implementation was shared by the expansions
/// of both trees, and a two-tree planner grew each tree about half as often as a one-tree
/// planner grew its one. After the join an `Expend_f` spends `t_root + t_goal` (Table 2: 2 + 4
/// ms for the AM-RRT* family, 3 + 3 ms for RT-RRT*) and, with about 1 ms for the expansion
/// itself (an assumption), a call held 150 / (6 + 1) = 21 of them. Before the join an
/// `Expend` costs 3-4 ms, so a call held more (37-50); one cap for both phases is the simpler
/// model and the slower one before the join, for one- and two-tree planners alike. The
/// paper's own counts at goal on bug_trap (AM-RRT*(D) 76 nodes, RT-RRT* 445, AM-RRT*(E)
/// 1,062) are what `docs/results/pace/README.md` compares against.
pub const PAPER_EXPANSIONS_PER_CALL: u32 = 20;

/// Rewiring visits per phase and expansion at the paper's pace: 2-4 ms of Python at an
/// assumed 0.25-0.5 ms per visit (a neighbourhood query and its cost checks).
pub const PAPER_VISITS: u16 = 8;

/// The row of one goal of a run.
#[allow(clippy::too_many_arguments)]
pub fn row(
    prep: &Prepared,
    cfg: Named,
    seed: u64,
    g: &crate::sim::GoalRun,
    clock: ClockKind,
    final_nodes: usize,
    anytime_cost_m: Option<f32>,
    run_wall_s: f64,
) -> Row {
    let optimal = prep.optima().get(g.goal_index).copied().flatten();
    row_with_optimum(
        prep,
        optimal,
        cfg,
        seed,
        g,
        clock,
        final_nodes,
        anytime_cost_m,
        run_wall_s,
    )
}

/// [`row`] with the leg's optimum given (`None`: not known yet, or skipped).
#[allow(clippy::too_many_arguments)]
pub fn row_with_optimum(
    prep: &Prepared,
    optimal: Option<f64>,
    cfg: Named,
    seed: u64,
    g: &crate::sim::GoalRun,
    clock: ClockKind,
    final_nodes: usize,
    anytime_cost_m: Option<f32>,
    run_wall_s: f64,
) -> Row {
    Row {
        planner: cfg.name().to_string(),
        scenario: prep.scenario.name.clone(),
        goal_index: g.goal_index + 1,
        seed,
        reached: g.result.reached,
        search_time_s: g.search_s,
        path_length_m: Some(g.result.travelled),
        optimal_m: optimal.map(|o| o as f32),
        travelled_ratio: optimal
            .filter(|_| g.result.reached)
            .map(|o| (g.result.travelled as f64 / o) as f32),
        collisions: g.result.collisions,
        nodes_at_goal: g.result.nodes_at_goal,
        search_time_call_end_s: g.search_call_end_s,
        nodes_at_call_end: g.result.nodes_at_call_end,
        calls: g.result.calls,
        cost_at_start_m: g.result.cost_at_start,
        anytime_cost_m,
        final_nodes,
        clock,
        run_wall_s,
        disc_x_m: None,
        disc_y_m: None,
        disc_r_m: None,
        cost_before_drop_m: None,
        replan_s: None,
        replanned_cost_m: None,
        travelled_after_drop_m: None,
        optimal_after_drop_m: None,
    }
}

/// A snapshot of the planner for a picture (`run`'s and `moving`'s).
pub(crate) fn scene<const N: usize>(
    p: &SizedPlanner<'_, '_, N>,
    trail: &[Point],
    scenario: &crate::scenario::Scenario,
    active: usize,
    title: String,
) -> crate::draw::Scene {
    let mut path = vec![Point::ZERO; p.tree().len().max(1)];
    let n = p.path(&mut path).map_or(0, |i| i.len);
    path.truncate(n);
    crate::draw::Scene {
        title,
        forward: crate::draw::edges(p.tree()),
        reverse: crate::draw::edges(p.reverse_tree()),
        path,
        trail: trail.to_vec(),
        circles: p.map().obstacles().iter().map(|(_, c)| c).collect(),
        start: scenario.start,
        goals: scenario.goals.clone(),
        active: Some(active),
        agent: trail.last().copied(),
        meet: None,
    }
}
