//! Bounded working storage for the rewiring sweeps (paper, section 4.2, Algorithms 4-6): the
//! queue and stack of node ids, and the set of nodes already seen in the current sweep.
//!
//! The queue and stack are `heapless` containers of [`SWEEP_CAP`] ids, whatever the arena's
//! size: a sweep's frontier is a band of the tree, not the tree, so they need not be `N` deep.
//! A push onto a full one is refused and the node is left unseen, so the sweep can queue it
//! later from another neighbour. The "seen" sets are two bits in each node's flag byte
//! ([`crate::tree`]), cleared when a sweep restarts from the root.

use crate::tree::NodeId;

/// Capacity of every sweep queue and stack: 256 ids, 512 bytes each. Measured against
/// `N`-deep queues on the reference maps with 8,192-node trees (docs/guides/firmware.md): search
/// times and travelled paths unchanged, the tree's cost after 100 ms 0.6-0.8 % higher on
/// office (the goal sweep's frontier there outgrows 256), unchanged on bug_trap and maze.
pub const SWEEP_CAP: usize = 256;

/// FIFO of node ids for breadth-first sweeps.
pub type NodeQueue<const Q: usize> = heapless::Deque<NodeId, Q>;

/// LIFO of node ids for depth-first sweeps.
pub type NodeStack<const S: usize> = heapless::Vec<NodeId, S>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounded_queue_refuses_when_full() {
        let mut q = NodeQueue::<2>::new();
        q.push_back(NodeId(1)).unwrap();
        q.push_back(NodeId(2)).unwrap();
        assert_eq!(q.push_back(NodeId(3)), Err(NodeId(3)));
        assert_eq!(q.pop_front(), Some(NodeId(1)));
    }
}
