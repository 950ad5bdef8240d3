//! One tree's search: its storage ([`TreeStore`]: arena, spatial index, rewiring state) and
//! one expansion (paper Algorithm 2 with the AM-RRT* primitives of section 3.2).
//!
//! An expansion samples a state, finds `Nearest`, steers towards the sample, and adds the new
//! state below the neighbour that gives it the lowest cost over a free segment:
//!
//! - Sampling: [`crate::sample`]; with `p_beacon` (tuned), once the goal is joined, a share of
//!   the samples falls in the `e_max` disc around a node of the current path instead
//!   (RRT*-Smart's beacons), and with `p_gap` (tuned) a share of the others in a narrow
//!   passage of the informed ellipse (a slit a few cells wide in a drawn wall, which uniform
//!   samples almost never reach; only on maps whose cells are at most `e_max / 16`). When the
//!   nearest node's step towards such a sample is blocked, the sample itself is the new state
//!   (below a neighbour that sees it, or nothing): steering would put it outside the passage.
//! - RRT-Connect's greedy step (`TreeStore::connect`, the `connect` tactic): the planner makes the
//!   other tree walk straight towards a new node that met nothing within `sigma`.
//! - `Nearest(T, x)`: the Euclidean-nearest node when the segment to it is free or the metric
//!   is Euclidean; otherwise the node nearest by the assisting metric (a scan of the tree; the
//!   Euclidean nearest if the metric cannot place `x`). With `nearest_step` only the
//!   steering step towards `x` is tested, and the steering takes that step, and the parent
//!   choice that segment, without testing them again.
//! - Steering: a step of at most `e_max` along the segment when it is free (`e_search` instead
//!   while the tree's goal is not in it, when a tuned configuration sets it). Otherwise AM-RRT*
//!   with a non-Euclidean metric draws `steer_candidates` states in the disc of radius
//!   `min(e_max, d_E)` around the nearest node (independently, or with `steer_fan` spread
//!   evenly in angle, [`crate::geometry::DiscFan`]) and keeps the free one closest to the sample by
//!   the metric (a fixed number of candidates instead of the reference's fixed 2 ms, so a fast
//!   implementation does not pay milliseconds per sample; candidates are ranked by the metric
//!   and their segments tested in that order, which picks the same one with fewer segment
//!   tests); AM-RRT*(E) steps towards the first
//!   obstacle and stops short of it (bisection of the free prefix); RT-RRT* gives up.
//! - The node is added when the neighbourhood holds fewer than `n_max` nodes, or the sample was
//!   farther than `e_max` from its nearest node, or the new state is the goal. With
//!   `rewire_new`, a node added inside the informed ellipse then offers itself as parent to
//!   its neighbours, as RRT* does; with `density_trades`, a state the rule turns away inside
//!   the ellipse instead takes the slot of the neighbourhood's leaf
//!   with the highest `Cost(x) + d_E(x, goal)` when that is above the new state's own bound:
//!   the nodes move to where they can shorten the path, and since a neighbourhood's bounds
//!   only decrease, trades cannot cycle.
//! - The goal joins below the cheapest node within `e_max` that sees it over a free segment,
//!   tried whenever a new node lands within `e_max` of it *and* whenever an expansion adds no
//!   node (a duplicate sample, a dense neighbourhood), so neither the duplicate test nor the
//!   density rule can keep a reachable goal out; a node already standing on the goal (within
//!   1e-4 of a cell) becomes the goal's node.
//! - `Nearest` never picks a node inside a dynamic obstacle or a cell the live overlay marked:
//!   every segment from it is blocked, so it could be no one's parent, and as the nearest node
//!   of every sample around the obstacle it kept the way around from growing (issue 24: a disc
//!   dropped on a grafted trunk left RT-RRT*-1 holding for 3,000 calls).
//! - Starving (liveness; not in the paper): once the density rule has turned away
//!   [`STARVING`] states in a row while the tree's goal is not in it, a state with no node
//!   within `e_max / sqrt(n_max)` (the spacing of `n_max` nodes spread over an `e_max` disc)
//!   is let in whatever the count around it. A room smaller than `e_max` whose ways out are
//!   narrow otherwise holds `n_max` nodes and nothing else can grow; the nodes let in keep a
//!   spacing, so a neighbourhood still holds a bounded number (at most about `4 n_max`).
//!   Counted in [`crate::Stats::starving_admits`]; 0 in 600 searches on the paper's maps.
//! - A full arena makes room while the tree's goal is not joined, or joined only over a path
//!   that crosses a dynamic obstacle: one leaf is recycled (among 16 random nodes, the leaf with
//!   the highest `Cost(x) + d_E(x, goal)` among those that share their index bucket with
//!   another node, or among all when none does; never the root, the goal or the new node's
//!   parent) and the new node takes its slot. Thinning where the tree is dense keeps the lone
//!   nodes at its frontier: the highest bound alone picked the frontier of every detour, and a
//!   64-node tree never got through the built-in maze (issue 23, case 3). Once a free path
//!   exists, a full tree rewires what it has (the paper's behaviour).

mod admit;

pub(crate) use crate::store::{NEAR_CAP, Near, TreeStore};

use crate::clock::{Clock, Deadline, Meter};
use crate::config::{Base, Config};
use crate::geometry::{DiscFan, Ellipse, Point, sample_disc, unit_f32};
use crate::map::Map;
use crate::metric::{Metric, Prepared};
use crate::sample::{GoalView, sample_state};
use crate::slots::{sat_u32, sort_small_by, to_u16, units};
use crate::tree::{Cost, Edge, NodeId, Tree, charged};
use rand_core::Rng;

/// Most nodes one greedy connection (RRT-Connect's step, the `connect` tactic) adds.
pub const CONNECT_STEPS: usize = 32;

/// States turned away by the density rule in a row, while a tree's goal is not in it, after
/// which the tree counts as starving and the density rule keeps out only states within the
/// cover's spacing of a node (module docs). On the paper's maps no search refused this many
/// in a row (measured: 600 first-leg searches of the 20 planners, 8,192 nodes, 0 admits), so
/// the paper's configurations grow as printed there.
pub const STARVING: u16 = 1024;

/// What one gap-sample draw is charged, before its cell reads: a square root and a
/// sine-cosine, measured at 22 us a draw on the M4F firmware where a unit of the search's
/// other work averages 1.7 us.
const GAP_DRAW_UNITS: u32 = 12;

/// AM-RRT*(E)'s steering towards an obstacle stops this fraction of `e_max` short of it (and
/// adds nothing when the free prefix is shorter than that).
const STEP_BACK: f32 = 0.05;

/// A gap sample is a free cell with occupied cells within `e_max / GAP_WIDTH_DIV` on both
/// sides along its row or its column (`Search::p_gap`); a map whose cells are coarser than
/// that draws none.
const GAP_WIDTH_DIV: f32 = 16.0;

/// The most cells a gap sample looks along each way ([`GAP_WIDTH_DIV`]).
const GAP_MAX_CELLS: u32 = 32;

/// Steering candidates ranked at once (more are drawn in several batches).
const STEER_BATCH: usize = 32;
/// [`STEER_BATCH`] as a candidate count.
const STEER_BATCH_U16: u16 = 32;

/// What a new state offers a full arena (`recycle_when_full`): a leaf may give up
/// its slot when its cost bound is above `bound` and at least `cover` other nodes (capped by
/// [`TreeStore::cover`]) share its index bucket ([`crate::config::Memory::recycle_cover`]).
pub(crate) struct Trade {
    bound: Cost,
    cover: u16,
}

/// Two states closer than this fraction of a grid cell are the same state: a new sample there
/// is dropped, and a goal there joins as that node.
pub(crate) const DUPLICATE: f32 = 1e-4;

/// Squared distance under which two states on a grid of `cell`-metre cells are the same.
pub(crate) fn duplicate_sq(cell: f32) -> f32 {
    let d = DUPLICATE * cell;
    d * d
}

/// Adds `id` to a candidate list, dropping the last candidate when the list is full.
fn keep_candidate(near: &mut Near, id: NodeId) {
    if !near.contains(&id) {
        if near.is_full() {
            near.pop();
        }
        let _ = near.push(id);
    }
}

/// What one expansion needs to see of the world: map, metric and configuration.
pub(crate) struct Env<'a, 'm, M, const K: usize> {
    pub map: &'a Map<'m, K>,
    pub metric: &'a M,
    pub cfg: &'a Config,
    /// The call's deadline: long loops inside one expansion check it too, so that a call
    /// overruns its budget by at most one short step (see [`crate::planner::Planner::plan`]).
    pub call: Deadline,
}

impl<M: Metric, const K: usize> Env<'_, '_, M, K> {
    /// `free_path`, charged by the cells it may cross (and a body's exact stage by its work).
    pub fn free<C: Clock + ?Sized>(&self, a: Point, b: Point, meter: &Meter<'_, C>) -> bool {
        let inv = 1.0 / self.map.grid().cell_size();
        let cells = (libm::fabsf(a.x - b.x) + libm::fabsf(a.y - b.y)) * inv;
        meter.charge(sat_u32(cells).saturating_add(2));
        // A robot body's exact stage near walls costs more: charged as it is done.
        let (free, work) = self.map.free_path_work(a, b);
        meter.charge(work);
        free
    }

    /// Whether the planner prefers clearance ([`crate::Config::clearance_weight`] above 0, and
    /// the crate's `clearance` feature on; the planner refuses a weight without a clearance
    /// field or without the feature).
    #[inline]
    pub fn weighted(&self) -> bool {
        cfg!(feature = "clearance") && self.cfg.clearance_weight > 0.0
    }

    /// A new free edge `a-b` as the tree records it: its clearance class, charged by the
    /// points it samples (class 0 and no work without a preference).
    #[inline(never)]
    pub fn edge<C: Clock + ?Sized>(&self, a: Point, b: Point, meter: &Meter<'_, C>) -> Edge {
        if !self.weighted() {
            return Edge::default();
        }
        let (class, work) = self.map.clearance_class(a, b);
        meter.charge(work);
        Edge {
            blocked: false,
            class,
        }
    }

    /// The length an edge of Euclidean length `len` and class `class` is charged
    /// ([`crate::tree::charged`]).
    #[inline]
    pub fn charged(&self, len: f32, class: u8) -> f32 {
        charged(len, class, self.cfg.clearance_weight)
    }

    /// Whether a subtree move below `top` (which refreshes the cost of every node it carries)
    /// ends before the call's deadline ([`Meter::affords`]). The subtree is counted only
    /// when the whole tree would not fit in the time left.
    pub fn affords_move<C: Clock + ?Sized, const N: usize>(
        &self,
        tree: &Tree<N>,
        top: NodeId,
        meter: &Meter<'_, C>,
    ) -> bool {
        if meter.expired(&self.call) {
            return false;
        }
        if meter.affords(tree.len() as u64, &self.call) {
            return true;
        }
        let carried = tree.subtree_len(top, tree.len());
        meter.charge(units(carried / 8));
        meter.affords(carried as u64, &self.call)
    }

    /// Squared distance under which two states are the same ([`DUPLICATE`] of a cell).
    pub fn duplicate_sq(&self) -> f32 {
        duplicate_sq(self.map.grid().cell_size())
    }

    /// `d_A` to a prepared end ([`Metric::prepare`]), charged 2 units plus what the metric
    /// reports.
    pub fn metric_to<C: Clock + ?Sized>(
        &self,
        a: Point,
        to: &Prepared,
        meter: &Meter<'_, C>,
    ) -> f32 {
        let d = self.metric.distance_to(a, to);
        meter.charge(2u32.saturating_add(self.metric.take_work()));
        d
    }

    /// The `Nearby` radius: `e_max` for AM-RRT*; RT-RRT*'s shrinking
    /// `max(sqrt(area * n_max / (pi * n)), e_max)`.
    pub fn radius(&self, nodes: usize) -> f32 {
        let e = self.cfg.search.e_max;
        match self.cfg.base {
            Base::AmRrt => e,
            Base::RtRrt => {
                let area = self.map.grid().width_m() * self.map.grid().height_m();
                let r = crate::geometry::sqrt(
                    area * self.cfg.memory.n_max as f32
                        / (core::f32::consts::PI * nodes.max(1) as f32),
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
        self.nearest_for_step(env, x, None, meter).map(|(id, _)| id)
    }

    /// `Nearest(T, x)`, and whether the step of length `step` from it towards `x` is known to
    /// be free: with `step` (`nearest_step`) the Euclidean-nearest node's view
    /// is tested over that step only (module docs).
    fn nearest_for_step<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        x: Point,
        step: Option<f32>,
        meter: &Meter<'_, C>,
    ) -> Option<(NodeId, bool)> {
        meter.charge(8);
        // A node inside a dynamic obstacle can be no one's parent (every segment from it is
        // blocked): it is nobody's nearest either, or it would capture every sample around the
        // obstacle and the way around it could never grow (issue 24, Fig. 7).
        // Likewise a node in a cell the live overlay marked.
        let obstacles = env.map.obstacles();
        let marked = env.map.marked_cells() > 0;
        let cells = env.map.live();
        let positions = self.tree.positions();
        let usable = |id: NodeId| {
            (obstacles.is_empty() && !marked)
                || positions
                    .get(id.index())
                    .is_some_and(|&p| !obstacles.contains(p) && (!marked || cells.point_free(p)))
        };
        let (near, _) = self.index.nearest_where(x, positions, usable)?;
        if env.metric.is_euclidean() {
            return Some((near, false));
        }
        let a = self.pos(near);
        let end = step.map_or(x, |e| a.step_towards(x, e));
        if env.free(a, end, meter) {
            return Some((near, step.is_some()));
        }
        let mut best = (near, f32::INFINITY);
        let to = env.metric.prepare(x);
        for id in self.tree.ids() {
            // The metric scan reads the whole tree (about 2 ms for 2,048 nodes on a Cortex-M4
            // at 168 MHz): it gives up when the call's time is over.
            if id.0 & 63 == 63 && meter.expired(&env.call) {
                return None;
            }
            if !usable(id) {
                continue;
            }
            let d = env.metric_to(self.pos(id), &to, meter);
            if d < best.1 {
                best = (id, d);
            }
        }
        Some((best.0, false))
    }

    /// Steers from node `from` towards `x` (module docs); `None` when no state can be reached.
    /// `step_free`: the straight step was already tested free (`reuse_tests`).
    #[allow(clippy::too_many_arguments)]
    fn steer<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        from: NodeId,
        x: Point,
        e_max: f32,
        step_free: bool,
        meter: &Meter<'_, C>,
    ) -> Option<Point> {
        let a = self.pos(from);
        let step = a.step_towards(x, e_max);
        if step_free || env.free(a, step, meter) {
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
            let len = a.dist(step) * lo - STEP_BACK * e_max;
            if len < STEP_BACK * e_max {
                return None;
            }
            let p = a.step_towards(step, len);
            return env.free(a, p, meter).then_some(p);
        }
        // The free candidate closest to `x` by the metric (the first drawn among equals). The
        // metric is cheaper than a segment test of `e_max`: candidates are ranked first, in
        // batches, and segments tested in rank order until one is free.
        let radius = e_max.min(a.dist(x));
        let to = env.metric.prepare(x);
        let mut best: Option<(Point, f32)> = None;
        let mut left = env.cfg.search.steer_candidates;
        let mut fan = env
            .cfg
            .tactics
            .steer_fan
            .then(|| DiscFan::new(rng, a, radius, env.cfg.search.steer_candidates));
        while left > 0 {
            let n = left.min(STEER_BATCH_U16);
            left = left.saturating_sub(n);
            let mut batch = heapless::Vec::<(f32, Point), STEER_BATCH>::new();
            for _ in 0..n {
                let c = match fan.as_mut() {
                    Some(f) => f.next_state(rng),
                    None => sample_disc(rng, a, radius),
                };
                meter.charge(2);
                if !env.map.free_point(c) {
                    continue;
                }
                let d = env.metric_to(c, &to, meter);
                if best.is_none_or(|(_, bd)| d < bd) {
                    let _ = batch.push((d, c));
                }
            }
            // Lowest first (the first drawn among equals): a selection, not a sort, since the
            // first or second candidate tested is usually free.
            let mut tested: u32 = 0; // one bit per candidate (STEER_BATCH = 32)
            for _ in 0..batch.len() {
                let mut pick: Option<(usize, f32, Point)> = None;
                for (i, &(d, c)) in batch.iter().enumerate() {
                    let untested = tested & (1u32 << (i & 31)) == 0;
                    if untested && pick.is_none_or(|(_, pd, _)| d.total_cmp(&pd).is_lt()) {
                        pick = Some((i, d, c));
                    }
                }
                let Some((i, d, c)) = pick else {
                    break;
                };
                if env.free(a, c, meter) {
                    best = Some((c, d));
                    break;
                }
                tested |= 1u32 << (i & 31);
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
        mut target: Option<&mut Target>,
        meter: &Meter<'_, C>,
    ) -> Grown {
        let mut grown = Grown::default();
        let added = self.add_sample(env, rng, target.as_deref_mut(), meter, &mut grown.full);
        grown.added = added.map(|(id, _)| id);
        let Some(t) = target else {
            return grown;
        };
        if t.node.is_some() {
            return grown;
        }
        let joined = match added {
            Some((id, true)) => Some(id),
            // A new node near the goal, or no new node at all (the sample was a duplicate or
            // the neighbourhood was dense): try to connect the goal to the tree directly, so
            // neither the duplicate test nor the density rule can keep it out.
            Some((id, false)) if self.pos(id).dist(t.pos) > env.cfg.search.e_max => None,
            _ => self.join(env, rng, t, meter, &mut grown.full),
        };
        if let Some(g) = joined {
            t.node = Some(g);
            grown.goal_joined = true;
        }
        grown
    }

    /// Connects `goal` to the tree: the node already standing on it, or a new node below the
    /// cheapest node within `e_max` that sees it over a free segment (making room in a full
    /// arena). `None` when no node qualifies.
    fn join<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        target: &mut Target,
        meter: &Meter<'_, C>,
        full: &mut bool,
    ) -> Option<NodeId> {
        let goal = target.pos;
        meter.charge(8);
        let (q, d2) = self.index.nearest(goal, self.tree.positions())?;
        if d2 < env.duplicate_sq() {
            return Some(q);
        }
        let e_max = env.cfg.search.e_max;
        if d2 > e_max * e_max {
            return None;
        }
        let mut near = Near::new();
        self.nearby(goal, e_max, &mut near, meter);
        keep_candidate(&mut near, q);
        let (parent, edge) = self.best_parent(env, goal, &mut near, None, meter)?;
        self.insert_making_room(rng, goal, parent, edge, Some(target), None, meter, full)
    }

    /// Sample, nearest, steer and add (module docs): the new node, and whether it stands on
    /// the goal.
    fn add_sample<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        target: Option<&mut Target>,
        meter: &Meter<'_, C>,
        full: &mut bool,
    ) -> Option<(NodeId, bool)> {
        let cfg = env.cfg;
        let t = cfg.tactics;
        let view = target.as_deref().map(|t| self.goal_view(env, t, meter));
        let beacon = match (target.as_deref(), &view) {
            (Some(t), Some(v)) if v.ellipse.is_some() => self.beacon_sample(env, rng, t, meter),
            _ => None,
        };
        let gap = match (beacon, &view) {
            (None, Some(v)) => v.ellipse.and_then(|e| self.gap_sample(env, rng, &e, meter)),
            _ => None,
        };
        // A sample that landed in a narrow passage (not the fallback draw).
        let narrow = gap.is_some_and(|(_, n)| n);
        let x_rand = match beacon.or(gap.map(|(p, _)| p)) {
            Some(p) => p,
            None => sample_state(
                rng,
                env.map,
                view.as_ref(),
                cfg.search.p_goal,
                cfg.search.p_uniform,
                cfg.search.sample_attempts,
            )?,
        };
        meter.charge(4);
        // Between the parts of a step, the call's deadline (issue 25: sampling, nearest,
        // steering and the neighbourhood together ran 1 ms without a look at the clock on a
        // Cortex-M4F); a state dropped at the deadline is one a next call draws again.
        if meter.expired(&env.call) {
            return None;
        }
        // Longer steps while this tree's goal is not in it (tuned configurations).
        let searching = target.as_deref().is_some_and(|t| t.node.is_none());
        let step = if searching {
            cfg.search_step()
        } else {
            cfg.search.e_max
        };
        // `nearest_step`: `Nearest` tests its Euclidean choice over the step only; with
        // `reuse_tests` no segment is tested twice in an expansion (the steering's step, the
        // parent's segment).
        let (x_nearest, step_free) =
            self.nearest_for_step(env, x_rand, t.nearest_step.then_some(step), meter)?;
        if meter.expired(&env.call) {
            return None;
        }
        // A narrow sample whose nearest node's step is blocked is taken as it is, below any
        // node within the radius that sees it (`best_parent`, none: no node): steering from
        // the nearest node would put the node outside the passage the sample found.
        let direct = narrow && !step_free;
        let x_new = if direct {
            x_rand
        } else {
            self.steer(
                env,
                rng,
                x_nearest,
                x_rand,
                step,
                step_free && t.reuse_tests,
                meter,
            )?
        };
        if meter.expired(&env.call) {
            return None;
        }
        let is_goal = target
            .as_deref()
            .is_some_and(|t| t.node.is_none() && t.pos == x_new);
        // Not already in the tree (the goal is then joined to that node by `join`).
        let nearest_sq = match self.index.nearest(x_new, self.tree.positions()) {
            Some((_, d2)) if d2 < env.duplicate_sq() => return None,
            Some((_, d2)) => d2,
            None => f32::INFINITY,
        };
        let radius = env.radius(self.tree.len());
        let mut near = Near::new();
        let found = self.nearby(x_new, radius, &mut near, meter);
        if meter.expired(&env.call) {
            return None;
        }
        let far_sample = self.pos(x_nearest).dist(x_rand) > cfg.search.e_max;
        // Denser where a node can still shorten the path (tuned configurations).
        let informed = view
            .as_ref()
            .and_then(|v| v.ellipse)
            .is_some_and(|e| e.contains(x_new));
        let n_max = if informed {
            cfg.memory.n_max.max(cfg.memory.n_max_informed)
        } else {
            cfg.memory.n_max
        };
        // A starving search (liveness): a state in a hole of the cover the rule aims at (no
        // node within `e_max / sqrt(n_max)`, the spacing of `n_max` nodes spread over an
        // `e_max` disc) is let in, so no region whose way out is narrow stays closed.
        let spacing = cfg.search.e_max / crate::geometry::sqrt(f32::from(n_max.max(1)));
        let hole = searching && self.refused >= STARVING && nearest_sq > spacing * spacing;
        let room = found < n_max as usize || far_sample || is_goal;
        let by_hole = hole && !room;
        let dense = !room && !hole;
        // A dense neighbourhood inside the ellipse may still trade (`density_trades`): its
        // worst leaf for a state that bounds a shorter path.
        let swap = match (&view, target.as_deref()) {
            (Some(v), Some(tg)) if dense && informed && t.density_trades => {
                let cover = self.cover(cfg.memory.recycle_cover);
                self.worst_leaf(&near, x_new, v.goal, tg.node, cover, meter)
            }
            _ => None,
        };
        if dense && swap.is_none() {
            if searching {
                self.refused = self.refused.saturating_add(1);
            }
            if cfg.base == Base::RtRrt {
                let _ = self.goal_queue.push_back(x_nearest);
            }
            return None;
        }
        // Keep x_nearest a candidate even when the list was truncated (steered: it sees
        // `x_new`).
        let seen = if direct {
            None
        } else {
            keep_candidate(&mut near, x_nearest);
            // The steering's segment from x_nearest is known free.
            t.reuse_tests.then_some(x_nearest)
        };
        let (parent, edge) = self.best_parent(env, x_new, &mut near, seen, meter)?;
        // The new state's cost bound below `parent`: a lower bound of a path through it.
        let bound = |s: &Self, goal: Point| {
            s.cost(parent).extend(
                env.charged(s.pos(parent).dist(x_new), edge.class) + x_new.dist(goal),
                false,
            )
        };
        let id = match (swap, &view, target) {
            // A dense neighbourhood's trade: the worst leaf's slot, if the state does better.
            (Some((score, victim)), Some(v), Some(t)) => {
                if bound(self, v.goal) >= score || victim == parent {
                    return None;
                }
                let mut keep = [parent, t.node.unwrap_or(parent)];
                if !self.remove_leaf_renaming(victim, &mut keep) {
                    return None;
                }
                if t.node.is_some() {
                    t.node = Some(keep[1]);
                }
                self.insert(x_new, keep[0], edge).ok()?
            }
            // A full tree may trade a leaf for a state that can shorten the path
            // (`recycle_when_full`).
            (_, _, target) => {
                let trade = (t.recycle_when_full && informed).then(|| Trade {
                    bound: bound(self, view.as_ref().map_or(x_new, |v| v.goal)),
                    cover: cfg.memory.recycle_cover,
                });
                self.insert_making_room(rng, x_new, parent, edge, target, trade, meter, full)?
            }
        };
        // RRT*'s rewiring around the new node: each neighbour takes it as parent when that is
        // cheaper over a free segment (`rewire_new`, inside the informed ellipse). A
        // trade may have renamed one of `near`'s ids; `try_rewire` checks cost and segment of
        // whatever node an id now names, so that is at worst a wasted test.
        if t.rewire_new && informed {
            for &nb in near.iter() {
                if meter.expired(&env.call) {
                    break;
                }
                meter.charge(1);
                self.try_rewire(env, id, nb, meter);
            }
        }
        if cfg.base == Base::RtRrt {
            let _ = self.goal_queue.push_back(id);
        }
        self.refused = 0;
        if by_hole {
            self.holes = self.holes.saturating_add(1);
        }
        Some((id, is_goal))
    }

    /// RRT-Connect's greedy step (the `connect` tactic): from the node nearest `x`, straight
    /// steps of at most `step` towards `x`, each added below the last when its segment is free,
    /// until a node within `step` of `x` sees it over a free segment (returned), or a step is
    /// blocked, the arena is full or [`CONNECT_STEPS`] nodes were added (`None`; the nodes
    /// added stay, as in RRT-Connect). `blocked`: nodes whose segment to `x` is known blocked.
    pub(crate) fn connect<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        x: Point,
        step: f32,
        blocked: &[NodeId],
        meter: &Meter<'_, C>,
    ) -> Option<NodeId> {
        meter.charge(8);
        let (mut from, _) = self.index.nearest(x, self.tree.positions())?;
        if blocked.contains(&from) && self.pos(from).dist(x) <= step {
            return None; // the meet test found this segment blocked
        }
        for _ in 0..=CONNECT_STEPS {
            let a = self.pos(from);
            if a.dist(x) <= step {
                return env.free(a, x, meter).then_some(from);
            }
            let next = a.step_towards(x, step);
            if self.tree.is_full() || !env.free(a, next, meter) {
                return None;
            }
            meter.charge(4);
            let edge = env.edge(a, next, meter);
            from = self.insert(next, from, edge).ok()?;
        }
        None
    }

    /// With probability [`crate::config::Search::p_gap`] (no draw at all when it is 0): a free
    /// state of `ellipse` in a narrow passage, one narrower than `e_max / 8`, or failing that
    /// the first free state drawn; nothing when the call's deadline passes among the draws.
    fn gap_sample<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        ellipse: &Ellipse,
        meter: &Meter<'_, C>,
    ) -> Option<(Point, bool)> {
        // A map whose cells are coarse for this `e_max` has no passage that narrow: no draw.
        let reach = sat_u32(env.cfg.search.e_max / GAP_WIDTH_DIV / env.map.grid().cell_size())
            .min(GAP_MAX_CELLS);
        let p = env.cfg.search.p_gap;
        if reach == 0 || p <= 0.0 || unit_f32(rng) >= p {
            return None;
        }
        let attempts = env.cfg.search.sample_attempts.saturating_mul(4);
        // A draw is a square root and a sine-cosine (software double precision on a
        // Cortex-M4F: about as long as a dozen units of other work) and up to four rows of
        // `reach` cells. Measured on the M4F firmware, 256 draws took 5.8 ms while charged
        // as 256 units, and the tuned set's calls overran by as much (issue 42): the draws
        // are charged at their cost and the deadline is checked between batches of them.
        let per_draw = GAP_DRAW_UNITS.saturating_add(reach / 2);
        let mut charged = 0u16;
        let (narrow, first, draws) =
            crate::sample::narrow_free(rng, env.map, ellipse, to_u16(reach), attempts, |batch| {
                charged = charged.saturating_add(batch);
                meter.charge(u32::from(batch).saturating_mul(per_draw));
                !meter.expired(&env.call)
            });
        meter.charge(u32::from(draws.saturating_sub(charged)).saturating_mul(per_draw));
        match narrow {
            Some(p) => Some((p, true)),
            None => first.map(|p| (p, false)),
        }
    }

    /// With probability [`crate::config::Search::p_beacon`] (no draw at all when it is 0): a free state in the
    /// `e_max` disc around a uniformly chosen node of the path to the joined goal.
    fn beacon_sample<M: Metric, R: Rng + ?Sized, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        rng: &mut R,
        target: &Target,
        meter: &Meter<'_, C>,
    ) -> Option<Point> {
        let p = env.cfg.search.p_beacon;
        if p <= 0.0 || unit_f32(rng) >= p {
            return None;
        }
        let goal = target.node?;
        let depth = self.tree.depth(goal)?;
        let mut b = goal;
        for _ in 0..rng.next_u32().checked_rem(units(depth).saturating_add(1))? {
            b = self.tree.parent(b)?;
        }
        meter.charge(units(depth).saturating_add(4));
        let s = sample_disc(rng, self.pos(b), env.cfg.search.e_max);
        env.map.free_point(s).then_some(s)
    }

    /// The candidate giving `x` the lowest cost over a free segment, and that edge: candidates
    /// are ordered by the cost they would give, and segments are tested in that order until
    /// one is free (`seen`'s segment to `x` is known free: the steering tested it). With a
    /// clearance preference the order is by the Euclidean cost, a lower bound: the scan goes
    /// on past the first free candidate while a later one's bound is below the best charged
    /// cost found (branch and bound; the same choice as testing all).
    pub(crate) fn best_parent<M: Metric, C: Clock + ?Sized, const K: usize>(
        &self,
        env: &Env<'_, '_, M, K>,
        x: Point,
        candidates: &mut Near,
        seen: Option<NodeId>,
        meter: &Meter<'_, C>,
    ) -> Option<(NodeId, Edge)> {
        // Each key once (a square root each), then the sort: computed inside the comparisons,
        // the keys cost about 2,000 software square roots per call of this function on a
        // Cortex-M4F, 2 ms (issue 25). Same keys, same stable sort: the same order.
        let mut keyed: heapless::Vec<(u64, NodeId), NEAR_CAP> = heapless::Vec::new();
        for &id in candidates.iter() {
            let key = self.cost(id).extend(self.pos(id).dist(x), false).sort_key();
            // As many as `candidates` hold: never refused.
            let _ = keyed.push((key, id));
        }
        sort_small_by(&mut keyed, |a, b| a.0.cmp(&b.0));
        for (slot, &(_, id)) in candidates.iter_mut().zip(keyed.iter()) {
            *slot = id;
        }
        // Up to 64 segment tests: the call's deadline is checked before each (issue 25: on a
        // Cortex-M4F the tuned set's long steps made this loop run 3 ms past it). A deadline
        // passed drops the state, as a blocked neighbourhood does.
        let mut best: Option<(Cost, NodeId, Edge)> = None;
        for (&id, &(key, _)) in candidates.iter().zip(keyed.iter()) {
            if best.is_some_and(|(c, _, _)| key >= c.sort_key()) {
                break;
            }
            let p = self.pos(id);
            if seen != Some(id) {
                if meter.expired(&env.call) {
                    return best.map(|(_, id, e)| (id, e));
                }
                if !env.free(p, x, meter) {
                    continue;
                }
            }
            if !env.weighted() {
                return Some((id, Edge::default()));
            }
            let edge = env.edge(p, x, meter);
            let cost = self
                .cost(id)
                .extend(env.charged(p.dist(x), edge.class), false);
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, id, edge));
            }
        }
        best.map(|(_, id, e)| (id, e))
    }
}

#[cfg(test)]
mod tests;
