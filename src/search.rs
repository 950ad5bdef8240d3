//! One tree's search: its storage ([`TreeStore`]: arena, spatial index, rewiring state) and
//! one expansion (paper Algorithm 2 with the AM-RRT* primitives of section 3.2).
//!
//! An expansion samples a state, finds `Nearest`, steers towards the sample, and adds the new
//! state below the neighbour that gives it the lowest cost over a free segment:
//!
//! - `Nearest(T, x)`: the Euclidean-nearest node when the segment to it is free or the metric
//!   is Euclidean; otherwise the node nearest by the assisting metric (a scan of the tree; the
//!   Euclidean nearest if the metric cannot place `x`).
//! - Steering: a step of at most `e_max` along the segment when it is free. Otherwise AM-RRT*
//!   with a non-Euclidean metric draws `steer_candidates` states in the disc of radius
//!   `min(e_max, d_E)` around the nearest node and keeps the free one closest to the sample by
//!   the metric (a fixed number of candidates instead of the reference's fixed 2 ms, so a fast
//!   implementation does not pay milliseconds per sample); AM-RRT*(E) steps towards the first
//!   obstacle and stops short of it (bisection of the free prefix); RT-RRT* gives up.
//! - The node is added when the neighbourhood holds fewer than `n_max` nodes, or the sample was
//!   farther than `e_max` from its nearest node, or the new state is the goal. The goal joins as a
//!   child of a new node within `e_max` of it over a free segment.

use crate::clock::{Clock, Meter};
use crate::config::{Base, Config};
use crate::error::TreeError;
use crate::geometry::{Ellipse, Point, sample_disc};
use crate::index::SpatialIndex;
use crate::map::Map;
use crate::metric::Metric;
use crate::sample::{GoalView, sample_state};
use crate::sweep::{NodeQueue, NodeStack, SeenSet};
use crate::tree::{Cost, NodeId, Tree};
use rand_core::Rng;

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
    pub(crate) root_queue: NodeQueue<N>,
    pub(crate) root_seen: SeenSet<N>,
    pub(crate) goal_stack: NodeStack<N>,
    /// Goal rewiring's queue; RT-RRT*'s random-rewiring queue.
    pub(crate) goal_queue: NodeQueue<N>,
    pub(crate) goal_seen: SeenSet<N>,
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
            root_seen: SeenSet::new(),
            goal_stack: NodeStack::new(),
            goal_queue: NodeQueue::new(),
            goal_seen: SeenSet::new(),
        }
    }

    /// The tree.
    pub fn tree(&self) -> &Tree<N> {
        &self.tree
    }

    /// Empties the tree and makes a root at `pos`; forgets all rewiring state.
    pub(crate) fn reset(&mut self, pos: Point) {
        let root = self.tree.reset(pos);
        self.index.clear();
        let _ = self.index.insert(root, pos);
        self.restart_sweeps();
    }

    /// Empties the tree entirely.
    pub(crate) fn clear(&mut self) {
        self.tree.clear();
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
        self.root_seen.clear();
    }

    pub(crate) fn restart_goal_sweep(&mut self) {
        self.goal_stack.clear();
        self.goal_queue.clear();
        self.goal_seen.clear();
    }

    /// Adds a node and indexes it.
    pub(crate) fn insert(
        &mut self,
        pos: Point,
        parent: NodeId,
        blocked: bool,
    ) -> Result<NodeId, TreeError> {
        let id = self.tree.add(pos, parent, blocked)?;
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
        meter.charge(4 + n as u32);
        n
    }
}

/// What one expansion needs to see of the world: map, metric and configuration.
pub(crate) struct Env<'a, 'm, M, const K: usize> {
    pub map: &'a Map<'m, K>,
    pub metric: &'a M,
    pub cfg: &'a Config,
}

impl<M: Metric, const K: usize> Env<'_, '_, M, K> {
    /// `free_path`, charged by the cells it may cross.
    pub fn free<C: Clock + ?Sized>(&self, a: Point, b: Point, meter: &Meter<'_, C>) -> bool {
        let inv = 1.0 / self.map.grid().cell_size();
        let cells = (libm::fabsf(a.x - b.x) + libm::fabsf(a.y - b.y)) * inv;
        meter.charge(2 + cells as u32);
        self.map.free_path(a, b)
    }

    /// `d_A`, charged (2 units plus what the metric reports).
    pub fn metric<C: Clock + ?Sized>(&self, a: Point, b: Point, meter: &Meter<'_, C>) -> f32 {
        let d = self.metric.distance(a, b);
        meter.charge(2u32.saturating_add(self.metric.take_work()));
        d
    }

    /// The `Nearby` radius: `e_max` for AM-RRT*; RT-RRT*'s shrinking
    /// `max(sqrt(area * n_max / (pi * n)), e_max)`.
    pub fn radius(&self, nodes: usize) -> f32 {
        let e = self.cfg.e_max;
        match self.cfg.base {
            Base::AmRrt => e,
            Base::RtRrt => {
                let area = self.map.grid().width_m() * self.map.grid().height_m();
                let r = libm::sqrtf(
                    area * self.cfg.n_max as f32 / (core::f32::consts::PI * nodes.max(1) as f32),
                );
                r.max(e)
            }
        }
    }
}

/// The goal of one tree and whether it has joined.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Target {
    pub pos: Point,
    pub node: Option<NodeId>,
}

/// What an expansion did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Grown {
    /// The node added (if any).
    pub added: Option<NodeId>,
    /// The goal joined the tree in this expansion.
    pub goal_joined: bool,
    /// A node could not be added because the arena is full.
    pub full: bool,
}

impl<const N: usize, const B: usize> TreeStore<N, B> {
    /// `Nearest(T, x)` (module docs).
    pub(crate) fn nearest<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        x: Point,
        meter: &Meter<'_, C>,
    ) -> Option<NodeId> {
        meter.charge(8);
        let (near, _) = self.index.nearest(x, self.tree.positions())?;
        if env.metric.is_euclidean() || env.free(self.pos(near), x, meter) {
            return Some(near);
        }
        let mut best = (near, f32::INFINITY);
        for id in self.tree.ids() {
            let d = env.metric(self.pos(id), x, meter);
            if d < best.1 {
                best = (id, d);
            }
        }
        Some(best.0)
    }

    /// Steers from node `from` towards `x` (module docs); `None` when no state can be reached.
    fn steer<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        from: NodeId,
        x: Point,
        meter: &Meter<'_, C>,
    ) -> Option<Point> {
        let a = self.pos(from);
        let e_max = env.cfg.e_max;
        let step = a.step_towards(x, e_max);
        if env.free(a, step, meter) {
            return Some(step);
        }
        if env.cfg.base == Base::RtRrt {
            return None;
        }
        if env.metric.is_euclidean() {
            // Largest free prefix of a-step by bisection, then back off a little.
            let (mut lo, mut hi) = (0.0f32, 1.0f32);
            for _ in 0..12 {
                let mid = 0.5 * (lo + hi);
                if env.free(a, a.lerp(step, mid), meter) {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            let len = a.dist(step) * lo - 0.05 * e_max;
            if len < 0.05 * e_max {
                return None;
            }
            let p = a.step_towards(step, len);
            return env.free(a, p, meter).then_some(p);
        }
        let radius = e_max.min(a.dist(x));
        let mut best: Option<(Point, f32)> = None;
        for _ in 0..env.cfg.steer_candidates {
            let c = sample_disc(rng, a, radius);
            if !env.free(a, c, meter) {
                continue;
            }
            let d = env.metric(c, x, meter);
            if best.is_none_or(|(_, bd)| d < bd) {
                best = Some((c, d));
            }
        }
        best.map(|(p, _)| p)
    }

    /// The sampler's view of this tree's goal.
    pub(crate) fn goal_view<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        target: &Target,
        meter: &Meter<'_, C>,
    ) -> GoalView {
        let root = self.tree.root().map(|r| self.pos(r)).unwrap_or(target.pos);
        let ellipse = target.node.and_then(|g| {
            let c = self.cost(g);
            if c.blocked {
                None
            } else {
                Ellipse::new(root, target.pos, c.length)
            }
        });
        let line_from = if env.cfg.base == Base::RtRrt && target.node.is_none() {
            meter.charge(8);
            self.index
                .nearest(target.pos, self.tree.positions())
                .map(|(id, _)| self.pos(id))
        } else {
            None
        };
        GoalView {
            goal: target.pos,
            in_tree: target.node.is_some(),
            ellipse,
            line_from,
        }
    }

    /// One expansion (module docs). `target` is this tree's goal, updated when it joins.
    pub(crate) fn expand<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        target: Option<&mut Target>,
        meter: &Meter<'_, C>,
    ) -> Grown {
        let cfg = env.cfg;
        let mut grown = Grown::default();
        let view = target.as_deref().map(|t| self.goal_view(env, t, meter));
        let Some(x_rand) = sample_state(
            rng,
            env.map,
            view.as_ref(),
            cfg.p_goal,
            cfg.p_uniform,
            cfg.sample_attempts,
        ) else {
            return grown;
        };
        meter.charge(4);
        let Some(x_nearest) = self.nearest(env, x_rand, meter) else {
            return grown;
        };
        let Some(x_new) = self.steer(env, rng, x_nearest, x_rand, meter) else {
            return grown;
        };
        // Not already in the tree.
        if let Some((_, d2)) = self.index.nearest(x_new, self.tree.positions())
            && d2 < 1e-8
        {
            return grown;
        }
        let radius = env.radius(self.tree.len());
        let mut near = Near::new();
        let found = self.nearby(x_new, radius, &mut near, meter);
        let is_goal = target
            .as_deref()
            .is_some_and(|t| t.node.is_none() && t.pos == x_new);
        let far_sample = self.pos(x_nearest).dist(x_rand) > cfg.e_max;
        if !(found < cfg.n_max as usize || far_sample || is_goal) {
            if cfg.base == Base::RtRrt {
                let _ = self.goal_queue.push_back(x_nearest);
            }
            return grown;
        }
        if !near.contains(&x_nearest) {
            // Keep x_nearest a candidate even when the list was truncated.
            if near.is_full() {
                near.pop();
            }
            let _ = near.push(x_nearest);
        }
        let Some(parent) = self.best_parent(env, x_new, &mut near, meter) else {
            return grown;
        };
        let id = match self.insert(x_new, parent, false) {
            Ok(id) => id,
            Err(_) => {
                grown.full = true;
                return grown;
            }
        };
        grown.added = Some(id);
        if cfg.base == Base::RtRrt {
            let _ = self.goal_queue.push_back(id);
        }
        if let Some(t) = target
            && t.node.is_none()
        {
            if is_goal {
                t.node = Some(id);
                grown.goal_joined = true;
            } else if x_new.dist(t.pos) <= cfg.e_max && env.free(x_new, t.pos, meter) {
                match self.insert(t.pos, id, false) {
                    Ok(g) => {
                        t.node = Some(g);
                        grown.goal_joined = true;
                    }
                    Err(_) => grown.full = true,
                }
            }
        }
        grown
    }

    /// The candidate giving `x` the lowest cost over a free segment: candidates are ordered by
    /// the cost they would give, and segments are tested in that order until one is free.
    pub(crate) fn best_parent<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        x: Point,
        candidates: &mut Near,
        meter: &Meter<'_, C>,
    ) -> Option<NodeId> {
        let key = |id: NodeId| self.cost(id).extend(self.pos(id).dist(x), false);
        candidates.sort_unstable_by_key(|&id| key(id));
        candidates
            .iter()
            .copied()
            .find(|&id| env.free(self.pos(id), x, meter))
    }
}
