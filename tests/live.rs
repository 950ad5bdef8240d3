//! Live map updates (issue 27): cells marked and cleared at run time through the caller-owned
//! overlay (`Map::with_overlay`, `Planner::set_cells`). A 20 m x 10 m hall at 0.1 m cells is
//! split by a wall at x = 10 m with two doors, A (y 2-3 m, on the straight line from start to
//! goal) and B (y 7-8 m). Checked: the trees' edge flags match the live cells after every
//! call; every waypoint is free of the live map; an agent whose door closes goes round and
//! never crosses the closed door; a goal cut off by a closed door joins once it opens; an
//! agent in a marked cell holds; edits are refused without an overlay or outside the grid.
//!
//! Deterministic: fixed seeds, a fake clock, a cap on expansions per call.

use std::time::Duration;

use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::error::{InputError, MapError};
use bi_am_rrt::map::pack_grid;
use bi_am_rrt::{
    Circle, Config, Euclidean, Map, OccupancyGrid, Planner, Point, Progress, Status, Storage, Wait,
};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

const CELL: f32 = 0.1;
const COLS: u16 = 200;
const ROWS: u16 = 100;
const N: usize = 1024;
const B: usize = 64;
const K: usize = 4;
const STEP: f32 = 0.1;
/// Door A's cells (inclusive corners) and door B's.
const DOOR_A: ((u16, u16), (u16, u16)) = ((100, 20), (101, 29));
const DOOR_B: ((u16, u16), (u16, u16)) = ((100, 70), (101, 79));
const START: Point = Point::new(3.0, 2.5);
const GOAL: Point = Point::new(17.0, 2.5);

fn grid() -> OccupancyGrid<'static> {
    use std::sync::OnceLock;
    static BITS: OnceLock<Vec<u8>> = OnceLock::new();
    let bits = BITS.get_or_init(|| {
        let mut bits = vec![0u8; OccupancyGrid::bytes_needed(COLS, ROWS)];
        pack_grid(&mut bits, COLS, ROWS, |c, r| {
            (100..=101).contains(&c) && !(20..=29).contains(&r) && !(70..=79).contains(&r)
        })
        .unwrap();
        bits
    });
    OccupancyGrid::new(bits, COLS, ROWS, CELL).unwrap()
}

fn config() -> Config {
    let mut cfg = Config::default().for_grid(&grid());
    cfg.budget.t_exp = Duration::from_millis(5);
    cfg.budget.max_expansions = 40;
    cfg
}

type P<'s, 'm> = Planner<'s, 'm, Euclidean, XorShiftRng, N, B, K>;

fn planner<'s, 'm>(storage: &'s mut Storage<N, B>, overlay: &'m mut [u8], seed: u64) -> P<'s, 'm> {
    let map = Map::new(grid()).with_overlay(overlay).unwrap();
    Planner::new(
        storage,
        map,
        Euclidean,
        XorShiftRng::seed_from_u64(seed),
        config(),
        START,
    )
    .unwrap()
}

fn overlay() -> Vec<u8> {
    vec![0xa5; OccupancyGrid::bytes_needed(COLS, ROWS)]
}

/// Every edge of both trees is flagged blocked exactly when it crosses a live occupied cell
/// or a dynamic obstacle.
fn check_flags<const NN: usize, const BB: usize>(
    p: &Planner<'_, '_, Euclidean, XorShiftRng, NN, BB, K>,
) {
    let map = p.map();
    for tree in [p.tree(), p.reverse_tree()] {
        tree.validate().expect("tree invariants");
        for id in tree.ids() {
            let Some(parent) = tree.parent(id) else {
                continue;
            };
            let (a, b) = (tree.position(parent).unwrap(), tree.position(id).unwrap());
            let expected = !map.live().segment_free(a, b) || map.obstacles().blocks_segment(a, b);
            assert_eq!(
                tree.edge_blocked(id),
                Some(expected),
                "edge {a:?}-{b:?} flagged wrongly"
            );
        }
    }
}

/// The waypoint is the agent's own position or reachable over a segment free of the live map.
fn check_waypoint(p: &P<'_, '_>, agent: Point, pr: &Progress) {
    if pr.waypoint != agent {
        assert!(
            p.map().free_now(agent, pr.waypoint),
            "waypoint {:?} not free from {agent:?}: {pr:?}",
            pr.waypoint
        );
    }
}

fn in_door(p: Point, door: ((u16, u16), (u16, u16))) -> bool {
    let ((c0, r0), (c1, r1)) = door;
    let lo = Point::new(c0 as f32 * CELL, r0 as f32 * CELL);
    let hi = Point::new((c1 + 1) as f32 * CELL, (r1 + 1) as f32 * CELL);
    p.x >= lo.x && p.x <= hi.x && p.y >= lo.y && p.y <= hi.y
}

/// Door A closes while the agent heads for it: it goes round through door B, every segment
/// it drives free of the live map.
fn door_closes(seed: u64) -> (bool, u32, f32) {
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut bits = overlay();
    let mut p = planner(&mut storage, &mut bits, seed);
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
    let (mut agent, mut closed, mut travelled) = (START, false, 0.0);
    for call in 0..2_000 {
        if !closed && agent.x > 7.0 {
            let (a, b) = DOOR_A;
            assert_eq!(p.set_cells(a, b, true).unwrap(), 20);
            closed = true;
        }
        let pr = p.plan(&clock, agent).unwrap();
        check_flags(&p);
        check_waypoint(&p, agent, &pr);
        if pr.status == Status::Arrived {
            return (true, call, travelled);
        }
        let next = agent.step_towards(pr.waypoint, STEP);
        assert!(
            p.map().free_now(agent, next),
            "drove {agent:?} -> {next:?} through the live map"
        );
        if closed {
            assert!(
                !in_door(next, DOOR_A),
                "through the closed door at {next:?}"
            );
        }
        travelled += agent.dist(next);
        agent = next;
    }
    (false, 2_000, travelled)
}

#[test]
fn a_closing_door_sends_the_agent_round() {
    for seed in 0..4 {
        let (arrived, calls, travelled) = door_closes(seed);
        println!("seed {seed}: arrived {arrived} in {calls} calls, travelled {travelled:.2} m");
        assert!(arrived, "seed {seed}");
        // Through door B the way is at least 2 x sqrt(7^2 + 4.5^2) = 16.6 m (door A's is 14 m).
        assert!(travelled > 16.6, "seed {seed}: {travelled}");
    }
}

/// Same seed, same edits, same clock: the same run.
#[test]
fn live_edits_are_deterministic() {
    assert_eq!(door_closes(7), door_closes(7));
}

/// Promise 4 with live edits: both doors closed, the goal cannot join (the agent holds); once
/// door B opens it joins and the agent arrives.
#[test]
fn a_goal_behind_a_closed_door_joins_when_it_opens() {
    for seed in 0..4 {
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut bits = overlay();
        let mut p = planner(&mut storage, &mut bits, seed);
        for (a, b) in [DOOR_A, DOOR_B] {
            p.set_cells(a, b, true).unwrap();
        }
        p.set_goal(GOAL).unwrap();
        let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
        let mut agent = START;
        for _ in 0..300 {
            let pr = p.plan(&clock, agent).unwrap();
            check_flags(&p);
            check_waypoint(&p, agent, &pr);
            assert!(!pr.goal_in_tree || pr.goal_cost.is_some_and(|c| c.blocked));
            agent = agent.step_towards(pr.waypoint, STEP);
            assert!(agent.x < 10.0, "seed {seed}: through a closed door");
        }
        let (a, b) = DOOR_B;
        assert_eq!(p.set_cells(a, b, false).unwrap(), 20);
        let mut arrived = None;
        for call in 0..3_000 {
            let pr = p.plan(&clock, agent).unwrap();
            check_flags(&p);
            check_waypoint(&p, agent, &pr);
            if pr.status == Status::Arrived {
                arrived = Some(call);
                break;
            }
            agent = agent.step_towards(pr.waypoint, STEP);
        }
        println!("seed {seed}: arrived {arrived:?} calls after door B opened");
        assert!(arrived.is_some(), "seed {seed}");
    }
}

/// A door that closes on the tree's edges and opens again: the edges through it reopen (no
/// node is lost), and re-flagging for a circle elsewhere leaves the walled edges blocked (the
/// two sources keep separate flags).
#[test]
fn edges_through_a_door_close_and_reopen() {
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut bits = overlay();
    let mut p = planner(&mut storage, &mut bits, 3);
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
    // Grow without moving until the goal is in the tree through door A.
    let mut joined = false;
    for _ in 0..400 {
        let pr = p.grow(&clock);
        if pr.goal_cost.is_some_and(|c| !c.blocked && c.length < 14.5) {
            joined = true;
            break;
        }
    }
    assert!(joined, "the goal never joined through door A");
    let through = |p: &P<'_, '_>| {
        let t = p.tree();
        t.ids()
            .filter(|&id| {
                t.parent(id).is_some_and(|q| {
                    let (a, b) = (t.position(q).unwrap(), t.position(id).unwrap());
                    (a.x - 10.05) * (b.x - 10.05) <= 0.0 && a.y.max(b.y) < 5.0
                })
            })
            .collect::<Vec<_>>()
    };
    let crossing = through(&p);
    assert!(!crossing.is_empty());
    let (a, b) = DOOR_A;
    p.set_cells(a, b, true).unwrap();
    // Plain growth (no rewiring past the budget) applies the edit first.
    let before = p.tree().len();
    let grow = |p: &mut P<'_, '_>| {
        let pr = p.grow(&clock);
        check_flags(p);
        pr
    };
    let pr = grow(&mut p);
    assert!(p.tree().len() >= before);
    assert!(pr.goal_cost.is_some_and(|c| c.blocked || c.length > 17.0));
    // A circle far from the door re-flags the obstacles' bit of every edge.
    p.add_obstacle(Circle::new(Point::new(15.0, 8.0), 0.3))
        .unwrap();
    check_flags(&p);
    for &id in &crossing {
        if p.tree().contains(id) && through(&p).contains(&id) {
            assert_eq!(p.tree().edge_blocked(id), Some(true));
        }
    }
    p.set_cells(a, b, false).unwrap();
    grow(&mut p);
    for &id in &crossing {
        if p.tree().contains(id) && through(&p).contains(&id) {
            assert_eq!(p.tree().edge_blocked(id), Some(false), "{id:?}");
        }
    }
}

/// An agent standing in a cell the overlay marked holds (not an error); so does one in a wall
/// cell of a map with live cells (the cell may have closed on it), and it plans again once the
/// overlay clears the cell.
#[test]
fn an_agent_in_a_marked_cell_holds() {
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut bits = overlay();
    let mut p = planner(&mut storage, &mut bits, 1);
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
    let mut agent = START;
    for _ in 0..10 {
        let pr = p.plan(&clock, agent).unwrap();
        agent = agent.step_towards(pr.waypoint, STEP);
    }
    let cell = p.map().grid().cell_of(agent).unwrap();
    p.set_cells((cell.0 - 1, cell.1 - 1), (cell.0 + 1, cell.1 + 1), true)
        .unwrap();
    let pr = p.plan(&clock, agent).unwrap();
    assert_eq!(pr.waypoint, agent);
    assert_eq!(pr.status, Status::Waiting(Wait::AgentInObstacle), "{pr:?}");
    // In a wall cell of a live map: holds, until the overlay clears it.
    let in_wall = Point::new(10.05, 5.0);
    let pr = p.plan(&clock, in_wall).unwrap();
    assert_eq!(
        (pr.waypoint, pr.status),
        (in_wall, Status::Waiting(Wait::AgentInObstacle))
    );
    p.set_cells((100, 40), (101, 60), false).unwrap();
    p.set_cells((cell.0 - 1, cell.1 - 1), (cell.0 + 1, cell.1 + 1), false)
        .unwrap();
    let pr = p.plan(&clock, in_wall).unwrap();
    assert_ne!(pr.status, Status::Waiting(Wait::AgentInObstacle), "{pr:?}");
}

/// Issue 41: a wall cell cleared with `set_cells(.., false)` and marked again while the agent
/// stands on it made `plan` return `Err(InObstacle)` (the cell looked like the grid's own wall
/// again), while a cell the grid never had occupied made it hold. A door closing on the robot
/// is an everyday event: the agent holds, and says why, in both cases.
#[test]
fn regression_door_closing_on_the_agent_holds() {
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut bits = overlay();
    let mut p = planner(&mut storage, &mut bits, 3);
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
    // Open a wall panel (x 10.0-10.2 m, y 4-6 m), stand in it, then close it again.
    p.set_cells((100, 40), (101, 60), false).unwrap();
    let in_panel = Point::new(10.05, 5.0);
    assert!(p.plan(&clock, in_panel).is_ok());
    p.set_cells((100, 40), (101, 60), true).unwrap();
    let pr = p
        .plan(&clock, in_panel)
        .expect("a door closing on the agent is not an error");
    assert_eq!(pr.waypoint, in_panel);
    assert_eq!(pr.status, Status::Waiting(Wait::AgentInObstacle), "{pr:?}");
    // A cell the grid never had occupied, marked under the agent: the same.
    let open = Point::new(5.05, 5.05);
    let c = p.map().grid().cell_of(open).unwrap();
    p.set_cells(c, c, true).unwrap();
    let pr = p.plan(&clock, open).unwrap();
    assert_eq!(pr.status, Status::Waiting(Wait::AgentInObstacle), "{pr:?}");
    // Without live cells the grid never changes: a position in its wall is an input error.
    let mut storage2 = Box::new(Storage::<N, B>::new());
    let mut fixed: P<'_, '_> = Planner::new(
        &mut storage2,
        Map::new(grid()),
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        config(),
        START,
    )
    .unwrap();
    fixed.set_goal(GOAL).unwrap();
    assert_eq!(fixed.plan(&clock, in_panel), Err(InputError::InObstacle));
}

#[test]
fn edits_are_refused_without_an_overlay_or_outside_the_grid() {
    let mut storage = Box::new(Storage::<N, B>::new());
    let mut p: P<'_, '_> = Planner::new(
        &mut storage,
        Map::new(grid()),
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        config(),
        START,
    )
    .unwrap();
    assert_eq!(p.set_cells((0, 0), (1, 1), true), Err(MapError::NoOverlay));
    let mut short = vec![0u8; OccupancyGrid::bytes_needed(COLS, ROWS) - 1];
    assert_eq!(
        Map::<'_, K>::new(grid()).with_overlay(&mut short).err(),
        Some(MapError::BufferTooShort)
    );
    let mut bits = overlay();
    let mut map: Map<'_, K> = Map::new(grid()).with_overlay(&mut bits).unwrap();
    assert_eq!(
        map.set_cells((0, 0), (COLS, 3), true),
        Err(MapError::CellOutside)
    );
    assert_eq!(map.marked_cells(), 0);
    assert!(!map.live().edited());
    // Marking twice changes the cells once; marking a wall changes nothing.
    assert_eq!(map.set_cells((5, 5), (6, 6), true), Ok(4));
    assert_eq!(map.set_cells((6, 6), (5, 5), true), Ok(0));
    assert_eq!(map.set_cells((100, 0), (100, 3), true), Ok(0));
    assert_eq!(map.marked_cells(), 4);
    assert!(map.live().is_occupied(5, 6) && !map.grid().is_occupied(5, 6));
    assert_eq!(map.set_cells((5, 5), (6, 6), false), Ok(4));
    assert!(!map.live().edited());
}

/// Random edits (marks and clears anywhere, doors included) interleaved with circles added and
/// removed and planning calls: the flags always match the live cells and every waypoint is
/// free.
#[test]
fn random_edits_keep_the_trees_exact() {
    for seed in 0..12u64 {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        let mut storage = Box::new(Storage::<N, B>::new());
        let mut bits = overlay();
        let mut p = planner(&mut storage, &mut bits, seed);
        p.set_goal(GOAL).unwrap();
        let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
        let mut agent = START;
        for _ in 0..400 {
            let r = rng.next_u32();
            if r % 5 == 0 {
                let c = (rng.next_u32() % u32::from(COLS)) as u16;
                let row = (rng.next_u32() % u32::from(ROWS)) as u16;
                let (w, h) = ((rng.next_u32() % 12) as u16, (rng.next_u32() % 12) as u16);
                let far = ((c + w).min(COLS - 1), (row + h).min(ROWS - 1));
                p.set_cells((c, row), far, r % 2 == 0).unwrap();
            } else if r % 23 == 1 {
                let door = if r % 2 == 0 { DOOR_A } else { DOOR_B };
                p.set_cells(door.0, door.1, r % 3 == 0).unwrap();
            } else if r % 7 == 2 {
                // A circle somewhere (re-flags the obstacles' bit of every edge), or one less.
                if p.map().obstacles().len() < K && r % 2 == 0 {
                    let c = Point::new(
                        (rng.next_u32() % 200) as f32 * 0.1,
                        (rng.next_u32() % 100) as f32 * 0.1,
                    );
                    let _ = p.add_obstacle(Circle::new(c, 0.2));
                } else {
                    let first = p.map().obstacles().iter().next().map(|(id, _)| id);
                    if let Some(id) = first {
                        p.remove_obstacle(id).unwrap();
                    }
                }
            }
            let pr = match p.plan(&clock, agent) {
                Ok(pr) => pr,
                Err(e) => panic!("seed {seed}: {e} at {agent:?}"),
            };
            check_flags(&p);
            check_waypoint(&p, agent, &pr);
            if pr.status == Status::Arrived {
                break;
            }
            agent = agent.step_towards(pr.waypoint, STEP);
        }
    }
}

/// A lidar's kind of edits on a fine map (30 m x 20 m at 0.05 m, pillars): from the 20th call
/// on, before every call, a 7 x 7-cell blob (a person) moves to a random place within 3 m of
/// the agent and 20 single cells within 4 m are marked or cleared. The flags stay exact,
/// every waypoint is free, the agent arrives, and the edges re-tested per call are counted
/// (2 x 2,048 nodes; 150 ms at 1.6 us a unit, a Cortex-M4F's pace).
#[test]
fn lidar_like_edits_on_a_fine_map() {
    const C: u16 = 600;
    const R: u16 = 400;
    const F: f32 = 0.05;
    let mut rng = XorShiftRng::seed_from_u64(5);
    let pillars: Vec<(f32, f32)> = (0..40)
        .map(|_| {
            (
                3.0 + (rng.next_u32() % 2400) as f32 / 100.0,
                (rng.next_u32() % 2000) as f32 / 100.0,
            )
        })
        .collect();
    let mut bits = vec![0u8; OccupancyGrid::bytes_needed(C, R)];
    pack_grid(&mut bits, C, R, |c, r| {
        let (x, y) = ((c as f32 + 0.5) * F, (r as f32 + 0.5) * F);
        (y - 10.0).abs() > 0.6
            && pillars
                .iter()
                .any(|&(px, py)| (x - px).abs() < 0.4 && (y - py).abs() < 0.4)
    })
    .unwrap();
    let grid = OccupancyGrid::new(&bits, C, R, F).unwrap();
    let mut overlay = vec![0u8; bits.len()];
    let map: Map<'_, K> = Map::new(grid).with_overlay(&mut overlay).unwrap();
    let mut cfg = Config::default().for_grid(&grid);
    cfg.budget.t_exp = Duration::from_millis(150);
    let mut storage = Box::new(Storage::<2048, 256>::new());
    let (start, goal) = (Point::new(2.0, 10.0), Point::new(28.0, 10.0));
    let mut p: Planner<'_, '_, _, _, 2048, 256, K> = Planner::new(
        &mut storage,
        map,
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        cfg,
        start,
    )
    .unwrap();
    p.set_goal(goal).unwrap();
    let clock = FakeClock::nanos().with_work_cost(1600).with_step(1);
    let budget = 150_000_000 / 1600;
    let mut agent = start;
    let (mut most_work, mut most_retested, mut before) = (0u64, 0u64, 0u64);
    let mut blob: Option<(u16, u16)> = None;
    let near = |rng: &mut XorShiftRng, at: (u16, u16), reach: i32, hi: (u16, u16)| {
        let d = |rng: &mut XorShiftRng| (rng.next_u32() % (2 * reach as u32)) as i32 - reach;
        (
            (at.0 as i32 + d(rng)).clamp(0, hi.0 as i32) as u16,
            (at.1 as i32 + d(rng)).clamp(0, hi.1 as i32) as u16,
        )
    };
    let mut arrived = false;
    for call in 0..400 {
        if call >= 20 {
            if let Some((c, r)) = blob {
                p.set_cells((c, r), (c + 6, r + 6), false).unwrap();
            }
            let at = grid.cell_of(agent).unwrap();
            let (c, r) = near(&mut rng, at, 60, (C - 8, R - 8));
            p.set_cells((c, r), (c + 6, r + 6), true).unwrap();
            blob = Some((c, r));
            for _ in 0..20 {
                let cell = near(&mut rng, at, 80, (C - 1, R - 1));
                p.set_cells(cell, cell, rng.next_u32() % 2 == 0).unwrap();
            }
        }
        let pr = p.plan(&clock, agent).unwrap();
        check_flags(&p);
        if pr.waypoint != agent {
            assert!(p.map().free_now(agent, pr.waypoint), "{pr:?}");
        }
        let retested = p.stats().retested - before;
        before = p.stats().retested;
        if call >= 20 {
            most_work = most_work.max(pr.work);
            most_retested = most_retested.max(retested);
        }
        if pr.status == Status::Arrived {
            arrived = true;
            break;
        }
        agent = agent.step_towards(pr.waypoint, 0.7);
    }
    println!(
        "lidar-like edits: most work in a call {most_work} units (budget {budget}), most edges \
         re-tested in a call {most_retested}"
    );
    assert!(arrived);
}
