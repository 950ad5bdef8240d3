//! The planner's unit tests.

use super::*;
use crate::clock::FakeClock;
use crate::map::{OccupancyGrid, pack_grid};
use crate::metric::Euclidean;
use rand_core::SeedableRng;

/// Issue 24, finding 7: Meet tested only the 16 cheapest pairs within `sigma`; with
/// `meet_all_pairs` (the paper's Meet) a free pair further down the list joins the trees.
/// A wall at x = 20 (y below 30); 16 cheap reverse nodes behind it, two dearer ones above
/// it, in sight of the new forward node.
#[test]
fn meet_all_pairs_finds_a_free_pair_beyond_the_cheapest_sixteen() {
    let mut bits = [0u8; OccupancyGrid::bytes_needed(40, 40)];
    pack_grid(&mut bits, 40, 40, |c, r| c == 20 && r < 30).unwrap();
    let grid = OccupancyGrid::new(&bits, 40, 40, 1.0).unwrap();
    for all in [false, true] {
        let mut storage = Storage::<64, 16>::new();
        let mut cfg = Config::bi_am_rrt().with_sigma(40.0);
        cfg.as_printed.meet_all_pairs = all;
        let rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
        let mut p = Planner::<_, _, 64, 16, 0>::new(
            &mut storage,
            Map::new(grid),
            Euclidean,
            rng,
            cfg,
            Point::new(10.0, 5.0),
        )
        .unwrap();
        p.set_goal(Point::new(30.0, 5.0)).unwrap();
        let root = p.fwd.tree.root().unwrap();
        let new = p.fwd.insert(Point::new(10.0, 34.0), root, false).unwrap();
        let rev_root = p.rev.tree.root().unwrap();
        for k in 0..16u8 {
            let y = 2.0 + 0.3 * f32::from(k);
            p.rev.insert(Point::new(21.5, y), rev_root, false).unwrap();
        }
        let up = p
            .rev
            .insert(Point::new(30.0, 36.0), rev_root, false)
            .unwrap();
        p.rev.insert(Point::new(25.0, 36.0), up, false).unwrap();
        let clock = FakeClock::nanos();
        let meter = Meter::new(&clock);
        p.call = Deadline::after(&clock, core::time::Duration::from_secs(1));
        let met = p.try_meet(new, true, &meter).is_ok();
        assert_eq!(met, all, "meet_all_pairs {all}");
        if all {
            assert!(p.goal_node().is_some(), "the goal joined through the meet");
        }
    }
}

/// Found in review before live edits landed: grafting the reverse trunk copied each
/// edge's blocked flag as an obstacle's, so the next re-flagging for an obstacle cleared
/// an edge that crosses a marked cell. The trunk's walled edge stays blocked after a
/// circle is added elsewhere.
#[test]
fn regression_a_grafted_trunk_keeps_its_walled_edges() {
    let bits = [0u8; OccupancyGrid::bytes_needed(40, 40)];
    let grid = OccupancyGrid::new(&bits, 40, 40, 1.0).unwrap();
    let mut overlay = [0u8; OccupancyGrid::bytes_needed(40, 40)];
    let map = Map::new(grid).with_overlay(&mut overlay).unwrap();
    let mut storage = Storage::<64, 16>::new();
    let cfg = Config::bi_am_rrt().with_sigma(40.0);
    let rng = rand_xorshift::XorShiftRng::seed_from_u64(1);
    let mut p = Planner::<_, _, 64, 16, 2>::new(
        &mut storage,
        map,
        Euclidean,
        rng,
        cfg,
        Point::new(5.0, 5.0),
    )
    .unwrap();
    p.set_goal(Point::new(35.0, 5.0)).unwrap();
    // Reverse trunk: goal <- (25, 5) <- (20, 5); a door closes between (25, 5) and the goal.
    let rev_root = p.rev.tree.root().unwrap();
    let mid = p
        .rev
        .insert(Point::new(25.0, 5.0), rev_root, false)
        .unwrap();
    let end = p.rev.insert(Point::new(20.0, 5.0), mid, false).unwrap();
    p.set_cells((30, 0), (30, 39), true).unwrap();
    let clock = FakeClock::nanos();
    let meter = Meter::new(&clock);
    p.apply_updates(&meter);
    assert_eq!(p.rev.tree.edge_sources(mid), (false, true));
    // The forward tree meets the trunk's far end.
    let root = p.fwd.tree.root().unwrap();
    let new = p.fwd.insert(Point::new(15.0, 5.0), root, false).unwrap();
    assert!(p.graft(new, end, &meter));
    let goal = p.goal_node().unwrap();
    assert_eq!(p.fwd.tree.edge_blocked(goal), Some(true));
    p.add_obstacle(Circle::new(Point::new(5.0, 35.0), 1.0))
        .unwrap();
    assert_eq!(
        p.fwd.tree.edge_blocked(goal),
        Some(true),
        "re-flagging cleared it"
    );
    assert!(p.fwd.cost(goal).blocked);
}
