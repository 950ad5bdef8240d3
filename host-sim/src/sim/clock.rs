//! Clocks of the simulator: the wall clock (real time, as in the paper's experiments) and the
//! virtual clock (time advanced by the planner's work, bit-for-bit repeatable).
//!
//! The virtual clock is the core's `FakeClock` advanced by a fixed number of nanoseconds per
//! unit of work the planner reports. [`VIRTUAL_NS_PER_UNIT`] was calibrated on the
//! development machine so that one virtual second is about one wall second there
//! (`host-sim calibrate` measures it again: wall time divided by work units over a set of runs).

use std::cell::Cell;
use std::time::Instant;

use bi_am_rrt::clock::{Clock, FakeClock};

/// Nanoseconds of virtual time per unit of planner work.
pub const VIRTUAL_NS_PER_UNIT: u64 = 12;

/// Real time since creation, in nanoseconds; counts the work reported too.
#[derive(Debug)]
pub struct WallClock {
    start: Instant,
    work: Cell<u64>,
}

impl Default for WallClock {
    fn default() -> Self {
        Self::new()
    }
}

impl WallClock {
    /// A clock starting now.
    pub fn new() -> Self {
        Self {
            start: Instant::now(),
            work: Cell::new(0),
        }
    }

    /// Work units reported so far.
    pub fn work(&self) -> u64 {
        self.work.get()
    }
}

impl Clock for WallClock {
    fn now(&self) -> u64 {
        self.start.elapsed().as_nanos() as u64
    }
    fn ticks_per_second(&self) -> u64 {
        1_000_000_000
    }
    fn charge(&self, units: u32) {
        self.work.set(self.work.get() + units as u64);
    }
}

/// A virtual clock with `ns_per_unit` nanoseconds per unit of work (and 1 ns per reading, so
/// time always moves).
pub fn virtual_clock(ns_per_unit: u64) -> FakeClock {
    FakeClock::nanos().with_work_cost(ns_per_unit).with_step(1)
}

/// Which clock a run uses.
#[derive(
    Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum ClockKind {
    /// Work-driven, repeatable (work units at a fixed rate).
    Virtual,
    /// Real time: the monotonic clock (`steady` is the old spelling of `bench`).
    #[value(alias = "steady")]
    Wall,
    /// The thread's CPU time: real time without the time the thread spends descheduled on
    /// a busy machine.
    Cpu,
}

/// The CPU time of the calling thread, in nanoseconds (what benchmarks time with: it does not
/// count time the thread spends descheduled on a busy machine). Counts its own readings.
#[derive(Debug)]
pub struct CpuClock {
    start: std::time::Duration,
    reads: Cell<u64>,
}

impl Default for CpuClock {
    fn default() -> Self {
        Self::new()
    }
}

impl CpuClock {
    /// A clock reading zero now (on this thread).
    pub fn new() -> Self {
        Self {
            start: cpu_time::ThreadTime::now().as_duration(),
            reads: Cell::new(0),
        }
    }

    /// Times the clock was read.
    pub fn reads(&self) -> u64 {
        self.reads.get()
    }
}

impl Clock for CpuClock {
    fn now(&self) -> u64 {
        self.reads.set(self.reads.get() + 1);
        let t = cpu_time::ThreadTime::now().as_duration();
        t.saturating_sub(self.start).as_nanos() as u64
    }
    fn ticks_per_second(&self) -> u64 {
        1_000_000_000
    }
}
