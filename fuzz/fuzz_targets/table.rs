//! The byte readers of the core on arbitrary bytes (issue 7, fuzz target b): the diffusion
//! table reader, the roadmap reader, the occupancy grid constructor with its collision tests, and the spatial
//! index with arbitrary bounds. Nothing may panic; what is accepted must answer queries.
#![no_main]

use bi_am_rrt::index::SpatialIndex;
use bi_am_rrt::map::OccupancyGrid;
use bi_am_rrt::metric::DiffusionTable;
use bi_am_rrt::tree::NodeId;
use bi_am_rrt::{Metric, Point};

fn f32_at(data: &[u8], at: usize) -> f32 {
    let mut b = [0u8; 4];
    for (i, slot) in b.iter_mut().enumerate() {
        *slot = data.get(at + i).copied().unwrap_or(0);
    }
    f32::from_le_bytes(b)
}

libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    // The table reader on the bytes as they are, then with a fixed-up checksum so the fuzzer
    // gets past it.
    let probe = |i: usize| Point::new(f32_at(data, i), f32_at(data, i + 4));
    if let Ok(t) = DiffusionTable::new(data) {
        let mut out = [0f32; 32];
        let _ = t.coordinates(probe(0), &mut out);
        let _ = t.distance(probe(8), probe(16));
        let _ = t.covers(probe(24));
    }
    // The reader that skips the checksum must be as safe on any bytes.
    if let Ok(t) = DiffusionTable::new_unverified(data) {
        let mut out = [0f32; 32];
        let _ = t.coordinates(probe(0), &mut out);
        let _ = t.distance(probe(8), probe(16));
        let _ = t.covers(probe(24));
    }
    if data.len() >= 32 {
        let mut fixed = data.to_vec();
        let sum = bi_am_rrt::metric::fnv1a32(&fixed[32..]);
        fixed[28..32].copy_from_slice(&sum.to_le_bytes());
        if let Ok(t) = DiffusionTable::new(&fixed) {
            let (a, b) = (probe(8), probe(16));
            let (d, e) = (t.distance(a, b), t.distance(b, a));
            assert!(
                d.to_bits() == e.to_bits() || (d.is_nan() && e.is_nan()),
                "symmetric"
            );
        }
    }
    // The roadmap reader (feature `roadmap`): what it accepts must answer every query.
    if let Ok(rm) = bi_am_rrt::roadmap::Roadmap::from_bytes(data) {
        for i in 0..rm.len().min(64) {
            let _ = rm.node(i);
            let _ = rm.tangent(i, probe(0));
            assert!(rm.neighbours(i).all(|j| j < rm.len()), "edges name nodes");
        }
    }
    // The grid constructor and its queries.
    let w = u16::from_le_bytes([data.first().copied().unwrap_or(1), 0]);
    let h = u16::from_le_bytes([data.get(1).copied().unwrap_or(1), 0]);
    let cell = f32_at(data, 2);
    if let Ok(g) = OccupancyGrid::new(data.get(6..).unwrap_or(&[]), w, h, cell) {
        let (a, b) = (probe(6), probe(14));
        let _ = g.segment_free(a, b);
        let _ = g.point_free(a);
        let _ = g.cell_of(b);
        let mut cells = 0u32;
        let _ = g.for_each_cell(a, b, |_, _| {
            cells += 1;
            if cells > 200_000 {
                core::ops::ControlFlow::Break(())
            } else {
                core::ops::ControlFlow::Continue(())
            }
        });
    }
    // The spatial index with arbitrary bounds and points.
    if let Some(mut idx) =
        SpatialIndex::<16, 8>::with_bounds(f32_at(data, 0), f32_at(data, 4), f32_at(data, 8))
    {
        let pts: Vec<Point> = (0..16).map(|i| probe(12 + 8 * i)).collect();
        let mut kept = Vec::new();
        for (i, p) in pts.iter().enumerate() {
            if idx.insert(NodeId(i as u16), *p).is_ok() {
                kept.push(i);
            }
        }
        // Removal walks the singly linked bucket of the position given: every other kept
        // node goes, and must be found there.
        let mut removed = Vec::new();
        for (k, &i) in kept.iter().enumerate() {
            if k % 2 == 1 {
                assert!(idx.remove(NodeId(i as u16), pts[i]).is_ok(), "remove {i}");
                removed.push(i);
            }
        }
        kept.retain(|i| !removed.contains(i));
        assert_eq!(idx.len(), kept.len());
        let q = probe(3);
        let found = idx.nearest(q, &pts).map(|(_, d2)| d2);
        let oracle = kept
            .iter()
            .map(|&i| pts[i].dist_sq(q))
            .min_by(|a, b| a.total_cmp(b));
        if q.is_finite() && oracle.is_some_and(|d| d.is_finite()) {
            assert_eq!(found, oracle, "nearest differs from the linear scan");
        }
        let mut out = heapless::Vec::<NodeId, 16>::new();
        let _ = idx.within(q, f32_at(data, 5), &pts, &mut out);
    }
});
