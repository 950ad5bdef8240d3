//! What each command runs, on the floors below (scenario, metric, sim, results, draw): one
//! module per study, none importing another. The binary's `cmd/` folder holds each command's
//! options and calls one of these.
//!
//! - `run`: one run drawn (pictures, a GIF, result.json);
//! - `moving`: people walking through a scenario and a door (issue 27);
//! - `experiment`: the paper's matrix of planners x scenarios x seeds, in parallel;
//! - `report`: charts and the Markdown report of a results folder, and `compare`;
//! - `bench`: every leg against its exact optimum and the baselines, OMPL-style;
//! - `soak`, `stress`, `bounds` (frozen clock, calibration) and `growth`: measurements.

pub mod bench;
pub mod bounds;
pub mod experiment;
pub mod growth;
pub mod moving;
pub mod report;
pub mod run;
pub mod soak;
pub mod stress;
