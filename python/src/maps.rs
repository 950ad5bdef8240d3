//! Maps and scenarios: `Map` (a ROS map_server YAML, a PNG, a numpy array) and `Scenario` (a
//! map, a start, goals, the robot's radius), the built-in scenarios and scenario files, all
//! through `host_sim::scenario`.
//!
//! Frames: a map read from a ROS YAML, or given an `origin`, takes positions in its ROS frame
//! (metres, y up from the origin, the lower-left corner of the image); any other map in
//! metres from its top-left corner, y down (the planner's own frame). Arrays are rows from the
//! top, as an image and matplotlib's `imshow` have them.

use std::path::PathBuf;

use bi_am_rrt::Point;
use host_sim::scenario::{self as hs, MapFile, OwnedGrid};
use numpy::{PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;

use crate::Xy;
use crate::errors::{lib, point, value};

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<Map>()?;
    m.add_class::<Scenario>()?;
    m.add_function(wrap_pyfunction!(load_scenarios, m)?)?;
    m.add_function(wrap_pyfunction!(builtin_names, m)?)?;
    Ok(())
}

/// A map's frame: ROS (an origin, y up) or the planner's (top-left, y down).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    origin: Option<[f64; 2]>,
    height_m: f64,
}

impl Frame {
    pub(crate) fn of(file: &MapFile) -> Self {
        let g = file.grid.grid();
        Self {
            origin: file.ros_origin,
            height_m: f64::from(g.rows()) * f64::from(g.cell_size()),
        }
    }

    /// A position of this frame in the planner's.
    pub(crate) fn to_planner(self, p: Xy) -> Point {
        match self.origin {
            Some([ox, oy]) => Point::new((p.0 - ox) as f32, (self.height_m - (p.1 - oy)) as f32),
            None => Point::new(p.0 as f32, p.1 as f32),
        }
    }

    /// A planner position in this frame.
    pub(crate) fn to_user(self, p: Point) -> Xy {
        match self.origin {
            Some([ox, oy]) => (f64::from(p.x) + ox, self.height_m - f64::from(p.y) + oy),
            None => (f64::from(p.x), f64::from(p.y)),
        }
    }
}

/// An occupancy grid map (immutable).
///
/// Build one with `Map.from_ros`, `Map.from_png` or `Map.from_array`.
#[pyclass(module = "bi_am_rrt", frozen)]
#[derive(Clone)]
pub struct Map {
    pub(crate) file: MapFile,
    /// Where it came from (a path, `array`, `builtin:NAME`).
    pub(crate) source: String,
}

impl Map {
    pub(crate) fn frame(&self) -> Frame {
        Frame::of(&self.file)
    }
}

/// An `f32` as the `f64` of its shortest decimal.
fn short(v: f32) -> f64 {
    v.to_string().parse().unwrap_or(f64::from(v))
}

fn check_resolution(r: f64) -> PyResult<f32> {
    hs::check_resolution("resolution_m", r as f32).map_err(|e| value(format!("{e:#}")))?;
    Ok(r as f32)
}

#[pymethods]
impl Map {
    /// Reads a ROS map_server map: the YAML file and the PGM or PNG image it names (its
    /// `resolution`, `origin`, `negate`, thresholds and `mode` are applied as map_server does).
    /// Positions on this map are in its ROS frame.
    #[staticmethod]
    fn from_ros(yaml_path: PathBuf) -> PyResult<Self> {
        let file = hs::load_ros_yaml(&yaml_path).map_err(lib)?;
        Ok(Self {
            file,
            source: yaml_path.display().to_string(),
        })
    }

    /// Reads a PNG map (dark pixels are walls, the reference's threshold rule) with cells of
    /// `resolution_m` metres. Positions are metres from its top-left corner, y down.
    #[staticmethod]
    fn from_png(path: PathBuf, resolution_m: f64) -> PyResult<Self> {
        let r = check_resolution(resolution_m)?;
        let mut grid = hs::load_png(&path).map_err(lib)?;
        grid.cell_bits = r.to_bits();
        Ok(Self {
            file: grid.into(),
            source: path.display().to_string(),
        })
    }

    /// A map from a 2-D numpy array of `bool` (True: occupied) or `uint8` (non-zero:
    /// occupied), rows from the top. With `origin=(x, y)` positions are in a ROS-like frame
    /// (y up, the array's lower-left corner at `origin`); without, metres from the top-left
    /// corner, y down.
    #[staticmethod]
    #[pyo3(signature = (array, resolution_m, origin=None))]
    fn from_array(
        array: &Bound<'_, PyAny>,
        resolution_m: f64,
        origin: Option<Xy>,
    ) -> PyResult<Self> {
        let r = check_resolution(resolution_m)?;
        if let Some(o) = origin {
            point("origin", o)?;
        }
        let cells: (usize, usize, Vec<bool>) =
            if let Ok(a) = array.extract::<PyReadonlyArray2<'_, bool>>() {
                let v = a.as_array();
                (v.nrows(), v.ncols(), v.iter().copied().collect())
            } else if let Ok(a) = array.extract::<PyReadonlyArray2<'_, u8>>() {
                let v = a.as_array();
                (v.nrows(), v.ncols(), v.iter().map(|&c| c != 0).collect())
            } else {
                return Err(describe_bad_array(array));
            };
        let (rows, cols, occupied) = cells;
        let most = usize::from(u16::MAX);
        if rows == 0 || cols == 0 || rows > most || cols > most {
            return Err(value(format!(
                "array of {rows} x {cols} cells: a map has 1 to {most} rows and columns"
            )));
        }
        let grid = OwnedGrid::from_fn(cols as u16, rows as u16, r, |c, row| {
            occupied[usize::from(row) * cols + usize::from(c)]
        })
        .map_err(|e| value(format!("{e:#}")))?;
        Ok(Self {
            file: MapFile {
                grid,
                ros_origin: origin.map(|o| [o.0, o.1]),
            },
            source: "array".into(),
        })
    }

    /// `(rows, cols)`.
    #[getter]
    fn shape(&self) -> (usize, usize) {
        (
            usize::from(self.file.grid.height),
            usize::from(self.file.grid.width),
        )
    }

    /// Cell side in metres (the map's `f32`, as the shortest decimal that reads back to it:
    /// 0.05, not 0.0500000007).
    #[getter]
    fn resolution_m(&self) -> f64 {
        short(f32::from_bits(self.file.grid.cell_bits))
    }

    /// Width in metres.
    #[getter]
    fn width_m(&self) -> f64 {
        f64::from(self.file.grid.width) * self.resolution_m()
    }

    /// Height in metres.
    #[getter]
    fn height_m(&self) -> f64 {
        f64::from(self.file.grid.height) * self.resolution_m()
    }

    /// The ROS origin `(x, y)` (the lower-left corner), or None for the top-left frame.
    #[getter]
    fn origin(&self) -> Option<Xy> {
        self.file.ros_origin.map(|[x, y]| (x, y))
    }

    /// Where the map came from.
    #[getter]
    fn source(&self) -> String {
        self.source.clone()
    }

    /// `(left, right, bottom, top)` of the map in its frame: matplotlib's `extent` for
    /// `imshow(map.to_array(), extent=map.extent, origin="upper")` (top-left frame: bottom
    /// is the height, top 0, so the y axis points down as the frame's does).
    #[getter]
    fn extent(&self) -> (f64, f64, f64, f64) {
        let f = self.frame();
        let (w, h) = (self.width_m() as f32, self.height_m() as f32);
        let low = f.to_user(Point::new(0.0, h));
        let high = f.to_user(Point::new(w, 0.0));
        (low.0, high.0, low.1, high.1)
    }

    /// The cells as a `bool` array (True: occupied), rows from the top.
    fn to_array<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<bool>>> {
        let g = self.file.grid.grid();
        let rows: Vec<Vec<bool>> = (0..g.rows())
            .map(|r| (0..g.cols()).map(|c| g.is_occupied(c, r)).collect())
            .collect();
        PyArray2::from_vec2(py, &rows).map_err(|e| value(e.to_string()))
    }

    /// Whether a point is in a free cell (False outside the map).
    fn is_free(&self, p: Xy) -> PyResult<bool> {
        let p = self.frame().to_planner(point("point", p)?);
        let g = self.file.grid.grid();
        Ok(g.cell_of(p).is_some_and(|(c, r)| !g.is_occupied(c, r)))
    }

    fn __repr__(&self) -> String {
        let (rows, cols) = self.shape();
        format!(
            "Map({} x {} cells of {} m, {})",
            cols,
            rows,
            self.resolution_m(),
            self.source
        )
    }
}

fn describe_bad_array(array: &Bound<'_, PyAny>) -> PyErr {
    let dtype = array
        .getattr("dtype")
        .map(|d| d.to_string())
        .unwrap_or_else(|_| array.get_type().to_string());
    let ndim = array
        .getattr("ndim")
        .and_then(|n| n.extract::<usize>())
        .ok();
    match ndim {
        Some(n) if n != 2 => value(format!(
            "a map array has 2 dimensions (rows, columns); this one has {n}"
        )),
        _ => value(format!(
            "a map array is a 2-D numpy array of bool or uint8; this one is {dtype} (convert it: \
             array.astype(bool))"
        )),
    }
}

/// A scenario: a map, a start, goals in order, the robot's radius.
#[pyclass(module = "bi_am_rrt", frozen)]
#[derive(Clone)]
pub struct Scenario {
    pub(crate) inner: hs::Scenario,
}

impl Scenario {
    pub(crate) fn frame(&self) -> Frame {
        Frame {
            origin: self.inner.ros_origin,
            height_m: f64::from(self.inner.map.height)
                * f64::from(f32::from_bits(self.inner.map.cell_bits)),
        }
    }

    /// The map of a scenario as a Python `Map`.
    pub(crate) fn map_of(s: &hs::Scenario) -> Map {
        Map {
            file: MapFile {
                grid: s.map.clone(),
                ros_origin: s.ros_origin,
            },
            source: s.source.clone(),
        }
    }

    pub(crate) fn build(
        map: &Map,
        start: Xy,
        goals: Vec<Xy>,
        name: String,
        sigma_m: Option<f64>,
        robot_radius: f64,
    ) -> PyResult<hs::Scenario> {
        let f = map.frame();
        let start = f.to_planner(point("start", start)?);
        let goals = goals
            .into_iter()
            .enumerate()
            .map(|(i, g)| point(&format!("goal {}", i + 1), g).map(|g| f.to_planner(g)))
            .collect::<PyResult<Vec<_>>>()?;
        if let Some(s) = sigma_m {
            crate::errors::finite("sigma_m", s)?;
        }
        crate::errors::finite("robot_radius", robot_radius)?;
        let mut s = hs::Scenario::new(
            name,
            map.file.grid.clone(),
            map.source.clone(),
            start,
            goals,
            sigma_m.map(|s| s as f32),
        );
        s.ros_origin = map.file.ros_origin;
        if robot_radius != 0.0 {
            s = s
                .with_robot_radius(robot_radius as f32)
                .map_err(|e| value(format!("{e:#}")))?;
        }
        Ok(s)
    }
}

#[pymethods]
impl Scenario {
    /// A scenario on `map`: the agent starts at `start` and drives to each of `goals` in turn
    /// (positions in the map's frame). `robot_radius` (metres) makes the robot a disc; the
    /// map is then inflated for it. `sigma_m` is the trees' connection distance (default:
    /// the paper's 30 m, scaled to the map).
    #[new]
    #[pyo3(signature = (map, start, goals, name="custom".to_string(), sigma_m=None, robot_radius=0.0))]
    fn new(
        map: &Map,
        start: Xy,
        goals: Vec<Xy>,
        name: String,
        sigma_m: Option<f64>,
        robot_radius: f64,
    ) -> PyResult<Self> {
        let inner = Self::build(map, start, goals, name, sigma_m, robot_radius)?;
        inner.validate().map_err(|e| value(format!("{e:#}")))?;
        Ok(Self { inner })
    }

    /// A built-in scenario by name (`builtin_names()`: the paper's four maps and small ones).
    #[staticmethod]
    fn builtin(name: &str) -> PyResult<Self> {
        let inner = hs::builtin_by_name(name).map_err(|e| value(format!("{e:#}")))?;
        Ok(Self { inner })
    }

    /// This scenario for a robot of `radius` metres (the map inflated for its disc).
    fn with_robot_radius(&self, radius: f64) -> PyResult<Self> {
        crate::errors::finite("radius", radius)?;
        let inner = self
            .inner
            .clone()
            .with_robot_radius(radius as f32)
            .map_err(|e| value(format!("{e:#}")))?;
        Ok(Self { inner })
    }

    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    #[getter]
    fn map(&self) -> Map {
        Self::map_of(&self.inner)
    }

    #[getter]
    fn start(&self) -> Xy {
        self.frame().to_user(self.inner.start)
    }

    #[getter]
    fn goals(&self) -> Vec<Xy> {
        let f = self.frame();
        self.inner.goals.iter().map(|&g| f.to_user(g)).collect()
    }

    #[getter]
    fn robot_radius(&self) -> f64 {
        f64::from(self.inner.robot_radius)
    }

    /// The trees' connection distance the planners get (metres).
    #[getter]
    fn sigma_m(&self) -> f64 {
        f64::from(self.inner.sigma())
    }

    #[getter]
    fn source(&self) -> String {
        self.inner.source.clone()
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario({:?}, {} goals, {})",
            self.inner.name,
            self.inner.goals.len(),
            self.inner.source
        )
    }
}

/// The scenarios of a scenario file (TOML, as `host-sim` reads it; map paths relative to the
/// file), or of the built-in set with `path="builtin"`. `names` keeps those (in the file's
/// order).
#[pyfunction]
#[pyo3(signature = (path, names=None))]
fn load_scenarios(path: PathBuf, names: Option<Vec<String>>) -> PyResult<Vec<Scenario>> {
    let all = hs::load_scenarios(&path, names.as_deref()).map_err(lib)?;
    Ok(all.into_iter().map(|inner| Scenario { inner }).collect())
}

/// The names of the built-in scenarios.
#[pyfunction]
fn builtin_names() -> Vec<&'static str> {
    bi_am_rrt::builtin::every().map(|s| s.name).collect()
}
