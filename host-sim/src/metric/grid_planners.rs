//! Grid planners beside the exact optimum (issue 42): what nav2's grid planners do, on the
//! same cells (the grid of cells with room for a robot body). A* on the 8-connected graph of
//! free cell centres (a diagonal only between two free side cells: NavFn's and Smac 2D's
//! kind of path), by the `pathfinding` crate, and Theta* (any-angle: a node takes its
//! parent's parent as parent when it sees it, nav2's Theta* planner's kind), both from the
//! start to its cell's centre and from the goal's cell's centre to the goal. Line of sight is
//! the core's segment test on the same grid. `host-sim optimum` prints their lengths and CPU
//! times next to the exact optimum.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;

/// An A* queue entry: (f, node), smallest f first (A*, Theta* and the exact optimum's
/// search, `optimum`).
#[derive(PartialEq)]
pub(crate) struct Open(pub(crate) f64, pub(crate) usize);

impl Eq for Open {}

impl PartialOrd for Open {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for Open {
    fn cmp(&self, other: &Self) -> Ordering {
        other.0.total_cmp(&self.0).then(other.1.cmp(&self.1))
    }
}

/// A grid planner's answer: the path's length in metres, and its points.
#[derive(Clone, Debug)]
pub struct GridPath {
    /// Length in metres, the ends included.
    pub length_m: f64,
    /// The path: the start, cell centres, the goal.
    pub points: Vec<Point>,
}

const STEPS: [(i32, i32); 8] = [
    (1, 0),
    (-1, 0),
    (0, 1),
    (0, -1),
    (1, 1),
    (1, -1),
    (-1, 1),
    (-1, -1),
];

/// Micro-cells: A*'s integer costs (a diagonal rounds to 1,414,214, so the path found is a
/// shortest one to within a millionth of a cell a step).
const UNIT: u64 = 1_000_000;
const DIAG: u64 = 1_414_214;

fn free(grid: &OccupancyGrid<'_>, c: i32, r: i32) -> bool {
    c >= 0
        && r >= 0
        && c < i32::from(grid.cols())
        && r < i32::from(grid.rows())
        && !grid.is_occupied(c as u16, r as u16)
}

/// The free neighbours of cell `(c, r)` (no corner cutting) and the step's cost.
fn neighbours(grid: &OccupancyGrid<'_>, (c, r): (i32, i32)) -> Vec<((i32, i32), u64)> {
    STEPS
        .iter()
        .filter(|&&(dx, dy)| {
            free(grid, c + dx, r + dy)
                && (dx == 0 || dy == 0 || (free(grid, c + dx, r) && free(grid, c, r + dy)))
        })
        .map(|&(dx, dy)| {
            (
                (c + dx, r + dy),
                if dx != 0 && dy != 0 { DIAG } else { UNIT },
            )
        })
        .collect()
}

fn cell(grid: &OccupancyGrid<'_>, p: Point) -> Option<(i32, i32)> {
    let (c, r) = grid.cell_of(p)?;
    let (c, r) = (i32::from(c), i32::from(r));
    free(grid, c, r).then_some((c, r))
}

fn centre(grid: &OccupancyGrid<'_>, (c, r): (i32, i32)) -> Point {
    grid.cell_center(c as u16, r as u16)
}

fn finish(grid: &OccupancyGrid<'_>, a: Point, b: Point, cells: &[(i32, i32)]) -> GridPath {
    let mut points = vec![a];
    points.extend(cells.iter().map(|&q| centre(grid, q)));
    points.push(b);
    points.dedup();
    let length_m = points.windows(2).map(|w| f64::from(w[0].dist(w[1]))).sum();
    GridPath { length_m, points }
}

/// A* on the 8-connected grid (octile heuristic) from `a` to `b`; `None` when either end's
/// cell is occupied or no path joins them.
pub fn astar8(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> Option<GridPath> {
    let (s, g) = (cell(grid, a)?, cell(grid, b)?);
    let octile = |&(c, r): &(i32, i32)| {
        let (dx, dy) = (u64::from(c.abs_diff(g.0)), u64::from(r.abs_diff(g.1)));
        let (lo, hi) = (dx.min(dy), dx.max(dy));
        // Rounded down: never above the true cost.
        lo * (DIAG - 1) + (hi - lo) * UNIT
    };
    let (cells, _) =
        pathfinding::prelude::astar(&s, |&q| neighbours(grid, q), octile, |&q| q == g)?;
    Some(finish(grid, a, b, &cells))
}

/// Theta* from `a` to `b` over free cell centres: A* on the 8-connected grid where a cell
/// reached from `u` takes `u`'s parent as parent when the segment between their centres is
/// free (the core's test), with the Euclidean heuristic; `None` as [`astar8`].
pub fn theta_star(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> Option<GridPath> {
    let (s, g) = (cell(grid, a)?, cell(grid, b)?);
    let cols = usize::from(grid.cols());
    let idx = |(c, r): (i32, i32)| r as usize * cols + c as usize;
    let n = cols * usize::from(grid.rows());
    let mut cost = vec![f64::INFINITY; n];
    let mut parent = vec![usize::MAX; n];
    let mut closed = vec![false; n];
    let at = |i: usize| ((i % cols) as i32, (i / cols) as i32);
    let pos = |i: usize| centre(grid, at(i));
    let h = |i: usize| f64::from(pos(i).dist(centre(grid, g)));
    let mut open = BinaryHeap::new();
    let si = idx(s);
    cost[si] = 0.0;
    parent[si] = si;
    open.push(Open(h(si), si));
    while let Some(Open(_, u)) = open.pop() {
        if closed[u] {
            continue;
        }
        if u == idx(g) {
            let mut cells = vec![at(u)];
            let mut v = u;
            while parent[v] != v {
                v = parent[v];
                cells.push(at(v));
            }
            cells.reverse();
            return Some(finish(grid, a, b, &cells));
        }
        closed[u] = true;
        for (q, _) in neighbours(grid, at(u)) {
            let v = idx(q);
            if closed[v] {
                continue;
            }
            let p = parent[u];
            let (via, c) = if grid.segment_free(pos(p), pos(v)) {
                (p, cost[p] + f64::from(pos(p).dist(pos(v))))
            } else {
                (u, cost[u] + f64::from(pos(u).dist(pos(v))))
            };
            if c < cost[v] {
                cost[v] = c;
                parent[v] = via;
                open.push(Open(c + h(v), v));
            }
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::optimum::Corners;
    use crate::scenario::OwnedGrid;

    /// On random maps: A* is no shorter than the exact optimum, and Theta* lies between the
    /// optimum and A*'s length (any angle, but through cell centres); each path's segments are
    /// free by the core's test.
    #[test]
    fn grid_planners_bracket_the_optimum() {
        let mut next = crate::metric::optimum::xorshift(0x9e37_79b9_7f4a_7c15u64);
        let mut compared = 0;
        for case in 0..100 {
            let (w, h) = (10 + (next() % 30) as u16, 10 + (next() % 30) as u16);
            let occ: Vec<bool> = (0..usize::from(w) * usize::from(h))
                .map(|_| next() % 100 < [10, 25][case % 2])
                .collect();
            let g = OwnedGrid::from_fn(w, h, 0.5, |c, r| {
                occ[usize::from(r) * usize::from(w) + usize::from(c)]
            })
            .unwrap();
            let grid = g.grid();
            let free: Vec<(u16, u16)> = (0..h)
                .flat_map(|r| (0..w).map(move |c| (c, r)))
                .filter(|&(c, r)| !grid.is_occupied(c, r))
                .collect();
            if free.len() < 2 {
                continue;
            }
            let pick = |v: u64| {
                let (c, r) = free[(v % free.len() as u64) as usize];
                grid.cell_center(c, r)
            };
            let (a, b) = (pick(next()), pick(next()));
            let opt = Corners::of(&grid).shortest(a, b);
            let (x, t) = (astar8(&grid, a, b), theta_star(&grid, a, b));
            assert_eq!(opt.is_some(), x.is_some(), "case {case}");
            assert_eq!(opt.is_some(), t.is_some(), "case {case}");
            let (Some(opt), Some(x), Some(t)) = (opt, x, t) else {
                continue;
            };
            compared += 1;
            assert!(
                x.length_m >= opt - 1e-6,
                "case {case}: A* {} < {opt}",
                x.length_m
            );
            assert!(
                t.length_m >= opt - 1e-6,
                "case {case}: Theta* {} < {opt}",
                t.length_m
            );
            assert!(t.length_m <= x.length_m + 1e-6, "case {case}");
            for p in [&x, &t] {
                for s in p.points.windows(2) {
                    assert!(grid.segment_free(s[0], s[1]), "case {case}: {s:?}");
                }
            }
        }
        assert!(compared > 50);
    }
}

/// The width of the passage at free cell `(c, r)`, in cells: the shorter of the two free runs
/// through it, along its row and along its column (a 1-cell corridor's cells: 1; a door's: the
/// door's width; a room's: at least the room's narrower side). 0 for an occupied cell.
pub fn passage_cells(grid: &OccupancyGrid<'_>, c: i32, r: i32) -> u32 {
    if !free(grid, c, r) {
        return 0;
    }
    let run = |dc: i32, dr: i32| {
        let mut n = 0;
        while free(grid, c + dc * (n + 1), r + dr * (n + 1)) {
            n += 1;
        }
        n as u32
    };
    (1 + run(1, 0) + run(-1, 0)).min(1 + run(0, 1) + run(0, -1))
}

/// Where a grid path runs ([`passage_cells`] along it, each piece of the path counted at the
/// cell of its midpoint).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Passages {
    /// The path's length, in metres.
    pub length_m: f64,
    /// The part of it in passages narrower than the width asked about, in metres.
    pub narrow_m: f64,
    /// The median passage width along the path (weighted by length), in metres.
    pub median_width_m: f64,
}

/// How much of `path` runs through passages narrower than `width_m` ([`Passages`]).
pub fn passages(grid: &OccupancyGrid<'_>, path: &GridPath, width_m: f64) -> Passages {
    let cell = f64::from(grid.cell_size());
    let mut pieces: Vec<(f64, f64)> = path
        .points
        .windows(2)
        .filter_map(|w| {
            let len = f64::from(w[0].dist(w[1]));
            let (c, r) = grid.cell_of(w[0].lerp(w[1], 0.5))?;
            let width = f64::from(passage_cells(grid, i32::from(c), i32::from(r))) * cell;
            Some((width, len))
        })
        .collect();
    let narrow_m = pieces
        .iter()
        .filter(|(w, _)| *w < width_m)
        .map(|(_, l)| l)
        .sum();
    pieces.sort_by(|a, b| a.0.total_cmp(&b.0));
    let half = pieces.iter().map(|p| p.1).sum::<f64>() / 2.0;
    let mut acc = 0.0;
    let median_width_m = pieces
        .iter()
        .find(|(_, l)| {
            acc += l;
            acc >= half
        })
        .map_or(0.0, |p| p.0);
    Passages {
        length_m: path.length_m,
        narrow_m,
        median_width_m,
    }
}
