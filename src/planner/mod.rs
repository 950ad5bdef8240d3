//! The real-time planner (paper Algorithm 1): a forward tree rooted at the agent, optionally a
//! reverse tree rooted at the goal, expansion and rewiring for `t_exp` per call, meet and graft
//! of the two trees, an agent-following root, and dynamic obstacles.
//!
//! # One `plan` call
//!
//! The call's budget `t_exp` starts when it is made. First the root follows the agent (below),
//! then, until `t_exp` has passed on the caller's clock (or `max_expansions` is
//! reached): expand the forward tree; then rewire it from the root for `t_root`; then, once the goal is
//! in it, goal rewiring for `t_goal` (and the second kind for another `t_goal` with the new
//! rewiring), then `path_shortcuts` shortcuts of the path (tuned) — RT-RRT* runs its random
//! rewiring for `t_goal` instead. While the goal is not in
//! the forward tree and bidirectional search is on, each step also expands the reverse tree
//! (rooted at the goal, growing towards the agent's position when the goal was set) and
//! rewires it from its root. With `rewire_after_join` ([`crate::Tactics`]), neither tree rewires
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
//! forward tree alone. With the `connect` tactic, a node that meets nothing within `sigma` (no free
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

mod follow;
mod meet;
mod step;
mod updates;

use rand_core::Rng;

use crate::clock::{Clock, Deadline, Meter};
use crate::config::{Base, Config, RewireMode};
#[cfg(feature = "roadmap")]
use crate::error::RoadmapError;
use crate::error::{InputError, ObstacleError, SetupError, TreeError};
use crate::expand::{Env, Near, Target, TreeStore};
use crate::geometry::Point;
use crate::map::{Circle, Map, Moving, ObstacleId};
use crate::metric::Metric;
use crate::motion::{Choice, choose};
use crate::rewire::Slice;
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

/// The agent stands at the root when it is within `e_max / AT_ROOT_DIV` of it (Algorithm 1's
/// "the agent reached the root"): the tree then re-roots at the path's next node.
const AT_ROOT_DIV: f32 = 10.0;

/// Storage for a planner's two trees: `N` nodes and `B` index buckets each. Keep it wherever
/// there is room (a `static`, a `Box`, the stack of a thread with a large stack); the planner
/// borrows it.
///
/// Its size is [`Storage::BYTES`]: 42 bytes per node of `N` and 4 per bucket of `B` (both
/// trees), plus 3,208 bytes on 32-bit targets (3,296 on 64-bit ones) that do not grow with
/// either, e.g. `Storage<2048, 256>` 90,248 bytes on a Cortex-M. Choose `N` for the longest
/// path through your map's narrowest passages (`host-sim run` names legs that need more
/// nodes than a tree holds) and `B` near `N / 8` (the index's buckets cover the map; more of
/// them mean fewer nodes scanned per query). An all-zero `Storage` is the empty one, so a
/// `static` of it goes to `.bss`: no flash and no stack copy.
#[derive(Clone, Debug, Default)]
pub struct Storage<const N: usize, const B: usize> {
    forward: TreeStore<N, B>,
    reverse: TreeStore<N, B>,
}

// The formula of `Storage::BYTES`, checked on every target the crate is compiled for (a
// thumbv7em build fails if it drifts).
#[cfg(any(target_pointer_width = "32", target_pointer_width = "64"))]
const _: () = {
    use core::mem::size_of;
    assert!(size_of::<Storage<64, 16>>() == Storage::<64, 16>::BYTES);
    assert!(size_of::<Storage<1024, 128>>() == Storage::<1024, 128>::BYTES);
    assert!(size_of::<Storage<2048, 256>>() == Storage::<2048, 256>::BYTES);
    assert!(size_of::<Storage<8192, 1024>>() == Storage::<8192, 1024>::BYTES);
};

impl<const N: usize, const B: usize> Storage<N, B> {
    /// Bytes per node of `N`, both trees: per tree a position (8), a cost (4), three links of
    /// 2 (parent, first child, next sibling), a flag byte and the spatial index's link (2).
    pub const BYTES_PER_NODE: usize = 42;
    /// Bytes per index bucket of `B`, both trees (a 2-byte list head each).
    pub const BYTES_PER_BUCKET: usize = 4;
    /// The bytes that grow with neither `N` nor `B` (per tree: the three bounded sweep queues
    /// of 256 ids and a few counters): 3,208 on 32-bit targets, 3,296 on 64-bit ones.
    pub const FIXED_BYTES: usize = if usize::BITS >= 64 { 3_296 } else { 3_208 };
    /// `size_of::<Storage<N, B>>()` by the formula `42 N + 4 B + FIXED_BYTES`: exact when `N`
    /// is a multiple of 8 and `B` of 4 (the crate checks it as it compiles, for every 32- and
    /// 64-bit target), otherwise within 16 bytes (alignment).
    pub const BYTES: usize = Self::BYTES_PER_NODE
        .saturating_mul(N)
        .saturating_add(Self::BYTES_PER_BUCKET.saturating_mul(B))
        .saturating_add(Self::FIXED_BYTES);

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
    /// Tree expansions done in this call (a step that grows both trees counts two).
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
    /// Whether the goal joined in the `roadmap` tactic's first step: over the straight
    /// segment or the attached roadmap's path (module [`crate::roadmap`]).
    #[cfg(feature = "roadmap")]
    pub roadmap: bool,
    /// States let in by the starving rule (a search whose density rule had turned away
    /// 1,024 states in a row admits a state no node is near: the expansion's starving rule),
    /// both trees (0 in 600 first-leg searches on the paper's maps).
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
    /// The roadmap attached ([`Planner::set_roadmap`]).
    #[cfg(feature = "roadmap")]
    roadmap: Option<crate::roadmap::Roadmap<'m>>,
    /// Where the current goal's roadmap search stands (`roadmap_join`).
    #[cfg(feature = "roadmap")]
    roadmap_stage: crate::roadmap::Stage,
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
        let dup_sq = crate::expand::duplicate_sq(map.grid().cell_size());
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
            #[cfg(feature = "roadmap")]
            roadmap: None,
            #[cfg(feature = "roadmap")]
            roadmap_stage: crate::roadmap::Stage::Idle,
        })
    }

    /// Attaches a roadmap baked for this map (module [`crate::roadmap`]; `None` detaches it):
    /// with the `roadmap` tactic on ([`crate::Tactics`]), the first call after each
    /// [`Planner::set_goal`] searches it for a first path. Refused when it was baked from
    /// another map or for another robot body ([`RoadmapError::WrongMap`]:
    /// [`crate::roadmap::Roadmap::fits`] [`Map::metric_grid`]) or has `N` nodes or more
    /// ([`RoadmapError::TooLarge`]: the search's scratch is the reverse arena's free slots).
    #[cfg(feature = "roadmap")]
    pub fn set_roadmap(
        &mut self,
        roadmap: Option<crate::roadmap::Roadmap<'m>>,
    ) -> Result<(), RoadmapError> {
        if let Some(rm) = &roadmap {
            if !rm.fits(&self.map.metric_grid()) {
                return Err(RoadmapError::WrongMap);
            }
            if rm.len() >= N {
                return Err(RoadmapError::TooLarge);
            }
        }
        self.roadmap = roadmap;
        // A search under way was of the roadmap before: it starts over with this one.
        if !matches!(self.roadmap_stage, crate::roadmap::Stage::Idle) {
            self.roadmap_stage = crate::roadmap::Stage::Due;
        }
        Ok(())
    }

    /// The planner's name in the paper's terms, from its configuration and its metric's kind
    /// ([`Metric::kind`]): `Bi-AM-RRT*(D)`, `AM-RRT*(E)-2 tuned`.
    pub fn name(&self) -> crate::config::PlannerName {
        self.cfg.name(self.metric.kind())
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
            return Err(crate::error::ConfigError {
                param: "t_exp",
                rule: crate::error::Rule::NonZero,
            });
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
        #[cfg(feature = "roadmap")]
        {
            self.roadmap_stage = crate::roadmap::Stage::Due;
        }
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
        #[cfg(feature = "roadmap")]
        {
            self.roadmap_stage = crate::roadmap::Stage::Idle;
        }
        self.rev_goal = None;
        self.rev.clear();
        self.fwd.restart_goal_sweep();
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
}

#[cfg(test)]
mod tests;
