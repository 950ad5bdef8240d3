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
//! Three prunings keep it exact and make it scale (issue 42): a path over free cell centres,
//! a real path, bounds the search (only corners inside the ellipse whose foci are the ends and
//! whose lengths sum to that bound take part); a shortest path bends at a corner only round its
//! occupied cell (a taut string), so from a corner only the successors on that side are tested;
//! and a segment is walked crossing by crossing and dropped at its first blocked piece, the
//! core's span test answering for long free ones. The figures are those of the plain search to
//! the bit (`the_bound_changes_no_figure`, 400 random maps). `host-sim optimum` prints each
//! leg's figure and CPU time: on nav2's warehouse (1,006 x 1,674 cells) about 1 s for the
//! longest leg (10 s with the bound alone), a 1,024-cell map of 900 blocks 0.2 s a leg, a
//! 129-cell maze of 1-cell corridors 0.1-0.2 s a leg (about 700 s before), a 511-cell one
//! 25-40 s a leg (45,000 corners: the scan of every candidate corner per expansion is what
//! remains).
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
    /// The grid's packed cells: the core's segment test, a fast conservative first look.
    bits: Vec<u8>,
    /// Corner positions in cell units.
    corners: Vec<(f64, f64)>,
    /// Per corner, the diagonal direction (x, y in {-1, 1}) of its one occupied cell.
    quadrant: Vec<(f64, f64)>,
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
            bits: grid.bits().to_vec(),
            corners: Vec::new(),
            quadrant: Vec::new(),
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
                    let q = match (a, b, c) {
                        (true, _, _) => (-1.0, -1.0),
                        (_, true, _) => (1.0, -1.0),
                        (_, _, true) => (-1.0, 1.0),
                        _ => (1.0, 1.0),
                    };
                    me.quadrant.push(q);
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
    /// interior: every piece between two grid-line crossings is tested at its midpoint, and
    /// every lattice point it passes through where two squares touch diagonally shuts it. The
    /// crossings are walked in order and the walk stops at the first blocked piece (a segment
    /// into a wall costs a few cells, not its length).
    fn sees(&self, a: (f64, f64), b: (f64, f64)) -> bool {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        // After the first pieces (most blocked segments end there, in a maze), the core's test:
        // it refuses a segment within a thousandth of a cell of an occupied cell (more than
        // the rounding to f32), so a segment it passes stays out of every closed square and
        // this one sees it too; what it refuses the walk decides.
        let mut pieces = 0u32;
        // The crossings of one axis, in increasing t: (k - p) / d for the integers k strictly
        // between p and p + d (the same values as sorting them all would give).
        struct Axis {
            p: f64,
            d: f64,
            k: f64,
            end: f64,
        }
        impl Axis {
            fn new(p: f64, d: f64) -> Self {
                let (lo, hi) = if d > 0.0 { (p, p + d) } else { (p + d, p) };
                if d > 0.0 {
                    Axis {
                        p,
                        d,
                        k: lo.floor() + 1.0,
                        end: hi,
                    }
                } else if d < 0.0 {
                    // Descending from the largest integer below `hi` to the smallest above `lo`.
                    Axis {
                        p,
                        d,
                        k: hi.ceil() - 1.0,
                        end: lo,
                    }
                } else {
                    Axis {
                        p,
                        d,
                        k: 0.0,
                        end: 0.0,
                    }
                }
            }
            fn next_t(&self) -> f64 {
                let more = if self.d > 0.0 {
                    self.k < self.end
                } else if self.d < 0.0 {
                    self.k > self.end
                } else {
                    false
                };
                if more {
                    (self.k - self.p) / self.d
                } else {
                    f64::INFINITY
                }
            }
            fn advance(&mut self) {
                self.k += if self.d > 0.0 { 1.0 } else { -1.0 };
            }
        }
        const EPS: f64 = 1e-9;
        let (mut ax, mut ay) = (Axis::new(a.0, dx), Axis::new(a.1, dy));
        let mut prev = 0.0f64;
        loop {
            let (tx, ty) = (ax.next_t(), ay.next_t());
            let t = tx.min(ty).min(1.0);
            // Through a lattice point where two squares touch diagonally: closed, blocked.
            if t > 0.0 && t < 1.0 {
                let (px, py) = (a.0 + t * dx, a.1 + t * dy);
                let (i, j) = (round_nn(px), round_nn(py));
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
            if t - prev >= 1e-12 && self.piece_blocked(a, (dx, dy), 0.5 * (prev + t)) {
                return false;
            }
            pieces += 1;
            if pieces == 8 && t < 1.0 && self.core_free(a, b) {
                return true;
            }
            if t >= 1.0 {
                return true;
            }
            if tx == t {
                ax.advance();
            }
            if ty == t {
                ay.advance();
            }
            prev = t;
        }
    }

    /// The core's segment test (`OccupancyGrid::segment_free`) on the segment in metres.
    fn core_free(&self, a: (f64, f64), b: (f64, f64)) -> bool {
        let Ok(grid) = OccupancyGrid::new(
            &self.bits,
            self.cols as u16,
            self.rows as u16,
            self.cell as f32,
        ) else {
            return false;
        };
        let m = |p: (f64, f64)| Point::new((p.0 * self.cell) as f32, (p.1 * self.cell) as f32);
        grid.segment_free(m(a), m(b))
    }

    /// Whether the piece of the segment from `a` along `d` whose midpoint is at `t` lies in
    /// the interior of the union of the squares.
    fn piece_blocked(&self, a: (f64, f64), d: (f64, f64), t: f64) -> bool {
        const EPS: f64 = 1e-9;
        let (mx, my) = (a.0 + t * d.0, a.1 + t * d.1);
        let on_x = (mx - round_nn(mx)).abs() < EPS;
        let on_y = (my - round_nn(my)).abs() < EPS;
        match (on_x, on_y) {
            // Strictly inside a cell.
            (false, false) => self.occ(floor_nn(mx) as i64, floor_nn(my) as i64),
            // Along a vertical grid line: inside the union only between two occupied cells.
            (true, false) => {
                let (i, r) = (round_nn(mx) as i64, floor_nn(my) as i64);
                self.occ(i - 1, r) && self.occ(i, r)
            }
            (false, true) => {
                let (c, j) = (floor_nn(mx) as i64, round_nn(my) as i64);
                self.occ(c, j - 1) && self.occ(c, j)
            }
            (true, true) => {
                let (i, j) = (round_nn(mx) as i64, round_nn(my) as i64);
                self.occ(i - 1, j - 1) && self.occ(i, j - 1) && self.occ(i - 1, j) && self.occ(i, j)
            }
        }
    }

    /// The length in metres of the shortest path from `a` to `b` (positions in metres), or
    /// `None` when the goal cannot be reached.
    ///
    /// A* over the visibility graph, with prunings that keep it exact (module docs): a path
    /// over cell centres (A* on the 8-connected grid: a real path, so no shorter than the
    /// optimum) bounds the search, so only the corners inside the ellipse of foci `a` and `b`
    /// whose lengths sum to that bound take part; an edge is tested only when it can still
    /// beat the bound and the goal's label; and from a corner only the edges that keep the
    /// path taut round its occupied cell.
    pub fn shortest(&self, a: Point, b: Point) -> Option<f64> {
        let s = (a.x as f64 / self.cell, a.y as f64 / self.cell);
        let g = (b.x as f64 / self.cell, b.y as f64 / self.cell);
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        if self.sees(s, g) {
            return Some(dist(s, g) * self.cell);
        }
        // Above the bound by a relative 1e-6 (the centre path's points are f32 metres): a
        // corner path as long stays in.
        let bound = self
            .centre_path(s, g)
            .map_or(f64::INFINITY, |u| u * (1.0 + 1e-6) + 1e-6);
        type Xy = (f64, f64);
        let (cand, quad): (Vec<Xy>, Vec<Xy>) = self
            .corners
            .iter()
            .copied()
            .zip(self.quadrant.iter().copied())
            .filter(|&(c, _)| dist(s, c) + dist(c, g) < bound)
            .unzip();
        // Nodes: the candidate corners, then the goal, then the start.
        let n = cand.len();
        let pos = |i: usize| match i.cmp(&n) {
            Ordering::Less => cand[i],
            Ordering::Equal => g,
            Ordering::Greater => s,
        };
        let mut best = vec![f64::INFINITY; n + 2];
        let mut parent = vec![usize::MAX; n + 2];
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
            let limit = |goal: f64| goal.min(bound);
            // A shortest path bends at a corner only round its occupied cell: from the corner,
            // the way back and the way on enclose that cell's diagonal (module docs).
            let back = (u < n).then(|| {
                let pp = pos(parent[u]);
                ((pp.0 - pu.0, pp.1 - pu.1), quad[u])
            });
            for v in 0..=n {
                if closed[v] {
                    continue;
                }
                let pv = pos(v);
                let c = best[u] + dist(pu, pv);
                // Only edges that improve and can still beat the goal's label and the bound.
                if c < best[v]
                    && c + dist(pv, g) < limit(best[n])
                    && back.is_none_or(|(a, w)| taut(a, (pv.0 - pu.0, pv.1 - pu.1), w))
                    && self.sees(pu, pv)
                {
                    best[v] = c;
                    parent[v] = u;
                    open.push(Open(c + dist(pv, g), v));
                }
            }
        }
        None
    }

    /// The length (cell units) of a path from `s` to `g` over free cell centres: `s` to its
    /// cell's centre, 8-connected steps between free centres (a diagonal only between two free
    /// side cells, so every step's segment is free), the goal cell's centre to `g`
    /// ([`crate::grid_planners::astar8`]). A real path's length, so no shorter than the
    /// optimum. `None` when either end's cell is occupied or no such path exists.
    fn centre_path(&self, s: (f64, f64), g: (f64, f64)) -> Option<f64> {
        let grid = OccupancyGrid::new(
            &self.bits,
            self.cols as u16,
            self.rows as u16,
            self.cell as f32,
        )
        .ok()?;
        let m = |p: (f64, f64)| Point::new((p.0 * self.cell) as f32, (p.1 * self.cell) as f32);
        crate::grid_planners::astar8(&grid, m(s), m(g)).map(|p| p.length_m / self.cell)
    }

    /// The search as it was before the bound (every corner a candidate; the same answers):
    /// the tests compare the two.
    #[cfg(test)]
    fn shortest_unbounded(&self, a: Point, b: Point) -> Option<f64> {
        let s = (a.x as f64 / self.cell, a.y as f64 / self.cell);
        let g = (b.x as f64 / self.cell, b.y as f64 / self.cell);
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        if self.sees(s, g) {
            return Some(dist(s, g) * self.cell);
        }
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
                if c < best[v] && c + dist(pv, g) < best[n] && self.sees(pu, pv) {
                    best[v] = c;
                    open.push(Open(c + dist(pv, g), v));
                }
            }
        }
        None
    }
}

/// Whether a path that comes to a corner from direction `a` (the corner to the previous
/// vertex) and leaves along `b` is taut round the corner's occupied cell, whose diagonal
/// from the corner is `w`: `w` lies strictly inside the smaller angle between `a` and `b`
/// (the cell blocks every shortcut), or the path goes straight on. Any other bend can be
/// shortened by moving off the corner, so a shortest path never makes it.
fn taut(a: (f64, f64), b: (f64, f64), w: (f64, f64)) -> bool {
    let cross = |p: (f64, f64), q: (f64, f64)| p.0 * q.1 - p.1 * q.0;
    let ab = cross(a, b);
    if ab == 0.0 {
        // Straight on (or straight back, which a shortest path never does either).
        return a.0 * b.0 + a.1 * b.1 < 0.0;
    }
    cross(a, w) * ab > 0.0 && cross(w, b) * ab > 0.0
}

/// `x.floor()` without the library call for the non-negative values a map's coordinates
/// take (the call was a third of the search's time on a nav2 map).
#[inline]
fn floor_nn(x: f64) -> f64 {
    if (0.0..9.0e15).contains(&x) {
        (x as i64) as f64
    } else {
        x.floor()
    }
}

/// `x.round()` (half away from zero) the same way.
#[inline]
fn round_nn(x: f64) -> f64 {
    if (0.0..9.0e15).contains(&x) {
        ((x + 0.5) as i64) as f64
    } else {
        x.round()
    }
}

/// An A* queue entry: (f, node), smallest f first (also Theta*'s, `grid_planners`).
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

/// `host-sim optimum`: each leg's exact optimum and the CPU time it took, uncached, with a
/// line per leg as it ends; beside it A* on the 8-connected grid and Theta* on the same cells
/// ([`crate::grid_planners`]), their lengths / optimum and CPU times.
pub fn report(s: &Scenario) {
    let t0 = cpu_time::ThreadTime::now().as_duration().as_secs_f64();
    let grid = s.reach_grid();
    let corners = Corners::of(&grid);
    println!(
        "{}: {} x {} cells of {} m, {} obstacle corners ({:.3} s CPU)",
        s.name,
        grid.cols(),
        grid.rows(),
        grid.cell_size(),
        corners.len(),
        cpu_time::ThreadTime::now().as_duration().as_secs_f64() - t0
    );
    let cpu = || cpu_time::ThreadTime::now().as_duration().as_secs_f64();
    type Planner = fn(&OccupancyGrid<'_>, Point, Point) -> Option<crate::grid_planners::GridPath>;
    let planners: [(&str, Planner); 2] = [
        ("A* (8-connected)", crate::grid_planners::astar8),
        ("Theta*", crate::grid_planners::theta_star),
    ];
    for (k, (a, b)) in leg_starts(s)
        .into_iter()
        .zip(s.goals.iter().copied())
        .enumerate()
    {
        let t = cpu();
        let d = corners.shortest(a, b);
        println!(
            "  leg {}: exact optimum {} ({:.3} s CPU)",
            k + 1,
            d.map_or("unreachable".to_string(), |d| format!("{d:.4} m")),
            cpu() - t
        );
        // The grid planners on the same cells (module `grid_planners`).
        for (name, plan) in planners {
            let t = cpu();
            let p = plan(&grid, a, b);
            let took = cpu() - t;
            let ratio = match (&p, d) {
                (Some(p), Some(d)) if d > 0.0 => format!(" ({:.4} x optimum)", p.length_m / d),
                _ => String::new(),
            };
            println!(
                "    {name}: {}{ratio} ({took:.3} s CPU)",
                p.map_or("no path".to_string(), |p| format!("{:.4} m", p.length_m)),
            );
        }
    }
}

/// Bumped whenever `Corners` or `shortest` would give another figure.
const CACHE_VERSION: u64 = 1;
// (Unchanged by the bounded search of issue 42: the same figures, faster.)

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

    /// The bounded search gives the unbounded one's figure to the last bit on random maps
    /// (cells occupied at 10, 25 and 40 %: narrow passages and diagonal pinches among them, at
    /// 1, 0.25 and 0.05 m cells), ends anywhere in free cells.
    #[test]
    fn the_bound_changes_no_figure() {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        for case in 0..400 {
            let (w, h) = (8 + (next() % 40) as u16, 8 + (next() % 40) as u16);
            let density = [10, 25, 40][case % 3];
            let occ: Vec<bool> = (0..usize::from(w) * usize::from(h))
                .map(|_| next() % 100 < density)
                .collect();
            let cell = [1.0f32, 0.25, 0.05][case % 3];
            let g = OwnedGrid::from_fn(w, h, cell, |c, r| {
                occ[usize::from(r) * usize::from(w) + usize::from(c)]
            })
            .unwrap();
            let grid = g.grid();
            let k = Corners::of(&grid);
            let free: Vec<(u16, u16)> = (0..h)
                .flat_map(|r| (0..w).map(move |c| (c, r)))
                .filter(|&(c, r)| !grid.is_occupied(c, r))
                .collect();
            if free.len() < 2 {
                continue;
            }
            for _ in 0..4 {
                let pick = |v: u64| {
                    let (c, r) = free[(v % free.len() as u64) as usize];
                    Point::new((c as f32 + 0.3) * cell, (r as f32 + 0.6) * cell)
                };
                let (a, b) = (pick(next()), pick(next()));
                let (x, y) = (k.shortest(a, b), k.shortest_unbounded(a, b));
                assert_eq!(
                    x.map(f64::to_bits),
                    y.map(f64::to_bits),
                    "case {case}: {a:?} -> {b:?}: {x:?} vs {y:?}"
                );
            }
        }
    }

    #[test]
    fn walled_off_goal_is_unreachable() {
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, _| c == 5).unwrap();
        let k = Corners::of(&g.grid());
        assert_eq!(k.shortest(Point::new(2.0, 5.0), Point::new(8.0, 5.0)), None);
    }
}
