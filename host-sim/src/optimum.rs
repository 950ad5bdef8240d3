//! The exact shortest path between two points of a grid map, the yardstick of every benchmark
//! and experiment row (`optimal_m`, `travelled / optimal`).
//!
//! Obstacles are the grid's occupied cells taken as closed squares. A shortest path among
//! polygons bends only at their convex corners, so the path is the shortest one in the
//! visibility graph over the start, the goal and the lattice points where an obstacle has a
//! convex corner (one occupied cell of the four around the point). Two nodes see each other
//! when their segment does not enter the interior of the union of the squares and does not pass
//! through a point where two squares touch diagonally (closed squares close that gap): it may
//! run along a wall or touch a corner, which is what makes the figure the infimum of the lengths
//! of collision-free paths. A* (Euclidean heuristic) searches the graph
//! with edges tested lazily, so only the nodes that can beat the current best are expanded.
//!
//! Checked against the exact optima of the 24 reference legs in
//! `../shared/anchors/reference-figures.md` (test `optima_match_the_reference_figures`).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;

use crate::maps::Scenario;

/// The visibility-graph nodes of one map (convex obstacle corners) and its cells.
pub struct Corners {
    cols: i64,
    rows: i64,
    cell: f64,
    occupied: Vec<bool>,
    /// Corner positions in cell units.
    corners: Vec<(f64, f64)>,
}

impl Corners {
    /// The corners of `grid`.
    pub fn of(grid: &OccupancyGrid<'_>) -> Self {
        let (cols, rows) = (grid.cols() as i64, grid.rows() as i64);
        let mut occupied = vec![false; (cols * rows) as usize];
        for r in 0..rows {
            for c in 0..cols {
                occupied[(r * cols + c) as usize] = grid.is_occupied(c as u16, r as u16);
            }
        }
        let mut me = Self {
            cols,
            rows,
            cell: grid.cell_size() as f64,
            occupied,
            corners: Vec::new(),
        };
        for j in 1..rows {
            for i in 1..cols {
                // Cells around lattice point (i, j): NW, NE, SW, SE.
                let (a, b, c, d) = (
                    me.occ(i - 1, j - 1),
                    me.occ(i, j - 1),
                    me.occ(i - 1, j),
                    me.occ(i, j),
                );
                let n = [a, b, c, d].iter().filter(|&&o| o).count();
                if n == 1 {
                    me.corners.push((i as f64, j as f64));
                }
            }
        }
        me
    }

    /// Number of corners.
    pub fn len(&self) -> usize {
        self.corners.len()
    }

    /// Whether the map has no corner (an empty map).
    pub fn is_empty(&self) -> bool {
        self.corners.is_empty()
    }

    fn occ(&self, c: i64, r: i64) -> bool {
        c >= 0
            && r >= 0
            && c < self.cols
            && r < self.rows
            && self.occupied[(r * self.cols + c) as usize]
    }

    /// Whether the segment between two points (cell units) stays out of the obstacles'
    /// interior: every piece between two grid-line crossings is tested at its midpoint.
    fn sees(&self, a: (f64, f64), b: (f64, f64)) -> bool {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let mut ts: Vec<f64> = Vec::with_capacity(2 + (dx.abs() + dy.abs()) as usize + 2);
        ts.push(0.0);
        ts.push(1.0);
        for (p, d) in [(a.0, dx), (a.1, dy)] {
            if d != 0.0 {
                let (lo, hi) = if d > 0.0 { (p, p + d) } else { (p + d, p) };
                let mut k = lo.floor() + 1.0;
                while k < hi {
                    ts.push((k - p) / d);
                    k += 1.0;
                }
            }
        }
        ts.sort_by(|x, y| x.total_cmp(y));
        const EPS: f64 = 1e-9;
        // Through a lattice point where two squares touch diagonally: closed, blocked.
        for &t in &ts {
            if t <= 0.0 || t >= 1.0 {
                continue;
            }
            let (px, py) = (a.0 + t * dx, a.1 + t * dy);
            let (i, j) = (px.round(), py.round());
            if (px - i).abs() < EPS && (py - j).abs() < EPS {
                let (i, j) = (i as i64, j as i64);
                let (nw, ne, sw, se) = (
                    self.occ(i - 1, j - 1),
                    self.occ(i, j - 1),
                    self.occ(i - 1, j),
                    self.occ(i, j),
                );
                if (nw && se) || (ne && sw) {
                    return false;
                }
            }
        }
        for w in ts.windows(2) {
            if w[1] - w[0] < 1e-12 {
                continue;
            }
            let t = 0.5 * (w[0] + w[1]);
            let (mx, my) = (a.0 + t * dx, a.1 + t * dy);
            let on_x = (mx - mx.round()).abs() < EPS;
            let on_y = (my - my.round()).abs() < EPS;
            let blocked = match (on_x, on_y) {
                // Strictly inside a cell.
                (false, false) => self.occ(mx.floor() as i64, my.floor() as i64),
                // Along a vertical grid line: inside the union only between two occupied cells.
                (true, false) => {
                    let (i, r) = (mx.round() as i64, my.floor() as i64);
                    self.occ(i - 1, r) && self.occ(i, r)
                }
                (false, true) => {
                    let (c, j) = (mx.floor() as i64, my.round() as i64);
                    self.occ(c, j - 1) && self.occ(c, j)
                }
                (true, true) => {
                    let (i, j) = (mx.round() as i64, my.round() as i64);
                    self.occ(i - 1, j - 1)
                        && self.occ(i, j - 1)
                        && self.occ(i - 1, j)
                        && self.occ(i, j)
                }
            };
            if blocked {
                return false;
            }
        }
        true
    }

    /// The length in metres of the shortest path from `a` to `b` (positions in metres), or
    /// `None` when the goal cannot be reached.
    pub fn shortest(&self, a: Point, b: Point) -> Option<f64> {
        let s = (a.x as f64 / self.cell, a.y as f64 / self.cell);
        let g = (b.x as f64 / self.cell, b.y as f64 / self.cell);
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        if self.sees(s, g) {
            return Some(dist(s, g) * self.cell);
        }
        // Nodes: the corners, then the goal, then the start.
        let n = self.corners.len();
        let pos = |i: usize| match i.cmp(&n) {
            Ordering::Less => self.corners[i],
            Ordering::Equal => g,
            Ordering::Greater => s,
        };
        let mut best = vec![f64::INFINITY; n + 2];
        let mut closed = vec![false; n + 2];
        let mut open = BinaryHeap::new();
        best[n + 1] = 0.0;
        open.push(Open(dist(s, g), n + 1));
        while let Some(Open(_, u)) = open.pop() {
            if closed[u] {
                continue;
            }
            if u == n {
                return Some(best[n] * self.cell);
            }
            closed[u] = true;
            let pu = pos(u);
            for v in 0..=n {
                if closed[v] {
                    continue;
                }
                let pv = pos(v);
                let c = best[u] + dist(pu, pv);
                // Only edges that improve and can still beat the goal's current label.
                if c < best[v] && c + dist(pv, g) < best[n] && self.sees(pu, pv) {
                    best[v] = c;
                    open.push(Open(c + dist(pv, g), v));
                }
            }
        }
        None
    }
}

/// An A* queue entry: (f, node), smallest f first.
#[derive(PartialEq)]
struct Open(f64, usize);

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

/// The start of each leg of a scenario: leg `k` goes from goal `k - 1` (or the start) to goal
/// `k`.
pub fn leg_starts(s: &Scenario) -> Vec<Point> {
    std::iter::once(s.start)
        .chain(s.goals.iter().copied())
        .take(s.goals.len())
        .collect()
}

/// The exact optimum of every leg of a scenario, in metres (`None`: unreachable).
///
/// The legs are searched in parallel, and each result is kept in a small file under the
/// system's temporary directory (`bi-am-rrt-optima/`), named by a hash of everything it
/// depends on (the grid's cells and cell size, the leg's end points, this module's version):
/// a nav2 map's optima take a minute and a half (warehouse, 50 m at 0.03 m), and a bench run
/// again on the same scenario reads them back. Set `BIAMRRT_OPTIMA_CACHE=0` to search afresh.
pub fn leg_optima(s: &Scenario) -> Vec<Option<f64>> {
    use rayon::prelude::*;
    // For a robot disc, in the space inflated for it.
    let grid = s.reach_grid();
    let legs: Vec<(Point, Point)> = leg_starts(s)
        .into_iter()
        .zip(s.goals.iter().copied())
        .collect();
    let keys: Vec<u64> = legs.iter().map(|&(a, b)| cache_key(&grid, a, b)).collect();
    let cached: Vec<Option<Option<f64>>> = keys.iter().map(|&k| cache_read(k)).collect();
    if cached.iter().all(Option::is_some) {
        return cached.into_iter().flatten().collect();
    }
    let corners = Corners::of(&grid);
    legs.par_iter()
        .zip(cached)
        .zip(&keys)
        .map(|((&(a, b), hit), &key)| {
            hit.unwrap_or_else(|| {
                let d = corners.shortest(a, b);
                cache_write(key, d);
                d
            })
        })
        .collect()
}

/// Bumped whenever `Corners` or `shortest` would give another figure.
const CACHE_VERSION: u64 = 1;

fn cache_dir() -> Option<std::path::PathBuf> {
    (std::env::var("BIAMRRT_OPTIMA_CACHE").as_deref() != Ok("0"))
        .then(|| std::env::temp_dir().join("bi-am-rrt-optima"))
}

/// FNV-1a (64-bit) over the version, the grid and the two end points.
fn cache_key(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |bytes: &[u8]| {
        for &x in bytes {
            h = (h ^ u64::from(x)).wrapping_mul(0x0100_0000_01b3);
        }
    };
    eat(&CACHE_VERSION.to_le_bytes());
    eat(&(grid.cols() as u64).to_le_bytes());
    eat(&(grid.rows() as u64).to_le_bytes());
    eat(&grid.cell_size().to_bits().to_le_bytes());
    eat(grid.bits());
    for v in [a.x, a.y, b.x, b.y] {
        eat(&v.to_bits().to_le_bytes());
    }
    h
}

fn cache_read(key: u64) -> Option<Option<f64>> {
    let text = std::fs::read_to_string(cache_dir()?.join(format!("{key:016x}"))).ok()?;
    match text.trim() {
        "none" => Some(None),
        t => t.parse::<f64>().ok().filter(|d| d.is_finite()).map(Some),
    }
}

fn cache_write(key: u64, d: Option<f64>) {
    let Some(dir) = cache_dir() else { return };
    let text = d.map_or_else(|| "none".to_string(), |d| format!("{d:?}"));
    // A failed write only costs the next run the search again.
    let _ = std::fs::create_dir_all(&dir).and_then(|()| {
        let tmp = dir.join(format!("{key:016x}.{}", std::process::id()));
        std::fs::write(&tmp, text)?;
        std::fs::rename(tmp, dir.join(format!("{key:016x}")))
    });
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::maps::OwnedGrid;

    #[test]
    fn around_one_block() {
        // A 2 x 2 block in the middle of a 10 x 10 map: the way from one side to the other
        // goes over two of its corners.
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, r| {
            (4..6).contains(&c) && (4..6).contains(&r)
        })
        .unwrap();
        let k = Corners::of(&g.grid());
        assert_eq!(k.len(), 4);
        let d = k
            .shortest(Point::new(2.0, 5.0), Point::new(8.0, 5.0))
            .unwrap();
        let want = 2.0 * (2.0f64 * 2.0 + 1.0).sqrt() + 2.0;
        assert!((d - want).abs() < 1e-9, "{d} vs {want}");
        // Along the block's face: a straight segment touching the wall is allowed.
        let d = k
            .shortest(Point::new(2.0, 4.0), Point::new(8.0, 4.0))
            .unwrap();
        assert!((d - 6.0).abs() < 1e-9);
        // Cell size scales the answer.
        let g2 = OwnedGrid::from_fn(10, 10, 0.5, |c, r| {
            (4..6).contains(&c) && (4..6).contains(&r)
        })
        .unwrap();
        let d2 = Corners::of(&g2.grid())
            .shortest(Point::new(1.0, 2.5), Point::new(4.0, 2.5))
            .unwrap();
        assert!((d2 - want / 2.0).abs() < 1e-6, "{d2}");
    }

    #[test]
    fn closed_squares_shut_a_diagonal_pinch() {
        // Cells (4, 4) and (5, 5) touch at lattice point (5, 5): the straight way from the
        // north-east to the south-west through that point is shut; the path goes around.
        let g =
            OwnedGrid::from_fn(10, 10, 1.0, |c, r| (c, r) == (4, 4) || (c, r) == (5, 5)).unwrap();
        let k = Corners::of(&g.grid());
        let (a, b) = (Point::new(7.0, 3.0), Point::new(3.0, 7.0));
        let d = k.shortest(a, b).unwrap();
        assert!(d > a.dist(b) as f64 + 0.1, "{d}");
    }

    #[test]
    fn walled_off_goal_is_unreachable() {
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, _| c == 5).unwrap();
        let k = Corners::of(&g.grid());
        assert_eq!(k.shortest(Point::new(2.0, 5.0), Point::new(8.0, 5.0)), None);
    }
}
