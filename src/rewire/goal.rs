//! Goal rewiring (AM-RRT*'s sweep towards the goal inside the informed ellipse; the second
//! kind is paper Algorithms 5-6): the module's "Goal rewiring".

use super::*;

impl<const N: usize, const B: usize> TreeStore<N, B> {
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
        let open = env.cfg.tactics.open_frontier;
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
            let printed = env.cfg.as_printed;
            // Algorithm 5 as printed runs Algorithm 6 only while a list holds more than two
            // nodes; the phase ends otherwise (AsPrinted::alg5_gate).
            let (s_len, q_len) = (self.goal_stack.len(), self.goal_queue.len());
            if second_kind && printed.alg5_gate && s_len <= 2 && q_len <= 2 {
                return;
            }
            // Pick x_r1, and x_r2 for the second kind.
            let from_stack = match (second_kind, printed.alg5_gate) {
                (true, true) => s_len > 2,
                (true, false) => s_len > 2 || q_len < 2,
                (false, _) => s_len > 0,
            };
            let x1 = if from_stack {
                self.goal_stack.pop().or_else(|| self.dequeue_goal())
            } else {
                self.dequeue_goal()
            };
            let Some(x1) = x1 else {
                continue;
            };
            let x2 = match (second_kind, from_stack, printed.alg6_takes_x_r2) {
                (false, _, _) => None,
                (true, true, false) => self.goal_stack.last().copied(),
                (true, true, true) => self.goal_stack.pop(),
                (true, false, false) => self.goal_queue.back().copied(),
                (true, false, true) => self.dequeue_goal(),
            };
            let x1_pos = self.pos(x1);
            if !inside(x1_pos) {
                // As printed, the clearing test follows for this x_r1 too
                // (AsPrinted::alg6_clear_outside).
                if printed.alg6_clear_outside {
                    let d1 = env.metric_to(x1_pos, &to_goal, meter);
                    self.clear_if_receding(env, &to_goal, second_kind, x1_pos, x2, d1, meter);
                }
                continue;
            }
            let d1 = env.metric_to(x1_pos, &to_goal, meter);
            self.nearby(x1_pos, radius, &mut near, meter);
            // Decreasing d_A(., goal): the neighbour nearest the goal ends on top of the stack.
            let mut keyed: heapless::Vec<(f32, NodeId), { crate::expand::NEAR_CAP }> =
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
                // `open_frontier` enqueues every unseen neighbour, as root rewiring does: no
                // segment test for the frontier (the rewire above tests its own).
                if !self.tree.marked(x_near, Mark::Goal)
                    && (printed_cost || open || env.free(seen_from, self.pos(x_near), meter))
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
            self.clear_if_receding(env, &to_goal, second_kind, x1_pos, x2, d1, meter);
        }
    }

    /// The clearing test that ends a visit: the stack (the current branch) is emptied when
    /// the branch stopped approaching the goal (module docs; `d1` is `d_A(x_r1, goal)`).
    #[allow(clippy::too_many_arguments)]
    fn clear_if_receding<M: Metric, C: Clock + ?Sized, const K: usize>(
        &mut self,
        env: &Env<'_, '_, M, K>,
        to_goal: &crate::metric::Prepared,
        second_kind: bool,
        x1_pos: Point,
        x2: Option<NodeId>,
        d1: f32,
        meter: &Meter<'_, C>,
    ) {
        let clear = if second_kind && env.cfg.as_printed.alg6_clear {
            // len(S) > 1 and d_A(Second(S), goal) > d_A(x_r1, goal) + d_A(x_r1, x_r2).
            // Second(S): the node under the top (none when the stack holds one or none).
            let second = self.goal_stack.iter().rev().nth(1).copied();
            second.is_some_and(|second| {
                let slack = match x2 {
                    Some(x2) => env.metric_to(x1_pos, &env.metric.prepare(self.pos(x2)), meter),
                    None => 0.0,
                };
                env.metric_to(self.pos(second), to_goal, meter) > d1 + slack
            })
        } else {
            self.goal_stack
                .last()
                .is_some_and(|&top| env.metric_to(self.pos(top), to_goal, meter) > d1)
        };
        if clear {
            self.goal_stack.clear();
        }
    }
}
