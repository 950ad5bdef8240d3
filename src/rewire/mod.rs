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
//!   unseen neighbours with a free segment (with `open_frontier`: all unseen neighbours, as
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
//!   segment is tested from `x_r1` where the paper has `FreePath(x_near, x_r2)`. (4) A node
//!   outside the ellipse is skipped before the clearing test, where Algorithm 6 (and
//!   AM-RRT*'s reference, for the first kind) tests the stack after every `x_r1`. (5)
//!   Algorithm 4 enqueues `x_near` only over a free segment to `x_r1`; the code enqueues
//!   every unseen neighbour, as the first kind does. (6) Algorithm 5 runs Algorithm 6 only
//!   while the queue or the stack holds more than two nodes (and Algorithm 6 then takes from
//!   the stack only when it holds more than two); the code runs the second kind on shorter
//!   lists too. Each is a switch of [`crate::AsPrinted`] (`Config::as_printed`, off in both
//!   named sets): (1) `alg4-take`, (2) `alg6-clear`, (3) `alg6-cost` with `alg6-take` for
//!   the pop of `x_r2`, (4) `alg6-clear-outside`, (5) `alg4-free`, (6) `alg5-gate`. With all
//!   of them on (`AsPrinted::ALL`, with the Meet over every pair), Algorithms 4-6 run as
//!   printed, the clearing test's "or" read as "and" and Algorithm 4's cost test, which can
//!   never pass as printed, read as the true cost. Measured one at a time at the paper's
//!   pace, 25 seeds: `docs/results/printed/README.md`. The goal queue's order was a bug
//!   (fixed: first in, first out).
//! - **Path shortcuts** (tuned, [`crate::config::Rewiring::path_shortcuts`]; not in the
//!   paper): a cursor walks the path from the goal towards the root, a few nodes per
//!   expansion, and offers each node its grandparent as parent (Theta*'s any-angle step, Nash
//!   et al. 2007): the path straightens between the tree's corner nodes. With `corner_cuts`
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

mod goal;
mod random;
mod root;
mod shortcuts;

use crate::clock::{Clock, Deadline, Meter};
use crate::expand::{Env, Near, Target, TreeStore};
use crate::geometry::{Ellipse, Point};
use crate::metric::Metric;
use crate::slots::{sort_small_by, units};
use crate::tree::{Edge, Mark, NodeId};

/// Why [`TreeStore::rewire`] left an edge as it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Refused {
    /// Not shorter, not affordable before the deadline, or not a change.
    NoGain,
    /// Shorter, but the segment is blocked.
    Hidden,
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
}

#[cfg(test)]
mod tests;
