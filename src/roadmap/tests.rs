//! The roadmap's unit tests: its format, its search and the planner's use of it.

use super::*;
use crate::clock::FakeClock;
use crate::error::RoadmapError;
use crate::map::{Circle, Map, OccupancyGrid, pack_grid};
use crate::metric::{Euclidean, map_hash};
use crate::planner::{Planner, Status, Storage};
use crate::{Config, Point};
use rand_core::SeedableRng;

const COLS: u16 = 20;
const ROWS: u16 = 20;
const BYTES: usize = OccupancyGrid::bytes_needed(COLS, ROWS);

/// A 20 m map, 1 m cells, a wall along column 10 from the top (row 0) to row 15: from
/// (5.5, 5.5) to (15.5, 5.5) the way goes round the wall's end.
fn wall_bits() -> [u8; BYTES] {
    let mut bits = [0u8; BYTES];
    pack_grid(&mut bits, COLS, ROWS, |c, r| c == 10 && r <= 15).unwrap();
    bits
}

const START: Point = Point::new(5.5, 5.5);
const GOAL: Point = Point::new(15.5, 5.5);

/// The roadmap of the wall map: a node 0.6 cells off each convex corner of the wall's end
/// (the vertices (10, 16) and (11, 16)), an edge between them, written for `grid`.
fn wall_roadmap(grid: &OccupancyGrid<'_>, out: &mut [u8]) -> usize {
    let nodes = [Point::new(9.4, 16.6), Point::new(11.6, 16.6)];
    // Diagonals into the occupied cell (10, 15): (+1, -1) and (-1, -1).
    let corners = [1u8, 0];
    write(grid, &nodes, &corners, &[0, 1, 2], &[1, 0], out).unwrap()
}

#[test]
fn a_roadmap_reads_back_what_was_written() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let mut buf = [0u8; 256];
    let n = wall_roadmap(&grid, &mut buf);
    assert_eq!(n, bytes_needed(2, 2));
    let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
    assert_eq!((rm.len(), rm.edges()), (2, 1));
    assert_eq!(rm.node(1), Some(Point::new(11.6, 16.6)));
    assert_eq!(rm.neighbours(0).collect::<heapless::Vec<_, 4>>(), [1]);
    assert_eq!(rm.map_hash(), map_hash(&grid).unwrap());
    // Tangency: along the wall's end, yes; into the wall's cell along its diagonal, no.
    assert!(rm.tangent(0, Point::new(11.6, 16.6)));
    assert!(!rm.tangent(0, Point::new(8.4, 17.6)));
}

#[test]
fn a_damaged_roadmap_is_refused_with_its_reason() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let mut buf = [0u8; 256];
    let n = wall_roadmap(&grid, &mut buf);
    let good = &buf[..n];
    assert_eq!(
        Roadmap::from_bytes(&good[..10]).err(),
        Some(RoadmapError::Truncated)
    );
    assert_eq!(
        Roadmap::from_bytes(&good[..n - 4]).err(),
        Some(RoadmapError::Truncated)
    );
    let mut bad = [0u8; 256];
    bad[..n].copy_from_slice(good);
    bad[0] = b'X';
    assert_eq!(
        Roadmap::from_bytes(&bad[..n]).err(),
        Some(RoadmapError::BadMagic)
    );
    bad[..n].copy_from_slice(good);
    bad[4] = 9;
    assert_eq!(
        Roadmap::from_bytes(&bad[..n]).err(),
        Some(RoadmapError::UnsupportedVersion)
    );
    // An edge to a node that does not exist (the last two bytes name node 0's neighbour).
    bad[..n].copy_from_slice(good);
    let far = n - 4;
    bad[far..far + 2].copy_from_slice(&7u16.to_le_bytes());
    assert_eq!(
        Roadmap::from_bytes(&bad[..n]).err(),
        Some(RoadmapError::BadHeader)
    );
    // A position that is not finite.
    bad[..n].copy_from_slice(good);
    bad[HEADER_BYTES..HEADER_BYTES + 4].copy_from_slice(&f32::NAN.to_bits().to_le_bytes());
    assert_eq!(
        Roadmap::from_bytes(&bad[..n]).err(),
        Some(RoadmapError::BadHeader)
    );
    // Every prefix and every single-byte change is refused or read without a panic.
    for cut in 0..n {
        let _ = Roadmap::from_bytes(&good[..cut]);
    }
    for at in 0..n {
        bad[..n].copy_from_slice(good);
        bad[at] ^= 0xa5;
        if let Ok(rm) = Roadmap::from_bytes(&bad[..n]) {
            for i in 0..rm.len() {
                let _ = rm.neighbours(i).count();
            }
        }
    }
}

fn planner_on<'s, 'm>(
    storage: &'s mut Storage<64, 16>,
    map: Map<'m, 2>,
    cfg: Config,
) -> Planner<'s, 'm, Euclidean, rand_xorshift::XorShiftRng, 64, 16, 2> {
    let rng = rand_xorshift::XorShiftRng::seed_from_u64(3);
    Planner::new(storage, map, Euclidean, rng, cfg, START).unwrap()
}

/// Sets the goal at [`GOAL`] and plans once from [`START`]: the goal joins over the roadmap in
/// that call, its first path `want` long, every segment of the path free.
fn joins_over_the_roadmap_in_the_first_call(
    p: &mut Planner<'_, '_, Euclidean, rand_xorshift::XorShiftRng, 64, 16, 2>,
    want: f32,
    case: &dyn core::fmt::Debug,
) {
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(10).with_step(1);
    let progress = p.plan(&clock, START).unwrap();
    assert!(progress.goal_in_tree && p.stats().roadmap, "{case:?}");
    let first = p.stats().first_cost.unwrap();
    assert!((first - want).abs() < 1e-3, "{case:?}: {first} vs {want}");
    let mut path = [Point::ZERO; 16];
    let info = p.path(&mut path).unwrap();
    for w in path[..info.len].windows(2) {
        assert!(p.map().free_path(w[0], w[1]), "{case:?}: {:?}", w);
    }
}

/// A default planner on `grid` (one tree or two), one expansion a call, `rm` attached.
fn one_step_planner<'s, 'm>(
    storage: &'s mut Storage<64, 16>,
    grid: OccupancyGrid<'m>,
    rm: Roadmap<'m>,
    bidirectional: bool,
) -> Planner<'s, 'm, Euclidean, rand_xorshift::XorShiftRng, 64, 16, 2> {
    let mut cfg = Config::default().for_grid(&grid);
    cfg.bidirectional = bidirectional;
    cfg.budget.max_expansions = 1;
    let mut p = planner_on(storage, Map::new(grid), cfg);
    p.set_roadmap(Some(rm)).unwrap();
    p
}

/// With the roadmap, the goal joins in the first call over the roadmap's path (start, both
/// corner nodes, goal), before any expansion could; every edge of the path is free; the agent
/// then drives it to the goal.
#[test]
fn the_goal_joins_over_the_roadmap_in_the_first_call() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let mut buf = [0u8; 256];
    let n = wall_roadmap(&grid, &mut buf);
    let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
    for bidirectional in [true, false] {
        let mut storage = Storage::<64, 16>::new();
        let mut p = one_step_planner(&mut storage, grid, rm, bidirectional);
        p.set_goal(GOAL).unwrap();
        let clock = FakeClock::nanos().with_work_cost(10).with_step(1);
        let progress = p.plan(&clock, START).unwrap();
        assert!(progress.goal_in_tree, "bidirectional {bidirectional}");
        assert!(p.stats().roadmap);
        let mut path = [Point::ZERO; 16];
        let info = p.path(&mut path).unwrap();
        assert!(info.to_goal && !info.blocked);
        let path = &path[..info.len];
        // The first path is the roadmap's (rewiring in the same call may shorten it since).
        let (a, b) = (Point::new(9.4, 16.6), Point::new(11.6, 16.6));
        let want = START.dist(a) + a.dist(b) + b.dist(GOAL);
        let first = p.stats().first_cost.unwrap();
        assert!((first - want).abs() < 1e-3, "{first} vs {want}");
        for w in path.windows(2) {
            assert!(p.map().free_path(w[0], w[1]), "{:?}", w);
        }
        if !bidirectional {
            assert_eq!(
                p.reverse_tree().len(),
                0,
                "the borrowed reverse arena is emptied"
            );
        }
        let mut agent = progress.waypoint;
        let mut arrived = false;
        for _ in 0..200 {
            let progress = p.plan(&clock, agent).unwrap();
            assert!(p.map().free_path(agent, progress.waypoint));
            agent = agent.step_towards(progress.waypoint, 0.7);
            if progress.status == Status::Arrived {
                arrived = true;
                break;
            }
        }
        assert!(arrived, "bidirectional {bidirectional}");
    }
}

/// A disc on the roadmap's edge: the path found is tested, refused, and the trees search as
/// they would have (nothing of the roadmap kept); the goal still joins.
#[test]
fn a_blocked_roadmap_path_is_dropped_and_the_trees_search() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let mut buf = [0u8; 256];
    let n = wall_roadmap(&grid, &mut buf);
    let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
    let mut storage = Storage::<64, 16>::new();
    let mut cfg = Config::default().for_grid(&grid);
    cfg.budget.max_expansions = 1;
    let mut p = planner_on(&mut storage, Map::new(grid), cfg);
    p.set_roadmap(Some(rm)).unwrap();
    p.add_obstacle(Circle::new(Point::new(10.5, 16.6), 0.3))
        .unwrap();
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(10).with_step(1);
    let progress = p.plan(&clock, START).unwrap();
    assert!(!p.stats().roadmap);
    assert!(!progress.goal_in_tree);
    let rev = p.reverse_tree();
    let roadmap_nodes = [Point::new(9.4, 16.6), Point::new(11.6, 16.6)];
    assert!(
        rev.ids()
            .all(|i| !roadmap_nodes.contains(&rev.position(i).unwrap())),
        "no roadmap node kept"
    );
    let mut agent = START;
    for _ in 0..400 {
        let progress = p.plan(&clock, agent).unwrap();
        assert!(p.map().free_path(agent, progress.waypoint));
        agent = agent.step_towards(progress.waypoint, 0.7);
        if progress.status == Status::Arrived {
            return;
        }
    }
    panic!("the trees did not reach the goal");
}

/// A roadmap node the root or the goal does not see is dropped (the root's are tested before
/// the search opens, the goal's once the way the search settles on ends there): here a disc
/// hides the root's (the goal's) nearest node, a corner of the wall's end that gives the
/// shortest way, and the search goes on with the next, a node above the root (the goal) that
/// reaches the wall's end over an edge: the goal joins in the first call over that way, every
/// segment of it free.
#[test]
fn a_node_an_end_does_not_see_is_dropped_and_the_search_goes_on() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let (a, b) = (Point::new(9.4, 16.6), Point::new(11.6, 16.6));
    for root_side in [true, false] {
        // The wall end's corners and a node C (no corner) above the root or the goal, in
        // order of x, joined in a chain; a disc on the segment from that end to its corner
        // (at y 10.5), clear of its segment to C.
        let (c, nodes, corners, disc, want) = if root_side {
            let c = Point::new(7.5, 17.5);
            let want = START.dist(c) + c.dist(a) + a.dist(b) + b.dist(GOAL);
            (c, [c, a, b], [NO_CORNER, 1, 0], Point::new(7.3, 10.5), want)
        } else {
            let c = Point::new(13.5, 17.5);
            let want = START.dist(a) + a.dist(b) + b.dist(c) + c.dist(GOAL);
            (
                c,
                [a, b, c],
                [1, 0, NO_CORNER],
                Point::new(13.7, 10.5),
                want,
            )
        };
        let mut buf = [0u8; 256];
        let n = write(
            &grid,
            &nodes,
            &corners,
            &[0, 1, 3, 4],
            &[1, 0, 2, 1],
            &mut buf,
        )
        .unwrap();
        let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
        let end = if root_side { START } else { GOAL };
        let corner = if root_side { a } else { b };
        for bidirectional in [false, true] {
            let case = (root_side, bidirectional);
            let mut storage = Storage::<64, 16>::new();
            let mut p = one_step_planner(&mut storage, grid, rm, bidirectional);
            p.add_obstacle(Circle::new(disc, 0.5)).unwrap();
            assert!(!p.map().free_path(end, corner) && p.map().free_path(end, c));
            joins_over_the_roadmap_in_the_first_call(&mut p, want, &case);
        }
    }
}

/// Found on MovingAI's maze of 8-cell corridors with a 0.5 m body (issue 42): a start or a goal
/// beside a wall had its 8 nearest roadmap nodes behind the walls, so it saw none of them, the
/// search ended with no path and the trees took 30-85 ms (or more than 0.1 s) where the
/// roadmap's way takes about 1 ms. An end that sees none of its candidates, or whose
/// candidates the search cannot reach, now takes the next nearest. On the wall map, a box
/// beside the start and one beside the goal (walls of one cell round 3 x 3 free cells) hold 9
/// nodes each, nearer their end than the wall end's corners and hidden from it: with those of
/// the start's box, the goal's (joined to nothing, so the search cannot reach them, or joined
/// to the corner beside the goal, so each way the search settles on ends at one the goal does
/// not see), or both, one tree or two, the goal joins in the first call over the wall end's
/// corners.
#[test]
fn regression_an_end_that_sees_none_of_its_nearest_nodes_takes_the_next() {
    let mut bits = [0u8; BYTES];
    let in_box = |c: u16, r: u16, c0: u16| (c0..c0 + 5).contains(&c) && (8..13).contains(&r);
    let inside = |c: u16, r: u16, c0: u16| (c0 + 1..c0 + 4).contains(&c) && (9..12).contains(&r);
    pack_grid(&mut bits, COLS, ROWS, |c, r| {
        (c == 10 && r <= 15)
            || (in_box(c, r, 1) && !inside(c, r, 1))
            || (in_box(c, r, 15) && !inside(c, r, 15))
    })
    .unwrap();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let (a, b) = (Point::new(9.4, 16.6), Point::new(11.6, 16.6));
    let want = START.dist(a) + a.dist(b) + b.dist(GOAL);
    let decoys =
        |c0: f32| (0..9).map(move |k| Point::new(c0 + 1.5 + (k / 3) as f32, 9.5 + (k % 3) as f32));
    let cases = [
        (true, false, false),
        (false, true, false),
        (false, true, true),
        (true, true, true),
    ];
    for (start_box, goal_box, joined) in cases {
        // Nodes in order of x: the start box's, the wall end's corners, the goal box's; an
        // edge joins the corners, and the corner beside the goal to its box's nodes if
        // `joined`.
        let mut nodes: heapless::Vec<Point, 20> = heapless::Vec::new();
        let mut corners: heapless::Vec<u8, 20> = heapless::Vec::new();
        if start_box {
            for p in decoys(1.0) {
                nodes.push(p).unwrap();
                corners.push(NO_CORNER).unwrap();
            }
        }
        let ia = nodes.len();
        nodes.extend_from_slice(&[a, b]).unwrap();
        corners.extend_from_slice(&[1, 0]).unwrap();
        if goal_box {
            for p in decoys(15.0) {
                nodes.push(p).unwrap();
                corners.push(NO_CORNER).unwrap();
            }
        }
        for p in decoys(1.0).chain(decoys(15.0)) {
            assert!(!grid_free(&grid, START, p) && !grid_free(&grid, GOAL, p));
        }
        let ib = ia + 1;
        let mut edges: heapless::Vec<(usize, usize), 20> = heapless::Vec::new();
        edges.push((ia, ib)).unwrap();
        if joined {
            for d in ib + 1..nodes.len() {
                edges.push((ib, d)).unwrap();
            }
        }
        // Each node's edges, both ways, in order of the far node.
        let mut first = [0u32; 21];
        let mut far: heapless::Vec<u16, 40> = heapless::Vec::new();
        for (i, f) in first.iter_mut().enumerate().take(nodes.len()) {
            *f = far.len() as u32;
            for j in 0..nodes.len() {
                if edges.contains(&(i, j)) || edges.contains(&(j, i)) {
                    far.push(j as u16).unwrap();
                }
            }
        }
        first[nodes.len()] = far.len() as u32;
        let mut buf = [0u8; 512];
        let n = write(
            &grid,
            &nodes,
            &corners,
            &first[..=nodes.len()],
            &far,
            &mut buf,
        )
        .unwrap();
        let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
        for bidirectional in [false, true] {
            let case = (start_box, goal_box, joined, bidirectional);
            let mut storage = Storage::<64, 16>::new();
            let mut p = one_step_planner(&mut storage, grid, rm, bidirectional);
            joins_over_the_roadmap_in_the_first_call(&mut p, want, &case);
        }
    }
}

/// Whether the segment from `a` to `b` is free on `grid` alone.
fn grid_free(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> bool {
    Map::<2>::new(*grid).free_path(a, b)
}

/// A roadmap of another map, or one with more nodes than the reverse arena has free slots,
/// is refused with its reason; the paper's configuration (tactic off) ignores a roadmap.
#[test]
fn a_roadmap_of_another_map_or_too_large_is_refused() {
    let bits = wall_bits();
    let grid = OccupancyGrid::new(&bits, COLS, ROWS, 1.0).unwrap();
    let mut other_bits = [0u8; BYTES];
    pack_grid(&mut other_bits, COLS, ROWS, |c, r| c == 9 && r <= 15).unwrap();
    let other = OccupancyGrid::new(&other_bits, COLS, ROWS, 1.0).unwrap();
    let mut buf = [0u8; 256];
    let n = wall_roadmap(&other, &mut buf);
    let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
    let mut storage = Storage::<64, 16>::new();
    let cfg = Config::default().for_grid(&grid);
    let mut p = planner_on(&mut storage, Map::new(grid), cfg);
    assert_eq!(p.set_roadmap(Some(rm)), Err(RoadmapError::WrongMap));
    // 64 nodes in a row: one more than the arena's free slots.
    let nodes: [Point; 64] = core::array::from_fn(|i| Point::new(0.5 + 0.25 * i as f32, 19.5));
    let first = [0u32; 65];
    let mut big = [0u8; 1024];
    let n = write(&grid, &nodes, &[NO_CORNER; 64], &first, &[], &mut big).unwrap();
    let rm = Roadmap::from_bytes(&big[..n]).unwrap();
    assert_eq!(p.set_roadmap(Some(rm)), Err(RoadmapError::TooLarge));
    // The paper's planner ignores a roadmap.
    let n = wall_roadmap(&grid, &mut buf);
    let rm = Roadmap::from_bytes(&buf[..n]).unwrap();
    let mut storage = Storage::<64, 16>::new();
    let mut cfg = Config::paper().for_grid(&grid);
    cfg.budget.max_expansions = 1;
    let mut p = planner_on(&mut storage, Map::new(grid), cfg);
    p.set_roadmap(Some(rm)).unwrap();
    p.set_goal(GOAL).unwrap();
    let clock = FakeClock::nanos().with_work_cost(10).with_step(1);
    p.plan(&clock, START).unwrap();
    assert!(!p.stats().roadmap);
}

/// The comb of [`regression_a_roadmap_path_longer_than_128_nodes_joins`]: 70 walls, from the
/// top and the bottom in turn (1 m cells, two free columns between them).
const WALLS: u16 = 70;
const COMB_COLS: u16 = 3 * WALLS + 3;
const COMB_ROWS: u16 = 20;
const COMB_BYTES: usize = OccupancyGrid::bytes_needed(COMB_COLS, COMB_ROWS);

fn comb_bits() -> [u8; COMB_BYTES] {
    let top = |i: u16| i.is_multiple_of(2);
    let mut bits = [0u8; COMB_BYTES];
    pack_grid(&mut bits, COMB_COLS, COMB_ROWS, |c, r| {
        c >= 2 && (c - 2) % 3 == 0 && {
            let i = (c - 2) / 3;
            i < WALLS && if top(i) { r <= 15 } else { r >= 4 }
        }
    })
    .unwrap();
    bits
}

/// The comb's roadmap, written into `buf` (its length returned), with a start and a goal at
/// its two ends and the length of the roadmap's way between them: a node half a cell off
/// each wall's end, either side of it, in a chain of edges. The start sees past the first
/// node and the goal past the last: the shortest way over the roadmap leaves both out.
fn comb_roadmap(grid: &OccupancyGrid<'_>, buf: &mut [u8]) -> (usize, (Point, Point), f32) {
    let top = |i: u16| i.is_multiple_of(2);
    let mut nodes = [Point::ZERO; 2 * WALLS as usize];
    for i in 0..WALLS {
        let c = f32::from(3 * i + 2);
        let y = if top(i) { 16.5 } else { 3.5 };
        nodes[2 * usize::from(i)] = Point::new(c - 0.5, y);
        nodes[2 * usize::from(i) + 1] = Point::new(c + 1.5, y);
    }
    let n = nodes.len();
    let corners = [NO_CORNER; 2 * WALLS as usize];
    let mut first = [0u32; 2 * WALLS as usize + 1];
    let mut far = [0u16; 2 * (2 * WALLS as usize - 1)];
    let mut e = 0usize;
    for (i, f) in first.iter_mut().enumerate().take(n) {
        *f = e as u32;
        if i > 0 {
            far[e] = (i - 1) as u16;
            e += 1;
        }
        if i + 1 < n {
            far[e] = (i + 1) as u16;
            e += 1;
        }
    }
    first[n] = e as u32;
    let len = write(grid, &nodes, &corners, &first, &far, buf).unwrap();
    let ends = (
        Point::new(0.5, 17.5),
        Point::new(f32::from(COMB_COLS) - 1.5, 2.5),
    );
    let inner = &nodes[1..n - 1];
    let want = ends.0.dist(inner[0])
        + inner.windows(2).map(|w| w[0].dist(w[1])).sum::<f32>()
        + inner[inner.len() - 1].dist(ends.1);
    (len, ends, want)
}

/// A planner of `N` slots a tree on the comb, the roadmap attached and the goal set.
fn comb<'s, 'm, const N: usize>(
    storage: &'s mut Storage<N, 16>,
    grid: OccupancyGrid<'m>,
    rm: Roadmap<'m>,
    cfg: Config,
    (start, goal): (Point, Point),
) -> Planner<'s, 'm, Euclidean, rand_xorshift::XorShiftRng, N, 16, 2> {
    let rng = rand_xorshift::XorShiftRng::seed_from_u64(3);
    let mut p = Planner::new(storage, Map::<2>::new(grid), Euclidean, rng, cfg, start).unwrap();
    p.set_roadmap(Some(rm)).unwrap();
    p.set_goal(goal).unwrap();
    p
}

/// Runs `f` on the comb's grid and roadmap, with the roadmap's ends and its way's length.
fn on_comb(f: impl FnOnce(OccupancyGrid<'_>, Roadmap<'_>, (Point, Point), f32)) {
    let bits = comb_bits();
    let grid = OccupancyGrid::new(&bits, COMB_COLS, COMB_ROWS, 1.0).unwrap();
    let mut buf = [0u8; 4096];
    let (len, ends, want) = comb_roadmap(&grid, &mut buf);
    f(grid, Roadmap::from_bytes(&buf[..len]).unwrap(), ends, want);
}

/// Every segment of the planner's path is free.
fn assert_path_free<const N: usize>(
    p: &Planner<'_, '_, Euclidean, rand_xorshift::XorShiftRng, N, 16, 2>,
) -> usize {
    let mut path = [Point::ZERO; 512];
    let info = p.path(&mut path).unwrap();
    assert!(info.to_goal);
    for w in path[..info.len].windows(2) {
        assert!(p.map().free_path(w[0], w[1]), "{:?}", w);
    }
    info.len
}

/// Found on a MovingAI maze of 8-cell corridors (issue 42): its legs' roadmap paths have 164-201
/// nodes and the search kept at most 128, so the roadmap never joined there and its search
/// was wasted. The path now stays in the arena's last free slots, whatever its length. On the
/// comb the way zigzags round every wall's end, 140 roadmap nodes. With 512 slots a tree the
/// goal joins over them in the first call; with 256 the branch and the path would overlap in
/// the arena, so the path is dropped and the trees search.
#[test]
fn regression_a_roadmap_path_longer_than_128_nodes_joins() {
    on_comb(|grid, rm, ends, want| {
        let mut cfg = Config::default().for_grid(&grid);
        cfg.bidirectional = false;
        cfg.budget.max_expansions = 1;
        let clock = FakeClock::nanos().with_work_cost(10).with_step(1);
        // 512 slots: the 140-node branch joins in the first call, its cost the roadmap path's.
        let mut storage = Storage::<512, 16>::new();
        let mut p = comb(&mut storage, grid, rm, cfg, ends);
        let progress = p.plan(&clock, ends.0).unwrap();
        assert!(progress.goal_in_tree && p.stats().roadmap);
        let first_cost = p.stats().first_cost.unwrap();
        assert!((first_cost - want).abs() < 1e-2, "{first_cost} vs {want}");
        let nodes = assert_path_free(&p);
        assert!(nodes > 128, "{nodes} nodes");
        // 256 slots: 1 + 2 x 140 > 256, the path is dropped; the arena is left empty.
        let mut storage = Storage::<256, 16>::new();
        let mut p = comb(&mut storage, grid, rm, cfg, ends);
        p.plan(&clock, ends.0).unwrap();
        assert!(!p.stats().roadmap);
        assert_eq!(p.reverse_tree().len(), 0);
    });
}

/// Found on the MovingAI maze with calls of 50 us (issue 42): the roadmap's search ran only in
/// a new goal's first call and was dropped at that call's deadline, so a caller whose calls
/// are shorter than the search never got the roadmap's path (the trees took 11-16 ms where
/// the search takes 0.25 ms). The search now goes on in the next calls, the trees waiting.
/// On the comb, with calls of 2 us (200 work units) and with a clock that never advances and
/// a work cap of 300 units a call, one tree and two: the goal joins over the roadmap after
/// several calls, with the roadmap path's cost, before any tree expansion; every segment of
/// the path is free.
#[test]
fn regression_a_call_shorter_than_the_roadmap_search_keeps_it() {
    on_comb(|grid, rm, ends, want| {
        for bidirectional in [false, true] {
            for frozen in [false, true] {
                let mut cfg = Config::default().for_grid(&grid);
                cfg.bidirectional = bidirectional;
                let clock = if frozen {
                    cfg.budget.max_work = 300;
                    FakeClock::nanos()
                } else {
                    cfg.budget.t_exp = core::time::Duration::from_micros(2);
                    FakeClock::nanos().with_work_cost(10).with_step(1)
                };
                let case = (bidirectional, frozen);
                let mut storage = Storage::<512, 16>::new();
                let mut p = comb(&mut storage, grid, rm, cfg, ends);
                let mut calls = 0;
                while calls < 100 {
                    calls += 1;
                    let progress = p.plan(&clock, ends.0).unwrap();
                    if progress.goal_in_tree {
                        break;
                    }
                    assert_eq!(
                        p.stats().expansions,
                        0,
                        "{case:?}: the trees wait (call {calls})"
                    );
                }
                assert!(calls > 2, "{case:?}: the search fits one call ({calls})");
                assert!(p.stats().roadmap, "{case:?}: joined without the roadmap");
                let first_cost = p.stats().first_cost.unwrap();
                assert!(
                    (first_cost - want).abs() < 1e-2,
                    "{case:?}: {first_cost} vs {want}"
                );
                assert_path_free(&p);
            }
        }
    });
}
