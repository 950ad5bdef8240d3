//! Rewiring (paper section 4.2, Algorithms 3-6, and the AM-RRT* / RT-RRT* sweeps they extend).
//! Every sweep is resumable: its queue, stack and seen-set live in the [`TreeStore`], a call
//! works until its deadline or its visit cap and returns, and the next call continues where it
//! stopped. A sweep that runs dry restarts from the root and forgets what it had seen.
//!
//! Costs compare blocked-last ([`Cost`]), so a node whose path crosses a dynamic obstacle takes
//! any parent with a free path. A rewire never increases a node's cost: it happens only when
//! the new cost is strictly lower, and a cost-lowering edge can never close a cycle.
//!
//! - **Root rewiring, first kind** (AM-RRT*, RT-RRT*): breadth-first from the root; a dequeued
//!   node `x` takes as parent any `x_near` in `Nearby(x)` with `Cost(x_near) + d(x_near, x) <
//!   Cost(x)` over a free segment; unseen neighbours are enqueued.
//! - **Root rewiring, second kind** (Algorithm 4, while the queue holds more than two nodes):
//!   `x_r1` is dequeued and `x_r2`, the next in the queue, is only *peeked* (it gets its own
//!   turn as `x_r1` later, so no node loses its visit); `x_r1` looks for a parent among the
//!   nodes near `x_r2`, which reaches up to about `2 e_max` and straightens corners. The
//!   paper's garbled cost test is read as the true costs above.
//! - **Goal rewiring, first kind** (AM-RRT*): a stack (current branch) and a queue (next
//!   branches) sweep from the root towards the goal inside the informed ellipse. A node `x`
//!   offers itself as parent to its neighbours, visited in order of decreasing `d_A(., goal)`;
//!   unseen neighbours with a free segment (in the tuned profile: all unseen neighbours, as
//!   root rewiring enqueues them, issue 26) form the frontier, pushed on the stack (the one
//!   nearest the goal by the metric on top) and enqueued (first in, first out, as the paper's
//!   Enqueue and Dequeue; it was last in, first out until issue 24). When the stack's top is
//!   farther from the goal than `x` was, the branch stopped approaching: the stack is cleared.
//! - **Goal rewiring, second kind** (Algorithms 5-6): `x_r1` popped (from the stack when it
//!   holds more than two nodes, else from the queue) and `x_r2` peeked after it; inside the
//!   ellipse, `x_r2` offers itself as parent to the nodes near `x_r1`. The paper's `len(S) > 1
//!   or ...` clearing test is read as `and` (the notes), i.e. the same "stopped approaching"
//!   test as the first kind.
//! - **Where this departs from Algorithms 4-6 as printed** (issue 24; the audit is
//!   `shared/notes/fidelity-audit.md`): (1) Algorithm 4 *peeks* `x_r2` where the paper
//!   dequeues it, so the sweep advances one node per step, not two, and its printed cost
//!   `Cost(x_r1) + d_E(x_r2, x_near) + d_E(x_r1, x_r2)` (never below `Cost(x_r1)`) is read as
//!   the true cost `Cost(x_near) + d_E(x_near, x_r1)`. (2) Algorithm 6's clearing test is
//!   printed `len(S) > 1 or d_A(Second(S), goal) > d_A(x_r1, goal) + d_A(x_r1, x_r2)`; read
//!   with "or" it empties the stack whenever it holds two nodes; the code tests, for both
//!   kinds, `d_A(top(S), goal) > d_A(x_r1, goal)` (the top, not `Second(S)`, and without the
//!   slack `d_A(x_r1, x_r2)`), which is neither the printed test nor its "and" reading. (3)
//!   Algorithm 6's cost test: the printed `Cost(x_r2) + d_E(x_r1, x_near) + d_E(x_r1, x_r2)`
//!   (the way through `x_r1`, an upper bound) is replaced by the true cost of the new edge
//!   `Cost(x_r2) + d_E(x_r2, x_near)`, which accepts more rewires, and the frontier's free
//!   segment is tested from `x_r1` where the paper has `FreePath(x_near, x_r2)`. (4) The first
//!   kind skips a node outside the ellipse before the clearing test (the reference runs it).
//!   (1)-(3) are switches of [`crate::AsPrinted`] (`Config::as_printed`, off in both named
//!   sets), one per departure: with them on, Algorithms 4 and 6 run as printed (the clearing
//!   test with "or" read as "and"). Measured one at a time at the paper's pace, 25 seeds
//!   (`docs/results-printed.md`): none moves a path length, search time or node count
//!   outside seed noise. The goal queue's order was a bug (fixed: first in, first out).
//! - **Path shortcuts** (tuned, [`crate::config::Rewiring::path_shortcuts`]; not in the
//!   paper): a cursor walks the path from the goal towards the root, a few nodes per
//!   expansion, and offers each node its grandparent as parent (Theta*'s any-angle step, Nash
//!   et al. 2007): the path straightens between the tree's corner nodes. In the tuned profile
//!   a node whose grandparent is hidden round a corner makes a **corner cut** (issue 26):
//!   the farthest point of its parent's edge that it sees, or of its own edge that the
//!   grandparent sees, becomes a new node and its parent, or, when neither end sees past the
//!   parent, the parent splits in two (a point on each edge, as far out as they see each
//!   other). Each cut is shorter by the triangle inequality, its new edges are parts of free
//!   edges or tested, and cuts from both sides close in on the obstacle's corner: the tree's
//!   path bends where the shortest path does, not at sampled nodes, as the shortcuts of a path
//!   simplifier (OMPL's `shortcutPath`) place vertices on a path's segments. A cut costs at
//!   most 22 segment tests (one when the corner is already cut) and two arena slots.
//! - **Random rewiring** (RT-RRT*): new nodes (and the nearest node of rejected samples) are
//!   queued; a dequeued node offers itself as parent to its neighbours and requeues those it
//!   improved.

use crate::clock::{Clock, Deadline, Meter};
use crate::geometry::{Ellipse, Point};
use crate::metric::Metric;
use crate::search::{Env, Near, Target, TreeStore};
use crate::slots::{sort_small_by, units};
use crate::tree::{Edge, Mark, NodeId};

/// Segment tests of one corner cut's bisection ([`TreeStore::cut_corner`]), after a first
/// test 1/32 of the way along the parent's edge: the cut point lies within 1/256 of the
/// edge of the farthest point seen.
const CUT_STEPS: usize = 5;

/// Why [`TreeStore::rewire`] left an edge as it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refused {
    /// Not shorter, not affordable before the deadline, or not a change.
    NoGain,
    /// Shorter, but the segment is blocked.
    Hidden,
}

/// The largest `d` in `(0, reach]` at which `sees(d)` holds, by bisection from `reach / 32`
/// ([`CUT_STEPS`] more tests), for the corner cuts; `None` when the first test fails or the
/// call's deadline passes.
fn farthest_seen<M: Metric, C: Clock + ?Sized, const K: usize>(
    env: &Env<'_, '_, M, K>,
    meter: &Meter<'_, C>,
    reach: f32,
    mut sees: impl FnMut(f32) -> bool,
) -> Option<f32> {
    let first = reach / 32.0;
    if meter.expired(&env.call) || !sees(first) {
        return None;
    }
    let (mut lo, mut hi) = (first, reach);
    for _ in 0..CUT_STEPS {
        if meter.expired(&env.call) {
            return None;
        }
        let mid = 0.5 * (lo + hi);
        if sees(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(lo)
}

/// Limits of one rewiring call.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Slice {
    /// Time limit.
    pub deadline: Deadline,
    /// Node visits allowed.
    pub visits: u32,
}

impl<const N: usize, const B: usize> TreeStore<N, B> {
    /// The goal-rewiring queue's `Enqueue`: a frontier is added at the far end from where
    /// [`TreeStore::dequeue_goal`] takes, so the queue is first in, first out (the paper: "the
    /// addition of x to the end of Q"; the reference prepends the frontier and pops the
    /// list's end). Whether the bounded queue took it.
    pub(crate) fn enqueue_goal(&mut self, id: NodeId) -> bool {
        self.goal_queue.push_front(id).is_ok()
    }

    /// The goal-rewiring queue's `Dequeue`: "removing and returning the first item" (the
    /// oldest). Its next item, Algorithm 6's `x_r2`, is `goal_queue.back()`.
    pub(crate) fn dequeue_goal(&mut self) -> Option<NodeId> {
        self.goal_queue.pop_back()
    }

    /// Makes `parent` the parent of `child` when that lowers `child`'s cost over a free
    /// segment. Returns whether the edge changed.
    pub(crate) fn try_rewire<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        parent: NodeId,
        child: NodeId,
        meter: &Meter<'_, C>,
    ) -> bool {
        self.try_rewire_via(env, parent, child, None, false, meter)
    }

    /// [`TreeStore::try_rewire`], the cost compared being that of the way `parent` - `via` -
    /// `child` when `via` is given (Algorithm 6 as printed; never below the new edge's own
    /// cost, so the child's cost still falls). `known_free`: the caller tested the segment.
    pub(crate) fn try_rewire_via<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        parent: NodeId,
        child: NodeId,
        via: Option<Point>,
        known_free: bool,
        meter: &Meter<'_, C>,
    ) -> bool {
        self.rewire(env, parent, child, via, known_free, meter)
            .is_ok()
    }

    /// [`TreeStore::try_rewire_via`], saying why an edge was not changed.
    fn rewire<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        parent: NodeId,
        child: NodeId,
        via: Option<Point>,
        known_free: bool,
        meter: &Meter<'_, C>,
    ) -> Result<(), Refused> {
        if parent == child || self.tree.parent(child) == Some(parent) {
            return Err(Refused::NoGain);
        }
        let (pp, pc) = (self.pos(parent), self.pos(child));
        let length = match via {
            Some(v) => pp.dist(v) + v.dist(pc),
            None => pp.dist(pc),
        };
        // The Euclidean cost first: a lower bound of the charged one (clearance preference).
        let new = self.cost(parent).extend(length, false);
        if new >= self.cost(child) || !env.affords_move(&self.tree, child, meter) {
            return Err(Refused::NoGain);
        }
        if !(known_free || env.free(pp, pc, meter)) {
            return Err(Refused::Hidden);
        }
        let edge = env.edge(pp, pc, meter);
        if edge.class > 0
            && self
                .cost(parent)
                .extend(env.charged(length, edge.class), false)
                >= self.cost(child)
        {
            return Err(Refused::NoGain);
        }
        self.move_below(child, parent, edge, meter)
            .ok_or(Refused::NoGain)
    }

    /// `UpdateEdge`: `child` below `parent`, charging the moved subtree (its costs are
    /// refreshed).
    fn move_below<C: Clock + ?Sized>(
        &mut self,
        child: NodeId,
        parent: NodeId,
        edge: Edge,
        meter: &Meter<'_, C>,
    ) -> Option<()> {
        let moved = self.tree.set_parent(child, parent, edge).ok()?;
        meter.charge(units(moved).saturating_add(4));
        Some(())
    }

    /// Path shortcuts ([`crate::config::Rewiring::path_shortcuts`], module docs): up to `tests` nodes of the
    /// path to `goal`, from where the last call stopped, each offered its grandparent as
    /// parent (kept while it shortens the path, as Theta* does); back to the goal after the
    /// root.
    pub(crate) fn shortcut_path<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        goal: NodeId,
        tests: u16,
        meter: &Meter<'_, C>,
    ) {
        // A cursor renamed or dropped by recycling names some other node or none: any node
        // may be shortcut, so that only costs a pass.
        let mut x = self
            .shortcut_at
            .filter(|x| x.index() < self.tree.len())
            .unwrap_or(goal);
        for _ in 0..tests {
            // Each test may move a subtree: the call's deadline is checked before each.
            if meter.expired(&env.call) {
                break;
            }
            meter.charge(1);
            let grand = self
                .tree
                .parent(x)
                .and_then(|p| Some((p, self.tree.parent(p)?)));
            let Some((parent, grand)) = grand else {
                x = goal; // the root or its child: a new pass
                continue;
            };
            // The grandparent as parent when that is shorter and `x` sees it; when it is
            // hidden, a corner cut (tuned; the cursor goes on from the cut's new node).
            x = match self.rewire(env, grand, x, None, false, meter) {
                Ok(()) => x,
                Err(Refused::Hidden) if env.cfg.profile.is_tuned() => self
                    .cut_corner(env, x, parent, grand, meter)
                    .unwrap_or(parent),
                Err(_) => parent,
            };
        }
        self.shortcut_at = Some(x);
    }

    /// A corner cut (tuned profile, module docs): `x` cannot see its
    /// grandparent `g` round its parent `p`. A point `q` of one of the two edges at `p`
    /// becomes a new node below `g` and the parent of `x`: first the farthest point of `p - g`
    /// that `x` sees, else the farthest point of `p - x` that `g` sees (bisection from `p`,
    /// [`CUT_STEPS`] tests). The way `x - q - g` is shorter than `x - p - g` (triangle
    /// inequality: `q` lies on one of the two segments), and cuts from both sides in turn
    /// close in on the corner, as a path simplifier's shortcuts place new vertices on a
    /// path's segments. Kept only when it shortens the path by a tenth of a cell; the part of
    /// the old edge that `q` keeps is tested too (a rounded point may leave the line).
    /// Returns the new node.
    fn cut_corner<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        x: NodeId,
        p: NodeId,
        g: NodeId,
        meter: &Meter<'_, C>,
    ) -> Option<NodeId> {
        if self.tree.is_full() || self.cost(x).blocked {
            return None;
        }
        let (px, pp, pg) = (self.pos(x), self.pos(p), self.pos(g));
        // (the eye, the edge's far end): x looking along p - g, then g along p - x.
        let one = [(px, pg), (pg, px)]
            .into_iter()
            .find_map(|(eye, end)| self.cut_point(env, eye, pp, end, meter));
        // Neither end sees past `p`: `p` splits in two, one point on each edge.
        let (a, b) = match one {
            Some(q) => (q, None),
            None => {
                let (a, b) = self.split_points(env, px, pp, pg, meter)?;
                (a, Some(b))
            }
        };
        let last = b.unwrap_or(a);
        // The new edges g - a (- b) - x, each with its clearance class.
        let (e_ga, e_ab, e_x) = (
            env.edge(pg, a, meter),
            b.map(|b| env.edge(a, b, meter)).unwrap_or_default(),
            env.edge(last, px, meter),
        );
        let cost = self
            .cost(g)
            .extend(env.charged(pg.dist(a), e_ga.class), false);
        let cost = b.map_or(cost, |b| {
            cost.extend(env.charged(a.dist(b), e_ab.class), false)
        });
        if cost.extend(env.charged(last.dist(px), e_x.class), false) >= self.cost(x)
            || self.tree.len().saturating_add(2) > N
        {
            return None;
        }
        let cut = self.insert(a, g, e_ga).ok()?;
        let cut = match b {
            Some(b) => self.insert(b, cut, e_ab).ok()?,
            None => cut,
        };
        self.move_below(x, cut, e_x, meter)?;
        Some(cut)
    }

    /// A corner node `p` split in two (the last corner cut, [`TreeStore::cut_corner`]): the
    /// points `a` of `p - g` and `b` of `p - x` at the same distance `d` from `p`, for the
    /// largest `d` (bisection) at which they see each other, when the way `a - b` is shorter
    /// than `a - p - b` by a tenth of a cell and the rest of both edges, `a - g` and `b - x`,
    /// is free. The cuts from both sides then pull `a` and `b` round the corner.
    fn split_points<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        px: Point,
        pp: Point,
        pg: Point,
        meter: &Meter<'_, C>,
    ) -> Option<(Point, Point)> {
        let (lg, lx) = (pp.dist(pg), pp.dist(px));
        let reach = lg.min(lx);
        if reach.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return None;
        }
        let at = |d: f32| (pp.lerp(pg, d / lg), pp.lerp(px, d / lx));
        let lo = farthest_seen(env, meter, reach, |d| {
            let (a, b) = at(d);
            env.free(a, b, meter)
        })?;
        let (a, b) = at(lo);
        let gain = 2.0 * lo - a.dist(b);
        (gain > 0.1 * env.map.grid().cell_size()
            && env.free(a, pg, meter)
            && env.free(b, px, meter))
        .then_some((a, b))
    }

    /// The farthest point `q` of the free segment `p - end` that `eye` sees, when the way
    /// `eye - q` is shorter than `eye - p - q` by a tenth of a cell and `q - end` is free
    /// ([`TreeStore::cut_corner`]). A corner already cut (`eye` sees nothing of the segment
    /// past `p`) costs one test.
    fn cut_point<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        eye: Point,
        p: Point,
        end: Point,
        meter: &Meter<'_, C>,
    ) -> Option<Point> {
        let lo = farthest_seen(env, meter, 1.0, |t| env.free(eye, p.lerp(end, t), meter))?;
        let q = p.lerp(end, lo);
        let gain = eye.dist(p) + p.dist(q) - eye.dist(q);
        (gain > 0.1 * env.map.grid().cell_size() && env.free(q, end, meter)).then_some(q)
    }

    /// Root rewiring, both kinds (module docs). `second_kind` enables Algorithm 4.
    pub(crate) fn rewire_root<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        slice: Slice,
        second_kind: bool,
        meter: &Meter<'_, C>,
    ) {
        let Some(root) = self.tree.root() else {
            return;
        };
        let radius = env.radius(self.tree.len());
        let mut near = Near::new();
        for _ in 0..slice.visits {
            if meter.expired(&slice.deadline) {
                return;
            }
            if self.root_queue.is_empty() {
                self.tree.clear_marks(Mark::Root);
                self.tree.mark(root, Mark::Root);
                let _ = self.root_queue.push_back(root);
            }
            let Some(x1) = self.root_queue.pop_front() else {
                return;
            };
            // Second kind: search around the next node in line, which stays queued (or is
            // taken too, Algorithm 4 as printed).
            let center = match self.root_queue.front() {
                Some(&x2) if second_kind && self.root_queue.len() >= 2 => {
                    if env.cfg.as_printed.alg4_takes_x_r2 {
                        self.root_queue.pop_front();
                    }
                    x2
                }
                _ => x1,
            };
            self.nearby(self.pos(center), radius, &mut near, meter);
            for &x_near in near.iter() {
                // A visit is up to 64 tests (a millisecond on a Cortex-M4F, issue 25): past
                // the deadline the rest are skipped, the neighbours still queued.
                if !meter.expired(&slice.deadline) {
                    meter.charge(1);
                    self.try_rewire(env, x_near, x1, meter);
                }
                // Seen only once queued: a node refused by the full (bounded) queue can still
                // be queued later in the sweep, from another neighbour.
                if !self.tree.marked(x_near, Mark::Root)
                    && self.root_queue.push_back(x_near).is_ok()
                {
                    self.tree.mark(x_near, Mark::Root);
                }
            }
        }
    }

    /// RT-RRT*'s random rewiring (module docs).
    pub(crate) fn rewire_random<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        slice: Slice,
        meter: &Meter<'_, C>,
    ) {
        let radius = env.radius(self.tree.len());
        let mut near = Near::new();
        for _ in 0..slice.visits {
            if meter.expired(&slice.deadline) {
                return;
            }
            let Some(x) = self.goal_queue.pop_front() else {
                return;
            };
            self.nearby(self.pos(x), radius, &mut near, meter);
            for &x_near in near.iter() {
                if meter.expired(&slice.deadline) {
                    break;
                }
                meter.charge(1);
                if self.try_rewire(env, x, x_near, meter) {
                    let _ = self.goal_queue.push_back(x_near);
                }
            }
        }
    }

    /// Goal rewiring of one kind (module docs), towards `goal`, whose node must be in the tree.
    pub(crate) fn rewire_goal<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        goal: &Target,
        slice: Slice,
        second_kind: bool,
        meter: &Meter<'_, C>,
    ) {
        let (Some(root), Some(goal_node)) = (self.tree.root(), goal.node) else {
            return;
        };
        let radius = env.radius(self.tree.len());
        let mut near = Near::new();
        let mut frontier = Near::new();
        let to_goal = env.metric.prepare(goal.pos);
        let tuned = env.cfg.profile.is_tuned();
        for _ in 0..slice.visits {
            if meter.expired(&slice.deadline) {
                return;
            }
            if self.goal_stack.is_empty() && self.goal_queue.is_empty() {
                self.tree.clear_marks(Mark::Goal);
                self.tree.mark(root, Mark::Goal);
                let _ = self.goal_stack.push(root);
            }
            // The ellipse follows the goal's current cost (it shrinks as rewiring succeeds).
            let goal_cost = self.cost(goal_node);
            let ellipse = if goal_cost.blocked {
                None
            } else {
                Ellipse::new(self.pos(root), goal.pos, goal_cost.length * 1.0001)
            };
            let inside = |p: Point| ellipse.as_ref().is_none_or(|e| e.contains(p));
            // Pick x_r1, and x_r2 for the second kind.
            let from_stack = if second_kind {
                self.goal_stack.len() > 2 || self.goal_queue.len() < 2
            } else {
                !self.goal_stack.is_empty()
            };
            let x1 = if from_stack {
                self.goal_stack.pop().or_else(|| self.dequeue_goal())
            } else {
                self.dequeue_goal()
            };
            let Some(x1) = x1 else {
                continue;
            };
            let printed = env.cfg.as_printed;
            let x2 = match (second_kind, from_stack, printed.alg6_takes_x_r2) {
                (false, _, _) => None,
                (true, true, false) => self.goal_stack.last().copied(),
                (true, true, true) => self.goal_stack.pop(),
                (true, false, false) => self.goal_queue.back().copied(),
                (true, false, true) => self.dequeue_goal(),
            };
            let x1_pos = self.pos(x1);
            if !inside(x1_pos) {
                continue;
            }
            let d1 = env.metric_to(x1_pos, &to_goal, meter);
            self.nearby(x1_pos, radius, &mut near, meter);
            // Decreasing d_A(., goal): the neighbour nearest the goal ends on top of the stack.
            let mut keyed: heapless::Vec<(f32, NodeId), { crate::search::NEAR_CAP }> =
                heapless::Vec::new();
            // A visit is up to 64 metric readings and 128 tests (a millisecond on a Cortex-M4F,
            // issue 25): past the deadline the rest are skipped; a neighbour left out stays
            // unseen, so a later visit can still take it into the sweep.
            for &id in near.iter() {
                if meter.expired(&slice.deadline) {
                    break;
                }
                let _ = keyed.push((env.metric_to(self.pos(id), &to_goal, meter), id));
            }
            sort_small_by(&mut keyed, |a, b| b.0.total_cmp(&a.0));
            frontier.clear();
            let parent = x2.unwrap_or(x1);
            // Algorithm 6's printed cost test: the way through x_r1, and the segments tested
            // from x_r2 (AsPrinted::alg6_cost).
            let printed_cost = printed.alg6_cost && x2.is_some();
            let (via, seen_from) = if printed_cost {
                (Some(x1_pos), self.pos(parent))
            } else {
                (None, x1_pos)
            };
            for &(_, x_near) in keyed.iter() {
                if meter.expired(&slice.deadline) {
                    break;
                }
                meter.charge(1);
                if printed_cost && !env.free(seen_from, self.pos(x_near), meter) {
                    continue;
                }
                self.try_rewire_via(env, parent, x_near, via, printed_cost, meter);
                // The tuned profile enqueues every unseen neighbour, as root rewiring does:
                // no segment test for the frontier (the rewire above tests its own).
                if !self.tree.marked(x_near, Mark::Goal)
                    && (printed_cost || tuned || env.free(seen_from, self.pos(x_near), meter))
                    && frontier.push(x_near).is_ok()
                {
                    self.tree.mark(x_near, Mark::Goal);
                }
            }
            for &f in frontier.iter() {
                let _ = self.goal_stack.push(f);
            }
            for &f in frontier.iter().rev() {
                // Refused by the full (bounded) queue: unseen again, so a later visit can
                // queue it (it may still be on the stack).
                if !self.enqueue_goal(f) {
                    self.tree.unmark(f, Mark::Goal);
                }
            }
            let clear = if second_kind && printed.alg6_clear {
                // len(S) > 1 and d_A(Second(S), goal) > d_A(x_r1, goal) + d_A(x_r1, x_r2).
                // Second(S): the node under the top (none when the stack holds one or none).
                let second = self.goal_stack.iter().rev().nth(1).copied();
                second.is_some_and(|second| {
                    let slack = match x2 {
                        Some(x2) => env.metric_to(x1_pos, &env.metric.prepare(self.pos(x2)), meter),
                        None => 0.0,
                    };
                    env.metric_to(self.pos(second), &to_goal, meter) > d1 + slack
                })
            } else {
                self.goal_stack
                    .last()
                    .is_some_and(|&top| env.metric_to(self.pos(top), &to_goal, meter) > d1)
            };
            if clear {
                self.goal_stack.clear();
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 24, finding 1: the goal-rewiring queue pushed frontiers at its front and took
    /// from its front too, a LIFO over frontier batches (the newest batch first). The paper's
    /// Dequeue takes the first item, Enqueue adds at the end: batches come out in the order
    /// they went in (within a batch, the reference's order: the frontier is prepended whole
    /// and taken from the list's end, so its last node, the one nearest the goal, first).
    #[test]
    fn regression_the_goal_rewiring_queue_is_first_in_first_out() {
        let mut store = TreeStore::<64, 16>::new();
        store.reset(Point::new(1.0, 1.0));
        let batch = |store: &mut TreeStore<64, 16>, ids: [u16; 2]| {
            // As rewire_goal enqueues a frontier.
            for &f in ids.iter().rev() {
                assert!(store.enqueue_goal(NodeId(f)));
            }
        };
        batch(&mut store, [1, 2]);
        batch(&mut store, [3, 4]);
        assert_eq!(
            store.goal_queue.back(),
            Some(&NodeId(2)),
            "x_r2 peeks the next out"
        );
        let order: heapless::Vec<u16, 8> =
            core::iter::from_fn(|| store.dequeue_goal().map(|n| n.0)).collect();
        assert_eq!(order[..], [2, 1, 4, 3]);
    }
    use crate::clock::FakeClock;
    use crate::config::{AsPrinted, Config};
    use crate::map::{Map, OccupancyGrid, pack_grid};
    use crate::metric::Euclidean;

    /// A zig-zag path of `points` below the root at `points[0]`; returns the last node.
    /// A path from (2.5, 2.5) to (2.5, 16.5) round the end of a wall at row 10, columns 0-11
    /// ([`wall_end`]), its corner nodes away from the wall's corners.
    const ZIGZAG: [(f32, f32); 9] = [
        (2.5, 2.5),
        (6.5, 4.5),
        (4.5, 7.5),
        (10.5, 6.5),
        (14.5, 9.5),
        (13.5, 12.5),
        (8.5, 14.5),
        (6.5, 17.5),
        (2.5, 16.5),
    ];

    /// The bits of a 20 x 20 m map of 1 m cells with a wall at row 10 over columns 0-11.
    fn wall_end() -> [u8; OccupancyGrid::bytes_needed(20, 20)] {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
        pack_grid(&mut bits, 20, 20, |c, r| r == 10 && c < 12).unwrap();
        bits
    }

    fn zigzag(store: &mut TreeStore<64, 16>, points: &[Point]) -> NodeId {
        store.reset(points[0]);
        let mut last = NodeId(0);
        for p in &points[1..] {
            last = store.insert(*p, last, false).unwrap();
        }
        last
    }

    /// The Euclidean environment of `map` and `cfg`, without a call deadline.
    fn euclidean_env<'a, 'm>(map: &'a Map<'m, 1>, cfg: &'a Config) -> Env<'a, 'm, Euclidean, 1> {
        Env {
            map,
            metric: &Euclidean,
            cfg,
            call: Deadline::NEVER,
        }
    }

    /// An empty 20 x 20 m map and the Euclidean Bi-AM-RRT* configuration.
    fn open_map(bits: &mut [u8]) -> (Map<'_, 1>, Config) {
        pack_grid(bits, 20, 20, |_, _| false).unwrap();
        let map = Map::new(OccupancyGrid::new(bits, 20, 20, 1.0).unwrap());
        (map, Config::bi_am_rrt(crate::MetricKind::Euclidean))
    }

    /// Issue 25, second round: a rewiring visit tested all its (up to 64) neighbours once
    /// started, a millisecond on a Cortex-M4F, and the tuned set's calls ran that far past
    /// their deadline. x1 hangs below a detour (root - a - b - x1, cost 15) with the root
    /// 3 m away: a visit with time left rewires it below the root; a visit whose deadline
    /// passes while it gathers the neighbours (1 ms a unit of work) tests none of them.
    #[test]
    fn regression_a_rewiring_visit_stops_testing_at_the_deadline() {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
        let (map, cfg) = open_map(&mut bits);
        let env = euclidean_env(&map, &cfg);
        for (deadline, parent) in [
            (Deadline::NEVER, 0u16),
            (Deadline::from_ticks(0, 1_000_000), 2),
        ] {
            let clock = FakeClock::nanos().with_work_cost(1_000_000);
            let meter = Meter::new(&clock);
            let mut store = TreeStore::<64, 16>::new();
            assert!(store.index.reshape(20.0, 20.0, 8.0));
            let x1 = zigzag(
                &mut store,
                &[(2.0, 2.0), (2.0, 8.0), (5.0, 8.0), (5.0, 2.0)].map(|(x, y)| Point::new(x, y)),
            );
            store.tree.mark(NodeId(0), Mark::Root);
            store.tree.mark(x1, Mark::Root);
            store.root_queue.push_back(x1).unwrap();
            let slice = Slice {
                deadline,
                visits: 1,
            };
            store.rewire_root(&env, slice, false, &meter);
            store.tree.validate().unwrap();
            assert_eq!(store.tree.parent(x1), Some(NodeId(parent)), "{deadline:?}");
        }
    }

    #[test]
    fn algorithm_4_as_printed_takes_x_r2_out_of_the_queue() {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
        let (map, base) = open_map(&mut bits);
        let front_after_one_step = |take: bool| {
            let mut cfg = base;
            cfg.as_printed.alg4_takes_x_r2 = take;
            let env = euclidean_env(&map, &cfg);
            let clock = FakeClock::new(1);
            let meter = Meter::new(&clock);
            let mut store = TreeStore::<64, 16>::new();
            assert!(store.index.reshape(20.0, 20.0, 2.0));
            store.reset(Point::new(2.0, 2.0));
            for k in 1..=4u16 {
                let id = store
                    .insert(Point::new(2.0 + 3.0 * f32::from(k), 2.0), NodeId(0), false)
                    .unwrap();
                store.tree.mark(id, Mark::Root);
                store.root_queue.push_back(id).unwrap();
            }
            store.tree.mark(NodeId(0), Mark::Root);
            let slice = Slice {
                deadline: Deadline::NEVER,
                visits: 1,
            };
            store.rewire_root(&env, slice, true, &meter);
            store.tree.validate().unwrap();
            store.root_queue.front().map(|n| n.0)
        };
        assert_eq!(front_after_one_step(false), Some(2), "x_r2 peeked");
        assert_eq!(front_after_one_step(true), Some(3), "x_r2 dequeued");
    }

    /// One step of Algorithm 6 from the stack `[p, q, x_r1]` (bottom to top) on a straight
    /// tree `root (1) - q (7) - x_r1 (9) - p (13) - goal (18)` along `y = 10`, every node
    /// already seen (no frontier): what is left on the stack.
    fn goal_stack_after_one_step(printed: AsPrinted) -> heapless::Vec<u16, 8> {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
        let (map, mut cfg) = open_map(&mut bits);
        cfg.as_printed = printed;
        let env = euclidean_env(&map, &cfg);
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        let goal = zigzag(
            &mut store,
            &[1.0, 7.0, 9.0, 13.0, 18.0].map(|x| Point::new(x, 10.0)),
        );
        for k in 0..5 {
            store.tree.mark(NodeId(k), Mark::Goal);
        }
        let (q, x1, p) = (NodeId(1), NodeId(2), NodeId(3));
        for id in [p, q, x1] {
            store.goal_stack.push(id).unwrap();
        }
        let target = Target {
            pos: Point::new(18.0, 10.0),
            node: Some(goal),
        };
        let slice = Slice {
            deadline: Deadline::NEVER,
            visits: 1,
        };
        store.rewire_goal(&env, &target, slice, true, &meter);
        store.tree.validate().unwrap();
        store.goal_stack.iter().map(|n| n.0).collect()
    }

    #[test]
    fn algorithm_6_as_printed_takes_x_r2_and_tests_the_second_node_with_slack() {
        let run = |take: bool, clear: bool| {
            let mut printed = AsPrinted::NONE;
            printed.alg6_takes_x_r2 = take;
            printed.alg6_clear = clear;
            goal_stack_after_one_step(printed)
        };
        // Peeked x_r2 = q stays on top; q (11 m from the goal) is farther than x_r1 (9 m):
        // this crate's test clears the stack.
        assert_eq!(run(false, false)[..], []);
        // Taken, q is gone; the top p (5 m) is nearer than x_r1: kept.
        assert_eq!(run(true, false)[..], [3]);
        // The printed test looks at Second(S) = p: 5 > 9 + d(x_r1, q) = 11 fails: kept.
        assert_eq!(run(false, true)[..], [3, 1]);
        // Both: one node left, len(S) > 1 fails: kept.
        assert_eq!(run(true, true)[..], [3]);
    }

    #[test]
    fn algorithm_6_as_printed_compares_the_way_through_x_r1() {
        let mut bits = [0u8; OccupancyGrid::bytes_needed(20, 20)];
        let (map, cfg) = open_map(&mut bits);
        let env = euclidean_env(&map, &cfg);
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        for (via, rewired) in [(None, true), (Some(Point::new(2.0, 6.0)), false)] {
            let mut store = TreeStore::<64, 16>::new();
            assert!(store.index.reshape(20.0, 20.0, 2.0));
            // x_near (6, 2) reached round a detour: cost about 7.2.
            let near = zigzag(
                &mut store,
                &[(2.0, 2.0), (4.0, 5.0), (6.0, 2.0)].map(|(x, y)| Point::new(x, y)),
            );
            let before = store.cost(near).length;
            // The root as x_r2: its edge costs 4 < 7.2; through x_r1 (2, 6) 4 + 5.7 > 7.2.
            let done = store.try_rewire_via(&env, NodeId(0), near, via, false, &meter);
            assert_eq!(done, rewired, "via {via:?}, cost before {before}");
            store.tree.validate().unwrap();
        }
    }

    #[test]
    fn corner_cuts_pull_the_path_round_the_corner() {
        // The map and zigzag of the test below; the shortest way from (2.5, 2.5) to (2.5,
        // 16.5) round the wall's end touches its corners (12, 10) and (12, 11).
        let bits = wall_end();
        let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 20, 20, 1.0).unwrap());
        let (start, end) = (Point::new(2.5, 2.5), Point::new(2.5, 16.5));
        let optimum = start.dist(Point::new(12.0, 10.0)) + 1.0 + Point::new(12.0, 11.0).dist(end);
        let pts = ZIGZAG.map(|(x, y)| Point::new(x, y));
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        let mut lengths = [0.0f32; 2];
        for (cuts, length) in [false, true].into_iter().zip(&mut lengths) {
            let paper = Config::bi_am_rrt(crate::MetricKind::Euclidean);
            let cfg = if cuts { paper.tuned() } else { paper };
            let env = euclidean_env(&map, &cfg);
            let mut store = TreeStore::<64, 16>::new();
            assert!(store.index.reshape(20.0, 20.0, 2.0));
            let goal = zigzag(&mut store, &pts);
            for _ in 0..40 {
                store.shortcut_path(&env, goal, 4, &meter);
            }
            store.tree.validate().unwrap();
            let mut x = goal;
            while let Some(p) = store.tree.parent(x) {
                assert!(map.free_path(store.pos(p), store.pos(x)), "cuts {cuts}");
                x = p;
            }
            assert_eq!(x, NodeId(0));
            *length = store.cost(goal).length;
            assert!(
                *length >= optimum - 1e-3,
                "cuts {cuts}: {length} < {optimum}"
            );
        }
        // Measured: 27.36 m through the corner nodes, 24.17 m with cuts (optimum 24.08 m).
        assert!(lengths[0] > 1.05 * optimum, "{lengths:?} vs {optimum}");
        assert!(lengths[1] < 1.005 * optimum, "{lengths:?} vs {optimum}");
    }

    #[test]
    fn path_shortcuts_straighten_the_path_and_keep_it_free() {
        // 20 x 20 m; a wall at row 10 over columns 0-11 (the way round is past column 12).
        let bits = wall_end();
        let map: Map<'_, 1> = Map::new(OccupancyGrid::new(&bits, 20, 20, 1.0).unwrap());
        let cfg = Config::bi_am_rrt(crate::MetricKind::Euclidean);
        let env = euclidean_env(&map, &cfg);
        let clock = FakeClock::new(1);
        let meter = Meter::new(&clock);
        let mut store = TreeStore::<64, 16>::new();
        assert!(store.index.reshape(20.0, 20.0, 2.0));
        let pts = ZIGZAG.map(|(x, y)| Point::new(x, y));
        let goal = zigzag(&mut store, &pts);
        let before = store.cost(goal).length;
        for _ in 0..20 {
            store.shortcut_path(&env, goal, 4, &meter);
        }
        let after = store.cost(goal).length;
        store.tree.validate().unwrap();
        // Every edge of the path is free, and the path still goes round the wall's end.
        let mut x = goal;
        let mut hops = 0;
        while let Some(p) = store.tree.parent(x) {
            assert!(map.free_path(store.pos(p), store.pos(x)));
            x = p;
            hops += 1;
        }
        assert_eq!(x, NodeId(0));
        // Straight through the corner nodes (10.5, 6.5) or (14.5, 9.5) and (13.5, 12.5).
        assert!(after < before - 5.0, "{before} -> {after}");
        assert!(hops <= 4, "{hops} edges left");
        let direct = pts[0].dist(pts[8]);
        assert!(
            after > direct,
            "the wall is in the way: {after} vs {direct}"
        );
    }
}
