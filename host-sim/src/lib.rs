//! The desktop simulator of `bi-am-rrt`: it loads maps (PNG with the reference's threshold
//! rule, scenario files, the core's built-in scenarios), bakes the diffusion and geodesic
//! metric data, drives agents with the core's protocol, runs the paper's 20-planner matrix in
//! parallel, and writes CSV, JSON and pictures.
//!
//! Without the default feature `sim` only the loaders, the grid graph, the metrics and the
//! clocks are built (no `faer`, no `plotters`): what the fuzz targets need.
//!
//! The library in floors, lowest first, one folder each (a module imports only from floors
//! below it, and no study imports another):
//!
//! - `scenario`: maps and scenarios (PNG maps with the reference's threshold rule, ROS maps,
//!   scenario files, the core's built-ins).
//! - `metric`: the metric data and the exact measures of a map: `graph` (the grid graph),
//!   `diffusion` (the diffusion map and its tables; `diffusion::aggregate`, the pieces of a
//!   large map), `bake` (tables baked and cached), the geodesic metric and `AnyMetric`
//!   (`mod.rs`), `optimum` (exact shortest paths), `grid_planners` (A*, Theta*), `clearance`
//!   (a driven trail's distance from the walls).
//! - `results`: results folders (rows, manifest, summary, merge) and `stats`.
//! - `draw`: pictures, and `chart` (bar and box panels).
//! - `sim`: a scenario prepared for runs, a configuration fitted to it, a planner built on
//!   it, the agent's drive, the paper's pace, a run's rows (`prepared`, re-exported), the
//!   clocks (`clock`) and the planners as commands name them (`planners`).
//! - `study`: what each command runs (`run`, `moving`, `experiment`, `report`, `bench`,
//!   `soak`, `stress`, `bounds`, `growth`), each on the floors only. The binary's `main.rs`
//!   is the clap tree; `cmd/` holds one file per command (its options and which study it
//!   runs) and `args.rs` the option groups they share.
//!
//! The core never knows this crate exists: everything here goes through the core's public API
//! (`Planner`, `Metric`, `Clock`, `DiffusionTable`, ...).

#[cfg(feature = "sim")]
pub mod draw;
pub mod metric;
pub mod results;
pub mod scenario;
pub mod sim;
#[cfg(feature = "sim")]
pub mod study;
