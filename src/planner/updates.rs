//! What the caller changes between calls: dynamic obstacles (paper, section 3: circles;
//! beyond it, moving ones) and live cells, and the edges re-flagged for them; the module's
//! "Dynamic obstacles", "Moving obstacles" and "Live cells".

use super::*;

impl<'s, 'm, M: Metric, R: Rng, const N: usize, const B: usize, const K: usize>
    Planner<'s, 'm, M, R, N, B, K>
{
    /// Adds a dynamic obstacle (module docs).
    pub fn add_obstacle(&mut self, circle: Circle) -> Result<ObstacleId, ObstacleError> {
        let id = self.map.obstacles_mut().add(circle)?;
        self.reflag();
        Ok(id)
    }

    /// Removes a dynamic obstacle.
    pub fn remove_obstacle(&mut self, id: ObstacleId) -> Result<Circle, ObstacleError> {
        let c = self.map.obstacles_mut().remove(id)?;
        self.reflag();
        Ok(c)
    }

    /// Adds an obstacle that may move ([`crate::map::Moving`]; module [`crate::motion`]).
    pub fn add_moving_obstacle(&mut self, obstacle: Moving) -> Result<ObstacleId, ObstacleError> {
        let id = self.map.obstacles_mut().add_moving(obstacle)?;
        self.reflag();
        Ok(id)
    }

    /// Submits what is now known of an obstacle (its disc at the next call, velocity and
    /// horizon, as a perception stack reports it): O(K), nothing else is done until the next
    /// `plan` or `grow` call re-flags the edges (O(N K) work, charged to that call). The
    /// planner does not move obstacles by itself: submit each one's state before every call
    /// (a state not updated is predicted from where it was given).
    pub fn update_obstacle(
        &mut self,
        id: ObstacleId,
        obstacle: Moving,
    ) -> Result<(), ObstacleError> {
        self.map.obstacles_mut().update(id, obstacle)?;
        self.stale = true;
        Ok(())
    }

    fn reflag(&mut self) {
        self.reflag_trees(true);
    }

    /// Marks (`occupied`) or clears every cell of the rectangle with corners `a` and `b`
    /// (`(col, row)`, inclusive) in the live map ([`Map::set_cells`]: the map needs an
    /// overlay): O(cells) to submit; the next `plan` or `grow` call re-tests the edges of both
    /// trees near the changed cells (an edge crossing a marked cell is blocked like one
    /// through a circle, one whose cells cleared reopens) and charges that work. Returns how
    /// many cells changed. The diffusion table is not rebaked (docs/guides/moving.md says what that
    /// costs).
    pub fn set_cells(
        &mut self,
        a: (u16, u16),
        b: (u16, u16),
        occupied: bool,
    ) -> Result<u32, crate::error::MapError> {
        self.map.set_cells(a, b, occupied)
    }

    /// Re-flags every edge of both trees against the obstacles; the rewiring sweeps restart
    /// (where a flag changed, or everywhere with `restart`).
    fn reflag_trees(&mut self, restart: bool) {
        self.stale = false;
        let obstacles = self.map.obstacles();
        for store in [&mut *self.fwd, &mut *self.rev] {
            let changed = store
                .tree
                .reflag_edges(|a, b| obstacles.blocks_segment(a, b));
            if changed || restart {
                store.restart_sweeps();
            }
        }
    }

    /// Applies the obstacle updates submitted since the last call: the edges are re-flagged,
    /// and the rewiring sweeps restart only where a flag changed.
    pub(super) fn apply_updates<C: Clock + ?Sized>(&mut self, meter: &Meter<'_, C>) {
        if self.stale {
            let k = self.map.obstacles().len().saturating_add(1);
            let nodes = self.fwd.tree.len().saturating_add(self.rev.tree.len());
            meter.charge(units(nodes.saturating_mul(k)));
            self.reflag_trees(false);
        }
        if let Some(changed) = self.map.take_changed() {
            self.rewall_trees(changed, meter);
        }
    }

    /// Re-tests, against the live cells, every edge of both trees whose cells may include one
    /// in `changed` (`[col0, row0, col1, row1]`); the rewiring sweeps restart where a flag
    /// changed. Work: a box test per edge, and the cells of each edge re-tested.
    fn rewall_trees<C: Clock + ?Sized>(&mut self, changed: [u16; 4], meter: &Meter<'_, C>) {
        let cells = self.map.live();
        let grid = cells.grid();
        let inv = 1.0 / grid.cell_size();
        // The changed box in metres, grown by a cell for the contact margin.
        let [c0, r0, c1, r1] = changed.map(f32::from);
        let (lo, hi) = (
            Point::new(c0 - 1.0, r0 - 1.0),
            Point::new(c1 + 2.0, r1 + 2.0),
        );
        let mut retested = 0u64;
        for store in [&mut *self.fwd, &mut *self.rev] {
            meter.charge(units(store.tree.len()));
            let changed = store.tree.rewall_edges(|a, b| {
                let (p, q) = (
                    Point::new(a.x * inv, a.y * inv),
                    Point::new(b.x * inv, b.y * inv),
                );
                let near = p.x.max(q.x) >= lo.x
                    && p.x.min(q.x) <= hi.x
                    && p.y.max(q.y) >= lo.y
                    && p.y.min(q.y) <= hi.y;
                near.then(|| {
                    // About the cells the segment crosses.
                    meter.charge(sat_u32((p.x - q.x).abs() + (p.y - q.y).abs() + 2.0));
                    retested = retested.saturating_add(1);
                    !cells.segment_free(a, b)
                })
            });
            if changed {
                store.restart_sweeps();
            }
        }
        self.stats.retested = self.stats.retested.saturating_add(retested);
    }
}
