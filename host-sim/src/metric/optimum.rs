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
//! of collision-free paths. A* searches the graph with edges tested lazily, so only the nodes
//! that can beat the current best are expanded.
//!
//! Prunings that keep it exact make it scale (issue 42):
//! - **Dead ends are filled** (`Corners`): a free cell with at most one free side-neighbour,
//!   peeled off again and again, can only be entered and left over that one side, so a
//!   shortest path between points outside never needs it; the search runs on the map with
//!   them occupied, and a leg whose end lies in one opens the cells from it to the live map
//!   (or to where its two ends' ways meet). A maze of 1-cell corridors without loops is all
//!   dead ends: its leg searches the corridor between its ends and nothing else.
//! - **The heuristic is the lattice's distance to the goal** (`Graph::lattice_to`, A* per
//!   leg from the goal towards the start with Dial's buckets over the cells' corners, steps
//!   along free grid lines and across free cells): every free segment has a staircase over
//!   the cells it crosses at most 1.0824 times as long, so that distance over 1.0824, less
//!   the goal cell's half diagonal, never exceeds the distance left and is consistent; in a
//!   maze or a building it follows the corridors and doors where the straight line does not.
//!   Points the lattice search leaves (off the way between the ends) get a bound from its
//!   last key instead.
//! - **From a corner, only the corners in view**, found by casting shadows row by row in four
//!   quadrants (`Graph::lattice_in_view`: a superset, `sees` decides), and only on the
//!   side that keeps the path taut round the corner's occupied cell (a shortest path bends
//!   only round it); none of them head on into its cell (no taut way on from there). A row
//!   is read a run of cells at a time from bit rows of the map and of its corners (`CastRows`),
//!   so a cast over a room of fine cells costs its words, not its cells.
//! - **A segment is walked crossing by crossing** and dropped at its first blocked piece, the
//!   core's span test answering for long free ones.
//! - **Long edges are tested lazily**: an edge free over its first pieces that beats every
//!   edge into its corner so far waits on the open list untested, and most are outdone before
//!   they come off it (`Graph::search_path`).
//!
//! On the filled map, the figures are those of the plain search (every corner from every
//! corner, the straight line as heuristic) to the bit (`the_prunings_change_no_figure`: 400
//! random maps; `..._on_a_maze`: 1-cell corridors with loops); the fill changes none beyond
//! the rounding of a sum (`filling_dead_ends_changes_no_figure`: 240 mazes with and without
//! loops and maps of 30-45 % clutter, ends inside cells, on their sides and corners, on the
//! map's edge, in dead ends and not). `host-sim optimum --no-grid` prints each leg's figure
//! and CPU time (`scripts/gen-maps.py --big` for the generated maps; the figures of the last
//! measurement are in `docs/notebook/exact-optimum.md`): about a second a leg at most, on the
//! mazes of 1-cell corridors up to 4,095 cells (2.9 million corners, legs of 216-690 km) and
//! on the longest legs across a 4,096-cell building drawn like a SLAM map at 0.05 m (there
//! the lattice search over most of its 16.8 million points is most of it).
//!
//! Checked against the exact optima of the 24 reference legs in
//! `../shared/anchors/reference-figures.md` (test `optima_match_the_reference_figures`).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;
use bitvec::vec::BitVec;

use crate::scenario::Scenario;

/// The lattice's unit step, and its diagonal rounded down (`lattice_to`).
const LATTICE_UNIT: f64 = 64.0;
const DIAG_DOWN: u32 = 90;
/// The octile length over the Euclidean at its worst, sqrt(4 - 2 sqrt 2) = 1.0823922...,
/// rounded up.
const LATTICE_STRETCH: f64 = 1.082_393;
/// The farthest a corner of the goal's cell is from the goal.
const GOAL_CELL: f64 = std::f64::consts::SQRT_2;

/// On a map of fewer corners a search scans them all from every corner.
const FOV_MIN: usize = 256;
/// A corner's shadow casting gives up after this many cells per corner of the map (and the
/// search scans every corner instead).
const FOV_BUDGET: usize = 64;
/// ... and never before this many cells.
const FOV_CELLS: usize = 1 << 21;

/// An edge on the search's open list: its key (label plus heuristic), its label and its index;
/// the least key first, then the least label (two labels a bit apart may make one key), then
/// the first pushed.
struct OpenEdge(f64, f64, usize);

impl PartialEq for OpenEdge {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for OpenEdge {}

impl PartialOrd for OpenEdge {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl Ord for OpenEdge {
    fn cmp(&self, other: &Self) -> Ordering {
        (other.0.total_cmp(&self.0))
            .then(other.1.total_cmp(&self.1))
            .then(other.2.cmp(&self.2))
    }
}

/// Each leg's exact optimum on one map: the map with its dead ends filled (below), and the
/// way back out of each dead end.
///
/// **Dead ends** (issue 42: a maze of 1-cell corridors is almost all dead ends, and A* opened
/// most of them): a free cell with at most one free side-neighbour is a dead end, and so is
/// one whose other neighbours are dead ends (filled one by one, like peeling the leaves off a
/// tree). Its only way out is the side it shares with that neighbour (its other corners are
/// walled, or pinches that closed squares shut), so a path that goes in and comes back out
/// can go straight along that side instead, no longer: a shortest path between two points
/// outside the dead ends never enters one, and the search runs on the map with them filled
/// (fewer corners, a lattice that follows only the live corridors). An end inside a dead end
/// opens the cells from it to the live map (or to where the two ends' ways meet) again for
/// its leg. The figure is the same as on the unfilled map (test
/// `filling_dead_ends_changes_no_figure`).
pub struct Corners {
    /// The map with its dead ends filled.
    filled: Graph,
    /// Per cell: `LIVE` (occupied, or free and not a dead end), else the neighbour a dead end
    /// opens onto, or `ROOT` when the whole piece of the map was a dead end.
    up: Vec<u32>,
    /// The corners of the map before the fill.
    all: usize,
}

/// [`Corners::up`]'s marks.
const LIVE: u32 = u32::MAX;
const ROOT: u32 = u32::MAX - 1;

impl Corners {
    /// The corners of `grid`, its dead ends filled.
    pub fn of(grid: &OccupancyGrid<'_>) -> Self {
        let (cols, rows) = (grid.cols() as usize, grid.rows() as usize);
        let mut occupied = vec![false; cols * rows];
        for r in 0..rows {
            for c in 0..cols {
                occupied[r * cols + c] = grid.is_occupied(c as u16, r as u16);
            }
        }
        let up = dead_ends(&occupied, cols, rows);
        // The map's corners (`Graph::corner_at`): lattice points inside it with one occupied
        // cell of the four around.
        let all = (1..rows)
            .flat_map(|j| (1..cols).map(move |i| (i, j)))
            .filter(|&(i, j)| {
                let at = |c: usize, r: usize| usize::from(occupied[r * cols + c]);
                at(i - 1, j - 1) + at(i, j - 1) + at(i - 1, j) + at(i, j) == 1
            })
            .count();
        for (o, &u) in occupied.iter_mut().zip(&up) {
            *o |= u != LIVE;
        }
        Self {
            filled: Graph::new(grid, &occupied),
            up,
            all,
        }
    }

    /// Number of obstacle corners of the map.
    pub fn len(&self) -> usize {
        self.all
    }

    /// Whether the map has no corner (an empty map).
    pub fn is_empty(&self) -> bool {
        self.all == 0
    }

    /// Number of corners left once the dead ends are filled.
    pub fn live(&self) -> usize {
        self.filled.len()
    }

    /// The length in metres of the shortest path from `a` to `b` (positions in metres), or
    /// `None` when the goal cannot be reached.
    ///
    /// A* over the visibility graph with prunings that keep it exact (module docs): the
    /// lattice's distance to the goal as heuristic (`Graph::lattice_to`); from a corner, only
    /// the corners in view (`Graph::lattice_in_view`) on the side that keeps the path taut
    /// round its occupied cell; no edge into a corner head on; an edge tested only when it
    /// can still beat the goal's label; the map's dead ends filled but the ends' own.
    pub fn shortest(&self, a: Point, b: Point) -> Option<f64> {
        self.shortest_path(a, b).map(|(d, _)| d)
    }

    /// [`Self::shortest`] and the path's points, from `a` to `b` (metres): its straight
    /// pieces are one fewer.
    pub fn shortest_path(&self, a: Point, b: Point) -> Option<(f64, Vec<Point>)> {
        self.leg(a, b).shortest_path(a, b)
    }

    /// The map's graph without the fill (the tests' yardstick).
    #[cfg(test)]
    fn unfilled(&self) -> Graph {
        let mut g = self.filled.clone();
        let dead: Vec<usize> = (0..self.up.len()).filter(|&k| self.up[k] != LIVE).collect();
        g.open(&dead);
        g
    }

    /// The filled map for a leg from `a` to `b`: the cells from each end's dead end out to
    /// the live map opened again, or only to where the two ways meet when both ends lie in
    /// one dead end (above it, the way from one end to the other does not go).
    fn leg(&self, a: Point, b: Point) -> std::borrow::Cow<'_, Graph> {
        use std::borrow::Cow;
        let g = &self.filled;
        // The dead cells whose closed square holds an end.
        let cells = |p: Point| -> Vec<usize> {
            let p = (f64::from(p.x) / g.cell, f64::from(p.y) / g.cell);
            cells_holding(p, g.cols, g.rows)
                .map(|(c, r)| (r * g.cols + c) as usize)
                .filter(|&k| self.up[k] != LIVE)
                .collect()
        };
        let (from_a, from_b) = (cells(a), cells(b));
        if from_a.is_empty() && from_b.is_empty() {
            return Cow::Borrowed(g);
        }
        // The cells on `a`'s ways out, up to the live map or the whole piece's last cell.
        let mut on_a = vec![false; self.up.len()];
        let way = |k: usize| {
            std::iter::successors(Some(k), |&k| match self.up[k] {
                ROOT => None,
                u if self.up[u as usize] == LIVE => None,
                u => Some(u as usize),
            })
        };
        for &e in &from_a {
            for k in way(e) {
                if on_a[k] {
                    break;
                }
                on_a[k] = true;
            }
        }
        // `b`'s ways, each up to the first cell on one of `a`'s (where they meet: above it,
        // neither way is needed), then `a`'s up to the first cell where they meet.
        let mut open: Vec<usize> = from_a.iter().chain(&from_b).copied().collect();
        let mut meet = vec![false; self.up.len()];
        for &e in &from_b {
            for k in way(e) {
                open.push(k);
                if on_a[k] {
                    meet[k] = true;
                    break;
                }
            }
        }
        for &e in &from_a {
            for k in way(e) {
                open.push(k);
                if meet[k] {
                    break;
                }
            }
        }
        let mut leg = g.clone();
        leg.open(&open);
        Cow::Owned(leg)
    }
}

/// Each cell's mark of [`Corners::up`]: dead ends peeled off one by one (a free cell with at
/// most one free side-neighbour that is not one already), each pointing at the neighbour it
/// opens onto. Outside the map counts as walled.
fn dead_ends(occupied: &[bool], cols: usize, rows: usize) -> Vec<u32> {
    let mut up = vec![LIVE; cols * rows];
    let sides = |k: usize| {
        let (c, r) = (k % cols, k / cols);
        [
            (c + 1 < cols).then(|| k + 1),
            (c > 0).then(|| k - 1),
            (r + 1 < rows).then(|| k + cols),
            (r > 0).then(|| k - cols),
        ]
    };
    let mut free_sides = vec![0u8; cols * rows];
    let mut peel: Vec<usize> = Vec::new();
    for k in 0..cols * rows {
        if !occupied[k] {
            free_sides[k] = sides(k).iter().flatten().filter(|&&n| !occupied[n]).count() as u8;
            if free_sides[k] <= 1 {
                peel.push(k);
            }
        }
    }
    while let Some(k) = peel.pop() {
        let mut onto = ROOT;
        for n in sides(k).into_iter().flatten() {
            if !occupied[n] && up[n] == LIVE {
                onto = n as u32;
                free_sides[n] -= 1;
                if free_sides[n] == 1 {
                    peel.push(n);
                }
            }
        }
        up[k] = onto;
    }
    up
}

/// The visibility-graph nodes of one map (convex obstacle corners) and its cells.
#[derive(Clone)]
struct Graph {
    cols: i64,
    rows: i64,
    cell: f64,
    /// The grid's packed cells: the core's segment test, a fast conservative first look
    /// (on the map before the fill: a straight segment between two points outside a dead end
    /// never crosses one, it would go in and out over the one side it opens onto).
    bits: Vec<u8>,
    /// Corner positions (lattice points, in cell units), in the lattice's row-major order.
    corners: Vec<(u16, u16)>,
    /// Per corner, the diagonal direction (x, y in {-1, 1}) of its one occupied cell.
    quadrant: Vec<(i8, i8)>,
    /// Per word of the corners' row-major bits ([`CastRows::corners`]), the corners before
    /// it: a corner's number is its rank.
    rank: Vec<u32>,
    /// Per lattice point, its lattice steps (`lattice_to`): bit k for the k-th of right,
    /// left, down, up (beside a free cell or the map's edge), down-right, up-left, up-right,
    /// down-left (across a free cell).
    steps: Vec<u8>,
    /// The shadow casts' rows (`lattice_in_view`).
    cast: CastRows,
}

/// A map's rows for the shadow casts, read a word at a time: the occupied cells by rows (bit
/// `r * cols + c`) and by columns (bit `c * rows + r`), and the corners' lattice points
/// likewise (bit `j * (cols + 1) + i` and `i * (rows + 1) + j`).
#[derive(Clone)]
struct CastRows {
    occ: [BitVec<u64>; 2],
    corners: [BitVec<u64>; 2],
}

impl CastRows {
    /// The rows of a `cols` x `rows` map with cells `occupied` (row-major), no corners yet.
    fn of(occupied: &[bool], cols: usize, rows: usize) -> Self {
        let by_cols = (0..cols).flat_map(|c| (0..rows).map(move |r| r * cols + c));
        Self {
            occ: [
                occupied.iter().copied().collect(),
                by_cols.map(|k| occupied[k]).collect(),
            ],
            corners: [0, 1].map(|_| BitVec::repeat(false, (cols + 1) * (rows + 1))),
        }
    }

    /// Marks lattice point `(i, j)` a corner or not.
    fn mark(&mut self, (cols, rows): (i64, i64), (i, j): (i64, i64), corner: bool) {
        let [a, b] = &mut self.corners;
        put(a, (j * (cols + 1) + i) as usize, corner);
        put(b, (i * (rows + 1) + j) as usize, corner);
    }

    /// Frees cell `(c, r)`.
    fn free(&mut self, (cols, rows): (i64, i64), (c, r): (i64, i64)) {
        let [a, b] = &mut self.occ;
        put(a, (r * cols + c) as usize, false);
        put(b, (c * rows + r) as usize, false);
    }
}

/// Sets bit `k` of `bits` to `on`, on its word (a leg frees a whole corridor's cells).
fn put(bits: &mut BitVec<u64>, k: usize, on: bool) {
    let word = &mut bits.as_raw_mut_slice()[k / 64];
    let mask = 1u64 << (k % 64);
    *word = if on { *word | mask } else { *word & !mask };
}

/// The first bit at or after `from` (and up to `to`, both inclusive) that differs from bit
/// `from`, in `words` (least significant bit first), if any: the end of a run.
fn run_end(words: &[u64], from: usize, to: usize) -> Option<usize> {
    let flip = if words[from / 64] >> (from % 64) & 1 == 1 {
        u64::MAX
    } else {
        0
    };
    let mut w = from / 64;
    // The bits that differ, those before `from` masked off.
    let mut diff = (words[w] ^ flip) & (u64::MAX << (from % 64));
    loop {
        if diff != 0 {
            let at = w * 64 + diff.trailing_zeros() as usize;
            return (at <= to).then_some(at);
        }
        w += 1;
        if w * 64 > to {
            return None;
        }
        diff = words[w] ^ flip;
    }
}

/// Each set bit from `from` to `to` (inclusive) in `words`, in order.
fn each_one(words: &[u64], from: usize, to: usize, mut f: impl FnMut(usize)) {
    let mut w = from / 64;
    let mut bits = words[w] & (u64::MAX << (from % 64));
    loop {
        while bits != 0 {
            let at = w * 64 + bits.trailing_zeros() as usize;
            if at > to {
                return;
            }
            f(at);
            bits &= bits - 1;
        }
        w += 1;
        if w * 64 > to {
            return;
        }
        bits = words[w];
    }
}

/// Whether lattice point `(i, j)` (inside the map) is a convex corner (one occupied cell of
/// the four around it, as `occ` tells), and that cell's diagonal direction from it.
fn corner_of(occ: impl Fn(i64, i64) -> bool, i: i64, j: i64) -> Option<(f64, f64)> {
    // Cells around lattice point (i, j): NW, NE, SW, SE.
    let (a, b, c, d) = (occ(i - 1, j - 1), occ(i, j - 1), occ(i - 1, j), occ(i, j));
    let n = [a, b, c, d].iter().filter(|&&o| o).count();
    (n == 1).then(|| match (a, b, c) {
        (true, _, _) => (-1.0, -1.0),
        (_, true, _) => (1.0, -1.0),
        (_, _, true) => (-1.0, 1.0),
        _ => (1.0, 1.0),
    })
}

/// Lattice point `(i, j)`'s steps ([`Graph::steps`]) on a map whose cells `occ` tells.
fn steps_of(occ: impl Fn(i64, i64) -> bool, (cols, rows): (i64, i64), i: i64, j: i64) -> u8 {
    // Free cells around (i, j), outside the map counting as free (as in `sees`).
    let (nw, ne, sw, se) = (
        !occ(i - 1, j - 1),
        !occ(i, j - 1),
        !occ(i - 1, j),
        !occ(i, j),
    );
    let (r, l, d, u) = (i < cols, i > 0, j < rows, j > 0);
    let bits = [
        r && (ne || se),
        l && (nw || sw),
        d && (sw || se),
        u && (nw || ne),
        r && d && se,
        l && u && nw,
        r && u && ne,
        l && d && sw,
    ];
    bits.iter()
        .enumerate()
        .fold(0u8, |m, (k, &b)| m | (u8::from(b) << k))
}

impl Graph {
    /// The corners of `grid` with its cells `occupied` (row-major).
    fn new(grid: &OccupancyGrid<'_>, occupied: &[bool]) -> Self {
        let (cols, rows) = (grid.cols() as i64, grid.rows() as i64);
        let mut me = Self {
            cols,
            rows,
            cell: grid.cell_size() as f64,
            cast: CastRows::of(occupied, cols as usize, rows as usize),
            bits: grid.bits().to_vec(),
            corners: Vec::new(),
            quadrant: Vec::new(),
            rank: Vec::new(),
            steps: vec![0; ((cols + 1) * (rows + 1)) as usize],
        };
        // From the cells as given (a byte a cell: faster to read than the bit rows).
        let occ = |c: i64, r: i64| {
            c >= 0 && r >= 0 && c < cols && r < rows && occupied[(r * cols + c) as usize]
        };
        for j in 1..rows {
            for i in 1..cols {
                if corner_of(occ, i, j).is_some() {
                    me.cast.mark((cols, rows), (i, j), true);
                }
            }
        }
        me.number_corners();
        for j in 0..=rows {
            for i in 0..=cols {
                me.steps[(j * (cols + 1) + i) as usize] = steps_of(occ, (cols, rows), i, j);
            }
        }
        me
    }

    /// Whether lattice point `(i, j)` (inside the map) is a convex corner, and its cell's
    /// diagonal direction ([`corner_of`]).
    fn corner_at(&self, i: i64, j: i64) -> Option<(f64, f64)> {
        corner_of(|c, r| self.occ(c, r), i, j)
    }

    /// Lattice point `(i, j)`'s steps ([`Self::steps`], [`steps_of`]).
    fn steps_at(&self, i: i64, j: i64) -> u8 {
        steps_of(|c, r| self.occ(c, r), (self.cols, self.rows), i, j)
    }

    /// The graph with `cells` (row-major indices) free: their corners' marks and steps
    /// recomputed, and the corners numbered again.
    fn open(&mut self, cells: &[usize]) {
        let w = self.cols + 1;
        let size = (self.cols, self.rows);
        let at = |k: usize| ((k as i64) % self.cols, (k as i64) / self.cols);
        for &k in cells {
            self.cast.free(size, at(k));
        }
        // Each lattice point once (a leg opens a corridor's cells, each point shared by up to
        // four of them).
        let mut met: BitVec<u64> = BitVec::repeat(false, self.steps.len());
        let points = cells.iter().flat_map(|&k| {
            let (c, r) = at(k);
            [(c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1)]
        });
        for (i, j) in points {
            let p = (j * w + i) as usize;
            if met.replace(p, true) {
                continue;
            }
            self.steps[p] = self.steps_at(i, j);
            let inner = i > 0 && j > 0 && i < self.cols && j < self.rows;
            let corner = inner && self.corner_at(i, j).is_some();
            self.cast.mark(size, (i, j), corner);
        }
        self.number_corners();
    }

    /// The corners' positions, quadrants and numbers from their bits, in row-major order.
    fn number_corners(&mut self) {
        let bits = self.cast.corners[0].as_raw_slice();
        let w = (self.cols + 1) as usize;
        self.corners.clear();
        self.quadrant.clear();
        self.rank.clear();
        for (k, &word) in bits.iter().enumerate() {
            self.rank.push(self.corners.len() as u32);
            let mut m = word;
            while m != 0 {
                let p = k * 64 + m.trailing_zeros() as usize;
                m &= m - 1;
                let (i, j) = ((p % w) as i64, (p / w) as i64);
                // A corner's bit is set where `corner_at` finds one (`new`, `open`).
                let q = self.corner_at(i, j).unwrap_or_default();
                debug_assert!(q != (0.0, 0.0), "({i}, {j}) marked a corner");
                self.corners.push((i as u16, j as u16));
                self.quadrant.push((q.0 as i8, q.1 as i8));
            }
        }
    }

    /// The number of the corner at lattice point `(i, j)`, a corner.
    fn corner_number(&self, i: i64, j: i64) -> usize {
        let p = (j * (self.cols + 1) + i) as usize;
        let below = self.cast.corners[0].as_raw_slice()[p / 64] & ((1u64 << (p % 64)) - 1);
        self.rank[p / 64] as usize + below.count_ones() as usize
    }

    /// Number of corners.
    fn len(&self) -> usize {
        self.corners.len()
    }

    fn occ(&self, c: i64, r: i64) -> bool {
        if c < 0 || r < 0 || c >= self.cols || r >= self.rows {
            return false;
        }
        let k = (r * self.cols + c) as usize;
        self.cast.occ[0].as_raw_slice()[k / 64] >> (k % 64) & 1 != 0
    }

    /// Corner `k`'s position, in cell units.
    fn corner(&self, k: usize) -> (f64, f64) {
        let (i, j) = self.corners[k];
        (f64::from(i), f64::from(j))
    }

    /// The diagonal direction of corner `k`'s occupied cell.
    fn quad(&self, k: usize) -> (f64, f64) {
        let (x, y) = self.quadrant[k];
        (f64::from(x), f64::from(y))
    }

    /// Whether the segment between two points (cell units) stays out of the obstacles'
    /// interior: every piece between two grid-line crossings is tested at its midpoint, and
    /// every lattice point it passes through where two squares touch diagonally shuts it. The
    /// crossings are walked in order and the walk stops at the first blocked piece (a segment
    /// into a wall costs a few cells, not its length).
    fn sees(&self, a: (f64, f64), b: (f64, f64)) -> bool {
        self.walk(a, b, false) == Some(true)
    }

    /// [`Self::sees`] decided within the segment's first pieces: `None` when they are free and
    /// more of the segment is left (the rest of the test is the costly part of a long free
    /// segment; a blocked one ends in its first pieces in most cases).
    fn sees_at_first(&self, a: (f64, f64), b: (f64, f64)) -> Option<bool> {
        self.walk(a, b, true)
    }

    /// The walk of [`Self::sees`]; with `first_only`, `None` after the first pieces.
    fn walk(&self, a: (f64, f64), b: (f64, f64), first_only: bool) -> Option<bool> {
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
                        k: floor_nn(lo) + 1.0,
                        end: hi,
                    }
                } else if d < 0.0 {
                    // Descending from the largest integer below `hi` to the smallest above `lo`.
                    Axis {
                        p,
                        d,
                        k: ceil_nn(hi) - 1.0,
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
                        return Some(false);
                    }
                }
            }
            if t - prev >= 1e-12 && self.piece_blocked(a, (dx, dy), 0.5 * (prev + t)) {
                return Some(false);
            }
            pieces += 1;
            if pieces == 8 && t < 1.0 {
                if first_only {
                    return None;
                }
                if self.core_free(a, b) {
                    return Some(true);
                }
            }
            if t >= 1.0 {
                return Some(true);
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

    /// [`Corners::shortest_path`] on this graph.
    fn shortest_path(&self, a: Point, b: Point) -> Option<(f64, Vec<Point>)> {
        self.search_path(a, b, FOV_MIN, FOV_BUDGET).map(|(d, pts)| {
            let m = |p: (f64, f64)| Point::new((p.0 * self.cell) as f32, (p.1 * self.cell) as f32);
            (d, pts.into_iter().map(m).collect())
        })
    }

    /// [`Corners::shortest`] on this graph, casting shadows from a corner when it has at least
    /// `fov_min` corners, each cast giving up after `fov_budget` cells per corner (and at
    /// least `FOV_CELLS`).
    #[cfg(test)]
    fn search(&self, a: Point, b: Point, fov_min: usize, fov_budget: usize) -> Option<f64> {
        self.search_path(a, b, fov_min, fov_budget).map(|(d, _)| d)
    }

    /// [`Self::search`] with the path's points (cell units).
    fn search_path(
        &self,
        a: Point,
        b: Point,
        fov_min: usize,
        fov_budget: usize,
    ) -> Option<(f64, Vec<(f64, f64)>)> {
        let s = (a.x as f64 / self.cell, a.y as f64 / self.cell);
        let g = (b.x as f64 / self.cell, b.y as f64 / self.cell);
        // An end off the map (or not a number) has no path: refused before a walk along a
        // segment that long (a point 1e30 m away took for ever, issue 45's bad-input test).
        let on_map = |p: (f64, f64)| {
            (0.0..=self.cols as f64).contains(&p.0) && (0.0..=self.rows as f64).contains(&p.1)
        };
        if !on_map(s) || !on_map(g) {
            return None;
        }
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        if self.sees(s, g) {
            return Some((dist(s, g) * self.cell, vec![s, g]));
        }
        let to_goal = self.lattice_to(g, s);
        // The heuristic (`lattice_to`): the straight line or the lattice's distance over its
        // stretch less the goal cell's half diagonal, whichever is longer; infinite where the
        // lattice does not reach (nor does any path).
        let h: Vec<f64> = (0..self.len())
            .map(|k| {
                let p = self.corner(k);
                match to_goal.at(p.0 as i64, p.1 as i64) {
                    u32::MAX => f64::INFINITY,
                    d => dist(p, g)
                        .max(f64::from(d) / LATTICE_UNIT / LATTICE_STRETCH - GOAL_CELL - 1e-9),
                }
            })
            .collect();
        // Nodes: the corners, then the goal, then the start.
        let n = self.corners.len();
        let pos = |i: usize| match i.cmp(&n) {
            Ordering::Less => self.corner(i),
            Ordering::Equal => g,
            Ordering::Greater => s,
        };
        let hv = |i: usize| if i < n { h[i] } else { 0.0 };
        // In a building most of the corners the start looks at first (it casts no shadows)
        // lie behind its room's walls: the lattice tells most of them without a walk.
        let start_view = StartView::new(self, &to_goal, s);
        let cast = n >= fov_min;
        let mut seen = vec![0u32; n];
        let mut stamp = 0u32;
        let mut view: Vec<usize> = Vec::new();
        // Long edges are tested lazily. The open list holds edges (the node, where from, its
        // label, whether tested). An edge is tested at once as far as its first pieces (where a
        // blocked edge ends in most cases, in a maze); one that is free there and goes on is
        // pushed untested when it beats every edge pushed into its node so far, else tested
        // whole at once, and an untested edge is tested when it comes off the list. The first
        // edge of a node that passes closes it: the least free edge into it from a closed node,
        // with the eager search's label (the heuristic is consistent), after a fraction of the
        // long tests in a building, where most long edges are outdone before they come off.
        // Edges into the goal are tested whole at once (the goal's label bounds the search).
        //
        let mut best = vec![f64::INFINITY; n + 2];
        let mut least = vec![f64::INFINITY; n + 2];
        let mut parent = vec![usize::MAX; n + 2];
        let mut closed = vec![false; n + 2];
        let mut edges: Vec<(usize, usize, f64, bool)> = vec![(n + 1, usize::MAX, 0.0, true)];
        let mut open = BinaryHeap::new();
        open.push(OpenEdge(dist(s, g), 0.0, 0));
        while let Some(OpenEdge(_, _, e)) = open.pop() {
            let (u, from, c, tested) = edges[e];
            if closed[u] || (!tested && !self.sees(pos(from), pos(u))) {
                continue;
            }
            best[u] = c;
            parent[u] = from;
            if u == n {
                let mut points = vec![g];
                let mut v = n;
                while v != n + 1 {
                    v = parent[v];
                    points.push(pos(v));
                }
                points.reverse();
                return Some((best[n] * self.cell, points));
            }
            closed[u] = true;
            let pu = pos(u);
            // A shortest path bends at a corner only round its occupied cell: from the corner,
            // the way back and the way on enclose that cell's diagonal (module docs).
            let back = (u < n).then(|| {
                let pp = pos(parent[u]);
                ((pp.0 - pu.0, pp.1 - pu.1), self.quad(u))
            });
            // The corners in view of a corner, when the shadows find them sooner than a
            // scan of every corner would; else every corner (and always the goal).
            let mut in_view = None;
            if let Some((a, w)) = back.filter(|_| cast) {
                let reach = best[n] - best[u];
                let far = self.cols.max(self.rows) + 1;
                let depth = if reach.is_finite() {
                    (ceil_nn(reach) as i64 + 1).min(far)
                } else {
                    far
                };
                let halves = taut_halves(a, w);
                stamp += 1;
                view.clear();
                let budget = n.saturating_mul(fov_budget).max(FOV_CELLS);
                let ok = self.lattice_in_view(
                    (pu.0 as i64, pu.1 as i64),
                    depth,
                    budget,
                    &halves,
                    &mut |k| {
                        if seen[k] != stamp {
                            seen[k] = stamp;
                            view.push(k);
                        }
                    },
                );
                if ok.is_some() {
                    // In the order of a scan: the same relaxations, the same figure.
                    view.sort_unstable();
                    view.push(n);
                    in_view = Some(&view);
                }
            }
            let every: Vec<usize>;
            let order: &[usize] = match in_view {
                Some(v) => v,
                None => {
                    every = (0..=n).collect();
                    &every
                }
            };
            for &v in order {
                if closed[v] {
                    continue;
                }
                let pv = pos(v);
                let c = best[u] + dist(pu, pv);
                let d = (pv.0 - pu.0, pv.1 - pu.1);
                // Only edges that can still beat the goal's label; not into a corner head on
                // (its cell straight ahead: no taut way on from there).
                if c < best[v]
                    && c + hv(v) < best[n]
                    && (v == n || {
                        let q = self.quad(v);
                        d.0 * q.0 <= 0.0 || d.1 * q.1 <= 0.0
                    })
                    && back.is_none_or(|(a, w)| taut(a, d, w))
                {
                    if u == n + 1 && v < n && start_view.hides(&to_goal, pv) {
                        continue;
                    }
                    let tested = match self.sees_at_first(pu, pv) {
                        Some(false) => continue,
                        Some(true) => true,
                        None if v == n || c >= least[v] => {
                            if !self.sees(pu, pv) {
                                continue;
                            }
                            true
                        }
                        None => false,
                    };
                    if tested {
                        best[v] = c;
                    }
                    least[v] = least[v].min(c);
                    open.push(OpenEdge(c + hv(v), c, edges.len()));
                    edges.push((v, u, c, tested));
                }
            }
        }
        None
    }

    /// The corners that may see lattice point `(i0, j0)` (their numbers, to `found`): the
    /// corners of every free cell that a ray from it reaches without crossing an occupied
    /// cell's interior, found by casting shadows row by row in four quadrants (a superset: a
    /// ray grazing an occupied cell's corner or slipping through a diagonal pinch is kept,
    /// `sees` decides). A row is read a run at a time from [`CastRows`] (each block of
    /// occupied cells narrows the rays once; a run of free cells gives its corners from its
    /// bits), so a cast over a room of fine cells costs its words, not its
    /// cells. Rays are followed to `depth` rows (a point of row `d` is at least `d - 1`
    /// away). `None` once more than `budget` cells were looked at (the caller scans its
    /// candidates instead).
    fn lattice_in_view(
        &self,
        (i0, j0): (i64, i64),
        depth: i64,
        budget: usize,
        halves: &[(f64, f64)],
        found: &mut impl FnMut(usize),
    ) -> Option<()> {
        // Shadows shrink by this much (slopes are at most 1 in a quadrant, coordinates below
        // 2^16: the slopes' rounding is far below it, and far below the overlap of two
        // neighbouring cells' slopes, so a block of occupied cells shades what its cells do
        // one by one).
        const EPS: f64 = 1e-9;
        let mut looked = 0usize;
        let mut rays: Vec<(f64, f64)> = Vec::new();
        let mut next: Vec<(f64, f64)> = Vec::new();
        // A quadrant's frame: lateral x' and depth y' (rows d of y' in [d - 1, d]), their unit
        // vectors in the grid's frame: up (grid y decreasing), down, right, left. The lateral
        // axis always points along increasing grid indices, so a frame's row is a run of
        // bits: the grid's rows in the first two, its columns in the last two.
        let axes: [((i64, i64), (i64, i64)); 4] = [
            ((1, 0), (0, -1)),
            ((1, 0), (0, 1)),
            ((0, 1), (1, 0)),
            ((0, 1), (-1, 0)),
        ];
        // Slope (x' / y') of a lattice point of the frame; a point at depth 0 lies on the
        // quadrant's side (the origin itself is never a cell's far corner that matters).
        let slope = |x: i64, y: i64| {
            if y == 0 {
                if x > 0 {
                    f64::INFINITY
                } else if x < 0 {
                    f64::NEG_INFINITY
                } else {
                    f64::NAN
                }
            } else {
                x as f64 / y as f64
            }
        };
        // The least and the largest slope through cell `c` of row `d` (its corners').
        let slopes = |c: i64, d: i64| {
            let s = [
                slope(c, d - 1),
                slope(c + 1, d - 1),
                slope(c, d),
                slope(c + 1, d),
            ];
            let s = s.iter().copied().filter(|v| !v.is_nan());
            (
                s.clone().fold(f64::INFINITY, f64::min),
                s.fold(f64::NEG_INFINITY, f64::max),
            )
        };
        for (lat, dep) in axes {
            let by_rows = usize::from(lat.1 != 0);
            // The frame's lateral origin and extent (cells of a row), its rows' count, the
            // line of the origin and the sense of depth along the lines.
            let (base, extent, lines, origin, sense) = if by_rows == 0 {
                (i0, self.cols, self.rows, j0, dep.1)
            } else {
                (j0, self.rows, self.cols, i0, dep.0)
            };
            let (occ, corners) = (
                self.cast.occ[by_rows].as_raw_slice(),
                self.cast.corners[by_rows].as_raw_slice(),
            );
            // The line of row d's cells, and of the frame's lattice points at depth y.
            let cell_line = |d: i64| {
                if sense > 0 {
                    origin + d - 1
                } else {
                    origin - d
                }
            };
            let point_line = |y: i64| origin + y * sense;
            // Columns c of the frame on the map.
            let (m0, m1) = (-base, extent - 1 - base);
            // The quadrant's slopes t in [-1, 1] whose direction t lat + dep keeps to every
            // half-plane {b : n . b >= 0} (widened by EPS).
            let (mut lo, mut hi) = (-1.0f64, 1.0f64);
            for &(nx, ny) in halves {
                let p = nx * lat.0 as f64 + ny * lat.1 as f64;
                let q = nx * dep.0 as f64 + ny * dep.1 as f64;
                if p > 0.0 {
                    lo = lo.max((-EPS - q) / p);
                } else if p < 0.0 {
                    hi = hi.min((-EPS - q) / p);
                } else if q < -EPS {
                    hi = lo - 1.0;
                }
            }
            if lo > hi {
                continue;
            }
            rays.clear();
            rays.push((lo, hi));
            for d in 1..=depth {
                let line = cell_line(d);
                // A row off the map: every ray has left it and never comes back to a corner.
                if rays.is_empty() || line < 0 || line >= lines {
                    break;
                }
                // Cell c of the row (on the map) is bit `row + base + c`.
                let row = line * extent;
                let bit = |k: i64| occ[k as usize / 64] >> (k as usize % 64) & 1 == 1;
                // Cell 0 of the row occupied (or off the map): the ray along the frame's
                // axis, between cells -1 and 0, is shut when cell -1 is too.
                let zero_shut = !(m0..=m1).contains(&0) || bit(row + base);
                next.clear();
                for &(lo, hi) in &rays {
                    let (df, dn) = ((d - 1) as f64, d as f64);
                    let (xmin, xmax) = ((lo * df).min(lo * dn), (hi * df).max(hi * dn));
                    let (c0, c1) = (floor_any(xmin - EPS), floor_any(xmax + EPS));
                    let mut run = lo;
                    let mut any_inside = false;
                    let mark = next.len();
                    let mut c = c0;
                    while c <= c1 {
                        // The block of cells from c on that are all occupied (or off the
                        // map) or all free, to c1 at most.
                        let (end, occupied) = if c < m0 {
                            (c1.min(m0 - 1), true)
                        } else if c > m1 {
                            (c1, true)
                        } else {
                            any_inside = true;
                            let last = c1.min(m1);
                            let first = (row + base + c) as usize;
                            let end = run_end(occ, first, (row + base + last) as usize)
                                .map_or(last, |k| c + (k - first) as i64 - 1);
                            looked += (end - c + 1) as usize;
                            if looked > budget {
                                return None;
                            }
                            (end, bit(row + base + c))
                        };
                        if occupied {
                            // The slopes through the block's interior, shrunk.
                            let smin = slopes(c, d).0 + EPS;
                            let smax = if end == -1 && zero_shut {
                                EPS
                            } else {
                                slopes(end, d).1 - EPS
                            };
                            if smin < smax {
                                if smin > run {
                                    next.push((run, smin.min(hi)));
                                }
                                run = run.max(smax);
                            }
                        } else {
                            // The corners of the free cells: lattice points c..=end + 1 at
                            // depths d - 1 and d.
                            for y in [d - 1, d] {
                                let at = point_line(y) * (extent + 1) + base;
                                let (from, to) = ((at + c) as usize, (at + end + 1) as usize);
                                each_one(corners, from, to, |k| {
                                    let x = c + (k - from) as i64;
                                    let (i, j) = if by_rows == 0 {
                                        (base + x, point_line(y))
                                    } else {
                                        (point_line(y), base + x)
                                    };
                                    found(self.corner_number(i, j));
                                });
                            }
                        }
                        c = end + 1;
                    }
                    if run <= hi {
                        next.push((run, hi));
                    }
                    if !any_inside {
                        // Every ray of this run has left the map.
                        next.truncate(mark);
                    }
                }
                next.retain(|&(a, b)| a <= b);
                std::mem::swap(&mut rays, &mut next);
            }
        }
        Some(())
    }

    /// A lower bound of each lattice point's distance to the corners of the free cells around
    /// `g` over the lattice (in 1/`LATTICE_UNIT` of a cell; `u32::MAX`: not reached): steps
    /// along a grid line beside a free cell (or the map's edge) and across a free cell's
    /// diagonal, the diagonal rounded down. A* from `g` towards the start `s` (the octile
    /// distance to `s`'s cell as its heuristic, with Dial's buckets, one per key modulo a
    /// power of two above the most a key grows in a step), stopped some way past `s` (below).
    ///
    /// The heuristic of [`Corners::shortest`]: a free segment between two lattice points has
    /// a lattice path over the cells it crosses (a Bresenham staircase) at most
    /// `LATTICE_STRETCH` times as long (the octile over the Euclidean length at its worst),
    /// so a shortest path of length L from a corner to the goal, taken on to a corner of the
    /// goal's cell (at most sqrt 2 further), gives a lattice path no longer than
    /// `LATTICE_STRETCH` (L + sqrt 2): this distance over the stretch, less sqrt 2, never
    /// exceeds L, and falls by no more than a segment's length along it (consistent: A*
    /// stays exact).
    fn lattice_to(&self, g: (f64, f64), s: (f64, f64)) -> ToGoal {
        let w = self.cols + 1;
        let at = |i: i64, j: i64| (j * w + i) as usize;
        let mut dist = vec![u32::MAX; (w * (self.rows + 1)) as usize];
        const NB: usize = 256;
        const _: () = assert!(2 * DIAG_DOWN as usize <= NB && (LATTICE_UNIT as usize) < NB);
        // Each entry: a point (`j << 16 | i`: its row and column, so that no division finds
        // them; a map has at most 4,096 cells a side) and its distance when queued.
        let mut buckets: [Vec<(u32, u32)>; NB] = std::array::from_fn(|_| Vec::new());
        let pack = |i: i64, j: i64| ((j as u32) << 16) | i as u32;
        let mut queued = 0usize;
        let mut start_left: Vec<(i64, i64)> = self.lattice_points_of(s).collect();
        start_left.sort_unstable();
        start_left.dedup();
        // The key's heuristic: the lattice's octile distance to the box round the start's
        // points (their nearest, so consistent; 0 on each of them).
        let to_start = Octile::around(&start_left);
        let mut start_left: Vec<usize> = start_left.into_iter().map(|(i, j)| at(i, j)).collect();
        // The least key queued: the buckets hold keys from it to it plus `NB` less one (the
        // goal's points are at most a cell apart, their keys within two diagonals).
        let mut f = u32::MAX;
        for (i, j) in self.lattice_points_of(g) {
            let p = at(i, j);
            if dist[p] != 0 {
                dist[p] = 0;
                let key = to_start.at(i, j);
                f = f.min(key);
                buckets[key as usize & (NB - 1)].push((pack(i, j), 0));
                queued += 1;
            }
        }
        // Once the start's points are settled (the largest at D), the search goes on to keys
        // of D times the stretch, plus four steps, and stops: a point it did not settle is at
        // least that key less its heuristic from the goal (`ToGoal::at`), which already
        // exceeds what a shortest path can have left there when it lies off the way, so a
        // short leg on a big map costs a short search.
        let span = (
            start_left.iter().copied().min().unwrap_or(usize::MAX),
            start_left.iter().copied().max().unwrap_or(0),
        );
        let mut stop: Option<u32> = None;
        let wi = w as isize;
        let offset: [isize; 8] = [1, -1, wi, -wi, wi + 1, -wi - 1, -wi + 1, wi - 1];
        let step: [(i64, i64); 8] = [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
        ];
        let unit = LATTICE_UNIT as u32;
        let length: [u32; 8] = [
            unit, unit, unit, unit, DIAG_DOWN, DIAG_DOWN, DIAG_DOWN, DIAG_DOWN,
        ];
        // The least key left is at least `f` (the heuristic is consistent).
        while queued > 0 {
            if let Some(cap) = stop.filter(|&cap| f > cap) {
                return ToGoal {
                    dist,
                    w,
                    cap: Some(cap),
                    to_start,
                };
            }
            // A step may keep the key (along the heuristic's slope): the bucket is taken out
            // while it is settled and taken again until no step lands in it.
            let b = f as usize & (NB - 1);
            let mut spare = Vec::new();
            loop {
                let settling = std::mem::replace(&mut buckets[b], spare);
                if settling.is_empty() {
                    spare = settling;
                    break;
                }
                queued -= settling.len();
                for &(ij, d) in &settling {
                    let (i, j) = (i64::from(ij & 0xffff), i64::from(ij >> 16));
                    let u = at(i, j);
                    // A point whose distance fell since it was queued is settled from its
                    // later entry.
                    if dist[u] != d {
                        continue;
                    }
                    if (span.0..=span.1).contains(&u) && stop.is_none() && !start_left.is_empty() {
                        start_left.retain(|&p| p != u);
                        if start_left.is_empty() {
                            let far = f64::from(d) * LATTICE_STRETCH + 4.0 * LATTICE_UNIT;
                            stop = Some(far.ceil().min(f64::from(u32::MAX / 4)) as u32);
                        }
                    }
                    let mut m = self.steps[u];
                    while m != 0 {
                        let k = m.trailing_zeros() as usize;
                        m &= m - 1;
                        let v = u.wrapping_add_signed(offset[k]);
                        let c = d + length[k];
                        if c < dist[v] {
                            dist[v] = c;
                            let (vi, vj) = (i + step[k].0, j + step[k].1);
                            let key = c + to_start.at(vi, vj);
                            buckets[key as usize & (NB - 1)].push((pack(vi, vj), c));
                            queued += 1;
                        }
                    }
                }
                spare = settling;
                spare.clear();
            }
            // The emptied bucket keeps its allocation.
            buckets[b] = spare;
            f += 1;
        }
        ToGoal {
            dist,
            w,
            cap: None,
            to_start,
        }
    }

    /// A point's lattice points: the corners of the free cells whose closed square holds it.
    fn lattice_points_of(&self, p: (f64, f64)) -> impl Iterator<Item = (i64, i64)> + '_ {
        cells_holding(p, self.cols, self.rows)
            .filter(|&(c, r)| !self.occ(c, r))
            .flat_map(|(c, r)| [(c, r), (c + 1, r), (c, r + 1), (c + 1, r + 1)])
    }

    /// The plain search (every corner a candidate from every corner, the straight line as
    /// heuristic; the same answers): the tests compare the two.
    #[cfg(test)]
    fn shortest_unbounded(&self, a: Point, b: Point) -> Option<f64> {
        use crate::metric::grid_planners::Open;
        let s = (a.x as f64 / self.cell, a.y as f64 / self.cell);
        let g = (b.x as f64 / self.cell, b.y as f64 / self.cell);
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        if self.sees(s, g) {
            return Some(dist(s, g) * self.cell);
        }
        let n = self.corners.len();
        let pos = |i: usize| match i.cmp(&n) {
            Ordering::Less => self.corner(i),
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

/// The cells of a `cols` x `rows` map whose closed square holds point `p` (cell units): one
/// to four, none off the map.
fn cells_holding(p: (f64, f64), cols: i64, rows: i64) -> impl Iterator<Item = (i64, i64)> {
    let on_map = (0.0..=cols as f64).contains(&p.0) && (0.0..=rows as f64).contains(&p.1);
    let (pi, pj) = if on_map {
        (floor_any(p.0), floor_any(p.1))
    } else {
        (-2, -2)
    };
    (pj - 1..=pj)
        .flat_map(move |r| (pi - 1..=pi).map(move |c| (c, r)))
        .filter(move |&(c, r)| {
            c >= 0
                && r >= 0
                && c < cols
                && r < rows
                && (c as f64) <= p.0
                && p.0 <= (c + 1) as f64
                && (r as f64) <= p.1
                && p.1 <= (r + 1) as f64
        })
}

/// The octile distance (the lattice's steps, `LATTICE_UNIT` and `DIAG_DOWN`) from a lattice
/// point to the nearest point of a box.
struct Octile {
    x0: i64,
    x1: i64,
    y0: i64,
    y1: i64,
}

impl Octile {
    /// The box round `points` (the origin when there are none: any box is consistent).
    fn around(points: &[(i64, i64)]) -> Self {
        let Some(&(i, j)) = points.first() else {
            return Self {
                x0: 0,
                x1: 0,
                y0: 0,
                y1: 0,
            };
        };
        points.iter().fold(
            Self {
                x0: i,
                x1: i,
                y0: j,
                y1: j,
            },
            |b, &(i, j)| Self {
                x0: b.x0.min(i),
                x1: b.x1.max(i),
                y0: b.y0.min(j),
                y1: b.y1.max(j),
            },
        )
    }

    /// From lattice point `(i, j)`.
    #[inline]
    fn at(&self, i: i64, j: i64) -> u32 {
        let dx = (self.x0 - i).max(i - self.x1).max(0) as u64;
        let dy = (self.y0 - j).max(j - self.y1).max(0) as u64;
        let (lo, hi) = (dx.min(dy), dx.max(dy));
        (u64::from(DIAG_DOWN) * lo + LATTICE_UNIT as u64 * (hi - lo)).min(u64::from(u32::MAX / 4))
            as u32
    }
}

/// [`Graph::lattice_to`]'s answer.
struct ToGoal {
    /// Per lattice point (`w` a row), its distance once settled, else the best found.
    dist: Vec<u32>,
    w: i64,
    /// The key the search stopped past (`None`: it settled every point it reaches).
    cap: Option<u32>,
    to_start: Octile,
}

impl ToGoal {
    /// Lattice point `(i, j)`'s distance as the search left it: the distance when settled,
    /// else at least it (`u32::MAX`: not reached).
    fn raw(&self, i: i64, j: i64) -> u32 {
        self.dist[(j * self.w + i) as usize]
    }

    /// Lattice point `(i, j)`'s distance when the search settled it: every point whose key
    /// is not above the cap (the keys come off in order).
    fn exact(&self, i: i64, j: i64) -> Option<u32> {
        let d = self.raw(i, j);
        let settled = match self.cap {
            None => d != u32::MAX,
            Some(cap) => u64::from(d) + u64::from(self.to_start.at(i, j)) <= u64::from(cap),
        };
        settled.then_some(d)
    }

    /// A lower bound of lattice point `(i, j)`'s distance to the goal (`u32::MAX`: none).
    /// A point the search settled has its distance; one it did not has a key above the cap
    /// (the keys come off in order), so its distance is at least the cap less its heuristic,
    /// and the least of the two bounds keeps steps from changing it by more than their
    /// length (consistent).
    fn at(&self, i: i64, j: i64) -> u32 {
        let d = self.dist[(j * self.w + i) as usize];
        match self.cap {
            None => d,
            Some(cap) => d.min((cap + 1).saturating_sub(self.to_start.at(i, j))),
        }
    }
}

/// What the lattice says of the start's view: its lattice points (the corners of the free
/// cells that hold it) with their distances to the goal, those the lattice search settled.
/// A free segment from the start to a corner, taken on to one of them, gives a lattice path
/// between the two no longer than the stretch times that way (the lattice's bound,
/// [`Graph::lattice_to`]), so a corner nearer the goal over the lattice than one of them by
/// more lies out of the start's view.
struct StartView {
    s: (f64, f64),
    points: Vec<((f64, f64), f64)>,
}

impl StartView {
    fn new(graph: &Graph, to_goal: &ToGoal, s: (f64, f64)) -> Self {
        let points = graph
            .lattice_points_of(s)
            .filter_map(|(i, j)| Some(((i as f64, j as f64), f64::from(to_goal.exact(i, j)?))))
            .collect();
        Self { s, points }
    }

    /// Whether corner `v` (a lattice point) is out of the start's view for certain.
    fn hides(&self, to_goal: &ToGoal, v: (f64, f64)) -> bool {
        let dist =
            |p: (f64, f64), q: (f64, f64)| ((p.0 - q.0).powi(2) + (p.1 - q.1).powi(2)).sqrt();
        let dv = f64::from(to_goal.raw(v.0 as i64, v.1 as i64));
        let sv = dist(self.s, v);
        self.points
            .iter()
            .any(|&(q, dq)| dq > dv + LATTICE_STRETCH * LATTICE_UNIT * (sv + dist(self.s, q)) + 1.0)
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

/// The half-planes `{b : n . b >= 0}` (their normals `n`) where a way on `b` from a corner
/// reached from direction `a` (the corner to the previous vertex), round the occupied cell
/// whose diagonal from the corner is `w`, can be [`taut`]: on the far side of `a` and of `w`,
/// in the sense that turns from one to the other. No half-plane (no restriction) when `a`
/// runs along `w`: then `taut` itself refuses every way on but straight on.
fn taut_halves(a: (f64, f64), w: (f64, f64)) -> Vec<(f64, f64)> {
    let cross = a.0 * w.1 - a.1 * w.0;
    if cross == 0.0 {
        return Vec::new();
    }
    let sign = cross.signum();
    let unit = |v: (f64, f64)| {
        let l = (v.0 * v.0 + v.1 * v.1).sqrt();
        (v.0 / l, v.1 / l)
    };
    let (a, w) = (unit(a), unit(w));
    vec![(-sign * a.1, sign * a.0), (-sign * w.1, sign * w.0)]
}

/// `x.floor()` as an integer, for any sign, without the library call (`as` rounds towards
/// zero: one less where that rounded up).
#[inline]
fn floor_any(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x { t - 1 } else { t }
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

/// `x.ceil()` the same way.
#[inline]
fn ceil_nn(x: f64) -> f64 {
    if (0.0..9.0e15).contains(&x) {
        let t = (x as i64) as f64;
        if t < x { t + 1.0 } else { t }
    } else {
        x.ceil()
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
/// ([`crate::metric::grid_planners`]), their lengths / optimum and CPU times (with `grid`).
pub fn report(s: &Scenario, grid_planners: bool) {
    let t0 = cpu_time::ThreadTime::now().as_duration().as_secs_f64();
    let grid = s.reach_grid();
    let corners = Corners::of(&grid);
    println!(
        "{}: {} x {} cells of {} m, {} obstacle corners, {} once its dead ends are filled \
         ({:.3} s CPU)",
        s.name,
        grid.cols(),
        grid.rows(),
        grid.cell_size(),
        corners.len(),
        corners.live(),
        cpu_time::ThreadTime::now().as_duration().as_secs_f64() - t0
    );
    let cpu = || cpu_time::ThreadTime::now().as_duration().as_secs_f64();
    type Planner =
        fn(&OccupancyGrid<'_>, Point, Point) -> Option<crate::metric::grid_planners::GridPath>;
    let planners: &[(&str, Planner)] = if grid_planners {
        &[
            ("A* (8-connected)", crate::metric::grid_planners::astar8),
            ("Theta*", crate::metric::grid_planners::theta_star),
        ]
    } else {
        &[]
    };
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
        for &(name, plan) in planners {
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
const CACHE_VERSION: u64 = 3;
// (3: dead ends filled, issue 42; the same figures but for a sum's rounding.)
// (2: the lattice heuristic and the shadows of issue 42. The same figures on every test map,
// but another order of expansion could break a tie in the last bit.)

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

/// A xorshift generator for the tests' random maps.
#[cfg(test)]
pub(crate) fn xorshift(mut state: u64) -> impl FnMut() -> u64 {
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        state
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::OwnedGrid;

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
        // Its points: the start, two corners of the block, the goal.
        let (len, pts) = k
            .shortest_path(Point::new(2.0, 5.0), Point::new(8.0, 5.0))
            .unwrap();
        assert_eq!(len, d);
        assert_eq!(pts.len(), 4, "{pts:?}");
        let sum: f64 = pts.windows(2).map(|w| f64::from(w[0].dist(w[1]))).sum();
        assert!((sum - d).abs() < 1e-5, "{sum} vs {d}");
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

    /// The pruned search (the lattice heuristic, with and without shadow casting from every
    /// corner) gives the plain one's figure to the last bit on random maps (cells occupied at
    /// 10, 25 and 40 %: narrow passages and diagonal pinches among them, at 1, 0.25 and
    /// 0.05 m cells), ends anywhere in free cells, and on a maze of 1-cell corridors.
    #[test]
    fn the_prunings_change_no_figure() {
        let mut next = xorshift(0x2545_f491_4f6c_dd1du64);
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
                let leg = k.leg(a, b);
                let (x, y) = (k.shortest(a, b), leg.shortest_unbounded(a, b));
                assert_eq!(
                    x.map(f64::to_bits),
                    y.map(f64::to_bits),
                    "case {case}: {a:?} -> {b:?}: {x:?} vs {y:?}"
                );
                // Shadow casting from every corner: the same figure.
                let z = leg.search(a, b, 0, usize::MAX);
                assert_eq!(
                    z.map(f64::to_bits),
                    y.map(f64::to_bits),
                    "case {case}, in view: {a:?} -> {b:?}: {z:?} vs {y:?}"
                );
            }
        }
    }

    /// The same on a maze of 1-cell corridors with some walls knocked through (loops: more
    /// than one way), at the defaults (enough corners for the shadows) and casting always.
    #[test]
    fn the_prunings_change_no_figure_on_a_maze() {
        let mut next = xorshift(0x9e37_79b9_7f4a_7c15u64);
        // Depth-first carving of 30 x 30 rooms: 61 x 61 cells, 60 walls knocked through.
        let n = 30usize;
        let side = 2 * n + 1;
        let open = carve_maze(n, 60, &mut next);
        let g = OwnedGrid::from_fn(side as u16, side as u16, 0.5, |c, r| {
            !open[usize::from(r) * side + usize::from(c)]
        })
        .unwrap();
        let k = Corners::of(&g.grid());
        assert!(k.len() >= FOV_MIN, "{} corners", k.len());
        assert!(
            k.live() < k.len(),
            "{} of {} corners live",
            k.live(),
            k.len()
        );
        let rooms: Vec<Point> = (0..n * n)
            .map(|i| {
                Point::new(
                    ((2 * (i % n) + 1) as f32 + 0.5) * 0.5,
                    ((2 * (i / n) + 1) as f32 + 0.5) * 0.5,
                )
            })
            .collect();
        for _ in 0..12 {
            let a = rooms[(next() % rooms.len() as u64) as usize];
            let b = rooms[(next() % rooms.len() as u64) as usize];
            let leg = k.leg(a, b);
            let want = leg.shortest_unbounded(a, b).map(f64::to_bits);
            assert_eq!(k.shortest(a, b).map(f64::to_bits), want, "{a:?} -> {b:?}");
            assert_eq!(
                leg.search(a, b, 0, usize::MAX).map(f64::to_bits),
                want,
                "{a:?} -> {b:?}"
            );
        }
    }

    /// A depth-first maze of `n` x `n` rooms (1-cell corridors, `2 n + 1` cells a side) with
    /// `loops` walls knocked through at random: the open cells.
    fn carve_maze(n: usize, loops: usize, next: &mut impl FnMut() -> u64) -> Vec<bool> {
        let side = 2 * n + 1;
        let mut open = vec![false; side * side];
        let mut seen = vec![false; n * n];
        let mut stack = vec![(0usize, 0usize)];
        seen[0] = true;
        open[side + 1] = true;
        while let Some(&(x, y)) = stack.last() {
            let nb: Vec<(usize, usize)> = [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)]
                .iter()
                .map(|&(dx, dy)| (x as i64 + dx, y as i64 + dy))
                .filter(|&(a, b)| a >= 0 && b >= 0 && a < n as i64 && b < n as i64)
                .map(|(a, b)| (a as usize, b as usize))
                .filter(|&(a, b)| !seen[b * n + a])
                .collect();
            if nb.is_empty() {
                stack.pop();
                continue;
            }
            let (a, b) = nb[(next() % nb.len() as u64) as usize];
            seen[b * n + a] = true;
            open[(y + b + 1) * side + (x + a + 1)] = true;
            open[(2 * b + 1) * side + (2 * a + 1)] = true;
            stack.push((a, b));
        }
        for _ in 0..loops {
            let (c, r) = (
                1 + (next() % (side as u64 - 2)) as usize,
                1 + (next() % (side as u64 - 2)) as usize,
            );
            open[r * side + c] = true;
        }
        open
    }

    /// Filling the dead ends changes no figure: on mazes of 1-cell corridors with and without
    /// loops and on random clutter at 30-45 % (pockets and dead-end corridors), with ends
    /// anywhere: inside cells, on their sides and corners, on the map's edge, both in one dead
    /// end, in two, or in none; the filled search against the plain search on the map as drawn.
    #[test]
    fn filling_dead_ends_changes_no_figure() {
        let mut next = xorshift(0x0bad_5eed_dead_e11du64);
        let mut deep = 0;
        for case in 0..240 {
            let (w, h, open): (usize, usize, Vec<bool>) = if case % 2 == 0 {
                let n = 4 + (next() % 10) as usize;
                let loops = [0, 0, 3, 20][case / 2 % 4];
                (2 * n + 1, 2 * n + 1, carve_maze(n, loops, &mut next))
            } else {
                let (w, h) = (6 + (next() % 30) as usize, 6 + (next() % 30) as usize);
                let density = 30 + next() % 16;
                (w, h, (0..w * h).map(|_| next() % 100 >= density).collect())
            };
            let cell = [1.0f32, 0.25, 0.05][case % 3];
            let g = OwnedGrid::from_fn(w as u16, h as u16, cell, |c, r| {
                !open[usize::from(r) * w + usize::from(c)]
            })
            .unwrap();
            let k = Corners::of(&g.grid());
            let plain = k.unfilled();
            let free: Vec<usize> = (0..w * h).filter(|&i| open[i]).collect();
            if free.len() < 2 {
                continue;
            }
            for _ in 0..6 {
                let mut pick = || {
                    let i = free[(next() % free.len() as u64) as usize];
                    let (c, r) = ((i % w) as f32, (i / w) as f32);
                    // Inside, on a side, on a corner, or on the map's edge.
                    let (x, y) = match next() % 5 {
                        0 | 1 => (c + 0.3, r + 0.6),
                        2 => (c + 0.5, r),
                        3 => (c, r),
                        _ => (0.0, r + 0.5),
                    };
                    Point::new(x * cell, y * cell)
                };
                let (a, b) = (pick(), pick());
                let dead = |p: Point| {
                    let (c, r) = ((p.x / cell) as usize, (p.y / cell) as usize);
                    c < w && r < h && k.up[r * w + c] != LIVE
                };
                deep += usize::from(dead(a) && dead(b));
                let (x, y) = (k.shortest(a, b), plain.shortest_unbounded(a, b));
                match (x, y) {
                    (Some(x), Some(y)) => assert!(
                        (x - y).abs() <= 1e-9 * y.max(1.0),
                        "case {case}: {a:?} -> {b:?}: {x} vs {y}"
                    ),
                    _ => assert_eq!(x, y, "case {case}: {a:?} -> {b:?}"),
                }
            }
        }
        // Both ends in dead ends (in one, or in two) came up often enough to count.
        assert!(deep > 100, "{deep} legs with both ends in dead ends");
    }

    /// Issue 45: an end 1e30 m off the map made the search walk that segment crossing by
    /// crossing (for ever, to a user); an end off the map now has no path at once.
    #[test]
    fn regression_an_end_off_the_map_has_no_path() {
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, r| c == 5 && r > 2).unwrap();
        let corners = Corners::of(&g.grid());
        let inside = Point::new(2.5, 8.5);
        for off in [
            Point::new(1e30, 3.0),
            Point::new(-0.5, 3.0),
            Point::new(3.0, 10.5),
            Point::new(f32::NAN, 1.0),
        ] {
            assert_eq!(corners.shortest(inside, off), None, "{off:?}");
            assert_eq!(corners.shortest(off, inside), None, "{off:?}");
        }
        assert!(corners.shortest(inside, Point::new(8.5, 8.5)).is_some());
    }

    /// A `w` x `h` map (row-major) of `walls` random walls up to `long` cells long and
    /// `thick` thick, lying either way: rooms of sparse walls.
    fn sparse_walls(
        (w, h): (i64, i64),
        walls: u64,
        (long, thick): (u64, u64),
        next: &mut impl FnMut() -> u64,
    ) -> Vec<bool> {
        let mut o = vec![false; (w * h) as usize];
        for _ in 0..walls {
            let (x, y) = ((next() % w as u64) as i64, (next() % h as u64) as i64);
            let (bw, bh) = (1 + (next() % long) as i64, 1 + (next() % thick) as i64);
            let (bw, bh) = if next().is_multiple_of(2) {
                (bw, bh)
            } else {
                (bh, bw)
            };
            for r in y..(y + bh).min(h) {
                for c in x..(x + bw).min(w) {
                    o[(r * w + c) as usize] = true;
                }
            }
        }
        o
    }

    /// The shadow casts read rows a word at a time: on maps wider than a word (rooms of
    /// sparse walls, where runs span words, and clutter, where they are short), from corners
    /// and from points on the map's edge, every corner in view is found.
    #[test]
    fn shadow_casts_find_every_corner_in_view() {
        let mut next = xorshift(0x6a09_e667_f3bc_c909u64);
        let mut checked = 0usize;
        for case in 0..24 {
            let (w, h) = (60 + (next() % 140) as i64, 60 + (next() % 140) as i64);
            let occ: Vec<bool> = if case % 2 == 0 {
                let walls = 6 + next() % 10;
                sparse_walls((w, h), walls, (30, 4), &mut next)
            } else {
                (0..w * h).map(|_| next() % 100 < 8).collect()
            };
            let g = OwnedGrid::from_fn(w as u16, h as u16, 0.05, |c, r| {
                occ[usize::from(r) * w as usize + usize::from(c)]
            })
            .unwrap();
            let graph = Graph::new(&g.grid(), &occ);
            let n = graph.len();
            for t in 0..12 {
                let o = if t % 4 == 3 {
                    (0, (next() % (h as u64 + 1)) as i64)
                } else if n > 0 {
                    let p = graph.corners[(next() % n as u64) as usize];
                    (i64::from(p.0), i64::from(p.1))
                } else {
                    continue;
                };
                // Every corner in view within `depth - 1`, the cast's promise.
                let depth = 2 + (next() % (w.max(h) as u64)) as i64;
                let mut found = vec![false; n];
                let cast =
                    graph.lattice_in_view(o, depth, usize::MAX, &[], &mut |k| found[k] = true);
                assert!(cast.is_some());
                let p = (o.0 as f64, o.1 as f64);
                for (k, &was_found) in found.iter().enumerate() {
                    let q = graph.corner(k);
                    let far = ((q.0 - p.0).powi(2) + (q.1 - p.1).powi(2)).sqrt();
                    if q != p && far <= (depth - 1) as f64 && graph.sees(p, q) {
                        assert!(was_found, "case {case}: {q:?} sees {p:?} but was not cast");
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 2_000, "only {checked} corners in view");
    }

    /// The lattice hides no corner the start sees: random maps (rooms of sparse walls and
    /// 10-40 % clutter, at 1 and 0.05 m), starts inside cells, on their sides and corners,
    /// goals anywhere; and it does hide corners behind walls.
    #[test]
    fn the_lattice_hides_no_corner_in_the_starts_view() {
        let mut next = xorshift(0xbb67_ae85_84ca_a73bu64);
        let (mut seen, mut hidden) = (0usize, 0usize);
        for case in 0..60 {
            let (w, h) = (20 + (next() % 100) as i64, 20 + (next() % 100) as i64);
            let occ: Vec<bool> = if case % 2 == 0 {
                let walls = 4 + next() % 8;
                sparse_walls((w, h), walls, (40, 3), &mut next)
            } else {
                let density = [10, 25, 40][case % 3];
                (0..w * h).map(|_| next() % 100 < density).collect()
            };
            let cell = [1.0f32, 0.05][case % 2];
            let g = OwnedGrid::from_fn(w as u16, h as u16, cell, |c, r| {
                occ[usize::from(r) * w as usize + usize::from(c)]
            })
            .unwrap();
            let graph = Graph::new(&g.grid(), &occ);
            let free: Vec<(i64, i64)> = (0..h)
                .flat_map(|r| (0..w).map(move |c| (c, r)))
                .filter(|&(c, r)| !occ[(r * w + c) as usize])
                .collect();
            if free.len() < 2 {
                continue;
            }
            for t in 0..6 {
                let pick = |v: u64, frac: (f64, f64)| {
                    let (c, r) = free[(v % free.len() as u64) as usize];
                    (c as f64 + frac.0, r as f64 + frac.1)
                };
                let frac = [(0.3, 0.6), (0.0, 0.5), (0.0, 0.0), (1.0, 0.25)][t % 4];
                let (s, goal) = (pick(next(), frac), pick(next(), (0.5, 0.5)));
                let to_goal = graph.lattice_to(goal, s);
                let view = StartView::new(&graph, &to_goal, s);
                for k in 0..graph.len() {
                    let v = graph.corner(k);
                    let hides = view.hides(&to_goal, v);
                    if graph.sees(s, v) {
                        assert!(
                            !hides,
                            "case {case}: {s:?} sees {v:?}, the lattice hides it"
                        );
                        seen += 1;
                    } else if hides {
                        hidden += 1;
                    }
                }
            }
        }
        assert!(
            seen > 5_000 && hidden > 1_000,
            "{seen} seen, {hidden} hidden"
        );
    }

    #[test]
    fn walled_off_goal_is_unreachable() {
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, _| c == 5).unwrap();
        let k = Corners::of(&g.grid());
        assert_eq!(k.shortest(Point::new(2.0, 5.0), Point::new(8.0, 5.0)), None);
    }
}
