//! Experiment for issue 26 (not part of the planner): how fast could a first solution be found
//! on a roadmap baked offline from the grid, as the diffusion table is, and searched at query
//! time? The roadmap is a reduced visibility graph: a node just off every convex corner of the
//! occupied cells, and an edge between two nodes that see each other over a free segment whose
//! line is tangent to the obstacle at both ends (a shortest path bends only at convex corners,
//! and each of its segments is tangent there). A query tests the segment start-goal, connects
//! start and goal to the nearest nodes they see, and runs A* (Euclidean heuristic).
//!
//! ```text
//! cargo run --release -p host-sim --example roadmap_probe -- SCENARIOS [--bench DIR] \
//!     [--maps a,b] [--cold] [--hull-m M --max-angle A] [--wall-m M] [--block-m M]
//! ```
//!
//! With `--bench` (a `host-sim bench ... --ompl` output of the same scenarios), each leg's
//! query time is divided by RRT-Connect's median first-solution time there, and each path by
//! the leg's optimum. Times are warm (the median of 21 batches of 1,000 runs of the same
//! query). `--block-m` keeps one corner per square block of that side (fewer nodes on fine
//! maps, at the price of completeness); `--wall-m` keeps corners with a side at least that
//! long; `--hull-m M --max-angle A` keeps corners that are vertices of the obstacle's outline
//! at the scale of M metres, at least 2 cells (the occupied cells within it span less than A
//! degrees).
//! `--cold` flushes the caches before each query (as `bench --cold`) and times it alone.
//! Findings: docs/notebook/first-solution.md, "A baked roadmap".

use std::cmp::Reverse;
use std::collections::{BinaryHeap, HashMap};
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use bi_am_rrt::geometry::Point;
use bi_am_rrt::map::OccupancyGrid;
use host_sim::results::stats::median;

/// Nodes stand this far (in cells) off their corner, along the corner's diagonal.
const OFFSET_CELLS: f32 = 0.6;
/// Nodes start and goal try to see, nearest first.
const CONNECT: usize = 16;

struct Roadmap {
    nodes: Vec<Point>,
    /// Per node: the diagonal pointing into its corner's occupied cell.
    into: Vec<(f32, f32)>,
    /// Compressed adjacency (both directions).
    first: Vec<u32>,
    next: Vec<u16>,
}

impl Roadmap {
    fn bake(g: &OccupancyGrid<'_>, thin: &Thin) -> Self {
        let cell = g.cell_size();
        let (cols, rows) = (i32::from(g.cols()), i32::from(g.rows()));
        let occ = |c: i32, r: i32| {
            c < 0 || r < 0 || c >= cols || r >= rows || g.is_occupied(c as u16, r as u16)
        };
        let (mut nodes, mut into) = (Vec::new(), Vec::new());
        let cells = |m: Option<f32>| m.map_or(1, |m| ((m / cell).round() as i32).max(1));
        let (block, wall) = (cells(thin.block_m), cells(thin.wall_m));
        let reach = thin.hull_m.map_or(1, |m| cells(Some(m)).max(2));
        let widest = thin.max_angle_deg.to_radians();
        let mut taken = std::collections::HashSet::new();
        for vy in 1..rows {
            for vx in 1..cols {
                let q = [
                    occ(vx - 1, vy - 1),
                    occ(vx, vy - 1),
                    occ(vx - 1, vy),
                    occ(vx, vy),
                ];
                if q.iter().filter(|&&o| o).count() != 1 {
                    continue;
                }
                let d = match q.iter().position(|&o| o) {
                    Some(0) => (-1.0, -1.0),
                    Some(1) => (1.0, -1.0),
                    Some(2) => (-1.0, 1.0),
                    _ => (1.0, 1.0),
                };
                let p = Point::new(
                    (vx as f32 - OFFSET_CELLS * d.0) * cell,
                    (vy as f32 - OFFSET_CELLS * d.1) * cell,
                );
                // The occupied quadrant's cell, and how far the obstacle's two sides run from the
                // corner (in cells): a bump of pixel noise has two short sides.
                let (cx, cy) = (vx + (d.0 as i32 - 1) / 2, vy + (d.1 as i32 - 1) / 2);
                let run = |sx: i32, sy: i32| {
                    (0..wall)
                        .take_while(|&k| occ(cx + k * sx, cy + k * sy))
                        .count() as i32
                };
                if wall > 1 && run(d.0 as i32, 0) < wall && run(0, d.1 as i32) < wall {
                    continue;
                }
                // A vertex of the obstacle's outline at the scale `reach`: the occupied cells
                // within `reach` of the corner, seen from it, span less than `max_angle` (the
                // middle steps of a staircase, a diagonal wall's pixels, span about 180).
                if reach > 1 {
                    let (mut lo, mut hi) = (0.0f32, 0.0f32);
                    let mut wraps = false;
                    for r in -reach..reach {
                        for c in -reach..reach {
                            let (x, y) = (c as f32 + 0.5, r as f32 + 0.5);
                            if x * x + y * y > (reach * reach) as f32 || !occ(vx + c, vy + r) {
                                continue;
                            }
                            // Angle from the corner's diagonal.
                            let a = (d.0 * y - d.1 * x).atan2(d.0 * x + d.1 * y);
                            wraps |= a.abs() > 0.95 * std::f32::consts::PI;
                            lo = lo.min(a);
                            hi = hi.max(a);
                        }
                    }
                    if wraps || hi - lo > widest {
                        continue;
                    }
                }
                let key = (vx / block, vy / block);
                if block > 1 && !taken.insert(key) {
                    continue;
                }
                if g.point_free(p) && nodes.len() < usize::from(u16::MAX) {
                    nodes.push(p);
                    into.push(d);
                }
            }
        }
        let mut adj: Vec<Vec<u16>> = vec![Vec::new(); nodes.len()];
        for i in 0..nodes.len() {
            for j in i + 1..nodes.len() {
                let e = (nodes[j].x - nodes[i].x, nodes[j].y - nodes[i].y);
                if tangent(e, into[i]) && tangent(e, into[j]) && g.segment_free(nodes[i], nodes[j])
                {
                    adj[i].push(j as u16);
                    adj[j].push(i as u16);
                }
            }
        }
        let mut first = vec![0u32];
        let mut next = Vec::new();
        for a in adj {
            next.extend(a);
            first.push(next.len() as u32);
        }
        Self {
            nodes,
            into,
            first,
            next,
        }
    }

    fn bytes(&self) -> usize {
        self.nodes.len() * 8 + self.first.len() * 4 + self.next.len() * 2
    }

    /// The nodes `p` sees over a free segment tangent at the node, nearest first, at most
    /// [`CONNECT`] of them (the `CONNECT` nearest tangent nodes are tested).
    fn seen_from(
        &self,
        g: &OccupancyGrid<'_>,
        p: Point,
        order: &mut Vec<(f32, u16)>,
    ) -> Vec<(u16, f32)> {
        order.clear();
        for (i, n) in self.nodes.iter().enumerate() {
            let e = (n.x - p.x, n.y - p.y);
            if tangent(e, self.into[i]) {
                order.push((n.dist_sq(p), i as u16));
            }
        }
        let k = CONNECT.min(order.len());
        if k > 0 && k < order.len() {
            order.select_nth_unstable_by(k - 1, |a, b| a.0.total_cmp(&b.0));
        }
        order[..k].sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
        order[..k]
            .iter()
            .filter(|&&(_, i)| g.segment_free(p, self.nodes[usize::from(i)]))
            .map(|&(d2, i)| (i, d2.sqrt()))
            .collect()
    }

    /// The length of the shortest start-goal path over the roadmap, if any.
    fn query(
        &self,
        g: &OccupancyGrid<'_>,
        start: Point,
        goal: Point,
        s: &mut Scratch,
    ) -> Option<f32> {
        if g.segment_free(start, goal) {
            return Some(start.dist(goal));
        }
        let ends = self.seen_from(g, goal, &mut s.order);
        let starts = self.seen_from(g, start, &mut s.order);
        s.dist.clear();
        s.dist.resize(self.nodes.len(), f32::INFINITY);
        s.to_goal.clear();
        s.to_goal.resize(self.nodes.len(), f32::INFINITY);
        s.parent.clear();
        s.parent.resize(self.nodes.len(), u16::MAX);
        s.last = None;
        for &(i, d) in &ends {
            s.to_goal[usize::from(i)] = d;
        }
        s.heap.clear();
        for &(i, d) in &starts {
            s.dist[usize::from(i)] = d;
            let f = d + self.nodes[usize::from(i)].dist(goal);
            s.heap.push(Reverse((f.to_bits(), i)));
        }
        let mut best = f32::INFINITY;
        s.pops = 0;
        s.seen = (starts.len(), ends.len());
        while let Some(Reverse((f, i))) = s.heap.pop() {
            s.pops += 1;
            if f32::from_bits(f) >= best {
                break;
            }
            let i = usize::from(i);
            let di = s.dist[i];
            // A stale entry (the node was reached more cheaply since): already expanded.
            if f32::from_bits(f) > di + self.nodes[i].dist(goal) {
                continue;
            }
            if di + s.to_goal[i] < best {
                best = di + s.to_goal[i];
                s.last = Some(i as u16);
            }
            let (a, b) = (self.first[i] as usize, self.first[i + 1] as usize);
            for &j in &self.next[a..b] {
                let ju = usize::from(j);
                let nd = di + self.nodes[i].dist(self.nodes[ju]);
                if nd < s.dist[ju] {
                    s.dist[ju] = nd;
                    s.parent[ju] = i as u16;
                    let f = nd + self.nodes[ju].dist(goal);
                    s.heap.push(Reverse((f.to_bits(), j)));
                }
            }
        }
        best.is_finite().then_some(best)
    }
}

/// How the corners are thinned (all off by default).
struct Thin {
    block_m: Option<f32>,
    wall_m: Option<f32>,
    hull_m: Option<f32>,
    max_angle_deg: f32,
}

#[derive(Default)]
struct Scratch {
    order: Vec<(f32, u16)>,
    dist: Vec<f32>,
    to_goal: Vec<f32>,
    heap: BinaryHeap<Reverse<(u32, u16)>>,
    pops: usize,
    seen: (usize, usize),
    parent: Vec<u16>,
    last: Option<u16>,
}

impl Scratch {
    /// The roadmap nodes of the last query's path, start side first.
    fn path(&self) -> Vec<u16> {
        let mut v = Vec::new();
        let mut at = self.last;
        while let Some(i) = at.filter(|_| v.len() <= self.parent.len()) {
            v.push(i);
            at = Some(self.parent[usize::from(i)]).filter(|&p| p != u16::MAX);
        }
        v.reverse();
        v
    }
}

/// Whether the line along `e` through a corner node does not cut into the corner's occupied
/// quadrant (diagonal `d`): within 45 degrees of the diagonal, either way, it would.
fn tangent(e: (f32, f32), d: (f32, f32)) -> bool {
    let along = (e.0 * d.0 + e.1 * d.1).abs();
    along * along <= (e.0 * e.0 + e.1 * e.1) * 1.0001
}

/// The columns of a bench's `bench.csv` the probe reads.
#[derive(serde::Deserialize)]
struct BenchRow {
    map: String,
    leg: usize,
    planner: String,
    optimal_m: f64,
    first_us: Option<f64>,
}

/// Per (map, leg): RRT-Connect's median first-solution time (us) and the leg's optimum (m).
fn bench_figures(dir: &Path) -> Result<HashMap<(String, usize), (f64, f64)>> {
    let mut rdr = csv::Reader::from_path(dir.join("bench.csv")).context("bench.csv")?;
    let mut times: HashMap<(String, usize), (Vec<f64>, f64)> = HashMap::new();
    for row in rdr.deserialize::<BenchRow>() {
        let r = row?;
        if let (true, Some(us)) = (r.planner == "OMPL RRT-Connect", r.first_us) {
            let e = times
                .entry((r.map, r.leg))
                .or_insert((Vec::new(), r.optimal_m));
            e.0.push(us);
        }
    }
    Ok(times
        .into_iter()
        .filter_map(|(k, (mut t, opt))| median(&mut t).map(|m| (k, (m, opt))))
        .collect())
}

#[derive(clap::Parser)]
struct Args {
    /// Scenario file, or `builtin`.
    scenarios: PathBuf,
    /// A bench output of the same scenarios with `--ompl` (RRT-Connect's times, the optima).
    #[arg(long)]
    bench: Option<PathBuf>,
    /// Only these scenarios (comma-separated).
    #[arg(long, value_delimiter = ',')]
    maps: Option<Vec<String>>,
    /// Keep one corner per square block of this side, in metres.
    #[arg(long)]
    block_m: Option<f32>,
    /// Keep only corners where a side of the obstacle runs at least this long, in metres
    /// (drops the corners of pixel noise on fine maps).
    #[arg(long)]
    wall_m: Option<f32>,
    /// Keep only corners that are vertices of the obstacle's outline at this scale, in metres
    /// and at least 2 cells (pixel noise and the steps of a drawn diagonal are at the scale of
    /// a cell): the occupied cells within it span less than `--max-angle` seen from the corner.
    #[arg(long)]
    hull_m: Option<f32>,
    /// The widest angle, in degrees, for `--hull-m`.
    #[arg(long, default_value_t = 160.0)]
    max_angle: f32,
    /// Print each query's A* pops and how many nodes start and goal see (stderr).
    #[arg(long)]
    verbose: bool,
    /// Flush the caches (as `bench --cold`) before each query, timed alone (21 of them).
    #[arg(long)]
    cold: bool,
}

fn main() -> Result<()> {
    let args = <Args as clap::Parser>::parse();
    let bench = match &args.bench {
        Some(d) => bench_figures(d)?,
        None => HashMap::new(),
    };
    let scenarios = host_sim::scenario::load_scenarios(&args.scenarios, args.maps.as_deref())?;
    println!(
        "| map | nodes | edges | bytes | bake ms | per leg: query us (/ RRT-Connect), path / optimum |"
    );
    println!("|---|---|---|---|---|---|");
    for s in &scenarios {
        let g = s.map.grid();
        let t0 = Instant::now();
        let thin = Thin {
            block_m: args.block_m,
            wall_m: args.wall_m,
            hull_m: args.hull_m,
            max_angle_deg: args.max_angle,
        };
        let rm = Roadmap::bake(&g, &thin);
        let bake_ms = t0.elapsed().as_secs_f64() * 1e3;
        let mut legs = Vec::new();
        let mut ratios = Vec::new();
        let mut missed = 0;
        let starts = host_sim::metric::optimum::leg_starts(s);
        for (leg, (&from, &goal)) in starts.iter().zip(&s.goals).enumerate() {
            let mut sc = Scratch::default();
            let len = rm.query(&g, from, goal, &mut sc);
            let reps = if args.cold { 1 } else { 1000 };
            let mut batch = Vec::new();
            for _ in 0..21 {
                if args.cold {
                    host_sim::study::bench::flush_caches();
                }
                let t = Instant::now();
                for _ in 0..reps {
                    std::hint::black_box(rm.query(&g, from, goal, &mut sc));
                }
                batch.push(t.elapsed().as_secs_f64() * 1e6 / f64::from(reps));
            }
            let us = median(&mut batch).unwrap_or(f64::NAN);
            let mut cell = format!("{}: {us:.2}", leg + 1);
            if let Some(&(rc, opt)) = bench.get(&(s.name.clone(), leg + 1)) {
                // A query that found no path is no first solution: not a ratio.
                if len.is_some() {
                    ratios.push(us / rc);
                }
                cell += &format!(" ({:.2})", us / rc);
                if let Some(l) = len {
                    cell += &format!(", {:.3}", f64::from(l) / opt);
                }
            }
            if len.is_none() {
                cell += ", none";
                missed += 1;
            }
            if args.verbose {
                let path: Vec<String> = sc
                    .path()
                    .iter()
                    .map(|&i| s.show(rm.nodes[usize::from(i)]))
                    .collect();
                eprintln!("{} leg {}: path {}", s.name, leg + 1, path.join(" "));
                eprintln!(
                    "{} leg {}: pops {}, start sees {}, goal sees {}",
                    s.name,
                    leg + 1,
                    sc.pops,
                    sc.seen.0,
                    sc.seen.1
                );
            }
            legs.push(cell);
        }
        let worst = ratios.iter().copied().fold(f64::NAN, f64::max);
        let mut summary = median(&mut ratios).map_or(String::new(), |m| {
            format!("; median {m:.2}, worst {worst:.2}")
        });
        if missed > 0 {
            summary += &format!("; NO PATH on {missed} legs");
        }
        println!(
            "| {} | {} | {} | {} | {bake_ms:.0} | {}{summary} |",
            s.name,
            rm.nodes.len(),
            rm.next.len() / 2,
            rm.bytes(),
            legs.join("; ")
        );
    }
    Ok(())
}
