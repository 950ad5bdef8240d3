//! The desktop simulator of `bi-am-rrt`: it loads maps (PNG with the reference's threshold
//! rule, scenario files, the core's built-in scenarios), bakes the diffusion and geodesic
//! metric data, drives agents with the core's protocol, runs the paper's 20-planner matrix in
//! parallel, and writes CSV, JSON and pictures.
//!
//! The core never knows this crate exists: everything here goes through the core's public API
//! (`Planner`, `Metric`, `Clock`, `DiffusionTable`, ...).

pub mod bake;
pub mod clock;
pub mod diffusion;
pub mod draw;
pub mod experiment;
pub mod graph;
pub mod maps;
pub mod metrics;
pub mod run;
pub mod sim;
