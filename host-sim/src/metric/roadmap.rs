//! The roadmap bake (the core's module `bi_am_rrt::roadmap`, the `roadmap` tactic): a reduced
//! visibility graph of the grid the planner tests paths on.
//!
//! - **Nodes**: a node 0.6 cells off each convex corner of the occupied cells (a grid vertex
//!   with exactly one occupied cell of the four around it), along the corner's diagonal, kept
//!   when it is a vertex of the obstacle's outline at the scale of [`HULL_M`] (at least two
//!   cells): the occupied cells within that distance of the corner, seen from it, span less
//!   than [`MAX_ANGLE_DEG`]. The middle steps of a wall drawn as a staircase and the bumps of
//!   pixel noise on a SLAM map span about 180 degrees and are dropped, so a fine map does not
//!   carry thousands of corners that no shortest path needs (found with
//!   `host-sim/examples/roadmap_probe.rs` on nine maps: `docs/notebook/first-solution.md`).
//!   A speck ([`SPECK_M`]) has none: a SLAM map's sensor noise, thousands of cells on a big
//!   building, round which a path bends by less than a cell; its cells still block edges.
//! - **Edges**: between two nodes that see each other over a free segment tangent to the
//!   obstacle at both ends (a shortest path bends only at convex corners, tangentially),
//!   thinned to a greedy spanner of stretch [`STRETCH`] (an edge that two or three shorter
//!   ones already follow closely is dropped: the search opens fewer edges, the path it finds
//!   is within 5 % of the full graph's).
//!
//! The planner tests every edge of a path it takes from the roadmap, so a roadmap never makes
//! a path unsafe; a poor one only leaves the first solution to the trees.

use anyhow::{Result, bail};
use bi_am_rrt::geometry::Point;
use bi_am_rrt::map::OccupancyGrid;
use bi_am_rrt::roadmap::{self, NO_CORNER};
use rayon::prelude::*;

/// Nodes stand this far (in cells) off their corner, along the corner's diagonal (the
/// format's).
pub const OFFSET_CELLS: f32 = roadmap::NODE_OFFSET;
/// The scale, in metres, at which a corner must be a vertex of the obstacle's outline (at
/// least two cells).
pub const HULL_M: f32 = 0.3;
/// A corner whose occupied cells within [`HULL_M`] span this angle or more is dropped.
pub const MAX_ANGLE_DEG: f32 = 165.0;
/// An obstacle (with whatever lies within [`HULL_M`] of it) that fits within this distance of
/// its corner's vertex has no nodes: on a SLAM map at 0.05 m it is a speck of sensor noise a
/// cell or two across, a path bends round it by less than a cell, and a building of 200 m
/// has thousands of them. Its cells still block the edges (every edge is tested on the grid).
/// Cells of 0.25 m or more are never specks. For a robot of radius `r` the bake reads the
/// grid inflated by `r`, where a speck has grown by `r` all round: `SPECK_M + 2 r` there.
pub const SPECK_M: f32 = 0.15;
/// Most nodes a bake keeps: the edges are found by testing every pair (a building of 200 m at
/// 0.05 m, 11,473 nodes: 11 s of CPU; 37,219 for a robot of 0.1 m there: 39 s on two cores),
/// and a planner's reverse arena must hold the search's scratch (`N - 1` nodes): the
/// simulator's biggest arena holds 65,000 a tree ([`crate::sim::ARENAS`];
/// [`crate::sim::Prepared::arena_for`]).
pub const MAX_NODES: usize = 60_000;

/// The greedy spanner's stretch: an edge is dropped when the edges kept already join its ends
/// within this factor of its length. On a map of many small obstacles (nav2's depot: 40 edges
/// a node) most edges run beside a path of two or three shorter ones; the planner's search
/// relaxes every edge of each node it opens, and rewiring straightens the path it grafts.
pub const STRETCH: f32 = 1.05;

/// The greedy `t`-spanner of a graph (Althofer et al.): its edges in order of length, each
/// kept unless the kept ones already join its ends within `t` times its length (a Dijkstra
/// bounded by that length).
fn spanner(nodes: &[Point], adj: &[Vec<u16>], t: f32) -> Vec<Vec<u16>> {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    let mut edges: Vec<(f32, usize, usize)> = Vec::new();
    for (i, a) in adj.iter().enumerate() {
        for &j in a {
            let j = usize::from(j);
            if i < j {
                edges.push((nodes[i].dist(nodes[j]), i, j));
            }
        }
    }
    edges.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    let mut kept: Vec<Vec<u16>> = vec![Vec::new(); nodes.len()];
    let mut dist = vec![f32::INFINITY; nodes.len()];
    let mut touched: Vec<usize> = Vec::new();
    for (len, i, j) in edges {
        let bound = t * len;
        // Bounded Dijkstra from i over the kept edges: does it reach j within `bound`?
        let mut heap = BinaryHeap::new();
        dist[i] = 0.0;
        touched.push(i);
        heap.push(Reverse((0u32, i)));
        let mut joined = false;
        while let Some(Reverse((d, v))) = heap.pop() {
            let d = f32::from_bits(d);
            if d > dist[v] {
                continue;
            }
            if v == j {
                joined = true;
                break;
            }
            for &w in &kept[v] {
                let w = usize::from(w);
                let nd = d + nodes[v].dist(nodes[w]);
                if nd <= bound && nd < dist[w] {
                    if dist[w].is_infinite() {
                        touched.push(w);
                    }
                    dist[w] = nd;
                    heap.push(Reverse((nd.to_bits(), w)));
                }
            }
        }
        for v in touched.drain(..) {
            dist[v] = f32::INFINITY;
        }
        if !joined {
            kept[i].push(j as u16);
            kept[j].push(i as u16);
        }
    }
    kept
}

/// A baked roadmap: its bytes (the core's format) and what they hold.
#[derive(Clone, Debug)]
pub struct Baked {
    /// The roadmap in the core's format (`bi_am_rrt::roadmap::Roadmap::from_bytes`).
    pub bytes: Vec<u8>,
    /// Nodes.
    pub nodes: usize,
    /// Edges (each counted once).
    pub edges: usize,
}

/// The roadmap of a scenario, as every planner of `host-sim` and the firmware export get it:
/// baked from the grid the planner tests paths on (the scenario's, or the one inflated for the
/// robot's body) for the planner's map, at most [`MAX_NODES`] nodes.
pub fn of_scenario(sc: &crate::scenario::Scenario) -> Result<Baked> {
    let map = sc.planner_map::<1>()?;
    let space = sc
        .space
        .as_ref()
        .map_or_else(|| sc.map.grid(), |s| s.grid());
    bake(&space, &map.metric_grid(), sc.robot_radius, MAX_NODES)
        .map_err(|e| anyhow::anyhow!("scenario {}: {e:#}", sc.name))
}

/// Bakes the roadmap of `space` (the grid the planner tests paths on: the scenario's, or the
/// grid inflated for the robot's body) for the planner's map `metric_grid` (its
/// `Map::metric_grid`: the roadmap records its hash and size); `radius` is the robot's, by
/// which `space` was inflated (0: a point). Errors when more than `max_nodes` nodes are kept.
pub fn bake(
    space: &OccupancyGrid<'_>,
    metric_grid: &OccupancyGrid<'_>,
    radius: f32,
    max_nodes: usize,
) -> Result<Baked> {
    let cell = space.cell_size();
    let (cols, rows) = (i32::from(space.cols()), i32::from(space.rows()));
    let occ = |c: i32, r: i32| {
        c < 0 || r < 0 || c >= cols || r >= rows || space.is_occupied(c as u16, r as u16)
    };
    let reach = ((HULL_M / cell).round() as i32).max(2);
    let join = ((HULL_M / cell).round() as i32).max(1);
    let widest = MAX_ANGLE_DEG.to_radians();
    // A speck grows by the body's radius all round on the inflated grid; the flood's window
    // reaches past it (for a point, the outline's own window).
    let speck = SPECK_M + 2.0 * radius.max(0.0);
    let win = reach.max((speck / cell).ceil() as i32 + 1);
    let mut nodes: Vec<Point> = Vec::new();
    let mut corners: Vec<u8> = Vec::new();
    let mut dirs: Vec<(f32, f32)> = Vec::new();
    let mut verts: Vec<(f32, f32)> = Vec::new();
    let mut window: Vec<bool> = Vec::new();
    let mut stack: Vec<(i32, i32)> = Vec::new();
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
            // The diagonal from the vertex into the occupied cell.
            let d = match q.iter().position(|&o| o) {
                Some(0) => (-1.0f32, -1.0f32),
                Some(1) => (1.0, -1.0),
                Some(2) => (-1.0, 1.0),
                _ => (1.0, 1.0),
            };
            // A vertex of the outline at the scale `reach`: the occupied cells of the window
            // joined to the corner's own cell within it, across gaps narrower than `HULL_M`
            // (`join` cells: on a fine map pixel noise beside a wall is part of the wall; on
            // a coarse one another wall across a corridor is another obstacle, as in a maze
            // of 1-cell corridors, where every wall's end is a corner a path bends round). The
            // flood runs to `win` cells, the angles count within `reach`.
            let side = 2 * win as usize;
            let inside = |c: i32, r: i32| {
                let (x, y) = (c as f32 + 0.5, r as f32 + 0.5);
                (-win..win).contains(&c)
                    && (-win..win).contains(&r)
                    && x * x + y * y <= (win * win) as f32
                    && occ(vx + c, vy + r)
            };
            let at = |c: i32, r: i32| ((r + win) as usize) * side + (c + win) as usize;
            window.clear();
            window.resize(side * side, false);
            let own = (
                if d.0 > 0.0 { 0 } else { -1 },
                if d.1 > 0.0 { 0 } else { -1 },
            );
            stack.clear();
            stack.push(own);
            window[at(own.0, own.1)] = true;
            let (mut lo, mut hi, mut wraps, mut far) = (0.0f32, 0.0f32, false, 0.0f32);
            while let Some((c, r)) = stack.pop() {
                let (x, y) = (c as f32 + 0.5, r as f32 + 0.5);
                far = far.max(x * x + y * y);
                if x * x + y * y <= (reach * reach) as f32 {
                    let a = (d.0 * y - d.1 * x).atan2(d.0 * x + d.1 * y);
                    wraps |= a.abs() > 0.95 * std::f32::consts::PI;
                    lo = lo.min(a);
                    hi = hi.max(a);
                }
                for dr in -join..=join {
                    for dc in -join..=join {
                        let (nc, nr) = (c + dc, r + dr);
                        if inside(nc, nr) && !window[at(nc, nr)] {
                            window[at(nc, nr)] = true;
                            stack.push((nc, nr));
                        }
                    }
                }
            }
            if wraps || hi - lo >= widest || far.sqrt() * cell <= speck {
                continue;
            }
            let p = Point::new(
                (vx as f32 - OFFSET_CELLS * d.0) * cell,
                (vy as f32 - OFFSET_CELLS * d.1) * cell,
            );
            if !space.point_free(p) {
                continue;
            }
            if nodes.len() >= max_nodes.min(roadmap::MAX_NODES) {
                bail!(
                    "the roadmap would keep more than {max_nodes} nodes (corners of a fine or \
                     cluttered map): run without it ('@roadmap=false')"
                );
            }
            nodes.push(p);
            corners.push(u8::from(d.0 > 0.0) | (u8::from(d.1 > 0.0) << 1));
            dirs.push(d);
            verts.push((vx as f32, vy as f32));
        }
    }
    let tangent = |e: (f32, f32), d: (f32, f32)| {
        let along = (e.0 * d.0 + e.1 * d.1).abs();
        along * along <= (e.0 * e.0 + e.1 * e.1) * 1.0001
    };
    // In order of x, then y (the core's attach scans outwards from a point's x).
    let mut order: Vec<usize> = (0..nodes.len()).collect();
    order.sort_by(|&a, &b| {
        nodes[a]
            .x
            .total_cmp(&nodes[b].x)
            .then(nodes[a].y.total_cmp(&nodes[b].y))
    });
    let nodes: Vec<Point> = order.iter().map(|&i| nodes[i]).collect();
    let corners: Vec<u8> = order.iter().map(|&i| corners[i]).collect();
    let dirs: Vec<(f32, f32)> = order.iter().map(|&i| dirs[i]).collect();
    let verts: Vec<(f32, f32)> = order.iter().map(|&i| verts[i]).collect();
    // Every pair, the segment tests (nearly all the bake's time) on all cores.
    let later: Vec<Vec<u16>> = (0..nodes.len())
        .into_par_iter()
        .map(|i| {
            (i + 1..nodes.len())
                .filter(|&j| {
                    // Tangent at both corners: tested on the corners themselves (grid
                    // vertices), not on the nodes beside them, whose offset tilts a segment
                    // along a corridor a cell wide by up to a third of it.
                    let e = (verts[j].0 - verts[i].0, verts[j].1 - verts[i].1);
                    tangent(e, dirs[i])
                        && tangent(e, dirs[j])
                        && space.segment_free(nodes[i], nodes[j])
                })
                .map(|j| j as u16)
                .collect()
        })
        .collect();
    let mut adj: Vec<Vec<u16>> = vec![Vec::new(); nodes.len()];
    for (i, js) in later.iter().enumerate() {
        for &j in js {
            adj[i].push(j);
            adj[usize::from(j)].push(i as u16);
        }
    }
    let adj = spanner(&nodes, &adj, STRETCH);
    let mut first = vec![0u32];
    let mut far = Vec::new();
    for a in &adj {
        far.extend_from_slice(a);
        first.push(far.len() as u32);
    }
    debug_assert!(corners.iter().all(|&c| c < NO_CORNER));
    let mut bytes = vec![0u8; roadmap::bytes_needed(nodes.len(), far.len())];
    roadmap::write(metric_grid, &nodes, &corners, &first, &far, &mut bytes)
        .map_err(|e| anyhow::anyhow!("roadmap bake: {e}"))?;
    Ok(Baked {
        bytes,
        nodes: nodes.len(),
        edges: far.len() / 2,
    })
}
