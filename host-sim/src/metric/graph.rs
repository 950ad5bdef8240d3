//! The grid graph of a map (shared by the geodesic metric and the diffusion bake): one node per
//! free cell centre of the largest connected component; an edge between two nodes at most 2.5
//! cells apart whose bounding box of cells is entirely free (which is when their straight
//! segment is free); edge weight = the distance between the centres, in cells.
//!
//! Ties between components of equal size go to the first found in row-major order. Nodes are
//! numbered in row-major cell order. Adjacency is stored compressed (CSR).

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;

/// Cell offsets `(dx, dy)` of the neighbours: `dx^2 + dy^2 <= 6.25`, excluding `(0, 0)`.
pub fn neighbour_offsets() -> Vec<(i32, i32)> {
    let mut v = Vec::new();
    for dy in -2i32..=2 {
        for dx in -2i32..=2 {
            if (dx, dy) != (0, 0) && (dx * dx + dy * dy) as f64 <= 6.25 {
                v.push((dx, dy));
            }
        }
    }
    v
}

/// The length in metres of a shortest 8-connected path over the free cells of `grid` from
/// `a` through the centres of their cells to `b` (steps of 1 and sqrt 2 cells, a diagonal only
/// between two free side cells), or `None` when there is none: the A* of
/// [`crate::metric::grid_planners::astar8`]. The agent protocol's call budget per leg follows it
/// ([`crate::sim::Prepared::leg_calls`]).
pub fn grid_path_length(grid: &OccupancyGrid<'_>, a: Point, b: Point) -> Option<f64> {
    crate::metric::grid_planners::astar8(grid, a, b).map(|p| p.length_m)
}

/// The connected components of the free cells (4-neighbours; the same components as the
/// graph's edges give): per cell in row-major order, the label of its component (the index of
/// the component's first cell), or `None` for an occupied cell.
pub fn components(grid: &OccupancyGrid<'_>) -> Vec<Option<u32>> {
    let (cols, rows) = (grid.cols() as usize, grid.rows() as usize);
    let free = |i: usize| !grid.is_occupied((i % cols) as u16, (i / cols) as u16);
    let mut comp = vec![None; cols * rows];
    let mut stack = Vec::new();
    for start in 0..cols * rows {
        if comp[start].is_some() || !free(start) {
            continue;
        }
        let label = Some(start as u32);
        comp[start] = label;
        stack.push(start);
        while let Some(i) = stack.pop() {
            let (c, r) = (i % cols, i / cols);
            let near = [
                (c > 0).then(|| i - 1),
                (c + 1 < cols).then_some(i + 1),
                (r > 0).then(|| i - cols),
                (r + 1 < rows).then_some(i + cols),
            ];
            for j in near.into_iter().flatten() {
                if comp[j].is_none() && free(j) {
                    comp[j] = label;
                    stack.push(j);
                }
            }
        }
    }
    comp
}

/// The grid graph (module docs).
#[derive(Clone, Debug)]
pub struct GridGraph {
    /// Columns of the map.
    pub cols: u32,
    /// Rows of the map.
    pub rows: u32,
    /// Cell side in metres.
    pub cell: f32,
    /// Node of each cell (`u32::MAX`: none).
    pub node_of_cell: Vec<u32>,
    /// Cell index (`row * cols + col`) of each node.
    pub cell_of_node: Vec<u32>,
    /// CSR row starts (length nodes + 1).
    pub offsets: Vec<u32>,
    /// CSR neighbour nodes.
    pub targets: Vec<u32>,
    /// CSR edge weights, in cells.
    pub weights: Vec<f64>,
}

impl GridGraph {
    /// Builds the graph of `grid`.
    pub fn build(grid: &OccupancyGrid<'_>) -> Self {
        Self::build_keeping(grid, None)
    }

    /// [`GridGraph::build`] on the component of cell `keep` (column, row) when it is free,
    /// else on the largest.
    pub fn build_keeping(grid: &OccupancyGrid<'_>, keep: Option<(u16, u16)>) -> Self {
        let (cols, rows) = (grid.cols() as i32, grid.rows() as i32);
        let free = |c: i32, r: i32| {
            c >= 0 && r >= 0 && c < cols && r < rows && !grid.is_occupied(c as u16, r as u16)
        };
        let offs = neighbour_offsets();
        // Edge test between free cells: the whole bounding box is free.
        let edge = |c: i32, r: i32, dx: i32, dy: i32| {
            let (c2, r2) = (c + dx, r + dy);
            if !free(c2, r2) {
                return false;
            }
            for y in r.min(r2)..=r.max(r2) {
                for x in c.min(c2)..=c.max(c2) {
                    if !free(x, y) {
                        return false;
                    }
                }
            }
            true
        };
        let n_cells = (cols * rows) as usize;
        let comp = components(grid);
        // The largest component; ties go to the first found in row-major order.
        let mut size = std::collections::HashMap::<u32, usize>::new();
        for l in comp.iter().flatten() {
            *size.entry(*l).or_default() += 1;
        }
        let (largest_label, largest_size) = size
            .into_iter()
            .max_by_key(|&(l, n)| (n, std::cmp::Reverse(l)))
            .unwrap_or((u32::MAX, 0));
        let kept = keep.and_then(|(c, r)| {
            let i = usize::from(r) * cols as usize + usize::from(c);
            (c < grid.cols() && r < grid.rows())
                .then(|| comp[i])
                .flatten()
        });
        let best_label = kept.unwrap_or(largest_label);
        let best_size = kept.map_or(largest_size, |l| {
            comp.iter().filter(|x| **x == Some(l)).count()
        });
        let comp: Vec<u32> = comp.into_iter().map(|l| l.unwrap_or(u32::MAX)).collect();
        let mut node_of_cell = vec![u32::MAX; n_cells];
        let mut cell_of_node = Vec::with_capacity(best_size);
        for (i, &l) in comp.iter().enumerate() {
            if l == best_label && best_label != u32::MAX {
                node_of_cell[i] = cell_of_node.len() as u32;
                cell_of_node.push(i as u32);
            }
        }
        let mut offsets = Vec::with_capacity(cell_of_node.len() + 1);
        let mut targets = Vec::new();
        let mut weights = Vec::new();
        offsets.push(0);
        for &cell in &cell_of_node {
            let (c, r) = (cell as i32 % cols, cell as i32 / cols);
            for &(dx, dy) in &offs {
                if edge(c, r, dx, dy) {
                    let j = ((r + dy) * cols + c + dx) as usize;
                    targets.push(node_of_cell[j]);
                    weights.push(((dx * dx + dy * dy) as f64).sqrt());
                }
            }
            offsets.push(targets.len() as u32);
        }
        Self {
            cols: cols as u32,
            rows: rows as u32,
            cell: grid.cell_size(),
            node_of_cell,
            cell_of_node,
            offsets,
            targets,
            weights,
        }
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.cell_of_node.len()
    }

    /// Whether the graph has no node.
    pub fn is_empty(&self) -> bool {
        self.cell_of_node.is_empty()
    }

    /// Number of directed edges (twice the undirected count).
    pub fn edge_count(&self) -> usize {
        self.targets.len()
    }

    /// The node of the cell containing `p` (`None` off the graph).
    pub fn node_at(&self, p: Point) -> Option<u32> {
        let inv = 1.0 / self.cell;
        let (x, y) = (p.x * inv, p.y * inv);
        if !(x >= 0.0 && y >= 0.0) {
            return None;
        }
        let c = (x as u32).min(self.cols.saturating_sub(1));
        let r = (y as u32).min(self.rows.saturating_sub(1));
        if x > self.cols as f32 || y > self.rows as f32 {
            return None;
        }
        let n = *self.node_of_cell.get((r * self.cols + c) as usize)?;
        (n != u32::MAX).then_some(n)
    }

    /// The centre of a node's cell, in metres.
    pub fn position(&self, node: u32) -> Point {
        let cell = self.cell_of_node[node as usize];
        let (c, r) = (cell % self.cols, cell / self.cols);
        Point::new((c as f32 + 0.5) * self.cell, (r as f32 + 0.5) * self.cell)
    }

    /// Neighbours of a node with edge weights (cells).
    pub fn neighbours(&self, node: u32) -> impl Iterator<Item = (u32, f64)> + '_ {
        let (a, b) = (
            self.offsets[node as usize] as usize,
            self.offsets[node as usize + 1] as usize,
        );
        self.targets[a..b]
            .iter()
            .copied()
            .zip(self.weights[a..b].iter().copied())
    }

    /// Shortest-path distances (cells) from `src` to every node, written into `dist`.
    pub fn dijkstra(&self, src: u32, dist: &mut Vec<f64>) {
        #[derive(PartialEq)]
        struct Item(f64, u32);
        impl Eq for Item {}
        impl PartialOrd for Item {
            fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
                Some(self.cmp(o))
            }
        }
        impl Ord for Item {
            fn cmp(&self, o: &Self) -> Ordering {
                o.0.total_cmp(&self.0).then(o.1.cmp(&self.1))
            }
        }
        dist.clear();
        dist.resize(self.len(), f64::INFINITY);
        let mut heap = BinaryHeap::with_capacity(self.len());
        dist[src as usize] = 0.0;
        heap.push(Item(0.0, src));
        while let Some(Item(d, u)) = heap.pop() {
            if d > dist[u as usize] {
                continue;
            }
            for (v, w) in self.neighbours(u) {
                let nd = d + w;
                if nd < dist[v as usize] {
                    dist[v as usize] = nd;
                    heap.push(Item(nd, v));
                }
            }
        }
    }
}

#[cfg(test)]
mod grid_path_tests {
    use super::*;
    use crate::scenario::OwnedGrid;

    #[test]
    fn grid_path_length_goes_round_a_wall() {
        // 10 x 10 cells of 1 m, a wall along column 5 from row 0 to row 8.
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, r| c == 5 && r <= 8).unwrap();
        let g = g.grid();
        // Straight along a free row: 8 cells.
        assert_eq!(
            grid_path_length(&g, Point::new(0.5, 9.5), Point::new(8.5, 9.5)),
            Some(8.0)
        );
        // Round the wall's end: longer than the straight 8 m, within the octile bound.
        let d = grid_path_length(&g, Point::new(0.5, 0.5), Point::new(9.5, 0.5)).unwrap();
        // Down nine rows and back up at least, past the wall's end at row 8.
        assert!(d > 18.0 && d < 30.0, "{d}");
        // Into the wall, or walled off: none.
        assert_eq!(
            grid_path_length(&g, Point::new(5.5, 0.5), Point::new(9.5, 0.5)),
            None
        );
        let closed = OwnedGrid::from_fn(10, 10, 1.0, |c, _| c == 5).unwrap();
        assert_eq!(
            grid_path_length(&closed.grid(), Point::new(0.5, 0.5), Point::new(9.5, 0.5)),
            None
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::OwnedGrid;

    #[test]
    fn offsets_and_small_graph() {
        assert_eq!(neighbour_offsets().len(), 20);
        // 5 x 3 map with a wall cell in the middle of the middle row.
        let g = OwnedGrid::from_fn(5, 3, 1.0, |c, r| c == 2 && r == 1).unwrap();
        let graph = GridGraph::build(&g.grid());
        assert_eq!(graph.len(), 14);
        // (3,0) -> (4,2) is a knight move whose bounding box is free: an edge of length sqrt 5.
        let a = graph.node_at(Point::new(3.5, 0.5)).unwrap();
        let b = graph.node_at(Point::new(4.5, 2.5)).unwrap();
        assert!(
            graph
                .neighbours(a)
                .any(|(v, w)| v == b && (w - 5f64.sqrt()).abs() < 1e-12)
        );
        // (0,1) -> (2,0) has the wall cell (2,1) in its bounding box: no edge.
        let a = graph.node_at(Point::new(0.5, 1.5)).unwrap();
        let b = graph.node_at(Point::new(2.5, 0.5)).unwrap();
        assert!(!graph.neighbours(a).any(|(v, _)| v == b));
        // (1,1) -> (3,1) passes through the wall: no edge.
        let c = graph.node_at(Point::new(1.5, 1.5)).unwrap();
        let d = graph.node_at(Point::new(3.5, 1.5)).unwrap();
        assert!(!graph.neighbours(c).any(|(v, _)| v == d));
        let mut dist = Vec::new();
        graph.dijkstra(c, &mut dist);
        // Around the wall without cutting its corners: (1,1) -> (1,0) -> (3,0) -> (3,1) = 4.
        assert!((dist[d as usize] - 4.0).abs() < 1e-12);
        assert!(graph.node_at(Point::new(2.5, 1.5)).is_none());
    }

    #[test]
    fn largest_component_wins_ties_in_row_major_order() {
        // Two 2-cell pockets separated by a full wall column; the left one comes first.
        let g = OwnedGrid::from_fn(3, 2, 1.0, |c, _| c == 1).unwrap();
        let graph = GridGraph::build(&g.grid());
        assert_eq!(graph.len(), 2);
        assert!(graph.node_at(Point::new(0.5, 0.5)).is_some());
        assert!(graph.node_at(Point::new(2.5, 0.5)).is_none());
    }
}
