//! The planner end to end on the built-in maps, deterministic (virtual clock, fixed seeds).

mod common;

use std::collections::HashSet;
use std::time::Duration;

use bi_am_rrt::builtin::{self};
use bi_am_rrt::map::Circle;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Euclidean, Map, MetricKind, Named, Planner, Point, Storage};
use common::e2e::{B, K, N, clock, planner_on, run, test_config};
use common::{Protocol, drive, landmark_table, path_meets};
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

#[test]
fn meet_and_graft_make_one_tree_with_the_goal() {
    let s = &builtin::BUG_TRAP;
    let mut met = 0;
    for seed in 1..=12 {
        let mut storage = Box::new(Storage::<N, B>::new());
        let cfg = Config::am_rrt().with_bidirectional(true);
        let mut p = planner_on(&mut storage, s, Euclidean, cfg, seed);
        let clock = clock();
        p.set_goal(s.goals[0]).unwrap();
        assert!(p.searching_backwards());
        let mut calls = 0;
        loop {
            let pr = p.plan(&clock, s.start).unwrap();
            if pr.goal_in_tree {
                break;
            }
            calls += 1;
            assert!(calls < 500, "seed {seed}: no meet");
        }
        // One valid tree holding the goal; the reverse tree is gone.
        p.tree().validate().unwrap();
        assert!(!p.searching_backwards());
        assert!(p.reverse_tree().is_empty());
        let g = p.goal_node().unwrap();
        assert_eq!(p.tree().position(g), Some(s.goals[0]));
        let mut path = vec![Point::ZERO; N];
        let n = p.path(&mut path).unwrap().len;
        assert_eq!(path[0], p.root_position());
        assert_eq!(path[n - 1], s.goals[0]);
        for w in path[..n].windows(2) {
            assert!(p.map().free_path(w[0], w[1]), "grafted path crosses a wall");
        }
        met += usize::from(p.stats().met);
    }
    // In the bug trap the goal joins through the reverse tree most of the time.
    assert!(met >= 8, "met {met} of 12");
}

#[test]
fn an_obstacle_dropped_on_the_path_is_avoided() {
    let s = &builtin::OPEN;
    let table = landmark_table(&s.grid, 8);
    for cfg in [Config::bi_am_rrt(), Config::am_rrt(), Config::rt_rrt()] {
        let mut storage = Box::new(Storage::<N, B>::new());
        let metric = DiffusionTable::new(&table).unwrap();
        let mut p = planner_on(&mut storage, s, metric, cfg, 11);
        let clock = clock();
        let mut dropped: Option<(Circle, u32)> = None;
        let mut blocked_calls = Vec::new();
        let r = drive(
            &mut p,
            &clock,
            s.goals[0],
            Protocol::default(),
            |p, agent, call| {
                if let Some((c, at)) = dropped {
                    if path_meets(p, &c) {
                        blocked_calls.push(call - at);
                    }
                    return;
                }
                if agent.dist(s.start) < 3.0 {
                    return;
                }
                // Drop a disc on the path, about 8 m ahead of the agent.
                let mut path = vec![Point::ZERO; N];
                let n = p.path(&mut path).unwrap().len;
                let mut ahead = 0.0;
                for w in path[..n].windows(2) {
                    ahead += w[0].dist(w[1]);
                    if ahead > 8.0 && w[1].dist(s.goals[0]) > 4.0 {
                        let c = Circle::new(w[1], 1.5);
                        p.add_obstacle(c).unwrap();
                        assert!(path_meets(p, &c));
                        dropped = Some((c, call));
                        return;
                    }
                }
            },
        );
        let name = p.name();
        assert!(dropped.is_some(), "{name}: no drop");
        assert!(r.reached && r.collisions == 0, "{name}: {r:?}");
        // The path leaves the disc within a few calls and never goes back through it.
        assert!(
            blocked_calls.len() <= 3,
            "{name}: path through the obstacle at {blocked_calls:?}"
        );
    }
}

#[test]
fn rewiring_never_increases_a_cost() {
    let s = &builtin::MAZE;
    let table = landmark_table(&s.grid, 8);
    for cfg in [
        Config::am_rrt(),
        Config::bi_am_rrt(),
        Config::rt_rrt().with_new_rewiring(true),
    ] {
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut p = planner_on(
            &mut storage,
            s,
            DiffusionTable::new(&table).unwrap(),
            cfg,
            5,
        );
        let clock = clock();
        p.set_goal(s.goals[0]).unwrap();
        // The agent stays away from the root, so the tree is never re-rooted.
        let agent = s.start + Point::new(1.0, 0.0);
        let mut rewired = 0;
        for _ in 0..40 {
            let before: Vec<_> = p
                .tree()
                .ids()
                .map(|id| p.tree().cost(id).unwrap())
                .collect();
            let parents: Vec<_> = p.tree().ids().map(|id| p.tree().parent(id)).collect();
            p.plan(&clock, agent).unwrap();
            p.tree().validate().unwrap();
            for (i, old) in before.iter().enumerate() {
                let id = bi_am_rrt::tree::NodeId(i as u16);
                let new = p.tree().cost(id).unwrap();
                assert!(
                    new <= *old,
                    "{}: node {i} cost {old:?} -> {new:?}",
                    p.name()
                );
                rewired += usize::from(p.tree().parent(id) != parents[i]);
            }
        }
        assert!(rewired > 0, "{}: rewiring never changed an edge", p.name());
    }
}

#[test]
fn a_full_arena_is_reported_and_planning_goes_on() {
    let s = &builtin::OPEN;
    let mut storage = Box::new(Storage::<48, 64>::new());
    let cfg = Config::am_rrt();
    let mut p = planner_on(&mut storage, s, Euclidean, cfg, 3);
    let clock = clock();
    let mut saw_full = false;
    let r = drive(
        &mut p,
        &clock,
        s.goals[0],
        Protocol::default(),
        |p, _, _| {
            saw_full |= p.tree().is_full();
        },
    );
    assert!(saw_full, "the arena filled up");
    assert!(r.reached && r.collisions == 0, "{r:?}");
    assert_eq!(p.tree().len(), 48);
}

/// The tuned configurations reach the goal with every move checked, like the paper's.
#[test]
fn tuned_configurations_reach_the_goal() {
    let proto = Protocol {
        speed: 2.0,
        ..Protocol::default()
    };
    let mut failures = Vec::new();
    for s in [&builtin::BUG_TRAP, &builtin::MAZE] {
        for m in [MetricKind::Euclidean, MetricKind::Diffusion] {
            let cfg = Named {
                metric: m,
                cfg: Config::bi_am_rrt().tuned(),
            };
            let r = run(cfg, s, 7, proto);
            if !r.reached || r.collisions > 0 {
                failures.push(format!("{} on {}: {r:?}", cfg.name(), s.name));
            }
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}

/// A tree that lives forever: once the arena is full and the goal is in it, the tuned planner
/// trades leaves that cannot improve the path for states that can, so the path keeps getting
/// shorter where the paper's planner (which only rewires a full tree) stalls.
#[test]
fn a_full_tuned_tree_keeps_improving() {
    let s = &builtin::BUG_TRAP;
    // Per configuration: (length when the arena filled, length 200 calls later) per seed.
    let mut runs = Vec::new();
    // The tuned set without its path shortcuts (and so without corner cuts): with them the
    // path is within 1-12 % of the optimum when the arena fills and does not leave its way
    // round the obstacles in 600 calls; what is checked here is that trades go on improving
    // a full tree where the paper's stops.
    let mut tuned = Config::bi_am_rrt().tuned();
    tuned.rewiring.path_shortcuts = 0;
    for cfg in [Config::bi_am_rrt(), tuned] {
        let mut lengths = Vec::new();
        for seed in 11..=16 {
            let mut storage = Box::new(Storage::<256, 256>::new());
            let mut p = planner_on(&mut storage, s, Euclidean, cfg, seed);
            p.set_goal(s.goals[0]).unwrap();
            let clock = clock();
            let mut at_full = None;
            for _ in 0..200 {
                let pr = p.grow(&clock);
                if pr.nodes == 256 && pr.goal_in_tree && at_full.is_none() {
                    at_full = pr.goal_cost.map(|c| c.length);
                }
            }
            let at_full = at_full.expect("the arena filled with the goal in the tree");
            let end = p.tree().cost(p.goal_node().unwrap()).unwrap();
            assert_eq!(p.tree().len(), 256);
            assert!(!end.blocked && end.length <= at_full);
            p.tree().validate().unwrap();
            lengths.push((at_full, end.length));
        }
        eprintln!("{}: {lengths:?}", cfg.name(MetricKind::Euclidean));
        runs.push(lengths);
    }
    // Measured (seeds 11-16, 200 calls of 20 ms): the paper's tree improves on one seed of six
    // once full (97.33 -> 97.25 m), the tuned one without shortcuts on all six (e.g. 88.3 ->
    // 88.0, 97.4 -> 96.9 m; the optimum is 74.4 m: a 256-node tree on this map stalls short
    // of it). With shortcuts and corner cuts the tuned paths are 75.0-83.5 m when the arena
    // fills. Before issue 26's corner cuts the full tuned set (shortcuts on) improved on two
    // of six.
    let improved = |l: &[(f32, f32)]| l.iter().filter(|(full, end)| end < full).count();
    assert!(improved(&runs[1]) >= 2, "tuned: {:?}", runs[1]);
    assert!(improved(&runs[1]) > improved(&runs[0]), "{runs:?}");
}

/// The occupied buckets of the planner's spatial index (`side`-metre squares from the origin).
fn occupied_buckets(tree: &bi_am_rrt::tree::Tree<1024>, side: f32) -> HashSet<(u32, u32)> {
    tree.positions()
        .iter()
        .map(|p| ((p.x / side) as u32, (p.y / side) as u32))
        .collect()
}

/// Regression (tuned bug_trap protocol, leg 4 travelled 1.40 x the optimum): a full tuned tree
/// traded every leaf far from the current goal's path for states near it, so the part of the
/// map the next goal needed was empty and the agent set off the long way round. With
/// `recycle_cover`, trades never take the last nodes of an index bucket: every bucket the
/// tree reached keeps a node. Without it the same run empties buckets (the test can fail).
/// 1,024 nodes on the 60 m map: the cover's cap (`N / (2 x buckets)`) allows 2 per bucket.
#[test]
fn trades_keep_a_cover_of_the_map() {
    let s = &builtin::BUG_TRAP;
    let tuned = Config::bi_am_rrt().tuned();
    assert!(tuned.memory.recycle_cover > 0);
    let mut uncovered = Vec::new();
    for cover in [tuned.memory.recycle_cover, 0] {
        let mut cfg = tuned;
        cfg.memory.recycle_cover = cover;
        let mut storage = Box::new(Storage::<1024, 256>::new());
        let mut p = planner_on(&mut storage, s, Euclidean, cfg, 11);
        let side = bi_am_rrt::index::SpatialIndex::<1024, 256>::with_bounds(
            s.grid.width_m(),
            s.grid.height_m(),
            test_config(cfg, s).search.e_max,
        )
        .unwrap()
        .bucket_side();
        p.set_goal(s.goals[0]).unwrap();
        let clock = clock();
        let mut when_full = None;
        for _ in 0..200 {
            let pr = p.grow(&clock);
            if pr.nodes == 1024 && pr.goal_in_tree && when_full.is_none() {
                when_full = Some((
                    occupied_buckets(p.tree(), side),
                    p.tree().positions().to_vec(),
                ));
            }
        }
        let (before, positions) = when_full.expect("the arena filled with the goal in the tree");
        assert_ne!(
            positions,
            p.tree().positions(),
            "cover {cover}: the full tree traded nodes"
        );
        let after = occupied_buckets(p.tree(), side);
        p.tree().validate().unwrap();
        uncovered.push(before.difference(&after).count());
        eprintln!(
            "cover {cover}: {} buckets occupied when full, {} of them empty 200 calls later",
            before.len(),
            uncovered.last().unwrap()
        );
    }
    assert_eq!(uncovered[0], 0, "with the cover rule no bucket empties");
    assert!(uncovered[1] > 0, "without it, trades empty buckets");
}

#[test]
fn a_goal_sequence_reuses_the_tree() {
    let s = &builtin::MAZE;
    let table = landmark_table(&s.grid, 8);
    for cfg in [
        Config::bi_am_rrt(),
        Config::rt_rrt().with_bidirectional(true),
    ] {
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut p = planner_on(
            &mut storage,
            s,
            DiffusionTable::new(&table).unwrap(),
            cfg,
            21,
        );
        let clock = clock();
        let proto = Protocol {
            speed: 2.0,
            ..Protocol::default()
        };
        let mut nodes = 0;
        for (i, goal) in s.goals.iter().enumerate() {
            let r = drive(&mut p, &clock, *goal, proto, |_, _, _| {});
            assert!(
                r.reached && r.collisions == 0,
                "{} goal {i}: {r:?}",
                p.name()
            );
            assert!(p.tree().len() >= nodes, "the tree is kept between goals");
            nodes = p.tree().len();
            assert_eq!(p.root_position(), *goal);
        }
    }
}

/// Issue 8: two 2,048-node trees took 152,684 bytes (37 per node) and overflowed a 128 KiB
/// chip. The layout is now 21 bytes per node per tree plus a fixed part (bucket heads and
/// bounded sweep queues) that does not grow with `N`.
#[test]
fn regression_storage_fits_4096_nodes_in_96_kib() {
    use core::mem::size_of;
    let per_tree = |total: usize, n: usize| total / 2 - 21 * n;
    let s2048 = size_of::<Storage<2048, 256>>();
    let s1024 = size_of::<Storage<1024, 256>>();
    assert!(s2048 <= 2 * (21 * 2048 + 2_200), "{s2048} bytes");
    assert_eq!(
        per_tree(s2048, 2048),
        per_tree(s1024, 1024),
        "the fixed part grows with N"
    );
    // The office firmware's stack high-water mark is about 5 KiB (docs/results/firmware/office.txt; CI
    // checks the real total against 96 KiB).
    assert!(
        s2048 + 6 * 1024 <= 96 * 1024,
        "{s2048} bytes leave no room for a stack"
    );
}

/// `Storage::BYTES` (the formula its docs give: 42 bytes a node, 4 a bucket, a fixed part) is
/// its size: exactly when `N` is a multiple of 8 and `B` of 4, within 16 bytes otherwise. The
/// crate checks four sizes as it compiles for any target (thumbv7em in CI); this checks more.
#[test]
fn storage_bytes_follow_the_formula() {
    use core::mem::size_of;
    macro_rules! check {
        ($($n:literal, $b:literal);*) => {$(
            let (actual, formula) = (size_of::<Storage<$n, $b>>(), Storage::<$n, $b>::BYTES);
            if $n % 8 == 0 && $b % 4 == 0 {
                assert_eq!(actual, formula, "Storage<{}, {}>", $n, $b);
            } else {
                assert!(actual.abs_diff(formula) <= 16, "Storage<{}, {}>: {actual} vs {formula}", $n, $b);
            }
        )*};
    }
    check!(8, 4; 16, 8; 128, 16; 256, 32; 512, 64; 1000, 128; 4096, 512; 8192, 256;
        61, 10; 62, 17; 67, 19; 101, 10; 1023, 255; 2047, 33);
    assert_eq!(
        Storage::<2048, 256>::BYTES,
        87_040 + Storage::<1, 1>::FIXED_BYTES
    );
}

/// RRT-Connect's greedy step (the tuned profile, here with the paper's parameters): across
/// open space the reverse tree walks straight to the forward tree's first node and the goal
/// joins in the first step, where the paper's trees, which meet only within `sigma`, need
/// several steps to come that close.
#[test]
fn connect_joins_the_trees_across_open_space() {
    let s = &builtin::OPEN;
    // A free corridor between y = 30 and the top edge: 36 m from start to goal.
    let (start, goal) = (Point::new(2.5, 35.5), Point::new(37.5, 35.5));
    for connect in [true, false] {
        for seed in 0..10 {
            let mut cfg = Config::bi_am_rrt().with_sigma(2.0);
            // The `connect` tactic alone.
            cfg.tactics.connect = connect;
            cfg.budget.max_expansions = 1;
            let mut storage = Box::new(Storage::<N, B>::new());
            let mut p: Planner<'_, '_, _, _, N, B, K> = Planner::new(
                &mut storage,
                Map::new(s.grid),
                Euclidean,
                XorShiftRng::seed_from_u64(seed),
                cfg,
                start,
            )
            .unwrap();
            p.set_goal(goal).unwrap();
            let clock = clock();
            let steps = (1..=3).find(|_| p.grow(&clock).goal_in_tree);
            if connect {
                // A first forward node lies within e_max (5 m) of the start, above y = 30: the
                // segment from the goal to it misses every box.
                assert_eq!(
                    steps,
                    Some(1),
                    "seed {seed}: the trees met in the first step"
                );
                assert!(p.stats().met);
                // The joining segment: a forward node and a node of the reverse tree, both
                // on the path.
                let [f, r] = p.stats().meet.expect("the meet's segment");
                p.tree().validate().unwrap();
                let mut buf = [Point::ZERO; 64];
                let info = p.path(&mut buf).unwrap();
                assert!(info.to_goal && !info.blocked);
                let path = &buf[..info.len];
                assert_eq!(path.last(), Some(&goal));
                for w in path.windows(2) {
                    assert!(s.grid.segment_free(w[0], w[1]), "{w:?} crosses a box");
                }
                assert!(
                    path.contains(&f) && path.contains(&r),
                    "{f:?} {r:?} {path:?}"
                );
            } else {
                // Each tree grows at most 5 m per step: 3 steps leave them 6 m apart at best.
                assert_eq!(steps, None, "seed {seed}");
            }
        }
    }
}

/// The soak regression (issue 10): with path shortcuts the tuned tree's path is a few long
/// straight edges, and the root, which the agent must reach before it can turn, jumped to the
/// next node tens of metres ahead. A goal that changed meanwhile found the agent bound to it:
/// on office, planned / optimal went from 1.02 in the first minute to 1.23 in the fourth (one
/// goal 10.8 m away cost 80 m). The root now advances at most `e_max` at a time.
#[test]
fn regression_a_new_goal_finds_the_agent_bound_to_a_far_root() {
    let s = &builtin::BUG_TRAP;
    let table = landmark_table(&s.grid, 8);
    let cfg = test_config(Config::bi_am_rrt().tuned(), s);
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut p = planner_on(
        &mut storage,
        s,
        DiffusionTable::new(&table).unwrap(),
        cfg,
        5,
    );
    let clock = clock();
    let mut farthest = 0.0f32;
    for goal in s.goals.iter().chain(s.goals.iter().rev()) {
        let r = drive(&mut p, &clock, *goal, Protocol::default(), |p, agent, _| {
            farthest = farthest.max(agent.dist(p.root_position()));
        });
        assert!(r.reached && r.collisions == 0, "goal {goal:?}: {r:?}");
    }
    assert!(
        farthest <= 1.1 * cfg.search.e_max + 1e-3,
        "the agent was bound to a root {farthest} m away"
    );
}

/// A planner on the built-in bug trap (seed 3) after 60 calls of 20 ms towards its first goal,
/// its tree checked, handed to `f`.
fn grown_towards_goal_1<T>(
    cfg: Config,
    f: impl FnOnce(&Planner<'_, '_, DiffusionTable<'_>, XorShiftRng, N, B, K>) -> T,
) -> T {
    let s = &builtin::BUG_TRAP;
    let table = landmark_table(&s.grid, 8);
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut p = planner_on(
        &mut storage,
        s,
        DiffusionTable::new(&table).unwrap(),
        cfg,
        3,
    );
    p.set_goal(s.goals[0]).unwrap();
    let clock = clock();
    for _ in 0..60 {
        p.grow(&clock);
    }
    p.tree().validate().unwrap();
    f(&p)
}

/// The protocol regression of the density trades (issue 10): on the reference bug trap, legs
/// 4 and 6 travelled 1.035-1.066 x the optimum because the agent first went back 2.7-4 m.
/// Standing on the root when a new goal was set, the tuned planner moved the root before the
/// goal joined, towards the node nearest a goal not yet in the tree, and once the goal joined
/// the root moved to the path's first node even when the next one was in plain sight. With a
/// root step (tuned) the root now waits for the goal, and it is first offered as parent to
/// the node after the next one.
#[test]
fn regression_the_root_moves_before_the_goal_joins() {
    let s = &builtin::BUG_TRAP;
    let table = landmark_table(&s.grid, 8);
    for tuned in [true, false] {
        let base = Config::bi_am_rrt();
        let cfg = test_config(if tuned { base.tuned() } else { base }, s);
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut p = planner_on(
            &mut storage,
            s,
            DiffusionTable::new(&table).unwrap(),
            cfg,
            2,
        );
        let clock = clock();
        // Grow a tree, then stand on its root with a new goal and a call too short to join it.
        p.set_goal(s.goals[0]).unwrap();
        for _ in 0..20 {
            p.grow(&clock);
        }
        let agent = p.root_position();
        p.set_goal(s.goals[1]).unwrap();
        p.set_t_exp(Duration::from_nanos(1)).unwrap();
        let r = p.plan(&clock, agent).unwrap();
        assert!(
            !r.goal_in_tree,
            "tuned {tuned}: the goal joined in a 1 ns call"
        );
        let moved = p.root_position() != agent;
        // The paper's planner moves on towards the node nearest the goal (its behaviour,
        // kept); the tuned one waits for the goal.
        assert_eq!(moved, !tuned, "tuned {tuned}: root moved {moved}");
    }
}

/// The tuned profile's density trades (with its rewiring of a new node's neighbours): once a
/// neighbourhood inside the ellipse is full, states near the path take the slots of worse
/// leaves, so the path keeps shortening where the density rule held it (on the reference maps
/// it held the tuned tree's cost flat between 0.1 s and 1 s of CPU). The tuned parameters
/// with and without the `density_trades` tactic alone; the 2,048-node arena fills either way.
#[test]
fn density_trades_shorten_the_path() {
    let mut runs = Vec::new();
    for trades in [true, false] {
        let mut cfg = Config::bi_am_rrt().tuned();
        cfg.tactics.density_trades = trades;
        grown_towards_goal_1(cfg, |p| {
            let cost = p.tree().cost(p.goal_node().unwrap()).unwrap();
            assert!(!cost.blocked);
            eprintln!(
                "density_trades {trades}: path {} m, {} nodes",
                cost.length,
                p.tree().len()
            );
            runs.push((cost.length, p.tree().len()));
        });
    }
    // Measured (seed 3, 60 calls of 20 ms): 75.21 m with trades, 75.57 m without (the
    // goal's optimum: 74.4 m).
    assert!(runs[0].0 < runs[1].0, "{runs:?}");
}

/// Issue 24, findings 8 and 9: the reference counts the agent's wait from when the goal is
/// set, and reads search time and nodes at goal after the call in which the goal joined. Both
/// definitions are reported; the wait is counted either way (`Protocol::wait_from_set`).
#[test]
fn both_search_definitions_and_both_waits() {
    let s = &builtin::BUG_TRAP;
    let cfg = Named::from_name("RT-RRT*").unwrap();
    let from_join = run(cfg, s, 3, Protocol::default());
    let from_set = run(
        cfg,
        s,
        3,
        Protocol {
            wait_from_set: true,
            ..Protocol::default()
        },
    );
    for r in [&from_join, &from_set] {
        assert!(r.reached, "{r:?}");
        let (at_join, at_end) = (r.search_ticks.unwrap(), r.search_ticks_call_end.unwrap());
        assert!(at_join <= at_end, "{r:?}");
        assert!(
            r.nodes_at_goal.unwrap() <= r.nodes_at_call_end.unwrap(),
            "{r:?}"
        );
    }
    // Same search (same seed, same clock); counted from the set, the wait has partly passed
    // when a slow search joins, so the agent starts no later.
    assert_eq!(from_join.search_ticks, from_set.search_ticks);
    assert!(
        from_set.calls <= from_join.calls,
        "{from_set:?} vs {from_join:?}"
    );
}

/// Issue 46 (F5): the expansion cap counts each tree's expansion, as Algorithm 1 runs
/// `Expend_f` and `Expend_r` one after the other, each with its own rewiring. A two-tree
/// planner under a cap of 20 grows each tree 10 times; a one-tree planner grows its one 20
/// times.
#[test]
fn the_expansion_cap_counts_each_tree() {
    let s = &builtin::MAZE;
    for (cfg, trees) in [(Config::bi_am_rrt(), 2u64), (Config::am_rrt(), 1)] {
        let mut cfg = cfg;
        cfg.budget.max_expansions = 20;
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut p = planner_on(&mut storage, s, Euclidean, cfg, 3);
        p.set_goal(s.goals[0]).unwrap();
        // A clock that never advances: only the cap ends the call.
        let frozen = bi_am_rrt::clock::FakeClock::nanos();
        let pr = p.plan(&frozen, s.start).unwrap();
        assert!(!pr.goal_in_tree, "the goal joined in the first call");
        let st = *p.stats();
        assert_eq!(pr.expansions, 20, "{trees} tree(s): {pr:?}");
        assert_eq!(st.expansions + st.reverse_expansions, 20);
        assert_eq!(st.reverse_expansions, if trees == 2 { 10 } else { 0 });
    }
}

/// Issue 46 (F6): the reference's agent rule (`Protocol::move_when_blocked`). In a 4 m wide
/// corridor a disc that spans it drops ahead of the moving agent: with this crate's rule the
/// agent holds (no collision, promise 1; the goal stays out of reach), with the reference's
/// it drives on along the blocked path through the disc to the goal, and the protocol counts
/// the collisions.
#[test]
fn the_reference_agent_rule_drives_into_a_dropped_disc() {
    let (cols, rows, cell) = (80, 8, 0.5);
    let mut bits = vec![0u8; bi_am_rrt::OccupancyGrid::bytes_needed(cols, rows)];
    bi_am_rrt::map::pack_grid(&mut bits, cols, rows, |_, _| false).unwrap();
    let grid = bi_am_rrt::OccupancyGrid::new(&bits, cols, rows, cell).unwrap();
    let (start, goal) = (Point::new(2.0, 2.0), Point::new(38.0, 2.0));
    for move_when_blocked in [false, true] {
        for seed in 1..=3 {
            let mut cfg = Config::am_rrt().for_grid(&grid);
            cfg.budget.t_exp = Duration::from_millis(5);
            let mut storage = Box::new(Storage::<N, B>::new());
            let mut p: Planner<'_, '_, _, _, N, B, K> = Planner::new(
                &mut storage,
                Map::new(grid),
                Euclidean,
                XorShiftRng::seed_from_u64(seed),
                cfg,
                start,
            )
            .unwrap();
            let proto = Protocol {
                move_when_blocked,
                max_calls: 150,
                ..Protocol::default()
            };
            let mut dropped = false;
            let r = bi_am_rrt::agent::run_to_goal(&mut p, &clock(), goal, &proto, |p, agent, _| {
                if !dropped && agent.x > 6.0 {
                    let disc = Circle::new(Point::new(agent.x + 4.0, 2.0), 2.5);
                    dropped = p.add_obstacle(disc).is_ok();
                }
            })
            .unwrap();
            assert!(dropped, "seed {seed}: no disc dropped");
            if move_when_blocked {
                // Through the disc, along the path it blocked, to the goal.
                assert!(r.collisions > 0 && r.reached, "seed {seed}: {r:?}");
            } else {
                assert_eq!(r.collisions, 0, "seed {seed}: the holding agent collided");
                assert!(!r.reached, "seed {seed}: reached through the disc");
            }
        }
    }
}
