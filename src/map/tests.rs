//! The map's unit tests.

use super::*;
use crate::error::ObstacleError;

fn grid_with<'a>(buf: &'a mut [u8], w: u16, h: u16, occ: &[(u16, u16)]) -> OccupancyGrid<'a> {
    pack_grid(buf, w, h, |c, r| occ.contains(&(c, r))).unwrap();
    OccupancyGrid::new(buf, w, h, 1.0).unwrap()
}

#[test]
fn constructor_rejects_bad_grids() {
    let buf = [0u8; 2];
    assert_eq!(
        OccupancyGrid::new(&buf, 0, 4, 1.0).unwrap_err(),
        MapError::EmptyGrid
    );
    assert_eq!(
        OccupancyGrid::new(&buf, 5, 4, 1.0).unwrap_err(),
        MapError::BufferTooShort
    );
    assert_eq!(
        OccupancyGrid::new(&buf, 4, 4, 0.0).unwrap_err(),
        MapError::BadCellSize
    );
    assert_eq!(
        OccupancyGrid::new(&buf, 4, 4, f32::NAN).unwrap_err(),
        MapError::BadCellSize
    );
    assert!(OccupancyGrid::new(&buf, 4, 4, 0.5).is_ok());
}

#[test]
fn diagonal_through_a_shared_corner_is_blocked() {
    let mut buf = [0u8; 2];
    // Occupied (1, 0) and (0, 1) share the corner (1, 1).
    let g = grid_with(&mut buf, 4, 4, &[(1, 0), (0, 1)]);
    assert!(!g.segment_free(Point::new(0.5, 0.5), Point::new(1.5, 1.5)));
    // The other diagonal through the same corner also touches both cells.
    assert!(!g.segment_free(Point::new(0.5, 1.5), Point::new(1.5, 0.5)));
    // A segment that stays clear of both is free.
    assert!(g.segment_free(Point::new(2.5, 0.5), Point::new(3.5, 3.5)));
}

#[test]
fn grazing_an_edge_counts_as_touching() {
    let mut buf = [0u8; 2];
    let g = grid_with(&mut buf, 4, 4, &[(1, 1)]);
    // Along the top edge of cell (1, 1) (the line y = 1).
    assert!(!g.segment_free(Point::new(0.2, 1.0), Point::new(3.8, 1.0)));
    // Just clear of it.
    assert!(g.segment_free(Point::new(0.2, 0.99), Point::new(3.8, 0.99)));
    // Vertical along x = 2 touches the right edge of (1, 1).
    assert!(!g.segment_free(Point::new(2.0, 0.5), Point::new(2.0, 3.5)));
    assert!(g.segment_free(Point::new(2.01, 0.5), Point::new(2.01, 3.5)));
}

/// Issue 41: on the MovingAI maze at 0.5 m the simulator counted a collision for goal 3's
/// call 666, a step from (99.72903, 50.000484) to (99.02903, 50.000843) that runs 0.48-0.84
/// mm above the wall cells' edge at y = 50 m. A nearly flat segment (its rise under the
/// contact margin) was tested against its whole x-range in every row it comes near, so
/// the wall cell (198, 99), which the segment passes 1.2 mm above, was found "touched"
/// though only the step's first 0.04 cells come within the margin, above the free cell
/// (199, 99). The longer segment the planner had checked passed; its sub-segment did not.
#[test]
fn regression_maze512_flat_step_graze() {
    let (w, h) = (256u16, 128u16);
    let mut buf = [0u8; OccupancyGrid::bytes_needed(256, 128)];
    // Row 99 (y in [49.5, 50) m) is a wall up to column 198; column 199 is free.
    pack_grid(&mut buf, w, h, |c, r| r == 99 && c <= 198).unwrap();
    let g = OccupancyGrid::new(&buf, w, h, 0.5).unwrap();
    let (a, b) = (
        Point::new(99.72903, 50.000484),
        Point::new(99.02903, 50.000843),
    );
    assert!(
        g.segment_free(a, b),
        "the step stays clear of the wall cell"
    );
    assert!(g.segment_free(b, a));
    // The parent segment the planner tested (further along the same line) passes too.
    let far = a + (b - a) * 1.5;
    assert!(g.segment_free(a, far));
    // Any piece of a segment that passes passes (sub-segments of the step).
    for k in 1..20 {
        let m = a.lerp(b, k as f32 / 20.0);
        assert!(g.segment_free(a, m) && g.segment_free(m, b), "{k}");
    }
    // A flat segment that really comes within the margin of the wall cell is blocked.
    let low = Point::new(99.3, 50.0001);
    assert!(!g.segment_free(a, low));
}

/// Issue 7, case 3: a subnormal cell size (1e-40) was accepted and `1 / cell` was infinite.
#[test]
fn regression_subnormal_and_overflowing_cell_sizes_are_refused() {
    let bits = [0u8; 2];
    for cell in [1.0e-40, f32::MIN_POSITIVE / 8.0, 1.0e38, f32::MAX] {
        assert_eq!(
            OccupancyGrid::new(&bits, 4, 4, cell).unwrap_err(),
            MapError::BadCellSize,
            "{cell}"
        );
    }
    let g = OccupancyGrid::new(&bits, 4, 4, 1.0e19).unwrap();
    assert!(g.width_m().is_finite());
    assert!(g.segment_free(Point::new(1.0e19, 1.0e19), Point::new(3.0e19, 2.0e19)));
}

#[test]
fn bounds_and_nan_are_not_free() {
    let mut buf = [0u8; 2];
    let g = grid_with(&mut buf, 4, 4, &[]);
    assert!(g.segment_free(Point::new(0.0, 0.0), Point::new(4.0, 4.0)));
    assert!(!g.segment_free(Point::new(0.5, 0.5), Point::new(4.5, 0.5)));
    assert!(!g.segment_free(Point::new(f32::NAN, 0.5), Point::new(1.0, 0.5)));
    assert!(!g.point_free(Point::new(-0.001, 1.0)));
    assert_eq!(g.cell_of(Point::new(4.0, 4.0)), Some((3, 3)));
}

#[test]
fn circle_uses_the_segment_distance() {
    let c = Circle::new(Point::new(5.0, 0.0), 1.0);
    // The infinite line through the segment passes through the centre; the segment does not.
    assert!(!c.intersects_segment(Point::new(0.0, 0.0), Point::new(3.9, 0.0)));
    assert!(c.intersects_segment(Point::new(0.0, 0.0), Point::new(4.0, 0.0)));
    assert!(c.intersects_segment(Point::new(4.0, -3.0), Point::new(4.0, 3.0)));
    assert!(!c.intersects_segment(Point::new(3.9, -3.0), Point::new(3.9, 3.0)));
}

#[test]
fn obstacle_set_is_bounded_and_ids_are_stable() {
    let mut o = Obstacles::<2>::new();
    let a = o.add(Circle::new(Point::new(1.0, 1.0), 0.5)).unwrap();
    let b = o.add(Circle::new(Point::new(2.0, 1.0), 0.5)).unwrap();
    assert_ne!(a, b);
    assert_eq!(
        o.add(Circle::new(Point::new(3.0, 1.0), 0.5)),
        Err(ObstacleError::Full)
    );
    assert_eq!(
        o.add(Circle::new(Point::new(3.0, 1.0), -1.0)),
        Err(ObstacleError::BadCircle)
    );
    assert_eq!(o.remove(a).unwrap().center, Point::new(1.0, 1.0));
    assert_eq!(o.remove(a), Err(ObstacleError::UnknownId));
    let c = o.add(Circle::new(Point::new(3.0, 1.0), 0.5)).unwrap();
    assert!(c != a && c != b);
    assert_eq!(o.get(b).unwrap().center, Point::new(2.0, 1.0));
    assert_eq!(o.len(), 2);
}

#[test]
fn map_checks_points_at_the_edge() {
    let mut buf = [0u8; 2];
    let mut m = Map::<'_, 4>::new(grid_with(&mut buf, 4, 4, &[(3, 3)]));
    assert_eq!(
        m.check_point(Point::new(f32::NAN, 1.0)),
        Err(InputError::NotFinite)
    );
    assert_eq!(
        m.check_point(Point::new(5.0, 1.0)),
        Err(InputError::OutOfBounds)
    );
    assert_eq!(
        m.check_point(Point::new(3.5, 3.5)),
        Err(InputError::InObstacle)
    );
    assert_eq!(m.check_point(Point::new(1.5, 1.5)), Ok(()));
    m.obstacles_mut()
        .add(Circle::new(Point::new(1.5, 1.5), 0.2))
        .unwrap();
    assert_eq!(
        m.check_point(Point::new(1.5, 1.5)),
        Err(InputError::InObstacle)
    );
    assert!(!m.free_path(Point::new(0.5, 1.5), Point::new(2.5, 1.5)));
}

#[test]
fn narrow_cells_have_walls_on_both_sides_within_reach() {
    // A 12 x 6 grid: a wall at column 6 from row 0 to row 3; a post at (2, 4).
    let mut buf = [0u8; OccupancyGrid::bytes_needed(12, 6)];
    let occ = [(6, 0), (6, 1), (6, 2), (6, 3), (2, 4)];
    let g = grid_with(&mut buf, 12, 6, &occ);
    let live = Map::<'_, 1>::new(g);
    let live = live.live();
    // (2, 5): the map's top edge and the post, each one cell away along the column.
    assert!(live.narrow_at(2, 5, 1));
    // (2, 3): the post 1 up, the bottom edge 4 down; the left edge 3 away, the wall 4.
    assert!(live.narrow_at(2, 3, 4) && !live.narrow_at(2, 3, 3));
    // (5, 1): the wall beside it but the left edge 6 away; the bottom edge 2 down, the
    // top edge 5 up: narrow along its column at reach 5.
    assert!(live.narrow_at(5, 1, 5) && !live.narrow_at(5, 1, 4));
    // (9, 5): the top edge above, the bottom edge 6 below; the row is open 10 cells left.
    assert!(live.narrow_at(9, 5, 6) && !live.narrow_at(9, 5, 5));
    // An occupied cell's own test is about its neighbours only (callers test it first).
    assert!(live.narrow_at(6, 1, 6));
}
