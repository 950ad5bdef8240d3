//! The planner's work meter (beyond the paper, whose budgets are read on a wall clock): the
//! work each call charges its [`Clock`], the work cap that bounds a call on a clock that never
//! advances (promise 3), and the paced readings that keep a costly clock's reads under 1 %
//! of a call. Public as [`crate::clock::Meter`].

use super::{Clock, Deadline};
use core::cell::Cell;
use core::time::Duration;

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
    pub(crate) last: Cell<Option<(u64, u64)>>,
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
pub(crate) const RATE_UNITS: u64 = 1024;

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
