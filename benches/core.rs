//! Benchmarks of the core building blocks (`cargo bench --bench core`):
//! - `free_path` of 5 m and 50 m segments in random directions on a 100 x 100 grid of 1 m
//!   cells (empty, so every segment is traversed to its end: the worst case; and 20 % random
//!   occupancy, where most long segments stop early);
//! - nearest and within-5 m queries on 4,096 uniformly spread nodes, against a linear scan in
//!   the same run;
//! - tree edge updates and re-rooting on 4,096 nodes.
//!
//! It also prints `size_of` of the tree and index types the planner uses.

use std::hint::black_box;
use std::mem::size_of;
use std::ops::ControlFlow;

use bi_am_rrt::geometry::Point;
use bi_am_rrt::index::{SpatialIndex, linear_nearest};
use bi_am_rrt::map::{OccupancyGrid, pack_grid};
use bi_am_rrt::tree::{NodeId, Tree};
use criterion::{Criterion, criterion_group, criterion_main};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

fn unit(rng: &mut XorShiftRng) -> f32 {
    (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

/// 256 segments of length `len` with random direction, both ends inside the 100 m map.
fn segments(rng: &mut XorShiftRng, len: f32) -> Vec<(Point, Point)> {
    let mut out = Vec::new();
    while out.len() < 256 {
        let a = Point::new(unit(rng) * 100.0, unit(rng) * 100.0);
        let th = unit(rng) * std::f32::consts::TAU;
        let b = a + Point::new(th.cos(), th.sin()) * len;
        if (0.0..=100.0).contains(&b.x) && (0.0..=100.0).contains(&b.y) {
            out.push((a, b));
        }
    }
    out
}

fn bench_free_path(c: &mut Criterion) {
    let mut rng = XorShiftRng::seed_from_u64(1);
    let empty = vec![0u8; OccupancyGrid::bytes_needed(100, 100)];
    let mut cluttered = vec![0u8; OccupancyGrid::bytes_needed(100, 100)];
    pack_grid(&mut cluttered, 100, 100, |_, _| unit(&mut rng) < 0.2).unwrap();
    for (name, bits) in [("empty", &empty), ("cluttered20", &cluttered)] {
        let g = OccupancyGrid::new(bits, 100, 100, 1.0).unwrap();
        for len in [5.0f32, 50.0] {
            let segs = segments(&mut rng, len);
            let mut i = 0usize;
            c.bench_function(&format!("free_path/{name}/{len}m"), |b| {
                b.iter(|| {
                    i = (i + 1) & 255;
                    let (p, q) = segs[i];
                    black_box(g.segment_free(black_box(p), black_box(q)))
                })
            });
        }
    }
}

fn bench_index(c: &mut Criterion) {
    let mut rng = XorShiftRng::seed_from_u64(2);
    let mut tree = Box::new(Tree::<4096>::new());
    let root = tree.reset(Point::new(50.0, 50.0));
    while !tree.is_full() {
        tree.add(
            Point::new(unit(&mut rng) * 100.0, unit(&mut rng) * 100.0),
            root,
            false,
        )
        .unwrap();
    }
    let mut idx = Box::new(SpatialIndex::<4096, 400>::with_bounds(100.0, 100.0, 5.0).unwrap());
    for id in tree.ids() {
        idx.insert(id, tree.position(id).unwrap()).unwrap();
    }
    let queries: Vec<Point> = (0..256)
        .map(|_| Point::new(unit(&mut rng) * 100.0, unit(&mut rng) * 100.0))
        .collect();
    let pos = tree.positions();
    let mut i = 0usize;
    c.bench_function("nearest/index/4096", |b| {
        b.iter(|| {
            i = (i + 1) & 255;
            black_box(idx.nearest(black_box(queries[i]), pos))
        })
    });
    c.bench_function("nearest/linear/4096", |b| {
        b.iter(|| {
            i = (i + 1) & 255;
            black_box(linear_nearest(pos, black_box(queries[i])))
        })
    });
    c.bench_function("within5m/index/4096", |b| {
        b.iter(|| {
            i = (i + 1) & 255;
            let mut n = 0u32;
            let _ = idx.for_each_within(black_box(queries[i]), 5.0, pos, |_, _| {
                n += 1;
                ControlFlow::Continue(())
            });
            black_box(n)
        })
    });
}

fn bench_tree(c: &mut Criterion) {
    let mut rng = XorShiftRng::seed_from_u64(3);
    // A random tree of 4,096 nodes: each node hangs below a random earlier one.
    let mut tree = Box::new(Tree::<4096>::new());
    tree.reset(Point::new(50.0, 50.0));
    while !tree.is_full() {
        let parent = NodeId((rng.next_u32() % tree.len() as u32) as u16);
        tree.add(
            Point::new(unit(&mut rng) * 100.0, unit(&mut rng) * 100.0),
            parent,
            false,
        )
        .unwrap();
    }
    c.bench_function("tree/set_parent/4096", |b| {
        b.iter(|| {
            let child = NodeId(1 + (rng.next_u32() % 4095) as u16);
            let parent = NodeId((rng.next_u32() % 4096) as u16);
            black_box(tree.set_parent(child, parent, false)).ok();
        })
    });
    c.bench_function("tree/set_root/4096", |b| {
        b.iter(|| {
            let node = NodeId((rng.next_u32() % 4096) as u16);
            black_box(tree.set_root(node)).ok();
        })
    });
}

fn print_sizes(_: &mut Criterion) {
    println!(
        "size_of Tree<2048>              = {} bytes",
        size_of::<Tree<2048>>()
    );
    println!(
        "size_of Tree<4096>              = {} bytes",
        size_of::<Tree<4096>>()
    );
    println!(
        "size_of SpatialIndex<4096, 400> = {} bytes",
        size_of::<SpatialIndex<4096, 400>>()
    );
    println!(
        "size_of SpatialIndex<4096, 1600> = {} bytes",
        size_of::<SpatialIndex<4096, 1600>>()
    );
}

criterion_group!(
    benches,
    print_sizes,
    bench_free_path,
    bench_index,
    bench_tree
);
criterion_main!(benches);
