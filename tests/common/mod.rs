//! Shared fixtures of the integration tests: grid-graph metrics for the built-in maps (a
//! landmark table in the diffusion-table format, and an exact geodesic metric), and the agent
//! protocol that drives a planner to a goal.
#![allow(dead_code)]

use std::cell::RefCell;
use std::collections::{BinaryHeap, HashMap};
use std::rc::Rc;

use bi_am_rrt::Planner;
pub use bi_am_rrt::agent::{Protocol, RunResult, run_to_goal};
use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::geometry::Point;
use bi_am_rrt::map::{Circle, OccupancyGrid};
use bi_am_rrt::metric::{ElementKind, Metric, TableHeader, write_table};
use rand_core::Rng;

pub mod checked;
pub mod e2e;

/// Dynamic obstacles a test map holds.
pub const K: usize = 4;

/// A virtual clock: 1 ns ticks, 30 ns per unit of work, 10 ns per reading.
pub fn clock() -> FakeClock {
    FakeClock::nanos().with_work_cost(30).with_step(10)
}

/// Free cells of the largest 8-connected component (no corner cutting), as a cell mask.
pub fn main_component(g: &OccupancyGrid<'_>) -> Vec<bool> {
    let (w, h) = (g.cols() as usize, g.rows() as usize);
    let free = |c: usize, r: usize| !g.is_occupied(c as u16, r as u16);
    let mut label = vec![usize::MAX; w * h];
    let mut best = (0, usize::MAX);
    for start in 0..w * h {
        if label[start] != usize::MAX || !free(start % w, start / w) {
            continue;
        }
        let mut stack = vec![start];
        label[start] = start;
        let mut size = 0;
        while let Some(i) = stack.pop() {
            size += 1;
            for (j, _) in neighbours(g, i) {
                if label[j] == usize::MAX {
                    label[j] = start;
                    stack.push(j);
                }
            }
        }
        if size > best.0 {
            best = (size, start);
        }
    }
    label.iter().map(|&l| l == best.1).collect()
}

/// 8-neighbours of cell `i` with their distances; a diagonal step needs both side cells free.
pub fn neighbours(g: &OccupancyGrid<'_>, i: usize) -> Vec<(usize, f32)> {
    let (w, h) = (g.cols() as i64, g.rows() as i64);
    let (c, r) = ((i as i64) % w, (i as i64) / w);
    let free =
        |c: i64, r: i64| c >= 0 && r >= 0 && c < w && r < h && !g.is_occupied(c as u16, r as u16);
    let mut out = Vec::new();
    for dr in -1..=1 {
        for dc in -1..=1 {
            if (dc, dr) == (0, 0) || !free(c + dc, r + dr) {
                continue;
            }
            if dc != 0 && dr != 0 && !(free(c + dc, r) && free(c, r + dr)) {
                continue;
            }
            let d = if dc != 0 && dr != 0 {
                std::f32::consts::SQRT_2
            } else {
                1.0
            };
            out.push((((r + dr) * w + c + dc) as usize, d));
        }
    }
    out
}

/// Dijkstra distances from cell `src` over the grid graph (infinite off the component).
pub fn dijkstra(g: &OccupancyGrid<'_>, src: usize) -> Vec<f32> {
    #[derive(PartialEq)]
    struct E(f32, usize);
    impl Eq for E {}
    impl PartialOrd for E {
        fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
            Some(self.cmp(o))
        }
    }
    impl Ord for E {
        fn cmp(&self, o: &Self) -> std::cmp::Ordering {
            o.0.total_cmp(&self.0)
        }
    }
    let n = g.cols() as usize * g.rows() as usize;
    let mut dist = vec![f32::INFINITY; n];
    let mut heap = BinaryHeap::new();
    dist[src] = 0.0;
    heap.push(E(0.0, src));
    while let Some(E(d, i)) = heap.pop() {
        if d > dist[i] {
            continue;
        }
        for (j, w) in neighbours(g, i) {
            if d + w < dist[j] {
                dist[j] = d + w;
                heap.push(E(d + w, j));
            }
        }
    }
    dist
}

fn cell_index(g: &OccupancyGrid<'_>, p: Point) -> Option<usize> {
    g.cell_of(p)
        .map(|(c, r)| r as usize * g.cols() as usize + c as usize)
}

/// A table in the diffusion-table format whose coordinates are graph distances to `k`
/// landmarks (farthest-point chosen), divided by `sqrt(k)`: a cheap stand-in for baked
/// diffusion coordinates with the same behaviour at walls (large jumps across them).
pub fn landmark_table(g: &OccupancyGrid<'_>, k: usize) -> Vec<u8> {
    let comp = main_component(g);
    let mut landmarks: Vec<Vec<f32>> = Vec::new();
    let mut next = comp.iter().position(|&c| c).expect("a free cell");
    for _ in 0..k {
        let d = dijkstra(g, next);
        // Farthest reachable cell from all landmarks so far.
        landmarks.push(d);
        next = (0..comp.len())
            .filter(|&i| comp[i])
            .max_by(|&a, &b| {
                let ma = landmarks.iter().map(|l| l[a]).fold(f32::INFINITY, f32::min);
                let mb = landmarks.iter().map(|l| l[b]).fold(f32::INFINITY, f32::min);
                ma.total_cmp(&mb)
            })
            .unwrap();
    }
    let norm = 1.0 / (k as f32).sqrt();
    let header = TableHeader {
        map_hash: None,
        kind: ElementKind::I16,
        dims: k as u16,
        cols: g.cols(),
        rows: g.rows(),
        cell_size: g.cell_size(),
        scale: 0.01,
        layout: bi_am_rrt::metric::Layout::Uniform,
    };
    let mut out = vec![0u8; header.table_len().unwrap()];
    let cols = g.cols() as usize;
    write_table(&header, &mut out, |c, r, coords| {
        let i = r as usize * cols + c as usize;
        for (slot, l) in coords.iter_mut().zip(&landmarks) {
            *slot = l[i] * norm;
        }
        comp[i]
    })
    .unwrap();
    out
}

/// Exact graph distances between the cells of two positions, one Dijkstra field per target
/// cell, cached.
pub struct Geodesic<'g> {
    grid: OccupancyGrid<'g>,
    comp: Vec<bool>,
    fields: RefCell<HashMap<usize, Rc<Vec<f32>>>>,
}

impl<'g> Geodesic<'g> {
    pub fn new(grid: OccupancyGrid<'g>) -> Self {
        Self {
            comp: main_component(&grid),
            grid,
            fields: RefCell::new(HashMap::new()),
        }
    }
}

impl Metric for Geodesic<'_> {
    fn distance(&self, a: Point, b: Point) -> f32 {
        let (Some(ia), Some(ib)) = (cell_index(&self.grid, a), cell_index(&self.grid, b)) else {
            return f32::INFINITY;
        };
        if !self.comp[ia] || !self.comp[ib] {
            return f32::INFINITY;
        }
        let field = self
            .fields
            .borrow_mut()
            .entry(ib)
            .or_insert_with(|| Rc::new(dijkstra(&self.grid, ib)))
            .clone();
        field[ia] * self.grid.cell_size()
    }
}

/// Runs the agent protocol (`bi_am_rrt::agent`), checking both trees' invariants after every
/// call before handing over to `on_call`.
pub fn drive<M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>(
    planner: &mut Planner<'_, '_, M, R, N, B, K>,
    clock: &FakeClock,
    goal: Point,
    proto: Protocol,
    mut on_call: impl FnMut(&mut Planner<'_, '_, M, R, N, B, K>, Point, u32),
) -> RunResult {
    run_to_goal(planner, clock, goal, &proto, |p, agent, call| {
        p.tree().validate().expect("forward tree invariants");
        p.reverse_tree()
            .validate()
            .expect("reverse tree invariants");
        on_call(p, agent, call)
    })
    .expect("goal accepted")
}

/// Whether any edge of the planner's current path meets `c`.
pub fn path_meets<M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>(
    planner: &Planner<'_, '_, M, R, N, B, K>,
    c: &Circle,
) -> bool {
    let mut buf = vec![Point::ZERO; N];
    let n = planner.path(&mut buf).unwrap().len;
    buf[..n]
        .windows(2)
        .any(|w| c.intersects_segment(w[0], w[1]))
}
