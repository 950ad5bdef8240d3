//! `Planner`: the core's planner (Algorithm 1's loop, one `plan` call per control period) on a
//! scenario, owned by a Python object. The core's planner borrows its storage, its map and its
//! metric; here one object owns all of them (a self-referential cell, `ouroboros`), in an arena
//! of 2,048, 4,096, 8,192, 16,384 or 65,000 nodes per tree (the sizes `host-sim` is compiled for).
//!
//! The interpreter's lock is released while the planner works (`plan`, `grow`): other Python
//! threads run meanwhile. A planner is used by one thread at a time (a lock inside).

use std::sync::{Arc, Mutex};

use bi_am_rrt::clock::{Clock, FakeClock};
use bi_am_rrt::map::ObstacleId;
use bi_am_rrt::{Circle, Moving, Point, Progress as CoreProgress, Status, Storage, Wait};
use host_sim::sim::clock::{VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock};
use host_sim::sim::{BUCKETS, Prepared, SizedPlanner};
use numpy::{PyArray1, PyArray2};
use ouroboros::self_referencing;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

use crate::Xy;
use crate::errors::{finite, lib, point, position, value};
use crate::maps::{Frame, Map, Scenario};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Planner>()?;
    m.add_class::<Progress>()?;
    m.add_function(wrap_pyfunction!(planner_names, m)?)?;
    Ok(())
}

/// The planner and everything it borrows.
#[self_referencing]
struct Cell<const N: usize> {
    prep: Arc<Prepared>,
    storage: Box<Storage<N, BUCKETS>>,
    overlay: Vec<u8>,
    space: Vec<u8>,
    #[borrows(prep, mut storage, mut overlay, mut space)]
    #[not_covariant]
    planner: SizedPlanner<'this, 'this, N>,
}

/// The arena sizes a planner can have.
enum Sized {
    N2048(Cell<2048>),
    N4096(Cell<4096>),
    N8192(Cell<8192>),
    N16384(Cell<16384>),
    N65000(Cell<65000>),
}

/// Runs `$body` with `$p` bound to the planner, whatever its arena.
macro_rules! on {
    ($sized:expr, $p:ident => $body:expr) => {
        match $sized {
            Sized::N2048(c) => c.with_planner_mut(|$p| $body),
            Sized::N4096(c) => c.with_planner_mut(|$p| $body),
            Sized::N8192(c) => c.with_planner_mut(|$p| $body),
            Sized::N16384(c) => c.with_planner_mut(|$p| $body),
            Sized::N65000(c) => c.with_planner_mut(|$p| $body),
        }
    };
}

/// The clock a planner's calls are measured on.
enum Clocks {
    /// Work units at `host-sim`'s 12 ns each: the same calls on every machine.
    Virtual(FakeClock),
    /// Real time.
    Wall(WallClock),
}

struct Inner {
    sized: Sized,
    clock: Clocks,
}

// Not inlined: the `match` over the arenas would carry every arena's storage in one frame.
#[inline(never)]
fn build<const N: usize>(
    prep: Arc<Prepared>,
    named: bi_am_rrt::Named,
    seed: u64,
    start: Point,
    live: bool,
) -> Result<Cell<N>, Refused> {
    let n = if live {
        host_sim::sim::live_bytes(&prep)
    } else {
        0
    };
    CellTryBuilder {
        prep,
        storage: Box::default(),
        overlay: vec![0; n],
        space: vec![0; n],
        planner_builder: |prep, storage, overlay, space| {
            let map = if live {
                host_sim::sim::live_map(prep, overlay, space).map_err(Refused::Lib)?
            } else {
                prep.scenario.planner_map().map_err(Refused::Lib)?
            };
            let metric = prep.metric(named.metric).map_err(Refused::Lib)?;
            let mut cfg = named.cfg;
            cfg.robot_radius = prep.scenario.robot_radius;
            cfg.clearance_weight = prep.scenario.clearance_weight();
            let rng = XorShiftRng::seed_from_u64(seed);
            let mut planner = bi_am_rrt::Planner::new(storage, map, metric, rng, cfg, start)
                .map_err(Refused::Setup)?;
            // The scenario's roadmap, as host-sim attaches it (the tuned `roadmap` tactic).
            prep.attach_roadmap(&mut planner);
            Ok(planner)
        },
    }
    .try_build()
}

/// Why a planner could not start.
enum Refused {
    /// The core refused its setup (the start, the configuration, the map, the table).
    Setup(bi_am_rrt::error::SetupError),
    /// The simulator could not prepare the map or the metric.
    Lib(anyhow::Error),
    /// An arena size it is not compiled for.
    Nodes(usize),
}

impl Refused {
    fn into_py(self) -> PyErr {
        use bi_am_rrt::error::SetupError as S;
        match self {
            Refused::Setup(S::Start(e)) => {
                let msg = format!("start: {e}");
                match e {
                    bi_am_rrt::error::InputError::InObstacle
                    | bi_am_rrt::error::InputError::NoRoom => {
                        crate::errors::InWallError::new_err(msg)
                    }
                    _ => crate::errors::PositionError::new_err(msg),
                }
            }
            Refused::Setup(S::Metric(e)) => lib(anyhow::anyhow!(
                "the diffusion table was not baked for this map: {e}"
            )),
            Refused::Setup(e) => value(format!("planner: {e}")),
            Refused::Lib(e) => lib(e),
            Refused::Nodes(n) => value(format!("nodes={n}: 2048, 4096, 8192, 16384 or 65000")),
        }
    }
}

/// What a `plan` or `grow` call did and where the agent should go.
#[pyclass(module = "bi_am_rrt", frozen, get_all)]
#[derive(Clone)]
pub struct Progress {
    /// The next waypoint `(x, y)`: reachable from the agent over a free segment, or the
    /// agent's own position when it holds.
    waypoint: Xy,
    /// `"no_goal"`, `"searching"`, `"following"`, `"arrived"`, `"waiting"`,
    /// `"unreachable"` or `"evading"`.
    status: &'static str,
    /// Why the agent holds (status `"waiting"`): `"path_blocked"`, `"agent_in_obstacle"`,
    /// `"agent_blocked"`, `"out_of_time"`, `"giving_way"`, `"cornered"`; else None.
    reason: Option<&'static str>,
    /// Work units done in the call.
    work: u64,
    /// The goal is a node of the forward tree.
    goal_in_tree: bool,
    /// The path's cost from the root to the goal (metres), once the goal is in the tree.
    goal_cost: Option<f64>,
    /// Forward tree size.
    nodes: usize,
    /// Reverse tree size (0 for one tree).
    reverse_nodes: usize,
    /// Expansions in the call.
    expansions: u32,
    /// The root moved along the path.
    advanced: bool,
    /// An arena is full (the planner keeps rewiring what it has).
    tree_full: bool,
}

#[pymethods]
impl Progress {
    fn __repr__(&self) -> String {
        format!(
            "Progress(status={:?}, reason={:?}, waypoint=({:.3}, {:.3}), goal_in_tree={}, nodes={}, \
             reverse_nodes={}, expansions={}, work={})",
            self.status,
            self.reason,
            self.waypoint.0,
            self.waypoint.1,
            if self.goal_in_tree { "True" } else { "False" },
            self.nodes,
            self.reverse_nodes,
            self.expansions,
            self.work
        )
    }
}

fn progress(p: &CoreProgress, f: Frame) -> Progress {
    let (status, reason) = match p.status {
        Status::NoGoal => ("no_goal", None),
        Status::Searching => ("searching", None),
        Status::Following => ("following", None),
        Status::Arrived => ("arrived", None),
        Status::Unreachable => ("unreachable", None),
        Status::Evading => ("evading", None),
        Status::Waiting(w) => (
            "waiting",
            Some(match w {
                Wait::PathBlocked => "path_blocked",
                Wait::AgentInObstacle => "agent_in_obstacle",
                Wait::AgentBlocked => "agent_blocked",
                Wait::OutOfTime => "out_of_time",
                Wait::GivingWay => "giving_way",
                Wait::Cornered => "cornered",
            }),
        ),
    };
    Progress {
        waypoint: f.to_user(p.waypoint),
        status,
        reason,
        work: p.work,
        goal_in_tree: p.goal_in_tree,
        goal_cost: p.goal_cost.map(|c| f64::from(c.length)),
        nodes: p.nodes,
        reverse_nodes: p.reverse_nodes,
        expansions: p.expansions,
        advanced: p.advanced,
        tree_full: p.tree_full,
    }
}

/// A planner on a scenario's map (Bi-AM-RRT* tuned by default; any of Table 1's 20 by name).
///
/// Positions are in the map's frame. Each `plan(agent)` call is one control period: it plans
/// for `t_exp` (150 ms unless `t_exp_ms` says) on the planner's clock and returns the next
/// waypoint. With `clock="virtual"` (the default) a call does a fixed amount of work (12 ns
/// a unit), so a run gives the same result on every machine; with `clock="wall"` it lasts
/// `t_exp` of real time.
#[pyclass(module = "bi_am_rrt")]
pub struct Planner {
    inner: Mutex<Inner>,
    frame: Frame,
    name: String,
    nodes: usize,
    params: std::collections::BTreeMap<String, String>,
    prep: Arc<Prepared>,
}

impl Planner {
    fn inner(&self) -> PyResult<std::sync::MutexGuard<'_, Inner>> {
        self.inner
            .lock()
            .map_err(|_| crate::errors::BiAmRrtError::new_err("the planner's lock is poisoned"))
    }
}

/// A scenario from what `Planner` and the simulator functions take: a `Scenario`, or a `Map`
/// with `start` (and no goals).
pub(crate) fn scenario_of(obj: &Bound<'_, PyAny>, start: Option<Xy>) -> PyResult<Scenario> {
    if let Ok(s) = obj.extract::<PyRef<'_, Scenario>>() {
        let mut inner = s.inner.clone();
        if let Some(p) = start {
            inner.start = s.frame().to_planner(point("start", p)?);
        }
        return Ok(Scenario { inner });
    }
    if let Ok(m) = obj.extract::<PyRef<'_, Map>>() {
        let Some(p) = start else {
            return Err(value("a planner on a Map needs start=(x, y)"));
        };
        let inner = Scenario::build(&m, p, Vec::new(), "map".into(), None, 0.0)?;
        return Ok(Scenario { inner });
    }
    Err(value(format!(
        "expected a Scenario or a Map, got {}",
        obj.get_type()
    )))
}

/// The planner configuration `spec` names, fitted to `prep`, with `params` set on it.
pub(crate) fn configure(
    spec: &str,
    prep: &Prepared,
    params: Option<&Bound<'_, PyDict>>,
    t_exp_ms: Option<f64>,
) -> PyResult<bi_am_rrt::Named> {
    let variant = host_sim::sim::planners::one(spec).map_err(|e| value(format!("{e:#}")))?;
    let mut named = variant
        .config_for(prep)
        .map_err(|e| value(format!("{e:#}")))?;
    if let Some(ms) = t_exp_ms {
        let ms = finite("t_exp_ms", ms)?;
        if ms <= 0.0 {
            return Err(value(format!("t_exp_ms {ms}: above 0 needed")));
        }
        named.cfg.budget.t_exp = std::time::Duration::from_secs_f64(ms / 1e3);
    }
    if let Some(d) = params {
        for (k, v) in d.iter() {
            let k: String = k.extract()?;
            let text = if let Ok(b) = v.extract::<bool>() {
                b.to_string()
            } else {
                v.str()?.to_string()
            };
            host_sim::sim::planners::apply(&mut named.cfg, &k, &text)
                .map_err(|e| value(format!("params[{k:?}] = {text}: {e:#}")))?;
        }
    }
    named
        .cfg
        .validate()
        .map_err(|e| value(format!("{}: {e}", variant.name)))?;
    Ok(named)
}

fn tree_arrays<'py, const N: usize>(
    py: Python<'py>,
    t: &bi_am_rrt::tree::Tree<N>,
    f: Frame,
) -> PyResult<Bound<'py, PyDict>> {
    let ids: Vec<_> = t.ids().collect();
    let mut index = vec![-1i64; N];
    for (k, id) in ids.iter().enumerate() {
        index[id.index()] = k as i64;
    }
    let mut xy = Vec::with_capacity(ids.len());
    let mut parent = Vec::with_capacity(ids.len());
    let mut cost = Vec::with_capacity(ids.len());
    let mut blocked = Vec::with_capacity(ids.len());
    for &id in &ids {
        let p = t.position(id).unwrap_or(Point::ZERO);
        let (x, y) = f.to_user(p);
        xy.push(vec![x, y]);
        parent.push(t.parent(id).map_or(-1, |q| index[q.index()]));
        cost.push(t.cost(id).map_or(f64::NAN, |c| f64::from(c.length)));
        blocked.push(t.edge_blocked(id).unwrap_or(false));
    }
    let d = PyDict::new(py);
    let xy = if xy.is_empty() {
        PyArray2::<f64>::zeros(py, [0, 2], false)
    } else {
        PyArray2::from_vec2(py, &xy).map_err(|e| value(e.to_string()))?
    };
    d.set_item("xy", xy)?;
    d.set_item("parent", PyArray1::from_vec(py, parent))?;
    d.set_item("cost", PyArray1::from_vec(py, cost))?;
    d.set_item("blocked", PyArray1::from_vec(py, blocked))?;
    Ok(d)
}

#[pymethods]
impl Planner {
    /// A planner on `scenario` (a `Scenario`, or a `Map` with `start`).
    ///
    /// - `planner`: `"tuned"` (the default), `"paper"` (Bi-AM-RRT*(D) with Table 2's values),
    ///   or any name of `planner_names()`, with `@field=value` overrides as `host-sim` takes.
    /// - `seed`: the random stream. `nodes`: 2048, 4096, 8192, 16384 or 65000 per tree
    ///   (default: 8192, or the smallest that holds the scenario's roadmap, as `host-sim run`).
    /// - `clock`: `"virtual"` (work units; deterministic) or `"wall"`. `t_exp_ms`: each call's
    ///   planning time (the paper: 150).
    /// - `params`: parameter-table values by name (`params()` lists them), e.g.
    ///   `{"e_max": 4.0}`. `live_cells`: a map whose cells `set_cells` may edit.
    /// - `table`: a `DiffusionTable` for the diffusion metric (else one is baked).
    /// - `robot_radius`: the robot's disc (metres; default: the scenario's, a point on a
    ///   `Map`): every waypoint keeps the disc clear of the walls and obstacles.
    #[new]
    #[pyo3(signature = (scenario, planner="tuned", seed=1, nodes=None, start=None, clock="virtual", t_exp_ms=None, params=None, live_cells=false, table=None, robot_radius=None))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        scenario: &Bound<'_, PyAny>,
        planner: &str,
        seed: u64,
        nodes: Option<usize>,
        start: Option<Xy>,
        clock: &str,
        t_exp_ms: Option<f64>,
        params: Option<&Bound<'_, PyDict>>,
        live_cells: bool,
        table: Option<PyRef<'_, crate::sim::DiffusionTable>>,
        robot_radius: Option<f64>,
    ) -> PyResult<Self> {
        let mut s = scenario_of(scenario, start)?;
        if let Some(r) = robot_radius {
            finite("robot_radius", r)?;
            s.inner = s
                .inner
                .with_robot_radius(r as f32)
                .map_err(|e| value(format!("{e:#}")))?;
        }
        let frame = s.frame();
        let start = s.inner.start;
        let mut prep = Prepared::new(s.inner).without_optimum();
        if let Some(t) = table {
            prep = prep
                .with_diffusion_table(t.bytes.clone())
                .map_err(|e| value(format!("{e:#}")))?;
        }
        let prep = Arc::new(prep);
        let named = configure(planner, &prep, params, t_exp_ms)?;
        let clock = match clock {
            "virtual" => Clocks::Virtual(virtual_clock(VIRTUAL_NS_PER_UNIT)),
            "wall" => Clocks::Wall(WallClock::new()),
            other => {
                return Err(value(format!("clock {other:?}: \"virtual\" or \"wall\"")));
            }
        };
        let p = prep.clone();
        // The diffusion bake (seconds on a large map) runs without the interpreter's lock.
        let (sized, nodes) = py
            .detach(move || -> Result<(Sized, usize), Refused> {
                let nodes = nodes.unwrap_or_else(|| p.arena_for(named));
                let sized = match nodes {
                    2048 => Sized::N2048(build(p, named, seed, start, live_cells)?),
                    4096 => Sized::N4096(build(p, named, seed, start, live_cells)?),
                    8192 => Sized::N8192(build(p, named, seed, start, live_cells)?),
                    16384 => Sized::N16384(build(p, named, seed, start, live_cells)?),
                    65000 => Sized::N65000(build(p, named, seed, start, live_cells)?),
                    n => return Err(Refused::Nodes(n)),
                };
                Ok((sized, nodes))
            })
            .map_err(Refused::into_py)?;
        Ok(Self {
            inner: Mutex::new(Inner { sized, clock }),
            frame,
            name: named.name().to_string(),
            nodes,
            params: host_sim::results::config_record(&named.cfg),
            prep,
        })
    }

    /// The planner's name (Table 1's, e.g. "Bi-AM-RRT*(D) tuned").
    #[getter]
    fn name(&self) -> String {
        self.name.clone()
    }

    /// Nodes per tree.
    #[getter]
    fn nodes(&self) -> usize {
        self.nodes
    }

    /// Every value of the parameter table as this planner has it (name -> text).
    fn params(&self) -> std::collections::BTreeMap<String, String> {
        self.params.clone()
    }

    /// The map it plans on.
    #[getter]
    fn map(&self) -> Map {
        Scenario::map_of(&self.prep.scenario)
    }

    /// Sets the goal (the forward tree starts a new search; the trees are kept). Raises
    /// `InWallError` for a goal in a wall (or where the robot's disc has no room) and
    /// `PositionError` for one outside the map or cut off from the start.
    fn set_goal(&self, goal: Xy) -> PyResult<()> {
        let g = self.frame.to_planner(point("goal", goal)?);
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => p.set_goal(g)).map_err(|e| position("goal", goal, e))
    }

    /// One control period with the agent at `agent`: plans for the call's budget and returns
    /// the `Progress` (the next waypoint, the status, and why the agent holds if it does).
    fn plan(&self, py: Python<'_>, agent: Xy) -> PyResult<Progress> {
        let a = self.frame.to_planner(point("agent", agent)?);
        let f = self.frame;
        let r = py.detach(|| -> PyResult<_> {
            let mut inner = self.inner()?;
            let Inner { sized, clock } = &mut *inner;
            Ok(match clock {
                Clocks::Virtual(c) => on!(sized, p => p.plan(c, a)),
                Clocks::Wall(c) => on!(sized, p => p.plan(c, a)),
            })
        })?;
        r.map(|p| progress(&p, f))
            .map_err(|e| position("agent", agent, e))
    }

    /// Planning while the agent stands still: expansion and rewiring for one call's budget.
    fn grow(&self, py: Python<'_>) -> PyResult<Progress> {
        let f = self.frame;
        let p = py.detach(|| -> PyResult<_> {
            let mut inner = self.inner()?;
            let Inner { sized, clock } = &mut *inner;
            Ok(match clock {
                Clocks::Virtual(c) => on!(sized, p => p.grow(c)),
                Clocks::Wall(c) => on!(sized, p => p.grow(c)),
            })
        })?;
        Ok(progress(&p, f))
    }

    /// The clock's reading in seconds (virtual: the work done so far at 12 ns a unit).
    fn clock_s(&self) -> PyResult<f64> {
        let inner = self.inner()?;
        Ok(match &inner.clock {
            Clocks::Virtual(c) => c.peek() as f64 / c.ticks_per_second() as f64,
            Clocks::Wall(c) => c.now() as f64 / c.ticks_per_second() as f64,
        })
    }

    /// Adds a circular obstacle at `center` (radius in metres), moving at `velocity` (m/s)
    /// if given; returns its id.
    #[pyo3(signature = (center, radius, velocity=None))]
    fn add_obstacle(&self, center: Xy, radius: f64, velocity: Option<Xy>) -> PyResult<u32> {
        let m = self.moving(center, radius, velocity)?;
        let mut inner = self.inner()?;
        let id = on!(&mut inner.sized, p => p.add_moving_obstacle(m))
            .map_err(|e| value(format!("obstacle: {e}")))?;
        Ok(id.0)
    }

    /// Reports where obstacle `id` is now (and its velocity): submit each one's state before
    /// every call.
    #[pyo3(signature = (id, center, radius, velocity=None))]
    fn update_obstacle(
        &self,
        id: u32,
        center: Xy,
        radius: f64,
        velocity: Option<Xy>,
    ) -> PyResult<()> {
        let m = self.moving(center, radius, velocity)?;
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => p.update_obstacle(ObstacleId(id), m))
            .map_err(|e| value(format!("obstacle {id}: {e}")))
    }

    /// Removes obstacle `id`.
    fn remove_obstacle(&self, id: u32) -> PyResult<()> {
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => p.remove_obstacle(ObstacleId(id)))
            .map(|_| ())
            .map_err(|e| value(format!("obstacle {id}: {e}")))
    }

    /// Marks (`occupied=True`) or clears the cells of the rectangle with corner cells `a` and
    /// `b` (`(col, row)`, rows from the top, inclusive) on a planner made with
    /// `live_cells=True`; returns how many cells changed.
    fn set_cells(&self, a: (u16, u16), b: (u16, u16), occupied: bool) -> PyResult<u32> {
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => p.set_cells(a, b, occupied))
            .map_err(|e| value(format!("set_cells: {e}")))
    }

    /// The forward tree as numpy arrays: `xy` (n x 2), `parent` (row of each node's parent,
    /// -1 for the root), `cost` (metres from the root), `blocked` (the edge to the parent
    /// crosses an obstacle).
    fn tree<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = self.frame;
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => tree_arrays(py, p.tree(), f))
    }

    /// The reverse tree (two-tree planners; empty otherwise), as `tree()`.
    fn reverse_tree<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let f = self.frame;
        let mut inner = self.inner()?;
        on!(&mut inner.sized, p => tree_arrays(py, p.reverse_tree(), f))
    }

    /// The current path from the root (n x 2), to the goal once it is in the tree, else to
    /// the node nearest it.
    fn path<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let f = self.frame;
        let mut inner = self.inner()?;
        let pts: Vec<Vec<f64>> = on!(&mut inner.sized, p => {
            let mut buf = vec![Point::ZERO; p.tree().len().max(1)];
            match p.path(&mut buf) {
                Ok(info) => buf[..info.len]
                    .iter()
                    .map(|&q| {
                        let (x, y) = f.to_user(q);
                        vec![x, y]
                    })
                    .collect(),
                Err(_) => Vec::new(),
            }
        });
        if pts.is_empty() {
            return Ok(PyArray2::<f64>::zeros(py, [0, 2], false));
        }
        PyArray2::from_vec2(py, &pts).map_err(|e| value(e.to_string()))
    }

    /// Counters since the goal was set: `expansions`, `reverse_expansions`, `goal_found_at`
    /// (clock ticks), `nodes_at_goal`, `first_cost`, `met`.
    fn stats<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let mut inner = self.inner()?;
        let s = on!(&mut inner.sized, p => *p.stats());
        let d = PyDict::new(py);
        d.set_item("expansions", s.expansions)?;
        d.set_item("reverse_expansions", s.reverse_expansions)?;
        d.set_item("goal_found_at", s.goal_found_at)?;
        d.set_item("nodes_at_goal", s.nodes_at_goal)?;
        d.set_item("first_cost", s.first_cost)?;
        d.set_item("met", s.met)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        format!(
            "Planner({:?} on {:?}, {} nodes per tree)",
            self.name, self.prep.scenario.name, self.nodes
        )
    }
}

impl Planner {
    fn moving(&self, center: Xy, radius: f64, velocity: Option<Xy>) -> PyResult<Moving> {
        let c = self.frame.to_planner(point("center", center)?);
        let r = finite("radius", radius)?;
        if r <= 0.0 {
            return Err(value(format!("radius {r}: above 0 needed")));
        }
        let circle = Circle::new(c, r as f32);
        Ok(match velocity {
            None => Moving::still(circle),
            Some(v) => {
                let v = point("velocity", v)?;
                // The planner's frame has y down: a ROS frame's y velocity flips.
                let flip = if self.frame_is_ros() { -1.0 } else { 1.0 };
                Moving::new(circle, Point::new(v.0 as f32, (flip * v.1) as f32))
            }
        })
    }

    fn frame_is_ros(&self) -> bool {
        self.prep.scenario.ros_origin.is_some()
    }
}

/// The names `Planner(planner=...)` takes: Table 1's 20 planners, and the words `tuned` and
/// `paper`.
#[pyfunction]
fn planner_names() -> Vec<String> {
    let mut out = vec!["tuned".to_string(), "paper".to_string()];
    out.extend(
        bi_am_rrt::Named::table1()
            .iter()
            .map(|n| n.name().to_string()),
    );
    out
}
