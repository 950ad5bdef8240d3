//! RT-RRT*'s random rewiring (Naderi et al., 2015), which the RT-RRT* planners run in place
//! of goal rewiring: the module's "Random rewiring".

use super::*;

impl<const N: usize, const B: usize> TreeStore<N, B> {
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
}
