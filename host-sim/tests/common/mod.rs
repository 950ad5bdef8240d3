//! Scenarios shared by the simulator's test files.

use bi_am_rrt::Point;
use host_sim::scenario::{OwnedGrid, Scenario};

/// Issue 27's door scenes' hall: 40 m x 30 m at 1 m cells, walled, split by a wall at x = 20 m
/// with doorways at y 5-10 m (on the way from the start to the goal) and 20-25 m.
pub fn two_doors() -> Scenario {
    let map = OwnedGrid::from_fn(40, 30, 1.0, |c, r| {
        c == 0
            || r == 0
            || c == 39
            || r == 29
            || (c == 20 && !(5..10).contains(&r) && !(20..25).contains(&r))
    })
    .unwrap();
    Scenario::new(
        "two-doors",
        map,
        "test",
        Point::new(5.5, 7.5),
        vec![Point::new(34.5, 7.5)],
        Some(18.0),
    )
}
