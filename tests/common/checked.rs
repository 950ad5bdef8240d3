//! The waypoint rule checked at every call and every move (issue 7's harness): a planner on
//! a built-in scenario with a 5 ms budget, driven towards a goal while circles are dropped
//! and removed.

use std::collections::VecDeque;
use std::time::Duration;

use bi_am_rrt::builtin::Scenario;
use bi_am_rrt::{Circle, Config, Map, Metric, Planner, Point, Status, Storage};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

pub use super::{K, clock};

pub fn planner<'s, M: Metric, const N: usize, const B: usize>(
    storage: &'s mut Storage<N, B>,
    s: &'static Scenario,
    metric: M,
    cfg: Config,
    start: Point,
    seed: u64,
) -> Planner<'s, 'static, M, XorShiftRng, N, B, K> {
    let mut cfg = cfg.with_sigma(s.sigma);
    cfg.budget.t_exp = Duration::from_millis(5);
    Planner::new(
        storage,
        Map::new(s.grid),
        metric,
        XorShiftRng::seed_from_u64(seed),
        cfg,
        start,
    )
    .unwrap()
}

#[derive(Debug, Default)]
pub struct Tally {
    pub calls: u32,
    pub moves: u32,
    pub unsafe_moves: u32,
    pub reached: bool,
    pub statuses: Vec<Status>,
}

/// Drives the agent `speed` metres towards each waypoint as soon as it is given, checking the
/// waypoint rule after every call and every move against the obstacles present;
/// `between(planner, agent, call)` runs after each move (to drop or remove obstacles).
pub fn drive_checked<M: Metric, R: Rng, const N: usize, const B: usize>(
    p: &mut Planner<'_, '_, M, R, N, B, K>,
    goal: Point,
    max_calls: u32,
    speed: f32,
    mut between: impl FnMut(&mut Planner<'_, '_, M, R, N, B, K>, Point, Point, u32),
) -> Tally {
    let clock = clock();
    let mut agent = p.root_position();
    p.set_goal(goal).unwrap();
    let mut t = Tally::default();
    for call in 0..max_calls {
        let pr = p.plan(&clock, agent).unwrap();
        t.calls += 1;
        p.tree().validate().expect("forward tree");
        p.reverse_tree().validate().expect("reverse tree");
        if t.statuses.last() != Some(&pr.status) {
            t.statuses.push(pr.status);
        }
        assert!(
            pr.waypoint == agent || p.map().free_path(agent, pr.waypoint),
            "call {call}: waypoint {:?} not reachable from {agent:?}: {pr:?}",
            pr.waypoint
        );
        if pr.waypoint == agent && agent != goal {
            assert!(
                matches!(pr.status, Status::Waiting(_) | Status::Searching),
                "holding without a reason: {pr:?}"
            );
        }
        let step = agent.step_towards(pr.waypoint, speed);
        if step != agent {
            t.moves += 1;
            if !p.map().free_path(agent, step) {
                t.unsafe_moves += 1;
            }
        }
        agent = step;
        if pr.goal_in_tree && agent == goal {
            t.reached = true;
            break;
        }
        between(p, agent, pr.waypoint, call);
    }
    t
}

/// Every 3 calls a disc of radius 0.5 lands on the midpoint of agent -> waypoint; each disc
/// leaves again 12 calls later.
pub fn drive_with_drops<M: Metric, R: Rng, const N: usize, const B: usize>(
    p: &mut Planner<'_, '_, M, R, N, B, K>,
    goal: Point,
) -> Tally {
    let mut live = VecDeque::new();
    drive_checked(p, goal, 1_500, 0.7, |p, agent, waypoint, call| {
        while live.front().is_some_and(|&(at, _)| call >= at + 12) {
            let (_, id) = live.pop_front().unwrap();
            p.remove_obstacle(id).unwrap();
        }
        if call % 3 == 0 && agent != waypoint {
            let c = Circle::new(agent.lerp(waypoint, 0.5), 0.5);
            if !c.contains(goal)
                && let Ok(id) = p.add_obstacle(c)
            {
                live.push_back((call, id));
            }
        }
    })
}
