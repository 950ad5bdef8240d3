//! The real-time planner (paper Algorithm 1): a forward tree rooted at the agent, optionally a
//! reverse tree rooted at the goal, expansion and rewiring for `t_exp` per call, meet and graft
//! of the two trees, an agent-following root, and dynamic obstacles.
//!
//! # One `plan` call
//!
//! Until `t_exp` has passed on the caller's clock (or `max_expansions_per_call` is reached):
//! expand the forward tree; then rewire it from the root for `t_root`; then, once the goal is
//! in it, goal rewiring for `t_goal` (and the second kind for another `t_goal` with the new
//! rewiring) — RT-RRT* runs its random rewiring for `t_goal` instead. While the goal is not in
//! the forward tree and bidirectional search is on, each step also expands the reverse tree
//! (rooted at the goal, growing towards the agent's position when the goal was set) and
//! rewires it from its root.
//!
//! Then the path is read from the root to the goal (or, before the goal joins, to the node
//! `Nearest` the goal). If the agent is within `e_max / 10` of the root and the path's first
//! edge is free, the tree is re-rooted at the path's next node. The root is the waypoint
//! returned. (The agent must also see that node over a free segment; otherwise it first
//! finishes its way to the root, so it never cuts a corner.)
//!
//! # Meet and graft
//!
//! Every node added to either tree is checked against the other tree: among the nodes within
//! `sigma`, the 16 pairs with the lowest total cost `Cost_f(a) + d_E(a, b) + Cost_r(b)` are
//! tested for a free segment in cost order, and the first free one is taken. The reverse tree's
//! trunk (from `b` to the goal) is then grafted below `a`, each edge keeping its blocked flag,
//! so the goal joins the forward tree; the reverse tree is emptied and search continues with the
//! forward tree alone. Search time is read when the goal joins, not at the end of the call.
//!
//! # Dynamic obstacles
//!
//! Adding or removing one re-flags every edge of both trees (blocked when it meets any
//! circle), recomputes all costs and restarts every rewiring sweep from the root. Because costs
//! compare blocked-last, rewiring moves blocked nodes onto any free branch the tree holds, and
//! the returned path leaves the obstacle as soon as such a branch exists. The agent never gets a
//! waypoint across a blocked edge: it waits at the root until rewiring has found a way around.

use rand_core::Rng;

use crate::clock::{Clock, Deadline, Meter};
use crate::config::{Base, Config, RewireMode};
use crate::error::{InputError, ObstacleError, TreeError};
use crate::geometry::Point;
use crate::map::{Circle, Map, ObstacleId};
use crate::metric::Metric;
use crate::rewire::Slice;
use crate::search::{Env, Target, TreeStore};
use crate::tree::{Cost, NodeId, Tree};

/// Storage for a planner's two trees: `N` nodes and `B` index buckets each. Keep it wherever
/// there is room (a `static`, a `Box`, the stack of a thread with a large stack); the planner
/// borrows it.
#[derive(Clone, Debug, Default)]
pub struct Storage<const N: usize, const B: usize> {
    forward: TreeStore<N, B>,
    reverse: TreeStore<N, B>,
}

impl<const N: usize, const B: usize> Storage<N, B> {
    /// Empty storage (a `const fn`).
    pub const fn new() -> Self {
        Self {
            forward: TreeStore::new(),
            reverse: TreeStore::new(),
        }
    }
}

/// What a `plan` call did and where the agent should go.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Progress {
    /// The next waypoint: the forward tree's root.
    pub waypoint: Point,
    /// Whether the goal is a node of the forward tree.
    pub goal_in_tree: bool,
    /// Cost of the path from the root to the goal, once the goal is in the tree.
    pub goal_cost: Option<Cost>,
    /// Forward tree size.
    pub nodes: usize,
    /// Reverse tree size (0 when not in use).
    pub reverse_nodes: usize,
    /// Expansions done in this call.
    pub expansions: u32,
    /// Whether the root moved along the path in this call.
    pub advanced: bool,
    /// Whether an arena filled up (the planner keeps rewiring what it has).
    pub tree_full: bool,
}

/// Counters over the planner's life since the goal was set.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stats {
    /// Clock tick at which the goal joined the forward tree.
    pub goal_found_at: Option<u64>,
    /// Forward tree size when the goal joined.
    pub nodes_at_goal: Option<usize>,
    /// Expansions of the forward tree since the goal was set.
    pub expansions: u64,
    /// Expansions of the reverse tree since the goal was set.
    pub reverse_expansions: u64,
    /// Whether the goal joined through a meet of the two trees.
    pub met: bool,
}

/// The planner. `N` nodes and `B` buckets per tree, up to `K` dynamic obstacles; `M` the
/// assisting metric, `R` the random number generator.
pub struct Planner<'s, 'm, M, R, const N: usize, const B: usize, const K: usize> {
    cfg: Config,
    map: Map<'m, K>,
    metric: M,
    rng: R,
    fwd: &'s mut TreeStore<N, B>,
    rev: &'s mut TreeStore<N, B>,
    goal: Option<Target>,
    /// The reverse tree's target (the agent's position when the goal was set), while the
    /// reverse tree is growing.
    rev_goal: Option<Target>,
    stats: Stats,
    full: bool,
}

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// A planner at `start` on `map`. Errors when `start` is not finite, outside the map or in
    /// an obstacle.
    pub fn new(
        storage: &'s mut Storage<N, B>,
        map: Map<'m, K>,
        metric: M,
        rng: R,
        cfg: Config,
        start: Point,
    ) -> Result<Self, InputError> {
        map.check_point(start)?;
        let (w, h) = (map.grid().width_m(), map.grid().height_m());
        let side = cfg.e_max.max(map.grid().cell_size());
        let Storage { forward, reverse } = storage;
        for store in [&mut *forward, &mut *reverse] {
            store.index.reshape(w, h, side);
        }
        forward.reset(start);
        reverse.clear();
        Ok(Self {
            cfg,
            map,
            metric,
            rng,
            fwd: forward,
            rev: reverse,
            goal: None,
            rev_goal: None,
            stats: Stats::default(),
            full: false,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// The map with its dynamic obstacles.
    pub fn map(&self) -> &Map<'m, K> {
        &self.map
    }

    /// The assisting metric.
    pub fn metric(&self) -> &M {
        &self.metric
    }

    /// The forward tree (rooted at the agent).
    pub fn tree(&self) -> &Tree<N> {
        &self.fwd.tree
    }

    /// The reverse tree (rooted at the goal; empty unless bidirectional search is running).
    pub fn reverse_tree(&self) -> &Tree<N> {
        &self.rev.tree
    }

    /// The goal, if set.
    pub fn goal(&self) -> Option<Point> {
        self.goal.map(|g| g.pos)
    }

    /// The goal's node in the forward tree, once it has joined.
    pub fn goal_node(&self) -> Option<NodeId> {
        self.goal.and_then(|g| g.node)
    }

    /// Whether the reverse tree is growing.
    pub fn searching_backwards(&self) -> bool {
        self.rev_goal.is_some()
    }

    /// Counters since the goal was set.
    pub fn stats(&self) -> &Stats {
        &self.stats
    }

    /// Sets (or changes) the goal. The forward tree keeps its nodes; with bidirectional search
    /// a reverse tree starts at the goal, growing towards the current root. Errors when the
    /// goal is not finite, outside the map, in an obstacle, or placed by the metric at an
    /// infinite distance from the root (unreachable).
    pub fn set_goal(&mut self, goal: Point) -> Result<(), InputError> {
        self.map.check_point(goal)?;
        let root = self.root_position();
        if !self.metric.distance(root, goal).is_finite() {
            return Err(InputError::Unreachable);
        }
        self.goal = Some(Target {
            pos: goal,
            node: None,
        });
        self.stats = Stats::default();
        self.fwd.restart_goal_sweep();
        if self.cfg.bidirectional {
            self.rev.reset(goal);
            self.rev_goal = Some(Target {
                pos: root,
                node: None,
            });
        } else {
            self.rev.clear();
            self.rev_goal = None;
        }
        Ok(())
    }

    /// Forgets the goal; the tree stays.
    pub fn clear_goal(&mut self) {
        self.goal = None;
        self.rev_goal = None;
        self.rev.clear();
        self.fwd.restart_goal_sweep();
    }

    /// Adds a dynamic obstacle (module docs).
    pub fn add_obstacle(&mut self, circle: Circle) -> Result<ObstacleId, ObstacleError> {
        let id = self.map.obstacles_mut().add(circle)?;
        self.reflag();
        Ok(id)
    }

    /// Removes a dynamic obstacle.
    pub fn remove_obstacle(&mut self, id: ObstacleId) -> Result<Circle, ObstacleError> {
        let c = self.map.obstacles_mut().remove(id)?;
        self.reflag();
        Ok(c)
    }

    fn reflag(&mut self) {
        let obstacles = self.map.obstacles();
        for store in [&mut *self.fwd, &mut *self.rev] {
            store
                .tree
                .reflag_edges(|a, b| obstacles.blocks_segment(a, b));
            store.restart_sweeps();
        }
    }

    /// The forward tree's root: where the agent is, or is heading.
    pub fn root_position(&self) -> Point {
        self.fwd
            .tree
            .root()
            .map(|r| self.fwd.pos(r))
            .unwrap_or(Point::ZERO)
    }

    /// The node the path leads to: the goal once in the tree, else the node `Nearest` it.
    fn path_end<C: Clock + ?Sized>(&self, meter: &Meter<'_, C>) -> Option<NodeId> {
        let goal = self.goal?;
        if goal.node.is_some() {
            return goal.node;
        }
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
        };
        self.fwd.nearest(&env, goal.pos, meter)
    }

    /// Writes the current path (root first) into `buf` and returns its length: to the goal
    /// once it is in the tree, else to the tree node nearest the goal; just the root when no
    /// goal is set.
    pub fn path(&self, buf: &mut [Point]) -> Result<usize, TreeError> {
        let clock = crate::clock::FakeClock::new(1);
        let meter = Meter::new(&clock);
        let end = self
            .path_end(&meter)
            .or(self.fwd.tree.root())
            .ok_or(TreeError::UnknownNode)?;
        self.fwd.tree.path_points(end, buf)
    }

    /// One planning step of `t_exp` (module docs) for an agent at `agent`: [`Planner::grow`],
    /// then the root follows the agent along the path. Errors (doing nothing) when `agent` is
    /// not finite or outside the map.
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
        let meter = Meter::new(clock);
        let expansions = self.expand_for(&meter, clock);
        let advanced = self.follow(agent, &meter);
        Ok(self.progress(expansions, advanced))
    }

    /// Expansion and rewiring for `t_exp` without moving the root: planning while the agent
    /// stands still.
    pub fn grow<C: Clock + ?Sized>(&mut self, clock: &C) -> Progress {
        let meter = Meter::new(clock);
        let expansions = self.expand_for(&meter, clock);
        self.progress(expansions, false)
    }

    fn expand_for<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>, clock: &C) -> u32 {
        let call = Deadline::after(clock, self.cfg.t_exp);
        let mut expansions = 0;
        self.full = false;
        while expansions < self.cfg.max_expansions_per_call && !meter.expired(&call) {
            self.step(meter, call);
            expansions += 1;
        }
        expansions
    }

    fn progress(&self, expansions: u32, advanced: bool) -> Progress {
        let goal_node = self.goal_node();
        Progress {
            waypoint: self.root_position(),
            goal_in_tree: goal_node.is_some(),
            goal_cost: goal_node.and_then(|g| self.fwd.tree.cost(g)),
            nodes: self.fwd.tree.len(),
            reverse_nodes: self.rev.tree.len(),
            expansions,
            advanced,
            tree_full: self.full,
        }
    }

    /// Re-roots at the path's next node when the agent has reached the root.
    fn follow<C: Clock + ?Sized>(&mut self, agent: Point, meter: &Meter<'_, C>) -> bool {
        let root = self.root_position();
        if agent.dist(root) > self.cfg.e_max / 10.0 {
            return false;
        }
        let Some(end) = self.path_end(meter) else {
            return false;
        };
        // The node after the root on the path to `end`: walk up from `end`.
        let tree = &self.fwd.tree;
        let mut next = end;
        for _ in 0..tree.len() {
            match tree.parent(next) {
                Some(p) if Some(p) == tree.root() => break,
                Some(p) => next = p,
                None => return false,
            }
        }
        if tree.parent(next) != tree.root() || tree.edge_blocked(next) != Some(false) {
            return false;
        }
        // The agent is near the root, not always on it: it must see the next node in a
        // straight free line, or it first finishes its way to the root.
        if !self.map.free_path(agent, self.fwd.pos(next)) {
            return false;
        }
        meter.charge(N as u32 / 8);
        if self.fwd.tree.set_root(next).is_err() {
            return false;
        }
        self.fwd.restart_sweeps();
        true
    }

    /// Sub-budget for a rewiring phase.
    fn slice<C: Clock + ?Sized>(
        &self,
        meter: &Meter<'_, C>,
        budget: core::time::Duration,
        call: Deadline,
    ) -> Slice {
        let visits = match self.cfg.rewire_mode {
            RewireMode::Faithful => u32::MAX,
            RewireMode::PerExpansion { visits } => visits as u32,
        };
        Slice {
            deadline: meter.deadline(budget, call),
            // A frozen clock must still end the phase: never more than 4 sweeps of the arena.
            visits: visits.min(4 * N as u32),
        }
    }

    /// One expansion of each growing tree and the rewiring after it.
    fn step<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>, call: Deadline) {
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
        };
        let grown = self
            .fwd
            .expand(&env, &mut self.rng, self.goal.as_mut(), meter);
        self.full |= grown.full;
        self.stats.expansions += 1;
        if grown.goal_joined {
            self.goal_joined(meter);
        } else if let (Some(a), true) = (grown.added, self.rev_goal.is_some()) {
            self.try_meet(a, true, meter);
        }
        // Rewiring of the forward tree.
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
        };
        let slice = self.slice(meter, self.cfg.t_root, call);
        self.fwd
            .rewire_root(&env, slice, self.cfg.new_rewiring, meter);
        match (self.cfg.base, self.goal) {
            (Base::RtRrt, _) => {
                let slice = self.slice(meter, self.cfg.t_goal, call);
                self.fwd.rewire_random(&env, slice, meter);
            }
            (Base::AmRrt, Some(goal)) if goal.node.is_some() => {
                let slice = self.slice(meter, self.cfg.t_goal, call);
                self.fwd.rewire_goal(&env, &goal, slice, false, meter);
                if self.cfg.new_rewiring {
                    let slice = self.slice(meter, self.cfg.t_goal, call);
                    self.fwd.rewire_goal(&env, &goal, slice, true, meter);
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
            self.stats.reverse_expansions += 1;
            if let Some(b) = grown.added {
                self.try_meet(b, false, meter);
            }
            if self.rev_goal.is_some() {
                let env = Env {
                    map: &self.map,
                    metric: &self.metric,
                    cfg: &self.cfg,
                };
                let slice = self.slice(meter, self.cfg.t_root, call);
                self.rev
                    .rewire_root(&env, slice, self.cfg.new_rewiring, meter);
            }
        }
    }

    /// Records the goal joining the forward tree and retires the reverse tree.
    fn goal_joined<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>) {
        if self.stats.goal_found_at.is_none() {
            self.stats.goal_found_at = Some(meter.now());
            self.stats.nodes_at_goal = Some(self.fwd.tree.len());
        }
        self.fwd.restart_goal_sweep();
        if self.rev_goal.take().is_some() {
            self.rev.clear();
        }
    }

    /// Meet test for a node just added to one tree (`forward` tells which) against the other,
    /// and graft on success (module docs).
    fn try_meet<C: Clock + ?Sized>(&mut self, new: NodeId, forward: bool, meter: &Meter<'_, C>) {
        const PAIRS: usize = 16;
        let (this, other) = if forward {
            (&*self.fwd, &*self.rev)
        } else {
            (&*self.rev, &*self.fwd)
        };
        let p = this.pos(new);
        let c_new = this.cost(new);
        let sigma = self.cfg.sigma;
        // The PAIRS cheapest candidates, kept sorted by total cost.
        let mut best: heapless::Vec<(Cost, NodeId), PAIRS> = heapless::Vec::new();
        let mut seen = 0u32;
        let _ = other
            .index
            .for_each_within(p, sigma, other.tree.positions(), |id, d2| {
                seen += 1;
                let c_other = other.cost(id);
                let total = Cost {
                    length: c_new.length + libm::sqrtf(d2) + c_other.length,
                    blocked: c_new.blocked || c_other.blocked,
                };
                let at = best.partition_point(|(c, _)| *c <= total);
                if at < PAIRS {
                    if best.is_full() {
                        best.pop();
                    }
                    let _ = best.insert(at, (total, id));
                }
                core::ops::ControlFlow::Continue(())
            });
        meter.charge(seen + 4);
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
        };
        let Some(&(_, partner)) = best
            .iter()
            .find(|(_, id)| env.free(p, other.pos(*id), meter))
        else {
            return;
        };
        let (a, b) = if forward {
            (new, partner)
        } else {
            (partner, new)
        };
        if self.graft(a, b, meter) {
            self.stats.met = true;
            self.goal_joined(meter);
        }
    }

    /// Grafts the reverse tree's trunk from `b` to its root (the goal) below forward node `a`.
    /// Refused (returns false, changing nothing) when the forward arena lacks room.
    fn graft<C: Clock + ?Sized>(&mut self, a: NodeId, b: NodeId, meter: &Meter<'_, C>) -> bool {
        let rev = &self.rev.tree;
        let mut depth = 0usize;
        let mut v = Some(b);
        while let Some(x) = v {
            depth += 1;
            if depth > rev.len() {
                return false;
            }
            v = rev.parent(x);
        }
        if self.fwd.tree.len() + depth > N {
            self.full = true;
            return false;
        }
        meter.charge(4 * depth as u32);
        let mut parent = a;
        let mut blocked = false; // the meeting segment was tested free
        let mut v = Some(b);
        while let Some(x) = v {
            let pos = self.rev.pos(x);
            match self.fwd.insert(pos, parent, blocked) {
                Ok(id) => parent = id,
                Err(_) => return false,
            }
            blocked = self.rev.tree.edge_blocked(x).unwrap_or(false);
            v = self.rev.tree.parent(x);
        }
        if let Some(goal) = self.goal.as_mut() {
            goal.node = Some(parent);
        }
        true
    }
}
