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
    /// a busy machine. Every reading is a system call (about 0.4-0.8 us here).
    Cpu,
    /// The thread's CPU time read at most once a millisecond, the monotonic clock's advance
    /// in between ([`CpuMonoClock`]): CPU time as a measurement, at the cost of a vDSO
    /// reading (about 30 ns) for the planner, as a robot's clock or OMPL's termination
    /// condition. Never below the thread's CPU time.
    #[value(name = "cpu-mono")]
    #[serde(rename = "cpu-mono")]
    CpuMono,
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

/// Thread CPU time, read cheaply: the thread's CPU time at most once every [`Self::RESYNC_NS`]
/// of real time, and in between the monotonic clock's advance since that reading.
///
/// Why: a thread CPU time reading is a system call (0.4-0.8 us on the development machine,
/// more on cold caches), and a planner reads its clock at every deadline check, where a robot
/// reads a cycle counter or the monotonic clock (a vDSO read of about 30 ns) and OMPL's timed
/// termination condition reads the monotonic clock. Timed with [`CpuClock`], a query of 20 us
/// paid 5-10 us for its own readings. This clock keeps CPU time as the measurement (a span
/// from one of its readings to another counts the CPU time between them, the time the thread
/// was descheduled only within one resync window) and gives the planner a reading as cheap as
/// theirs.
///
/// A reading is never below the thread's CPU time (the monotonic clock advances at least as
/// fast), and never below an earlier reading (after a resync that finds the thread was
/// descheduled, the clock holds until CPU time catches up).
#[derive(Debug)]
pub struct CpuMonoClock {
    /// CPU time at the clock's creation.
    start: std::time::Duration,
    /// The last resync: CPU time since `start` (ns) and the monotonic instant it was read at.
    sync: Cell<(u64, Instant)>,
    /// The last reading returned.
    last: Cell<u64>,
    /// Readings, and thread CPU time readings (resyncs) among them.
    reads: Cell<u64>,
    resyncs: Cell<u64>,
}

impl Default for CpuMonoClock {
    fn default() -> Self {
        Self::new()
    }
}

impl CpuMonoClock {
    /// Real time between two thread CPU time readings, at most (1 ms: under 0.1 % of the
    /// time in system calls).
    pub const RESYNC_NS: u64 = 1_000_000;

    /// A clock reading zero now (on this thread).
    pub fn new() -> Self {
        // The instant first: the CPU time read after it is then not below the CPU time at
        // that instant, and a reading never falls below the thread's CPU time.
        let at = Instant::now();
        let start = cpu_time::ThreadTime::now().as_duration();
        Self {
            start,
            sync: Cell::new((0, at)),
            last: Cell::new(0),
            reads: Cell::new(0),
            resyncs: Cell::new(0),
        }
    }

    /// Reads the thread's CPU time now (a system call) and reckons from it; the next readings
    /// add the monotonic clock's advance to it. Returns the reading, as [`Clock::now`].
    pub fn resync(&self) -> u64 {
        self.resyncs.set(self.resyncs.get() + 1);
        // The instant first (see `new`).
        let at = Instant::now();
        let cpu = cpu_time::ThreadTime::now()
            .as_duration()
            .saturating_sub(self.start)
            .as_nanos() as u64;
        self.sync.set((cpu, at));
        self.settle(cpu)
    }

    /// Times the clock was read ([`Clock::now`] and [`Self::resync`]).
    pub fn reads(&self) -> u64 {
        self.reads.get()
    }

    /// Thread CPU time readings so far (system calls).
    pub fn resyncs(&self) -> u64 {
        self.resyncs.get()
    }

    /// Counts a reading of `t` and returns it, held at the last reading at least.
    fn settle(&self, t: u64) -> u64 {
        self.reads.set(self.reads.get() + 1);
        let t = t.max(self.last.get());
        self.last.set(t);
        t
    }
}

impl Clock for CpuMonoClock {
    fn now(&self) -> u64 {
        let (cpu, at) = self.sync.get();
        let since = at.elapsed().as_nanos() as u64;
        if since >= Self::RESYNC_NS {
            return self.resync();
        }
        self.settle(cpu + since)
    }
    fn ticks_per_second(&self) -> u64 {
        1_000_000_000
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The clock never goes back, never reads less than the thread's CPU time, nor more
    /// than the real time since it was made (give or take a system call's time); it reads
    /// the CPU time again once a millisecond of real time has passed (a busy loop of 5 ms
    /// with reads every few us).
    #[test]
    fn cpu_mono_never_goes_back_and_stays_between_cpu_and_real_time() {
        let made = Instant::now();
        let clock = CpuMonoClock::new();
        let (mut last, mut reads, mut asked) = (0, 0, 0);
        let mut x = 0u64;
        let mut i = 0u64;
        while made.elapsed() < std::time::Duration::from_millis(5) {
            i += 1;
            x = x.wrapping_mul(6364136223846793005).wrapping_add(i);
            if i.is_multiple_of(500) {
                let cpu = (cpu_time::ThreadTime::now().as_duration() - clock.start).as_nanos();
                let t = if i.is_multiple_of(100_000) {
                    asked += 1;
                    clock.resync()
                } else {
                    clock.now()
                };
                reads += 1;
                let real = made.elapsed().as_nanos();
                assert!(t >= last, "went back: {t} after {last}");
                assert!(t as u128 >= cpu, "{t} below the CPU time {cpu}");
                assert!(
                    t as u128 <= real + 100_000,
                    "{t} above the real time {real}"
                );
                last = t;
            }
        }
        std::hint::black_box(x);
        assert!(clock.resyncs() > asked, "no resync of its own in 5 ms");
        assert_eq!(clock.reads(), reads);
    }
}
