//! A clearance preference (beyond the paper, which plans for a point and charges every edge its
//! length: section 3's `Cost`). A robot that can pass 1 mm from a wall does not want to; as
//! nav2's inflation layer does, the cost of a metre rises near walls, so that the planner keeps
//! a margin where the space allows it and still takes a narrow door when that is the way.
//!
//! Two pieces. A **clearance field**, one byte per cell, built once from the static grid
//! ([`clearance_field`]: on the host at export time, or at boot into a caller buffer; it can
//! sit in flash): a cell whose centre lies `d` metres beyond the body's edge (its distance to
//! the nearest occupied cell or the map's edge, minus the robot's radius) holds the penalty
//! `p = (1 - d / margin)^2` for `d < margin` (1 at the body's edge, falling to 0 at `margin`),
//! as `round(255 p)`; cells beyond the margin hold 0. An edge's **clearance class**
//! ([`class_of`]) is the largest penalty at points at most half a cell apart along it (its
//! closest approach to a wall), in eighths (0-7), kept in three spare bits of the tree's flag
//! byte; the edge then costs
//! `length x (1 + weight x class / 7)` ([`crate::tree::charged`],
//! [`crate::Config::clearance_weight`]). Class 0 costs the length itself, so a planner with
//! weight 0 computes bit for bit what it did before there was a preference.
//!
//! The preference is built with the crate's `clearance` feature (off by default, so that a
//! firmware that does not use it carries none of its code); the field builder and the class
//! are always there, the planner charges classes only with the feature.
//!
//! The preference is soft: walls, live cells and dynamic discs stay hard constraints (the body,
//! [`crate::map`]); the field reads the static grid only (live cells and obstacles do not
//! raise it). Heuristics that need a lower bound (the informed ellipse, the goal estimates)
//! stay Euclidean: a weighted length is never shorter.

use crate::error::MapError;
use crate::geometry::Point;
use crate::map::OccupancyGrid;
use crate::tree::MAX_CLASS;

/// Most points an edge's class samples (a longer edge samples more sparsely).
pub const MAX_SAMPLES: u32 = 256;

/// Writes the clearance field of `grid` for a robot of `radius` metres wanting `margin`
/// metres beyond its body (module docs) into `out` (at least `cols x rows` bytes, row-major
/// like the grid: byte `row x cols + col`). Occupied cells hold 255. O(boundary cells x
/// (2 reach + 1)^2) with `reach = (radius + margin) / cell + 1`: only occupied cells with a
/// free neighbour can be nearest to a free cell. Errors for a radius or margin that is NaN,
/// infinite or negative ([`MapError::BadRadius`], [`MapError::BadMargin`]), a margin of more
/// than 255 cells, or a short buffer.
pub fn clearance_field(
    grid: &OccupancyGrid<'_>,
    radius: f32,
    margin: f32,
    out: &mut [u8],
) -> Result<(), MapError> {
    if !(radius.is_finite() && radius >= 0.0) {
        return Err(MapError::BadRadius);
    }
    let cell = grid.cell_size();
    let reach_f = (radius + margin) / cell + 1.0;
    if !(margin.is_finite() && margin >= 0.0 && reach_f <= 256.0) {
        return Err(MapError::BadMargin);
    }
    let (w, h) = (grid.cols(), grid.rows());
    let n = usize::from(w).saturating_mul(usize::from(h));
    let Some(out) = out.get_mut(..n) else {
        return Err(MapError::BufferTooShort);
    };
    let penalty = |dist: f32| -> u8 {
        let d = dist - radius;
        if margin <= 0.0 || d >= margin {
            return 0;
        }
        let f = 1.0 - d.max(0.0) / margin;
        // In [0, 255]: the cast cannot wrap.
        #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
        let v = libm::roundf(255.0 * f * f) as u8;
        v
    };
    // The map's edge first: a cell centre's distance to the nearest side.
    let (wm, hm) = (grid.width_m(), grid.height_m());
    for row in 0..h {
        for col in 0..w {
            let c = grid.cell_center(col, row);
            let edge = c.x.min(wm - c.x).min(c.y).min(hm - c.y);
            let v = if grid.is_occupied(col, row) {
                255
            } else {
                penalty(edge)
            };
            if let Some(o) = out.get_mut(cell_index(col, row, w)) {
                *o = v;
            }
        }
    }
    if margin <= 0.0 {
        return Ok(());
    }
    // In [1, 256]: the cast cannot wrap.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let reach = libm::ceilf(reach_f) as u16;
    for row in 0..h {
        for col in 0..w {
            if !grid.is_occupied(col, row) || !has_free_neighbour(grid, col, row) {
                continue;
            }
            // The occupied square [col, col+1] x [row, row+1] (in cells) stamps its penalty
            // on the free cells around it.
            let (r0, r1) = (
                row.saturating_sub(reach),
                row.saturating_add(reach).min(h.saturating_sub(1)),
            );
            let (c0, c1) = (
                col.saturating_sub(reach),
                col.saturating_add(reach).min(w.saturating_sub(1)),
            );
            for rr in r0..=r1 {
                for cc in c0..=c1 {
                    let i = cell_index(cc, rr, w);
                    let Some(o) = out.get_mut(i) else { continue };
                    if *o == 255 {
                        continue;
                    }
                    let gap = |a: u16, b: u16| f32::from(a.abs_diff(b).saturating_sub(1)) + 0.5;
                    let (gx, gy) = (
                        if cc == col { 0.0 } else { gap(cc, col) },
                        if rr == row { 0.0 } else { gap(rr, row) },
                    );
                    let v = penalty(libm::sqrtf(gx * gx + gy * gy) * cell);
                    *o = (*o).max(v);
                }
            }
        }
    }
    Ok(())
}

/// Whether a 4-neighbour of `(col, row)` inside the grid is free.
fn has_free_neighbour(grid: &OccupancyGrid<'_>, col: u16, row: u16) -> bool {
    let (w, h) = (grid.cols(), grid.rows());
    [
        (col.checked_sub(1), Some(row)),
        (col.checked_add(1).filter(|&c| c < w), Some(row)),
        (Some(col), row.checked_sub(1)),
        (Some(col), row.checked_add(1).filter(|&r| r < h)),
    ]
    .into_iter()
    .any(|(c, r)| matches!((c, r), (Some(c), Some(r)) if !grid.is_occupied(c, r)))
}

#[inline]
fn cell_index(col: u16, row: u16, width: u16) -> usize {
    usize::from(row)
        .saturating_mul(usize::from(width))
        .saturating_add(usize::from(col))
}

/// The clearance class (0-7) of segment `a-b` under `field` (module docs) and the work it
/// took (samples / 4 + 1 units): the largest penalty at `n = clamp(ceil(2 |ab| / cell), 1,
/// MAX_SAMPLES) + 1` points spaced evenly from `a` to `b` (both ends included), in eighths,
/// rounded. Points outside the map or the field count as full penalty.
///
/// The largest, not the mean: an edge is charged for its closest approach to a wall over its
/// whole length, so a long edge that grazes a corner costs as much as one that runs along the
/// wall (with the mean it would cost nearly its length: measured on nav2's warehouse, the
/// trails then still passed corners in open space at the body's radius).
#[inline(never)]
pub fn class_of(grid: &OccupancyGrid<'_>, field: &[u8], a: Point, b: Point) -> (u8, u32) {
    let len = a.dist(b);
    let pieces = 2.0 * len * (1.0 / grid.cell_size());
    // Clamped to [1, MAX_SAMPLES] before the cast (NaN goes to 1).
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    let n = if pieces >= MAX_SAMPLES as f32 {
        MAX_SAMPLES
    } else if pieces >= 1.0 {
        libm::ceilf(pieces) as u32
    } else {
        1
    };
    let w = grid.cols();
    let mut most = 0u8;
    for i in 0..=n {
        #[allow(clippy::cast_precision_loss)]
        let t = i as f32 / n as f32;
        let v = grid
            .cell_of(a.lerp(b, t))
            .and_then(|(c, r)| field.get(cell_index(c, r, w)).copied())
            .unwrap_or(255);
        most = most.max(v);
    }
    // most / 255 in eighths (0-7), rounded: (7 most + 127) / 255 (at most 1,912: no overflow).
    #[allow(clippy::arithmetic_side_effects)]
    let class = (u32::from(MAX_CLASS) * u32::from(most) + 127) / 255;
    #[allow(clippy::cast_possible_truncation)]
    (
        class.min(u32::from(MAX_CLASS)) as u8,
        (n / 4).saturating_add(1),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::map::pack_grid;

    /// A 20 x 10 grid at 0.5 m with a wall along row 0 (a corridor along its top).
    fn walled(out: &mut [u8]) -> OccupancyGrid<'_> {
        pack_grid(out, 20, 10, |_, row| row == 0).unwrap();
        OccupancyGrid::new(out, 20, 10, 0.5).unwrap()
    }

    #[test]
    fn penalty_falls_with_the_distance_from_the_wall() {
        let mut bits = [0u8; 25];
        let g = walled(&mut bits);
        let mut f = [0u8; 200];
        clearance_field(&g, 0.0, 2.0, &mut f).unwrap();
        // Column 10, rows 1.. (centres 0.25, 0.75, ... m from the wall's square): falling
        // towards the middle, the map's far edge raising it again, and equal to the formula.
        let col: [u8; 9] = core::array::from_fn(|k| f[(k + 1) * 20 + 10]);
        assert!(col[..5].windows(2).all(|w| w[0] > w[1]), "{col:?}");
        for (k, &v) in col.iter().enumerate() {
            let d = 0.25 + 0.5 * k as f32;
            // The map's bottom edge is nearer for the last rows.
            let d = d.min(5.0 - (0.75 + 0.5 * k as f32));
            let p = if d >= 2.0 {
                0.0
            } else {
                (1.0 - d / 2.0).powi(2)
            };
            assert_eq!(v, (255.0 * p).round() as u8, "row {}", k + 1);
        }
        assert_eq!(f[10], 255, "occupied cells hold full penalty");
    }

    #[test]
    fn classes_rank_edges_by_their_distance_from_the_wall() {
        let mut bits = [0u8; 25];
        let g = walled(&mut bits);
        let mut f = [0u8; 200];
        clearance_field(&g, 0.0, 2.0, &mut f).unwrap();
        // From x = 3 to 7 m: more than the margin from the map's side edges.
        let along = |y: f32| class_of(&g, &f, Point::new(3.0, y), Point::new(7.0, y)).0;
        let (near, mid, far) = (along(0.6), along(1.6), along(2.6));
        assert!(near > mid && mid >= far, "{near} {mid} {far}");
        assert_eq!(far, 0);
        assert!(near <= MAX_CLASS);
        // The closest approach counts, however short: an edge far from the wall but for one
        // end costs as one along it.
        let graze = class_of(&g, &f, Point::new(3.0, 2.6), Point::new(7.0, 0.6)).0;
        assert_eq!(graze, near);
    }

    #[test]
    fn zero_margin_or_bad_input() {
        let mut bits = [0u8; 25];
        let g = walled(&mut bits);
        let mut f = [7u8; 200];
        clearance_field(&g, 0.0, 0.0, &mut f).unwrap();
        assert!(f[20..].iter().all(|&v| v == 0));
        assert_eq!(
            clearance_field(&g, f32::NAN, 1.0, &mut f),
            Err(MapError::BadRadius)
        );
        assert_eq!(
            clearance_field(&g, 0.0, -1.0, &mut f),
            Err(MapError::BadMargin)
        );
        assert_eq!(
            clearance_field(&g, 0.0, 1e9, &mut f),
            Err(MapError::BadMargin)
        );
        assert_eq!(
            clearance_field(&g, 0.0, 1.0, &mut f[..10]),
            Err(MapError::BufferTooShort)
        );
    }
}
