//! The agent protocol of the papers' benchmarks, in the core so that the simulator, the tests
//! and the firmware example drive a planner the same way:
//!
//! 1. the goal is set at time 0 (on the caller's clock);
//! 2. `plan` is called again and again with the agent's position;
//! 3. *search time* is the time until the goal joined the forward tree (read by the planner at
//!    that moment, not at the end of the call);
//! 4. the agent starts moving once the goal is in the tree and `wait` has passed, then moves
//!    `speed` metres towards the current waypoint per call (stopping on it when closer; with
//!    [`Protocol::move_when_blocked`], the AM-RRT* reference's rule, an agent whose path is
//!    blocked drives on along it);
//! 5. every motion segment is checked against the live cells and the dynamic obstacles where
//!    they are, by exact distances rather than the planner's own test ([`Map::body_clear`]):
//!    a segment along which the robot's disc (a point without a body) comes nearer an
//!    occupied cell than its radius counts as a collision (the agent moves anyway, as a robot
//!    whose planner failed would);
//! 6. the run ends when the goal is in the tree and the agent stands on it, or after
//!    `max_calls` calls (or, with `stop_when_found`, once the goal has joined the tree).

use core::time::Duration;

use rand_core::Rng;

use crate::clock::Clock;
use crate::error::InputError;
use crate::geometry::Point;
#[allow(unused_imports)] // the module docs link to it
use crate::map::Map;
use crate::metric::Metric;
use crate::planner::{Planner, Progress};

/// Parameters of the protocol.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Protocol {
    /// Metres moved towards the waypoint per `plan` call (papers: 0.7).
    pub speed: f32,
    /// Time the agent waits before it starts (papers: 0.25 s), counted from the goal joining
    /// the tree, or from the goal being set with `wait_from_set`.
    pub wait: Duration,
    /// Count `wait` from when the goal is set, as the AM-RRT* reference's benchmark does
    /// (`time.time() - goal_start_time > 0.25`); the agent still waits for the goal to join.
    /// Off: from the join (this crate's protocol until issue 24, kept as the default so the
    /// results stay comparable).
    pub wait_from_set: bool,
    /// Calls before the run is abandoned.
    pub max_calls: u32,
    /// End the run after the call in which the goal joined the tree (search time only).
    pub stop_when_found: bool,
    /// The AM-RRT* reference's agent rule (Figs. 7 and 10 as the papers ran them): when the
    /// forward tree's path to the goal becomes blocked (its cost crosses an obstacle), the
    /// agent drives on along that path as it stood then (its root and up to [`AHEAD`] - 1 of
    /// its nodes, `e_max / 8` apart at least), whatever its blocked flags, instead of moving
    /// to `plan`'s waypoint, until it stands clear of every obstacle with the tree's path
    /// free again (or is past those nodes); then it moves to the waypoint again. Every
    /// segment that is not clear counts as a collision. The planner itself is unchanged (it
    /// re-roots at an agent it cannot reach), so the protocol keeps the path. Off (this
    /// crate's rule, promise 1): the agent moves to the waypoint, and holds where none is
    /// clear.
    pub move_when_blocked: bool,
}

impl Default for Protocol {
    fn default() -> Self {
        Self {
            speed: 0.7,
            wait: Duration::from_millis(250),
            wait_from_set: false,
            max_calls: 3_000,
            stop_when_found: false,
            move_when_blocked: false,
        }
    }
}

/// What a run measured.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct RunResult {
    /// The agent stood on the goal before `max_calls`.
    pub reached: bool,
    /// Clock ticks from setting the goal until it joined the forward tree.
    pub search_ticks: Option<u64>,
    /// Distance the agent travelled, in metres.
    pub travelled: f32,
    /// Motion segments that were not free.
    pub collisions: u32,
    /// `plan` calls made.
    pub calls: u32,
    /// Forward tree size when the goal joined.
    pub nodes_at_goal: Option<usize>,
    /// Clock ticks from setting the goal to the end of the call in which it joined (the
    /// reference's definition: it reads the time after `plan` returns).
    pub search_ticks_call_end: Option<u64>,
    /// Forward tree size at the end of the call in which the goal joined (the reference's
    /// definition of nodes at goal).
    pub nodes_at_call_end: Option<usize>,
    /// Cost of the tree's path from the root to the goal when the agent started moving (the
    /// root may already be a node ahead of the agent: it follows the agent's path).
    pub cost_at_start: Option<f32>,
    /// The last call's report.
    pub last: Option<Progress>,
}

/// Runs the protocol from the planner's root to `goal`. `on_call(planner, agent, call)` runs
/// after every call (to drop obstacles, record pictures, check invariants, ...). Errors only
/// when the goal is refused.
pub fn run_to_goal<'s, 'm, M, R, C, F, const N: usize, const B: usize, const K: usize>(
    planner: &mut Planner<'s, 'm, M, R, N, B, K>,
    clock: &C,
    goal: Point,
    protocol: &Protocol,
    mut on_call: F,
) -> Result<RunResult, InputError>
where
    M: Metric,
    R: Rng,
    C: Clock + ?Sized,
    F: FnMut(&mut Planner<'s, 'm, M, R, N, B, K>, Point, u32),
{
    let mut agent = planner.root_position();
    let t0 = clock.now();
    planner.set_goal(goal)?;
    let wait = clock.ticks(protocol.wait);
    let mut res = RunResult::default();
    // The reference's rule: the path kept when it became blocked, while it stays blocked.
    let mut ahead: Option<Ahead> = None;
    for call in 0..protocol.max_calls {
        let p = planner.plan(clock, agent)?;
        res.calls = call.saturating_add(1);
        res.last = Some(p);
        if let Some(found) = planner.stats().goal_found_at {
            res.search_ticks.get_or_insert(found.saturating_sub(t0));
            res.nodes_at_goal = planner.stats().nodes_at_goal;
            if res.search_ticks_call_end.is_none() {
                res.search_ticks_call_end = Some(clock.now().saturating_sub(t0));
                res.nodes_at_call_end = Some(planner.tree().len());
            }
            let from = if protocol.wait_from_set { t0 } else { found };
            if clock.now() >= from.saturating_add(wait) {
                if res.cost_at_start.is_none() {
                    res.cost_at_start = p.goal_cost.map(|c| c.length);
                }
                // Blocked: the tree's path crosses an obstacle; or the agent, driving along
                // the kept path, is inside one (the planner then has no path from it).
                let blocked = protocol.move_when_blocked
                    && (p.goal_cost.is_some_and(|c| c.blocked)
                        || (ahead.is_some() && !planner.map().body_clear(agent, agent)));
                let target = if blocked {
                    ahead
                        .get_or_insert_with(|| Ahead::of(planner))
                        .next(agent)
                        .unwrap_or(p.waypoint)
                } else {
                    ahead = None;
                    p.waypoint
                };
                let step = agent.step_towards(target, protocol.speed);
                if !planner.map().body_clear(agent, step) {
                    res.collisions = res.collisions.saturating_add(1);
                }
                res.travelled += agent.dist(step);
                agent = step;
            }
        }
        on_call(planner, agent, call);
        if protocol.stop_when_found && res.search_ticks.is_some() {
            break;
        }
        if p.goal_in_tree && agent == goal {
            res.reached = true;
            break;
        }
    }
    Ok(res)
}

/// Nodes of a path the reference's agent keeps ([`Protocol::move_when_blocked`]), at least
/// `e_max / 8` apart: at least 8 `e_max` of path, far past an obstacle that blocks it.
pub const AHEAD: usize = 64;

/// The first [`AHEAD`] nodes of the forward tree's path to the goal, its root first, and how
/// many the agent has passed.
#[derive(Clone, Copy, Debug)]
struct Ahead {
    points: [Point; AHEAD],
    len: usize,
    passed: usize,
}

impl Default for Ahead {
    fn default() -> Self {
        Self {
            points: [Point::ZERO; AHEAD],
            len: 0,
            passed: 0,
        }
    }
}

impl Ahead {
    /// The path's nodes from the root, nearest first (at most one step per tree node).
    fn of<M, R, const N: usize, const B: usize, const K: usize>(
        planner: &Planner<'_, '_, M, R, N, B, K>,
    ) -> Self
    where
        M: Metric,
        R: Rng,
    {
        let tree = planner.tree();
        let mut a = Self::default();
        let Some(mut node) = planner.goal_node() else {
            return a;
        };
        let gap = planner.config().search.e_max / 8.0;
        // Walking up from the goal to the root, the last AHEAD nodes met (goal side first),
        // each at least `gap` from the one kept before it (the root always kept).
        for _ in 0..=tree.len() {
            let Some(p) = tree.position(node) else {
                break;
            };
            let last = a.len.checked_sub(1).and_then(|i| a.points.get(i));
            let up = tree.parent(node);
            if up.is_some() && last.is_some_and(|q| q.dist(p) < gap) {
                // Too near the node kept before it.
            } else if a.len < AHEAD {
                if let Some(slot) = a.points.get_mut(a.len) {
                    *slot = p;
                }
                a.len = a.len.saturating_add(1);
            } else {
                a.points.rotate_left(1);
                if let Some(slot) = a.points.last_mut() {
                    *slot = p;
                }
            }
            match up {
                Some(up) => node = up,
                None => break,
            }
        }
        // The root first.
        if let Some(path) = a.points.get_mut(..a.len) {
            path.reverse();
        }
        a
    }

    /// The point to drive to from `agent`: the first one not yet reached.
    fn next(&mut self, agent: Point) -> Option<Point> {
        while self.passed < self.len && self.points.get(self.passed) == Some(&agent) {
            self.passed = self.passed.saturating_add(1);
        }
        self.points
            .get(self.passed)
            .filter(|_| self.passed < self.len)
            .copied()
    }
}
