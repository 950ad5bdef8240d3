//! `free_path` against two oracles on thousands of random segments over random grids:
//! - very fine sampling along the segment (every cell a sample lands in must be reported, and a
//!   sample in an occupied cell means the segment is blocked);
//! - an exact segment-versus-square test in f64 (every cell within half the contact margin must
//!   be reported, no cell farther than twice the margin may be).
//!
//! Plus explicit corner cases. Deterministic: a seeded xorshift generator.

use std::collections::BTreeSet;
use std::ops::ControlFlow;

use bi_am_rrt::geometry::Point;
use bi_am_rrt::map::{CONTACT_MARGIN, OccupancyGrid, pack_grid};
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

fn unit(rng: &mut XorShiftRng) -> f64 {
    (rng.next_u64() >> 11) as f64 / (1u64 << 53) as f64
}

/// Whether the segment meets the square `[c, c+1] x [r, r+1]` grown by `d` on every side
/// (Liang-Barsky clipping in f64, cell units).
fn meets_square(a: (f64, f64), b: (f64, f64), c: f64, r: f64, d: f64) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - (c - d)),
        (dx, (c + 1.0 + d) - a.0),
        (-dy, a.1 - (r - d)),
        (dy, (r + 1.0 + d) - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
        }
    }
    t0 <= t1
}

fn reported_cells(g: &OccupancyGrid<'_>, a: Point, b: Point) -> BTreeSet<(u16, u16)> {
    let mut cells = BTreeSet::new();
    let _ = g.for_each_cell(a, b, |c, r| {
        cells.insert((c, r));
        ControlFlow::Continue(())
    });
    cells
}

struct Case {
    w: u16,
    h: u16,
    cell: f32,
    bits: Vec<u8>,
}

impl Case {
    fn random(rng: &mut XorShiftRng) -> Self {
        let w = 1 + (rng.next_u32() % 40) as u16;
        let h = 1 + (rng.next_u32() % 30) as u16;
        let cell = [1.0f32, 0.5, 0.25, 2.0][(rng.next_u32() % 4) as usize];
        let density = unit(rng) * 0.5;
        let mut bits = vec![0u8; OccupancyGrid::bytes_needed(w, h)];
        pack_grid(&mut bits, w, h, |_, _| unit(rng) < density).unwrap();
        Self { w, h, cell, bits }
    }

    fn grid(&self) -> OccupancyGrid<'_> {
        OccupancyGrid::new(&self.bits, self.w, self.h, self.cell).unwrap()
    }

    /// A random point in the map; a third of the coordinates snap to half-cell multiples so
    /// corners and grid lines are hit exactly.
    fn point(&self, rng: &mut XorShiftRng) -> Point {
        let mut coord = |cells: u16| {
            let v = unit(rng) * cells as f64;
            let v = if rng.next_u32().is_multiple_of(3) {
                (v * 2.0).round() / 2.0
            } else {
                v
            };
            (v * self.cell as f64) as f32
        };
        Point::new(coord(self.w), coord(self.h))
    }
}

#[test]
fn free_path_matches_exact_and_sampled_oracles() {
    let mut rng = XorShiftRng::seed_from_u64(0x5eed_f00d);
    let mut segments = 0;
    let mut blocked = 0;
    for _ in 0..60 {
        let case = Case::random(&mut rng);
        let g = case.grid();
        for _ in 0..200 {
            let a = case.point(&mut rng);
            // Mix long segments with short ones (planner steps are short).
            let b = if rng.next_u32().is_multiple_of(2) {
                case.point(&mut rng)
            } else {
                let q = case.point(&mut rng);
                a.lerp(q, 0.1)
            };
            let cells = reported_cells(&g, a, b);
            let inv = 1.0 / case.cell as f64;
            let (ac, bc) = (
                (a.x as f64 * inv, a.y as f64 * inv),
                (b.x as f64 * inv, b.y as f64 * inv),
            );
            let m = CONTACT_MARGIN as f64;
            for r in 0..case.h {
                for c in 0..case.w {
                    let (cf, rf) = (c as f64, r as f64);
                    let listed = cells.contains(&(c, r));
                    if meets_square(ac, bc, cf, rf, 0.5 * m) {
                        assert!(listed, "cell ({c},{r}) touched by {a:?}-{b:?} not reported");
                    }
                    if !meets_square(ac, bc, cf, rf, 2.0 * m) {
                        assert!(!listed, "cell ({c},{r}) reported but away from {a:?}-{b:?}");
                    }
                }
            }
            // Fine sampling: 20 samples per cell of length.
            let len_cells = a.dist(b) as f64 * inv;
            let n = (len_cells * 20.0).ceil() as usize + 1;
            let mut sampled_occupied = false;
            for k in 0..=n {
                let t = k as f64 / n as f64;
                let (x, y) = (ac.0 + (bc.0 - ac.0) * t, ac.1 + (bc.1 - ac.1) * t);
                let (c, r) = (
                    (x.floor() as i64).clamp(0, case.w as i64 - 1) as u16,
                    (y.floor() as i64).clamp(0, case.h as i64 - 1) as u16,
                );
                assert!(cells.contains(&(c, r)), "sampled cell ({c},{r}) missing");
                sampled_occupied |= g.is_occupied(c, r);
            }
            let free = g.segment_free(a, b);
            let any_reported_occupied = cells.iter().any(|&(c, r)| g.is_occupied(c, r));
            assert_eq!(free, !any_reported_occupied, "{a:?}-{b:?}");
            if sampled_occupied {
                assert!(!free, "a sample of {a:?}-{b:?} lies in an occupied cell");
            }
            segments += 1;
            blocked += usize::from(!free);
        }
    }
    assert_eq!(segments, 12_000);
    // The random grids are neither all free nor all blocked.
    assert!(blocked > 2_000 && blocked < 10_000, "blocked {blocked}");
}

fn grid(w: u16, h: u16, occupied: &[(u16, u16)]) -> Vec<u8> {
    let mut bits = vec![0u8; OccupancyGrid::bytes_needed(w, h)];
    pack_grid(&mut bits, w, h, |c, r| occupied.contains(&(c, r))).unwrap();
    bits
}

#[test]
fn corner_cases() {
    let p = Point::new;
    // Two occupied cells sharing only the corner (2, 2).
    let bits = grid(5, 5, &[(1, 1), (2, 2)]);
    let g = OccupancyGrid::new(&bits, 5, 5, 1.0).unwrap();
    // Through the shared corner along the other diagonal: blocked.
    assert!(!g.segment_free(p(1.5, 2.5), p(2.5, 1.5)));
    assert!(!g.segment_free(p(3.0, 1.0), p(1.0, 3.0)));
    // Ending exactly on the corner: blocked (the point touches both cells).
    assert!(!g.segment_free(p(4.5, 0.5), p(2.0, 2.0)));
    // Any anti-diagonal near that corner meets one of the two cells.
    assert!(!g.segment_free(p(1.5, 2.6), p(2.6, 1.5)));
    assert!(!g.segment_free(p(4.5, 0.5), p(0.5, 4.5)));
    // Clear of both cells: free.
    assert!(g.segment_free(p(3.5, 0.5), p(4.5, 3.5)));
    assert!(g.segment_free(p(0.5, 0.5), p(0.5, 4.5)));
    // Reaching a corner of an occupied cell: blocked; stopping 5 mm short: free.
    assert!(!g.segment_free(p(0.5, 2.0), p(1.0, 2.0)));
    assert!(g.segment_free(p(0.5, 2.0), p(0.995, 2.0)));
    // Along an occupied cell's edge: blocked; 1 cm beside it: free.
    assert!(!g.segment_free(p(1.2, 1.0), p(1.8, 1.0)));
    assert!(g.segment_free(p(1.2, 0.99), p(1.8, 0.99)));
    assert!(!g.segment_free(p(1.0, 0.2), p(1.0, 1.0)));
    assert!(g.segment_free(p(1.0, 0.2), p(1.0, 0.99)));
    // Degenerate segments are points.
    assert!(g.point_free(p(0.5, 0.5)));
    assert!(!g.point_free(p(1.5, 1.5)));
    assert!(!g.point_free(p(2.0, 2.0)));
    // Map bounds: the border itself is inside; a hair beyond is not.
    assert!(g.segment_free(p(0.0, 4.0), p(5.0, 4.0)));
    assert!(!g.segment_free(p(0.0, 4.0), p(5.001, 4.0)));
    assert!(!g.segment_free(p(0.5, 0.5), p(0.5, f32::INFINITY)));
    // A long axis-aligned run checks a bit range across bytes.
    let bits = grid(40, 3, &[(37, 1)]);
    let g = OccupancyGrid::new(&bits, 40, 3, 1.0).unwrap();
    assert!(!g.segment_free(p(0.5, 1.5), p(39.5, 1.5)));
    assert!(g.segment_free(p(0.5, 1.5), p(36.9, 1.5)));
    assert!(g.segment_free(p(39.5, 1.5), p(38.1, 1.5)));
    assert!(g.segment_free(p(0.5, 0.5), p(39.5, 0.5)));
}

/// `point_free` has its own fast path: it must answer exactly as the degenerate segment `p-p`
/// does, on random points and on points on and a margin's width around cell edges and corners,
/// at several cell sizes.
#[test]
fn point_free_is_the_degenerate_segment() {
    let p = Point::new;
    let mut rng = XorShiftRng::seed_from_u64(7);
    for cell in [1.0f32, 0.5, 0.05, 3.0] {
        let (w, h) = (23u16, 17u16);
        let mut bits = vec![0u8; OccupancyGrid::bytes_needed(w, h)];
        pack_grid(&mut bits, w, h, |_, _| unit(&mut rng) < 0.3).unwrap();
        let g = OccupancyGrid::new(&bits, w, h, cell).unwrap();
        let mut points = Vec::new();
        for _ in 0..20_000 {
            let (x, y) = (unit(&mut rng) * 24.0 - 0.5, unit(&mut rng) * 18.0 - 0.5);
            points.push(p(x as f32 * cell, y as f32 * cell));
        }
        let offsets = [
            0.0f32,
            CONTACT_MARGIN,
            -CONTACT_MARGIN,
            0.5 * CONTACT_MARGIN,
            1e-6,
        ];
        for c in 0..=w {
            for r in 0..=h {
                for dx in offsets {
                    for dy in offsets {
                        points.push(p((c as f32 + dx) * cell, (r as f32 + dy) * cell));
                    }
                }
            }
        }
        points.push(p(f32::NAN, 1.0));
        points.push(p(1.0, f32::INFINITY));
        for q in points {
            assert_eq!(
                g.point_free(q),
                g.segment_free(q, q),
                "{q:?} at cell {cell}"
            );
        }
    }
}
