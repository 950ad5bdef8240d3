//! Bounded working storage for the rewiring sweeps (paper, section 4.2, Algorithms 4-6): the
//! queue and stack of node ids, and the set of nodes already seen in the current sweep.
//!
//! The queue and stack are `heapless` containers of fixed capacity: a push onto a full one is
//! refused (the sweep then simply does not extend that way, and restarts later). The seen set
//! has one generation stamp per arena slot; forgetting everything (which the rewiring does each
//! time a sweep restarts from the root) bumps the generation in O(1) instead of clearing.

use crate::tree::NodeId;

/// FIFO of node ids for breadth-first sweeps.
pub type NodeQueue<const Q: usize> = heapless::Deque<NodeId, Q>;

/// LIFO of node ids for depth-first sweeps.
pub type NodeStack<const S: usize> = heapless::Vec<NodeId, S>;

/// A set of node ids below `N`, cleared in O(1) by generation stamping.
#[derive(Clone, Debug)]
pub struct SeenSet<const N: usize> {
    stamp: [u16; N],
    generation: u16,
}

impl<const N: usize> Default for SeenSet<N> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize> SeenSet<N> {
    /// An empty set.
    pub const fn new() -> Self {
        Self {
            stamp: [0; N],
            generation: 1,
        }
    }

    /// Forgets every member: O(1), except once every 65,535 calls when the stamps wrap and are
    /// zeroed (O(N)).
    pub fn clear(&mut self) {
        self.generation = self.generation.wrapping_add(1);
        if self.generation == 0 {
            self.stamp.fill(0);
            self.generation = 1;
        }
    }

    /// Whether `id` is a member (ids at or above `N` never are).
    #[inline]
    pub fn contains(&self, id: NodeId) -> bool {
        self.stamp
            .get(id.index())
            .is_some_and(|&s| s == self.generation)
    }

    /// Adds `id`; returns whether it was new (false also for ids at or above `N`).
    #[inline]
    pub fn insert(&mut self, id: NodeId) -> bool {
        match self.stamp.get_mut(id.index()) {
            Some(s) if *s != self.generation => {
                *s = self.generation;
                true
            }
            _ => false,
        }
    }

    /// Removes `id`.
    #[inline]
    pub fn remove(&mut self, id: NodeId) {
        if let Some(s) = self.stamp.get_mut(id.index()) {
            *s = 0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seen_set_survives_generation_wrap() {
        let mut s = SeenSet::<4>::new();
        assert!(s.insert(NodeId(2)));
        assert!(!s.insert(NodeId(2)));
        assert!(!s.insert(NodeId(9)));
        for _ in 0..70_000 {
            s.clear();
            assert!(!s.contains(NodeId(2)));
        }
        assert!(s.insert(NodeId(3)));
        assert!(s.contains(NodeId(3)) && !s.contains(NodeId(2)));
        s.remove(NodeId(3));
        assert!(!s.contains(NodeId(3)));
    }

    #[test]
    fn bounded_queue_refuses_when_full() {
        let mut q = NodeQueue::<2>::new();
        q.push_back(NodeId(1)).unwrap();
        q.push_back(NodeId(2)).unwrap();
        assert_eq!(q.push_back(NodeId(3)), Err(NodeId(3)));
        assert_eq!(q.pop_front(), Some(NodeId(1)));
    }
}
