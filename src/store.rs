//! One tree's storage: the arena ([`crate::tree`]), its spatial index ([`crate::index`]) and
//! the resumable state of its rewiring sweeps (module `rewire`); paper Algorithm 1 keeps a
//! forward and a reverse tree, each one of these. Expansion (module `expand`) and rewiring
//! extend it with their own `impl` blocks.

use crate::clock::{Clock, Meter};
use crate::error::TreeError;
use crate::geometry::Point;
use crate::index::SpatialIndex;
use crate::slots::units;
use crate::sweep::{NodeQueue, NodeStack, SWEEP_CAP};
use crate::tree::{Cost, Edge, Mark, NodeId, Tree};

/// Most neighbours one `Nearby` query hands to the planner (more are counted, not used).
pub const NEAR_CAP: usize = 64;

/// The neighbour list type.
pub(crate) type Near = heapless::Vec<NodeId, NEAR_CAP>;

/// Storage of one tree: the arena of `N` nodes, a spatial index of up to `B` buckets and the
/// resumable state of its rewiring sweeps. Two of these (forward and reverse tree) make a
/// [`crate::planner::Storage`].
#[derive(Clone, Debug)]
pub struct TreeStore<const N: usize, const B: usize> {
    pub(crate) tree: Tree<N>,
    pub(crate) index: SpatialIndex<N, B>,
    pub(crate) root_queue: NodeQueue<SWEEP_CAP>,
    pub(crate) goal_stack: NodeStack<SWEEP_CAP>,
    /// Goal rewiring's queue; RT-RRT*'s random-rewiring queue.
    pub(crate) goal_queue: NodeQueue<SWEEP_CAP>,
    /// Where the path shortcuts ([`crate::config::Rewiring::path_shortcuts`]) go on (`None`: at the goal).
    pub(crate) shortcut_at: Option<NodeId>,
    /// States the density rule turned away in a row while the tree's goal is not in it
    /// (saturating): from [`STARVING`] on, the tree is starving (module docs).
    pub(crate) refused: u16,
    /// States let in by the starving rule since the goal was set (saturating; the planner
    /// zeroes it with its stats).
    pub(crate) holes: u32,
}

impl<const N: usize, const B: usize> Default for TreeStore<N, B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const B: usize> TreeStore<N, B> {
    /// Empty storage (a `const fn`, so it can be a `static`).
    pub const fn new() -> Self {
        Self {
            tree: Tree::new(),
            index: SpatialIndex::new(),
            root_queue: NodeQueue::new(),
            goal_stack: NodeStack::new(),
            goal_queue: NodeQueue::new(),
            shortcut_at: None,
            refused: 0,
            holes: 0,
        }
    }

    /// Empties the tree and makes a root at `pos`; forgets all rewiring state.
    pub(crate) fn reset(&mut self, pos: Point) {
        let root = self.tree.reset(pos);
        self.refused = 0;
        self.index.clear();
        let _ = self.index.insert(root, pos);
        self.restart_sweeps();
    }

    /// Empties the tree entirely.
    pub(crate) fn clear(&mut self) {
        self.tree.clear();
        self.refused = 0;
        self.index.clear();
        self.restart_sweeps();
    }

    /// Forgets the progress of every rewiring sweep (they restart from the root).
    pub(crate) fn restart_sweeps(&mut self) {
        self.restart_root_sweep();
        self.restart_goal_sweep();
    }

    pub(crate) fn restart_root_sweep(&mut self) {
        self.root_queue.clear();
        self.tree.clear_marks(Mark::Root);
    }

    pub(crate) fn restart_goal_sweep(&mut self) {
        self.goal_stack.clear();
        self.goal_queue.clear();
        self.tree.clear_marks(Mark::Goal);
        self.shortcut_at = None;
    }

    /// Adds a node and indexes it.
    pub(crate) fn insert(
        &mut self,
        pos: Point,
        parent: NodeId,
        edge: impl Into<Edge>,
    ) -> Result<NodeId, TreeError> {
        let id = self.tree.add(pos, parent, edge)?;
        // Cannot fail: the id is below N and new, the position finite.
        let _ = self.index.insert(id, pos);
        Ok(id)
    }

    pub(crate) fn pos(&self, id: NodeId) -> Point {
        self.tree.position(id).unwrap_or(Point::ZERO)
    }

    pub(crate) fn cost(&self, id: NodeId) -> Cost {
        self.tree.cost(id).unwrap_or(Cost {
            length: f32::INFINITY,
            blocked: true,
        })
    }

    /// Nodes within `radius` of `p` into `out`; returns how many there were in all.
    pub(crate) fn nearby<C: Clock + ?Sized>(
        &self,
        p: Point,
        radius: f32,
        out: &mut Near,
        meter: &Meter<'_, C>,
    ) -> usize {
        let n = self.index.within(p, radius, self.tree.positions(), out);
        meter.charge(units(n).saturating_add(4));
        n
    }
}
