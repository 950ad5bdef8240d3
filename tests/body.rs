//! A robot with a body (issue 41): the disc rule of `map::inflate` against an independent
//! distance computation, live edits that re-inflate as a fresh inflation would, every
//! waypoint segment of every call keeping the disc clear of the walls and the circles (by
//! this file's own `f64` distances, not the planner's tests), and the errors a body can give.
//!
//! Deterministic: seeded generators, a fake clock, proptest with fixed case counts.

use std::time::Duration;

use bi_am_rrt::clock::FakeClock;
use bi_am_rrt::error::{InputError, MapError, SetupError};
use bi_am_rrt::map::{CONTACT_MARGIN, ROOM_SAMPLES, inflate, pack_grid};
use bi_am_rrt::{Circle, Config, Euclidean, Map, OccupancyGrid, Planner, Point, Storage};
use proptest::prelude::*;
use rand_core::{Rng, SeedableRng};
use rand_xorshift::XorShiftRng;

/// Distance from segment `a-b` to the closed box `[lo, hi]`, in `f64` (0 when they meet).
fn seg_box(a: [f64; 2], b: [f64; 2], lo: [f64; 2], hi: [f64; 2]) -> f64 {
    // Sample-free: the distance between a segment and a convex box is reached at an end of
    // the segment or at a corner of the box, unless they cross.
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1, mut meets) = (0.0f64, 1.0f64, true);
    for (p, q) in [
        (-d[0], a[0] - lo[0]),
        (d[0], hi[0] - a[0]),
        (-d[1], a[1] - lo[1]),
        (d[1], hi[1] - a[1]),
    ] {
        if p == 0.0 {
            meets &= q >= 0.0;
        } else if p < 0.0 {
            t0 = t0.max(q / p);
        } else {
            t1 = t1.min(q / p);
        }
    }
    if meets && t0 <= t1 {
        return 0.0;
    }
    let seg_pt = |p: [f64; 2]| {
        let l2 = d[0] * d[0] + d[1] * d[1];
        let t = if l2 > 0.0 {
            (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        (a[0] + t * d[0] - p[0]).hypot(a[1] + t * d[1] - p[1])
    };
    let box_pt = |p: [f64; 2]| {
        let dx = (lo[0] - p[0]).max(p[0] - hi[0]).max(0.0);
        let dy = (lo[1] - p[1]).max(p[1] - hi[1]).max(0.0);
        dx.hypot(dy)
    };
    [lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]]
        .into_iter()
        .map(seg_pt)
        .fold(box_pt(a).min(box_pt(b)), f64::min)
}

/// The least distance from segment `a-b` to an occupied cell of `occ` (row-major, `w` wide,
/// cells of `cell` m) or to the map's edge.
fn clearance(occ: &[bool], w: usize, h: usize, cell: f64, a: Point, b: Point) -> f64 {
    let (a, b) = ([a.x as f64, a.y as f64], [b.x as f64, b.y as f64]);
    let (wm, hm) = (w as f64 * cell, h as f64 * cell);
    let mut best = [
        a[0],
        a[1],
        b[0],
        b[1],
        wm - a[0],
        wm - b[0],
        hm - a[1],
        hm - b[1],
    ]
    .into_iter()
    .fold(f64::INFINITY, f64::min);
    for (i, _) in occ.iter().enumerate().filter(|(_, o)| **o) {
        let lo = [(i % w) as f64 * cell, (i / w) as f64 * cell];
        best = best.min(seg_box(a, b, lo, [lo[0] + cell, lo[1] + cell]));
    }
    best
}

/// A random map of `w x h` cells: a border-free scatter of rectangular blocks.
fn random_map(rng: &mut XorShiftRng, w: usize, h: usize, blocks: usize) -> Vec<bool> {
    let mut occ = vec![false; w * h];
    for _ in 0..blocks {
        let (bw, bh) = (
            1 + rng.next_u32() as usize % 4,
            1 + rng.next_u32() as usize % 4,
        );
        let (x, y) = (
            rng.next_u32() as usize % (w - bw),
            rng.next_u32() as usize % (h - bh),
        );
        for r in y..y + bh {
            for c in x..x + bw {
                occ[r * w + c] = true;
            }
        }
    }
    occ
}

fn packed(occ: &[bool], w: u16, h: u16) -> Vec<u8> {
    let mut bits = vec![0u8; OccupancyGrid::bytes_needed(w, h)];
    pack_grid(&mut bits, w, h, |c, r| {
        occ[usize::from(r) * usize::from(w) + usize::from(c)]
    })
    .unwrap();
    bits
}

/// The rule, stated independently: a cell is marked when its square lies closer than the
/// radius to an occupied cell's square or to the outside of the map, or is occupied itself.
/// Checked in `f64` over random grids, cell sizes and radii; a band of a relative 1e-5 around
/// the radius is left to rounding (the rule marks there, being conservative).
#[test]
fn inflation_follows_the_rule_by_independent_distances() {
    let mut rng = XorShiftRng::seed_from_u64(41);
    for case in 0..60 {
        let (w, h) = (12 + case % 9, 10 + case % 7);
        let occ = random_map(&mut rng, w, h, 6);
        let cell = [0.05f32, 0.1, 0.25, 0.5, 1.0][case % 5];
        let radius = cell * (rng.next_u32() % 400) as f32 / 100.0;
        let bits = packed(&occ, w as u16, h as u16);
        let g = OccupancyGrid::new(&bits, w as u16, h as u16, cell).unwrap();
        let mut out = vec![0u8; bits.len()];
        let inflated = match inflate(&g, radius, &mut out) {
            Ok(i) => i,
            Err(MapError::NoRoom) => continue,
            Err(e) => panic!("{e}"),
        };
        assert_eq!(inflated.inflation(), radius);
        let (cellf, rf) = (f64::from(cell), f64::from(radius));
        for r in 0..h {
            for c in 0..w {
                let lo = [c as f64 * cellf, r as f64 * cellf];
                let hi = [lo[0] + cellf, lo[1] + cellf];
                // Gap to the outside: the cells between this one and the edge.
                let edge = [c, r, w - 1 - c, h - 1 - r].into_iter().min().unwrap() as f64 * cellf;
                let mut d = edge;
                for (i, _) in occ.iter().enumerate().filter(|(_, o)| **o) {
                    let (oc, or) = ((i % w) as f64 * cellf, (i / w) as f64 * cellf);
                    let gx = (oc - hi[0]).max(lo[0] - (oc + cellf)).max(0.0);
                    let gy = (or - hi[1]).max(lo[1] - (or + cellf)).max(0.0);
                    d = d.min(gx.hypot(gy));
                }
                let marked = inflated.is_occupied(c as u16, r as u16);
                let own = occ[r * w + c];
                if own || (radius > 0.0 && d < rf * (1.0 - 1e-5)) {
                    assert!(
                        marked,
                        "case {case}: cell ({c}, {r}) at {d} m of r {rf} not marked"
                    );
                }
                if marked && !own {
                    assert!(
                        radius > 0.0 && d < rf * (1.0 + 1e-5),
                        "case {case}: cell ({c}, {r}) at {d} m marked for r {rf}"
                    );
                }
            }
        }
    }
}

const W: u16 = 48;
const H: u16 = 36;
type P<'s, 'm> = Planner<'s, 'm, Euclidean, XorShiftRng, 512, 64, 4>;

/// 4-neighbour component labels of the free cells of `g` (the test's own flood fill).
fn components(g: &OccupancyGrid<'_>) -> Vec<usize> {
    let (w, h) = (usize::from(g.cols()), usize::from(g.rows()));
    let mut comp = vec![usize::MAX; w * h];
    for s in 0..w * h {
        if comp[s] != usize::MAX || g.is_occupied((s % w) as u16, (s / w) as u16) {
            continue;
        }
        let mut stack = vec![s];
        comp[s] = s;
        while let Some(i) = stack.pop() {
            let (c, r) = (i % w, i / w);
            for (dc, dr) in [(1i64, 0i64), (-1, 0), (0, 1), (0, -1)] {
                let (nc, nr) = (c as i64 + dc, r as i64 + dr);
                if nc < 0 || nr < 0 || nc >= w as i64 || nr >= h as i64 {
                    continue;
                }
                let j = nr as usize * w + nc as usize;
                if comp[j] == usize::MAX && !g.is_occupied(nc as u16, nr as u16) {
                    comp[j] = s;
                    stack.push(j);
                }
            }
        }
    }
    comp
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    /// Promise 1 for a disc: on random maps, cell sizes, radii and circles, every waypoint
    /// segment of every call keeps the whole disc clear: at least `r` from every occupied cell
    /// and the map's edge, and `R + r` from every circle's centre, by this file's distances.
    #[test]
    fn every_waypoint_keeps_the_disc_clear(
        seed in 0u64..1_000_000,
        cell_i in 0usize..4,
        r_pct in 0u32..250,
        w_i in 0usize..3,
    ) {
        let mut rng = XorShiftRng::seed_from_u64(seed);
        let cell = [0.1f32, 0.25, 0.5, 1.0][cell_i];
        let radius = cell * r_pct as f32 / 100.0;
        // With and without a clearance preference (a soft cost: the disc's clearance is
        // the same hard constraint either way).
        let weight = if cfg!(feature = "clearance") { [0.0f32, 1.0, 4.0][w_i] } else { 0.0 };
        let occ = random_map(&mut rng, usize::from(W), usize::from(H), 14);
        let bits = packed(&occ, W, H);
        let grid = OccupancyGrid::new(&bits, W, H, cell).unwrap();
        let mut field = vec![0u8; usize::from(W) * usize::from(H)];
        bi_am_rrt::clearance::clearance_field(&grid, radius, 3.0 * cell, &mut field).unwrap();
        let mut space = vec![0u8; bits.len()];
        let Ok(map) = Map::<'_, 4>::new(grid).with_body(radius, &mut space) else {
            return Ok(()); // no room for the disc anywhere
        };
        let map = if weight > 0.0 { map.with_clearance(&field).unwrap() } else { map };
        let cspace = *map.live().grid();
        let comp = components(&cspace);
        // A start and a goal with room for the disc, in one component of the free space.
        let free: Vec<usize> = (0..comp.len()).filter(|&i| comp[i] != usize::MAX).collect();
        prop_assume!(free.len() > 20);
        let at = |i: usize| Point::new(
            ((i % usize::from(W)) as f32 + 0.5) * cell,
            ((i / usize::from(W)) as f32 + 0.5) * cell,
        );
        let s = free[rng.next_u32() as usize % free.len()];
        let same: Vec<usize> = free.iter().copied().filter(|&i| comp[i] == comp[s] && i != s).collect();
        prop_assume!(!same.is_empty());
        let g = same[rng.next_u32() as usize % same.len()];
        let (start, goal) = (at(s), at(g));
        prop_assume!(map.check_point(start).is_ok() && map.check_point(goal).is_ok());
        let mut cfg = Config::default().for_grid(&grid);
        cfg.robot_radius = radius;
        cfg.clearance_weight = weight;
        cfg.budget.t_exp = Duration::from_millis(2);
        cfg.budget.max_expansions = 30;
        let mut storage = Box::new(Storage::<512, 64>::new());
        let mut p: P<'_, '_> =
            Planner::new(&mut storage, map, Euclidean, XorShiftRng::seed_from_u64(seed), cfg, start)
                .unwrap();
        // Two still circles away from the start and the goal.
        let mut circles = Vec::new();
        for _ in 0..2 {
            let c = Circle::new(at(free[rng.next_u32() as usize % free.len()]), cell * 1.5);
            if c.center.dist(start) > c.radius + radius + cell && c.center.dist(goal) > c.radius + radius + cell {
                p.add_obstacle(c).unwrap();
                circles.push(c);
            }
        }
        let clock = FakeClock::nanos().with_work_cost(30).with_step(10);
        let tol = 1e-5 * f64::from(cell);
        p.set_goal(goal).unwrap();
        let mut agent = start;
        for _ in 0..200 {
            let pr = p.plan(&clock, agent).unwrap();
            let (a, b) = (agent, pr.waypoint);
            let d = clearance(&occ, usize::from(W), usize::from(H), f64::from(cell), a, b);
            prop_assert!(
                d >= f64::from(radius) - tol,
                "waypoint segment {a:?} -> {b:?} at {d} m of a wall, r {radius}"
            );
            for c in &circles {
                let dc = f64::from(bi_am_rrt::geometry::segment_point_dist_sq(a, b, c.center)).sqrt();
                prop_assert!(dc >= f64::from(c.radius + radius) - tol, "circle {c:?} at {dc} m");
            }
            // The driven step, a piece of that segment, passes the protocol's exact check.
            let step = agent.step_towards(pr.waypoint, cell * 2.0);
            prop_assert!(p.map().body_clear(agent, step), "step {agent:?} -> {step:?}");
            agent = step;
            if pr.status == bi_am_rrt::Status::Arrived {
                break;
            }
        }
        // The cached costs, clearance classes included, still match their recomputation.
        prop_assert_eq!(p.tree().validate(), Ok(()));
        prop_assert_eq!(p.reverse_tree().validate(), Ok(()));
    }
}

/// Live edits on a body's map re-inflate when they are submitted: after every edit of a
/// random sequence (marks and clears, walls of the grid among them), the inflated live cells
/// equal a fresh `inflate` of the live cells as the test tracks them.
#[test]
fn live_edits_inflate_as_a_fresh_inflation() {
    let mut rng = XorShiftRng::seed_from_u64(7);
    for case in 0..12 {
        let (w, h) = (40u16, 30u16);
        let mut occ = random_map(&mut rng, usize::from(w), usize::from(h), 10);
        let bits = packed(&occ, w, h);
        let cell = [0.1f32, 0.5][case % 2];
        let radius = cell * (0.3 + (case % 4) as f32 * 0.6);
        let grid = OccupancyGrid::new(&bits, w, h, cell).unwrap();
        let (mut overlay, mut space) = (vec![0u8; bits.len()], vec![0u8; bits.len()]);
        let Ok(mut map) = Map::<'_, 4>::new(grid)
            .with_overlay(&mut overlay)
            .and_then(|m| m.with_body(radius, &mut space))
        else {
            continue;
        };
        for _ in 0..25 {
            let a = (rng.next_u32() as u16 % w, rng.next_u32() as u16 % h);
            let b = (
                (a.0 + rng.next_u32() as u16 % 4).min(w - 1),
                (a.1 + rng.next_u32() as u16 % 4).min(h - 1),
            );
            let mark = rng.next_u32() % 2 == 0;
            map.set_cells(a, b, mark).unwrap();
            for r in a.1..=b.1 {
                for c in a.0..=b.0 {
                    occ[usize::from(r) * usize::from(w) + usize::from(c)] = mark;
                }
            }
            let now = packed(&occ, w, h);
            let mut fresh = vec![0u8; now.len()];
            let live = OccupancyGrid::new(&now, w, h, cell).unwrap();
            match inflate(&live, radius, &mut fresh) {
                Ok(f) => {
                    let got = *map.live().grid();
                    for r in 0..h {
                        for c in 0..w {
                            assert_eq!(
                                got.is_occupied(c, r),
                                f.is_occupied(c, r),
                                "case {case}: cell ({c}, {r}) after an edit of {a:?}-{b:?}"
                            );
                        }
                    }
                }
                Err(MapError::NoRoom) => {}
                Err(e) => panic!("{e}"),
            }
        }
    }
}

/// What a body refuses, each with an error that names it.
#[test]
fn a_body_refuses_what_does_not_fit() {
    let (w, h) = (20u16, 10u16);
    // A 10 m x 5 m room at 0.5 m cells, a wall at column 10 with a 1 m door (rows 4-5).
    let occ: Vec<bool> = (0..usize::from(w) * usize::from(h))
        .map(|i| i % usize::from(w) == 10 && !(4..=5).contains(&(i / usize::from(w))))
        .collect();
    let bits = packed(&occ, w, h);
    let grid = OccupancyGrid::new(&bits, w, h, 0.5).unwrap();
    let mut space = vec![0u8; bits.len()];
    for bad in [f32::NAN, -0.1, f32::INFINITY] {
        assert_eq!(
            Map::<'_, 4>::new(grid).with_body(bad, &mut space).err(),
            Some(MapError::BadRadius)
        );
    }
    assert_eq!(
        Map::<'_, 4>::new(grid).with_body(3.0, &mut space).err(),
        Some(MapError::NoRoom)
    );
    let mut short = vec![0u8; bits.len() - 1];
    assert_eq!(
        Map::<'_, 4>::new(grid).with_body(0.3, &mut short).err(),
        Some(MapError::BufferTooShort)
    );
    let cfg = |r: f32| {
        let mut c = Config::default().for_grid(&grid);
        c.robot_radius = r;
        c
    };
    let start = Point::new(2.25, 2.25);
    let mut storage = Box::new(Storage::<512, 64>::new());
    // A configuration whose radius the map was not inflated for.
    let r = P::new(
        &mut storage,
        Map::new(grid),
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        cfg(0.3),
        start,
    );
    assert_eq!(r.err(), Some(SetupError::Body));
    let bad = P::new(
        &mut storage,
        Map::new(grid),
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        cfg(f32::NAN),
        start,
    );
    assert!(matches!(bad.err(), Some(SetupError::Config(_))));
    // A start next to the wall: free for a point, no room for the disc.
    let map = Map::<'_, 4>::new(grid).with_body(0.3, &mut space).unwrap();
    assert_eq!(
        map.check_point(Point::new(4.75, 1.0)),
        Err(InputError::NoRoom)
    );
    let r = P::new(
        &mut storage,
        map,
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        cfg(0.3),
        Point::new(4.75, 1.0),
    );
    assert_eq!(r.err(), Some(SetupError::Start(InputError::NoRoom)));
    // The 1 m door (y 2-3 m): the cells rule closes it to any disc at 0.5 m cells (a cell on
    // each side of a wall), but the exact test lets a 0.6 m disc through and stops a 1.1 m one.
    let through = (Point::new(4.0, 2.5), Point::new(6.0, 2.5));
    let map = Map::<'_, 4>::new(grid).with_body(0.3, &mut space).unwrap();
    assert!((0..h).all(|r| map.live().grid().is_occupied(10, r)));
    assert!(map.free_path(through.0, through.1));
    assert!(!map.free_path(Point::new(4.0, 2.25), Point::new(6.0, 2.25)));
    let map = Map::<'_, 4>::new(grid).with_body(0.55, &mut space).unwrap();
    assert!(!map.free_path(through.0, through.1));
    assert_eq!(
        map.check_point(Point::new(5.25, 2.5)),
        Err(InputError::NoRoom)
    );
    // Live cells on a grid baked into flash need a RAM copy.
    let mut baked_bits = vec![0u8; bits.len()];
    let baked = inflate(&grid, 0.3, &mut baked_bits).unwrap();
    let mut overlay = vec![0u8; bits.len()];
    let mut map = Map::<'_, 4>::new(grid)
        .with_overlay(&mut overlay)
        .unwrap()
        .with_baked_body(baked)
        .unwrap();
    assert_eq!(
        map.set_cells((1, 1), (1, 1), true),
        Err(MapError::BodyInFlash)
    );
    let other = OccupancyGrid::new(&baked_bits, w, h, 0.25).unwrap();
    assert_eq!(
        Map::<'_, 4>::new(grid).with_baked_body(other).err(),
        Some(MapError::BodyMismatch)
    );
}

/// A circle of radius R blocks R + r for a body of radius r; what the obstacle set gives back
/// is the disc as added.
#[test]
fn circles_grow_by_the_radius() {
    let (w, h) = (40u16, 40u16);
    let bits = vec![0u8; OccupancyGrid::bytes_needed(w, h)];
    let grid = OccupancyGrid::new(&bits, w, h, 0.5).unwrap();
    let mut space = vec![0u8; bits.len()];
    let map = Map::<'_, 4>::new(grid).with_body(0.4, &mut space).unwrap();
    let mut cfg = Config::default().for_grid(&grid);
    cfg.robot_radius = 0.4;
    let mut storage = Box::new(Storage::<512, 64>::new());
    let mut p = P::new(
        &mut storage,
        map,
        Euclidean,
        XorShiftRng::seed_from_u64(1),
        cfg,
        Point::new(2.0, 10.0),
    )
    .unwrap();
    let c = Circle::new(Point::new(10.0, 10.0), 1.0);
    let id = p.add_obstacle(c).unwrap();
    assert_eq!(p.map().obstacles().get(id), Some(c));
    // A segment 1.3 m from the centre: clear of the disc, not of the robot's.
    let (a, b) = (Point::new(5.0, 11.3), Point::new(15.0, 11.3));
    assert!(!c.intersects_segment(a, b));
    assert!(!p.map().free_path(a, b));
    let (a, b) = (Point::new(5.0, 11.45), Point::new(15.0, 11.45));
    assert!(p.map().free_path(a, b));
    assert_eq!(p.remove_obstacle(id), Ok(c));
}

/// The exact test, against this file's distances on random grids, radii and segments: a
/// segment it passes keeps the radius from every occupied cell and the map's edge (sound),
/// and one that keeps the radius plus twice the contact margin passes (complete to within
/// the margin).
#[test]
fn the_exact_test_is_sound_and_complete_to_the_margin() {
    let mut rng = XorShiftRng::seed_from_u64(4141);
    let (mut passed, mut refused) = (0, 0);
    for case in 0..200 {
        let (w, h) = (30usize, 24usize);
        let occ = random_map(&mut rng, w, h, 8);
        let bits = packed(&occ, w as u16, h as u16);
        let cell = [0.05f32, 0.25, 1.0][case % 3];
        let radius = cell * (rng.next_u32() % 300) as f32 / 100.0;
        let grid = OccupancyGrid::new(&bits, w as u16, h as u16, cell).unwrap();
        let mut space = vec![0u8; bits.len()];
        let Ok(map) = Map::<'_, 4>::new(grid).with_body(radius, &mut space) else {
            continue;
        };
        let (wm, hm) = (grid.width_m(), grid.height_m());
        for _ in 0..40 {
            let pt = |rng: &mut XorShiftRng| {
                Point::new(
                    (rng.next_u32() % 10_000) as f32 / 10_000.0 * wm,
                    (rng.next_u32() % 10_000) as f32 / 10_000.0 * hm,
                )
            };
            // Mostly short segments (a few cells: they end near walls), some across the map.
            let a = pt(&mut rng);
            let far = pt(&mut rng);
            let b = if rng.next_u32() % 4 == 0 {
                far
            } else {
                a.lerp(far, 0.1)
            };
            let d = clearance(&occ, w, h, f64::from(cell), a, b);
            let free = map.free_path(a, b);
            if free {
                passed += 1;
                assert!(
                    d >= f64::from(radius) - 1e-5 * f64::from(cell),
                    "case {case}: {a:?}-{b:?} passed at {d} m for r {radius}"
                );
            } else {
                refused += 1;
                assert!(
                    d < f64::from(radius) + 2.0 * f64::from(CONTACT_MARGIN * cell) + 1e-5,
                    "case {case}: {a:?}-{b:?} refused at {d} m for r {radius}"
                );
            }
        }
    }
    assert!(
        passed > 500 && refused > 500,
        "{passed} passed, {refused} refused"
    );
}

/// A body's `Live::is_occupied`, against this file's distances: a cell it calls free has a
/// sample point (`ROOM_SAMPLES`) with room for the disc, and one it calls occupied has none
/// with room plus twice the contact margin; a door wider than the disc's diameter reads open
/// even where no cell centre has room in it.
#[test]
fn cells_with_room_by_independent_distances() {
    let mut rng = XorShiftRng::seed_from_u64(42);
    for case in 0..40 {
        let (w, h) = (14 + case % 5, 11 + case % 4);
        let occ = random_map(&mut rng, w, h, 5);
        let cell = [0.1f32, 0.5, 1.0][case % 3];
        let radius = cell * (rng.next_u32() % 300) as f32 / 100.0;
        let bits = packed(&occ, w as u16, h as u16);
        let g = OccupancyGrid::new(&bits, w as u16, h as u16, cell).unwrap();
        let mut space = vec![0u8; bits.len()];
        let Ok(map) = Map::<'_, 4>::new(g).with_body(radius, &mut space) else {
            continue;
        };
        let live = map.live();
        let (cf, rf) = (f64::from(cell), f64::from(radius));
        let margin = 2.0 * f64::from(CONTACT_MARGIN) * cf + 1e-6;
        for r in 0..h {
            for c in 0..w {
                let room = ROOM_SAMPLES
                    .iter()
                    .map(|&(u, v)| {
                        let p = Point::new((c as f32 + u) * cell, (r as f32 + v) * cell);
                        clearance(&occ, w, h, cf, p, p)
                    })
                    .fold(0.0f64, f64::max);
                if live.is_occupied(c as u16, r as u16) {
                    assert!(
                        occ[r * w + c] || room < rf + margin,
                        "case {case}: ({c}, {r}) has {room} m of room for r {rf}"
                    );
                } else {
                    assert!(
                        room >= rf - 1e-5 * cf,
                        "case {case}: ({c}, {r}) {room} m, r {rf}"
                    );
                }
            }
        }
    }
    // A 2 m door on a 1 m grid (column 5, rows 4-5): a 1.2 m disc fits on the line between
    // the door's two cells, where no cell centre has room; the cells read open.
    let occ: Vec<bool> = (0..200)
        .map(|i| i % 20 == 5 && !(4..=5).contains(&(i / 20)))
        .collect();
    let bits = packed(&occ, 20, 10);
    let g = OccupancyGrid::new(&bits, 20, 10, 1.0).unwrap();
    let mut space = vec![0u8; bits.len()];
    let map = Map::<'_, 4>::new(g).with_body(0.6, &mut space).unwrap();
    assert!(!map.live().is_occupied(5, 4) && !map.live().is_occupied(5, 5));
    assert!(map.free_path(Point::new(3.0, 5.0), Point::new(8.0, 5.0)));
    let map = Map::<'_, 4>::new(g).with_body(1.05, &mut space).unwrap();
    assert!(map.live().is_occupied(5, 4) && map.live().is_occupied(5, 5));
}
