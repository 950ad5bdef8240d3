//! One `plan` call (paper Algorithm 1): the root follows the agent, then expansion
//! (Algorithm 2) and rewiring (Algorithms 3-6, RT-RRT*'s random rewiring) share `t_exp` until
//! the caller's clock says it has passed; the module's "One `plan` call".

use super::*;

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// One planning step for an agent at `agent`: [`Planner::grow`], then the root follows the
    /// agent along the path.
    ///
    /// # The waypoint rule
    ///
    /// The waypoint returned is reachable from `agent` over a segment free of the map and of
    /// every dynamic obstacle present when `plan` returns (with moving obstacles and a stated
    /// motion, also clear of their predicted sweeps: module [`crate::motion`]). When the agent is off the root and
    /// cannot reach it (an obstacle dropped between them, or an agent that is not where the
    /// tree thinks), the tree is first re-rooted at the agent: a node at the agent's position
    /// joins the tree below the cheapest node within `e_max` that it sees past the map (the new
    /// edge flagged blocked if a circle crosses it), and becomes the root; if no node is in
    /// sight the forward tree restarts at the agent. When no waypoint qualifies, the waypoint
    /// is the agent's own position and [`Progress::status`] says why; the tree survives and
    /// the agent goes on once the way is free.
    ///
    /// # Bounded work
    ///
    /// `t_exp` counts from the moment of the call: anchoring the agent (at most one O(N)
    /// re-rooting) and following it (at most [`FOLLOW_STEPS`]) spend it first. A call stops
    /// expanding when `t_exp` has passed on `clock`, after `max_expansions` expansions, or
    /// once `max_work` work units are done ([`Config::budget`]), whichever comes first; every
    /// rewiring phase checks the same limits before each node it visits, and the metric
    /// nearest scan every 64 nodes (with the budget's `clock_every` set, these checks reuse
    /// the last clock reading until that much work has been done since it, or with
    /// `clock_every_max` up to that much when a reading is costly, adding at most that much
    /// work to the overrun). Work that cannot stop half-way and grows with the tree
    /// (a re-rooting, a rewire that moves a large subtree: each refreshes the cost of every
    /// node it carries) starts only when it ends before the deadline at the slowest rate the
    /// calls have measured ([`Meter::affords`]); while the agent waits at the root, the
    /// expansions leave time for following it once the goal joins or the path changes
    /// (retried after the loop; when it does not fit, the agent holds with
    /// [`Wait::OutOfTime`]). On a real clock a call therefore overruns `t_exp` by at most the
    /// rest of one short piece of an expansion step: under 1 ms on a Cortex-M4F model, as
    /// `firmware/sequence.sh` measures it over the office's six goals (the worst calls of both
    /// sets are in `docs/guides/firmware.md`'s table, which CI keeps equal to that run's
    /// output). And whatever the clock (even one that never advances) a call does at most
    /// `max_work + W_step` units, where `W_step` is the most work between two checks:
    /// one expansion or one rewiring visit. Both are `O(N + e_max / cell)`: an expansion does
    /// at most one metric nearest scan (N metric evaluations), one meet test (N visits and 16
    /// segment tests), one graft (4 units per grafted node, at most N), one re-rooting (N)
    /// and a bounded number of segment tests (`sample_attempts`, `steer_candidates`, 64
    /// parent candidates, and with `connect` the greedy connection's up to 32 steps),
    /// each `2 + 2 e / cell` units at most (`e` the longer of `e_max` and `e_search`; a meet,
    /// connect or shortcut segment at most `2 + (width + height) / cell`; with a robot body of
    /// radius `r`, a test near a wall also charges its exact stage, a unit per row of a band
    /// `2 r / cell + 1` cells wide and per occupied cell it measures), with `rewire_new`
    /// up to 64 rewires around the new node, and with `path_shortcuts` that many
    /// rewires on the path; a rewiring visit tests at
    /// most 64 neighbours, each rewire charging the subtree it moves (at most N). With
    /// obstacle updates submitted since the last call, the call starts by re-flagging both
    /// trees (`2 N (K + 1)` units, before the expansions: it spends the budget); with live
    /// cells edited since the last call, by re-testing the edges near them (a unit per node
    /// of both trees and, per edge near the changed cells, about the cells it crosses:
    /// [`Stats::retested`] counts them), likewise before the expansions; and with
    /// obstacles present the waypoint rule (module [`crate::motion`]) ends the call with at
    /// most about 65 tests of the `K` obstacles and as many grid segments, for which the
    /// expansions leave [`crate::motion::RULE_UNITS`] units per obstacle. Measured
    /// (`host-sim frozen`, Bi-AM-RRT*(D) on the reference maps, N = 8192): calls ended within
    /// 3,345 units of the cap. One unit is about 12 ns on the development machine and about
    /// 200 instructions on a Cortex-M4F.
    ///
    /// Errors (doing nothing) when `agent` is not finite, outside the map or, on a map without
    /// live cells, inside the grid's walls ([`Map::in_wall`]: the grid never changes, so the
    /// position is wrong). An agent inside a dynamic obstacle, in any occupied cell of a map
    /// with live cells (a door may close on the robot), or with a body closer to a wall than
    /// its radius is not an error: it holds ([`Wait::AgentInObstacle`]).
    pub fn plan<C: Clock + ?Sized>(
        &mut self,
        clock: &C,
        agent: Point,
    ) -> Result<Progress, InputError> {
        if !agent.is_finite() {
            return Err(InputError::NotFinite);
        }
        if !self.map.grid().contains(agent) {
            return Err(InputError::OutOfBounds);
        }
        if self.map.in_wall(agent) && !self.map.has_overlay() {
            return Err(InputError::InObstacle);
        }
        // The call's budget starts now: anchoring and following the agent spend it too, and
        // they come first, so nothing but the final check runs after the last expansion.
        self.call = Deadline::after(clock, self.cfg.budget.t_exp);
        self.deferred = false;
        let meter = self.meter(clock);
        self.apply_updates(&meter);
        let trapped = self.trapped(agent);
        if !trapped {
            self.anchor(agent, &meter);
        }
        let mut advanced = !trapped && self.follow(agent, &meter, Deadline::NEVER);
        // The path may only now lead somewhere. When the goal joins in this call the agent
        // follows at once, within the budget (`expand_for`): after the deadline, a re-rooting
        // (O(N), milliseconds on a Cortex-M4F) made the join's call overrun (issue 25). When
        // rewiring changed or cleared the first edge (or the search is stuck), once more after
        // the loop, in the time the loop left for it.
        let follow = (!advanced && !trapped).then_some(agent);
        let expansions = self.expand_for(&meter, follow, &mut advanced);
        if !advanced && !trapped {
            advanced = self.follow(agent, &meter, self.call);
        }
        self.keep_rate(&meter, clock);
        Ok(self.progress(Some(agent), expansions, advanced, &meter))
    }

    /// Expansion and rewiring for `t_exp` without moving the root: planning while the agent
    /// stands still (bounded as [`Planner::plan`]). The waypoint is the root, unchecked: no
    /// agent position is given.
    pub fn grow<C: Clock + ?Sized>(&mut self, clock: &C) -> Progress {
        self.call = Deadline::after(clock, self.cfg.budget.t_exp);
        let meter = self.meter(clock);
        self.apply_updates(&meter);
        let expansions = self.expand_for(&meter, None, &mut false);
        self.keep_rate(&meter, clock);
        self.progress(None, expansions, false, &meter)
    }

    /// The call's meter (set after the call's deadline, whose reading it may pace against):
    /// the work cap, and the clock readings of the budget's `clock_every` and
    /// `clock_every_max` ([`Config::budget`]).
    fn meter<'c, C: Clock + ?Sized>(&self, clock: &'c C) -> Meter<'c, C> {
        let (tps, rate) = self.rate;
        let same_clock = tps == clock.ticks_per_second();
        Meter::with_cap(clock, self.cfg.budget.max_work as u64)
            .reading_every(self.cfg.budget.clock_every)
            .paced(self.cfg.budget.clock_every_max, self.call.start())
            .expecting(if same_clock { rate } else { (0, 0) })
    }

    /// Keeps the rate a call's meter measured for the next call (see [`Planner::meter`]).
    fn keep_rate<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>, clock: &C) {
        let (tps, (rate, refresh)) = self.rate;
        let same_clock = tps == clock.ticks_per_second();
        let (r, f) = meter.rates();
        let keep = |new: u64, old: u64| if new > 0 || !same_clock { new } else { old };
        self.rate = (clock.ticks_per_second(), (keep(r, rate), keep(f, refresh)));
    }

    /// Expansions until the call's deadline (set by the caller) or the expansion cap. With
    /// `follow` (the agent, not yet advanced in this call), the agent follows the path as soon
    /// as the goal joins the forward tree; `advanced` tells whether it did.
    fn expand_for<C: Clock + ?Sized>(
        &mut self,
        meter: &Meter<'_, C>,
        follow: Option<Point>,
        advanced: &mut bool,
    ) -> u32 {
        let call = self.call;
        let mut expansions = 0;
        self.full = false;
        // An agent at the root that has not moved yet may move in or after the loop (once
        // the goal joins, or rewiring changes the first edge): the steps leave time for that
        // (when the budget allows, `Meter::reserving`).
        let root = self.root_position();
        let pending = follow.is_some_and(|a| a.dist(root) <= self.cfg.search.e_max / AT_ROOT_DIV);
        let steps = if pending {
            meter.reserving(self.reroot_nodes().saturating_mul(2), call)
        } else {
            call
        };
        // The waypoint rule's tests of moving obstacles run after the loop (module `motion`).
        let obstacles = self.map.obstacles().len() as u64;
        let steps = if obstacles > 0 && self.cfg.motion.period + self.cfg.motion.horizon > 0.0 {
            meter.reserving(obstacles.saturating_mul(crate::motion::RULE_UNITS), steps)
        } else {
            steps
        };
        while expansions < self.cfg.budget.max_expansions && !meter.expired(&steps) {
            // A new goal's first step: the roadmap's path, or the straight one (module
            // `roadmap`). Tried after a tree step or two, it cost more than it saved.
            // A search the call's time cut short goes on in the next call, before any tree
            // step: its scratch is the reverse arena's last slots.
            #[cfg(feature = "roadmap")]
            if !matches!(self.roadmap_stage, crate::roadmap::Stage::Idle) {
                match self.roadmap_join(meter, steps) {
                    None => break,
                    Some(true) => {
                        if let Some(agent) = follow
                            && !*advanced
                        {
                            *advanced = self.follow(agent, meter, call);
                        }
                    }
                    Some(false) => {}
                }
            }
            let joined = self.goal_node().is_some();
            // Each tree's expansion counts (Algorithm 1 runs `Expend_f` and then `Expend_r`,
            // each with its own rewiring): a step that grows both trees counts two, so one-
            // and two-tree planners get the same growth from a cap. A step is never split:
            // the count may end one over the cap.
            let before = self
                .stats
                .expansions
                .saturating_add(self.stats.reverse_expansions);
            self.step(meter, steps);
            let grown = self
                .stats
                .expansions
                .saturating_add(self.stats.reverse_expansions)
                .saturating_sub(before);
            expansions = expansions.saturating_add(grown.clamp(1, 2) as u32);
            if let Some(agent) = follow
                && !*advanced
                && !joined
                && self.goal_node().is_some()
            {
                *advanced = self.follow(agent, meter, call);
            }
        }
        expansions
    }

    /// Sub-budget for a rewiring phase.
    fn slice<C: Clock + ?Sized>(
        &self,
        meter: &Meter<'_, C>,
        budget: core::time::Duration,
        call: Deadline,
    ) -> Slice {
        let visits = match self.cfg.rewiring.mode {
            RewireMode::Faithful => u32::MAX,
            RewireMode::PerExpansion { visits } => visits as u32,
        };
        Slice {
            deadline: meter.deadline(budget, call),
            // A frozen clock must still end the phase: never more than 4 sweeps of the arena.
            visits: visits.min(units(N).saturating_mul(4)),
        }
    }

    /// One expansion of each growing tree and the rewiring after it.
    fn step<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>, call: Deadline) {
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call,
        };
        let grown = self
            .fwd
            .expand(&env, &mut self.rng, self.goal.as_mut(), meter);
        self.full |= grown.full;
        self.stats.expansions = self.stats.expansions.saturating_add(1);
        self.stats.starving_admits = self.fwd.holes.saturating_add(self.rev.holes);
        if grown.goal_joined {
            self.goal_joined(meter);
        } else if let (Some(a), true) = (grown.added, self.rev_goal.is_some())
            && let Err(blocked) = self.try_meet(a, true, meter)
        {
            self.connect(a, true, &blocked, meter);
        }
        // Rewiring of the forward tree.
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call,
        };
        let searching = self.goal.is_some_and(|g| g.node.is_none());
        // `rewire_after_join`: no root rewiring before the goal joins (the same first paths,
        // less work).
        let after_join = self.cfg.tactics.rewire_after_join;
        if !after_join || !searching {
            let slice = self.slice(meter, self.cfg.rewiring.t_root, call);
            self.fwd
                .rewire_root(&env, slice, self.cfg.new_rewiring, meter);
        }
        match (self.cfg.base, self.goal) {
            (Base::RtRrt, _) => {
                let slice = self.slice(meter, self.cfg.rewiring.t_goal, call);
                self.fwd.rewire_random(&env, slice, meter);
            }
            (Base::AmRrt, Some(goal)) if goal.node.is_some() => {
                let slice = self.slice(meter, self.cfg.rewiring.t_goal, call);
                self.fwd.rewire_goal(&env, &goal, slice, false, meter);
                if self.cfg.new_rewiring {
                    let slice = self.slice(meter, self.cfg.rewiring.t_goal, call);
                    self.fwd.rewire_goal(&env, &goal, slice, true, meter);
                }
                if let (Some(g), n @ 1..) = (goal.node, self.cfg.rewiring.path_shortcuts) {
                    self.fwd.shortcut_path(&env, g, n, meter);
                }
            }
            _ => {}
        }
        // The reverse tree, while the goal is not in the forward tree.
        if self.rev_goal.is_some() {
            let grown = self
                .rev
                .expand(&env, &mut self.rng, self.rev_goal.as_mut(), meter);
            self.full |= grown.full;
            self.stats.reverse_expansions = self.stats.reverse_expansions.saturating_add(1);
            self.stats.starving_admits = self.fwd.holes.saturating_add(self.rev.holes);
            if let Some(b) = grown.added
                && let Err(blocked) = self.try_meet(b, false, meter)
            {
                self.connect(b, false, &blocked, meter);
            }
            if self.rev_goal.is_some() && !after_join {
                let env = Env {
                    map: &self.map,
                    metric: &self.metric,
                    cfg: &self.cfg,
                    call,
                };
                let slice = self.slice(meter, self.cfg.rewiring.t_root, call);
                self.rev
                    .rewire_root(&env, slice, self.cfg.new_rewiring, meter);
            }
        }
    }

    /// Records the goal joining the forward tree and retires the reverse tree.
    pub(super) fn goal_joined<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>) {
        if self.stats.goal_found_at.is_none() {
            self.stats.goal_found_at = Some(meter.now());
            self.stats.nodes_at_goal = Some(self.fwd.tree.len());
            self.stats.first_cost = self
                .goal_node()
                .and_then(|g| self.fwd.tree.cost(g))
                .map(|c| c.length);
        }
        self.fwd.restart_goal_sweep();
        if self.rev_goal.take().is_some() {
            self.rev.clear();
        }
    }
}
