//! Promise 2: no input makes the core panic; bad input gets an `Err` naming the problem, and
//! the trees stay valid, down to the tiniest capacities. The link-time proof is
//! `firmware/panic-never`; the fuzz targets (`fuzz/`) explore inputs without end.
//! Deterministic: virtual clock, fixed seeds.

mod common;

use bi_am_rrt::builtin::{self};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::error::{InputError, SetupError};
use bi_am_rrt::map::{Circle, OccupancyGrid};
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::{Config, Euclidean, Map, Planner, Point, Status, Storage};
use common::checked::{K, Tally, clock, drive_checked, drive_with_drops, planner};
use common::e2e::planner_on;
use common::landmark_table;
use rand_core::SeedableRng;
use rand_xorshift::XorShiftRng;

/// Issue 7, case 3: `OccupancyGrid::new(&[0], 2, 2, 1e19)` and `Planner::new` succeeded, then
/// `plan()` panicked in `f32::clamp` (the spatial index had overflowed to a 0 x 0 grid).
#[test]
fn regression_release_panic_on_an_accepted_huge_map() {
    static BITS: [u8; 1] = [0];
    for cell in [1.0e19f32, 1.0e30, 1.0e-30, 1.0e-3] {
        let grid = OccupancyGrid::new(&BITS, 2, 2, cell).unwrap();
        let mut storage = Box::new(Storage::<64, 8>::new());
        let mut cfg = Config::bi_am_rrt();
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

/// Tiny capacities (issue 7): arenas of 64 nodes and far fewer, with obstacles dropped on the
/// way, keep returning valid waypoints (or a clear state) and never corrupt a tree; without
/// obstacles, 64 and 16 nodes are enough to cross the open field.
#[test]
fn tiny_capacities_stay_valid() {
    fn run<const N: usize, const B: usize>(seed: u64, drops: bool) -> Tally {
        let s = &builtin::OPEN;
        let mut storage = Box::new(Storage::<N, B>::new());
        let cfg = Config::bi_am_rrt();
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
/// refuses a table of another size or cell (every version), and a version-3 or -4 table
/// (pieces or uniform, the layouts host-sim writes) of another grid of the same size (its
/// recorded hash), with `SetupError::Metric(WrongMap)`.
#[test]
fn regression_a_table_of_another_map_is_refused() {
    use bi_am_rrt::Metric;
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
        let cfg = Config::bi_am_rrt();
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
    // Issue 44: a uniform table is bound to its map too (version 4, the hash before the
    // entries), and reads the same distances as the version-1 table of the same entries.
    let uniform = |bits: &[u8], n: u16, stamp: bool| {
        let g = OccupancyGrid::new(bits, n, n, 1.0).unwrap();
        let header = TableHeader {
            kind: ElementKind::F32,
            dims: 2,
            cols: n,
            rows: n,
            cell_size: 1.0,
            scale: 1.0,
            layout: Layout::Uniform,
            map_hash: stamp.then(|| fnv1a32(bits)),
        };
        let mut out = vec![0u8; header.table_len().unwrap()];
        bi_am_rrt::metric::write_table(&header, &mut out, |c, r, xy| {
            xy[0] = c as f32;
            xy[1] = r as f32;
            !g.is_occupied(c, r)
        })
        .unwrap();
        out
    };
    for stamp in [false, true] {
        let t = uniform(&small, 150, stamp);
        assert_eq!(
            DiffusionTable::new(&t).unwrap().header().version(),
            if stamp { 4 } else { 1 }
        );
        assert_eq!(try_plan(&small, 150, &t), Ok(()), "stamp {stamp}");
        assert_eq!(try_plan(&big, 200, &t), wrong, "stamp {stamp}");
    }
    assert_eq!(try_plan(&other, 150, &uniform(&small, 150, true)), wrong);
    assert_eq!(try_plan(&other, 150, &uniform(&small, 150, false)), Ok(()));
    let (v1, v4) = (uniform(&small, 150, false), uniform(&small, 150, true));
    let (v1, v4) = (
        DiffusionTable::new(&v1).unwrap(),
        DiffusionTable::new(&v4).unwrap(),
    );
    for (a, b) in [
        ((1.5, 1.5), (140.5, 120.5)),
        ((10.2, 3.3), (10.2, 3.3)),
        ((20.0, 50.0), (149.9, 0.1)),
    ] {
        let (a, b) = (Point::new(a.0, a.1), Point::new(b.0, b.1));
        assert_eq!(v1.distance(a, b).to_bits(), v4.distance(a, b).to_bits());
    }
}

#[test]
fn bad_input_is_an_error_not_a_panic() {
    let s = &builtin::OPEN;
    let mut storage = Box::new(Storage::<256, 64>::new());
    let cfg = Config::am_rrt();
    let rng = || XorShiftRng::seed_from_u64(1);
    let new = |st: &mut Storage<256, 64>, at: Point| {
        Planner::<_, _, 256, 64, K>::new(st, Map::new(s.grid), Euclidean, rng(), cfg, at).err()
    };
    assert_eq!(
        new(&mut storage, Point::new(f32::NAN, 1.0)),
        Some(SetupError::Start(InputError::NotFinite))
    );
    assert_eq!(
        new(&mut storage, Point::new(-1.0, 1.0)),
        Some(SetupError::Start(InputError::OutOfBounds))
    );
    assert_eq!(
        new(&mut storage, Point::new(12.0, 12.0)),
        Some(SetupError::Start(InputError::InObstacle))
    );
    let mut p = planner_on(&mut storage, s, Euclidean, cfg, 1);
    assert_eq!(
        p.set_goal(Point::new(1.0, f32::INFINITY)),
        Err(InputError::NotFinite)
    );
    assert_eq!(
        p.set_goal(Point::new(41.0, 1.0)),
        Err(InputError::OutOfBounds)
    );
    assert_eq!(
        p.set_goal(Point::new(25.0, 10.0)),
        Err(InputError::InObstacle)
    );
    let clock = clock();
    assert_eq!(
        p.plan(&clock, Point::new(f32::NAN, 0.0)),
        Err(InputError::NotFinite)
    );
    assert_eq!(
        p.plan(&clock, Point::new(0.0, 40.5)),
        Err(InputError::OutOfBounds)
    );
    assert_eq!(
        p.add_obstacle(Circle::new(Point::new(5.0, 5.0), f32::NAN)),
        Err(bi_am_rrt::error::ObstacleError::BadCircle)
    );
    assert_eq!(
        p.remove_obstacle(bi_am_rrt::map::ObstacleId(99)),
        Err(bi_am_rrt::error::ObstacleError::UnknownId)
    );
    for i in 0..K {
        p.add_obstacle(Circle::new(Point::new(30.0 + i as f32, 35.0), 0.3))
            .unwrap();
    }
    assert_eq!(
        p.add_obstacle(Circle::new(Point::new(5.0, 35.0), 0.3)),
        Err(bi_am_rrt::error::ObstacleError::Full)
    );
    // No goal: planning still works and the waypoint is the root.
    let pr = p.plan(&clock, s.start).unwrap();
    assert_eq!(pr.waypoint, s.start);
    assert!(!pr.goal_in_tree);
}
