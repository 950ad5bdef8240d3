//! Spatial index over a tree's nodes: Euclidean nearest and within-radius queries (the paper's
//! `Nearest` and `Nearby`) whose cost grows with the neighbourhood, not with the tree.
//!
//! A fixed grid of at most `B` square buckets covers the map; each bucket keeps an intrusive
//! singly linked list of node ids: one `u16` per node (its successor, which also says whether
//! it is indexed) and one per bucket, nothing allocated, and all zero when empty. A node's
//! bucket follows from its position, so removal takes the position and walks that bucket. A within-radius
//! query visits only the buckets that overlap the query disc's bounding box. A nearest query
//! visits square rings of buckets outward from the query's bucket and stops as soon as the ring
//! still to come cannot hold anything closer than the best found. With buckets about the size
//! of the planner's neighbourhood radius (`e_max`) a `Nearby` query reads 9 buckets.
//!
//! The index stores ids only; queries read positions from the slice the tree exposes
//! ([`crate::tree::Tree::positions`]), so a node must keep its position while it is indexed
//! (tree nodes never move). [`linear_nearest`] and [`linear_within`] are the brute-force
//! oracles the tests compare against.

use core::ops::ControlFlow;

use crate::error::IndexError;
use crate::geometry::Point;
use crate::slots::{cell_index, rd, rd_link, sat_u32, to_u16, wr, wr_link};
use crate::tree::NodeId;

const NONE: u16 = u16::MAX;
/// `next` slot of a node that is not indexed (the all-zero state).
const OUT: u16 = 0;
/// `next` slot of an indexed node that ends its bucket's list; otherwise the slot holds the
/// successor's id + 1 (ids are below `u16::MAX - 1`).
const END: u16 = u16::MAX;

/// A bucket grid over `[0, width] x [0, height]` indexing up to `N` nodes in at most `B`
/// buckets.
#[derive(Clone, Debug)]
pub struct SpatialIndex<const N: usize, const B: usize> {
    /// First node of each bucket, as a link (`id + 1`, 0 for none).
    head: [u16; B],
    /// Per node: [`OUT`], [`END`] or the successor's id + 1.
    next: [u16; N],
    /// Bucket columns and rows (0 x 0 until shaped: then one bucket covers everything).
    cols: u16,
    rows: u16,
    side: f32,
    inv_side: f32,
    len: usize,
    /// One past the highest id indexed since the last clear: `clear` resets only
    /// `next[..hi]` (a reverse tree of a few nodes is cleared in nanoseconds, not by
    /// rewriting all `N` links).
    hi: usize,
}

impl<const N: usize, const B: usize> Default for SpatialIndex<N, B> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, const B: usize> SpatialIndex<N, B> {
    const SIZES_FIT: () = assert!(
        N > 0 && N < END as usize - 1 && B > 0 && B < NONE as usize,
        "SpatialIndex capacities must be 1..65535"
    );

    /// An empty index with a single bucket (give it a shape with [`SpatialIndex::reshape`]).
    /// A `const fn` whose value is all zero bytes, so an index in a `static` lands in `.bss`.
    pub const fn new() -> Self {
        let () = Self::SIZES_FIT;
        Self {
            head: [0; B],
            next: [OUT; N],
            cols: 0,
            rows: 0,
            side: 0.0,
            inv_side: 0.0,
            len: 0,
            hi: 0,
        }
    }

    /// An empty index over a `width x height` metre map with square buckets of side at least
    /// `min_side` metres (larger when `B` buckets of that side would not cover the map).
    /// `None` unless all three are finite and positive.
    pub fn with_bounds(width: f32, height: f32, min_side: f32) -> Option<Self> {
        let mut idx = Self::new();
        idx.reshape(width, height, min_side).then_some(idx)
    }

    /// Empties the index and lays its buckets over a `width x height` metre map (as
    /// [`SpatialIndex::with_bounds`]). Returns `false`, leaving the index unchanged, unless all
    /// three are finite and positive.
    // The f64 counts are whole numbers in 1..=B < 65,535 once checked, and the f32 side is
    // checked finite and positive: the casts cannot truncate.
    #[allow(clippy::cast_possible_truncation, clippy::cast_sign_loss)]
    pub fn reshape(&mut self, width: f32, height: f32, min_side: f32) -> bool {
        let good = |v: f32| v.is_finite() && v > 0.0;
        if !(good(width) && good(height) && good(min_side)) {
            return false;
        }
        // In f64: width * height overflows f32 for maps near its range.
        let (w, h) = (width as f64, height as f64);
        let area_side = libm::sqrt(w * h / B as f64);
        let mut side = (min_side as f64).max(area_side);
        let count = |s: f64| (libm::ceil(w / s).max(1.0), libm::ceil(h / s).max(1.0));
        // Rounding up can overshoot B a little: grow the side until it fits (a few steps).
        for _ in 0..64 {
            let (c, r) = count(side);
            if c * r <= B as f64 {
                break;
            }
            side *= 1.05;
        }
        let (c, r) = count(side);
        let side = side as f32;
        // The grid's extent and the inverse side must stay finite and positive in f32.
        let usable = |v: f32| v.is_finite() && v > 0.0;
        if c * r > B as f64
            || !usable(side)
            || !usable(1.0 / side)
            || !usable(c as f32 * side)
            || !usable(r as f32 * side)
        {
            return false;
        }
        self.clear();
        self.cols = c as u16;
        self.rows = r as u16;
        self.side = side;
        self.inv_side = 1.0 / side;
        true
    }

    /// Side of a bucket in metres.
    pub fn bucket_side(&self) -> f32 {
        self.side
    }

    /// Buckets per row and per column.
    pub fn shape(&self) -> (u16, u16) {
        (self.cols.max(1), self.rows.max(1))
    }

    /// Number of indexed nodes.
    pub fn len(&self) -> usize {
        self.len
    }

    /// Whether nothing is indexed.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Whether `id` is indexed.
    pub fn contains(&self, id: NodeId) -> bool {
        self.next.get(id.index()).is_some_and(|&n| n != OUT)
    }

    /// Removes every node: O(the ids and buckets in use), nothing at all when no node was
    /// indexed since the last clear. Only the buckets of the current shape can hold a node
    /// (a [`SpatialIndex::reshape`] clears before it changes the shape), so the others stay
    /// zero; a planner made afresh clears its reverse tree's index, and the first goal's
    /// clear then does not write its `B` heads again (cold caches: 4 KB of writes a query).
    pub fn clear(&mut self) {
        if self.hi == 0 {
            return;
        }
        let (c, r) = self.shape();
        let used = usize::from(c).saturating_mul(usize::from(r));
        match self.head.get_mut(..used) {
            Some(heads) => heads.fill(0),
            None => self.head.fill(0),
        }
        match self.next.get_mut(..self.hi) {
            Some(used) => used.fill(OUT),
            None => self.next.fill(OUT),
        }
        self.len = 0;
        self.hi = 0;
    }

    /// The bucket of position `p`.
    fn bucket(&self, p: Point) -> usize {
        let (c, r) = self.bucket_coords(p);
        cell_index(c, r, self.shape().0)
    }

    /// Indexes node `id` at position `p`. Positions outside the map go to the nearest border
    /// bucket (queries stay exact).
    pub fn insert(&mut self, id: NodeId, p: Point) -> Result<(), IndexError> {
        let i = id.index();
        if i >= N {
            return Err(IndexError::IdOutOfRange);
        }
        if !p.is_finite() {
            return Err(IndexError::NotFinite);
        }
        if self.contains(id) {
            return Err(IndexError::Membership);
        }
        let b = self.bucket(p);
        let first = rd_link(&self.head, b);
        wr(
            &mut self.next,
            i,
            if first == NONE {
                END
            } else {
                first.wrapping_add(1)
            },
        );
        wr_link(&mut self.head, b, id.0);
        self.len = self.len.saturating_add(1);
        self.hi = self.hi.max(i.saturating_add(1));
        Ok(())
    }

    /// Removes node `id`, indexed at position `p`: O(nodes in its bucket).
    pub fn remove(&mut self, id: NodeId, p: Point) -> Result<(), IndexError> {
        let i = id.index();
        if i >= N {
            return Err(IndexError::IdOutOfRange);
        }
        if !self.contains(id) || !p.is_finite() {
            return Err(IndexError::Membership);
        }
        let b = self.bucket(p);
        let after = self.successor(id.0);
        // Find the link that points at `id`: the bucket head or a predecessor's `next`.
        let mut prev = NONE;
        let mut v = rd_link(&self.head, b);
        for _ in 0..N {
            if v == id.0 || v == NONE {
                break;
            }
            prev = v;
            v = self.successor(v);
        }
        if v != id.0 {
            // Not in the bucket of `p`: indexed at another position.
            return Err(IndexError::Membership);
        }
        if prev == NONE {
            wr_link(&mut self.head, b, after);
        } else {
            wr(
                &mut self.next,
                prev as usize,
                if after == NONE {
                    END
                } else {
                    after.wrapping_add(1)
                },
            );
        }
        wr(&mut self.next, i, OUT);
        self.len = self.len.saturating_sub(1);
        Ok(())
    }

    /// The node after `v` in its bucket, `NONE` at the end (or for a node not indexed).
    #[inline]
    fn successor(&self, v: u16) -> u16 {
        match rd(&self.next, v as usize, OUT) {
            OUT | END => NONE,
            n => n.wrapping_sub(1),
        }
    }

    /// Whether at least `k` indexed nodes other than `id` share the bucket of `p` (the
    /// position of `id`), counting no further than that. Returns the answer and the nodes
    /// visited.
    pub fn bucket_has_others(&self, id: NodeId, p: Point, k: u16) -> (bool, u32) {
        let (c, r) = self.bucket_coords(p);
        let b = cell_index(c, r, self.shape().0);
        let (mut others, mut seen) = (0u16, 0u32);
        let _ = self.for_each_in_bucket(b, |n| {
            seen = seen.saturating_add(1);
            if n != id {
                others = others.saturating_add(1);
            }
            if others >= k {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        });
        (others >= k, seen)
    }

    /// The indexed node nearest to `q` (Euclidean) with its squared distance.
    pub fn nearest(&self, q: Point, positions: &[Point]) -> Option<(NodeId, f32)> {
        self.nearest_where(q, positions, |_| true)
    }

    /// The nearest indexed node among those for which `accept` is true.
    #[allow(clippy::arithmetic_side_effects)] // bucket coordinates and rings < 65,536: no i32 overflow
    pub fn nearest_where<F>(
        &self,
        q: Point,
        positions: &[Point],
        mut accept: F,
    ) -> Option<(NodeId, f32)>
    where
        F: FnMut(NodeId) -> bool,
    {
        if self.len == 0 || !q.is_finite() {
            return None;
        }
        if Self::scan_is_cheaper(positions.len(), self.bucket_count() / 4) {
            let mut best: Option<(NodeId, f32)> = None;
            for (i, p) in positions.iter().enumerate() {
                let id = NodeId(to_u16(i));
                let d2 = p.dist_sq(q);
                if best.is_none_or(|(_, bd)| d2 < bd) && self.contains(id) && accept(id) {
                    best = Some((id, d2));
                }
            }
            return best;
        }
        let (qc, qr) = self.bucket_coords(q);
        let (qc, qr) = (qc as i32, qr as i32);
        let (cols, rows) = self.shape();
        // Distances to every indexed point are at least the distances from q's projection onto
        // the grid rectangle (points lie in it and projection onto a convex set does not
        // increase distances), so ring bounds are computed from the projection.
        let qp = Point::new(
            q.x.max(0.0).min(cols as f32 * self.side),
            q.y.max(0.0).min(rows as f32 * self.side),
        );
        let max_ring = (qc.max(cols as i32 - 1 - qc)).max(qr.max(rows as i32 - 1 - qr));
        let mut best: Option<(NodeId, f32)> = None;
        for k in 0..=max_ring {
            if let Some((_, d2)) = best {
                // Everything not yet visited lies outside the square of rings 0..k-1.
                let s = self.side;
                let lo_x = (qc - k + 1) as f32 * s;
                let hi_x = (qc + k) as f32 * s;
                let lo_y = (qr - k + 1) as f32 * s;
                let hi_y = (qr + k) as f32 * s;
                let gap = (qp.x - lo_x)
                    .min(hi_x - qp.x)
                    .min(qp.y - lo_y)
                    .min(hi_y - qp.y);
                if gap > 0.0 && gap * gap >= d2 {
                    break;
                }
            }
            let _ = self.for_each_ring_bucket(qc, qr, k, |b| {
                self.for_each_in_bucket(b, |id| {
                    if let Some(p) = positions.get(id.index()) {
                        let d2 = p.dist_sq(q);
                        if best.is_none_or(|(_, bd)| d2 < bd) && accept(id) {
                            best = Some((id, d2));
                        }
                    }
                    ControlFlow::Continue(())
                })
            });
        }
        best
    }

    /// Calls `f(id, squared distance)` for every indexed node within `radius` of `q` (closed
    /// disc), stopping early if `f` breaks.
    pub fn for_each_within<F>(
        &self,
        q: Point,
        radius: f32,
        positions: &[Point],
        mut f: F,
    ) -> ControlFlow<()>
    where
        F: FnMut(NodeId, f32) -> ControlFlow<()>,
    {
        if !q.is_finite() || radius.is_nan() || radius < 0.0 {
            return ControlFlow::Continue(());
        }
        let r2 = radius * radius;
        let (c0, r0) = self.bucket_coords(Point::new(q.x - radius, q.y - radius));
        let (c1, r1) = self.bucket_coords(Point::new(q.x + radius, q.y + radius));
        let span = |lo: u16, hi: u16| usize::from(hi.saturating_sub(lo)).saturating_add(1);
        let boxed = span(c0, c1).saturating_mul(span(r0, r1));
        if Self::scan_is_cheaper(positions.len(), boxed) {
            for (i, p) in positions.iter().enumerate() {
                let id = NodeId(to_u16(i));
                let d2 = p.dist_sq(q);
                if d2 <= r2 && self.contains(id) {
                    f(id, d2)?;
                }
            }
            return ControlFlow::Continue(());
        }
        for row in r0..=r1 {
            for col in c0..=c1 {
                let b = cell_index(col, row, self.shape().0);
                self.for_each_in_bucket(b, |id| match positions.get(id.index()) {
                    Some(p) => {
                        let d2 = p.dist_sq(q);
                        if d2 <= r2 {
                            f(id, d2)
                        } else {
                            ControlFlow::Continue(())
                        }
                    }
                    None => ControlFlow::Continue(()),
                })?;
            }
        }
        ControlFlow::Continue(())
    }

    /// Collects into `out` the nodes within `radius` of `q`. Returns the number found, which
    /// exceeds `out`'s capacity when some did not fit (the first ones found are kept).
    pub fn within<const K: usize>(
        &self,
        q: Point,
        radius: f32,
        positions: &[Point],
        out: &mut heapless::Vec<NodeId, K>,
    ) -> usize {
        out.clear();
        let mut found: usize = 0;
        let _ = self.for_each_within(q, radius, positions, |id, _| {
            found = found.saturating_add(1);
            let _ = out.push(id);
            ControlFlow::Continue(())
        });
        found
    }

    /// Number of buckets in the grid.
    fn bucket_count(&self) -> usize {
        let (cols, rows) = self.shape();
        usize::from(cols).saturating_mul(usize::from(rows))
    }

    /// Whether reading all `nodes` positions costs less than visiting `buckets` buckets: a
    /// small tree on a large grid, where most buckets are empty (a search tree of a dozen
    /// nodes on a 40 x 40 grid). The answer is the same either way (only the order in which
    /// nodes at equal distances are met may differ).
    fn scan_is_cheaper(nodes: usize, buckets: usize) -> bool {
        nodes <= buckets
    }

    fn bucket_coords(&self, p: Point) -> (u16, u16) {
        // Saturating float-to-int casts map NaN and negatives to 0; clamp the far side.
        let (cols, rows) = self.shape();
        let c = to_u16(sat_u32(p.x * self.inv_side).min(u32::from(cols).saturating_sub(1)));
        let r = to_u16(sat_u32(p.y * self.inv_side).min(u32::from(rows).saturating_sub(1)));
        (c, r)
    }

    fn for_each_in_bucket<F>(&self, b: usize, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(NodeId) -> ControlFlow<()>,
    {
        let mut v = rd_link(&self.head, b);
        for _ in 0..N {
            if v == NONE {
                break;
            }
            f(NodeId(v))?;
            v = self.successor(v);
        }
        ControlFlow::Continue(())
    }

    /// Visits the in-grid buckets at Chebyshev distance exactly `k` from bucket `(qc, qr)`.
    #[allow(clippy::arithmetic_side_effects)] // bucket coordinates and rings < 65,536: no i32 overflow
    fn for_each_ring_bucket<F>(&self, qc: i32, qr: i32, k: i32, mut f: F) -> ControlFlow<()>
    where
        F: FnMut(usize) -> ControlFlow<()>,
    {
        let (cols, rows) = self.shape();
        let (cols, rows) = (cols as i32, rows as i32);
        let mut visit = |c: i32, r: i32| {
            if c >= 0 && r >= 0 && c < cols && r < rows {
                f(usize::try_from(r * cols + c).unwrap_or(usize::MAX))
            } else {
                ControlFlow::Continue(())
            }
        };
        if k == 0 {
            return visit(qc, qr);
        }
        for c in (qc - k)..=(qc + k) {
            visit(c, qr - k)?;
            visit(c, qr + k)?;
        }
        for r in (qr - k + 1)..=(qr + k - 1) {
            visit(qc - k, r)?;
            visit(qc + k, r)?;
        }
        ControlFlow::Continue(())
    }
}

/// Brute-force nearest: the oracle for [`SpatialIndex::nearest`]. Ties go to the lowest index.
pub fn linear_nearest(positions: &[Point], q: Point) -> Option<(NodeId, f32)> {
    let mut best: Option<(NodeId, f32)> = None;
    for (i, p) in positions.iter().enumerate() {
        let d2 = p.dist_sq(q);
        if best.is_none_or(|(_, bd)| d2 < bd) {
            best = Some((NodeId(to_u16(i)), d2));
        }
    }
    best
}

/// Brute-force within-radius: calls `f` for every position within `radius` of `q`, in index
/// order. The oracle for [`SpatialIndex::for_each_within`].
pub fn linear_within<F: FnMut(NodeId)>(positions: &[Point], q: Point, radius: f32, mut f: F) {
    for (i, p) in positions.iter().enumerate() {
        if p.dist_sq(q) <= radius * radius {
            f(NodeId(to_u16(i)));
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bucket_side_grows_to_fit_the_budget() {
        let idx = SpatialIndex::<16, 16>::with_bounds(100.0, 100.0, 5.0).unwrap();
        let (c, r) = idx.shape();
        assert!(c as usize * r as usize <= 16);
        assert!(idx.bucket_side() >= 25.0);
        assert!(SpatialIndex::<16, 16>::with_bounds(f32::NAN, 1.0, 1.0).is_none());
    }

    /// Issue 7, case 3: `with_bounds(1e20, 1e20, 1.0)` overflowed width x height to infinity,
    /// left a 0 x 0 bucket grid, and `nearest()` panicked (in `f32::clamp`, and on `cols - 1`).
    #[test]
    fn regression_huge_bounds_do_not_panic() {
        let pts = [Point::new(5.0e19, 5.0e19), Point::new(1.0, 1.0)];
        for (w, h, side) in [
            (1.0e20, 1.0e20, 1.0),
            (3.0e38, 3.0e38, 1.0),
            (2.0e19, 2.0e19, 1.0e19),
            (1.0, 1.0, 3.0e38),
        ] {
            let Some(mut idx) = SpatialIndex::<8, 16>::with_bounds(w, h, side) else {
                continue;
            };
            let (c, r) = idx.shape();
            assert!(c >= 1 && r >= 1 && c as usize * r as usize <= 16, "{w} {h}");
            idx.insert(NodeId(0), pts[0]).unwrap();
            idx.insert(NodeId(1), pts[1]).unwrap();
            assert_eq!(
                idx.nearest(Point::new(0.0, 0.0), &pts).unwrap().0,
                NodeId(1)
            );
            let mut out = heapless::Vec::<NodeId, 4>::new();
            idx.within(Point::new(0.0, 0.0), 10.0, &pts, &mut out);
            assert_eq!(out.as_slice(), &[NodeId(1)]);
        }
        // The default (unshaped) index answers too.
        let mut idx = SpatialIndex::<8, 16>::new();
        idx.insert(NodeId(1), pts[1]).unwrap();
        assert_eq!(
            idx.nearest(Point::new(1.0e30, -4.0), &pts).unwrap().0,
            NodeId(1)
        );
    }

    #[test]
    fn insert_remove_and_query() {
        let pts = [
            Point::new(1.0, 1.0),
            Point::new(9.0, 9.0),
            Point::new(4.0, 5.0),
        ];
        let mut idx = SpatialIndex::<8, 64>::with_bounds(10.0, 10.0, 2.0).unwrap();
        for (i, p) in pts.iter().enumerate() {
            idx.insert(NodeId(i as u16), *p).unwrap();
        }
        assert_eq!(idx.insert(NodeId(0), pts[0]), Err(IndexError::Membership));
        assert_eq!(idx.insert(NodeId(8), pts[0]), Err(IndexError::IdOutOfRange));
        assert_eq!(
            idx.nearest(Point::new(8.0, 8.0), &pts).unwrap().0,
            NodeId(1)
        );
        assert_eq!(idx.remove(NodeId(1), pts[0]), Err(IndexError::Membership));
        idx.remove(NodeId(1), pts[1]).unwrap();
        assert_eq!(idx.remove(NodeId(1), pts[1]), Err(IndexError::Membership));
        assert_eq!(
            idx.nearest(Point::new(8.0, 8.0), &pts).unwrap().0,
            NodeId(2)
        );
        let mut out = heapless::Vec::<NodeId, 1>::new();
        assert_eq!(idx.within(Point::new(2.0, 3.0), 10.0, &pts, &mut out), 2);
        assert_eq!(out.len(), 1);
        idx.clear();
        assert!(idx.nearest(Point::new(8.0, 8.0), &pts).is_none());
    }

    /// `clear` writes only the buckets of the current shape, and nothing when no node was
    /// indexed since the last clear: every head and link must still read zero afterwards,
    /// through reshapes to fewer and to more buckets (it fails when a reshape does not clear
    /// before it shrinks the shape, or when the skip ignores an insert).
    #[test]
    fn a_clear_of_the_buckets_in_use_leaves_every_bucket_empty() {
        let pts: [Point; 8] =
            core::array::from_fn(|i| Point::new(1.1 * i as f32 + 0.3, 9.6 - 1.2 * i as f32));
        let all_zero = |idx: &SpatialIndex<8, 64>| {
            idx.head.iter().all(|&h| h == 0) && idx.next.iter().all(|&n| n == OUT)
        };
        let mut idx = SpatialIndex::<8, 64>::new();
        for side in [1.25f32, 5.0, 2.0, 1.25, 10.0, 1.25] {
            assert!(idx.reshape(10.0, 10.0, side));
            assert!(all_zero(&idx), "side {side}: a bucket kept a node");
            idx.clear();
            assert!(all_zero(&idx));
            for (i, p) in pts.iter().enumerate() {
                idx.insert(NodeId(i as u16), *p).unwrap();
            }
            assert_eq!(
                idx.nearest(Point::new(9.0, 1.0), &pts).map(|n| n.0),
                linear_nearest(&pts, Point::new(9.0, 1.0)).map(|n| n.0)
            );
        }
        idx.clear();
        assert!(all_zero(&idx));
        assert!(idx.is_empty() && idx.nearest(Point::new(5.0, 5.0), &pts).is_none());
    }
}
