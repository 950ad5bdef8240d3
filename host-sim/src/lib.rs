//! The desktop simulator of `bi-am-rrt`: it loads maps (PNG with the reference's threshold
//! rule, scenario files, the core's built-in scenarios), bakes the diffusion and geodesic
//! metric data, drives agents with the core's protocol, runs the paper's 20-planner matrix in
//! parallel, and writes CSV, JSON and pictures.
//!
//! Without the default feature `sim` only the loaders, the grid graph, the metrics and the
//! clocks are built (no `faer`, no `plotters`): what the fuzz targets need.
//!
//! Modules, one concern each: `maps` (PNG and ROS maps, scenario files, built-ins), `graph`
//! (grid graph), `diffusion` and `bake` (metric tables), `metrics`, `optimum` (exact shortest
//! paths), `clearance` (a driven trail's distance from the walls), `clock`, `sim` (a scenario prepared for runs, one run under the protocol), `run`
//! (one run drawn), `draw` (pictures), `experiment` (the matrix), `results` (results folders:
//! rows, manifest, summary, merge), `report` (charts and the Markdown report), `stats`,
//! `bench`, `soak`, `stress`, `bounds` and `growth` (measurements), `moving` (people walking
//! through a scenario, issue 27). `main.rs` is the
//! command-line layer.
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
