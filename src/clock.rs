//! Time as the caller supplies it: the [`Clock`] trait, [`Deadline`]s for the planner's time
//! budgets (the paper's `t_exp`, `t_root`, `t_goal`), and [`FakeClock`] for deterministic runs.
//!
//! The planner never reads a system timer. Every budget is measured on the clock passed to the
//! call, so a firmware passes its hardware timer, the simulator a wall or a virtual clock, and a
//! test a fake clock. Besides reading time, the planner *reports the work it does* through
//! [`Clock::charge`]; a real clock ignores that, while a virtual clock advances by it, which makes
//! a run bit-for-bit repeatable on any machine.

use core::cell::Cell;
use core::time::Duration;

/// A monotonic time source.
///
/// Contract, which the planner relies on:
/// - [`now`](Clock::now) never decreases, never fails and is cheap enough to read once per
///   unit of planner work (every expansion and every few rewiring steps);
/// - [`ticks_per_second`](Clock::ticks_per_second) is constant and non-zero;
/// - ticks may start anywhere; only differences are used;
/// - [`charge`](Clock::charge) is called with the amount of work just done (one unit is one
///   grid cell tested, one node visited, one metric evaluated); a clock that measures real time
///   ignores it (the default).
///
/// A clock that never advances is allowed: every planner call also stops after a fixed number
/// of work steps, so a frozen clock gives bounded calls, not a hang.
pub trait Clock {
    /// The current time in ticks.
    fn now(&self) -> u64;

    /// How many ticks make a second.
    fn ticks_per_second(&self) -> u64;

    /// Reports `units` of work done since the last report. Ignored by real-time clocks.
    #[inline]
    fn charge(&self, units: u32) {
        let _ = units;
    }

    /// A duration in this clock's ticks (rounded down, saturating).
    fn ticks(&self, d: Duration) -> u64 {
        // Saturating: `Duration::MAX` on a fast clock overflows even u128.
        let t = d
            .as_nanos()
            .checked_mul(self.ticks_per_second() as u128)
            .map_or(u128::MAX, |t| t / 1_000_000_000);
        u64::try_from(t).unwrap_or(u64::MAX)
    }

    /// A tick count of this clock as a duration.
    fn duration(&self, ticks: u64) -> Duration {
        let rate = core::num::NonZeroU64::new(self.ticks_per_second())
            .unwrap_or(core::num::NonZeroU64::MIN);
        let (secs, rest) = (ticks / rate, ticks % rate);
        // rest < rate, so rest * 10^9 / rate < 10^9.
        let nanos =
            (rest as u128).saturating_mul(1_000_000_000) / core::num::NonZeroU128::from(rate);
        let nanos = u64::try_from(nanos).unwrap_or(999_999_999);
        Duration::from_secs(secs).saturating_add(Duration::from_nanos(nanos))
    }
}

impl<C: Clock + ?Sized> Clock for &C {
    fn now(&self) -> u64 {
        (**self).now()
    }
    fn ticks_per_second(&self) -> u64 {
        (**self).ticks_per_second()
    }
    fn charge(&self, units: u32) {
        (**self).charge(units)
    }
}

/// A point in time after which a budget is spent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Deadline {
    start: u64,
    end: u64,
}

impl Deadline {
    /// A deadline that never passes (work that must finish, such as reading the path).
    pub const NEVER: Deadline = Deadline {
        start: 0,
        end: u64::MAX,
    };

    /// The deadline `budget` from now on `clock`.
    pub fn after<C: Clock + ?Sized>(clock: &C, budget: Duration) -> Self {
        let start = clock.now();
        Self {
            start,
            end: start.saturating_add(clock.ticks(budget)),
        }
    }

    /// The deadline `ticks` after `start`.
    pub const fn from_ticks(start: u64, ticks: u64) -> Self {
        Self {
            start,
            end: start.saturating_add(ticks),
        }
    }

    /// Whether the budget is spent (the clock reads at or past the end). A zero budget is
    /// expired at once.
    #[inline]
    pub fn expired<C: Clock + ?Sized>(&self, clock: &C) -> bool {
        clock.now() >= self.end
    }

    /// Ticks left, zero once expired.
    pub fn remaining<C: Clock + ?Sized>(&self, clock: &C) -> u64 {
        self.end.saturating_sub(clock.now())
    }

    /// Ticks since the deadline was set.
    pub fn elapsed<C: Clock + ?Sized>(&self, clock: &C) -> u64 {
        clock.now().saturating_sub(self.start)
    }

    /// The tick at which the budget started (the reading it was set on).
    pub const fn start(&self) -> u64 {
        self.start
    }

    /// The tick at which the budget ends.
    pub const fn end(&self) -> u64 {
        self.end
    }

    /// The earlier of two deadlines (a sub-budget never outlives its caller's budget).
    pub fn min(self, other: Deadline) -> Deadline {
        if other.end < self.end { other } else { self }
    }
}

/// Counts the work the planner does and reports it to the clock in batches, so a virtual clock
/// advances with work while a real clock is read as usual. A meter may also carry a *work
/// cap*: once that many units have been charged, every deadline reads as expired, whatever the
/// clock says. This is what bounds a planner call on a clock that never advances.
///
/// A meter may also read the clock *sparingly* ([`Meter::reading_every`]): deadline checks
/// then reuse the last reading until that many work units have been charged since it. A real
/// clock costs from a few cycles (a cycle counter) to a system call (a CPU-time clock, about
/// 0.3 us on Linux), and the planner checks its deadlines 50 to 80 times per expansion; reading
/// every few hundred units bounds the overrun by that much work instead.
///
/// A sparing meter may also *pace* its readings by what they cost ([`Meter::paced`]): it
/// measures one reading (a reading right after the caller's reading that set the call's
/// deadline) and the clock's rate per unit of work (between consecutive readings), and lets
/// the interval move between [`MIN_PACED`] and `most` units (from `every`, until a rate is
/// measured) so that a reading costs about 1/[`PACE`] of the work between two, but never past
/// the units that took 1/[`GAP_PER_SECOND`] of a second at the slowest rate it has measured
/// (units differ in cost: on a Cortex-M4F a unit of one phase of a step takes five times one
/// of another, issue 25). A CPU-time clock (a system call) is then read every few thousand
/// units, a cycle counter every few dozen; a virtual clock, whose readings cost nothing, still
/// every `every`.
#[derive(Debug)]
pub struct Meter<'c, C: Clock + ?Sized> {
    clock: &'c C,
    pending: Cell<u32>,
    used: Cell<u64>,
    cap: u64,
    /// Work units between two clock readings of the deadline checks (0: every check); with
    /// pacing, the fewest.
    every: u32,
    /// With pacing (above `every`), the most work units between two readings.
    most: u32,
    /// The current interval between readings, in work units.
    pace: Cell<u32>,
    /// What one reading costs, in ticks (0 while unmeasured).
    cost: Cell<u64>,
    /// The last reading and the work done when it was taken.
    last: Cell<Option<(u64, u64)>>,
    /// The slowest rate measured between two readings, in ticks per [`RATE_UNITS`] units.
    slowest: Cell<u64>,
    /// The reading that opens the current rate window (at least [`RATE_UNITS`] units long):
    /// how every meter, paced or not, measures its slowest rate.
    window: Cell<Option<(u64, u64)>>,
    /// The slowest rate over those windows, in ticks per [`RATE_UNITS`] units: what
    /// [`Meter::affords`] predicts with (the pacing's rate, over windows as short as
    /// [`MIN_PACED`] units, also counts the cost of readings and of phases that charge little).
    steady: Cell<u64>,
    /// A rate measured before this meter (the caller's last call), in the same unit: used
    /// until this meter's own windows measure a slower one.
    prior: u64,
    /// The slowest cost refresh timed by this meter ([`Meter::timed_refresh`]), in ticks per
    /// [`RATE_UNITS`] nodes: a node's refresh is a square root and a few additions, far more
    /// than an average unit on a core without an FPU (issue 25: the Cortex-M0+ build).
    refresh: Cell<u64>,
    /// The same, timed before this meter.
    refresh_prior: u64,
}

/// The fewest units between two readings of a paced meter whose readings cost something
/// measurable: a cycle counter, whose reading costs a few instructions, is read about this
/// often (issue 25: read every 256 units, the Cortex-M4F's slowest phases left 1-2 ms unread).
pub const MIN_PACED: u64 = 16;

/// The work over which [`Meter`] keeps its slowest rate (ticks per this many units).
const RATE_UNITS: u64 = 1024;

/// A paced meter ([`Meter::paced`]) spaces its readings so that one costs about `1 / PACE` of
/// the work between two (under 1 %).
pub const PACE: u64 = 128;

/// A paced meter never lets more work pass between two readings than took `1 / GAP_PER_SECOND`
/// of a second (0.25 ms) at the rate it measured: pacing by a reading's cost alone let 8,192
/// units pass unread on a Cortex-M4F, where they can take milliseconds, and the tuned set's
/// calls ran up to 19 ms over `t_exp` (issue 25). Units vary in cost, so the bound is a
/// quarter of the 1 ms a call may overrun.
pub const GAP_PER_SECOND: u64 = 4_000;

impl<'c, C: Clock + ?Sized> Meter<'c, C> {
    /// A meter over `clock` without a work cap.
    pub fn new(clock: &'c C) -> Self {
        Self::with_cap(clock, u64::MAX)
    }

    /// A meter over `clock` whose deadlines all expire once `cap` units have been charged.
    pub fn with_cap(clock: &'c C, cap: u64) -> Self {
        Self {
            clock,
            pending: Cell::new(0),
            used: Cell::new(0),
            cap,
            every: 0,
            most: 0,
            pace: Cell::new(0),
            cost: Cell::new(0),
            last: Cell::new(None),
            slowest: Cell::new(0),
            window: Cell::new(None),
            steady: Cell::new(0),
            prior: 0,
            refresh: Cell::new(0),
            refresh_prior: 0,
        }
    }

    /// With deadline checks that read the clock only once `units` work units have been charged
    /// since the last reading (0: at every check).
    pub fn reading_every(mut self, units: u32) -> Self {
        self.every = units;
        self.pace.set(units);
        self
    }

    /// With readings paced by their cost (type docs): at least [`Meter::reading_every`]'s
    /// units between two readings, at most `most`. `origin` is the reading the caller took
    /// just before (for the call's deadline): when `most` is above the fewest units, the meter
    /// reads the clock once now, and the difference is what a reading costs. (That reading
    /// serves the first deadline checks, so a call reads its clock no more often than a
    /// meter that reads every `every` units.)
    pub fn paced(mut self, most: u32, origin: u64) -> Self {
        self.most = most;
        if most > self.every && self.used.get() == 0 {
            let t = self.now();
            self.cost.set(t.saturating_sub(origin));
            self.last.set(Some((t, 0)));
        }
        self
    }

    /// The clock for a deadline check: the last reading while less than the interval (`every`,
    /// or the paced one) of work has been charged since it, else a fresh one.
    fn check_now(&self) -> u64 {
        let used = self.used.get();
        let last = self.last.get();
        if let Some((t, at)) = last
            && used.saturating_sub(at) < u64::from(self.pace.get())
        {
            return t;
        }
        self.flush();
        let t = self.clock.now();
        if self.most > self.every {
            self.repace(t, used, last);
        }
        self.last.set(Some((t, used)));
        self.measure(t, used);
        t
    }

    /// Keeps the slowest rate over windows of at least [`RATE_UNITS`] units (shorter ones
    /// would count a reading's own cost as work).
    fn measure(&self, t: u64, used: u64) {
        match self.window.get() {
            Some((t0, at)) if used.saturating_sub(at) >= RATE_UNITS => {
                let (dt, du) = (t.saturating_sub(t0), used.saturating_sub(at));
                let rate = dt.saturating_mul(RATE_UNITS).checked_div(du).unwrap_or(0);
                self.steady.set(self.steady.get().max(rate));
                self.window.set(Some((t, used)));
            }
            Some(_) => {}
            None => self.window.set(Some((t, used))),
        }
    }

    /// With the rates of an earlier meter on the same clock ([`Meter::rates`]) as what
    /// [`Meter::affords`] predicts with until this meter measures slower ones: a call's first
    /// milliseconds have no window of their own yet.
    pub fn expecting(mut self, (rate, refresh): (u64, u64)) -> Self {
        self.prior = rate;
        self.refresh_prior = refresh;
        self
    }

    /// What this meter measured, for the next one ([`Meter::expecting`]): the slowest rate
    /// over windows of `RATE_UNITS` units (ticks per `RATE_UNITS` units) and the slowest
    /// timed refresh (ticks per `RATE_UNITS` nodes); 0 for what it did not measure.
    pub fn rates(&self) -> (u64, u64) {
        (self.steady.get(), self.refresh.get())
    }

    /// Times a refresh of `nodes` nodes' costs that started at the reading `since` (taken
    /// with [`Meter::now`]). Refreshes of fewer than 64 nodes are not timed (too short to
    /// tell a rate).
    pub fn timed_refresh(&self, nodes: usize, since: u64) {
        let nodes = nodes as u64;
        if nodes < 64 {
            return;
        }
        let dt = self.now().saturating_sub(since);
        let rate = dt
            .saturating_mul(RATE_UNITS)
            .checked_div(nodes)
            .unwrap_or(0);
        self.refresh.set(self.refresh.get().max(rate));
    }

    /// Ticks per [`RATE_UNITS`] nodes refreshed: the slower of the refreshes timed and the
    /// slowest work rate (a node charged one unit), from this meter or the one before it.
    fn per_node(&self) -> u64 {
        let timed = self.refresh.get().max(self.refresh_prior);
        let work = self.steady.get().max(self.prior);
        timed.max(work)
    }

    /// `deadline` brought forward by the time refreshing `nodes` nodes takes (see
    /// [`Meter::affords`]), but only while that is at most half the time left (else
    /// `deadline` as is: a short budget is not given up to a reserve).
    pub fn reserving(&self, nodes: u64, deadline: Deadline) -> Deadline {
        let need = nodes.saturating_mul(self.per_node()) / RATE_UNITS;
        let left = deadline.end().saturating_sub(self.check_now());
        if need.saturating_mul(2) > left {
            return deadline;
        }
        Deadline::from_ticks(
            deadline.start(),
            deadline
                .end()
                .saturating_sub(deadline.start())
                .saturating_sub(need),
        )
    }

    /// Whether refreshing `nodes` nodes' costs, started now, would end before `deadline`, at
    /// the slowest rate measured ([`Meter::timed_refresh`], or a unit of work per node when
    /// slower); false once the deadline has passed or the work cap is reached. Work that
    /// cannot stop half-way checks this first: re-rooting a tree or moving a subtree
    /// refreshes the cost of every node it carries, milliseconds for a whole tree on a
    /// Cortex-M4F (issue 25). Before any rate is measured (a clock that has not moved, or
    /// too little work), only the deadline counts.
    pub fn affords(&self, nodes: u64, deadline: &Deadline) -> bool {
        if self.expired(deadline) {
            return false;
        }
        let need = nodes.saturating_mul(self.per_node()) / RATE_UNITS;
        self.check_now().saturating_add(need) < deadline.end()
    }

    /// Pacing (type docs): sets the interval from the clock's rate between the last two
    /// readings and the cost of a reading ([`Meter::paced`]).
    fn repace(&self, t: u64, used: u64, last: Option<(u64, u64)>) {
        // A reading that costs nothing measurable keeps the fewest units (the pace as set).
        let (Some((t0, at)), cost @ 1..) = (last, self.cost.get()) else {
            return;
        };
        let (dt, du) = (t.saturating_sub(t0), used.saturating_sub(at));
        // Units whose work takes PACE readings' time: PACE * cost / (dt / du); a clock that
        // did not move tells nothing until it does (the most units).
        let units = PACE
            .saturating_mul(cost)
            .saturating_mul(du)
            .checked_div(dt)
            .unwrap_or(u64::MAX);
        // ... and never more than a gap of 1 / GAP_PER_SECOND s at the slowest rate seen.
        let rate = dt.saturating_mul(RATE_UNITS).checked_div(du).unwrap_or(0);
        let slowest = self.slowest.get().max(rate);
        self.slowest.set(slowest);
        let gap = (self.clock.ticks_per_second() / GAP_PER_SECOND).max(1);
        let by_time = gap
            .saturating_mul(RATE_UNITS)
            .checked_div(slowest)
            .unwrap_or(u64::MAX);
        let paced = units.min(by_time).max(MIN_PACED).min(u64::from(self.most));
        self.pace.set(u32::try_from(paced).unwrap_or(self.most));
    }

    /// Records `units` of work.
    #[inline]
    pub fn charge(&self, units: u32) {
        self.used.set(self.used.get().saturating_add(units as u64));
        let p = self.pending.get().saturating_add(units);
        if p >= 4096 {
            self.clock.charge(p);
            self.pending.set(0);
        } else {
            self.pending.set(p);
        }
    }

    /// Work units charged since the meter was made.
    pub fn work(&self) -> u64 {
        self.used.get()
    }

    /// Whether the work cap is reached.
    pub fn exhausted(&self) -> bool {
        self.used.get() >= self.cap
    }

    /// Reports pending work, then reads the clock.
    pub fn now(&self) -> u64 {
        self.flush();
        self.clock.now()
    }

    /// Whether the work cap is reached or `deadline` has passed (on the last reading, see
    /// [`Meter::reading_every`]; pending work is reported before a fresh reading).
    pub fn expired(&self, deadline: &Deadline) -> bool {
        self.exhausted() || self.check_now() >= deadline.end()
    }

    /// A deadline `budget` from now, never later than `outer`.
    pub fn deadline(&self, budget: Duration, outer: Deadline) -> Deadline {
        Deadline::from_ticks(self.check_now(), self.clock.ticks(budget)).min(outer)
    }

    /// Reports pending work to the clock.
    pub fn flush(&self) {
        let p = self.pending.replace(0);
        if p > 0 {
            self.clock.charge(p);
        }
    }
}

impl<C: Clock + ?Sized> Drop for Meter<'_, C> {
    fn drop(&mut self) {
        self.flush();
    }
}

/// A [`Clock`] on `embassy_time::Instant` (feature `embassy-time`): for firmware built on
/// Embassy, whose time driver (a hardware timer the application configures) it reads.
#[cfg(feature = "embassy-time")]
#[derive(Clone, Copy, Debug, Default)]
pub struct EmbassyClock;

#[cfg(feature = "embassy-time")]
impl Clock for EmbassyClock {
    fn now(&self) -> u64 {
        embassy_time::Instant::now().as_ticks()
    }

    fn ticks_per_second(&self) -> u64 {
        embassy_time::TICK_HZ
    }
}

/// A clock for tests and virtual-time simulation. It reads a counter that advances
/// - by hand ([`FakeClock::advance`], [`FakeClock::set`]),
/// - by `step` ticks at every reading ([`FakeClock::with_step`]), so a loop bounded by a
///   deadline always ends, and/or
/// - by `per_unit` ticks per unit of work the planner reports ([`FakeClock::with_work_cost`]):
///   the virtual clock, whose time is a deterministic function of the work done.
#[derive(Debug, Default)]
pub struct FakeClock {
    now: Cell<u64>,
    rate: u64,
    step: u64,
    per_unit: u64,
    work: Cell<u64>,
}

impl FakeClock {
    /// A clock at tick 0 running at `ticks_per_second` (at least 1), advanced only by hand.
    pub const fn new(ticks_per_second: u64) -> Self {
        Self {
            now: Cell::new(0),
            rate: if ticks_per_second == 0 {
                1
            } else {
                ticks_per_second
            },
            step: 0,
            per_unit: 0,
            work: Cell::new(0),
        }
    }

    /// A nanosecond clock: 10^9 ticks per second.
    pub const fn nanos() -> Self {
        Self::new(1_000_000_000)
    }

    /// Advances by `step` ticks after every reading.
    pub const fn with_step(mut self, step: u64) -> Self {
        self.step = step;
        self
    }

    /// Advances by `per_unit` ticks per unit of work charged.
    pub const fn with_work_cost(mut self, per_unit: u64) -> Self {
        self.per_unit = per_unit;
        self
    }

    /// Moves the clock forward by `ticks`.
    pub fn advance(&self, ticks: u64) {
        self.now.set(self.now.get().saturating_add(ticks));
    }

    /// Moves the clock forward by a duration.
    pub fn advance_by(&self, d: Duration) {
        self.advance(self.ticks(d));
    }

    /// Sets the clock to `ticks` if that is not in the past (a clock never goes back).
    pub fn set(&self, ticks: u64) {
        self.now.set(self.now.get().max(ticks));
    }

    /// Total work units charged so far.
    pub fn work(&self) -> u64 {
        self.work.get()
    }

    /// The current reading without the automatic step.
    pub fn peek(&self) -> u64 {
        self.now.get()
    }
}

impl Clock for FakeClock {
    fn now(&self) -> u64 {
        let t = self.now.get();
        self.now.set(t.saturating_add(self.step));
        t
    }

    fn ticks_per_second(&self) -> u64 {
        self.rate
    }

    fn charge(&self, units: u32) {
        self.work.set(self.work.get().saturating_add(units as u64));
        self.advance(self.per_unit.saturating_mul(units as u64));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A clock that counts its readings and never advances.
    struct Counting(Cell<u32>);

    impl Clock for Counting {
        fn now(&self) -> u64 {
            self.0.set(self.0.get() + 1);
            0
        }
        fn ticks_per_second(&self) -> u64 {
            1_000
        }
    }

    #[test]
    fn a_sparing_meter_reads_the_clock_once_per_batch_of_work() {
        let c = Counting(Cell::new(0));
        let d = Deadline::from_ticks(0, 5);
        let every = Meter::new(&c);
        for _ in 0..100 {
            every.charge(10);
            assert!(!every.expired(&d));
        }
        assert_eq!(c.0.get(), 100, "by default every check reads");
        c.0.set(0);
        let sparing = Meter::with_cap(&c, 5_000).reading_every(100);
        let mut checks = 0;
        while !sparing.expired(&d) {
            sparing.charge(10);
            checks += 1;
        }
        assert_eq!(checks, 500, "the work cap still ends a frozen clock's loop");
        assert_eq!(c.0.get(), 50, "one reading per 100 units");
    }

    /// The work counts at which a paced meter (at least 256, at most 8,192 units apart) reads
    /// a clock whose reading costs `step` ticks and whose work costs 10 ticks a unit, over
    /// 100,000 deadline checks of one unit each, after `work_first` units charged before the
    /// first check.
    fn paced_readings(step: u64, work_first: u32) -> heapless::Vec<u64, 8192> {
        paced_readings_at(step, 10, work_first)
    }

    /// [`paced_readings`] with work costing `unit_ns` a unit.
    fn paced_readings_at(step: u64, unit_ns: u64, work_first: u32) -> heapless::Vec<u64, 8192> {
        let c = FakeClock::nanos().with_step(step).with_work_cost(unit_ns);
        let origin = c.now();
        let m = Meter::new(&c).reading_every(256).paced(8192, origin);
        let mut at = heapless::Vec::<u64, 8192>::new();
        at.push(0).unwrap(); // the meter's own reading
        m.charge(work_first);
        let d = Deadline::from_ticks(origin, u64::MAX / 2);
        for _ in 0..100_000 {
            let before = m.last.get();
            assert!(!m.expired(&d));
            if m.last.get() != before {
                at.push(m.work()).unwrap();
            }
            m.charge(1);
        }
        at
    }

    /// Checks that a costly clock's readings settle where one costs 1/128 of the work between
    /// two (u = 128 * 500 * u / (10 u + 500): u = 6,350 units) and a cheap clock's (1 tick)
    /// at the fewest units a paced meter allows ([`MIN_PACED`]).
    fn assert_paced(work_first: u32) {
        let costly = paced_readings(500, work_first);
        let gaps: heapless::Vec<u64, 8192> = costly.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(
            gaps[0] <= 256,
            "the fewest units until the rate is known: {gaps:?}"
        );
        let settled = &gaps[3..];
        assert!(
            settled.iter().all(|&g| (6_300..=6_400).contains(&g)),
            "{gaps:?}"
        );
        let cheap = paced_readings(1, work_first);
        assert!(
            cheap.windows(2).skip(2).all(|w| w[1] - w[0] == MIN_PACED),
            "{cheap:?}"
        );
    }

    /// A paced meter spaces a costly clock's readings and reads a cheap one often; a frozen
    /// clock still ends at the work cap.
    #[test]
    fn a_paced_meter_spaces_its_readings_by_their_cost() {
        assert_paced(0);
        let frozen = FakeClock::nanos().with_step(0);
        let m = Meter::with_cap(&frozen, 50_000)
            .reading_every(256)
            .paced(8192, 0);
        let d = Deadline::from_ticks(0, 10);
        let mut checks = 0;
        while !m.expired(&d) {
            m.charge(1);
            checks += 1;
        }
        assert_eq!(checks, 50_000);
    }

    /// Regression (fifth round's first soak): the cost of a reading was measured only when no
    /// work came before the first deadline check, and `plan` always anchors and follows the
    /// agent first, so the pacing never engaged there (a CPU clock read every 256 units).
    #[test]
    fn regression_pacing_engages_after_work_before_the_first_check() {
        assert_paced(100);
    }

    /// Issue 25: on a Cortex-M4F the tuned set's paced readings let up to 8,192 units pass
    /// unread, milliseconds of work there, and calls ran 19 ms over `t_exp`. A costly reading
    /// (5 us) with slow work (100 ns a unit) paces by cost to about 6,400 units (0.64 ms); the
    /// time bound keeps the work between two readings under 0.25 ms (2,091 units: the first
    /// interval, 256 units and a reading, measured the slowest rate).
    #[test]
    fn regression_paced_readings_leave_at_most_a_quarter_millisecond_unread() {
        let at = paced_readings_at(5_000, 100, 0);
        let gaps: heapless::Vec<u64, 8192> = at.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.len() > 20, "{gaps:?}");
        let settled = &gaps[3..];
        assert!(
            settled.iter().all(|&g| (2_000..=2_500).contains(&g)),
            "{gaps:?}"
        );
    }

    /// A clock read in 1 us whose work costs `ns` a unit, changed by the test.
    struct Phased {
        t: Cell<u64>,
        ns: Cell<u64>,
    }

    impl Clock for Phased {
        fn now(&self) -> u64 {
            self.t.set(self.t.get() + 1_000);
            self.t.get()
        }
        fn ticks_per_second(&self) -> u64 {
            1_000_000_000
        }
        fn charge(&self, units: u32) {
            self.t.set(self.t.get() + u64::from(units) * self.ns.get());
        }
    }

    /// Issue 25, second round: the time bound used the rate of the last interval only, and
    /// on a Cortex-M4F a unit of one phase of a step costs five times one of another: after
    /// a fast phase the pace let 874 units of a slow one pass unread (1.2 ms), and the tuned
    /// set's calls still ran 1-2 ms over. Work alternating between 10 and 100 ns a unit: once
    /// both were measured, no two readings are more than 0.25 ms (and a reading) apart.
    #[test]
    fn regression_paced_readings_follow_the_slowest_rate_seen() {
        let c = Phased {
            t: Cell::new(0),
            ns: Cell::new(100),
        };
        let origin = c.now();
        let m = Meter::new(&c).reading_every(256).paced(8192, origin);
        let d = Deadline::from_ticks(origin, u64::MAX / 2);
        let (mut last, mut worst) = (c.t.get(), 0);
        for i in 0..400_000u32 {
            c.ns.set(if (i / 20_000) % 2 == 0 { 100 } else { 10 });
            let before = m.last.get();
            assert!(!m.expired(&d));
            if let Some((t, _)) = m.last.get()
                && m.last.get() != before
            {
                if i > 40_000 {
                    worst = worst.max(t - last);
                }
                last = t;
            }
            m.charge(1);
        }
        assert!(worst <= 252_000, "{worst} ns between two readings");
    }

    /// Issue 25, second round: a paced meter never read more often than every `every` units
    /// (256), and a Cortex-M4F's slowest phases take 256 units in 1 ms. A clock that costs a
    /// tick to read is now read every [`MIN_PACED`] units.
    #[test]
    fn regression_a_cycle_counter_is_read_every_few_dozen_units() {
        let cheap = paced_readings(1, 0);
        let gaps: heapless::Vec<u64, 8192> = cheap.windows(2).map(|w| w[1] - w[0]).collect();
        assert!(gaps.iter().skip(2).all(|&g| g == MIN_PACED), "{gaps:?}");
        assert!(gaps.len() > 6_000);
    }

    /// Issue 25, third round: [`Meter::affords`] predicts a refresh at the slowest rate
    /// measured over a window of [`RATE_UNITS`] units (a unit a node), paced or not, or at
    /// the slowest refresh timed when slower, and hands both to the next meter; before any
    /// rate, only the deadline counts.
    #[test]
    fn affords_predicts_at_the_slowest_rate_measured() {
        let c = FakeClock::nanos().with_work_cost(10);
        let m = Meter::new(&c);
        let d = Deadline::from_ticks(c.now(), 100_000);
        assert!(
            m.affords(1_000_000, &d),
            "no rate yet: only the deadline counts"
        );
        for _ in 0..4 {
            m.charge(RATE_UNITS as u32);
            assert!(!m.expired(&d));
        }
        // 4,096 units at 10 ns: 40,960 ns gone, 59,040 left, 5,904 units' worth.
        assert!(m.affords(5_800, &d));
        assert!(!m.affords(6_000, &d));
        m.charge(6_000);
        assert!(!m.affords(0, &d), "past the deadline");
        // A timed refresh slower than a unit per node: 64 nodes in 64 us, 1 us a node.
        let m = Meter::new(&c).expecting(m.rates());
        let d = Deadline::from_ticks(c.now(), 1_000_000);
        assert!(m.affords(90_000, &d), "10 ns a node, from the last meter");
        let since = m.now();
        c.advance(64_000);
        m.timed_refresh(64, since);
        assert_eq!(m.rates().1, 1_024_000);
        // 64 us gone, 936 left: 936 nodes' worth.
        assert!(m.affords(900, &d) && !m.affords(1_000, &d));
        let next = Meter::new(&c).expecting(m.rates());
        assert!(!next.affords(1_000_000, &Deadline::from_ticks(c.now(), 1_000_000)));
    }

    #[test]
    fn deadlines_on_a_hand_advanced_clock() {
        let c = FakeClock::new(1_000);
        let d = Deadline::after(&c, Duration::from_millis(150));
        assert_eq!(d.end(), 150);
        assert!(!d.expired(&c));
        c.advance(149);
        assert!(!d.expired(&c));
        assert_eq!(d.remaining(&c), 1);
        c.advance(1);
        assert!(d.expired(&c));
        assert_eq!(d.remaining(&c), 0);
        c.set(10);
        assert_eq!(c.peek(), 150, "never goes back");
        assert!(Deadline::after(&c, Duration::ZERO).expired(&c));
    }

    #[test]
    fn a_stepping_clock_ends_every_deadline_loop() {
        let c = FakeClock::nanos().with_step(1_000);
        let d = Deadline::after(&c, Duration::from_micros(50));
        let mut spins = 0;
        while !d.expired(&c) {
            spins += 1;
        }
        assert_eq!(spins, 49);
    }

    #[test]
    fn work_advances_a_virtual_clock() {
        let c = FakeClock::nanos().with_work_cost(20);
        c.charge(5);
        c.charge(10);
        assert_eq!(c.peek(), 300);
        assert_eq!(c.work(), 15);
        assert_eq!(c.duration(1_500_000), Duration::from_micros(1_500));
        assert_eq!(c.ticks(Duration::from_secs(u64::MAX)), u64::MAX);
    }

    /// Issue 7, case 3: `ticks()` overflowed u128 with a fast clock and `Duration::MAX`.
    #[test]
    fn regression_ticks_overflow_with_a_fast_clock() {
        let fast = FakeClock::new(u64::MAX);
        assert_eq!(fast.ticks(Duration::MAX), u64::MAX);
        assert_eq!(fast.duration(u64::MAX), Duration::from_secs(1));
        assert_eq!(
            FakeClock::new(1).duration(u64::MAX),
            Duration::from_secs(u64::MAX)
        );
        let d = Deadline::after(&fast, Duration::MAX);
        assert!(!d.expired(&fast));
    }

    #[test]
    fn a_work_cap_expires_every_deadline() {
        let frozen = FakeClock::nanos();
        let meter = Meter::with_cap(&frozen, 100);
        let never = Deadline::after(&frozen, Duration::from_secs(10));
        assert!(!meter.expired(&never));
        meter.charge(99);
        assert!(!meter.expired(&never));
        meter.charge(1);
        assert!(meter.expired(&never) && meter.work() == 100);
    }
}
