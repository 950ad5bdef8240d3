//! The Python module `bi_am_rrt._core`: the planner of the `bi-am-rrt` crate (Bi-AM-RRT*,
//! Algorithms 1-6 of the paper, and the 19 other planners of its Table 1) and the simulator of
//! `host-sim` (maps, metric tables, runs, experiments, the exact optimum), for Python. The
//! package `bi_am_rrt` (Python, beside this crate) re-exports it and adds the plotting helper.
//!
//! Everything goes through the two crates' public APIs: a Python run is a `host-sim` run
//! (`tests/test_same_answers.py` compares them to the bit). Errors are Python exceptions
//! ([`errors`]); no input reaches a Rust panic (the core keeps no panic path at all, and
//! this layer checks dtypes, shapes and finiteness before it calls in).

use pyo3::prelude::*;

mod errors;
mod maps;
mod planner;
mod sim;

/// Positions cross the boundary as `(x, y)` tuples of floats in the map's own frame
/// ([`maps::Frame`]).
pub(crate) type Xy = (f64, f64);

#[pymodule]
fn _core(m: &Bound<'_, PyModule>) -> PyResult<()> {
    errors::register(m)?;
    maps::register(m)?;
    planner::register(m)?;
    sim::register(m)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}
