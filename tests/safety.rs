//! The core's promises, each broken once and kept since (issue 7): the waypoint rule, no panic
//! on accepted input, reachable goals join, and tiny capacities stay valid. Each regression
//! test is named after the bug it reproduces. Deterministic: virtual clock, fixed seeds.

mod common;

use std::collections::VecDeque;
use std::time::Duration;

use bi_am_rrt::builtin::{self, Scenario};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::error::{InputError, SetupError};
use bi_am_rrt::map::OccupancyGrid;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{
    Circle, Config, Euclidean, Map, Metric, MetricKind, Planner, Point, Status, Storage, Wait,
};
use common::landmark_table;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

const K: usize = 4;

fn clock() -> FakeClock {
    FakeClock::nanos().with_work_cost(30).with_step(10)
}

fn planner<'s, M: Metric, const N: usize, const B: usize>(
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
struct Tally {
    calls: u32,
    moves: u32,
    unsafe_moves: u32,
    reached: bool,
    statuses: Vec<Status>,
}

/// Drives the agent `speed` metres towards each waypoint as soon as it is given, checking the
/// waypoint rule after every call and every move against the obstacles present;
/// `between(planner, agent, call)` runs after each move (to drop or remove obstacles).
fn drive_checked<M: Metric, R: Rng, const N: usize, const B: usize>(
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

/// Issue 7, case 1: a circle dropped on the segment between the agent and its waypoint (the
/// root) was never re-checked, and the agent drove through it (425 crossing moves and 1,512
/// starting inside a circle in 18 runs).
#[test]
fn regression_agent_sent_through_a_new_circle() {
    let mut failures = Vec::new();
    let mut totals = (0, 0, 0);
    for s in [&builtin::OPEN, &builtin::MAZE, &builtin::BUG_TRAP] {
        let table = landmark_table(&s.grid, 8);
        for (name, cfg) in [
            ("Bi-AM-RRT*(E)", Config::bi_am_rrt(MetricKind::Euclidean)),
            ("Bi-AM-RRT*(D)", Config::bi_am_rrt(MetricKind::Diffusion)),
            ("AM-RRT*(E)", Config::am_rrt(MetricKind::Euclidean)),
        ] {
            for seed in [1, 2] {
                let mut storage = Box::new(Storage::<2048, 512>::new());
                let t = if cfg.metric == MetricKind::Diffusion {
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

/// Every 3 calls a disc of radius 0.5 lands on the midpoint of agent -> waypoint; each disc
/// leaves again 12 calls later.
fn drive_with_drops<M: Metric, R: Rng, const N: usize, const B: usize>(
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

/// Issue 7, case 2: `plan()` accepted an agent with a wall between it and the root (maze,
/// agent (32.5, 0.5), root (5, 5)) and returned the root as waypoint across the wall; an agent
/// inside a circle was sent on too.
#[test]
fn regression_agent_not_where_the_tree_thinks() {
    let s = &builtin::MAZE;
    let mut storage = Box::new(Storage::<2048, 512>::new());
    let cfg = Config::bi_am_rrt(MetricKind::Euclidean);
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

/// Issue 7, case 3: `OccupancyGrid::new(&[0], 2, 2, 1e19)` and `Planner::new` succeeded, then
/// `plan()` panicked in `f32::clamp` (the spatial index had overflowed to a 0 x 0 grid).
#[test]
fn regression_release_panic_on_an_accepted_huge_map() {
    static BITS: [u8; 1] = [0];
    for cell in [1.0e19f32, 1.0e30, 1.0e-30, 1.0e-3] {
        let grid = OccupancyGrid::new(&BITS, 2, 2, cell).unwrap();
        let mut storage = Box::new(Storage::<64, 8>::new());
        let mut cfg = Config::bi_am_rrt(MetricKind::Euclidean);
        cfg.search.e_max = cell * 0.7;
        let start = Point::new(cell * 0.5, cell * 0.5);
        let goal = Point::new(cell * 1.5, cell * 1.5);
        let made = Planner::<_, _, 64, 8, K>::new(
            &mut storage,
            Map::new(grid),
            Euclidean,
            XorShiftRng::seed_from_u64(1),
            cfg,
            start,
        );
        if cell != 1.0e-3 {
            // Squared distances would overflow (or vanish): refused, with a reason.
            assert_eq!(made.err(), Some(SetupError::Map), "cell {cell}");
            continue;
        }
        let mut p = made.unwrap();
        p.set_goal(goal).unwrap();
        let frozen = FakeClock::nanos().with_step(1_000);
        for _ in 0..20 {
            let pr = p.plan(&frozen, start).unwrap();
            assert!(pr.waypoint.is_finite());
        }
        p.tree().validate().unwrap();
        assert!(p.goal_node().is_some(), "cell {cell}: the goal joins");
    }
}

/// Issue 7, case 4: AM-RRT*(E) on the maze with the goal at the start (already a node) never
/// joined (the absolute duplicate test rejected it), and RT-RRT* never joined a goal 0.42 m
/// from the root (the density rule and the goal-line sampling kept it out).
#[test]
fn regression_reachable_goal_that_never_joins() {
    let s = &builtin::MAZE;
    let clock = clock();
    for seed in 1..=3 {
        let mut storage = Box::new(Storage::<2048, 512>::new());
        let cfg = Config::am_rrt(MetricKind::Euclidean);
        let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, seed);
        p.set_goal(s.goals[0]).unwrap();
        for _ in 0..20 {
            p.plan(&clock, s.start).unwrap();
        }
        p.set_goal(s.start).unwrap();
        let pr = p.plan(&clock, s.start).unwrap();
        assert!(
            pr.goal_in_tree,
            "seed {seed}: the goal at the root joins at once"
        );
        assert_eq!(pr.status, Status::Arrived);
    }
    let s = &builtin::OPEN;
    for seed in 1..=3 {
        let mut storage = Box::new(Storage::<2048, 512>::new());
        let cfg = Config::rt_rrt(MetricKind::Euclidean);
        let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, seed);
        // A dense neighbourhood around the root first.
        for _ in 0..30 {
            p.plan(&clock, s.start).unwrap();
        }
        let near = Point::new(s.start.x + 0.42, s.start.y);
        p.set_goal(near).unwrap();
        let joined = (0..50).any(|_| p.plan(&clock, s.start).unwrap().goal_in_tree);
        assert!(joined, "seed {seed}: a goal 0.42 m from the root joins");
    }
}

/// Issue 7, case 4 (full arena): on the office sequence the 8,192-node arena was full after
/// leg 1 and goal 2 never joined in 3,000 calls. Here: a 256-node arena fills on the maze's
/// first leg, and every later goal must still join and be reached.
#[test]
fn regression_full_arena_keeps_a_reachable_goal_out() {
    let s = &builtin::MAZE;
    let table = landmark_table(&s.grid, 8);
    for seed in [1, 2] {
        let mut storage = Box::new(Storage::<256, 64>::new());
        let cfg = Config::bi_am_rrt(MetricKind::Diffusion);
        let metric = DiffusionTable::new(&table).unwrap();
        let mut p = planner(&mut storage, s, metric, cfg, s.start, seed);
        let mut was_full = false;
        for (i, goal) in s.goals.iter().enumerate() {
            let t = drive_checked(&mut p, *goal, 3_000, 1.0, |p, _, _, _| {
                was_full |= p.tree().is_full();
            });
            assert!(
                t.reached && t.unsafe_moves == 0,
                "seed {seed} goal {i}: {t:?}"
            );
        }
        assert!(was_full, "the arena filled up");
    }
}

/// Issue 7, case 8: with a circle enclosing the goal the agent waited, but only
/// `goal_cost.blocked` said so; and `path()` returned segments through circles unflagged.
#[test]
fn regression_no_why_when_waiting() {
    let s = &builtin::OPEN;
    let mut storage = Box::new(Storage::<2048, 512>::new());
    let cfg = Config::bi_am_rrt(MetricKind::Euclidean);
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

/// Tiny capacities (issue 7): arenas of 64 nodes and far fewer, with obstacles dropped on the
/// way, keep returning valid waypoints (or a clear state) and never corrupt a tree; without
/// obstacles, 64 and 16 nodes are enough to cross the open field.
#[test]
fn tiny_capacities_stay_valid() {
    fn run<const N: usize, const B: usize>(seed: u64, drops: bool) -> Tally {
        let s = &builtin::OPEN;
        let mut storage = Box::new(Storage::<N, B>::new());
        let cfg = Config::bi_am_rrt(MetricKind::Euclidean);
        let mut p = planner(&mut storage, s, Euclidean, cfg, s.start, seed);
        if drops {
            drive_with_drops(&mut p, s.goals[0])
        } else {
            drive_checked(&mut p, s.goals[0], 1_500, 0.7, |_, _, _, _| {})
        }
    }
    let mut arrived = [0; 2];
    for seed in 1..=3 {
        for drops in [false, true] {
            for (n, t) in [
                (64, run::<64, 8>(seed, drops)),
                (16, run::<16, 4>(seed, drops)),
                (4, run::<4, 1>(seed, drops)),
                (1, run::<1, 1>(seed, drops)),
            ] {
                assert_eq!(t.unsafe_moves, 0, "{t:?}");
                if n >= 16 && !drops {
                    assert!(t.reached, "{n} nodes, seed {seed}: {:?}", t.statuses);
                }
                if n == 1 {
                    assert_eq!(t.statuses, [Status::Searching], "a lone root holds");
                }
                arrived[drops as usize] += t.reached as u32;
            }
        }
    }
    eprintln!(
        "tiny capacities arrived: {}/12 without drops, {}/12 with",
        arrived[0], arrived[1]
    );
}

/// Issue 23, case 5: a table baked from a 150 x 150 grid was accepted with a 200 x 200 grid,
/// and goals outside its area were refused with a misleading `Unreachable`. Now the planner
/// refuses a table of another size or cell (every version), and a version-3 table of another
/// grid of the same size (its recorded hash), with `SetupError::Metric(WrongMap)`.
#[test]
fn regression_a_table_of_another_map_is_refused() {
    use bi_am_rrt::metric::{ElementKind, Layout, TableError, TableHeader, fnv1a32};
    let grid = |n: u16, wall: u16| {
        let mut bits = vec![0u8; OccupancyGrid::bytes_needed(n, n)];
        bi_am_rrt::map::pack_grid(&mut bits, n, n, |c, r| c == wall && r > 2).unwrap();
        bits
    };
    // A one-block-per-cell pieces table (every free cell its own entry) of `bits`.
    let table = |bits: &[u8], n: u16, stamp: bool| {
        let g = OccupancyGrid::new(bits, n, n, 1.0).unwrap();
        let free = |c: u16, r: u16| !g.is_occupied(c, r);
        let entries = (0..n)
            .flat_map(|r| (0..n).map(move |c| (c, r)))
            .filter(|&(c, r)| free(c, r))
            .count() as u32;
        let header = TableHeader {
            kind: ElementKind::F32,
            dims: 2,
            cols: n,
            rows: n,
            cell_size: 1.0,
            scale: 1.0,
            layout: Layout::Pieces { block: 1, entries },
            map_hash: stamp.then(|| fnv1a32(bits)),
        };
        let mut out = vec![0u8; header.table_len().unwrap()];
        let cells: Vec<(u16, u16)> = (0..n)
            .flat_map(|r| (0..n).map(move |c| (c, r)))
            .filter(|&(c, r)| free(c, r))
            .collect();
        bi_am_rrt::metric::write_piece_table(
            &header,
            &mut out,
            |c, r| u8::from(free(c, r)),
            |e, xy| {
                let (c, r) = cells[e as usize];
                xy[0] = c as f32;
                xy[1] = r as f32;
                true
            },
        )
        .unwrap();
        out
    };
    let try_plan = |grid_bits: &[u8], n: u16, table_bytes: &[u8]| {
        let mut storage: Box<Storage<64, 16>> = Box::default();
        let t = DiffusionTable::new(table_bytes).unwrap();
        let g = OccupancyGrid::new(grid_bits, n, n, 1.0).unwrap();
        let cfg = Config::bi_am_rrt(MetricKind::Diffusion);
        Planner::<_, _, 64, 16, K>::new(
            &mut storage,
            Map::new(g),
            t,
            XorShiftRng::seed_from_u64(1),
            cfg,
            Point::new(1.5, 1.5),
        )
        .map(|_| ())
    };
    let small = grid(150, 70);
    let big = grid(200, 70);
    let wrong = Err(SetupError::Metric(TableError::WrongMap));
    // Another size: refused, stamped (version 3) or not (version 2).
    for stamp in [false, true] {
        let t = table(&small, 150, stamp);
        assert_eq!(try_plan(&big, 200, &t), wrong, "stamp {stamp}");
        assert_eq!(try_plan(&small, 150, &t), Ok(()), "stamp {stamp}");
    }
    // The same size, another wall: only the version-3 table can tell.
    let other = grid(150, 90);
    assert_eq!(try_plan(&other, 150, &table(&small, 150, true)), wrong);
    assert_eq!(try_plan(&other, 150, &table(&small, 150, false)), Ok(()));
    // A version-1 table of the 150 x 150 grid's size (landmarks) on the 200 x 200 one.
    let g = OccupancyGrid::new(&small, 150, 150, 1.0).unwrap();
    let v1 = landmark_table(&g, 2);
    assert_eq!(try_plan(&small, 150, &v1), Ok(()));
    assert_eq!(try_plan(&big, 200, &v1), wrong);
}
