//! The spatial index against a linear scan on random point sets, radii and queries (including
//! queries outside the map, and indexes with nodes removed). Deterministic: seeded xorshift.

use std::ops::ControlFlow;

use bi_am_rrt::geometry::Point;
use bi_am_rrt::index::{SpatialIndex, linear_nearest, linear_within};
use bi_am_rrt::tree::NodeId;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

const N: usize = 4096;
const B: usize = 1024;

fn unit(rng: &mut XorShiftRng) -> f32 {
    (rng.next_u32() >> 8) as f32 / (1u32 << 24) as f32
}

#[test]
fn index_agrees_with_linear_scan() {
    let mut rng = XorShiftRng::seed_from_u64(42);
    let mut queries = 0;
    for round in 0..40 {
        let (w, h) = (10.0 + unit(&mut rng) * 190.0, 10.0 + unit(&mut rng) * 190.0);
        let side = [0.5f32, 2.0, 5.0, 20.0][round % 4];
        let mut idx = Box::new(SpatialIndex::<N, B>::with_bounds(w, h, side).unwrap());
        // Small trees too: the index then scans its nodes instead of its buckets.
        let n = 1 + (rng.next_u32() as usize % if round % 4 == 1 { 64 } else { N });
        // Clustered or uniform points.
        let clustered = round % 3 == 0;
        let pts: Vec<Point> = (0..n)
            .map(|_| {
                if clustered {
                    Point::new(
                        (w * 0.3 + unit(&mut rng) * 3.0).min(w),
                        (h * 0.6 + unit(&mut rng) * 3.0).min(h),
                    )
                } else {
                    Point::new(unit(&mut rng) * w, unit(&mut rng) * h)
                }
            })
            .collect();
        for (i, p) in pts.iter().enumerate() {
            idx.insert(NodeId(i as u16), *p).unwrap();
        }
        // Remove a random tenth; the oracle sees only what is still indexed.
        let mut present = vec![true; n];
        for _ in 0..n / 10 {
            let i = rng.next_u32() as usize % n;
            if present[i] {
                idx.remove(NodeId(i as u16), pts[i]).unwrap();
                present[i] = false;
            }
        }
        assert_eq!(idx.len(), present.iter().filter(|&&p| p).count());
        for _ in 0..100 {
            // Some queries fall outside the map.
            let q = Point::new(
                -20.0 + unit(&mut rng) * (w + 40.0),
                -20.0 + unit(&mut rng) * (h + 40.0),
            );
            let got = idx.nearest_where(q, &pts, |id| id.0 % 7 != 3);
            let oracle = linear_nearest(
                &pts.iter()
                    .enumerate()
                    .map(|(i, p)| {
                        if present[i] && i % 7 != 3 {
                            *p
                        } else {
                            Point::new(1e9, 1e9)
                        }
                    })
                    .collect::<Vec<_>>(),
                q,
            )
            .filter(|(_, d2)| *d2 < 1e17);
            match (got, oracle) {
                (Some((gid, gd)), Some((_, od))) => {
                    assert_eq!(gd, od, "nearest distance for {q:?}");
                    assert_eq!(pts[gid.index()].dist_sq(q), gd);
                    assert!(present[gid.index()] && gid.0 % 7 != 3);
                }
                (None, None) => {}
                other => panic!("nearest mismatch {other:?}"),
            }
            let radius = unit(&mut rng) * 30.0;
            let mut got = Vec::new();
            let _ = idx.for_each_within(q, radius, &pts, |id, d2| {
                assert_eq!(d2, pts[id.index()].dist_sq(q));
                got.push(id);
                ControlFlow::Continue(())
            });
            got.sort();
            let mut want = Vec::new();
            linear_within(&pts, q, radius, |id| {
                if present[id.index()] {
                    want.push(id)
                }
            });
            assert_eq!(got, want, "within {radius} of {q:?}");
            queries += 1;
        }
    }
    assert_eq!(queries, 4_000);
}

#[test]
fn early_stop_and_truncated_collection() {
    let pts: Vec<Point> = (0..50).map(|i| Point::new(i as f32 * 0.1, 1.0)).collect();
    let mut idx = SpatialIndex::<64, 16>::with_bounds(10.0, 10.0, 1.0).unwrap();
    for (i, p) in pts.iter().enumerate() {
        idx.insert(NodeId(i as u16), *p).unwrap();
    }
    let mut seen = 0;
    let flow = idx.for_each_within(Point::new(2.5, 1.0), 100.0, &pts, |_, _| {
        seen += 1;
        if seen == 5 {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    assert_eq!((flow, seen), (ControlFlow::Break(()), 5));
    let mut out = heapless::Vec::<NodeId, 8>::new();
    assert_eq!(idx.within(Point::new(2.5, 1.0), 100.0, &pts, &mut out), 50);
    assert_eq!(out.len(), 8);
}
