//! Root rewiring (AM-RRT* and RT-RRT*'s sweep from the root; the second kind is paper
//! Algorithm 4): the module's "Root rewiring".

use super::*;

impl<const N: usize, const B: usize> TreeStore<N, B> {
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
            // Algorithm 4 as printed enqueues x_near only over a free segment to x_r1
            // (AsPrinted::alg4_free_enqueue).
            let free_only = center != x1 && env.cfg.as_printed.alg4_free_enqueue;
            let x1_pos = self.pos(x1);
            for &x_near in near.iter() {
                // A visit is up to 64 tests (a millisecond on a Cortex-M4F, issue 25): past
                // the deadline the rest are skipped, the neighbours still queued (with
                // `free_only`, not queued: untested).
                let in_time = !meter.expired(&slice.deadline);
                if in_time {
                    meter.charge(1);
                    self.try_rewire(env, x_near, x1, meter);
                }
                // Seen only once queued: a node refused by the full (bounded) queue can still
                // be queued later in the sweep, from another neighbour.
                if !self.tree.marked(x_near, Mark::Root)
                    && (!free_only || (in_time && env.free(self.pos(x_near), x1_pos, meter)))
                    && self.root_queue.push_back(x_near).is_ok()
                {
                    self.tree.mark(x_near, Mark::Root);
                }
            }
        }
    }
}
