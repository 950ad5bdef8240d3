//! Meet and graft of the two trees (paper Algorithm 1's bidirectional search, section 3.3),
//! and, with the `connect` tactic, RRT-Connect's greedy step; the module's "Meet and graft".

use super::*;

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// The `connect` tactic: the other tree walks straight towards node `new` of one tree (`forward`
    /// tells which), and the two are grafted when it reaches it (module docs). `blocked`:
    /// nodes of the other tree whose segment to `new` the meet test found blocked (not
    /// tested again).
    pub(super) fn connect<C: Clock + ?Sized>(
        &mut self,
        new: NodeId,
        forward: bool,
        blocked: &[NodeId],
        meter: &Meter<'_, C>,
    ) {
        if !self.cfg.tactics.connect {
            return;
        }
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        let step = self.cfg.search_step();
        let pair = if forward {
            let p = self.fwd.pos(new);
            self.rev
                .connect(&env, p, step, blocked, meter)
                .map(|b| (new, b))
        } else {
            let p = self.rev.pos(new);
            self.fwd
                .connect(&env, p, step, blocked, meter)
                .map(|a| (a, new))
        };
        if let Some((a, b)) = pair {
            self.meet(a, b, meter);
        }
    }

    /// The `roadmap` tactic (module [`crate::roadmap`]): searches the attached roadmap from the
    /// root to the goal, tests every edge of the path found, makes it a branch of the reverse
    /// tree (one-tree planners borrow the reverse arena for it) and grafts it below the root.
    /// `Some(joined)` once the goal's search has ended, `None` when the call's time ran out
    /// first: the search waits in [`crate::roadmap::Stage`] for the next call, its scratch in
    /// the reverse arena's last free slots (one per roadmap node), and the trees do not grow
    /// meanwhile.
    #[cfg(feature = "roadmap")]
    pub(super) fn roadmap_join<C: Clock + ?Sized>(
        &mut self,
        meter: &Meter<'_, C>,
        call: Deadline,
    ) -> Option<bool> {
        use crate::roadmap::{Poll, Scratch, Stage};
        let stage = core::mem::take(&mut self.roadmap_stage);
        let (Some(rm), Some(goal)) = (self.roadmap, self.goal) else {
            return Some(false);
        };
        if matches!(stage, Stage::Idle) || !self.cfg.tactics.roadmap || goal.node.is_some() {
            return Some(false);
        }
        let root = self.root_position();
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call,
        };
        let one_tree = self.rev_goal.is_none();
        // A stage left by an earlier call: the path's ends are tested again when it is found.
        let carried = matches!(stage, Stage::Open(_) | Stage::Found { .. });
        let mut stage = stage;
        // Open, run and end the search (each arm moves on or returns).
        let (len, mut tested) = loop {
            let scratch = self
                .rev
                .tree
                .spare(rm.len())
                .map(|(g, parent, heap, slot)| Scratch {
                    g,
                    parent,
                    heap,
                    slot,
                });
            stage = match stage {
                Stage::Idle => return Some(false),
                Stage::Due => {
                    // The straight segment first: when free, it is the path (no search).
                    if env.free(root, goal.pos, meter) {
                        Stage::Found { len: 0, tested: 0 }
                    } else if meter.expired(&call) {
                        self.roadmap_stage = Stage::Blocked;
                        return None;
                    } else {
                        Stage::Blocked
                    }
                }
                Stage::Blocked => {
                    let Some(mut scratch) = scratch else {
                        return Some(false);
                    };
                    match crate::roadmap::open(&rm, (root, goal.pos), &mut scratch, meter) {
                        Some(search) => Stage::Open(search),
                        None => return Some(false),
                    }
                }
                Stage::Open(mut search) => {
                    let Some(mut scratch) = scratch else {
                        return Some(false);
                    };
                    match crate::roadmap::resume(&rm, &env, &mut search, &mut scratch, meter) {
                        Poll::Pending => {
                            self.roadmap_stage = Stage::Open(search);
                            return None;
                        }
                        Poll::Found(len) => Stage::Found { len, tested: 0 },
                        Poll::NoPath => return Some(false),
                    }
                }
                Stage::Found { len, tested } => break (len, tested),
            };
        };
        // The branch fills the arena's first free slots while its nodes are read from the
        // last ones: they must not meet (a path longer than half the free slots is dropped).
        let base = if one_tree { 1 } else { self.rev.tree.len() };
        if base.saturating_add(len.saturating_mul(2)) > N {
            return Some(false);
        }
        // The path's `k`-th node from the goal's end (the search left its id there).
        fn node_at<const N: usize>(
            tree: &crate::tree::Tree<N>,
            rm: &crate::roadmap::Roadmap<'_>,
            k: usize,
        ) -> Option<Point> {
            tree.spare_from_end(k).and_then(|i| rm.node(usize::from(i)))
        }
        // Node `k` of the path counted from the goal's end, the goal standing for -1 and the
        // root for `len`.
        let node = |k: usize| {
            if k >= len {
                root
            } else {
                node_at(&self.rev.tree, &rm, k).unwrap_or(goal.pos)
            }
        };
        // Segment `k` joins nodes `k - 1` and `k`. The ends (segments 0 and `len`) were tested
        // when the search settled on its way, in this call unless `carried`. The roadmap's own
        // edges are tested here, against everything the map holds now. They are free of the
        // grid it was baked for (`fits` checked its cells): for a point robot on a map whose
        // live cells mark nothing, only the dynamic obstacles are left to test.
        let baked_free = self.map.radius() == 0.0 && self.map.marked_cells() == 0;
        let obstacles = units(self.map.obstacles().len());
        while tested <= len {
            let k = tested;
            let end = k == 0 || k == len;
            if carried || !end {
                let a = if k == 0 {
                    goal.pos
                } else {
                    node(k.saturating_sub(1))
                };
                let b = node(k);
                let free = if baked_free && !end {
                    meter.charge(obstacles.saturating_add(2));
                    !self.map.obstacles().blocks_segment(a, b)
                } else {
                    env.free(a, b, meter)
                };
                if !free {
                    return Some(false);
                }
            }
            tested = tested.saturating_add(1);
            if tested <= len && meter.expired(&call) {
                self.roadmap_stage = Stage::Found { len, tested };
                return None;
            }
        }
        // The path becomes a branch of the reverse tree below its root (the goal), and the
        // branch's last node meets the forward root.
        if one_tree {
            self.rev.reset(goal.pos);
        }
        let mut met = false;
        if let (Some(a), Some(mut parent)) = (self.fwd.tree.root(), self.rev.tree.root()) {
            let mut prev = goal.pos;
            let mut built = true;
            for k in 0..len {
                // (The branch's slots stay below the path's: checked above.)
                let Some(p) = node_at(&self.rev.tree, &rm, k) else {
                    built = false;
                    break;
                };
                let edge = env.edge(prev, p, meter);
                match self.rev.insert(p, parent, edge) {
                    Ok(id) => parent = id,
                    Err(_) => {
                        built = false;
                        break;
                    }
                }
                prev = p;
            }
            met = built && self.meet(a, parent, meter);
        }
        if one_tree {
            self.rev.clear();
        }
        self.stats.roadmap = met;
        Some(met)
    }

    /// Grafts the reverse tree below forward node `a` at reverse node `b` (their segment tested
    /// free) and records the goal joining; returns whether the graft was made.
    fn meet<C: Clock + ?Sized>(&mut self, a: NodeId, b: NodeId, meter: &Meter<'_, C>) -> bool {
        let segment = [self.fwd.pos(a), self.rev.pos(b)];
        let met = self.graft(a, b, meter);
        if met {
            self.stats.met = true;
            self.stats.meet = Some(segment);
            self.goal_joined(meter);
        }
        met
    }

    /// Meet test for a node just added to one tree (`forward` tells which) against the other,
    /// and graft on success (module docs). `Ok` when the trees met; otherwise `Err` with the
    /// nodes of the other tree whose segment to `new` was found blocked (none when a free pair
    /// was found but the graft was refused).
    pub(super) fn try_meet<C: Clock + ?Sized>(
        &mut self,
        new: NodeId,
        forward: bool,
        meter: &Meter<'_, C>,
    ) -> Result<(), heapless::Vec<NodeId, MEET_PAIRS>> {
        let (this, other) = if forward {
            (&*self.fwd, &*self.rev)
        } else {
            (&*self.rev, &*self.fwd)
        };
        let p = this.pos(new);
        let c_new = this.cost(new);
        let sigma = self.cfg.search.sigma;
        // The MEET_PAIRS cheapest candidates, kept sorted by total cost.
        let mut best: heapless::Vec<(Cost, NodeId), MEET_PAIRS> = heapless::Vec::new();
        let mut seen = 0u32;
        let _ = other
            .index
            .for_each_within(p, sigma, other.tree.positions(), |id, d2| {
                seen = seen.saturating_add(1);
                let c_other = other.cost(id);
                let total = Cost {
                    length: c_new.length + crate::geometry::sqrt(d2) + c_other.length,
                    blocked: c_new.blocked || c_other.blocked,
                };
                let at = best.partition_point(|(c, _)| *c <= total);
                if at < MEET_PAIRS {
                    if best.is_full() {
                        best.pop();
                    }
                    let _ = best.insert(at, (total, id));
                }
                core::ops::ControlFlow::Continue(())
            });
        meter.charge(seen.saturating_add(4));
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        let mut partner = best
            .iter()
            .find(|(_, id)| env.free(p, other.pos(*id), meter))
            .map(|&(_, id)| id);
        // The paper's Meet: any pair within sigma with a free segment (AsPrinted::meet_all_pairs).
        if partner.is_none() && self.cfg.as_printed.meet_all_pairs && best.is_full() {
            let call = self.call;
            let _ = other
                .index
                .for_each_within(p, sigma, other.tree.positions(), |id, _| {
                    if meter.expired(&call) {
                        return core::ops::ControlFlow::Break(());
                    }
                    meter.charge(1);
                    if best.iter().all(|&(_, b)| b != id) && env.free(p, other.pos(id), meter) {
                        partner = Some(id);
                        return core::ops::ControlFlow::Break(());
                    }
                    core::ops::ControlFlow::Continue(())
                });
        }
        let Some(partner) = partner else {
            let mut blocked = heapless::Vec::new();
            for &(_, id) in &best {
                let _ = blocked.push(id);
            }
            return Err(blocked);
        };
        let (a, b) = if forward {
            (new, partner)
        } else {
            (partner, new)
        };
        if self.meet(a, b, meter) {
            Ok(())
        } else {
            Err(heapless::Vec::new())
        }
    }

    /// Grafts the reverse tree's trunk from `b` to its root (the goal) below forward node `a`,
    /// recycling forward leaves when the arena lacks room. Refused (returns false) when the
    /// trunk cannot fit.
    pub(super) fn graft<C: Clock + ?Sized>(
        &mut self,
        a: NodeId,
        b: NodeId,
        meter: &Meter<'_, C>,
    ) -> bool {
        let rev = &self.rev.tree;
        let mut depth = 0usize;
        let mut v = Some(b);
        while let Some(x) = v {
            depth = depth.saturating_add(1);
            if depth > rev.len() {
                return false;
            }
            v = rev.parent(x);
        }
        let mut parent = a;
        let need = self.fwd.tree.len().saturating_add(depth).saturating_sub(N);
        if need > 0 {
            // Make room: recycle forward leaves (never `a` or its ancestors, which have
            // children). Refused when the trunk alone would not fit.
            self.full = true;
            let goal = self.goal.map_or(self.rev.pos(b), |g| g.pos);
            if depth >= N {
                return false;
            }
            let mut keep = [parent];
            for _ in 0..need {
                if !self.fwd.recycle(&mut self.rng, goal, &mut keep, meter) {
                    return false;
                }
            }
            parent = keep[0];
        }
        meter.charge(units(depth).saturating_mul(4));
        // The meeting segment was tested free; each later edge keeps both of its flags (an
        // edge through a marked cell stays walled, or re-flagging for an obstacle would clear
        // it).
        // The meeting segment's clearance class is measured; the trunk's edges keep theirs.
        let (mut blocked, mut walled) = (false, false);
        let mut class = self.clearance_class(self.fwd.pos(parent), self.rev.pos(b), meter);
        let mut v = Some(b);
        while let Some(x) = v {
            let pos = self.rev.pos(x);
            match self.fwd.insert(pos, parent, Edge { blocked, class }) {
                Ok(id) => parent = id,
                Err(_) => return false,
            }
            if walled {
                self.fwd.tree.set_edge_walled(parent, true);
            }
            (blocked, walled) = self.rev.tree.edge_sources(x);
            class = self.rev.tree.edge_class(x).unwrap_or(0);
            v = self.rev.tree.parent(x);
        }
        if let Some(goal) = self.goal.as_mut() {
            goal.node = Some(parent);
        }
        true
    }
}
