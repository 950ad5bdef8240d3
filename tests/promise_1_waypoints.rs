//! Promise 1: every waypoint `plan` returns is reachable from the agent over a free segment,
//! or the agent holds and `Progress` says why. Each regression test here is a way it was broken
//! once (issue 7) and kept since. The rule is also checked at every call of other files' runs:
//! `body.rs` (a robot with a disc), `moving.rs` (obstacles that move), `live.rs` (live cells),
//! `ops_sequences.rs` (random operation sequences) and `common::checked::drive_checked`.
//! Deterministic: virtual clock, fixed seeds.

mod common;

use bi_am_rrt::builtin::{self};
use bi_am_rrt::error::InputError;
use bi_am_rrt::map::Circle;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Euclidean, MetricKind, Named, Point, Status, Storage, Wait};
use common::checked::{clock, drive_checked, drive_with_drops, planner};
use common::landmark_table;

/// Issue 7, case 1: a circle dropped on the segment between the agent and its waypoint (the
/// root) was never re-checked, and the agent drove through it (425 crossing moves and 1,512
/// starting inside a circle in 18 runs).
#[test]
fn regression_agent_sent_through_a_new_circle() {
    let mut failures = Vec::new();
    let mut totals = (0, 0, 0);
    for s in [&builtin::OPEN, &builtin::MAZE, &builtin::BUG_TRAP] {
        let table = landmark_table(&s.grid, 8);
        for name in ["Bi-AM-RRT*(E)", "Bi-AM-RRT*(D)", "AM-RRT*(E)"] {
            let named = Named::from_name(name).unwrap();
            let cfg = named.cfg;
            for seed in [1, 2] {
                let mut storage = Box::new(Storage::<2048, 512>::new());
                let t = if named.metric == MetricKind::Diffusion {
                    let m = DiffusionTable::new(&table).unwrap();
                    let mut p = planner(&mut storage, s, m, cfg, s.start, seed);
                    drive_with_drops(&mut p, s.goals[0])
                } else {
                    let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, seed);
                    drive_with_drops(&mut p, s.goals[0])
                };
                totals.0 += t.moves;
                totals.1 += t.unsafe_moves;
                totals.2 += t.reached as u32;
                if t.unsafe_moves > 0 || !t.reached {
                    failures.push(format!("{} {name} seed {seed}: {t:?}", s.name));
                }
            }
        }
    }
    eprintln!(
        "moves {}, unsafe {}, arrived {}/18",
        totals.0, totals.1, totals.2
    );
    assert!(failures.is_empty(), "{failures:#?}");
}

/// Issue 7, case 2: `plan()` accepted an agent with a wall between it and the root (maze,
/// agent (32.5, 0.5), root (5, 5)) and returned the root as waypoint across the wall; an agent
/// inside a circle was sent on too.
#[test]
fn regression_agent_not_where_the_tree_thinks() {
    let s = &builtin::MAZE;
    let mut storage = Box::new(Storage::<2048, 512>::new());
    let cfg = Config::bi_am_rrt();
    let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, 3);
    p.set_goal(s.goals[0]).unwrap();
    let clock = clock();
    for _ in 0..5 {
        p.plan(&clock, s.start).unwrap();
    }
    // Teleported past a wall.
    let away = Point::new(32.5, 0.5);
    assert!(!p.map().free_path(away, p.root_position()));
    let pr = p.plan(&clock, away).unwrap();
    assert!(
        pr.waypoint == away || p.map().free_path(away, pr.waypoint),
        "{pr:?}"
    );
    assert_eq!(
        p.stats().reanchored + p.stats().restarted,
        1,
        "the tree follows the agent"
    );
    // From there the agent still arrives, safely.
    let t = drive_checked(&mut p, s.goals[0], 1_500, 0.7, |_, _, _, _| {});
    assert!(t.reached && t.unsafe_moves == 0, "{t:?}");
    // Inside the static map: an error. Inside a circle: hold, and say why.
    assert_eq!(
        p.plan(&clock, Point::new(12.5, 12.5)).unwrap_err(),
        InputError::InObstacle
    );
    let here = p.root_position();
    let id = p.add_obstacle(Circle::new(here, 1.0)).unwrap();
    let pr = p.plan(&clock, here).unwrap();
    assert_eq!(pr.waypoint, here);
    assert_eq!(pr.status, Status::Waiting(Wait::AgentInObstacle));
    p.remove_obstacle(id).unwrap();
    p.tree().validate().unwrap();
}

/// Issue 7, case 8: with a circle enclosing the goal the agent waited, but only
/// `goal_cost.blocked` said so; and `path()` returned segments through circles unflagged.
#[test]
fn regression_no_why_when_waiting() {
    let s = &builtin::OPEN;
    let mut storage = Box::new(Storage::<2048, 512>::new());
    let cfg = Config::bi_am_rrt();
    let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, 4);
    let clock = clock();
    assert_eq!(p.plan(&clock, s.start).unwrap().status, Status::NoGoal);
    let goal = s.goals[0];
    p.set_goal(goal).unwrap();
    let mut agent = s.start;
    let mut pr = p.plan(&clock, agent).unwrap();
    for _ in 0..50 {
        if pr.goal_in_tree {
            break;
        }
        assert_eq!(pr.status, Status::Searching);
        pr = p.plan(&clock, agent).unwrap();
    }
    assert_eq!(pr.status, Status::Following);
    for _ in 0..5 {
        agent = agent.step_towards(p.plan(&clock, agent).unwrap().waypoint, 0.7);
    }
    // A circle around the goal: every path to it is blocked.
    let id = p.add_obstacle(Circle::new(goal, 2.0)).unwrap();
    let mut buf = vec![Point::ZERO; 2048];
    let info = p.path(&mut buf).unwrap();
    assert!(info.to_goal && info.blocked, "{info:?}");
    for _ in 0..20 {
        let pr = p.plan(&clock, agent).unwrap();
        assert_eq!(pr.status, Status::Waiting(Wait::PathBlocked));
        assert!(p.map().free_path(agent, pr.waypoint) || pr.waypoint == agent);
        agent = agent.step_towards(pr.waypoint, 0.7);
    }
    p.remove_obstacle(id).unwrap();
    let t = drive_checked(&mut p, goal, 500, 0.7, |_, _, _, _| {});
    assert!(t.reached && t.unsafe_moves == 0, "{t:?}");
    assert!(t.statuses.contains(&Status::Following), "{t:?}");
}
