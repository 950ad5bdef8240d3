//! The assisting metrics on the host: the geodesic metric `d_G` (exact graph distances), the
//! diffusion metric read from a table (`bi_am_rrt::metric::DiffusionTable`), Euclidean, and one
//! enum over them so a run can pick any.
//!
//! # Geodesic metric: cost
//!
//! Exact shortest-path distances on the grid graph without an `n x n` matrix: the distance
//! field to a target node is computed by one Dijkstra run (O(E log V): about 170,000 edges on
//! a 100 x 100 map, 440,000 on office) the first time that target is asked for, then kept in
//! a cache of at most `max_fields` fields (`4 n` bytes each). A query whose target (or source:
//! the metric is symmetric) has a cached field costs one lookup. Preparation is only the graph
//! build. Targets the planner asks for again and again (the goal, the reverse tree's target)
//! are computed once; a random sample the tree steers towards costs one Dijkstra run. That work
//! (one unit per edge relaxed) is reported to the planner through `Metric::take_work`, so the
//! virtual clock charges it.

#[cfg(feature = "sim")]
pub mod bake;
pub mod clearance;
#[cfg(feature = "sim")]
pub mod diffusion;
pub mod graph;
pub mod grid_planners;
pub mod optimum;
pub mod roadmap;

use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::sync::Arc;

use bi_am_rrt::Point;
use bi_am_rrt::metric::{DiffusionTable, Euclidean, Metric, Prepared};

use crate::metric::graph::GridGraph;

/// `d_G` over a shared grid graph, with a per-target field cache (module docs).
/// `Send` (fields shared by `Arc`): a planner on it may move to another thread (the Python
/// bindings release the interpreter's lock while it plans).
pub struct Geodesic {
    graph: Arc<GridGraph>,
    fields: RefCell<HashMap<u32, Arc<[f32]>>>,
    max_fields: usize,
    scratch: RefCell<Vec<f64>>,
    runs: Cell<u64>,
    /// Edges relaxed by Dijkstra runs not yet reported through `take_work`.
    work: Cell<u64>,
}

impl Geodesic {
    /// A metric over `graph` caching at most `max_fields` distance fields.
    pub fn new(graph: Arc<GridGraph>, max_fields: usize) -> Self {
        Self {
            graph,
            fields: RefCell::new(HashMap::new()),
            max_fields: max_fields.max(1),
            scratch: RefCell::new(Vec::new()),
            runs: Cell::new(0),
            work: Cell::new(0),
        }
    }

    /// A cache of about `bytes` bytes.
    pub fn with_cache_bytes(graph: Arc<GridGraph>, bytes: usize) -> Self {
        let per = 4 * graph.len().max(1);
        Self::new(graph, bytes / per)
    }

    /// Dijkstra runs so far.
    pub fn dijkstra_runs(&self) -> u64 {
        self.runs.get()
    }

    /// The distance field to `node` (cells).
    pub fn field(&self, node: u32) -> Arc<[f32]> {
        if let Some(f) = self.fields.borrow().get(&node) {
            return f.clone();
        }
        let mut scratch = self.scratch.borrow_mut();
        self.graph.dijkstra(node, &mut scratch);
        self.runs.set(self.runs.get() + 1);
        // One work unit per directed edge (a Dijkstra run relaxes each once).
        self.work
            .set(self.work.get() + self.graph.edge_count() as u64);
        let field: Arc<[f32]> = scratch.iter().map(|&d| d as f32).collect();
        let mut fields = self.fields.borrow_mut();
        if fields.len() >= self.max_fields {
            // Simple bounded cache: start afresh (the goal's field is recomputed at once).
            fields.clear();
        }
        fields.insert(node, field.clone());
        field
    }
}

impl Metric for Geodesic {
    fn distance(&self, a: Point, b: Point) -> f32 {
        let (Some(na), Some(nb)) = (self.graph.node_at(a), self.graph.node_at(b)) else {
            return f32::INFINITY;
        };
        if na == nb {
            return 0.0;
        }
        // Symmetric: use whichever end has a field already.
        let cached_a = self.fields.borrow().get(&na).cloned();
        let d = match cached_a {
            Some(f) => f[nb as usize],
            None => self.field(nb)[na as usize],
        };
        d * self.graph.cell
    }

    fn take_work(&self) -> u32 {
        u32::try_from(self.work.replace(0)).unwrap_or(u32::MAX)
    }
}

/// Any of the metrics a run can use.
pub enum AnyMetric<'t> {
    /// `d_E`.
    Euclidean,
    /// `d_D` from a table.
    Diffusion(DiffusionTable<'t>),
    /// `d_G`.
    Geodesic(Geodesic),
}

impl Metric for AnyMetric<'_> {
    fn distance(&self, a: Point, b: Point) -> f32 {
        match self {
            Self::Euclidean => Euclidean.distance(a, b),
            Self::Diffusion(t) => t.distance(a, b),
            Self::Geodesic(g) => g.distance(a, b),
        }
    }

    fn is_euclidean(&self) -> bool {
        matches!(self, Self::Euclidean)
    }

    fn check_map(
        &self,
        grid: &bi_am_rrt::map::OccupancyGrid<'_>,
    ) -> Result<(), bi_am_rrt::metric::TableError> {
        match self {
            Self::Diffusion(t) => t.check_map(grid),
            _ => Ok(()),
        }
    }

    fn take_work(&self) -> u32 {
        match self {
            Self::Geodesic(g) => g.take_work(),
            _ => 0,
        }
    }

    fn prepare(&self, p: Point) -> Prepared {
        match self {
            Self::Diffusion(t) => t.prepare(p),
            _ => Prepared::plain(p),
        }
    }

    fn distance_to(&self, a: Point, to: &Prepared) -> f32 {
        match self {
            Self::Diffusion(t) => t.distance_to(a, to),
            _ => self.distance(a, to.point()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scenario::OwnedGrid;

    #[test]
    fn geodesic_goes_around_walls_and_caches() {
        // 10 x 10 with a wall at column 5, rows 0..8.
        let g = OwnedGrid::from_fn(10, 10, 1.0, |c, r| c == 5 && r < 8).unwrap();
        let graph = Arc::new(GridGraph::build(&g.grid()));
        let m = Geodesic::new(graph, 4);
        let (a, b) = (Point::new(3.5, 1.5), Point::new(7.5, 1.5));
        let d = m.distance(a, b);
        assert!(d > 10.0, "around the wall: {d}");
        assert_eq!(m.distance(b, a), d);
        assert_eq!(m.dijkstra_runs(), 1, "the second query reuses the field");
        assert_eq!(
            m.take_work() as usize,
            m.graph.edge_count(),
            "one run reported"
        );
        assert_eq!(m.take_work(), 0);
        assert_eq!(m.distance(a, Point::new(5.5, 3.5)), f32::INFINITY);
        let e = m.distance(a, Point::new(3.5, 4.5));
        assert!((e - 3.0).abs() < 1e-6);
    }
}
