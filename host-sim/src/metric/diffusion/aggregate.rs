//! The diffusion map of a large map, computed on the table's own pieces (issue 23).
//!
//! A version-2 table stores one entry per connected free piece of each `b x b` block of cells
//! ([`crate::metric::diffusion::Pieces`]). When the map has more free cells than a table can ever hold
//! entries (65,536), there is no point in solving the eigenproblem on the cells: the bake
//! solves it on the pieces instead, so its cost follows the table's size, not the map's.
//!
//! The coarse problem is the Galerkin projection of the cell graph's (module
//! [`crate::metric::diffusion`]) onto vectors that are constant on each piece: with `P` the
//! cell-to-piece aggregation, the coarse matrix is `P^T A2 P` (sums of the cell graph's `A2`
//! entries between and within pieces) and its degrees `P^T D2 1`; the top eigenvectors, which
//! are smooth over the map, are what such vectors represent well. Nothing joins two sides of a
//! wall: pieces are connected through the cell graph's own edges inside their block, and two
//! pieces are coupled only by the cell edges between them (a one-cell door couples them by
//! its few edges, a one-cell wall by none). With `b = 1` the projection is the cell graph's
//! matrix itself.
//!
//! The cell graph is never stored: each cell keeps a 20-bit mask of its edges (the offsets of
//! [`crate::metric::graph::neighbour_offsets`], whose bounding box of cells is free), so memory is
//! about 20 bytes per cell plus the coarse graph. The time scale `t` is chosen against
//! shortest paths of the piece graph (edges between the pieces' centroids).

use std::time::Instant;

use anyhow::{Result, bail};
use bi_am_rrt::Point;
use bi_am_rrt::map::OccupancyGrid;
use rayon::prelude::*;

use crate::metric::diffusion::{DiffusionMap, Options, Report, diffusion_of};
use crate::metric::graph::neighbour_offsets;

/// Bit of a cell's mask: the cell is a node of the graph (in its largest component).
const NODE: u32 = 1 << 31;

/// The cell graph of a map as one edge mask per cell (module docs).
pub struct CellEdges {
    /// Columns.
    pub cols: u32,
    /// Rows.
    pub rows: u32,
    /// Cell side in metres.
    pub cell: f32,
    /// Per cell: bit `k` when offset `k` leads to a neighbour; [`NODE`] for graph nodes.
    mask: Vec<u32>,
    offs: Vec<(i32, i32)>,
    /// Nodes (free cells of the largest component).
    pub nodes: usize,
}

impl CellEdges {
    /// The edges of `grid` (the rule of [`crate::metric::graph::GridGraph`]), limited to its largest
    /// component (ties to the first in row-major order).
    pub fn build(grid: &OccupancyGrid<'_>) -> Self {
        Self::build_keeping(grid, None)
    }

    /// [`CellEdges::build`] on the component of cell `keep` (column, row) when it is free,
    /// else on the largest.
    pub fn build_keeping(grid: &OccupancyGrid<'_>, keep: Option<(u16, u16)>) -> Self {
        let (cols, rows) = (grid.cols() as i32, grid.rows() as i32);
        let offs = neighbour_offsets();
        let free = |c: i32, r: i32| {
            c >= 0 && r >= 0 && c < cols && r < rows && !grid.is_occupied(c as u16, r as u16)
        };
        let mut mask = vec![0u32; (cols * rows) as usize];
        mask.par_chunks_mut(cols as usize)
            .enumerate()
            .for_each(|(r, row)| {
                let r = r as i32;
                for (c, m) in row.iter_mut().enumerate() {
                    let c = c as i32;
                    if !free(c, r) {
                        continue;
                    }
                    for (k, &(dx, dy)) in offs.iter().enumerate() {
                        let box_free = (r.min(r + dy)..=r.max(r + dy))
                            .all(|y| (c.min(c + dx)..=c.max(c + dx)).all(|x| free(x, y)));
                        if box_free {
                            *m |= 1 << k;
                        }
                    }
                }
            });
        // Largest component (labels by first cell, row-major), then keep only its cells.
        let n = mask.len();
        let mut comp = vec![u32::MAX; n];
        let (mut best, mut best_label) = (0usize, u32::MAX);
        let mut stack = Vec::new();
        for start in 0..n {
            let (c, r) = ((start as i32) % cols, (start as i32) / cols);
            if comp[start] != u32::MAX || !free(c, r) {
                continue;
            }
            comp[start] = start as u32;
            stack.push(start);
            let mut size = 0;
            while let Some(i) = stack.pop() {
                size += 1;
                let m = mask[i];
                for (k, &(dx, dy)) in offs.iter().enumerate() {
                    if m & (1 << k) != 0 {
                        let j = (i as i64 + dy as i64 * cols as i64 + dx as i64) as usize;
                        if comp[j] == u32::MAX {
                            comp[j] = start as u32;
                            stack.push(j);
                        }
                    }
                }
            }
            if size > best {
                (best, best_label) = (size, start as u32);
            }
        }
        if let Some((c, r)) = keep.filter(|&(c, r)| c < grid.cols() && r < grid.rows()) {
            let l = comp[usize::from(r) * cols as usize + usize::from(c)];
            if l != u32::MAX {
                best_label = l;
            }
        }
        for (m, &l) in mask.iter_mut().zip(&comp) {
            *m = if l == best_label && l != u32::MAX {
                *m | NODE
            } else {
                0
            };
        }
        Self {
            cols: cols as u32,
            rows: rows as u32,
            cell: grid.cell_size(),
            mask,
            offs,
            nodes: best,
        }
    }

    /// Whether a cell is a node.
    pub fn is_node(&self, cell: usize) -> bool {
        self.mask.get(cell).is_some_and(|m| m & NODE != 0)
    }

    /// The neighbours of a node cell with their distance in cells.
    fn neighbours(&self, cell: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let m = self.mask[cell];
        let cols = self.cols as i64;
        self.offs
            .iter()
            .enumerate()
            .filter(move |(k, _)| m & (1 << k) != 0)
            .map(move |(_, &(dx, dy))| {
                (
                    (cell as i64 + dy as i64 * cols + dx as i64) as usize,
                    ((dx * dx + dy * dy) as f64).sqrt(),
                )
            })
    }

    /// Bytes this structure and a bake on it hold per map cell (mask, labels, degrees).
    pub const BYTES_PER_CELL: usize = 4 + 4 + 1 + 8;
}

/// The pieces of every `block x block` block: the aggregation `P` (module docs).
pub struct Aggregation {
    /// Block side in cells.
    pub block: u32,
    /// Per map cell (row-major): its piece in its block, 1..=15, or 0 (no node).
    pub piece: Vec<u8>,
    /// Per block (row-major): the index of its first piece.
    first: Vec<u32>,
    /// Pieces in all (block by block, in order).
    pub count: usize,
    cols: u32,
}

impl Aggregation {
    /// Splits every block of `edges` into the pieces its cells form with the edges inside the
    /// block (a block with more than 15 merges the rest into its 15th, which cannot happen
    /// below 6 x 6 blocks). `None` as soon as there are more than `limit` pieces.
    pub fn of(edges: &CellEdges, block: u32, limit: usize) -> Option<Self> {
        let (cols, rows, b) = (edges.cols, edges.rows, block.max(1));
        let (bcols, brows) = (cols.div_ceil(b), rows.div_ceil(b));
        let mut piece = vec![0u8; (cols * rows) as usize];
        let mut first = Vec::with_capacity((bcols * brows) as usize);
        let mut count = 0usize;
        let mut stack = Vec::new();
        for br in 0..brows {
            for bc in 0..bcols {
                first.push(count as u32);
                let (c0, r0) = (bc * b, br * b);
                let (c1, r1) = ((c0 + b).min(cols), (r0 + b).min(rows));
                let mut q = 0u8;
                for r in r0..r1 {
                    for c in c0..c1 {
                        let cell = (r * cols + c) as usize;
                        if !edges.is_node(cell) || piece[cell] != 0 {
                            continue;
                        }
                        if q < 15 {
                            q += 1;
                            count += 1;
                            if count > limit {
                                return None;
                            }
                        }
                        piece[cell] = q;
                        stack.push(cell);
                        while let Some(i) = stack.pop() {
                            for (j, _) in edges.neighbours(i) {
                                let (jc, jr) = (j as u32 % cols, j as u32 / cols);
                                if (c0..c1).contains(&jc) && (r0..r1).contains(&jr) && piece[j] == 0
                                {
                                    piece[j] = q;
                                    stack.push(j);
                                }
                            }
                        }
                    }
                }
            }
        }
        Some(Self {
            block: b,
            piece,
            first,
            count,
            cols,
        })
    }

    /// The piece (entry) of a cell, `None` off the graph.
    pub fn of_cell(&self, cell: usize) -> Option<u32> {
        let q = *self.piece.get(cell)?;
        if q == 0 {
            return None;
        }
        let (c, r) = (cell as u32 % self.cols, cell as u32 / self.cols);
        let bcols = self.cols.div_ceil(self.block);
        let blk = (r / self.block) * bcols + c / self.block;
        Some(self.first[blk as usize] + q as u32 - 1)
    }
}

/// The coarse graph of an aggregation: `P^T A2 P` as rows (diagonal included), the pieces'
/// centroids (cells) and the cells each stands for.
pub struct Coarse {
    /// Rows of the projected matrix.
    pub rows: Vec<Vec<(u32, f64)>>,
    /// Centroid of each piece, in cells.
    pub centroid: Vec<(f64, f64)>,
    /// Cells in each piece.
    pub cells: Vec<u32>,
}

impl Coarse {
    /// Projects the cell graph's `A2` (module [`crate::metric::diffusion`], steps 1-2) onto `agg`.
    pub fn project(edges: &CellEdges, agg: &Aggregation) -> Self {
        let r = edges.cell as f64;
        let kernel = |w_cells: f64| {
            let w = w_cells * r;
            (-(w * w) / (2.0 * r)).exp()
        };
        let cols = edges.cols as usize;
        let n = edges.mask.len();
        // Kernel degrees of the node cells.
        let mut d = vec![0.0f64; n];
        d.par_iter_mut().enumerate().for_each(|(i, di)| {
            if edges.is_node(i) {
                *di = edges.neighbours(i).map(|(_, w)| kernel(w)).sum();
            }
        });
        let mut rows: Vec<Vec<(u32, f64)>> = vec![Vec::new(); agg.count];
        let mut sum = vec![(0.0f64, 0.0f64); agg.count];
        let mut cells = vec![0u32; agg.count];
        fn add(row: &mut Vec<(u32, f64)>, q: u32, v: f64) {
            match row.iter_mut().find(|(j, _)| *j == q) {
                Some(e) => e.1 += v,
                None => row.push((q, v)),
            }
        }
        for i in 0..n {
            let Some(p) = agg.of_cell(i) else { continue };
            let di = d[i];
            let pu = p as usize;
            add(&mut rows[pu], p, 1.0 / (2.0 * di));
            for (j, w) in edges.neighbours(i) {
                let q = agg.of_cell(j).expect("a node's neighbour is a node");
                add(&mut rows[pu], q, kernel(w) / (2.0 * di * d[j]));
            }
            sum[pu].0 += (i % cols) as f64 + 0.5;
            sum[pu].1 += (i / cols) as f64 + 0.5;
            cells[pu] += 1;
        }
        let centroid = sum
            .iter()
            .zip(&cells)
            .map(|(&(x, y), &k)| (x / k.max(1) as f64, y / k.max(1) as f64))
            .collect();
        Self {
            rows,
            centroid,
            cells,
        }
    }

    /// Shortest paths over the piece graph, edges weighted by centroid distance (cells).
    pub fn dijkstra(&self, src: u32, dist: &mut Vec<f64>) {
        use std::cmp::Reverse;
        use std::collections::BinaryHeap;
        dist.clear();
        dist.resize(self.rows.len(), f64::INFINITY);
        let mut heap = BinaryHeap::new();
        dist[src as usize] = 0.0;
        heap.push(Reverse((0u64, src)));
        while let Some(Reverse((bits, u))) = heap.pop() {
            let du = f64::from_bits(bits);
            if du > dist[u as usize] {
                continue;
            }
            let (ux, uy) = self.centroid[u as usize];
            for &(v, _) in &self.rows[u as usize] {
                let (vx, vy) = self.centroid[v as usize];
                let nd = du + ((ux - vx).powi(2) + (uy - vy).powi(2)).sqrt();
                if nd < dist[v as usize] {
                    dist[v as usize] = nd;
                    // Non-negative floats order like their bits.
                    heap.push(Reverse((nd.to_bits(), v)));
                }
            }
        }
    }

    /// The centre of a piece in metres.
    pub fn position(&self, p: u32, cell: f32) -> Point {
        let (x, y) = self.centroid[p as usize];
        Point::new(x as f32 * cell, y as f32 * cell)
    }
}

/// The diffusion map of the pieces of `agg` (module docs): one node per piece, coordinates on
/// the cell graph's scale (the mass is the number of node cells).
pub fn aggregated_map(
    edges: &CellEdges,
    agg: &Aggregation,
    opts: &Options,
) -> Result<(Coarse, DiffusionMap)> {
    if agg.count <= opts.eigenpairs + 2 {
        bail!(
            "the map has {} pieces at block side {}: too few for {} eigenpairs",
            agg.count,
            agg.block,
            opts.eigenpairs
        );
    }
    let t0 = Instant::now();
    let coarse = Coarse::project(edges, agg);
    let report = Report {
        seconds_matrix: t0.elapsed().as_secs_f64(),
        ..Report::default()
    };
    let map = diffusion_of(
        coarse.rows.clone(),
        edges.nodes as f64,
        opts,
        report,
        &|s, d| coarse.dijkstra(s, d),
    )?;
    Ok((coarse, map))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::metric::bake::bake_diffusion;
    use crate::metric::diffusion::{BasisChoice, TableOptions, diffusion_map};
    use crate::metric::graph::GridGraph;
    use crate::scenario::OwnedGrid;
    use bi_am_rrt::{DiffusionTable, Metric};

    /// With blocks of one cell, the projection is the cell graph's own problem: the same
    /// eigenvalues and, up to sign, the same coordinates.
    #[test]
    fn blocks_of_one_cell_are_the_cell_graph() {
        let g = OwnedGrid::from_fn(18, 15, 0.05, |c, r| {
            (c == 7 && r < 11) || (r == 6 && c > 11)
        })
        .unwrap();
        let opts = Options::default();
        let fine = diffusion_map(&GridGraph::build(&g.grid()), &opts).unwrap();
        let edges = CellEdges::build(&g.grid());
        let agg = Aggregation::of(&edges, 1, usize::MAX).unwrap();
        assert_eq!(agg.count, edges.nodes);
        let (_, coarse) = aggregated_map(&edges, &agg, &opts).unwrap();
        for (a, b) in fine
            .report
            .eigenvalues
            .iter()
            .zip(&coarse.report.eigenvalues)
        {
            assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        }
        assert!((fine.report.t / coarse.report.t - 1.0).abs() < 1e-6);
        for (a, b) in fine.coords.iter().zip(&coarse.coords) {
            assert!(
                (a.abs() - b.abs()).abs() <= 1e-6 * a.abs().max(1.0),
                "{a} vs {b}"
            );
        }
    }

    /// A wall one cell thick stays a wall and a door one cell wide stays a door, whatever the
    /// block side: 0.05 m cells, blocks of 4 straddling the wall.
    #[test]
    fn a_one_cell_wall_stays_a_wall_and_a_one_cell_door_a_door() {
        let map = |door: bool| {
            OwnedGrid::from_fn(64, 48, 0.05, move |c, r| c == 30 && !(door && r == 2)).unwrap()
        };
        let opts = TableOptions {
            basis: BasisChoice::Pieces,
            coarsen: 4,
            ..TableOptions::default()
        };
        let at = |c: u32, r: u32| Point::new((c as f32 + 0.5) * 0.05, (r as f32 + 0.5) * 0.05);
        // The door open: one component; across the wall far from the door is a long way.
        let open = bake_diffusion(&map(true), &Options::default(), &opts).unwrap();
        let t = DiffusionTable::new(&open.table).unwrap();
        let across = t.distance(at(29, 40), at(31, 40));
        let along = t.distance(at(29, 40), at(29, 33));
        let by_door = t.distance(at(29, 2), at(31, 2));
        assert!(
            across.is_finite() && across > 5.0 * along,
            "{across} vs {along}"
        );
        assert!(by_door < along, "{by_door} vs {along}");
        // The door shut: the left side (the smaller) is another component, unreachable.
        let shut = bake_diffusion(&map(false), &Options::default(), &opts).unwrap();
        let t = DiffusionTable::new(&shut.table).unwrap();
        assert!(t.distance(at(29, 40), at(31, 40)).is_infinite());
        assert!(t.distance(at(31, 40), at(31, 33)).is_finite());
    }

    /// The bake of a map too large for its memory limit is refused before it starts, naming
    /// the knob; a table budget that no block side meets names it too.
    #[test]
    fn bakes_that_cannot_fit_say_which_knob_to_turn() {
        let g = OwnedGrid::from_fn(400, 400, 0.05, |c, r| c % 50 == 0 && r % 7 != 0).unwrap();
        let small = TableOptions {
            max_memory: 1 << 20,
            ..TableOptions::default()
        };
        let e = bake_diffusion(&g, &Options::default(), &small)
            .err()
            .unwrap();
        assert!(format!("{e:#}").contains("--max-memory"), "{e:#}");
        let tight = TableOptions {
            max_bytes: 80_200,
            ..TableOptions::default()
        };
        let e = bake_diffusion(&g, &Options::default(), &tight)
            .err()
            .unwrap();
        assert!(format!("{e:#}").contains("--max-bytes"), "{e:#}");
        // The default budget follows the map: this 160,000-cell map bakes on its pieces.
        let b = bake_diffusion(&g, &Options::default(), &TableOptions::default()).unwrap();
        assert!(matches!(b.basis, crate::metric::bake::Basis::Pieces { .. }));
        assert!(b.table.len() <= TableOptions::default().budget(160_000));
        // The table is bound to the grid it was baked from (version 3).
        let t = DiffusionTable::new(&b.table).unwrap();
        assert!(t.header().map_hash.is_some());
        assert!(t.check_map(&g.grid()).is_ok());
        let other = OwnedGrid::from_fn(400, 400, 0.05, |c, r| c % 50 == 1 && r % 7 != 0).unwrap();
        assert!(t.check_map(&other.grid()).is_err());
    }
}
