//! The tree arena: a fixed-capacity RRT* tree with cached costs (paper, section 3: `Cost`,
//! `UpdateEdge`, `SetRoot`).
//!
//! Nodes live in parallel arrays of capacity `N` (struct of arrays), addressed by [`NodeId`], a
//! `u16` newtype. Parent, first-child and sibling links are ids too, so the children of a node
//! form an intrusive doubly linked list and no node owns a vector. Every node caches its
//! [`Cost`]: the length of the tree path from the root, and whether any edge of that path
//! crosses a dynamic obstacle (the edge's *blocked* flag). An edge's length is Euclidean, or
//! weighted by the edge's clearance class (three bits of the node's flag byte, no extra RAM)
//! when the planner prefers clearance ([`charged`]; beyond the paper). The caches stay exact:
//! changing an edge recomputes the costs of the moved subtree (a preorder walk along the links,
//! with no stack), and re-rooting reverses the edges on the old-root-to-new-root path and
//! recomputes all costs. A cost is always recomputed the same way (`parent cost + charged
//! |parent - node|`), so cached and freshly recomputed costs agree to the bit.
//!
//! Resetting is O(1) (the node count drops to zero); nothing is reallocated. An operation that
//! fails returns an error and leaves the tree exactly as it was.

use core::cmp::Ordering;

use crate::error::TreeError;
use crate::geometry::Point;
use crate::slots::{copy_slot, rd, rd_link, reverse, wr, wr_link};

const NONE: u16 = u16::MAX;

/// An edge's clearance class in its flag bits.
fn class_bits(class: u8) -> u8 {
    class.min(MAX_CLASS) << CLASS_SHIFT
}

/// Identifies a node of one [`Tree`]. Ids are dense (`0..len`) and stay valid until the tree
/// is reset.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct NodeId(pub u16);

impl NodeId {
    /// The id as an array index.
    #[inline]
    pub const fn index(self) -> usize {
        self.0 as usize
    }
}

/// The cost of reaching a node from the root: path length plus a *blocked* flag. Costs compare
/// blocked-last: every unblocked cost is smaller than every blocked one, and costs with the same
/// flag compare by length (`f32::total_cmp`, so the order is total).
#[derive(Clone, Copy, Debug, Default)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Cost {
    /// Length of the path from the root, in metres: Euclidean, each edge weighted by its
    /// clearance class when the planner has a clearance preference ([`charged`]).
    pub length: f32,
    /// Some edge of the path crosses a dynamic obstacle.
    pub blocked: bool,
}

/// A new edge as the tree records it: whether it crosses a dynamic obstacle, and its
/// clearance class (0-7, [`crate::Map::clearance_class`]; 0 = open space or no clearance
/// preference), which weights its length by `1 + weight x class / 7`
/// ([`Tree::set_clearance_weight`]). A `bool` converts to an edge of class 0 with that
/// blocked flag.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Edge {
    /// The edge crosses a dynamic obstacle.
    pub blocked: bool,
    /// Clearance class, 0-7 (larger values clamp to 7).
    pub class: u8,
}

impl From<bool> for Edge {
    fn from(blocked: bool) -> Self {
        Edge { blocked, class: 0 }
    }
}

/// Highest clearance class an edge records.
pub const MAX_CLASS: u8 = 7;

/// The length an edge of Euclidean length `len` and clearance class `class` is charged under
/// a clearance preference of `weight`: `len` itself for class 0 (so a planner without a
/// preference computes exactly what it did before there was one), else
/// `len x (1 + weight x class / 7)`.
#[inline]
pub fn charged(len: f32, class: u8, weight: f32) -> f32 {
    if class == 0 {
        len
    } else {
        len * (1.0 + weight * f32::from(class.min(MAX_CLASS)) / f32::from(MAX_CLASS))
    }
}

impl Cost {
    /// The root's cost.
    pub const ZERO: Cost = Cost {
        length: 0.0,
        blocked: false,
    };

    /// The cost after one more edge of length `len` whose own blocked flag is `blocked`.
    #[inline]
    pub fn extend(self, len: f32, blocked: bool) -> Cost {
        Cost {
            length: self.length + len,
            blocked: self.blocked || blocked,
        }
    }
}

impl Ord for Cost {
    fn cmp(&self, o: &Self) -> Ordering {
        self.blocked
            .cmp(&o.blocked)
            .then(self.length.total_cmp(&o.length))
    }
}

impl Cost {
    /// An integer with the order of [`Cost`]'s `cmp` (blocked last, then `total_cmp` of the
    /// length): sorting by it compares integers instead of floats and flags (issue 25: the
    /// parent choice's sort of 64 candidates took 0.3 ms on a Cortex-M4F).
    pub fn sort_key(&self) -> u64 {
        let bits = self.length.to_bits();
        // `total_cmp`'s order as unsigned integers: negative lengths flipped entirely,
        // positive ones with the sign bit set.
        let ordered = if bits & 0x8000_0000 != 0 {
            !bits
        } else {
            bits | 0x8000_0000
        };
        (u64::from(self.blocked) << 32) | u64::from(ordered)
    }
}

impl PartialOrd for Cost {
    fn partial_cmp(&self, o: &Self) -> Option<Ordering> {
        Some(self.cmp(o))
    }
}

impl PartialEq for Cost {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o) == Ordering::Equal
    }
}

impl Eq for Cost {}

/// A broken invariant found by [`Tree::validate`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum Invariant {
    /// The root has a parent, or a non-root node has none.
    RootParent(NodeId),
    /// A link (parent, child or sibling) points outside `0..len`.
    DanglingLink(NodeId),
    /// A node's parent does not list it among its children, or a child list is inconsistent.
    ChildList(NodeId),
    /// Following parents from this node does not reach the root within `len` steps.
    NotConnected(NodeId),
    /// The cached cost differs from the recomputed one.
    StaleCost(NodeId),
}

/// A tree of at most `N` nodes (`N < 65,535`) with cached path costs. See the module docs.
#[derive(Clone, Debug)]
pub struct Tree<const N: usize> {
    pos: [Point; N],
    cost: [f32; N],
    parent: [u16; N],
    first_child: [u16; N],
    next_sibling: [u16; N],
    /// Bit 0: the edge from the parent is blocked by a dynamic obstacle. Bit 1: the cached path
    /// is blocked. Bits 2-3: the marks of the rewiring sweeps ([`Mark`]). Bit 4: the edge
    /// crosses a cell the live overlay marked. Bits 5-7: the edge's clearance class.
    flags: [u8; N],
    len: u16,
    root: u16,
    /// The clearance preference's weight ([`charged`]).
    weight: f32,
}

const EDGE_BLOCKED: u8 = 1;
const PATH_BLOCKED: u8 = 2;
/// Bit 4: the edge from the parent crosses a cell the live overlay marked
/// ([`Tree::rewall_edges`]); kept apart from the obstacles' bit so that re-flagging one source
/// never clears the other's.
const EDGE_WALLED: u8 = 16;
/// The edge is blocked, by an obstacle or by a marked cell.
const EDGE_ANY: u8 = EDGE_BLOCKED | EDGE_WALLED;
/// Bits 5-7: the edge's clearance class.
const CLASS_SHIFT: u8 = 5;
const CLASS_BITS: u8 = 0b1110_0000;
/// What an edge carries when it is reversed (re-rooting).
const EDGE_OWN: u8 = EDGE_ANY | CLASS_BITS;

/// A per-node mark kept in the node's flag byte, for the rewiring sweeps' "seen" sets (two
/// bits per node instead of a separate set; see [`crate::rewire`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Mark {
    /// Seen by the root sweep.
    Root = 4,
    /// Seen by the goal sweep.
    Goal = 8,
}

impl<const N: usize> Default for Tree<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> Tree<N> {
    const CAPACITY_FITS: () = assert!(N > 0 && N < NONE as usize, "Tree capacity must be 1..65535");

    /// An empty tree (no root yet; see [`Tree::reset`]). A `const fn`, so a tree can be a
    /// `static`.
    pub const fn new() -> Self {
        let () = Self::CAPACITY_FITS;
        Self {
            pos: [Point::ZERO; N],
            cost: [0.0; N],
            parent: [0; N],
            first_child: [0; N],
            next_sibling: [0; N],
            flags: [0; N],
            len: 0,
            root: 0,
            weight: 0.0,
        }
    }

    /// Sets the clearance preference's weight ([`charged`]; 0, the default, charges every edge
    /// its Euclidean length) and recomputes every cost. A weight that is not finite or is
    /// negative counts as 0.
    pub fn set_clearance_weight(&mut self, weight: f32) {
        self.weight = if weight.is_finite() && weight > 0.0 {
            weight
        } else {
            0.0
        };
        if self.len > 0 {
            self.refresh_subtree(self.root);
        }
    }

    /// The clearance preference's weight.
    pub fn clearance_weight(&self) -> f32 {
        self.weight
    }

    /// The capacity `N`.
    pub const fn capacity(&self) -> usize {
        N
    }

    /// Number of nodes.
    pub const fn len(&self) -> usize {
        self.len as usize
    }

    /// Whether the tree has no node (not even a root).
    pub const fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether no node can be added.
    pub const fn is_full(&self) -> bool {
        self.len as usize >= N
    }

    /// Whether `id` is a node without children.
    pub fn is_leaf(&self, id: NodeId) -> bool {
        self.contains(id) && rd_link(&self.first_child, id.index()) == NONE
    }

    /// Marks `id`; returns whether it was unmarked (false too for an unknown id).
    pub(crate) fn mark(&mut self, id: NodeId, m: Mark) -> bool {
        if !self.contains(id) || self.marked(id, m) {
            return false;
        }
        self.set_flag(id.0, m as u8, true);
        true
    }

    /// Removes mark `m` from `id`.
    pub(crate) fn unmark(&mut self, id: NodeId, m: Mark) {
        self.set_flag(id.0, m as u8, false);
    }

    /// Whether `id` carries mark `m`.
    pub(crate) fn marked(&self, id: NodeId, m: Mark) -> bool {
        rd(&self.flags, id.index(), 0) & m as u8 != 0
    }

    /// The arena's last `n` slots of each of four arrays, as scratch for a search that may
    /// run over several calls while the tree does not grow (module `roadmap`): positions,
    /// parents and both child links; `None` when the tree's nodes reach into them. A node
    /// added later sets every field of its slot, so nothing written here is ever read as a
    /// node, and the slots stay as they were left while the tree has fewer than `N - n` nodes.
    #[cfg(feature = "roadmap")]
    #[allow(clippy::type_complexity)] // four arrays of the arena, named by the caller
    pub(crate) fn spare(
        &mut self,
        n: usize,
    ) -> Option<(&mut [Point], &mut [u16], &mut [u16], &mut [u16])> {
        let from = N.checked_sub(n)?;
        if usize::from(self.len) > from {
            return None;
        }
        Some((
            self.pos.get_mut(from..)?,
            self.parent.get_mut(from..)?,
            self.first_child.get_mut(from..)?,
            self.next_sibling.get_mut(from..)?,
        ))
    }

    /// The `k`-th `u16` from the end of [`Tree::spare`]'s third slice (what a roadmap search
    /// left there, `roadmap::resume`): read from the arena's slot `N - 1 - k`, `None` once
    /// that slot holds a node.
    #[cfg(feature = "roadmap")]
    pub(crate) fn spare_from_end(&self, k: usize) -> Option<u16> {
        let i = N.checked_sub(k)?.checked_sub(1)?;
        (i >= usize::from(self.len)).then(|| rd(&self.first_child, i, NONE))
    }

    /// Clears mark `m` from every node: O(len) byte writes.
    pub(crate) fn clear_marks(&mut self, m: Mark) {
        let n = self.len();
        for f in self.flags.iter_mut().take(n) {
            *f &= !(m as u8);
        }
    }

    /// Whether `id` names a node of this tree.
    #[inline]
    pub const fn contains(&self, id: NodeId) -> bool {
        id.0 < self.len
    }

    /// Removes every node and makes a single root at `pos`: O(1).
    pub fn reset(&mut self, pos: Point) -> NodeId {
        self.len = 1;
        self.root = 0;
        self.init_node(0, pos, NONE);
        wr(&mut self.cost, 0, 0.0);
        wr(&mut self.flags, 0, 0);
        NodeId(0)
    }

    /// Removes every node, the root included: O(1).
    pub fn clear(&mut self) {
        self.len = 0;
        self.root = 0;
    }

    /// The root, `None` for an empty tree.
    pub const fn root(&self) -> Option<NodeId> {
        if self.len == 0 {
            None
        } else {
            Some(NodeId(self.root))
        }
    }

    /// All node ids, `0..len`.
    pub fn ids(&self) -> impl DoubleEndedIterator<Item = NodeId> + ExactSizeIterator + use<N> {
        (0..self.len).map(NodeId)
    }

    /// The positions of all nodes, indexed by [`NodeId::index`] (what the spatial index reads).
    pub fn positions(&self) -> &[Point] {
        self.pos.get(..self.len as usize).unwrap_or(&[])
    }

    /// Position of a node.
    #[inline]
    pub fn position(&self, id: NodeId) -> Option<Point> {
        self.positions().get(id.index()).copied()
    }

    /// Cached cost of a node.
    #[inline]
    pub fn cost(&self, id: NodeId) -> Option<Cost> {
        self.contains(id).then(|| self.cost_of(id.0))
    }

    /// Parent of a node (`None` for the root or an unknown id).
    #[inline]
    pub fn parent(&self, id: NodeId) -> Option<NodeId> {
        if !self.contains(id) {
            return None;
        }
        let p = rd_link(&self.parent, id.index());
        (p != NONE).then_some(NodeId(p))
    }

    /// Edges from a node up to the root (`None` for an unknown id): at most `len` steps.
    pub fn depth(&self, id: NodeId) -> Option<usize> {
        if !self.contains(id) {
            return None;
        }
        let mut v = id;
        for d in 0..self.len as usize {
            match self.parent(v) {
                Some(p) => v = p,
                None => return Some(d),
            }
        }
        None // a cycle (never in a valid tree)
    }

    /// The first child of a node (the most recently attached), if any.
    pub fn first_child(&self, id: NodeId) -> Option<NodeId> {
        if !self.contains(id) {
            return None;
        }
        let c = rd_link(&self.first_child, id.index());
        (c != NONE).then_some(NodeId(c))
    }

    /// The next sibling of a node in its parent's child list, if any.
    pub fn next_sibling(&self, id: NodeId) -> Option<NodeId> {
        if !self.contains(id) {
            return None;
        }
        let s = rd_link(&self.next_sibling, id.index());
        (s != NONE).then_some(NodeId(s))
    }

    /// Whether the edge from the node's parent is marked as crossing a dynamic obstacle or a
    /// cell the live overlay marked.
    pub fn edge_blocked(&self, id: NodeId) -> Option<bool> {
        self.contains(id)
            .then(|| rd(&self.flags, id.index(), 0) & EDGE_ANY != 0)
    }

    /// Why the edge from the node's parent is blocked: `(by an obstacle, by a marked cell)`.
    pub(crate) fn edge_sources(&self, id: NodeId) -> (bool, bool) {
        let f = rd(&self.flags, id.index(), 0);
        (f & EDGE_BLOCKED != 0, f & EDGE_WALLED != 0)
    }

    /// Sets the walled flag of the edge from `child`'s parent (see [`Tree::rewall_edges`]) and
    /// updates the subtree's costs.
    pub(crate) fn set_edge_walled(&mut self, child: NodeId, walled: bool) {
        if self.contains(child) && rd_link(&self.parent, child.index()) != NONE {
            self.set_flag(child.0, EDGE_WALLED, walled);
            self.refresh_subtree(child.0);
        }
    }

    /// The children of a node, most recently attached first.
    pub fn children(&self, id: NodeId) -> Children<'_, N> {
        let first = if self.contains(id) {
            rd_link(&self.first_child, id.index())
        } else {
            NONE
        };
        Children {
            tree: self,
            next: first,
        }
    }

    /// Whether `node` lies in the subtree of `top` (a node is in its own subtree). Walks up from
    /// `node`: O(depth).
    pub fn in_subtree(&self, node: NodeId, top: NodeId) -> bool {
        if !self.contains(node) || !self.contains(top) {
            return false;
        }
        let mut v = node.0;
        for _ in 0..=self.len {
            if v == top.0 {
                return true;
            }
            if v == NONE {
                return false;
            }
            v = rd_link(&self.parent, v as usize);
        }
        false
    }

    /// Adds a node at `pos` as a child of `parent` over `edge` (a `bool` marks the new edge as
    /// crossing a dynamic obstacle; an [`Edge`] gives its clearance class too). `Err(Full)`
    /// when the arena is full.
    pub fn add(
        &mut self,
        pos: Point,
        parent: NodeId,
        edge: impl Into<Edge>,
    ) -> Result<NodeId, TreeError> {
        let edge = edge.into();
        if !self.contains(parent) {
            return Err(TreeError::UnknownNode);
        }
        if self.is_full() {
            return Err(TreeError::Full);
        }
        let id = self.len;
        self.len = self.len.saturating_add(1);
        self.init_node(id, pos, NONE);
        self.link(id, parent.0);
        wr(
            &mut self.flags,
            id as usize,
            if edge.blocked { EDGE_BLOCKED } else { 0 } | class_bits(edge.class),
        );
        self.refresh_cost(id);
        Ok(NodeId(id))
    }

    /// `UpdateEdge`: makes `parent` the parent of `child` over `edge` (its blocked flag, and
    /// its clearance class when an [`Edge`] is given), and updates the cached costs of the
    /// whole moved subtree. Returns the size of the moved subtree (the work done).
    /// `Err(WouldCycle)` when `parent` lies in `child`'s subtree (which includes `child == root`).
    pub fn set_parent(
        &mut self,
        child: NodeId,
        parent: NodeId,
        edge: impl Into<Edge>,
    ) -> Result<usize, TreeError> {
        let edge = edge.into();
        if !self.contains(child) || !self.contains(parent) {
            return Err(TreeError::UnknownNode);
        }
        if self.in_subtree(parent, child) {
            return Err(TreeError::WouldCycle);
        }
        let c = child.0;
        self.unlink(c);
        self.link(c, parent.0);
        self.set_flag(c, EDGE_BLOCKED, edge.blocked);
        // A new edge was tested against the live cells (`free_path`).
        self.set_flag(c, EDGE_WALLED, false);
        self.set_flag(c, CLASS_BITS, false);
        self.set_flag(c, class_bits(edge.class), true);
        Ok(self.refresh_subtree(c))
    }

    /// The clearance class of the edge from `id`'s parent (0 for the root).
    pub fn edge_class(&self, id: NodeId) -> Option<u8> {
        self.contains(id)
            .then(|| (rd(&self.flags, id.index(), 0) & CLASS_BITS) >> CLASS_SHIFT)
    }

    /// Sets the blocked flag of the edge from `child`'s parent and updates the subtree's costs.
    pub fn set_edge_blocked(&mut self, child: NodeId, blocked: bool) -> Result<(), TreeError> {
        if !self.contains(child) {
            return Err(TreeError::UnknownNode);
        }
        if rd_link(&self.parent, child.index()) != NONE {
            self.set_flag(child.0, EDGE_BLOCKED, blocked);
            self.refresh_subtree(child.0);
        }
        Ok(())
    }

    /// Sets every edge's blocked flag from `blocked(parent position, child position)` and then
    /// recomputes every cost: O(N) calls. Used when dynamic obstacles appear, move or
    /// disappear. Returns whether some flag changed.
    pub fn reflag_edges<F>(&mut self, mut blocked: F) -> bool
    where
        F: FnMut(Point, Point) -> bool,
    {
        let mut changed = false;
        for v in 0..self.len {
            let p = rd_link(&self.parent, v as usize);
            let b = p != NONE
                && blocked(
                    rd(&self.pos, p as usize, Point::ZERO),
                    rd(&self.pos, v as usize, Point::ZERO),
                );
            changed |= (rd(&self.flags, v as usize, 0) & EDGE_BLOCKED != 0) != b;
            self.set_flag(v, EDGE_BLOCKED, b);
        }
        self.refresh_subtree(self.root);
        changed
    }

    /// Sets the walled flag of every edge `walled(parent position, child position)` decides
    /// (`None` leaves it: the planner asks only about edges near the cells that changed), then
    /// recomputes every cost when one changed: O(N) calls. Returns whether some flag changed.
    pub fn rewall_edges<F>(&mut self, mut walled: F) -> bool
    where
        F: FnMut(Point, Point) -> Option<bool>,
    {
        let mut changed = false;
        for v in 0..self.len {
            let p = rd_link(&self.parent, v as usize);
            if p == NONE {
                continue;
            }
            let (a, b) = (
                rd(&self.pos, p as usize, Point::ZERO),
                rd(&self.pos, v as usize, Point::ZERO),
            );
            if let Some(w) = walled(a, b) {
                changed |= (rd(&self.flags, v as usize, 0) & EDGE_WALLED != 0) != w;
                self.set_flag(v, EDGE_WALLED, w);
            }
        }
        if changed {
            self.refresh_subtree(self.root);
        }
        changed
    }

    /// `SetRoot`: re-roots the tree at `new_root` by reversing the edges on the path from the
    /// old root (each edge keeps its blocked flag and clearance class), then recomputes every
    /// cost: O(depth + N).
    pub fn set_root(&mut self, new_root: NodeId) -> Result<(), TreeError> {
        if !self.contains(new_root) {
            return Err(TreeError::UnknownNode);
        }
        let mut prev = NONE;
        let mut prev_flag = 0;
        let mut cur = new_root.0;
        for _ in 0..self.len {
            if cur == NONE {
                break;
            }
            let next = rd_link(&self.parent, cur as usize);
            let flag = rd(&self.flags, cur as usize, 0) & EDGE_OWN;
            self.unlink(cur);
            if prev != NONE {
                self.link(cur, prev);
            }
            // The edge between `prev` and `cur` now hangs below `prev`; it keeps its flags,
            // which were stored at `prev` while `cur` was its parent.
            if let Some(f) = self.flags.get_mut(cur as usize) {
                *f = (*f & !EDGE_OWN) | prev_flag;
            }
            prev_flag = flag;
            prev = cur;
            cur = next;
        }
        self.root = new_root.0;
        self.refresh_subtree(self.root);
        Ok(())
    }

    /// Removes a leaf (a node without children, not the root) and frees its slot: O(1) plus
    /// the moved node's children. Ids stay dense, so the last node moves into the freed slot:
    /// the result is `Some((old, new))` when a node changed id that way (every id held
    /// elsewhere must be renamed), `None` when the removed node was the last one.
    pub fn remove_leaf(&mut self, id: NodeId) -> Result<Option<(NodeId, NodeId)>, TreeError> {
        if !self.contains(id) {
            return Err(TreeError::UnknownNode);
        }
        if id.0 == self.root || rd_link(&self.first_child, id.index()) != NONE {
            return Err(TreeError::NotALeaf);
        }
        self.unlink(id.0);
        let last = self.len.saturating_sub(1);
        self.len = last;
        if id.0 == last {
            return Ok(None);
        }
        // Move `last` into `id`'s slot and point every link at it.
        let (from, to) = (last as usize, id.index());
        copy_slot(&mut self.pos, from, to);
        copy_slot(&mut self.cost, from, to);
        copy_slot(&mut self.flags, from, to);
        let parent = rd_link(&self.parent, from);
        // The link that points at `last` (its parent's first child, or its previous sibling).
        let prev = self.prev_sibling(last);
        copy_slot(&mut self.parent, from, to);
        copy_slot(&mut self.next_sibling, from, to);
        copy_slot(&mut self.first_child, from, to);
        if prev != NONE {
            wr_link(&mut self.next_sibling, prev as usize, id.0);
        } else if parent != NONE {
            wr_link(&mut self.first_child, parent as usize, id.0);
        }
        let mut c = rd_link(&self.first_child, to);
        for _ in 0..self.len {
            if c == NONE {
                break;
            }
            wr_link(&mut self.parent, c as usize, id.0);
            c = rd_link(&self.next_sibling, c as usize);
        }
        if self.root == last {
            self.root = id.0;
        }
        Ok(Some((NodeId(last), id)))
    }

    /// Writes the path from the root to `to` (both included, root first) into `buf` and returns
    /// its number of nodes. `Err(BufferTooSmall)` leaves `buf`'s contents unspecified.
    pub fn path_ids(&self, to: NodeId, buf: &mut [NodeId]) -> Result<usize, TreeError> {
        self.write_path(to, buf, NodeId)
    }

    /// Like [`Tree::path_ids`], writing positions.
    pub fn path_points(&self, to: NodeId, buf: &mut [Point]) -> Result<usize, TreeError> {
        self.write_path(to, buf, |v| rd(&self.pos, v as usize, Point::ZERO))
    }

    /// Walks from `to` up to the root writing `item(node)` for each, then reverses.
    fn write_path<T>(
        &self,
        to: NodeId,
        buf: &mut [T],
        item: impl Fn(u16) -> T,
    ) -> Result<usize, TreeError> {
        if !self.contains(to) {
            return Err(TreeError::UnknownNode);
        }
        let mut n = 0;
        let mut v = to.0;
        while v != NONE {
            if n >= self.len as usize {
                // Only a corrupted tree could get here; refuse rather than loop.
                return Err(TreeError::WouldCycle);
            }
            *buf.get_mut(n).ok_or(TreeError::BufferTooSmall)? = item(v);
            n = n.saturating_add(1);
            v = rd_link(&self.parent, v as usize);
        }
        if let Some(path) = buf.get_mut(..n) {
            reverse(path);
        }
        Ok(n)
    }

    /// Checks every structural invariant (O(N * depth)): the root has no parent and every
    /// other node has one; links stay in range; parent and child lists agree; every node
    /// reaches the root (so there is no cycle); cached costs equal recomputed costs.
    pub fn validate(&self) -> Result<(), Invariant> {
        let n = self.len;
        if n == 0 {
            return Ok(());
        }
        let ok = |v: u16| v == NONE || v < n;
        for v in 0..n {
            let i = v as usize;
            let id = NodeId(v);
            let links = [
                rd_link(&self.parent, i),
                rd_link(&self.first_child, i),
                rd_link(&self.next_sibling, i),
            ];
            if !links.iter().all(|&l| ok(l)) {
                return Err(Invariant::DanglingLink(id));
            }
            if (v == self.root) != (rd_link(&self.parent, i) == NONE) {
                return Err(Invariant::RootParent(id));
            }
            // Reaches the root within n steps.
            if !self.in_subtree(id, NodeId(self.root)) {
                return Err(Invariant::NotConnected(id));
            }
            // Every child lists this node as parent, and the list ends.
            let mut c = rd_link(&self.first_child, i);
            let mut count = 0u16;
            while c != NONE {
                count = count.saturating_add(1);
                if count > n || rd_link(&self.parent, c as usize) != v {
                    return Err(Invariant::ChildList(id));
                }
                c = rd_link(&self.next_sibling, c as usize);
            }
            // And this node appears in its parent's list.
            let p = rd_link(&self.parent, i);
            if p != NONE && !self.children(NodeId(p)).any(|c| c == id) {
                return Err(Invariant::ChildList(id));
            }
        }
        // Costs: the root costs zero and every other node costs its parent's cost plus the
        // edge. With connectivity checked above this recurrence, checked locally at every node,
        // means by induction that each cached cost equals the sum along its root path.
        for v in 0..n {
            let i = v as usize;
            let p = rd_link(&self.parent, i);
            let expected = if p == NONE {
                Cost::ZERO
            } else {
                self.cost_of(p)
                    .extend(self.edge_len(p, v), rd(&self.flags, i, 0) & EDGE_ANY != 0)
            };
            let cached = self.cost_of(v);
            if cached.blocked != expected.blocked
                || cached.length.to_bits() != expected.length.to_bits()
            {
                return Err(Invariant::StaleCost(NodeId(v)));
            }
        }
        Ok(())
    }

    // --- internals (ids here are known to be < len) ---

    fn cost_of(&self, v: u16) -> Cost {
        Cost {
            length: rd(&self.cost, v as usize, 0.0),
            blocked: rd(&self.flags, v as usize, 0) & PATH_BLOCKED != 0,
        }
    }

    fn init_node(&mut self, id: u16, pos: Point, parent: u16) {
        let i = id as usize;
        wr(&mut self.pos, i, pos);
        wr_link(&mut self.parent, i, parent);
        wr_link(&mut self.first_child, i, NONE);
        wr_link(&mut self.next_sibling, i, NONE);
    }

    fn set_flag(&mut self, v: u16, bit: u8, on: bool) {
        if let Some(f) = self.flags.get_mut(v as usize) {
            *f = if on { *f | bit } else { *f & !bit };
        }
    }

    /// Pushes `c` (currently detached) at the front of `p`'s child list.
    fn link(&mut self, c: u16, p: u16) {
        let first = rd_link(&self.first_child, p as usize);
        wr_link(&mut self.parent, c as usize, p);
        wr_link(&mut self.next_sibling, c as usize, first);
        wr_link(&mut self.first_child, p as usize, c);
    }

    /// Detaches `c` from its parent's child list (no-op for a detached node).
    fn unlink(&mut self, c: u16) {
        let p = rd_link(&self.parent, c as usize);
        if p == NONE {
            return;
        }
        let prev = self.prev_sibling(c);
        let next = rd_link(&self.next_sibling, c as usize);
        if prev == NONE {
            wr_link(&mut self.first_child, p as usize, next);
        } else {
            wr_link(&mut self.next_sibling, prev as usize, next);
        }
        wr_link(&mut self.parent, c as usize, NONE);
        wr_link(&mut self.next_sibling, c as usize, NONE);
    }

    /// The sibling listed just before `c` in its parent's child list (`NONE` when `c` is the
    /// first child or the root). The list is singly linked (one link less per node), so this
    /// walks it: O(children of the parent).
    fn prev_sibling(&self, c: u16) -> u16 {
        let p = rd_link(&self.parent, c as usize);
        if p == NONE {
            return NONE;
        }
        let mut prev = NONE;
        let mut v = rd_link(&self.first_child, p as usize);
        for _ in 0..self.len {
            if v == c || v == NONE {
                break;
            }
            prev = v;
            v = rd_link(&self.next_sibling, v as usize);
        }
        prev
    }

    /// The charged length of the edge from `p` to its child `v` ([`charged`]).
    fn edge_len(&self, p: u16, v: u16) -> f32 {
        let d = rd(&self.pos, p as usize, Point::ZERO).dist(rd(&self.pos, v as usize, Point::ZERO));
        let class = (rd(&self.flags, v as usize, 0) & CLASS_BITS) >> CLASS_SHIFT;
        charged(d, class, self.weight)
    }

    /// Recomputes the cached cost of `v` from its parent's.
    fn refresh_cost(&mut self, v: u16) {
        let i = v as usize;
        let p = rd_link(&self.parent, i);
        if p == NONE {
            wr(&mut self.cost, i, 0.0);
            self.set_flag(v, PATH_BLOCKED, false);
            return;
        }
        let c = self
            .cost_of(p)
            .extend(self.edge_len(p, v), rd(&self.flags, i, 0) & EDGE_ANY != 0);
        wr(&mut self.cost, i, c.length);
        self.set_flag(v, PATH_BLOCKED, c.blocked);
    }

    /// The size of `top`'s subtree, counted up to `limit` (a walk of the links, no cost
    /// computed: a fraction of what refreshing the subtree's costs takes). 0 for an unknown
    /// node.
    pub fn subtree_len(&self, top: NodeId, limit: usize) -> usize {
        if !self.contains(top) {
            return 0;
        }
        let mut v = top.0;
        for done in 1..limit.min(self.len as usize) {
            match self.next_preorder(v, top.0) {
                Some(next) => v = next,
                None => return done,
            }
        }
        limit.min(self.len as usize)
    }

    /// Recomputes the costs of `top`'s whole subtree in preorder (parents before children),
    /// walking the intrusive links: no stack, O(subtree size). Returns the subtree's size.
    fn refresh_subtree(&mut self, top: u16) -> usize {
        let mut v = top;
        for done in 1..=self.len as usize {
            self.refresh_cost(v);
            match self.next_preorder(v, top) {
                Some(next) => v = next,
                None => return done,
            }
        }
        self.len as usize
    }

    /// The node after `v` in a preorder walk of `top`'s subtree.
    fn next_preorder(&self, v: u16, top: u16) -> Option<u16> {
        let fc = rd_link(&self.first_child, v as usize);
        if fc != NONE {
            return Some(fc);
        }
        let mut u = v;
        for _ in 0..self.len {
            if u == top {
                return None;
            }
            let s = rd_link(&self.next_sibling, u as usize);
            if s != NONE {
                return Some(s);
            }
            u = rd_link(&self.parent, u as usize);
            if u == NONE {
                return None;
            }
        }
        None
    }
}

/// Iterator over the children of a node.
#[derive(Clone, Debug)]
pub struct Children<'t, const N: usize> {
    tree: &'t Tree<N>,
    next: u16,
}

impl<const N: usize> Iterator for Children<'_, N> {
    type Item = NodeId;
    fn next(&mut self) -> Option<NodeId> {
        if self.next == NONE {
            return None;
        }
        let c = self.next;
        self.next = rd_link(&self.tree.next_sibling, c as usize);
        Some(NodeId(c))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f32, y: f32) -> Point {
        Point::new(x, y)
    }

    #[test]
    fn costs_follow_edges_and_reroot() {
        let mut t = Tree::<8>::new();
        let r = t.reset(p(0.0, 0.0));
        let a = t.add(p(3.0, 0.0), r, false).unwrap();
        let b = t.add(p(3.0, 4.0), a, false).unwrap();
        let c = t.add(p(0.0, 4.0), b, true).unwrap();
        assert_eq!(t.cost(b).unwrap().length, 7.0);
        assert_eq!(
            t.cost(c).unwrap(),
            Cost {
                length: 10.0,
                blocked: true
            }
        );
        // Shortcut c to the root: c's cost drops and it is no longer blocked.
        t.set_parent(c, r, false).unwrap();
        assert_eq!(
            t.cost(c).unwrap(),
            Cost {
                length: 4.0,
                blocked: false
            }
        );
        // b below c: b's cost follows.
        t.set_parent(b, c, false).unwrap();
        assert_eq!(t.cost(b).unwrap().length, 7.0);
        assert_eq!(t.set_parent(c, b, false), Err(TreeError::WouldCycle));
        assert_eq!(t.set_parent(r, a, false), Err(TreeError::WouldCycle));
        t.validate().unwrap();
        // Re-root at b: path r -> c -> b reverses.
        t.set_edge_blocked(b, true).unwrap();
        t.set_root(b).unwrap();
        t.validate().unwrap();
        assert_eq!(t.root(), Some(b));
        assert_eq!(t.subtree_len(b, 100), t.len());
        assert_eq!(t.subtree_len(b, 2), 2);
        assert_eq!(t.subtree_len(c, 100), 3, "c carries r and a");
        assert_eq!(t.subtree_len(a, 100), 1);
        assert_eq!(t.parent(c), Some(b));
        assert_eq!(t.parent(r), Some(c));
        assert_eq!(t.edge_blocked(c), Some(true), "the c-b edge keeps its flag");
        assert_eq!(
            t.cost(r).unwrap(),
            Cost {
                length: 7.0,
                blocked: true
            }
        );
        assert_eq!(t.cost(a).unwrap().length, 10.0);
        let mut buf = [NodeId(0); 8];
        let n = t.path_ids(a, &mut buf).unwrap();
        assert_eq!(&buf[..n], &[b, c, r, a]);
        let mut small = [Point::ZERO; 2];
        assert_eq!(t.path_points(a, &mut small), Err(TreeError::BufferTooSmall));
    }

    /// `Cost::sort_key` orders as `Cost::cmp` does, on every kind of length.
    #[test]
    fn sort_keys_order_as_costs_do() {
        let lengths = [
            f32::NEG_INFINITY,
            -3.5,
            -0.0,
            0.0,
            1e-30,
            1.0,
            1.000_000_1,
            7.25e9,
            f32::INFINITY,
            f32::NAN,
            -f32::NAN,
        ];
        let mut costs = heapless::Vec::<Cost, 32>::new();
        for blocked in [false, true] {
            for &length in &lengths {
                costs.push(Cost { length, blocked }).unwrap();
            }
        }
        for a in &costs {
            for b in &costs {
                assert_eq!(a.sort_key().cmp(&b.sort_key()), a.cmp(b), "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn full_arena_is_an_error_and_changes_nothing() {
        let mut t = Tree::<2>::new();
        let r = t.reset(p(0.0, 0.0));
        t.add(p(1.0, 0.0), r, false).unwrap();
        let before = t.clone();
        assert_eq!(t.add(p(2.0, 0.0), r, false), Err(TreeError::Full));
        assert_eq!(t.positions(), before.positions());
        assert_eq!(
            t.add(p(2.0, 0.0), NodeId(5), false),
            Err(TreeError::UnknownNode)
        );
        t.reset(p(4.0, 4.0));
        assert_eq!(t.len(), 1);
        t.validate().unwrap();
    }
}
