//! Planner configuration: the base algorithm, the two switches of the paper (bidirectional
//! search, new rewiring), the parameters of its Table 2 and the tuned planner's tactics. The
//! 20 planners of the paper's Table 1 are configurations of the one planner, each with the
//! kind of metric it runs with (`names.rs`); every value is in one table (`params.rs`).

use core::time::Duration;

use crate::error::ConfigError;

mod names;
mod params;
mod tactics;
pub use names::{Named, PlannerName};
pub use params::{NAMED_SET_VISITS, PARAMS, Param, SetError, Value, param, set};
pub use tactics::Tactics;

/// The base real-time planner.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Base {
    /// RT-RRT* (Naderi et al., 2015): goal-directed sampling on the segment from the goal's
    /// nearest node, an adaptive neighbourhood radius, random rewiring instead of goal
    /// rewiring; the metric only chooses the nearest node, and only when the Euclidean-nearest
    /// node's segment to the sample is blocked. Departures from the AM-RRT* reference's RT-RRT*
    /// (issue 24): `Nearest` is Euclidean-first for RT-RRT*(D) (the reference always takes the
    /// node nearest by `d_A`); the goal line starts at the Euclidean-nearest node (the
    /// reference: the `d_A`-nearest); steering stops at `e_max` and gives up when blocked (the
    /// reference goes all the way, or to 99 % of the way to the obstacle; Table 2's `e_max` 5 m
    /// supports ours); Bi-RT-RRT*'s reverse tree gets root rewiring only, no random rewiring;
    /// the new rewiring (`-2`) can change only root rewiring (Algorithm 4), RT-RRT* having no
    /// goal rewiring.
    RtRrt,
    /// AM-RRT* (Armstrong et al., 2021): goal sampling, metric-guided nearest node and
    /// steering, goal rewiring sorted by the metric.
    AmRrt,
}

/// Which assisting metric a planner runs with, for its name: a metric names its kind
/// ([`crate::Metric::kind`]), so a configuration does not hold one.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum MetricKind {
    /// `d_E`, written (E).
    Euclidean,
    /// `d_D`, written (D).
    Diffusion,
    /// `d_G`, written (G).
    Geodesic,
    /// A metric of the caller's own, written (?).
    Other,
}

impl MetricKind {
    /// The letter used in planner names.
    pub const fn letter(self) -> char {
        match self {
            Self::Euclidean => 'E',
            Self::Diffusion => 'D',
            Self::Geodesic => 'G',
            Self::Other => '?',
        }
    }
}

/// How the rewiring phases share time with expansion.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum RewireMode {
    /// As the reference: after every expansion, root rewiring runs for its full `t_root` and
    /// goal (or random) rewiring for its full budget, sweeps restarting as often as they end.
    /// With thousands of nodes the budgets, not sampling, set the expansion rate.
    Faithful,
    /// After every expansion each rewiring phase visits at most `visits` nodes (and stops
    /// earlier when its time budget ends), resuming where it stopped at the next expansion.
    /// Rewiring work then grows with the expansions, not with wall time spent idle.
    PerExpansion {
        /// Node visits per phase and expansion.
        visits: u16,
    },
}

/// Which parts of Algorithms 4-6 and the Meet run exactly as printed (issue 24). The paper's
/// reading of each is available here, one switch per departure so each can be measured
/// apart; [`AsPrinted::NONE`] (both named sets) is this crate's reading, documented in
/// `rewire.rs`. Algorithm 4's printed cost test (`Cost(x_r1) + ...` against `Cost(x_r1)`)
/// can never pass and has no switch: its reading is always the true cost.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct AsPrinted {
    /// Algorithm 4 dequeues `x_r2` (the sweep takes two nodes per step, and `x_r2` gets no
    /// turn of its own); off: `x_r2` is peeked and visited later as `x_r1`.
    pub alg4_takes_x_r2: bool,
    /// Algorithm 6 pops (or dequeues) `x_r2`; off: peeked.
    pub alg6_takes_x_r2: bool,
    /// Algorithm 6's printed cost test: `x_r2` becomes the parent of `x_near` when
    /// `Cost(x_r2) + d_E(x_r1, x_near) + d_E(x_r1, x_r2) < Cost(x_near)` (the way through
    /// `x_r1`, an upper bound of the new edge's cost) over a free `x_near`-`x_r2` segment, and
    /// the frontier is the neighbours with a free segment to `x_r2`. Off: the new edge's true
    /// cost `Cost(x_r2) + d_E(x_r2, x_near)`, the frontier tested from `x_r1`.
    pub alg6_cost: bool,
    /// Algorithm 6's printed clearing test with its "or" read as "and" (read with "or" it
    /// empties the stack whenever it holds two nodes): `len(S) > 1` and `d_A(Second(S),
    /// goal) > d_A(x_r1, goal) + d_A(x_r1, x_r2)`. Off: `d_A(top(S), goal) > d_A(x_r1,
    /// goal)`, the first kind's test.
    pub alg6_clear: bool,
    /// The paper's Meet ("true when the Euclidean distance between T_f and T_r is less than
    /// sigma and there is no obstacle blocking it") tests every pair within `sigma` for a
    /// free segment: after the 16 cheapest pairs (by the joined path's cost) the others in
    /// index order, until a free one or the call's deadline. Off: the 16 cheapest only, so a
    /// new node whose cheap partners are all behind a wall waits for the next one (issue 24;
    /// measured to make no difference, `docs/results/printed/README.md`).
    pub meet_all_pairs: bool,
    /// Algorithm 4 enqueues `x_near` only when `FreePath(x_near, x_r1)` (the printed `If`
    /// holds the enqueue too). Off: every unseen neighbour is enqueued, as the first kind
    /// enqueues them.
    pub alg4_free_enqueue: bool,
    /// Algorithm 5 runs Algorithm 6 only while `len(Q) > 2` or `len(S) > 2`, and Algorithm 6
    /// takes `x_r1` and `x_r2` from the stack when `len(S) > 2`, else from the queue; with
    /// shorter lists the second phase ends (the printed loop idles to its end). Off: the
    /// second kind also runs on shorter lists (`x_r1` from the stack when it holds more than
    /// two nodes or the queue fewer than two, `x_r2` then possibly none).
    pub alg5_gate: bool,
    /// Algorithm 6's clearing test (`S = []`) follows the ellipse test for every `x_r1`, also
    /// one outside the ellipse (and the first kind's, as AM-RRT*'s reference runs it). Off:
    /// a node outside the ellipse is skipped before the test.
    pub alg6_clear_outside: bool,
}

impl AsPrinted {
    /// This crate's reading of every part (the named sets).
    pub const NONE: Self = Self {
        alg4_takes_x_r2: false,
        alg6_takes_x_r2: false,
        alg6_cost: false,
        alg6_clear: false,
        meet_all_pairs: false,
        alg4_free_enqueue: false,
        alg5_gate: false,
        alg6_clear_outside: false,
    };
    /// Every part as printed.
    pub const ALL: Self = Self {
        alg4_takes_x_r2: true,
        alg6_takes_x_r2: true,
        alg6_cost: true,
        alg6_clear: true,
        meet_all_pairs: true,
        alg4_free_enqueue: true,
        alg5_gate: true,
        alg6_clear_outside: true,
    };
    /// The switches' names, as `host-sim --as-printed` takes them.
    pub const NAMES: [&'static str; 8] = [
        "alg4-take",
        "alg6-take",
        "alg6-cost",
        "alg6-clear",
        "meet-all-pairs",
        "alg4-free",
        "alg5-gate",
        "alg6-clear-outside",
    ];

    /// Sets the switch named `name` (one of [`AsPrinted::NAMES`]); whether the name is known.
    pub fn set(&mut self, name: &str, on: bool) -> bool {
        let field = match name {
            "alg4-take" => &mut self.alg4_takes_x_r2,
            "alg6-take" => &mut self.alg6_takes_x_r2,
            "alg6-cost" => &mut self.alg6_cost,
            "alg6-clear" => &mut self.alg6_clear,
            "meet-all-pairs" => &mut self.meet_all_pairs,
            "alg4-free" => &mut self.alg4_free_enqueue,
            "alg5-gate" => &mut self.alg5_gate,
            "alg6-clear-outside" => &mut self.alg6_clear_outside,
            _ => return false,
        };
        *field = on;
        true
    }
}

/// Growth: sampling, steering and the meeting of the two trees.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Search {
    /// `e_max`: longest edge added by an expansion, and the `Nearby` radius, in metres.
    pub e_max: f32,
    /// Steering step while the tree's goal is not in it (the first solution), in metres; 0 =
    /// `e_max` (the paper). Edges stay free whatever their length; `Nearby` keeps `e_max`.
    pub e_search: f32,
    /// `sigma`: connection distance of the two trees, in metres.
    pub sigma: f32,
    /// Candidates drawn by the stochastic steering (replaces the reference's 2 ms `t_steer`).
    pub steer_candidates: u16,
    /// Rejection-sampling attempts for one free sample before the expansion is skipped.
    pub sample_attempts: u16,
    /// Probability threshold above which the goal (or RT-RRT*'s goal line) is sampled while
    /// the goal is not in the tree (paper: 0.7).
    pub p_goal: f32,
    /// Below this probability a uniform state is sampled, above it the informed ellipse once
    /// the goal is in the tree (reference: 0.7 / 1.5; the paper prints 0.5).
    pub p_uniform: f32,
    /// Once the goal is in the tree, the probability that a sample is drawn in the `e_max`
    /// disc around a node of the current path instead (RRT*-Smart's beacons, Nasir et al.
    /// 2013: after the shortcuts, the path's nodes are its corners, where a new node can still
    /// shorten it); 0 = never (the paper).
    pub p_beacon: f32,
    /// Once the goal is in the tree, the probability that a sample is drawn in a narrow
    /// passage of the informed ellipse instead: a free cell with walls on both sides within
    /// `e_max / 16` along its row or its column, found by rejection among up to
    /// `4 sample_attempts` draws (the first free draw when none is narrow). A slit of a few
    /// cells in a drawn wall is a region uniform sampling almost never reaches, and the
    /// shortest path often goes through it (issue 26: nav2's warehouse). A narrow sample
    /// that the nearest node's step does not reach is added as it is, below a neighbour
    /// within `e_max` that sees it (none: no node), not steered to. Nothing is drawn on
    /// a map whose cells are coarser than `e_max / 16`: the paper's 1 m maps never draw.
    /// 0 = never (the paper).
    pub p_gap: f32,
}

/// Rewiring and the root's moves.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Rewiring {
    /// `t_root`: root rewiring budget per expansion.
    pub t_root: Duration,
    /// `t_goal` (AM-RRT*) or `t_rand` (RT-RRT*): goal or random rewiring budget per expansion
    /// (goal rewiring gets it twice with the new rewiring: once per kind).
    pub t_goal: Duration,
    /// How the rewiring phases share time with expansion.
    pub mode: RewireMode,
    /// Path nodes offered their grandparent as parent per expansion once the goal is in the
    /// tree (Theta*'s shortcut; module `rewire`); 0 = none (the paper).
    pub path_shortcuts: u16,
    /// Longest step of the root along the path, in metres: the root is the agent's next
    /// waypoint, and the agent must reach it before it can turn, so when the path's next edge
    /// is longer (search steps, connections, shortcuts and rewiring make long straight
    /// edges) a node this far along it becomes the root instead, and the root moves on past
    /// nodes the agent already stands on; a goal that changes then finds the agent at most
    /// this far from where it can turn. With a step, the root also moves only along a path
    /// to the goal (not towards the node nearest a goal not yet joined, unless the arena is
    /// full and the search stuck: [`crate::planner::STUCK_EXPANSIONS`]), and with
    /// `path_shortcuts` the node after the next one is first offered the root as parent. 0 =
    /// to the next node whatever its distance, also while searching (the paper).
    pub root_step: f32,
}

/// What one `plan` or `grow` call may spend, and how often it reads the clock.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Budget {
    /// `t_exp`: expansion time per `plan` call.
    pub t_exp: Duration,
    /// Hard cap on tree expansions per call, whatever the clock says (a frozen clock still
    /// gives bounded calls). Each tree's expansion counts, so a step that grows both trees
    /// counts two (Algorithm 1 calls `Expend` once per tree, each with its rewiring); the
    /// count may end one over the cap, as a step is not split.
    pub max_expansions: u32,
    /// Hard cap on the work of one call, in work units (one grid cell tested, node visited
    /// or metric evaluated; about 12 ns each on the development machine and about 200
    /// instructions on a Cortex-M4F): once reached, every budget of the call reads as spent,
    /// whatever the clock says. The default, 25,000,000, is twice the paper's `t_exp` of
    /// 150 ms on the development machine. See [`crate::Planner::plan`] for the bound.
    pub max_work: u32,
    /// Work units between two clock readings of the deadline checks (see
    /// [`crate::clock::Meter::reading_every`]); 0 reads the clock at every check (the paper's
    /// implementation). The call then overruns `t_exp` by at most this much work more.
    pub clock_every: u32,
    /// Above `clock_every`: the readings are paced by what they cost
    /// ([`crate::clock::Meter::paced`]), at most this many work units apart (and never more
    /// than 0.25 ms of work at the slowest rate measured), so that a reading costs under 1 %
    /// of the work between two; `clock_every` apart while a reading's cost is not measurable
    /// (a virtual clock), down to [`crate::clock::MIN_PACED`] for a cycle counter. 0 (or at
    /// most `clock_every`): every `clock_every` units (the paper).
    pub clock_every_max: u32,
}

/// Where the arena's nodes go: the density rule and the trades of a full arena.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Memory {
    /// `n_max`: node density limit within the neighbourhood.
    pub n_max: u16,
    /// Density limit for new states inside the informed ellipse once the goal is in the tree
    /// (where a node can still shorten the path); 0 = `n_max` everywhere (the paper).
    pub n_max_informed: u16,
    /// With `density_trades` or `recycle_when_full` ([`Tactics`]): a leaf is traded (full
    /// arena, or a neighbourhood the density rule holds) only while at least this many other nodes share its spatial-index bucket
    /// (about `e_max` square), so every part of the map the tree has reached keeps that many
    /// nodes for the goals that come next instead of giving them all to the current path; 0 =
    /// no such rule. Capped at `N / (2 x buckets)` so the cover holds at most half the arena
    /// (none with 256 nodes on a 60 m map, 2 with 8,192 nodes on the 100 m and 200 m
    /// reference maps).
    pub recycle_cover: u16,
}

/// How the agent and the obstacles move (beyond the paper, whose obstacles stay put; module
/// [`crate::motion`]). All zero (the default): waypoints and tree edges are judged against
/// where the obstacles are now, as in the paper.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Motion {
    /// The agent's top speed in m/s: a waypoint `d` metres away must stay clear of every
    /// obstacle's sweep for `d / agent_speed` seconds (0: not stated, 0 s).
    pub agent_speed: f32,
    /// Seconds between two `plan` calls: the agent drives one waypoint for at most this long
    /// before the next call, and the waypoint must stay clear that much longer.
    pub period: f32,
    /// Seconds ahead a tree edge is judged (every edge, against each obstacle's sweep over
    /// `[0, horizon]`), and the time a waypoint must stay clear after the agent could reach
    /// it: the agent gives way to what is predicted to cross its way this soon.
    pub horizon: f32,
    /// Top speed of any obstacle in m/s: past its prediction's horizon an obstacle may be
    /// anywhere it can reach at this speed, and during the first `period` the agent keeps out
    /// of where any obstacle could be at this speed whatever it reported (so the agent never
    /// drives into an obstacle that turns without notice).
    pub obstacle_speed: f32,
}

impl Motion {
    /// Nothing stated: the paper's still obstacles.
    pub const NONE: Self = Self {
        agent_speed: 0.0,
        period: 0.0,
        horizon: 0.0,
        obstacle_speed: 0.0,
    };
}

/// Everything that configures a planner, on one screen: which planner (Table 1's two
/// switches on a base, and the tactics), then the groups of parameters; the metric is the
/// value passed to [`crate::Planner::new`]. [`Config::default`] is the tuned Bi-AM-RRT*(D);
/// [`Config::paper`] the paper's, and [`Named::table1`] all 20 of the paper's planners (each
/// a configuration and a kind of metric). Fit the lengths to a map with [`Config::for_grid`].
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Config {
    /// Base algorithm.
    pub base: Base,
    /// Grow a reverse tree from the goal until the trees meet (suffix `-1`, prefix `Bi-`).
    pub bidirectional: bool,
    /// The paper's new rewiring (Algorithms 4 and 6; suffix `-2`, prefix `Bi-`). On RT-RRT*
    /// only Algorithm 4 applies (it has no goal rewiring).
    pub new_rewiring: bool,
    /// The tuned planner's tactics ([`Tactics`]; the paper's planner: none).
    pub tactics: Tactics,
    /// Sampling, steering, meeting.
    pub search: Search,
    /// Rewiring and the root.
    pub rewiring: Rewiring,
    /// Time and work per call.
    pub budget: Budget,
    /// The density rule and trades.
    pub memory: Memory,
    /// Which parts of Algorithms 4-6 run as printed ([`AsPrinted`]; both named sets: none).
    pub as_printed: AsPrinted,
    /// How the agent and the obstacles move ([`Motion::NONE`] unless stated).
    pub motion: Motion,
    /// The robot's radius in metres (beyond the paper, which plans for a point: 0). The map
    /// must be inflated for at least this radius ([`crate::Map::with_body`],
    /// [`crate::Map::with_baked_body`]); the planner then keeps the whole disc clear of the
    /// walls, the live cells and the dynamic discs (each grown by the map's radius).
    pub robot_radius: f32,
    /// The clearance preference (beyond the paper: 0, every edge costs its length): how much
    /// more a metre costs at the body's edge than in open space, the cost falling to the
    /// length itself at the margin the map's clearance field was built for
    /// ([`crate::clearance`], [`crate::Map::with_clearance`]). 1 makes a metre along a wall
    /// cost up to 2; paths then keep off walls where the space allows, at some length. Needs
    /// the crate's `clearance` feature.
    pub clearance_weight: f32,
}

impl Default for Config {
    /// The tuned Bi-AM-RRT*(D): what a user gets without choosing (fit it to the map with
    /// [`Config::for_grid`]).
    fn default() -> Self {
        Self::bi_am_rrt().tuned()
    }
}

impl Config {
    /// The base planner with Table 2's parameters, unidirectional, original rewiring.
    pub const fn new(base: Base) -> Self {
        let (t_root, t_goal, n_max) = match base {
            Base::RtRrt => (3, 3, 12),
            Base::AmRrt => (2, 4, 20),
        };
        Self {
            base,
            bidirectional: false,
            new_rewiring: false,
            tactics: Tactics::NONE,
            search: Search {
                e_max: 5.0,
                e_search: 0.0,
                sigma: 30.0,
                steer_candidates: 24,
                sample_attempts: 64,
                p_goal: 0.7,
                p_uniform: 0.7 / 1.5,
                p_beacon: 0.0,
                p_gap: 0.0,
            },
            rewiring: Rewiring {
                t_root: Duration::from_millis(t_root),
                t_goal: Duration::from_millis(t_goal),
                mode: RewireMode::PerExpansion {
                    visits: NAMED_SET_VISITS,
                },
                path_shortcuts: 0,
                root_step: 0.0,
            },
            budget: Budget {
                t_exp: Duration::from_millis(150),
                max_expansions: 20_000,
                max_work: 25_000_000,
                clock_every: 0,
                clock_every_max: 0,
            },
            memory: Memory {
                n_max,
                n_max_informed: 0,
                recycle_cover: 0,
            },
            as_printed: AsPrinted::NONE,
            motion: Motion::NONE,
            robot_radius: 0.0,
            clearance_weight: 0.0,
        }
    }

    /// The paper's proposal, Bi-AM-RRT*(D) with Table 2's parameters (labelled as the
    /// paper's: no [`Tactics`]).
    pub const fn paper() -> Self {
        Self::bi_am_rrt()
    }

    /// The tuned version of a configuration: the same planner (base, metric, Table 1's
    /// switches) with every tactic on ([`Tactics::TUNED`]) and these parameters,
    /// measured against the paper's (`docs/notebook/against-ompl.md`):
    /// - `clock_every` 256 and `clock_every_max` 8,192: the deadlines read the clock at most
    ///   every 256 work units instead of 50-80 times per expansion, and the readings are paced
    ///   by what they cost: a CPU-time clock (about 0.5 us a reading here) is read every few
    ///   thousand units (at most 8,192, about 100 us), a cycle counter every few dozen (tens
    ///   of us on a 168 MHz Cortex-M4F), a virtual clock still every 256;
    /// - rewiring visits 4 nodes per phase and expansion instead of 24: three times the
    ///   expansions, the same rewiring work per second;
    /// - `e_search` 20 m: long steps until the first solution (the edges are tested free as
    ///   any other; rewiring shortens them later);
    /// - 16 steering candidates, spread evenly in angle (as well as 24 independent draws);
    /// - `n_max_informed` 4 `n_max`: the tree densifies inside the informed ellipse after the
    ///   density rule has saturated the rest of the map;
    /// - `recycle_cover` 2: trades never take one of the last two nodes of a spatial-index
    ///   bucket: a cover of every part of the map reached stays for the next goals;
    /// - `p_goal` 0.5: half the samples are the goal while it is not in the tree (the paper
    ///   samples it 30 % of the time);
    /// - `path_shortcuts` 4: the path straightens between its corner nodes (Theta*'s step);
    /// - `p_beacon` 0.2: a fifth of the samples fall near the path's nodes (its corners);
    /// - `p_gap` 0.4: of the other informed samples, two in five are drawn in the ellipse's
    ///   narrow passages (on maps fine enough to have any: cells of at most `e_max / 16`),
    ///   and one the nearest node's step does not reach becomes a node where it was drawn;
    /// - `root_step` `e_max`: the root (the agent's next waypoint) advances at most `e_max`
    ///   at a time along the long edges the shortcuts make, only along a path to the goal,
    ///   and takes the path's node after next as child first when that is shorter.
    pub const fn tuned(mut self) -> Self {
        self.tactics = Tactics::TUNED;
        self.budget.clock_every = 256;
        self.budget.clock_every_max = 8192;
        self.rewiring.mode = RewireMode::PerExpansion { visits: 4 };
        self.search.e_search = 20.0;
        self.search.steer_candidates = 16;
        self.memory.n_max_informed = self.memory.n_max.saturating_mul(4);
        self.memory.recycle_cover = 2;
        self.search.p_goal = 0.5;
        self.rewiring.path_shortcuts = 4;
        self.search.p_beacon = 0.2;
        self.search.p_gap = 0.4;
        self.rewiring.root_step = self.search.e_max;
        self
    }

    /// The configuration with its lengths fitted to a map of `width_m` x `height_m` metres
    /// in cells of `cell_m` (the rule that follows the map, [`length_scale`]): `e_max`,
    /// `sigma`, `e_search` and `root_step` are multiplied by the map's length scale, and the
    /// three steps are kept at least [`MIN_STEP_CELLS`] cells long. On maps 100-200 m across
    /// (the paper's) the scale is exactly 1 and nothing changes, bit for bit; a 20 m map at
    /// 0.05 m gets a fifth of Table 2's lengths (`e_max` 1 m, `sigma` 6 m), a 400 m map twice
    /// them. Counts (`n_max`, candidates) and times do not depend on the map's size.
    pub fn for_map(mut self, width_m: f32, height_m: f32, cell_m: f32) -> Self {
        let k = length_scale(width_m.max(height_m));
        let floor = if cell_m.is_finite() && cell_m > 0.0 {
            MIN_STEP_CELLS * cell_m
        } else {
            0.0
        };
        let step = |len: f32| {
            if len > 0.0 { (len * k).max(floor) } else { len }
        };
        self.search.e_max = step(self.search.e_max);
        self.search.e_search = step(self.search.e_search);
        self.rewiring.root_step = step(self.rewiring.root_step);
        self.search.sigma *= k;
        self
    }

    /// [`Config::for_map`] for this grid's size and cell.
    pub fn for_grid(self, grid: &crate::map::OccupancyGrid<'_>) -> Self {
        self.for_map(grid.width_m(), grid.height_m(), grid.cell_size())
    }

    /// RT-RRT* (with the Euclidean metric) or RT-RRT*(D) (with a diffusion table).
    pub const fn rt_rrt() -> Self {
        Self::new(Base::RtRrt)
    }

    /// AM-RRT*(E/D/G), with the metric passed to the planner.
    pub const fn am_rrt() -> Self {
        Self::new(Base::AmRrt)
    }

    /// Bi-RT-RRT* / Bi-RT-RRT*(D): both switches on.
    pub const fn bi_rt_rrt() -> Self {
        Self::rt_rrt()
            .with_bidirectional(true)
            .with_new_rewiring(true)
    }

    /// Bi-AM-RRT*(E/D/G): both switches on (the paper's proposal).
    pub const fn bi_am_rrt() -> Self {
        Self::am_rrt()
            .with_bidirectional(true)
            .with_new_rewiring(true)
    }

    /// With bidirectional search on or off.
    pub const fn with_bidirectional(mut self, on: bool) -> Self {
        self.bidirectional = on;
        self
    }

    /// The steering step while a tree's goal is not in it: `e_search`, or `e_max` when that
    /// is 0.
    pub fn search_step(&self) -> f32 {
        if self.search.e_search > 0.0 {
            self.search.e_search
        } else {
            self.search.e_max
        }
    }

    /// With the new rewiring on or off.
    pub const fn with_new_rewiring(mut self, on: bool) -> Self {
        self.new_rewiring = on;
        self
    }

    /// With the connection distance `sigma`.
    pub const fn with_sigma(mut self, sigma: f32) -> Self {
        self.search.sigma = sigma;
        self
    }

    /// With a rewiring mode.
    pub const fn with_rewire_mode(mut self, mode: RewireMode) -> Self {
        self.rewiring.mode = mode;
        self
    }

    /// Checks every value against its rule in the parameter table ([`PARAMS`], in its
    /// order); the error names the first value out of range and its rule. A configuration
    /// that passes gives a planner that grows: `t_exp` is not zero, `e_max` is finite and
    /// positive, `sigma` finite and not negative, `n_max`, the sampling and steering counts and
    /// both per-call caps at least 1, the four probabilities in `[0, 1]`, and the motion's
    /// speeds, period and horizon, the body's radius and weight finite and not negative.
    pub fn validate(&self) -> Result<(), ConfigError> {
        params::check(self)
    }

    /// The paper's name of this configuration run with a metric of kind `metric` (a
    /// `Display` value; [`crate::Planner::name`] gives the name with the planner's metric).
    pub const fn name(&self, metric: MetricKind) -> PlannerName {
        PlannerName(Named { metric, cfg: *self })
    }
}

/// Map extents (longest side, metres) between which Table 2's lengths apply as printed: the
/// paper's maps are 100 m and 200 m across.
pub const PAPER_EXTENT_M: (f32, f32) = (100.0, 200.0);

/// Shortest steering step [`Config::for_map`] gives, in cells: a step of a cell or two would
/// make the tree crawl on a coarse grid.
pub const MIN_STEP_CELLS: f32 = 4.0;

/// The length scale of a map `extent_m` across (its longest side): 1 within
/// [`PAPER_EXTENT_M`], `extent / 100` below it, `extent / 200` above it, so the lengths are
/// continuous in the extent, proportional to it off the paper's range and Table 2's on it. A
/// non-finite or non-positive extent gives 1.
pub fn length_scale(extent_m: f32) -> f32 {
    let (lo, hi) = PAPER_EXTENT_M;
    if !(extent_m.is_finite() && extent_m > 0.0) {
        1.0
    } else if extent_m < lo {
        extent_m / lo
    } else if extent_m > hi {
        extent_m / hi
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests;
