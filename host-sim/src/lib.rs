//! The desktop simulator of `bi-am-rrt`: it loads maps (PNG with the reference's threshold
//! rule, scenario files, the core's built-in scenarios), bakes the diffusion and geodesic
//! metric data, drives agents with the core's protocol, runs the paper's 20-planner matrix in
//! parallel, and writes CSV, JSON and pictures.
//!
//! Without the default feature `sim` only the loaders, the grid graph, the metrics and the
//! clocks are built (no `faer`, no `plotters`): what the fuzz targets need.
//!
//! The library in floors, lowest first (a module imports only from floors below it and from
//! none of the commands):
//!
//! - Scenarios and geometry: `maps` (PNG and ROS maps, scenario files, built-ins), `graph`
//!   (the grid graph), `optimum` (exact shortest paths), `grid_planners` (A*, Theta*),
//!   `clearance` (a driven trail's distance from the walls), `stats`, `clock`.
//! - Metric data: `diffusion`, `aggregate` and `bake` (metric tables), `metrics`.
//! - Results and drawing: `results` (results folders: rows, manifest, summary, merge), `draw`
//!   (pictures), `chart` (bar and box panels).
//! - The simulation: `sim` (a scenario prepared for runs, a configuration fitted to it, the
//!   agent's drive, the paper's pace, a run's rows, a planner's scene for a picture),
//!   `planners` (planner names and `@field=value` overrides). One circle is left:
//!   `aggregate` and `diffusion` use each other's types.
//! - Commands, each on the floors only: `run` (one run drawn), `moving` (people walking
//!   through a scenario, issue 27), `experiment` (the matrix), `report` (charts and the
//!   Markdown report), `bench`, `soak`, `stress`, `bounds` and `growth` (measurements). The
//!   binary's `main.rs` is the clap tree; `cmd/` holds one file per command (its options and
//!   what it runs) and `args.rs` the option groups they share.
//!
//! The core never knows this crate exists: everything here goes through the core's public API
//! (`Planner`, `Metric`, `Clock`, `DiffusionTable`, ...).

#[cfg(feature = "sim")]
pub mod aggregate;
#[cfg(feature = "sim")]
pub mod bake;
#[cfg(feature = "sim")]
pub mod bench;
#[cfg(feature = "sim")]
pub mod bounds;
#[cfg(feature = "sim")]
pub mod chart;
pub mod clearance;
pub mod clock;
#[cfg(feature = "sim")]
pub mod diffusion;
#[cfg(feature = "sim")]
pub mod draw;
#[cfg(feature = "sim")]
pub mod experiment;
pub mod graph;
pub mod grid_planners;
#[cfg(feature = "sim")]
pub mod growth;
pub mod maps;
pub mod metrics;
#[cfg(feature = "sim")]
pub mod moving;
pub mod optimum;
#[cfg(feature = "sim")]
pub mod planners;
#[cfg(feature = "sim")]
pub mod report;
pub mod results;
#[cfg(feature = "sim")]
pub mod run;
#[cfg(feature = "sim")]
pub mod sim;
#[cfg(feature = "sim")]
pub mod soak;
pub mod stats;
#[cfg(feature = "sim")]
pub mod stress;
