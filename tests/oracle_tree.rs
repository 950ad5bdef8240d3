//! Property tests of the tree arena: long random operation sequences checked after every
//! operation against a plain model (a parent vector) and the tree's own invariant check:
//! no cycle, parent/child links agree, every node reaches the root, cached costs equal costs
//! recomputed along the model's paths, re-rooting keeps the node set and the undirected edges,
//! removing a leaf moves the last node into its slot with every link renamed,
//! and failed operations (full arena, cycles, unknown ids) change nothing.

use std::collections::BTreeSet;

use bi_am_rrt::error::TreeError;
use bi_am_rrt::geometry::Point;
use bi_am_rrt::tree::{Cost, NodeId, Tree};
use proptest::prelude::*;

const CAP: usize = 24;

#[derive(Clone, Debug)]
enum Op {
    Add {
        parent: usize,
        x: f32,
        y: f32,
        blocked: bool,
    },
    SetParent {
        child: usize,
        parent: usize,
        blocked: bool,
    },
    SetRoot {
        node: usize,
    },
    SetEdgeBlocked {
        node: usize,
        blocked: bool,
    },
    /// Block every edge that crosses the vertical line x = `x` (a stand-in for an obstacle).
    Reflag {
        x: f32,
    },
    Reset {
        x: f32,
        y: f32,
    },
    RemoveLeaf {
        node: usize,
    },
    UnknownId,
}

fn op() -> impl Strategy<Value = Op> {
    let coord = 0.0f32..100.0;
    prop_oneof![
        6 => (any::<usize>(), coord.clone(), coord.clone(), prop::bool::weighted(0.2))
            .prop_map(|(parent, x, y, blocked)| Op::Add { parent, x, y, blocked }),
        6 => (any::<usize>(), any::<usize>(), prop::bool::weighted(0.2))
            .prop_map(|(child, parent, blocked)| Op::SetParent { child, parent, blocked }),
        2 => any::<usize>().prop_map(|node| Op::SetRoot { node }),
        2 => (any::<usize>(), any::<bool>()).prop_map(|(node, blocked)| Op::SetEdgeBlocked { node, blocked }),
        1 => coord.clone().prop_map(|x| Op::Reflag { x }),
        1 => (coord.clone(), coord).prop_map(|(x, y)| Op::Reset { x, y }),
        3 => any::<usize>().prop_map(|node| Op::RemoveLeaf { node }),
        1 => Just(Op::UnknownId),
    ]
}

/// The model: positions, parents, edge flags and the root.
#[derive(Clone, Debug, Default)]
struct Model {
    pos: Vec<Point>,
    parent: Vec<Option<usize>>,
    blocked: Vec<bool>,
    root: usize,
}

impl Model {
    fn is_ancestor_or_self(&self, anc: usize, mut v: usize) -> bool {
        loop {
            if v == anc {
                return true;
            }
            match self.parent[v] {
                Some(p) => v = p,
                None => return false,
            }
        }
    }

    /// Cost summed along the path in root order, as the tree's cache does.
    fn cost(&self, v: usize) -> Cost {
        let mut path = vec![v];
        while let Some(p) = self.parent[*path.last().unwrap()] {
            path.push(p);
        }
        path.reverse();
        let mut c = Cost::ZERO;
        for w in path.windows(2) {
            c = c.extend(self.pos[w[0]].dist(self.pos[w[1]]), self.blocked[w[1]]);
        }
        c
    }

    fn undirected_edges(&self) -> BTreeSet<(usize, usize, bool)> {
        (0..self.pos.len())
            .filter_map(|v| self.parent[v].map(|p| (p.min(v), p.max(v), self.blocked[v])))
            .collect()
    }
}

fn check(tree: &Tree<CAP>, m: &Model) -> Result<(), TestCaseError> {
    prop_assert_eq!(tree.validate(), Ok(()));
    prop_assert_eq!(tree.len(), m.pos.len());
    prop_assert_eq!(tree.root(), Some(NodeId(m.root as u16)));
    for v in 0..m.pos.len() {
        let id = NodeId(v as u16);
        prop_assert_eq!(tree.position(id), Some(m.pos[v]));
        prop_assert_eq!(tree.parent(id), m.parent[v].map(|p| NodeId(p as u16)));
        let (c, mc) = (tree.cost(id).unwrap(), m.cost(v));
        prop_assert_eq!(c.length.to_bits(), mc.length.to_bits(), "cost of {}", v);
        prop_assert_eq!(c.blocked, mc.blocked);
        let mut children: Vec<usize> = tree.children(id).map(|c| c.index()).collect();
        children.sort();
        let want: Vec<usize> = (0..m.pos.len())
            .filter(|&c| m.parent[c] == Some(v))
            .collect();
        prop_assert_eq!(children, want);
    }
    // Path extraction agrees with the model's parents.
    if let Some(last) = m.pos.len().checked_sub(1) {
        let mut buf = [NodeId(0); CAP];
        let n = tree.path_ids(NodeId(last as u16), &mut buf).unwrap();
        prop_assert_eq!(buf[0], NodeId(m.root as u16));
        prop_assert_eq!(buf[n - 1], NodeId(last as u16));
        for w in buf[..n].windows(2) {
            prop_assert_eq!(m.parent[w[1].index()], Some(w[0].index()));
        }
    }
    Ok(())
}

proptest! {
    // A fixed seed: the same cases on every machine and every run.
    #![proptest_config(ProptestConfig {
        cases: 512,
        rng_seed: proptest::test_runner::RngSeed::Fixed(0xB1A3_2026),
        ..ProptestConfig::default()
    })]

    #[test]
    fn tree_matches_model(ops in prop::collection::vec(op(), 1..200)) {
        let mut tree = Box::new(Tree::<CAP>::new());
        let mut m = Model { pos: vec![Point::new(50.0, 50.0)], parent: vec![None], blocked: vec![false], root: 0 };
        tree.reset(m.pos[0]);
        check(&tree, &m)?;
        for op in ops {
            let n = m.pos.len();
            match op {
                Op::Add { parent, x, y, blocked } => {
                    let parent = parent % n;
                    let r = tree.add(Point::new(x, y), NodeId(parent as u16), blocked);
                    if n == CAP {
                        prop_assert_eq!(r, Err(TreeError::Full));
                    } else {
                        prop_assert_eq!(r, Ok(NodeId(n as u16)));
                        m.pos.push(Point::new(x, y));
                        m.parent.push(Some(parent));
                        m.blocked.push(blocked);
                    }
                }
                Op::SetParent { child, parent, blocked } => {
                    let (child, parent) = (child % n, parent % n);
                    let r = tree.set_parent(NodeId(child as u16), NodeId(parent as u16), blocked);
                    if m.is_ancestor_or_self(child, parent) {
                        prop_assert_eq!(r, Err(TreeError::WouldCycle));
                    } else {
                        prop_assert!(r.is_ok_and(|moved| moved >= 1 && moved <= n));
                        m.parent[child] = Some(parent);
                        m.blocked[child] = blocked;
                    }
                }
                Op::SetRoot { node } => {
                    let node = node % n;
                    let before_edges = m.undirected_edges();
                    tree.set_root(NodeId(node as u16)).unwrap();
                    // Model: reverse the path root -> node.
                    let mut path = vec![node];
                    while let Some(p) = m.parent[*path.last().unwrap()] {
                        path.push(p);
                    }
                    let flags: Vec<bool> = path.iter().map(|&v| m.blocked[v]).collect();
                    m.parent[node] = None;
                    m.blocked[node] = false;
                    for k in 1..path.len() {
                        m.parent[path[k]] = Some(path[k - 1]);
                        m.blocked[path[k]] = flags[k - 1];
                    }
                    m.root = node;
                    prop_assert_eq!(&m.undirected_edges(), &before_edges);
                    let tree_edges: BTreeSet<_> = tree
                        .ids()
                        .filter_map(|v| tree.parent(v).map(|p| {
                            (p.index().min(v.index()), p.index().max(v.index()), tree.edge_blocked(v).unwrap())
                        }))
                        .collect();
                    prop_assert_eq!(tree_edges, before_edges, "re-rooting keeps the edges");
                }
                Op::SetEdgeBlocked { node, blocked } => {
                    let node = node % n;
                    tree.set_edge_blocked(NodeId(node as u16), blocked).unwrap();
                    if m.parent[node].is_some() {
                        m.blocked[node] = blocked;
                    }
                }
                Op::Reflag { x } => {
                    let crosses = |a: Point, b: Point| (a.x - x) * (b.x - x) <= 0.0;
                    tree.reflag_edges(crosses);
                    for v in 0..n {
                        m.blocked[v] = m.parent[v].is_some_and(|p| crosses(m.pos[p], m.pos[v]));
                    }
                }
                Op::Reset { x, y } => {
                    prop_assert_eq!(tree.reset(Point::new(x, y)), NodeId(0));
                    m = Model { pos: vec![Point::new(x, y)], parent: vec![None], blocked: vec![false], root: 0 };
                }
                Op::RemoveLeaf { node } => {
                    let v = node % n;
                    let leaf = v != m.root && !m.parent.contains(&Some(v));
                    let before = tree.clone();
                    let r = tree.remove_leaf(NodeId(v as u16));
                    if !leaf {
                        prop_assert_eq!(r, Err(TreeError::NotALeaf));
                        prop_assert_eq!(tree.positions(), before.positions());
                    } else {
                        // Model: the last node moves into the freed slot.
                        let last = n - 1;
                        if v != last {
                            prop_assert_eq!(r, Ok(Some((NodeId(last as u16), NodeId(v as u16)))));
                            m.pos[v] = m.pos[last];
                            m.parent[v] = m.parent[last];
                            m.blocked[v] = m.blocked[last];
                            for p in m.parent.iter_mut() {
                                if *p == Some(last) {
                                    *p = Some(v);
                                }
                            }
                            if m.root == last {
                                m.root = v;
                            }
                        } else {
                            prop_assert_eq!(r, Ok(None));
                        }
                        m.pos.pop();
                        m.parent.pop();
                        m.blocked.pop();
                    }
                }
                Op::UnknownId => {
                    let bad = NodeId(n as u16);
                    let before = tree.clone();
                    prop_assert_eq!(tree.add(Point::ZERO, bad, false), Err(TreeError::UnknownNode));
                    prop_assert_eq!(tree.set_parent(bad, NodeId(0), false), Err(TreeError::UnknownNode));
                    prop_assert_eq!(tree.set_root(bad), Err(TreeError::UnknownNode));
                    prop_assert_eq!(tree.position(bad), None);
                    prop_assert_eq!(tree.positions(), before.positions());
                }
            }
            check(&tree, &m)?;
        }
    }
}
