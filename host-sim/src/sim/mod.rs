//! The simulation floor: a scenario prepared for runs (its metric data, its legs' optima, a
//! configuration fitted to it), a planner built on it and the agent's drive, the paper's pace
//! (`prepared`, re-exported here), the clocks a run is timed with (`clock`), and the planners
//! as commands name them with their `@field=value` overrides (`planners`).

pub mod clock;
#[cfg(feature = "sim")]
pub mod planners;
#[cfg(feature = "sim")]
mod prepared;
#[cfg(feature = "sim")]
pub use prepared::*;
