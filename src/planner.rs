//! The real-time planner (paper Algorithm 1): a forward tree rooted at the agent, optionally a
//! reverse tree rooted at the goal, expansion and rewiring for `t_exp` per call, meet and graft
//! of the two trees, an agent-following root, and dynamic obstacles.
//!
//! # One `plan` call
//!
//! The call's budget `t_exp` starts when it is made. First the root follows the agent (below),
//! then, until `t_exp` has passed on the caller's clock (or `max_expansions_per_call` is
//! reached): expand the forward tree; then rewire it from the root for `t_root`; then, once the goal is
//! in it, goal rewiring for `t_goal` (and the second kind for another `t_goal` with the new
//! rewiring), then `path_shortcuts` shortcuts of the path (tuned) — RT-RRT* runs its random
//! rewiring for `t_goal` instead. While the goal is not in
//! the forward tree and bidirectional search is on, each step also expands the reverse tree
//! (rooted at the goal, growing towards the agent's position when the goal was set) and
//! rewires it from its root. With `rewire_while_searching` off (tuned), neither tree rewires
//! from its root until the goal has joined.
//!
//! Following the agent: the path is read from the root to the goal (or, before the goal
//! joins, to the node `Nearest` the goal). If the agent is within `e_max / 10` of the root and
//! the path's first edge is free, the tree is re-rooted at the path's next node (an O(N) cost
//! update, done before the expansions so that it spends the budget instead of overrunning it,
//! and so that this call's rewiring already works from the new root; when that finds no next
//! node, it is tried once more after the expansions, which may have joined the goal). The root
//! is the waypoint returned. (The agent must also see that node over a free segment; otherwise it first
//! finishes its way to the root, so it never cuts a corner.)
//!
//! # The waypoint rule (safety)
//!
//! Before planning, a call checks that the agent can reach the root over a segment free of the
//! map and of every circle. When it cannot (a circle dropped between them, or an agent that is
//! not where the tree thinks) the agent's position becomes the root: a node there joins the
//! tree below the cheapest node it sees past the map within `e_max` (the edge flagged blocked
//! when a circle crosses it), or the forward tree restarts at the agent when no node is in
//! sight. After planning, the waypoint is checked once more: the agent's own position is
//! returned instead when the root is not reachable, and [`Status`] says why the agent holds.
//!
//! # Meet and graft
//!
//! Every node added to either tree is checked against the other tree: among the nodes within
//! `sigma`, the 16 pairs with the lowest total cost `Cost_f(a) + d_E(a, b) + Cost_r(b)` are
//! tested for a free segment in cost order, and the first free one is taken. The reverse tree's
//! trunk (from `b` to the goal) is then grafted below `a`, each edge keeping its blocked flag,
//! so the goal joins the forward tree; the reverse tree is emptied and search continues with the
//! forward tree alone. In the tuned profile, a node that meets nothing within `sigma` (no free
//! pair, or a refused graft) makes the other tree walk straight towards it from its nearest
//! node (not one whose segment the meet test already found blocked), in free steps of
//! `e_search` (RRT-Connect's greedy step, at most 32 nodes); reaching it is a meet. With
//! [`crate::AsPrinted::meet_all_pairs`] the pairs after the 16 cheapest are tested too (the
//! paper's Meet). Search
//! time is read when the goal joins, not at the end of the call.
//!
//! # Dynamic obstacles
//!
//! Adding or removing one re-flags every edge of both trees (blocked when it meets any
//! circle), recomputes all costs and restarts every rewiring sweep from the root. Because costs
//! compare blocked-last, rewiring moves blocked nodes onto any free branch the tree holds, and
//! the returned path leaves the obstacle as soon as such a branch exists. The agent never gets a
//! waypoint across a blocked edge: it waits at the root until rewiring has found a way around.
//!
//! # Moving obstacles (beyond the paper)
//!
//! An obstacle may carry a velocity and a horizon ([`crate::map::Moving`]); the caller submits
//! each one's state before a call ([`Planner::update_obstacle`], O(K), applied at the start
//! of the next call: the edges are re-flagged, O(N K) work charged to that call, and the
//! sweeps restart only where a flag changed). Tree edges are judged against each obstacle's
//! sweep over the motion's `horizon` ([`crate::config::Motion`]; the stated rule: every edge,
//! near the root or far ahead, against the same window), so the path passes behind a walking
//! person rather than in front. The waypoint rule generalises as module [`crate::motion`]
//! states: the waypoint's segment stays clear of every sweep for the drive at the agent's top
//! speed, the period until the next call and the horizon; otherwise the agent goes as far as
//! is clear, gives way ([`Wait::GivingWay`]), evades ([`Status::Evading`]) or, with nothing
//! clear, holds ([`Wait::Cornered`]). Within its first period a move never comes nearer any
//! obstacle than holding would, whatever the obstacle does within the stated top speed.
//!
//! # Live cells (beyond the paper)
//!
//! On a map with an overlay ([`crate::map::Overlay`]) the caller marks and clears cells
//! ([`Planner::set_cells`], O(cells)); the next call re-tests every edge of both trees whose
//! bounding box comes within a cell of the changed cells (a box test per edge, then the cells
//! of each edge near it, charged to that call) and sets the edge's *walled* flag, kept apart
//! from the obstacles' flag so that re-flagging for a circle never clears it. Costs treat a
//! walled edge as a blocked one (the paper's rule for circles): rewiring moves nodes off it, the
//! agent is never sent across it, and it reopens when its cells clear. New edges, the agent's
//! anchor, sampling and the waypoint rule read the live cells; a node in a marked cell is
//! nobody's `Nearest`; an agent in a marked cell holds. The assisting metric is not rebaked.

use rand_core::Rng;

use crate::clock::{Clock, Deadline, Meter};
use crate::config::{Base, Config, RewireMode};
use crate::error::{InputError, ObstacleError, SetupError, TreeError};
use crate::geometry::Point;
use crate::map::{Circle, Map, Moving, ObstacleId};
use crate::metric::Metric;
use crate::motion::{Choice, choose};
use crate::rewire::Slice;
use crate::search::{Env, Near, Target, TreeStore};
use crate::slots::{sat_u32, sort_small_by, units};
use crate::tree::{Cost, Edge, NodeId, Tree};

/// With a root step (`root_step`, [`Config::rewiring`]), the root waits for the goal to join
/// before it moves, unless the forward arena is full and the search has made this many expansions per
/// node of the arena without the goal: then it moves on towards the node nearest the goal, as
/// the paper's planners always do (liveness: a full tree that cannot move never joins).
pub const STUCK_EXPANSIONS: u64 = 4;

/// Most path nodes one call re-roots past while following the agent ([`Planner::plan`]): the
/// next waypoint and the nodes the agent already stands on.
pub const FOLLOW_STEPS: usize = 4;

/// Most pairs one meet test tries (the cheapest by total cost).
const MEET_PAIRS: usize = 16;

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

/// What the planner is doing, in words a firmware can act on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Status {
    /// No goal is set: the tree grows, the waypoint is the root.
    NoGoal,
    /// The goal is not in the tree yet; the waypoint leads towards the tree node nearest it.
    Searching,
    /// The goal is in the tree over a free path: follow the waypoints.
    Following,
    /// The agent stands on the goal.
    Arrived,
    /// The agent holds (the waypoint is where it is, or the node it is already heading to),
    /// for the reason given. Nothing is lost: the tree keeps growing and rewiring, and the
    /// agent goes on once the way is free.
    Waiting(Wait),
    /// The assisting metric places the goal at an infinite distance from the agent (a region
    /// its table cuts off): the tree keeps growing, but the metric cannot guide it there.
    Unreachable,
    /// A moving obstacle is predicted to reach the agent where it stands: the waypoint is a
    /// point off the path that stays clear longer (module [`crate::motion`]); the agent
    /// comes back to the path once the way is clear.
    Evading,
}

/// Why the agent holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Wait {
    /// Every path the tree holds to the goal crosses a dynamic obstacle or a marked cell;
    /// rewiring looks for a way around (or the obstacle may leave).
    PathBlocked,
    /// The agent stands inside a dynamic obstacle or an occupied live cell, or its body is
    /// closer to one (or to a wall) than its radius: any motion would cross it.
    AgentInObstacle,
    /// A dynamic obstacle lies between the agent and every tree node it could go to.
    AgentBlocked,
    /// The path changed in this call, and moving the root onto it (a re-rooting refreshes
    /// the cost of every node: milliseconds for thousands of nodes on a microcontroller)
    /// would have ended after the call's budget: the agent goes on at the next call.
    OutOfTime,
    /// A moving obstacle is predicted to cross the way to the next waypoint within the time
    /// the agent needs to drive it plus the motion's `period` and `horizon`
    /// ([`crate::config::Motion`]): the agent gives way where it stands.
    GivingWay,
    /// No move, holding included, stays clear of the obstacles' predicted sweeps for the
    /// drive alone: the agent holds (it drives into no obstacle; one may run into it).
    Cornered,
}

/// What a `plan` call did and where the agent should go.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Progress {
    /// The next waypoint: reachable from the agent's position over a segment free of the map
    /// and of every dynamic obstacle present, or the agent's own position when none is (then
    /// `status` says why).
    pub waypoint: Point,
    /// What the planner is doing.
    pub status: Status,
    /// Work units done in this call (see [`Planner::plan`] for the bound).
    pub work: u64,
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

/// What [`Planner::path`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct PathInfo {
    /// Points written, root first.
    pub len: usize,
    /// The path ends at the goal (false: at the tree node nearest it, or at the root).
    pub to_goal: bool,
    /// Some edge of the path crosses a dynamic obstacle: not a path to drive.
    pub blocked: bool,
}

/// Counters over the planner's life since the goal was set.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Stats {
    /// Clock tick at which the goal joined the forward tree.
    pub goal_found_at: Option<u64>,
    /// Forward tree size when the goal joined.
    pub nodes_at_goal: Option<usize>,
    /// Length of the path to the goal when it joined (the first solution's cost).
    pub first_cost: Option<f32>,
    /// Expansions of the forward tree since the goal was set.
    pub expansions: u64,
    /// Expansions of the reverse tree since the goal was set.
    pub reverse_expansions: u64,
    /// Whether the goal joined through a meet of the two trees.
    pub met: bool,
    /// Tree edges re-tested against the live cells because cells near them changed (both
    /// trees, since the goal was set).
    pub retested: u64,
    /// The joining segment of that meet: the forward node and the reverse node it grafted
    /// (the paper's Fig. 7b).
    pub meet: Option<[Point; 2]>,
    /// Times the agent was found off the tree's root (a dynamic obstacle between them, or the
    /// agent moved elsewhere) and the tree was re-rooted at the agent.
    pub reanchored: u32,
    /// Times no tree node could reach the agent and the forward tree restarted from it.
    pub restarted: u32,
    /// States let in by the starving rule (a search whose density rule had turned away
    /// [`crate::search::STARVING`] states in a row admits a state no node is near; module
    /// `search`), both trees (0 in 600 first-leg searches on the paper's maps).
    pub starving_admits: u32,
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
    /// The deadline of the current call (`t_exp`).
    call: Deadline,
    /// A step of [`Planner::follow`] was put off in this call: it would have ended after
    /// the deadline.
    deferred: bool,
    /// An obstacle was updated since the last call ([`Planner::update_obstacle`]): the next
    /// call re-flags the edges first.
    stale: bool,
    /// The rates the last call measured ([`Meter::rates`]) and the clock's ticks per second
    /// they were measured in: the next call predicts with them from its start.
    rate: (u64, (u64, u64)),
}

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// A planner at `start` on `map`. Errors name the problem: a configuration field out of
    /// range ([`Config::validate`]), a start that is not finite, outside the map or in an
    /// obstacle, or a map too large to index.
    pub fn new(
        storage: &'s mut Storage<N, B>,
        map: Map<'m, K>,
        metric: M,
        rng: R,
        cfg: Config,
        start: Point,
    ) -> Result<Self, SetupError> {
        cfg.validate()?;
        let (w, h) = (map.grid().width_m(), map.grid().height_m());
        // Squared distances must neither overflow across the map nor underflow at the
        // duplicate scale (1e-4 cell): cells from about 1e-15 m, maps up to about 1e19 m.
        let dup_sq = crate::search::duplicate_sq(map.grid().cell_size());
        if !(w * w + h * h).is_finite() || dup_sq < f32::MIN_POSITIVE {
            return Err(SetupError::Map);
        }
        // The map must be inflated for the body the configuration names (a larger radius is
        // conservative); the dynamic discs then grow by the map's radius.
        if cfg.robot_radius > map.radius() {
            return Err(SetupError::Body);
        }
        if cfg.clearance_weight > 0.0 && !(cfg!(feature = "clearance") && map.has_clearance()) {
            return Err(SetupError::Clearance);
        }
        map.check_point(start)?;
        metric
            .check_map(&map.metric_grid())
            .map_err(SetupError::Metric)?;
        let side = cfg.search.e_max.max(map.grid().cell_size());
        let mut map = map;
        let m = &cfg.motion;
        map.obstacles_mut().set_sweep(m.horizon, m.obstacle_speed);
        let radius = map.radius();
        map.obstacles_mut().set_pad(radius);
        let Storage { forward, reverse } = storage;
        for store in [&mut *forward, &mut *reverse] {
            if !store.index.reshape(w, h, side) {
                return Err(SetupError::Map);
            }
        }
        for store in [&mut *forward, &mut *reverse] {
            store.tree.set_clearance_weight(cfg.clearance_weight);
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
            deferred: false,
            rate: (0, (0, 0)),
            call: Deadline::NEVER,
            stale: false,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &Config {
        &self.cfg
    }

    /// Changes the time budget `t_exp` of the next calls (a caller that knows how much time it
    /// has this cycle). Refused, leaving it unchanged, when zero.
    pub fn set_t_exp(
        &mut self,
        t_exp: core::time::Duration,
    ) -> Result<(), crate::error::ConfigError> {
        if t_exp.is_zero() {
            return Err(crate::error::ConfigError::TExp);
        }
        self.cfg.budget.t_exp = t_exp;
        Ok(())
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
        self.stats = Stats::default();
        self.fwd.holes = 0;
        self.rev.holes = 0;
        self.begin_search(goal);
        Ok(())
    }

    /// Starts the search for `goal` from the current forward tree (goal not joined yet).
    fn begin_search(&mut self, goal: Point) {
        let root = self.root_position();
        self.goal = Some(Target {
            pos: goal,
            node: None,
        });
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

    /// Adds an obstacle that may move ([`crate::map::Moving`]; module [`crate::motion`]).
    pub fn add_moving_obstacle(&mut self, obstacle: Moving) -> Result<ObstacleId, ObstacleError> {
        let id = self.map.obstacles_mut().add_moving(obstacle)?;
        self.reflag();
        Ok(id)
    }

    /// Submits what is now known of an obstacle (its disc at the next call, velocity and
    /// horizon, as a perception stack reports it): O(K), nothing else is done until the next
    /// `plan` or `grow` call re-flags the edges (O(N K) work, charged to that call). The
    /// planner does not move obstacles by itself: submit each one's state before every call
    /// (a state not updated is predicted from where it was given).
    pub fn update_obstacle(
        &mut self,
        id: ObstacleId,
        obstacle: Moving,
    ) -> Result<(), ObstacleError> {
        self.map.obstacles_mut().update(id, obstacle)?;
        self.stale = true;
        Ok(())
    }

    fn reflag(&mut self) {
        self.reflag_trees(true);
    }

    /// Marks (`occupied`) or clears every cell of the rectangle with corners `a` and `b`
    /// (`(col, row)`, inclusive) in the live map ([`Map::set_cells`]: the map needs an
    /// overlay): O(cells) to submit; the next `plan` or `grow` call re-tests the edges of both
    /// trees near the changed cells (an edge crossing a marked cell is blocked like one
    /// through a circle, one whose cells cleared reopens) and charges that work. Returns how
    /// many cells changed. The diffusion table is not rebaked (docs/moving.md says what that
    /// costs).
    pub fn set_cells(
        &mut self,
        a: (u16, u16),
        b: (u16, u16),
        occupied: bool,
    ) -> Result<u32, crate::error::MapError> {
        self.map.set_cells(a, b, occupied)
    }

    /// Re-flags every edge of both trees against the obstacles; the rewiring sweeps restart
    /// (where a flag changed, or everywhere with `restart`).
    fn reflag_trees(&mut self, restart: bool) {
        self.stale = false;
        let obstacles = self.map.obstacles();
        for store in [&mut *self.fwd, &mut *self.rev] {
            let changed = store
                .tree
                .reflag_edges(|a, b| obstacles.blocks_segment(a, b));
            if changed || restart {
                store.restart_sweeps();
            }
        }
    }

    /// Applies the obstacle updates submitted since the last call: the edges are re-flagged,
    /// and the rewiring sweeps restart only where a flag changed.
    fn apply_updates<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>) {
        if self.stale {
            let k = self.map.obstacles().len().saturating_add(1);
            let nodes = self.fwd.tree.len().saturating_add(self.rev.tree.len());
            meter.charge(units(nodes.saturating_mul(k)));
            self.reflag_trees(false);
        }
        if let Some(changed) = self.map.take_changed() {
            self.rewall_trees(changed, meter);
        }
    }

    /// Re-tests, against the live cells, every edge of both trees whose cells may include one
    /// in `changed` (`[col0, row0, col1, row1]`); the rewiring sweeps restart where a flag
    /// changed. Work: a box test per edge, and the cells of each edge re-tested.
    fn rewall_trees<C: Clock + ?Sized>(&mut self, changed: [u16; 4], meter: &Meter<'_, C>) {
        let cells = self.map.live();
        let grid = cells.grid();
        let inv = 1.0 / grid.cell_size();
        // The changed box in metres, grown by a cell for the contact margin.
        let [c0, r0, c1, r1] = changed.map(f32::from);
        let (lo, hi) = (
            Point::new(c0 - 1.0, r0 - 1.0),
            Point::new(c1 + 2.0, r1 + 2.0),
        );
        let mut retested = 0u64;
        for store in [&mut *self.fwd, &mut *self.rev] {
            meter.charge(units(store.tree.len()));
            let changed = store.tree.rewall_edges(|a, b| {
                let (p, q) = (
                    Point::new(a.x * inv, a.y * inv),
                    Point::new(b.x * inv, b.y * inv),
                );
                let near = p.x.max(q.x) >= lo.x
                    && p.x.min(q.x) <= hi.x
                    && p.y.max(q.y) >= lo.y
                    && p.y.min(q.y) <= hi.y;
                near.then(|| {
                    // About the cells the segment crosses.
                    meter.charge(sat_u32((p.x - q.x).abs() + (p.y - q.y).abs() + 2.0));
                    retested = retested.saturating_add(1);
                    !cells.segment_free(a, b)
                })
            });
            if changed {
                store.restart_sweeps();
            }
        }
        self.stats.retested = self.stats.retested.saturating_add(retested);
    }

    /// Whether an agent at `p` stands inside a dynamic obstacle or a marked cell: any motion
    /// would cross it, so it holds.
    fn trapped(&self, p: Point) -> bool {
        self.map.obstacles().contains_now(p) || !self.map.live().point_free(p)
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
            call: Deadline::NEVER,
        };
        self.fwd.nearest(&env, goal.pos, meter)
    }

    /// Writes the tree's current path (root first) into `buf` and returns what it is: to the
    /// goal once it is in the tree, else to the tree node nearest the goal; just the root when
    /// no goal is set. The path is the tree's, not a promise: it may cross a dynamic obstacle
    /// (`blocked`) and, before the goal joins, it ends short of the goal (`to_goal` false).
    /// Only [`Progress::waypoint`] is checked against the agent's position.
    pub fn path(&self, buf: &mut [Point]) -> Result<PathInfo, TreeError> {
        let clock = crate::clock::FakeClock::new(1);
        let meter = Meter::new(&clock);
        let end = self
            .path_end(&meter)
            .or(self.fwd.tree.root())
            .ok_or(TreeError::UnknownNode)?;
        let len = self.fwd.tree.path_points(end, buf)?;
        Ok(PathInfo {
            len,
            to_goal: self.goal_node() == Some(end),
            blocked: self.fwd.tree.cost(end).is_some_and(|c| c.blocked),
        })
    }

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
    /// rest of one short piece of an expansion step: measured on a Cortex-M4F model
    /// (`scripts/firmware-sequence.sh`, office, all six goals, 2 x 2,048 nodes, 150 ms),
    /// 0.67 ms (paper's set) and 0.40 ms (tuned) at worst. And whatever the clock (even
    /// one that never advances) a call does at most `max_work + W_step` units, where `W_step` is the most work between two checks:
    /// one expansion or one rewiring visit. Both are `O(N + e_max / cell)`: an expansion does
    /// at most one metric nearest scan (N metric evaluations), one meet test (N visits and 16
    /// segment tests), one graft (4 units per grafted node, at most N), one re-rooting (N)
    /// and a bounded number of segment tests (`sample_attempts`, `steer_candidates`, 64
    /// parent candidates, and in the tuned profile the greedy connection's up to 32 steps),
    /// each `2 + 2 e / cell` units at most (`e` the longer of `e_max` and `e_search`; a meet,
    /// connect or shortcut segment at most `2 + (width + height) / cell`; with a robot body of
    /// radius `r`, a test near a wall also charges its exact stage, a unit per row of a band
    /// `2 r / cell + 1` cells wide and per occupied cell it measures), in the tuned
    /// profile up to 64 rewires around the new node, and with `path_shortcuts` that many
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
        let pending = follow.is_some_and(|a| a.dist(root) <= self.cfg.search.e_max / 10.0);
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
            let joined = self.goal_node().is_some();
            self.step(meter, steps);
            expansions = expansions.saturating_add(1);
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

    /// The call's report. With an agent position, the waypoint rule is enforced here, last.
    fn progress<C: Clock + ?Sized>(
        &self,
        agent: Option<Point>,
        expansions: u32,
        advanced: bool,
        meter: &Meter<'_, C>,
    ) -> Progress {
        let goal_node = self.goal_node();
        let goal_cost = goal_node.and_then(|g| self.fwd.tree.cost(g));
        let root = self.root_position();
        let at = agent.unwrap_or(root);
        let arrived = goal_node.is_some() && self.goal.is_some_and(|g| g.pos == at);
        let trapped = agent.is_some() && self.trapped(at);
        // The waypoint rule (module `motion`): the root when it is clear, else a nearer point
        // on the way, else hold, else evade.
        let planned = if arrived { at } else { root };
        let choice = match agent {
            Some(a) if !trapped => {
                // The rule's tests of the obstacles (none to charge without obstacles: the
                // paper's check of one segment, as before).
                meter.charge(units(self.map.obstacles().len().saturating_mul(64)));
                choose(&self.map, &self.cfg.motion, a, planned)
            }
            Some(_) => Choice::Hold,
            None => Choice::Planned,
        };
        let waypoint = match choice {
            Choice::Planned => planned,
            Choice::Shortened(q) | Choice::Evade(q) => q,
            Choice::Hold | Choice::Cornered => at,
        };
        let status = match self.goal {
            None => Status::NoGoal,
            Some(_) if trapped => Status::Waiting(Wait::AgentInObstacle),
            Some(_) if arrived => Status::Arrived,
            Some(_) if matches!(choice, Choice::Cornered) => Status::Waiting(Wait::Cornered),
            Some(_) if matches!(choice, Choice::Evade(_)) => Status::Evading,
            Some(_)
                if matches!(choice, Choice::Hold)
                    && agent.is_some_and(|a| a != root && !self.map.free_now(a, root)) =>
            {
                Status::Waiting(Wait::AgentBlocked)
            }
            Some(_) if matches!(choice, Choice::Hold) && agent != Some(root) => {
                Status::Waiting(Wait::GivingWay)
            }
            Some(g) if !self.metric.distance(at, g.pos).is_finite() => Status::Unreachable,
            Some(_) if goal_node.is_none() => Status::Searching,
            Some(_) if goal_cost.is_some_and(|c| c.blocked) => Status::Waiting(Wait::PathBlocked),
            Some(_) if matches!(choice, Choice::Hold) => Status::Waiting(Wait::GivingWay),
            Some(_) if self.deferred && agent == Some(root) => Status::Waiting(Wait::OutOfTime),
            Some(_) => Status::Following,
        };
        Progress {
            waypoint,
            status,
            work: meter.work(),
            goal_in_tree: goal_node.is_some(),
            goal_cost,
            nodes: self.fwd.tree.len(),
            reverse_nodes: self.rev.tree.len(),
            expansions,
            advanced,
            tree_full: self.full,
        }
    }

    /// Makes sure the agent can reach the root: when a straight free segment does not join
    /// them, the agent's position becomes the root (see [`Planner::plan`]).
    fn anchor<C: Clock + ?Sized>(&mut self, agent: Point, meter: &Meter<'_, C>) {
        let root = self.root_position();
        meter.charge(12);
        if agent == root || self.map.free_now(agent, root) {
            return;
        }
        // The agent stands on a node: that node becomes the root.
        if let Some((q, d2)) = self.fwd.index.nearest(agent, self.fwd.tree.positions())
            && d2 < crate::search::duplicate_sq(self.map.grid().cell_size())
            && self.fwd.tree.set_root(q).is_ok()
        {
            meter.charge(units(N / 8));
            self.stats.reanchored = self.stats.reanchored.saturating_add(1);
            self.fwd.restart_sweeps();
            return;
        }
        // Candidates: nodes within e_max, cheapest first (edges crossing a circle last), joined
        // to the agent past the map.
        let mut near = Near::new();
        self.fwd
            .nearby(agent, self.cfg.search.e_max, &mut near, meter);
        let circles = self.map.obstacles();
        let crosses = |id: NodeId| circles.blocks_segment(self.fwd.pos(id), agent);
        let key = |id: NodeId| {
            self.fwd
                .cost(id)
                .extend(self.fwd.pos(id).dist(agent), crosses(id))
        };
        sort_small_by(&mut near, |&a, &b| key(a).cmp(&key(b)));
        let cells = self.map.live();
        let parent = near.iter().copied().find(|&id| {
            meter.charge(4);
            cells.segment_free(self.fwd.pos(id), agent)
        });
        let goal = self.goal.map_or(agent, |g| g.pos);
        let anchored = parent.is_some_and(|parent| {
            let blocked = self
                .map
                .obstacles()
                .blocks_segment(self.fwd.pos(parent), agent);
            let mut keep = [parent, self.goal_node().unwrap_or(parent)];
            if self.fwd.tree.is_full() {
                self.full = true;
                if !self.fwd.recycle(&mut self.rng, goal, &mut keep, meter) {
                    return false;
                }
                self.rename_goal(keep[1]);
            }
            let class = self.clearance_class(self.fwd.pos(keep[0]), agent, meter);
            let Ok(id) = self.fwd.insert(agent, keep[0], Edge { blocked, class }) else {
                return false;
            };
            meter.charge(units(N / 8));
            self.fwd.tree.set_root(id).is_ok()
        });
        if anchored {
            self.stats.reanchored = self.stats.reanchored.saturating_add(1);
            self.fwd.restart_sweeps();
        } else {
            // No node reaches the agent (or no room): the tree cannot serve it; start over here.
            self.stats.restarted = self.stats.restarted.saturating_add(1);
            self.fwd.reset(agent);
            if let Some(goal) = self.goal {
                self.begin_search(goal.pos);
            }
        }
    }

    /// After recycling in the forward tree: the goal node's id may have moved.
    fn rename_goal(&mut self, renamed: NodeId) {
        if let Some(g) = self.goal.as_mut()
            && g.node.is_some()
        {
            g.node = Some(renamed);
        }
    }

    /// Re-roots at the path's next node when the agent has reached the root; with a root
    /// step ([`Config::rewiring`]), on past nodes the agent already stands on (a short edge
    /// would hold it for a call), at most [`FOLLOW_STEPS`] nodes per call.
    ///
    /// A step starts only when it ends before `by` ([`Meter::affords`]): the call's deadline
    /// once the call has expanded, never at its start, where following is the progress every
    /// call makes (a `t_exp` shorter than a re-rooting then overruns by one).
    fn follow<C: Clock + ?Sized>(
        &mut self,
        agent: Point,
        meter: &Meter<'_, C>,
        by: Deadline,
    ) -> bool {
        let steps = if self.cfg.rewiring.root_step > 0.0 {
            FOLLOW_STEPS
        } else {
            1
        };
        let mut advanced = false;
        for _ in 0..steps {
            if !self.follow_once(agent, meter, by) {
                break;
            }
            advanced = true;
        }
        advanced
    }

    /// One step of [`Planner::follow`].
    fn follow_once<C: Clock + ?Sized>(
        &mut self,
        agent: Point,
        meter: &Meter<'_, C>,
        by: Deadline,
    ) -> bool {
        let root = self.root_position();
        if agent.dist(root) > self.cfg.search.e_max / 10.0 {
            return false;
        }
        // With a root step (tuned), the root moves only along a path to the goal: towards
        // the node nearest a goal not yet joined it could take the agent the wrong way just
        // before the goal joins (a search takes tens of microseconds). Unless the search is
        // stuck: a full arena that has made `STUCK_EXPANSIONS x N` expansions without the
        // goal finds it only by moving on, as the paper's planners do (the nodes left behind
        // become the ones recycled).
        let stuck = self.fwd.tree.is_full()
            && self.stats.expansions >= (N as u64).saturating_mul(STUCK_EXPANSIONS);
        if self.cfg.rewiring.root_step > 0.0 && self.goal_node().is_none() && !stuck {
            return false;
        }
        let Some(end) = self.path_end(meter) else {
            return false;
        };
        // The node after the root on the path to `end`, and the one after it: walk up from
        // `end`.
        let tree = &self.fwd.tree;
        let (mut next, mut after) = (end, None);
        for _ in 0..tree.len() {
            match tree.parent(next) {
                Some(p) if Some(p) == tree.root() => break,
                Some(p) => (next, after) = (p, Some(next)),
                None => return false,
            }
        }
        if tree.parent(next) != tree.root() || tree.edge_blocked(next) != Some(false) {
            return false;
        }
        // A re-rooting refreshes every cost in the tree (with a long first edge split first,
        // a subtree move): it starts only when it ends before `by`.
        if !meter.affords(self.reroot_nodes(), &by) {
            self.deferred = true;
            return false;
        }
        // With path shortcuts (tuned), the root is offered as parent to the node after
        // `next` first: the agent is about to commit to the path's first edge, which the
        // anytime shortcuts may not have reached yet (a goal that joins in a call leaves its
        // first edges as the search made them).
        let next = match after {
            Some(n2)
                if self.cfg.rewiring.path_shortcuts > 0 && self.shortcut_from_root(n2, meter) =>
            {
                n2
            }
            _ => next,
        };
        let next = self.split_long_edge(next, meter);
        // The agent is near the root, not always on it: it must see the next node in a
        // straight free line, or it first finishes its way to the root.
        if !self.map.free_path(agent, self.fwd.pos(next)) {
            return false;
        }
        meter.charge(units(self.fwd.tree.len()));
        let since = meter.now();
        if self.fwd.tree.set_root(next).is_err() {
            return false;
        }
        meter.timed_refresh(self.fwd.tree.len(), since);
        self.fwd.restart_sweeps();
        true
    }

    /// The nodes a step of [`Planner::follow`] refreshes at most: a re-rooting refreshes every
    /// node's cost, and a long first edge's split moves a subtree first.
    fn reroot_nodes(&self) -> u64 {
        (self.fwd.tree.len() as u64).saturating_mul(2)
    }

    /// Makes `node` a child of the root when the segment is free and that shortens its path
    /// (a Theta* shortcut at the root, by the rewiring step). Whether it did.
    fn shortcut_from_root<C: Clock + ?Sized>(
        &mut self,
        node: NodeId,
        meter: &Meter<'_, C>,
    ) -> bool {
        let Some(root) = self.fwd.tree.root() else {
            return false;
        };
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        self.fwd.try_rewire(&env, root, node, meter)
    }

    /// The root step ([`Config::rewiring`]): when the edge from the root to the path's next
    /// node `next` is longer than the step, a node that far along it becomes the next waypoint instead, so
    /// a goal that changes never finds the agent bound to a root far away. The edge was
    /// free, so are its parts. Returns the node to re-root at: `next` when the edge is short,
    /// the step 0, or the arena has no slot to give.
    fn split_long_edge<C: Clock + ?Sized>(&mut self, next: NodeId, meter: &Meter<'_, C>) -> NodeId {
        let Some(root) = self.fwd.tree.root() else {
            return next;
        };
        let (a, b) = (self.fwd.pos(root), self.fwd.pos(next));
        let step = self.cfg.rewiring.root_step;
        if step <= 0.0 || a.dist(b) <= step {
            return next;
        }
        let mut keep = [next, self.goal_node().unwrap_or(next)];
        if self.fwd.tree.is_full() {
            let toward = self.goal.map_or(b, |g| g.pos);
            if !self.fwd.recycle(&mut self.rng, toward, &mut keep, meter) {
                return next;
            }
            self.rename_goal(keep[1]);
        }
        let [next, _] = keep;
        let Some(root) = self.fwd.tree.root() else {
            return next;
        };
        // Both halves lie on the edge's line: they keep its clearance class.
        let edge = Edge {
            blocked: false,
            class: self.fwd.tree.edge_class(next).unwrap_or(0),
        };
        let Ok(mid) = self.fwd.insert(a.step_towards(b, step), root, edge) else {
            return next;
        };
        match self.fwd.tree.set_parent(next, mid, edge) {
            Ok(moved) => {
                meter.charge(units(moved).saturating_add(4));
                mid
            }
            // Cannot happen (`mid` is a new leaf); it would stay a harmless leaf.
            Err(_) => next,
        }
    }

    /// The clearance class of a new edge `a-b` (0 without a clearance preference), charged.
    fn clearance_class<C: Clock + ?Sized>(&self, a: Point, b: Point, meter: &Meter<'_, C>) -> u8 {
        if !cfg!(feature = "clearance") || self.cfg.clearance_weight <= 0.0 {
            return 0;
        }
        let (class, work) = self.map.clearance_class(a, b);
        meter.charge(work);
        class
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
        // Tuned: no root rewiring before the goal joins (the same first paths, less work).
        let tuned = self.cfg.profile.is_tuned();
        if !tuned || !searching {
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
            if self.rev_goal.is_some() && !tuned {
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
    fn goal_joined<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>) {
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

    /// Tuned profile: the other tree walks straight towards node `new` of one tree (`forward`
    /// tells which), and the two are grafted when it reaches it (module docs). `blocked`:
    /// nodes of the other tree whose segment to `new` the meet test found blocked (not
    /// tested again).
    fn connect<C: Clock + ?Sized>(
        &mut self,
        new: NodeId,
        forward: bool,
        blocked: &[NodeId],
        meter: &Meter<'_, C>,
    ) {
        if !self.cfg.profile.is_tuned() {
            return;
        }
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        let step = self.cfg.search_step();
        let pair = if forward {
            let p = self.fwd.pos(new);
            self.rev
                .connect(&env, p, step, blocked, meter)
                .map(|b| (new, b))
        } else {
            let p = self.rev.pos(new);
            self.fwd
                .connect(&env, p, step, blocked, meter)
                .map(|a| (a, new))
        };
        if let Some((a, b)) = pair {
            self.meet(a, b, meter);
        }
    }

    /// Grafts the reverse tree below forward node `a` at reverse node `b` (their segment tested
    /// free) and records the goal joining; returns whether the graft was made.
    fn meet<C: Clock + ?Sized>(&mut self, a: NodeId, b: NodeId, meter: &Meter<'_, C>) -> bool {
        let segment = [self.fwd.pos(a), self.rev.pos(b)];
        let met = self.graft(a, b, meter);
        if met {
            self.stats.met = true;
            self.stats.meet = Some(segment);
            self.goal_joined(meter);
        }
        met
    }

    /// Meet test for a node just added to one tree (`forward` tells which) against the other,
    /// and graft on success (module docs). `Ok` when the trees met; otherwise `Err` with the
    /// nodes of the other tree whose segment to `new` was found blocked (none when a free pair
    /// was found but the graft was refused).
    fn try_meet<C: Clock + ?Sized>(
        &mut self,
        new: NodeId,
        forward: bool,
        meter: &Meter<'_, C>,
    ) -> Result<(), heapless::Vec<NodeId, MEET_PAIRS>> {
        let (this, other) = if forward {
            (&*self.fwd, &*self.rev)
        } else {
            (&*self.rev, &*self.fwd)
        };
        let p = this.pos(new);
        let c_new = this.cost(new);
        let sigma = self.cfg.search.sigma;
        // The MEET_PAIRS cheapest candidates, kept sorted by total cost.
        let mut best: heapless::Vec<(Cost, NodeId), MEET_PAIRS> = heapless::Vec::new();
        let mut seen = 0u32;
        let _ = other
            .index
            .for_each_within(p, sigma, other.tree.positions(), |id, d2| {
                seen = seen.saturating_add(1);
                let c_other = other.cost(id);
                let total = Cost {
                    length: c_new.length + crate::geometry::sqrt(d2) + c_other.length,
                    blocked: c_new.blocked || c_other.blocked,
                };
                let at = best.partition_point(|(c, _)| *c <= total);
                if at < MEET_PAIRS {
                    if best.is_full() {
                        best.pop();
                    }
                    let _ = best.insert(at, (total, id));
                }
                core::ops::ControlFlow::Continue(())
            });
        meter.charge(seen.saturating_add(4));
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        let mut partner = best
            .iter()
            .find(|(_, id)| env.free(p, other.pos(*id), meter))
            .map(|&(_, id)| id);
        // The paper's Meet: any pair within sigma with a free segment (AsPrinted::meet_all_pairs).
        if partner.is_none() && self.cfg.as_printed.meet_all_pairs && best.is_full() {
            let call = self.call;
            let _ = other
                .index
                .for_each_within(p, sigma, other.tree.positions(), |id, _| {
                    if meter.expired(&call) {
                        return core::ops::ControlFlow::Break(());
                    }
                    meter.charge(1);
                    if best.iter().all(|&(_, b)| b != id) && env.free(p, other.pos(id), meter) {
                        partner = Some(id);
                        return core::ops::ControlFlow::Break(());
                    }
                    core::ops::ControlFlow::Continue(())
                });
        }
        let Some(partner) = partner else {
            let mut blocked = heapless::Vec::new();
            for &(_, id) in &best {
                let _ = blocked.push(id);
            }
            return Err(blocked);
        };
        let (a, b) = if forward {
            (new, partner)
        } else {
            (partner, new)
        };
        if self.meet(a, b, meter) {
            Ok(())
        } else {
            Err(heapless::Vec::new())
        }
    }

    /// Grafts the reverse tree's trunk from `b` to its root (the goal) below forward node `a`,
    /// recycling forward leaves when the arena lacks room. Refused (returns false) when the
    /// trunk cannot fit.
    fn graft<C: Clock + ?Sized>(&mut self, a: NodeId, b: NodeId, meter: &Meter<'_, C>) -> bool {
        let rev = &self.rev.tree;
        let mut depth = 0usize;
        let mut v = Some(b);
        while let Some(x) = v {
            depth = depth.saturating_add(1);
            if depth > rev.len() {
                return false;
            }
            v = rev.parent(x);
        }
        let mut parent = a;
        let need = self.fwd.tree.len().saturating_add(depth).saturating_sub(N);
        if need > 0 {
            // Make room: recycle forward leaves (never `a` or its ancestors, which have
            // children). Refused when the trunk alone would not fit.
            self.full = true;
            let goal = self.goal.map_or(self.rev.pos(b), |g| g.pos);
            if depth >= N {
                return false;
            }
            let mut keep = [parent];
            for _ in 0..need {
                if !self.fwd.recycle(&mut self.rng, goal, &mut keep, meter) {
                    return false;
                }
            }
            parent = keep[0];
        }
        meter.charge(units(depth).saturating_mul(4));
        // The meeting segment was tested free; each later edge keeps both of its flags (an
        // edge through a marked cell stays walled, or re-flagging for an obstacle would clear
        // it).
        // The meeting segment's clearance class is measured; the trunk's edges keep theirs.
        let (mut blocked, mut walled) = (false, false);
        let mut class = self.clearance_class(self.fwd.pos(parent), self.rev.pos(b), meter);
        let mut v = Some(b);
        while let Some(x) = v {
            let pos = self.rev.pos(x);
            match self.fwd.insert(pos, parent, Edge { blocked, class }) {
                Ok(id) => parent = id,
                Err(_) => return false,
            }
            if walled {
                self.fwd.tree.set_edge_walled(parent, true);
            }
            (blocked, walled) = self.rev.tree.edge_sources(x);
            class = self.rev.tree.edge_class(x).unwrap_or(0);
            v = self.rev.tree.parent(x);
        }
        if let Some(goal) = self.goal.as_mut() {
            goal.node = Some(parent);
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::clock::FakeClock;
    use crate::config::MetricKind;
    use crate::map::{OccupancyGrid, pack_grid};
    use crate::metric::Euclidean;
    use rand_core::SeedableRng;

    /// Issue 24, finding 7: Meet tested only the 16 cheapest pairs within `sigma`; with
    /// `meet_all_pairs` (the paper's Meet) a free pair further down the list joins the trees.
    /// A wall at x = 20 (y below 30); 16 cheap reverse nodes behind it, two dearer ones above
    /// it, in sight of the new forward node.
    #[test]
    fn meet_all_pairs_finds_a_free_pair_beyond_the_cheapest_sixteen() {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(40, 40)];
        pack_grid(&mut bits, 40, 40, |c, r| c == 20 && r < 30).unwrap();
        let grid = OccupancyGrid::new(&bits, 40, 40, 1.0).unwrap();
        for all in [false, true] {
            let mut storage = Storage::<64, 16>::new();
            let mut cfg = Config::bi_am_rrt(MetricKind::Euclidean).with_sigma(40.0);
            cfg.as_printed.meet_all_pairs = all;
            let rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
            let mut p = Planner::<_, _, 64, 16, 0>::new(
                &mut storage,
                Map::new(grid),
                Euclidean,
                rng,
                cfg,
                Point::new(10.0, 5.0),
            )
            .unwrap();
            p.set_goal(Point::new(30.0, 5.0)).unwrap();
            let root = p.fwd.tree.root().unwrap();
            let new = p.fwd.insert(Point::new(10.0, 34.0), root, false).unwrap();
            let rev_root = p.rev.tree.root().unwrap();
            for k in 0..16u8 {
                let y = 2.0 + 0.3 * f32::from(k);
                p.rev.insert(Point::new(21.5, y), rev_root, false).unwrap();
            }
            let up = p
                .rev
                .insert(Point::new(30.0, 36.0), rev_root, false)
                .unwrap();
            p.rev.insert(Point::new(25.0, 36.0), up, false).unwrap();
            let clock = FakeClock::nanos();
            let meter = Meter::new(&clock);
            p.call = Deadline::after(&clock, core::time::Duration::from_secs(1));
            let met = p.try_meet(new, true, &meter).is_ok();
            assert_eq!(met, all, "meet_all_pairs {all}");
            if all {
                assert!(p.goal_node().is_some(), "the goal joined through the meet");
            }
        }
    }

    /// Found in review before live edits landed: grafting the reverse trunk copied each
    /// edge's blocked flag as an obstacle's, so the next re-flagging for an obstacle cleared
    /// an edge that crosses a marked cell. The trunk's walled edge stays blocked after a
    /// circle is added elsewhere.
    #[test]
    fn regression_a_grafted_trunk_keeps_its_walled_edges() {
        let bits = [0u8; OccupancyGrid::bytes_needed(40, 40)];
        let grid = OccupancyGrid::new(&bits, 40, 40, 1.0).unwrap();
        let mut overlay = [0u8; OccupancyGrid::bytes_needed(40, 40)];
        let map = Map::new(grid).with_overlay(&mut overlay).unwrap();
        let mut storage = Storage::<64, 16>::new();
        let cfg = Config::bi_am_rrt(MetricKind::Euclidean).with_sigma(40.0);
        let rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
        let mut p = Planner::<_, _, 64, 16, 2>::new(
            &mut storage,
            map,
            Euclidean,
            rng,
            cfg,
            Point::new(5.0, 5.0),
        )
        .unwrap();
        p.set_goal(Point::new(35.0, 5.0)).unwrap();
        // Reverse trunk: goal <- (25, 5) <- (20, 5); a door closes between (25, 5) and the goal.
        let rev_root = p.rev.tree.root().unwrap();
        let mid = p
            .rev
            .insert(Point::new(25.0, 5.0), rev_root, false)
            .unwrap();
        let end = p.rev.insert(Point::new(20.0, 5.0), mid, false).unwrap();
        p.set_cells((30, 0), (30, 39), true).unwrap();
        let clock = FakeClock::nanos();
        let meter = Meter::new(&clock);
        p.apply_updates(&meter);
        assert_eq!(p.rev.tree.edge_sources(mid), (false, true));
        // The forward tree meets the trunk's far end.
        let root = p.fwd.tree.root().unwrap();
        let new = p.fwd.insert(Point::new(15.0, 5.0), root, false).unwrap();
        assert!(p.graft(new, end, &meter));
        let goal = p.goal_node().unwrap();
        assert_eq!(p.fwd.tree.edge_blocked(goal), Some(true));
        p.add_obstacle(Circle::new(Point::new(5.0, 35.0), 1.0))
            .unwrap();
        assert_eq!(
            p.fwd.tree.edge_blocked(goal),
            Some(true),
            "re-flagging cleared it"
        );
        assert!(p.fwd.cost(goal).blocked);
    }
}
