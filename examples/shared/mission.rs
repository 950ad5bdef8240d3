//! The mission shared by the firmware example and its host twin: the same planner, map, seed,
//! virtual clock and protocol, so both must print the same line, bit for bit.

use core::fmt;

use bi_am_rrt::agent::{Protocol, RunResult, run_to_goal};
use bi_am_rrt::builtin;
use bi_am_rrt::clock::{Clock, FakeClock};
use bi_am_rrt::config::PlannerName;
use bi_am_rrt::error::{InputError, SetupError};
use bi_am_rrt::{Config, Euclidean, Map, MetricKind, Planner, Storage};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Two trees of 2,048 nodes with 256 index buckets each: `Storage::BYTES`, 90,248 bytes on a
/// 32-bit target (all zero when empty, so a `static` of it lands in `.bss`). The firmware's one
/// planner storage.
pub type MissionStorage = Storage<2048, 256>;

/// Why the mission could not fly: the library's reason.
#[derive(Clone, Copy, Debug)]
pub enum Refused {
    /// `Planner::new` refused the configuration, map or start.
    Setup(SetupError),
    /// `set_goal` refused the goal.
    Goal(InputError),
}

impl fmt::Display for Refused {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Setup(e) => write!(f, "the planner refused its start: {e}"),
            Self::Goal(e) => write!(f, "the planner refused the goal: {e}"),
        }
    }
}

/// What the mission measured.
pub struct Mission {
    pub planner: PlannerName,
    pub scenario: &'static str,
    pub result: RunResult,
    pub work: u64,
}

impl Mission {
    /// Whether the agent arrived without collision.
    pub fn ok(&self) -> bool {
        self.result.reached && self.result.collisions == 0
    }
}

impl fmt::Display for Mission {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let r = &self.result;
        write!(
            f,
            "{} on {}: reached {}, search {} us (virtual), path {} m (f32 bits {:08x}), {} collisions, {} nodes at goal, {} plan calls, {} work units",
            self.planner,
            self.scenario,
            r.reached,
            r.search_ticks.map_or(0, |t| t / 1_000),
            Metres(r.travelled),
            r.travelled.to_bits(),
            r.collisions,
            r.nodes_at_goal.unwrap_or(0),
            r.calls,
            self.work
        )
    }
}

/// A length printed to the millimetre (`47.353`) with integer formatting only: `core::fmt`'s
/// float code is about 11 KB of the firmware's flash. The twin line adds the `f32`'s bits.
pub struct Metres(pub f32);

impl fmt::Display for Metres {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if !(self.0.is_finite() && self.0 >= 0.0 && self.0 < 1.0e12) {
            return f.write_str("(not a length)");
        }
        let mm = (self.0 * 1000.0 + 0.5) as u64;
        write!(f, "{}.{:03}", mm / 1000, mm % 1000)
    }
}

/// Bi-AM-RRT*(E) drives the agent across the built-in 40 m field (map in flash) under the
/// benchmark protocol, in calls of 5 ms on a virtual clock of 12 ns per work unit (until issue
/// 42, calls of 20 ms: 130 M work units where 5 ms take 48 M, and CI's soft-float QEMU runs
/// took 2.5 minutes on the RISC-V build, 5 on the Cortex-M0+ one). Not inlined (nor is the
/// office mission): its planner's stack frame is gone before the next mission starts
/// (inlined, the compiler may keep both missions' frames live at once: 1.8 KB more stack
/// measured on the office sequence).
#[inline(never)]
pub fn fly(storage: &mut MissionStorage) -> Result<Mission, Refused> {
    let scenario = &builtin::OPEN;
    let map: Map<'static, 4> = Map::new(scenario.grid);
    let mut cfg = Config::bi_am_rrt();
    cfg.budget.t_exp = core::time::Duration::from_millis(5);
    let rng = XorShiftRng::seed_from_u64(1);
    let mut planner =
        Planner::new(storage, map, Euclidean, rng, cfg, scenario.start).map_err(Refused::Setup)?;
    let clock = FakeClock::nanos().with_work_cost(12).with_step(1);
    let result = run_to_goal(
        &mut planner,
        // As a `dyn Clock`, like the office mission's real clock: one copy of the planner's
        // code serves both (examples/firmware.rs).
        &clock as &dyn Clock,
        scenario.goals[0],
        &Protocol::default(),
        |_, _, _| {},
    )
    .map_err(Refused::Goal)?;
    Ok(Mission {
        planner: cfg.name(MetricKind::Euclidean),
        scenario: scenario.name,
        result,
        work: clock.work(),
    })
}
