//! Clearance of a driven trail: how far the robot's centre stayed from the walls, by exact
//! distances from each trail segment to the squares of the occupied cells (and to the map's
//! edge), computed here in `f64` and independently of the planner's own tests. `run` reports
//! it per goal with the trail itself (`result.json`), so a robot radius can be checked
//! against what was driven.

use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;

/// Distance from segment `a-b` to the closed box `[lo, hi]` (0 when they meet), in `f64`.
pub fn segment_box_dist(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1, mut meets) = (0.0f64, 1.0f64, true);
    for (p, q) in [
        (-d[0], a[0] - lo[0]),
        (d[0], hi[0] - a[0]),
        (-d[1], a[1] - lo[1]),
        (d[1], hi[1] - a[1]),
    ] {
        if p == 0.0 {
            meets &= q >= 0.0;
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    if meets && t0 <= t1 {
        return 0.0;
    }
    let seg_point = |p: [f64; 2]| {
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a[0] + t * d[0] - p[0]).hypot(a[1] + t * d[1] - p[1])
    };
    let box_point = |p: [f64; 2]| {
        let dx = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
        let dy = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
        dx.hypot(dy)
    };
    [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
        .into_iter()
        .map(seg_point)
        .fold(box_point(a).min(box_point(b)), f64::min)
}

/// The distance from segment `a-b` (metres) to the nearest occupied cell of `grid` or the
/// map's edge: the cells of a box around the segment, grown until it holds one.
pub fn segment_clearance(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> f64 {
    let (a, b) = (
        [f64::from(a.x), f64::from(a.y)],
        [f64::from(b.x), f64::from(b.y)],
    );
    let cell = f64::from(grid.cell_size());
    let (wm, hm) = (f64::from(grid.width_m()), f64::from(grid.height_m()));
    let edge = [
        a[0],
        a[1],
        b[0],
        b[1],
        wm - a[0],
        wm - b[0],
        hm - a[1],
        hm - b[1],
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min)
    .max(0.0);
    let mut reach = cell;
    loop {
        let idx =
            |v: f64, n: u16| ((v / cell).floor().max(0.0) as u32).min(u32::from(n) - 1) as u16;
        let (c0, c1) = (
            idx(a[0].min(b[0]) - reach, grid.cols()),
            idx(a[0].max(b[0]) + reach, grid.cols()),
        );
        let (r0, r1) = (
            idx(a[1].min(b[1]) - reach, grid.rows()),
            idx(a[1].max(b[1]) + reach, grid.rows()),
        );
        let mut best = edge;
        for r in r0..=r1 {
            for c in c0..=c1 {
                if grid.is_occupied(c, r) {
                    let lo = [f64::from(c) * cell, f64::from(r) * cell];
                    let d = segment_box_dist(a, b, lo, [lo[0] + cell, lo[1] + cell]);
                    best = best.min(d);
                }
            }
        }
        // Every cell nearer than `reach` lies in the box: the answer is final.
        if best <= reach || reach > wm.max(hm) {
            return best;
        }
        reach *= 2.0;
    }
}

/// Clearance along a trail: the least over its segments, and the median and 10th percentile
/// over points spaced half a cell apart along it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Clearance {
    /// The least distance from the trail to a wall or the map's edge, metres.
    pub min_m: f64,
    /// The median of the distances at points half a cell apart along the trail, metres.
    pub median_m: f64,
    /// Their 10th percentile: how close the trail's tightest tenth runs, metres.
    pub p10_m: f64,
    /// The least distance over the trail without its first and last metre (where the start
    /// and the goal, often near a wall, bound it); `None` for a trail under 2 m.
    pub inner_min_m: Option<f64>,
}

/// How far from each end [`Clearance::inner_min_m`] starts, metres.
pub const INNER_FROM_ENDS_M: f32 = 1.0;

/// [`Clearance`] of `trail` on `grid` (`None` for a trail of fewer than two points).
pub fn trail_clearance(grid: &OccupancyGrid<'_>, trail: &[Point]) -> Option<Clearance> {
    if trail.len() < 2 {
        return None;
    }
    let min_m = trail
        .windows(2)
        .map(|w| segment_clearance(grid, w[0], w[1]))
        .fold(f64::INFINITY, f64::min);
    let step = 0.5 * grid.cell_size();
    let mut at: Vec<f64> = Vec::new();
    for w in trail.windows(2) {
        let n = (w[0].dist(w[1]) / step).ceil().max(1.0) as u32;
        for k in 0..n {
            let p = w[0].lerp(w[1], k as f32 / n as f32);
            at.push(segment_clearance(grid, p, p));
        }
    }
    at.sort_by(f64::total_cmp);
    // The trail between arc lengths 1 m and L - 1 m.
    let total: f32 = trail.windows(2).map(|w| w[0].dist(w[1])).sum();
    let (lo, hi) = (INNER_FROM_ENDS_M, total - INNER_FROM_ENDS_M);
    let mut inner_min_m = None::<f64>;
    let mut s0 = 0.0f32;
    for w in trail.windows(2) {
        let len = w[0].dist(w[1]);
        let (t0, t1) = ((lo - s0).max(0.0), (hi - s0).min(len));
        if len > 0.0 && t0 < t1 {
            let (a, b) = (w[0].lerp(w[1], t0 / len), w[0].lerp(w[1], t1 / len));
            let d = segment_clearance(grid, a, b);
            inner_min_m = Some(inner_min_m.map_or(d, |m| m.min(d)));
        }
        s0 += len;
    }
    Some(Clearance {
        min_m,
        median_m: at[at.len() / 2],
        p10_m: at[at.len() / 10],
        inner_min_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::OwnedGrid;

    #[test]
    fn distances_to_a_wall_and_the_edge() {
        // 10 x 10 cells of 0.5 m, a wall cell at (4, 4): [2, 2.5] x [2, 2.5] m.
        let g = OwnedGrid::from_fn(10, 10, 0.5, |c, r| (c, r) == (4, 4)).unwrap();
        let g = g.grid();
        let d = segment_clearance(&g, Point::new(1.0, 3.0), Point::new(4.0, 3.0));
        assert!((d - 0.5).abs() < 1e-6, "{d}");
        // Along the diagonal past the corner (2.5, 2.5).
        let d = segment_clearance(&g, Point::new(3.0, 3.5), Point::new(3.5, 3.0));
        // The line x + y = 6.5 passes the corner at 1.5 / sqrt 2.
        assert!((d - 1.5 / 2f64.sqrt()).abs() < 1e-6, "{d}");
        // Near the edge, far from the wall.
        let d = segment_clearance(&g, Point::new(0.2, 4.5), Point::new(0.2, 4.8));
        assert!((d - 0.2).abs() < 1e-6, "{d}");
        // Through the wall.
        assert_eq!(
            segment_clearance(&g, Point::new(1.0, 2.25), Point::new(4.0, 2.25)),
            0.0
        );
        let c = trail_clearance(
            &g,
            &[
                Point::new(1.0, 3.0),
                Point::new(4.0, 3.0),
                Point::new(4.0, 4.0),
            ],
        )
        .unwrap();
        assert!(
            (c.min_m - 0.5).abs() < 1e-6 && c.median_m >= c.p10_m && c.p10_m >= c.min_m,
            "{c:?}"
        );
    }
}
