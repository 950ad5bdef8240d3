//! Following the agent and the waypoint rule (paper Algorithm 1, lines 3-6, and beyond it
//! the safety rule): re-rooting at the path's next node, the agent's anchor when it cannot
//! see the root, and the [`Progress`] a call returns; the module's "One `plan` call" and
//! "The waypoint rule".

use super::*;

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// The call's report. With an agent position, the waypoint rule is enforced here, last.
    pub(super) fn progress<C: Clock + ?Sized>(
        &self,
        agent: Option<Point>,
        expansions: u32,
        advanced: bool,
        meter: &Meter<'_, C>,
    ) -> Progress {
        let goal_node = self.goal_node();
        let goal_cost = goal_node.and_then(|g| self.fwd.tree.cost(g));
        let root = self.root_position();
        let at = agent.unwrap_or(root);
        let arrived = goal_node.is_some() && self.goal.is_some_and(|g| g.pos == at);
        let trapped = agent.is_some() && self.trapped(at);
        // The waypoint rule (module `motion`): the root when it is clear, else a nearer point
        // on the way, else hold, else evade.
        let planned = if arrived { at } else { root };
        let choice = match agent {
            Some(a) if !trapped => {
                // The rule's tests of the obstacles (none to charge without obstacles: the
                // paper's check of one segment, as before).
                meter.charge(units(self.map.obstacles().len().saturating_mul(64)));
                choose(&self.map, &self.cfg.motion, a, planned)
            }
            Some(_) => Choice::Hold,
            None => Choice::Planned,
        };
        let waypoint = match choice {
            Choice::Planned => planned,
            Choice::Shortened(q) | Choice::Evade(q) => q,
            Choice::Hold | Choice::Cornered => at,
        };
        let status = match self.goal {
            None => Status::NoGoal,
            Some(_) if trapped => Status::Waiting(Wait::AgentInObstacle),
            Some(_) if arrived => Status::Arrived,
            Some(_) if matches!(choice, Choice::Cornered) => Status::Waiting(Wait::Cornered),
            Some(_) if matches!(choice, Choice::Evade(_)) => Status::Evading,
            Some(_)
                if matches!(choice, Choice::Hold)
                    && agent.is_some_and(|a| a != root && !self.map.free_now(a, root)) =>
            {
                Status::Waiting(Wait::AgentBlocked)
            }
            Some(_) if matches!(choice, Choice::Hold) && agent != Some(root) => {
                Status::Waiting(Wait::GivingWay)
            }
            Some(g) if !self.metric.distance(at, g.pos).is_finite() => Status::Unreachable,
            Some(_) if goal_node.is_none() => Status::Searching,
            Some(_) if goal_cost.is_some_and(|c| c.blocked) => Status::Waiting(Wait::PathBlocked),
            Some(_) if matches!(choice, Choice::Hold) => Status::Waiting(Wait::GivingWay),
            Some(_) if self.deferred && agent == Some(root) => Status::Waiting(Wait::OutOfTime),
            Some(_) => Status::Following,
        };
        Progress {
            waypoint,
            status,
            work: meter.work(),
            goal_in_tree: goal_node.is_some(),
            goal_cost,
            nodes: self.fwd.tree.len(),
            reverse_nodes: self.rev.tree.len(),
            expansions,
            advanced,
            tree_full: self.full,
        }
    }

    /// Makes sure the agent can reach the root: when a straight free segment does not join
    /// them, the agent's position becomes the root (see [`Planner::plan`]).
    pub(super) fn anchor<C: Clock + ?Sized>(&mut self, agent: Point, meter: &Meter<'_, C>) {
        let root = self.root_position();
        meter.charge(12);
        if agent == root || self.map.free_now(agent, root) {
            return;
        }
        // The agent stands on a node: that node becomes the root.
        if let Some((q, d2)) = self.fwd.index.nearest(agent, self.fwd.tree.positions())
            && d2 < crate::expand::duplicate_sq(self.map.grid().cell_size())
            && self.fwd.tree.set_root(q).is_ok()
        {
            meter.charge(units(N / 8));
            self.stats.reanchored = self.stats.reanchored.saturating_add(1);
            self.fwd.restart_sweeps();
            return;
        }
        // Candidates: nodes within e_max, cheapest first (edges crossing a circle last), joined
        // to the agent past the map.
        let mut near = Near::new();
        self.fwd
            .nearby(agent, self.cfg.search.e_max, &mut near, meter);
        let circles = self.map.obstacles();
        let crosses = |id: NodeId| circles.blocks_segment(self.fwd.pos(id), agent);
        let key = |id: NodeId| {
            self.fwd
                .cost(id)
                .extend(self.fwd.pos(id).dist(agent), crosses(id))
        };
        sort_small_by(&mut near, |&a, &b| key(a).cmp(&key(b)));
        let cells = self.map.live();
        let parent = near.iter().copied().find(|&id| {
            meter.charge(4);
            cells.segment_free(self.fwd.pos(id), agent)
        });
        let goal = self.goal.map_or(agent, |g| g.pos);
        let anchored = parent.is_some_and(|parent| {
            let blocked = self
                .map
                .obstacles()
                .blocks_segment(self.fwd.pos(parent), agent);
            let mut keep = [parent, self.goal_node().unwrap_or(parent)];
            if self.fwd.tree.is_full() {
                self.full = true;
                if !self.fwd.recycle(&mut self.rng, goal, &mut keep, meter) {
                    return false;
                }
                self.rename_goal(keep[1]);
            }
            let class = self.clearance_class(self.fwd.pos(keep[0]), agent, meter);
            let Ok(id) = self.fwd.insert(agent, keep[0], Edge { blocked, class }) else {
                return false;
            };
            meter.charge(units(N / 8));
            self.fwd.tree.set_root(id).is_ok()
        });
        if anchored {
            self.stats.reanchored = self.stats.reanchored.saturating_add(1);
            self.fwd.restart_sweeps();
        } else {
            // No node reaches the agent (or no room): the tree cannot serve it; start over here.
            self.stats.restarted = self.stats.restarted.saturating_add(1);
            self.fwd.reset(agent);
            if let Some(goal) = self.goal {
                self.begin_search(goal.pos);
            }
        }
    }

    /// Whether an agent at `p` stands inside a dynamic obstacle or a marked cell: any motion
    /// would cross it, so it holds.
    pub(super) fn trapped(&self, p: Point) -> bool {
        self.map.obstacles().contains_now(p) || !self.map.live().point_free(p)
    }

    /// After recycling in the forward tree: the goal node's id may have moved.
    fn rename_goal(&mut self, renamed: NodeId) {
        if let Some(g) = self.goal.as_mut()
            && g.node.is_some()
        {
            g.node = Some(renamed);
        }
    }

    /// Re-roots at the path's next node when the agent has reached the root; with a root
    /// step ([`Config::rewiring`]), on past nodes the agent already stands on (a short edge
    /// would hold it for a call), at most [`FOLLOW_STEPS`] nodes per call.
    ///
    /// A step starts only when it ends before `by` ([`Meter::affords`]): the call's deadline
    /// once the call has expanded, never at its start, where following is the progress every
    /// call makes (a `t_exp` shorter than a re-rooting then overruns by one).
    pub(super) fn follow<C: Clock + ?Sized>(
        &mut self,
        agent: Point,
        meter: &Meter<'_, C>,
        by: Deadline,
    ) -> bool {
        let steps = if self.cfg.rewiring.root_step > 0.0 {
            FOLLOW_STEPS
        } else {
            1
        };
        let mut advanced = false;
        for _ in 0..steps {
            if !self.follow_once(agent, meter, by) {
                break;
            }
            advanced = true;
        }
        advanced
    }

    /// One step of [`Planner::follow`].
    fn follow_once<C: Clock + ?Sized>(
        &mut self,
        agent: Point,
        meter: &Meter<'_, C>,
        by: Deadline,
    ) -> bool {
        let root = self.root_position();
        if agent.dist(root) > self.cfg.search.e_max / AT_ROOT_DIV {
            return false;
        }
        // With a root step (tuned), the root moves only along a path to the goal: towards
        // the node nearest a goal not yet joined it could take the agent the wrong way just
        // before the goal joins (a search takes tens of microseconds). Unless the search is
        // stuck: a full arena that has made `STUCK_EXPANSIONS x N` expansions without the
        // goal finds it only by moving on, as the paper's planners do (the nodes left behind
        // become the ones recycled).
        let stuck = self.fwd.tree.is_full()
            && self.stats.expansions >= (N as u64).saturating_mul(STUCK_EXPANSIONS);
        if self.cfg.rewiring.root_step > 0.0 && self.goal_node().is_none() && !stuck {
            return false;
        }
        let Some(end) = self.path_end(meter) else {
            return false;
        };
        // The node after the root on the path to `end`, and the one after it: walk up from
        // `end`.
        let tree = &self.fwd.tree;
        let (mut next, mut after) = (end, None);
        for _ in 0..tree.len() {
            match tree.parent(next) {
                Some(p) if Some(p) == tree.root() => break,
                Some(p) => (next, after) = (p, Some(next)),
                None => return false,
            }
        }
        if tree.parent(next) != tree.root() || tree.edge_blocked(next) != Some(false) {
            return false;
        }
        // A re-rooting refreshes every cost in the tree (with a long first edge split first,
        // a subtree move): it starts only when it ends before `by`.
        if !meter.affords(self.reroot_nodes(), &by) {
            self.deferred = true;
            return false;
        }
        // With path shortcuts (tuned), the root is offered as parent to the node after
        // `next` first: the agent is about to commit to the path's first edge, which the
        // anytime shortcuts may not have reached yet (a goal that joins in a call leaves its
        // first edges as the search made them).
        let next = match after {
            Some(n2)
                if self.cfg.rewiring.path_shortcuts > 0 && self.shortcut_from_root(n2, meter) =>
            {
                n2
            }
            _ => next,
        };
        let next = self.split_long_edge(next, meter);
        // The agent is near the root, not always on it: it must see the next node in a
        // straight free line, or it first finishes its way to the root.
        if !self.map.free_path(agent, self.fwd.pos(next)) {
            return false;
        }
        meter.charge(units(self.fwd.tree.len()));
        let since = meter.now();
        if self.fwd.tree.set_root(next).is_err() {
            return false;
        }
        meter.timed_refresh(self.fwd.tree.len(), since);
        self.fwd.restart_sweeps();
        true
    }

    /// The nodes a step of [`Planner::follow`] refreshes at most: a re-rooting refreshes every
    /// node's cost, and a long first edge's split moves a subtree first.
    pub(super) fn reroot_nodes(&self) -> u64 {
        (self.fwd.tree.len() as u64).saturating_mul(2)
    }

    /// Makes `node` a child of the root when the segment is free and that shortens its path
    /// (a Theta* shortcut at the root, by the rewiring step). Whether it did.
    fn shortcut_from_root<C: Clock + ?Sized>(
        &mut self,
        node: NodeId,
        meter: &Meter<'_, C>,
    ) -> bool {
        let Some(root) = self.fwd.tree.root() else {
            return false;
        };
        let env = Env {
            map: &self.map,
            metric: &self.metric,
            cfg: &self.cfg,
            call: self.call,
        };
        self.fwd.try_rewire(&env, root, node, meter)
    }

    /// The root step ([`Config::rewiring`]): when the edge from the root to the path's next
    /// node `next` is longer than the step, a node that far along it becomes the next waypoint instead, so
    /// a goal that changes never finds the agent bound to a root far away. The edge was
    /// free, so are its parts. Returns the node to re-root at: `next` when the edge is short,
    /// the step 0, or the arena has no slot to give.
    fn split_long_edge<C: Clock + ?Sized>(&mut self, next: NodeId, meter: &Meter<'_, C>) -> NodeId {
        let Some(root) = self.fwd.tree.root() else {
            return next;
        };
        let (a, b) = (self.fwd.pos(root), self.fwd.pos(next));
        let step = self.cfg.rewiring.root_step;
        if step <= 0.0 || a.dist(b) <= step {
            return next;
        }
        let mut keep = [next, self.goal_node().unwrap_or(next)];
        if self.fwd.tree.is_full() {
            let toward = self.goal.map_or(b, |g| g.pos);
            if !self.fwd.recycle(&mut self.rng, toward, &mut keep, meter) {
                return next;
            }
            self.rename_goal(keep[1]);
        }
        let [next, _] = keep;
        let Some(root) = self.fwd.tree.root() else {
            return next;
        };
        // Both halves lie on the edge's line: they keep its clearance class.
        let edge = Edge {
            blocked: false,
            class: self.fwd.tree.edge_class(next).unwrap_or(0),
        };
        let Ok(mid) = self.fwd.insert(a.step_towards(b, step), root, edge) else {
            return next;
        };
        match self.fwd.tree.set_parent(next, mid, edge) {
            Ok(moved) => {
                meter.charge(units(moved).saturating_add(4));
                mid
            }
            // Cannot happen (`mid` is a new leaf); it would stay a harmless leaf.
            Err(_) => next,
        }
    }

    /// The clearance class of a new edge `a-b` (0 without a clearance preference), charged.
    pub(super) fn clearance_class<C: Clock + ?Sized>(
        &self,
        a: Point,
        b: Point,
        meter: &Meter<'_, C>,
    ) -> u8 {
        if !cfg!(feature = "clearance") || self.cfg.clearance_weight <= 0.0 {
            return 0;
        }
        let (class, work) = self.map.clearance_class(a, b);
        meter.charge(work);
        class
    }
}
