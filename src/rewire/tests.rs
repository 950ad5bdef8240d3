//! Rewiring's unit tests.

use super::*;

/// Issue 24, finding 1: the goal-rewiring queue pushed frontiers at its front and took
/// from its front too, a LIFO over frontier batches (the newest batch first). The paper's
/// Dequeue takes the first item, Enqueue adds at the end: batches come out in the order
/// they went in (within a batch, the reference's order: the frontier is prepended whole
/// and taken from the list's end, so its last node, the one nearest the goal, first).
#[test]
fn regression_the_goal_rewiring_queue_is_first_in_first_out() {
    let mut store = TreeStore::<64, 16>::new();
    store.reset(Point::new(1.0, 1.0));
    let batch = |store: &mut TreeStore<64, 16>, ids: [u16; 2]| {
        // As rewire_goal enqueues a frontier.
        for &f in ids.iter().rev() {
            assert!(store.enqueue_goal(NodeId(f)));
        }
    };
    batch(&mut store, [1, 2]);
    batch(&mut store, [3, 4]);
    assert_eq!(
        store.goal_queue.back(),
        Some(&NodeId(2)),
        "x_r2 peeks the next out"
    );
    let order: heapless::Vec<u16, 8> =
        core::iter::from_fn(|| store.dequeue_goal().map(|n| n.0)).collect();
    assert_eq!(order[..], [2, 1, 4, 3]);
}
use crate::clock::FakeClock;
use crate::config::{AsPrinted, Config};
use crate::map::{Map, OccupancyGrid, pack_grid};
use crate::metric::Euclidean;

/// A zig-zag path of `points` below the root at `points[0]`; returns the last node.
/// A path from (2.5, 2.5) to (2.5, 16.5) round the end of a wall at row 10, columns 0-11
/// ([`wall_end`]), its corner nodes away from the wall's corners.
const ZIGZAG: [(f32, f32); 9] = [
    (2.5, 2.5),
    (6.5, 4.5),
    (4.5, 7.5),
    (10.5, 6.5),
    (14.5, 9.5),
    (13.5, 12.5),
    (8.5, 14.5),
    (6.5, 17.5),
    (2.5, 16.5),
];

/// The bits of a 20 x 20 m map of 1 m cells with a wall at row 10 over columns 0-11.
fn wall_end() -> [u8; OccupancyGrid::bytes_needed(20, 20)] {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
    pack_grid(&mut bits, 20, 20, |c, r| r == 10 && c < 12).unwrap();
    bits
}

fn zigzag(store: &mut TreeStore<64, 16>, points: &[Point]) -> NodeId {
    store.reset(points[0]);
    let mut last = NodeId(0);
    for p in &points[1..] {
        last = store.insert(*p, last, false).unwrap();
    }
    last
}

/// The Euclidean environment of `map` and `cfg`, without a call deadline.
fn euclidean_env<'a, 'm>(map: &'a Map<'m, 1>, cfg: &'a Config) -> Env<'a, 'm, Euclidean, 1> {
    Env {
        map,
        metric: &Euclidean,
        cfg,
        call: Deadline::NEVER,
    }
}

/// An empty 20 x 20 m map and the Euclidean Bi-AM-RRT* configuration.
fn open_map(bits: &mut [u8]) -> (Map<'_, 1>, Config) {
    pack_grid(bits, 20, 20, |_, _| false).unwrap();
    let map = Map::new(OccupancyGrid::new(bits, 20, 20, 1.0).unwrap());
    (map, Config::bi_am_rrt())
}

/// Issue 25, second round: a rewiring visit tested all its (up to 64) neighbours once
/// started, a millisecond on a Cortex-M4F, and the tuned set's calls ran that far past
/// their deadline. x1 hangs below a detour (root - a - b - x1, cost 15) with the root
/// 3 m away: a visit with time left rewires it below the root; a visit whose deadline
/// passes while it gathers the neighbours (1 ms a unit of work) tests none of them.
#[test]
fn regression_a_rewiring_visit_stops_testing_at_the_deadline() {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
    let (map, cfg) = open_map(&mut bits);
    let env = euclidean_env(&map, &cfg);
    for (deadline, parent) in [
        (Deadline::NEVER, 0u16),
        (Deadline::from_ticks(0, 1_000_000), 2),
    ] {
        let clock = FakeClock::nanos().with_work_cost(1_000_000);
        let meter = Meter::new(&clock);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 8.0));
        let x1 = zigzag(
            &mut store,
            &[(2.0, 2.0), (2.0, 8.0), (5.0, 8.0), (5.0, 2.0)].map(|(x, y)| Point::new(x, y)),
        );
        store.tree.mark(NodeId(0), Mark::Root);
        store.tree.mark(x1, Mark::Root);
        store.root_queue.push_back(x1).unwrap();
        let slice = Slice {
            deadline,
            visits: 1,
        };
        store.rewire_root(&env, slice, false, &meter);
        store.tree.validate().unwrap();
        assert_eq!(store.tree.parent(x1), Some(NodeId(parent)), "{deadline:?}");
    }
}

#[test]
fn algorithm_4_as_printed_takes_x_r2_out_of_the_queue() {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
    let (map, base) = open_map(&mut bits);
    let front_after_one_step = |take: bool| {
        let mut cfg = base;
        cfg.as_printed.alg4_takes_x_r2 = take;
        let env = euclidean_env(&map, &cfg);
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        store.reset(Point::new(2.0, 2.0));
        for k in 1..=4u16 {
            let id = store
                .insert(Point::new(2.0 + 3.0 * f32::from(k), 2.0), NodeId(0), false)
                .unwrap();
            store.tree.mark(id, Mark::Root);
            store.root_queue.push_back(id).unwrap();
        }
        store.tree.mark(NodeId(0), Mark::Root);
        let slice = Slice {
            deadline: Deadline::NEVER,
            visits: 1,
        };
        store.rewire_root(&env, slice, true, &meter);
        store.tree.validate().unwrap();
        store.root_queue.front().map(|n| n.0)
    };
    assert_eq!(front_after_one_step(false), Some(2), "x_r2 peeked");
    assert_eq!(front_after_one_step(true), Some(3), "x_r2 dequeued");
}

/// One visit of goal rewiring (the second kind, Algorithm 6, or the first) on an open map:
/// the tree is the straight chain `chain` from the root (every node already seen), plus an
/// optional branch node hung below a chain node; `stack` (bottom to top, node ids, the
/// branch's id next after the chain's) is the goal stack. Returns what is left on the stack.
fn goal_stack_after_a_visit(
    printed: AsPrinted,
    chain: &[Point],
    branch: Option<(Point, u16)>,
    stack: &[u16],
    second_kind: bool,
) -> heapless::Vec<u16, 8> {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
    let (map, mut cfg) = open_map(&mut bits);
    cfg.as_printed = printed;
    let env = euclidean_env(&map, &cfg);
    let clock = FakeClock::new(1);
    let meter = Meter::new(&clock);
    let mut store = TreeStore::<64, 16>::new();
    assert!(store.index.reshape(20.0, 20.0, 2.0));
    let goal = zigzag(&mut store, chain);
    if let Some((at, below)) = branch {
        store.insert(at, NodeId(below), false).unwrap();
    }
    for id in store.tree.ids().collect::<heapless::Vec<NodeId, 64>>() {
        store.tree.mark(id, Mark::Goal);
    }
    for &id in stack {
        store.goal_stack.push(NodeId(id)).unwrap();
    }
    let target = Target {
        pos: store.pos(goal),
        node: Some(goal),
    };
    let slice = Slice {
        deadline: Deadline::NEVER,
        visits: 1,
    };
    store.rewire_goal(&env, &target, slice, second_kind, &meter);
    store.tree.validate().unwrap();
    store.goal_stack.iter().map(|n| n.0).collect()
}

/// One step of Algorithm 6 from the stack `[p, q, x_r1]` (bottom to top) on a straight
/// tree `root (1) - q (7) - x_r1 (9) - p (13) - goal (18)` along `y = 10`.
fn goal_stack_after_one_step(printed: AsPrinted) -> heapless::Vec<u16, 8> {
    let chain = [1.0, 7.0, 9.0, 13.0, 18.0].map(|x| Point::new(x, 10.0));
    goal_stack_after_a_visit(printed, &chain, None, &[3, 1, 2], true)
}

#[test]
fn algorithm_6_as_printed_takes_x_r2_and_tests_the_second_node_with_slack() {
    let run = |take: bool, clear: bool| {
        let mut printed = AsPrinted::NONE;
        printed.alg6_takes_x_r2 = take;
        printed.alg6_clear = clear;
        goal_stack_after_one_step(printed)
    };
    // Peeked x_r2 = q stays on top; q (11 m from the goal) is farther than x_r1 (9 m):
    // this crate's test clears the stack.
    assert_eq!(run(false, false)[..], []);
    // Taken, q is gone; the top p (5 m) is nearer than x_r1: kept.
    assert_eq!(run(true, false)[..], [3]);
    // The printed test looks at Second(S) = p: 5 > 9 + d(x_r1, q) = 11 fails: kept.
    assert_eq!(run(false, true)[..], [3, 1]);
    // Both: one node left, len(S) > 1 fails: kept.
    assert_eq!(run(true, true)[..], [3]);
}

#[test]
fn algorithm_6_as_printed_compares_the_way_through_x_r1() {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
    let (map, cfg) = open_map(&mut bits);
    let env = euclidean_env(&map, &cfg);
    let clock = FakeClock::new(1);
    let meter = Meter::new(&clock);
    for (via, rewired) in [(None, true), (Some(Point::new(2.0, 6.0)), false)] {
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        // x_near (6, 2) reached round a detour: cost about 7.2.
        let near = zigzag(
            &mut store,
            &[(2.0, 2.0), (4.0, 5.0), (6.0, 2.0)].map(|(x, y)| Point::new(x, y)),
        );
        let before = store.cost(near).length;
        // The root as x_r2: its edge costs 4 < 7.2; through x_r1 (2, 6) 4 + 5.7 > 7.2.
        let done = store.try_rewire_via(&env, NodeId(0), near, via, false, &meter);
        assert_eq!(done, rewired, "via {via:?}, cost before {before}");
        store.tree.validate().unwrap();
    }
}

#[test]
fn corner_cuts_pull_the_path_round_the_corner() {
    // The map and zigzag of the test below; the shortest way from (2.5, 2.5) to (2.5,
    // 16.5) round the wall's end touches its corners (12, 10) and (12, 11).
    let bits = wall_end();
    let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 20, 20, 1.0).unwrap());
    let (start, end) = (Point::new(2.5, 2.5), Point::new(2.5, 16.5));
    let optimum = start.dist(Point::new(12.0, 10.0)) + 1.0 + Point::new(12.0, 11.0).dist(end);
    let pts = ZIGZAG.map(|(x, y)| Point::new(x, y));
    let clock = FakeClock::new(1);
    let meter = Meter::new(&clock);
    let mut lengths = [0.0f32; 2];
    for (cuts, length) in [false, true].into_iter().zip(&mut lengths) {
        let paper = Config::bi_am_rrt();
        let cfg = if cuts { paper.tuned() } else { paper };
        let env = euclidean_env(&map, &cfg);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        let goal = zigzag(&mut store, &pts);
        for _ in 0..40 {
            store.shortcut_path(&env, goal, 4, &meter);
        }
        store.tree.validate().unwrap();
        let mut x = goal;
        while let Some(p) = store.tree.parent(x) {
            assert!(map.free_path(store.pos(p), store.pos(x)), "cuts {cuts}");
            x = p;
        }
        assert_eq!(x, NodeId(0));
        *length = store.cost(goal).length;
        assert!(
            *length >= optimum - 1e-3,
            "cuts {cuts}: {length} < {optimum}"
        );
    }
    // Measured: 27.36 m through the corner nodes, 24.17 m with cuts (optimum 24.08 m).
    assert!(lengths[0] > 1.05 * optimum, "{lengths:?} vs {optimum}");
    assert!(lengths[1] < 1.005 * optimum, "{lengths:?} vs {optimum}");
}

#[test]
fn path_shortcuts_straighten_the_path_and_keep_it_free() {
    // 20 x 20 m; a wall at row 10 over columns 0-11 (the way round is past column 12).
    let bits = wall_end();
    let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 20, 20, 1.0).unwrap());
    let cfg = Config::bi_am_rrt();
    let env = euclidean_env(&map, &cfg);
    let clock = FakeClock::new(1);
    let meter = Meter::new(&clock);
    let mut store = TreeStore::<64, 16>::new();
    assert!(store.index.reshape(20.0, 20.0, 2.0));
    let pts = ZIGZAG.map(|(x, y)| Point::new(x, y));
    let goal = zigzag(&mut store, &pts);
    let before = store.cost(goal).length;
    for _ in 0..20 {
        store.shortcut_path(&env, goal, 4, &meter);
    }
    let after = store.cost(goal).length;
    store.tree.validate().unwrap();
    // Every edge of the path is free, and the path still goes round the wall's end.
    let mut x = goal;
    let mut hops = 0;
    while let Some(p) = store.tree.parent(x) {
        assert!(map.free_path(store.pos(p), store.pos(x)));
        x = p;
        hops += 1;
    }
    assert_eq!(x, NodeId(0));
    // Straight through the corner nodes (10.5, 6.5) or (14.5, 9.5) and (13.5, 12.5).
    assert!(after < before - 5.0, "{before} -> {after}");
    assert!(hops <= 4, "{hops} edges left");
    let direct = pts[0].dist(pts[8]);
    assert!(
        after > direct,
        "the wall is in the way: {after} vs {direct}"
    );
}

/// Issue 46 (F2): Algorithm 4 as printed enqueues `x_near` only over a free segment to
/// `x_r1`. On the wall map, `x_r1` (5, 8) sits below the wall and `x_r2` (13, 9) at its end;
/// `x_near` (12, 12) lies near `x_r2` but behind the wall from `x_r1`.
#[test]
fn algorithm_4_as_printed_enqueues_only_neighbours_x_r1_sees() {
    let bits = wall_end();
    let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 20, 20, 1.0).unwrap());
    let queued_after_one_step = |free_only: bool| {
        let mut cfg = Config::bi_am_rrt();
        cfg.as_printed.alg4_free_enqueue = free_only;
        let env = euclidean_env(&map, &cfg);
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        store.reset(Point::new(2.0, 2.0));
        let x1 = store
            .insert(Point::new(5.0, 8.0), NodeId(0), false)
            .unwrap();
        let x2 = store
            .insert(Point::new(13.0, 9.0), NodeId(0), false)
            .unwrap();
        let third = store
            .insert(Point::new(16.0, 6.0), NodeId(0), false)
            .unwrap();
        let behind = store.insert(Point::new(12.0, 12.0), x2, false).unwrap();
        for id in [NodeId(0), x1, x2, third] {
            store.tree.mark(id, Mark::Root);
        }
        for id in [x1, x2, third] {
            store.root_queue.push_back(id).unwrap();
        }
        let slice = Slice {
            deadline: Deadline::NEVER,
            visits: 1,
        };
        store.rewire_root(&env, slice, true, &meter);
        store.tree.validate().unwrap();
        store.root_queue.iter().any(|&n| n == behind)
    };
    assert!(queued_after_one_step(false), "every unseen neighbour");
    assert!(!queued_after_one_step(true), "behind the wall from x_r1");
}

/// Issue 46 (F3): Algorithm 5 as printed runs Algorithm 6 only while the stack or the queue
/// holds more than two nodes. With two on the stack and none queued, the second kind pops
/// `x_r1` in this crate's reading and does nothing as printed.
#[test]
fn algorithm_5_as_printed_runs_the_second_kind_only_on_long_lists() {
    let run = |gate: bool| {
        let mut printed = AsPrinted::NONE;
        printed.alg5_gate = gate;
        let chain = [1.0, 7.0, 9.0, 13.0, 18.0].map(|x| Point::new(x, 10.0));
        goal_stack_after_a_visit(printed, &chain, None, &[1, 3], true)
    };
    assert_eq!(run(true)[..], [1, 3], "gated: untouched");
    assert_ne!(run(false)[..], [1, 3], "this crate's reading: x_r1 popped");
}

/// Issue 46 (F1): the clearing test follows every `x_r1`, also one outside the ellipse, as
/// printed. The tree: root (1, 10) - q (7, 10) - p (13, 10) - goal (18, 10) and a branch
/// x_r1 (9, 14) below q, outside the thin ellipse; the stack `[p, q, x_r1]`. Popped, x_r1
/// (9.85 m from the goal) leaves q (11 m) on top: the branch recedes.
#[test]
fn algorithm_6_as_printed_tests_the_stack_after_a_node_outside_the_ellipse() {
    let chain = [1.0, 7.0, 13.0, 18.0].map(|x| Point::new(x, 10.0));
    for second_kind in [false, true] {
        let run = |outside: bool| {
            let mut printed = AsPrinted::NONE;
            printed.alg6_clear_outside = outside;
            let branch = Some((Point::new(9.0, 14.0), 1));
            goal_stack_after_a_visit(printed, &chain, branch, &[2, 1, 4], second_kind).len()
        };
        assert_eq!(run(true), 0, "second kind {second_kind}: cleared");
        assert_eq!(run(false), 2, "second kind {second_kind}: skipped");
    }
}
