//! The exceptions of the module: bad values are `ValueError`s (a wrong dtype, shape, a NaN, a
//! position outside the map), with two of their own for positions the planner refuses; what a
//! file or a run reports is a `BiAmRrtError`. Each message names the problem as the Rust side
//! words it.

use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;

create_exception!(
    bi_am_rrt,
    BiAmRrtError,
    PyException,
    "A file, a table or a run the library could not use (the message says why)."
);
create_exception!(
    bi_am_rrt,
    PositionError,
    PyValueError,
    "A position the planner refuses: not finite, outside the map, in a wall, or cut off."
);
create_exception!(
    bi_am_rrt,
    InWallError,
    PositionError,
    "A goal or an agent inside an obstacle, or closer to a wall than the robot's radius."
);

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("BiAmRrtError", py.get_type::<BiAmRrtError>())?;
    m.add("PositionError", py.get_type::<PositionError>())?;
    m.add("InWallError", py.get_type::<InWallError>())?;
    Ok(())
}

/// A library error as a `BiAmRrtError` with its whole chain of causes.
pub(crate) fn lib(e: anyhow::Error) -> PyErr {
    BiAmRrtError::new_err(format!("{e:#}"))
}

/// A `ValueError`.
pub(crate) fn value(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// The core's refusal of a position (`what`: "goal", "agent").
pub(crate) fn position(what: &str, at: crate::Xy, e: bi_am_rrt::error::InputError) -> PyErr {
    use bi_am_rrt::error::InputError as E;
    let msg = format!("{what} ({}, {}): {e}", at.0, at.1);
    match e {
        E::InObstacle | E::NoRoom => InWallError::new_err(msg),
        _ => PositionError::new_err(msg),
    }
}

/// A finite float, or a `ValueError` naming `what`.
pub(crate) fn finite(what: &str, v: f64) -> PyResult<f64> {
    if v.is_finite() {
        Ok(v)
    } else {
        Err(value(format!("{what} is {v}: a finite number is needed")))
    }
}

/// A finite point, or a `ValueError` naming `what`.
pub(crate) fn point(what: &str, p: crate::Xy) -> PyResult<crate::Xy> {
    if p.0.is_finite() && p.1.is_finite() {
        Ok(p)
    } else {
        Err(value(format!(
            "{what} ({}, {}): coordinates must be finite numbers",
            p.0, p.1
        )))
    }
}
