//! What a full arena does with a new state (beyond the paper, which stops growing): the
//! trades (`density_trades`, `recycle_when_full`) and the recycling of a leaf while the goal is not joined;
//! the module's bullet "A full arena makes room".

use super::*;

impl<const N: usize, const B: usize> TreeStore<N, B> {
    /// Inserts a node below `parent` (its edge free). When the arena is full, one leaf is
    /// recycled first ([`TreeStore::recycle`]) if the tree has a `target` that still needs
    /// room: one not joined yet (promise: a goal that can be reached joins) or joined over a
    /// path that crosses a dynamic obstacle (the tree must grow a way around). Once a free
    /// path exists, a full tree rewires what it has, unless `trade` gives the new state's cost
    /// bound: then a leaf with a higher bound makes room (`recycle_when_full`). Sets
    /// `full` when the arena was full.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn insert_making_room<R: Rng + ?Sized, C: Clock + ?Sized>(
        &mut self,
        rng: &mut R,
        pos: Point,
        parent: NodeId,
        edge: Edge,
        target: Option<&mut Target>,
        trade: Option<Trade>,
        meter: &Meter<'_, C>,
        full: &mut bool,
    ) -> Option<NodeId> {
        if !self.tree.is_full() {
            return self.insert(pos, parent, edge).ok();
        }
        *full = true;
        let t = target?;
        let needs_room = t.node.is_none_or(|g| self.cost(g).blocked);
        if !needs_room && trade.is_none() {
            return None;
        }
        let mut keep = [parent, t.node.unwrap_or(parent)];
        let above = if needs_room { None } else { trade };
        if !self.recycle_above(rng, t.pos, &mut keep, above.as_ref(), meter) {
            return None;
        }
        if t.node.is_some() {
            t.node = Some(keep[1]);
        }
        self.insert(pos, keep[0], edge).ok()
    }

    /// Frees one slot of the arena by removing the leaf least likely to lie on a path to
    /// `toward`: among a few random nodes, the leaf (not the root, not in `keep`) with the
    /// highest `Cost(x) + d_E(x, toward)`, a lower bound of the best path through it, taken
    /// first among leaves that share their index bucket (module docs); a
    /// bounded scan when no drawn node is a usable leaf. Ids in `keep` and in the rewiring
    /// sweeps are renamed when the arena's last node moves into the freed slot. Returns whether
    /// a node was removed.
    pub(crate) fn recycle<R: Rng + ?Sized, C: Clock + ?Sized>(
        &mut self,
        rng: &mut R,
        toward: Point,
        keep: &mut [NodeId],
        meter: &Meter<'_, C>,
    ) -> bool {
        self.recycle_above(rng, toward, keep, None, meter)
    }

    /// The cover a trade keeps per index bucket: `k`, at most `N / (2 x buckets)`, so the
    /// cover never holds more than half the arena (a small arena on a large map keeps none).
    pub(super) fn cover(&self, k: u16) -> u16 {
        let (cols, rows) = self.index.shape();
        let buckets = usize::from(cols)
            .saturating_mul(usize::from(rows))
            .saturating_mul(2);
        k.min(to_u16(N.checked_div(buckets).unwrap_or(0)))
    }

    /// Whether at least `k` other nodes share the index bucket of node `id`.
    fn has_company<C: Clock + ?Sized>(&self, id: NodeId, k: u16, meter: &Meter<'_, C>) -> bool {
        let (yes, seen) = self.index.bucket_has_others(id, self.pos(id), k);
        meter.charge(seen.saturating_add(2));
        yes
    }

    /// [`TreeStore::recycle`] for a trade when given: removing only a leaf whose score is
    /// above the trade's bound and which keeps the trade's cover (without the fallback scan:
    /// no such leaf among the draws, no removal).
    fn recycle_above<R: Rng + ?Sized, C: Clock + ?Sized>(
        &mut self,
        rng: &mut R,
        toward: Point,
        keep: &mut [NodeId],
        trade: Option<&Trade>,
        meter: &Meter<'_, C>,
    ) -> bool {
        const DRAWS: usize = 16;
        let len = self.tree.len();
        if len < 2 {
            return false;
        }
        let usable = |s: &Self, id: NodeId| {
            s.tree.is_leaf(id) && s.tree.root() != Some(id) && !keep.contains(&id)
        };
        // Blocked paths first (Cost orders them last, so they score highest).
        let score = |s: &Self, id: NodeId| s.cost(id).extend(s.pos(id).dist(toward), false);
        let mut drawn: heapless::Vec<(Cost, NodeId), DRAWS> = heapless::Vec::new();
        for _ in 0..DRAWS {
            let id = NodeId(to_u16(rng.next_u32().checked_rem(units(len)).unwrap_or(0)));
            if usable(self, id) && !drawn.iter().any(|&(_, d)| d == id) {
                let _ = drawn.push((score(self, id), id));
            }
        }
        // Highest score first; among equal scores the first drawn.
        sort_small_by(&mut drawn, |a, b| b.0.cmp(&a.0));
        let mut best = if let Some(t) = trade {
            // A trade takes the best-scored leaf above the bound whose bucket keeps the
            // cover: every part of the map the tree has reached keeps a node for the goals
            // to come.
            let cover = self.cover(t.cover);
            let Some(b) = drawn
                .iter()
                .take_while(|&&(sc, _)| sc > t.bound)
                .find(|&&(_, id)| cover == 0 || self.has_company(id, cover, meter))
                .copied()
            else {
                meter.charge(units(DRAWS).saturating_add(8));
                return false;
            };
            Some(b)
        } else {
            // Making room for a search: a leaf that shares its index bucket goes first, so the
            // tree thins where it is dense and keeps its lone frontier nodes (its reach).
            drawn
                .iter()
                .find(|&&(_, id)| self.has_company(id, 1, meter))
                .or(drawn.first())
                .copied()
        };
        let mut scanned: usize = 0;
        if best.is_none() {
            let from = rng.next_u32() as usize;
            best = (0..len)
                .map(|i| NodeId(to_u16(from.wrapping_add(i).checked_rem(len).unwrap_or(0))))
                .inspect(|_| scanned = scanned.saturating_add(1))
                .find(|&id| usable(self, id))
                .map(|id| (score(self, id), id));
        }
        meter.charge(units(DRAWS.saturating_add(scanned)).saturating_add(8));
        let Some((_, victim)) = best else {
            return false;
        };
        self.remove_leaf_renaming(victim, keep)
    }

    /// The leaf of `near` (not the root, not `goal_node`, not one of the last `cover` nodes of
    /// its index bucket) with the highest cost bound `Cost(x) + d_E(x, goal)`, with that
    /// bound, when it is above the best bound `x` could have below any node of `near`
    /// (`density_trades`).
    pub(super) fn worst_leaf<C: Clock + ?Sized>(
        &self,
        near: &Near,
        x: Point,
        goal: Point,
        goal_node: Option<NodeId>,
        cover: u16,
        meter: &Meter<'_, C>,
    ) -> Option<(Cost, NodeId)> {
        meter.charge(units(near.len()).saturating_add(2));
        let mut lowest: Option<Cost> = None;
        let mut worst: Option<(Cost, NodeId)> = None;
        for &id in near.iter() {
            let p = self.pos(id);
            let c = self.cost(id);
            let via = c.extend(p.dist(x) + x.dist(goal), false);
            if lowest.is_none_or(|l| via < l) {
                lowest = Some(via);
            }
            if self.tree.is_leaf(id) && self.tree.root() != Some(id) && goal_node != Some(id) {
                let score = c.extend(p.dist(goal), false);
                if worst.is_none_or(|(w, _)| score > w)
                    && (cover == 0 || self.has_company(id, cover, meter))
                {
                    worst = Some((score, id));
                }
            }
        }
        worst.filter(|&(w, _)| lowest.is_some_and(|l| w > l))
    }

    /// Removes leaf `victim` from the arena and the index; an id of `keep` naming the node
    /// that moved into its slot is renamed, and so are the sweeps'. Whether it was removed.
    pub(super) fn remove_leaf_renaming(&mut self, victim: NodeId, keep: &mut [NodeId]) -> bool {
        let _ = self.index.remove(victim, self.pos(victim));
        match self.tree.remove_leaf(victim) {
            Ok(moved) => {
                if let Some((old, new)) = moved {
                    let _ = self.index.remove(old, self.pos(new));
                    let _ = self.index.insert(new, self.pos(new));
                    for k in keep.iter_mut().filter(|k| **k == old) {
                        *k = new;
                    }
                }
                self.rename_in_sweeps(moved);
                true
            }
            Err(_) => {
                let _ = self.index.insert(victim, self.pos(victim));
                false
            }
        }
    }

    /// After a removal: ids in the sweeps' queues and stack that moved are renamed, and ids
    /// that no longer exist are replaced by the root (a harmless extra visit).
    fn rename_in_sweeps(&mut self, moved: Option<(NodeId, NodeId)>) {
        let len = self.tree.len();
        let root = self.tree.root().unwrap_or(NodeId(0));
        let fix = |id: &mut NodeId| {
            if let Some((old, new)) = moved
                && *id == old
            {
                *id = new;
            } else if id.index() >= len {
                *id = root;
            }
        };
        self.root_queue.iter_mut().for_each(fix);
        self.goal_queue.iter_mut().for_each(fix);
        self.goal_stack.iter_mut().for_each(fix);
    }
}
