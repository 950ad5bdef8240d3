//! The simulator for Python: metric data (`DiffusionTable`, the geodesic distance), the exact
//! optimum, `run` (one planner driven through a scenario's goals by the agent protocol, as
//! `host-sim run` drives it) and `experiment` (the planners x scenarios x seeds matrix of
//! `host-sim experiment`). Rows come back as lists of dicts, the columns of `host-sim`'s
//! `runs.csv` and `result.json`: `pandas.DataFrame(rows)` takes them as they are.

use std::path::PathBuf;
use std::sync::Arc;

use bi_am_rrt::Point;
use bi_am_rrt::agent::Protocol;
use bi_am_rrt::clock::Clock;
use bi_am_rrt::metric::Metric;
use host_sim::metric::diffusion::TableOptions;
use host_sim::results::{Goals, Pace, Row};
use host_sim::scenario::Scenario as HsScenario;
use host_sim::sim::clock::{
    ClockKind, CpuClock, CpuMonoClock, VIRTUAL_NS_PER_UNIT, WallClock, virtual_clock,
};
use host_sim::sim::{GoalRun, Prepared, drive_each, with_planner};
use host_sim::study::experiment::{self as exp, Existing, ExperimentArgs};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::Xy;
use crate::errors::{lib, point, value};
use crate::maps::{Map, Scenario};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<DiffusionTable>()?;
    m.add_function(wrap_pyfunction!(exact_optimum, m)?)?;
    m.add_function(wrap_pyfunction!(geodesic_distance, m)?)?;
    m.add_function(wrap_pyfunction!(run, m)?)?;
    m.add_function(wrap_pyfunction!(experiment, m)?)?;
    Ok(())
}

/// A diffusion table (the assisting metric `d_D` of the paper, section 4): baked from a map,
/// saved and loaded in the file format `host-sim bake` writes, given to a `Planner`.
#[pyclass(module = "bi_am_rrt", frozen)]
pub struct DiffusionTable {
    pub(crate) bytes: Vec<u8>,
}

#[pymethods]
impl DiffusionTable {
    /// Bakes the table of a `Scenario` (the part of its map the start can reach, inflated for
    /// its robot) or of a `Map` (its largest free region). Seconds on a large map; the
    /// interpreter's lock is released meanwhile.
    #[staticmethod]
    fn bake(py: Python<'_>, of: &Bound<'_, PyAny>) -> PyResult<Self> {
        let scenario = if let Ok(s) = of.extract::<PyRef<'_, Scenario>>() {
            Some(s.inner.clone())
        } else {
            None
        };
        let map = of
            .extract::<PyRef<'_, Map>>()
            .ok()
            .map(|m| m.file.grid.clone());
        let bytes = py.detach(move || -> Result<Vec<u8>, anyhow::Error> {
            if let Some(s) = scenario {
                let prep = Prepared::new(s);
                return Ok(prep.diffusion()?.table.clone());
            }
            let Some(grid) = map else {
                anyhow::bail!("DiffusionTable.bake takes a Scenario or a Map");
            };
            let b = host_sim::metric::bake::bake_diffusion(
                &grid,
                &host_sim::metric::diffusion::Options::default(),
                &TableOptions::default(),
            )?;
            Ok(b.table)
        });
        bytes.map(|bytes| Self { bytes }).map_err(lib)
    }

    /// Reads a table file (`host-sim bake`'s, or `save`'s); its checksum is verified.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<Self> {
        let bytes = std::fs::read(&path)
            .map_err(|e| lib(anyhow::anyhow!("reading {}: {e}", path.display())))?;
        bi_am_rrt::DiffusionTable::new(&bytes)
            .map_err(|e| lib(anyhow::anyhow!("{}: {e}", path.display())))?;
        Ok(Self { bytes })
    }

    /// Writes the table file.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        host_sim::metric::bake::write_file(&path, &self.bytes).map_err(lib)
    }

    /// The table's bytes (the file's contents).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, pyo3::types::PyBytes> {
        pyo3::types::PyBytes::new(py, &self.bytes)
    }

    /// The diffusion distance between two points of the map the table was baked for, in
    /// planner coordinates (metres from the map's top-left corner, y down); infinite between
    /// regions the table keeps apart.
    fn distance(&self, a: Xy, b: Xy) -> PyResult<f64> {
        let (a, b) = (point("a", a)?, point("b", b)?);
        let t = bi_am_rrt::DiffusionTable::new_unverified(&self.bytes)
            .map_err(|e| value(e.to_string()))?;
        Ok(f64::from(t.distance(
            Point::new(a.0 as f32, a.1 as f32),
            Point::new(b.0 as f32, b.1 as f32),
        )))
    }

    fn __len__(&self) -> usize {
        self.bytes.len()
    }

    fn __repr__(&self) -> String {
        format!("DiffusionTable({} bytes)", self.bytes.len())
    }
}

/// The exact shortest path between `a` and `b` on `map` (positions in its frame; a path of a
/// point among the occupied cells taken as closed squares): `(length_m, points)` with the
/// points an `n x 2` list, or None when `b` cannot be reached from `a`. For a robot with a
/// body, pass a `Scenario` with its radius: the path is then the disc centre's.
#[pyfunction]
fn exact_optimum(
    py: Python<'_>,
    map: &Bound<'_, PyAny>,
    a: Xy,
    b: Xy,
) -> PyResult<Option<(f64, Vec<Xy>)>> {
    let s = crate::planner::scenario_of(map, Some(a))?;
    let f = s.frame();
    let (pa, pb) = (f.to_planner(point("a", a)?), f.to_planner(point("b", b)?));
    let inner = s.inner;
    on_free_cell(&inner, "a", a, pa)?;
    on_free_cell(&inner, "b", b, pb)?;
    let r = py.detach(move || {
        let grid = inner.reach_grid();
        let corners = host_sim::metric::optimum::Corners::of(&grid);
        corners.shortest_path(pa, pb)
    });
    Ok(r.map(|(d, pts)| (d, pts.into_iter().map(|p| f.to_user(p)).collect())))
}

/// The geodesic distance (the shortest path over the 8-connected grid of free cells, the
/// paper's `d_G`) between `a` and `b` on a `Map` or `Scenario`, in metres; infinite when
/// they are not connected.
#[pyfunction]
fn geodesic_distance(map: &Bound<'_, PyAny>, a: Xy, b: Xy) -> PyResult<f64> {
    let s = crate::planner::scenario_of(map, Some(a))?;
    let f = s.frame();
    let (pa, pb) = (f.to_planner(point("a", a)?), f.to_planner(point("b", b)?));
    on_free_cell(&s.inner, "a", a, pa)?;
    on_free_cell(&s.inner, "b", b, pb)?;
    let prep = Prepared::new(s.inner);
    let g = host_sim::metric::Geodesic::new(prep.graph(), 2);
    Ok(f64::from(g.distance(pa, pb)))
}

/// A position in a free cell of the scenario's map (where its robot has room), or the
/// exception that says why not.
fn on_free_cell(s: &HsScenario, what: &str, user: Xy, p: Point) -> PyResult<()> {
    let g = s.reach_grid();
    match g.cell_of(p) {
        None => Err(crate::errors::PositionError::new_err(format!(
            "{what} ({}, {}): position outside the map",
            user.0, user.1
        ))),
        Some((c, r)) if g.is_occupied(c, r) => Err(crate::errors::InWallError::new_err(format!(
            "{what} ({}, {}): position inside an obstacle (or without room for the robot)",
            user.0, user.1
        ))),
        Some(_) => Ok(()),
    }
}

fn clock_kind(clock: &str) -> PyResult<ClockKind> {
    match clock {
        "virtual" => Ok(ClockKind::Virtual),
        "wall" => Ok(ClockKind::Wall),
        "cpu" => Ok(ClockKind::Cpu),
        "cpu-mono" => Ok(ClockKind::CpuMono),
        other => Err(value(format!(
            "clock {other:?}: \"virtual\", \"cpu\", \"cpu-mono\" or \"wall\""
        ))),
    }
}

fn pace_of(pace: &str) -> PyResult<Pace> {
    match pace {
        "full" => Ok(Pace::Full),
        "paper" => Ok(Pace::Paper),
        other => Err(value(format!("pace {other:?}: \"full\" or \"paper\""))),
    }
}

/// Rows as `host-sim` writes them (its JSON, read by Python's `json`): the same numbers as its
/// files to the last digit (an `f32` is written as the shortest decimal that reads back to it,
/// as in `result.json` and `runs.csv`).
fn to_py<'py, T: serde::Serialize>(py: Python<'py>, v: &T) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| value(e.to_string()))?;
    py.import("json")?.call_method1("loads", (text,))
}

/// Drives one planner through a scenario's goals, as `host-sim run` does (the agent
/// protocol: at most 0.7 m a call, each leg's call cap), and returns one dict per goal: the
/// columns of `runs.csv` (`reached`, `path_length_m`, `search_time_s`, `optimal_m`, ...), the
/// trail's clearance and the `trail` itself (positions in the map's frame): `result.json`'s
/// goals, the same to the bit for the same seed on the virtual clock.
///
/// `optimum=False` skips each leg's exact optimum (`optimal_m` None).
#[pyfunction]
#[pyo3(signature = (scenario, planner="tuned", seed=1, all_goals=false, clock="virtual", t_exp_ms=None, pace="full", optimum=true, params=None))]
#[allow(clippy::too_many_arguments)]
fn run<'py>(
    py: Python<'py>,
    scenario: PyRef<'_, Scenario>,
    planner: &str,
    seed: u64,
    all_goals: bool,
    clock: &str,
    t_exp_ms: Option<f64>,
    pace: &str,
    optimum: bool,
    params: Option<&Bound<'py, PyDict>>,
) -> PyResult<Bound<'py, PyAny>> {
    let kind = clock_kind(clock)?;
    let paper = pace_of(pace)? == Pace::Paper;
    if paper && kind != ClockKind::Virtual {
        return Err(value(
            "pace=\"paper\" needs clock=\"virtual\" (every call lasts its full t_exp)",
        ));
    }
    let prep = Prepared::new(scenario.inner.clone());
    let prep = if optimum {
        prep
    } else {
        prep.without_optimum()
    };
    let prep = Arc::new(prep);
    let mut cfg = crate::planner::configure(planner, &prep, params, t_exp_ms)?;
    if paper {
        host_sim::sim::paper_pace(&mut cfg.cfg);
    }
    let p2 = prep.clone();
    let (rows, legs) = py
        .detach(move || drive_run(&p2, cfg, seed, all_goals, kind, paper))
        .map_err(lib)?;
    to_py(py, &host_sim::study::run::result_goals(&prep, &rows, &legs))
}

/// `host-sim run`'s drive without its pictures: the rows and each goal's trail.
fn drive_run(
    prep: &Prepared,
    cfg: bi_am_rrt::Named,
    seed: u64,
    all_goals: bool,
    kind: ClockKind,
    paper: bool,
) -> anyhow::Result<(Vec<Row>, Vec<Vec<Point>>)> {
    let goals: Vec<usize> = if all_goals {
        (0..prep.scenario.goals.len()).collect()
    } else {
        vec![0]
    };
    let leg_starts = host_sim::metric::optimum::leg_starts(&prep.scenario);
    let mut legs: Vec<Vec<Point>> = vec![Vec::new(); prep.scenario.goals.len()];
    let wall = WallClock::new();
    let cpu = CpuClock::new();
    let cpu_mono = CpuMonoClock::new();
    let virt = virtual_clock(VIRTUAL_NS_PER_UNIT);
    let t_exp_ticks = virt.ticks(cfg.cfg.budget.t_exp);
    let mut call_end = 0u64;
    let protocol = Protocol::default();
    let started = std::time::Instant::now();
    let (runs, final_nodes) = with_planner(prep, cfg, seed, |p| {
        let hook = |_: &mut host_sim::sim::SimPlanner<'_, '_>, gi: usize, agent: Point, _| {
            // At the paper's pace every call lasts its full t_exp.
            if paper {
                let end = call_end.saturating_add(t_exp_ticks).max(virt.peek());
                virt.set(end);
                call_end = end;
            }
            let leg = &mut legs[gi];
            if leg.is_empty() {
                leg.push(leg_starts[gi]);
            }
            if leg.last() != Some(&agent) {
                leg.push(agent);
            }
        };
        let runs: Vec<GoalRun> = match kind {
            ClockKind::Wall => drive_each(p, prep, &wall, &goals, &protocol, hook, |_| {})?,
            ClockKind::Cpu => drive_each(p, prep, &cpu, &goals, &protocol, hook, |_| {})?,
            ClockKind::CpuMono => drive_each(p, prep, &cpu_mono, &goals, &protocol, hook, |_| {})?,
            ClockKind::Virtual => drive_each(p, prep, &virt, &goals, &protocol, hook, |_| {})?,
        };
        Ok((runs, p.tree().len()))
    })?;
    let wall_s = started.elapsed().as_secs_f64();
    let rows = runs
        .iter()
        .map(|g| host_sim::sim::row(prep, cfg, seed, g, kind, final_nodes, None, wall_s))
        .collect();
    Ok((rows, legs))
}

/// Runs the matrix planners x scenarios x `repeats` seeds (from `seed`) as `host-sim
/// experiment` does, in parallel (`jobs` threads; all cores by default), and returns one dict
/// per goal run: `runs.csv`'s rows. `planners`: a list of names or one comma-separated string
/// (`"all"`: Table 1's 20). `out`: a results folder to keep (`host-sim report` draws it);
/// `resume=True` runs only what it lacks. Without `out` the folder is temporary.
#[pyfunction]
#[pyo3(signature = (scenarios, planners=None, repeats=1, seed=1, all_goals=false, clock="virtual", t_exp_ms=None, pace="full", optimum=true, search_only=false, jobs=None, out=None, resume=false))]
#[allow(clippy::too_many_arguments)]
fn experiment<'py>(
    py: Python<'py>,
    scenarios: &Bound<'py, PyAny>,
    planners: Option<&Bound<'py, PyAny>>,
    repeats: u32,
    seed: u64,
    all_goals: bool,
    clock: &str,
    t_exp_ms: Option<f64>,
    pace: &str,
    optimum: bool,
    search_only: bool,
    jobs: Option<usize>,
    out: Option<PathBuf>,
    resume: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let scs: Vec<HsScenario> = if let Ok(s) = scenarios.extract::<PyRef<'_, Scenario>>() {
        vec![s.inner.clone()]
    } else {
        scenarios
            .try_iter()?
            .map(|s| Ok(s?.extract::<PyRef<'_, Scenario>>()?.inner.clone()))
            .collect::<PyResult<_>>()?
    };
    let spec = match planners {
        None => "tuned".to_string(),
        Some(p) => match p.extract::<String>() {
            Ok(s) => s,
            Err(_) => p.extract::<Vec<String>>()?.join(","),
        },
    };
    let variants =
        host_sim::sim::planners::parse_variants(&spec).map_err(|e| value(format!("{e:#}")))?;
    if let Some(ms) = t_exp_ms
        && !(ms.is_finite() && ms >= 1.0)
    {
        return Err(value(format!("t_exp_ms {ms}: at least 1 needed")));
    }
    let temp = match &out {
        Some(_) => None,
        None => Some(tempfile::tempdir().map_err(|e| lib(e.into()))?),
    };
    let dir = out.clone().unwrap_or_else(|| {
        temp.as_ref()
            .map(|t| t.path().join("results"))
            .unwrap_or_default()
    });
    let args = ExperimentArgs {
        scenarios: scs,
        planners: variants,
        repeats,
        clock: clock_kind(clock)?,
        goals: if all_goals { Goals::All } else { Goals::First },
        seed,
        jobs,
        faithful: false,
        wait_from_set: false,
        move_when_blocked: false,
        pace: pace_of(pace)?,
        no_optimum: !optimum,
        as_printed: bi_am_rrt::AsPrinted::default(),
        meet_all_pairs: false,
        obstacle: None,
        search_only,
        anytime_ms: 0,
        table: TableOptions::default(),
        t_exp: t_exp_ms.map(|ms| std::time::Duration::from_secs_f64(ms / 1e3)),
        shard: None,
        existing: if resume {
            Existing::Resume
        } else {
            Existing::Refuse
        },
        out: dir.clone(),
    };
    let rows = py
        .detach(|| -> anyhow::Result<Vec<Row>> {
            exp::run(&args)?;
            host_sim::results::read_rows(&dir, false)
        })
        .map_err(lib)?;
    drop(temp);
    to_py(py, &rows)
}
