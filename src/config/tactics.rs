//! The tuned planner's tactics: engineering changes beyond the paper's Algorithms 1-6, each
//! with a name. The paper's planner runs with none of them ([`Tactics::NONE`]); the tuned one
//! ([`crate::Config::tuned`]) with all of them ([`Tactics::TUNED`]), the set that won in every
//! measurement (`docs/notebook/tuned-default.md`). Each can be
//! turned on or off alone (`host-sim ... 'NAME@connect=false'`), so each can be measured apart.

/// Which of the tuned planner's tactics run. Off, each part runs as the paper's algorithm
/// (or the AM-RRT* reference implementation) does.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Tactics {
    /// Steering candidates spread evenly in angle around the node
    /// ([`crate::geometry::DiscFan`]: a random first direction, then equal turns, each at a
    /// random radius) instead of independent draws in the disc: fewer candidates cover every
    /// direction, and one sine-cosine serves the whole batch.
    pub steer_fan: bool,
    /// `Nearest` tests the Euclidean-nearest node's view of the sample over the steering step
    /// only (`e_max`, or `e_search` while searching), not the whole way: a far sample (the
    /// goal behind a wall, a uniform state across the map) no longer costs a segment test as
    /// long as the map.
    pub nearest_step: bool,
    /// A segment tested in an expansion is not tested again in it (the steering's straight
    /// step after `nearest_step`'s test, the parent's segment after the steering's): the same
    /// decisions, less work.
    pub reuse_tests: bool,
    /// No root rewiring (either tree) before the goal joins: every expansion goes to growth
    /// while searching; the first paths were the same either way on the reference maps.
    pub rewire_after_join: bool,
    /// RRT-Connect's greedy step between the two trees while searching (Kuffner and LaValle):
    /// when a new node meets nothing within `sigma`, the other tree walks straight towards it
    /// in free steps until it sees it or a step is blocked.
    pub connect: bool,
    /// A node added inside the informed ellipse offers itself as parent to its neighbours
    /// (RRT*'s rewiring step) right away, besides the sweeps.
    pub rewire_new: bool,
    /// A neighbourhood inside the ellipse that the density rule holds trades its worst leaf
    /// (the highest `Cost(x) + d_E(x, goal)`) for a state that bounds a shorter path.
    pub density_trades: bool,
    /// A full arena trades a leaf that cannot improve the path for a new state inside the
    /// ellipse that can ([`crate::config::Memory::recycle_cover`] keeps a cover).
    pub recycle_when_full: bool,
    /// With [`crate::config::Rewiring::path_shortcuts`], a path node whose grandparent is
    /// hidden round a corner takes a new node on one of its two edges as parent, or its parent
    /// splits in two (module `rewire`): the path closes in on the obstacles' corners.
    pub corner_cuts: bool,
    /// The goal-rewiring sweep enqueues every unseen neighbour, as root rewiring does, without
    /// a segment test for the frontier (each rewire still tests its own segment): a quarter
    /// more expansions on a fine map, where that test was most of the sweep's work.
    pub open_frontier: bool,
    /// With a roadmap attached (`Planner::set_roadmap`, feature `roadmap`), a new goal's
    /// first step joins it over the straight segment when that is free, else over the
    /// roadmap's path, grafted as the first solution (module `roadmap`); the trees search as
    /// ever when it has none. Without a roadmap it does nothing.
    pub roadmap: bool,
}

impl Tactics {
    /// The paper's planner: none.
    pub const NONE: Self = Self {
        steer_fan: false,
        nearest_step: false,
        reuse_tests: false,
        rewire_after_join: false,
        connect: false,
        rewire_new: false,
        density_trades: false,
        recycle_when_full: false,
        corner_cuts: false,
        open_frontier: false,
        roadmap: false,
    };

    /// The tuned planner: all.
    pub const TUNED: Self = Self {
        steer_fan: true,
        nearest_step: true,
        reuse_tests: true,
        rewire_after_join: true,
        connect: true,
        rewire_new: true,
        density_trades: true,
        recycle_when_full: true,
        corner_cuts: true,
        open_frontier: true,
        roadmap: true,
    };

    /// Each tactic's name (the field's), in declaration order.
    pub const NAMES: [&'static str; 11] = [
        "steer_fan",
        "nearest_step",
        "reuse_tests",
        "rewire_after_join",
        "connect",
        "rewire_new",
        "density_trades",
        "recycle_when_full",
        "corner_cuts",
        "open_frontier",
        "roadmap",
    ];

    /// The switches in [`Tactics::NAMES`] order.
    pub const fn as_array(&self) -> [bool; 11] {
        [
            self.steer_fan,
            self.nearest_step,
            self.reuse_tests,
            self.rewire_after_join,
            self.connect,
            self.rewire_new,
            self.density_trades,
            self.recycle_when_full,
            self.corner_cuts,
            self.open_frontier,
            self.roadmap,
        ]
    }
}
